"""Export: to_urdf read back by load_urdf and by Pinocchio, save_arm/load_arm exact, every error path."""

from __future__ import annotations

import dataclasses
import functools
import json
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from lxml import etree
from numpy.testing import assert_array_equal
from scipy.spatial.transform import Rotation

import armdyn as ad
from armdyn import ModelError, load_urdf
from armdyn.io.model_file import FORMAT, VERSION, arm_from_dict, arm_to_dict, load_arm, save_arm
from armdyn.io.urdf_out import ARMDYN_NAMESPACE, UNBOUNDED, rpy, to_urdf
from armdyn.model.arm import Link
from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint, rot_x, rot_z, trans
from tests.helpers import URDFS, pin_q

DRIVE = f"{{{ARMDYN_NAMESPACE}}}drive"
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
STATES = 20
LAWS = {"stribeck", "sigmoid"} <= {field.name for field in dataclasses.fields(Link)}  # this Link has both


def _tree() -> ad.Robot:
    """A tree (depth first) with what URDF cannot say directly: a rotated base, DH frame offsets, a tool on a middle
    link, asymmetric Coulomb friction, motors and gears, an unlimited prismatic and a half-limited revolute joint."""
    body = functools.partial(Inertial, inertia=[[0.03, 0.001, -0.002], [0.001, 0.04, 0.0015], [-0.002, 0.0015, 0.05]])
    offset = trans(x=0.3) @ rot_x(np.pi / 2)  # standard DH: Tx(a) Rx(alpha) after the motion
    links = [
        Link("trunk", Joint("R", trans(z=0.4), frame_offset=offset, name="trunk"), body(3.0, [0.1, 0.02, -0.05]),
             viscous=0.002, coulomb=(0.4, -0.3), motor_inertia=2e-4, gear_ratio=-60.0, limits=(-2.5, 2.5)),
        Link("slide", Joint("P", rot_z(0.3) @ trans(0.1, 0.0, 0.2), [0.6, 0.0, 0.8], name="slide"),
             body(2.0, [0.0, 0.05, 0.1]), parent=0, viscous=3.0, coulomb=(1.0, -1.0)),
        Link("wrist", Joint("R", trans(y=0.25) @ rot_x(-0.7), [0.0, 1.0, 0.0], offset, name="wrist"),
             body(1.5, [0.02, 0.0, 0.03]), parent=1, viscous=0.3, limits=(-np.inf, 1.0)),
        Link("side", Joint("R", trans(0.2, -0.1, 0.0) @ rot_z(-1.1), [1.0, 0.0, 0.0], name="side"),
             body(0.8, [0.05, 0.05, 0.0]), parent=0, coulomb=(0.2, -0.2), motor_inertia=1e-3),
    ]  # fmt: skip
    base = np.eye(4)
    base[:3, :3] = Rotation.from_euler("xyz", [0.2, -0.4, 1.0]).as_matrix()
    base[:3, 3] = [0.5, -0.2, 0.1]
    tool = trans(0.05, 0.0, 0.12) @ rot_x(0.3)
    return ad.Robot(links, name="tree", base=base, tool=tool, tool_link=1, gravity=[0.3, -0.2, -9.7],
                    configurations={"home": [0.1, 0.2, 0.3, 0.4]}, description="a tree -- of four joints")  # fmt: skip


@functools.cache
def _arm(name: str) -> ad.Robot:
    """A built-in arm, the UR5, the Panda with its fingers locked (7 joints), or the tree above."""
    if name == "tree":
        return _tree()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # mimic fingers (locked here) and the like
        if name == "ur5":
            return load_urdf(URDFS["ur5"])
        if name == "panda7":
            return load_urdf(URDFS["panda"], tool_link="panda_hand_tcp", locked=FINGERS)
    return ad.models.load(name)


ARMS = [*ad.models.names(), "ur5", "panda7", "tree"]


