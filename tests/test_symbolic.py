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


@pytest.mark.slow
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


@pytest.mark.slow
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
def test_a_closed_form_too_deep_to_compile_points_to_generated_code(monkeypatch: pytest.MonkeyPatch) -> None:
    """A 7-joint arm's expanded closed form nests deeper than Python's compiler goes (RecursionError after
    half a minute, measured on the Panda): compile() says so and names the route that scales."""
    from armdyn.symbolic import codegen

    def too_deep(*args: object) -> None:
        raise RecursionError("maximum recursion depth exceeded during compilation")

    monkeypatch.setattr(codegen, "_compiled", too_deep)
    with pytest.raises(ad.ModelError, match=r"2-joint arm is too deep .*generate_code\(arm\)\.compile\(\)"):
        derive(ad.models.two_link_planar()).compile()


@pytest.mark.slow
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


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("gcc") is None, reason="no C compiler on this machine")
def test_generated_c_equals_the_kernels(tmp_path: Path) -> None:
    arm = ad.models.stanford()
    source = tmp_path / "stanford.c"
    source.write_text(derive(arm).to_c())
    library = tmp_path / "libstanford.so"
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-o", str(library), str(source), "-lm"], check=True)
    lib = ctypes.CDLL(str(library))
    pointer = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
    lib.armdyn_tau.argtypes = [pointer, pointer, pointer, pointer]
    lib.armdyn_M.argtypes = [pointer, pointer]
    q, qd, qdd = np.array([0.3, -0.4, 0.6, 0.2, 0.5, -0.1]), np.full(6, 0.3), np.full(6, -0.2)
    tau, M = np.zeros(6), np.zeros(36)
    lib.armdyn_tau(q, qd, qdd, tau)
    lib.armdyn_M(q, M)
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


# ----- exact numbers, the default route, progress ----------------------------------------------------
def dh_arm() -> ad.Robot:
    """A user's own 3-DOF DH arm with a twist of pi/2 (written as a float)."""
    return ad.Robot.from_dh(
        [
            {"alpha": np.pi / 2, "mass": 1, "com": [0, 0, 0.1], "inertia": [0.01, 0.01, 0.01]},
            {"a": 0.5, "mass": 1, "com": [-0.25, 0, 0], "inertia": [0.01, 0.02, 0.02]},
            {"a": 0.4, "mass": 1, "com": [-0.2, 0, 0], "inertia": [0.01, 0.02, 0.02]},
        ],
        name="my_arm",
    )


def float_coefficients(expr: sympy.Expr) -> list[float]:
    """Every floating or rational number in a SymPy expression."""
    return [float(x) for x in expr.atoms(sympy.Float, sympy.Rational) if x != 0]


def test_exact_values_a_user_writes_are_exact() -> None:
    from armdyn.symbolic.algebra import exact_float, number, transform

    assert exact_float(float(np.cos(np.pi / 2)), geometric=True) == 0
    assert exact_float(0.5) == se.Rational(1, 2) and exact_float(0.1) == se.Rational(1, 10)
    assert exact_float(0.1 + 0.2) == se.Rational(3, 10) and exact_float(1 / 3) == se.Rational(1, 3)
    assert exact_float(9.81) == se.Rational(981, 100) and exact_float(-1.0) == -1
    assert exact_float(float(np.cos(np.pi / 4)), geometric=True) == se.sqrt(2) / 2
    assert exact_float(float(np.sin(np.pi / 3)), geometric=True) == se.sqrt(3) / 2
    assert exact_float(0.3 * float(np.sin(np.pi / 4)), geometric=True) == se.Rational(3, 20) * se.sqrt(2)
    rotation = ad.model.joint.dh_joint("R", 0.0, np.pi / 2, 0.0, 0.0).frame_offset
    assert transform(rotation) == se.DenseMatrix([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])
    rng = np.random.default_rng(0)
    for x in rng.normal(size=200) * 10.0 ** rng.integers(-6, 6, 200):  # any float reads back as itself
        assert float(number(float(x))) == x and float(number(float(x), geometric=True)) == x


