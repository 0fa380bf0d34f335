"""armdyn's simulation loop timed: the PUMA 560 under zero torque against the Robotics Toolbox's fdyn, and
computed-torque tracking at 1 kHz against real time.

    .venv/bin/python benchmarks/bench_simulation.py                      # about 6 minutes (fdyn: up to 5)
    .venv/bin/python benchmarks/bench_simulation.py --skip-toolbox       # about 1 minute
    .venv/bin/python benchmarks/bench_simulation.py --fdyn-timeout 60
    .venv/bin/python benchmarks/bench_simulation.py --quick              # a smoke run, fdyn capped at 10 s

Four parts, all in this one process except the Toolbox's run:

1. the PUMA 560 released at qr for 1 s, zero torque, with its friction: armdyn's simulate() with its default
   method (fixed-step RK4, dt = 1 ms, one compiled call), the same at dt = 0.2 ms, and method="rk45" (scipy's
   solve_ivp, Python right-hand side); the Toolbox's puma.fdyn(T=1, q0=qr) with zero torque and its default
   solver (scipy's RK45 at its default tolerances) once, in a subprocess with a time limit. The final states
   are compared joint by joint;
2. 10 s of PUMA 560 computed-torque tracking at 1 kHz, ComputedTorque(100, 20) on a sinusoid, and
3. 5 s of the RR arm of Example 4.4-1 likewise: wall time, real-time factor and tracking error;
4. where the time goes: the tracking run split into its compiled loop, its energies and the rest, simulate()
   with less work per step, and armdyn's kernels called in a compiled loop (each checked against a reference
   computation on the same states), summed into the per-step cost of possible step designs.

Times are medians over repeats; the candidates' repeats are interleaved so that machine noise hits all of
them alike (the timing, checking and tables are benchmarks/harness.py's). The Toolbox's run is timed once.
Prints plain tables and writes the same as Markdown to results_simulation.md; --quick runs every part with
few repeats, few kernel states and fdyn stopped after 10 s, and writes nothing.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path

import numba
import numpy as np
from harness import (
    SECOND,
    Candidate,
    Report,
    Spans,
    Table,
    arguments,
    describe,
    emit,
    measure,
    ms,
    parse,
    ratio,
    relative_error,
    run_worker,
    samples,
    sci,
    timed_step,
    us,
    version,
    wall,
)
from numba import njit

import armdyn as ad
from armdyn import simulation
from armdyn.control import PID, ComputedTorque
from armdyn.dynamics.aba import aba_core
from armdyn.dynamics.crba import crba_core, mass_matrix_and_bias
from armdyn.dynamics.energy import energy_core
from armdyn.dynamics.friction import smooth_coulomb
from armdyn.dynamics.packed import workspace_size
from armdyn.dynamics.rnea import INVERSE_DYNAMICS, NONLINEAR, rnea_core
from armdyn.dynamics.spatial import NUMBA_OPTIONS
from armdyn.simulation import _solve, simulate
from armdyn.trajectories import Sinusoid

# ----- settings -------------------------------------------------------------------------------
T_FALL, DT = 1.0, 1e-3  # part 1: seconds simulated, armdyn's default step
DT_FINE = 2e-4  # part 1: armdyn's RK4 again with a step inside its stability region (see the notes)
FALL_REPEATS, RK45_REPEATS = 15, 3  # part 1: timed runs per armdyn candidate
FDYN_TIMEOUT = 300.0  # seconds for the Toolbox's fdyn (its import and model building not counted)
WORKER_ALLOWANCE = 120.0  # extra seconds the worker may take to import the Toolbox before it is killed
T_PUMA, T_RR = 10.0, 5.0  # parts 2 and 3: seconds simulated at DT
GAINS = (100.0, 20.0)  # ComputedTorque(kp, kv)
TRACK_REPEATS = 15  # parts 2 to 4: timed runs per simulate() candidate
REAL_TIME_TARGET, TOOLBOX_TARGET = 200.0, 1000.0
KERNEL_STATES, KERNEL_REPEATS = 1000, 15  # part 4: distinct states per compiled loop, timed loops
TOLERANCE = 1e-8
RK4_LIMIT = 2.785  # fixed-step RK4 is stable for real eigenvalues lambda with -2.785 < lambda dt < 0
SEED = 20240611
RESULTS = Path(__file__).with_name("results_simulation.md")
QUICK = {"FALL_REPEATS": 2, "RK45_REPEATS": 1, "TRACK_REPEATS": 2, "KERNEL_STATES": 100, "KERNEL_REPEATS": 2}
QUICK_LIMITS = {"fdyn_timeout": 10.0}  # --quick: seconds for the Toolbox's fdyn at the most


# ----- formats ----------------------------------------------------------------------------------
def verdict(value: float, target: float) -> str:
    if value >= target:
        return f"met ({ratio(value / target)}x the target)"
    return f"NOT MET: {ratio(value)}x is {100 * (1 - value / target):.0f}% short of {target:,.0f}x"


# ----- 1. the PUMA 560 released at qr -----------------------------------------------------------
def fdyn_worker(limit: float, q0: list[float]) -> None:
    """Runs in a subprocess: the Toolbox's fdyn once, stopped by an alarm after ``limit`` seconds."""

    def build() -> object:
        import roboticstoolbox as rtb

        return rtb.models.DH.Puma560()

    puma, build_s = timed_step("ready", build)
    emit("ready", seconds=build_s, qr=[float(x) for x in puma.qr])
    n = puma.n
    progress = {"t": 0.0, "x": np.concatenate([q0, np.zeros(n)]), "evaluations": 0}
    rate = puma._fdyn  # the right-hand side fdyn integrates: counted, to say where a stopped run got to

    def counted(t: float, x: np.ndarray, torque: object, torque_args: dict) -> np.ndarray:
        progress["t"], progress["x"] = float(t), x
        progress["evaluations"] += 1
        return rate(t, x, torque, torque_args)

    puma._fdyn = counted

    class OutOfTimeError(Exception):
        pass

    def stop(signum: int, frame: object) -> None:
        raise OutOfTimeError

    signal.signal(signal.SIGALRM, stop)
    signal.setitimer(signal.ITIMER_REAL, limit)
    start = time.perf_counter()
    try:
        result = puma.fdyn(T=T_FALL, q0=np.array(q0))  # Q=None: zero torque; solver="RK45", its defaults
    except OutOfTimeError:
        elapsed, x = time.perf_counter() - start, np.asarray(progress["x"], dtype=float)
        emit("fdyn", stopped=True, seconds=elapsed, t=progress["t"], evaluations=progress["evaluations"],
             q=x[:n].tolist(), qd=x[n:].tolist())  # fmt: skip
        return
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
    elapsed = time.perf_counter() - start
    emit(
        "fdyn",
        stopped=False,
        seconds=elapsed,
        steps=len(result.t) - 1,
        evaluations=progress["evaluations"],
        t=float(result.t[-1]),
        q=[float(x) for x in result.q[-1]],
        qd=[float(x) for x in result.qd[-1]],
    )


