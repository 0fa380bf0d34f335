"""armdyn's simulation loop timed: the PUMA 560 under zero torque against the Robotics Toolbox's fdyn, and
computed-torque tracking at 1 kHz against real time.

    .venv/bin/python benchmarks/bench_simulation.py                      # about 6 minutes (fdyn: up to 5)
    .venv/bin/python benchmarks/bench_simulation.py --skip-toolbox       # about 1 minute
    .venv/bin/python benchmarks/bench_simulation.py --fdyn-timeout 60

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
them alike. The Toolbox's run is timed once. Prints plain tables and writes the same as Markdown to
results_simulation.md.
"""

from __future__ import annotations

import argparse
import datetime
import gc
import json
import math
import os
import platform
import signal
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numba
import numpy as np
from common import cpu_model, ratio, source_state, us, version
from numba import njit

import armdyn as ad
from armdyn.control import PID, ComputedTorque
from armdyn.dynamics import kernels as K
from armdyn.dynamics.compiled import compile_robot
from armdyn.simulation import simulate
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
EVENT = "@@event "  # prefix of the worker's result lines on its stdout


# ----- timing -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Candidate:
    """A zero-argument call to time, ``repeats`` times."""

    fn: Callable[[], object]
    repeats: int = TRACK_REPEATS


def samples(*candidates: Candidate) -> list[list[float]]:
    """Seconds of each timed call of each candidate, after one warm-up call; repeats interleaved, garbage
    collector off."""
    for candidate in candidates:
        candidate.fn()  # warm-up: armdyn compiles or loads its machine code on a first call
    times: list[list[int]] = [[] for _ in candidates]
    collecting = gc.isenabled()
    gc.disable()
    try:
        for repeat in range(max(candidate.repeats for candidate in candidates)):
            for candidate, values in zip(candidates, times, strict=True):
                if repeat < candidate.repeats:
                    start = time.perf_counter_ns()
                    candidate.fn()
                    values.append(time.perf_counter_ns() - start)
    finally:
        if collecting:
            gc.enable()
    return [[value / 1e9 for value in values] for values in times]


def measure(*candidates: Candidate) -> list[float]:
    """Median seconds per call of each candidate (see samples)."""
    return [statistics.median(values) for values in samples(*candidates)]


def relative_error(ours: object, theirs: object) -> float:
    """Largest difference relative to the largest entry of the reference."""
    ours, theirs = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if ours.shape != theirs.shape:
        raise AssertionError(f"shapes differ: {ours.shape} vs {theirs.shape}")
    return float(np.max(np.abs(ours - theirs)) / max(np.max(np.abs(theirs)), 1e-300))


# ----- tables -----------------------------------------------------------------------------------
@dataclass
class Table:
    title: str
    headers: Sequence[str]
    rows: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    left: int = 2  # columns aligned left in Markdown; the others are numbers

    def text(self) -> str:
        widths = [max(len(row[i]) for row in [self.headers, *self.rows]) for i in range(len(self.headers))]

        def line(cells: Sequence[str]) -> str:
            return "  ".join(cell.ljust(width) for cell, width in zip(cells, widths, strict=True)).rstrip()

        rule = "  ".join("-" * width for width in widths)
        body = [self.title, "=" * len(self.title), line(self.headers), rule, *map(line, self.rows)]
        return "\n".join(body + [f"  * {note}" for note in self.notes]) + "\n"

    def markdown(self) -> str:
        body = [f"## {self.title}", "", "| " + " | ".join(self.headers) + " |"]
        body.append("|" + "|".join("---" if i < self.left else "---:" for i in range(len(self.headers))) + "|")
        body += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in self.rows]
        if self.notes:
            body += ["", *(f"- {note}" for note in self.notes)]
        return "\n".join(body) + "\n"


def ms(value: float) -> str:
    """Seconds shown as milliseconds, about three significant digits."""
    return us(value * 1e3)


def sci(value: float) -> str:
    return f"{value:.1e}"


