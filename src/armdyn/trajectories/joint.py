"""Desired trajectories q_d(t) with their velocities and accelerations (Chapter 4).

Each trajectory is called as ``trajectory(t)`` and returns (q_d, qd_d, qdd_d); t may be a
scalar or an array of times (leading axis); any such callable is a trajectory. The sinusoid
and the quintic also pack into numbers (``arrays``) for their compiled form (``desired``),
which the compiled simulation loop runs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar, cast

import numpy as np
from numba import njit

from armdyn import inputs
from armdyn.dynamics.spatial import NUMBA_OPTIONS, sin_cos
from armdyn.errors import ModelError
from armdyn.inputs import LARGEST_STATE

T = TypeVar("T", float, np.ndarray)

HOLD, SINUSOID, QUINTIC = 0, 1, 2
SHORTEST_SPAN = 1e-100  # a Quintic's t1 - t0 below this: span**2 would underflow (see Quintic.__call__)


def _times(t: object) -> np.ndarray:
    """t as a float array of finite times below LARGEST_STATE in magnitude, or a ModelError naming t.
    A plain float in range (simulate's every step) skips the general check."""
    if type(t) is float and -LARGEST_STATE < t < LARGEST_STATE:  # False for NaN
        return np.asarray(t, dtype=float)
    return inputs.numbers(t, "t")


def _joints(n: object) -> int | None:
    """The number of joints asked for: None (as many as the longest parameter) or an int >= 1."""
    return None if n is None else inputs.integer(n, "n", 1)


def _numbers(value: object, name: str, where: str) -> np.ndarray:
    """inputs.numbers, but a plain float or float64 array in range (checked by one comparison, which
    NaN fails) is taken as it is: simulate's Python loop calls a trajectory at every step."""
    if type(value) is float and abs(value) < LARGEST_STATE:
        return np.array(value)
    if type(value) is np.ndarray and value.dtype == np.float64 and value.size and abs(value).max() < LARGEST_STATE:
        return value
    return inputs.numbers(value, name, where=where)


def _per_joint(kind: str, named: dict[str, object], n: int | None) -> list[np.ndarray]:
    """Each parameter of a trajectory as (n,): a number for every joint or one per joint, finite and
    below LARGEST_STATE (so that no product of them overflows), or a ModelError naming it. With n
    None, n is the length of the longest."""
    where = f" in a {kind}"
    arrays = {name: _numbers(value, name, where) for name, value in named.items()}
    for name, array in arrays.items():
        if array.ndim > 1 or not array.size:
            raise ModelError(f"{name} must be a number or a 1-D array, one per joint{where}, got shape {array.shape}")
    width = n if n is not None else max(array.size for array in arrays.values())
    for name, array in arrays.items():
        if array.size not in (1, width):
            raise ModelError(f"{name} must have 1 or {width} values (one per joint){where}, got {array.size}")
    return [np.broadcast_to(np.atleast_1d(array), (width,)) for array in arrays.values()]


@dataclass(frozen=True)
class Sinusoid:
    """q_d = offset + amplitude sin(2 pi frequency t + phase), per joint (frequency in Hz).

    The book's Example 4.4-1, theta_1d = 0.1 sin(pi t), theta_2d = 0.1 cos(pi t), is
    Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0, pi/2]).
    """

    amplitude: object
    frequency: object
    phase: object = 0.0
    offset: object = 0.0

    def arrays(self, n: int | None) -> np.ndarray:
        """(4, n): amplitude, angular frequency, phase, offset, broadcast to n joints (n None: as
        many as the longest); a parameter that is not a finite number or one per joint is a
        ModelError naming it."""
        names = ("amplitude", "frequency", "phase", "offset")
        packed = np.stack(_per_joint("Sinusoid", dict(zip(names, self._values(), strict=True)), n))
        packed[1] *= 2 * np.pi
        return packed

    def _values(self) -> tuple:
        return self.amplitude, self.frequency, self.phase, self.offset

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_d, qd_d, qdd_d) at the time or times t, each (..., n)."""
        amplitude, omega, phase, offset = self.arrays(_joints(n))
        angle = omega * _times(t)[..., None] + phase
        return (
            offset + amplitude * np.sin(angle),
            amplitude * omega * np.cos(angle),
            -amplitude * omega**2 * np.sin(angle),
        )


@njit(inline="always", **NUMBA_OPTIONS)
def sinusoid_at(params: np.ndarray, i: int, t: float, out: np.ndarray) -> None:
    """Joint i of a Sinusoid packed by ``arrays``: out[:, i] = q_d, qd_d, qdd_d."""
    amplitude, omega, phase, offset = params[0, i], params[1, i], params[2, i], params[3, i]
    sine, cosine = sin_cos(omega * t + phase)
    out[0, i] = offset + amplitude * sine
    out[1, i] = amplitude * omega * cosine
    out[2, i] = -amplitude * omega * omega * sine


def quintic_blend(u: T) -> tuple[T, T, T]:
    """The quintic time law of a rest-to-rest move (Lewis, Dawson and Abdallah 2004, Section 4.2):
    s(u) = 10 u^3 - 15 u^4 + 6 u^5 with ds/du and d^2s/du^2, for u in [0, 1] (a float or an array); the
    one home of the law, compiled as ``compiled_quintic_blend``."""
    return 10 * u**3 - 15 * u**4 + 6 * u**5, 30 * u**2 - 60 * u**3 + 30 * u**4, 60 * u - 180 * u**2 + 120 * u**3


compiled_quintic_blend = cast(
    Callable[[float], tuple[float, float, float]], njit(inline="always", **NUMBA_OPTIONS)(quintic_blend)
)


@dataclass(frozen=True)
class Quintic:
    """A point-to-point move from q0 at t0 to q1 at t1, at rest at both ends (a quintic in time)."""

    q0: object
    q1: object
    t0: float = 0.0
    t1: float = 1.0

    def __post_init__(self) -> None:
        t0, t1 = (inputs.number(value, name, " in a Quintic") for name, value in (("t0", self.t0), ("t1", self.t1)))
        if not t1 > t0:
            raise ModelError(f"a Quintic needs t1 > t0, got t0 = {self.t0}, t1 = {self.t1}")

    def arrays(self, n: int | None) -> np.ndarray:
        """(4, n): q0, q1, t0, t1 (n None: as many joints as the longer of q0 and q1)."""
        q0, q1 = _per_joint("Quintic", {"q0": self.q0, "q1": self.q1}, n)
        n = q0.shape[0]
        return np.stack([q0, q1, np.full(n, float(self.t0)), np.full(n, float(self.t1))])

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_d, qd_d, qdd_d) at the time or times t, each (..., n): at rest outside [t0, t1]."""
        q0, q1, t0, t1 = self.arrays(_joints(n))
        times = _times(t)[..., None]
        span = t1 - t0
        if span[0] < SHORTEST_SPAN:
            return _short_move(q0, q1, times, t0, span)
        shape, slope, curvature = quintic_blend(np.clip((times - t0) / span, 0.0, 1.0))
        rate = slope / span
        accel = curvature / span**2
        return q0 + (q1 - q0) * shape, (q1 - q0) * rate, (q1 - q0) * accel


