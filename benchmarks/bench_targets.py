"""The speed targets in one run: armdyn against Pinocchio and MuJoCo, as ratios (10th percentile and median).

    .venv/bin/python benchmarks/bench_targets.py            # or: make bench (about 4 minutes)
    .venv/bin/python benchmarks/bench_targets.py --quick    # a smoke run, nothing written

On the UR5, the Panda with its fingers (9 joints) and without (7 joints) and the PUMA 560, every arm without
friction (Pinocchio's rnea and aba have none); Pinocchio reads the URDFs itself, and the PUMA 560 is built
for it from armdyn's links (motor inertia as armature, bench_task.pinocchio_model). Before anything is
timed, armdyn's result is checked against Pinocchio's on the same state.

1. One state per call: each public method (allocating its result, and with ``out=``), its compiled kernel
   (armdyn.dynamics.kernels) and Pinocchio's call, interleaved; tool pose against forwardKinematics +
   updateFramePlacement, the world-aligned Jacobian against computeFrameJacobian, forward-dynamics
   derivatives against computeABADerivatives.
2. A batch of 100,000 states with ``out=`` against rneaInParallel / abaInParallel on 2 threads.
3. Simulation: the PUMA 560 under computed torque for 10 s at 1 kHz (real-time factor), and the compiled
   loop's time per RK4 step against four forward dynamics and one computed-torque law in a compiled loop;
   1,000 runs of the UR5 against ``mujoco.rollout`` on 2 threads.

Each ratio is armdyn's time over the peer's (below 1: armdyn is faster) for the batches and the rollouts the
peer's over armdyn's (above 1: armdyn is faster), as the targets are stated. Writes the tables to
results_targets.md.
"""

from __future__ import annotations

import os
import re
import statistics
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import armdyn as ad

# isort: split
import numba
import numpy as np
import pinocchio as pin
from bench_simulation import GAINS, _loop_aba, _loop_computed_torque
from bench_task import PANDA, ROBOTS, panda, pinocchio_model
from harness import Candidate, Report, Table, arguments, check, describe, ratio, samples, us

from armdyn import simulation
from armdyn.control import PID, ComputedTorque
from armdyn.dynamics import kernels
from armdyn.simulation import plant_variants
from armdyn.trajectories import Sinusoid

RESULTS = Path(__file__).with_name("results_targets.md")
CALLS, REPEATS = 2000, 15  # one-state calls per timed loop, loops per candidate
BATCH, BATCH_REPEATS = 100_000, 9
RUNS, STEPS = 1000, 1000  # the rollouts: runs of STEPS steps of 1 ms
SIM_REPEATS = 9
QUICK = {"CALLS": 100, "REPEATS": 3, "BATCH": 2000, "BATCH_REPEATS": 2, "RUNS": 20, "STEPS": 100, "SIM_REPEATS": 2}
THREADS = 2


def percentiles(times: list[float]) -> tuple[float, float]:
    """(10th percentile, median) of a candidate's loop times."""
    return float(np.percentile(times, 10)), statistics.median(times)


def pair_ratio(ours: list[float], theirs: list[float], invert: bool = False) -> tuple[str, str]:
    """The ratios of the 10th percentiles and of the medians."""
    (p_ours, m_ours), (p_theirs, m_theirs) = percentiles(ours), percentiles(theirs)
    if invert:
        return ratio(p_theirs / p_ours), ratio(m_theirs / m_ours)
    return ratio(p_ours / p_theirs), ratio(m_ours / m_theirs)


