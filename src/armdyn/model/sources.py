"""Where an arm was read from: the file of each arm that a loader made, kept as long as the arm lives.

``armdyn.load_urdf`` records its file here; ``armdyn.viewer`` reads it back to draw the arm's meshes. An arm made
otherwise (``from_dh``, ``replace``, ``with_payload`` ...) has no file.
"""

from __future__ import annotations

import weakref
from pathlib import Path
from typing import TYPE_CHECKING

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