def run_fdyn(limit: float, q0: np.ndarray) -> dict:
    """The worker's outcome: {"step": "done", ...}, {"step": "timeout", ...} (fdyn stopped at its limit) or
    {"step": "error", ...}."""
    command = [sys.executable, __file__, "--fdyn-worker", "--fdyn-timeout", str(limit), "--state"]
    command.append(json.dumps([float(x) for x in q0]))
    events = run_worker(command, [("ready", WORKER_ALLOWANCE), ("fdyn", limit + WORKER_ALLOWANCE)])
    for phase in ("ready", "fdyn"):
        event = events[phase]
        if "timeout" in event:
            return {"step": "error", "error": f"the worker was killed: no '{phase}' within {event['timeout']:.0f} s"}
        if "error" in event:
            return {"step": "error", "error": event["error"]}
    fdyn = events["fdyn"]
    return fdyn | {"step": "timeout" if fdyn["stopped"] else "done", "ready": events["ready"]}


def stiffness(arm: ad.Robot, q: np.ndarray, eps: float) -> float:
    """Largest rate (1/s) of the smoothed friction near rest: eig of M(q)^-1 (diag(Tc / eps) + B)."""
    slope = np.abs(arm.coulomb_friction).max(axis=1) / eps + arm.viscous_friction
    return float(np.max(np.linalg.eigvals(np.linalg.solve(arm.inertia_matrix(q), np.diag(slope))).real))


def state_at(result: object, t: float) -> tuple[np.ndarray, np.ndarray]:
    """(q, qd) of a simulate() result at time t, linearly interpolated between its samples."""
    q = np.array([np.interp(t, result.t, column) for column in result.q.T])
    qd = np.array([np.interp(t, result.t, column) for column in result.qd.T])
    return q, qd


