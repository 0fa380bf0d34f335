"""load_urdf(path) -> Robot, read from the XML with lxml; meshes are never loaded.

Revolute, continuous (one coordinate, the angle), prismatic and fixed joints; branching
trees. Fixed joints are merged into their parent body (parallel-axis theorem). Joints
are numbered depth first from the root, children in file order. Every number that reaches
the model is checked finite where it is read, so an error names the element; joints that
move no mass in any configuration (a singular M(q)) are found after the arm is built.
Locked joints (``locked``) are fixed by ArmModel.reduced once the whole arm is built; the
tool may sit on any link (``tool_link``), a merged one included. A joint's ``<armdyn:drive>``
element (namespace ``ARMDYN_NAMESPACE``, written by armdyn.io.urdf_out.to_urdf) carries the
friction and motor that ``<dynamics>`` cannot hold; other URDF readers ignore it.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn import inputs
from armdyn.dynamics import lagrange
from armdyn.errors import ModelError
from armdyn.io.urdf_out import ARMDYN_NAMESPACE
from armdyn.model.arm import Link
from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint
from armdyn.model.sources import record_source
from armdyn.robot import Robot

if TYPE_CHECKING:
    from lxml import etree

_MOVING = {"revolute", "continuous", "prismatic"}
# The XML namespace of armdyn's URDF extension, declared as xmlns:armdyn on <robot>
# <armdyn:drive> attributes: the Link field each gives and how many numbers it holds
_DRIVE = {"viscous": 1, "coulomb": 2, "motor_inertia": 1, "gear_ratio": 1, "stribeck": 2, "sigmoid": 3}
# The test for joints that move no mass: M(q) is factored at this many random configurations
# (a fixed seed, so that loading is deterministic); a pivot counts as zero below these.
_SAMPLES, _SEED = 4, 20240531
_PIVOT_RELATIVE = 1e-9  # of the joint's own diagonal entry M_jj
_DIAGONAL_RELATIVE = 1e-13  # of the largest diagonal entry of M
# The 3-vectors of the file that reach the model, checked on the XML itself before it is read
# (so that _pose and _read_joint meet exactly 3 numbers, each small enough to square): (element, child, attributes)
_VECTORS = (
    ("joint", "origin", ("xyz", "rpy")),
    ("joint", "axis", ("xyz",)),
    ("link", "inertial/origin", ("xyz", "rpy")),
)
# <inertia> attributes: the URDF specification requires all six (a default of 1 kg m^2 for a missing
# moment would be an invented inertia; Pinocchio refuses such a file too)
_MOMENTS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


# ----- what load_urdf reads of the file: <robot>, its <link> and <joint> elements ---------------------------------
# (the rest, <visual>, <collision>, <material>, <transmission>, <gazebo>, <calibration>, <safety_controller>,
# never reaches the model and is not read)
@dataclass(frozen=True)
class _Inertial:
    """A link's ``<inertial>``."""

    origin: np.ndarray | None  # 4x4 pose of the inertial frame in the link frame; None when <origin> is absent
    mass: float | None  # None when <mass> is absent: the link is massless
    inertia: np.ndarray | None  # 3x3 in the inertial frame; None when <inertia> is absent (zero)


@dataclass(frozen=True)
class _Link:
    name: str
    inertial: _Inertial | None  # None when <inertial> is absent: the link is massless


@dataclass(frozen=True)
class _Limit:
    lower: float | None  # None when the attribute is absent (the specification: 0)
    upper: float | None


@dataclass(frozen=True)
class _Dynamics:
    damping: str | None  # the attribute's text, read by _finite (absent or empty: 0)
    friction: str | None


@dataclass(frozen=True)
class _Joint:
    name: str
    type: str | None  # as written; load_urdf refuses all but revolute, continuous, prismatic and fixed
    parent: str | None  # the link attribute of <parent> and <child>
    child: str | None
    origin: np.ndarray | None  # 4x4 pose of the joint frame in the parent link frame; None when <origin> is absent
    axis: np.ndarray  # as written; 1 0 0 when <axis> (the specification) or its xyz is absent
    limit: _Limit | None
    dynamics: _Dynamics | None
    mimic: bool  # whether the joint has a <mimic> element
    drive: dict[str, str] | None = None  # the attributes of its <armdyn:drive>, None when absent