def arms() -> dict[str, tuple[ad.Robot, pin.Model]]:
    """The four arms without friction, each with Pinocchio's model of it."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's mimic finger joint loads as an independent joint
        ur5 = ad.load_urdf(ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf").without_friction()
        panda9 = ad.load_urdf(PANDA).without_friction()
    full = pin.buildModelFromUrdf(str(PANDA))
    panda7, reduced, _ = panda()  # the fingers locked in both libraries (bench_task)
    puma = ad.models.puma560().without_friction()
    return {
        "UR5": (ur5, pin.buildModelFromUrdf(str(ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf"))),
        "Panda 9": (panda9, full),
        "Panda 7": (panda7, reduced),
        "PUMA 560": (puma, pinocchio_model(puma)[0]),
    }


def tool_frame(arm: ad.Robot, model: pin.Model) -> int:
    """A Pinocchio frame at armdyn's tool: added to the model on the joint of armdyn's tool link."""
    data, q = model.createData(), np.linspace(-0.4, 0.5, arm.n)
    pin.forwardKinematics(model, data, q)
    joint = model.getJointId(arm.links[arm.tool_link].joint.name)
    placement = data.oMi[joint].inverse() * pin.SE3(arm.tool_pose(q))
    return model.addFrame(pin.Frame("armdyn_tool", joint, 0, placement, pin.FrameType.OP_FRAME))


def one_state(name: str, arm: ad.Robot, model: pin.Model, rng: np.random.Generator) -> list[list[str]]:
    """Part 1 for one arm: rows (function, peer, public/peer, out=/peer, kernel/peer; each p10 and median)."""
    frame = tool_frame(arm, model)
    data, n, packed = model.createData(), arm.n, arm.packed
    q, qd, qdd = rng.uniform(-1, 1, (3, n))
    tau = arm.inverse_dynamics(q, qd, qdd)
    vector, matrix, jac, pose = np.empty(n), np.empty((n, n)), np.empty((6, n)), np.empty((4, 4))
    derivatives = (np.empty((n, n)), np.empty((n, n)), np.empty((n, n)))
    world = pin.LOCAL_WORLD_ALIGNED

    def pin_pose() -> object:
        pin.forwardKinematics(model, data, q)
        return pin.updateFramePlacement(model, data, frame)

    def pin_mass() -> np.ndarray:
        M = pin.crba(model, data, q)
        return np.triu(M) + np.triu(M, 1).T

    rows = []
    cases: list[tuple[str, str, Callable, Callable, Callable, Callable, Callable]] = [
        ("inverse_dynamics", "pin.rnea", lambda: arm.inverse_dynamics(q, qd, qdd),
         lambda: arm.inverse_dynamics(q, qd, qdd, out=vector),
         lambda: kernels.inverse_dynamics(packed, q, qd, qdd, vector), lambda: pin.rnea(model, data, q, qd, qdd),
         lambda: pin.rnea(model, data, q, qd, qdd)),
        ("inertia_matrix", "pin.crba", lambda: arm.inertia_matrix(q), lambda: arm.inertia_matrix(q, out=matrix),
         lambda: kernels.inertia_matrix(packed, q, matrix), lambda: pin.crba(model, data, q), pin_mass),
        ("gravity_vector", "pin.computeGeneralizedGravity", lambda: arm.gravity_vector(q),
         lambda: arm.gravity_vector(q, out=vector), lambda: kernels.gravity_vector(packed, q, vector),
         lambda: pin.computeGeneralizedGravity(model, data, q),
         lambda: pin.computeGeneralizedGravity(model, data, q)),
        ("forward_dynamics", "pin.aba", lambda: arm.forward_dynamics(q, qd, tau),
         lambda: arm.forward_dynamics(q, qd, tau, out=vector),
         lambda: kernels.forward_dynamics(packed, q, qd, tau, vector), lambda: pin.aba(model, data, q, qd, tau),
         lambda: pin.aba(model, data, q, qd, tau)),
        ("coriolis_matrix", "pin.computeCoriolisMatrix", lambda: arm.coriolis_matrix(q, qd),
         lambda: arm.coriolis_matrix(q, qd, out=matrix), lambda: kernels.coriolis_matrix(packed, q, qd, matrix),
         lambda: pin.computeCoriolisMatrix(model, data, q, qd),
         lambda: pin.computeCoriolisMatrix(model, data, q, qd)),
        ("tool_pose", "forwardKinematics + updateFramePlacement", lambda: arm.tool_pose(q),
         lambda: arm.tool_pose(q, out=pose), lambda: kernels.pose(packed, q, kernels.TOOL, pose), pin_pose,
         lambda: pin_pose().homogeneous),
        ("jacobian", "computeFrameJacobian(LOCAL_WORLD_ALIGNED)", lambda: arm.jacobian(q),
         lambda: arm.jacobian(q, out=jac), lambda: kernels.jacobian(packed, q, kernels.TOOL, kernels.WORLD, jac),
         lambda: pin.computeFrameJacobian(model, data, q, frame, world),
         lambda: pin.computeFrameJacobian(model, data, q, frame, world)),
        ("forward_dynamics_derivatives", "computeABADerivatives",
         lambda: arm.forward_dynamics_derivatives(q, qd, tau),
         lambda: arm.forward_dynamics_derivatives(q, qd, tau, out=derivatives), None,
         lambda: pin.computeABADerivatives(model, data, q, qd, tau),
         lambda: pin.computeABADerivatives(model, data, q, qd, tau)[:2]),
    ]  # fmt: skip
    for function, peer, public, out, kernel, theirs, theirs_value in cases:
        ours_value = public()
        if function == "forward_dynamics_derivatives":
            ours_value = ours_value[:2]
        check(f"{name} {function}", ours_value, theirs_value(), 1e-8)
        candidates = [Candidate(fn, CALLS, REPEATS) for fn in (public, out, kernel, theirs) if fn is not None]
        times = samples(*candidates)
        peer_times = times[-1]
        cells = [" / ".join(pair_ratio(t, peer_times)) for t in times[:-1]]
        if kernel is None:
            cells.append("-")
        rows.append([name, function, peer, us(percentiles(peer_times)[1] * 1e6), *cells])
    return rows


def batches(name: str, arm: ad.Robot, model: pin.Model, rng: np.random.Generator) -> list[list[str]]:
    """Part 2 for one arm: batch inverse and forward dynamics against Pinocchio's parallel calls."""
    n, pool = arm.n, pin.ModelPool(model, THREADS)
    Q, QD, QDD = rng.uniform(-1, 1, (3, BATCH, n))
    TAU = arm.inverse_dynamics(Q, QD, QDD)
    ours, theirs = np.empty((BATCH, n)), np.empty((n, BATCH), order="F")
    rows = []
    for function, call, peer, args in (
        ("inverse_dynamics", arm.inverse_dynamics, pin.rneaInParallel, (Q, QD, QDD)),
        ("forward_dynamics", arm.forward_dynamics, pin.abaInParallel, (Q, QD, TAU)),
    ):
        transposed = [a.T for a in args]
        call(*args, out=ours)
        peer(THREADS, pool, *transposed, theirs)
        check(f"{name} batch {function}", ours, theirs.T, 1e-8)
        times = samples(
            Candidate(lambda c=call, a=args: c(*a, out=ours), 1, BATCH_REPEATS, BATCH),
            Candidate(lambda p=peer, a=transposed: p(THREADS, pool, *a, theirs), 1, BATCH_REPEATS, BATCH),
        )
        peer_name = f"pin.{peer.__name__}({THREADS}, pool, ..., out)"
        medians = [us(percentiles(t)[1] * 1e6) for t in times]
        rows.append([name, function, peer_name, *medians, " / ".join(pair_ratio(times[0], times[1], invert=True))])
    return rows


