"""Closed forms: the book's examples symbol by symbol, every built-in arm against the numeric
kernels, the two derivation routes against each other, and the generated code."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import symengine as se
import sympy
from numpy.testing import assert_allclose
from typer.testing import CliRunner

import armdyn as ad
from armdyn.cli import app
from armdyn.symbolic import derive
from armdyn.symbolic.derive import derive_raw
from tests.strategies import random_robot

m1, m2, a1, a2, g, m, J = sympy.symbols("m1 m2 a1 a2 g m J", positive=True)
q1, q2, q3 = sympy.symbols("q1 q2 q3")
qd1, qd2, qd3 = sympy.symbols("qd1 qd2 qd3")
qdd1, qdd2 = sympy.symbols("qdd1 qdd2")
c1, c2, s2, c12 = sympy.cos(q1), sympy.cos(q2), sympy.sin(q2), sympy.cos(q1 + q2)


def same(actual: sympy.Matrix, expected: sympy.Matrix) -> None:
    """Equal entry by entry, as SymPy proves it."""
    assert actual.shape == expected.shape
    for x, y in zip(actual, expected, strict=True):
        assert sympy.simplify(sympy.expand_trig(x - y)) == 0, (x, y)


@pytest.fixture(scope="module")
def rr() -> ad.symbolic.ClosedForm:
    return derive(ad.models.two_link_planar(symbolic=True), friction="symbolic")


def test_two_link_arm_is_example_3_2_2(rr: ad.symbolic.ClosedForm) -> None:
    same(
        rr.M,
        sympy.Matrix(
            [
                [(m1 + m2) * a1**2 + m2 * a2**2 + 2 * m2 * a1 * a2 * c2, m2 * a2**2 + m2 * a1 * a2 * c2],
                [m2 * a2**2 + m2 * a1 * a2 * c2, m2 * a2**2],
            ]
        ),
    )
    same(rr.V, sympy.Matrix([-m2 * a1 * a2 * (2 * qd1 * qd2 + qd2**2) * s2, m2 * a1 * a2 * qd1**2 * s2]))
    same(rr.G, sympy.Matrix([(m1 + m2) * g * a1 * c1 + m2 * g * a2 * c12, m2 * g * a2 * c12]))
    same(rr.Vm, m2 * a1 * a2 * s2 * sympy.Matrix([[-qd2, -(qd1 + qd2)], [qd1, 0]]))
    same(rr.S, (2 * qd1 + qd2) * m2 * a1 * a2 * s2 * sympy.Matrix([[0, 1], [-1, 0]]))
    same(rr.V_i[0], -m2 * a1 * a2 * s2 * sympy.Matrix([[0, 1], [1, 1]]))
    same(rr.V_i[1], m2 * a1 * a2 * s2 * sympy.Matrix([[1, 0], [0, 0]]))
    assert rr.G[1].has(c12) and rr.G[0].has(c12)  # the book's c12, not c1 c2 - s1 s2


def test_two_link_regressor_is_the_books(rr: ad.symbolic.ClosedForm) -> None:
    k1, v1, k2, v2 = sympy.symbols("k1 v1 k2 v2")
    assert list(rr.phi) == [m1, m2, k1, v1, k2, v2]
    w11 = a1**2 * qdd1 + g * a1 * c1
    w12 = (
        (a1**2 + a2**2 + 2 * a1 * a2 * c2) * qdd1
        + (a2**2 + a1 * a2 * c2) * qdd2
        - a1 * a2 * (2 * qd1 * qd2 + qd2**2) * s2
        + g * a1 * c1
        + g * a2 * c12
    )
    w22 = (a2**2 + a1 * a2 * c2) * qdd1 + a2**2 * qdd2 + a1 * a2 * qd1**2 * s2 + g * a2 * c12
    expected = sympy.Matrix([[w11, w12, sympy.sign(qd1), qd1, 0, 0], [0, w22, 0, 0, sympy.sign(qd2), qd2]])
    same(rr.W, expected)
    same(rr.W * rr.phi, rr.tau)


def test_polar_arm_is_example_3_2_1() -> None:
    form = derive(ad.models.polar_rp(symbolic=True))
    theta, r, thd, rd = q1, q2, qd1, qd2
    same(form.M, sympy.Matrix([[m * r**2, 0], [0, m]]))
    same(form.V, sympy.Matrix([2 * m * r * rd * thd, -m * r * thd**2]))
    same(form.G, sympy.Matrix([m * g * r * sympy.cos(theta), m * g * sympy.sin(theta)]))


def test_cylindrical_arm_is_exercise_3_2_3() -> None:
    form = derive(ad.models.cylindrical(symbolic=True))
    r = q3
    same(form.M, sympy.Matrix([[J + m2 * r**2, 0, 0], [0, m1 + m2, 0], [0, 0, m2]]))
    same(form.V, sympy.Matrix([2 * m2 * r * qd3 * qd1, 0, -m2 * r * qd1**2]))
    same(form.G, sympy.Matrix([0, (m1 + m2) * g, 0]))


@pytest.mark.parametrize("factory", [ad.models.two_link_planar, ad.models.polar_rp, ad.models.cylindrical])
def test_mdot_minus_2vm_is_skew_symbolically(factory: object) -> None:
    S = derive(factory(symbolic=True)).S
    assert (S + S.T).applyfunc(sympy.simplify) == sympy.zeros(*S.shape)


# ----- symbolic equals numeric ----------------------------------------------------------------------
def evaluate_python(form: ad.symbolic.ClosedForm, name: str, *states: np.ndarray) -> np.ndarray:
    namespace: dict = {}
    exec(form.to_python(), namespace)
    n = form.robot.n
    out = np.zeros((n, n) if name in ("M", "Vm") else n)
    return namespace[name](*states, out)


@pytest.mark.parametrize("name", [x for x in ad.models.names() if x not in ("two_link_planar", "polar_rp")])
def test_closed_form_of_every_built_in_arm_equals_the_kernels(name: str) -> None:
    arm = ad.models.load(name)
    form = derive(arm)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1.5, 1.5, arm.n) for _ in range(3))
        scale = 1e-10 * (1 + np.abs(arm.inverse_dynamics(q, qd, qdd)).max())
        assert_allclose(evaluate_python(form, "M", q), arm.inertia_matrix(q), atol=scale)
        assert_allclose(evaluate_python(form, "Vm", q, qd), arm.coriolis_matrix(q, qd), atol=scale)
        assert_allclose(evaluate_python(form, "G", q), arm.gravity_vector(q), atol=scale)
        assert_allclose(evaluate_python(form, "tau", q, qd, qdd), arm.inverse_dynamics(q, qd, qdd), atol=scale)


@pytest.mark.parametrize("factory", [ad.models.two_link_planar, ad.models.polar_rp, ad.models.cylindrical])
def test_book_arms_with_values_equal_the_kernels(factory: object) -> None:
    form = derive(factory(symbolic=True))
    values = {s: 1.0 + 0.3 * k for k, s in enumerate(sorted(form._parameter_names()))}
    numeric = factory(**{k: v for k, v in values.items()})
    compiled = form.compile(values)
    rng = np.random.default_rng(1)
    q, qd, qdd = (rng.uniform(0.2, 1.5, (4, numeric.n)) for _ in range(3))
    assert_allclose(compiled.M(q), numeric.inertia_matrix(q), rtol=1e-12, atol=1e-12)
    assert_allclose(compiled.Vm(q, qd), numeric.coriolis_matrix(q, qd), rtol=1e-12, atol=1e-12)
    assert_allclose(compiled.G(q[0]), numeric.gravity_vector(q[0]), rtol=1e-12, atol=1e-12)
    assert_allclose(compiled.tau(q, qd, qdd), numeric.inverse_dynamics(q, qd, qdd), rtol=1e-12, atol=1e-12)


def test_compile_needs_values_for_symbols() -> None:
    with pytest.raises(ad.ModelError, match="needs numeric values"):
        derive(ad.models.polar_rp(symbolic=True)).compile()


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_lagrange_and_recursive_routes_agree(seed: int) -> None:
    """The book's trace formula and the composite-rigid-body recursion give the same polynomials."""
    arm = random_robot(seed, 3, chain=seed % 2 == 0)
    book, recursive = derive_raw(arm, "lagrange"), derive_raw(arm, "recursive")

    def entries(raw: object) -> list:
        return [x for row in raw.M for x in row] + raw.G + raw.tau

    for x, y in zip(entries(book), entries(recursive), strict=True):
        terms = se.expand(x - y).as_coefficients_dict()  # term -> coefficient; a bare number is its own term
        residual = max(abs(float(c) * (float(t) if t.is_Number else 1.0)) for t, c in terms.items())
        assert residual < 1e-9


