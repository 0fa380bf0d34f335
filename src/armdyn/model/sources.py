"""Where an arm was read from, kept as long as the arm lives: the file of each arm that a loader made, and the
geometry of an arm read from a MuJoCo model.

``armdyn.load_urdf`` records its file here and ``armdyn.load_mjcf`` its model's geoms; ``armdyn.viewer`` reads
them back to draw the arm's meshes. An arm made otherwise (``from_dh``, ``replace``, ``with_payload`` ...) has
neither.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from armdyn.model.arm import ArmModel

_SOURCES: weakref.WeakKeyDictionary[ArmModel, Path] = weakref.WeakKeyDictionary()


def record_source(arm: ArmModel, path: Path) -> None:
    """Remember that ``arm`` was read from the file ``path``.

    Parameters
    ----------
    arm : ArmModel
        The arm a loader made.
    path : pathlib.Path
        Its file.
    """
    _SOURCES[arm] = Path(path).resolve()


def source_file(arm: ArmModel) -> Path | None:
    """The file ``arm`` was read from (``record_source``), or None for an arm made otherwise.

    Parameters
    ----------
    arm : ArmModel
        The arm.

    Returns
    -------
    pathlib.Path or None
        The file, resolved.
    """
    return _SOURCES.get(arm)


@dataclass(frozen=True, eq=False)
class Geom:
    """One piece of an arm's drawing as a MuJoCo model describes it (``armdyn.load_mjcf`` records them).

    Parameters
    ----------
    link : int
        The arm link that carries it (-1: the base).
    kind : str
        "sphere", "capsule", "ellipsoid", "cylinder", "box" or "mesh" (MuJoCo's geom types).
    pose : numpy.ndarray
        Its frame in the link's frame, 4x4.
    size : numpy.ndarray
        MuJoCo's size: the radius, the radius and half-length along z, the three radii, the radius and
        half-length, or the three half-sizes.
    vertices : numpy.ndarray, optional
        A mesh's vertices in its frame, (V, 3) (default None for the other kinds).
    faces : numpy.ndarray, optional
        A mesh's triangles, (F, 3) indices (default None).
    name : str, optional
        The geom's name in the model (default "").
    index : int, optional
        The geom's id in the model (default -1: none).
    """

    link: int
    kind: str
    pose: np.ndarray
    size: np.ndarray
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    name: str = ""
    index: int = -1


_GEOMETRY: weakref.WeakKeyDictionary[ArmModel, tuple[Geom, ...]] = weakref.WeakKeyDictionary()


def record_geometry(arm: ArmModel, geoms: Sequence[Geom]) -> None:
    """Remember how ``arm`` is drawn: the geoms of the MuJoCo model it was read from.

    Parameters
    ----------
    arm : ArmModel
        The arm a loader made.
    geoms : sequence of Geom
        Its geoms, each on the link that carries it.
    """
    _GEOMETRY[arm] = tuple(geoms)


def geometry_of(arm: ArmModel) -> tuple[Geom, ...]:
    """The geoms ``record_geometry`` recorded for ``arm`` (empty for an arm made otherwise).

    Parameters
    ----------
    arm : ArmModel
        The arm.

    Returns
    -------
    tuple of Geom
        Its geoms.
    """
    return _GEOMETRY.get(arm, ())
