"""load_mjcf(path or text) and from_mujoco(model): a MuJoCo model read into a Robot through MuJoCo's own compiler.

armdyn has no MJCF parser of its own: the file goes through ``mujoco.MjModel.from_xml_path`` (or
``from_xml_string``), so defaults, classes, includes, ``fromto`` capsules and inertias computed from
geoms are exactly MuJoCo's, and the Robot is read from the compiled ``mjModel``:

- each body's frame in its parent's is ``body_pos``, ``body_quat``; its inertia ``body_mass``,
  ``body_ipos``, ``body_iquat`` and the principal moments ``body_inertia``;
- a hinge turns the body about the axis ``jnt_axis`` through the anchor ``jnt_pos`` by qpos - qpos0
  (qpos0 is the joint's ``ref``), a slide moves it along the axis: MuJoCo's forward kinematics. The
  armdyn joint frame sits at the anchor (placement ``T Trans(p) Rot(a, -ref)``) and its link frame
  goes back to the body frame (``frame_offset = Trans(-p)``), so armdyn's q is MuJoCo's qpos and its
  link frames are MuJoCo's body frames. Several joints in one body become a chain of links, the
  body's mass on the last; a body without joints is merged into the link that carries it (its mass
  added by the parallel-axis theorem); bodies welded to the world carry no dynamics;
- joint ``armature``, ``damping`` and ``frictionloss`` (dof_armature, dof_damping, dof_frictionloss)
  are the links' motor inertia (joint side, G = 1), viscous and symmetric Coulomb friction; the
  ``armature`` and ``damping`` of an actuator on the joint add gear^2 times theirs, as MuJoCo's M and
  passive force count them.

MuJoCo's dry friction ``frictionloss`` is a constraint with a soft solver, which approaches the
Coulomb law F = Tc sgn(qd) that armdyn uses; the other quantities are the same equations. A
``<custom><numeric name="armdyn:link:JOINT">`` written by armdyn.io.mjcf_out.to_mjcf carries the
link's friction and motor as armdyn keeps them (asymmetric Coulomb, Stribeck, sigmoid, Jm and G) and
is read in place of the joint's attributes.
"""

from __future__ import annotations

import os
import reprlib
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn import inputs, kinematics
from armdyn.errors import MissingDependencyError, ModelError
from armdyn.io.mjcf_out import DRIVE_FIELDS, DRIVE_NUMERIC, INERTIA_TENDON, LINK_FIELDS, LINK_NUMERIC
from armdyn.io.urdf_out import UNBOUNDED
from armdyn.model.arm import Link
from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint
from armdyn.model.sources import Geom, record_geometry
from armdyn.robot import Robot

if TYPE_CHECKING:
    from armdyn.actuators.arm import ActuatedArm
    from armdyn.actuators.motors import DCMotor

# mjtJoint and mjtTrn values (MuJoCo's enums, read from the package when it is there)
_FREE, _BALL, _SLIDE, _HINGE = 0, 1, 2, 3
_VOLTAGE_INPUT = 8  # mjINPUT_VOLTAGE: the plain voltage-commanded dcmotor


def _mujoco() -> Any:
    """The mujoco package, or a MissingDependencyError naming the extra that installs it."""
    try:
        import mujoco
    except ImportError:
        raise MissingDependencyError("mujoco", "mjcf", needed_by="armdyn.load_mjcf (MuJoCo's compiler)") from None
    return mujoco


def load_mjcf(
    source: str | os.PathLike[str],
    gravity: object = None,
    tool_link: str | None = None,
    locked: Mapping[str, object] | None = None,
    strict: bool = True,
    drives: bool = False,
) -> Robot | ActuatedArm:
    """Read a MuJoCo MJCF model (a file, or its XML text) into a Robot, through MuJoCo's compiler.

    The file is compiled by ``mujoco.MjModel.from_xml_path`` (text by ``from_xml_string``, its
    includes and assets relative to the working directory) and read by ``from_mujoco``: one
    fixed-base kinematic tree of hinge and slide joints, numbered as MuJoCo numbers its degrees of
    freedom, so that M(q), the bias C(q, qd) qd + G(q) and inverse dynamics equal MuJoCo's at
    q = qpos, qd = qvel (Lewis, Dawson and Abdallah 2004, eq. 3.2.30; Section 3.6 for the drives).
    MuJoCo also compiles URDF files, so a ``.urdf`` path is read as MuJoCo reads it. The model's geoms are
    recorded with the arm (``armdyn.model.sources.geometry_of``), and the viewer draws them.

    Parameters
    ----------
    source : str or os.PathLike
        The MJCF file, or MJCF text (a string that starts with '<').
    gravity : array_like, optional
        Gravity in the world frame, 3 values (default None: the model's ``<option gravity>``, zero
        when the model disables gravity).
    tool_link : str, optional
        A body or site of the model whose frame is the tool (default None: the body of the last
        joint).
    locked : mapping of str to value, optional
        Joints held fixed, by name: a hinge or slide to its value (rad or m, as
        ``load_urdf(locked=)``); a free joint of a body on the world to its pose
        [x, y, z, qw, qx, qy, qz] in the world frame, or None for its qpos0 (the body's pose in the
        file): the floating base becomes the arm's fixed base there (default None).
    strict : bool, optional
        As ``load_urdf``: refuse joints that move no mass in any configuration (default True).
    drives : bool, optional
        False (default): the Robot, whose input is the joint torque. True: the arm with its
        drives (an ``armdyn.actuators.ActuatedArm``), every joint driven by one MuJoCo
        ``dcmotor`` (see ``from_mujoco``).

    Returns
    -------
    Robot or armdyn.actuators.ActuatedArm
        The arm, named after the model; with ``drives``, the arm with its DC drives.

    Raises
    ------
    armdyn.ModelError
        When the file is missing, or MuJoCo cannot compile it (MuJoCo's message, which names a
        missing mesh or a bad element and its line, with the file named); and as ``from_mujoco``.
    armdyn.MissingDependencyError
        When the ``mujoco`` package is not installed (``pip install 'armdyn[mjcf]'``).
    TypeError
        When ``source`` is not a str or os.PathLike.

    Warns
    -----
    UserWarning
        As ``from_mujoco``.
    """
    mujoco = _mujoco()
    text, path = _source(source)
    where = "the MJCF text" if path is None else str(path)
    try:
        model = mujoco.MjModel.from_xml_string(text) if path is None else mujoco.MjModel.from_xml_path(str(path))
    except ValueError as error:
        message = " ".join(str(error).split())
        raise ModelError(f"{where}: MuJoCo cannot compile it: {message}") from None
    return _read(model, gravity, tool_link, locked, strict, drives, where if path is None else path.name)


