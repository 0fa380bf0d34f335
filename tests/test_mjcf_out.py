"""to_mjcf against MuJoCo's own dynamics: M(q), the bias, inverse dynamics with damping and the tool pose to
1e-12 on the built-in arms, the UR5 and the Panda (with friction and motors too), an arm with DC drives, the
custom data, the warnings and the errors."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn.actuators import DCMotor, Hydraulic, motor_drives, with_actuators
from armdyn.io.mjcf_out import DRIVE_FIELDS, DRIVE_NUMERIC, INERTIA_TENDON, LINK_FIELDS, LINK_NUMERIC, to_mjcf
from tests.helpers import URDFS

mujoco = pytest.importorskip("mujoco")

STATES = 20
TOLERANCE = 1e-12
BUILT_IN = [name for name in ad.models.names() if name != "stanford"]  # stanford: see the refusal test


def load(name: str) -> ad.Robot:
    """A built-in arm, or the UR5 or Panda of example-robot-data."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ad.load_urdf(URDFS[name]) if name in URDFS else ad.models.load(name)


def with_friction_and_motors(arm: ad.Robot) -> ad.Robot:
    """The arm with viscous and symmetric Coulomb friction, rotor inertia and gears on every joint."""
    links = [
        dataclasses.replace(
            link,
            viscous=0.1 * (j + 1),
            coulomb=(0.05 * (j + 1), -0.05 * (j + 1)),
            motor_inertia=1e-3 * (j + 1),
            gear_ratio=(-1.0) ** j * (10.0 + j),
            stribeck=(0.0, 0.0),
            sigmoid=(0.0, 0.0, 0.0),
        )
        for j, link in enumerate(arm.links)
    ]
    return arm.replace(links)


def compiled(arm: object) -> mujoco.MjModel:
    """MuJoCo's model of to_mjcf(arm), with contacts, joint limits and dry friction switched off."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = mujoco.MjModel.from_xml_string(to_mjcf(arm))  # type: ignore[arg-type]
    model.opt.disableflags |= (
        mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS
        | mujoco.mjtDisableBit.mjDSBL_CONTACT
        | mujoco.mjtDisableBit.mjDSBL_LIMIT
    )
    return model


def random_states(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(34)
    return rng.uniform(-np.pi, np.pi, (STATES, n)), rng.uniform(-2, 2, (STATES, n)), rng.uniform(-3, 3, (STATES, n))


def relative(mine: list[np.ndarray], theirs: list[np.ndarray]) -> float:
    """The largest difference over the states relative to the largest magnitude of the quantity."""
    mine_array, theirs_array = np.array(mine), np.array(theirs)
    return float(np.abs(mine_array - theirs_array).max() / np.abs(theirs_array).max())


def mujoco_quantities(model: mujoco.MjModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> dict[str, np.ndarray]:
    """M, the bias, the inverse dynamics and the tool site's pose at one state."""
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = q, qd
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    bias = data.qfrc_bias.copy()
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tool")
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    data.qacc[:] = qdd
    mujoco.mj_inverse(model, data)
    return {"M": full, "bias": bias, "inverse": data.qfrc_inverse.copy(), "tool": pose}


def without_coulomb(arm: ad.Robot) -> ad.Robot:
    """The arm with its Coulomb, Stribeck and sigmoid friction removed, viscous friction and motors kept."""
    return arm.replace(
        [
            dataclasses.replace(link, coulomb=(0.0, 0.0), stribeck=(0.0, 0.0), sigmoid=(0.0, 0.0, 0.0))
            for link in arm.links
        ]
    )


def worst_errors(arm: ad.Robot) -> dict[str, float]:
    """The worst relative error of each quantity over the random states, MuJoCo against armdyn."""
    model = compiled(arm)
    assert model.nv == arm.n and model.nu == arm.n
    frictionless, viscous = arm.without_friction(), without_coulomb(arm)
    mine: dict[str, list[np.ndarray]] = {"M": [], "bias": [], "inverse": [], "tool": []}
    theirs: dict[str, list[np.ndarray]] = {"M": [], "bias": [], "inverse": [], "tool": []}
    for q, qd, qdd in zip(*random_states(arm.n), strict=True):
        for key, value in mujoco_quantities(model, q, qd, qdd).items():
            theirs[key].append(value)
        mine["M"].append(arm.inertia_matrix(q))
        mine["bias"].append(frictionless.inverse_dynamics(q, qd, np.zeros(arm.n)))
        mine["inverse"].append(viscous.inverse_dynamics(q, qd, qdd))
        mine["tool"].append(arm.tool_pose(q))
    return {key: relative(mine[key], theirs[key]) for key in mine}


