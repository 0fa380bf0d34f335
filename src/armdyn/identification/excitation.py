"""Identification as a workflow: an exciting trajectory, data the regressor explains, then ``identify``.

1. ``excitation_trajectory`` optimizes a finite Fourier series per joint (Swevers, Ganseman,
   Tukel, De Schutter and Van Brussel, "Optimal robot excitation and identification", IEEE
   Trans. Robotics and Automation 13(5), 1997)::

       q_i(t) = q0_i + sum_l a_il / (w_f l) sin(w_f l t) - b_il / (w_f l) cos(w_f l t),  l = 1..H

   periodic with w_f = 2 pi / period, so that the stacked base regressor at ``samples``
   times over one period has the smallest condition number (scipy.optimize's SLSQP from a
   random or given start), with every joint within its position limits (and, optionally,
   its velocity limits) at all times. The result, a FourierTrajectory, is a trajectory of
   armdyn.simulate (``trajectory(t) -> (q_d, qd_d, qdd_d)``) with a ``condition_number``.
2. ``identification_data`` records (q, qd, qdd, tau) along it: by default the arm simulated
   under computed-torque control tracking it, or the inverse dynamics along the desired path
   (the textbook route), with Gaussian noise of a given standard deviation on tau (and
   optionally on q).
3. ``armdyn.identify`` on those data estimates the base parameters with standard errors.

Friction is the same law in the data as in the regressor: the exact Coulomb sign law
(Fc+ for qd > 0, Fc- for qd < 0, 0 at rest). ``identification_data`` simulates with
``coulomb_smoothing=0``; simulate's default smooths the law through zero velocity (tanh(qd /
eps)), which the regressor does not model and which biases every estimate (``identify``
warns, and its ``velocity_band`` leaves such samples out). The simulation records each
step's state, acceleration and torque together, so every sample satisfies tau = W phi
exactly (to rounding); with the sign law the fixed-step integrator lets a joint hesitate
for some steps where its velocity reverses (a tracking error of a few hundredths of a
radian, harmless: those samples satisfy the law as well).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np

from armdyn import inputs
from armdyn.dynamics.regressor import BaseParameters, base_parameters, regressor
from armdyn.errors import ArgumentError, ModelError
from armdyn.model import ArmModel
from armdyn.robot import Robot

PRISMATIC_SPAN = 0.5
"""Half the range (m) a prismatic joint without limits moves over; a revolute one takes [-pi, pi]."""
CONSTRAINT_POINTS = 40
"""Times per harmonic over one period at which the limits are imposed during the optimization."""
CHECK_POINTS = 400
"""Times per harmonic at which the optimized trajectory is checked (and shrunk into the limits)."""
METHODS = ("simulate", "inverse_dynamics")


@dataclass(frozen=True, eq=False)
class FourierTrajectory:
    """A finite Fourier series per joint (Swevers et al. 1997), a trajectory of armdyn.simulate.

    q_i(t) = q0_i + sum_l a_il / (w_f l) sin(w_f l t) - b_il / (w_f l) cos(w_f l t), l = 1..H,
    qd_i(t) = sum_l a_il cos(w_f l t) + b_il sin(w_f l t), with w_f = 2 pi / period. Made by
    ``excitation_trajectory``, or directly from coefficients.

    Parameters
    ----------
    period : float
        The period (s), 2 pi / w_f.
    q0 : array_like
        The offsets q0_i, (n,).
    a, b : array_like
        The coefficients a_il and b_il (rad/s or m/s), each (n, H).
    condition_number : float, optional
        The condition number of the stacked base regressor at the optimization's sample times
        (NaN, the default, when not computed).

    Raises
    ------
    armdyn.ModelError
        When the period is not a positive number, or q0, a and b are not finite arrays of
        shapes (n,), (n, H) and (n, H).
    """

    period: float
    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    condition_number: float = float("nan")

    def __post_init__(self) -> None:
        period = _positive(self.period, "period")
        q0 = inputs.vector(self.q0, "q0")
        arrays = {}
        for name in ("a", "b"):
            try:
                value = np.array(getattr(self, name), dtype=float)
            except (TypeError, ValueError):
                raise ModelError(f"{name} must be an array of numbers of shape (n, H)") from None
            if value.shape != (q0.shape[0], value.shape[-1] if value.ndim else 0) or value.shape[1] < 1:
                raise ModelError(f"{name} must have shape ({q0.shape[0]}, H) to match q0, got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise ModelError(f"{name} must be finite")
            arrays[name] = value
        if arrays["a"].shape != arrays["b"].shape:
            raise ModelError(f"a and b must have the same shape, got {arrays['a'].shape} and {arrays['b'].shape}")
        for name, value in (("q0", q0.copy()), *arrays.items()):
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        object.__setattr__(self, "period", period)
        object.__setattr__(self, "condition_number", float(self.condition_number))

    @property
    def n(self) -> int:
        """The number of joints."""
        return self.q0.shape[0]

    @property
    def harmonics(self) -> int:
        """H, the number of harmonics per joint."""
        return self.a.shape[1]

    @property
    def frequency(self) -> float:
        """w_f = 2 pi / period (rad/s), the fundamental angular frequency."""
        return 2 * np.pi / self.period

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_d, qd_d, qdd_d) at time t.

        Parameters
        ----------
        t : float or array_like
            A time (s), or an array of times.
        n : int, optional
            The number of joints the caller expects (the trajectory protocol of
            armdyn.trajectories); checked when given.

        Returns
        -------
        tuple of numpy.ndarray
            q_d, qd_d and qdd_d, each (n,) for one time or (*t.shape, n).

        Raises
        ------
        armdyn.ModelError
            When t is not finite numbers, or n is not the trajectory's number of joints.
        """
        if n is not None and n != self.n:
            raise ModelError(f"this Fourier trajectory has {self.n} joints, not {n}")
        try:
            times = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"t must be a time or an array of times (s), got {t!r}") from None
        if not np.all(np.isfinite(times)):
            raise ModelError(f"t must be finite, got {t!r}")
        rates = self.frequency * np.arange(1, self.harmonics + 1)
        angle = times[..., None, None] * rates  # (..., 1, H)
        sine, cosine = np.sin(angle), np.cos(angle)
        q = self.q0 + ((self.a * sine - self.b * cosine) / rates).sum(-1)
        qd = (self.a * cosine + self.b * sine).sum(-1)
        qdd = ((self.b * cosine - self.a * sine) * rates).sum(-1)
        return q, qd, qdd

    def sample_times(self, samples: int) -> np.ndarray:
        """``samples`` equally spaced times over one period, from 0 (the period itself excluded).

        Parameters
        ----------
        samples : int
            How many times.

        Returns
        -------
        numpy.ndarray
            The times (s), (samples,).

        Raises
        ------
        armdyn.ModelError
            When samples is not an integer of at least 1.
        """
        return np.arange(_count(samples, "samples", 1)) * (self.period / samples)


