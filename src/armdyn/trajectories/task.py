"""Paths in task coordinates y_d(t) with their velocities and accelerations (Example 4.2-1): a circle,
a straight line and a tool-pose line, each with a quintic time law (Lewis, Dawson and
Abdallah 2004, Sections 3.5 and 4.2)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from armdyn import inputs
from armdyn.errors import ModelError
from armdyn.trajectories.joint import quintic_blend


@dataclass(frozen=True)
class Circle:
    """A circle in task coordinates (Example 4.2-1): y_d = c + r [cos wt, sin wt] in the first
    two coordinates, w = 2 pi / period, with its velocity and acceleration; a third coordinate
    of the centre, if given, is held (a circle parallel to the x-y plane, for ToolPosition).

    Parameters
    ----------
    centre : sequence of 2 or 3 float
        The centre c (m).
    radius : float
        The radius r (m), at least 0.
    period : float
        The time of one turn (s), positive.
    """

    centre: tuple[float, ...]
    radius: float
    period: float

    def __post_init__(self) -> None:
        centre = inputs.numbers(self.centre, "centre", None, " of a Circle")
        if centre.shape not in ((2,), (3,)):
            raise ModelError(f"centre of a Circle must have 2 or 3 coordinates, got shape {centre.shape}")
        object.__setattr__(self, "centre", tuple(centre))
        object.__setattr__(self, "radius", inputs.number(self.radius, "radius", " of a Circle", minimum=0.0))
        if not inputs.number(self.period, "period", " of a Circle") > 0:
            raise ModelError(f"period of a Circle must be positive, got {self.period!r}")

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y_d, yd_d, ydd_d) at time t (s), each of the centre's length.

        Parameters
        ----------
        t : float
            The time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The desired position, velocity and acceleration.

        Raises
        ------
        armdyn.ModelError
            When ``t`` is not a finite number.
        """
        w = 2.0 * np.pi / self.period
        angle = w * inputs.number(t, "t")
        ring, turn = np.zeros(len(self.centre)), np.zeros(len(self.centre))
        ring[:2], turn[:2] = (np.cos(angle), np.sin(angle)), (-np.sin(angle), np.cos(angle))
        return np.array(self.centre) + self.radius * ring, self.radius * w * turn, -self.radius * w * w * ring


def _quintic(t: float, start_time: float, duration: float) -> tuple[float, float, float]:
    """s(t) = 10 u^3 - 15 u^4 + 6 u^5, u = (t - t0) / T held in [0, 1], with its first two rates."""
    u = min(max((t - start_time) / duration, 0.0), 1.0)
    s, slope, curvature = quintic_blend(u)
    if u in (0.0, 1.0):
        return s, 0.0, 0.0
    return s, slope / duration, curvature / duration**2