def verdict(value: float, target: float) -> str:
    if value >= target:
        return f"met ({ratio(value / target)}x the target)"
    return f"NOT MET: {ratio(value)}x is {100 * (1 - value / target):.0f}% short of {target:,.0f}x"


# ----- 1. the PUMA 560 released at qr -----------------------------------------------------------
def fdyn_worker(limit: float, q0: list[float]) -> None:
    """Runs in a subprocess: the Toolbox's fdyn once, stopped by an alarm after ``limit`` seconds."""

    def emit(step: str, **values: object) -> None:
        print(EVENT + json.dumps({"step": step, **values}), flush=True)

    start = time.perf_counter()
    import roboticstoolbox as rtb

    puma = rtb.models.DH.Puma560()
    emit("ready", seconds=time.perf_counter() - start, qr=[float(x) for x in puma.qr])
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
        emit("timeout", seconds=elapsed, t=progress["t"], evaluations=progress["evaluations"],
             q=x[:n].tolist(), qd=x[n:].tolist())  # fmt: skip
        return
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
    elapsed = time.perf_counter() - start
    emit(
        "done",
        seconds=elapsed,
        steps=len(result.t) - 1,
        evaluations=progress["evaluations"],
        t=float(result.t[-1]),
        q=[float(x) for x in result.q[-1]],
        qd=[float(x) for x in result.qd[-1]],
    )


def run_fdyn(limit: float, q0: np.ndarray) -> dict:
    """The worker's outcome: {"step": "done", ...}, {"step": "timeout", ...} or {"step": "error", ...}."""
    command = [sys.executable, __file__, "--fdyn-worker", "--fdyn-timeout", str(limit), "--state"]
    command.append(json.dumps([float(x) for x in q0]))
    try:
        process = subprocess.run(command, capture_output=True, text=True, timeout=limit + WORKER_ALLOWANCE)
    except subprocess.TimeoutExpired:
        return {"step": "error", "error": f"the worker was killed after {limit + WORKER_ALLOWANCE:.0f} s"}
    events = {}
    for line in process.stdout.splitlines():
        if line.startswith(EVENT):
            event = json.loads(line[len(EVENT) :])
            events[event["step"]] = event
    for step in ("done", "timeout"):
        if step in events:
            return events[step] | {"ready": events.get("ready", {})}
    tail = " ".join(process.stderr.strip().splitlines()[-3:])[-300:]
    return {"step": "error", "error": f"worker exited with code {process.returncode}: {tail}"}


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
    times = dict(zip(runs, measure(*(Candidate(fn, repeats) for fn, repeats in runs.values())), strict=True))
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
    timed = dict(zip(runs, samples(*(Candidate(fn) for fn in runs.values())), strict=True))
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
_NJIT = {"cache": True, "fastmath": {"contract"}, "error_model": "numpy", "boundscheck": False}


@njit(**_NJIT)
def _loop_aba(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray, out: np.ndarray) -> None:
    w = np.empty(200 * Q.shape[1] + 128)
    for s in range(Q.shape[0]):
        K.aba_core(m, w, 0, Q[s], QD[s], TAU[s], out[s])


@njit(**_NJIT)
def _loop_crba(m: np.ndarray, Q: np.ndarray, out: np.ndarray) -> None:
    w = np.empty(200 * Q.shape[1] + 128)
    for s in range(Q.shape[0]):
        K.crba_core(m, w, 0, Q[s], out[s])


@njit(**_NJIT)
def _loop_nonlinear(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, out: np.ndarray) -> None:
    w = np.empty(200 * Q.shape[1] + 128)
    for s in range(Q.shape[0]):
        K.rnea_core(m, w, 0, Q[s], QD[s], QD[s], QD[s], K.NONLINEAR, out[s])


@njit(**_NJIT)
def _loop_inverse(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, U: np.ndarray, out: np.ndarray) -> None:
    w = np.empty(200 * Q.shape[1] + 128)
    for s in range(Q.shape[0]):
        K.rnea_core(m, w, 0, Q[s], QD[s], U[s], QD[s], K.INVERSE_DYNAMICS, out[s])


