"""What a robot is: inertials, joints, links, the Robot, URDF import, the built-in arms."""

from armdyn.model.inertial import Inertial
from armdyn.model.joint import Joint, dh_joint
from armdyn.model.robot import Link, Robot

__all__ = ["Inertial", "Joint", "Link", "Robot", "dh_joint"]