ARMS = [*BUILT_IN, *sorted(URDFS)]


@pytest.mark.parametrize("friction", [False, True], ids=["as built", "friction and motors"])
@pytest.mark.parametrize("name", ARMS)
def test_mujoco_computes_armdyns_dynamics(name: str, friction: bool) -> None:
    arm = load(name)
    arm = with_friction_and_motors(arm) if friction else arm
    errors = worst_errors(arm)
    print(f"{name}{' with friction and motors' if friction else ''}: worst relative errors {errors}")
    assert max(errors.values()) < TOLERANCE, errors


def test_the_friction_and_motors_are_written_as_mujoco_holds_them() -> None:
    arm = with_friction_and_motors(load("puma560"))
    model = compiled(arm)
    for j, link in enumerate(arm.links):
        joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, link.name)
        dof = model.jnt_dofadr[joint]
        assert model.dof_armature[dof] == pytest.approx(link.gear_ratio**2 * link.motor_inertia, rel=1e-15)
        assert model.dof_damping[dof] == pytest.approx(link.gear_ratio**2 * link.viscous, rel=1e-15)
        assert model.dof_frictionloss[dof] == pytest.approx(abs(link.gear_ratio) * link.coulomb[0], rel=1e-15)
        assert model.actuator_trnid[j, 0] == joint and model.actuator_gear[j, 0] == 1.0
        # the Link's own fields, motor side, read back from the custom data
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, LINK_NUMERIC + link.name)
        start, size = model.numeric_adr[index], model.numeric_size[index]
        assert size == len(LINK_FIELDS)
        expected = [link.viscous, *link.coulomb, link.motor_inertia, link.gear_ratio, *link.stribeck, *link.sigmoid]
        assert model.numeric_data[start : start + size].tolist() == expected


def test_limits_and_the_base_transform() -> None:
    arm = load("scara")
    lower = np.where(np.isfinite(arm.qlim[0]), arm.qlim[0], -1.0)
    links = [
        dataclasses.replace(link, limits=(float(lower[j]), float(lower[j]) + 1.5)) for j, link in enumerate(arm.links)
    ]
    axis, angle = np.array([1.0, 2.0, -0.5]) / np.sqrt(5.25), 0.7
    cross = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    base = np.eye(4)
    base[:3, :3] = np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross  # Rodrigues
    base[:3, 3] = [0.3, -0.2, 1.0]
    moved = arm.replace(links, base=base)
    model = compiled(moved)
    assert model.jnt_limited.all()
    np.testing.assert_array_equal(model.jnt_range, np.array([link.limits for link in links]))
    errors = worst_errors(moved)
    assert max(errors.values()) < TOLERANCE, errors


def test_point_masses_change_m_by_less_than_1e_12() -> None:
    """two_link_planar's point masses have no exact MJCF (MuJoCo refuses zero moments): the smallest moment
    MuJoCo takes changes M by about 1e-14 relative."""
    arm = load("two_link_planar")
    text = to_mjcf(arm)
    assert "2e-14" in text
    errors = worst_errors(arm)
    print(f"two_link_planar: M off by {errors['M']:.2e} relative")
    assert 0 < errors["M"] < TOLERANCE


def test_the_pumas_third_link_needs_a_tendon() -> None:
    """Its principal moments break A + B >= C, which MuJoCo refuses: the excess turns with q2 + q3, a tendon."""
    model = compiled(load("puma560"))
    assert model.ntendon == 1
    assert mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TENDON, 0) == INERTIA_TENDON + "q3"
    assert model.tendon_armature[0] > 0


def test_a_body_with_no_exact_mjcf_is_refused() -> None:
    with pytest.raises(ad.ModelError, match=r"link 'q5'.*triangle inequality"):
        to_mjcf(load("stanford"))


def test_the_visual_capsules_leave_m_unchanged() -> None:
    arm = load("ur5")
    text = to_mjcf(arm)
    bare = "\n".join(line for line in text.splitlines() if 'type="capsule"' not in line)
    with_geoms, without = mujoco.MjModel.from_xml_string(text), mujoco.MjModel.from_xml_string(bare)
    assert with_geoms.ngeom > 0 and without.ngeom == 0
    np.testing.assert_array_equal(with_geoms.body_mass, without.body_mass)
    np.testing.assert_array_equal(with_geoms.body_inertia, without.body_inertia)
    assert (with_geoms.geom_contype == 0).all() and (with_geoms.geom_conaffinity == 0).all()