@njit(**_NJIT)
def _loop_computed_torque(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, U: np.ndarray, out: np.ndarray) -> None:
    """tau = M(q) u + N(q, qd) by CRBA, RNEA and a matrix-vector product."""
    n = Q.shape[1]
    w, M, N = np.empty(200 * n + 128), np.empty((n, n)), np.empty(n)
    for s in range(Q.shape[0]):
        K.crba_core(m, w, 0, Q[s], M)
        K.rnea_core(m, w, 0, Q[s], QD[s], QD[s], QD[s], K.NONLINEAR, N)
        for i in range(n):
            total = N[i]
            for j in range(n):
                total += M[i, j] * U[s, j]
            out[s, i] = total


@njit(inline="always", **_NJIT)
def _cholesky_solve(M: np.ndarray, N: np.ndarray, tau: np.ndarray, y: np.ndarray) -> None:
    """y = M^-1 (tau - N) by a Cholesky factorization of M in place."""
    n = N.shape[0]
    for j in range(n):
        total = M[j, j]
        for k in range(j):
            total -= M[j, k] * M[j, k]
        pivot = math.sqrt(total)
        M[j, j] = pivot
        for i in range(j + 1, n):
            total = M[i, j]
            for k in range(j):
                total -= M[i, k] * M[j, k]
            M[i, j] = total / pivot
    for i in range(n):
        total = tau[i] - N[i]
        for k in range(i):
            total -= M[i, k] * y[k]
        y[i] = total / M[i, i]
    for i in range(n - 1, -1, -1):
        total = y[i]
        for k in range(i + 1, n):
            total -= M[k, i] * y[k]
        y[i] = total / M[i, i]


@njit(**_NJIT)
def _loop_cholesky(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray, out: np.ndarray) -> None:
    """qdd = M^-1 (tau - N) by CRBA, RNEA and a Cholesky solve."""
    n = Q.shape[1]
    w, M, N = np.empty(200 * n + 128), np.empty((n, n)), np.empty(n)
    for s in range(Q.shape[0]):
        K.crba_core(m, w, 0, Q[s], M)
        K.rnea_core(m, w, 0, Q[s], QD[s], QD[s], QD[s], K.NONLINEAR, N)
        _cholesky_solve(M, N, TAU[s], out[s])


FUSED = hasattr(K, "mass_matrix_and_bias")  # M and N in one pass, in armdyn's newer kernels


@njit(**_NJIT)
def _loop_fused(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray, out: np.ndarray) -> None:
    """qdd = M^-1 (tau - N), M and N by kernels.mass_matrix_and_bias (compiled only when it exists)."""
    n = Q.shape[1]
    w, M, N = np.empty(200 * n + 128), np.empty((n, n)), np.empty(n)
    for s in range(Q.shape[0]):
        K.mass_matrix_and_bias(m, w, 0, Q[s], QD[s], M, N)
        _cholesky_solve(M, N, TAU[s], out[s])


@njit(**_NJIT)
def _loop_fused_torque(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, U: np.ndarray, out: np.ndarray) -> None:
    """tau = M u + N, M and N by kernels.mass_matrix_and_bias (compiled only when it exists)."""
    n = Q.shape[1]
    w, M, N = np.empty(200 * n + 128), np.empty((n, n)), np.empty(n)
    for s in range(Q.shape[0]):
        K.mass_matrix_and_bias(m, w, 0, Q[s], QD[s], M, N)
        for i in range(n):
            total = N[i]
            for j in range(n):
                total += M[i, j] * U[s, j]
            out[s, i] = total


@njit(**_NJIT)
def _loop_energy(m: np.ndarray, Q: np.ndarray, QD: np.ndarray, out: np.ndarray) -> None:
    w = np.empty(200 * Q.shape[1] + 128)
    for s in range(Q.shape[0]):
        K.energy_core(m, w, 0, Q[s], QD[s], out[s])