def test_derive_on_a_dh_arm_with_a_twist_is_exact_and_fast() -> None:
    """A twist of np.pi/2 gives cos = 6e-17: no round-off terms, no q1 in M, by the default (recursive) route."""
    arm = dh_arm()
    form = derive(arm)
    for entry in form.M:
        assert not entry.has(q1)  # the first joint's angle cannot enter M of a serial chain
    for matrix in (form.M, form.Vm, form.V, form.G, form.F, form.tau):
        for entry in matrix:
            assert all(abs(x) > 1e-12 for x in float_coefficients(entry)), entry
    for text in (form.latex(), form.to_c(), form.to_python(), form.pretty()):
        assert not [x for x in re_numbers(text) if 0 < abs(x) < 1e-12]
    assert form.method == "recursive"
    book = derive(arm, method="lagrange")  # the book's route reaches the same exact polynomials
    for x, y in zip(book.raw.tau + book.raw.G, form.raw.tau + form.raw.G, strict=True):
        assert se.expand(x - y) == 0
    rng = np.random.default_rng(2)
    q, qd, qdd = (rng.uniform(-1.5, 1.5, 3) for _ in range(3))
    assert_allclose(evaluate_python(form, "M", q), arm.inertia_matrix(q), atol=1e-12)
    assert_allclose(evaluate_python(form, "tau", q, qd, qdd), arm.inverse_dynamics(q, qd, qdd), atol=1e-12)


def re_numbers(text: str) -> list[float]:
    import re

    return [float(x) for x in re.findall(r"(?<![\w.])\d+\.?\d*(?:[eE][-+]?\d+)?", text)]


@pytest.mark.parametrize("factory", [ad.models.two_link_planar, ad.models.polar_rp, ad.models.cylindrical])
def test_lagrange_route_equals_the_recursive_one_on_the_books_arms(factory: object) -> None:
    arm = factory(symbolic=True)
    book, recursive = derive_raw(arm, "lagrange"), derive_raw(arm, "recursive")
    for name in ("M", "Vm"):
        flat = [[x for row in getattr(raw, name) for x in row] for raw in (book, recursive)]
        for x, y in zip(*flat, strict=True):
            assert se.expand(x - y) == 0
    for x, y in zip(book.G + book.tau, recursive.G + recursive.tau, strict=True):
        assert se.expand(x - y) == 0
    assert derive(arm, method="lagrange").method == "lagrange"


def test_derive_reports_progress() -> None:
    calls: list[tuple[float, str]] = []
    derive(dh_arm(), progress=lambda fraction, stage: calls.append((fraction, stage)))
    fractions = [f for f, _ in calls]
    assert fractions == sorted(fractions) and fractions[0] == 0.0 and calls[-1] == (1.0, "done")
    stages = [s for _, s in calls]
    assert "inertia matrix" in stages and "Christoffel symbols" in stages and "SymPy form of M" in stages


# ----- LaTeX that compiles ----------------------------------------------------------------------------
MATH_ONLY = {"aligned", "matrix", "bmatrix", "pmatrix", "cases", "split", "gathered", "array"}
DISPLAY = {"align*", "align", "equation", "equation*", "gather", "gather*", "multline", "multline*"}
ALIGNING = {"aligned", "matrix", "bmatrix", "pmatrix", "cases", "split", "array", "align*", "align", "tabular"}
MATH_COMMANDS = {"frac", "dot", "ddot", "left", "right", "operatorname", "sin", "cos", "sqrt", "cdot", "tau", "quad"}


