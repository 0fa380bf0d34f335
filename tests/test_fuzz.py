"""Fuzzing the public surface: hostile inputs give a correct result or a clear error, never garbage.

Every callable reachable from ``armdyn.__all__`` (the Robot methods and constructors, the model
classes, ``load_urdf``, ``identify``, ``base_parameters``, ``armdyn.kinematics``,
``armdyn.lagrange``, ``armdyn.models``), ``armdyn.simulate`` with the controllers and
trajectories, ``armdyn.properties``, ``armdyn.statespace``, the compiled closed forms and every
command of the ``armdyn`` CLI is called with values from tests/fuzz_values.py: NaN, infinities,
complex numbers, huge values, wrong shapes and dtypes, junk objects, bad ``out=`` buffers,
hostile files, mixed with valid but unusual values (int arrays, lists, views, batches).

The rule (tests/fuzz_values.py): a case passes when the call returns the result its plain
float equivalent gives (finite), or raises ModelError or TypeError naming the argument. Any
other exception, a RuntimeWarning or ComplexWarning, a NaN or infinity in a result, a changed
input, or an unnamed argument fails. A command passes with exit code 0 (no NaN printed), or
exit code 2 with one ``error: ...`` line on stderr and no traceback.

Cases that could take the interpreter down (compiled kernels and compiled closed forms with
bad ``out=`` buffers, huge batches, simulations and commands asked for enormous runs, XML
bombs) run in child interpreters with a memory limit (``RISKY``), started at the beginning
and collected at the end; a crash fails the test, naming the case, and the child is restarted
after it. Each test reports every class of failure it found with a reproduction each; the
last line of the module's output counts the cases tried. ARMDYN_FUZZ_REPORT=file writes every
failure there, grouped into classes (and file.json, one record per case).

Each target is swept: every parameter gets every kind of value its Arg lists, on an arm
hypothesis picks, then a few cases corrupt two parameters at once (fuzz_values.fuzz);
hypothesis runs derandomized, so a run is reproducible. The commands are found from the typer
app itself, so a new command or option is fuzzed without a change here.
"""

from __future__ import annotations

import atexit
import contextlib
import copy
import dataclasses
import functools
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from hypothesis import strategies as st
from typer.testing import CliRunner

import armdyn as ad
import armdyn.control.drives
from armdyn import actuators, cli, control, kinematics, properties, statespace, study, task_space, trajectories
from armdyn.cli import app
from armdyn.dynamics import regressor as parameterization
from tests import fuzz_values as fv
from tests.fuzz_values import (
    NOTHING,
    Arg,
    Kinds,
    Target,
    Value,
    choice_values,
    finite,
    items_values,
    lazy,
    non_negative,
    none_is_valid,
    out_values,
    positive,
    relabel,
    scalar_values,
    state_values,
)
from tests.strategies import random_robot

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent
CHILD_MEMORY = 3 * 2**30  # address space of a child interpreter: a huge allocation fails fast there
CHILD_TIMEOUT = 300.0  # seconds for one child interpreter, its cold compile of the kernels included (a fresh clone)
CHILD_COUNT = [0]  # cases tried in child interpreters
# files written for the cases (removed at the end); a child interpreter is given a folder inside the parent's
SCRATCH = Path(os.environ.get("ARMDYN_FUZZ_SCRATCH") or tempfile.mkdtemp(prefix="armdyn-fuzz-"))
if "ARMDYN_FUZZ_SCRATCH" not in os.environ:
    atexit.register(shutil.rmtree, SCRATCH, ignore_errors=True)


def junk(verdict: str = "bad", skip: tuple[str, ...] = (), **names: tuple[str, ...]) -> list[Value]:
    """The junk objects of fuzz_values as Values."""
    return [Value(f"junk: {label}", value, verdict, **names) for label, value in fv.junk_values() if label not in skip]


# ----- arms and their valid states ------------------------------------------------------------


def _build_arms() -> list[tuple[str, ad.Robot]]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arms = [(name, ad.models.load(name)) for name in ("two_link_planar", "cylindrical", "puma560", "scara")]
        arms += [("polar_rp", ad.models.polar_rp()), ("random tree (4 joints)", random_robot(7, 4))]
    return arms


ARMS = _build_arms()
SMALL_ARMS = [item for item in ARMS if item[0] in ("two_link_planar", "cylindrical", "scara")]
_STATES: dict[int, dict[str, np.ndarray]] = {}


def states(arm: ad.Robot) -> dict[str, np.ndarray]:
    """Valid states of an arm (fixed, away from singular configurations): q, qd, qdd, tau, p."""
    if id(arm) not in _STATES:
        rng = np.random.default_rng(arm.n)
        lower, upper = arm.qlim
        prismatic = np.array(arm.kinds) == "prismatic"
        q = np.where(prismatic, rng.uniform(0.3, 1.0, arm.n), rng.uniform(-1.0, 1.0, arm.n))
        q = np.clip(q, lower, upper)
        qd = rng.uniform(0.2, 1.0, arm.n) * rng.choice([-1.0, 1.0], arm.n)
        qdd = rng.uniform(-1.0, 1.0, arm.n)
        tau = arm.inverse_dynamics(q, qd, qdd)
        _STATES[id(arm)] = {"q": q, "qd": qd, "qdd": qdd, "tau": tau, "p": arm.inertia_matrix(q) @ qd}
    return {k: v.copy() for k, v in _STATES[id(arm)].items()}


def _state_arg(name: str, **options: object) -> Arg:
    """A state argument named like its key in ``states`` (q, qd, qdd, tau, p)."""
    bounded = options.pop("bounded", name == "q")
    return Arg(
        lambda arm: states(arm)[name],
        lambda arm: state_values(states(arm)[name], bounded=bounded, **options),
        state=True,
    )


def _one_state(key: str, none_ok: bool = False, **options: object) -> Arg:
    def values(arm: ad.Robot) -> Kinds:
        kinds = state_values(states(arm)[key], batch=False, bounded=key == "q")
        return none_is_valid(kinds) if none_ok else kinds

    return Arg(lambda arm: states(arm)[key], values, **options)


def _out_arg(shape: Callable[[ad.Robot], tuple[int, ...]], risky: bool = False) -> Arg:
    return Arg(lambda arm: None, lambda arm: out_values(shape(arm), risky), alone=True)


@functools.cache
def _arm_items(arm: ad.Robot, robot_only: bool, symbolic_ok: bool = False) -> tuple[Value, ...]:
    plain = ad.ArmModel(arm.links, name=arm.name, gravity=arm.gravity, base=arm.base, tool=arm.tool)
    items = [
        Value("the arm", arm, "same", arm),
        Value("an ArmModel (not a Robot)", plain, "bad" if robot_only else "same", arm),
        Value("a symbolic arm", ad.models.two_link_planar(symbolic=True), "either" if symbolic_ok else "bad"),
        Value("the Robot class", ad.Robot, "bad"),
        Value("a name", arm.name, "bad"),
        Value("a Link", arm.links[0], "bad"),
        Value("a list of links", list(arm.links), "bad"),
    ]
    return tuple(items + junk())


def _robot_arg(robot_only: bool = False, symbolic_ok: bool = False) -> Arg:
    """A function's arm argument: the arm, its plain ArmModel, a symbolic arm, junk."""
    return Arg(
        lambda arm: arm, lambda arm: items_values(_arm_items(arm, robot_only, symbolic_ok)), names=("robot", "arm")
    )


def _method(name: str, args: dict[str, Arg], arms: list | None = None, **options: object) -> Target:
    return Target(f"Robot.{name}", lambda arm, **kw: getattr(arm, name)(**kw), args, arms or ARMS, **options)


# ----- the dynamics, kinematics and parameterization as Robot methods ---------------------------


def VECTOR(arm: ad.Robot) -> tuple[int, ...]:
    return (arm.n,)


def MATRIX(arm: ad.Robot) -> tuple[int, ...]:
    return (arm.n, arm.n)


DYNAMICS = {  # method: (state arguments, shape of out= or None when it has none)
    "inverse_dynamics": (("q", "qd", "qdd"), VECTOR),
    "forward_dynamics": (("q", "qd", "tau"), VECTOR),
    "inverse_dynamics_derivatives": (("q", "qd", "qdd"), None),
    "forward_dynamics_derivatives": (("q", "qd", "tau"), None),
    "inertia_matrix": (("q",), MATRIX),
    "inertia_matrix_dot": (("q", "qd"), None),
    "coriolis_matrix": (("q", "qd"), MATRIX),
    "coriolis_vector": (("q", "qd"), VECTOR),
    "gravity_vector": (("q",), VECTOR),
    "friction": (("qd",), VECTOR),
    "nonlinear_terms": (("q", "qd"), VECTOR),
    "kinetic_energy": (("q", "qd"), None),
    "potential_energy": (("q",), None),
    "energies": (("q", "qd"), lambda arm: (2,)),
}


def dynamics_targets() -> list[Target]:
    wrench = np.array([1.0, -2.0, 0.5, 0.1, 0.2, -0.3])
    targets = []
    for name, (names, _) in DYNAMICS.items():
        args = {k: _state_arg(k) for k in names}
        if name == "inverse_dynamics":
            args["f_ext"] = Arg(
                lambda arm: None, lambda arm: none_is_valid(state_values(wrench, batch=False, bounded=False))
            )
        targets.append(_method(name, args))
    args = {k: _state_arg(k) for k in ("q", "qd", "qdd")}
    args["out"] = _out_arg(lambda arm: (arm.n, 14 * arm.n))
    targets.append(_method("regressor", args))
    targets.append(Target("Robot.parameters", lambda arm: arm.parameters(), {}, ARMS, sweeps=3))
    targets.append(
        Target("Robot.to_urdf", lambda arm: arm.to_urdf(), {}, ARMS, view=lambda text: np.array([len(text)]))
    )
    targets.append(
        Target("Robot.to_mjcf", lambda arm: arm.to_mjcf(), {}, ARMS, view=lambda text: np.array([len(text)]))
    )
    return targets


def _link_values(arm: ad.Robot) -> Kinds:
    n = arm.n
    items = [Value(f"valid {k!r}", k, "same", k) for k in (None, 0, n - 1)]
    items += [Value("numpy int64", np.int64(n - 1), "same", n - 1), Value("numpy uint8", np.uint8(0), "same", 0)]
    items += [Value(f"{k!r}"[:30], k, "bad") for k in (-1, n, 10**400, 1.0, True, np.bool_(False), "1", [1])]
    items += [Value("0-d int array", np.array(0), "either", 0), Value("numpy float64", np.float64(0), "bad")]
    return items_values(items + junk(skip=("None",)))


FRAME = Arg(
    lambda arm: "base",
    lambda arm: choice_values(["base", "tool", np.str_("tool")], ["BASE", "world", "", "base ", b"base", 0]),
)
LINK = Arg(lambda arm: None, _link_values)


def kinematics_targets() -> list[Target]:
    q = _state_arg("q", complex_ok=True)
    qd = _state_arg("qd", complex_ok=True)
    return [
        _method("link_transforms", {"q": q}),
        _method("tool_pose", {"q": q}),
        _method("link_transform_derivatives", {"q": q}),
        _method("jacobian", {"q": q, "frame": FRAME, "link": LINK}),
        _method("jacobian_dot", {"q": q, "qd": qd, "frame": FRAME, "link": LINK}),
        Target("Robot.plot", _drawn, {"q": _one_state("q", none_ok=True)}, SMALL_ARMS),
        Target("Robot.view", _viewed, {"q": _one_state("q", none_ok=True)}, SMALL_ARMS[:1]),
    ]


def _viewed(arm: ad.Robot, **kwargs: object) -> np.ndarray:
    """Robot.view's scene at the configuration given: its tool position and centre of mass (the server closed)."""
    with arm.view(**kwargs) as viewer:
        data = viewer.scene_data()
        return np.concatenate([np.ravel(data["tool"])[:16], np.ravel(data["com"])])