def fall(arm: ad.Robot, args: argparse.Namespace) -> list[Table]:
    q0 = arm.qr
    runs = {
        f"simulate(), rk4, dt = {DT * 1e3:g} ms (default)": (
            partial(simulate, arm, None, None, t_final=T_FALL, dt=DT, q0=q0),
            FALL_REPEATS,
        ),
        f"simulate(), rk4, dt = {DT_FINE * 1e3:g} ms": (
            partial(simulate, arm, None, None, t_final=T_FALL, dt=DT_FINE, q0=q0),
            FALL_REPEATS,
        ),
        'simulate(method="rk45")': (
            partial(simulate, arm, None, None, t_final=T_FALL, dt=DT, q0=q0, method="rk45"),
            RK45_REPEATS,
        ),
    }
    print(f"  armdyn: {len(runs)} candidates ...", flush=True)
    results = {label: fn() for label, (fn, _) in runs.items()}
    candidates = (Candidate(fn, repeats=repeats) for fn, repeats in runs.values())
    times = dict(zip(runs, measure(*candidates, unit=SECOND), strict=True))
    default, _, adaptive = runs

    toolbox: dict = {"step": "skipped"}
    if not args.skip_toolbox:
        print(f"  Toolbox: puma.fdyn(T={T_FALL:g}, q0=qr) once, limit {args.fdyn_timeout:.0f} s ...", flush=True)
        toolbox = run_fdyn(args.fdyn_timeout, q0)
    ran = toolbox["step"] in ("done", "timeout")
    fdyn_label = f"puma.fdyn(T={T_FALL:g}, q0=qr), RK45 (default)"
    t_ref = toolbox["t"] if ran else T_FALL  # states are compared where fdyn got to: t = 1 s if it finished
    reference = (np.array(toolbox["q"]), np.array(toolbox["qd"])) if ran else None

    rows = []
    for label, (_, repeats) in runs.items():
        result = results[label]
        q, qd = state_at(result, t_ref)
        evaluations = result.info.get("evaluations", 4 * (len(result.t) - 1))
        against, vs_fdyn = "-", ["-", "-"]
        if ran:
            bound = "" if toolbox["step"] == "done" else "> "
            against = bound + ratio(toolbox["seconds"] / times[label])
            vs_fdyn = [sci(np.max(np.abs(q - reference[0]))), sci(np.max(np.abs(qd - reference[1])))]
        vs_rk45 = sci(np.max(np.abs(q - state_at(results[adaptive], t_ref)[0]))) if label != adaptive else "-"
        rows.append(["armdyn", label, f"{evaluations:,}", ms(times[label]), str(repeats), against, *vs_fdyn, vs_rk45])
    if ran:
        vs_rk45 = sci(np.max(np.abs(reference[0] - state_at(results[adaptive], t_ref)[0])))
        if toolbox["step"] == "done":
            cells = [fdyn_label, f"{toolbox['evaluations']:,}", ms(toolbox["seconds"])]
        else:
            stopped = f"{fdyn_label}: stopped at t = {t_ref:.3g} s of {T_FALL:g} s"
            cells = [stopped, f"> {toolbox['evaluations']:,}", f"> {ms(toolbox['seconds'])}"]
        rows.append(["Toolbox", *cells, "1", "1.00", "0", "0", vs_rk45])
    else:
        rows.append(["Toolbox", fdyn_label, "-", "-", "-", "-", "-", "-", "-"])

    eps = 1e-3  # simulate()'s default coulomb_smoothing
    rate = stiffness(arm, q0, eps)
    gravity = np.abs(arm.gravity_vector(q0))
    holding = np.abs(arm.coulomb_friction).min(axis=1)
    if ran:
        target = verdict(toolbox["seconds"] / times[default], TOOLBOX_TARGET)
        bound = " (a lower bound: fdyn was stopped)" if toolbox["step"] == "timeout" else ""
        against = f"the default armdyn run against fdyn: {target}{bound}."
    else:
        against = f"the Toolbox's run: {toolbox.get('error', 'skipped (--skip-toolbox)')}."
    where = (
        f"t = {t_ref:g} s, the end"
        if toolbox["step"] != "timeout"
        else f"t = {t_ref:.4g} s, where fdyn was stopped (its state: that of its last right-hand-side "
        "evaluation; armdyn's interpolated between its 1 ms samples)"
    )
    notes = [
        "wall ms: median of the runs (armdyn: the whole simulate() call) or the one run (Toolbox: fdyn() alone, "
        "after importing the Toolbox and building the model; its right-hand side wrapped in a call counter, well "
        "under 1% of its cost). evaluations: of the forward dynamics (armdyn's RK4: 4 per step; rk45 and fdyn: "
        "the solver's count).",
        f"fdyn/this: the Toolbox's time over this row's; {against}",
        f"max |dq|, |dqd|: largest difference over the joints, in rad and rad/s, of the states at {where}. "
        "armdyn smooths Coulomb friction as Tc tanh(qd / 1e-3); the Toolbox applies Tc sgn(qd). rk45 runs "
        "solve_ivp at rtol 1e-8, atol 1e-10; fdyn at scipy's defaults (rtol 1e-3, atol 1e-6).",
        f"At qr the arm is upright: |G(qr)| = [{', '.join(f'{g:.2g}' for g in gravity)}] N m is below the Coulomb "
        f"friction of every joint (at least [{', '.join(f'{h:.2g}' for h in holding)}] N m), so the arm does not "
        "fall: friction holds it and the run tests sticking, the hardest case for an integrator of sgn(qd).",
        f"The smoothed friction is stiff near rest: M(qr)^-1 (diag(Tc / eps) + B) has eigenvalues up to "
        f"{rate:,.0f} 1/s, i.e. lambda dt = {rate * DT:.1f} at dt = {DT * 1e3:g} ms, outside fixed-step RK4's "
        f"stability interval ({RK4_LIMIT}); at dt = {DT_FINE * 1e3:g} ms, {rate * DT_FINE:.1f}. See table 1b.",
    ]
    if ran and not np.allclose(toolbox["ready"].get("qr", q0), q0):
        notes.append(
            f"WARNING: the Toolbox's qr {toolbox['ready']['qr']} is not armdyn's {list(q0)}; fdyn ran from armdyn's."
        )
    summary = Table(
        f"1a. PUMA 560 released at qr, zero torque, with friction, {T_FALL:g} s simulated",
        ["simulator", "method", "evaluations", "wall ms", "runs", "fdyn/this", "max |dq| vs fdyn",
         "max |dqd| vs fdyn", "max |dq| vs rk45"],
        rows,
        notes,
        left=2,
    )  # fmt: skip

    names = {label: name for label, name in zip(runs, ["rk4 1 ms", f"rk4 {DT_FINE * 1e3:g} ms", "rk45"], strict=True)}
    columns = [(name, results[label].q[-1] - q0, results[label].qd[-1]) for label, name in names.items()]
    if toolbox["step"] == "done":
        columns.append(("fdyn", reference[0] - q0, reference[1]))
    joints = [[str(j + 1), *(sci(c[1][j]) for c in columns), *(sci(c[2][j]) for c in columns)] for j in range(arm.n)]
    states = Table(
        f"1b. The same runs: final state per joint at t = {T_FALL:g} s",
        ["joint", *(f"q - qr, {c[0]}" for c in columns), *(f"qd, {c[0]}" for c in columns)],
        joints,
        [
            "q - qr in rad, qd in rad/s. With the smoothed friction, joints 2 and 3 creep at the small speed at "
            "which Tc tanh(qd / eps) balances gravity; the others should stay at rest. Where RK4 at 1 ms moves a "
            "joint that rk45 and RK4 at the finer step keep at rest, that is the integrator, not the dynamics.",
        ],
        left=1,
    )
    return [summary, states]