@dataclass(frozen=True)
class Line:
    """A straight line in task coordinates with a quintic time law: y_d = a + s(t) (b - a),
    s = 10 u^3 - 15 u^4 + 6 u^5, u = (t - start_time) / duration held in [0, 1], so the motion
    starts and stops with zero velocity and acceleration.

    Parameters
    ----------
    start, end : sequence of float
        The end points a and b, of the output's length m (m for positions).
    duration : float
        The time of the motion (s), positive.
    start_time : float, optional
        When the motion starts (s); default 0. Before it y_d = a, after it y_d = b.
    """

    start: tuple[float, ...]
    end: tuple[float, ...]
    duration: float
    start_time: float = 0.0

    def __post_init__(self) -> None:
        start = inputs.numbers(self.start, "start", None, " of a Line")
        end = inputs.numbers(self.end, "end", None, " of a Line")
        if start.ndim != 1 or end.shape != start.shape or not start.size:
            raise ModelError(f"start and end of a Line must be two points of one length, got shapes {start.shape} "
                             f"and {end.shape}")  # fmt: skip
        object.__setattr__(self, "start", tuple(start))
        object.__setattr__(self, "end", tuple(end))
        if not inputs.number(self.duration, "duration", " of a Line") > 0:
            raise ModelError(f"duration of a Line must be positive, got {self.duration!r}")
        object.__setattr__(self, "start_time", inputs.number(self.start_time, "start_time", " of a Line"))

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y_d, yd_d, ydd_d) at time t (s), each (m,).

        Parameters
        ----------
        t : float
            The time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The desired position, velocity and acceleration.

        Raises
        ------
        armdyn.ModelError
            When ``t`` is not a finite number.
        """
        s, sd, sdd = _quintic(inputs.number(t, "t"), self.start_time, self.duration)
        a, b = np.array(self.start), np.array(self.end)
        return a + s * (b - a), sd * (b - a), sdd * (b - a)


def _pose(pose: object, name: str) -> np.ndarray:
    """A checked 4 x 4 homogeneous pose: finite, a proper rotation to 1e-6, last row [0, 0, 0, 1]."""
    T = inputs.numbers(pose, name, (4, 4), " of a PoseLine")
    R = T[:3, :3]
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0 or np.abs(T[3] - [0, 0, 0, 1]).max() > 0:
        raise ModelError(f"{name} of a PoseLine must be a homogeneous pose: a rotation (R R^T = I, det R = 1) and "
                         "the last row [0, 0, 0, 1]")  # fmt: skip
    return T


@dataclass(frozen=True)
class PoseLine:
    """A tool pose path for ToolPose: the position on the straight line from the start pose to the
    end pose, the rotation about one fixed world axis, both with the quintic law of ``Line``.

    R_d(t) = exp(s(t) [u]x) R_a with u the rotation vector of R_b R_a^T; the angular velocity is
    sdot u and the angular acceleration sddot u (world axes). Gives (y_d, yd_d, ydd_d) in ToolPose's
    coordinates: y_d = [p; rotation vector of R_d], yd_d = [v; w], ydd_d = [a; alpha].

    Parameters
    ----------
    start, end : array_like
        The 4 x 4 homogeneous start and end poses (e.g. from ``arm.tool_pose(q)``).
    duration : float
        The time of the motion (s), positive.
    start_time : float, optional
        When the motion starts (s); default 0.
    """

    start: np.ndarray
    end: np.ndarray
    duration: float
    start_time: float = 0.0
    if TYPE_CHECKING:  # at run time no field: the rotation vector of R_b R_a^T, set by __post_init__
        _axis: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        from scipy.spatial.transform import Rotation

        start, end = _pose(self.start, "start"), _pose(self.end, "end")
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "end", end)
        if not inputs.number(self.duration, "duration", " of a PoseLine") > 0:
            raise ModelError(f"duration of a PoseLine must be positive, got {self.duration!r}")
        object.__setattr__(self, "start_time", inputs.number(self.start_time, "start_time", " of a PoseLine"))
        object.__setattr__(self, "_axis", Rotation.from_matrix(end[:3, :3] @ start[:3, :3].T).as_rotvec())

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y_d, yd_d, ydd_d) at time t (s), each (6,).

        Parameters
        ----------
        t : float
            The time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The desired pose [p; rotation vector], twist [v; w] and its rate.

        Raises
        ------
        armdyn.ModelError
            When ``t`` is not a finite number.
        """
        from scipy.spatial.transform import Rotation

        s, sd, sdd = _quintic(inputs.number(t, "t"), self.start_time, self.duration)
        a, b, u = self.start[:3, 3], self.end[:3, 3], self._axis
        R = Rotation.from_rotvec(s * u).as_matrix() @ self.start[:3, :3]
        y = np.concatenate([a + s * (b - a), Rotation.from_matrix(R).as_rotvec()])
        return y, np.concatenate([sd * (b - a), sd * u]), np.concatenate([sdd * (b - a), sdd * u])