def _drawn(arm: ad.Robot, **kwargs: object) -> np.ndarray:
    """Robot.plot's figure as the vertices of its lines (the figure closed: hundreds of cases)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = arm.plot(**kwargs)
    try:
        lines = fig.axes[0].lines
        return np.concatenate([np.ravel(getattr(line, "get_data_3d", line.get_data)()) for line in lines])
    finally:
        plt.close(fig)


# ----- model variants and constructors --------------------------------------------------------


def inertia_values(valid: tuple = (0.01, 0.02, 0.015)) -> Kinds:
    """Values for an inertia tensor about the centre of mass: 3 moments, 6 values or 3x3."""
    tensor = np.diag(np.asarray(valid, dtype=float))
    items = [
        Value("3 moments", list(valid), "same", tensor),
        Value("6 values", [*valid, 0.0, 0.0, 0.0], "same", tensor),
        Value("3x3 nested list", tensor.tolist(), "same", tensor),
        Value("3x3 int zeros", np.zeros((3, 3), dtype=int), "same", np.zeros((3, 3))),
        Value("3x3 float32", tensor.astype(np.float32), "same", tensor.astype(np.float32).astype(float)),
        Value("negative moment", [-0.01, 0.02, 0.015], "bad"),
        Value("not symmetric", [[0.01, 0.005, 0], [0, 0.02, 0], [0, 0, 0.015]], "bad"),
        Value("indefinite", [[0.01, 0.05, 0], [0.05, 0.01, 0], [0, 0, 0.015]], "bad"),
        # refused, or accepted with a warning where strict=False says so
        Value("triangle inequality broken", [0.01, 0.01, 0.5], "either", names=("triangle",)),
        Value("NaN moment", [np.nan, 0.02, 0.015], "bad"),
        Value("inf moment", [np.inf, 0.02, 0.015], "bad"),
        Value("1e300 moments", [1e300, 1e300, 1e300], "either"),
        Value("complex moments", [0.01 + 1j, 0.02, 0.015], "bad"),
        Value("shape (2, 2)", np.eye(2), "bad"),
        Value("shape (4,)", [0.01, 0.02, 0.015, 0.0], "bad"),
        Value("shape (3, 3, 1)", np.zeros((3, 3, 1)), "bad"),
        Value("scalar", 0.01, "bad"),
        Value("text moments", ["a", "b", "c"], "bad"),
        Value("ragged", [[0.01, 0], [0, 0.02, 0], [0, 0, 0.015]], "bad"),
    ]
    return items_values(items + junk(skip=("None",)))


def transform_values(none_ok: bool = True) -> Kinds:
    """Values for a 4x4 rigid transform (a base, a tool, a placement)."""
    c, s = np.cos(0.3), np.sin(0.3)
    turn = np.array([[c, -s, 0, 0.1], [s, c, 0, 0.2], [0, 0, 1, 0.3], [0, 0, 0, 1.0]])
    eye = np.eye(4)
    entry = np.arange(16).reshape(4, 4)
    items = [
        Value("rotation about z", turn, "same", turn),
        Value("nested list", turn.tolist(), "same", turn),
        Value("int identity", np.eye(4, dtype=int), "same", eye),
        Value("read-only", fv._readonly(turn), "same", turn),
        Value("Fortran order", np.asfortranarray(turn), "same", turn),
        Value("float32 identity", np.eye(4, dtype=np.float32), "same", eye),
        Value("float32 rotation", turn.astype(np.float32), "either", turn.astype(np.float32).astype(float)),
        Value("scaled by 2", np.diag([2.0, 2.0, 2.0, 1.0]), "bad"),
        Value("mirror", np.diag([1.0, -1.0, 1.0, 1.0]), "bad"),
        Value("last row [0 0 1 1]", np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1.0]]), "bad"),
        Value("NaN translation", np.where(entry == 3, np.nan, eye), "bad"),
        Value("inf rotation", np.where(entry == 0, np.inf, eye), "bad"),
        Value("1e300 translation", np.where(entry == 3, 1e300, eye), "either"),
        Value("nearly rigid (1e-12 off)", eye + 1e-12 * np.diag([1.0, 0, 0, 0]), "either", eye),
        Value("shape (3, 3)", np.eye(3), "bad"),
        Value("shape (4, 4, 1)", np.eye(4)[..., None], "bad"),
        Value("batch (2, 4, 4)", np.stack([eye, eye]), "bad"),
        Value("complex identity", np.eye(4, dtype=complex), "bad"),
        Value("object identity", np.eye(4).astype(object), "either", eye),
        Value("text", np.full((4, 4), "x"), "bad"),
        Value("flat 16", np.eye(4).ravel(), "bad"),
        Value("None", None, "same" if none_ok else "bad", eye if none_ok else NOTHING),
    ]
    return items_values(items + junk(skip=("None",)))


def gravity_arg() -> Arg:
    g = np.array([0.0, 0.0, -9.81])
    return Arg(lambda arm: g.copy(), lambda arm: state_values(g, batch=False, bounded=False), names=("gravity",))


def _configurations_values(arm: ad.Robot) -> Kinds:
    n = arm.n
    ok = {"qa": [0.1] * n}
    items = [
        Value("valid mapping", ok, "same", ok),
        Value("None", None, "same", None),
        Value("int values", {"qa": [1] * n}, "same", {"qa": [1.0] * n}),
        Value("n+1 values", {"qa": [0.1] * (n + 1)}, "bad"),
        Value("NaN values", {"qa": [np.nan] * n}, "bad"),
        Value("text values", {"qa": ["x"] * n}, "bad"),
        Value("name not an identifier", {"1 bad": [0.1] * n}, "bad"),
        Value("name clashing with an attribute", {"n": [0.1] * n}, "bad"),
        Value("int key", {1: [0.1] * n}, "bad"),
        Value("list of pairs", [("qa", [0.1] * n)], "bad"),
        Value("a string", "qa", "bad"),
        Value("complex values", {"qa": [1j] * n}, "bad"),
        Value("1e300 values", {"qa": [1e300] * n}, "either"),
    ]
    return items_values(items + junk(skip=("None",)))


def _tool_link_values(arm: ad.Robot) -> Kinds:
    n = arm.n
    return scalar_values(
        [0, n - 1], lambda x: "same" if float(x).is_integer() and 0 <= x < n else "bad", none="same", integer=True
    )


def _pair(value: Value) -> np.ndarray | None:
    """The value as a pair of real numbers, or None."""
    try:
        if np.iscomplexobj(value.value):
            return None
        pair = np.asarray(value.value, dtype=float)
    except (TypeError, ValueError, ArithmeticError):
        return None
    return pair if pair.shape == (2,) else None


def _as_limits(value: Value) -> Value:
    """Joint limits: an infinite bound means no limit (valid), but lower must not exceed upper
    and a limit must leave some room (not both bounds at the same infinity)."""
    pair = _pair(value)
    if pair is not None and value.label.endswith("inf entry") and not np.isnan(pair).any():
        value.verdict = "same" if pair[0] <= pair[1] and pair[0] < np.inf and pair[1] > -np.inf else "bad"
        value.reference = pair if value.verdict == "same" else NOTHING
    return value


def _as_coulomb(value: Value) -> Value:
    """Coulomb levels (Tc+, Tc-): Tc+ >= 0 >= Tc-, whatever the kind of value."""
    pair = _pair(value)
    if pair is not None and value.verdict == "same" and not pair[0] >= 0 >= pair[1]:
        value.verdict = "bad"
    return value


def _links_values(arm: ad.Robot, none_ok: bool = True) -> Kinds:
    links = list(arm.links)
    forward = [dataclasses.replace(links[0], parent=1), *links[1:]]
    text_link = copy.copy(links[0])  # a Link refuses a text parent: made past its check, for the arm to refuse
    object.__setattr__(text_link, "parent", "base")
    text_parent = [text_link, *links[1:]]
    items = [
        Value("a tuple of the links", tuple(links), "same", links),
        Value("None (its own)", None, "same" if none_ok else "bad", None if none_ok else NOTHING),
        Value("empty list", [], "bad"),
        Value("a Link not in a list", links[0], "bad"),
        Value("ints", [1, 2], "bad"),
        Value("a string", "links", "bad"),
        Value("the same link twice", [links[0], links[0]], "bad"),
        Value("a parent after its child", forward, "bad", names=("parent",)),
        Value("a parent given as text", text_parent, "bad", names=("parent",)),
        Value("None among the links", [*links[:-1], None], "bad"),
    ]
    items.append(Value("a generator of the links", (link for link in links), "either", links))
    return items_values(items + junk(skip=("None",)))


def variant_targets() -> list[Target]:
    com = np.array([0.01, 0.0, 0.02])
    payload = {
        "mass": Arg(lambda arm: 0.5, lambda arm: scalar_values([0.5, 2.0], non_negative), names=("payload",)),
        "com": Arg(
            lambda arm: com,
            lambda arm: state_values(com, batch=False, bounded=False),
            names=("centre of mass", "center of mass", "payload"),
        ),
        "inertia": Arg(lambda arm: None, lambda arm: inertia_values(), names=("payload",)),
    }

    def label(default: str) -> Arg:
        return Arg(
            lambda arm: default,
            lambda arm: choice_values(["x", "a b"], [], [None, 1, b"x", "", "é" * 50], "either"),
        )

    replace = {
        "name": label("renamed"),
        "description": label(""),
        "gravity": gravity_arg(),
        "base": Arg(lambda arm: None, lambda arm: transform_values()),
        "tool": Arg(lambda arm: None, lambda arm: transform_values()),
        "tool_link": Arg(lambda arm: arm.n - 1, _tool_link_values),
        "configurations": Arg(lambda arm: None, _configurations_values, names=("configuration",)),
        "links": Arg(lambda arm: None, _links_values, names=("link", "Link", "joint")),
    }
    configuration_names = Arg(
        lambda arm: next(iter(arm.configurations)),
        lambda arm: choice_values(list(arm.configurations), ["nope", "QZ", ""], [np.str_("qz")]),
        names=("configuration",),
    )
    configured = [item for item in ARMS if item[1].configurations]
    return [
        _method("with_payload", payload),
        _method("replace", replace),
        _method("with_gravity", {"gravity": gravity_arg()}),
        _method("configuration", {"name": configuration_names}, configured),
    ]


DH_ROWS = [
    {"a": 1.0, "mass": 1.0, "com": [-0.5, 0.0, 0.0], "inertia": [0.01, 0.02, 0.02], "B": 0.1, "Tc": (0.2, -0.2)},
    {"kind": "P", "alpha": 0.3, "theta": 0.1, "d": 0.2, "mass": 0.5, "Jm": 1e-4, "G": 50.0, "qlim": (0.0, 1.0)},
]
DH_KEY_NAMES = {
    "mass": ("mass",),
    "com": ("com", "centre of mass", "center of mass"),
    "inertia": ("inertia",),
    "Jm": ("Jm", "motor inertia"),
    "G": ("G", "gear ratio"),
    "B": ("B", "viscous"),
    "Tc": ("Tc", "Coulomb"),
    "qlim": ("qlim", "limits"),
    "kind": ("kind",),
    "name": ("name",),
    "a": ("a",),
    "alpha": ("alpha",),
    "d": ("d",),
    "theta": ("theta",),
    "strict": ("strict",),
}


def _dh_key_kinds(key: str) -> Kinds:
    """The kinds of value for one key of a DH row."""
    if key in ("mass", "Jm", "B"):
        return scalar_values([0.5], non_negative)
    if key == "G":
        return scalar_values([2.0, -3.0], lambda x: "bad" if x == 0 or not np.isfinite(x) else finite(x))
    if key in ("a", "alpha", "d", "theta"):
        return scalar_values([0.5, -0.2], finite)
    if key == "com":
        return state_values(np.array([0.1, 0.0, 0.0]), batch=False, bounded=False)
    if key == "inertia":
        return inertia_values()
    if key in ("Tc", "qlim"):
        return state_values(np.array((0.2, -0.1) if key == "Tc" else (-1.0, 1.0)), batch=False, bounded=False)
    if key == "kind":
        return choice_values(["R", "P", "revolute", "prismatic", "r"], ["X", "", "RP", "fixed"])
    if key == "name":
        return choice_values(["j", "joint 7"], [], [None, 1, b"j", ""], "either")
    return choice_values([True, False], [], ["no", 0, None], "either")


@st.composite
def _dh_row_value(draw: st.DrawFn, key: str, kind: st.SearchStrategy[Value]) -> Value:
    """A DH table with one entry of one row replaced by a value of the given kind."""
    value = draw(kind)
    index = draw(st.integers(0, 1))
    pair = value.reference if isinstance(value.reference, np.ndarray) and value.reference.shape == (2,) else None
    broken = pair is not None and (
        (key == "Tc" and not pair[0] >= 0 >= pair[1]) or (key == "qlim" and pair[0] > pair[1])
    )
    if broken and value.verdict == "same":
        value.verdict = "bad"
    if key == "qlim":
        value = _as_limits(value)
    rows = copy.deepcopy(DH_ROWS)
    rows[index][key] = value.value
    reference = NOTHING
    if value.reference is not NOTHING:
        reference = copy.deepcopy(DH_ROWS)
        reference[index][key] = value.reference
    names = (*DH_KEY_NAMES[key], *value.names)
    return Value(f"row {index} {key}: {value.label}", rows, value.verdict, reference, names=names)


def dh_table_values() -> Kinds:
    """DH tables with one entry of one row replaced, or tables that are no table at all."""
    rows = copy.deepcopy(DH_ROWS)
    items = [
        Value("tuple of rows", tuple(rows), "same", copy.deepcopy(DH_ROWS)),
        Value("empty table", [], "bad"),
        Value("a row not in a list", rows[0], "bad"),
        Value("None as a row", [rows[0], None], "bad"),
        Value("a string", "RP", "bad"),
        Value("rows as lists", [list(r.items()) for r in rows], "bad"),
        Value("unknown key", [rows[0], {**rows[1], "mass2": 1.0}], "bad", names=("mass2", "key")),
        Value("empty rows (massless)", [{}, {}], "same", [{}, {}]),
    ]
    kinds = items_values(items + junk())
    kinds.append(lazy(lambda: Value("generator of rows", (dict(r) for r in DH_ROWS), "either", DH_ROWS)))
    return kinds + [_dh_row_value(key, kind) for key in DH_KEY_NAMES for kind in _dh_key_kinds(key)]


def _object_values(valid: object, kind: type, callable_ok: bool = False) -> Kinds:
    items = [Value(f"a {kind.__name__}", valid, "same", valid), Value("a Robot", ARMS[0][1], "bad")]
    items += [Value(v.label, v.value, "either" if callable_ok and callable(v.value) else "bad") for v in junk()]
    return items_values(items)


def axis_values() -> Kinds:
    z = np.array([0.0, 0.0, 1.0])
    diagonal = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    items = [
        Value("list", [0.0, 0.0, 1.0], "same", z),
        Value("int array", np.array([0, 0, 1]), "same", z),
        Value("float32", z.astype(np.float32), "same", z),
        Value("diagonal unit", diagonal, "same", diagonal),
        Value("column (3, 1)", z[:, None], "either", z),
        Value("length 2", [0.0, 0.0, 2.0], "bad"),
        Value("zero", [0.0, 0.0, 0.0], "bad"),
        Value("NaN", [np.nan, 0.0, 1.0], "bad"),
        Value("inf", [np.inf, 0.0, 0.0], "bad"),
        Value("two values", [0.0, 1.0], "bad"),
        Value("four values", [0.0, 0.0, 1.0, 0.0], "bad"),
        Value("complex", [0.0, 0.0, 1.0 + 0j], "bad"),
        Value("text", ["0", "0", "x"], "bad"),
        Value("nearly unit (1 + 1e-12)", [0.0, 0.0, 1.0 + 1e-12], "either", z),
    ]
    return items_values(items + junk())


def constructor_targets() -> list[Target]:
    joint = ad.Joint()
    inertial = ad.Inertial(1.0, [0.1, 0, 0], [0.01, 0.02, 0.02], "l")
    no_arm = [("-", None)]
    names = Arg(lambda arm: "x", lambda arm: choice_values(["x", "joint 1"], [], [None, 7, b"x", "", "\x00"], "either"))
    strict = Arg(lambda arm: True, lambda arm: choice_values([True, False], [], ["no", 0, None], "either"))
    planar = ARMS[0][1]

    def vector(v: tuple | list, rule: Callable[[Value], Value], **options: object) -> Arg:
        values = lambda arm: [kind.map(rule) for kind in state_values(np.array(v), batch=False, bounded=False)]  # noqa: E731
        return Arg(lambda arm: v, values, **options)

    robot_args = {
        "links": Arg(
            lambda arm: list(planar.links), lambda arm: _links_values(planar, False), names=("link", "Link", "joint")
        ),
        "name": names,
        "gravity": gravity_arg(),
        "base": Arg(lambda arm: None, lambda arm: transform_values()),
        "tool": Arg(lambda arm: None, lambda arm: transform_values()),
        "tool_link": Arg(lambda arm: None, lambda arm: _tool_link_values(planar)),
        "configurations": Arg(lambda arm: None, lambda arm: _configurations_values(planar), names=("configuration",)),
        "description": names,
    }
    dh_args = {
        "table": Arg(lambda arm: copy.deepcopy(DH_ROWS), lambda arm: dh_table_values(), names=("row", "joint")),
        "convention": Arg(
            lambda arm: "standard",
            lambda arm: choice_values(["standard", "modified"], ["Standard", "craig", "", b"standard"]),
        ),
        "gravity": gravity_arg(),
        "name": names,
    }
    inertial_args = {
        "mass": Arg(lambda arm: 1.0, lambda arm: scalar_values([1.0, 0.0], non_negative)),
        "com": vector([0.1, 0.0, 0.0], lambda value: value, names=("centre of mass", "center of mass")),
        "inertia": Arg(lambda arm: [0.01, 0.02, 0.02], lambda arm: inertia_values()),
        "name": names,
        "strict": strict,
    }
    joint_args = {
        "kind": Arg(
            lambda arm: "revolute",
            lambda arm: choice_values(["R", "P", "continuous", "Prismatic"], ["X", "", "fixed", "rp"]),
        ),
        "placement": Arg(lambda arm: np.eye(4), lambda arm: transform_values(none_ok=False)),
        "axis": Arg(lambda arm: [0.0, 0.0, 1.0], lambda arm: axis_values()),
        "frame_offset": Arg(lambda arm: np.eye(4), lambda arm: transform_values(none_ok=False)),
        "name": names,
    }
    link_args = {
        "name": names,
        "joint": Arg(lambda arm: joint, lambda arm: _object_values(joint, ad.Joint)),
        "inertial": Arg(lambda arm: inertial, lambda arm: _object_values(inertial, ad.Inertial)),
        "parent": Arg(
            lambda arm: -1,
            lambda arm: scalar_values(
                [-1, 0], lambda x: "same" if x.is_integer() and x >= -1 else "either", integer=True
            ),
        ),
        "viscous": Arg(lambda arm: 0.1, lambda arm: scalar_values([0.1, 0.0], non_negative)),
        "coulomb": vector((0.2, -0.1), _as_coulomb, names=("Coulomb",)),
        "motor_inertia": Arg(
            lambda arm: 1e-4, lambda arm: scalar_values([1e-4, 0.0], non_negative), names=("motor inertia",)
        ),
        "gear_ratio": Arg(
            lambda arm: 10.0,
            lambda arm: scalar_values([10.0, -5.0], lambda x: "bad" if x == 0 else finite(x)),
            names=("gear ratio",),
        ),
        "limits": vector((-1.0, 1.0), _as_limits, names=("limit",)),
    }
    return [
        Target("Robot.from_dh", lambda arm, **kw: ad.Robot.from_dh(**kw), dh_args, no_arm),
        Target("Robot(links, ...)", lambda arm, **kw: ad.Robot(**kw), robot_args, no_arm),
        Target("ArmModel", lambda arm, **kw: ad.ArmModel(**kw), robot_args, no_arm, sweeps=1),
        Target("Inertial", lambda arm, **kw: ad.Inertial(**kw), inertial_args, no_arm),
        Target("Joint", lambda arm, **kw: ad.Joint(**kw), joint_args, no_arm),
        Target("Link", lambda arm, **kw: ad.Link(**kw), link_args, no_arm),
    ]


# ----- the built-in models -------------------------------------------------------------------

MODEL_NAMES = {"m1": ("mass",), "m2": ("mass",), "m": ("mass",), "a1": ("length",), "a2": ("length",)}
MODEL_NAMES |= {"g": ("gravity",), "J": ("inertia",)}


def model_targets() -> list[Target]:
    no_arm = [("-", None)]

    def parameters(**defaults: tuple[float, Callable]) -> dict[str, Arg]:
        args = {
            key: Arg(lambda arm, v=value: v, lambda arm, v=value, r=rule: scalar_values([v], r), names=MODEL_NAMES[key])
            for key, (value, rule) in defaults.items()
        }
        args["symbolic"] = Arg(
            lambda arm: False, lambda arm: choice_values([False, True], [], ["yes", 1, None], "either"), alone=True
        )
        return args

    names = choice_values(
        ad.models.names(),
        ["", "nosuch", " puma560", "names", "load", "__init__", "puma560\x00", "Robot"],
        ["PUMA560", np.str_("scara")],
    )
    fixed = (ad.models.puma560, ad.models.stanford, ad.models.scara, ad.models.names)
    return [
        Target(
            "models.load",
            lambda arm, **kw: ad.models.load(**kw),
            {"name": Arg(lambda arm: "scara", lambda arm: names, names=("arm",))},
            no_arm,
        ),
        Target(
            "models.two_link_planar",
            lambda arm, **kw: ad.models.two_link_planar(**kw),
            parameters(
                m1=(1.0, non_negative), m2=(2.0, non_negative), a1=(1.0, finite), a2=(0.5, finite), g=(9.8, finite)
            ),
            no_arm,
        ),
        Target(
            "models.polar_rp",
            lambda arm, **kw: ad.models.polar_rp(**kw),
            parameters(m=(1.0, non_negative), g=(9.8, finite)),
            no_arm,
        ),
        Target(
            "models.cylindrical",
            lambda arm, **kw: ad.models.cylindrical(**kw),
            parameters(J=(1.0, non_negative), m1=(1.0, non_negative), m2=(2.0, non_negative), g=(9.8, finite)),
            no_arm,
        ),
        Target("models.puma560, stanford, scara, names", lambda arm: [f() for f in fixed], {}, no_arm),
    ]


# ----- URDF files -----------------------------------------------------------------------------

URDF = """<?xml version="1.0"?>
<robot name="{robot_name}">
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="{l1_com}" rpy="0 0 0"/><mass value="{l1_mass}"/>
      <inertia ixx="{l1_ixx}" ixy="{l1_ixy}" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
  </link>
  <link name="l2">
    <inertial><origin xyz="0.2 0 0" rpy="0 0 0"/><mass value="0.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="j1" type="{j1_type}">
    <parent link="{j1_parent}"/><child link="l1"/>
    <origin xyz="{j1_xyz}" rpy="{j1_rpy}"/><axis xyz="{j1_axis}"/>
    <limit lower="{j1_lower}" upper="{j1_upper}" effort="10" velocity="1"/>
    <dynamics damping="{j1_damping}" friction="{j1_friction}"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="l1"/><child link="{j2_child}"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="1"/>
  </joint>
