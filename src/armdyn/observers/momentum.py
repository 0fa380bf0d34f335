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

Cost. p and tau - beta come from one O(n) recursion (armdyn.dynamics.momentum: neither M nor Vm is formed),
in ``momentum_and_rate``, which simulate's compiled loop can call too. ``MomentumObserver.step`` is one compiled
call of five arguments: the observer's whole state (the packed model, gains, smoothing, sign laws, the last
sample's p, rate and torque, the residual) lives in one flat array, the checks of the sample are compiled in, and
the workspace is on the call's stack. ``observe`` computes the samples' p and rate in parallel blocks (they are
independent), then runs the filter in order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.friction import coulomb_torque, friction_vector, sigmoid, sign_law_table, smooth_coulomb
from armdyn.dynamics.momentum import momentum_core
from armdyn.dynamics.packed import (
    HEADER,
    MOMENTUM_JOINT,
    N_JOINTS,
    SIGMOID_AMPLITUDE,
    STRIDE,
    VISCOUS,
    workspace_size,
)
from armdyn.dynamics.rnea import BATCH_CHUNKS
from armdyn.dynamics.spatial import NUMBA_OPTIONS, VECTOR, one_state, scratch, states_status
from armdyn.dynamics.status import NOT_FINITE, OK, WRONG_LENGTH, WRONG_SHAPE
from armdyn.errors import ModelError
from armdyn.inputs import LARGEST_STATE, without_read_only
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


# The observer's memory: one flat array (every array argument of a compiled call costs its dispatch about 50 ns):
# the packed model (_model_size(n) values), then a header and blocks of n values, block k at base + _MEMORY_HEADER + k n
# (base = _model_size(n)), the last the sign-law table (4 n, rows per joint).
_LAST_TIME, _COUNT, _HELD, _REFERENCE_STEP, _LARGEST_GAIN, _MEMORY_HEADER = 0, 1, 2, 3, 4, 5
# _DECAY: exp(-K dt0) at the reference step dt0; _TABLE: 4 blocks, (n, 4); the workspace is the step's own (stack)
_GAINS, _EPS, _P0, _RATE0, _TAU0, _RESIDUAL, _DECAY, _TABLE = range(8)
_MEMORY_BLOCKS = _TABLE + 4
NOT_AFTER = 100
"""The step kernel's status when t is not after the last sample's time (the others: armdyn.dynamics.status)."""
DECAY_SHIFT = 1e-4
"""exp(-K dt) is taken from exp(-K dt0) at a reference step dt0 while K |dt - dt0| stays below this (_decay)."""


@njit(inline="always", **NUMBA_OPTIONS)
def _model_size(n: int) -> int:
    """The values of the packed model of an arm of n joints: where the observer's own memory starts."""
    return HEADER + STRIDE * n


@njit(inline="always", **NUMBA_OPTIONS)
def _memory_size(n: int) -> int:
    """The values of a MomentumObserver's memory for n joints."""
    return _model_size(n) + _MEMORY_HEADER + _MEMORY_BLOCKS * n


@njit(inline="always", **NUMBA_OPTIONS)
def momentum_and_rate(
    model: np.ndarray,
    table: np.ndarray,
    eps: np.ndarray,
    work: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    tau: np.ndarray,
    p: np.ndarray,
    rate: np.ndarray,
) -> None:
    """p = M qd and the known rate tau - beta = tau + Vm^T qd - G - F of one state, by one O(n) recursion
    (armdyn.dynamics.momentum.momentum_core: no M, no Vm), compiled and inlined into its caller.

    Parameters
    ----------
    model : numpy.ndarray
        The packed arm.
    table : numpy.ndarray
        The sign laws, (n, 4) (friction.sign_law_table).
    eps : numpy.ndarray
        The Coulomb smoothing per joint, (n,): 0 for the exact sign law (friction.smooth_coulomb).
    work : numpy.ndarray
        Scratch of packed.workspace_size(n) values (momentum_core's records, then G in n values).
    q, qd, tau : numpy.ndarray
        The state and the applied torque, (n,).
    p, rate : numpy.ndarray
        Outputs, (n,): the momentum and pdot without the external torque; arrays of their own (not views of
        ``work``).

    Returns
    -------
    None
        p and rate are written in place.
    """
    n = int(model[N_JOINTS])
    G = work[MOMENTUM_JOINT * n : MOMENTUM_JOINT * n + n]
    momentum_core(model, work, q, qd, p, rate, G)
    # Which laws the arm has, decided once: with the tests inside the joints' loop, the compiled loop evaluates
    # every law's exp and tanh for every joint (about 20 ns a joint), whether the joint has the law or not.
    general, sigmoids = False, False
    for i in range(n):
        general |= (eps[i] > 0.0) | (table[i, 2] != 0.0)
        sigmoids |= model[HEADER + STRIDE * i + SIGMOID_AMPLITUDE] != 0.0
    for i in range(n):
        friction = model[HEADER + STRIDE * i + VISCOUS] * qd[i]
        if general:
            friction += smooth_coulomb(table, eps, i, qd[i])
        else:  # smooth_coulomb's exact law without Stribeck friction
            friction += coulomb_torque(table[i, 0], table[i, 1], qd[i])
        if sigmoids:
            friction += sigmoid(model, i, qd[i])
        rate[i] = tau[i] + rate[i] - G[i] - friction


