"""Simulation of the arm under control (Chapter 4, Appendix B: the book's TRESP program).

``simulate`` integrates M qdd + N(q, qd) + tau_d = tau with fixed-step fourth-order
Runge-Kutta, the controller run once per step (or once per sample period, with the torque
held in between), or with an adaptive solver of scipy.integrate.solve_ivp. When the
controller and the trajectory are armdyn's own and the disturbance is constant, the whole
RK4 run is one compiled Numba call.

Coulomb friction is smoothed: Fd_i = tanh(qd_i / eps_i) Tc+ (qd_i >= 0) or -tanh(qd_i / eps_i) Tc-
(qd_i < 0), continuous through zero velocity, so the integrator does not chatter. With
``coulomb_smoothing="auto"`` (the default) eps_i = max(1e-3 rad/s, Tc_i dt / M_ii(q0)), which
keeps the stiffness of the smoothed law within fixed-step RK4's stability region; a number
sets every eps_i, and eps -> 0 recovers Fd = Tc sgn(qd). The integral
of the error for PID control is accumulated once per controller evaluation.
"""

from __future__ import annotations

import csv
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from numba import njit

from armdyn import control as C
from armdyn import trajectories as T
from armdyn.dynamics import kernels as K
from armdyn.dynamics.compiled import COULOMB_NEG, COULOMB_POS, HEADER, STRIDE
from armdyn.dynamics.vectorized import sin_cos
from armdyn.errors import ModelError
from armdyn.model.robot import Robot

_OPTS = {"cache": True, "fastmath": {"contract"}, "error_model": "numpy", "boundscheck": False}
ADAPTIVE = ("rk45", "rk23", "dop853", "radau", "bdf", "lsoda")