</robot>
"""
SLOTS = {
    "robot_name": "fuzz",
    "l1_com": "0.1 0 0",
    "l1_mass": "1.0",
    "l1_ixx": "0.02",
    "l1_ixy": "0",
    "j1_type": "revolute",
    "j1_parent": "base",
    "j1_xyz": "0 0 0.1",
    "j1_rpy": "0 0 0",
    "j1_axis": "0 0 1",
    "j1_lower": "-1",
    "j1_upper": "1",
    "j1_damping": "0.1",
    "j1_friction": "0.05",
    "j2_child": "l2",
}
NUMBER_TOKENS = {
    "nan": "bad",
    "inf": "bad",
    "-inf": "bad",
    "abc": "bad",
    "": "either",
    "1 2": "bad",
    "0x10": "bad",
    "-1": "either",
    "1e300": "either",
    "1e16": "either",
    "-0": "either",
    "1_000": "either",
    "\u0661": "either",
    "1e-320": "either",
}
VECTOR_TOKENS = {
    "nan 0 0": "bad",
    "0 inf 0": "bad",
    "1 2": "bad",
    "1 2 3 4": "bad",
    "a b c": "bad",
    "0,0,1": "bad",
    "": "either",
    "0 0 0": "either",
    "1e300 0 0": "either",
    "1e16 0 1": "either",
    "0 0 1e-320": "either",
}
SLOT_TOKENS = {
    "j1_type": {
        "floating": "bad",
        "planar": "bad",
        "spherical": "bad",
        "": "bad",
        "REVOLUTE": "bad",
        "prismatic": "either",
        "continuous": "either",
        "fixed": "either",
    },
    "j1_parent": {"l2": "bad", "nosuch": "bad", "l1": "bad", "": "bad"},
    "j2_child": {"l1": "bad", "base": "bad", "nosuch": "bad"},
    "robot_name": {
        "": "bad",
        "<": "bad",
        '"': "bad",
        "&#0;": "bad",
        "&amp;": "either",
        "\u540d": "either",
        "x" * 100_000: "either",
    },
}
SECRET = "SECRET-TOKEN-4711"
_FILES = [0]


def _write(content: str | bytes, suffix: str = ".urdf") -> Path:
    _FILES[0] += 1
    path = SCRATCH / f"case{_FILES[0]}{suffix}"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content, encoding="utf-8")
    return path


def _urdf(**changes: str) -> str:
    return URDF.format(**(SLOTS | changes))


def _no_secret(robot: object) -> str | None:
    return f"read an external entity into the model: name {robot.name!r}" if SECRET in robot.name else None


def _structural(risky: bool) -> list[tuple[str, Callable[[], str | bytes], str]]:
    """(label, content maker, verdict) for whole files."""
    good = _urdf()
    secret = SCRATCH / "secret.txt"
    secret.write_text(SECRET)
    chain = "".join(
        f'<link name="c{i}"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>'
        f'<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
        f'<joint name="k{i}" type="revolute"><parent link="{"base" if i == 0 else f"c{i - 1}"}"/>'
        f'<child link="c{i}"/><origin xyz="0.1 0 0"/><axis xyz="0 0 1"/></joint>'
        for i in range(150)
    )
    if risky:
        laughs = "".join(f'<!ENTITY l{i} "{("&l" + str(i - 1) + ";") * 10}">' for i in range(1, 12))
        blowup = "x" * 50_000
        return [
            (
                "billion laughs",
                lambda: f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY l0 "ha">{laughs}]><robot name="&l11;"/>',
                "bad",
            ),
            (
                "quadratic blowup",
                lambda: f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "{blowup}">]><robot name="{"&a;" * 50_000}"/>',
                "bad",
            ),
        ]
    return [
        ("empty file", lambda: "", "bad"),
        ("binary junk", lambda: bytes(range(256)) * 8, "bad"),
        ("NUL bytes in XML", lambda: good.replace('<link name="base"/>', '<link name="base"/>\x00'), "bad"),
        ("latin-1 bytes", lambda: good.replace("fuzz", "f\u00fc").encode("latin-1"), "either"),
        ("UTF-16 with BOM", lambda: good.encode("utf-16"), "either"),
        ("UTF-8 BOM", lambda: b"\xef\xbb\xbf" + good.encode(), "either"),
        ("truncated", lambda: good[: len(good) // 2], "bad"),
        ("html root", lambda: "<html><body>no robot</body></html>", "bad"),
        ("robot without a name", lambda: good.replace(' name="fuzz"', ""), "bad"),
        (
            "link defined twice",
            lambda: good.replace('<link name="base"/>', '<link name="base"/><link name="l2"/>'),
            "bad",
        ),
        ("no joints", lambda: '<robot name="r"><link name="base"/></robot>', "bad"),
        ("two roots", lambda: good.replace('<link name="base"/>', '<link name="base"/><link name="orphan"/>'), "bad"),
        (
            "external entity (XXE)",
            lambda: good.replace(
                '<?xml version="1.0"?>', f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY s SYSTEM "{secret}">]>'
            ).replace('name="fuzz"', 'name="&s;"'),
            "either",
        ),
        (
            "external DTD",
            lambda: good.replace(
                '<?xml version="1.0"?>', '<?xml version="1.0"?><!DOCTYPE robot SYSTEM "http://127.0.0.1:9/x.dtd">'
            ),
            "either",
        ),
        ("long chain (150 joints)", lambda: f'<robot name="chain"><link name="base"/>{chain}</robot>', "either"),
        (
            "mimic joint",
            lambda: good.replace('<axis xyz="0 1 0"/>', '<axis xyz="0 1 0"/><mimic joint="j1"/>'),
            "either",
        ),
        ("comment only", lambda: "<!-- nothing -->", "bad"),
        (
            "massless file",
            lambda: good.replace('value="1.0"', 'value="0"').replace('value="0.5"', 'value="0"'),
            "either",
        ),
    ]


def _slot_value(slot: str, token: str, verdict: str) -> Value:
    path = _write(_urdf(**{slot: token}))
    return Value(f"{slot}={token[:12]!r}", path, verdict, names=(path.name, "path"))


def _file_value(label: str, make: Callable[[], str | bytes], verdict: str) -> Value:
    path = _write(make())
    return Value(label, path, verdict, names=(path.name, "path"), check=_no_secret if "XXE" in label else None)


def urdf_values(risky: bool = False) -> Kinds:
    """Paths to URDF files: the valid template with one attribute replaced (every slot, every
    token), whole hostile files, and paths that are no file."""
    kinds = [lazy(lambda a=item: _file_value(*a)) for item in _structural(risky)]
    if risky:
        return kinds
    for slot in SLOTS:
        tokens = SLOT_TOKENS.get(slot) or (
            VECTOR_TOKENS if slot in ("l1_com", "j1_xyz", "j1_rpy", "j1_axis") else NUMBER_TOKENS
        )
        for token, verdict in tokens.items():
            verdict = "bad" if slot == "j1_axis" and token in ("", "0 0 0") else verdict
            kinds.append(lazy(lambda a=(slot, token, verdict): _slot_value(*a)))
    good = _write(_urdf())
    items = [
        Value("str path", str(good), "same", good),
        Value("missing file", SCRATCH / "missing.urdf", "bad", names=("missing.urdf",)),
        Value("a folder", SCRATCH, "bad", names=(SCRATCH.name,)),
        Value("path with NUL", str(good) + "\x00", "bad", names=(good.name, "path")),
        Value("bytes path", bytes(good), "either", good),
        Value("file URL", good.as_uri(), "bad", names=("file:",)),
        Value("/dev/null", Path("/dev/null"), "bad", names=("null",)),
        Value("int", 3, "bad"),
    ]
    return kinds + items_values(items + junk())


def urdf_targets(risky: bool = False) -> list[Target]:
    good = _write(_urdf())
    gravity = np.array([0.0, 0.0, -9.81])
    args = {
        "path": Arg(lambda arm: good, lambda arm: urdf_values(risky)),
        "strict": Arg(lambda arm: True, lambda arm: choice_values([True, False], [], ["no", 0, None], "either")),
        "gravity": Arg(lambda arm: gravity, lambda arm: state_values(gravity, batch=False, bounded=False)),
    }
    if risky:
        args = {"path": args["path"]}
    return [Target("load_urdf" + (" (XML bombs)" if risky else ""), lambda arm, **kw: ad.load_urdf(**kw), args)]


MJCF = """<mujoco model="fuzz">
  <worldbody>
    <body name="upper">
      <joint name="j1" axis="0 0 1" damping="0.1" armature="0.01"/>
      <inertial pos="0.2 0 0" mass="1" diaginertia="0.01 0.02 0.02"/>
      <body name="fore" pos="0.4 0 0">
        <joint name="j2" axis="0 1 0"/>
        <inertial pos="0.1 0 0.02" mass="0.5" diaginertia="0.005 0.01 0.01"/>
        <site name="tip" pos="0.2 0 0"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <dcmotor joint="j1" gear="50" resistance="1.2" motorconst="0.05 0.05" inductance="0.002 0"/>
    <dcmotor joint="j2" gear="30" resistance="2" motorconst="0.04 0.04" inductance="0.003 0"/>
  </actuator>