def _source(source: object) -> tuple[str | None, Path | None]:
    """(text, None) for MJCF text, (None, path) for a file that exists; the errors name the file."""
    if isinstance(source, str) and source.lstrip().startswith("<"):
        return source, None
    try:
        name = os.fspath(source)  # type: ignore[call-overload]
    except TypeError:
        raise TypeError(
            f"source must be MJCF text or a str or os.PathLike naming the file, got {type(source).__name__}"
        ) from None
    path = Path(os.fsdecode(name))
    if not path.is_file():
        raise ModelError(f"{path}: no such MJCF file; check the path")
    return None, path


@dataclass
class _Moving:
    """What becomes one Link: the joint, its parent link, its friction, the mass it carries."""

    name: str
    kind: str
    placement: np.ndarray
    axis: np.ndarray
    offset: np.ndarray
    parent: int
    joint_id: int
    body: Inertial = field(default_factory=Inertial)


def from_mujoco(
    model: object,
    gravity: object = None,
    tool_link: str | None = None,
    locked: Mapping[str, object] | None = None,
    strict: bool = True,
    drives: bool = False,
) -> Robot | ActuatedArm:
    """A compiled MuJoCo model (``mujoco.MjModel``) as a Robot, or with ``drives`` as the arm with its drives.

    Hinge and slide joints in a tree of bodies (see the module docstring for the frames); joint
    ``armature``, ``damping`` and ``frictionloss`` become each link's motor inertia (G = 1),
    viscous and symmetric Coulomb friction, an actuator's ``armature`` and ``damping`` adding
    gear^2 times theirs. Refused, by name: ball joints, free joints (unless locked, on a body of the
    world), tendons and equality constraints (a loop closed by ``connect`` or ``weld``, a coupling
    by ``joint``), none of which a serial-chain robot equation holds, unless they hold only locked
    joints (a fixed tendon over locked joints, an equality between them, a ``connect`` or ``weld``
    within one rigid part: a gripper with its fingers locked).

    With ``drives``, every joint must be driven by one ``dcmotor`` actuator, which becomes a DC drive
    of Section 3.6 (Lewis, Dawson and Abdallah 2004; armdyn.actuators.DCMotor): MuJoCo's gear g
    (joint torque g K i, rotor speed g qd) is the ratio r = 1/g; resistance R; the one motor
    constant K = sqrt(Kt Ke) MuJoCo keeps is both K_M and K_b; the inductance L = R tau_e (zero
    without electrical dynamics); the rotor inertia J_M is the actuator's armature plus the
    joint's armature / g^2, the rotor's viscous friction B_M the actuator's damping (the joint's
    damping and frictionloss stay at the joint); a symmetric ``ctrlrange`` is the voltage limit.
    Settings without a counterpart in that drive (cogging, LuGre friction, the thermal model, the
    on-board controller and inputs other than the voltage, a force or current saturation, an
    asymmetric ctrlrange, a delay) are named in a warning; ``motor``, ``position``, ``velocity``
    and other actuators have no DC-drive counterpart (an ideal torque source, a servo law) and are
    refused with ``drives``, by name; without ``drives`` the Robot's input is the joint torque and
    actuators only add their armature and damping.

    Parameters
    ----------
    model : mujoco.MjModel
        The compiled model.
    gravity : array_like, optional
        Gravity in the world frame, 3 values (default None: ``model.opt.gravity``, zero when the
        model disables gravity).
    tool_link : str, optional
        A body or site whose frame is the tool (default None: the body of the last joint).
    locked : mapping of str to value, optional
        Joints held fixed, by name (see ``load_mjcf``).
    strict : bool, optional
        Refuse joints that move no mass in any configuration (default True; see ``load_urdf``).
    drives : bool, optional
        Return the arm with its DC drives (default False: the Robot).

    Returns
    -------
    Robot or armdyn.actuators.ActuatedArm
        The arm; with ``drives``, the arm with its DC drives.

    Raises
    ------
    armdyn.ModelError
        When ``model`` is not a mujoco.MjModel; when it has a ball joint, a free joint that is not
        locked (or not on a body of the world), a tendon or an equality constraint that holds a joint
        that moves (named); when
        ``locked`` names no joint of the model or holds a bad value; when ``tool_link`` is neither a
        body nor a site, or is welded to the world; when gravity is not 3 finite numbers; when no
        joint moves; with ``strict``, when joints move no mass; with ``drives``, when a joint has no
        dcmotor or one of another kind (named).
    armdyn.MissingDependencyError
        When the ``mujoco`` package is not installed.

    Warns
    -----
    UserWarning
        Joint springs (``stiffness``), gravity compensation (``gravcomp``) and polynomial damping,
        which the robot equation here does not hold; and, with ``drives``, dcmotor settings without
        a counterpart.
    """
    return _read(model, gravity, tool_link, locked, strict, drives, "the MuJoCo model")


