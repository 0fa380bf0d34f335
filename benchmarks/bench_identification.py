"""Identification of a simulated Panda by armdyn and by MuJoCo's mujoco.sysid, side by side: wall time, error of
the link masses and of the torques predicted on held-out samples.

    PYTHONPATH=src python benchmarks/bench_identification.py [--quick]

The case. The TRUE arm is example-robot-data's Panda (panda.urdf, the two fingers locked at 2 cm: 7 revolute
joints, the hand and fingers merged into link 7), with the friction of Gaz et al. (2019, armdyn.models.
panda_gaz2019) per joint: their sigmoid law when armdyn's Link carries one, else viscous plus Coulomb friction
at the sigmoid's limits. The PRIOR (the starting model of both methods) is a copy whose link masses, centres of
mass and inertias are each off by 10 to 30% (random sign), without friction. The log: an exciting Fourier
trajectory (armdyn.identification.excitation.excitation_trajectory, a few SLSQP iterations) for DURATION s at
RATE Hz, the sample times jittered by up to 0.5 ms, q and qd exact at those times, the torque the true arm's
inverse dynamics needs plus Gaussian noise of 1% of each joint's RMS torque. The first 70% of the samples train,
the last 30% are held out.

1. mujoco.sysid fits by simulation: the Panda is compiled by MuJoCo from the URDF (visuals and collisions
   removed, fixed bodies fused), its inertias set to the prior's at full precision (MuJoCo's M(q) and gravity
   are checked against armdyn's to 1e-10 first), RK4 at the log's 1 ms, no contacts, one motor actuator of
   gear 1 per joint taking the logged torque, jointpos and jointvel sensors. The training samples are cut
   into windows of CHUNK s (an open-loop run of a 7-joint arm under logged torques drifts away over
   seconds), each starting from its logged q and qd. Parameters: every link's ten inertial parameters in
   sysid's log-Cholesky (pseudo-inertia) form, and each joint's damping and frictionloss; sysid.optimize
   with its default MuJoCo least-squares optimizer (finite-difference Jacobians), at most SYSID_ITERATIONS
   iterations.
2. armdyn: armdyn.identification.workflow.identify_log(prior, Log(t, q, qd, tau), friction=...,
   consistent=True, holdout=0.3) with its defaults otherwise (preprocessing, the friction law by variable
   projection, least squares, the physically consistent semidefinite program toward the prior).

Both identified models are judged alike: their link masses against the truth's, the error of the rigid-body
base parameters (Gautier's regrouping: what joint torques can determine at all, as a norm relative to the
truth's), and the RMS per joint of measured minus predicted torque on the held-out samples, the prediction
from the exact states (armdyn's inverse dynamics of an arm carrying the model's parameters; armdyn's own
``predict``, offsets included, for armdyn). Some link masses of the Panda (link 1's: its joint axis is
vertical and nothing above it moves it) do not enter the joint torques at all: their error only says how far
each method stayed near its prior. Prints one table (and writes it as Markdown to results_identification.md;
--quick: a shorter log and fewer sysid iterations, nothing written).
"""

from __future__ import annotations

import dataclasses
import os
import sysconfig
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import armdyn as ad

# isort: split
import numpy as np
from harness import Report, Table, arguments, describe, ratio, seconds, version

from armdyn.dynamics.regressor import base_parameters, parameters
from armdyn.identification.excitation import excitation_trajectory
from armdyn.model import Inertial