def _short_move(q0: np.ndarray, q1: np.ndarray, times: np.ndarray, t0: np.ndarray, span: np.ndarray) -> tuple:
    """A Quintic over less than SHORTEST_SPAN seconds, where span**2 underflows: the same
    polynomials divided by span twice, float overflow let through to infinity, then refused if any
    (the rates inside so brief a move exceed the float range); at rest outside it."""
    with np.errstate(over="ignore", invalid="ignore"):
        shape, slope, curvature = quintic_blend(np.clip((times - t0) / span, 0.0, 1.0))
        rate = (q1 - q0) * (slope / span)
        accel = (q1 - q0) * (curvature / span / span)
    if not (np.all(np.isfinite(rate)) and np.all(np.isfinite(accel))):
        raise ModelError(
            f"t falls inside a Quintic move of only t1 - t0 = {span[0]:g} s: its velocity or acceleration "
            "there exceeds the float range"
        )
    return q0 + (q1 - q0) * shape, rate, accel


@njit(inline="always", **NUMBA_OPTIONS)
def quintic_at(params: np.ndarray, i: int, t: float, out: np.ndarray) -> None:
    """Joint i of a Quintic packed by ``arrays``: out[:, i] = q_d, qd_d, qdd_d."""
    a, b, t0, t1 = params[0, i], params[1, i], params[2, i], params[3, i]
    span = t1 - t0
    shape, slope, curvature = compiled_quintic_blend(min(max((t - t0) / span, 0.0), 1.0))
    out[0, i] = a + (b - a) * shape
    out[1, i] = (b - a) * slope / span
    out[2, i] = (b - a) * curvature / span**2