def _states(arm: ad.Robot, seed: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """STATES random (q, qd, qdd), q within the joint limits (at most +-3), velocities away from zero."""
    rng = np.random.default_rng(seed)
    lower, upper = np.maximum(arm.qlim[0], -3.0), np.minimum(arm.qlim[1], 3.0)
    q = rng.uniform(lower, upper, (STATES, arm.n))
    qd = rng.choice([-1.0, 1.0], (STATES, arm.n)) * rng.uniform(0.1, 2.0, (STATES, arm.n))
    return q, qd, rng.uniform(-3.0, 3.0, (STATES, arm.n))


def _assert_relative(actual: np.ndarray, expected: np.ndarray, tolerance: float, what: str) -> None:
    """Per state: max |actual - expected| <= tolerance max |expected| (the last axes of one state)."""
    axes = tuple(range(1, np.ndim(expected)))
    error = np.max(np.abs(np.asarray(actual) - expected), axis=axes)
    scale = np.max(np.abs(expected), axis=axes)
    worst = int(np.argmax(error - tolerance * scale))
    assert np.all(error <= tolerance * scale), f"{what}: {error[worst]:.3e} against {scale[worst]:.3e}"


def _load_back(arm: ad.Robot, path: Path) -> ad.Robot:
    """load_urdf of an exported file, as its header says: the arm's gravity, the tool link 'tool'; an arm built
    with inertias that break the triangle inequality (the PUMA 560's published ones) loads with strict=False."""
    strict = all(link.inertial.strict for link in arm.links)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*triangle inequality")
        return load_urdf(path, gravity=arm.gravity, tool_link="tool", strict=strict)


def _assert_same_dynamics(loaded: ad.Robot, arm: ad.Robot, tolerance: float) -> None:
    """M(q), inverse dynamics with friction, G(q) and the tool pose of ``loaded`` equal ``arm``'s at STATES states."""
    assert loaded.joint_names == arm.joint_names
    q, qd, qdd = _states(arm)
    _assert_relative(loaded.inertia_matrix(q), arm.inertia_matrix(q), tolerance, "M")
    _assert_relative(loaded.inverse_dynamics(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd), tolerance, "tau")
    _assert_relative(loaded.gravity_vector(q), arm.gravity_vector(q), tolerance, "G")
    _assert_relative(loaded.friction(qd), arm.friction(qd), tolerance, "F")
    _assert_relative(loaded.tool_pose(q), arm.tool_pose(q), tolerance, "tool pose")


# ----- URDF -------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ARMS)
def test_urdf_loads_back_with_the_same_dynamics(name: str, tmp_path: Path) -> None:
    arm = _arm(name)
    path = tmp_path / f"{name}.urdf"
    text = to_urdf(arm, path)
    assert path.read_text(encoding="utf-8") == text
    loaded = _load_back(arm, path)
    _assert_same_dynamics(loaded, arm, 1e-12)
    assert_array_equal(loaded.qlim, _unbounded_qlim(arm))


def _unbounded_qlim(arm: ad.Robot) -> np.ndarray:
    """The limits a loaded arm has: those of the arm, an infinite bound written as +-1e16 (continuous joints stay
    unlimited)."""
    qlim = np.clip(arm.qlim, -UNBOUNDED, UNBOUNDED)
    continuous = (np.array(arm.kinds) == "revolute") & np.all(np.isinf(arm.qlim), axis=0)
    qlim[:, continuous] = [[-np.inf], [np.inf]]
    return qlim


@pytest.mark.parametrize("name", ARMS)
def test_pinocchio_reads_the_urdf_with_the_same_dynamics(name: str) -> None:
    """Pinocchio's crba and rnea of the written URDF equal armdyn's (friction off; the reflected motor inertias
    G^2 Jm as Pinocchio's armature) to 1e-10; continuous joints are (cos, sin) there."""
    arm = _arm(name)
    model = pin.buildModelFromXML(to_urdf(arm))
    model.gravity.linear = arm.gravity
    ids = [model.getJointId(joint) for joint in arm.joint_names]
    columns = [model.joints[i].idx_v for i in ids]
    assert sorted(columns) == list(range(arm.n)) == list(range(model.nv))
    model.armature[columns] = arm.reflected_inertia
    data, bare = model.createData(), arm.without_friction()
    q, qd, qdd = _states(arm)
    for x, xd, xdd in zip(q, qd, qdd, strict=True):
        config, v, a = pin_q(model, ids, x), np.zeros(arm.n), np.zeros(arm.n)
        v[columns], a[columns] = xd, xdd
        _assert_relative(pin.crba(model, data, config)[np.ix_(columns, columns)][None], bare.inertia_matrix(x)[None],
                         1e-10, "M")  # fmt: skip
        _assert_relative(pin.rnea(model, data, config, v, a)[columns][None], bare.inverse_dynamics(x, xd, xdd)[None],
                         1e-10, "tau")  # fmt: skip


def test_loaded_limits_are_the_arms_with_infinite_bounds_as_1e16(tmp_path: Path) -> None:
    for name in ("cylindrical", "tree", "two_link_planar", "puma560"):
        arm = _arm(name)
        to_urdf(arm, tmp_path / "arm.urdf")
        assert_array_equal(_load_back(arm, tmp_path / "arm.urdf").qlim, _unbounded_qlim(arm), err_msg=name)


def _joints(text: str) -> dict[str, etree._Element]:
    root = etree.fromstring(text.encode())
    return {joint.get("name"): joint for joint in root.iterfind("joint")}


def test_urdf_holds_joint_side_friction_and_the_drive_only_where_needed() -> None:
    """SCARA (symmetric Coulomb, no motors): plain <dynamics>, no extension; PUMA 560 (asymmetric Coulomb, gears):
    <dynamics damping> joint side, and <armdyn:drive> with the Link's own motor-side values."""
    scara, puma = _arm("scara"), _arm("puma560")
    for link in scara.links:
        joint = _joints(to_urdf(scara))[link.name]
        assert joint.find(DRIVE) is None
        assert float(joint.find("dynamics").get("damping")) == link.viscous
        assert float(joint.find("dynamics").get("friction")) == link.coulomb[0] == -link.coulomb[1]
    joints = _joints(to_urdf(puma))
    for link, damping in zip(puma.links, puma.viscous_friction, strict=True):
        joint = joints[link.name]
        assert float(joint.find("dynamics").get("damping")) == damping
        assert joint.find("dynamics").get("friction") is None  # asymmetric: URDF cannot say it
        drive = joint.find(DRIVE)
        assert float(drive.get("viscous")) == link.viscous
        assert [float(word) for word in drive.get("coulomb").split()] == list(link.coulomb)
        assert float(drive.get("motor_inertia")) == link.motor_inertia
        assert float(drive.get("gear_ratio")) == link.gear_ratio
    assert "<!-- Written by armdyn" in to_urdf(puma) and "gravity=(0.0, 0.0, -9.81)" in to_urdf(puma)
    assert "- -" in to_urdf(_arm("tree")) and "a tree --" not in to_urdf(_arm("tree"))  # no '--' in an XML comment


def test_origin_rpy_gives_the_rotation_back_to_1e15(tmp_path: Path) -> None:
    """Random rotations, and rotations at and near pitch = +-pi/2 (yaw and roll not separable there)."""
    rng = np.random.default_rng(11)
    rotations = list(Rotation.random(200, random_state=rng).as_matrix())
    for near in (0.0, 1e-17, 1e-12, 1e-8, 1e-5):
        for sign in (-1.0, 1.0):
            angles = [rng.uniform(-np.pi, np.pi), sign * np.pi / 2 + near, rng.uniform(-np.pi, np.pi)]
            rotations.append(Rotation.from_euler("xyz", angles).as_matrix())
    body = Inertial(1.0, [0.1, 0.0, 0.0], [0.01, 0.02, 0.02])
    for rotation in rotations:
        placement = np.eye(4)
        placement[:3, :3], placement[:3, 3] = rotation, rng.normal(size=3)
        arm = ad.Robot([Link("j", Joint("R", placement, [0.0, 0.0, 1.0], name="j"), body)])
        to_urdf(arm, tmp_path / "one.urdf")
        loaded = load_urdf(tmp_path / "one.urdf").links[0].joint.placement
        assert_array_equal(loaded[:3, 3], placement[:3, 3])
        assert np.max(np.abs(loaded - placement)) <= 1e-15, rpy(rotation)


def test_names_that_clash_are_made_unique(tmp_path: Path) -> None:
    """Joints named 'base' and 'tool_joint': the links and fixed joints the file adds get other names."""
    body = Inertial(1.0, [0.1, 0.0, 0.0], [0.01, 0.02, 0.02])
    links = [Link("base", Joint("R", name="base"), body), Link("tool_joint", Joint("R", trans(x=0.5)), body, 0)]
    arm = ad.Robot(links, base=trans(z=1.0))
    text = to_urdf(arm, tmp_path / "clash.urdf")
    root = etree.fromstring(text.encode())
    for tag in ("link", "joint"):
        names = [element.get("name") for element in root.iterfind(tag)]
        assert len(names) == len(set(names)), names
    _assert_same_dynamics(load_urdf(tmp_path / "clash.urdf", tool_link="tool"), arm, 1e-12)


def test_to_urdf_refuses_symbolic_and_non_arms(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"robot 'two_link_planar'.*symbolic"):
        to_urdf(ad.models.two_link_planar(symbolic=True))
    with pytest.raises(ModelError, match="needs an ArmModel"):
        to_urdf("puma560")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match=r"missing.*cannot write the URDF"):
        to_urdf(_arm("scara"), tmp_path / "missing" / "arm.urdf")


