"""load_urdf(path) -> Robot, parsing through yourdfpy; meshes are never loaded.

Revolute, continuous (one coordinate, the angle), prismatic and fixed joints; branching
trees. Fixed joints are merged into their parent body (parallel-axis theorem). Joints
are numbered depth first from the root, children in file order.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.arm import Link
from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint
from armdyn.robot import Robot

_MOVING = {"revolute", "continuous", "prismatic"}


def _parse(path: Path):
    import yourdfpy
    from lxml import etree

    try:  # yourdfpy would recover from broken XML on its own: parse strictly first
        etree.parse(str(path))
    except etree.XMLSyntaxError as error:
        raise ModelError(f"{path}: malformed XML ({error})") from None
    try:
        urdf = yourdfpy.URDF.load(
            str(path), build_scene_graph=False, build_collision_scene_graph=False, load_meshes=False,
            load_collision_meshes=False,
        )  # fmt: skip
    except etree.XMLSyntaxError as error:
        raise ModelError(f"{path}: malformed XML ({error})") from None
    except Exception as error:  # yourdfpy raises several kinds on bad content
        raise ModelError(f"{path}: not a valid URDF ({type(error).__name__}: {error})") from None
    return urdf.robot


def _origin(element: object) -> np.ndarray:
    origin = getattr(element, "origin", None)
    return np.eye(4) if origin is None else np.array(origin, dtype=float)


def _body(urdf_link: object, strict: bool) -> Inertial:
    """The link's mass properties in its own frame (URDF gives them in the inertial frame)."""
    inertial = urdf_link.inertial
    if inertial is None or inertial.mass is None:
        return Inertial(0.0, name=urdf_link.name)
    pose = _origin(inertial)
    rotation = pose[:3, :3]
    tensor = np.zeros((3, 3)) if inertial.inertia is None else np.array(inertial.inertia, dtype=float)
    return Inertial(inertial.mass, pose[:3, 3], rotation @ tensor @ rotation.T, urdf_link.name, strict)


def load_urdf(path: str | os.PathLike[str], strict: bool = True, gravity: object = (0.0, 0.0, -9.81)) -> Robot:
    """Read a URDF file into a Robot.

    Revolute, continuous, prismatic and fixed joints, in branching trees; fixed joints are
    merged into their parent body and the moving joints numbered depth first from the root,
    children in file order. ``<dynamics damping friction>`` become viscous and (symmetric)
    Coulomb friction. Mimic joints load as independent joints, with a warning naming them.
    Meshes are never loaded.

    Parameters
    ----------
    path : str or os.PathLike
        The URDF file.
    strict : bool, optional
        True (default) refuses inertias whose principal moments break the triangle
        inequality; False accepts them with a warning, as CAD exports sometimes carry.
    gravity : array_like, optional
        Acceleration of gravity in the world frame, 3 values (default [0, 0, -9.81]).

    Returns
    -------
    Robot
        The arm, named after the URDF's robot, one link per moving joint.

    Raises
    ------
    armdyn.ModelError
        When the file is missing, is malformed XML or not a valid URDF; when it has floating
        or planar joints, a joint of unknown type, a kinematic loop, a link defined twice, a
        joint naming an undefined link, more or fewer than one root link, or no moving joint;
        when a joint axis has no direction; and when a link's mass properties, friction or
        limits are invalid (see Inertial and Link).
    """
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{path}: no such URDF file")
    robot = _parse(path)
    links = {link.name: link for link in robot.links}
    for name in links:
        if sum(link.name == name for link in robot.links) > 1:
            raise ModelError(f"{path.name}: link '{name}' is defined more than once")
    children: dict[str, list] = {name: [] for name in links}
    parent_of: dict[str, str] = {}
    for joint in robot.joints:
        where = f"{path.name}: joint '{joint.name}'"
        if joint.type in ("floating", "planar"):
            raise ModelError(f"{where} is {joint.type}; armdyn models fixed-base arms (revolute, prismatic, fixed)")
        if joint.type not in _MOVING | {"fixed"}:
            raise ModelError(f"{where} has unknown type '{joint.type}'")
        for end in (joint.parent, joint.child):
            if end not in links:
                raise ModelError(f"{where} refers to link '{end}', which the file does not define")
        if joint.child in parent_of:
            raise ModelError(
                f"{where}: link '{joint.child}' already has parent joint '{parent_of[joint.child]}': "
                "a kinematic loop, which a tree cannot hold"
            )
        parent_of[joint.child] = joint.name
        children[joint.parent].append(joint)
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        raise ModelError(f"{path.name}: expected one root link, found {roots or 'none (the joints form a loop)'}")
    built: list[Link] = []
    mimics: list[str] = []
    # Depth-first walk. Each stack entry: (urdf joint, index of the moving parent, placement
    # of the joint in that parent's frame accumulated across fixed joints)
    stack = [(joint, -1, np.eye(4)) for joint in reversed(children[roots[0]])]
    while stack:
        joint, parent, prefix = stack.pop()
        placement = prefix @ _origin(joint)
        if joint.type == "fixed":
            child_body = _body(links[joint.child], strict).transformed(placement)
            if parent >= 0:
                owner = built[parent]
                built[parent] = _with_inertial(owner, owner.inertial + child_body)
            stack.extend((child, parent, placement) for child in reversed(children[joint.child]))
            continue
        if joint.mimic is not None:
            mimics.append(joint.name)
        built.append(_moving_link(path.name, joint, parent, placement, _body(links[joint.child], strict)))
        index = len(built) - 1
        stack.extend((child, index, np.eye(4)) for child in reversed(children[joint.child]))
    if mimics:
        warnings.warn(f"{path.name}: mimic joints {mimics} are loaded as independent joints", stacklevel=2)
    if not built:
        raise ModelError(f"{path.name}: the file has no revolute, continuous or prismatic joint")
    return Robot(built, name=robot.name, gravity=gravity, description=f"URDF {path.name}")


def _with_inertial(link: Link, inertial: Inertial) -> Link:
    import dataclasses

    return dataclasses.replace(link, inertial=inertial)


def _moving_link(file: str, joint: object, parent: int, placement: np.ndarray, body: Inertial) -> Link:
    where = f"{file}: joint '{joint.name}'"
    axis = np.array([1.0, 0.0, 0.0] if joint.axis is None else joint.axis, dtype=float)
    norm = np.linalg.norm(axis)
    if not np.isfinite(norm) or norm == 0:
        raise ModelError(f"{where}: axis {axis} has no direction")
    if abs(norm - 1.0) > 1e-6:
        warnings.warn(f"{where}: axis {axis} is not a unit vector; using its direction", stacklevel=3)
    kind = "prismatic" if joint.type == "prismatic" else "revolute"
    limits = (-np.inf, np.inf)
    if joint.type != "continuous" and joint.limit is not None and joint.limit.lower is not None:
        limits = (float(joint.limit.lower), float(joint.limit.upper))
    damping = friction = 0.0
    if joint.dynamics is not None:
        damping = float(joint.dynamics.damping or 0.0)
        friction = float(joint.dynamics.friction or 0.0)
    try:
        return Link(
            joint.name,
            Joint(kind, placement, axis / norm, name=joint.name),
            body,
            parent=parent,
            viscous=damping,
            coulomb=(friction, -friction),
            limits=limits,
        )
    except ModelError as error:
        raise ModelError(f"{file}: {error}") from None