# ----- settings -------------------------------------------------------------------------------
DURATION, RATE = 10.0, 1000.0  # s of log, samples per second
JITTER = 0.5e-3  # the largest shift of a sample time (s)
NOISE = 0.01  # torque noise, a share of each joint's RMS torque
TRAIN = 0.7  # the share of the log that trains; the rest is held out
PERTURBATION = (0.1, 0.3)  # the prior's parameters are off by this share, either sign
CHUNK = 0.5  # s: sysid's windows of open-loop simulation
SYSID_ITERATIONS = 5  # the most iterations of sysid's optimizer
EXCITATION_ITERATIONS = 3  # SLSQP iterations of the exciting trajectory
SPEED = [2.0] * 4 + [2.4] * 3  # rad/s: the excitation's speed limits, under the Panda's (2.175, 2.61)
SEED = 0
QUICK = {"DURATION": 4.0, "SYSID_ITERATIONS": 1, "EXCITATION_ITERATIONS": 1}
RESULTS = Path(__file__).with_name("results_identification.md")

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
PANDA = ROBOTS / "panda_description" / "urdf" / "panda.urdf"
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
# Gaz et al.'s (2019) sigmoid friction (A, alpha, shift) per joint, as armdyn.models.panda_gaz2019 carries it:
# used when armdyn's Link has no sigmoid field (then only the law's limits, as Coulomb friction)
GAZ_SIGMOID = list(zip([0.54615, 0.87224, 0.64068, 1.2794, 0.83904, 0.30301, 0.56489],
                       [5.1181, 9.0657, 10.136, 5.5903, 8.3469, 17.133, 10.336],
                       [0.039533, 0.025882, -0.04607, 0.036194, 0.026226, -0.021047, 0.0035526],
                       strict=True))  # fmt: skip


# ----- the case -------------------------------------------------------------------------------
def has_sigmoid() -> bool:
    """Whether armdyn's Link carries the sigmoid friction law of Gaz et al."""
    return any(field.name == "sigmoid" for field in dataclasses.fields(ad.Link))


def true_panda() -> ad.Robot:
    """The Panda of example-robot-data, fingers locked, with Gaz et al.'s friction (see the module docstring)."""
    arm = ad.load_urdf(PANDA, locked=FINGERS)
    laws = [link.sigmoid for link in ad.models.panda_gaz2019().links] if has_sigmoid() else GAZ_SIGMOID
    links = []
    for link, (amplitude, slope, shift) in zip(arm.links, laws, strict=True):
        if has_sigmoid():
            fields: dict[str, object] = {"viscous": 0.0, "coulomb": (0.0, 0.0), "sigmoid": (amplitude, slope, shift)}
        else:
            at_rest = 1.0 / (1.0 + np.exp(-slope * shift))  # the law's limits: A (1 - s(alpha shift)), -A s(...)
            fields = {"viscous": 0.0, "coulomb": (amplitude * (1.0 - at_rest), -amplitude * at_rest)}
        links.append(dataclasses.replace(link, **fields))
    return arm.replace(links, name="panda_true")


def perturbed(arm: ad.Robot, rng: np.random.Generator) -> ad.Robot:
    """The prior: each link's mass, centre of mass (its distance from the link origin, in a direction turned
    by the same share) and inertia about the centre of mass (scaled whole: it stays physical) off by a random
    share in PERTURBATION, random sign; no friction."""
    low, high = PERTURBATION

    def off() -> float:
        return 1.0 + rng.choice([-1.0, 1.0]) * rng.uniform(low, high)

    links = []
    for link in arm.links:
        inertial = link.inertial
        com = np.asarray(inertial.com, dtype=float)
        push = rng.standard_normal(3)
        com = com * off() + np.linalg.norm(com) * rng.uniform(low, high) * push / np.linalg.norm(push)
        changed = Inertial(float(inertial.mass) * off(), com, np.asarray(inertial.inertia) * off(), link.name, False)
        links.append(dataclasses.replace(link, inertial=changed, viscous=0.0, coulomb=(0.0, 0.0)))
    return arm.replace(links, name="panda_prior")