# ----- <armdyn:drive> read by load_urdf ---------------------------------------------------------------------------
def _one_joint(drive: str) -> str:
    return (
        f"<robot name='r' xmlns:armdyn='{ARMDYN_NAMESPACE}'><link name='base'/>"
        "<joint name='j' type='continuous'><parent link='base'/><child link='l'/><axis xyz='0 0 1'/>"
        f"<dynamics damping='7' friction='8'/>{drive}</joint>"
        "<link name='l'><inertial><origin xyz='0.1 0 0'/><mass value='1'/>"
        "<inertia ixx='0.01' ixy='0' ixz='0' iyy='0.02' iyz='0' izz='0.02'/></inertial></link></robot>"
    )


def test_load_urdf_takes_the_drive_in_place_of_dynamics(tmp_path: Path) -> None:
    path = tmp_path / "drive.urdf"
    path.write_text(_one_joint("<armdyn:drive viscous='0.5' coulomb='0.25 -0.125' gear_ratio='-2'/>"))
    link = load_urdf(path).links[0]
    assert (link.viscous, link.coulomb, link.motor_inertia, link.gear_ratio) == (0.5, (0.25, -0.125), 0.0, -2.0)
    path.write_text(_one_joint("<drive viscous='0.5'/>"))  # not in armdyn's namespace: not ours, not read
    link = load_urdf(path).links[0]
    assert (link.viscous, link.coulomb) == (7.0, (8.0, -8.0))