@dataclass(frozen=True)
class _Robot:
    name: str
    links: list[_Link]
    joints: list[_Joint]


def _parse(path: Path) -> _Robot:
    from lxml import etree

    try:  # strictly: a URDF with broken XML is refused, not recovered
        root = etree.parse(str(path)).getroot()
    except etree.XMLSyntaxError as error:
        raise ModelError(f"{path}: malformed XML ({error})") from None
    except OSError as error:  # lxml's for bytes that are not in the file's encoding (UTF-8 unless declared)
        raise ModelError(
            f"{path}: cannot be read as XML ({error}); a URDF is text, in UTF-8 unless its <?xml?> declaration "
            "names another encoding"
        ) from None
    if root.tag != "robot":
        raise ModelError(f"{path}: not a URDF: the root element is <{root.tag}>, where a URDF has <robot name='...'>")
    if not root.get("name"):
        raise ModelError(
            f"{path}: the <robot> element has no name, which the URDF specification requires "
            "(Pinocchio's parser refuses it too); add name='...' to <robot>"
        )
    _check_vectors(root, path.name)
    links = [_read_link(element, path) for element in root.iterfind("link")]
    return _Robot(root.get("name"), links, [_read_joint(element, path) for element in root.iterfind("joint")])


def _name(element: etree._Element, path: Path) -> str:
    """The name attribute of a <link> or <joint>, which the URDF specification requires."""
    name = element.get("name")
    if name is None:
        raise ModelError(
            f"{path}: not a valid URDF: the <{element.tag}> element on line {element.sourceline} has no name, which "
            f"the URDF specification requires; add name='...' to it"
        )
    return name


def _number(element: etree._Element, attribute: str, default: float | None, where: str, what: str) -> float | None:
    """An attribute read as a number (Python's float: NaN and infinity pass, for the checks that name them), or
    ``default`` when it is absent; refused unless it is a number."""
    text = element.get(attribute)
    if text is None:
        return default
    try:
        return float(text)
    except ValueError:
        raise ModelError(
            f"{where}: {what} {attribute} is '{text}', not a number; write a finite number in the file"
        ) from None


def _pose(origin: etree._Element | None) -> np.ndarray | None:
    """The 4x4 pose an ``<origin xyz rpy>`` gives (each 0 0 0 when absent), None for no element.

    rpy are fixed-axis roll, pitch, yaw: R = Rz(yaw) Ry(pitch) Rx(roll), written out term by term as trimesh's
    euler_matrix (axes 'sxyz', which yourdfpy used) writes it, so the poses are those of earlier versions to the
    bit. Both vectors are 3 numbers (``_check_vectors``); NaN or infinity pass here, to be refused by ``_origin``
    naming the joint or link."""
    if origin is None:
        return None
    xyz = [float(word) for word in origin.get("xyz", "0 0 0").split()]
    roll, pitch, yaw = np.array([float(word) for word in origin.get("rpy", "0 0 0").split()])
    with np.errstate(invalid="ignore"):  # sin and cos of infinity are NaN, refused by _origin
        si, sj, sk = np.sin(roll), np.sin(pitch), np.sin(yaw)
        ci, cj, ck = np.cos(roll), np.cos(pitch), np.cos(yaw)
    cc, cs, sc, ss = ci * ck, ci * sk, si * ck, si * sk
    pose = np.eye(4)
    pose[:3, :3] = [
        [cj * ck, sj * sc - cs, sj * cc + ss],
        [cj * sk, sj * ss + cc, sj * cs - sc],
        [-sj, cj * si, cj * ci],
    ]
    pose[:3, 3] = xyz
    return pose


