"""to_mjcf(arm, path=None): an arm written as MuJoCo MJCF, so that MuJoCo computes the same dynamics.

The frames are those of armdyn.io.urdf_out: a MuJoCo body's frame is its joint's frame after the
motion (the body's ``pos``/``quat`` place the joint frame in the parent body, the joint sits at the
body's origin), while an armdyn link frame may sit further on, by the joint's ``frame_offset``
(Appendix A: the standard Denavit-Hartenberg Tx(a) Rx(alpha)). So each body's ``pos``/``quat`` is
its parent's ``frame_offset`` composed with its own ``placement`` (the base transform composed in
for the bodies at the root, which hang from MuJoCo's world body), each ``<inertial>`` is described
in that frame, and the tool, a site named "tool", is composed with the tool link's
``frame_offset``. Joint-space dynamics (M, C, G, friction) are unchanged.

MuJoCo holds the joint-side rotor inertia G^2 Jm (``armature``), viscous friction G^2 B
(``damping``) and symmetric Coulomb friction |G| Tc+ (``frictionloss``, MuJoCo's dry friction,
which its constraint solver applies; an asymmetric law is written at its mean level
(Tc+ - Tc-) / 2). It cannot hold asymmetric Coulomb friction, the Stribeck and sigmoid laws, or
the Link's own Jm, G, B and Tc (only their joint-side products): those go, as the Link keeps
them, in a ``<custom><numeric name="armdyn:link:<joint>">`` element (``LINK_NUMERIC``, fields
``LINK_FIELDS``), which MuJoCo keeps and ignores. A DC drive of an ActuatedArm is written as
MuJoCo's ``dcmotor`` actuator and kept exactly in ``armdyn:drive:<joint>`` (``DRIVE_NUMERIC``,
``DRIVE_FIELDS``).

MuJoCo refuses a moving body whose mass or principal moment of inertia about its centre of mass
is below mjMINVAL = 1e-15 (SI units), and ``fullinertia`` whose principal moments A <= B <= C are
below 1e-14 or break the triangle inequality A + B >= C; each body with a joint is checked with
only the bodies welded to it, and a sum of bodies that satisfy the inequality satisfies it, so no
arrangement of bodies holds a tensor that breaks it. Such bodies are written as follows (every
other body exactly):

- a body that only ever turns about one fixed axis a (every revolute joint from the base to it
  parallel: planar arms, a first link) feels only a^T I a: its inertia is written as
  max(a^T I a, MIN_INERTIA) times the identity, exact unless a^T I a is below MIN_INERTIA =
  2e-14 kg m^2 (a point mass);
- any other body: A raised to MIN_INERTIA (its tensor plus a multiple of the identity), and when
  A + B < C (the PUMA 560's third link, the Stanford arm's fifth) the excess d n n^T about C's
  axis n is taken out of the body and written as the ``armature`` d of a fixed tendon
  ``armdyn:inertia:<joint>`` (``INERTIA_TENDON``) of length sum_j c_j q_j, c_j = n . a_j over the
  revolute joints j from the base to the body, whose velocity is the body's angular velocity
  along n: exact when the c_j do not change with q (else the arm is refused);
- a mass below MIN_INERTIA is raised to it.

M(q) changes by at most a few 1e-14 kg m^2 per raised body. Numbers are written with ``repr``, the
shortest text that reads back as the same double; quaternions are full-precision.
"""

from __future__ import annotations

import dataclasses
import math
import os
import reprlib
import warnings
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, TypeGuard

import numpy as np
from lxml import etree

from armdyn import kinematics
from armdyn.actuators.hydraulics import Hydraulic
from armdyn.actuators.motors import DCMotor
from armdyn.errors import ModelError
from armdyn.io.urdf_out import UNBOUNDED, _friction_laws, _numbers, _unique
from armdyn.model.arm import ArmModel, Link
from armdyn.model.inertial import Inertial

if TYPE_CHECKING:
    from armdyn.actuators.arm import ActuatedArm

_Drive = DCMotor | Hydraulic

LINK_NUMERIC = "armdyn:link:"
"""The name prefix of the ``<numeric>`` element that keeps a joint's Link fields (followed by the joint's name)."""