@pytest.mark.parametrize(
    ("drive", "message"),
    [
        ("viscous='0.5' damping='1'", r"joint 'j': <armdyn:drive> has an unknown attribute 'damping'"),
        ("viscous='fast'", r"joint 'j': <armdyn:drive> viscous is 'fast', not a number"),
        ("coulomb='0.3'", r"joint 'j': <armdyn:drive> coulomb is '0.3': it must hold 2 number"),
        ("gear_ratio='nan'", r"joint 'j': <armdyn:drive> gear_ratio is nan, not a finite number"),
        ("coulomb='-0.3 0.3'", r"link 'j': Coulomb friction must be Tc\+ >= 0"),
    ],
)
def test_load_urdf_refuses_a_bad_drive(drive: str, message: str, tmp_path: Path) -> None:
    path = tmp_path / "bad.urdf"
    path.write_text(_one_joint(f"<armdyn:drive {drive}/>"))
    with pytest.raises(ModelError, match=message):
        load_urdf(path)


# ----- Stribeck and sigmoid friction ------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True, eq=False)
class _LawLink(Link):
    """A Link with the Stribeck and sigmoid friction fields, whether or not this version's Link has them."""

    stribeck: tuple[float, float] = (0.0, 0.0)
    sigmoid: tuple[float, float, float] = (0.0, 0.0, 0.0)


