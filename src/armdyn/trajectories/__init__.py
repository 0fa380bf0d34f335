"""Desired motions: joint trajectories q_d(t) (``joint``: a sinusoid and a quintic move, each beside its
compiled form, and a circle of a planar arm's tool by inverse kinematics) and paths in task
coordinates y_d(t) (``task``: a circle, a line and a tool-pose line)."""

from armdyn.trajectories.joint import (
    HOLD,
    QUINTIC,
    SHORTEST_SPAN,
    SINUSOID,
    CartesianCircle,
    Quintic,
    Sinusoid,
    describe_trajectory,
    desired,
    packed,
    quintic_at,
    sinusoid_at,
)
from armdyn.trajectories.task import Circle, Line, PoseLine

__all__ = [
    "HOLD",
    "QUINTIC",
    "SHORTEST_SPAN",
    "SINUSOID",
    "CartesianCircle",
    "Circle",
    "Line",
    "PoseLine",
    "Quintic",
    "Sinusoid",
    "describe_trajectory",
    "desired",
    "packed",
    "quintic_at",
    "sinusoid_at",
]