</mujoco>"""


def mjcf_values() -> Kinds:
    """MJCF sources: a good file and its text, files MuJoCo cannot compile or a tree cannot hold, paths that are
    no file, junk."""
    good = _write(MJCF, ".xml")

    def file(label: str, text: str) -> Value:
        path = _write(text, ".xml")
        return Value(label, path, "bad", names=(path.name,))

    hostile = [
        ("not XML", "<<<"),
        ("a URDF's root", "<robot name='x'/>"),
        ("bad number", MJCF.replace('mass="1"', 'mass="x"')),
        ("missing mesh", MJCF.replace("<site", "<geom type='mesh' mesh='m'/><site").replace(
            "<worldbody>", "<asset><mesh name='m' file='missing.stl'/></asset><worldbody>")),
        ("ball joint", MJCF.replace('<joint name="j2" axis="0 1 0"/>', '<joint name="j2" type="ball"/>')),
        ("free joint", MJCF.replace('<joint name="j1" axis="0 0 1" damping="0.1" armature="0.01"/>',
                                    '<freejoint name="j1"/>')),
        ("no joint", "<mujoco><worldbody><body><geom size='0.1'/></body></worldbody></mujoco>"),
    ]  # fmt: skip
    items = [
        Value("str path", str(good), "same", good),
        Value("MJCF text", MJCF, "same", good),
        Value("missing file", SCRATCH / "missing.xml", "bad", names=("missing.xml",)),
        Value("a folder", SCRATCH, "bad", names=(SCRATCH.name,)),
        Value("path with NUL", str(good) + "\x00", "bad", names=(good.name, "source")),
        Value("int", 3, "bad"),
        Value("bytes path", bytes(good), "either", good),
    ]
    junk_sources = junk(skip=("bytes",), names=("source",))
    return [lazy(lambda a=item: file(*a)) for item in hostile] + items_values(items + junk_sources)


def mjcf_targets() -> list[Target]:
    import mujoco

    good = _write(MJCF, ".xml")
    model = mujoco.MjModel.from_xml_string(MJCF)
    gravity = np.array([0.0, 0.0, -9.81])
    q = np.array([0.3, -0.7])
    view = lambda arm: arm.inertia_matrix(q)  # noqa: E731 (a Robot or the arm with its drives)
    gravities = state_values(gravity, batch=False, bounded=False)

    def model_gravity(value: Value) -> Value:  # None is valid: the model's own gravity
        return dataclasses.replace(value, verdict="either") if value.value is None else value

    flags = Arg(lambda arm: False, lambda arm: choice_values([True, False], [], ["no", 0, None], "either"))
    common = {
        "gravity": Arg(lambda arm: gravity, lambda arm: [kind.map(model_gravity) for kind in gravities]),
        "tool_link": Arg(
            lambda arm: None, lambda arm: choice_values(["tip", "fore"], ["upper ", "nothing"], [], "bad")
        ),
        "locked": Arg(
            lambda arm: None,
            lambda arm: choice_values([{}], [{"j3": 0.0}, {"j1": np.nan}, {"j1": 0.0, "j2": 0.0}], [], "bad"),
            names=("lock", "locking"),
        ),
        "strict": flags,
        "drives": flags,
    }
    models = items_values([Value("compiled model", model, "same", model), *junk(names=("model",))])
    sources = {"source": Arg(lambda arm: good, lambda arm: mjcf_values())}
    compiled = {"model": Arg(lambda arm: model, lambda arm: models)}
    return [
        Target("load_mjcf", lambda arm, **kw: ad.load_mjcf(**kw), sources | common, view=view),
        Target("from_mujoco", lambda arm, **kw: ad.from_mujoco(**kw), compiled | common, view=view),
    ]


# ----- identification, parameterization ------------------------------------------------------

_SAMPLES: dict[int, dict[str, np.ndarray]] = {}


def samples(arm: ad.Robot) -> dict[str, np.ndarray]:
    """Well-exciting samples (40 states) with their torques."""
    if id(arm) not in _SAMPLES:
        rng = np.random.default_rng(1)
        lower, upper = arm.qlim
        low, high = np.where(np.isfinite(lower), lower, -np.pi), np.where(np.isfinite(upper), upper, np.pi)
        q = rng.uniform(low, high, (40, arm.n))
        qd, qdd = rng.uniform(-2, 2, (2, 40, arm.n))
        _SAMPLES[id(arm)] = {"q": q, "qd": qd, "qdd": qdd, "tau": arm.inverse_dynamics(q, qd, qdd)}
    return {k: v.copy() for k, v in _SAMPLES[id(arm)].items()}


DRIVES = Arg(lambda arm: True, lambda arm: choice_values([True, False, np.True_], [], ["no", 0, 1, None]))


def _count(low: int, high: int) -> Callable[[float], str]:
    """A rule for a count: at least ``low``; above ``high`` it may be refused."""

    def rule(x: float) -> str:
        if not np.isfinite(x) or x < low:
            return "bad"
        return "same" if x.is_integer() and x <= high else "either"

    return rule


def parameterization_targets() -> list[Target]:
    sample_args = {
        k: Arg(
            lambda arm, k=k: samples(arm)[k],
            lambda arm, k=k: state_values(samples(arm)[k], batch=False, bounded=k == "q"),
            sample=10,
        )
        for k in ("q", "qd", "qdd", "tau")
    }
    base_args = {
        "arm": _robot_arg(),
        "samples": Arg(lambda arm: 30, lambda arm: scalar_values([30, 12], _count(1, 10**4), integer=True)),
        "seed": Arg(lambda arm: 0, lambda arm: scalar_values([0, 5], _count(0, 10**9), integer=True)),
        "tolerance": Arg(
            lambda arm: 1e-9, lambda arm: scalar_values([1e-9, 0.5], lambda x: "same" if 0 < x < 1 else "bad")
        ),
        "drives": DRIVES,
        "at_rest": Arg(lambda arm: False, lambda arm: choice_values([True, False, np.True_], [], ["no", 0, 1, None])),
    }
    return [
        Target(
            "identify",
            lambda _arm, **kw: ad.identify(**kw),
            {"arm": _robot_arg(), **sample_args, "drives": DRIVES},
            [ARMS[0]],
            combos=4,
        ),
        Target("base_parameters", lambda _arm, **kw: ad.base_parameters(**kw), base_args, SMALL_ARMS),
        Target(
            "dynamics.regressor.parameters",
            lambda _arm, **kw: parameterization.parameters(**kw),
            {"arm": _robot_arg()},
            ARMS,
        ),
    ]


# ----- armdyn.kinematics and armdyn.lagrange as free functions --------------------------------


def _frames_values(arm: ad.Robot) -> Kinds:
    """Values for the joint frames (..., n, 4, 4) that joint_axes takes."""
    frames = kinematics.joint_frames(arm, states(arm)["q"])[1]
    nan, big = frames.copy(), frames.copy()
    nan[0, 0, 3] = np.nan
    big[0, 0, 3] = 1e300
    items = [
        Value("the frames", frames, "same", frames),
        Value("nested lists", frames.tolist(), "same", frames),
        Value("a batch of 2", np.stack([frames, frames]), "same", np.stack([frames, frames])),
        Value("read-only", fv._readonly(frames), "same", frames),
        Value("one frame fewer", frames[:-1], "bad"),
        Value("one frame (4, 4)", frames[0], "bad"),
        Value("3x3 frames", frames[:, :3, :3], "bad"),
        Value("NaN entry", nan, "bad"),
        Value("1e300 entry", big, "either"),
        Value("complex frames", frames + 0j, "either", frames, real_part=True),
        Value("text", np.full(frames.shape, "x"), "bad"),
    ]
    return items_values(items + junk())


def module_targets() -> list[Target]:
    robot = _robot_arg()
    q = _state_arg("q", complex_ok=True)
    qd = _state_arg("qd", complex_ok=True)
    qdd = _state_arg("qdd", complex_ok=True)
    value = Arg(lambda arm: states(arm)["q"], lambda arm: state_values(states(arm)["q"], complex_ok=True), names=("q",))
    targets = []
    for name, args in (
        ("joint_frames", {"q": q}),
        ("link_transforms", {"q": q}),
        ("tool_pose", {"q": q}),
        ("twist_generators", {"q": q}),
        ("link_transform_derivatives", {"q": q}),
        ("jacobian", {"q": q, "frame": FRAME, "link": LINK}),
        ("jacobian_dot", {"q": q, "qd": qd, "frame": FRAME, "link": LINK}),
        ("as_state", {"value": value}),
        ("joint_axes", {"joints": Arg(lambda arm: kinematics.joint_frames(arm, states(arm)["q"])[1], _frames_values)}),
    ):
        function = getattr(kinematics, name)
        targets.append(
            Target(f"kinematics.{name}", lambda _arm, f=function, **kw: f(**kw), {"arm": robot, **args}, ARMS)
        )
    three = np.array([0.1, 0.2, 0.3])
    targets += [
        Target(
            "kinematics.skew",
            lambda arm, **kw: kinematics.skew(**kw),
            {"v": Arg(lambda arm: three, lambda arm: state_values(three, complex_ok=True))},
        ),
        Target(
            "kinematics.joint_motion",
            lambda arm, **kw: kinematics.joint_motion(**kw),
            {
                "revolute": Arg(lambda arm: True, lambda arm: choice_values([True, False, np.False_], [1, "yes"])),
                "axis": Arg(lambda arm: [0.0, 0.0, 1.0], lambda arm: axis_values()),
                "q": Arg(
                    lambda arm: 0.3,
                    lambda arm: scalar_values([0.3, -1.0], finite, complex_verdict="either", arrays_ok=True),
                ),
            },
        ),
    ]
    lagrange = {
        "pseudo_inertias": {},
        "inertia_matrix": {"q": q},
        "second_derivatives": {"q": q},
        "inertia_matrix_partials": {"q": q},
        "inertia_matrix_dot": {"q": q, "qd": qd},
        "christoffel_symbols": {"q": q},
        "coriolis_matrix": {"q": q, "qd": qd},
        "coriolis_vector": {"q": q, "qd": qd},
        "potential_energy": {"q": q},
        "gravity_vector": {"q": q},
        "kinetic_energy": {"q": q, "qd": qd},
        "friction": {"qd": qd},
        "inverse_dynamics": {"q": q, "qd": qd, "qdd": qdd},
    }
    for name, args in lagrange.items():
        function = getattr(ad.lagrange, name)
        targets.append(Target(f"lagrange.{name}", lambda _arm, f=function, **kw: f(**kw), {"arm": robot, **args}, ARMS))
    return targets


# ----- controllers, trajectories, state-variable forms, properties ----------------------------


def _gain_values(arm: ad.Robot) -> Kinds:
    n = arm.n
    extra = [
        ("per joint", [5.0] * n, "same"),
        ("n+1 values", [5.0] * (n + 1), "bad"),
        ("negative entry", [5.0] * (n - 1) + [-1.0], "bad"),
        ("NaN entry", [5.0] * (n - 1) + [np.nan], "bad"),
        ("matrix (n, n)", np.eye(n) * 5.0, "bad"),
    ]
    return scalar_values([5.0, 0.0], non_negative, extra=extra)


def control_targets() -> list[Target]:
    def law(kind: str) -> Callable:
        def call(arm: ad.Robot, kp: object, kv: object, ki: object, q: object, qd: object) -> np.ndarray:
            controller = {
                "ComputedTorque": lambda: control.ComputedTorque(kp, kv, ki, model=arm),
                "PDGravity": lambda: control.PDGravity(kp, kv, model=arm),
                "PID": lambda: control.PID(kp, kv, ki),
            }[kind]()
            s = states(arm)
            return controller(0.0, q, qd, s["q"] * 0.9, s["qd"] * 0.5, s["qdd"], s["q"] * 0.1)

        return call

    gain = Arg(lambda arm: 5.0, _gain_values)
    state = {"q": _state_arg("q", bounded=False), "qd": _state_arg("qd")}  # the laws need no sine of q
    targets = [
        Target(
            "control.ComputedTorque(...)(t, q, qd, ...)",
            law("ComputedTorque"),
            {"kp": gain, "kv": gain, "ki": gain, **state},
            SMALL_ARMS,
        ),
        Target(
            "control.PID(...)(t, q, qd, ...)", law("PID"), {"kp": gain, "kv": gain, "ki": gain, **state}, SMALL_ARMS
        ),
        Target(
            "control.PDGravity(...)(t, q, qd, ...)",
            law("PDGravity"),
            {"kp": gain, "kv": gain, "ki": Arg(lambda arm: 0.0, None), **state},
            SMALL_ARMS,
        ),
    ]
    pid = control.PID(5.0, 1.0)
    wrapped = Arg(lambda arm: pid, lambda arm: _object_values(pid, control.PID, True), names=("controller",))
    limit = scalar_values([10.0, np.inf], lambda x: "same" if x > 0 and not np.isnan(x) else "bad")
    targets += [
        Target(
            "control.Saturated",
            lambda arm, **kw: control.Saturated(**kw),
            {"controller": wrapped, "limit": Arg(lambda arm: 10.0, lambda arm: limit, names=("torque limit",))},
            view=lambda saturated: np.minimum(np.atleast_1d(np.asarray(saturated.limit, dtype=float)), 1e308),
        ),
        Target(
            "control.Digital",
            lambda arm, **kw: control.Digital(**kw),
            {
                "controller": wrapped,
                "period": Arg(lambda arm: 0.01, lambda arm: scalar_values([0.01], positive), names=("sample period",)),
            },
        ),
    ]

    def sinusoid(arm: object, amplitude: object, frequency: object, phase: object, offset: object, t: object) -> tuple:
        return trajectories.Sinusoid(amplitude, frequency, phase, offset)(t, 3)

    def quintic(arm: object, q0: object, q1: object, t0: object, t1: object, t: object) -> tuple:
        return trajectories.Quintic(q0, q1, t0, t1)(t, 3)

    three = np.array([0.1, 0.2, 0.3])
    vector = Arg(lambda arm: three, lambda arm: state_values(three, batch=False, bounded=False, scalar_ok=True))
    time_arg = Arg(
        lambda arm: 0.3,
        lambda arm: scalar_values([0.3, 0.0], lambda x: "either" if np.isinf(x) else finite(x), arrays_ok=True),
    )
    t0 = Arg(lambda arm: 0.0, lambda arm: scalar_values([0.0, -1.0], lambda x: "bad" if x >= 1 else finite(x)))
    t1 = Arg(lambda arm: 1.0, lambda arm: scalar_values([1.0, 2.0], lambda x: "bad" if x <= 0 else finite(x)))
    targets += [
        Target(
            "trajectories.Sinusoid(...)(t)",
            sinusoid,
            {"amplitude": vector, "frequency": vector, "phase": vector, "offset": vector, "t": time_arg},
        ),
        Target(
            "trajectories.Quintic(...)(t)", quintic, {"q0": vector, "q1": vector, "t0": t0, "t1": t1, "t": time_arg}
        ),
    ]
    return targets


def statespace_targets() -> list[Target]:
    arm_arg = _robot_arg(robot_only=True)

    def x(arm: ad.Robot) -> np.ndarray:
        s = states(arm)
        return np.concatenate([s["q"], s["qd"]])

    x_arg = Arg(x, lambda arm: state_values(x(arm)), state=True)

    def jacobian_values(arm: ad.Robot) -> Kinds:
        n = arm.n
        return items_values(
            [
                Value("None", None, "same", None),
                Value(
                    "identity callable", lambda q: np.broadcast_to(np.eye(n), (*np.shape(q)[:-1], n, n)), "same", None
                ),
                Value("returns NaN", lambda q: np.full((n, n), np.nan), "bad"),
                Value("returns (n, n+1)", lambda q: np.zeros((n, n + 1)), "bad"),
                Value("returns a vector", lambda q: np.zeros(n), "bad"),
                Value("returns text", lambda q: "J", "bad"),
                Value("returns None", lambda q: None, "bad"),
                Value("not callable", np.eye(n), "bad"),
                Value("a string", "jacobian", "bad"),
            ]
        )

    def jdot_values(arm: ad.Robot) -> Kinds:
        return items_values(
            [
                Value("None", None, "same", None),
                Value("zeros without output_jacobian", lambda q, qd: np.zeros(arm.n), "bad"),
                Value("not callable", 3.0, "bad"),
            ]
        )

    n_values = scalar_values([2, 6], lambda x: "same" if x.is_integer() and 1 <= x <= 100 else "bad", integer=True)
    state = _state_arg
    return [
        Target(
            "statespace.state_derivative",
            lambda _, /, **kw: statespace.state_derivative(**kw),
            {"arm": arm_arg, "x": x_arg, "tau": state("tau")},
            ARMS,
        ),
        Target(
            "statespace.drift_and_input",
            lambda _, /, **kw: statespace.drift_and_input(**kw),
            {"arm": arm_arg, "x": x_arg},
            ARMS,
        ),
        Target(
            "statespace.brunovsky",
            lambda _, /, **kw: statespace.brunovsky(**kw),
            {"n": Arg(lambda arm: 2, lambda arm: n_values)},
        ),
        Target(
            "statespace.linearizing_torque",
            lambda _, /, **kw: statespace.linearizing_torque(**kw),
            {
                "arm": arm_arg,
                "q": state("q"),
                "qd": state("qd"),
                "u": state("qdd"),
                "output_jacobian": Arg(lambda arm: None, jacobian_values),
                "output_jacobian_dot_qd": Arg(lambda arm: None, jdot_values),
            },
            ARMS,
        ),
        Target(
            "statespace.hamiltonian",
            lambda _, /, **kw: statespace.hamiltonian(**kw),
            {"arm": arm_arg, "q": state("q"), "p": state("p")},
            ARMS,
        ),
        Target(
            "statespace.hamiltonian_rates",
            lambda _, /, **kw: statespace.hamiltonian_rates(**kw),
            {"arm": arm_arg, "q": state("q"), "p": state("p"), "tau": state("tau")},
            ARMS,
        ),
        Target(
            "statespace.linearize",
            lambda _, /, **kw: statespace.linearize(**kw),
            {"arm": arm_arg, "q0": _one_state("q"), "qd0": _one_state("qd"), "tau0": _one_state("tau")},
            SMALL_ARMS,
        ),
    ]


def _limits_values(arm: ad.Robot) -> Kinds:
    pairs = np.array([[-1.0, 1.0]] * arm.n)
    pairs[np.array(arm.kinds) == "prismatic"] = [0.2, 1.0]
    extra = [Value("None", None, "same", None), Value("lower > upper", pairs[:, ::-1].copy(), "bad")]
    return items_values(extra) + none_is_valid(state_values(pairs, batch=False, bounded=False))


def properties_targets() -> list[Target]:
    robot = _robot_arg(robot_only=True)
    only = Arg(
        lambda arm: "gravity",
        lambda arm: choice_values(
            ["gravity", ("inertia",), ["friction", "gravity"]], ["nope", (), [1], b"gravity", {"gravity": 1}, "Gravity"]
        ),
    )
    limits = Arg(lambda arm: None, _limits_values, names=("limits",), sample=25)
    check_args = {
        "arm": robot,
        "samples": Arg(lambda arm: 6, lambda arm: scalar_values([6, 4], _count(4, 50), integer=True)),
        "seed": Arg(lambda arm: 0, lambda arm: scalar_values([0, 3], _count(0, 10**6), integer=True)),
        "limits": limits,
        "only": only,
    }
    span = Arg(lambda arm: 1.0, lambda arm: scalar_values([1.0, 0.5], positive))
    return [
        Target("properties.check", lambda _arm, **kw: properties.check(**kw), check_args, SMALL_ARMS, combos=10),
        Target(
            "properties.joint_ranges",
            lambda _arm, **kw: properties.joint_ranges(**kw),
            {"arm": _robot_arg(True, symbolic_ok=True), "limits": limits, "prismatic_span": span},
            ARMS,
        ),
    ]


# ----- the surfaces added since: task space, drives, many runs, studies, derivatives, generated code --------


def _task_arms(square: bool) -> list[tuple[str, ad.Robot]]:
    """Arms with an output: square (m = n) for the task_* functions, m <= n for the operational space."""
    arms = [("two_link_planar", ARMS[0][1]), ("cylindrical", ARMS[1][1])]
    return arms if square else [*arms, ("puma560", ARMS[2][1])]


def _task_output(arm: ad.Robot) -> object:
    return task_space.PlanarPosition() if arm.n == 2 else task_space.ToolPosition()


def _task_rows(arm: ad.Robot) -> int:
    return 2 if arm.n == 2 else 3


def _output_values(arm: ad.Robot) -> Kinds:
    items = [
        Value("the output", _task_output(arm), "same", _task_output(arm)),
        Value("ToolPose (m = 6 rows)", task_space.ToolPose(), "either" if arm.n == 6 else "bad", names=("rows",)),
        Value("the output's class", type(_task_output(arm)), "bad"),
        Value("a Robot", arm, "bad"),
        Value("a string", "tool", "bad"),
    ]
    return items_values(items + junk())


def _task_state(key: str, m: bool = False, bounded: bool = False) -> Arg:
    """A state of a task function: q, qd, tau (n values) or yddot, f (m values, from qdd)."""

    def base(arm: ad.Robot) -> np.ndarray:
        return states(arm)[key][: _task_rows(arm)] if m else states(arm)[key]

    return Arg(base, lambda arm: state_values(base(arm), bounded=bounded), state=True, sample=18)


def _max_condition(x: float) -> str:
    if np.isnan(x) or x <= 0:
        return "bad"
    return "same" if 1e4 <= x < 1e15 else "either"


TASK_FUNCTIONS = {  # name: (its states (key, m values?), its out= shape from (n, m) or None, takes damping)
    "task_inertia": ((("q", False),), lambda n, m: (m, m), True),
    "task_coriolis": ((("q", False), ("qd", False)), lambda n, m: (m, m), True),
    "task_gravity": ((("q", False),), lambda n, m: (m,), True),
    "task_nonlinear": ((("q", False), ("qd", False)), lambda n, m: (m,), True),
    "task_friction": ((("q", False), ("qd", False)), lambda n, m: (m,), True),
    "task_regressor": ((("q", False), ("qd", False), ("yddot", True)), lambda n, m: (m, 14 * n), True),
    "task_force": ((("q", False), ("tau", False)), lambda n, m: (m,), True),
    "task_forward_dynamics": ((("q", False), ("qd", False), ("f", True)), lambda n, m: (m,), False),
    "task_inverse_dynamics": ((("q", False), ("qd", False), ("yddot", True)), lambda n, m: (n,), True),
    "operational_inertia": ((("q", False),), lambda n, m: (m, m), True),
    "operational_space": ((("q", False), ("qd", False)), None, True),
    "operational_coriolis": ((("q", False), ("qd", False)), None, True),
    "condition_number": ((("q", False),), None, False),
}
TASK_KEYS = {"q": "q", "qd": "qd", "tau": "tau", "yddot": "qdd", "f": "qdd"}


def _aliased_pair(shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Two arrays of ``shape`` sharing all but their first entry (one buffer)."""
    size = int(np.prod(shape))
    buffer = np.empty(size + 1)
    return buffer[:size].reshape(shape), buffer[1:].reshape(shape)


