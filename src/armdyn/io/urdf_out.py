"""to_urdf(arm, path=None): an arm written as URDF, read back by armdyn.load_urdf with the same dynamics.

A URDF child link's frame is its joint's frame after the motion (``<origin>``, then the rotation
about or translation along ``<axis>``); an armdyn link frame may sit further on, by the joint's
``frame_offset`` (Appendix A: the standard Denavit-Hartenberg Tx(a) Rx(alpha)). The file therefore
uses the moved joint frames as its link frames: each joint's ``<origin>`` is its parent's
``frame_offset`` composed with its own ``placement``, each body's ``<inertial>`` is described in
that frame (centre of mass and inertia about it, in the frame's axes), and the tool frame, a fixed
joint to a link named "tool", is composed with the tool link's ``frame_offset``. Joint-space
dynamics (M, C, G, friction) are unchanged; the loaded arm's link frames are the joint frames. A
base transform becomes a fixed joint from a root link "world" to "base_link".

URDF has no gravity (a comment records it; pass it to ``load_urdf``), no asymmetric Coulomb
friction, motors, gears or the Stribeck and sigmoid friction laws: those go in an
``<armdyn:drive>`` element inside the joint (namespace ``urn:armdyn:urdf``), which other URDF
readers ignore and armdyn.load_urdf reads back. Numbers are written with ``repr``, the shortest
text that reads back as the same double; an ``<origin rpy>`` reproduces its rotation to 1e-15.
"""

from __future__ import annotations

import os
import reprlib
from collections.abc import Iterable
from math import atan2, hypot
from pathlib import Path

import numpy as np
from lxml import etree

from armdyn.errors import ModelError
from armdyn.model.arm import ArmModel, Link

ARMDYN_NAMESPACE = "urn:armdyn:urdf"
"""The XML namespace of the <armdyn:drive> element: friction and motors that <dynamics> cannot hold."""

# The number written where URDF requires one that armdyn does not have: an infinite joint limit, the
# <limit> effort and velocity (required by the URDF specification for revolute and prismatic joints)
UNBOUNDED = 1e16
_DRIVE = f"{{{ARMDYN_NAMESPACE}}}drive"


def rpy(rotation: np.ndarray) -> tuple[float, float, float]:
    """Fixed-axis roll, pitch and yaw of a rotation, as URDF's ``<origin rpy>`` reads them.

    R = Rz(yaw) Ry(pitch) Rx(roll). Pitch and yaw come from R's first column; roll from the
    remainder (Rz(yaw) Ry(pitch))^T R = Rx(roll), so that at and near pitch = +-pi/2 (where
    yaw and roll are not separable) the three still give R back to rounding.

    Parameters
    ----------
    rotation : numpy.ndarray
        A rotation matrix, (3, 3) (the upper-left block of a 4x4 pose is taken as well).

    Returns
    -------
    tuple of float
        (roll, pitch, yaw) in radians, pitch in [-pi/2, pi/2].
    """
    r = np.asarray(rotation, dtype=float)[:3, :3]
    pitch = atan2(-r[2, 0], hypot(r[0, 0], r[1, 0]))
    yaw = atan2(r[1, 0], r[0, 0])
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    rest = (
        np.array([[cp, 0.0, -sp], [0.0, 1.0, 0.0], [sp, 0.0, cp]])
        @ np.array([[cy, sy, 0.0], [-sy, cy, 0.0], [0.0, 0.0, 1.0]])
        @ r
    )
    return atan2(rest[2, 1], rest[1, 1]), pitch, yaw