@njit(inline="always", **NUMBA_OPTIONS)
def _increment(held: bool, dt: float, p: float, p0: float, rate: float, rate0: float, tau: float, tau0: float) -> float:
    """(p - p0 - the integral of the known terms over the step) / dt: the trapezoid rule, or tau0 held over it."""
    known = dt * (tau0 + 0.5 * ((rate - tau) + (rate0 - tau0))) if held else 0.5 * dt * (rate + rate0)
    return (p - p0 - known) / dt


@njit(inline="always", **NUMBA_OPTIONS)
def _decay(reference: float, x: float) -> float:
    """exp(-K dt) = exp(-K dt0) exp(-x), x = K (dt - dt0), |x| <= DECAY_SHIFT: exp(-x) by its series to x^3 (the next
    term, x^4 / 24 <= 4e-18, is below rounding). A sampled log's steps differ in their last bits, so an exact exp
    per step would cost one exp per joint and sample for nothing."""
    return reference * (1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0))))


LOG_BLOCK = 16384
"""Samples whose p and rate observe computes at once (in parallel): its extra memory stays 2 LOG_BLOCK n values."""


@njit(parallel=True, **NUMBA_OPTIONS)
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
    """The residual over a whole log: block by block, p and the known rate of the block's samples in parallel chunks
    (they are independent), then the filter r_k = a r_{k-1} + (1 - a) dw_k / dt_k in order, a = exp(-K dt_k) by
    _decay (as the step kernel); r_0 = 0."""
    samples, n = q.shape
    r = np.empty((samples, n))
    block = min(samples, LOG_BLOCK)
    p, rate = np.empty((block + 1, n)), np.empty((block + 1, n))  # row 0: the sample before the block
    reference = np.ones(n)
    reference_step, largest = 0.0, gains.max()
    for j in range(n):
        r[0, j] = 0.0
    start = 0
    while start < samples:
        stop = min(start + block, samples)
        count = stop - start
        chunks = min(count, BATCH_CHUNKS)
        for chunk in prange(chunks):
            work = np.empty(workspace_size(n))
            for k in range(start + chunk * count // chunks, start + (chunk + 1) * count // chunks):
                row = k - start + 1
                momentum_and_rate(model, table, eps, work, q[k], qd[k], tau[k], p[row], rate[row])
        for k in range(max(start, 1), stop):
            i = k - start + 1
            dt = t[k] - t[k - 1]
            if abs(dt - reference_step) * largest > DECAY_SHIFT:
                for j in range(n):
                    reference[j] = np.exp(-gains[j] * dt)
                reference_step = dt
            shift = dt - reference_step
            for j in range(n):
                a = _decay(reference[j], gains[j] * shift)
                step = _increment(held, dt, p[i, j], p[i - 1, j], rate[i, j], rate[i - 1, j], tau[k, j], tau[k - 1, j])
                r[k, j] = a * r[k - 1, j] + (1.0 - a) * step
        for j in range(n):
            p[0, j], rate[0, j] = p[count, j], rate[count, j]
        start = stop
    return r


@njit(inline="always", **NUMBA_OPTIONS)
def _finite(x: np.ndarray, n: int) -> bool:
    """x has n values, each of magnitude below inputs.LARGEST_STATE (NaN fails): no branch per value."""
    if x.shape[0] != n:
        return False
    good = True
    for k in range(n):
        good &= abs(x[k]) < LARGEST_STATE
    return good


@one_state(types.int64(VECTOR, types.float64, VECTOR, VECTOR, VECTOR))
def observer_step(memory: np.ndarray, t: float, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> int:
    """One sample into a MomentumObserver's memory (its layout above): its residual block updated in place.

    Parameters
    ----------
    memory : numpy.ndarray
        The observer's memory, _memory_size(n) values, the packed model first.
    t : float
        The sample's time.
    q, qd, tau : numpy.ndarray
        The sample, (n,) each.

    Returns
    -------
    int
        OK; WRONG_LENGTH + k or NOT_FINITE + k for state argument k (q, qd, tau) of the wrong length or not
        finite; WRONG_SHAPE for a memory of the wrong size; NOT_AFTER when t is not after the last sample.
        The memory is changed only when OK.
    """
    n = int(memory[N_JOINTS])
    if n < 1 or memory.shape[0] != _memory_size(n):
        return WRONG_SHAPE
    base = _model_size(n)
    model = memory[:base]
    if not (_finite(q, n) & _finite(qd, n) & _finite(tau, n)):  # one test on the fast path; which rule, then
        return states_status(model, q, qd, tau, 3)
    started = memory[base + _COUNT] > 0.0
    dt = t - memory[base + _LAST_TIME]
    if started and not dt > 0.0:
        return NOT_AFTER
    o = base + _MEMORY_HEADER
    table = memory[o + _TABLE * n : o + _MEMORY_BLOCKS * n].reshape((n, 4))
    eps = memory[o + _EPS * n : o + (_EPS + 1) * n]
    # the workspace and p, rate on the stack: no allocation, and the compiler knows they are no other array's
    work, p, rate = scratch(workspace_size(n)), scratch(n), scratch(n)
    momentum_and_rate(model, table, eps, work, q, qd, tau, p, rate)
    if started:
        if abs(dt - memory[base + _REFERENCE_STEP]) * memory[base + _LARGEST_GAIN] > DECAY_SHIFT:
            for j in range(n):
                memory[o + _DECAY * n + j] = np.exp(-memory[o + _GAINS * n + j] * dt)
            memory[base + _REFERENCE_STEP] = dt
        shift = dt - memory[base + _REFERENCE_STEP]
        held = memory[base + _HELD] != 0.0
        for j in range(n):
            a = _decay(memory[o + _DECAY * n + j], memory[o + _GAINS * n + j] * shift)
            step = _increment(held, dt, p[j], memory[o + _P0 * n + j], rate[j], memory[o + _RATE0 * n + j], tau[j],
                              memory[o + _TAU0 * n + j])  # fmt: skip
            memory[o + _RESIDUAL * n + j] = a * memory[o + _RESIDUAL * n + j] + (1.0 - a) * step
    memory[base + _LAST_TIME] = t
    memory[base + _COUNT] += 1.0
    for j in range(n):
        memory[o + _P0 * n + j] = p[j]
        memory[o + _RATE0 * n + j] = rate[j]
        memory[o + _TAU0 * n + j] = tau[j]
    return OK


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
        array = np.ascontiguousarray(value, dtype=float)
        if array.ndim != 2 or array.shape[1] != n or array.shape[0] != times.shape[0]:
            raise ModelError(f"{name} must have shape ({times.shape[0]}, {n}) to match t, got {array.shape}")
        finite = np.isfinite(array)
        if not finite.all():
            bad = np.argwhere(~finite)[0]
            raise ModelError(f"{name} holds {array[tuple(bad)]} at sample {bad[0]}, joint {bad[1] + 1}")
        arrays.append(array)
    if times.ndim != 1 or times.shape[0] < 2 or not np.all(np.isfinite(times)):
        raise ModelError(f"t must be at least 2 finite sample times (N,), got shape {times.shape}")
    dt = np.diff(times)
    if np.any(dt <= 0):
        raise ModelError(f"t must increase: sample {int(np.argmax(dt <= 0)) + 1} is not after the one before")
    K = _gains(gains, n)
    eps = _smoothing(arm, coulomb_smoothing)
    q_, qd_, tau_, times = without_read_only((*arrays, np.ascontiguousarray(times)))  # one compile for any log
    table, smoothing = sign_law_table(arm), np.zeros(n) if eps is None else eps
    return _observe_log(_packed(arm), table, smoothing, times, q_, qd_, tau_, K, bool(held_torque))


@dataclass
class MomentumObserver:
    """The observer for a control loop: one sample per ``step`` call, its state kept between calls.

    The settings are read when the observer is made (its compiled memory holds them): for other gains, make a new
    observer.

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
        model = _packed(self.arm)
        self._K = _gains(self.gains, self.arm.n)
        self._eps = _smoothing(self.arm, self.coulomb_smoothing)
        n = self.arm.n
        self._memory = np.zeros(_memory_size(n))
        base = _model_size(n)
        self._memory[:base] = model
        self._header = self._memory[base : base + _MEMORY_HEADER]
        start = base + _MEMORY_HEADER
        block = [self._memory[start + k * n : start + (k + 1) * n] for k in range(_TABLE)]
        block[_GAINS][:] = self._K
        if self._eps is not None:
            block[_EPS][:] = self._eps
        table = self._memory[start + _TABLE * n : start + _MEMORY_BLOCKS * n]
        table[:] = sign_law_table(self.arm).ravel()
        self._header[_HELD] = 1.0 if self.held_torque else 0.0
        self._header[_LARGEST_GAIN] = self._K.max()
        self._decay = block[_DECAY]
        self.residual = block[_RESIDUAL]
        self._rate0, self._tau0 = block[_RATE0], block[_TAU0]
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
        self._header[_LAST_TIME] = self._header[_COUNT] = self._header[_REFERENCE_STEP] = 0.0
        self._decay[:] = 1.0  # exp(-K 0), the reference step 0 (as observe starts)
        self.residual[:] = 0.0

    def step(self, t: float, q: object, qd: object, tau: object) -> np.ndarray:
        """Take one sample and return the residual r (n,), the estimate of tau_ext.

        One compiled call when t is a float and q, qd, tau are C-contiguous float64 arrays (n,) (the checks of
        length and finiteness are compiled in); other inputs (lists, integers, other dtypes) are converted first.

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
        try:
            status = observer_step(self._memory, t, q, qd, tau)
        except TypeError:  # not the signature's types: convert, then the same call
            return self._converted_step(t, q, qd, tau)
        if status:
            self._refuse(status, t, q, qd, tau)
        return self.residual

    def _converted_step(self, t: object, q: object, qd: object, tau: object) -> np.ndarray:
        n = self.arm.n
        try:
            time = float(t)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise ModelError(f"t must be a number (s), got {t!r}") from None
        values = []
        for name, value in (("q", q), ("qd", qd), ("tau", tau)):
            try:
                array = np.ascontiguousarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise ModelError(f"{name} must be {n} finite numbers, got {value!r}") from None
            if array.shape != (n,):
                raise ModelError(f"{name} must be {n} finite numbers, got {value!r}")
            if not array.flags.writeable:  # the signature's arrays are writable ones
                array = array.copy()
            values.append(array)
        status = observer_step(self._memory, time, values[0], values[1], values[2])
        if status:
            self._refuse(status, time, q, qd, tau)
        return self.residual

    def _refuse(self, status: int, t: object, q: object, qd: object, tau: object) -> None:
        """The ModelError of a step kernel's status."""
        if status == NOT_AFTER:
            raise ModelError(f"t must increase: {t} is not after {self._header[_LAST_TIME]}")
        for base in (WRONG_LENGTH, NOT_FINITE):
            if base <= status < base + 3:
                name, value = (("q", q), ("qd", qd), ("tau", tau))[status - base]
                raise ModelError(f"{name} must be {self.arm.n} finite numbers, got {value!r}")
        raise ModelError(f"the observer's memory is damaged (status {status}); make a new MomentumObserver")

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
        if self._header[_COUNT] == 0.0:
            raise ModelError("hold needs a sample first (step)")
        if array.shape != (self.arm.n,) or not np.all(np.isfinite(array)):
            raise ModelError(f"tau must be {self.arm.n} finite numbers, got {tau!r}")
        self._rate0 += array - self._tau0
        self._tau0[:] = array