# ----- an arm with DC drives -----------------------------------------------------------------------------------
def puma_with_drives(**changes: object) -> ad.actuators.ActuatedArm:
    """The PUMA 560 with symmetric Coulomb friction, its motors as DC drives (K_M = K_b, a voltage limit)."""
    arm = load("puma560")
    arm = arm.replace([dataclasses.replace(link, coulomb=(link.coulomb[0], -link.coulomb[0])) for link in arm.links])
    electrics = {
        "torque_constant": 0.22,
        "back_emf": 0.22,
        "resistance": 2.1,
        "inductance": 2e-3,
        "voltage_limit": 40.0,
    }
    return with_actuators(*motor_drives(arm, **(electrics | changes)))


def test_dc_drives_become_dcmotor_actuators() -> None:
    actuated = puma_with_drives()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = mujoco.MjModel.from_xml_string(actuated.to_mjcf())
    assert model.nu == actuated.n and model.na == actuated.n
    for j, drive in enumerate(actuated.drives):
        assert model.actuator_dyntype[j] == mujoco.mjtDyn.mjDYN_DCMOTOR
        assert model.actuator_gainprm[j, :2].tolist() == [drive.resistance, math.sqrt(0.22 * 0.22)]
        assert model.actuator_dynprm[j, 0] == pytest.approx(drive.inductance / drive.resistance, rel=1e-15)
        assert model.actuator_gear[j, 0] == 1 / drive.gear_ratio
        assert model.actuator_armature[j] == drive.rotor_inertia
        assert model.actuator_damping[j] == drive.viscous
        assert model.actuator_ctrllimited[j] and model.actuator_ctrlrange[j].tolist() == [-40.0, 40.0]
        dof = model.jnt_dofadr[model.actuator_trnid[j, 0]]
        assert model.dof_frictionloss[dof] == pytest.approx(abs(1 / drive.gear_ratio) * drive.coulomb[0], rel=1e-15)
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, DRIVE_NUMERIC + actuated.robot.links[j].name)
        start = model.numeric_adr[index]
        data = model.numeric_data[start : start + model.numeric_size[index]]
        assert len(data) == len(DRIVE_FIELDS)
        assert dict(zip(DRIVE_FIELDS, data, strict=True))["gear_ratio"] == drive.gear_ratio
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
    mine, theirs = [], []
    for q, qd, qdd in zip(*random_states(actuated.n), strict=True):
        theirs.append(mujoco_quantities(model, q, qd, qdd)["M"])
        mine.append(actuated.inertia_matrix(q))
    error = relative(mine, theirs)
    print(f"puma560 with DC drives: M off by {error:.2e} relative")
    assert error < TOLERANCE


def test_drive_settings_without_a_counterpart_warn() -> None:
    arm, drives = motor_drives(load("puma560"), 0.22, 0.3, 2.1, 2e-3, current_limit=8.0)
    drives[1] = dataclasses.replace(drives[1], current_limit=math.inf, coulomb=(0.1, -0.1), stiffness=100.0)
    drives[2] = dataclasses.replace(drives[2], current_limit=math.inf, coulomb=(0.1, -0.1))
    drives[0] = dataclasses.replace(drives[0], coulomb=(0.2, -0.2))  # q4, q5, q6 keep asymmetric rotor friction
    actuated = with_actuators(arm, drives)
    with pytest.warns(UserWarning) as record:
        text = to_mjcf(actuated)
    messages = " ".join(str(item.message) for item in record)
    assert "'motor q2' on joint 'q2' (a flexible shaft" in messages
    assert "['motor q1', 'motor q4', 'motor q5', 'motor q6'] have a current limit" in messages
    assert "['motor q4', 'motor q5', 'motor q6'] have asymmetric rotor Coulomb friction" in messages
    assert "K_M != K_b" in messages and "motor q3" in messages
    model = mujoco.MjModel.from_xml_string(text)
    written = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(model.nu)]
    assert written == ["motor q1", "motor q3", "motor q4", "motor q5", "motor q6"]
    assert not model.actuator_forcelimited.any()  # the current limit is not written as a torque clamp