@njit(**_NJIT)
def _loop_coulomb(coulomb: np.ndarray, eps: float, QD: np.ndarray, out: np.ndarray) -> None:
    """The smoothed Coulomb friction of every joint, as simulate() applies it."""
    for s in range(QD.shape[0]):
        for i in range(QD.shape[1]):
            rate = QD[s, i]
            smooth = math.tanh(rate / eps)
            out[s, i] = smooth * coulomb[i, 0] if rate >= 0.0 else -smooth * coulomb[i, 1]


def kernels(arm: ad.Robot, rng: np.random.Generator) -> tuple[list[list[str]], dict[str, float]]:
    """Microseconds per call of each kernel in a compiled loop over distinct states; rows and the times."""
    m = compile_robot(arm)
    n = arm.n
    Q, QD, U = rng.uniform(-1.0, 1.0, (3, KERNEL_STATES, n))
    matrix = np.empty((KERNEL_STATES, n, n))
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
    energy = np.empty((KERNEL_STATES, 2))
    loops = {
        "aba": ("forward dynamics, ABA (aba_core)", partial(_loop_aba, m, Q, QD, U, outs["aba"]), reference_fd),
        "cholesky": (
            "forward dynamics, CRBA + RNEA + Cholesky solve",
            partial(_loop_cholesky, m, Q, QD, U, outs["cholesky"]),
            reference_fd,
        ),
        "fused": (
            "forward dynamics, mass_matrix_and_bias + Cholesky solve",
            partial(_loop_fused, m, Q, QD, U, outs["fused"]),
            reference_fd,
        ),
        "crba": ("M(q), CRBA (crba_core)", partial(_loop_crba, m, Q, matrix), reference_M),
        "nonlinear": (
            "N(q, qd), RNEA (rnea_core, NONLINEAR)",
            partial(_loop_nonlinear, m, Q, QD, outs["nonlinear"]),
            reference_N,
        ),
        "computed": (
            "computed torque M u + N: CRBA + RNEA + M u",
            partial(_loop_computed_torque, m, Q, QD, U, outs["computed"]),
            reference_tau,
        ),
        "fused_torque": (
            "computed torque M u + N: mass_matrix_and_bias + M u",
            partial(_loop_fused_torque, m, Q, QD, U, outs["fused_torque"]),
            reference_tau,
        ),
        "inverse": (
            "computed torque M u + N: one RNEA with qdd = u",
            partial(_loop_inverse, m, Q, QD, U, outs["inverse"]),
            reference_tau,
        ),
        "energy": (
            "kinetic + potential energy (energy_core)",
            partial(_loop_energy, m, Q, QD, energy),
            reference_energy,
        ),
        "coulomb": (
            f"smoothed Coulomb friction, {n} tanh",
            partial(_loop_coulomb, arm.coulomb_friction.copy(), 1e-3, QD, outs["coulomb"]),
            None,
        ),
    }
    if not FUSED:
        del loops["fused"], loops["fused_torque"]
    times = measure(*(Candidate(call, KERNEL_REPEATS) for _, call, _ in loops.values()))
    per_call = {name: seconds / KERNEL_STATES * 1e6 for name, seconds in zip(loops, times, strict=True)}
    results = outs | {"crba": matrix, "energy": energy}
    rows = []
    for name, (label, _, reference) in loops.items():
        agreement = "-"
        if reference is not None:
            error = relative_error(results[name], reference)
            agreement = sci(error) + ("" if error <= TOLERANCE else f" (DIFFERS: more than {TOLERANCE:g})")
        rows.append([label, us(per_call[name]), agreement])
    return rows, per_call