def _read_link(element: etree._Element, path: Path) -> _Link:
    name = _name(element, path)
    found = element.find("inertial")
    if found is None:
        return _Link(name, None)
    where = f"{path.name}: link '{name}'"
    mass = found.find("mass")
    inertia = found.find("inertia")
    tensor = None
    if inertia is not None:
        moments = {key: _number(inertia, key, None, where, "<inertial><inertia>") for key in _MOMENTS}
        missing = [key for key in _MOMENTS if moments[key] is None]
        if missing:
            raise ModelError(
                f"{where}: <inertial><inertia> lacks {', '.join(missing)}; the URDF specification requires all six "
                "(ixx ixy ixz iyy iyz izz): write them in the file"
            )
        tensor = np.array(
            [
                [moments["ixx"], moments["ixy"], moments["ixz"]],
                [moments["ixy"], moments["iyy"], moments["iyz"]],
                [moments["ixz"], moments["iyz"], moments["izz"]],
            ]
        )
    return _Link(
        name,
        _Inertial(
            _pose(found.find("origin")),
            None if mass is None else _number(mass, "value", 0.0, where, "<inertial><mass>"),
            tensor,
        ),
    )


def _read_joint(element: etree._Element, path: Path) -> _Joint:
    name = _name(element, path)
    where = f"{path.name}: joint '{name}'"
    ends = []
    for end in ("parent", "child"):
        found = element.find(end)
        if found is None:
            raise ModelError(
                f"{path}: not a valid URDF: joint '{name}' has no <{end}> element, which the URDF specification "
                f"requires; add <{end} link='...'/> to it"
            )
        ends.append(found.get("link"))
    axis = element.find("axis")  # absent: 1 0 0 (the specification); without xyz, 1 0 0 too (urdfdom reads 0 0 0)
    xyz = "1 0 0" if axis is None else axis.get("xyz", "1 0 0")
    limit = element.find("limit")
    if limit is not None:
        for attribute in ("effort", "velocity"):  # never reach the model, but must be numbers as in any URDF
            _number(limit, attribute, None, where, "<limit>")
        limit = _Limit(*(_number(limit, bound, None, where, "<limit>") for bound in ("lower", "upper")))
    dynamics = element.find("dynamics")
    if dynamics is not None:
        dynamics = _Dynamics(dynamics.get("damping"), dynamics.get("friction"))
    mimic = element.find("mimic")
    if mimic is not None:  # loaded as an independent joint; multiplier and offset must be numbers all the same
        for attribute in ("multiplier", "offset"):
            _number(mimic, attribute, None, where, "<mimic>")
    origin = _pose(element.find("origin"))
    axis = np.array([float(word) for word in xyz.split()])
    parent, child = ends
    drive = element.find(f"{{{ARMDYN_NAMESPACE}}}drive")
    attributes = None if drive is None else {str(key): str(value) for key, value in drive.attrib.items()}
    return _Joint(
        name, element.get("type"), parent, child, origin, axis, limit, dynamics, mimic is not None, attributes
    )


def _check_vectors(root: etree._Element, file: str) -> None:
    """Refuse an xyz, rpy or axis of the file that reaches the model (``_VECTORS``) unless it is
    3 numbers, each below LARGEST_STATE (1e15) in magnitude where finite: products of larger
    values overflow. NaN and infinity are left to the checks that name them (``_origin``,
    ``_moving_link``)."""
    for kind, child, attributes in _VECTORS:
        for element in root.iterfind(kind):
            found = element.find(child)
            if found is None:
                continue
            tags = "".join(f"<{tag}>" for tag in child.split("/"))
            for attribute in attributes:
                text = found.get(attribute)
                if text is not None:
                    _check_vector(text, f"{file}: {kind} '{element.get('name')}': {tags} {attribute} '{text}'")