# ----- 2 and 3. computed-torque tracking --------------------------------------------------------
def tracking(arms: dict[str, tuple[ad.Robot, Sinusoid, float]]) -> tuple[list[list[str]], dict[str, float]]:
    """Rows per arm, and the median seconds of each run."""
    runs = {
        name: partial(simulate, arm, ComputedTorque(*GAINS), trajectory, t_final=t_final, dt=DT)
        for name, (arm, trajectory, t_final) in arms.items()
    }
    timed = dict(zip(runs, samples(*(Candidate(fn, repeats=TRACK_REPEATS) for fn in runs.values())), strict=True))
    times = {name: statistics.median(values) for name, values in timed.items()}
    rows = []
    for name, fn in runs.items():
        t_final = arms[name][2]
        result = fn()
        error = np.abs(result.error)
        last = result.t >= result.t[-1] - 1.0
        steps = len(result.t) - 1
        factor = t_final / times[name]
        target = verdict(factor, REAL_TIME_TARGET) if name.startswith("PUMA") else "-"
        rows.append(
            [name, f"{t_final:g}", f"{steps:,}", ms(times[name]), ms(min(timed[name])),
             us(times[name] / steps * 1e6), ratio(factor), ratio(t_final / min(timed[name])), target,
             sci(error[-1].max()), sci(error[last].max()), sci(error.max())]
        )  # fmt: skip
    return rows, times


def tracking_error(arm: ad.Robot, trajectory: Sinusoid) -> list[list[str]]:
    """The PUMA 560's tracking run once per variant (untimed): what its tracking error comes from."""
    variants = {
        f"as in part 2 (dt = {DT * 1e3:g} ms, friction smoothed with eps = 1e-3)": (arm, DT, 1e-3),
        "arm.without_friction()": (arm.without_friction(), DT, 1e-3),
        f"dt = {DT_FINE * 1e3:g} ms": (arm, DT_FINE, 1e-3),
        "coulomb_smoothing = 1e-2": (arm, DT, 1e-2),
    }
    rows = []
    for label, (plant, dt, eps) in variants.items():
        result = simulate(plant, ComputedTorque(*GAINS), trajectory, t_final=T_PUMA, dt=dt, coulomb_smoothing=eps)
        error = np.abs(result.error)
        last = result.t >= result.t[-1] - 1.0
        rows.append([label, sci(error[-1].max()), sci(error[last].max())])
    return rows


# ----- 4. where the time goes -------------------------------------------------------------------
# Each loop runs one of armdyn's kernels (inlined, as simulation.py inlines them into its loop) over
# distinct states, with one workspace of packed.workspace_size(n) values for the whole loop.
@njit(inline="always", **NUMBA_OPTIONS)
def _torque(M: np.ndarray, N: np.ndarray, u: np.ndarray, tau: np.ndarray) -> None:
    """tau = M u + N."""
    n = N.shape[0]
    for i in range(n):
        total = N[i]
        for j in range(n):
            total += M[i, j] * u[j]
        tau[i] = total


@njit(**NUMBA_OPTIONS)
def _loop_aba(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray, out: np.ndarray) -> None:
    work = np.empty(workspace_size(Q.shape[1]))
    for s in range(Q.shape[0]):
        aba_core(model, work, Q[s], QD[s], TAU[s], out[s])