def _tuple_out_values(shapes: list[tuple[int, ...]], name: str) -> Kinds:
    """Values for an out= that is a tuple of arrays of ``shapes``: fresh ones (the result must be
    them), one array for two, overlapping ones, wrong lengths, dtypes and junk."""

    def fresh() -> Value:
        arrays = tuple(np.full(s, np.nan) for s in shapes)

        def check(result: object) -> str | None:
            parts = tuple(result) if isinstance(result, tuple) else tuple(vars(result).values())
            used = all(any(p is a for p in parts) for a in arrays)
            return None if used else f"{name} returned new arrays instead of out's"

        return Value("a tuple of fresh arrays", arrays, "same", None, check=check)

    def same_twice() -> Value:
        one = np.empty(shapes[0])
        return Value("one array for two outputs", (one,) * len(shapes), "bad")

    def overlapping() -> Value:
        if shapes[0] != shapes[1]:
            return Value("one array for two outputs", tuple(np.empty(s) for s in shapes[:1] * len(shapes)), "bad")
        a, b = _aliased_pair(shapes[0])
        return Value("two overlapping views of one buffer", (a, b, *(np.empty(s) for s in shapes[2:])), "bad")

    def one_dtype(dtype: object, label: str) -> Value:
        return Value(label, tuple(np.empty(s, dtype=dtype if i == 0 else float) for i, s in enumerate(shapes)), "bad")

    items = [
        Value("one short of a tuple", tuple(np.empty(s) for s in shapes[:-1]), "bad"),
        Value("one too many", tuple(np.empty(s) for s in [*shapes, shapes[0]]), "bad"),
        Value("one array, not a tuple", np.empty(shapes[0]), "bad"),
        Value("a read-only first array", tuple(_readonly_array(s, i == 0) for i, s in enumerate(shapes)), "bad"),
        Value("a tuple of lists", tuple(np.zeros(s).tolist() for s in shapes), "bad"),
        Value("a tuple of None", (None,) * len(shapes), "either"),
    ]
    kinds = [lazy(fresh), lazy(same_twice), lazy(overlapping)]
    kinds += [
        lazy(functools.partial(one_dtype, d, f"{label} first array"))
        for d, label in ((np.float32, "float32"), (np.int64, "int64"), (complex, "complex128"), (">f8", "big-endian"))
    ]
    return none_is_valid(kinds + items_values(items + junk(skip=("None",))))


def _readonly_array(shape: tuple[int, ...], readonly: bool) -> np.ndarray:
    array = np.empty(shape)
    array.setflags(write=not readonly)
    return array


def _space_shapes(arm: ad.Robot, name: str) -> list[tuple[int, ...]]:
    n, m = arm.n, _task_rows(arm)
    if name == "operational_coriolis":
        return [(m, m), (m,)]
    return [(m, n), (m, m), (n, m), (m,), (m,), (m,), (n, n)]  # J, Lambda, Jbar, mu, p, friction, Nproj


def task_space_targets() -> list[Target]:
    damping = Arg(lambda arm: None, lambda arm: none_is_valid(scalar_values([1e-3, 0.1], positive)))
    max_condition = Arg(lambda arm: 1e8, lambda arm: scalar_values([1e8, 1e6], _max_condition))
    targets = []
    for name, (keys, shape, damped) in TASK_FUNCTIONS.items():
        function = getattr(task_space, name)
        args = {"arm": _robot_arg(robot_only=True), "output": Arg(_task_output, _output_values)}
        args |= {k: _task_state(TASK_KEYS[k], m, bounded=k == "q") for k, m in keys}
        if damped:
            args |= {"damping": damping, "max_condition": max_condition}
        if shape is not None:
            args["out"] = _out_arg(lambda arm, s=shape: s(arm.n, _task_rows(arm)))
        elif name.startswith("operational_"):
            args["out"] = Arg(lambda arm: None, lambda arm, k=name: _tuple_out_values(_space_shapes(arm, k), k),
                              alone=True)  # fmt: skip
        arms = _task_arms(square=not name.startswith("operational_") and name != "condition_number")
        view = (lambda space: tuple(vars(space).values())) if name == "operational_space" else None
        call = functools.partial(_task_call, function)
        targets.append(Target(f"task_space.{name}", call, args, arms, view=view, combos=8))
    jacobian = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.2]])
    targets.append(
        Target(
            "task_space.damped_inverse",
            lambda _arm, **kw: task_space.damped_inverse(**kw),
            {
                "J": Arg(lambda arm: jacobian, lambda arm: relabel(state_values(jacobian, bounded=False), ANY_SHAPE)),
                "damping": Arg(lambda arm: 0.1, lambda arm: scalar_values([0.1, 1e-3], positive)),
            },
        )
    )
    return targets


ANY_SHAPE = dict.fromkeys(
    [
        "shape (n-1,)",
        "shape (n+1,)",
        "shape (2, n+1)",
        "shape (n, 1)",
        "empty batch (0, n)",
        "list of 1-element arrays",
    ],
    "either",
)  # a Jacobian of any (m, n) or (..., m, n) shape is valid: the shapes a state's generic rule refuses


def _task_call(function: Callable, _arm: ad.Robot, **kwargs: object) -> object:
    return function(**kwargs)


# drives


SYMBOLS = (
    "J_M",
    "B_M",
    "K_M",
    "K_b",
    "R_a",
    "inductance L",
    "gear ratio r",
    "voltage limit",
    "current limit",
    "Coulomb",
    "B_s",
    "shaft stiffness K",
    "tau_v",
    "K_v",
    "K_q",
    "K_c",
    "D_m",
    "area A",
    "C_tp",
    "V_t",
    "beta_e",
    "P_s",
    "stroke",
)  # how a drive's messages name its parameters (as its docstring does)


def _motor_args() -> dict[str, Arg]:
    def number(valid: float, rule: Callable[[float], str], none: str = "bad", *extra: tuple) -> Arg:
        return Arg(lambda arm: valid, lambda arm: scalar_values([valid], rule, none=none, extra=extra), names=SYMBOLS)

    def limit(x: float) -> str:
        return "bad" if np.isnan(x) or x <= 0 else "same" if x < 1e15 or x == np.inf else "either"

    def ratio(x: float) -> str:
        return "bad" if not np.isfinite(x) or x == 0 else "same" if 1e-200 < abs(x) < 1e15 else "either"

    coulomb_pairs = [("a pair (0.1, -0.1)", (0.1, -0.1), "same"), ("pair with Tc- > 0", (0.1, 0.1), "bad"),
                     ("pair with NaN", (np.nan, -0.1), "bad"), ("three values", (0.1, -0.1, 0.0), "bad")]  # fmt: skip
    return {
        "rotor_inertia": number(2e-4, non_negative),
        "viscous": number(1e-3, non_negative),
        "torque_constant": number(0.2, positive),
        "back_emf": number(0.2, positive),
        "resistance": number(2.0, positive),
        "inductance": number(2e-3, non_negative),
        "gear_ratio": number(0.02, ratio),
        "voltage_limit": number(40.0, limit),
        "current_limit": number(8.0, limit),
        "coulomb": number(0.0, non_negative, "bad", *coulomb_pairs),
        "stiffness": Arg(lambda arm: None, lambda arm: none_is_valid(scalar_values([300.0], positive))),
        "shaft_damping": number(0.0, lambda x: "either" if x > 0 and np.isfinite(x) else non_negative(x)),
        "name": Arg(lambda arm: "motor", lambda arm: choice_values(["motor", "m1"], [], ["", "a */ b", "x\n\x00"])),
    }


def _valve_args() -> dict[str, Arg]:
    valid = dict(valve_time_constant=5e-3, valve_gain=0.1, flow_gain=0.1, pressure_coefficient=1e-11, area=1e-3,
                 leakage=1e-11, volume=2e-4, bulk_modulus=1.4e9, supply_pressure=7e6)  # fmt: skip
    rules = dict(pressure_coefficient=non_negative, leakage=non_negative)

    def limit(x: float) -> str:
        return "bad" if np.isnan(x) or x <= 0 else "same" if x < 1e15 or x == np.inf else "either"

    args = {
        k: Arg(lambda arm, v=v: v, lambda arm, v=v, k=k: scalar_values([v], rules.get(k, positive)), names=SYMBOLS)
        for k, v in valid.items()
    }
    args["flow_gain"] = Arg(lambda arm: 0.1, lambda arm: scalar_values([0.1], positive), names=SYMBOLS)
    args["rotary"] = Arg(lambda arm: True, lambda arm: choice_values([True, False], ["yes", 1, None]))
    args["orifice"] = Arg(lambda arm: "linear", lambda arm: choice_values(["linear"], ["", "SQRT", "cubic"], ["sqrt"]))
    args["current_limit"] = Arg(lambda arm: np.inf, lambda arm: scalar_values([0.5], limit), names=SYMBOLS)
    args["stroke"] = Arg(lambda arm: np.inf, lambda arm: scalar_values([1e-3], limit), names=SYMBOLS)
    return args


def _drive_view(drive: object) -> np.ndarray:
    """A drive's numbers, the limits' infinity kept as 1e308 (a NaN stays a NaN)."""
    numbers = []
    for f in dataclasses.fields(drive):
        value = getattr(drive, f.name)
        if isinstance(value, (int, float, np.number)) or (isinstance(value, tuple) and f.name == "coulomb"):
            numbers += list(np.ravel(np.asarray(value, dtype=float)))
    array = np.array(numbers)
    return np.where(np.isinf(array), np.sign(array) * 1e308, array)


def _motor() -> object:
    return actuators.DCMotor(2e-4, 1e-3, 0.2, 0.2, 2.0, 2e-3, 0.02, voltage_limit=40.0, current_limit=8.0)


def _valve() -> object:
    return actuators.Hydraulic(5e-3, 0.1, 1.0, 1e-12, 1e-4, 1e-12, 1e-4, 1e9, 1e7, rotary=True, current_limit=0.5)


@functools.cache
def _driven_arms() -> list[tuple[str, object]]:
    """Arms with drives: two_link_planar on rigid DC motors, and on a flexible motor and a rotary valve."""
    arm = ARMS[0][1]
    flexible = dataclasses.replace(_motor(), stiffness=300.0, shaft_damping=0.5, name="flexible")
    return [
        ("two_link_planar, DC motors", actuators.with_actuators(arm, [_motor(), _motor()])),
        ("two_link_planar, flexible motor and valve", actuators.with_actuators(arm, [flexible, _valve()])),
    ]


def _drives_values(arm: ad.Robot) -> Kinds:
    motor = _motor()
    items = [
        Value("two motors", [motor, motor], "same", [motor, motor]),
        Value("a tuple of two", (motor, motor), "same", [motor, motor]),
        Value("a motor and a rotary valve", [motor, _valve()], "either"),
        Value("one motor", [motor], "bad"),
        Value("three motors", [motor] * 3, "bad"),
        Value("a lone motor", motor, "bad"),
        Value(
            "a piston on a revolute joint",
            [motor, dataclasses.replace(_valve(), rotary=False)],
            "bad",
            names=("revolute", "rotary"),
        ),
        Value("None in the list", [motor, None], "bad"),
        Value("a number in the list", [motor, 1.0], "bad"),
        Value("the DCMotor class", [motor, actuators.DCMotor], "bad"),
        Value("empty list", [], "bad"),
    ]
    return items_values(items + junk())


def _driven_state(arm: object) -> dict[str, np.ndarray]:
    q = states(arm.robot)["q"]
    x = arm.initial_state(q, states(arm.robot)["qd"])
    return {"q": q, "qd": states(arm.robot)["qd"], "x": x + 0.1 * np.arange(x.size) / x.size, "v": np.full(arm.n, 2.0)}


def _driven_arg(key: str, bounded: bool = False, batch: bool = True, none_ok: bool = False) -> Arg:
    def values(arm: object) -> Kinds:
        kinds = state_values(_driven_state(arm)[key], bounded=bounded, batch=batch)
        return none_is_valid(kinds) if none_ok else kinds

    return Arg(lambda arm: _driven_state(arm)[key], values, state=batch)


ZERO_IS_BAD = {"negative zeros": "bad"}  # -0.0 where the rule is > 0 (a bandwidth, a mass scale)
PER_VARIANT = {  # (count, n) = (3, 2) factors: one row per variant is valid (a batch of 2 or 1 is not)
    **ZERO_IS_BAD,
    "broadcast view (stride 0)": "same",
    "mismatched batch (3, n) vs (2, n)": "either",
}


def actuator_targets() -> list[Target]:
    no_arm = [("-", None)]
    drives_args = {"arm": _robot_arg(robot_only=True), "drives": Arg(lambda arm: [_motor()] * arm.n, _drives_values)}
    bandwidth = Arg(lambda arm: None, lambda arm: none_is_valid(relabel(
        state_values(np.full(arm.n, 500.0), batch=False, bounded=False, scalar_ok=True), ZERO_IS_BAD)))  # fmt: skip
    driven = _driven_arms()
    return [
        Target(
            "actuators.DCMotor",
            lambda arm, **kw: actuators.DCMotor(**kw),
            _motor_args(),
            no_arm,
            view=_drive_view,
            combos=10,
        ),
        Target(
            "actuators.Hydraulic",
            lambda arm, **kw: actuators.Hydraulic(**kw),
            _valve_args(),
            no_arm,
            view=_drive_view,
            combos=10,
        ),
        Target(
            "actuators.with_actuators",
            lambda _arm, **kw: actuators.with_actuators(**kw),
            drives_args,
            [ARMS[0]],
            view=lambda a: np.minimum(a.packed_drives(), 1e308),
            combos=5,
        ),
        Target(
            "actuators.ActuatedArm(robot, drives)",
            lambda _arm, **kw: actuators.ActuatedArm(kw["arm"], kw["drives"]),
            drives_args,
            [ARMS[0]],
            view=lambda a: np.minimum(a.packed_drives(), 1e308),
            combos=5,
        ),
        Target(
            "ActuatedArm.state_derivative",
            lambda arm, **kw: arm.state_derivative(**kw),
            {"x": _driven_arg("x"), "v": _driven_arg("v")},
            driven,
            combos=10,
        ),
        Target(
            "ActuatedArm.initial_state",
            lambda arm, **kw: arm.initial_state(**kw),
            {"q": _driven_arg("q", bounded=True), "qd": _driven_arg("qd", none_ok=True)},
            driven,
            combos=10,
        ),
        Target(
            "ActuatedArm.stable_step",
            lambda arm, **kw: arm.stable_step(**kw),
            {"q": _driven_arg("q", bounded=True, batch=False), "bandwidth": bandwidth},
            driven,
            combos=10,
        ),
    ]


# derivatives with out= and the smoothed Coulomb law


def derivative_targets() -> list[Target]:
    smoothing = choice_values([], ["AUTO", ""], ["auto"], junk="bad") + none_is_valid(
        scalar_values([0.0, 1e-3], non_negative)
    )
    targets = []
    for name, third, count in (("inverse_dynamics_derivatives", "qdd", 2), ("forward_dynamics_derivatives", "tau", 3)):
        args = {k: Arg(lambda arm, k=k: states(arm)[k], None) for k in ("q", "qd", third)}
        args["out"] = Arg(
            lambda arm, c=count: None, lambda arm, c=count: _tuple_out_values([(arm.n, arm.n)] * c, "out"), alone=True
        )
        args["coulomb_smoothing"] = Arg(lambda arm: None, lambda arm: smoothing)
        targets.append(_method(f"{name} (out=, coulomb_smoothing=)", args, corrupt_two=False))
        targets[-1].call = functools.partial(_call_method, name)
    return targets


# generated code


def _generated(arm: ad.Robot, functions: object = ("tau",)) -> object:
    return ad.symbolic.generate_code(arm, functions)


def generated_code_targets() -> list[Target]:
    arms = [ARMS[0], ARMS[1]]
    functions = items_values(
        [
            Value("('tau',)", ("tau",), "same", ("tau",)),
            Value("'tau' (one name)", "tau", "same", ("tau",)),
            Value("every function", ["tau", "M", "G", "N", "Vm", "Wb"], "either"),
            Value("an unknown name", ["tau", "D"], "bad"),
            Value("a name in another case", ["TAU"], "bad"),
            Value("empty list", [], "bad"),
            Value("a number in the list", ["tau", 1], "bad"),
            Value("a generator", (f for f in ["tau"]), "either"),
            *junk(),
        ]
    )

    def c_source(arm: ad.Robot, prefix: object) -> str:
        return _generated(arm).c(prefix)

    prefixes = choice_values(
        ["armdyn_", "", "my_arm_", "_x"],
        ["1x", "a b", "a-b", "x;", "*/", "a\n", "é_"],
        ["A", "x" * 200],
    )

    def python_source(arm: ad.Robot) -> str:
        return _generated(arm).python()

    def compiled(arm: ad.Robot, values: object) -> np.ndarray:
        return CLOSED_FORM().compile(values).M(np.array([0.3, 0.7]))

    def values_values(arm: ad.Robot) -> Kinds:
        names = CLOSED_FORM()._parameter_names()
        valid = dict.fromkeys(names, 1.0)
        first = names[0]
        items = [
            Value("every parameter", valid, "same", valid),
            Value("numpy floats", {k: np.float64(1.0) for k in names}, "same", valid),
            Value("one missing", {k: 1.0 for k in names[1:]}, "bad", names=(first, "values")),
            Value("one NaN", {**valid, first: np.nan}, "bad", names=(first, "values")),
            Value("one inf", {**valid, first: np.inf}, "bad", names=(first, "values")),
            Value("one text", {**valid, first: "heavy"}, "bad", names=(first, "values")),
            Value("one complex", {**valid, first: 1j}, "bad", names=(first, "values")),
            Value("one array", {**valid, first: np.ones(2)}, "bad", names=(first, "values")),
            Value("an unknown key too", {**valid, "zz": 1.0}, "either", valid),
            Value("a list", list(valid.values()), "bad"),
            Value("None", None, "bad"),
        ]
        return items_values(items + junk(skip=("None", "dict")))

    return [
        Target(
            "symbolic.generate_code",
            lambda arm, **kw: _generated(arm, **kw).python(),
            {"functions": Arg(lambda arm: ("tau",), lambda arm: functions)},
            arms,
            view=lambda source: len(source),
        ),
        Target(
            "GeneratedCode.c(prefix)",
            c_source,
            {"prefix": Arg(lambda arm: "armdyn_", lambda arm: prefixes, names=("prefix", "identifier"))},
            arms,
            view=lambda source: 0,
        ),
        Target("GeneratedCode.python()", python_source, {}, arms, view=lambda source: 0),
        Target(
            "ClosedForm.compile(values)",
            compiled,
            {"values": Arg(lambda arm: dict.fromkeys(CLOSED_FORM()._parameter_names(), 1.0), values_values)},
            [ARMS[0]],
            corrupt_two=False,
        ),
    ]