LINK_FIELDS = (
    "viscous",
    "coulomb+",
    "coulomb-",
    "motor_inertia",
    "gear_ratio",
    "stribeck_Fs",
    "stribeck_vs",
    "sigmoid_A",
    "sigmoid_alpha",
    "sigmoid_shift",
)
"""The order of the numbers of an ``armdyn:link:<joint>`` element: the Link's B, (Tc+, Tc-), Jm, G (motor
side, as the Link keeps them), then the Stribeck (Fs, vs) and sigmoid (A, alpha, shift) friction (joint side)."""

DRIVE_NUMERIC = "armdyn:drive:"
"""The name prefix of the ``<numeric>`` element that keeps a joint's DC drive (followed by the joint's name)."""

DRIVE_FIELDS = (
    "rotor_inertia",
    "viscous",
    "torque_constant",
    "back_emf",
    "resistance",
    "inductance",
    "gear_ratio",
    "voltage_limit",
    "current_limit",
    "coulomb+",
    "coulomb-",
    "stiffness",
    "shaft_damping",
)
"""The order of the numbers of an ``armdyn:drive:<joint>`` element: the DCMotor's fields as it keeps them
(gear ratio r with q = r q_M; inf for no limit, and a stiffness of inf for a rigid shaft)."""

INERTIA_TENDON = "armdyn:inertia:"
"""The name prefix of the fixed tendon whose armature holds the part of a link's inertia that breaks the
triangle inequality (followed by the joint's name); see the module docstring."""

MIN_INERTIA = 2e-14
"""The smallest mass (kg) and principal moment of inertia (kg m^2) written for a moving body: twice the 1e-14
below which MuJoCo's ``fullinertia`` refuses a principal moment (mjMINVAL = 1e-15 for the mass), a margin
for the rounding of the principal moments."""


