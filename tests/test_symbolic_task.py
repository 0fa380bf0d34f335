"""Closed forms in task coordinates (Section 3.5): Example 3.5-1 symbol for symbol, the
polar arm seen by a camera, symbolic against numeric, and the outputs that are refused."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import sympy
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn import task_space as ts
from armdyn.symbolic import TaskClosedForm, derive
from tests.strategies import random_robot

J, m, m1, m2, g = sympy.symbols("J m m1 m2 g", positive=True)
q1, q2, q3 = sympy.symbols("q1 q2 q3")


def same(actual: sympy.Matrix, expected: sympy.Matrix) -> None:
    """Equal entry by entry, as SymPy proves it."""
    assert actual.shape == expected.shape
    assert sympy.simplify(actual - expected) == sympy.zeros(*expected.shape), actual


def overhead_camera(f: float, H: float) -> ts.Camera:
    """The camera of Example A.3-3, on the axis normal to the arm's plane at depth H: x_c = -y, y_c = x."""
    pose = np.eye(4)
    pose[:3, :3] = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    pose[:3, 3] = [0.0, 0.0, -H]
    return ts.Camera(f, pose)


@pytest.fixture(scope="module")
def cylindrical() -> TaskClosedForm:
    return derive(ad.models.cylindrical(symbolic=True), output=ts.ToolPosition())


def test_cylindrical_arm_is_example_3_5_1(cylindrical: TaskClosedForm) -> None:
    theta, r = q1, q3  # q = [theta, h, r]
    c, s, Jb = sympy.cos(theta), sympy.sin(theta), J / r**2
    same(cylindrical.h, sympy.Matrix([r * c, r * s, q2]))
    same(cylindrical.J, sympy.Matrix([[-r * s, 0, c], [r * c, 0, s], [0, 1, 0]]))
    assert sympy.simplify(cylindrical.det_J - r) == 0
    same(cylindrical.J_inv, sympy.Matrix([[-s / r, c / r, 0], [0, 0, 1], [c, s, 0]]))
    book = sympy.Matrix([[m2 + Jb * s**2, -Jb * s * c, 0], [-Jb * s * c, m2 + Jb * c**2, 0], [0, 0, m1 + m2]])
    assert sympy.simplify(cylindrical.Mbar - book) == sympy.zeros(3, 3)
    assert cylindrical.Gbar == sympy.Matrix([0, 0, g * (m1 + m2)])  # constant
    assert cylindrical.Fbar == sympy.zeros(3, 1)
    assert cylindrical.expanded


def test_cylindrical_arm_keeps_mbar_dot_minus_2_vmbar_skew(cylindrical: TaskClosedForm) -> None:
    q, qd = cylindrical.q, cylindrical.qd
    Mbar_dot = cylindrical.Mbar.applyfunc(lambda e: sum(sympy.diff(e, q[i]) * qd[i] for i in range(3)))
    S = Mbar_dot - 2 * cylindrical.Vmbar
    assert sympy.simplify(S + S.T) == sympy.zeros(3, 3)
    ydot = cylindrical.J * qd
    same(cylindrical.Nbar, cylindrical.Vmbar * ydot + cylindrical.Fbar + cylindrical.Gbar)


@pytest.mark.parametrize(("f", "H"), [(3.0, 3.0), (2.0, 4.0)])
def test_polar_arm_seen_from_overhead_is_a_point_mass(f: float, H: float) -> None:
    """Example 3.2-1 through the camera of Example A.3-3: y = (f / H) [-r s, r c], Mbar = m (H / f)^2 1."""
    form = derive(ad.models.polar_rp(symbolic=True), output=overhead_camera(f, H))
    theta, r, k = q1, q2, sympy.Rational(f) / sympy.Rational(H)
    same(form.h, k * sympy.Matrix([-r * sympy.sin(theta), r * sympy.cos(theta)]))
    assert form.Mbar == m / k**2 * sympy.eye(2)
    assert form.Vmbar == sympy.zeros(2, 2)
    assert form.Gbar == sympy.Matrix([-m * g / k, 0])  # constant: gravity -g y appears along -u
    same(form.Nbar, form.Gbar)


# ----- symbolic equals numeric ----------------------------------------------------------------------
def states(arm: ad.Robot, output: ts.TaskOutput, seed: int, count: int = 4) -> list[tuple[np.ndarray, np.ndarray]]:
    """Random states, (q, qd), where J is well conditioned."""
    rng = np.random.default_rng(seed)
    chosen = []
    while len(chosen) < count:
        q, qd = rng.uniform(-2, 2, arm.n), rng.uniform(-2, 2, arm.n)
        if np.all(np.isfinite(q)) and ts.condition_number(arm, output, q) < 1e4:
            chosen.append((q, qd))
    return chosen


def assert_matches_numeric(form: TaskClosedForm, arm: ad.Robot, output: ts.TaskOutput, values: dict) -> None:
    compiled = form.compile(values)
    for q, qd in states(arm, output, seed=7):
        pairs = [
            (compiled.Mbar(q), ts.task_inertia(arm, output, q)),
            (compiled.Vmbar(q, qd), ts.task_coriolis(arm, output, q, qd)),
            (compiled.Gbar(q), ts.task_gravity(arm, output, q)),
            (compiled.Fbar(q, qd), ts.task_friction(arm, output, q, qd)),
            (compiled.Nbar(q, qd), ts.task_nonlinear(arm, output, q, qd)),
            (compiled.h(q), output.value(arm, q)),
            (compiled.J(q), output.jacobian(arm, q)),
        ]
        for symbolic, numeric in pairs:
            assert_allclose(symbolic, numeric, rtol=1e-10, atol=1e-10 * (1 + np.abs(numeric).max()))


