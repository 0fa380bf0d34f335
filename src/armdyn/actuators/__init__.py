"""Actuator dynamics and the arm-plus-actuator system (Lewis, Dawson and Abdallah 2004, Section 3.6).

``motors``: the DC motor behind a gear (rigid or flexible shaft), its transfer function and Example
3.6-1; ``hydraulics``: the servo valve and piston; ``arm``: the arm with a drive on every joint
(``ActuatedArm``, ``with_actuators``, ``motor_drives``, the PUMA 560 with its drives); ``sizing``:
representative drives for an arm; ``packing``: the drives as the compiled stepper takes them (the arm with
its drives is simulated by ``armdyn.simulate``, under a drive-level law of armdyn.control.drives).
"""

from armdyn.actuators.arm import (
    PUMA560_ELECTRICS,
    ActuatedArm,
    Drive,
    motor_drives,
    puma560_with_drives,
    with_actuators,
)
from armdyn.actuators.hydraulics import Hydraulic
from armdyn.actuators.motors import DCMotor, example_3_6_1, transfer_function
from armdyn.actuators.packing import DriveRecord, stable_step
from armdyn.actuators.sizing import representative_drives

__all__ = [
    "PUMA560_ELECTRICS",
    "ActuatedArm",
    "DCMotor",
    "Drive",
    "DriveRecord",
    "Hydraulic",
    "example_3_6_1",
    "motor_drives",
    "puma560_with_drives",
    "representative_drives",
    "stable_step",
    "transfer_function",
    "with_actuators",
]
