"""The exceptions armdyn raises, each a subclass of the built-in exception of its kind (as in python-control).

- ``ModelError`` (a ValueError): an arm model or an argument that breaks a physical or structural rule.
- ``ArgumentError`` (a ModelError and a TypeError): an argument of the wrong kind, such as an arm that is not
  an armdyn arm, or a symbolic arm where numbers are needed.
- ``SingularError`` (a ModelError): a state at which the arm's equations have no unique solution, M(q)
  singular or J(q) singular or too ill-conditioned.
- ``SimulationError`` (a RuntimeError): a run that could not go on; it holds the run up to then.
- ``MissingDependencyError`` (an ImportError): an optional module is not installed; it names the extra
  of armdyn that installs it.
"""

from __future__ import annotations

from typing import Any

__all__ = ["ArgumentError", "MissingDependencyError", "ModelError", "SimulationError", "SingularError"]


class ModelError(ValueError):
    """An arm model or an input that breaks a physical or structural rule.

    The message names the link (or argument) and the rule broken; armdyn never
    silently corrects a model.
    """


class ArgumentError(ModelError, TypeError):
    """An argument of the wrong kind: an arm that is not an armdyn arm, a symbolic arm where numbers are needed,
    a controller or trajectory of another kind than the function takes.

    Both a ModelError (so that one ``except armdyn.ModelError`` catches every bad input) and a TypeError
    (what Python raises for an argument of the wrong type).
    """


class SingularError(ModelError):
    """A state at which a matrix the computation inverts is singular (M(q), or J(q) in task space).

    Parameters
    ----------
    message : str
        What is singular, where, and what to change.
    state : object, optional
        The state: the configuration q, or its index in a batch of states.
    joint : str, optional
        The joint about which nothing moves (M singular), when one is known.
    condition : float, optional
        The condition number of the matrix at the state (``inf`` when exactly singular).
    """

    def __init__(
        self, message: str, *, state: Any = None, joint: str | None = None, condition: float | None = None
    ) -> None:
        super().__init__(message)
        self.state = state
        self.joint = joint
        self.condition = condition

    def __reduce__(self) -> tuple[Any, ...]:  # pickled with its attributes (Dask sends errors between processes)
        return _rebuild, (type(self), self.args, self.__dict__)


class SimulationError(RuntimeError):
    """A run that could not go on: M(q) became singular or the state non-finite (a diverging closed loop).

    Parameters
    ----------
    message : str
        When the run stopped, which joint, and why.
    result : object
        The run up to the last good sample (a simulation result).
    """

    def __init__(self, message: str, result: Any) -> None:
        super().__init__(message)
        self.result = result

    def __reduce__(self) -> tuple[Any, ...]:
        return _rebuild, (type(self), self.args, self.__dict__)


class MissingDependencyError(ImportError):
    """An optional module that a function needs is not installed.

    The message names the module, what needs it, and the command that installs it:
    ``pip install 'armdyn[extra]'``, with ``extra`` one of the extras of pyproject.toml.

    Parameters
    ----------
    module : str
        The module that could not be imported (``"control"``, ``"dask.distributed"``).
    extra : str
        The extra of armdyn that installs it (``"control"``, ``"cluster"``, ``"casadi"``, ``"jax"``, ``"test"``,
        ``"bench"``, ``"docs"``).
    needed_by : str, optional
        What needs it, for the message (``"armdyn.control.lqr"``).
    """

    def __init__(self, module: str, extra: str, needed_by: str | None = None) -> None:
        what = f"{needed_by} needs" if needed_by else "this needs"
        super().__init__(
            f"{what} the optional module '{module}', which is not installed: pip install 'armdyn[{extra}]'",
            name=module,
        )
        self.module = module
        self.extra = extra
        self.needed_by = needed_by

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.module, self.extra, self.needed_by)


def _rebuild(cls: type[BaseException], args: tuple[Any, ...], state: dict[str, Any]) -> BaseException:
    """An exception of ``cls`` with ``args`` and the attributes ``state``, without calling its __init__."""
    error = cls.__new__(cls, *args)
    error.args = args
    error.__dict__.update(state)
    return error