@njit(**NUMBA_OPTIONS)
def _loop_crba(model: np.ndarray, Q: np.ndarray, out: np.ndarray) -> None:
    work = np.empty(workspace_size(Q.shape[1]))
    for s in range(Q.shape[0]):
        crba_core(model, work, Q[s], out[s])


@njit(**NUMBA_OPTIONS)
def _loop_nonlinear(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, out: np.ndarray) -> None:
    work = np.empty(workspace_size(Q.shape[1]))
    for s in range(Q.shape[0]):
        rnea_core(model, work, Q[s], QD[s], QD[s], QD[s], NONLINEAR, out[s])


@njit(**NUMBA_OPTIONS)
def _loop_inverse(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, U: np.ndarray, out: np.ndarray) -> None:
    work = np.empty(workspace_size(Q.shape[1]))
    for s in range(Q.shape[0]):
        rnea_core(model, work, Q[s], QD[s], U[s], QD[s], INVERSE_DYNAMICS, out[s])


@njit(**NUMBA_OPTIONS)
def _loop_computed_torque(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, U: np.ndarray, out: np.ndarray) -> None:
    """tau = M(q) u + N(q, qd) by CRBA, RNEA and a matrix-vector product."""
    n = Q.shape[1]
    work, M, N = np.empty(workspace_size(n)), np.empty((n, n)), np.empty(n)
    for s in range(Q.shape[0]):
        crba_core(model, work, Q[s], M)
        rnea_core(model, work, Q[s], QD[s], QD[s], QD[s], NONLINEAR, N)
        _torque(M, N, U[s], out[s])


@njit(**NUMBA_OPTIONS)
def _free_stops(n: int) -> np.ndarray:
    """Joint stops at infinity (none), as simulation.stop_torque reads them."""
    stops = np.zeros((n, 4))
    stops[:, 0], stops[:, 1] = -np.inf, np.inf
    return stops


@njit(**NUMBA_OPTIONS)
def _loop_cholesky(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray, out: np.ndarray) -> None:
    """qdd = M^-1 (tau - N) by CRBA, RNEA and the simulation's Cholesky solve (simulation._solve)."""
    n = Q.shape[1]
    work, M, N = np.empty(workspace_size(n)), np.empty((n, n)), np.empty(n)
    no_coulomb, no_smoothing = np.zeros((n, 4)), np.zeros(n)  # the model's own Coulomb friction is in N
    free = _free_stops(n)
    for s in range(Q.shape[0]):
        crba_core(model, work, Q[s], M)
        rnea_core(model, work, Q[s], QD[s], QD[s], QD[s], NONLINEAR, N)
        _solve(M, N, TAU[s], no_coulomb, no_smoothing, free, Q[s], QD[s], out[s], 0.0)


@njit(**NUMBA_OPTIONS)
def _loop_fused(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray, out: np.ndarray) -> None:
    """qdd = M^-1 (tau - N), M and N by crba.mass_matrix_and_bias, then simulation._solve."""
    n = Q.shape[1]
    work, M, N = np.empty(workspace_size(n)), np.empty((n, n)), np.empty(n)
    no_coulomb, no_smoothing = np.zeros((n, 4)), np.zeros(n)
    free = _free_stops(n)
    for s in range(Q.shape[0]):
        mass_matrix_and_bias(model, work, Q[s], QD[s], M, N)
        _solve(M, N, TAU[s], no_coulomb, no_smoothing, free, Q[s], QD[s], out[s], 0.0)


@njit(**NUMBA_OPTIONS)
def _loop_fused_torque(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, U: np.ndarray, out: np.ndarray) -> None:
    """tau = M u + N, M and N by crba.mass_matrix_and_bias."""
    n = Q.shape[1]
    work, M, N = np.empty(workspace_size(n)), np.empty((n, n)), np.empty(n)
    for s in range(Q.shape[0]):
        mass_matrix_and_bias(model, work, Q[s], QD[s], M, N)
        _torque(M, N, U[s], out[s])


@njit(**NUMBA_OPTIONS)
def _loop_energy(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, out: np.ndarray) -> None:
    work = np.empty(workspace_size(Q.shape[1]))
    for s in range(Q.shape[0]):
        energy_core(model, work, Q[s], QD[s], out[s])


@njit(**NUMBA_OPTIONS)
def _loop_coulomb(coulomb: np.ndarray, eps: np.ndarray, QD: np.ndarray, out: np.ndarray) -> None:
    """The smoothed Coulomb friction of every joint, as simulate() applies it (friction.smooth_coulomb)."""
    for s in range(QD.shape[0]):
        for i in range(QD.shape[1]):
            out[s, i] = smooth_coulomb(coulomb, eps, i, QD[s, i])