def to_urdf(arm: ArmModel, path: str | os.PathLike[str] | None = None) -> str:
    """The arm as URDF text, written to ``path`` too when given.

    One ``<joint>`` and child ``<link>`` per joint of the arm, named after the joint
    ("<joint>_link"), parents before children so that load_urdf numbers them as the arm does
    (a tree whose order is not depth first loads back depth first); the tool as a fixed joint
    to a link "tool", so that ``load_urdf(path, gravity=arm.gravity, tool_link="tool")`` gives
    the arm's M(q), inverse dynamics with friction, G(q) and tool pose. Per joint:

    - ``<origin xyz rpy>``: the joint frame in the parent's frame (see the module docstring);
    - ``<axis>``; ``<limit lower upper effort velocity>`` (an infinite bound as +-1e16, effort
      and velocity, which armdyn does not model, as 1e16), or type continuous for a revolute
      joint without limits;
    - ``<dynamics damping friction>``: the joint-side viscous coefficient G^2 B and the Coulomb
      level |G| Tc+ when Tc- = -Tc+ (URDF's symmetric friction; otherwise damping only);
    - ``<armdyn:drive viscous coulomb motor_inertia gear_ratio stribeck sigmoid/>`` when the
      joint has what ``<dynamics>`` cannot hold: asymmetric Coulomb friction, a motor (Jm != 0
      or G != 1), Stribeck or sigmoid friction. It holds the Link's values as they are (B and
      Tc motor side); armdyn.load_urdf then uses it in place of ``<dynamics>``.

    Per link, ``<inertial>`` with its origin at the centre of mass (no rotation), the mass,
    and the inertia about the centre of mass. Lewis, Dawson and Abdallah 2004, Section 3.2
    (mass properties) and Appendix A (link frames).

    Parameters
    ----------
    arm : ArmModel
        A numeric arm (a Robot or any ArmModel).
    path : str or os.PathLike, optional
        The file to write (UTF-8); default None writes no file.

    Returns
    -------
    str
        The URDF text.

    Raises
    ------
    armdyn.ModelError
        When ``arm`` is not an ArmModel, or has symbolic (SymPy) parameters, which a URDF
        cannot hold; when the file cannot be written (the message names it).
    """
    if not isinstance(arm, ArmModel):
        raise ModelError(f"to_urdf needs an ArmModel (a Robot), got {reprlib.repr(arm)}")
    if arm.is_symbolic:
        raise ModelError(
            f"robot '{arm.name}' has symbolic (SymPy) parameters, and a URDF holds numbers: substitute numbers first"
        )
    links, joints = {"tool"}, set(arm.joint_names)
    has_base = not np.array_equal(arm.base, np.eye(4))
    root = _unique("world", links) if has_base else _unique("base_link", links)
    base = _unique("base_link", links) if has_base else root
    names = [_unique(f"{link.name}_link", links) for link in arm.links]
    robot = etree.Element("robot", name=arm.name, nsmap={"armdyn": ARMDYN_NAMESPACE})
    robot.append(etree.Comment(_comment(arm)))
    etree.SubElement(robot, "link", name=root)
    if has_base:
        _fixed(robot, _unique("base_joint", joints), root, base, arm.base)
        etree.SubElement(robot, "link", name=base)
    for index, link in enumerate(arm.links):
        parent = base if link.parent < 0 else names[link.parent]
        offset = np.eye(4) if link.parent < 0 else arm.links[link.parent].joint.frame_offset
        robot.append(_joint(link, parent, names[index], offset @ link.joint.placement))
        robot.append(_link(link, names[index]))
    tool_pose = arm.links[arm.tool_link].joint.frame_offset @ arm.tool
    _fixed(robot, _unique("tool_joint", joints), names[arm.tool_link], "tool", tool_pose)
    etree.SubElement(robot, "link", name="tool")
    etree.indent(robot, space="  ")
    text = '<?xml version="1.0" encoding="utf-8"?>\n' + etree.tostring(robot, encoding="unicode") + "\n"
    if path is not None:
        try:
            Path(path).write_text(text, encoding="utf-8")
        except OSError as error:
            raise ModelError(f"{path}: cannot write the URDF ({error.strerror or error})") from None
    return text


def _unique(name: str, taken: set[str]) -> str:
    """``name``, with underscores appended until it is not in ``taken``; then taken."""
    while name in taken:
        name += "_"
    taken.add(name)
    return name


def _numbers(values: Iterable[float]) -> str:
    """Numbers as URDF text: each by repr, the shortest text that reads back as the same double."""
    return " ".join(repr(float(value)) for value in values)