def to_mjcf(arm: ArmModel | ActuatedArm, path: str | os.PathLike[str] | None = None) -> str:
    """The arm as MuJoCo MJCF text, written to ``path`` too when given.

    A ``<body>`` per joint of the arm, named after the joint ("<joint>_link") and nested as the
    arm's tree, so that ``mujoco.MjModel.from_xml_string`` gives the arm's M(q), its bias
    C(q, qd) qd + G(q) (``qfrc_bias``), its inverse dynamics with viscous friction
    (``mj_inverse``) and its tool pose (the site "tool"). ``<option gravity>`` is the arm's
    gravity; MuJoCo's integrator and time step are left at their defaults. Per joint:

    - the body's ``pos`` and ``quat`` (w x y z): the joint frame in the parent body's frame (see
      the module docstring; the base transform is in those of the bodies at the root);
    - ``<joint type="hinge"|"slide" axis>`` at the body's origin, with ``range`` and
      ``limited="true"`` when a limit is finite (an infinite side written as +-1e16);
      ``armature`` G^2 Jm, ``damping`` G^2 B and ``frictionloss`` |G| (Tc+ - Tc-) / 2 (|G| Tc+ when
      Tc- = -Tc+);
    - ``<inertial pos mass fullinertia>``: the centre of mass and the inertia about it in the
      body's frame, where MuJoCo would refuse it (a point mass, a thin rod, a massless link, moments
      that break the triangle inequality) changed as the module docstring says: exactly, or
      with a fixed tendon ``armdyn:inertia:<joint>``, or by at most ``MIN_INERTIA``;
    - ``<numeric name="armdyn:link:<joint>" data>`` (``LINK_FIELDS``) when the joint has what
      MuJoCo cannot hold: asymmetric Coulomb friction, Stribeck or sigmoid friction, a motor
      (Jm != 0 or G != 1);
    - a ``<motor>`` actuator named after the joint with gear 1 (the control is the joint torque);
    - a capsule from the body's origin to each child's (and to the tool) for MuJoCo's viewer,
      without contacts (contype and conaffinity 0) or mass (``inertiafromgeom="false"``).

    An ActuatedArm (``armdyn.actuators.with_actuators``) is its arm with, per rigid DC drive, a
    ``<dcmotor>`` actuator in place of the motor: ``gear`` 1/r (MuJoCo's gear is the book's 1/r),
    ``resistance`` R_a, ``motorconst`` "K_M K_b", ``inductance`` "L 0" (one activation, the
    armature current), ``armature`` J_M and ``damping`` B_M (MuJoCo reflects both to the joint
    times gear^2), ``ctrlrange`` +-voltage limit when finite; the rotor's symmetric Coulomb
    friction adds |1/r| Tc+ to the joint's ``frictionloss``. The control is the voltage v. Each DC
    drive is kept as well in ``<numeric name="armdyn:drive:<joint>" data>`` (``DRIVE_FIELDS``).
    A current limit and asymmetric rotor Coulomb friction have no counterpart (MuJoCo's
    ``saturation`` clamps the torque, not the current loop; ``frictionloss`` is symmetric): the
    drive is written without them, with a warning. A drive with no MuJoCo counterpart (a flexible
    shaft, a hydraulic drive) gets no actuator, with a warning.
    Lewis, Dawson and Abdallah 2004, Sections 3.2 (mass properties) and 3.6 (actuators), and
    Appendix A (link frames).

    Parameters
    ----------
    arm : ArmModel or ActuatedArm
        A numeric arm (a Robot or any ArmModel), or an arm with its drives.
    path : str or os.PathLike, optional
        The file to write (UTF-8); default None writes no file.

    Returns
    -------
    str
        The MJCF text.

    Raises
    ------
    armdyn.ModelError
        When ``arm`` is neither an ArmModel nor an ActuatedArm, or has symbolic (SymPy)
        parameters; when a body's principal moments break the triangle inequality, which MuJoCo
        refuses, and no tendon can hold the excess (the message names the link); when the file
        cannot be written (the message names it).

    Warns
    -----
    UserWarning
        Naming the joints whose friction MuJoCo simulates differently (asymmetric Coulomb,
        Stribeck or sigmoid friction: only viscous and symmetric Coulomb friction are simulated),
        the drives without an actuator, and the DC drives with K_M != K_b (MuJoCo uses
        K = sqrt(K_M K_b) for both).
    """
    drives: Sequence[_Drive | None]
    if isinstance(arm, ArmModel):
        robot, drives = arm, [None] * arm.n
    elif _is_actuated(arm):
        robot, drives = arm.robot, arm.drives
    else:
        raise ModelError(f"to_mjcf needs an ArmModel (a Robot) or an ActuatedArm, got {reprlib.repr(arm)}")
    if robot.is_symbolic:
        raise ModelError(
            f"robot '{robot.name}' has symbolic (SymPy) parameters, and an MJCF holds numbers: substitute numbers first"
        )
    links = [_driven_link(link, drive) for link, drive in zip(robot.links, drives, strict=True)]
    _warn_friction(robot.name, links)
    root = etree.Element("mujoco", model=robot.name)
    root.append(etree.Comment(_comment(robot)))
    etree.SubElement(root, "compiler", angle="radian", inertiafromgeom="false", autolimits="true")
    etree.SubElement(root, "option", gravity=_numbers(robot.gravity))
    custom = etree.Element("custom")
    world = etree.SubElement(root, "worldbody")
    actuator = etree.Element("actuator")
    tendons = etree.Element("tendon")
    bodies = {"world"}
    names = [_unique(f"{link.name}_link", bodies) for link in links]
    elements: list[etree._Element] = []
    radius = _radius(robot)
    turning = _turning_axes(robot)
    for index, link in enumerate(links):
        parent_element = world if link.parent < 0 else elements[link.parent]
        before = robot.base if link.parent < 0 else links[link.parent].joint.frame_offset
        pose = before @ link.joint.placement
        body = etree.SubElement(parent_element, "body", name=names[index], **_pose(pose))
        if link.parent >= 0:
            _capsule(parent_element, pose[:3, 3], radius)
        body.append(_joint(link))
        inertia, excess, coefficients = _mujoco_inertia(robot, index, turning[index])
        body.append(_inertial(link, inertia))
        if excess:
            tendon = etree.SubElement(tendons, "fixed", name=INERTIA_TENDON + link.name, armature=repr(float(excess)))
            for joint, coefficient in reversed(coefficients.items()):
                etree.SubElement(tendon, "joint", joint=joint, coef=repr(coefficient))
        if _needs_numeric(link):
            etree.SubElement(
                custom, "numeric", name=LINK_NUMERIC + link.name, data=_numbers(_link_data(robot.links[index]))
            )
        elements.append(body)
    tool = links[robot.tool_link].joint.frame_offset @ robot.tool
    etree.SubElement(elements[robot.tool_link], "site", name="tool", **_pose(tool))
    _capsule(elements[robot.tool_link], tool[:3, 3], radius)
    _actuators(actuator, custom, robot, drives)
    if len(custom):
        root.insert(3, custom)
    if len(tendons):
        root.append(tendons)
    if len(actuator):
        root.append(actuator)
    etree.indent(root, space="  ")
    text = etree.tostring(root, encoding="unicode") + "\n"
    if path is not None:
        try:
            Path(path).write_text(text, encoding="utf-8")
        except OSError as error:
            raise ModelError(f"{path}: cannot write the MJCF ({error.strerror or error})") from None
    return text


