"""Desired trajectories q_d(t) with their velocities and accelerations (Chapter 4).

Each trajectory is called as ``trajectory(t)`` and returns (q_d, qd_d, qdd_d); t may be a
scalar or an array of times (leading axis); any such callable is a trajectory. The sinusoid
and the quintic also pack into numbers (``arrays``) for their compiled form (``desired``),
which the compiled simulation loop runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from armdyn.dynamics.spatial import NUMBA_OPTIONS, sin_cos
from armdyn.errors import ModelError
from armdyn.inputs import vector as _vector

HOLD, SINUSOID, QUINTIC = 0, 1, 2


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

    def arrays(self, n: int) -> np.ndarray:
        """(4, n): amplitude, angular frequency, phase, offset, broadcast to n joints."""
        parts = [
            _vector(v, k) for k, v in zip(("amplitude", "frequency", "phase", "offset"), self._values(), strict=True)
        ]
        try:
            packed = np.stack([np.broadcast_to(p, (n,)) for p in parts])
        except ValueError:
            raise ModelError(f"a Sinusoid's arrays must have 1 or {n} values") from None
        packed = packed.copy()
        packed[1] *= 2 * np.pi
        return packed

    def _values(self) -> tuple:
        return self.amplitude, self.frequency, self.phase, self.offset

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        amplitude, omega, phase, offset = self.arrays(n or _width(self._values()))
        angle = omega * np.asarray(t, dtype=float)[..., None] + phase
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


@dataclass(frozen=True)
class Quintic:
    """A point-to-point move from q0 at t0 to q1 at t1, at rest at both ends (a quintic in time)."""

    q0: object
    q1: object
    t0: float = 0.0
    t1: float = 1.0

    def __post_init__(self) -> None:
        if not self.t1 > self.t0:
            raise ModelError(f"a Quintic needs t1 > t0, got t0 = {self.t0}, t1 = {self.t1}")

    def arrays(self, n: int) -> np.ndarray:
        """(4, n): q0, q1, t0, t1."""
        try:
            q0, q1 = (np.broadcast_to(_vector(v, "q0/q1"), (n,)) for v in (self.q0, self.q1))
        except ValueError:
            raise ModelError(f"a Quintic's q0 and q1 must have 1 or {n} values") from None
        return np.stack([q0, q1, np.full(n, float(self.t0)), np.full(n, float(self.t1))])

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q0, q1, t0, t1 = self.arrays(n or _width((self.q0, self.q1)))
        span = t1 - t0
        s = np.clip((np.asarray(t, dtype=float)[..., None] - t0) / span, 0.0, 1.0)
        shape = 10 * s**3 - 15 * s**4 + 6 * s**5
        rate = (30 * s**2 - 60 * s**3 + 30 * s**4) / span
        accel = (60 * s - 180 * s**2 + 120 * s**3) / span**2
        return q0 + (q1 - q0) * shape, (q1 - q0) * rate, (q1 - q0) * accel


@njit(inline="always", **NUMBA_OPTIONS)
def quintic_at(params: np.ndarray, i: int, t: float, out: np.ndarray) -> None:
    """Joint i of a Quintic packed by ``arrays``: out[:, i] = q_d, qd_d, qdd_d."""
    a, b, t0, t1 = params[0, i], params[1, i], params[2, i], params[3, i]
    span = t1 - t0
    s = min(max((t - t0) / span, 0.0), 1.0)
    out[0, i] = a + (b - a) * (10 * s**3 - 15 * s**4 + 6 * s**5)
    out[1, i] = (b - a) * (30 * s**2 - 60 * s**3 + 30 * s**4) / span
    out[2, i] = (b - a) * (60 * s - 180 * s**2 + 120 * s**3) / span**2


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

    def __call__(self, t: object, n: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        w = 2 * np.pi / self.period
        x = self.centre[0] + self.radius * np.cos(w * t)
        y = self.centre[1] + self.radius * np.sin(w * t)
        xd, yd = -self.radius * w * np.sin(w * t), self.radius * w * np.cos(w * t)
        xdd, ydd = -(w**2) * (x - self.centre[0]), -(w**2) * (y - self.centre[1])
        a1, a2 = self.a1, self.a2
        c2 = (x**2 + y**2 - a1**2 - a2**2) / (2 * a1 * a2)
        if np.any(np.abs(c2) > 1):
            raise ModelError("the circle leaves the arm's workspace")
        s2 = np.sqrt(1 - c2**2) * (1.0 if self.elbow_up else -1.0)
        q2 = np.arctan2(s2, c2)
        q1 = np.arctan2(y, x) - np.arctan2(a2 * s2, a1 + a2 * c2)
        s1, c1 = np.sin(q1), np.cos(q1)
        s12, c12 = np.sin(q1 + q2), np.cos(q1 + q2)
        J = np.array([[-a1 * s1 - a2 * s12, -a2 * s12], [a1 * c1 + a2 * c12, a2 * c12]])
        J = np.moveaxis(J, (0, 1), (-2, -1))
        qd = np.linalg.solve(J, np.stack([xd, yd], -1)[..., None])[..., 0]
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


def _width(values: tuple) -> int:
    return max(np.atleast_1d(np.asarray(v, dtype=float)).shape[0] for v in values)


def describe(trajectory: object) -> str:
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