def _check_vector(text: str, where: str) -> None:
    """One xyz, rpy or axis attribute's text must be 3 numbers, none of them finite yet 1e15 or more in magnitude."""
    try:
        values = [float(word) for word in text.split()]
    except ValueError:
        raise ModelError(f"{where} is not 3 numbers separated by spaces") from None
    if len(values) != 3:
        raise ModelError(f"{where} holds {len(values)} numbers where the URDF specification has 3")
    if any(np.isfinite(value) and abs(value) >= inputs.LARGEST_STATE for value in values):
        raise ModelError(
            f"{where} holds a value of {inputs.LARGEST_STATE:.0e} or more in magnitude: beyond the range the "
            "dynamics are computed in (metres and radians); write smaller values"
        )


def _origin(element: _Joint | _Inertial, where: str) -> np.ndarray:
    """The pose an element's ``<origin>`` gives (identity when absent), refused unless finite."""
    pose = np.eye(4) if element.origin is None else element.origin.copy()
    if not np.all(np.isfinite(pose)):
        raise ModelError(f"{where}: <origin> has a NaN or infinite xyz or rpy; write finite numbers in the file")
    return pose


def _finite(value: str | float, where: str, what: str) -> float:
    """``value`` as a float, refused with a ModelError naming ``where`` and ``what`` unless finite."""
    try:
        number = float(value)  # the file's <dynamics> damping and friction reach here as text
    except (TypeError, ValueError):
        raise ModelError(f"{where}: {what} is '{value}', not a number; write a finite number in the file") from None
    if not np.isfinite(number):
        raise ModelError(f"{where}: {what} is {number}, not a finite number; write a finite number in the file")
    return number


def _body(file: str, urdf_link: _Link, strict: bool) -> Inertial:
    """The link's mass properties in its own frame (URDF gives them in the inertial frame)."""
    where = f"{file}: link '{urdf_link.name}'"
    inertial = urdf_link.inertial
    if inertial is None or inertial.mass is None:
        return Inertial(0.0, name=urdf_link.name)
    mass = _finite(inertial.mass, where, "<inertial><mass> value")
    pose = _origin(inertial, f"{where}: <inertial>")
    rotation = pose[:3, :3]
    tensor = np.zeros((3, 3)) if inertial.inertia is None else inertial.inertia
    if not np.all(np.isfinite(tensor)):
        raise ModelError(
            f"{where}: <inertial><inertia> holds NaN or infinite values ({tensor[np.triu_indices(3)]}); "
            "write finite ixx ixy ixz iyy iyz izz in the file"
        )
    try:
        return Inertial(mass, pose[:3, 3], rotation @ tensor @ rotation.T, urdf_link.name, strict)
    except ModelError as error:
        raise ModelError(f"{file}: {error}") from None


