"""armdyn: the dynamics of robot manipulators (Lewis, Dawson and Abdallah, Chapter 3)."""

from armdyn import kinematics
from armdyn.dynamics import lagrange
from armdyn.dynamics.regressor import base_parameters, identify
from armdyn.errors import ModelError
from armdyn.model import Inertial, Joint, Link, Robot
from armdyn.model import catalog as models
from armdyn.model.urdf import load_urdf

__version__ = "0.1.0"


def __getattr__(name: str) -> object:
    """armdyn.symbolic and armdyn.properties load on first use (SymPy and SciPy take a moment)."""
    if name in ("symbolic", "properties"):
        import importlib

        return importlib.import_module(f"armdyn.{name}")
    raise AttributeError(f"module 'armdyn' has no attribute '{name}'")


__all__ = [
    "Inertial",
    "Joint",
    "Link",
    "ModelError",
    "Robot",
    "base_parameters",
    "identify",
    "kinematics",
    "lagrange",
    "load_urdf",
    "models",
]