def stepper() -> list[list[str]]:
    """Part 3a: the PUMA 560 under computed torque, 10 s at 1 kHz; the compiled loop's time per step against
    four forward dynamics and one law."""
    puma = ad.models.puma560()
    trajectory = Sinusoid(0.1, 0.5, phase=np.arange(6) % 2 * np.pi / 2, offset=puma.qz)
    t_final = STEPS * 10 * 1e-3
    steps = round(t_final / 1e-3)
    run = lambda: ad.simulate(puma, ComputedTorque(*GAINS), trajectory, t_final=t_final, dt=1e-3)  # noqa: E731
    run()
    loop: list[float] = []  # per run: the seconds in the compiled loop (simulate calls it in chunks of rows)
    original = simulation.run_rk4

    def timed(*args: object) -> object:
        start = time.perf_counter()
        try:
            return original(*args)
        finally:
            loop[-1] += time.perf_counter() - start

    whole = []
    simulation.run_rk4 = timed
    try:
        for _ in range(SIM_REPEATS):
            loop.append(0.0)
            start = time.perf_counter()
            run()
            whole.append(time.perf_counter() - start)
    finally:
        simulation.run_rk4 = original
    rng = np.random.default_rng(3)
    states = 1000
    Q, QD, U = puma.qz + rng.uniform(-0.5, 0.5, (3, states, puma.n))
    TAU, out = puma.inverse_dynamics(Q, QD, U), np.empty((states, puma.n))
    kernel_times = samples(
        Candidate(lambda: _loop_aba(puma.packed, Q, QD, TAU, out), 1, 15, states),
        Candidate(lambda: _loop_computed_torque(puma.packed, Q, QD, U, out), 1, 15, states),
    )
    fd, law = (statistics.median(t) for t in kernel_times)
    per_step = statistics.median(loop) / steps
    factor = t_final / np.array(whole)
    return [
        ["PUMA 560, ComputedTorque on a sinusoid, 1 kHz RK4: real-time factor (p10 of times / median)",
         f"{t_final / np.percentile(whole, 90):.0f}x / {float(np.median(factor)):.0f}x", ">= 500x"],
        ["  the compiled loop per step", us(per_step * 1e6), "-"],
        ["  four forward dynamics + one law, compiled loops", us((4 * fd + law) * 1e6), "-"],
        ["  step / (4 FD + law)", ratio(per_step / (4 * fd + law)), "<= 1.3"],
    ]  # fmt: skip