def load_urdf(
    path: str | os.PathLike[str],
    strict: bool = True,
    gravity: object = (0.0, 0.0, -9.81),
    tool_link: str | None = None,
    locked: Mapping[str, float] | None = None,
) -> Robot:
    """Read a URDF file into a Robot.

    Revolute, continuous, prismatic and fixed joints, in branching trees; fixed joints are
    merged into their parent body and the moving joints numbered depth first from the root,
    children in file order. ``<dynamics damping friction>`` become viscous and (symmetric)
    Coulomb friction, unless the joint holds an ``<armdyn:drive>`` element (namespace
    ``urn:armdyn:urdf``, as armdyn.io.urdf_out.to_urdf writes it): its attributes ``viscous``,
    ``coulomb`` ("Tc+ Tc-"), ``motor_inertia``, ``gear_ratio``, ``stribeck`` ("Fs vs") and
    ``sigmoid`` ("A alpha shift") are then the Link's fields of those names (a missing one
    its default) and ``<dynamics>`` is not used. ``<limit lower upper>`` are the joint
    limits; as the URDF specification says (and as Pinocchio reads them), a missing
    ``lower`` or ``upper`` is 0. A continuous joint, or a revolute or prismatic joint
    without ``<limit>``, is unlimited. Mimic joints load as independent joints, with a
    warning naming them. Only ``<robot>``,
    ``<link>`` (its ``<inertial>``) and ``<joint>`` are read: meshes are never loaded, and
    ``<visual>``, ``<collision>`` and the rest of the file are not read.

    ``locked`` holds joints at given values, as Pinocchio's ``buildReducedModel`` does: the
    arm is loaded whole, then reduced by ``Robot.reduced(locked)`` (each locked joint becomes
    fixed there, its body merged into its parent's as a fixed joint's is, the joints below it
    kept), so ``load_urdf(path, locked=L)`` is ``load_urdf(path).reduced(L)``, without the
    mimic warning for a locked joint. ``tool_link`` names the URDF link whose frame is the
    tool (any link, a moving joint's child or one merged into a body through fixed or locked
    joints, whose frame then becomes ``tool`` in that body's frame); by default the tool frame
    is the link frame of the last moving joint of the whole file (depth first), and stays
    where it is when that joint is locked.

    A joint whose motion moves no mass or inertia in any configuration (its subtree is
    massless, or only a point mass on its own axis or a thin rod along it, or its motion repeats
    that of the joints before it) makes M(q) singular for every q, and forward dynamics
    undefined. Such joints are found by factoring M(q) (the Lagrange-Euler M of
    armdyn.dynamics.lagrange, in NumPy: loading compiles no kernel; LDL^T, parents first) at 4 random
    configurations within the joint limits (a range wider than a turn, or 2 m, is sampled
    on a turn, or 2 m, inside it): joint j counts when its pivot is zero at every one
    (below 1e-9 M_jj, or M_jj below 1e-13 of M's largest diagonal entry). A file whose
    links carry no mass at all (a kinematics-only file) is such an arm, every joint named; it
    loads with that warning whatever ``strict`` says, for its kinematics.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        The URDF file: XML text, UTF-8 unless its XML declaration names another encoding.
    strict : bool, optional
        True (default) refuses inertias whose principal moments break the triangle
        inequality, and arms whose M(q) is singular in every configuration (joints that move
        no mass, above) unless no link has mass at all. False loads both with a UserWarning
        naming the links or joints (CAD exports sometimes carry such inertias); M, G and
        inverse dynamics are then defined, forward dynamics raises a ModelError naming the
        joint.
    gravity : array_like, optional
        Acceleration of gravity in the world frame, 3 values (default [0, 0, -9.81]).
    tool_link : str, optional
        The URDF link that carries the tool frame (default None: the child link of the last
        moving joint, depth first).
    locked : mapping of str to float, optional
        Revolute, continuous or prismatic joints of the file, by name, to the value (rad or m)
        each is locked at, within its limits (default None: every joint moves).

    Returns
    -------
    Robot
        The arm, named after the URDF's robot, one link per moving joint.

    Raises
    ------
    armdyn.ModelError
        When the file is missing, cannot be read as XML (bytes not in its encoding), is
        malformed XML or not a valid URDF (the ``<robot>`` element without a name included);
        when ``gravity`` is not 3 finite numbers below 1e15; when the file has floating or
        planar joints, a joint of unknown type, a kinematic loop, a link defined twice, a joint
        naming an undefined link, more or fewer than one root link, or no moving joint; when a
        number that reaches the model (an ``<origin>`` of a joint or an ``<inertial>``, an
        axis, a mass, an inertia, a limit, a damping or friction, an ``<armdyn:drive>``
        attribute) is NaN or infinite, or not a number; when an ``<armdyn:drive>`` attribute is
        unknown or holds the wrong count of numbers; when an xyz, rpy or axis of a joint or an
        ``<inertial>`` is not 3 numbers, or holds one of 1e15 or more in magnitude (the message
        names the joint or link and the attribute); when a joint axis has no direction; when a link's mass properties,
        friction or limits are invalid (see Inertial and Link); and, with ``strict``, when an
        inertia breaks the triangle inequality or some joint moves no mass in any
        configuration (the message names them); when ``locked`` is not a mapping, names a
        joint the file does not have or a fixed one, or holds a value that is not finite or
        lies outside the joint's limits, or locks every moving joint; when ``tool_link`` is not
        a link of the file, or is fixed to the root link (no moving joint between them, also
        once the locked joints are fixed).
    TypeError
        When ``path`` is not a str, bytes or os.PathLike.

    Warns
    -----
    UserWarning
        Mimic joints loaded as independent joints; an axis that is not a unit vector; and,
        with ``strict=False``, inertias that break the triangle inequality and joints that
        move no mass (a singular M(q)).
    """
    path = _file_path(path)
    if not path.is_file():
        raise ModelError(f"{path}: no such URDF file; check the path")
    gravity = inputs.numbers(gravity, "gravity", (3,))  # an arm from a file is numeric: no SymPy gravity
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
        assert joint.parent is not None and joint.child is not None  # both name links of the file
        parent_of[joint.child] = joint.name
        children[joint.parent].append(joint)
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        raise ModelError(f"{path.name}: expected one root link, found {roots or 'none (the joints form a loop)'}")
    locked = _check_locked(path.name, robot.joints, locked)
    built: list[Link] = []
    mimics: list[str] = []
    # Where each URDF link's frame is: (index of the moving link whose body carries it, or -1
    # for the root's; the frame's pose in that link's frame)
    frames: dict[str, tuple[int, np.ndarray]] = {roots[0]: (-1, np.eye(4))}
    # Depth-first walk. Each stack entry: (urdf joint, index of the moving parent, placement
    # of the joint in that parent's frame accumulated across fixed joints)
    stack = [(joint, -1, np.eye(4)) for joint in reversed(children[roots[0]])]
    while stack:
        joint, parent, prefix = stack.pop()
        placement = prefix @ _origin(joint, f"{path.name}: joint '{joint.name}' ({joint.type})")
        if joint.type == "fixed":
            child_body = _body(path.name, links[joint.child], strict).transformed(placement)
            if parent >= 0:
                owner = built[parent]
                built[parent] = _with_inertial(owner, owner.inertial + child_body)
            frames[joint.child] = (parent, placement)
            stack.extend((child, parent, placement) for child in reversed(children[joint.child]))
            continue
        if joint.mimic and joint.name not in locked:
            mimics.append(joint.name)
        built.append(_moving_link(path.name, joint, parent, placement, _body(path.name, links[joint.child], strict)))
        index = len(built) - 1
        frames[joint.child] = (index, np.eye(4))
        stack.extend((child, index, np.eye(4)) for child in reversed(children[joint.child]))
    if mimics:
        warnings.warn(f"{path.name}: mimic joints {mimics} are loaded as independent joints", stacklevel=2)
    if not built:
        raise ModelError(f"{path.name}: the file has no revolute, continuous or prismatic joint")
    tool_index, tool = _tool_frame(path.name, roots[0], frames, tool_link)
    arm = Robot(
        built, name=robot.name, gravity=gravity, tool=tool, tool_link=tool_index, description=f"URDF {path.name}"
    )
    if locked:
        try:
            arm = arm.reduced(locked)
        except ModelError as error:
            raise ModelError(f"{path.name}: {error}") from None
    massless = _massless_joints(arm)
    if massless:
        kinematics_only = "" if arm.has_dynamics else " (no link of the file carries any: a kinematics-only file)"
        message = (
            f"{path.name}: joints {massless} move no mass or inertia in any configuration{kinematics_only}, so the "
            "inertia matrix M(q) is singular for every q and forward dynamics is undefined (the pivots of M for these "
            f"joints vanish at {_SAMPLES} random configurations within the joint limits)"
        )
        if strict and arm.has_dynamics:  # a file with no mass at all is for kinematics: it loads, with the warning
            raise ModelError(
                message + "; give the links these joints move mass and inertia off their axes (or make the joints "
                "fixed), or pass strict=False to load the arm anyway with a warning"
            )
        warnings.warn(message + "; loaded as given", stacklevel=2)
    record_source(arm, path)  # for the viewer's meshes
    return arm