@functools.cache
def CLOSED_FORM() -> object:
    return ad.symbolic.derive(ad.models.two_link_planar(symbolic=True))


# studies


def _spec_values() -> Kinds:
    items = [
        Value("the default", "max_error_after < 1e-3", "same", "max_error_after < 1e-3"),
        Value("two clauses", "max_error_after < 1e-3 and max_tau < 200", "either"),
        Value("a window of 0.01 s", "max-error-after-0.01s < 1e-3", "either"),
        Value("a window past t_final", "max-error-after-9s < 1e-3", "either", names=("window", "after", "t_final")),
        Value("a joint", "max_error_after theta2 < 1e-3", "either"),
        Value("an unknown joint", "max_error_after q9 < 1e-3", "either"),
        Value("a Requirement", study.Requirement("max_tau < 200"), "either"),
        Value("bound 1e-3e5", "max_error_after < 1e-3e5", "bad", names=("spec", "bound", "1e-3e5")),
        Value("bound nan", "max_error_after < nan", "bad", names=("spec", "bound")),
        Value("bound inf", "max_tau < inf", "bad", names=("spec", "bound")),
        Value("no operator", "max_error_after 1e-3", "bad", names=("spec",)),
        Value("an unknown quantity", "speed < 1", "bad", names=("spec", "quantity")),
        Value("empty", "", "bad", names=("spec",)),
        Value("'and' alone", "and", "bad", names=("spec",)),
    ]
    return items_values(items + junk(skip=("str",), names=("spec",)))


def _distribution_values(valid: object) -> Kinds:
    items = [
        Value("Uniform(0, 0.5)", study.Uniform(0.0, 0.5), "same", study.Uniform(0.0, 0.5)),
        Value("Normal(0, 0.1)", study.Normal(0.0, 0.1), "either"),
        Value("Normal truncated", study.Normal(0.0, 0.1, -0.1, 0.1), "either"),
        Value("a constant 0.1", 0.1, "either"),
        Value("None", None, "either"),
        Value("NaN", np.nan, "bad"),
        Value("inf", np.inf, "bad"),
        Value("text", "wide", "bad"),
        Value("a Uniform's class", study.Uniform, "bad"),
        Value("a list of two", [0.0, 0.5], "bad"),
    ]
    return items_values(items + junk(skip=("None", "str")))


def _spec_class_targets() -> list[Target]:
    def uniform(_arm: object, low: object, high: object) -> object:
        made = study.Uniform(low, high)
        return np.array([made.low, made.high, *made.sample(np.random.default_rng(0), (3,))])

    def normal(_arm: object, mean: object, std: object, low: object, high: object) -> object:
        made = study.Normal(mean, std, low, high)
        return np.array([made.mean, made.std, *made.sample(np.random.default_rng(0), (3,))])

    def bounds(x: float) -> str:
        return "bad" if np.isnan(x) else "either"

    return [
        Target(
            "study.Uniform",
            uniform,
            {
                "low": Arg(lambda a: 0.0, lambda a: scalar_values([0.0], lambda x: "bad" if x > 0.5 else finite(x))),
                "high": Arg(lambda a: 0.5, lambda a: scalar_values([0.5], lambda x: "bad" if x < 0 else finite(x))),
            },
        ),
        Target(
            "study.Normal",
            normal,
            {
                "mean": Arg(
                    lambda a: 0.0,
                    lambda a: scalar_values([0.0, 0.1], lambda x: "either" if abs(x) > 0.5 else finite(x)),
                ),
                "std": Arg(lambda a: 0.1, lambda a: scalar_values([0.1], non_negative)),
                "low": Arg(
                    lambda a: -1.0,
                    lambda a: scalar_values([-1.0], lambda x: "bad" if np.isnan(x) or x >= 1 else "either"),
                ),
                "high": Arg(
                    lambda a: 1.0,
                    lambda a: scalar_values([1.0], lambda x: "bad" if np.isnan(x) or x <= -1 else "either"),
                ),
            },
        ),
        Target(
            "study.Requirement",
            lambda _arm, text: study.Requirement(text).clauses[0][2],
            {"text": Arg(lambda a: "max_error_after < 1e-3", lambda a: _spec_values())},
        ),
    ]


def _study_table(result: object) -> np.ndarray:
    table = result.table
    return np.asarray(table.select_dtypes("number"), dtype=float)


_STUDY_FOLDERS = [0]


def _fresh_folder() -> Path:
    _STUDY_FOLDERS[0] += 1
    return SCRATCH / f"study-{_STUDY_FOLDERS[0]}"


def study_targets() -> list[Target]:
    arm = ARMS[0][1]
    pid = control.PID(10.0, 2.0)
    laws = items_values(
        [
            Value("PID", pid, "same", pid),
            Value("ComputedTorque", control.ComputedTorque(100.0, 20.0), "either"),
            Value("Saturated PID", control.Saturated(pid, 5.0), "either"),
            Value("a DrivePID (a drive law)", control.drives.DrivePID(1.0, 0.1), "bad"),
            Value("PID kp NaN", control.PID(np.nan, 2.0), "bad", names=("kp",)),
            Value("a callable", lambda *a: np.zeros(2), "bad"),
            Value("None", None, "bad"),
            Value("the PID class", control.PID, "bad"),
        ]
    )
    paths = items_values(
        [
            Value("None", None, "same", None),
            Value("Sinusoid", trajectories.Sinusoid(0.1, 0.5), "either"),
            Value("Sinusoid of 3 joints", trajectories.Sinusoid([0.1] * 3, 0.5), "bad", names=("amplitude",)),
            Value("a callable", lambda t: (np.zeros(2),) * 3, "bad"),
            Value("a string", "sine", "bad"),
        ]
    )
    seconds = scalar_values([0.02], positive, extra=[("1e9 s", 1e9, "either"), ("not whole steps", 0.0205, "bad")])

    def make(_arm: object, **kw: object) -> object:
        made = study.Study(arm, **{"t_final": 0.02, "block": 4, **kw})
        return _study_table(made.run(5))

    def run(_arm: object, **kw: object) -> object:
        made = study.Study(arm, pid, t_final=0.02, after=0.01, payload=study.Uniform(0.0, 0.5), block=4)
        if isinstance(kw.get("out"), Value):
            kw["out"] = kw["out"].value
        return _study_table(made.run(**kw))

    def folder_values(arm: object) -> Kinds:
        def fresh() -> Value:
            return Value("a fresh folder", _fresh_folder(), "same", None)

        def missing_parent() -> Value:
            return Value("a folder whose parent is missing", _fresh_folder() / "a" / "b", "either", None)

        def a_file() -> Value:
            path = _write("not a folder", ".txt")
            return Value("a file", path, "bad")

        def read_only() -> Value:
            path = _fresh_folder()
            path.mkdir()
            path.chmod(0o500)
            return Value("a read-only folder", path, "bad" if os.geteuid() != 0 else "either")

        def other_study() -> Value:
            path = _fresh_folder()
            study.Study(ARMS[0][1], control.PID(5.0, 1.0), t_final=0.02, after=0.01, block=4).run(5, out=path)
            return Value("a folder of another study", path, "bad", names=("out", "another", "differ"))

        def damaged() -> Value:
            path = _fresh_folder()
            made = study.Study(ARMS[0][1], pid, t_final=0.02, after=0.01, payload=study.Uniform(0.0, 0.5), block=4)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                made.run(5, out=path)
            block = sorted(p for p in path.iterdir() if p.suffix == ".parquet")[0]
            block.write_bytes(block.read_bytes()[:40])
            return Value("a folder with a truncated block", path, "same", None)

        kinds = [lazy(fresh), lazy(missing_parent), lazy(a_file), lazy(read_only), lazy(other_study), lazy(damaged)]
        return none_is_valid(kinds + items_values(junk(skip=("None", "str", "bytes"))))

    counts = scalar_values([5, 3], _count(1, 100), integer=True, extra=[("10**12 runs", 10**12, "bad")])
    return [
        *_spec_class_targets(),
        Target(
            "study.Study(...)",
            make,
            {
                "controller": Arg(lambda a: pid, lambda a: laws, names=("controller", "law")),
                "trajectory": Arg(lambda a: None, lambda a: paths),
                "spec": Arg(lambda a: "max_error_after < 1e-3", lambda a: _spec_values(), sample=8),
                "after": Arg(
                    lambda a: 0.01,
                    lambda a: scalar_values([0.01], lambda x: "bad" if not 0 <= x < 0.02 else "same"),
                    sample=8,
                ),
                "dt": Arg(
                    lambda a: 1e-3,
                    lambda a: scalar_values([1e-3], lambda x: "bad" if not 0 < x <= 0.02 else "either"),
                    sample=8,
                ),
                "t_final": Arg(lambda a: 0.02, lambda a: seconds, sample=8),
                "payload": Arg(lambda a: None, lambda a: _distribution_values(None)),
                "start_error": Arg(lambda a: None, lambda a: _distribution_values(None), sample=6),
                "block": Arg(
                    lambda a: 4,
                    lambda a: scalar_values(
                        [4, 2],
                        lambda x: (
                            "same"
                            if x >= 1 and np.isfinite(x) and x < 1e15
                            else "bad"
                            if not np.isfinite(x) or x < 1
                            else "either"
                        ),
                        integer=True,
                    ),
                    sample=8,
                ),
            },
            combos=4,
        ),
        Target(
            "Study.run",
            run,
            {
                "runs": Arg(lambda a: 5, lambda a: counts, sample=10),
                "seed": Arg(
                    lambda a: 0,
                    lambda a: scalar_values(
                        [0, 7],
                        lambda x: (
                            "same"
                            if x.is_integer() and 0 <= x < 2**63
                            else "bad"
                            if x < 0 or not np.isfinite(x)
                            else "either"
                        ),
                        integer=True,
                    ),
                    sample=8,
                ),
                "out": Arg(lambda a: None, folder_values),
                "confidence": Arg(
                    lambda a: 0.95,
                    lambda a: scalar_values([0.95, 0.5], lambda x: "same" if 0 < x < 1 else "bad"),
                    sample=8,
                ),
                "progress": Arg(
                    lambda a: None,
                    lambda a: items_values(
                        [
                            Value("None", None, "same", None),
                            Value("print", print, "either"),
                            Value("5", 5, "bad"),
                            Value("text", "bar", "bad"),
                        ]
                    ),
                ),
                "timeout": Arg(lambda a: 10.0, lambda a: scalar_values([10.0], positive), sample=8),
                "damaged": Arg(
                    lambda a: "recompute", lambda a: choice_values(["recompute", "refuse"], ["", "REFUSE", "ignore"])
                ),
            },
            combos=4,
        ),
    ]


# simulate with drives and with many runs (risky: child interpreters)


def _driven_simulation_targets() -> list[Target]:
    drive_pid, cct = control.drives.DrivePID(20.0, 0.5), control.drives.CurrentComputedTorque(100.0, 20.0)

    def laws(arm: object) -> Kinds:
        return items_values(
            [
                Value("DrivePID", drive_pid, "same", drive_pid),
                Value("CurrentComputedTorque", cct, "either"),
                Value(
                    "CurrentComputedTorque with bandwidth",
                    control.drives.CurrentComputedTorque(100.0, 20.0, 0.0, 2000.0),
                    "either",
                ),
                Value("DrivePID kp NaN", control.drives.DrivePID(np.nan, 0.5), "bad", names=("kp",)),
                Value("DrivePID kv negative", control.drives.DrivePID(1.0, -0.5), "bad", names=("kv",)),
                Value("DrivePID 3 gains", control.drives.DrivePID([1.0] * 3, 0.5), "bad", names=("kp",)),
                Value(
                    "CurrentComputedTorque bandwidth 0",
                    control.drives.CurrentComputedTorque(1.0, 1.0, 0.0, 0.0),
                    "bad",
                    names=("bandwidth",),
                ),
                Value("a joint PID", control.PID(10.0, 2.0), "bad", names=("controller",)),
                Value("None", None, "either", names=("controller",)),
                Value("a callable", lambda *a: np.zeros(2), "bad", names=("controller",)),
            ]
        )

    def step_rule(x: float) -> str:  # more than 10**6 steps per sample of dt = 1 ms is refused
        return "bad" if x < 1e-9 else positive(x)

    tiny = ("1e-12 s (10**9 steps a sample)", 1e-12, "bad")
    step = none_is_valid(scalar_values([1e-4, 2e-4], step_rule, extra=[("1 s (above dt)", 1.0, "either"), tiny]))
    seconds = scalar_values(
        [0.01, 0.02], positive, extra=[("1e9 s", 1e9, "either"), ("not whole steps", 0.0105, "bad")]
    )
    args = {
        "controller": Arg(lambda arm: drive_pid, laws),
        "t_final": Arg(lambda arm: 0.01, lambda arm: seconds),
        "dt": Arg(
            lambda arm: 1e-3, lambda arm: scalar_values([1e-3], _divides(0.01), extra=[("1e-12 s", 1e-12, "either")])
        ),
        "step": Arg(lambda arm: None, lambda arm: step),
        "q0": Arg(
            lambda arm: states(arm.robot)["q"],
            lambda arm: none_is_valid(state_values(states(arm.robot)["q"], batch=False)),
            sample=20,
        ),
        "qd0": Arg(
            lambda arm: None,
            lambda arm: none_is_valid(state_values(states(arm.robot)["qd"], batch=False, bounded=False)),
            sample=20,
        ),
        "method": Arg(lambda arm: "rk4", lambda arm: choice_values(["rk4"], ["rk45", "euler", ""])),
        "joint_limits": Arg(
            lambda arm: "warn", lambda arm: choice_values(["warn", "ignore", "stop"], ["spring", "", "WARN"])
        ),
    }
    return [
        Target(
            "simulate (arm with drives)",
            lambda arm, **kw: ad.simulate(arm, **kw),
            args,
            _driven_arms(),
            view=_driven_run,
            combos=10,
        )
    ]


def _divides(t_final: float) -> Callable[[float], str]:
    """A rule for dt: positive, and t_final a whole number of its steps (else refused, naming dt)."""

    def rule(x: float) -> str:
        verdict = positive(x)
        whole = abs(t_final / x - round(t_final / x)) <= 1e-9 * (t_final / x) if verdict != "bad" else False
        return "bad" if verdict == "same" and (not whole or round(t_final / x) < 1) else verdict

    return rule


def _driven_run(result: object) -> tuple[np.ndarray, ...]:
    """What a run with drives computed: q, qd, qdd, tau and the drives' states and inputs (not their
    limit tables, whose infinities mean no limit)."""
    return result.q, result.qd, result.qdd, result.tau, result.drives.x, result.drives.v


