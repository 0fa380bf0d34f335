"""armdyn: the dynamics of robot manipulators (Lewis, Dawson and Abdallah, Chapter 3)."""

from armdyn import kinematics
from armdyn import models as models
from armdyn.dynamics import lagrange
from armdyn.dynamics.regressor import base_parameters
from armdyn.dynamics.threads import set_threads, threads
from armdyn.errors import ArgumentError, MissingDependencyError, ModelError, SimulationError, SingularError
from armdyn.identification import identify
from armdyn.io.mjcf import from_mujoco, load_mjcf
from armdyn.model import ArmModel, Inertial, Joint, Link
from armdyn.robot import Robot
from armdyn.urdf import load_urdf

__version__ = "0.1.0"


_LAZY_MODULES = (
    "actuators",
    "task_space",
    "symbolic",
    "properties",
    "statespace",
    "control",
    "trajectories",
    "simulation",
    "study",
    "plotting",
    "identification",
    "io",
)


def __getattr__(name: str) -> object:
    """The heavier parts load on first use: armdyn.symbolic (SymPy), armdyn.properties (SciPy),
    armdyn.actuators, armdyn.simulation and its companions; ``armdyn.simulate``
    are armdyn.simulation's."""
    import importlib

    if name in _LAZY_MODULES:
        return importlib.import_module(f"armdyn.{name}")
    if name == "simulate":
        return getattr(importlib.import_module("armdyn.simulation"), name)
    if name == "load_arm":
        return importlib.import_module("armdyn.io.model_file").load_arm
    import difflib

    known = sorted({*__all__, *_LAZY_MODULES, "simulate", "load_arm", "__version__"})
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.7)
    hint = f": did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
    raise AttributeError(f"module 'armdyn' has no attribute '{name}'{hint}")


__all__ = [
    "ArgumentError",
    "ArmModel",
    "Inertial",
    "Joint",
    "Link",
    "MissingDependencyError",
    "ModelError",
    "Robot",
    "SimulationError",
    "SingularError",
    "base_parameters",
    "from_mujoco",
    "identify",
    "kinematics",
    "lagrange",
    "load_mjcf",
    "load_urdf",
    "models",
    "set_threads",
    "threads",
]