def _read(
    model: object,
    gravity: object,
    tool_link: str | None,
    locked: Mapping[str, object] | None,
    strict: bool,
    drives: bool,
    _where: str,
) -> Robot | ActuatedArm:
    """from_mujoco, its messages naming ``_where`` (the file, the text, or the model)."""
    mujoco = _mujoco()
    if not isinstance(model, mujoco.MjModel):
        raise ModelError(f"model must be a mujoco.MjModel (from_mujoco), got {reprlib.repr(model)}")
    names = [_joint_name(model, j) for j in range(model.njnt)]
    locked = _check_locked(model, names, locked, _where)
    _refuse_what_a_tree_cannot_hold(mujoco, model, {names.index(key) for key in locked}, _where)
    if gravity is None:
        disabled = model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_GRAVITY
        gravity = np.zeros(3) if disabled else np.array(model.opt.gravity, dtype=float)
    gravity = inputs.numbers(gravity, "gravity", (3,))
    _warn_without_counterpart(model, names, _where)
    moving, frames = _tree(mujoco, model, names, locked, _where)
    if not moving:
        raise ModelError(f"{_where}: the model has no hinge or slide joint that moves")
    custom = _custom(mujoco, model, LINK_NUMERIC, LINK_FIELDS, _where)
    recorded = _custom(mujoco, model, DRIVE_NUMERIC, DRIVE_FIELDS, _where) if drives else {}
    links = [_link(model, item, custom.get(item.name), drives, _where) for item in moving]
    links = [
        _without_rotor_friction(link, recorded[link.name], _where)
        if link.name in recorded and link.name not in custom
        else link
        for link in links
    ]
    tool_index, tool = _tool_frame(mujoco, model, frames, tool_link, _where)
    name = _model_name(model) or "mujoco model"
    robot = Robot(links, name=name, gravity=gravity, tool=tool, tool_link=tool_index, description=f"MJCF {_where}")
    robot = _fold_inertia_tendons(mujoco, model, robot, names, _where)
    hinges = {key: value for key, value in locked.items() if model.jnt_type[names.index(key)] in (_HINGE, _SLIDE)}
    if hinges:
        try:
            robot = robot.reduced(hinges)
        except ModelError as error:
            raise ModelError(f"{_where}: {error}") from None
    _check_singular(robot, strict, _where)
    record_geometry(robot, _geometry(mujoco, model, robot, names, locked))
    if not drives:
        return robot
    from armdyn.actuators.arm import with_actuators

    return with_actuators(
        robot,
        [
            _recorded_drive(recorded[joint], joint, _where)
            if joint in recorded
            else _dc_drive(mujoco, model, names.index(joint), _where)
            for joint in robot.joint_names
        ],
    )


# ----- what a fixed-base tree of hinges and slides cannot hold -------------------------------------------------
def _refuse_what_a_tree_cannot_hold(mujoco: Any, model: Any, locked: set[int], where: str) -> None:
    """Ball joints, tendons and equality constraints, refused by name (free joints are checked with ``locked``).

    What constrains nothing that moves passes: a fixed tendon over locked joints only (a gripper's coupling with
    its fingers locked), a joint or tendon equality between locked joints (a URDF's mimic joint), a connect or
    weld between two bodies on the same link once the locked joints are fixed; and armdyn's inertia tendons."""
    balls = [_joint_name(model, j) for j in range(model.njnt) if model.jnt_type[j] == _BALL]
    if balls:
        raise ModelError(
            f"{where}: ball joints {balls}: armdyn models arms of hinge and slide joints (one coordinate each); "
            "model a ball joint as three hinges, or lock it by removing it from the file"
        )
    tendons = [
        _name(mujoco, model, mujoco.mjtObj.mjOBJ_TENDON, t, "tendon")
        for t in range(model.ntendon)
        if not _is_inertia_tendon(mujoco, model, t) and not _over_locked_joints(mujoco, model, t, locked)
    ]
    if tendons:
        raise ModelError(
            f"{where}: tendons {tendons}: a tendon couples joints (or closes a loop), which the robot equation of a "
            "kinematic tree does not hold; remove the tendons (and the actuators on them), or lock their joints"
        )
    constraints = [
        f"{_name(mujoco, model, mujoco.mjtObj.mjOBJ_EQUALITY, e, 'equality')} ({_equality(mujoco, model, e)})"
        for e in range(model.neq)
        if not _holds_nothing_that_moves(mujoco, model, e, locked)
    ]
    if constraints:
        raise ModelError(
            f"{where}: equality constraints {constraints}: a connect or weld closes a kinematic loop and a joint or "
            "tendon equality couples joints, which a kinematic tree does not hold; remove them, or lock the joints "
            "they couple (or those of the loop)"
        )


def _tendon_joints(mujoco: Any, model: Any, t: int) -> set[int] | None:
    """The joints of a fixed tendon; None for a spatial one (sites, geoms, pulleys: not joints alone)."""
    start, count = int(model.tendon_adr[t]), int(model.tendon_num[t])
    wraps = range(start, start + count)
    if any(int(model.wrap_type[w]) != int(mujoco.mjtWrap.mjWRAP_JOINT) for w in wraps):
        return None
    return {int(model.wrap_objid[w]) for w in wraps}