def _is_actuated(arm: object) -> TypeGuard[ActuatedArm]:
    """Whether ``arm`` is an arm with drives (an ActuatedArm: its ``robot`` and one DCMotor or Hydraulic per
    joint), recognised by what it holds: armdyn.actuators.arm imports armdyn.robot, which calls this module, so
    the class is not imported here."""
    robot, drives = getattr(arm, "robot", None), getattr(arm, "drives", None)
    return (
        isinstance(robot, ArmModel)
        and isinstance(drives, tuple)
        and len(drives) == robot.n
        and all(isinstance(drive, (DCMotor, Hydraulic)) for drive in drives)
    )


def _pose(pose: np.ndarray) -> dict[str, str]:
    """A frame's ``pos`` and ``quat`` attributes."""
    return {"pos": _numbers(pose[:3, 3]), "quat": _numbers(kinematics.quaternion(pose))}


def _comment(robot: ArmModel) -> str:
    """The header comment: the arm and where armdyn keeps what MuJoCo cannot hold."""
    about = f"{robot.name}: {robot.description}" if robot.description else robot.name
    text = (
        f" Written by armdyn from robot {about}. Bodies are the joint frames; the site 'tool' is the tool frame. "
        f"<numeric> elements named {LINK_NUMERIC}<joint> and {DRIVE_NUMERIC}<joint> keep the friction, motors "
        "and drives as armdyn holds them. "
    )
    return text.replace("--", "- -").replace("--", "- -")  # an XML comment cannot hold '--'


def _joint(link: Link) -> etree._Element:
    """A hinge or slide joint at the body's origin: axis, range, armature, damping and dry friction (the mean
    level of an asymmetric Coulomb law)."""
    joint = etree.Element("joint", name=link.name, type="hinge" if link.kind == "revolute" else "slide")
    joint.set("axis", _numbers(link.joint.axis))
    lower, upper = link.limits
    if math.isfinite(lower) or math.isfinite(upper):
        joint.set("range", _numbers(float(np.clip(value, -UNBOUNDED, UNBOUNDED)) for value in (lower, upper)))
        joint.set("limited", "true")
    else:
        joint.set("limited", "false")
    gear = link.gear_ratio
    armature, damping, (plus, minus) = gear**2 * link.motor_inertia, gear**2 * link.viscous, link.coulomb
    if armature != 0:
        joint.set("armature", repr(float(armature)))
    if damping != 0:
        joint.set("damping", repr(float(damping)))
    level = plus if plus == -minus else (plus - minus) / 2  # asymmetric: MuJoCo's nearest, the mean level
    if level != 0:
        joint.set("frictionloss", repr(float(abs(gear) * level)))
    return joint


def _inertial(link: Link, inertia: np.ndarray) -> etree._Element:
    """The body's ``<inertial>`` in the joint frame: the centre of mass, the mass (at least MIN_INERTIA) and
    the inertia about the centre of mass as given."""
    body = _body(link)
    mass = max(float(body.mass), MIN_INERTIA)
    full = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]
    return etree.Element("inertial", pos=_numbers(body.com), mass=repr(mass), fullinertia=_numbers(full))