def test_friction_laws_are_written_to_both_files_and_read_back_where_link_has_them(tmp_path: Path) -> None:
    """The writers take Stribeck (Fs, vs) and sigmoid (A, alpha, shift) friction from any Link that has them; the
    readers give them back when this version's Link has the fields (the same dynamics, friction included), and
    refuse them by name when it has not."""
    scara = _arm("scara")
    laws = [((0.3, 0.05), (0.0, 0.0, 0.0)), ((0.0, 0.0), (1.5, 25.0, 0.01)), ((0.2, 0.1), (0.8, 40.0, -0.02))]
    fields = [field.name for field in dataclasses.fields(Link) if field.name not in ("stribeck", "sigmoid")]
    links = [
        _LawLink(**{key: getattr(link, key) for key in fields}, stribeck=s, sigmoid=g)
        for link, (s, g) in zip(scara.links, [*laws, ((0.0, 0.0), (0.0, 0.0, 0.0))], strict=True)
    ]
    arm = scara.replace(links)
    joints = _joints(to_urdf(arm, tmp_path / "laws.urdf"))
    for link, (stribeck, sigmoid) in zip(arm.links, laws, strict=False):
        drive = joints[link.name].find(DRIVE)
        written = {key: [float(word) for word in drive.get(key, "0 0 0").split()] for key in ("stribeck", "sigmoid")}
        assert written["stribeck"][:2] == list(stribeck) and written["sigmoid"] == list(sigmoid)
    assert joints["q4"].find(DRIVE) is None  # symmetric Coulomb, no motor, no law: nothing beyond <dynamics>
    saved = arm_to_dict(arm)
    assert [link["stribeck"] for link in saved["links"]][:3] == [list(s) for s, _ in laws]
    assert [link["sigmoid"] for link in saved["links"]][:3] == [list(g) for _, g in laws]
    save_arm(arm, tmp_path / "laws.json")
    if LAWS:
        _assert_same_dynamics(_load_back(arm, tmp_path / "laws.urdf"), arm, 1e-12)
        assert arm_to_dict(load_arm(tmp_path / "laws.json")) == saved
    else:
        with pytest.raises(ModelError, match=r"laws.urdf: joint 'q1': <armdyn:drive> stribeck: this version"):
            _load_back(arm, tmp_path / "laws.urdf")
        with pytest.raises(ModelError, match=r"laws.json: key 'links\[0\].stribeck': this version of armdyn has no"):
            load_arm(tmp_path / "laws.json")


# ----- the model file -----------------------------------------------------------------------------------------------
def _flat(value: object) -> list[float]:
    """Every number of a model file's object, in order (ints and floats; text and flags left out)."""
    if isinstance(value, dict):
        return [number for item in value.values() for number in _flat(item)]
    if isinstance(value, list):
        return [number for item in value for number in _flat(item)]
    return [value] if isinstance(value, (int, float)) and not isinstance(value, bool) else []


@pytest.mark.parametrize("name", ARMS)
def test_model_file_gives_the_arm_back_exactly(name: str, tmp_path: Path) -> None:
    arm = _arm(name)
    path = save_arm(arm, tmp_path / f"{name}.json")
    assert path == tmp_path / f"{name}.json"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # published inertias marked strict: false load without a warning
        loaded = load_arm(path)
    assert isinstance(loaded, ad.Robot)
    assert arm_to_dict(loaded) == arm_to_dict(arm)  # == for every number, name, kind and flag
    assert _flat(json.loads(path.read_text())) == _flat(arm_to_dict(arm))
    assert (loaded.name, loaded.description, loaded.tool_link, loaded.dh) == (
        arm.name, arm.description, arm.tool_link, arm.dh,
    )  # fmt: skip
    for key, value in arm.configurations.items():
        assert_array_equal(getattr(loaded, key), value)
    for field in ("gravity", "base", "tool", "qlim", "reflected_inertia", "viscous_friction", "coulomb_friction"):
        assert_array_equal(getattr(loaded, field), getattr(arm, field), err_msg=field)
    for mine, theirs in zip(loaded.links, arm.links, strict=True):
        assert (mine.name, mine.parent, mine.kind, mine.limits) == (
            theirs.name,
            theirs.parent,
            theirs.kind,
            theirs.limits,
        )
        for key in ("placement", "axis", "frame_offset"):
            assert_array_equal(getattr(mine.joint, key), getattr(theirs.joint, key))
        assert_array_equal(mine.inertial.inertia, theirs.inertial.inertia)
        assert_array_equal(mine.inertial.com, theirs.inertial.com)
    _assert_same_dynamics(loaded, arm, 0.0)  # the same numbers: the same results to the bit


def test_model_file_layout(tmp_path: Path) -> None:
    """The documented keys; unlimited bounds as null; strict JSON (no NaN or Infinity); a pose's rows one per line."""
    path = save_arm(_arm("cylindrical"), tmp_path / "cylindrical.json")
    text = path.read_text()
    data = json.loads(text, parse_constant=lambda constant: pytest.fail(f"{constant} in the file"))
    assert (data["format"], data["version"]) == (FORMAT, VERSION) == ("armdyn-arm", 1)
    assert [link["limits"] for link in data["links"]] == [[None, None], [None, None], [0.0, None]]
    assert "[1.0, 0.0, 0.0, 0.0]," in text
    assert data["links"][0]["joint"]["kind"] == "revolute" and data["links"][1]["joint"]["kind"] == "prismatic"