def _over_locked_joints(mujoco: Any, model: Any, t: int, locked: set[int]) -> bool:
    """Whether tendon t is a fixed tendon over locked joints only (its length then never changes)."""
    joints = _tendon_joints(mujoco, model, t)
    return joints is not None and joints <= locked


def _holds_nothing_that_moves(mujoco: Any, model: Any, e: int, locked: set[int]) -> bool:
    """Whether equality e constrains only what the locked joints hold still (see _refuse_what_a_tree_cannot_hold)."""
    kind, ends = int(model.eq_type[e]), [int(i) for i in (model.eq_obj1id[e], model.eq_obj2id[e]) if i >= 0]
    if kind == int(mujoco.mjtEq.mjEQ_JOINT):
        return set(ends) <= locked
    if kind == int(mujoco.mjtEq.mjEQ_TENDON):
        return all(_over_locked_joints(mujoco, model, t, locked) for t in ends)
    if kind in (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD)):
        on_sites = int(model.eq_objtype[e]) == int(mujoco.mjtObj.mjOBJ_SITE)
        bodies = [int(model.site_bodyid[i]) if on_sites else i for i in ends] + [0] * (2 - len(ends))
        return _moved_by(model, bodies[0], locked) == _moved_by(model, bodies[1], locked)
    return False


def _moved_by(model: Any, body: int, locked: set[int]) -> int:
    """The last joint that moves a body, once the locked joints are fixed (-1: none, the body is the world's)."""
    while body > 0:
        first, count = int(model.body_jntadr[body]), int(model.body_jntnum[body])
        for j in reversed(range(first, first + count)):
            if j not in locked:
                return j
        body = int(model.body_parentid[body])
    return -1


def _equality(mujoco: Any, model: Any, e: int) -> str:
    """An equality constraint's kind, and for a joint equality the joints it couples."""
    kind = mujoco.mjtEq(int(model.eq_type[e])).name.removeprefix("mjEQ_").lower()
    if kind != "joint":
        return kind
    joints = [_joint_name(model, int(j)) for j in (model.eq_obj1id[e], model.eq_obj2id[e]) if j >= 0]
    return f"joint {' and '.join(joints)}"


def _is_inertia_tendon(mujoco: Any, model: Any, t: int) -> bool:
    """Whether tendon t is one that armdyn.io.mjcf_out.to_mjcf writes for an inertia MuJoCo refuses: named
    ``armdyn:inertia:JOINT``, fixed (joints only), with an armature and nothing else (no spring, damping,
    friction, limit or actuator)."""
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TENDON, t) or ""
    start, count = int(model.tendon_adr[t]), int(model.tendon_num[t])
    joints_only = all(int(model.wrap_type[w]) == int(mujoco.mjtWrap.mjWRAP_JOINT) for w in range(start, start + count))
    on_tendon = int(mujoco.mjtTrn.mjTRN_TENDON)
    driven = any(
        int(model.actuator_trntype[a]) == on_tendon and model.actuator_trnid[a, 0] == t for a in range(model.nu)
    )
    passive = model.tendon_stiffness[t] == 0 and model.tendon_damping[t] == 0 and model.tendon_frictionloss[t] == 0
    return name.startswith(INERTIA_TENDON) and joints_only and passive and not model.tendon_limited[t] and not driven


def _fold_inertia_tendons(mujoco: Any, model: Any, robot: Robot, names: list[str], where: str) -> Robot:
    """The armature d of each ``armdyn:inertia:JOINT`` tendon, sum_j c_j q_j, put back into that joint's link as
    the inertia d n n^T about its centre of mass: exact when n . omega = sum_j c_j qd_j at every state (omega the
    link's angular velocity in its frame; n is found from the link's angular Jacobian at random states, and
    the tendon refused, by name, when no n fits). The link's inertia then breaks the triangle inequality, as
    the arm's did before ``to_mjcf`` wrote it (Inertial with strict=False: a warning names the link)."""
    links = list(robot.links)
    inertia_tendons = [t for t in range(model.ntendon) if _is_inertia_tendon(mujoco, model, t)]
    for t in inertia_tendons:
        tendon = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TENDON, t)
        joint = tendon.removeprefix(INERTIA_TENDON)
        if joint not in robot.joint_names:
            raise ModelError(f"{where}: tendon '{tendon}' names joint '{joint}', which the arm does not have")
        index = robot.joint_names.index(joint)
        coefficients = np.zeros(robot.n)
        start, count = int(model.tendon_adr[t]), int(model.tendon_num[t])
        for w in range(start, start + count):
            coefficients[robot.joint_names.index(names[int(model.wrap_objid[w])])] += float(model.wrap_prm[w])
        states = np.random.default_rng(0).uniform(-np.pi, np.pi, (6, robot.n))
        angular = kinematics.jacobian(robot, states, frame="tool", link=index)[:, 3:, :]  # omega in the link frame
        rows = angular.transpose(0, 2, 1).reshape(-1, 3)  # n . omega = c . qd for every qd: J^T n = c
        n = np.linalg.lstsq(rows, np.tile(coefficients, len(states)), rcond=None)[0]
        if np.abs(rows @ n - np.tile(coefficients, len(states))).max() > 1e-9 * max(np.abs(coefficients).max(), 1):
            raise ModelError(
                f"{where}: tendon '{tendon}' is no inertia of link '{joint}': its length's rate is not the link's "
                "angular velocity along one direction of the link"
            )
        body = links[index].inertial
        inertia = body.inertia + float(model.tendon_armature[t]) * np.outer(n, n)
        links[index] = replace(links[index], inertial=Inertial(body.mass, body.com, inertia, name=joint, strict=False))
    return robot.replace(links) if inertia_tendons else robot