def _many_run_targets() -> list[Target]:
    from armdyn.simulation import plant_variants

    pid = control.PID(10.0, 2.0)
    arm0 = ARMS[0][1]

    def plants(arm: ad.Robot) -> Kinds:
        items = [
            Value("None", None, "same", None),
            Value("the arm", arm, "either"),
            Value("3 variants", plant_variants(arm, 3, payload_mass=[0.0, 0.1, 0.2]), "either"),
            Value("variants of another arm", plant_variants(ARMS[2][1], 3), "bad", names=("joints", "plants")),
            Value("4 variants for 3 runs", plant_variants(arm, 4), "bad", names=("runs", "plants", "variants")),
            Value("a list of arms", [arm, arm, arm], "bad"),
            Value("a symbolic arm", ad.models.two_link_planar(symbolic=True), "bad"),
        ]
        return items_values(items + junk(skip=("None",)))

    def variant_call(_arm: object, **kw: object) -> object:
        variants = plant_variants(arm0, **kw)
        return variants.packed, variants.coulomb

    n = arm0.n
    gain_rows = np.array([[10.0] * n, [2.0] * n, [0.0] * n])

    def gains(arm: ad.Robot) -> Kinds:
        items = [
            Value("(3, n)", gain_rows, "same", gain_rows),
            Value("(N, 3, n)", np.stack([gain_rows] * 3), "same", gain_rows),
            Value("(N+1, 3, n)", np.stack([gain_rows] * 4), "bad"),
            Value("(2, n)", gain_rows[:2], "bad"),
            Value("a negative kp", gain_rows * [[-1.0], [1.0], [1.0]], "bad", names=("kp", "gains")),
            Value("NaN entry", np.where(gain_rows == 10.0, np.nan, gain_rows), "bad"),
            Value("inf entry", np.where(gain_rows == 10.0, np.inf, gain_rows), "bad"),
            Value("text", "high", "bad"),
            Value("a list", gain_rows.tolist(), "same", gain_rows),
            Value("a scalar", 5.0, "bad"),
            Value("complex", gain_rows + 1j, "bad"),
        ]
        return none_is_valid(items_values(items + junk(skip=("None",))))

    keep = choice_values(
        ["summary", "full", 2, 1],
        ["all", "", 0, -1, 1.5, np.nan, 10**20, 10**400, 11],
        ["FULL", np.int64(3), True, 100],
    )
    after = none_is_valid(
        scalar_values([0.005, 0.0], lambda x: "same" if 0 <= x <= 0.01 else "bad", extra=[("text", "0.005", "either")])
    )
    runs = none_is_valid(
        scalar_values(
            [3, 1],
            lambda x: (
                "same" if x.is_integer() and 1 <= x <= 1e6 else "bad" if x < 1 or not np.isfinite(x) else "either"
            ),
            integer=True,
            extra=[("10**12 runs", 10**12, "bad"), ("2**62 runs", 2**62, "bad")],
        )
    )
    threads = none_is_valid(
        scalar_values(
            [1, 2],
            lambda x: "same" if x in (1, 2) else "bad" if x < 1 or not np.isfinite(x) or x > 1e6 else "either",
            integer=True,
        )
    )

    def rows(key: str) -> Callable[[ad.Robot], Kinds]:
        def values(arm: ad.Robot) -> Kinds:
            base = states(arm)[key] * 0.1
            per_run = np.stack([base, base * 0.5, base * 0.2])
            items = [
                Value("one row per run", per_run, "either"),
                Value("N+1 rows", np.stack([base] * 4), "bad"),
                Value("rows of n+1", np.zeros((3, arm.n + 1)), "bad"),
                Value("a row with NaN", np.where(np.arange(3)[:, None] == 1, np.nan, per_run), "bad"),
                Value("(N, 1, n)", per_run[:, None], "bad"),
            ]
            return none_is_valid(items_values(items) + state_values(base, batch=False, bounded=key == "q"))

        return values

    args = {
        "runs": Arg(lambda arm: 3, lambda arm: runs, sample=14),
        "plants": Arg(lambda arm: None, plants),
        "models": Arg(lambda arm: None, plants),
        "gains": Arg(lambda arm: None, gains),
        "keep": Arg(lambda arm: "summary", lambda arm: keep),
        "after": Arg(lambda arm: 0.005, lambda arm: after, sample=14),
        "threads": Arg(lambda arm: None, lambda arm: threads, sample=10),
        "q0": Arg(lambda arm: None, rows("q"), sample=20),
        "qd0": Arg(lambda arm: None, rows("qd"), sample=12),
        "disturbance": Arg(lambda arm: None, rows("tau"), sample=10),
    }

    def many(arm: ad.Robot, **kw: object) -> object:
        return ad.simulate(arm, pid, t_final=0.01, **kw)

    def view(ensemble: object) -> tuple:
        return ensemble.summaries, ensemble.outcome, tuple(np.asarray(v) for v in ensemble.samples.values())

    count = scalar_values([3, 1], _count(1, 10**6), integer=True, extra=[("10**12", 10**12, "bad")])
    masses = state_values(np.array([0.0, 0.1, 0.2]), batch=False, bounded=False, scalar_ok=True)
    return [
        Target("simulate (many runs)", many, args, [ARMS[0], ARMS[1]], view=view, combos=10),
        Target(
            "plant_variants",
            variant_call,
            {
                "count": Arg(lambda a: 3, lambda a: count),
                "payload_mass": Arg(lambda a: 0.0, lambda a: masses, sample=25),
                "mass_scale": Arg(  # one factor per joint (n = 2): a zero (or -0.0) is refused
                    lambda a: 1.0,
                    lambda a: relabel(
                        state_values(np.array([0.9, 1.1]), batch=False, bounded=False, scalar_ok=True), PER_VARIANT
                    ),
                    sample=25,
                ),
            },
            combos=6,
        ),
    ]


def _new_risky() -> list[Target]:
    return [*_driven_simulation_targets(), *_many_run_targets()]


# ----- risky cases, for child interpreters ----------------------------------------------------


def _closed_forms() -> list[Target]:
    form = ad.symbolic.derive(ad.models.two_link_planar()).compile()
    arms = [("two_link_planar closed form", ad.models.two_link_planar())]
    shapes = {
        "M": (("q",), MATRIX),
        "Vm": (("q", "qd"), MATRIX),
        "G": (("q",), VECTOR),
        "tau": (("q", "qd", "qdd"), VECTOR),
    }
    targets = []
    for name, (names, shape) in shapes.items():
        args = {k: _state_arg(k) for k in names}
        args["out"] = _out_arg(shape, risky=True)
        function = getattr(form, name)
        targets.append(Target(f"compiled closed form {name}", lambda arm, f=function, **kw: f(**kw), args, arms))
    return targets


def _huge(arm: ad.Robot, key: str, first: bool, states_: int) -> Kinds:
    """Huge batches as stride-0 views (no memory of their own): the call must refuse them or cope."""
    base = states(arm)[key]
    if not first:
        return items_values(
            [
                Value(
                    "(1, 10**5, n) by broadcasting: 10**10 states with the first",
                    np.broadcast_to(base, (1, 10**5, arm.n)),
                    "either",
                )
            ]
        )
    return items_values(
        [
            Value("10**5 states (stride-0 view)", np.broadcast_to(base, (10**5, arm.n)), "either"),
            Value(f"{states_:.0e} states (stride-0 view)", np.broadcast_to(base, (states_, arm.n)), "either"),
            Value("(10**5, 1, n) by broadcasting", np.broadcast_to(base, (10**5, 1, arm.n)), "either"),
        ]
    )


def _call_method(name: str, arm: ad.Robot, **kwargs: object) -> object:
    return getattr(arm, name)(**kwargs)


def _kernel_outs() -> list[Target]:
    """The compiled kernels' one-state entries with every kind of out= buffer, and huge batches."""
    targets = []
    for name, (names, shape) in DYNAMICS.items():
        if shape is None:
            continue
        args = {k: Arg(lambda arm, k=k: states(arm)[k], None) for k in names}
        args["out"] = _out_arg(shape, risky=True)
        call = functools.partial(_call_method, name)
        targets.append(Target(f"Robot.{name} out=", call, args, ARMS, sweeps=2))

        if name not in ("inverse_dynamics", "forward_dynamics", "inertia_matrix", "coriolis_matrix"):
            continue
        size = 10**9 if name == "inverse_dynamics" else 10**6  # checking 10**9 states alone takes seconds
        big = {
            k: Arg(lambda arm, k=k: states(arm)[k], lambda arm, k=k, i=i, m=size: _huge(arm, k, i == 0, m))
            for i, k in enumerate(names)
        }
        targets.append(Target(f"Robot.{name} huge batch", call, big, [ARMS[0]], combos=1))
    return targets


def _simulation_targets() -> list[Target]:
    def controllers(arm: ad.Robot) -> Kinds:
        n = arm.n
        symbolic = ad.models.two_link_planar(symbolic=True)
        return items_values(
            [
                Value("PID with per-joint gains", control.PID([10.0] * n, 2.0), "same", control.PID(10.0, 2.0)),
                Value("None", None, "either"),
                Value("ComputedTorque", control.ComputedTorque(100.0, 20.0), "either"),
                Value("PDGravity", control.PDGravity(10.0, 2.0), "either"),
                Value("PID kp NaN", control.PID(np.nan, 2.0), "bad", names=("kp",)),
                Value("PID kp negative", control.PID(-1.0, 2.0), "bad", names=("kp",)),
                Value("PID kv n+1 values", control.PID(1.0, [2.0] * (n + 1)), "bad", names=("kv",)),
                Value("PID kp text", control.PID("high", 2.0), "bad", names=("kp",)),
                Value("PID kp 1e300", control.PID(1e300, 2.0), "either", names=("kp",)),
                Value("ComputedTorque ki inf", control.ComputedTorque(1.0, 1.0, np.inf), "bad", names=("ki",)),
                Value(
                    "ComputedTorque with a model of other joints",
                    control.ComputedTorque(1.0, 1.0, model=ARMS[2][1] if n != 6 else ARMS[0][1]),
                    "bad",
                    names=("model",),
                ),
                Value(
                    "ComputedTorque with a symbolic model",
                    control.ComputedTorque(1.0, 1.0, model=symbolic),
                    "bad",
                    names=("model", "symbolic"),
                ),
                Value(
                    "Digital period 1.5 dt", control.Digital(control.PID(1.0, 1.0), 0.0015), "bad", names=("period",)
                ),
                Value(
                    "Saturated, n+1 limits",
                    control.Saturated(control.PID(1.0, 1.0), [1.0] * (n + 1)),
                    "bad",
                    names=("limit",),
                ),
                Value("a callable returning NaN", lambda *a: np.full(n, np.nan), "bad"),
                Value("a callable returning n+1 values", lambda *a: np.zeros(n + 1), "bad"),
                Value("a string", "pid", "bad"),
                Value("a number", 3.0, "bad"),
                Value("the PID class", control.PID, "bad"),
            ]
        )

    def trajectory_values(arm: ad.Robot) -> Kinds:
        n = arm.n
        return items_values(
            [
                Value("None", None, "same", None),
                Value("Sinusoid", trajectories.Sinusoid(0.1, 0.5), "either"),
                Value("Quintic", trajectories.Quintic(0.0, 0.1, 0.0, 0.01), "either"),
                Value("Sinusoid amplitude NaN", trajectories.Sinusoid(np.nan, 0.5), "bad", names=("amplitude",)),
                Value(
                    "Sinusoid n+1 amplitudes",
                    trajectories.Sinusoid([0.1] * (n + 1), 0.5),
                    "bad",
                    names=("amplitude", "Sinusoid"),
                ),
                Value("Sinusoid text frequency", trajectories.Sinusoid(0.1, "fast"), "bad", names=("frequency",)),
                Value("Quintic q1 inf", trajectories.Quintic(0.0, np.inf), "bad", names=("q1", "q0/q1")),
                Value("a callable returning n+1 values", lambda t: (np.zeros(n + 1),) * 3, "bad"),
                Value("a callable returning NaN", lambda t: (np.full(n, np.nan),) * 3, "bad"),
                Value("a string", "sine", "bad"),
                Value("a number", 1.0, "bad"),
            ]
        )

    def events(arm: ad.Robot) -> Kinds:
        other = ARMS[2][1] if arm.n != 6 else ARMS[0][1]
        return items_values(
            [
                Value("same arm at t = 0", [(0.0, arm)], "same", ()),
                Value("same arm after the end", [(1e300, arm)], "same", ()),
                Value("payload at 0.005 s", [(0.005, arm.with_payload(0.5))], "either"),
                Value("NaN time", [(np.nan, arm)], "bad"),
                Value("negative time", [(-1.0, arm)], "bad"),
                Value("text time", [("0.5", arm)], "bad"),
                Value("other joints", [(0.5, other)], "bad"),
                Value("a pair not in a list", (0.5, arm), "bad"),
                Value("a lone time", [0.5], "bad"),
                Value("a number", 5, "bad"),
                Value("a string", "later", "bad"),
                Value("a dict", {0.5: arm}, "bad"),
                Value("None", None, "bad"),
            ]
        )

    def disturbance(arm: ad.Robot) -> Kinds:
        n = arm.n
        return items_values(
            [
                Value("callable", lambda t, q, qd: np.zeros(n), "same", None),
                Value("callable returning NaN", lambda t, q, qd: np.full(n, np.nan), "bad"),
            ]
        ) + none_is_valid(state_values(np.full(n, 0.5), batch=False, bounded=False, scalar_ok=True))

    progress = items_values(
        [Value("None", None, "same", None), Value("print", print, "either"), Value("a string", "bar", "bad")]
        + [Value(v.label, v.value, "either" if callable(v.value) else "bad") for v in junk(skip=("None",))]
    )

    def whole_steps(t_final: float, dt: float) -> str:
        """simulate's rule for the times: positive, and t_final a whole number of steps dt (else refused)."""
        kind = positive(t_final) if positive(dt) == "same" else positive(dt)
        if kind == "same" and abs(t_final / dt - round(t_final / dt)) > 1e-9 * (t_final / dt):
            return "bad"
        return "bad" if kind == "same" and round(t_final / dt) < 1 else kind

    seconds = scalar_values([0.01, 0.02], lambda x: whole_steps(x, 1e-3), extra=[("1e9 s", 1e9, "either")])
    step = scalar_values([1e-3, 2e-3], lambda x: whole_steps(0.01, x), extra=[("1e-12 s", 1e-12, "either")])
    args = {
        "controller": Arg(lambda arm: control.PID(10.0, 2.0), controllers, names=("diverged",)),
        "trajectory": Arg(lambda arm: None, trajectory_values),
        "t_final": Arg(lambda arm: 0.01, lambda arm: seconds),
        "dt": Arg(lambda arm: 1e-3, lambda arm: step),
        "method": Arg(
            lambda arm: "rk4",
            lambda arm: choice_values(
                ["rk4", "rk45", "rk23", "dop853", "radau", "bdf", "lsoda"],
                ["euler", "", "RK4 "],
                ["RK45", "Radau", np.str_("rk4")],
            ),
        ),
        "q0": _one_state("q", none_ok=True),
        "qd0": _one_state("qd", none_ok=True, names=("diverged",)),
        "disturbance": Arg(lambda arm: None, disturbance, names=("diverged",)),
        "events": Arg(lambda arm: (), events, names=("event",)),
        "coulomb_smoothing": Arg(
            lambda arm: "auto",
            lambda arm: choice_values(["auto"], ["AUTO", "none", ""]) + scalar_values([0.0, 1e-3], non_negative),
        ),
        "progress": Arg(lambda arm: None, lambda arm: progress),
    }
    return [Target("simulate", lambda arm, **kw: ad.simulate(arm, **kw), args, [ARMS[0], ARMS[2], ARMS[4]])]


def _risky_other() -> list[Target]:
    arm = ARMS[0][1]
    huge_n = items_values([Value(f"n = {k}", k, "either") for k in (10**5, 10**9, 2**62)])
    count = items_values([Value(f"samples = {k}", k, "either") for k in (10**12, 2**62)])
    argv = [
        ["simulate", "two_link_planar", "--t-final", "1e9"],
        ["simulate", "two_link_planar", "--dt", "1e-12"],
        ["simulate", "two_link_planar", "--t-final", "1e6", "--dt", "1e-3"],
        ["check", "two_link_planar", "--samples", "1000000000000"],
        ["identify", "two_link_planar", "/dev/zero"],
    ]
    commands = items_values([Value(" ".join(a), a, "either") for a in argv])
    return [
        Target(
            "statespace.brunovsky (huge n)",
            lambda _, **kw: statespace.brunovsky(**kw),
            {"n": Arg(lambda a: 2, lambda a: huge_n)},
        ),
        Target(
            "properties.check (huge samples)",
            lambda _, **kw: properties.check(arm, only="gravity", **kw),
            {"samples": Arg(lambda a: 6, lambda a: count)},
        ),
        Target(
            "base_parameters (huge samples)",
            lambda _, **kw: ad.base_parameters(arm, **kw),
            {"samples": Arg(lambda a: 6, lambda a: count)},
        ),
        *urdf_targets(risky=True),
        Target(
            "armdyn CLI (enormous runs)",
            lambda _, argv: _command(argv),
            {"argv": Arg(lambda a: [], lambda a: commands)},
        ),
    ]


RISKY: dict[str, Callable[[], list[Target]]] = {
    "kernels with out= and huge batches": _kernel_outs,
    "compiled closed forms": _closed_forms,
    "simulate": _simulation_targets,
    "huge sizes, XML bombs, enormous CLI runs": _risky_other,
    "simulate with drives and many runs": _new_risky,
}


def _run_child(group: str, skip: int = 0) -> tuple[subprocess.Popen, float, Path]:
    """Start a child interpreter on a group of risky cases; its output goes to files in its folder."""
    folder = Path(tempfile.mkdtemp(prefix="child-", dir=SCRATCH))
    code = f"from tests.fuzz_values import child_main; child_main({group!r}, {skip})"
    with (folder / "stdout").open("w") as out, (folder / "stderr").open("w") as err:
        process = subprocess.Popen(
            [sys.executable, "-c", code],
            cwd=ROOT,
            stdout=out,
            stderr=err,
            env=os.environ | {"ARMDYN_FUZZ_SCRATCH": str(folder), "NUMBA_NUM_THREADS": "1"},
        )
    return process, time.monotonic(), folder


_CHILDREN: dict[str, tuple[subprocess.Popen, float, Path]] = {}


def _start_children(groups: list[str]) -> None:
    """Start the selected groups of risky cases at once, each in its own child (they run while the
    in-process cases do; the test of each group collects it)."""
    for group in groups:
        if group not in _CHILDREN:
            _CHILDREN[group] = _run_child(group)


