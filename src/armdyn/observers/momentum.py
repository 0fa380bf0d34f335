"""The generalized-momentum observer: the external joint torque without acceleration, without M's inverse.

With p = M(q) qd, the robot equation M qdd + Vm qd + F + G = tau + tau_ext (3.3.1, tau_ext = -tau_d) and
the skew property of Table 3.3.1, Mdot = Vm + Vm^T for the Christoffel Vm, give

    pdot = tau + Vm^T(q, qd) qd - G(q) - F(qd) + tau_ext = tau - beta(q, qd) + tau_ext,

so the residual r(t) = K [p(t) - p(0) - integral of (tau - beta + r) ds] obeys rdot = K (tau_ext - r): a
first-order filter of tau_ext with a gain K per joint (De Luca and Mattone, "Actuator failure detection
and isolation using generalized momenta", ICRA 2003; Haddadin, De Luca and Albu-Schaeffer, "Robot
collisions: a survey on detection, isolation, and identification", IEEE T-RO 33(6), 2017).

Sampled data: over a step the known terms are integrated by the trapezoid rule (or, for a torque held
over each step as simulate's RK4 applies it, by its held value) and the residual's first-order dynamics
taken exactly for a tau_ext constant over the step,

    w_k - w_{k-1} = p_k - p_{k-1} - integral over the step of (tau - beta),
    r_k = a r_{k-1} + (1 - a) (w_k - w_{k-1}) / dt_k,      a = exp(-K dt_k),

which tends to the continuous observer as the step shrinks (first order in dt). The friction and the
motor inertia are the arm's (M includes the reflected motor inertias): an identified arm plugs in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from armdyn.dynamics.coriolis import coriolis_core
from armdyn.dynamics.crba import crba_core
from armdyn.dynamics.friction import friction_vector, sigmoid, sign_law_table, smooth_coulomb
from armdyn.dynamics.packed import HEADER, STRIDE, VISCOUS, workspace_size
from armdyn.dynamics.rnea import gravity_core
from armdyn.errors import ModelError
from armdyn.model import ArmModel


def _gains(gains: object, n: int) -> np.ndarray:
    """K per joint: positive finite numbers, one or n, or a ModelError naming the rule."""
    try:
        K = np.broadcast_to(np.asarray(gains, dtype=float), (n,)).copy()
    except (TypeError, ValueError):
        raise ModelError(f"gains must be one positive number or {n} (1/s), got {gains!r}") from None
    if not np.all(np.isfinite(K)) or np.any(K <= 0):
        raise ModelError(f"gains must be positive finite numbers (1/s), one per joint; got {K.tolist()}")
    return K


def _packed(arm: ArmModel) -> np.ndarray:
    """The arm's packed model for the compiled kernels, or a ModelError: the observer needs a numeric Robot."""
    packed = getattr(arm, "packed", None)
    if packed is None:
        raise ModelError(f"the observer needs a numeric armdyn Robot (its compiled dynamics), got {arm!r:.60}")
    return packed


def _smoothing(arm: ArmModel, coulomb_smoothing: object) -> np.ndarray | None:
    if coulomb_smoothing is None:
        return None
    try:
        eps = np.broadcast_to(np.asarray(coulomb_smoothing, dtype=float), (arm.n,)).copy()
    except (TypeError, ValueError):
        raise ModelError(f"coulomb_smoothing must be a number >= 0 or {arm.n}, got {coulomb_smoothing!r}") from None
    if not np.all(np.isfinite(eps)) or np.any(eps < 0):
        raise ModelError(f"coulomb_smoothing must be finite numbers >= 0, got {eps.tolist()}")
    return eps if np.any(eps > 0) else None