@dataclass(frozen=True)
class CartesianCircle:
    """The tool of a two-link planar arm (Example 3.2-2 geometry) on a circle (Example 4.2-1).

    centre (x, y), radius, period in seconds; joint values by the arm's inverse kinematics
    (elbow down, or up with elbow_up=True), velocities by J^-1 ydot and accelerations by
    J^-1 (yddot - Jdot qd).
    """

    a1: float
    a2: float
    centre: tuple[float, float]
    radius: float
    period: float
    elbow_up: bool = False

    def __post_init__(self) -> None:
        where = " in a CartesianCircle"
        for name in ("a1", "a2", "radius", "period"):
            value = inputs.number(getattr(self, name), name, where)
            if value < 0 or (value == 0 and name != "radius"):
                raise ModelError(f"{name} must be {'at least 0' if name == 'radius' else 'positive'}{where}, "
                                 f"got {value:g}")  # fmt: skip
        inputs.numbers(self.centre, "centre", (2,), where)

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_d, qd_d, qdd_d) at the time or times t, each (..., 2); a ModelError where the circle
        leaves the workspace, meets its boundary (J singular) or its rates exceed the float range."""
        if _joints(n) not in (None, 2):
            raise ModelError(f"n must be 2 for a CartesianCircle (a two-link planar arm), got {n}")
        t = _times(t)
        with np.errstate(all="ignore"):  # overflow (tiny period, huge t) becomes inf, refused below
            path = self._path(t)
        if not all(np.all(np.isfinite(part)) for part in path):
            raise ModelError("the circle's joint rates exceed the float range (period too short for its radius?)")
        return path

    def _path(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q_d, qd_d, qdd_d by inverse kinematics, J^-1 ydot and J^-1 (yddot - Jdot qd)."""
        w = 2 * np.pi / self.period
        x = self.centre[0] + self.radius * np.cos(w * t)
        y = self.centre[1] + self.radius * np.sin(w * t)
        xd, yd = -self.radius * w * np.sin(w * t), self.radius * w * np.cos(w * t)
        xdd, ydd = -(w**2) * (x - self.centre[0]), -(w**2) * (y - self.centre[1])
        a1, a2 = self.a1, self.a2
        c2 = (x**2 + y**2 - a1**2 - a2**2) / (2 * a1 * a2)
        if not np.all(np.abs(c2) <= 1):  # NaN fails too
            raise ModelError("the circle leaves the arm's workspace")
        s2 = np.sqrt(1 - c2**2) * (1.0 if self.elbow_up else -1.0)
        q2 = np.arctan2(s2, c2)
        q1 = np.arctan2(y, x) - np.arctan2(a2 * s2, a1 + a2 * c2)
        s1, c1 = np.sin(q1), np.cos(q1)
        s12, c12 = np.sin(q1 + q2), np.cos(q1 + q2)
        J = np.array([[-a1 * s1 - a2 * s12, -a2 * s12], [a1 * c1 + a2 * c12, a2 * c12]])
        J = np.moveaxis(J, (0, 1), (-2, -1))
        try:
            qd = np.linalg.solve(J, np.stack([xd, yd], -1)[..., None])[..., 0]
        except np.linalg.LinAlgError:
            raise ModelError("the circle meets the boundary of the arm's workspace, where J is singular") from None
        q1d, q2d = qd[..., 0], qd[..., 1]
        jdot_qd = np.stack(
            [
                -a1 * c1 * q1d**2 - a2 * c12 * (q1d + q2d) ** 2,
                -a1 * s1 * q1d**2 - a2 * s12 * (q1d + q2d) ** 2,
            ],
            -1,
        )
        qdd = np.linalg.solve(J, (np.stack([xdd, ydd], -1) - jdot_qd)[..., None])[..., 0]
        return np.stack([q1, q2], -1), qd, qdd


@njit(inline="always", **NUMBA_OPTIONS)
def desired(kind: int, params: np.ndarray, t: float, q0: np.ndarray, out: np.ndarray) -> None:
    """The compiled trajectories: out rows q_d, qd_d, qdd_d at time t (HOLD keeps q0)."""
    for i in range(q0.shape[0]):
        if kind == SINUSOID:
            sinusoid_at(params, i, t, out)
        elif kind == QUINTIC:
            quintic_at(params, i, t, out)
        else:
            out[0, i] = q0[i]
            out[1, i] = 0.0
            out[2, i] = 0.0


def packed(trajectory: object, n: int) -> tuple[int, np.ndarray] | None:
    """(kind, params) of a trajectory the compiled loop runs, or None for any other callable."""
    if trajectory is None:
        return HOLD, np.zeros((4, n))
    if isinstance(trajectory, Sinusoid):
        return SINUSOID, trajectory.arrays(n)
    if isinstance(trajectory, Quintic):
        return QUINTIC, trajectory.arrays(n)
    return None


def describe_trajectory(trajectory: object) -> str:
    """A short description of a trajectory for titles and reports."""
    if trajectory is None:
        return "hold the start"
    if isinstance(trajectory, Sinusoid):
        return "sinusoid"
    if isinstance(trajectory, Quintic):
        return f"quintic move in {float(trajectory.t1) - float(trajectory.t0):g} s"
    if isinstance(trajectory, CartesianCircle):
        return f"circle of radius {trajectory.radius:g} m"
    return getattr(trajectory, "__name__", type(trajectory).__name__)