def kernels(arm: ad.Robot, rng: np.random.Generator) -> tuple[list[list[str]], dict[str, float]]:
    """Microseconds per call of each kernel in a compiled loop over distinct states, each loop's result
    checked against a reference before timing; rows and the times."""
    model, n = arm.packed, arm.n
    Q, QD, U = rng.uniform(-1.0, 1.0, (3, KERNEL_STATES, n))
    reference_fd = np.array([arm.forward_dynamics(q, qd, u) for q, qd, u in zip(Q, QD, U, strict=True)])
    reference_M = np.array([arm.inertia_matrix(q) for q in Q])
    reference_N = np.array([arm.nonlinear_terms(q, qd) for q, qd in zip(Q, QD, strict=True)])
    reference_tau = np.einsum("sij,sj->si", reference_M, U) + reference_N
    reference_energy = np.array(
        [[arm.kinetic_energy(q, qd), arm.potential_energy(q)] for q, qd in zip(Q, QD, strict=True)]
    )
    outs = {
        name: np.empty((KERNEL_STATES, n))
        for name in ("aba", "cholesky", "fused", "nonlinear", "inverse", "computed", "fused_torque", "coulomb")
    }
    outs["crba"], outs["energy"] = np.empty((KERNEL_STATES, n, n)), np.empty((KERNEL_STATES, 2))
    state, torque, coulomb = (model, Q, QD, U), (model, Q, QD), (arm.coulomb_friction.copy(), np.full(n, 1e-3), QD)
    kinds = [  # name, label, loop, its inputs (before its output), the reference its result is checked against
        ("aba", "forward dynamics, ABA (aba_core)", _loop_aba, state, reference_fd),
        ("cholesky", "forward dynamics, CRBA + RNEA + Cholesky solve", _loop_cholesky, state, reference_fd),
        ("fused", "forward dynamics, mass_matrix_and_bias + Cholesky solve", _loop_fused, state, reference_fd),
        ("crba", "M(q), CRBA (crba_core)", _loop_crba, (model, Q), reference_M),
        ("nonlinear", "N(q, qd), RNEA (rnea_core, NONLINEAR)", _loop_nonlinear, torque, reference_N),
        ("computed", "computed torque M u + N: CRBA + RNEA + M u", _loop_computed_torque, state, reference_tau),
        ("fused_torque", "computed torque M u + N: mass_matrix_and_bias + M u", _loop_fused_torque, state,
         reference_tau),
        ("inverse", "computed torque M u + N: one RNEA with qdd = u", _loop_inverse, state, reference_tau),
        ("energy", "kinetic + potential energy (energy_core)", _loop_energy, torque, reference_energy),
        ("coulomb", f"smoothed Coulomb friction, {n} tanh", _loop_coulomb, coulomb, None),
    ]  # fmt: skip
    loops = {
        name: (label, partial(loop, *inputs, outs[name]), reference) for name, label, loop, inputs, reference in kinds
    }
    agreement = {}
    for name, (_, call, reference) in loops.items():
        call()
        agreement[name] = "-"
        if reference is not None:
            error = relative_error(outs[name], reference)
            agreement[name] = sci(error) + ("" if error <= TOLERANCE else f" (DIFFERS: more than {TOLERANCE:g})")
    candidates = (Candidate(call, repeats=KERNEL_REPEATS, states=KERNEL_STATES) for _, call, _ in loops.values())
    per_call = dict(zip(loops, measure(*candidates), strict=True))
    rows = [[label, us(per_call[name]), agreement[name]] for name, (label, _, _) in loops.items()]
    return rows, per_call