def _body(link: Link) -> Inertial:
    """The link's mass properties in its joint frame (the MuJoCo body's frame)."""
    offset = link.joint.frame_offset
    return link.inertial if np.array_equal(offset, np.eye(4)) else link.inertial.transformed(offset)


def _mujoco_inertia(robot: ArmModel, index: int, axis: np.ndarray | None) -> tuple[np.ndarray, float, dict[str, float]]:
    """(inertia written, excess d, tendon coefficients): the inertia about the centre of mass, unchanged when
    MuJoCo accepts it (principal moments A <= B <= C with A >= MIN_INERTIA and A + B >= C). Otherwise:

    - a body that only turns about the fixed unit ``axis`` (zero: never turns) feels a^T I a alone, written
      as max(a^T I a, MIN_INERTIA) times the identity;
    - any other body: A raised to MIN_INERTIA (the tensor plus a multiple of the identity), and when
      A + B < C the excess d n n^T about C's axis n taken out, so that C = A + B (to 1e-9), and written as
      the armature d of a fixed tendon sum_j c_j q_j whose velocity is n . omega, the body's angular velocity
      along n, when the c_j (n . a_j, a_j the axis of revolute joint j from the base to the body) are
      constant; the kinetic energy d (n . omega)^2 / 2 is then MuJoCo's tendon armature's.

    Raises armdyn.ModelError, naming the link, when the c_j change with q (no exact MJCF)."""
    link = robot.links[index]
    body = _body(link)
    inertia = (body.inertia + body.inertia.T) / 2
    moments, vectors = np.linalg.eigh(inertia)
    if moments[0] >= MIN_INERTIA and moments[0] + moments[1] >= moments[2]:
        return inertia, 0.0, {}
    if axis is not None:
        return max(float(axis @ inertia @ axis), MIN_INERTIA) * np.eye(3), 0.0, {}
    raised = max(MIN_INERTIA - moments[0], 0.0)
    inertia, moments = inertia + raised * np.eye(3), moments + raised
    excess = moments[2] - moments[0] - moments[1]
    if excess <= 0:
        return inertia, 0.0, {}
    excess += 1e-9 * moments[2]
    coefficients = _tendon(robot, index, vectors[:, 2])
    if coefficients is None:
        raise ModelError(
            f"link '{link.name}': principal moments {_numbers(moments)} break the triangle inequality "
            "(A + B >= C), which MuJoCo refuses, and the body turns about its largest moment's axis at rates "
            "that change with q, so no tendon can hold the excess: no exact MJCF"
        )
    n = vectors[:, 2]
    return inertia - excess * np.outer(n, n), float(excess), coefficients


def _tendon(robot: ArmModel, index: int, direction: np.ndarray) -> dict[str, float] | None:
    """The constant coefficients c_j = n . a_j (joint name -> c_j, zeros left out) of the revolute joints j
    from the base to link ``index``, n the unit ``direction`` in its joint frame; None when they change with q
    (checked at q = 0 and four random states)."""
    chain, j = [], index
    while j >= 0:
        chain.append(j)
        j = robot.links[j].parent
    rng = np.random.default_rng(0)
    states = [np.zeros(robot.n), *rng.uniform(-np.pi, np.pi, (4, robot.n))]
    rows = []
    for q in states:
        frames = kinematics.link_transforms(robot, q)
        joints = [frames[k] @ np.linalg.inv(robot.links[k].joint.frame_offset) for k in range(robot.n)]
        n_world = joints[index][:3, :3] @ direction
        rows.append(
            [
                float(n_world @ joints[k][:3, :3] @ robot.links[k].joint.axis)
                if robot.links[k].kind == "revolute"
                else 0.0
                for k in chain
            ]
        )
    table = np.array(rows)
    if np.abs(table - table[0]).max() > 1e-12:
        return None
    return {robot.links[k].name: float(c) for k, c in zip(chain, table[0], strict=True) if abs(c) > 1e-12}


