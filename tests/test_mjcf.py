"""armdyn.load_mjcf and from_mujoco against MuJoCo itself: M(q), the bias (qfrc_bias) and mj_inverse on
example-robot-data's URDFs as MuJoCo compiles them and on the MJCF arms that robosuite ships; the dcmotor
actuators as the DC drives of Section 3.6, simulated by both; and the models a tree cannot hold."""

from __future__ import annotations

import dataclasses
import importlib.metadata
import itertools
import warnings
from pathlib import Path

import numpy as np
import pytest
from lxml import etree
from scipy.integrate import solve_ivp

import armdyn as ad
from armdyn.errors import ModelError
from armdyn.io.mjcf import _joint_name, from_mujoco, load_mjcf
from tests.helpers import ROBOTS

mujoco = pytest.importorskip("mujoco")

STATES = 20
TOLERANCE = 1e-12
# robosuite's arms (the package's own assets, read by MuJoCo; robosuite itself is never imported) and
# robosuite-models' arms: the MJCF arms robot-learning users know best
ROBOSUITE_ARMS = ["baxter", "iiwa", "jaco", "kinova3", "panda", "sawyer", "spot_arm", "tiago", "ur5e", "xarm7"]
ROBOSUITE_MODELS_ARMS = ["aloha", "arx5", "pr2", "vx300s", "yumi", "z1"]
FLOATING = [("robosuite", "gr1"), ("robosuite", "spot"), ("robosuite-models", "go2"), ("robosuite-models", "h1")]


def _assets(distribution: str) -> Path | None:
    folder = {"robosuite": "robosuite/models/assets/robots", "robosuite-models": "robosuite_models/assets/robots"}
    try:
        return Path(importlib.metadata.distribution(distribution).locate_file(folder[distribution]))
    except importlib.metadata.PackageNotFoundError:
        return None


def _robot_xml(distribution: str, name: str) -> Path:
    root = _assets(distribution)
    if root is None:
        pytest.skip(f"{distribution} is not installed (make test installs it, files only: pip install --no-deps)")
    return root / name / "robot.xml"


# ----- MuJoCo as the oracle -----------------------------------------------------------------------------------
def mujoco_dynamics(model, q, qd, qdd, dofs):
    """M, qfrc_bias and mj_inverse's qfrc_inverse at each state, on the degrees of freedom ``dofs`` (the others at
    qpos0 and at rest). Friction loss, contacts, joint limits, springs and equality constraints are switched off:
    what is compared is M qdd + C qd + G + damping qd."""
    model.opt.disableflags |= (
        mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS
        | mujoco.mjtDisableBit.mjDSBL_CONTACT
        | mujoco.mjtDisableBit.mjDSBL_LIMIT
        | mujoco.mjtDisableBit.mjDSBL_SPRING
        | mujoco.mjtDisableBit.mjDSBL_EQUALITY  # what armdyn drops holds only locked joints
    )
    data = mujoco.MjData(model)
    qpos_of = np.array([model.jnt_qposadr[model.dof_jntid[d]] for d in dofs])
    M, bias, inverse = [], [], []
    for k in range(len(q)):
        data.qpos[:], data.qvel[:] = model.qpos0, 0.0
        data.qpos[qpos_of], data.qvel[dofs] = q[k], qd[k]
        mujoco.mj_forward(model, data)
        full = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, full)
        M.append(full[np.ix_(dofs, dofs)])
        bias.append(data.qfrc_bias[dofs].copy())
        data.qacc[:] = 0.0
        data.qacc[dofs] = qdd[k]
        mujoco.mj_inverse(model, data)
        inverse.append(data.qfrc_inverse[dofs].copy())
    return np.array(M), np.array(bias), np.array(inverse)


def random_states(arm, seed: int = 0):
    rng = np.random.default_rng(seed)
    lower, upper = arm.qlim
    finite = np.isfinite(lower) & np.isfinite(upper) & (upper - lower < 100)
    lower, upper = np.where(finite, lower, -np.pi), np.where(finite, upper, np.pi)
    q = rng.uniform(lower, upper, (STATES, arm.n))
    return q, rng.normal(0, 1.5, (STATES, arm.n)), rng.normal(0, 3, (STATES, arm.n))


def relative(ours: np.ndarray, theirs: np.ndarray) -> float:
    return float(np.abs(ours - theirs).max() / max(np.abs(theirs).max(), 1e-300))


def without_coulomb(arm):
    return arm.replace([dataclasses.replace(link, coulomb=(0.0, 0.0)) for link in arm.links])


def assert_same_dynamics(model, arm, label: str, seed: int = 0) -> tuple[float, float, float]:
    """armdyn's M, bias and inverse dynamics (its viscous friction in, Coulomb out) equal MuJoCo's to 1e-12."""
    names = [_joint_name(model, j) for j in range(model.njnt)]
    dofs = np.array([model.jnt_dofadr[names.index(name)] for name in arm.joint_names])
    q, qd, qdd = random_states(arm, seed)
    M, bias, inverse = mujoco_dynamics(model, q, qd, qdd, dofs)
    errors = (
        relative(arm.inertia_matrix(q), M),
        relative(arm.without_friction().inverse_dynamics(q, qd, np.zeros_like(q)), bias),
        relative(without_coulomb(arm).inverse_dynamics(q, qd, qdd), inverse),
    )
    print(f"{label}: n = {arm.n}, relative errors M {errors[0]:.1e}, bias {errors[1]:.1e}, inverse {errors[2]:.1e}")
    assert max(errors) < TOLERANCE, (label, errors)
    return errors