def mujoco_servos(path: Path, kp: np.ndarray, kv: np.ndarray) -> object:
    """The UR5 in MuJoCo (bench_ensemble.mujoco_ur5's settings) with a position servo on every joint:
    force kp (ctrl - q) - kv qd, the law of armdyn's PID(kp, kv, 0) to a constant target."""
    import mujoco

    text = re.sub(r"<(visual|collision)>.*?</\1>", "", path.read_text(), flags=re.S)
    spec = mujoco.MjSpec.from_string(text)
    for k, joint in enumerate(spec.joints):
        actuator = spec.add_actuator(name=f"servo_{joint.name}", target=joint.name)
        actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
        actuator.gainprm[0], actuator.biasprm[1], actuator.biasprm[2] = kp[k], -kp[k], -kv[k]
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    model = spec.compile()
    model.jnt_actfrclimited[:] = 0  # MuJoCo's URDF import clamps at the effort limits; armdyn's PID does not
    model.opt.timestep, model.opt.integrator = 1e-3, mujoco.mjtIntegrator.mjINT_RK4
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
    return model


def rollouts() -> list[list[str]]:
    """Part 3b: RUNS runs of the UR5 against mujoco.rollout on 2 threads: from random starts under zero
    torque, and PD to a random target from rest."""
    import mujoco
    from bench_ensemble import mujoco_ur5
    from mujoco import rollout

    path = ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf"
    arm = ad.load_urdf(path)
    rng = np.random.default_rng(1)
    q0, qd0 = rng.uniform(-np.pi, np.pi, (RUNS, 6)), rng.uniform(-1, 1, (RUNS, 6))
    target = rng.uniform(-1.0, 1.0, (RUNS, 6))
    t_final, bandwidth = STEPS * 1e-3, 20.0
    inertia = np.diag(arm.inertia_matrix(np.zeros(arm.n)))  # gains that give each joint the same bandwidth
    kp, kv = bandwidth**2 * inertia, 2.0 * bandwidth * inertia
    rows = []
    payloads = plant_variants(arm, RUNS, payload_mass=rng.uniform(0.0, 5.0, RUNS))
    for case, model, law, plants in (
        ("zero torque, random starts", mujoco_ur5(path), None, None),
        ("zero torque, random starts, a payload of 0-5 kg each (MuJoCo: none)", mujoco_ur5(path), None, payloads),
        (f"PD to a random target from rest ({bandwidth:g} rad/s)", mujoco_servos(path, kp, kv), PID(kp, kv, 0.0), None),
    ):  # fmt: skip
        size = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        states = np.zeros((RUNS, size))
        start, velocity = (q0, qd0) if law is None else (np.zeros((RUNS, 6)), np.zeros((RUNS, 6)))
        states[:, 1 : 1 + model.nq], states[:, 1 + model.nq : 1 + model.nq + model.nv] = start, velocity
        controls = None if law is None else np.repeat(target[:, None, :], STEPS, axis=1)
        paths = None if law is None else [Sinusoid(0.0, 1.0, 0.0, goal) for goal in target]
        datas = [mujoco.MjData(model) for _ in range(THREADS)]

        def ours(
            law: object = law, paths: object = paths, start: np.ndarray = start, velocity: np.ndarray = velocity,
            plants: object = plants,
        ) -> object:  # fmt: skip
            return ad.simulate(arm, law, paths, t_final=t_final, q0=start, qd0=velocity, runs=RUNS, threads=THREADS,
                               plants=plants)  # fmt: skip

        def theirs(
            model: object = model, datas: list = datas, states: np.ndarray = states, controls: object = controls
        ) -> object:
            return rollout.rollout(model, datas, states, controls, nstep=STEPS)

        finals, _ = theirs()
        difference = float(np.abs(finals[:, -1, 1 : 1 + model.nq] - ours().summaries[:, 4]).max())
        times = samples(Candidate(ours, 1, 5), Candidate(theirs, 1, 5))
        note = "the same law" if law is None else "armdyn holds the law over each step, MuJoCo evaluates it per stage"
        note = note if plants is None else "the payloads are armdyn's only"
        rows += [
            [f"UR5, {RUNS} runs of {t_final:g} s at 1 ms, {case}: mujoco.rollout / simulate(runs) (p10 / median)",
             " / ".join(pair_ratio(times[0], times[1], invert=True)), ">= 5x"],
            [f"  largest difference of the final joint angles (rad; {note})", f"{difference:.1e}",
             "<= 1e-9" if law is None and plants is None else "-"],
        ]  # fmt: skip
    return rows