def _collect(group: str) -> tuple[int, list[dict]]:
    """Wait for a group's child; restart it past a crash (at most three times)."""
    failures: list[dict] = []
    count = 0
    process, started, folder = _CHILDREN.pop(group, None) or _run_child(group)
    for _ in range(4):
        try:
            process.wait(timeout=max(1.0, CHILD_TIMEOUT - (time.monotonic() - started)))
            timed_out = False
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
            timed_out = True
        output = (folder / "stdout").read_text(errors="replace")
        stderr = (folder / "stderr").read_text(errors="replace")
        last, finished = None, False
        for line in output.splitlines():
            word, _, rest = line.partition(" ")
            if word == "CASE":
                index, _, label = rest.partition(" ")
                last = (int(index), label)
                count = max(count, int(index))
            elif word == "FAIL":
                failures.append(json.loads(rest))
            elif word == "DONE":
                finished = True
                count = max(count, int(rest))
        if finished and process.returncode == 0:
            break
        where = f"case {last[0]}: {last[1]}" if last else "before the first case"
        kind = "timed out" if timed_out else f"crashed the interpreter (exit status {process.returncode})"
        detail = " ".join(stderr.strip().splitlines()[-3:])[-300:]
        failures.append(
            {
                "target": group,
                "arm": "-",
                "args": [],
                "labels": where,
                "culprit": where,
                "kind": kind,
                "detail": detail,
                "repro": f"{group}, {where}",
            }
        )
        if last is None or timed_out:
            break
        process, started, folder = _run_child(group, last[0])
    return count, failures


# ----- the command line -----------------------------------------------------------------------


class CommandLineFailure(Exception):  # noqa: N818 (a failure of the rule, not an error of the test)
    """A command's outcome broke the CLI rule (see ``_cli_problem``)."""


def _command(argv: list[str]) -> str:
    """Run a command in a scratch folder: its output when it succeeded; a ModelError with its
    error line when it refused the arguments cleanly; a CommandLineFailure otherwise."""
    # a viewer that would serve until Ctrl-C (`view` without --html, `simulate --view`) returns at once
    serving = mock.patch.object(cli, "_wait_for_ctrl_c", lambda: None)
    with tempfile.TemporaryDirectory(dir=SCRATCH) as folder, contextlib.chdir(folder), serving:
        result = CliRunner().invoke(app, argv, catch_exceptions=True)
    problem = _cli_problem(result)
    if problem:
        raise CommandLineFailure(problem)
    if result.exit_code != 0:
        raise ad.ModelError(f"argv refused: {result.stderr.strip()}")
    return result.stdout


def _cli_problem(result: object) -> str:
    text = result.stdout + result.stderr
    if "Traceback" in text:
        return "printed a traceback"
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        return f"raised {type(result.exception).__name__}: {result.exception}"
    if result.exit_code == 0:
        return "printed NaN" if re.search(r"\bnan\b", result.stdout, re.IGNORECASE) else ""
    errors = [line for line in result.stderr.splitlines() if line.strip() and not line.startswith("warning: ")]
    if result.exit_code != 2:
        return f"exit code {result.exit_code}: {' | '.join(errors)[:200]}"
    if len(errors) != 1 or not errors[0].startswith("error: "):
        return f"not one 'error: ...' line on stderr: {errors[:3]}"
    if "internal error" in errors[0]:
        return errors[0]
    return ""


def _csv_files() -> dict[str, tuple[str | bytes, str]]:
    """Sample files for 'identify two_link_planar': (content, verdict) by label."""
    data = samples(ARMS[0][1])
    header = [f"{p}{i + 1}" for p in ("q", "qd", "qdd", "tau") for i in range(2)]
    rows = np.hstack([data[k] for k in ("q", "qd", "qdd", "tau")]).tolist()

    def csv(rows: list, header: list[str]) -> str:
        return "\n".join([",".join(header), *(",".join(str(x) for x in row) for row in rows)]) + "\n"

    good = csv(rows, header)
    return {
        "valid": (good, "either"),
        "empty": ("", "bad"),
        "header only": (",".join(header) + "\n", "bad"),
        "binary": (bytes(range(256)) * 4, "bad"),
        "NUL bytes": (good.replace(",", "\x00", 3), "bad"),
        "latin-1": (good.replace("q1", "q\u00e91").encode("latin-1"), "bad"),
        "ragged row": (good + "1,2\n", "bad"),
        "text cell": (good + ",".join(["x"] * 8) + "\n", "bad"),
        "nan cell": (good + ",".join(["nan"] * 8) + "\n", "bad"),
        "inf cell": (good + ",".join(["inf"] * 8) + "\n", "bad"),
        "1e308 cells": (good + ",".join(["1e308"] * 8) + "\n", "either"),
        "missing columns": (csv([r[:6] for r in rows], header[:6]), "bad"),
        "one sample": (csv(rows[:1], header), "bad"),
        "all zeros (no excitation)": (csv([[0.0] * 8] * 20, header), "bad"),
        "semicolons": (good.replace(",", ";"), "bad"),
        "BOM": (b"\xef\xbb\xbf" + good.encode(), "either"),
        "duplicate header": (csv([r + r[:1] for r in rows], [*header, "q1"]), "either"),
    }


NAMES = {
    "two_link_planar": "either",
    "": "bad",
    "nosuch": "bad",
    "names": "bad",
    "load": "bad",
    "__init__": "bad",
    "../two_link_planar": "bad",
    "two_link_planar\x00": "bad",
    "-": "bad",
}
NUMBERS = {
    "nan": "bad",
    "abc": "bad",
    "": "bad",
    "-inf": "bad",
    "0x10": "bad",
    "inf": "either",
    "-1": "either",
    "0": "either",
    "1e300": "either",
    "1e-300": "either",
}
INTEGERS = {
    "abc": "bad",
    "": "bad",
    "4.5": "bad",
    "nan": "bad",
    "-1": "either",
    "0": "either",
    "5": "either",
    "99999999999999999999999": "either",
}
STRINGS = {
    "": "bad",
    "nosuch": "bad",
    "nan": "bad",
    "1,nan": "bad",
    "1,2,3,4,5,6,7,8,9": "bad",
    ",": "bad",
    "-1": "either",
    "1e300": "either",
    "0.5": "either",
}
PATHS = {
    "missing/x.csv": "bad",
    ".": "either",
    "/proc/nope/x.csv": "bad",
    "/dev/full": "bad",
    "x\x00y.csv": "bad",
    "": "either",
    "out.csv": "either",
    "out.png": "either",
    "out.xyz": "either",
}
BASE = {  # command: its cheapest valid arguments (the CSV added for identify)
    "models": [],
    "show": ["two_link_planar"],
    "derive": ["two_link_planar", "--code", "c"],
    "check": ["two_link_planar", "--samples", "4"],
    "identify": ["two_link_planar"],
    "simulate": ["two_link_planar", "--t-final", "0.02"],
    "study": ["two_link_planar", "--runs", "20", "--t-final", "0.02", "--spec", "max-error-after-0.01s<1e-3"],
    "convert": ["two_link_planar", str(SCRATCH / "converted.xml")],
    "demo": None,
}


def _csv_files() -> dict[str, tuple[str | bytes, str]]:
    """Sample files for 'identify two_link_planar': (content, verdict) by label."""
    data = samples(ARMS[0][1])
    header = [f"{p}{i + 1}" for p in ("q", "qd", "qdd", "tau") for i in range(2)]
    rows = np.hstack([data[k] for k in ("q", "qd", "qdd", "tau")]).tolist()

    def csv(rows: list, header: list[str]) -> str:
        return "\n".join([",".join(header), *(",".join(str(x) for x in row) for row in rows)]) + "\n"

    good = csv(rows, header)
    return {
        "valid": (good, "either"),
        "empty": ("", "bad"),
        "header only": (",".join(header) + "\n", "bad"),
        "binary": (bytes(range(256)) * 4, "bad"),
        "NUL bytes": (good.replace(",", "\x00", 3), "bad"),
        "latin-1": (good.replace("q1", "q\u00e91").encode("latin-1"), "bad"),
        "ragged row": (good + "1,2\n", "bad"),
        "text cell": (good + ",".join(["x"] * 8) + "\n", "bad"),
        "nan cell": (good + ",".join(["nan"] * 8) + "\n", "bad"),
        "inf cell": (good + ",".join(["inf"] * 8) + "\n", "bad"),
        "1e308 cells": (good + ",".join(["1e308"] * 8) + "\n", "either"),
        "missing columns": (csv([r[:6] for r in rows], header[:6]), "bad"),
        "one sample": (csv(rows[:1], header), "bad"),
        "all zeros (no excitation)": (csv([[0.0] * 8] * 20, header), "bad"),
        "semicolons": (good.replace(",", ";"), "bad"),
        "BOM": (b"\xef\xbb\xbf" + good.encode(), "either"),
        "duplicate header": (csv([r + r[:1] for r in rows], [*header, "q1"]), "either"),
    }


def _with_files(label: str, argv: list, verdict: str) -> Value:
    """A command line whose placeholders become files written now: ("csv", label) a CSV file of
    _csv_files, ("urdf", slot, token) a URDF file with one attribute replaced."""
    csv_files = _csv_files()
    line = []
    for item in argv:
        if isinstance(item, tuple) and item[0] == "csv":
            special = {"missing file": "missing.csv", "a folder": "."}
            line.append(special.get(item[1]) or str(_write(csv_files[item[1]][0], ".csv")))
        elif isinstance(item, tuple):
            line.append(str(_write(_urdf(**({item[1]: item[2]} if item[1] else {})))))
        else:
            line.append(item)
    return Value(label, line, verdict)


def _tokens(command: str, parameter: object) -> dict[str, str]:
    """The tokens to try for an option, by its name and type."""
    if command == "demo":  # only bad folders: a valid one runs the whole demo, seconds each
        return {"missing/out": "bad", "/proc/nope/out": "bad", "x\x00y": "bad", "/dev/null": "bad"}
    if parameter.name in ("output", "plot", "csv", "animate", "draw"):
        return PATHS
    annotation = parameter.type_descriptor.annotation
    return INTEGERS if annotation is int else NUMBERS if annotation is float else STRINGS


def cli_targets() -> list[Target]:
    """One target per command of the app (found from the typer app itself): each argument and
    option in turn made hostile on the command's cheapest valid line."""
    import typer

    group = typer.main.get_command(app)
    targets = []
    for command, definition in group.commands.items():
        base = BASE.get(command, ["two_link_planar"])
        line = [command, *(base or [])] + ([("csv", "valid")] if command == "identify" else [])
        items: list[tuple[str, list, str]] = [(f"{command} --help", [command, "--help"], "either")]
        items.append((f"{command} --bogus", [*line, "--bogus"], "bad"))
        for parameter in definition.params:
            if parameter.param_type_name == "argument":
                position = 1 if parameter.name != "csv" else 2
                tokens: dict = dict(NAMES) if parameter.name == "name" else {}
                if parameter.name == "name":
                    tokens |= {("urdf", "", ""): "either", ("urdf", "j1_type", "floating"): "bad"}
                    tokens |= {("urdf", "l1_mass", "nan"): "bad", ("urdf", "robot_name", ""): "bad"}
                if parameter.name == "csv":
                    tokens = {("csv", label): verdict for label, (_, verdict) in _csv_files().items()}
                    tokens |= {("csv", "missing file"): "bad", ("csv", "a folder"): "bad"}
                for token, verdict in tokens.items():
                    if base is None or (verdict == "either" and command == "demo"):
                        continue
                    argv = [*line[:position], token, *line[position + 1 :]]
                    items.append((f"{command} <{parameter.name}> {token!r}"[:80], argv, verdict))
                items.append((f"{command} without <{parameter.name}>", line[:position], "bad"))
                continue
            option = parameter.opts[0]
            if parameter.is_flag:
                for flag in (*parameter.opts, *parameter.secondary_opts):
                    items.append((f"{command} {flag}", [*line, flag], "either"))
                items.append((f"{command} {option}=yes", [*line, f"{option}=yes"], "bad"))
                continue
            for token, verdict in _tokens(command, parameter).items():
                rest = list(line)
                if option in rest:
                    index = rest.index(option)
                    rest[index : index + 2] = []
                items.append((f"{command} {option} {token!r}", [*rest, option, token], verdict))
            items.append((f"{command} {option} (no value)", [*line, option], "bad"))
        kinds = [lazy(lambda a=item: _with_files(*a)) for item in items]
        sample = {"simulate": 70, "check": 20, "derive": 35, "identify": 25}.get(command)
        targets.append(
            Target(
                f"armdyn {command}",
                lambda _, argv: _command(argv),
                {"argv": Arg(lambda a: ["models"], lambda a, k=kinds: k, sample=sample)},
            )
        )
    app_level = items_values(
        [
            Value("armdyn --version", ["--version"], "either"),
            Value("armdyn nosuch", ["nosuch"], "bad"),
            Value("armdyn --bogus", ["--bogus"], "bad"),
            Value("armdyn --progress models", ["--progress", "models"], "either"),
        ]
    )
    targets.append(Target("armdyn", lambda _, argv: _command(argv), {"argv": Arg(lambda a: [], lambda a: app_level)}))
    return targets


# ----- the tests ------------------------------------------------------------------------------


def thread_targets() -> list[Target]:
    """armdyn.set_threads (restored after each case by the summary fixture's own setting) and threads."""
    import numba

    most = numba.config.NUMBA_NUM_THREADS

    def set_threads(arm: ad.Robot, count: object) -> int:
        try:
            ad.set_threads(count)
            return ad.threads()
        finally:
            numba.set_num_threads(1)

    counts = scalar_values([1, most], lambda x: "same" if x.is_integer() and 1 <= x <= most else "bad", integer=True)
    return [
        Target("set_threads", set_threads, {"count": Arg(lambda arm: 1, lambda arm: counts)}, SMALL_ARMS[:1]),
        Target("threads", lambda arm: ad.threads(), {}, SMALL_ARMS[:1], sweeps=1),
    ]


TARGETS = [
    *thread_targets(),
    *dynamics_targets(),
    *kinematics_targets(),
    *variant_targets(),
    *constructor_targets(),
    *model_targets(),
    *urdf_targets(),
    *mjcf_targets(),
    *parameterization_targets(),
    *module_targets(),
    *control_targets(),
    *statespace_targets(),
    *properties_targets(),
    *cli_targets(),
    *task_space_targets(),
    *actuator_targets(),
    *derivative_targets(),
    *generated_code_targets(),
    *study_targets(),
]


@pytest.fixture(scope="module", autouse=True)
def summary(request: pytest.FixtureRequest) -> Iterator[None]:
    """Start the child interpreters first; at the end, count the cases tried on one line.

    The compiled batch kernels run on one thread meanwhile: the cases are tiny batches, for which
    starting a parallel region costs milliseconds (more when the children are busy), and the
    results do not depend on the number of threads."""
    import numba

    start = time.perf_counter()
    risky = [item.callspec.params["group"] for item in request.session.items if item.name.startswith("test_risky")]
    _start_children(risky)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(threads)
    for process, _, _ in _CHILDREN.values():  # groups not collected (deselected): stop them
        process.kill()
        process.wait()
    _CHILDREN.clear()
    classes = {(f["kind"], f.get("culprit", "")) for f in fv.FAILURES}
    line = (
        f"fuzz: {fv.COUNT[0] + CHILD_COUNT[0]} cases tried ({CHILD_COUNT[0]} in child interpreters), "
        f"{len(fv.FAILURES)} failing in {len(classes)} classes, {time.perf_counter() - start:.1f} s"
    )
    report = os.environ.get("ARMDYN_FUZZ_REPORT")  # a file for every failure, grouped into classes (and as JSON)
    if report:
        Path(report).write_text(line + "\n" + fv.grouped(fv.FAILURES) + "\n", encoding="utf-8")
        Path(report).with_suffix(".json").write_text(json.dumps(fv.FAILURES, indent=1, default=str))
    reporter = request.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line("")
        reporter.write_line(line)
    else:
        print(line)
    shutil.rmtree(SCRATCH, ignore_errors=True)


def test_every_public_name_and_robot_method_is_fuzzed() -> None:
    """Each callable of armdyn.__all__ and each public Robot method has a target (a new one is
    not left out by accident)."""
    names = {target.name.split("(")[0].split(" ")[0] for target in TARGETS}
    exceptions = {
        name for name in ad.__all__ if isinstance(getattr(ad, name), type) and issubclass(getattr(ad, name), Exception)
    }
    public = {name for name in ad.__all__ if callable(getattr(ad, name))} - exceptions
    methods = {
        f"Robot.{name}"
        for name, value in vars(ad.Robot).items()
        if not name.startswith("_") and (callable(value) or isinstance(value, classmethod))
    }
    missing = sorted((public | methods) - names - {"Robot"})
    assert not missing, f"no fuzz target for {missing}"


@pytest.mark.parametrize("target", TARGETS, ids=[t.name for t in TARGETS])
def test_hostile_values(target: Target) -> None:
    failures = fv.fuzz(target)
    assert not failures, f"{len(failures)} failing cases:\n" + fv.grouped(failures)


@pytest.mark.parametrize("group", list(RISKY))
def test_risky_cases_in_a_child_interpreter(group: str) -> None:
    count, failures = _collect(group)
    CHILD_COUNT[0] += count
    fv.FAILURES.extend(failures)
    assert count > 0, "the child interpreter tried no case"
    assert not failures, f"{len(failures)} failing cases:\n" + fv.grouped(failures)