def _file_path(path: str | bytes | os.PathLike[str] | os.PathLike[bytes]) -> Path:
    """``path`` (str, bytes or os.PathLike) as a Path, or a TypeError naming it."""
    try:
        name = os.fspath(path)
    except TypeError:
        raise TypeError(
            f"path must be a str, bytes or os.PathLike naming the URDF file, got {type(path).__name__}"
        ) from None
    return Path(os.fsdecode(name))


def _massless_joints(arm: Robot) -> list[str]:
    """The joints whose pivot of M(q) is zero at every one of a few random configurations.

    M(q) = L D L^T with unit lower-triangular L, parents first (the joint order). The pivot
    D_jj is twice the least kinetic energy of moving joint j at unit speed while the joints
    before it move to cancel what they can: zero when joint j moves no mass (M_jj = 0,
    then its whole row is zero) or when its motion repeats that of joints before it (two
    coincident revolute axes with a massless link between them). A structural singularity holds at
    every configuration, a configuration-dependent one only on a set of measure zero, so a
    joint whose pivot vanishes at every sample is named. Exact zeros survive rounding only
    approximately, hence the relative thresholds ``_PIVOT_RELATIVE`` and ``_DIAGONAL_RELATIVE``.
    This covers what a rule on the subtree's mass alone would miss (a point mass on the
    joint's own axis, repeated axes). M is the Lagrange-Euler one in NumPy
    (armdyn.dynamics.lagrange.inertia_matrix, Lewis, Dawson and Abdallah 2004, eq. 3.2.30,
    with the motors' reflected inertia), the reference the compiled kernels are tested
    against: loading an arm compiles and loads no kernel.
    """
    lower, upper = arm.qlim
    # A range wider than 2 span (unlimited, or 1e16 as some files write) is sampled on 2 span inside it, nearest
    # 0: for a revolute joint the whole circle, M being periodic; for a prismatic one 2 m
    span = np.where(np.array(arm.kinds) == "revolute", np.pi, 1.0)
    wide = upper - lower > 2 * span
    middle = np.clip(0.0, np.where(wide, lower + span, 0.0), np.where(wide, upper - span, 0.0))
    lower, upper = np.where(wide, middle - span, lower), np.where(wide, middle + span, upper)
    q = np.random.default_rng(_SEED).uniform(lower, upper, (_SAMPLES, arm.n))
    work = lagrange.inertia_matrix(arm, q)  # NumPy (3.2.30): loading an arm compiles no kernel
    diagonal = np.diagonal(work, axis1=1, axis2=2).copy()
    largest = diagonal.max(axis=1)
    zero = np.zeros((_SAMPLES, arm.n), dtype=bool)
    for j in range(arm.n):
        pivot = work[:, j, j]
        zero[:, j] = (pivot <= _PIVOT_RELATIVE * diagonal[:, j]) | (diagonal[:, j] <= _DIAGONAL_RELATIVE * largest)
        # eliminate joint j from the joints after it; a zero pivot of a semi-definite matrix has a zero column
        column = work[:, j + 1 :, j]
        scale = np.where(zero[:, j], 0.0, 1.0 / np.where(zero[:, j], 1.0, pivot))
        work[:, j + 1 :, j + 1 :] -= scale[:, None, None] * column[:, :, None] * column[:, None, :]
    return [name for name, always in zip(arm.joint_names, np.all(zero, axis=0), strict=True) if always]