def _check_locked(model: Any, names: list[str], locked: object, where: str) -> dict[str, Any]:
    """``locked`` as a dict of joint names of the model; a free joint must be locked, on a body of the world."""
    if locked is None:
        locked = {}
    if not isinstance(locked, Mapping):
        raise ModelError(f"{where}: locked must be a mapping of joint name to value, got {reprlib.repr(locked)}")
    for key in locked:
        if key not in names:
            raise ModelError(f"{where}: cannot lock joint {key!r}: the model has no such joint (its joints: {names})")
    for j, name in enumerate(names):
        if model.jnt_type[j] != _FREE:
            continue
        body = int(model.jnt_bodyid[j])
        if model.body_parentid[body] != 0:
            raise ModelError(
                f"{where}: free joint '{name}' of body '{_body_name(model, body)}' is not on a body of the world; "
                "armdyn models fixed-base arms"
            )
        if name not in locked:
            raise ModelError(
                f"{where}: free joint '{name}' makes body '{_body_name(model, body)}' a floating base; armdyn models "
                f"fixed-base arms: lock it with locked={{'{name}': None}} (its pose in the file) or "
                f"locked={{'{name}': [x, y, z, qw, qx, qy, qz]}} (its pose in the world)"
            )
    return dict(locked)


def _warn_without_counterpart(model: Any, names: list[str], where: str) -> None:
    """A warning naming the joint springs, gravity compensation and polynomial damping the Robot leaves out."""
    springs = [names[j] for j in range(model.njnt) if model.jnt_stiffness[j] != 0]
    compensated = [_body_name(model, b) for b in range(model.nbody) if model.body_gravcomp[b] != 0]
    polynomial = [names[j] for j in range(model.njnt) if np.any(model.dof_dampingpoly[model.jnt_dofadr[j]] != 0)]
    for items, what in (
        (springs, "joints with springs (stiffness), which the robot equation here leaves out"),
        (compensated, "bodies with gravity compensation (gravcomp), which the robot equation here leaves out"),
        (polynomial, "joints with polynomial damping (dampingpoly), of which only the linear term is kept"),
    ):
        if items:
            warnings.warn(f"{where}: {what}: {items}", stacklevel=4)


# ----- the tree ---------------------------------------------------------------------------------------------
def _tree(
    mujoco: Any, model: Any, names: list[str], locked: dict[str, Any], where: str
) -> tuple[list[_Moving], dict[str, tuple[int, np.ndarray]]]:
    """The moving joints in MuJoCo's order and, per body, (the link that carries it or -1, its pose there)."""
    moving: list[_Moving] = []
    # per body: (index of the link whose frame carries it, -1 for the world; the body frame in that frame)
    frames: dict[int, tuple[int, np.ndarray]] = {0: (-1, np.eye(4))}
    for body in range(1, model.nbody):
        owner, prefix = frames[int(model.body_parentid[body])]
        prefix = prefix @ _pose(mujoco, model.body_pos[body], model.body_quat[body])
        for j in range(model.body_jntadr[body], model.body_jntadr[body] + model.body_jntnum[body]):
            kind, anchor, axis = int(model.jnt_type[j]), model.jnt_pos[j], np.array(model.jnt_axis[j], dtype=float)
            reference = float(model.qpos0[model.jnt_qposadr[j]]) if kind in (_HINGE, _SLIDE) else 0.0
            if kind == _FREE:  # locked (checked): the body's pose in the world
                owner, prefix = -1, _free_pose(mujoco, model, j, locked[names[j]], names[j], where)
                continue
            if kind == _HINGE:
                placement = prefix @ _translation(anchor) @ kinematics.joint_motion(True, axis, np.array(-reference))
                offset = _translation(-np.asarray(anchor, dtype=float))
            else:
                placement, offset = prefix @ kinematics.joint_motion(False, axis, np.array(-reference)), np.eye(4)
            moving.append(
                _Moving(names[j], "revolute" if kind == _HINGE else "prismatic", placement, axis, offset, owner, j)
            )
            owner, prefix = len(moving) - 1, np.eye(4)
        frames[body] = (owner, prefix)
        if owner >= 0:
            moving[owner].body = moving[owner].body + _body_inertial(mujoco, model, body).transformed(prefix)
    named = {_body_name(model, body): frame for body, frame in frames.items() if body > 0}
    return moving, named


def _body_inertial(mujoco: Any, model: Any, body: int) -> Inertial:
    """A body's mass, centre of mass and inertia about it, in the body frame."""
    axes = _rotation(mujoco, model.body_iquat[body])
    inertia = axes @ np.diag(model.body_inertia[body]) @ axes.T
    return Inertial(
        float(model.body_mass[body]), np.array(model.body_ipos[body]), inertia, name=_body_name(model, body)
    )


def _free_pose(mujoco: Any, model: Any, joint: int, value: object, name: str, where: str) -> np.ndarray:
    """The world pose a locked free joint holds its body at: [x, y, z, qw, qx, qy, qz], or qpos0 for None."""
    if value is None:
        address = model.jnt_qposadr[joint]
        value = model.qpos0[address : address + 7]
    pose = inputs.numbers(value, f"locked['{name}']", (7,), where=f" in {where}")
    norm = float(np.linalg.norm(pose[3:]))
    if norm == 0:
        raise ModelError(f"{where}: locked['{name}'] holds the quaternion 0 0 0 0, which is no rotation")
    return _pose(mujoco, pose[:3], pose[3:] / norm)