def latex_problems(text: str, document: bool = False) -> list[str]:
    """What would stop LaTeX: unbalanced braces or environments, math outside math mode, long lines."""
    import re

    problems = [f"line {k + 1} is {len(line)} characters" for k, line in enumerate(text.split("\n")) if len(line) > 300]
    stack: list[tuple[str, int]] = []  # (environment or "\\[" or "$", brace depth at its start)
    braces = 0
    math = 0  # math-mode depth
    body = re.sub(r"(?<!\\)%.*", "", text)
    tokens = re.findall(r"\\begin\{[^}]*\}|\\end\{[^}]*\}|\\\\|\\[a-zA-Z]+\*?|\\.|[{}$&_^]|[^\\{}$&_^]+", body)
    for token in tokens:
        if token.startswith("\\begin{"):
            name = token[7:-1]
            if name in MATH_ONLY and not math:
                problems.append(f"\\begin{{{name}}} outside math mode")
            if name in DISPLAY and math:
                problems.append(f"\\begin{{{name}}} inside math mode")
            stack.append((name, braces))
            math += name in MATH_ONLY or name in DISPLAY
        elif token.startswith("\\end{"):
            name = token[5:-1]
            if not stack or stack[-1] != (name, braces):
                problems.append(f"\\end{{{name}}} does not match {stack[-1] if stack else 'nothing'}")
                continue
            stack.pop()
            math -= name in MATH_ONLY or name in DISPLAY
        elif token == "\\[":
            if math:
                problems.append("\\[ inside math mode")
            stack.append(("\\[", braces))
            math += 1
        elif token == "\\]":
            if not stack or stack[-1] != ("\\[", braces):
                problems.append("\\] without its \\[")
                continue
            stack.pop()
            math -= 1
        elif token == "$":
            if stack and stack[-1] == ("$", braces):
                stack.pop()
                math -= 1
            else:
                stack.append(("$", braces))
                math += 1
        elif token == "{":
            braces += 1
        elif token == "}":
            braces -= 1
            if braces < 0:
                problems.append("} without its {")
                braces = 0
        elif token in ("_", "^") and not math:
            problems.append(f"{token} outside math mode")
        elif token == "&" and not any(name in ALIGNING for name, _ in stack):
            problems.append("& outside an alignment")
        elif token.startswith("\\") and token[1:] in MATH_COMMANDS - {"quad"} and not math:
            problems.append(f"{token} outside math mode")
    if braces:
        problems.append(f"{braces} unclosed braces")
    problems += [f"{name} never closed" for name, _ in stack]
    if document:
        for needed in (r"\documentclass", r"\usepackage{amsmath}", r"\begin{document}", r"\end{document}"):
            if needed not in text:
                problems.append(f"no {needed}")
    return problems


def test_the_latex_checker_finds_what_stops_latex() -> None:
    assert latex_problems("\\begin{aligned} x &= 1 \\end{aligned}") == ["\\begin{aligned} outside math mode"]
    assert latex_problems("\\[ \\begin{align*} x \\end{align*} \\]") == ["\\begin{align*} inside math mode"]
    assert latex_problems("two_link \\[ x^{2 \\]") != []
    assert (
        latex_problems("\\[ \\dot{q}_{1} \\] and $c_{12}$ \\begin{align*} M_{11} &= a \\\\ &\\quad + b \\end{align*}")
        == []
    )