def breakdown(arm: ad.Robot, trajectory: Sinusoid) -> tuple[list[list[str]], float]:
    """simulate() of the PUMA 560 split into its parts, and with less work per step, all runs interleaved.

    Returns the rows and the microseconds per step of the compiled loop."""
    steps = round(T_PUMA / DT) + 1
    tracking_run = partial(simulate, arm, ComputedTorque(*GAINS), trajectory, t_final=T_PUMA, dt=DT)
    one_step = partial(simulate, arm, ComputedTorque(*GAINS), trajectory, t_final=DT, dt=DT)
    threads = numba.get_num_threads()

    def single_thread(fn: Callable[[], object]) -> Callable[[], object]:
        def run() -> object:
            numba.set_num_threads(1)
            try:
                return fn()
            finally:
                numba.set_num_threads(threads)

        return run

    split: list[dict[str, float]] = []  # seconds of each part, and the total, per call
    with Spans(simulation, ("run_rk4", "_energies")) as parts:

        def in_parts() -> None:
            parts.spent.clear()
            total = wall(tracking_run)[1]
            split.append({name: spent / 1e9 for name, spent in parts.spent.items()} | {"total": total})

        runs = {
            "ComputedTorque on the sinusoid (part 2), timed in parts: the whole call": in_parts,
            "one step (t_final = dt): the fixed cost of a call": one_step,
            "zero torque, no trajectory (from qz)": partial(simulate, arm, None, None, t_final=T_PUMA, dt=DT),
            f"PID({GAINS[0]:g}, {GAINS[1]:g}) on the sinusoid": partial(
                simulate, arm, PID(*GAINS), trajectory, t_final=T_PUMA, dt=DT
            ),
            "ComputedTorque on the sinusoid, arm without friction": partial(
                simulate, arm.without_friction(), ComputedTorque(*GAINS), trajectory, t_final=T_PUMA, dt=DT
            ),
            f"one step, numba.set_num_threads(1) (default {threads})": single_thread(one_step),
            "ComputedTorque on the sinusoid, numba.set_num_threads(1)": single_thread(tracking_run),
        }
        candidates = (Candidate(fn, repeats=TRACK_REPEATS) for fn in runs.values())
        times = dict(zip(runs, measure(*candidates, unit=SECOND), strict=True))
    split = split[1:]  # the first call was the warm-up
    whole, fixed, fixed_single = (list(times)[i] for i in (0, 1, 5))

    def per_step(seconds: float) -> str:
        return us(seconds / steps * 1e6)

    rows = [[whole, ms(times[whole]), per_step(times[whole] - times[fixed])]]
    median = {name: statistics.median(s.get(name, 0.0) for s in split) for name in parts.originals}
    if "run_rk4" in median:
        rows.append(
            ["  of which the compiled loop (simulation.run_rk4)", ms(median["run_rk4"]), per_step(median["run_rk4"])]
        )
    if "_energies" in median:
        label = "  of which the energies after the run (simulation._energies, a Numba-parallel batch)"
        rows.append([label, ms(median["_energies"]), per_step(median["_energies"])])
    if len(median) == 2:
        rest = statistics.median(s["total"] - sum(s.get(name, 0.0) for name in median) for s in split)
        rows.append(["  of which the rest (set-up in Python, the Result)", ms(rest), "-"])
    for label in list(runs)[1:]:
        base = times[fixed_single] if "set_num_threads" in label else times[fixed]
        rows.append([label, ms(times[label]), "-" if label in (fixed, fixed_single) else per_step(times[label] - base)])
    loop = median.get("run_rk4")
    return rows, (loop / steps * 1e6 if loop is not None else math.nan)


# ----- the run ----------------------------------------------------------------------------------


def header(source: tuple[str, str], args: argparse.Namespace) -> list[str]:
    toolbox = "skipped (--skip-toolbox)" if args.skip_toolbox else version("roboticstoolbox-python")
    versions = {
        "numba": numba.__version__,
        "numpy": np.__version__,
        "scipy": version("scipy"),
        "roboticstoolbox": toolbox,
    }
    return describe(source, versions, " (the simulation loop runs on one)") + [
        f"armdyn's times are medians: {FALL_REPEATS} runs each at dt = 1 ms and 0.2 ms, {RK45_REPEATS} with rk45, "
        f"{TRACK_REPEATS} per tracking run, {KERNEL_REPEATS} loops of {KERNEL_STATES:,} states per kernel; the "
        "candidates' runs are interleaved. Each simulate() time is the whole call (setup, loop, Result).",
    ]


def warm_up(puma: ad.Robot, rr: ad.Robot, trajectories: Sequence[Sinusoid]) -> None:
    """The first simulate() calls (Numba compiles or loads its cache), untimed."""
    simulate(puma, None, None, t_final=0.01, dt=DT, q0=puma.qr)
    simulate(puma, None, None, t_final=0.01, dt=DT, q0=puma.qr, method="rk45")
    for arm, trajectory in zip((puma, rr), trajectories, strict=True):
        simulate(arm, ComputedTorque(*GAINS), trajectory, t_final=0.01, dt=DT)
    simulate(puma, PID(*GAINS), trajectories[0], t_final=0.01, dt=DT)