def _link(model: Any, item: _Moving, custom: np.ndarray | None, drives: bool, where: str) -> Link:
    """The Link of one moving joint: frames, limits, armature, damping and dry friction (or armdyn's own numbers)."""
    j, dof = item.joint_id, int(model.jnt_dofadr[item.joint_id])
    lower, upper = (float(v) for v in model.jnt_range[j]) if model.jnt_limited[j] else (-np.inf, np.inf)
    # a bound of UNBOUNDED (1e16) or beyond is none: what to_mjcf and to_urdf write for a half-limited joint
    lower, upper = (-np.inf if lower <= -UNBOUNDED else lower), (np.inf if upper >= UNBOUNDED else upper)
    gears = [a for a in range(model.nu) if _drives_joint(model, a, j)]
    reflected = [float(model.actuator_gear[a, 0]) ** 2 for a in gears]
    armature = float(model.dof_armature[dof])
    damping = float(model.dof_damping[dof])
    if not drives:  # with drives the dcmotor's rotor goes to the drive
        armature += sum(g2 * float(model.actuator_armature[a]) for g2, a in zip(reflected, gears, strict=True))
        damping += sum(g2 * float(model.actuator_damping[a]) for g2, a in zip(reflected, gears, strict=True))
    friction: dict[str, Any] = {"viscous": damping, "coulomb": (float(model.dof_frictionloss[dof]),) * 2}
    friction["coulomb"] = (friction["coulomb"][0], -friction["coulomb"][1])
    if armature and not drives:  # with drives the joint's armature is the rotor's (see _dc_drive)
        friction["motor_inertia"] = armature
    if custom is not None:
        v, tc_plus, tc_minus, jm, g, fs, vs, a, alpha, shift = (float(x) for x in custom)
        friction = {
            "viscous": v, "coulomb": (tc_plus, tc_minus), "motor_inertia": jm, "gear_ratio": g,
            "stribeck": (fs, vs), "sigmoid": (a, alpha, shift),
        }  # fmt: skip
    try:
        joint = Joint(item.kind, item.placement, item.axis / np.linalg.norm(item.axis), item.offset, name=item.name)
        return Link(item.name, joint, item.body, parent=item.parent, limits=(lower, upper), **friction)
    except ModelError as error:
        raise ModelError(f"{where}: {error}") from None


def _custom(mujoco: Any, model: Any, prefix: str, fields: tuple[str, ...], where: str) -> dict[str, np.ndarray]:
    """What armdyn.io.mjcf_out.to_mjcf kept as armdyn holds it, by joint: ``<numeric name="PREFIX JOINT">``
    (``armdyn:link:`` a Link's friction and motor, ``armdyn:drive:`` a DC drive), each holding its fields."""
    found = {}
    for k in range(model.nnumeric):
        name = _name(mujoco, model, mujoco.mjtObj.mjOBJ_NUMERIC, k, "numeric")
        if not name.startswith(prefix):
            continue
        start, size = int(model.numeric_adr[k]), int(model.numeric_size[k])
        if size != len(fields):
            raise ModelError(
                f"{where}: <numeric name='{name}'> holds {size} numbers; it must hold {len(fields)}: {' '.join(fields)}"
            )
        found[name.removeprefix(prefix)] = np.array(model.numeric_data[start : start + size], dtype=float)
    return found


def _tool_frame(
    mujoco: Any, model: Any, frames: dict[str, tuple[int, np.ndarray]], tool_link: object, where: str
) -> tuple[int | None, np.ndarray | None]:
    """(tool_link index, tool pose in that link's frame) for a body or site named ``tool_link`` (None: default)."""
    if tool_link is None:
        return None, None
    sites = {_name(mujoco, model, mujoco.mjtObj.mjOBJ_SITE, s, "site"): s for s in range(model.nsite)}
    if isinstance(tool_link, str) and tool_link in frames:
        index, pose = frames[tool_link]
    elif isinstance(tool_link, str) and tool_link in sites:
        site = sites[tool_link]
        index, pose = frames[_body_name(model, int(model.site_bodyid[site]))]
        pose = pose @ _pose(mujoco, model.site_pos[site], model.site_quat[site])
    else:
        raise ModelError(
            f"{where}: tool_link {tool_link!r} is neither a body nor a site of the model (its bodies: {list(frames)}; "
            f"its sites: {list(sites)})"
        )
    if index < 0:
        raise ModelError(
            f"{where}: tool_link '{tool_link}' is welded to the world (no joint moves it), so it cannot carry a tool; "
            "name a body or site that some joint moves"
        )
    return index, pose


def _check_singular(robot: Robot, strict: bool, where: str) -> None:
    """Joints that move no mass in any configuration: refused with ``strict``, else a warning (as load_urdf)."""
    from armdyn.urdf import _massless_joints

    massless = _massless_joints(robot)
    if not massless:
        return
    message = (
        f"{where}: joints {massless} move no mass or inertia in any configuration, so the inertia matrix M(q) is "
        "singular for every q and forward dynamics is undefined"
    )
    if strict and robot.has_dynamics:
        raise ModelError(message + "; give the bodies they move mass off their axes, or pass strict=False")
    warnings.warn(message + "; loaded as given", stacklevel=4)


