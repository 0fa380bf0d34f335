"""Every public callable documents its arguments in numpydoc form (Parameters, Returns, Raises).

The callables are found by walking the public surface, so a new public function is covered
without touching this file: every name in ``armdyn.__all__`` (the modules listed there are
walked in turn; a class contributes its constructor and its public methods, inherited ones
included, so ``Robot``'s methods, free functions of armdyn.dynamics.api, armdyn.kinematics and
armdyn.dynamics.regressor, are covered), the modules of MODULES, and the entry points of
ENTRY_POINTS, named one by one. A module's public names are its ``__all__`` or else the names
not starting with an underscore; a name counts when it is defined in that module (or, for a
package, in one of its submodules), so imported names are checked where they are defined.

The docstring parser is a small one, not numpydoc's (which armdyn does not depend on): a
section is a title line underlined with dashes; in Parameters each unindented line names one
parameter or several separated by commas (``q, qd, qdd : array_like``).
"""

from __future__ import annotations

import importlib
import inspect
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from types import FunctionType, ModuleType

import pytest

import armdyn

# Modules walked in full besides those named in armdyn.__all__.
MODULES = (
    "armdyn.symbolic",
    "armdyn.kinematics",
    "armdyn.models",
    "armdyn.statespace",
    "armdyn.properties",
    "armdyn.urdf",
    "armdyn.dynamics.regressor",
    "armdyn.model",
    "armdyn.excitation",
    "armdyn.task_space",
    "armdyn.control.task",
    "armdyn.control.drives",
    "armdyn.trajectories.task",
    "armdyn.actuators",
    "armdyn.study",
)
# Entry points named one by one (their modules are not walked in full); all of them need Raises.
ENTRY_POINTS = (
    "armdyn.load_urdf",
    "armdyn.simulation.simulate",
    "armdyn.simulation.simulate_many",
    "armdyn.simulation.plant_variants",
    "armdyn.properties.check",
    "armdyn.identify",
    "armdyn.symbolic.derive",
)
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


def _resolve(dotted: str) -> object:
    module_name, _, attribute = dotted.rpartition(".")
    return getattr(importlib.import_module(module_name), attribute)


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


def _function_item(function: Callable, raises: bool) -> Item:
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
        yield _function_item(getattr(cls, name), raises_for_own_methods and name in vars(cls))


def _module_items(module: ModuleType) -> Iterator[Item]:
    for name in _public_names(module):
        obj = getattr(module, name)
        if isinstance(obj, ModuleType) or not _defined_in(obj, module):
            continue  # imported names belong to the module that defines them
        if inspect.isclass(obj):
            yield from _class_items(obj, raises_for_own_methods=obj is armdyn.Robot)
        elif callable(obj):
            yield _function_item(obj, raises=False)


def collect() -> list[Item]:
    """Every callable to check, each once (a Robot method is also a kinematics function: merged)."""
    modules = [armdyn] + [obj for obj in (getattr(armdyn, n) for n in armdyn.__all__) if isinstance(obj, ModuleType)]
    modules += [importlib.import_module(name) for name in MODULES]
    sources: list[Item] = []
    for module in modules:
        sources += list(_module_items(module))
    for dotted in ENTRY_POINTS:
        sources.append(_function_item(_resolve(dotted), raises=True))
    merged: dict[int, Item] = {}
    for item in sources:
        key = id(getattr(item.target, "__func__", item.target))  # a classmethod bound to Robot or ArmModel
        if key in merged:
            merged[key].needs_raises |= item.needs_raises
        else:
            merged[key] = item
    return sorted(merged.values(), key=lambda item: item.label)


# ----- the parser -------------------------------------------------------------------------
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


def test_the_parser_reads_grouped_parameters_and_sections() -> None:
    doc = inspect.cleandoc(
        """Summary.

        Parameters
        ----------
        arm : Robot
            The arm.
        q, qd, qdd : array_like
            States,
            over two lines.
        out

        Returns
        -------
        numpy.ndarray
            tau.

        Raises
        ------
        ModelError
            When.
        """
    )
    assert documented_parameters(doc) == {"arm", "q", "qd", "qdd", "out"}
    assert set(sections(doc)) == {"Parameters", "Returns", "Raises"}
    assert has_section(doc, "Raises") and not has_section("Summary.\n\nReturns\n-------\n", "Returns")


# ----- the checks -------------------------------------------------------------------------
ITEMS = collect()


def test_the_walk_finds_the_public_surface() -> None:
    labels = {item.label for item in ITEMS}
    for expected in (
        "armdyn.dynamics.api.inverse_dynamics",
        "armdyn.kinematics.jacobian",
        "armdyn.model.arm.ArmModel",
        "armdyn.model.arm.ArmModel.from_dh",
        "armdyn.models.puma560",
        "armdyn.statespace.linearize",
        "armdyn.simulation.simulate",
        "armdyn.symbolic.closed_form.ClosedForm.to_c",
        "armdyn.urdf.load_urdf",
    ):
        assert expected in labels
    robot_methods = [item for item in ITEMS if item.label == "armdyn.dynamics.api.forward_dynamics"]
    assert robot_methods and robot_methods[0].needs_raises


def undocumented(item: Item) -> list[str]:
    """The parameters of the signature (not self/cls, *args, **kwargs) missing from Parameters."""
    assert item.signature is not None
    wanted = [
        name
        for name, parameter in item.signature.parameters.items()
        if name not in ("self", "cls") and parameter.kind not in SKIPPED_KINDS
    ]
    return [name for name in wanted if name not in documented_parameters(item.docstring)]


def test_an_undocumented_parameter_is_caught() -> None:
    def example(arm: object, q: object, *args: object, out: object = None, **kwargs: object) -> None:
        """Summary.

        Parameters
        ----------
        arm : Robot
            The arm.
        """

    item = _function_item(example, raises=False)
    assert undocumented(item) == ["q", "out"]
    assert not item.needs_returns


@pytest.mark.parametrize("item", ITEMS, ids=[item.label for item in ITEMS])
def test_parameters_are_documented(item: Item) -> None:
    if item.signature is None:
        pytest.skip("no signature to compare with")
    missing = undocumented(item)
    assert not missing, f"{item.label}: parameters {missing} are not in a numpydoc Parameters section"


@pytest.mark.parametrize(
    "item", [item for item in ITEMS if item.needs_returns], ids=[item.label for item in ITEMS if item.needs_returns]
)
def test_returns_are_documented(item: Item) -> None:
    assert has_section(item.docstring, "Returns"), f"{item.label} returns a value but has no Returns section"


@pytest.mark.parametrize(
    "item", [item for item in ITEMS if item.needs_raises], ids=[item.label for item in ITEMS if item.needs_raises]
)
def test_raises_are_documented(item: Item) -> None:
    assert has_section(item.docstring, "Raises"), f"{item.label} has no Raises section"
