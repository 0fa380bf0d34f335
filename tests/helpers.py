"""What several test files share: example-robot-data's URDFs and their Pinocchio twins, the command line
called in-process, exciting joint trajectories, and the reading of numpydoc docstrings.

Fixtures live in conftest.py; random arms for property tests live in strategies.py.
"""

from __future__ import annotations

import inspect
import re
import sysconfig
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from types import FunctionType, ModuleType
from typing import TYPE_CHECKING

import numpy as np

import armdyn

if TYPE_CHECKING:
    import pinocchio as pin

# ----- example-robot-data and Pinocchio ------------------------------------------------------------------------
ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
URDFS = {
    "panda": ROBOTS / "panda_description" / "urdf" / "panda.urdf",
    "ur5": ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf",
}


def pinocchio_pair(path: Path):
    """(armdyn arm, pinocchio model, pinocchio data, q index map, v index map), joints mapped by name."""
    import warnings

    import pinocchio as pin

    import armdyn as ad

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(path)
    model = pin.buildModelFromUrdf(str(path))
    ids = [model.getJointId(name) for name in arm.joint_names]
    q_index = np.array([model.joints[i].idx_q for i in ids])
    v_index = np.array([model.joints[i].idx_v for i in ids])
    return arm, model, model.createData(), q_index, v_index


def pin_q(model: pin.Model, ids: list[int], q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration for armdyn's q (continuous joints are (cos, sin) there)."""
    import pinocchio as pin

    config = pin.neutral(model)
    for value, joint_id in zip(q, ids, strict=True):
        joint = model.joints[joint_id]
        if joint.nq == 2:
            config[joint.idx_q : joint.idx_q + 2] = np.cos(value), np.sin(value)
        else:
            config[joint.idx_q] = value
    return config


# ----- trajectories ---------------------------------------------------------------------------------------------
def exciting(n: int, samples: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 10, samples, endpoint=False)[:, None, None]
    k = np.arange(1, 6)[None, None, :] * 2 * np.pi / 10
    a, b = rng.normal(0, 0.1, (2, 1, n, 5))
    return (
        (a * np.sin(k * t) + b * np.cos(k * t)).sum(-1),
        (k * (a * np.cos(k * t) - b * np.sin(k * t))).sum(-1),
        (-(k**2) * (a * np.sin(k * t) + b * np.cos(k * t))).sum(-1),
    )


# ----- the command line -----------------------------------------------------------------------------------------
def assert_one_error_line(result: object, *fragments: str) -> str:
    """A non-zero exit with exactly one line on stderr, 'error: ...', containing the fragments."""
    assert result.exit_code != 0, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def invoke(*args: str) -> object:
    from typer.testing import CliRunner

    from armdyn.cli import app

    return CliRunner().invoke(app, [str(arg) for arg in args], prog_name="armdyn")


# ----- numpydoc docstrings --------------------------------------------------------------------------------------
SKIPPED_KINDS = (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
_UNDERLINE = re.compile(r"^-{3,}\s*$")


@dataclass
class Item:
    """One callable to check: how the test names it, the callable and what it must document."""

    label: str
    target: Callable
    docstring: str
    signature: inspect.Signature | None
    needs_returns: bool
    needs_raises: bool


def _public_names(module: ModuleType) -> list[str]:
    names = getattr(module, "__all__", None)
    if names is None:
        names = [name for name in vars(module) if not name.startswith("_")]
    return [name for name in names if not name.startswith("_")]


def _defined_in(obj: object, module: ModuleType) -> bool:
    """Defined in this module or, for a package, in one of its submodules (what armdyn re-exports)."""
    home = getattr(obj, "__module__", None) or ""
    return home == module.__name__ or (hasattr(module, "__path__") and home.startswith(module.__name__ + "."))


def _signature(target: Callable) -> inspect.Signature | None:
    try:
        return inspect.signature(target)
    except (TypeError, ValueError):  # builtins without a signature
        return None


def _returns_something(signature: inspect.Signature | None) -> bool:
    """False only for a return annotated None (a missing annotation counts as returning something)."""
    if signature is None:
        return False
    annotation = signature.return_annotation
    return annotation not in (None, "None", type(None))


def _label(target: Callable) -> str:
    return f"{target.__module__}.{target.__qualname__}"


def function_item(function: Callable, raises: bool) -> Item:
    signature = _signature(function)
    return Item(
        _label(function), function, inspect.getdoc(function) or "", signature, _returns_something(signature), raises
    )


def _class_items(cls: type, raises_for_own_methods: bool) -> Iterator[Item]:
    """The constructor (documented in the class docstring or __init__'s) and the public methods."""
    home = next(klass for klass in cls.__mro__ if "__init__" in vars(klass))
    if home.__module__.startswith("armdyn"):  # not an exception's or object's own constructor
        texts = (inspect.getdoc(cls), vars(home)["__init__"].__doc__)
        docstring = "\n\n".join(inspect.cleandoc(text) for text in texts if text)
        yield Item(_label(cls), cls, docstring, _signature(cls), False, False)
    for name in sorted(dir(cls)):
        if name.startswith("_"):
            continue
        static = inspect.getattr_static(cls, name)
        if isinstance(static, (classmethod, staticmethod)):
            static = static.__func__
        if not isinstance(static, FunctionType) or not static.__module__.startswith("armdyn"):
            continue  # properties, data, and anything not written in armdyn
        yield function_item(getattr(cls, name), raises_for_own_methods and name in vars(cls))


def module_items(module: ModuleType) -> Iterator[Item]:
    for name in _public_names(module):
        obj = getattr(module, name)
        if isinstance(obj, ModuleType) or not _defined_in(obj, module):
            continue  # imported names belong to the module that defines them
        if inspect.isclass(obj):
            yield from _class_items(obj, raises_for_own_methods=obj is armdyn.Robot)
        elif callable(obj):
            yield function_item(obj, raises=False)


def sections(docstring: str) -> dict[str, list[str]]:
    """numpydoc sections: title -> the lines under its underline (the summary is not a section)."""
    lines = docstring.expandtabs().splitlines()
    found: dict[str, list[str]] = {}
    current: list[str] | None = None
    index = 0
    while index < len(lines):
        line = lines[index]
        following = lines[index + 1] if index + 1 < len(lines) else ""
        if line.strip() and not line.startswith(" ") and _UNDERLINE.match(following):
            current = found.setdefault(line.strip(), [])
            index += 2
            continue
        if current is not None:
            current.append(line)
        index += 1
    return found


def has_section(docstring: str, title: str) -> bool:
    """True when the docstring has a section of that title with something in it."""
    return any(line.strip() for line in sections(docstring).get(title, []))


def documented_parameters(docstring: str) -> set[str]:
    """The names in Parameters (and Other Parameters): unindented lines, before any ' : '."""
    names: set[str] = set()
    parts = sections(docstring)
    for title in ("Parameters", "Other Parameters"):
        for line in parts.get(title, []):
            if not line.strip() or line.startswith(" "):
                continue
            head = line.split(" : ", 1)[0].rstrip(":").strip()
            names |= {name.strip().lstrip("*") for name in head.split(",") if name.strip()}
    return names


def undocumented(item: Item) -> list[str]:
    """The parameters of the signature (not self/cls, *args, **kwargs) missing from Parameters."""
    assert item.signature is not None
    wanted = [
        name
        for name, parameter in item.signature.parameters.items()
        if name not in ("self", "cls") and parameter.kind not in SKIPPED_KINDS
    ]
    return [name for name in wanted if name not in documented_parameters(item.docstring)]