def _comment(arm: ArmModel) -> str:
    """The header comment: the arm, its gravity (which URDF cannot hold) and how to load the file back."""
    about = f"{arm.name}: {arm.description}" if arm.description else arm.name
    gravity = ", ".join(repr(float(value)) for value in arm.gravity)
    text = (
        f" Written by armdyn from robot {about}. URDF has no gravity: this arm's gravity (world frame, m/s^2) is "
        f"({gravity}); load with armdyn.load_urdf(path, gravity=({gravity}), tool_link='tool'). <armdyn:drive> "
        "holds friction and motors that <dynamics> cannot; other readers ignore it. "
    )
    return text.replace("--", "- -").replace("--", "- -")  # an XML comment cannot hold '--'


def _origin(parent: etree._Element, pose: np.ndarray) -> None:
    etree.SubElement(parent, "origin", xyz=_numbers(pose[:3, 3]), rpy=_numbers(rpy(pose)))


def _fixed(robot: etree._Element, name: str, parent: str, child: str, pose: np.ndarray) -> None:
    joint = etree.SubElement(robot, "joint", name=name, type="fixed")
    etree.SubElement(joint, "parent", link=parent)
    etree.SubElement(joint, "child", link=child)
    _origin(joint, pose)


def _joint(link: Link, parent: str, child: str, pose: np.ndarray) -> etree._Element:
    """A moving joint: origin, axis, limits, URDF's friction and, when needed, armdyn's drive."""
    lower, upper = link.limits
    continuous = link.kind == "revolute" and lower == -np.inf and upper == np.inf
    joint = etree.Element("joint", name=link.name, type="continuous" if continuous else link.kind)
    etree.SubElement(joint, "parent", link=parent)
    etree.SubElement(joint, "child", link=child)
    _origin(joint, pose)
    etree.SubElement(joint, "axis", xyz=_numbers(link.joint.axis))
    if not continuous:
        bounds = [float(np.clip(value, -UNBOUNDED, UNBOUNDED)) for value in (lower, upper)]
        etree.SubElement(
            joint,
            "limit",
            lower=repr(bounds[0]),
            upper=repr(bounds[1]),
            effort=repr(UNBOUNDED),
            velocity=repr(UNBOUNDED),
        )
    gear = link.gear_ratio
    damping, (plus, minus) = gear**2 * link.viscous, link.coulomb
    symmetric = plus == -minus
    if damping != 0 or (symmetric and plus != 0):
        dynamics = etree.SubElement(joint, "dynamics", damping=repr(damping))
        if symmetric:
            dynamics.set("friction", repr(abs(gear) * plus))
    laws = _friction_laws(link)
    if laws or not symmetric or link.motor_inertia != 0 or gear != 1:
        drive = etree.SubElement(joint, _DRIVE)
        drive.set("viscous", repr(float(link.viscous)))
        drive.set("coulomb", _numbers(link.coulomb))
        drive.set("motor_inertia", repr(float(link.motor_inertia)))
        drive.set("gear_ratio", repr(float(gear)))
        for key, value in laws.items():
            drive.set(key, _numbers(value))
    return joint


def _friction_laws(link: Link) -> dict[str, tuple[float, ...]]:
    """The Stribeck and sigmoid friction of a link that has them (a Link field each, zero for none)."""
    laws = {}
    for key in ("stribeck", "sigmoid"):
        value = getattr(link, key, None)
        if value is not None and any(number != 0 for number in value):
            laws[key] = tuple(value)
    return laws


def _link(link: Link, name: str) -> etree._Element:
    """A link with its ``<inertial>`` in the joint frame: origin at the centre of mass, inertia about it."""
    offset = link.joint.frame_offset
    body = link.inertial if np.array_equal(offset, np.eye(4)) else link.inertial.transformed(offset)
    inertia = (body.inertia + body.inertia.T) / 2
    element = etree.Element("link", name=name)
    inertial = etree.SubElement(element, "inertial")
    etree.SubElement(inertial, "origin", xyz=_numbers(body.com), rpy="0.0 0.0 0.0")
    etree.SubElement(inertial, "mass", value=repr(float(body.mass)))
    moments = {key: repr(float(inertia[i, j])) for key, (i, j) in _MOMENTS.items()}
    etree.SubElement(inertial, "inertia", **moments)
    return element


_MOMENTS = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}