# ----- example-robot-data's URDFs, compiled by MuJoCo ------------------------------------------------------------
def compiled_urdf(path: Path):
    """MuJoCo's compilation of a URDF, its <visual> and <collision> removed (their package:// meshes are not on
    MuJoCo's path; the inertias are the file's own), or None with MuJoCo's reason when it refuses the file."""
    tree = etree.parse(str(path))
    for element in tree.xpath("//visual | //collision"):
        element.getparent().remove(element)
    try:
        return mujoco.MjModel.from_xml_string(etree.tostring(tree, encoding="unicode")), ""
    except ValueError as error:
        return None, str(error).splitlines()[0]


URDF_FILES = sorted(path.relative_to(ROBOTS).as_posix() for path in ROBOTS.rglob("*.urdf"))


def _locked_equalities(model) -> dict[str, float]:
    """The joints of MuJoCo's joint equalities (a URDF's mimic joints), locked at 0."""
    joints = {int(j) for e in range(model.neq) for j in (model.eq_obj1id[e], model.eq_obj2id[e]) if j >= 0}
    return {_joint_name(model, j): 0.0 for j in joints}


@pytest.mark.slow
def test_every_urdf_that_mujoco_compiles_has_mujocos_dynamics() -> None:
    """Each example-robot-data URDF that MuJoCo compiles (its inertias must pass MuJoCo's checks) reads into the
    same M, bias and inverse dynamics; mimic joints (MuJoCo's joint equalities) are locked."""
    compared, refused_by_mujoco, without_joints = [], {}, []
    for relative_path in URDF_FILES:
        model, reason = compiled_urdf(ROBOTS / relative_path)
        if model is None:
            refused_by_mujoco[relative_path] = reason
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                arm = from_mujoco(model, locked=_locked_equalities(model), strict=False)
            except ModelError as error:
                assert "no hinge or slide joint" in str(error), (relative_path, error)
                without_joints.append(relative_path)
                continue
        assert_same_dynamics(model, arm, relative_path)
        compared.append(relative_path)
    print(f"compared {len(compared)} of {len(URDF_FILES)} URDFs; MuJoCo refuses {len(refused_by_mujoco)}:")
    for name, reason in refused_by_mujoco.items():
        print(f"  {name}: {reason}")
    print(f"no moving joint: {without_joints}")
    assert len(compared) >= 40
    assert {"ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf"} <= set(compared)
    assert all("inertia" in reason or "mjMINVAL" in reason for reason in refused_by_mujoco.values())


@pytest.mark.parametrize("name", ["ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf"])
def test_the_ur5_and_panda_as_mujoco_reads_them(name: str) -> None:
    model, _ = compiled_urdf(ROBOTS / name)
    arm = from_mujoco(model, locked=_locked_equalities(model))
    assert_same_dynamics(model, arm, name)
    # and the same arm as armdyn reads the URDF itself (Pinocchio's reading, tested elsewhere)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        direct = ad.load_urdf(ROBOTS / name, locked=_locked_equalities(model))
    q, qd, qdd = random_states(arm)
    ours = direct.inverse_dynamics(q[:, : direct.n], qd[:, : direct.n], qdd[:, : direct.n])
    theirs = arm.inverse_dynamics(q[:, : arm.n], qd[:, : arm.n], qdd[:, : arm.n])
    assert direct.joint_names == arm.joint_names
    assert relative(ours, theirs) < 1e-9  # MuJoCo rediagonalizes each inertia: 1e-16 in its principal axes


# ----- robosuite's MJCF arms -------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("distribution", "name"),
    [("robosuite", name) for name in ROBOSUITE_ARMS] + [("robosuite-models", name) for name in ROBOSUITE_MODELS_ARMS],
)
def test_robosuite_arms_have_mujocos_dynamics(distribution: str, name: str) -> None:
    path = _robot_xml(distribution, name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pr2 and yumi have joint springs, named in a warning (tested below)
        arm = load_mjcf(path)
    model = mujoco.MjModel.from_xml_path(str(path))
    assert arm.n == model.nv
    assert_same_dynamics(model, arm, f"{distribution} {name}")


def test_robosuite_panda_keeps_its_joint_friction_and_armature() -> None:
    path = _robot_xml("robosuite", "panda")
    arm = load_mjcf(path)
    model = mujoco.MjModel.from_xml_path(str(path))
    for link in arm.links:
        dof = model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, link.name)]
        assert link.viscous == model.dof_damping[dof] and link.viscous > 0
        assert link.coulomb == (model.dof_frictionloss[dof], -model.dof_frictionloss[dof])
        assert link.motor_inertia == model.dof_armature[dof] and link.gear_ratio == 1.0
    assert arm.name == "panda" and np.array_equal(arm.gravity, model.opt.gravity)