@dataclass
class Result:
    """A simulated run. Arrays have time as their first axis."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    q_d: np.ndarray | None
    arm: Robot
    info: dict = field(default_factory=dict)
    energy_of: Callable[[], np.ndarray] | None = field(default=None, repr=False)

    @cached_property
    def energy(self) -> np.ndarray:
        """K + P at every sample (computed when first read: one batch call per arm)."""
        return self.energy_of() if self.energy_of is not None else np.full(len(self.t), np.nan)

    @property
    def error(self) -> np.ndarray | None:
        """e = q_d - q (None without a trajectory)."""
        return None if self.q_d is None else self.q_d - self.q

    def plot(self, path: str | Path | None = None, title: str | None = None) -> object:
        """Joint values with their desired values, tracking errors and torques (matplotlib figure)."""
        from armdyn.plotting import plot_result

        return plot_result(self, path, title)

    def to_csv(self, path: str | Path) -> None:
        """One row per time: t, q_i, qd_i, qdd_i, tau_i (and q_d_i, e_i with a trajectory), energy."""
        n = self.q.shape[1]
        columns = {"t": self.t[:, None]}
        for name, values in (("q", self.q), ("qd", self.qd), ("qdd", self.qdd), ("tau", self.tau)):
            columns[name] = values
        if self.q_d is not None:
            columns["q_d"], columns["e"] = self.q_d, self.error
        header = ["t"] + [f"{name}{i + 1}" for name in list(columns)[1:] for i in range(n)] + ["energy"]
        table = np.hstack([*columns.values(), self.energy[:, None]])
        with open(path, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(header)
            writer.writerows(table.tolist())

    def to_npz(self, path: str | Path) -> None:
        arrays = {"t": self.t, "q": self.q, "qd": self.qd, "qdd": self.qdd, "tau": self.tau, "energy": self.energy}
        if self.q_d is not None:
            arrays |= {"q_d": self.q_d, "error": self.error}
        np.savez(path, **arrays)


# ----- the compiled loop ------------------------------------------------------------------------------
@njit(inline="always", **_OPTS)
def _desired(kind: int, traj: np.ndarray, t: float, q0: np.ndarray, out: np.ndarray) -> None:
    """out rows: q_d, qd_d, qdd_d (kinds: 0 hold q0, 1 sinusoid, 2 quintic)."""
    n = q0.shape[0]
    for i in range(n):
        if kind == 1:
            amplitude, omega, phase, offset = traj[0, i], traj[1, i], traj[2, i], traj[3, i]
            sine, cosine = sin_cos(omega * t + phase)
            out[0, i] = offset + amplitude * sine
            out[1, i] = amplitude * omega * cosine
            out[2, i] = -amplitude * omega * omega * sine
        elif kind == 2:
            a, b, t0, t1 = traj[0, i], traj[1, i], traj[2, i], traj[3, i]
            span = t1 - t0
            s = min(max((t - t0) / span, 0.0), 1.0)
            out[0, i] = a + (b - a) * (10 * s**3 - 15 * s**4 + 6 * s**5)
            out[1, i] = (b - a) * (30 * s**2 - 60 * s**3 + 30 * s**4) / span
            out[2, i] = (b - a) * (60 * s - 180 * s**2 + 120 * s**3) / span**2
        else:
            out[0, i] = q0[i]
            out[1, i] = 0.0
            out[2, i] = 0.0


@njit(inline="always", **_OPTS)
def smooth_coulomb(coulomb: np.ndarray, eps: np.ndarray, i: int, rate: float) -> float:
    """Fd_i: tanh(qd / eps_i) Tc+ for qd >= 0, -tanh(qd / eps_i) Tc- for qd < 0 (exact sgn for eps_i = 0)."""
    if eps[i] > 0.0:
        x = rate / eps[i]
        smooth = math.tanh(x) if abs(x) < 20.0 else (1.0 if x > 0.0 else -1.0)  # tanh(20) = 1 - 8e-18
        return smooth * coulomb[i, 0] if rate >= 0.0 else -smooth * coulomb[i, 1]
    return coulomb[i, 0] if rate > 0.0 else coulomb[i, 1] if rate < 0.0 else 0.0


@njit(**_OPTS)
def _accelerations(
    plant: np.ndarray, coulomb: np.ndarray, eps: np.ndarray, w: np.ndarray, q: np.ndarray, qd: np.ndarray,
    tau: np.ndarray, M: np.ndarray, N: np.ndarray, qdd: np.ndarray,
) -> None:  # fmt: skip
    """qdd = M^-1 (tau - N - Fd_smooth) by CRBA, RNEA and a Cholesky solve.

    For the arms of this library (n up to about ten) this is faster than the O(n)
    articulated-body algorithm and equal to it to rounding; ``tau`` carries the disturbance.
    """
    K.mass_matrix_and_bias(plant, w, 0, q, qd, M, N)
    _solve(M, N, tau, coulomb, eps, qd, qdd)


@njit(inline="always", **_OPTS)
def _solve(
    M: np.ndarray, N: np.ndarray, tau: np.ndarray, coulomb: np.ndarray, eps: np.ndarray, qd: np.ndarray, qdd: np.ndarray
) -> None:
    """qdd = M^-1 (tau - N - Fd_smooth) by Cholesky factorization (M is overwritten)."""
    n = qd.shape[0]
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
        total = tau[i] - N[i] - smooth_coulomb(coulomb, eps, i, qd[i])
        for k in range(i):
            total -= M[i, k] * qdd[k]
        qdd[i] = total / M[i, i]
    for i in range(n - 1, -1, -1):
        total = qdd[i]
        for k in range(i + 1, n):
            total -= M[k, i] * qdd[k]
        qdd[i] = total / M[i, i]


@njit(**_OPTS)
def _control(
    kind: int, model: np.ndarray, model_coulomb: np.ndarray, eps: np.ndarray, wc: np.ndarray, q: np.ndarray,
    qd: np.ndarray, desired: np.ndarray, e_int: np.ndarray, kp: np.ndarray, kv: np.ndarray, ki: np.ndarray,
    limit: np.ndarray, u: np.ndarray, M_: np.ndarray, Nv: np.ndarray, tau: np.ndarray,
) -> None:  # fmt: skip
    """The built-in controllers (armdyn.control) on the controller's own model, then saturation.

    The model's Coulomb friction is compensated with the same smooth law as the plant's.
    """
    n = q.shape[0]
    if kind == C.COMPUTED_TORQUE:
        for i in range(n):
            u[i] = desired[2, i] + kv[i] * (desired[1, i] - qd[i]) + kp[i] * (desired[0, i] - q[i]) + ki[i] * e_int[i]
        K.mass_matrix_and_bias(model, wc, 0, q, qd, M_, Nv)
        for i in range(n):
            total = Nv[i] + smooth_coulomb(model_coulomb, eps, i, qd[i])
            for j in range(n):
                total += M_[i, j] * u[j]
            tau[i] = total
    elif kind == C.PD_GRAVITY:
        K.gravity_core(model, wc, 0, q, Nv)
        for i in range(n):
            tau[i] = kp[i] * (desired[0, i] - q[i]) + kv[i] * (desired[1, i] - qd[i]) + Nv[i]
    else:
        for i in range(n):
            tau[i] = kp[i] * (desired[0, i] - q[i]) + kv[i] * (desired[1, i] - qd[i]) + ki[i] * e_int[i]
    for i in range(n):
        tau[i] = min(max(tau[i], -limit[i]), limit[i])


@njit(**_OPTS)
def run_rk4(
    plants: np.ndarray, coulombs: np.ndarray, switches: np.ndarray, model: np.ndarray, model_coulomb: np.ndarray,
    shared: bool, kind: int,
    kp: np.ndarray, kv: np.ndarray, ki: np.ndarray, limit: np.ndarray, hold: int, traj_kind: int,
    traj: np.ndarray, q0: np.ndarray, disturbance: np.ndarray, eps: np.ndarray, t0: float, dt: float,
    first: int, last: int, state: np.ndarray, tau_held: np.ndarray, e_int: np.ndarray,
    T_: np.ndarray, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray, TAU: np.ndarray, QDES: np.ndarray,
) -> None:  # fmt: skip
    """Steps first..last-1 of fixed-step RK4 (the book's TRESP), recording each step's start.

    state = [q; qd] is advanced in place; tau_held and e_int carry the controller's state.
    """
    n = q0.shape[0]
    w = np.empty(200 * n + 128)
    wc = np.empty(200 * n + 128)
    desired = np.empty((3, n))
    q, qd = state[:n].copy(), state[n:].copy()
    stages = np.empty((8, n))  # the RK4 slopes of q and qd
    k1q, k1v, k2q, k2v, k3q, k3v, k4q, k4v = stages[0], stages[1], stages[2], stages[3], stages[4], stages[5], \
        stages[6], stages[7]  # fmt: skip
    scratch = np.empty((6, n))
    qs, vs, net, applied, u, Nv = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4], scratch[5]
    M_, Mp = np.empty((n, n)), np.empty((n, n))
    for k in range(first, last):
        t = t0 + k * dt
        p = 0
        while p < switches.shape[0] and t >= switches[p]:
            p += 1
        plant, coulomb = plants[p], coulombs[p]
        _desired(traj_kind, traj, t, q0, desired)
        fresh = kind == C.COMPUTED_TORQUE and shared and p == 0 and k % hold == 0
        if kind > 0 and k % hold == 0:
            for i in range(n):
                e_int[i] += (desired[0, i] - q[i]) * dt * hold
            _control(kind, model, model_coulomb, eps, wc, q, qd, desired, e_int, kp, kv, ki, limit, u, M_, Nv,
                     tau_held)  # fmt: skip
        for i in range(n):
            applied[i] = tau_held[i] - disturbance[i]
        if fresh:  # the controller has just computed this state's M and N on the plant itself
            Mp[:, :] = M_
            _solve(Mp, Nv, applied, coulomb, eps, qd, k1v)
        else:
            _accelerations(plant, coulomb, eps, w, q, qd, applied, Mp, net, k1v)
        T_[k] = t
        for i in range(n):
            Q[k, i], QD[k, i], QDD[k, i], TAU[k, i], QDES[k, i] = q[i], qd[i], k1v[i], tau_held[i], desired[0, i]
        for i in range(n):
            k1q[i] = qd[i]
            qs[i], vs[i] = q[i] + 0.5 * dt * k1q[i], qd[i] + 0.5 * dt * k1v[i]
        _accelerations(plant, coulomb, eps, w, qs, vs, applied, Mp, net, k2v)
        for i in range(n):
            k2q[i] = vs[i]
            qs[i], vs[i] = q[i] + 0.5 * dt * k2q[i], qd[i] + 0.5 * dt * k2v[i]
        _accelerations(plant, coulomb, eps, w, qs, vs, applied, Mp, net, k3v)
        for i in range(n):
            k3q[i] = vs[i]
            qs[i], vs[i] = q[i] + dt * k3q[i], qd[i] + dt * k3v[i]
        _accelerations(plant, coulomb, eps, w, qs, vs, applied, Mp, net, k4v)
        for i in range(n):
            k4q[i] = vs[i]
            q[i] += dt / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i])
            qd[i] += dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i])
    state[:n] = q
    state[n:] = qd


# ----- the Python side ---------------------------------------------------------------------------------
def _plant_buffers(arms: list[Robot]) -> tuple[np.ndarray, np.ndarray]:
    """Compiled plants with their Coulomb friction taken out (the loop adds the smoothed one)."""
    plants, coulombs = [], []
    for arm in arms:
        buffer = arm._engine().model.copy()  # compiled once per Robot
        for i in range(arm.n):
            base = HEADER + STRIDE * i
            buffer[base + COULOMB_POS] = buffer[base + COULOMB_NEG] = 0.0
        plants.append(buffer)
        coulombs.append(arm.coulomb_friction.copy())
    if len({b.shape for b in plants}) != 1:
        raise ModelError("every arm of a run (events included) must have the same joints")
    return np.stack(plants), np.stack(coulombs)


def _unwrap(controller: object) -> tuple[C.Spec | None, float, object]:
    """(spec for the compiled loop or None, sample period (0 continuous), the controller)."""
    if controller is None:
        return C.Spec(0, 0.0, 0.0, 0.0), 0.0, None
    spec_of = getattr(controller, "spec", None)
    spec = spec_of() if spec_of is not None else None
    period = 0.0
    inner = controller
    while isinstance(inner, (C.Digital, C.Saturated)):
        if isinstance(inner, C.Digital):
            period = inner.period
        inner = inner.controller
    return spec, period, controller


def simulate(
    arm: Robot,
    controller: object = None,
    trajectory: object = None,
    t_final: float = 5.0,
    dt: float = 1e-3,
    method: str = "rk4",
    q0: Sequence[float] | None = None,
    qd0: Sequence[float] | None = None,
    disturbance: object = None,
    events: Sequence[tuple[float, Robot]] = (),
    coulomb_smoothing: float | str = "auto",
    progress: Callable[[float], None] | None = None,
) -> Result:
    """Simulate ``arm`` from (q0, qd0) (zeros by default) for t_final seconds.

    controller: None (zero torque), one of armdyn.control's, or any callable
    controller(t, q, qd, q_d, qd_d, qdd_d, e_int) -> tau. trajectory: None (hold q0),
    Sinusoid, Quintic, CartesianCircle or any callable t -> (q_d, qd_d, qdd_d).
    disturbance: tau_d, a constant vector or a callable (t, q, qd) -> tau_d.
    events: (time, arm) pairs: from that time the plant is that arm (a payload change).
    method: "rk4" (fixed step dt) or an adaptive solve_ivp method ("rk45", "rk23",
    "dop853", "radau", "bdf", "lsoda"), sampled every dt.
    """
    n = arm.n
    if not (t_final > 0 and dt > 0 and np.isfinite(t_final) and np.isfinite(dt)):
        raise ModelError(f"t_final and dt must be positive, got {t_final}, {dt}")
    q0 = np.zeros(n) if q0 is None else np.array(q0, dtype=float)
    qd0 = np.zeros(n) if qd0 is None else np.array(qd0, dtype=float)
    if q0.shape != (n,) or qd0.shape != (n,):
        raise ModelError(f"q0 and qd0 must have {n} values")
    events = sorted(events, key=lambda e: e[0])
    arms = [arm] + [e[1] for e in events]
    steps = round(t_final / dt)
    spec, period, controller = _unwrap(controller)
    if method == "rk4":
        compiled = (
            spec is not None
            and (trajectory is None or isinstance(trajectory, (T.Sinusoid, T.Quintic)))
            and (disturbance is None or not callable(disturbance))
            and (spec.model is None or not spec.model.is_symbolic)
        )
        if compiled:
            return _compiled_rk4(arm, arms, events, spec, period, trajectory, q0, qd0, disturbance, steps, dt,
                                 coulomb_smoothing, progress)  # fmt: skip
        return _python_rk4(arms, events, controller, period, trajectory, q0, qd0, disturbance, steps, dt,
                           coulomb_smoothing)  # fmt: skip
    if method.lower() in ADAPTIVE:
        if period:
            raise ModelError("a Digital controller needs method='rk4' (the book's fixed-step TRESP)")
        return _adaptive(arms, events, controller, trajectory, q0, qd0, disturbance, steps, dt, method,
                         coulomb_smoothing)  # fmt: skip
    raise ModelError(f"method must be 'rk4' or one of {ADAPTIVE}, got '{method}'")


def _compiled_rk4(arm, arms, events, spec, period, trajectory, q0, qd0, disturbance, steps, dt, eps, progress):
    n = arm.n
    plants, coulombs = _plant_buffers(arms)
    switches = np.array([e[0] for e in events], dtype=float)
    if spec.model is not None and spec.model.n != n:
        raise ModelError("the controller's model must have the plant's joints")
    models, model_coulombs = _plant_buffers([spec.model if spec.model is not None else arm])
    model, model_coulomb = models[0], model_coulombs[0]
    kp, kv, ki = (C._gains(g, name, n) for g, name in ((spec.kp, "kp"), (spec.kv, "kv"), (spec.ki, "ki")))
    limit = np.broadcast_to(np.asarray(spec.limit, dtype=float), (n,)).copy()
    hold = max(1, round(period / dt)) if period else 1
    if period and abs(hold * dt - period) > 1e-9 * period:
        raise ModelError(f"the sample period {period} must be a whole number of steps dt = {dt}")
    traj_kind, traj = 0, np.zeros((4, n))
    if isinstance(trajectory, T.Sinusoid):
        traj_kind, traj = T.SINUSOID, trajectory.arrays(n)
    elif isinstance(trajectory, T.Quintic):
        traj_kind, traj = T.QUINTIC, trajectory.arrays(n)
    tau_d = np.zeros(n) if disturbance is None else np.broadcast_to(np.asarray(disturbance, float), (n,)).copy()
    arrays = {name: np.empty((steps + 1, n)) for name in ("q", "qd", "qdd", "tau", "q_d")}
    times = np.empty(steps + 1)
    state, tau_held, e_int = np.concatenate([q0, qd0]), np.zeros(n), np.zeros(n)
    smoothing = _smoothing(arm, eps, dt, q0)
    chunks = 20 if progress is not None else 1
    bounds = np.linspace(0, steps + 1, chunks + 1).astype(int)
    for a, b in itertools.pairwise(bounds):
        run_rk4(
            plants, coulombs, switches, model, model_coulomb, spec.model is None, spec.kind, kp, kv, ki, limit,
            hold, traj_kind, traj, q0, tau_d, smoothing, 0.0, dt, int(a), int(b), state, tau_held, e_int, times,
            arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"], arrays["q_d"],
        )  # fmt: skip
        if progress is not None:
            progress(b / (steps + 1))
    q_d = arrays["q_d"] if trajectory is not None else None
    return Result(times, arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"], q_d, arm,
                  {"method": "rk4 (compiled)", "dt": dt, "integral": e_int},
                  lambda: _energies(arms, events, times, arrays["q"], arrays["qd"]))  # fmt: skip


def _energies(arms: list[Robot], events: list, times: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """K + P at every sample, each by the arm in force at that time (one batch call per arm)."""
    phase = np.searchsorted(np.array([e[0] for e in events], dtype=float), times, side="right")
    energy = np.empty(len(times))
    for index, arm in enumerate(arms):
        mask = phase == index
        if np.any(mask):
            kinetic_and_potential = arm._engine()._energies(q[mask], qd[mask])
            energy[mask] = kinetic_and_potential[:, 0] + kinetic_and_potential[:, 1]
    return energy


def _smoothing(arm: Robot, eps: object, dt: float, q0: np.ndarray) -> np.ndarray:
    """eps_i per joint. "auto": the friction's stiffness Tc_i / (eps_i M_ii) times dt stays at 1,
    inside RK4's stability limit (2.79), and eps_i is never below 1e-3 rad/s."""
    if isinstance(eps, str):
        if eps != "auto":
            raise ModelError(f"coulomb_smoothing must be 'auto' or a number, got '{eps}'")
        largest = np.abs(arm.coulomb_friction).max(axis=1)
        return np.maximum(1e-3, largest * dt / np.diag(arm.inertia_matrix(q0)))
    value = float(eps)
    if not (np.isfinite(value) and value >= 0):
        raise ModelError(f"coulomb_smoothing must be a non-negative number, got {eps}")
    return np.full(arm.n, value)


def _smooth_coulomb(arm: Robot, qd: np.ndarray, eps: np.ndarray) -> np.ndarray:
    coulomb = arm.coulomb_friction
    exact = np.where(qd > 0, coulomb[:, 0], np.where(qd < 0, coulomb[:, 1], 0.0))
    smooth = np.tanh(qd / np.where(eps > 0, eps, 1.0))
    return np.where(eps > 0, np.where(qd >= 0, smooth * coulomb[:, 0], -smooth * coulomb[:, 1]), exact)


def _plant_at(arms: list[Robot], events: list, t: float) -> Robot:
    index = sum(1 for e in events if t >= e[0])
    return arms[index]


def _dynamics(arms, events, eps):
    bare = [a.replace([_no_coulomb(link) for link in a.links]) for a in arms]

    def qdd(t: float, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        index = sum(1 for e in events if t >= e[0])
        return bare[index].forward_dynamics(q, qd, tau - _smooth_coulomb(arms[index], qd, eps))

    return qdd


def _no_coulomb(link):
    import dataclasses

    return dataclasses.replace(link, coulomb=(0.0, 0.0))


def _desired_of(trajectory: object, t: float, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if trajectory is None:
        return q0, np.zeros_like(q0), np.zeros_like(q0)
    q_d, qd_d, qdd_d = trajectory(t)
    return np.asarray(q_d, float), np.asarray(qd_d, float), np.asarray(qdd_d, float)


def _torque(controller, plant, t, q, qd, desired, e_int):
    if controller is None:
        return np.zeros_like(q)
    try:
        return np.asarray(controller(t, q, qd, *desired, e_int, plant=plant), dtype=float)
    except TypeError:
        return np.asarray(controller(t, q, qd, *desired, e_int), dtype=float)


def _tau_d(disturbance: object, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    if disturbance is None:
        return np.zeros_like(q)
    if callable(disturbance):
        return np.asarray(disturbance(t, q, qd), dtype=float)
    return np.broadcast_to(np.asarray(disturbance, dtype=float), q.shape)


def _python_rk4(arms, events, controller, period, trajectory, q0, qd0, disturbance, steps, dt, eps):
    """The same TRESP scheme in Python, for controllers and trajectories of the user's own."""
    n = arms[0].n
    qdd_of = _dynamics(arms, events, _smoothing(arms[0], eps, dt, q0))
    hold = max(1, round(period / dt)) if period else 1
    out = {name: np.empty((steps + 1, n)) for name in ("q", "qd", "qdd", "tau", "q_d")}
    times = np.empty(steps + 1)
    q, qd, tau, e_int = q0.copy(), qd0.copy(), np.zeros(n), np.zeros(n)
    for k in range(steps + 1):
        t = k * dt
        plant = _plant_at(arms, events, t)
        desired = _desired_of(trajectory, t, q0)
        if k % hold == 0:
            e_int = e_int + (desired[0] - q) * dt * hold
            tau = _torque(controller, plant, t, q, qd, desired, e_int)
        applied = tau - _tau_d(disturbance, t, q, qd)
        k1v = qdd_of(t, q, qd, applied)
        times[k] = t
        out["q"][k], out["qd"][k], out["qdd"][k], out["tau"][k], out["q_d"][k] = q, qd, k1v, tau, desired[0]
        k2v = qdd_of(t + dt / 2, q + dt / 2 * qd, qd + dt / 2 * k1v, applied)
        k3v = qdd_of(t + dt / 2, q + dt / 2 * (qd + dt / 2 * k1v), qd + dt / 2 * k2v, applied)
        k4v = qdd_of(t + dt, q + dt * (qd + dt / 2 * k2v), qd + dt * k3v, applied)
        k2q, k3q, k4q = qd + dt / 2 * k1v, qd + dt / 2 * k2v, qd + dt * k3v
        q = q + dt / 6 * (qd + 2 * k2q + 2 * k3q + k4q)
        qd = qd + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    q_d = out["q_d"] if trajectory is not None else None
    return Result(times, out["q"], out["qd"], out["qdd"], out["tau"], q_d, arms[0],
                  {"method": "rk4 (Python)", "dt": dt, "integral": e_int},
                  lambda: _energies(arms, events, times, out["q"], out["qd"]))  # fmt: skip


def _adaptive(arms, events, controller, trajectory, q0, qd0, disturbance, steps, dt, method, eps):
    """solve_ivp on x = [q; qd; e_int]; the controller runs at every function evaluation."""
    from scipy.integrate import solve_ivp

    n = arms[0].n
    qdd_of = _dynamics(arms, events, _smoothing(arms[0], eps, dt, q0))

    def rate(t: float, x: np.ndarray) -> np.ndarray:
        q, qd, e_int = x[:n], x[n : 2 * n], x[2 * n :]
        desired = _desired_of(trajectory, t, q0)
        tau = _torque(controller, _plant_at(arms, events, t), t, q, qd, desired, e_int)
        return np.concatenate([qd, qdd_of(t, q, qd, tau - _tau_d(disturbance, t, q, qd)), desired[0] - q])

    times = np.arange(steps + 1) * dt
    solution = solve_ivp(rate, (0.0, times[-1]), np.concatenate([q0, qd0, np.zeros(n)]), method=method.upper()
                         if method.lower() != "lsoda" else "LSODA", t_eval=times, rtol=1e-8, atol=1e-10)  # fmt: skip
    if not solution.success:
        raise ModelError(f"the {method} solver failed: {solution.message}")
    x = solution.y.T
    q, qd, e_int = x[:, :n], x[:, n : 2 * n], x[:, 2 * n :]
    qdd, tau, q_d = np.empty_like(q), np.empty_like(q), np.empty_like(q)
    for k, t in enumerate(times):
        desired = _desired_of(trajectory, t, q0)
        plant = _plant_at(arms, events, t)
        tau[k] = _torque(controller, plant, t, q[k], qd[k], desired, e_int[k])
        qdd[k] = qdd_of(t, q[k], qd[k], tau[k] - _tau_d(disturbance, t, q[k], qd[k]))
        q_d[k] = desired[0]
    return Result(times, q, qd, qdd, tau, q_d if trajectory is not None else None, arms[0],
                  {"method": method, "dt": dt, "evaluations": solution.nfev},
                  lambda: _energies(arms, events, times, q, qd))  # fmt: skip