def momentum(arm: ArmModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """p = M(q) qd, the generalized momentum, (..., n).

    Parameters
    ----------
    arm : ArmModel
        A Robot (its compiled M).
    q, qd : numpy.ndarray
        States, (..., n).

    Returns
    -------
    numpy.ndarray
        p, (..., n).
    """
    return np.einsum("...ij,...j->...i", arm.inertia_matrix(q), qd)  # type: ignore[attr-defined]


def known_rate(arm: ArmModel, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, eps: np.ndarray | None) -> np.ndarray:
    """tau - beta(q, qd) = tau + Vm^T(q, qd) qd - G(q) - F(qd): pdot without the external torque, (..., n).

    Parameters
    ----------
    arm : ArmModel
        A Robot (its compiled Vm and G).
    q, qd, tau : numpy.ndarray
        States and the applied joint torques, (..., n).
    eps : numpy.ndarray or None
        The Coulomb smoothing per joint (the law simulate's plant follows), None for the exact sign law.

    Returns
    -------
    numpy.ndarray
        (..., n).
    """
    coriolis = np.einsum("...ji,...j->...i", arm.coriolis_matrix(q, qd), qd)  # type: ignore[attr-defined]
    return tau + coriolis - arm.gravity_vector(q) - friction_vector(arm, qd, eps)  # type: ignore[attr-defined]


@njit(cache=True)
def _residual(increments: np.ndarray, dt: np.ndarray, gains: np.ndarray, start: np.ndarray) -> np.ndarray:
    """r_k = a r_{k-1} + (1 - a) dw_k / dt_k per joint, a = exp(-K dt_k); r_0 = start."""
    samples, n = increments.shape[0] + 1, gains.shape[0]
    r = np.empty((samples, n))
    r[0] = start
    for k in range(1, samples):
        for j in range(n):
            a = np.exp(-gains[j] * dt[k - 1])
            r[k, j] = a * r[k - 1, j] + (1.0 - a) * increments[k - 1, j] / dt[k - 1]
    return r


@njit(cache=True)
def _momentum_and_rate(
    model: np.ndarray,
    table: np.ndarray,
    eps: np.ndarray,
    scratch: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    q: np.ndarray,
    qd: np.ndarray,
    tau: np.ndarray,
    p: np.ndarray,
    rate: np.ndarray,
) -> None:
    """p = M qd and tau + Vm^T qd - G - F (the friction's sign smoothed by eps where eps > 0), compiled."""
    work, M, C, G = scratch
    crba_core(model, work, q, M)
    coriolis_core(model, work, q, qd, C)
    gravity_core(model, work, q, G)
    for i in range(q.shape[0]):
        momentum_i, coriolis_i = 0.0, 0.0
        for j in range(q.shape[0]):
            momentum_i += M[i, j] * qd[j]
            coriolis_i += C[j, i] * qd[j]
        friction = model[HEADER + STRIDE * i + VISCOUS] * qd[i] + smooth_coulomb(table, eps, i, qd[i])
        p[i] = momentum_i
        rate[i] = tau[i] + coriolis_i - G[i] - (friction + sigmoid(model, i, qd[i]))


@njit(inline="always", cache=True)
def momentum_and_rate(
    model: np.ndarray, table: np.ndarray, eps: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray,
    tau: np.ndarray, p: np.ndarray, rate: np.ndarray,
) -> None:  # fmt: skip
    """p = M qd and tau + Vm^T qd - G - F (De Luca and Mattone 2003), one state, compiled.

    Parameters
    ----------
    model : numpy.ndarray
        The packed arm.
    table : numpy.ndarray
        Its Coulomb and Stribeck laws, (n, 4) (friction.sign_law_table).
    eps : numpy.ndarray
        The smoothing of their sign per joint, (n,), 0 for the exact law.
    work : numpy.ndarray
        A workspace of packed.workspace_size(n) values.
    q, qd, tau : numpy.ndarray
        The state and the applied torque, (n,).
    p, rate : numpy.ndarray
        Where p and the known terms are written, (n,).
    """
    n = q.shape[0]
    _momentum_and_rate(model, table, eps, (work, np.empty((n, n)), np.empty((n, n)), np.empty(n)), q, qd, tau, p, rate)


@njit(cache=True)
def _update(
    r: np.ndarray,
    gains: np.ndarray,
    dt: float,
    held: bool,
    before: tuple[np.ndarray, np.ndarray, np.ndarray],
    now: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """r <- a r + (1 - a) (p - p0 - integral of the known terms) / dt, a = exp(-K dt), in place."""
    p0, rate0, tau0 = before
    p, rate, tau = now
    for j in range(r.shape[0]):
        if held:
            known = dt * (tau0[j] + 0.5 * ((rate[j] - tau[j]) + (rate0[j] - tau0[j])))
        else:
            known = 0.5 * dt * (rate[j] + rate0[j])
        a = np.exp(-gains[j] * dt)
        r[j] = a * r[j] + (1.0 - a) * (p[j] - p0[j] - known) / dt


@njit(cache=True)
def _observe_log(
    model: np.ndarray,
    table: np.ndarray,
    eps: np.ndarray,
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    tau: np.ndarray,
    gains: np.ndarray,
    held: bool,
) -> np.ndarray:
    """The residual over a whole log in one compiled loop, no per-sample array."""
    samples, n = q.shape
    scratch = (np.empty(workspace_size(n)), np.empty((n, n)), np.empty((n, n)), np.empty(n))
    p0, rate0, p, rate = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    r = np.zeros((samples, n))
    _momentum_and_rate(model, table, eps, scratch, q[0], qd[0], tau[0], p0, rate0)
    for k in range(1, samples):
        _momentum_and_rate(model, table, eps, scratch, q[k], qd[k], tau[k], p, rate)
        r[k] = r[k - 1]
        _update(r[k], gains, t[k] - t[k - 1], held, (p0, rate0, tau[k - 1]), (p, rate, tau[k]))
        p0[:] = p
        rate0[:] = rate
    return r


@njit(cache=True)
def _step(
    model: np.ndarray,
    table: np.ndarray,
    eps: np.ndarray,
    scratch: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    gains: np.ndarray,
    held: bool,
    memory: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    t: float,
    q: np.ndarray,
    qd: np.ndarray,
    tau: np.ndarray,
    r: np.ndarray,
) -> int:
    """One sample into the observer's memory (last time and count, p, rate, tau, and the current p, rate), r in
    place; 0, or 1 when t is not after the last sample."""
    last, p0, rate0, tau0, p, rate = memory
    _momentum_and_rate(model, table, eps, scratch, q, qd, tau, p, rate)
    if last[1] > 0.0:
        dt = t - last[0]
        if not dt > 0.0:
            return 1
        _update(r, gains, dt, held, (p0, rate0, tau0), (p, rate, tau))
    last[0], last[1] = t, 1.0
    p0[:] = p
    rate0[:] = rate
    tau0[:] = tau
    return 0


def observe(
    arm: ArmModel,
    t: object,
    q: object,
    qd: object,
    tau: object,
    gains: object = 50.0,
    held_torque: bool = False,
    coulomb_smoothing: object = None,
) -> np.ndarray:
    """The momentum observer's residual r over a whole log, in a few batched calls (see the module docstring).

    Parameters
    ----------
    arm : ArmModel
        A Robot: its M, Vm, G and friction are the model (an identified arm plugs in).
    t : array_like
        Sample times (N,), increasing.
    q, qd, tau : array_like
        Joint positions, velocities and applied torques, (N, n).
    gains : float or array_like, optional
        K per joint (1/s), > 0 (default 50: a time constant of 20 ms).
    held_torque : bool, optional
        True when tau_k was applied over the whole step [t_k, t_k+1] (simulate's RK4 holds it so); False
        (default) integrates it by the trapezoid rule, as for a measured torque.
    coulomb_smoothing : float or array_like, optional
        The smoothing eps of the Coulomb and Stribeck signs (as simulate's plant has it); default the exact law.

    Returns
    -------
    numpy.ndarray
        r, (N, n): r_0 = 0, then the estimate of tau_ext filtered by K / (s + K).

    Raises
    ------
    armdyn.ModelError
        When the arrays are not finite numbers of shapes (N,) and (N, n), t does not increase, or the
        gains are not positive.
    """
    times = np.asarray(t, dtype=float)
    n = arm.n
    arrays = []
    for name, value in (("q", q), ("qd", qd), ("tau", tau)):
        array = np.asarray(value, dtype=float)
        if array.ndim != 2 or array.shape[1] != n or array.shape[0] != times.shape[0]:
            raise ModelError(f"{name} must have shape ({times.shape[0]}, {n}) to match t, got {array.shape}")
        bad = np.argwhere(~np.isfinite(array))
        if bad.size:
            raise ModelError(f"{name} holds {array[tuple(bad[0])]} at sample {bad[0][0]}, joint {bad[0][1] + 1}")
        arrays.append(array)
    if times.ndim != 1 or times.shape[0] < 2 or not np.all(np.isfinite(times)):
        raise ModelError(f"t must be at least 2 finite sample times (N,), got shape {times.shape}")
    dt = np.diff(times)
    if np.any(dt <= 0):
        raise ModelError(f"t must increase: sample {int(np.argmax(dt <= 0)) + 1} is not after the one before")
    K = _gains(gains, n)
    eps = _smoothing(arm, coulomb_smoothing)
    q_, qd_, tau_ = arrays
    table, smoothing = sign_law_table(arm), np.zeros(n) if eps is None else eps
    return _observe_log(_packed(arm), table, smoothing, times, q_, qd_, tau_, K, bool(held_torque))


@dataclass
class MomentumObserver:
    """The observer for a control loop: one sample per ``step`` call, its state kept between calls.

    Parameters
    ----------
    arm : ArmModel
        A Robot (the model).
    gains : float or array_like
        K per joint (1/s), > 0.
    held_torque : bool, optional
        As ``observe``.
    coulomb_smoothing : float or array_like, optional
        As ``observe``.
    """

    arm: ArmModel
    gains: object = 50.0
    held_torque: bool = False
    coulomb_smoothing: object = None

    def __post_init__(self) -> None:
        self._model = _packed(self.arm)
        self._K = _gains(self.gains, self.arm.n)
        self._eps = _smoothing(self.arm, self.coulomb_smoothing)
        self.reset()

    @property
    def rates(self) -> np.ndarray:
        """K per joint (1/s), (n,): the gains as checked."""
        return self._K

    @property
    def smoothing(self) -> np.ndarray:
        """The Coulomb smoothing eps per joint, (n,) (zeros: the exact sign law)."""
        return np.zeros(self.arm.n) if self._eps is None else self._eps

    def reset(self) -> None:
        """Forget the past: the next step starts the observer (r = 0 there)."""
        n = self.arm.n
        self._scratch = (np.empty(workspace_size(n)), np.empty((n, n)), np.empty((n, n)), np.empty(n))
        self._memory = (np.zeros(2), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n))
        self._table = sign_law_table(self.arm)
        self._eps_array = np.zeros(n) if self._eps is None else self._eps
        self.residual = np.zeros(n)

    def step(self, t: float, q: object, qd: object, tau: object) -> np.ndarray:
        """Take one sample and return the residual r (n,), the estimate of tau_ext.

        Parameters
        ----------
        t : float
            The sample's time (s), after the last one.
        q, qd, tau : array_like
            The sample's state and applied torque, (n,).

        Returns
        -------
        numpy.ndarray
            r, (n,) (the observer's own array, updated in place by the next step).

        Raises
        ------
        armdyn.ModelError
            When a value is not n finite numbers, or t is not after the last sample.
        """
        n = self.arm.n
        values = []
        for name, value in (("q", q), ("qd", qd), ("tau", tau)):
            array = value if isinstance(value, np.ndarray) and value.dtype == np.float64 else np.asarray(value, float)
            if array.shape != (n,) or not np.isfinite(array).all():
                raise ModelError(f"{name} must be {n} finite numbers, got {value!r}")
            values.append(array)
        status = _step(self._model, self._table, self._eps_array, self._scratch, self._K, self.held_torque,
                       self._memory, float(t), values[0], values[1], values[2], self.residual)  # fmt: skip
        if status:
            raise ModelError(f"t must increase: {t} is not after {self._memory[0][0]}")
        return self.residual

    def hold(self, tau: object) -> None:
        """Set the torque held from the last sample on (``held_torque``): a controller knows the residual at a
        sample before it decides the torque it applies from there, and the residual does not depend on it.

        Parameters
        ----------
        tau : array_like
            The torque applied from the last sample's time to the next's, (n,).

        Raises
        ------
        armdyn.ModelError
            Without a sample yet, or when ``tau`` is not n finite numbers.
        """
        array = np.asarray(tau, dtype=float)
        last, _, rate0, tau0, _, _ = self._memory
        if last[1] == 0.0:
            raise ModelError("hold needs a sample first (step)")
        if array.shape != (self.arm.n,) or not np.all(np.isfinite(array)):
            raise ModelError(f"tau must be {self.arm.n} finite numbers, got {tau!r}")
        rate0 += array - tau0
        tau0[:] = array