@dataclass(frozen=True)
class Samples:
    """The simulated log: jittered times, exact q, qd, qdd, the true and the measured (noisy) torque."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau_true: np.ndarray
    tau: np.ndarray

    def part(self, keep: np.ndarray) -> Samples:
        return Samples(*(getattr(self, f.name)[keep] for f in dataclasses.fields(self)))


def simulated_log(arm: ad.Robot, rng: np.random.Generator) -> tuple[Samples, float]:
    """The log along an exciting trajectory, and the trajectory's condition number."""
    trajectory = excitation_trajectory(arm, period=DURATION, harmonics=5, iterations=EXCITATION_ITERATIONS,
                                       velocity_limits=SPEED, seed=SEED)  # fmt: skip
    count = round(DURATION * RATE) + 1
    t = np.arange(count) / RATE + rng.uniform(-JITTER, JITTER, count)
    t[0] = 0.0
    q, qd, qdd = (np.asarray(x, dtype=float) for x in trajectory(t))
    tau_true = arm.inverse_dynamics(q, qd, qdd)
    tau = tau_true + rng.standard_normal(tau_true.shape) * NOISE * np.sqrt(np.mean(tau_true**2, axis=0))
    return Samples(t, q, qd, qdd, tau_true, tau), trajectory.condition_number


# ----- MuJoCo's model of the same Panda -------------------------------------------------------
def mujoco_spec(arm: ad.Robot):
    """The Panda compiled by MuJoCo from the URDF (fingers fixed where armdyn locks them, fixed bodies fused),
    saved and read back as MJCF, with every body's inertial set from ``arm`` at full precision, RK4 at the
    log's interval, no contacts, a motor of gear 1 and jointpos/jointvel sensors per joint, no damping."""
    import mujoco

    root = ET.parse(PANDA).getroot()
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    for joint in root.iter("joint"):
        for element in joint.findall("dynamics"):
            joint.remove(element)
        if joint.get("name") in FINGERS:
            axis = np.array(joint.find("axis").get("xyz").split(), dtype=float)  # type: ignore[union-attr]
            origin = joint.find("origin")
            xyz = np.array(origin.get("xyz").split(), dtype=float) + FINGERS[joint.get("name")] * axis  # type: ignore
            origin.set("xyz", " ".join(repr(float(v)) for v in xyz))  # type: ignore[union-attr]
            joint.set("type", "fixed")
            for tag in ("axis", "limit", "mimic"):
                for element in joint.findall(tag):
                    joint.remove(element)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(extension, "compiler", fusestatic="true", discardvisual="true", balanceinertia="false")
    compiled = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "panda.xml")
        mujoco.mj_saveLastXML(path, compiled)
        spec = mujoco.MjSpec.from_string(Path(path).read_text())
    spec.option.timestep = 1.0 / RATE
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_RK4
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    spec.option.gravity = np.asarray(arm.gravity, dtype=float)
    for i, name in enumerate(arm.joint_names):
        set_inertial(spec.body(f"panda_link{i + 1}"), arm.links[i].inertial)
        spec.joint(name).damping[:] = 0.0  # MuJoCo 4: damping is a polynomial in the speed, [0] the linear one
        spec.joint(name).frictionloss = 0.0
        spec.joint(name).armature = 0.0
        motor = spec.add_actuator()
        motor.name, motor.target, motor.trntype = f"{name}_motor", name, mujoco.mjtTrn.mjTRN_JOINT
        motor.gear[0] = 1.0
    for kind, suffix in ((mujoco.mjtSensor.mjSENS_JOINTPOS, "pos"), (mujoco.mjtSensor.mjSENS_JOINTVEL, "vel")):
        for name in arm.joint_names:
            sensor = spec.add_sensor()
            sensor.name, sensor.type, sensor.objtype, sensor.objname = (
                f"{name}_{suffix}",
                kind,
                mujoco.mjtObj.mjOBJ_JOINT,
                name,
            )
    return spec


def set_inertial(body, inertial: Inertial) -> None:
    """A MuJoCo body's mass, centre of mass and inertia (principal moments and axes) from armdyn's."""
    set_body(body, float(inertial.mass), np.asarray(inertial.com, dtype=float), np.asarray(inertial.inertia))