@dataclass
class IdentificationData:
    """Samples for ``armdyn.identify``: what sensors would record along an excitation trajectory.

    Made by ``identification_data``; ``armdyn.identify(arm, data.q, data.qd, data.qdd,
    data.tau)`` estimates the base parameters from them.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times (s), (N,).
    q, qd, qdd : numpy.ndarray
        Joint positions (with their noise), velocities and accelerations, (N, n).
    tau : numpy.ndarray
        Joint torques (with their noise), (N, n).
    tau_exact : numpy.ndarray
        The torques without noise, (N, n).
    noise, position_noise : numpy.ndarray
        The standard deviations of the noise on tau and on q, per joint, (n,).
    method : str
        "simulate" or "inverse_dynamics", how the samples were made.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    tau_exact: np.ndarray
    noise: np.ndarray
    position_noise: np.ndarray
    method: str


def _positive(value: object, name: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(f"{name} must be a positive number, got {value!r}")
    if not (np.isfinite(value) and value > 0):
        raise ModelError(f"{name} must be a positive finite number, got {value!r}")
    return float(value)


def _count(value: object, name: str, minimum: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ArgumentError(f"{name} must be an integer, got {value!r}")
    if value < minimum:
        raise ModelError(f"{name} must be at least {minimum}, got {value}")
    return int(value)


def _per_joint(value: object, name: str, n: int, positive: bool) -> np.ndarray:
    """One number for every joint or n numbers, each > 0 (``positive``) or >= 0, as (n,)."""
    if isinstance(value, (bool, np.bool_)):
        raise ModelError(f"{name} must be a number or {n} numbers, got {value!r}")
    array = inputs.vector(value, name)
    if array.shape[0] not in (1, n):
        raise ModelError(f"{name} must be one number or {n} numbers (one per joint), got {array.shape[0]}")
    if np.any(array <= 0) if positive else np.any(array < 0):
        raise ModelError(f"{name} must be {'positive' if positive else 'non-negative'}, got {value!r}")
    return np.broadcast_to(array, (n,)).copy()


def _numeric_arm(arm: object, name: str = "arm") -> ArmModel:
    inputs.arm_argument(arm, ArmModel, name=name, numeric=True)
    return cast(ArmModel, arm)


def excitation_ranges(arm: ArmModel) -> tuple[np.ndarray, np.ndarray]:
    """The position range an excitation trajectory keeps each joint in: its limits, where finite.

    Parameters
    ----------
    arm : ArmModel
        The arm.

    Returns
    -------
    tuple of numpy.ndarray
        (lower, upper), each (n,): the joint limits; [-pi, pi] for a revolute joint and
        [-PRISMATIC_SPAN, PRISMATIC_SPAN] for a prismatic one where a limit is infinite.

    Raises
    ------
    armdyn.ArgumentError
        When ``arm`` is not an armdyn arm, or has symbolic parameters (an ArgumentError is a ModelError).
    """
    arm = _numeric_arm(arm)
    lower, upper = arm.qlim
    span = np.array([np.pi if kind == "revolute" else PRISMATIC_SPAN for kind in arm.kinds])
    return np.where(np.isfinite(lower), lower, -span), np.where(np.isfinite(upper), upper, span)


class _Series:
    """The linear maps from x = [q0 (n), a (n H), b (n H)] to q, qd and qdd at given times,
    each (T n, n + 2 n H) with rows (time, joint)."""

    def __init__(self, n: int, harmonics: int, period: float, times: np.ndarray) -> None:
        rates = 2 * np.pi / period * np.arange(1, harmonics + 1)
        angle = times[:, None] * rates
        sine, cosine = np.sin(angle), np.cos(angle)
        offsets = np.tile(np.eye(n), (len(times), 1))
        zeros = np.zeros_like(offsets)
        self.position = np.hstack([offsets, _joint_blocks(sine / rates, n), _joint_blocks(-cosine / rates, n)])
        self.velocity = np.hstack([zeros, _joint_blocks(cosine, n), _joint_blocks(sine, n)])
        self.acceleration = np.hstack([zeros, _joint_blocks(-sine * rates, n), _joint_blocks(cosine * rates, n)])
        self.count = len(times)
        self.n = n

    def states(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, qdd at the times, each (T, n)."""
        shape = (self.count, self.n)
        return tuple((matrix @ x).reshape(shape) for matrix in (self.position, self.velocity, self.acceleration))