def _check_locked(file: str, joints: list[_Joint], locked: object) -> dict:
    """``locked`` as a dict, refused unless it names moving joints of the file (values are checked by reduced)."""
    if locked is None:
        return {}
    if not isinstance(locked, Mapping):
        raise ModelError(f"{file}: locked must be a mapping of joint name to value, got {locked!r}")
    kinds = {joint.name: joint.type for joint in joints}
    moving = [joint.name for joint in joints if joint.type in _MOVING]
    for name in locked:
        if name not in kinds:
            raise ModelError(
                f"{file}: cannot lock joint '{name}': the file has no such joint (its moving joints: {moving})"
            )
        if kinds[name] not in _MOVING:
            raise ModelError(
                f"{file}: cannot lock joint '{name}': it is {kinds[name]}, already fixed; lock moving joints"
            )
    return dict(locked)


def _tool_frame(
    file: str, root: str, frames: dict[str, tuple[int, np.ndarray]], tool_link: object
) -> tuple[int | None, np.ndarray | None]:
    """(tool_link index, tool pose in that link's frame) for the URDF link named ``tool_link`` (None: the default)."""
    if tool_link is None:
        return None, None
    if not isinstance(tool_link, str) or tool_link not in frames:
        raise ModelError(f"{file}: tool_link {tool_link!r} is not a link of the file (its links: {list(frames)})")
    index, pose = frames[tool_link]
    if index < 0:
        raise ModelError(
            f"{file}: tool_link '{tool_link}' is fixed to the root link '{root}' (no moving joint between them), "
            "so it cannot carry a tool; name a link that some joint moves"
        )
    return index, pose