# ----- what the viewer draws ------------------------------------------------------------------------------------
_DRAWN = {2: "sphere", 3: "capsule", 4: "ellipsoid", 5: "cylinder", 6: "box", 7: "mesh"}  # mjtGeom values


def _geometry(mujoco: Any, model: Any, robot: Robot, names: list[str], locked: dict[str, Any]) -> list[Geom]:
    """The model's geoms on the arm's links, each posed in the frame of the link that carries it: the visual geoms
    (neither colliding nor collided with) when the model has any, else every geom; planes, height fields and the
    world body's geoms (the scene) left out. Each pose is read from MuJoCo's forward kinematics and armdyn's at
    one configuration (qpos0, the locked joints at their values), which fixes it, the geom being rigid on its link."""
    data = mujoco.MjData(model)
    qpos = np.array(model.qpos0, dtype=float)
    for name, value in locked.items():
        j = names.index(name)
        address = int(model.jnt_qposadr[j])
        if model.jnt_type[j] == _FREE:
            qpos[address : address + 7] = model.qpos0[address : address + 7] if value is None else value
        else:
            qpos[address] = float(value)  # type: ignore[arg-type]
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    q = np.array([qpos[model.jnt_qposadr[names.index(joint)]] for joint in robot.joint_names])
    frames = robot.link_transforms(q)
    still = {j for j in range(model.njnt) if names[j] not in robot.joint_names}  # locked (or a locked free joint)
    visual = (model.geom_contype == 0) & (model.geom_conaffinity == 0)
    chosen = visual if visual.any() else np.ones(model.ngeom, dtype=bool)
    geoms = []
    for g in np.flatnonzero(chosen):
        kind, body = _DRAWN.get(int(model.geom_type[g])), int(model.geom_bodyid[g])
        if kind is None or body == 0:
            continue
        mover = _moved_by(model, body, still)
        link = robot.joint_names.index(names[mover]) if mover >= 0 else -1
        world = np.eye(4)
        world[:3, :3], world[:3, 3] = np.reshape(data.geom_xmat[g], (3, 3)), data.geom_xpos[g]
        frame = robot.base if link < 0 else frames[link]
        vertices = faces = None
        if kind == "mesh":
            mesh = int(model.geom_dataid[g])
            start, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
            vertices = np.array(model.mesh_vert[start : start + count], dtype=np.float32)
            start, count = int(model.mesh_faceadr[mesh]), int(model.mesh_facenum[mesh])
            faces = np.array(model.mesh_face[start : start + count], dtype=np.uint32)
        pose = np.linalg.solve(frame, world)
        geoms.append(Geom(link, kind, pose, np.array(model.geom_size[g]), vertices, faces, model.geom(g).name, int(g)))
    return geoms


def _drives_joint(model: Any, actuator: int, joint: int) -> bool:
    """Whether the actuator acts on the joint itself (a joint transmission)."""
    joint_transmissions = (0, 1)  # mjTRN_JOINT, mjTRN_JOINTINPARENT
    return (
        int(model.actuator_trntype[actuator]) in joint_transmissions and int(model.actuator_trnid[actuator, 0]) == joint
    )


def _dc_drive(mujoco: Any, model: Any, joint: int, where: str) -> DCMotor:
    """The DC drive of Section 3.6 that a joint's one dcmotor actuator is (see from_mujoco for the mapping)."""
    from armdyn.actuators.motors import DCMotor

    name = _joint_name(model, joint)
    actuators = [a for a in range(model.nu) if _drives_joint(model, a, joint)]
    kinds = [_actuator_kind(mujoco, model, a) for a in actuators]
    if len(actuators) != 1 or kinds[0] != "dcmotor":
        found = ", ".join(f"'{_actuator_name(mujoco, model, a)}' ({k})" for a, k in zip(actuators, kinds, strict=True))
        raise ModelError(
            f"{where}: drives=True needs one dcmotor actuator on every joint; joint '{name}' has "
            f"{found or 'none'}. A motor is an ideal torque source and a position or velocity actuator a servo law, "
            "neither a drive of Section 3.6: load with drives=False, whose input is the joint torque"
        )
    a = actuators[0]
    actuator = _actuator_name(mujoco, model, a)
    gear = float(model.actuator_gear[a, 0])
    resistance, constant = float(model.actuator_gainprm[a, 0]), float(model.actuator_gainprm[a, 1])
    electrical = int(model.actuator_dyntype[a]) == int(mujoco.mjtDyn.mjDYN_DCMOTOR)
    inductance = resistance * float(model.actuator_dynprm[a, 0]) if electrical else 0.0
    dof = int(model.jnt_dofadr[joint])
    voltage_limit = _voltage_limit(mujoco, model, a, actuator, where)
    return DCMotor(
        rotor_inertia=float(model.actuator_armature[a]) + float(model.dof_armature[dof]) / gear**2,
        viscous=float(model.actuator_damping[a]),
        torque_constant=constant,
        back_emf=constant,
        resistance=resistance,
        inductance=inductance,
        gear_ratio=1.0 / gear,
        voltage_limit=voltage_limit,
        name=actuator,
    )