def test_regressor_of_a_numeric_arm_reproduces_tau() -> None:
    arm = ad.models.scara()
    form = derive(arm)
    state = {**dict(zip(form.q, [0.3, -0.2, 0.1, 0.5], strict=True))}
    state |= dict(zip(form.qd, [0.2, 0.1, -0.3, 0.4], strict=True))
    state |= dict(zip(form.qdd, [0.5, 0.1, 0.2, -0.3], strict=True))
    W = np.array(form.W.subs(state).evalf(), dtype=float)
    tau = arm.inverse_dynamics([0.3, -0.2, 0.1, 0.5], [0.2, 0.1, -0.3, 0.4], [0.5, 0.1, 0.2, -0.3])
    assert_allclose(W @ np.array(form.phi_values), tau, atol=1e-10)
    assert len(form.phi) == 14 * arm.n


# ----- the generated code --------------------------------------------------------------------------
def test_compiled_puma560_takes_one_state_or_a_batch() -> None:
    arm = ad.models.puma560()
    compiled = derive(arm).compile()
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-2, 2, (5, 6)) for _ in range(3))
    assert_allclose(compiled.M(q), arm.inertia_matrix(q), atol=1e-11)
    assert_allclose(compiled.G(q[2]), arm.gravity_vector(q[2]), atol=1e-11)
    assert_allclose(compiled.tau(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd), atol=1e-10)
    assert compiled.Vm(q.reshape(5, 1, 6), qd.reshape(5, 1, 6)).shape == (5, 1, 6, 6)
    counts, reduced = derive(arm).operation_counts(cse=False), derive(arm).operation_counts(cse=True)
    assert all(reduced[k] < counts[k] for k in counts)