@pytest.mark.slow
@pytest.mark.parametrize("name", ["two_link_planar", "puma560"])
def test_latex_export_compiles(name: str, tmp_path: Path) -> None:
    arm = ad.models.two_link_planar(symbolic=True) if name == "two_link_planar" else ad.models.load(name)
    form = derive(arm)
    assert latex_problems(form.latex()) == []
    document = form.latex_document()
    assert latex_problems(document, document=True) == []
    assert max(len(line) for line in document.split("\n")) <= 200
    if name == "puma560":  # one equation per entry, broken over lines
        assert r"M_{11} &=" in document and r"&\quad" in document and r"(V_m)_{66} &=" in document
    if shutil.which("pdflatex") is None:
        return
    (tmp_path / "form.tex").write_text(document)
    run = subprocess.run(
        ["pdflatex", "-interaction=nonstopmode", "-halt-on-error", "form.tex"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-3000:]
    assert (tmp_path / "form.pdf").stat().st_size > 0


# ----- the asymmetric Coulomb law as written ------------------------------------------------------------
def test_asymmetric_coulomb_law_prints_as_written() -> None:
    """Tc+ = 0.75 for qd > 0, Tc- = -0.25 for qd < 0: no sign^2, the same friction as the kernels."""
    arm = ad.Robot.from_dh(
        [
            {"a": 0.5, "mass": 1, "com": [-0.25, 0, 0], "inertia": [0.01, 0.02, 0.02], "Tc": (0.75, -0.25), "B": 0.5},
            {"a": 0.4, "mass": 1, "com": [-0.2, 0, 0], "inertia": [0.01, 0.02, 0.02], "Tc": (0.1, -0.1)},
        ]
    )
    form = derive(arm)
    law = form.F[0] - 0.5 * qd1
    assert law.has(sympy.Piecewise) and not law.has(sympy.sign)
    assert [law.subs(qd1, x) for x in (1.0, -1.0, 0.0)] == [0.75, -0.25, 0]
    assert form.F[1].has(sympy.sign) and not form.F[1].has(sympy.Piecewise)  # symmetric: Tc sgn(qd)
    pretty = form.pretty()
    assert "sign" not in pretty.split("F(qd) =")[1].split("\n")[2] and "for qd₁ > 0" in pretty
    assert "0.75" in pretty and "-0.25" in pretty and "for qd₁ < 0" in pretty
    latex = form.latex()
    assert r"0.75 & \text{for}\: \dot{q}_{1} > 0" in latex and r"-0.25 & \text{for}\: \dot{q}_{1} < 0" in latex
    assert "(0.75 if 0 < qd1 else (-0.25 if qd1 < 0 else 0.0))" in form.to_python()
    assert "((0 < qd1) ? 0.75 : ((qd1 < 0) ? -0.25 : 0.0))" in form.to_c()
    compiled = form.compile()
    q, qdd = np.array([0.3, -0.2]), np.array([0.1, 0.4])
    for qd in ([0.5, -0.5], [-0.5, 0.5], [0.0, 0.0], [0.0, -1e-300]):
        qd = np.array(qd)
        expected = arm.inverse_dynamics(q, qd, qdd)
        assert_allclose(evaluate_python(form, "tau", q, qd, qdd), expected, rtol=1e-14, atol=1e-14)
        assert_allclose(compiled.tau(q, qd, qdd), expected, rtol=1e-14, atol=1e-14)


# ----- large outputs ----------------------------------------------------------------------------------
@pytest.mark.slow
def test_pretty_summarises_long_entries_and_save_writes_them_in_full(tmp_path: Path) -> None:
    form = derive(ad.models.puma560())
    text = form.pretty()
    assert len(text) < 30_000 and max(len(line) for line in text.split("\n")) < 400
    assert "operations" in text and "form.save(" in text and "M[1,1] = ..." in text
    assert "M[6,6] = " in text and "M[6,6] = ..." not in text  # short entries are drawn
    full = form.save(str(tmp_path / "puma.txt")).read_text(encoding="utf-8")  # pretty(limit=None)
    assert len(full) > 200_000 and full.startswith("M(q) =\n") and "..." not in full
    assert form.save(tmp_path / "puma.tex").read_text(encoding="utf-8") == form.latex_document()
    assert form.save(tmp_path / "puma.py").read_text(encoding="utf-8") == form.to_python()
    assert form.save(tmp_path / "puma.c").read_text(encoding="utf-8") == form.to_c()
    with pytest.raises(ad.ModelError, match="suffix"):
        form.save(tmp_path / "puma.docx")
    with pytest.raises(ad.ModelError, match="does not exist"):
        form.save(tmp_path / "no" / "puma.tex")
    (tmp_path / "folder.tex").mkdir()
    with pytest.raises(ad.ModelError, match="is a folder"):
        form.save(tmp_path / "folder.tex")
    small = derive(ad.models.two_link_planar(symbolic=True))
    assert small.pretty() == small.pretty(limit=None)  # a small arm is drawn whole