def _joint_blocks(part: np.ndarray, n: int) -> np.ndarray:
    """(T n, n H): row (t, i) holds part[t, :] in the columns of joint i's harmonics."""
    T, H = part.shape
    out = np.zeros((T, n, n, H))
    for i in range(n):
        out[:, i, i, :] = part
    return out.reshape(T * n, n * H)


def _pack(q0: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.concatenate([q0, a.ravel(), b.ravel()])


def _unpack(x: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    H = (len(x) - n) // (2 * n)
    return x[:n].copy(), x[n : n + n * H].reshape(n, H).copy(), x[n + n * H :].reshape(n, H).copy()


class _Conditioning:
    """log cond(W_base) at the sample times (``value``), and its gradient in x (``gradient``).

    d log(s_max / s_min) = u_max^T dW v_max / s_max - u_min^T dW v_min / s_min (the singular
    vectors of the stacked W_base); dW by the chain rule through q, qd and qdd at each sample:
    forward differences of W in q and qd, and in qdd with a unit step (W is linear in qdd:
    exact), one batch of 3 n T states. The friction columns are differentiated by hand, since
    their Coulomb steps have no derivative: d(Fv column)/d qd_j = 1 on joint j's row. The
    singular values come from the small R of W = Q R (QR first: cheaper than the SVD of the
    tall W, and much cheaper where a threaded BLAS competes for busy cores).
    """

    STEP = 1e-6
    RANK_DEFICIENT = 80.0  # the value where s_min = 0: log(5.5e34), worse than any full-rank W

    def __init__(self, arm: ArmModel, base: BaseParameters, series: _Series) -> None:
        self.arm, self.series = arm, series
        self.columns = base.columns
        n = arm.n
        self.body = self.columns < 10 * n  # the columns whose derivatives in qd are taken by differences
        self.viscous = [
            (int((c - 10 * n) // 4), k) for k, c in enumerate(self.columns) if c >= 10 * n and (c - 10 * n) % 4 == 0
        ]
        self.cached: tuple | None = None

    def regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        return regressor(self.arm, q, qd, qdd)[..., self.columns]

    def _evaluate(self, x: np.ndarray) -> tuple:
        if self.cached is not None and np.array_equal(self.cached[0], x):
            return self.cached
        states = self.series.states(x)
        W = self.regressor(*states)  # (T, n, r)
        _, singular, Vt = np.linalg.svd(np.linalg.qr(W.reshape(-1, W.shape[-1]), mode="r"))
        self.cached = (x.copy(), states, W, singular, Vt)
        return self.cached

    def condition(self, x: np.ndarray) -> float:
        singular = self._evaluate(x)[3]
        return float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")

    def value(self, x: np.ndarray) -> float:
        singular = self._evaluate(x)[3]
        return float(np.log(singular[0] / singular[-1])) if singular[-1] > 0 else self.RANK_DEFICIENT

    def gradient(self, x: np.ndarray) -> np.ndarray:
        _, (q, qd, qdd), W, singular, Vt = self._evaluate(x)
        if not singular[-1] > 0:
            return np.zeros_like(x)  # no direction out of a rank-deficient start
        n, T, r = self.arm.n, self.series.count, len(self.columns)
        stacked = W.reshape(-1, r)
        first, last = Vt[0], Vt[-1]
        u_first, u_last = stacked @ first / singular[0], stacked @ last / singular[-1]
        G = (np.outer(u_first, first) / singular[0] - np.outer(u_last, last) / singular[-1]).reshape(T, n, r)
        eye = np.eye(n)[:, None, :]  # (j, 1, n): the step on joint j
        step = self.STEP
        same = [np.broadcast_to(value, (n, T, n)) for value in (q, qd, qdd)]
        shifted = self.regressor(
            np.concatenate([q + step * eye, same[0], same[0]]),
            np.concatenate([same[1], qd + step * eye, same[1]]),
            np.concatenate([same[2], same[2], qdd + eye]),
        )  # (3 n, T, n, r)
        change = shifted - W
        change[: 2 * n] /= step
        change[n : 2 * n, ..., ~self.body] = 0.0  # the friction columns in qd: by hand below
        slopes = np.einsum("stic,tic->st", change, G)  # d value / d (state s of joint j) at time t
        for joint, column in self.viscous:
            slopes[n + joint] += G[:, joint, column]
        g_q, g_qd, g_qdd = (slopes[k * n : (k + 1) * n].T.reshape(-1) for k in range(3))  # rows (time, joint)
        return self.series.position.T @ g_q + self.series.velocity.T @ g_qd + self.series.acceleration.T @ g_qdd


def _limits_of(arm: ArmModel, velocity_limits: object) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    lower, upper = excitation_ranges(arm)
    speed = None if velocity_limits is None else _per_joint(velocity_limits, "velocity_limits", arm.n, True)
    return lower, upper, speed


def _into_limits(
    x: np.ndarray, n: int, period: float, lower: np.ndarray, upper: np.ndarray, speed: np.ndarray | None
) -> np.ndarray:
    """x with each joint's oscillation shrunk about q0 (q0 moved inside first) until q stays within
    [lower, upper] and |qd| within ``speed`` at all times: checked at CHECK_POINTS times per harmonic,
    with the margin max|qdd| dt^2 / 8 that bounds how far q can pass its largest sampled value."""
    q0, a, b = _unpack(x, n)
    H = a.shape[1]
    middle, half = (lower + upper) / 2, (upper - lower) / 2
    q0 = np.clip(q0, middle - 0.999 * half, middle + 0.999 * half)
    rates = 2 * np.pi / period * np.arange(1, H + 1)
    spacing = period / (CHECK_POINTS * H)
    times = np.arange(CHECK_POINTS * H) * spacing
    angle = times[:, None, None] * rates  # (T, 1, H)
    sine, cosine = np.sin(angle), np.cos(angle)
    swing = ((a * sine - b * cosine) / rates).sum(-1)  # q - q0, (T, n)
    velocity = (a * cosine + b * sine).sum(-1)
    amplitude = np.hypot(a, b)
    margin = (amplitude * rates).sum(-1) * spacing**2 / 8  # max|qdd| dt^2 / 8, and for qd below
    with np.errstate(divide="ignore", invalid="ignore"):
        room_up = np.where(swing > 0, (upper - margin - q0) / swing, np.inf).min(0)
        room_down = np.where(swing < 0, (lower + margin - q0) / swing, np.inf).min(0)
        scale = np.minimum(1.0, np.minimum(room_up, room_down))
        if speed is not None:
            bound = speed - (amplitude * rates**2).sum(-1) * spacing**2 / 8
            scale = np.minimum(scale, np.min(np.where(velocity != 0, bound / np.abs(velocity), np.inf), 0))
    scale = np.clip(scale, 0.0, 1.0)[:, None]
    return _pack(q0, a * scale, b * scale)


def _start(
    rng: np.random.Generator, n: int, harmonics: int, period: float, lower: np.ndarray, upper: np.ndarray,
    speed: np.ndarray | None,
) -> np.ndarray:  # fmt: skip
    """Random coefficients: q0 near the middle of each range, the swing about 40% of the half range."""
    middle, half = (lower + upper) / 2, (upper - lower) / 2
    q0 = middle + rng.uniform(-0.1, 0.1, n) * half
    a, b = rng.standard_normal((2, n, harmonics))
    rates = 2 * np.pi / period * np.arange(1, harmonics + 1)
    reach = (np.hypot(a, b) / rates).sum(-1)  # the largest |q - q0| could be
    scale = 0.4 * half / reach
    if speed is not None:
        scale = np.minimum(scale, 0.4 * speed / np.hypot(a, b).sum(-1))
    return _pack(q0, a * scale[:, None], b * scale[:, None])


def excitation_trajectory(
    arm: ArmModel,
    period: float = 10.0,
    harmonics: int = 5,
    samples: int = 100,
    seed: int = 0,
    start: FourierTrajectory | None = None,
    velocity_limits: object = None,
    drives: bool = True,
    iterations: int = 100,
) -> FourierTrajectory:
    """An exciting trajectory for identification: a Fourier series per joint, optimized.

    The coefficients q0_i, a_il, b_il of the series of Swevers, Ganseman, Tukel, De Schutter
    and Van Brussel ("Optimal robot excitation and identification", IEEE Trans. Robotics and
    Automation 13(5), 1997; see FourierTrajectory) minimize the condition number of the base
    regressor stacked at ``samples`` equally spaced times over one period (the log of it, by
    scipy.optimize's SLSQP with its exact gradient), subject to each joint staying within its
    position limits (``excitation_ranges``) and, when given, |qd_i| <= velocity_limits_i, at
    CONSTRAINT_POINTS times per harmonic; the result is then checked at CHECK_POINTS times per
    harmonic and shrunk about q0 where needed, so the limits hold at all times. The search
    starts from random coefficients (``seed``) or from ``start``; the result is the better of
    the start and the optimum.

    Parameters
    ----------
    arm : ArmModel
        The arm (numeric parameters).
    period : float, optional
        The period (s) of the series, 2 pi / w_f; default 10.
    harmonics : int, optional
        H, harmonics per joint (default 5): 2 n H + n coefficients are optimized.
    samples : int, optional
        Times over one period at which the condition number is computed (default 100); the
        n ``samples`` equations must outnumber the base parameters.
    seed : int, optional
        Seed of the random start (default 0).
    start : FourierTrajectory, optional
        Start from these coefficients instead (same joints, period and harmonics).
    velocity_limits : float or array_like, optional
        The largest joint speed (rad/s or m/s), one for every joint or one per joint; default
        None, no limit beyond what the position limits imply.
    drives : bool, optional
        True (default) excites the friction and motor parameters too (``identify``'s drives).
    iterations : int, optional
        The most SLSQP iterations (default 100).

    Returns
    -------
    FourierTrajectory
        The trajectory, with ``condition_number`` at the sample times.

    Raises
    ------
    armdyn.ModelError
        When period is not a positive number, harmonics, samples, seed or iterations is not in
        range (samples too few to determine the base parameters), velocity_limits is not
        positive, or ``start`` does not match the arm, period and harmonics.
    armdyn.ArgumentError
        When ``arm`` is not a numeric armdyn arm, harmonics, samples, seed or iterations is not
        an integer, drives is not a bool, or ``start`` is not a FourierTrajectory (an
        ArgumentError is a ModelError and a TypeError).
    """
    from scipy.optimize import minimize

    arm = _numeric_arm(arm)
    n = arm.n
    period = _positive(period, "period")
    harmonics = _count(harmonics, "harmonics", 1)
    samples = _count(samples, "samples", 1)
    seed = _count(seed, "seed", 0)
    iterations = _count(iterations, "iterations", 1)
    if not isinstance(drives, (bool, np.bool_)):
        raise ArgumentError(f"drives must be True or False, got {drives!r}")
    base = base_parameters(arm, drives=bool(drives))
    if samples * n <= len(base):
        raise ModelError(
            f"samples must give more equations than the {len(base)} base parameters of '{arm.name}': at least "
            f"{len(base) // n + 1} samples of its {n} joints, got {samples}"
        )
    lower, upper, speed = _limits_of(arm, velocity_limits)
    if start is not None:
        if not isinstance(start, FourierTrajectory):
            raise ArgumentError(f"start must be a FourierTrajectory, got {type(start).__name__}")
        if (start.n, start.harmonics) != (n, harmonics) or not np.isclose(start.period, period):
            raise ModelError(
                f"start has {start.n} joints, {start.harmonics} harmonics and period {start.period:g} s; "
                f"'{arm.name}' needs {n} joints, and harmonics = {harmonics}, period = {period:g} s were asked"
            )
        x0 = _into_limits(_pack(start.q0, start.a, start.b), n, period, lower, upper, speed)
    else:
        x0 = _start(np.random.default_rng(seed), n, harmonics, period, lower, upper, speed)
    objective = _Conditioning(arm, base, _Series(n, harmonics, period, np.arange(samples) * (period / samples)))
    grid = _Series(n, harmonics, period, np.arange(CONSTRAINT_POINTS * harmonics) * (period / (CONSTRAINT_POINTS *
                   harmonics)))  # fmt: skip
    rows = grid.count
    low, high = np.tile(lower, rows), np.tile(upper, rows)
    constraints = [
        {"type": "ineq", "fun": lambda x: np.concatenate([grid.position @ x - low, high - grid.position @ x]),
         "jac": lambda x: np.vstack([grid.position, -grid.position])},
    ]  # fmt: skip
    if speed is not None:
        fastest = np.tile(speed, rows)
        constraints.append(
            {"type": "ineq", "fun": lambda x: np.concatenate([fastest - grid.velocity @ x,
                                                              fastest + grid.velocity @ x]),
             "jac": lambda x: np.vstack([-grid.velocity, grid.velocity])}
        )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        found = minimize(objective.value, x0, jac=objective.gradient, method="SLSQP", constraints=constraints,
                         options={"maxiter": iterations, "ftol": 1e-7})  # fmt: skip
    candidates = [x0]
    if np.all(np.isfinite(found.x)):
        candidates.append(_into_limits(found.x, n, period, lower, upper, speed))
    conditions = [objective.condition(x) for x in candidates]
    best = int(np.argmin(conditions))
    q0, a, b = _unpack(candidates[best], n)
    return FourierTrajectory(period, q0, a, b, conditions[best])


def identification_data(
    arm: Robot,
    trajectory: Callable,
    t_final: float | None = None,
    dt: float = 1e-3,
    noise: object = 0.0,
    position_noise: object = 0.0,
    seed: int = 0,
    method: str = "simulate",
    controller: object = None,
) -> IdentificationData:
    """Samples (q, qd, qdd, tau) along a trajectory, as sensors would record them, for ``identify``.

    With ``method="simulate"`` (default) the arm is simulated (armdyn.simulate, fixed-step
    RK4 with step dt) tracking the trajectory under ``controller`` (computed torque, kp = 100,
    kv = 20, by default), from the trajectory's own start q_d(0), qd_d(0), with Coulomb
    friction by the exact sign law (``coulomb_smoothing=0``, the regressor's law; see the
    module docstring); each sample is a step's state, acceleration and applied torque. With
    ``method="inverse_dynamics"`` the samples are the desired path itself every dt and the
    arm's inverse dynamics along it (the textbook route; no controller). Either way, Gaussian
    noise of standard deviation ``noise`` (N m or N) is added to tau and ``position_noise``
    (rad or m) to q, from a generator seeded with ``seed``. Noise on q makes the regressor's
    inputs inexact, which ``identify``'s standard errors do not count (keep it small).

    A trajectory other than armdyn's Sinusoid or Quintic (a FourierTrajectory, for one) runs in
    simulate's Python loop, a few seconds for 10 s of the PUMA 560 at dt = 1 ms; the
    PythonLoopWarning that simulate gives for it is silenced here.

    Parameters
    ----------
    arm : Robot
        The arm.
    trajectory : callable
        ``trajectory(t) -> (q_d, qd_d, qdd_d)``, e.g. from ``excitation_trajectory``; for
        "inverse_dynamics" it must accept an array of times.
    t_final : float, optional
        Seconds of data; default one period of the trajectory (its ``period``).
    dt : float, optional
        The sample interval (and simulation step), s; default 1e-3.
    noise : float or array_like, optional
        The standard deviation of the torque noise, one for every joint or one per joint;
        default 0.
    position_noise : float or array_like, optional
        The standard deviation of the noise on q, likewise; default 0.
    seed : int, optional
        Seed of the noise (default 0).
    method : str, optional
        "simulate" (default) or "inverse_dynamics".
    controller : callable, optional
        The controller of "simulate" (any of armdyn.control's, or one of your own); default
        ComputedTorque(100, 20).

    Returns
    -------
    IdentificationData
        The samples, with the torques before noise.

    Raises
    ------
    armdyn.ModelError
        When t_final is missing (a trajectory without a period) or not positive, dt is not
        positive, noise or position_noise is negative, seed is below 0, method is unknown, or a
        controller is given with "inverse_dynamics".
    armdyn.ArgumentError
        When ``arm`` is not a numeric armdyn Robot, ``trajectory`` is not callable, or seed is
        not an integer (an ArgumentError is a ModelError and a TypeError).
    armdyn.SimulationError
        When the simulation stops.
    """
    from armdyn import control
    from armdyn.simulation import PythonLoopWarning, Result, simulate

    inputs.arm_argument(arm, Robot, name="arm", numeric=True)
    n = arm.n
    if not callable(trajectory):
        raise ArgumentError(f"trajectory must be callable, t -> (q_d, qd_d, qdd_d), got {type(trajectory).__name__}")
    if t_final is None:
        if not hasattr(trajectory, "period"):
            raise ModelError("t_final is needed for a trajectory without a period")
        t_final = trajectory.period
    t_final, dt = _positive(t_final, "t_final"), _positive(dt, "dt")
    if dt > t_final:
        raise ModelError(f"dt must not exceed t_final, got dt = {dt:g} s and t_final = {t_final:g} s")
    noise = _per_joint(noise, "noise", n, False)
    position_noise = _per_joint(position_noise, "position_noise", n, False)
    seed = _count(seed, "seed", 0)
    if method not in METHODS:
        raise ModelError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if method == "simulate":
        law = control.ComputedTorque(100.0, 20.0) if controller is None else controller
        q_start, qd_start, _ = (np.asarray(value, dtype=float) for value in trajectory(0.0))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PythonLoopWarning)
            run = simulate(arm, law, trajectory, t_final=t_final, dt=dt, q0=q_start, qd0=qd_start,
                           coulomb_smoothing=0.0)  # fmt: skip
        assert isinstance(run, Result)  # one run (no per-run argument was given)
        t, q, qd, qdd, tau = run.t, run.q, run.qd, run.qdd, run.tau
    else:
        if controller is not None:
            raise ModelError("controller is for method='simulate'; 'inverse_dynamics' follows the path itself")
        t = np.arange(round(t_final / dt) + 1) * dt
        q, qd, qdd = (inputs.state(np.asarray(value, dtype=float), n, name, " from the trajectory")
                      for value, name in zip(trajectory(t), ("q_d", "qd_d", "qdd_d"), strict=True))  # fmt: skip
        if q.shape != (len(t), n):
            raise ModelError(f"the trajectory must give ({len(t)}, {n}) arrays for {len(t)} times, got {q.shape}")
        tau = arm.inverse_dynamics(q, qd, qdd)
    rng = np.random.default_rng(seed)
    measured_tau = tau + rng.standard_normal(tau.shape) * noise
    measured_q = q + rng.standard_normal(q.shape) * position_noise
    return IdentificationData(t, measured_q, qd, qdd, measured_tau, tau, noise, position_noise, method)