@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler on this machine")
def test_generated_c_equals_the_kernels(tmp_path: Path) -> None:
    arm = ad.models.stanford()
    source = tmp_path / "stanford.c"
    source.write_text(derive(arm).to_c())
    library = tmp_path / "libstanford.so"
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-o", str(library), str(source), "-lm"], check=True)
    lib = ctypes.CDLL(str(library))
    pointer = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
    lib.tau.argtypes = [pointer, pointer, pointer, pointer]
    lib.M.argtypes = [pointer, pointer]
    q, qd, qdd = np.array([0.3, -0.4, 0.6, 0.2, 0.5, -0.1]), np.full(6, 0.3), np.full(6, -0.2)
    tau, M = np.zeros(6), np.zeros(36)
    lib.tau(q, qd, qdd, tau)
    lib.M(q, M)
    assert_allclose(tau, arm.inverse_dynamics(q, qd, qdd), atol=1e-10)
    assert_allclose(M.reshape(6, 6), arm.inertia_matrix(q), atol=1e-10)


def test_latex_and_pretty_print_in_the_books_notation(rr: ad.symbolic.ClosedForm) -> None:
    text = rr.latex()
    assert r"c_{12}" in text and r"\begin{aligned}" in text and "M(q) &=" in text
    assert "c₁₂" in rr.pretty() or "c12" in rr.pretty()


def test_derive_command(tmp_path: Path) -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["derive", "two_link_planar"])
    assert result.exit_code == 0 and "M(q) =" in result.output
    out = tmp_path / "rr.tex"
    assert runner.invoke(app, ["derive", "two_link_planar", "--latex", "--output", str(out)]).exit_code == 0
    assert r"\begin{aligned}" in out.read_text()
    code = runner.invoke(app, ["derive", "scara", "--code", "python"])
    assert code.exit_code == 0 and "def tau(q, qd, qdd, out" in code.output
    assert runner.invoke(app, ["derive", "scara", "--code", "fortran"]).exit_code == 2
    assert runner.invoke(app, ["derive", "nosuch"]).exit_code == 2