def main() -> None:
    parser = arguments(__doc__, skip_toolbox="leave out the Robotics Toolbox's fdyn")
    parser.add_argument(
        "--fdyn-timeout", type=float, default=FDYN_TIMEOUT, help="seconds for the Toolbox's fdyn (default 300)"
    )
    parser.add_argument("--fdyn-worker", action="store_true", help=argparse.SUPPRESS)
    args = parse(parser, "fdyn_worker", lambda args: fdyn_worker(args.fdyn_timeout, json.loads(args.state)))
    report = Report.begin(args, "armdyn simulation benchmarks", RESULTS, globals(), QUICK, QUICK_LIMITS)
    rng = np.random.default_rng(SEED)
    report.note(*header(report.source, args))

    puma, rr = ad.models.puma560(), ad.models.two_link_planar()
    phases = np.where(np.arange(puma.n) % 2 == 0, 0.0, np.pi / 2)
    puma_trajectory = Sinusoid(0.1, 0.5, phase=phases, offset=puma.qz)
    rr_trajectory = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])
    seconds = wall(partial(warm_up, puma, rr, (puma_trajectory, rr_trajectory)))[1]
    report.note(
        f"armdyn's first simulate() calls in this process (compile or load machine code, untimed): {seconds:.1f} s",
        end="\n\n",
    )

    for table in fall(puma, args):
        report.show(table)

    arms = {
        f"PUMA 560, {T_PUMA:g} s": (puma, puma_trajectory, T_PUMA),
        f"RR arm (Example 4.4-1), {T_RR:g} s": (rr, rr_trajectory, T_RR),
    }
    rows, _ = tracking(arms)
    report.show(
        Table(
            f"2-3. Computed-torque tracking at {1 / DT:g} Hz (RK4, dt = {DT * 1e3:g} ms, compiled)",
            [
                "arm, simulated",
                "s",
                "steps",
                "wall ms",
                "best ms",
                "us/step",
                "x real time",
                "x, best run",
                f"target {REAL_TIME_TARGET:g}x",
                "final max |e|",
                "max |e|, last 1 s",
                "max |e|",
            ],
            rows,
            [
                f"ComputedTorque({GAINS[0]:g}, {GAINS[1]:g}) with the plant as its model; PUMA 560: "
                f"Sinusoid(0.1, 0.5, phase=[0, pi/2, 0, pi/2, 0, pi/2], offset=qz) from q0 = qz (joints 2, 4, 6 "
                "start 0.1 rad off the trajectory); RR arm: Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0, pi/2]) "
                "from q0 = 0 (joint 2 starts 0.1 rad off).",
                "wall ms: median of the runs, the whole simulate() call (best: the fastest run, the least disturbed "
                "by other processes); us/step and x real time (= simulated seconds / wall seconds) from the "
                "median, 'x, best run' from the best. e = q_d - q in rad: at the final time, over the last "
                "second, and over the run (the largest is the initial offset).",
            ],
            left=1,
        )
    )

    report.show(
        Table(
            "2b. PUMA 560 tracking error (rad) of the same run with less friction stiffness or a finer step",
            ["variant", "final max |e|", "max |e|, last 1 s"],
            tracking_error(puma, puma_trajectory),
            [
                "One untimed run each. The controller (on its own model, with the same smoothed friction) runs "
                "once per step and holds its torque over the step, while the plant's smoothed Coulomb friction "
                "changes by up to 2 Tc within a few eps of velocity: near each velocity reversal the held "
                "torque cannot cancel it, and RK4 at 1 ms is outside its stability interval there (table 1a).",
            ],
            left=1,
        )
    )

    kernel_rows, per_call = kernels(puma, rng)
    step_rows, loop_per_step = breakdown(puma, puma_trajectory)
    steps = round(T_PUMA / DT) + 1
    budget = T_PUMA / REAL_TIME_TARGET / steps * 1e6
    fd, controller = per_call["cholesky"], per_call["computed"]
    sums = [
        ("ABA design: 4 ABA + CRBA + RNEA + M u", 4 * per_call["aba"] + controller),
        ("Cholesky design: 4 (CRBA + RNEA + Cholesky) + CRBA + RNEA + M u", 4 * fd + controller),
        ("the same, the first stage from the controller's M and N: 3 FD + controller", 3 * fd + controller),
        (
            "the same with M and N by mass_matrix_and_bias: 3 FD + controller",
            3 * per_call["fused"] + per_call["fused_torque"],
        ),
    ]
    report.show(
        Table(
            f"4a. Where the time goes: simulate() of the PUMA 560, {T_PUMA:g} s at {DT * 1e3:g} ms, in parts and "
            "with less work per step",
            ["run", "wall ms", "us/step"],
            step_rows,
            [
                "us/step: a part's time / steps; for a whole call, (wall - the fixed cost of a call) / steps. "
                "Each RK4 step evaluates the forward dynamics 4 times (with the smoothed Coulomb friction), "
                "the controller once, and records the state. The parts are timed by wrapping the two functions "
                "of armdyn.simulation in timers for those runs only.",
                f"Budget for {REAL_TIME_TARGET:g}x real time: {ms(T_PUMA / REAL_TIME_TARGET)} ms per call, "
                f"{us(budget)} us per step including the fixed cost.",
            ],
            left=1,
        )
    )
    report.show(
        Table(
            f"4b. PUMA 560 kernels in a compiled loop over {KERNEL_STATES:,} distinct states (microseconds per call)",
            ["kernel", "us/call", "max rel. diff vs reference"],
            kernel_rows + [[f"sum, {label}", us(value), "-"] for label, value in sums],
            [
                "Each kernel is inlined into a Numba loop of this file (cache=True), as simulation.py inlines it "
                "into its loop; no Python call per state. References: arm.forward_dynamics, inertia_matrix, "
                "nonlinear_terms, inertia_matrix @ u + nonlinear_terms, kinetic_energy + potential_energy "
                "(forward dynamics with the arm's friction: Coulomb sgn(qd) in both). Each loop's result is "
                "checked against its reference before timing. The Cholesky solve is simulation._solve, given "
                "a zero Coulomb table (the model's Coulomb friction is already in N).",
                f"The sums are per-step costs of step designs, to compare with the compiled loop's "
                f"{us(loop_per_step)} us per step (4a) and the budget of {us(budget)} us per step for "
                f"{REAL_TIME_TARGET:g}x real time.",
            ],
            left=1,
        )
    )

    report.finish("the parts may have timed different versions.")


if __name__ == "__main__":
    main()