def set_body(body, mass: float, com: np.ndarray, about_com: np.ndarray) -> None:
    import mujoco

    moments, axes = np.linalg.eigh((about_com + about_com.T) / 2)
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, axes.reshape(-1))
    body.explicitinertial = True
    body.mass, body.ipos, body.inertia, body.iquat = mass, com, np.maximum(moments, 0.0), quaternion
    body.fullinertia = np.full(6, np.nan)


def mujoco_agreement(model, arm: ad.Robot, rng: np.random.Generator, states: int = 5) -> float:
    """The largest relative difference of MuJoCo's M(q) and gravity torque from armdyn's at random states."""
    import mujoco

    data = mujoco.MjData(model)
    worst = 0.0
    for _ in range(states):
        q = rng.uniform(arm.qlim[0], arm.qlim[1])
        data.qpos[:], data.qvel[:] = q, 0.0
        mujoco.mj_forward(model, data)
        mass = np.zeros((arm.n, arm.n))
        mujoco.mj_fullM(model, data, mass)
        expected_mass, expected_gravity = arm.inertia_matrix(q), arm.gravity_vector(q)
        worst = max(worst, np.abs(mass - expected_mass).max() / np.abs(expected_mass).max(),
                    np.abs(data.qfrc_bias - expected_gravity).max() / np.abs(expected_gravity).max())  # fmt: skip
    return worst


def pseudo_inertia_modifier(name: str):
    """Writes a sysid pseudo-inertia parameter (log-Cholesky theta, Rucker and Wensing 2022) into the body.

    sysid's own modifier (model_modifier.apply_body_theta_inertia) sets the body's diagonal inertia to 0 and
    its frame quaternion to NaN with a full inertia, which MuJoCo 4.0.0's compiler refuses ("mass and inertia
    of moving bodies must be larger than mjMINVAL"); this one writes the same parameters through
    sysid's pi_from_theta as principal moments and axes."""
    from mujoco.sysid._src.model_modifier import pi_from_theta, skew

    def modify(spec, parameter) -> None:
        pi = pi_from_theta(np.asarray(parameter.value, dtype=float))
        mass, first = float(pi[0]), pi[1:4]
        com = first / mass
        about_origin = pi[4:].reshape(3, 3)
        set_body(spec.body(name), mass, com, about_origin + mass * skew(com) @ skew(com))

    return modify


def joint_modifier(name: str, what: str):
    """Writes a sysid parameter into a joint's damping (linear term) or frictionloss."""

    def modify(spec, parameter) -> None:
        joint = spec.joint(name)
        if what == "damping":
            joint.damping[0] = parameter.value[0]
        else:
            joint.frictionloss = parameter.value[0]

    return modify


def sysid_problem(arm: ad.Robot, train: Samples):
    """sysid's problem started at ``arm``: (spec, ParameterDict, residual function) on the training windows.

    Each window of CHUNK s starts from its logged q and qd at its own time; the logged torques drive the motors.
    The parameters: each link's pseudo-inertia (10), each joint's damping and frictionloss (started at the
    arm's viscous friction and mean Coulomb friction, at least 0.05, bounded by 0 and 5)."""
    from mujoco import sysid

    spec = mujoco_spec(arm)
    model = spec.compile()
    window = round(CHUNK * RATE)
    initial, controls, sensors, names = [], [], [], []
    for k, first in enumerate(range(0, len(train.t) - window + 1, window)):
        part = slice(first, first + window)
        state = sysid.create_initial_state(model, train.q[first], train.qd[first])
        state[0] = train.t[first]  # the full physics state starts with the time: the window's own
        initial.append(state)
        controls.append(sysid.TimeSeries(train.t[part], train.tau[part]))
        sensors.append(sysid.TimeSeries.from_names(train.t[part], np.hstack([train.q[part], train.qd[part]]), model))
        names.append(f"window{k}")
    sequences = sysid.ModelSequences("panda", spec, names, initial, controls, sensors)
    parameters_ = sysid.ParameterDict()
    for i in range(arm.n):
        body = f"panda_link{i + 1}"
        parameters_.add(sysid.body_inertia_param(spec, model, body, inertia_type=sysid.InertiaType.Pseudo,
                                                 modifier=pseudo_inertia_modifier(body)))  # fmt: skip
    for link, name in zip(arm.links, arm.joint_names, strict=True):
        starts = {"damping": link.viscous, "frictionloss": (link.coulomb[0] - link.coulomb[1]) / 2}
        for what, value in starts.items():
            parameters_.add(sysid.Parameter(f"{name}_{what}", max(value, 0.05), 0.0, 5.0,
                                            modifier=joint_modifier(name, what)))  # fmt: skip
    return spec, parameters_, sysid.build_residual_fn(models_sequences=[sequences])