def _turning_axes(robot: ArmModel) -> list[np.ndarray | None]:
    """Per link, the one axis (unit, in its joint frame) that the body turns about when every revolute joint
    from the base to it is parallel to it (rotations about parallel axes keep them parallel, so q = 0 tells);
    zeros for a body that never turns (prismatic joints only); None for a body that turns about more axes."""
    frames: list[np.ndarray] = []
    axes: list[np.ndarray | None] = []
    world: list[np.ndarray | None] = []  # the common revolute axis from the base, in the world frame
    for link in robot.links:
        before = robot.base if link.parent < 0 else frames[link.parent]
        joint = before @ link.joint.placement
        frames.append(joint @ link.joint.frame_offset)
        common = np.zeros(3) if link.parent < 0 else world[link.parent]
        if common is not None and link.kind == "revolute":
            mine = joint[:3, :3] @ link.joint.axis
            if not common.any():
                common = mine
            elif np.linalg.norm(np.cross(common, mine)) > 1e-14:
                common = None
        world.append(common)
        axes.append(None if common is None else joint[:3, :3].T @ common)
    return axes


def _needs_numeric(link: Link) -> bool:
    """Whether the joint has what MuJoCo cannot hold (where urdf_out writes <armdyn:drive>)."""
    symmetric = link.coulomb[0] == -link.coulomb[1]
    return bool(_friction_laws(link)) or not symmetric or link.motor_inertia != 0 or link.gear_ratio != 1


def _link_data(link: Link) -> list[float]:
    """The Link's fields in the order of LINK_FIELDS."""
    return [link.viscous, *link.coulomb, link.motor_inertia, link.gear_ratio, *link.stribeck, *link.sigmoid]


def _warn_friction(name: str, links: Iterable[Link]) -> None:
    """Warn, naming the joints, when MuJoCo will simulate their friction differently from armdyn."""
    different = [link.name for link in links if link.coulomb[0] != -link.coulomb[1] or _friction_laws(link)]
    if different:
        warnings.warn(
            f"to_mjcf('{name}'): joints {different} have asymmetric Coulomb, Stribeck or sigmoid friction, which "
            "MuJoCo cannot simulate (its frictionloss is symmetric dry friction, written at the mean Coulomb level "
            f"(Tc+ - Tc-) / 2): they are kept exactly in <numeric name='{LINK_NUMERIC}<joint>'> for armdyn",
            UserWarning,
            stacklevel=3,
        )


def _radius(robot: ArmModel) -> float:
    """The viewer capsules' radius: a twentieth of the arm's longest link, 1 cm when it has none."""
    lengths = [float(np.linalg.norm(link.joint.placement[:3, 3])) for link in robot.links]
    lengths += [float(np.linalg.norm(link.joint.frame_offset[:3, 3])) for link in robot.links]
    longest = max(lengths, default=0.0)
    return longest / 20 if longest > 0 else 0.01


def _capsule(body: etree._Element, end: np.ndarray, radius: float) -> None:
    """A capsule from the body's origin to ``end`` for the viewer (no contact, no mass); none for a point."""
    if float(np.linalg.norm(end)) > radius / 10:
        etree.SubElement(
            body,
            "geom",
            type="capsule",
            fromto=_numbers([0.0, 0.0, 0.0, *end]),
            size=repr(radius),
            contype="0",
            conaffinity="0",
            group="1",
        )


# ----- actuators ---------------------------------------------------------------------------------------------
def _dcmotor_counterpart(drive: _Drive | None) -> str:
    """Why a drive has no MuJoCo actuator ('' when it is a rigid DC drive that ``dcmotor`` holds)."""
    if drive is None:
        return ""
    if not isinstance(drive, DCMotor):
        return "a hydraulic drive"
    if drive.flexible:
        return "a flexible shaft"
    return ""


def _driven_link(link: Link, drive: _Drive | None) -> Link:
    """The Link as MuJoCo's joint sees it: a rigid DC drive, written as ``dcmotor`` (its armature and damping
    are the actuator's), adds its rotor's symmetric Coulomb friction |1/r| Tc+ to the joint's."""
    if not isinstance(drive, DCMotor) or drive.flexible:
        return link
    plus, minus = _pair(drive)
    if plus != -minus:  # MuJoCo's frictionloss is symmetric: the rotor's asymmetric friction is kept in the record
        return link
    extra = abs(1 / drive.gear_ratio) * plus
    return dataclasses.replace(link, coulomb=(link.coulomb[0] + extra, link.coulomb[1] - extra))