def _recorded_drive(numbers: np.ndarray, joint: str, where: str) -> DCMotor:
    """The DC drive armdyn.io.mjcf_out.to_mjcf kept in ``armdyn:drive:JOINT`` (its fields, ``DRIVE_FIELDS``)."""
    from armdyn.actuators.motors import DCMotor

    J_M, B_M, K_M, K_b, R, L, r, v_max, i_max, plus, minus, stiffness, B_s = (float(x) for x in numbers)
    try:
        return DCMotor(
            J_M, B_M, K_M, K_b, R, L, r, voltage_limit=v_max, current_limit=i_max, coulomb=(plus, minus),
            stiffness=None if stiffness == np.inf else stiffness, shaft_damping=B_s, name=f"motor {joint}",
        )  # fmt: skip
    except ModelError as error:
        raise ModelError(f"{where}: <numeric name='{DRIVE_NUMERIC}{joint}'>: {error}") from None


def _without_rotor_friction(link: Link, numbers: np.ndarray, where: str) -> Link:
    """The joint's friction without the share |1/r| Tc+ that to_mjcf added to ``frictionloss`` for a rigid drive
    written as a dcmotor (the drive, read back from its record, carries it again)."""
    r, plus, minus, stiffness = float(numbers[6]), float(numbers[9]), float(numbers[10]), float(numbers[11])
    if stiffness != np.inf or r == 0 or plus != -minus:  # to_mjcf adds only a rigid drive's symmetric friction
        return link
    share = abs(1.0 / r) * plus
    level = link.coulomb[0] - share
    if level < -1e-9 * share:
        raise ModelError(
            f"{where}: joint '{link.name}': its frictionloss {link.coulomb[0]:g} is below the share {share:g} of the "
            f"rotor's Coulomb friction that <numeric name='{DRIVE_NUMERIC}{link.name}'> records"
        )
    try:
        return replace(link, coulomb=(max(level, 0.0), -max(level, 0.0)))
    except ModelError as error:
        raise ModelError(f"{where}: {error}") from None


def _voltage_limit(mujoco: Any, model: Any, a: int, actuator: str, where: str) -> float:
    """A symmetric ctrlrange as the voltage limit; the dcmotor settings without a counterpart, named in a warning."""
    without = []
    if np.any(model.actuator_biasprm[a] != 0):
        without.append("cogging or LuGre friction")
    if np.any(model.actuator_gainprm[a, 2:] != 0) or np.any(model.actuator_dynprm[a, 1:] != 0):
        without.append("the thermal model, the controller or a current-rate limit")
    if int(model.actuator_ctrlspec[a]) != _VOLTAGE_INPUT:
        without.append("inputs other than the terminal voltage")
    if model.actuator_forcelimited[a]:
        without.append(f"the force saturation {tuple(float(v) for v in model.actuator_forcerange[a])}")
    if model.actuator_delay[a] != 0 if hasattr(model, "actuator_delay") else False:
        without.append("a control delay")
    if np.any(model.actuator_dampingpoly[a] != 0):
        without.append("polynomial damping")
    limit = float("inf")
    if model.actuator_ctrllimited[a]:
        low, high = (float(v) for v in model.actuator_ctrlrange[a])
        if low == -high:
            limit = high
        else:
            without.append(f"the asymmetric ctrlrange ({low:g}, {high:g})")
    if without:
        warnings.warn(
            f"{where}: dcmotor '{actuator}' has settings without a counterpart in armdyn's DC drive, left out: "
            + "; ".join(without),
            stacklevel=5,
        )
    return limit


def _actuator_kind(mujoco: Any, model: Any, a: int) -> str:
    """An actuator's shortcut: dcmotor, motor, position, velocity or general (what its gain and bias say)."""
    gain, bias = int(model.actuator_gaintype[a]), int(model.actuator_biastype[a])
    if gain == int(mujoco.mjtGain.mjGAIN_DCMOTOR):
        return "dcmotor"
    if gain == int(mujoco.mjtGain.mjGAIN_FIXED) and bias == int(mujoco.mjtBias.mjBIAS_AFFINE):
        return "velocity" if model.actuator_biasprm[a, 1] == 0 else "position"
    if gain == int(mujoco.mjtGain.mjGAIN_FIXED) and bias == int(mujoco.mjtBias.mjBIAS_NONE):
        return "motor"
    return "general"


# ----- small pieces -------------------------------------------------------------------------------------------
def _rotation(mujoco: Any, quaternion: object) -> np.ndarray:
    """The rotation matrix of a unit quaternion (w, x, y, z), by MuJoCo's own mju_quat2Mat."""
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, np.asarray(quaternion, dtype=float))
    return matrix.reshape(3, 3)


def _pose(mujoco: Any, position: object, quaternion: object) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = _rotation(mujoco, quaternion), np.asarray(position, dtype=float)
    return pose


def _translation(vector: object) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = np.asarray(vector, dtype=float)
    return pose


def _name(mujoco: Any, model: Any, kind: Any, index: int, what: str) -> str:
    return mujoco.mj_id2name(model, kind, index) or f"{what} {index}"


def _joint_name(model: Any, joint: int) -> str:
    """A joint's name; an unnamed joint is named after its body (and its place there when the body has several)."""
    name = model.joint(joint).name
    if name:
        return str(name)
    body = int(model.jnt_bodyid[joint])
    first, count = int(model.body_jntadr[body]), int(model.body_jntnum[body])
    suffix = "" if count == 1 else f"_{joint - first}"
    return f"{_body_name(model, body)}_joint{suffix}"


def _body_name(model: Any, body: int) -> str:
    return str(model.body(body).name) or f"body {body}"


def _actuator_name(mujoco: Any, model: Any, a: int) -> str:
    return _name(mujoco, model, mujoco.mjtObj.mjOBJ_ACTUATOR, a, "actuator")


def _model_name(model: Any) -> str:
    return bytes(model.names[: bytes(model.names).index(b"\0")]).decode() if model.names else ""