def sysid_arm(arm: ad.Robot, spec, parameters_) -> ad.Robot:
    """``arm`` carrying the inertias, damping (viscous) and frictionloss (symmetric Coulomb) of sysid's
    parameters (MuJoCo's body frames are armdyn's link frames: checked by mujoco_agreement)."""
    import mujoco
    from mujoco import sysid

    fitted = sysid.apply_param_modifiers(parameters_, spec.copy())
    links = []
    for i, link in enumerate(arm.links):
        body = fitted.body(f"panda_link{i + 1}")
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, body.iquat)
        rotation = rotation.reshape(3, 3)
        inertia = rotation @ np.diag(body.inertia) @ rotation.T
        joint = fitted.joint(arm.joint_names[i])
        inertial = Inertial(float(body.mass[0]), np.array(body.ipos), inertia, link.name, False)
        friction = float(joint.frictionloss[0])
        links.append(dataclasses.replace(link, inertial=inertial, viscous=float(joint.damping[0]),
                                         coulomb=(friction, -friction)))  # fmt: skip
    return arm.replace(links, name="panda_sysid")


def cost(residual, parameters_) -> float:
    """sysid's cost: the sum of squares of its (normalized) residuals."""
    return float(np.sum(np.concatenate(residual(parameters_.as_vector(), parameters_)[0]) ** 2))


def run_sysid(prior: ad.Robot, truth: ad.Robot, train: Samples) -> tuple[ad.Robot, float, dict]:
    """mujoco.sysid from the prior on the training samples: the identified arm (armdyn's, carrying sysid's
    parameters), the wall time and facts about the run (its cost at the start, the end and the truth)."""
    from mujoco import sysid

    start = time.perf_counter()
    spec, parameters_, residual = sysid_problem(prior, train)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found, _ = sysid.optimize(parameters_, residual, optimizer="mujoco", verbose=False,
                                  max_iters=SYSID_ITERATIONS)  # fmt: skip
    seconds_ = time.perf_counter() - start
    true_spec, true_parameters, true_residual = sysid_problem(truth, train)
    round_trip = base_error(sysid_arm(truth, true_spec, true_parameters), truth)
    if not round_trip < 1e-9:
        raise AssertionError(f"sysid's parameters of the truth carried back to armdyn differ by {round_trip:.1e}")
    facts = {
        "windows": (len(train.t) - round(CHUNK * RATE)) // round(CHUNK * RATE) + 1,
        "parameters": int(parameters_.as_vector().size),
        "cost": (cost(residual, parameters_), cost(residual, found), cost(true_residual, true_parameters)),
    }
    return sysid_arm(prior, spec, found), seconds_, facts


# ----- armdyn ---------------------------------------------------------------------------------
def run_armdyn(prior: ad.Robot, samples: Samples, friction: str):
    """identify_log on the whole log with the last 30% held out: (the IdentifiedModel, wall time)."""
    from armdyn.identification.log import Log
    from armdyn.identification.workflow import identify_log

    log = Log(t=samples.t, q=samples.q, qd=samples.qd, tau=samples.tau, source="simulated panda")
    start = time.perf_counter()
    model = identify_log(prior, log, friction=friction, consistent=True, holdout=1.0 - TRAIN)
    return model, time.perf_counter() - start