def _actuators(
    actuator: etree._Element, custom: etree._Element, robot: ArmModel, drives: Sequence[_Drive | None]
) -> None:
    """A motor per joint of a bare arm; a dcmotor per rigid DC drive of an ActuatedArm, with warnings."""
    names: set[str] = set()
    missing, constants, limited, asymmetric = [], [], [], []
    for link, drive in zip(robot.links, drives, strict=True):
        if drive is None:
            etree.SubElement(actuator, "motor", name=_unique(link.name, names), joint=link.name, gear="1")
            continue
        if isinstance(drive, DCMotor):
            etree.SubElement(custom, "numeric", name=DRIVE_NUMERIC + link.name, data=_numbers(_drive_data(drive)))
        why = _dcmotor_counterpart(drive)
        if why:
            missing.append(f"'{drive.name}' on joint '{link.name}' ({why})")
            continue
        assert isinstance(drive, DCMotor)
        if drive.torque_constant != drive.back_emf:
            constants.append(drive.name)
        if math.isfinite(drive.current_limit):
            limited.append(drive.name)
        plus, minus = _pair(drive)
        if plus != -minus:
            asymmetric.append(drive.name)
        motor = etree.SubElement(actuator, "dcmotor", name=_unique(drive.name, names), joint=link.name)
        motor.set("gear", repr(1 / drive.gear_ratio))
        motor.set("resistance", repr(float(drive.resistance)))
        motor.set("motorconst", _numbers([drive.torque_constant, drive.back_emf]))
        if drive.inductance != 0:
            motor.set("inductance", _numbers([drive.inductance, 0.0]))
        motor.set("armature", repr(float(drive.rotor_inertia)))
        motor.set("damping", repr(float(drive.viscous)))
        if math.isfinite(drive.voltage_limit):
            motor.set("ctrlrange", _numbers([-drive.voltage_limit, drive.voltage_limit]))
            motor.set("ctrllimited", "true")
    if missing:
        warnings.warn(
            f"to_mjcf('{robot.name}'): drives {', '.join(missing)} have no MuJoCo counterpart: no actuator is "
            "written for them",
            UserWarning,
            stacklevel=3,
        )
    if asymmetric:
        warnings.warn(
            f"to_mjcf('{robot.name}'): drives {asymmetric} have asymmetric rotor Coulomb friction, which MuJoCo's "
            "frictionloss (symmetric) does not hold: written without it (kept in <numeric name='armdyn:drive:...'>)",
            UserWarning,
            stacklevel=3,
        )
    if limited:
        warnings.warn(
            f"to_mjcf('{robot.name}'): drives {limited} have a current limit, which MuJoCo's dcmotor does not hold "
            "(its saturation clamps the torque, not the current loop): written without it",
            UserWarning,
            stacklevel=3,
        )
    if constants:
        warnings.warn(
            f"to_mjcf('{robot.name}'): drives {constants} have K_M != K_b; MuJoCo's dcmotor uses "
            "K = sqrt(K_M K_b) for both",
            UserWarning,
            stacklevel=3,
        )


def _drive_data(drive: DCMotor) -> list[float]:
    """A DC drive's fields in the order of DRIVE_FIELDS (a rigid shaft's stiffness as inf)."""
    stiffness = math.inf if drive.stiffness is None else drive.stiffness
    plus, minus = _pair(drive)
    return [
        drive.rotor_inertia,
        drive.viscous,
        drive.torque_constant,
        drive.back_emf,
        drive.resistance,
        drive.inductance,
        drive.gear_ratio,
        drive.voltage_limit,
        drive.current_limit,
        plus,
        minus,
        stiffness,
        drive.shaft_damping,
    ]


def _pair(drive: DCMotor) -> tuple[float, float]:
    """The rotor's Coulomb friction (Tc+, Tc-), as DCMotor keeps it once checked."""
    coulomb = drive.coulomb
    assert isinstance(coulomb, tuple), "DCMotor keeps its Coulomb friction as the pair (Tc+, Tc-)"
    return coulomb
