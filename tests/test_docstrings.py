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
from types import ModuleType

import pytest

import armdyn
from tests.helpers import Item, documented_parameters, function_item, has_section, module_items, sections, undocumented

# Modules walked in full besides those named in armdyn.__all__.
MODULES = (
    "armdyn.symbolic",
    "armdyn.symbolic.backends",
    "armdyn.kinematics",
    "armdyn.models",
    "armdyn.statespace",
    "armdyn.properties",
    "armdyn.urdf",
    "armdyn.viewer",
    "armdyn.dynamics.regressor",
    "armdyn.dynamics.momentum",
    "armdyn.model",
    "armdyn.identification.excitation",
    "armdyn.identification.least_squares",
    "armdyn.identification.log",
    "armdyn.identification.preprocess",
    "armdyn.identification.friction",
    "armdyn.identification.workflow",
    "armdyn.identification.consistent",
    "armdyn.identification.report",
    "armdyn.identification.payload",
    "armdyn.identification.gains",
    "armdyn.io.urdf_out",
    "armdyn.io.mjcf_out",
    "armdyn.observers.momentum",
    "armdyn.observers.detection",
    "armdyn.observers.contact",
    "armdyn.observers.reaction",
    "armdyn.io.model_file",
    "armdyn.io.mjcf",
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
    "armdyn.simulation.plant_variants",
    "armdyn.properties.check",
    "armdyn.identify",
    "armdyn.identification.workflow.identify_log",
    "armdyn.symbolic.derive",
)


def _resolve(dotted: str) -> object:
    module_name, _, attribute = dotted.rpartition(".")
    return getattr(importlib.import_module(module_name), attribute)


def collect() -> list[Item]:
    """Every callable to check, each once (a Robot method is also a kinematics function: merged)."""
    modules = [armdyn] + [obj for obj in (getattr(armdyn, n) for n in armdyn.__all__) if isinstance(obj, ModuleType)]
    modules += [importlib.import_module(name) for name in MODULES]
    sources: list[Item] = []
    for module in modules:
        sources += list(module_items(module))
    for dotted in ENTRY_POINTS:
        sources.append(function_item(_resolve(dotted), raises=True))
    merged: dict[int, Item] = {}
    for item in sources:
        key = id(getattr(item.target, "__func__", item.target))  # a classmethod bound to Robot or ArmModel
        if key in merged:
            merged[key].needs_raises |= item.needs_raises
        else:
            merged[key] = item
    return sorted(merged.values(), key=lambda item: item.label)


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


def test_an_undocumented_parameter_is_caught() -> None:
    def example(arm: object, q: object, *args: object, out: object = None, **kwargs: object) -> None:
        """Summary.

        Parameters
        ----------
        arm : Robot
            The arm.
        """

    item = function_item(example, raises=False)
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
