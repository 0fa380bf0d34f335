"""armdyn: the dynamics of robot manipulators (Lewis, Dawson and Abdallah, Chapter 3)."""

from armdyn import kinematics
from armdyn.dynamics import lagrange
from armdyn.errors import ModelError
from armdyn.model import Inertial, Joint, Link, Robot
from armdyn.model import catalog as models
from armdyn.model.urdf import load_urdf

__version__ = "0.1.0"

__all__ = ["Inertial", "Joint", "Link", "ModelError", "Robot", "kinematics", "lagrange", "load_urdf", "models"]
