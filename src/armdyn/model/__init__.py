"""What an arm is: mass properties, joints, links and the ArmModel tree. Data and validation only."""

from armdyn.model.arm import ArmModel, Link
from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint, dh_joint

__all__ = ["ArmModel", "Inertial", "Joint", "Link", "dh_joint"]