def _with_inertial(link: Link, inertial: Inertial) -> Link:
    import dataclasses

    return dataclasses.replace(link, inertial=inertial)


def _moving_link(file: str, joint: _Joint, parent: int, placement: np.ndarray, body: Inertial) -> Link:
    where = f"{file}: joint '{joint.name}'"
    axis = joint.axis
    if not np.all(np.isfinite(axis)):
        raise ModelError(f"{where}: <axis> xyz {axis} holds NaN or infinite values; write a finite direction")
    norm = np.linalg.norm(axis)
    if norm == 0:
        raise ModelError(f"{where}: axis {axis} has no direction; write a non-zero <axis> xyz")
    if abs(norm - 1.0) > 1e-6:
        warnings.warn(f"{where}: axis {axis} is not a unit vector; using its direction", stacklevel=3)
    kind = "prismatic" if joint.type == "prismatic" else "revolute"
    limits = (-np.inf, np.inf)
    if joint.type != "continuous" and joint.limit is not None:  # the specification: lower and upper default to 0
        lower, upper = (
            0.0 if value is None else _finite(value, where, f"<limit> {bound}")
            for bound, value in (("lower", joint.limit.lower), ("upper", joint.limit.upper))
        )
        limits = (lower, upper)
    damping = friction = 0.0
    if joint.dynamics is not None:
        damping = _finite(joint.dynamics.damping or 0.0, where, "<dynamics> damping")
        friction = _finite(joint.dynamics.friction or 0.0, where, "<dynamics> friction")
    drive = (
        {"viscous": damping, "coulomb": (friction, -friction)} if joint.drive is None else _drive(joint.drive, where)
    )
    try:
        return Link(
            joint.name,
            Joint(kind, placement, axis / norm, name=joint.name),
            body,
            parent=parent,
            limits=limits,
            **drive,
        )
    except ModelError as error:
        raise ModelError(f"{file}: {error}") from None


def _drive(attributes: dict[str, str], where: str) -> dict[str, Any]:
    """The Link fields an ``<armdyn:drive>`` element gives: its friction and motor in full (a missing attribute
    is Link's default; ``<dynamics>`` is then not used), each attribute refused unless it holds its count of
    finite numbers."""
    import dataclasses

    fields = {field.name for field in dataclasses.fields(Link)}
    values: dict[str, Any] = {}
    for key, text in attributes.items():
        if key not in _DRIVE:
            raise ModelError(f"{where}: <armdyn:drive> has an unknown attribute '{key}' (known: {', '.join(_DRIVE)})")
        if key not in fields:
            raise ModelError(f"{where}: <armdyn:drive> {key}: this version of armdyn has no {key} friction")
        numbers = [_finite(word, where, f"<armdyn:drive> {key}") for word in text.split()]
        if len(numbers) != _DRIVE[key]:
            raise ModelError(f"{where}: <armdyn:drive> {key} is '{text}': it must hold {_DRIVE[key]} number(s)")
        values[key] = numbers[0] if _DRIVE[key] == 1 else tuple(numbers)
    return values