def test_a_hydraulic_drive_and_asymmetric_rotor_friction_are_named() -> None:
    robot = ad.Robot.from_dh([{"kind": "P", "mass": 1.0, "inertia": [0.1] * 3}, {"mass": 1.0, "inertia": [0.1] * 3}])
    motor = DCMotor(0.01, 0.001, 0.1, 0.1, 1.0, 1e-3, 0.1, coulomb=(0.2, -0.1), name="asymmetric")
    piston = _piston()
    actuated = with_actuators(robot, [piston, motor])
    with pytest.warns(UserWarning) as record:
        model = mujoco.MjModel.from_xml_string(to_mjcf(actuated))
    messages = " ".join(str(item.message) for item in record)
    assert f"'{piston.name}' on joint" in messages and "a hydraulic drive" in messages
    assert "drives ['asymmetric'] have asymmetric rotor Coulomb friction" in messages
    assert model.nu == 1 and mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, 0) == "asymmetric"


def _piston() -> Hydraulic:
    """A small linearised servo-valve piston."""
    import inspect

    parameters = inspect.signature(Hydraulic).parameters
    values = {name: 1.0 for name, p in parameters.items() if p.default is inspect.Parameter.empty}
    values["name"] = "piston"
    return Hydraulic(**values)


# ----- warnings and errors ---------------------------------------------------------------------------------------
def test_friction_mujoco_cannot_simulate_is_named_and_kept() -> None:
    arm = load("scara")
    links = list(arm.links)
    links[0] = dataclasses.replace(links[0], coulomb=(0.3, -0.1))
    links[1] = dataclasses.replace(links[1], stribeck=(0.2, 0.05))
    links[2] = dataclasses.replace(links[2], sigmoid=(0.5, 10.0, 0.1))
    changed = arm.replace(links)
    with pytest.warns(UserWarning, match="asymmetric Coulomb, Stribeck or sigmoid") as record:
        text = to_mjcf(changed)
    names = [link.name for link in links[:3]]
    assert str(names) in str(record[0].message)
    model = mujoco.MjModel.from_xml_string(text)
    for link in links[:3]:
        index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, LINK_NUMERIC + link.name)
        start = model.numeric_adr[index]
        data = dict(zip(LINK_FIELDS, model.numeric_data[start : start + len(LINK_FIELDS)], strict=True))
        assert (data["coulomb+"], data["coulomb-"]) == link.coulomb
        assert (data["stribeck_Fs"], data["stribeck_vs"]) == link.stribeck
        assert (data["sigmoid_A"], data["sigmoid_alpha"], data["sigmoid_shift"]) == link.sigmoid
    assert mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, LINK_NUMERIC + links[3].name) == -1


def test_the_file_is_written(tmp_path: Path) -> None:
    arm = load("scara")
    path = tmp_path / "scara.xml"
    text = arm.to_mjcf(path)
    assert path.read_text(encoding="utf-8") == text
    assert mujoco.MjModel.from_xml_path(str(path)).nv == arm.n


def test_errors(tmp_path: Path) -> None:
    with pytest.raises(ad.ModelError, match="symbolic"):
        to_mjcf(ad.models.two_link_planar(symbolic=True))
    with pytest.raises(ad.ModelError, match="needs an ArmModel"):
        to_mjcf("puma560")  # type: ignore[arg-type]
    with pytest.raises(ad.ModelError, match=r"missing.*arm\.xml: cannot write the MJCF"):
        to_mjcf(load("scara"), tmp_path / "missing" / "arm.xml")


def test_the_quaternion_gives_the_rotation_back_near_half_turns() -> None:
    """kinematics.quaternion (the MJCF writer's and the viewer's): MuJoCo's mju_quat2Mat of it is the rotation to
    1e-15, for random rotations and for turns of pi and pi - 1e-9 about random axes, with w >= 0."""
    from armdyn.kinematics import quaternion

    rng = np.random.default_rng(4)
    rotations = [np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(50)]
    rotations = [r * np.sign(np.linalg.det(r)) for r in rotations]
    for angle in (np.pi, np.pi - 1e-9):
        for axis in rng.normal(size=(10, 3)):
            u = axis / np.linalg.norm(axis)
            cross = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
            rotations.append(np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross)
    for rotation in rotations:
        q = np.array(quaternion(rotation))
        back = np.zeros(9)
        mujoco.mju_quat2Mat(back, q)
        assert q[0] >= 0 and abs(np.linalg.norm(q) - 1) < 1e-15
        assert np.abs(back.reshape(3, 3) - rotation).max() < 1e-15