def main() -> None:
    parser = arguments(__doc__)
    args = parser.parse_args()
    report = Report.begin(args, "armdyn's speed targets", RESULTS, globals(), QUICK)
    source = report.source
    versions = {"numba": numba.__version__, "numpy": np.__version__, "pinocchio": pin.__version__}
    report.note(*describe(source, versions))
    report.note(f"Load average before the run: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    rng = np.random.default_rng(2026)
    pairs = arms()
    head = ["arm", "function", "peer", "peer us (median)", "public/peer", "out=/peer", "kernel/peer"]
    table = Table("1. One state per call: armdyn / Pinocchio, p10 / median (below 1: armdyn faster)", head, [])
    for name, (arm, model) in pairs.items():
        table.rows += one_state(name, arm, model, rng)
    report.show(table)
    head = ["arm", "function", "peer", "armdyn us/state", "peer us/state", "peer/armdyn (p10 / median)"]
    table = Table(f"2. Batches of {BATCH:,} states, out=, {THREADS} threads (above 1: armdyn faster)", head, [])
    for name, (arm, model) in pairs.items():
        table.rows += batches(name, arm, model, rng)
    report.show(table)
    rows = stepper() + rollouts()
    report.show(Table("3. Simulation", ["measure", "value", "target"], rows))
    report.note(f"Load average after the run: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    report.finish("the ratios may mix two versions")


if __name__ == "__main__":
    sys.exit(main())