def test_model_file_refuses_symbolic_arms_and_other_suffixes(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"robot 'polar_rp'.*symbolic"):
        save_arm(ad.models.polar_rp(symbolic=True), tmp_path / "polar.json")
    with pytest.raises(ModelError, match=r"arm.urdf: .*suffix .json"):
        save_arm(_arm("scara"), tmp_path / "arm.urdf")
    with pytest.raises(ModelError, match=r"holds an ArmModel"):
        arm_to_dict(None)  # type: ignore[arg-type]
    with pytest.raises(ModelError, match=r"missing.*cannot write the model file"):
        save_arm(_arm("scara"), tmp_path / "missing" / "arm.json")


def _edited(tmp_path: Path, edit: object) -> Path:
    """The SCARA's model file after ``edit(data)`` changed its object."""
    data = arm_to_dict(_arm("scara"))
    edit(data)  # type: ignore[operator]
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(format="urdf"), r"key 'format' is 'urdf': not an armdyn model file"),
        (lambda d: d.update(version=2), r"key 'version' is 2: this armdyn reads version 1"),
        (lambda d: d.update(version=True), r"key 'version' is True"),
        (lambda d: d.pop("version"), r"missing key 'version'"),
        (lambda d: d.pop("gravity"), r"missing key 'gravity'"),
        (lambda d: d["links"][2]["inertial"].pop("mass"), r"missing key 'links\[2\].inertial.mass'"),
        (lambda d: d["links"][1]["joint"].pop("axis"), r"missing key 'links\[1\].joint.axis'"),
        (lambda d: d["links"][0].pop("sigmoid"), r"missing key 'links\[0\].sigmoid'"),
        (lambda d: d["links"][0].update(viscouss=1.0), r"unknown key 'links\[0\].viscouss'"),
        (lambda d: d.update(links={}), r"key 'links' must be a list"),
        (lambda d: d["links"].__setitem__(1, [1, 2]), r"key 'links\[1\]' must be a JSON object"),
        (lambda d: d["links"][0].update(limits=[0.0]), r"key 'links\[0\].limits' must be \[lower, upper\]"),
        (lambda d: d["links"][0]["inertial"].update(strict="yes"), r"links\[0\].inertial.strict' must be true or"),
        (lambda d: d["links"][0]["joint"].update(kind=1), r"key 'links\[0\].joint.kind' must be text"),
        (lambda d: d.update(configurations=[]), r"key 'configurations' must be an object"),
        (lambda d: d.update(dh=[1]), r"key 'dh' must be an object or null"),
        (lambda d: d["links"][2]["inertial"].update(mass=-1.0), r"link 'q3': mass must be non-negative"),
        (lambda d: d["links"][1].update(parent="q1"), r"link 'q2': parent must be an integer"),
        (lambda d: d["links"][1]["joint"].update(kind="ball"), r"joint 'q2': unknown joint kind 'ball'"),
        (lambda d: d.update(tool_link=9), r"tool_link 9 is not a link index"),
        (lambda d: d["links"][0].update(limits=[1.0, None, 2.0]), r"links\[0\].limits' must be \[lower, upper\]"),
    ],
)
def test_load_arm_refuses_a_bad_file_naming_it_and_the_key(edit: object, message: str, tmp_path: Path) -> None:
    path = _edited(tmp_path, edit)
    with pytest.raises(ModelError, match=r"edited.json: .*" + message):
        load_arm(path)


def test_load_arm_refuses_what_is_not_a_model_file(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"nowhere.json: cannot read the model file"):
        load_arm(tmp_path / "nowhere.json")
    path = tmp_path / "broken.json"
    path.write_text('{"format": "armdyn-arm",\n "version": 1,,}')
    with pytest.raises(ModelError, match=r"broken.json: not JSON \(line 2"):
        load_arm(path)
    path.write_text('{"format": "armdyn-arm", "version": NaN}')
    with pytest.raises(ModelError, match=r"broken.json: holds NaN"):
        load_arm(path)
    path.write_text("[1, 2]")
    with pytest.raises(ModelError, match=r"broken.json: the top level must be a JSON object"):
        load_arm(path)
    with pytest.raises(ModelError, match=r"my arm: missing key 'format'"):
        arm_from_dict({}, "my arm")