# ----- judging --------------------------------------------------------------------------------
def base_error(arm: ad.Robot, truth: ad.Robot) -> float:
    """|B (phi - phi_true)| / |B phi_true| over the rigid-body base parameters of the truth's regrouping B."""
    regrouping = base_parameters(truth, drives=False).regrouping
    n = truth.n
    rigid = regrouping[:, : 10 * n]
    keep = np.any(rigid != 0, axis=1) & ~np.any(regrouping[:, 10 * n :] != 0, axis=1)
    b = rigid[keep]
    estimate, exact = b @ parameters(arm)[: 10 * n], b @ parameters(truth)[: 10 * n]
    return float(np.linalg.norm(estimate - exact) / np.linalg.norm(exact))


def mass_errors(arm: ad.Robot, truth: ad.Robot) -> np.ndarray:
    return np.array([abs(a.inertial.mass - b.inertial.mass) / b.inertial.mass
                     for a, b in zip(arm.links, truth.links, strict=True)])  # fmt: skip


def rms(residual: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(residual**2, axis=0))


def main() -> None:
    parser = arguments(__doc__)
    parser.add_argument("--sysid-iterations", type=int, help=f"the most iterations of sysid's optimizer (default "
                        f"{SYSID_ITERATIONS}, --quick {QUICK['SYSID_ITERATIONS']})")  # fmt: skip
    args = parser.parse_args()
    report = Report.begin(args, "Identification of a simulated Panda: armdyn and mujoco.sysid", RESULTS, globals(),
                          QUICK)  # fmt: skip
    if args.sysid_iterations is not None:
        globals()["SYSID_ITERATIONS"] = args.sysid_iterations
    load_before = os.getloadavg()
    report.note(*describe(report.source, {"mujoco": version("mujoco"), "cvxpy": version("cvxpy"),
                                          "numpy": version("numpy")}))  # fmt: skip
    report.note(f"Load average (1, 5, 15 min) before: {', '.join(f'{x:.2f}' for x in load_before)}")
    rng = np.random.default_rng(SEED)
    truth = true_panda()
    friction = "sigmoid" if has_sigmoid() else "coulomb"
    prior = perturbed(truth, rng)
    samples, condition = simulated_log(truth, rng)
    train_mask = samples.t < TRAIN * samples.t[-1]
    train, held = samples.part(train_mask), samples.part(~train_mask)
    law = "sigmoid (Gaz et al. 2019)" if has_sigmoid() else "viscous + Coulomb (armdyn's Link has no sigmoid law here)"
    report.note(
        f"Log: {len(samples.t)} samples over {samples.t[-1]:.1f} s (times jittered by up to {JITTER * 1e3:g} ms), "
        f"torque noise {NOISE:.0%} of each joint's RMS torque, exciting trajectory with condition number "
        f"{condition:.3g}; the truth's friction: {law}; "
        f"training {train_mask.sum()} samples, held out {(~train_mask).sum()}."
    )
    agreement = mujoco_agreement(mujoco_spec(truth).compile(), truth, rng)
    report.note(f"MuJoCo's compile of the URDF against armdyn (M(q) and gravity at 5 random states): largest relative "
                f"difference {agreement:.1e}")  # fmt: skip
    if not agreement <= 1e-10:
        raise AssertionError(f"MuJoCo's Panda differs from armdyn's by {agreement:.1e}: not the same arm")

    rows: list[tuple[str, float | None, ad.Robot | None, np.ndarray, str]] = []

    def predicted_by(arm: ad.Robot) -> np.ndarray:
        return arm.inverse_dynamics(held.q, held.qd, held.qdd)

    rows.append(("prior (the starting model)", None, prior, predicted_by(prior), ""))
    rows.append(("truth (noise floor)", None, truth, predicted_by(truth), ""))

    try:
        identified, armdyn_seconds = run_armdyn(prior, samples, friction)  # the first call in this process
        again = run_armdyn(prior, samples, friction)[1]  # the solver's compiled problem and armdyn's code loaded
    except ImportError as error:
        report.note(f"armdyn.identification's log workflow is not available here ({error}): armdyn's row skipped")
    else:
        consistent = "consistent" if identified.arm is not None else "least squares"
        rows.append((f"armdyn identify_log ({friction}, {consistent})", armdyn_seconds, identified.arm,
                     identified.predict(held.q, held.qd, held.qdd),
                     f"first call; again on the same log {again:.3f} s"))  # fmt: skip

    identified_sysid, sysid_seconds, facts = run_sysid(prior, truth, train)
    start_cost, end_cost, true_cost = facts["cost"]
    rows.append((f"mujoco.sysid ({facts['parameters']} parameters, {facts['windows']} windows of {CHUNK:g} s)",
                 sysid_seconds, identified_sysid, predicted_by(identified_sysid),
                 f"cost {start_cost:.3g} -> {end_cost:.3g} in at most {SYSID_ITERATIONS} iterations (at the truth "
                 f"{true_cost:.3g})"))  # fmt: skip

    fastest = min(s for _, s, _, _, _ in rows if s is not None)
    table = Table(
        "Identification of the simulated Panda (held-out torque RMS per joint, N m)",
        ["method", "wall (s)", "ratio", "mass error median / max", "base params error",
         *(f"rms {j + 1}" for j in range(truth.n)), "note"],
    )  # fmt: skip
    for label, wall_seconds, arm, predicted, note in rows:
        masses = mass_errors(arm, truth) if arm is not None else None
        table.rows.append([
            label,
            "" if wall_seconds is None else seconds(wall_seconds),
            "" if wall_seconds is None else ratio(wall_seconds / fastest),
            "" if masses is None else f"{np.median(masses):.1%} / {masses.max():.1%}",
            "" if arm is None else f"{base_error(arm, truth):.2%}",
            *(f"{x:.3f}" for x in rms(held.tau - predicted)),
            note,
        ])  # fmt: skip
    table.notes += [
        f"Held out: the last {1 - TRAIN:.0%} of the log ({len(held.t)} samples); rms of measured minus predicted "
        f"torque at the exact states. The noise alone gives the truth's row.",
        "Mass error: |m - m_true| / m_true per link (median, max over the 7 links); link 1's mass does not enter "
        "the joint torques (vertical first axis), so its error is what each method kept from the prior.",
        "Base params error: |B (phi - phi_true)| / |B phi_true| over the rigid-body base parameters (Gautier's "
        "regrouping B of the truth): what joint torques determine.",
        "mujoco.sysid: sysid's pseudo-inertia modifier does not compile on MuJoCo 4.0.0 (see "
        "pseudo_inertia_modifier): the same parameterization is written by a replacement modifier; its friction "
        "is MuJoCo's damping and frictionloss"
        + (
            ", which cannot represent the sigmoid law."
            if has_sigmoid()
            else " (a soft constraint, not the exact sign law)."
        ),
        "sysid's cost (sum of squares of its normalized q, qd residuals over the windows) at the true parameters "
        "is the last number of its note: where it is above the cost reached, simulating the noisy torques through "
        "MuJoCo's friction makes a wrong model fit the windows better than the truth, and more iterations do not "
        "lead to the truth.",
    ]
    report.show(table)
    load_after = os.getloadavg()
    report.note(f"Load average (1, 5, 15 min) after: {', '.join(f'{x:.2f}' for x in load_after)}")
    report.finish("the times may mix two versions of armdyn")


if __name__ == "__main__":
    main()