@pytest.mark.parametrize(("distribution", "name"), FLOATING)
def test_a_floating_base_locked_is_the_fixed_base_arm(distribution: str, name: str) -> None:
    path = _robot_xml(distribution, name)
    model = mujoco.MjModel.from_xml_path(str(path))
    free = next(j for j in range(model.njnt) if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE)
    free_name = _joint_name(model, free)
    with pytest.raises(ModelError, match=rf"free joint '{free_name}'.*floating base.*locked="):
        load_mjcf(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = load_mjcf(path, locked={free_name: None})
    assert arm.n == model.nv - 6
    assert_same_dynamics(model, arm, f"{distribution} {name} (base locked at qpos0)")
    # the base held elsewhere: the tool moves with it
    pose = [0.5, -0.2, 1.0, np.cos(0.3), 0.0, 0.0, np.sin(0.3)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        moved = load_mjcf(path, locked={free_name: pose})
    start = model.qpos0[model.jnt_qposadr[free] :][:7]
    data = mujoco.MjData(model)
    data.qpos[:7] = pose
    mujoco.mj_kinematics(model, data)
    body = model.jnt_bodyid[model.dof_jntid[arm.n + 5]]
    expected = np.eye(4)
    expected[:3, :3], expected[:3, 3] = data.xmat[body].reshape(3, 3), data.xpos[body]
    q = model.qpos0[7:]
    assert np.allclose(moved.tool_pose(q), expected, atol=1e-12)
    assert not np.allclose(start, pose)


# ----- frames: MuJoCo's bodies are armdyn's link frames -----------------------------------------------------------
def test_link_frames_are_mujocos_body_frames_with_anchors_refs_and_several_joints_in_a_body() -> None:
    xml = """<mujoco model="frames">
      <compiler angle="radian"/>
      <worldbody>
        <body name="a" pos="0.1 0.2 0.3" quat="0.9 0.1 0.3 0.2">
          <joint name="ja" type="hinge" axis="0.3 0.4 0.5" pos="0.05 -0.02 0.01" ref="0.4"/>
          <joint name="jb" type="slide" axis="1 -1 0.2" ref="-0.1"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
          <body name="b" pos="0.3 0 0" euler="0.2 -0.4 1.0">
            <joint name="jc" type="hinge" axis="0 1 0" pos="0 0 0.05"/>
            <geom type="box" size="0.05 0.1 0.2" pos="0.1 0 0"/>
            <body name="c" pos="0.2 0.1 0"><geom type="sphere" size="0.05"/><site name="tip" pos="0.05 0 0"/></body>
          </body>
        </body>
      </worldbody>
    </mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    arm = load_mjcf(xml, tool_link="tip")
    assert arm.joint_names == ["ja", "jb", "jc"] and arm.kinds == ["revolute", "prismatic", "revolute"]
    assert_same_dynamics(model, arm, "frames")
    data = mujoco.MjData(model)
    for q in random_states(arm)[0]:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        tool = arm.tool_pose(q)
        site = model.site("tip").id
        assert np.allclose(tool[:3, 3], data.site_xpos[site], atol=1e-14)
        assert np.allclose(tool[:3, :3], data.site_xmat[site].reshape(3, 3), atol=1e-14)
        transforms = arm.link_transforms(q)
        for index, body in ((1, "a"), (2, "b")):  # body a has two joints: its frame is the second link's
            assert np.allclose(transforms[index][:3, 3], data.xpos[model.body(body).id], atol=1e-14)
            assert np.allclose(transforms[index][:3, :3], data.xmat[model.body(body).id].reshape(3, 3), atol=1e-14)


# ----- the dcmotor as the DC drive of Section 3.6 ----------------------------------------------------------------
DC_ARM = """<mujoco model="two joints with DC motors">
  <option gravity="0 0 -9.81" integrator="RK4" timestep="{step!r}"/>
  <worldbody>
    <body name="upper">
      <joint name="shoulder" axis="0 0 1" damping="0.05" armature="0.01" frictionloss="0"/>
      <inertial pos="0.2 0 0" mass="2" diaginertia="0.01 0.02 0.02"/>
      <body name="fore" pos="0.4 0 0">
        <joint name="elbow" axis="0 1 0" damping="0.02"/>
        <inertial pos="0.15 0 0.02" mass="1" diaginertia="0.005 0.01 0.01"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <dcmotor name="shoulder motor" joint="shoulder" gear="50" resistance="1.2" motorconst="0.05 0.05"
             inductance="0.002 0" armature="2e-5" damping="1e-5" ctrlrange="-24 24"/>
    <dcmotor name="elbow motor" joint="elbow" gear="-30" resistance="2.0" motorconst="0.04 0.04"
             inductance="0.003 0" armature="1e-5" damping="2e-5"/>
  </actuator>
</mujoco>"""
VOLTAGES = np.array([6.0, -4.0])


def test_dcmotors_become_dc_drives() -> None:
    arm = load_mjcf(DC_ARM.format(step=1e-3), drives=True)
    assert isinstance(arm, ad.actuators.ActuatedArm)
    shoulder, elbow = arm.drives
    assert shoulder.name == "shoulder motor" and shoulder.gear_ratio == 1 / 50 and elbow.gear_ratio == -1 / 30
    assert shoulder.resistance == 1.2 and shoulder.torque_constant == shoulder.back_emf == pytest.approx(0.05)
    assert shoulder.inductance == pytest.approx(0.002, rel=1e-15) and elbow.inductance == pytest.approx(0.003)
    assert shoulder.rotor_inertia == pytest.approx(2e-5 + 0.01 / 50**2, rel=1e-15) and shoulder.viscous == 1e-5
    assert shoulder.voltage_limit == 24.0 and elbow.voltage_limit == np.inf
    assert arm.robot.links[0].viscous == 0.05 and arm.robot.links[0].motor_inertia == 0.0


def test_dcmotor_rates_equal_mujocos_at_random_states() -> None:
    """MuJoCo's di/dt and M are armdyn's; its qacc is armdyn's with its one-step-ahead (actearly) current."""
    step = 1e-3
    arm = load_mjcf(DC_ARM.format(step=step), drives=True)
    model = mujoco.MjModel.from_xml_string(DC_ARM.format(step=step))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(36)
    tau_e = np.array([d.inductance / d.resistance for d in arm.drives])
    psi = tau_e * -np.expm1(-step / tau_e)
    for _ in range(STATES):
        q, qd, i, v = rng.uniform(-3, 3, 2), rng.normal(0, 2, 2), rng.normal(0, 3, 2), rng.uniform(-20, 20, 2)
        data.qpos[:], data.qvel[:], data.act[:], data.ctrl[:] = q, qd, i, v
        mujoco.mj_forward(model, data)
        rates = arm.state_derivative(np.concatenate([q, qd, i]), v)
        assert np.allclose(data.act_dot, rates[4:], rtol=1e-12, atol=1e-12 * np.abs(rates[4:]).max())
        full = np.zeros((2, 2))
        mujoco.mj_fullM(model, data, full)
        assert relative(arm.inertia_matrix(q), full) < TOLERANCE
        ahead = arm.state_derivative(np.concatenate([q, qd, i + psi * rates[4:]]), v)
        assert np.allclose(data.qacc, ahead[2:4], rtol=1e-11, atol=1e-11 * np.abs(ahead[2:4]).max())


def mujoco_run(text: str, step: float, duration: float, every: float, voltages: np.ndarray) -> np.ndarray:
    """[q, qd, i] every ``every`` seconds under constant voltages, from rest at q = 0, by MuJoCo's RK4 at ``step``."""
    model = mujoco.MjModel.from_xml_string(text)
    model.opt.timestep, model.opt.integrator = step, mujoco.mjtIntegrator.mjINT_RK4
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_LIMIT  # as armdyn's full model: no joint stops
    data = mujoco.MjData(model)
    data.ctrl[:] = voltages
    stride = round(every / step)
    samples = [np.concatenate([data.qpos, data.qvel, data.act])]
    for k in range(1, round(duration / step) + 1):
        mujoco.mj_step(model, data)
        if k % stride == 0:
            samples.append(np.concatenate([data.qpos, data.qvel, data.act]))
    return np.array(samples)


def assert_same_run_over_one_second(arm, text: str, voltages: np.ndarray, label: str) -> None:
    """Joint angles, speeds and currents over 1 s under constant voltages: MuJoCo's RK4 (first order in h on a
    dcmotor with inductance, whose force uses the current one step ahead) at h, h/2 and h/4, extrapolated twice
    (Richardson), against armdyn's full model (ActuatedArm.state_derivative) integrated to 1e-12: within 1e-6 of
    each signal's range."""
    duration, every = 1.0, 0.01
    times = np.linspace(0.0, duration, round(duration / every) + 1)
    exact = solve_ivp(
        lambda _, x: arm.state_derivative(x, voltages), (0.0, duration), np.zeros(arm.n_states), method="DOP853",
        rtol=1e-12, atol=1e-12, t_eval=times,
    ).y.T  # fmt: skip
    runs = [mujoco_run(text, h, duration, every, voltages) for h in (1e-4, 5e-5, 2.5e-5)]
    once = [2 * fine - coarse for coarse, fine in itertools.pairwise(runs)]
    twice = (4 * once[1] - once[0]) / 3
    scale = np.abs(exact).max(axis=0)
    error = np.abs(twice - exact).max(axis=0) / scale
    print(f"{label}: relative errors of [q, qd, i] after two extrapolations: {error}; raw at h/4: "
          f"{np.abs(runs[-1] - exact).max(axis=0) / scale}")  # fmt: skip
    assert np.all(np.ptp(exact[:, : arm.n], axis=0) > 0.2)  # the arm really moves
    assert np.all(error < 1e-6)


@pytest.mark.slow
def test_dcmotor_arm_simulated_by_mujoco_and_by_armdyn_agree_over_one_second() -> None:
    """The arm of an MJCF file with dcmotors, swinging under gravity, as MuJoCo runs it and as armdyn's drives do."""
    arm = load_mjcf(DC_ARM.format(step=1e-3), drives=True)
    assert_same_run_over_one_second(arm, DC_ARM.format(step=1e-3), VOLTAGES, "load_mjcf")


@pytest.mark.slow
def test_an_exported_arm_with_dc_drives_runs_in_mujoco_as_in_armdyn() -> None:
    """The other way: the SCARA with DC drives written by to_mjcf, run by MuJoCo, against armdyn's own model."""
    from armdyn.actuators import motor_drives, with_actuators

    scara = ad.models.load("scara").without_friction().without_motors()
    n = scara.n
    motors = scara.replace([dataclasses.replace(link, motor_inertia=2e-5, gear_ratio=30.0) for link in scara.links])
    arm, drives = motor_drives(motors, 0.05, 0.05, 1.5, 2e-3)
    actuated = with_actuators(arm, drives)
    voltages = np.linspace(3.0, -2.0, n)
    assert_same_run_over_one_second(actuated, actuated.to_mjcf(), voltages, "to_mjcf")


def test_dcmotor_settings_without_a_counterpart_are_named() -> None:
    xml = DC_ARM.format(step=1e-3).replace('armature="1e-5"', 'armature="1e-5" cogging="0.01 6 0"')
    with pytest.warns(UserWarning, match=r"dcmotor 'elbow motor'.*cogging"):
        load_mjcf(xml, drives=True)
    asymmetric = DC_ARM.format(step=1e-3).replace('ctrlrange="-24 24"', 'ctrlrange="-12 24"')
    with pytest.warns(UserWarning, match=r"dcmotor 'shoulder motor'.*asymmetric ctrlrange"):
        arm = load_mjcf(asymmetric, drives=True)
    assert arm.drives[0].voltage_limit == np.inf


def test_drives_need_a_dcmotor_on_every_joint() -> None:
    xml = DC_ARM.format(step=1e-3).replace(
        """<dcmotor name="elbow motor" joint="elbow" gear="-30" resistance="2.0" motorconst="0.04 0.04"
             inductance="0.003 0" armature="1e-5" damping="2e-5"/>""",
        '<position name="elbow servo" joint="elbow" kp="50" kv="2"/>',
    )
    with pytest.raises(ModelError, match=r"joint 'elbow' has 'elbow servo' \(position\).*drives=False"):
        load_mjcf(xml, drives=True)
    arm = load_mjcf(xml)  # the Robot: its input is the joint torque
    assert isinstance(arm, ad.Robot) and arm.n == 2
    # the motor's rotor still counts in M, as in MuJoCo's (armature, gear^2 times the actuator's)
    assert arm.links[0].motor_inertia == pytest.approx(0.01 + 50**2 * 2e-5, rel=1e-15)


# ----- what a fixed-base tree cannot hold, and files MuJoCo cannot compile ---------------------------------------
def test_a_ball_joint_a_tendon_and_a_loop_are_refused_by_name() -> None:
    ball = """<mujoco><worldbody><body name="b"><joint name="wrist" type="ball"/><geom size="0.1"/></body>
              </worldbody></mujoco>"""
    with pytest.raises(ModelError, match=r"ball joints \['wrist'\]"):
        load_mjcf(ball)
    two = """<mujoco><worldbody>
      <body name="a"><joint name="j1" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
        <site name="s1" pos="0.5 0 0"/>
        <body name="b" pos="0.5 0 0"><joint name="j2" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.5 0 0"
          size="0.05"/><site name="s2" pos="0.5 0 0"/></body></body>
      <body name="c" pos="1 0 0.5"><joint name="j3" axis="0 1 0"/><geom size="0.05"/></body>
      </worldbody>{extra}</mujoco>"""
    tendon = '<tendon><fixed name="coupling"><joint joint="j1" coef="1"/><joint joint="j2" coef="-1"/></fixed></tendon>'
    with pytest.raises(ModelError, match=r"tendons \['coupling'\]"):
        load_mjcf(two.format(extra=tendon))
    loop = '<equality><connect name="closing" body1="b" body2="c" anchor="0.5 0 0"/></equality>'
    with pytest.raises(ModelError, match=r"equality constraints \['closing \(connect\)'\].*loop"):
        load_mjcf(two.format(extra=loop))
    coupled = '<equality><joint name="mimic" joint1="j2" joint2="j1"/></equality>'
    with pytest.raises(ModelError, match=r"'mimic \(joint j2 and j1\)'"):
        load_mjcf(two.format(extra=coupled))
    assert load_mjcf(two.format(extra=coupled), locked={"j1": 0.0, "j2": 0.0}).joint_names == ["j3"]


def test_files_mujoco_cannot_compile_are_refused_with_its_message_and_the_file(tmp_path: Path) -> None:
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body><joint type='hinge'/><geom size='x'/></body></worldbody></mujoco>")
    with pytest.raises(ModelError, match=r"broken.xml: MuJoCo cannot compile it: .*"):
        load_mjcf(broken)
    meshed = tmp_path / "meshed.xml"
    meshed.write_text(
        "<mujoco><asset><mesh name='forearm' file='meshes/forearm.stl'/></asset><worldbody><body><joint/>"
        "<geom type='mesh' mesh='forearm'/></body></worldbody></mujoco>"
    )
    with pytest.raises(ModelError, match=r"meshed.xml: MuJoCo cannot compile it: .*forearm.stl"):
        load_mjcf(meshed)
    with pytest.raises(ModelError, match=r"nothere.xml: no such MJCF file"):
        load_mjcf(tmp_path / "nothere.xml")
    with pytest.raises(ModelError, match=r"the MJCF text: MuJoCo cannot compile it"):
        load_mjcf("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(TypeError, match=r"source must be MJCF text"):
        load_mjcf(3.5)  # type: ignore[arg-type]


def test_bad_arguments_are_refused_by_name() -> None:
    xml = DC_ARM.format(step=1e-3)
    with pytest.raises(ModelError, match=r"cannot lock joint 'wrist'.*its joints: \['shoulder', 'elbow'\]"):
        load_mjcf(xml, locked={"wrist": 0.0})
    with pytest.raises(ModelError, match=r"tool_link 'hand' is neither a body nor a site"):
        load_mjcf(xml, tool_link="hand")
    with pytest.raises(ModelError, match=r"gravity"):
        load_mjcf(xml, gravity=[0.0, np.nan, 0.0])
    with pytest.raises(ModelError, match=r"model must be a mujoco.MjModel"):
        from_mujoco("not a model")
    still = """<mujoco><worldbody><body><geom size="0.1"/></body></worldbody></mujoco>"""
    with pytest.raises(ModelError, match=r"no hinge or slide joint"):
        load_mjcf(still)
    massless = """<mujoco><worldbody><body><joint name="spin" axis="0 0 1"/>
                  <inertial pos="0 0 0.3" mass="1" diaginertia="1e-9 1e-9 1e-9"/></body></worldbody></mujoco>"""
    assert load_mjcf(massless).n == 1  # a point-like mass on its axis still has inertia 1e-9: it moves
    springs = DC_ARM.format(step=1e-3).replace('damping="0.02"', 'damping="0.02" stiffness="3"')
    with pytest.warns(UserWarning, match=r"springs \(stiffness\).*\['elbow'\]"):
        load_mjcf(springs)


def test_gravity_is_the_models_unless_given_or_disabled() -> None:
    xml = DC_ARM.format(step=1e-3).replace('gravity="0 0 -9.81"', 'gravity="0 -3 -9"')
    assert np.array_equal(load_mjcf(xml).gravity, [0.0, -3.0, -9.0])
    assert np.array_equal(load_mjcf(xml, gravity=[0, 0, -1]).gravity, [0.0, 0.0, -1.0])
    off = xml.replace("<option ", '<option><flag gravity="disable"/></option><option ')
    assert np.array_equal(load_mjcf(off).gravity, [0.0, 0.0, 0.0])


# ----- the command line -------------------------------------------------------------------------------------------
def test_commands_take_an_mjcf_file(tmp_path: Path) -> None:
    from tests.helpers import assert_one_error_line, invoke

    path = tmp_path / "driven.xml"
    path.write_text(DC_ARM.format(step=1e-3))
    shown = invoke("show", path, "--actuators", "file")
    assert shown.exit_code == 0, shown.output
    assert "two joints with DC motors" in shown.stdout and "shoulder motor" in shown.stdout
    run = invoke("simulate", path, "--actuators", "file", "--t-final", "0.05")
    assert run.exit_code == 0, run.output
    assert_one_error_line(invoke("show", tmp_path / "nothere.xml"), "nothere.xml: no such MJCF file")
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body><joint type='ball'/><geom size='0.1'/></body></worldbody></mujoco>")
    assert_one_error_line(invoke("show", broken), "broken.xml", "ball joints")
    assert_one_error_line(invoke("show", "puma560", "--actuators", "file"), "--actuators file reads the dcmotor")


@pytest.mark.parametrize("name", ["panda", "iiwa", "ur5e", "sawyer", "jaco", "kinova3", "xarm7"])
def test_pinocchios_own_mjcf_reader_gives_the_same_rigid_body_dynamics(name: str) -> None:
    """A second, independent reading of the same files: Pinocchio's MJCF parser (which leaves out armature,
    damping and friction loss) and armdyn's rigid-body inverse dynamics agree to 1e-12."""
    pin = pytest.importorskip("pinocchio")
    path = _robot_xml("robosuite", name)
    model = pin.buildModelFromMJCF(str(path))
    data = model.createData()
    arm = load_mjcf(path).without_friction().without_motors()
    ids = [model.getJointId(joint) for joint in arm.joint_names]
    q_index, v_index = [model.joints[i].idx_q for i in ids], [model.joints[i].idx_v for i in ids]
    q, qd, qdd = random_states(arm)
    theirs = []
    for k in range(STATES):
        configuration, velocity, acceleration = pin.neutral(model), np.zeros(model.nv), np.zeros(model.nv)
        configuration[q_index], velocity[v_index], acceleration[v_index] = q[k], qd[k], qdd[k]
        theirs.append(pin.rnea(model, data, configuration, velocity, acceleration)[v_index])
    assert relative(arm.inverse_dynamics(q, qd, qdd), np.array(theirs)) < TOLERANCE


# ----- round trips: to_mjcf then load_mjcf, to_urdf then load_urdf -------------------------------------------------
def _with_friction_and_motors(arm):
    """The arm with viscous, Coulomb (symmetric on even joints, asymmetric on odd), rotor inertia and gears on every
    joint, and Stribeck and sigmoid friction on the first two: what the files must carry."""
    rng = np.random.default_rng(7)
    links = []
    for j, link in enumerate(arm.links):
        plus = float(rng.uniform(0.05, 0.3))
        changes = {
            "viscous": float(rng.uniform(0.001, 0.01)),
            "coulomb": (plus, -plus if j % 2 == 0 else -0.5 * plus),
            "motor_inertia": float(rng.uniform(1e-5, 1e-4)),
            "gear_ratio": float(rng.choice([-1, 1]) * rng.uniform(5, 60)),
        }
        if j == 0:
            changes["stribeck"] = (0.2, 0.05)
        if j == 1:
            changes["sigmoid"] = (0.5, 10.0, 0.1)
        links.append(dataclasses.replace(link, **changes))
    return arm.replace(links)


def _round_trip_arms():
    arms = [(name, ad.models.load(name)) for name in ad.models.names() if name != "stanford"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arms += [("ur5", ad.load_urdf(ROBOTS / "ur_description/urdf/ur5_robot.urdf"))]
        arms += [("panda", ad.load_urdf(ROBOTS / "panda_description/urdf/panda.urdf"))]
    return arms + [(f"{name} with friction and motors", _with_friction_and_motors(arm)) for name, arm in arms]


ROUND_TRIP_ARMS = _round_trip_arms()


def assert_same_arm(back, arm, label: str) -> None:
    """The same M, G, inverse dynamics with friction, friction forces and tool pose at 20 states, to 1e-12."""
    assert back.joint_names == arm.joint_names and back.kinds == arm.kinds
    q, qd, qdd = random_states(arm, seed=3)
    errors = {
        "M": relative(back.inertia_matrix(q), arm.inertia_matrix(q)),
        "G": relative(back.gravity_vector(q), arm.gravity_vector(q)),
        "tau": relative(back.inverse_dynamics(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd)),
        "F": relative(back.friction(qd), arm.friction(qd)) if np.any(arm.friction(qd)) else 0.0,
        "tool": float(np.abs(back.tool_pose(q) - arm.tool_pose(q)).max()),
    }
    print(label, {key: f"{value:.1e}" for key, value in errors.items()})
    assert max(errors.values()) < TOLERANCE, (label, errors)
    limits = np.where(np.abs(back.qlim) >= 1e16, np.copysign(np.inf, back.qlim), back.qlim)  # URDF's "none"
    assert np.array_equal(limits, arm.qlim) and np.array_equal(back.gravity, arm.gravity)


@pytest.mark.parametrize(("name", "arm"), ROUND_TRIP_ARMS, ids=[name for name, _ in ROUND_TRIP_ARMS])
def test_load_mjcf_of_to_mjcf_is_the_same_arm(name: str, arm) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # friction MuJoCo cannot simulate, the PUMA's unphysical third link
        text = arm.to_mjcf()
        back = load_mjcf(text, tool_link="tool")
    assert_same_arm(back, arm, f"MJCF {name}")


@pytest.mark.parametrize(("name", "arm"), ROUND_TRIP_ARMS, ids=[name for name, _ in ROUND_TRIP_ARMS])
def test_load_urdf_of_to_urdf_is_the_same_arm(name: str, arm, tmp_path: Path) -> None:
    path = tmp_path / "arm.urdf"
    arm.to_urdf(path)
    moments = [np.linalg.eigvalsh(link.inertial.inertia) for link in arm.links]
    physical = all(a + b >= c - 1e-12 * c for a, b, c in moments)  # the PUMA's and the cylindrical arm's are not
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        back = ad.load_urdf(path, gravity=arm.gravity, tool_link="tool", strict=physical)
    assert_same_arm(back, arm, f"URDF {name}")


def test_the_stanford_arms_unphysical_link_has_no_mjcf() -> None:
    """Its fifth link's principal moments (0, 0.0004, 0.003) break the triangle inequality, which MuJoCo refuses,
    and the link turns about its largest moment's axis at rates that change with q (no tendon can hold it)."""
    with pytest.raises(ModelError, match=r"link 'q5'.*triangle inequality"):
        ad.models.load("stanford").to_mjcf()


def test_an_arm_with_its_dc_drives_comes_back_with_them() -> None:
    """The PUMA 560 with DC drives (current limits, K_M != K_b on one, asymmetric rotor friction on others):
    load_mjcf(drives=True) reads armdyn's record of each drive, so the drives, M' and the full model's state
    derivative are the same."""
    from armdyn.actuators import motor_drives, with_actuators

    arm, drives = motor_drives(ad.models.puma560(), 0.22, 0.3, 2.1, 2e-3, voltage_limit=40.0, current_limit=8.0)
    drives[2] = dataclasses.replace(drives[2], back_emf=0.25)
    actuated = with_actuators(arm, drives)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        back = load_mjcf(actuated.to_mjcf(), drives=True, tool_link="tool")
    assert [vars(d) | {"name": ""} for d in back.drives] == [vars(d) | {"name": ""} for d in actuated.drives]
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.uniform(-1, 1, (STATES, 12)), rng.uniform(-3, 3, (STATES, 6))], axis=1)
    v = rng.uniform(-30, 30, (STATES, 6))
    assert relative(back.state_derivative(x, v), actuated.state_derivative(x, v)) < TOLERANCE
    assert relative(back.inertia_matrix(x[:, :6]), actuated.inertia_matrix(x[:, :6])) < TOLERANCE


def test_convert_writes_each_format_and_show_reads_it_back(tmp_path: Path) -> None:
    from tests.helpers import assert_one_error_line, invoke

    puma = ad.models.puma560()
    q = np.array(puma.configurations["qn"])
    for suffix in (".xml", ".urdf", ".json"):
        path = tmp_path / f"puma560{suffix}"
        done = invoke("convert", "puma560", path)
        assert done.exit_code == 0, done.output
        assert f"wrote {path}" in done.stdout
        shown = invoke("show", path, "--no-strict")
        assert shown.exit_code == 0, shown.output
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        back = load_mjcf(tmp_path / "puma560.xml", tool_link="tool")
    assert relative(back.inertia_matrix(q), puma.inertia_matrix(q)) < TOLERANCE
    driven = tmp_path / "driven.xml"
    done = invoke("convert", "puma560", driven, "--actuators", "dc")
    assert done.exit_code == 0, done.output
    model = mujoco.MjModel.from_xml_path(str(driven))
    assert model.nu == 6 or "no MuJoCo counterpart" in done.stderr
    assert_one_error_line(invoke("convert", "puma560", tmp_path / "puma.stl"), "the suffix must be one of")
    assert_one_error_line(
        invoke("convert", "puma560", tmp_path / "p.urdf", "--actuators", "dc"), "only an MJCF file holds drives"
    )
    assert_one_error_line(invoke("convert", "puma560", tmp_path / "none" / "p.xml"), "does not exist")
    assert_one_error_line(invoke("convert", "stanford", tmp_path / "s.xml"), "link 'q5'", "triangle inequality")


# ----- the geometry the viewer draws -------------------------------------------------------------------------------
@pytest.mark.parametrize(("distribution", "name", "lock"), [("robosuite", "panda", False), ("robosuite", "gr1", True)])
def test_each_geom_rides_on_its_link_as_in_mujoco(distribution: str, name: str, lock: bool) -> None:
    """The geoms recorded for the viewer, posed on armdyn's links, are where MuJoCo puts them at random states (the
    humanoid with its base and a waist joint locked: geoms on locked bodies ride on the link that carries them)."""
    from armdyn.model.sources import geometry_of

    path = _robot_xml(distribution, name)
    model = mujoco.MjModel.from_xml_path(str(path))
    names = [_joint_name(model, j) for j in range(model.njnt)]
    locked = {names[0]: None, "torso_waist_yaw": 0.3} if lock else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = load_mjcf(path, locked=locked)
    geoms = geometry_of(arm)
    visual = (model.geom_contype == 0) & (model.geom_conaffinity == 0)
    assert len(geoms) == np.count_nonzero(visual & (model.geom_bodyid > 0)) > 10
    data = mujoco.MjData(model)
    for q in random_states(arm, seed=11)[0][:5]:
        data.qpos[:] = model.qpos0
        if lock:
            data.qpos[model.jnt_qposadr[names.index("torso_waist_yaw")]] = 0.3
        data.qpos[[model.jnt_qposadr[names.index(joint)] for joint in arm.joint_names]] = q
        mujoco.mj_kinematics(model, data)
        frames = arm.link_transforms(q)
        for geom in geoms:
            g = geom.index
            pose = (arm.base if geom.link < 0 else frames[geom.link]) @ geom.pose
            assert np.allclose(pose[:3, 3], data.geom_xpos[g], atol=1e-12)
            assert np.allclose(pose[:3, :3], data.geom_xmat[g].reshape(3, 3), atol=1e-12)


def test_the_viewer_draws_an_mjcf_arm_with_its_meshes() -> None:
    pytest.importorskip("trimesh")
    from armdyn.viewer import _drawings

    arm = load_mjcf(_robot_xml("robosuite", "panda"))
    drawings, notes = _drawings(arm, None)
    assert not notes
    assert all(drawing.kind == "mesh" and drawing.shapes for drawing in drawings.values())
    primitives = load_mjcf(
        DC_ARM.format(step=1e-3).replace("<inertial", '<geom type="box" size="0.1 0.02 0.02"/><inertial')
    )
    kinds = {drawing.kind for index, drawing in _drawings(primitives, None)[0].items() if index >= 0}
    assert kinds == {"box"}


GRIPPER = """<mujoco model="arm with a gripper">
  <worldbody>
    <body name="upper">
      <joint name="shoulder" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
      <body name="hand" pos="0.4 0 0">
        <joint name="wrist" axis="0 1 0"/>
        <geom type="box" size="0.03 0.05 0.02"/>
        <body name="left" pos="0.05 0.02 0"><joint name="left finger" type="slide" axis="0 1 0" range="0 0.04"/>
          <geom type="box" size="0.01 0.005 0.02"/><site name="left tip" pos="0.02 0 0"/></body>
        <body name="right" pos="0.05 -0.02 0"><joint name="right finger" type="slide" axis="0 -1 0" range="0 0.04"/>
          <geom type="box" size="0.01 0.005 0.02"/><site name="right tip" pos="0.02 0 0"/></body>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="split"><joint joint="left finger" coef="0.5"/><joint joint="right finger" coef="0.5"/></fixed>
  </tendon>
  <equality>
    <joint name="mirror" joint1="left finger" joint2="right finger"/>
    <connect name="closing" site1="left tip" site2="right tip"/>
  </equality>
  <actuator><position name="grip" tendon="split" kp="100"/></actuator>
</mujoco>"""


def test_a_gripper_coupled_by_tendons_and_equalities_loads_with_its_fingers_locked() -> None:
    """A gripper as MuJoCo models them (a tendon, a mirror equality, a closing connect): refused while its fingers
    move, loaded once they are locked, with MuJoCo's dynamics for the arm's joints."""
    with pytest.raises(ModelError, match=r"tendons \['split'\].*or lock their joints"):
        load_mjcf(GRIPPER)
    with pytest.raises(ModelError, match=r"equality constraints \['mirror \(joint left finger and right finger\)'"):
        load_mjcf(GRIPPER.replace("<tendon>", "<!--").replace("</tendon>", "-->").replace(
            '<actuator><position name="grip" tendon="split" kp="100"/></actuator>', ""))  # fmt: skip
    arm = load_mjcf(GRIPPER, locked={"left finger": 0.0, "right finger": 0.0})
    assert arm.joint_names == ["shoulder", "wrist"]
    assert_same_dynamics(mujoco.MjModel.from_xml_string(GRIPPER), arm, "gripper locked")
    with pytest.raises(ModelError, match=r"tendons \['split'\]"):  # the tendon still couples a moving finger
        load_mjcf(GRIPPER, locked={"left finger": 0.0})
    without_coupling = GRIPPER.replace("<tendon>", "<!--").replace("</tendon>", "-->").replace(
        '<actuator><position name="grip" tendon="split" kp="100"/></actuator>', "").replace(
        '<joint name="mirror" joint1="left finger" joint2="right finger"/>', "")  # fmt: skip
    with pytest.raises(ModelError, match=r"\['closing \(connect\)'\]"):  # the loop closes over a moving finger
        load_mjcf(without_coupling, locked={"left finger": 0.0})
    assert load_mjcf(without_coupling, locked={"left finger": 0.0, "right finger": 0.0}).n == 2