def tilted_camera() -> ts.Camera:
    """A camera 4 m below the plane, turned 0.3 rad about its x axis and 0.2 rad about z."""
    c, s, cz, sz = np.cos(0.3), np.sin(0.3), np.cos(0.2), np.sin(0.2)
    pose = np.eye(4)
    pose[:3, :3] = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]]) @ [[1, 0, 0], [0, c, -s], [0, s, c]]
    pose[:3, 3] = [0.2, 0.1, -4.0]
    return ts.Camera(800.0, pose)


@pytest.mark.slow
@pytest.mark.parametrize("output", [ts.PlanarPosition(), tilted_camera()], ids=["planar", "camera"])
def test_two_link_arm_in_task_coordinates_equals_numeric(output: ts.TaskOutput) -> None:
    values = {"m1": 1.3, "m2": 0.7, "a1": 0.9, "a2": 0.6, "g": 9.81}
    form = derive(ad.models.two_link_planar(symbolic=True), output=output)
    assert_matches_numeric(form, ad.models.two_link_planar(**values), output, values)


@pytest.mark.slow
def test_random_spatial_arm_with_a_tool_equals_numeric() -> None:
    """A general 3-joint spatial chain with friction, motors, a base and a tool offset."""
    tool, base = np.eye(4), np.eye(4)
    tool[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    tool[:3, 3] = [0.1, -0.05, 0.2]
    base[:3, 3] = [0.3, 0.2, -0.1]
    arm = random_robot(2, 3, chain=True).replace(tool=tool, base=base)
    output = ts.ToolPosition()
    form = derive(arm, output=output)
    assert not form.expanded  # a general arm: exact products, not expanded
    assert_matches_numeric(form, arm, output, {})
    link = derive(arm, output=ts.LinkPoint(2)).compile()
    q, _ = states(arm, output, seed=3, count=1)[0]
    assert_allclose(link.h(q), ts.LinkPoint(2).value(arm, q), atol=1e-12)
    assert_allclose(link.J(q), ts.LinkPoint(2).jacobian(arm, q), atol=1e-12)
    assert not np.allclose(link.h(q), output.value(arm, q))  # the link frame's origin, not the tool point


def test_compiled_terms_take_batches_and_need_values() -> None:
    form = derive(ad.models.polar_rp(symbolic=True), output=overhead_camera(3.0, 3.0))
    with pytest.raises(ad.ModelError, match="needs numeric values"):
        form.compile()
    compiled = form.compile({"m": 2.0, sympy.Symbol("g", positive=True): 9.8})
    q = np.column_stack([np.linspace(0, 1, 6), np.linspace(0.5, 1.5, 6)]).reshape(2, 3, 2)
    assert compiled.Mbar(q).shape == (2, 3, 2, 2)
    assert_allclose(compiled.Mbar(q), np.broadcast_to(2.0 * np.eye(2), (2, 3, 2, 2)))
    assert_allclose(compiled.Nbar(q, np.ones(2)), np.broadcast_to([-19.6, 0.0], (2, 3, 2)))


# ----- printing and progress ----------------------------------------------------------------------------
def test_printing_and_progress(cylindrical: TaskClosedForm) -> None:
    assert repr(cylindrical) == "TaskClosedForm('cylindrical', ToolPosition(), n=3)"
    text = cylindrical.pretty()
    assert "Mbar(q) =" in text and "Nbar(q, qd) =" in text and "Fbar" not in text
    assert "s₁" in text  # the book's notation
    assert "too wide" not in text and "characters wide" in cylindrical.pretty(limit=10)
    latex = cylindrical.latex()
    assert r"\bar{M}(q) &=" in latex and "s_{1}" in latex and latex.count(r"\begin{align*}") == 1
    calls = []
    derive(ad.models.polar_rp(), output=ts.PlanarPosition(), progress=lambda f, s: calls.append((f, s)))
    assert calls[-1] == (1.0, "done") and sum(s == "done" for _, s in calls) == 1
    assert "task space" in [s for _, s in calls]
    assert all(a[0] <= b[0] for a, b in itertools.pairwise(calls))


# ----- refused outputs ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("arm", "output", "message"),
    [
        (ad.models.cylindrical(), ts.ToolPose(), "ToolPose is not supported"),
        (ad.models.cylindrical(), ts.PlanarPosition(), "has 2 rows but arm 'cylindrical' has 3 joints"),
        (ad.models.two_link_planar(), ts.ToolPosition(), "square J"),
        (ad.models.two_link_planar(), ts.Output(lambda q: q, lambda q: np.eye(2)), "support the outputs"),
        (ad.models.two_link_planar(), "tool", "got str"),
        (ad.models.two_link_planar(), ts.LinkPoint(5), "out of range"),
        (ad.models.two_link_planar(), ts.PlanarPosition((0, 2)), "singular J at every q"),
    ],
)
def test_unsupported_outputs_are_refused(arm: ad.Robot, output: object, message: str) -> None:
    with pytest.raises(ad.ModelError, match=message):
        derive(arm, output=output)


def test_without_output_derive_is_unchanged() -> None:
    form = derive(ad.models.polar_rp(symbolic=True), output=None)
    assert isinstance(form, ad.symbolic.ClosedForm)
