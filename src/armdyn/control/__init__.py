"""Controllers (Chapter 4 and Sections 3.4 to 3.6): ``joint`` holds the joint-space laws (computed
torque, PD plus gravity, PID, digital, saturated), each beside its compiled law; ``task`` the laws in
task coordinates (computed torque on a square output, operational-space control); ``drives`` the laws
on the drives' inputs of an arm with actuators."""

from armdyn.control.drives import CurrentComputedTorque, DrivePID, VoltagePD
from armdyn.control.joint import (
    COMPUTED_TORQUE,
    KI,
    KP,
    KV,
    LIMIT,
    NO_CONTROL,
    PD_GRAVITY,
    PID,
    PID_JOINT,
    ComputedTorque,
    Digital,
    PDGravity,
    Saturated,
    Spec,
    accepts,
    call,
    computed_torque_law,
    control_law,
    describe_controller,
    pd_gravity_law,
    pid_law,
)
from armdyn.control.task import OperationalSpaceControl, TaskComputedTorque, Tracking

__all__ = [
    "COMPUTED_TORQUE",
    "KI",
    "KP",
    "KV",
    "LIMIT",
    "NO_CONTROL",
    "PD_GRAVITY",
    "PID",
    "PID_JOINT",
    "ComputedTorque",
    "CurrentComputedTorque",
    "Digital",
    "DrivePID",
    "OperationalSpaceControl",
    "PDGravity",
    "Saturated",
    "Spec",
    "TaskComputedTorque",
    "Tracking",
    "VoltagePD",
    "accepts",
    "call",
    "computed_torque_law",
    "control_law",
    "describe_controller",
    "pd_gravity_law",
    "pid_law",
]