class Parts:
    """Wraps named functions of armdyn.simulation in timers while in use (a name the module lacks is left
    out); ``spent`` holds the nanoseconds of each since the last ``clear``."""

    def __init__(self, names: Sequence[str]) -> None:
        import armdyn.simulation as module

        self.module, self.spent = module, {}
        self.originals = {name: getattr(module, name) for name in names if callable(getattr(module, name, None))}

    def _timer(self, name: str, original: Callable) -> Callable:
        def timed(*args: object, **kwargs: object) -> object:
            start = time.perf_counter_ns()
            try:
                return original(*args, **kwargs)
            finally:
                self.spent[name] = self.spent.get(name, 0) + time.perf_counter_ns() - start

        return timed

    def __enter__(self) -> Parts:
        for name, original in self.originals.items():
            setattr(self.module, name, self._timer(name, original))
        return self

    def __exit__(self, *exc: object) -> None:
        for name, original in self.originals.items():
            setattr(self.module, name, original)


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

    split: list[dict[str, int]] = []
    with Parts(("run_rk4", "_energies")) as parts:

        def in_parts() -> None:
            parts.spent.clear()
            start = time.perf_counter_ns()
            tracking_run()
            split.append(parts.spent | {"total": time.perf_counter_ns() - start})

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
        times = dict(zip(runs, measure(*(Candidate(fn) for fn in runs.values())), strict=True))
    split = split[1:]  # the first call was the warm-up
    whole, fixed, fixed_single = (list(times)[i] for i in (0, 1, 5))

    def per_step(seconds: float) -> str:
        return us(seconds / steps * 1e6)

    rows = [[whole, ms(times[whole]), per_step(times[whole] - times[fixed])]]
    median = {name: statistics.median(s.get(name, 0) for s in split) / 1e9 for name in parts.originals}
    if "run_rk4" in median:
        rows.append(
            ["  of which the compiled loop (simulation.run_rk4)", ms(median["run_rk4"]), per_step(median["run_rk4"])]
        )
    if "_energies" in median:
        label = "  of which the energies after the run (simulation._energies, a Numba-parallel batch)"
        rows.append([label, ms(median["_energies"]), per_step(median["_energies"])])
    if len(median) == 2:
        rest = statistics.median(s["total"] - sum(s.get(name, 0) for name in median) for s in split) / 1e9
        rows.append(["  of which the rest (set-up in Python, the Result)", ms(rest), "-"])
    for label in list(runs)[1:]:
        base = times[fixed_single] if "set_num_threads" in label else times[fixed]
        rows.append([label, ms(times[label]), "-" if label in (fixed, fixed_single) else per_step(times[label] - base)])
    loop = median.get("run_rk4")
    return rows, (loop / steps * 1e6 if loop is not None else math.nan)


# ----- the run ----------------------------------------------------------------------------------


def header(source: tuple[str, str], args: argparse.Namespace) -> list[str]:
    toolbox = "skipped (--skip-toolbox)" if args.skip_toolbox else version("roboticstoolbox-python")
    return [
        f"Date: {datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}",
        f"CPU: {cpu_model()}, {os.cpu_count()} logical cores; Numba threads {numba.get_num_threads()} "
        "(the simulation loop runs on one)",
        f"Versions: armdyn {ad.__version__}, numba {numba.__version__}, numpy {np.__version__}, "
        f"scipy {version('scipy')}, roboticstoolbox {toolbox}, Python {platform.python_version()}",
        f"armdyn source: {source[1]}, source hash {source[0]}",
        "The machine is shared and noisy: absolute times move from run to run; the ratios are what matter.",
        f"armdyn's times are medians: {FALL_REPEATS} runs each at dt = 1 ms and 0.2 ms, {RK45_REPEATS} with rk45, "
        f"{TRACK_REPEATS} per tracking run, {KERNEL_REPEATS} loops of {KERNEL_STATES:,} states per kernel; the "
        "candidates' runs are interleaved. Each simulate() time is the whole call (setup, loop, Result).",
    ]


