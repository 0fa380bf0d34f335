"""Task-space (Cartesian) dynamics: the robot equation in the coordinates of an output y = h(q).

Lewis, Dawson and Abdallah 2004, Section 3.5 (Example 3.5-1) and Khatib 1987. ``outputs``: the task
outputs y = h(q), the condition number of J and the damped inverse; ``quantities``: Mbar, Vmbar,
Gbar, Nbar and the task-space forward and inverse dynamics of a square output; ``operational``:
Khatib's operational space of an output with m <= n.
"""

from armdyn.task_space.operational import OperationalSpace, operational_coriolis, operational_inertia, operational_space
from armdyn.task_space.outputs import (
    DEFAULT_MAX_CONDITION,
    Camera,
    LinkPoint,
    Output,
    PlanarPosition,
    TaskOutput,
    ToolPose,
    ToolPosition,
    condition_number,
    damped_inverse,
)
from armdyn.task_space.quantities import (
    task_coriolis,
    task_force,
    task_forward_dynamics,
    task_friction,
    task_gravity,
    task_inertia,
    task_inverse_dynamics,
    task_nonlinear,
    task_regressor,
)

__all__ = [
    "DEFAULT_MAX_CONDITION",
    "Camera",
    "LinkPoint",
    "OperationalSpace",
    "Output",
    "PlanarPosition",
    "TaskOutput",
    "ToolPose",
    "ToolPosition",
    "condition_number",
    "damped_inverse",
    "operational_coriolis",
    "operational_inertia",
    "operational_space",
    "task_coriolis",
    "task_force",
    "task_forward_dynamics",
    "task_friction",
    "task_gravity",
    "task_inertia",
    "task_inverse_dynamics",
    "task_nonlinear",
    "task_regressor",
]