def warm_up(puma: ad.Robot, rr: ad.Robot, trajectories: Sequence[Sinusoid]) -> float:
    """Seconds for the first simulate() calls (Numba compiles or loads its cache), untimed."""
    start = time.perf_counter()
    simulate(puma, None, None, t_final=0.01, dt=DT, q0=puma.qr)
    simulate(puma, None, None, t_final=0.01, dt=DT, q0=puma.qr, method="rk45")
    for arm, trajectory in zip((puma, rr), trajectories, strict=True):
        simulate(arm, ComputedTorque(*GAINS), trajectory, t_final=0.01, dt=DT)
    simulate(puma, PID(*GAINS), trajectories[0], t_final=0.01, dt=DT)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--skip-toolbox", action="store_true", help="leave out the Robotics Toolbox's fdyn")
    parser.add_argument(
        "--fdyn-timeout", type=float, default=FDYN_TIMEOUT, help="seconds for the Toolbox's fdyn (default 300)"
    )
    parser.add_argument("--fdyn-worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--state", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.fdyn_worker:
        fdyn_worker(args.fdyn_timeout, json.loads(args.state))
        return

    started = time.perf_counter()
    rng = np.random.default_rng(SEED)
    source = source_state()
    lines = header(source, args)
    print("\n".join(lines), flush=True)
    tables = []

    def show(table: Table) -> None:
        tables.append(table)
        print(table.text(), flush=True)

    puma, rr = ad.models.puma560(), ad.models.two_link_planar()
    phases = np.where(np.arange(puma.n) % 2 == 0, 0.0, np.pi / 2)
    puma_trajectory = Sinusoid(0.1, 0.5, phase=phases, offset=puma.qz)
    rr_trajectory = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])
    seconds = warm_up(puma, rr, (puma_trajectory, rr_trajectory))
    lines.append(
        f"armdyn's first simulate() calls in this process (compile or load machine code, untimed): {seconds:.1f} s"
    )
    print(lines[-1], end="\n\n", flush=True)

    for table in fall(puma, args):
        show(table)

    arms = {
        f"PUMA 560, {T_PUMA:g} s": (puma, puma_trajectory, T_PUMA),
        f"RR arm (Example 4.4-1), {T_RR:g} s": (rr, rr_trajectory, T_RR),
    }
    rows, _ = tracking(arms)
    show(
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

    show(
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
    ]
    if FUSED:
        fused = 3 * per_call["fused"] + per_call["fused_torque"]
        sums.append(("the same with M and N by mass_matrix_and_bias: 3 FD + controller", fused))
    show(
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
    show(
        Table(
            f"4b. PUMA 560 kernels in a compiled loop over {KERNEL_STATES:,} distinct states (microseconds per call)",
            ["kernel", "us/call", "max rel. diff vs reference"],
            kernel_rows + [[f"sum, {label}", us(value), "-"] for label, value in sums],
            [
                "Each kernel is inlined into a Numba loop of this file (cache=True), as simulation.py inlines it "
                "into its loop; no Python call per state. References: arm.forward_dynamics, inertia_matrix, "
                "nonlinear_terms, inertia_matrix @ u + nonlinear_terms, kinetic_energy + potential_energy "
                "(forward dynamics with the arm's friction: Coulomb sgn(qd) in both).",
                f"The sums are per-step costs of step designs, to compare with the compiled loop's "
                f"{us(loop_per_step)} us per step (4a) and the budget of {us(budget)} us per step for "
                f"{REAL_TIME_TARGET:g}x real time.",
            ],
            left=1,
        )
    )

    elapsed = time.perf_counter() - started
    if source_state()[0] != source[0]:
        lines.append(
            f"WARNING: armdyn's source changed during the run (hash {source[0]} at the start, "
            f"{source_state()[0]} at the end): the parts may have timed different versions."
        )
        print(lines[-1])
    print(f"Total run time {elapsed:.0f} s; written to {RESULTS}")
    markdown = [
        "# armdyn simulation benchmarks",
        "",
        *(f"- {line}" for line in lines),
        f"- Run time {elapsed:.0f} s.",
        "",
    ]
    RESULTS.write_text("\n".join(markdown + [table.markdown() for table in tables]))


if __name__ == "__main__":
    main()
