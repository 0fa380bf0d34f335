"""TaskClosedForm: the robot equation in the coordinates of an output y = h(q), in closed form.

Lewis, Dawson and Abdallah 2004, Section 3.5 and Example 3.5-1. For an output with a square
Jacobian J = dh/dq (m = n, ydot = J qd), the arm obeys Mbar yddot + Nbar = f with

    Mbar  = J^-T M J^-1,                 Vmbar = J^-T (Vm - M J^-1 Jdot) J^-1,
    Gbar  = J^-T G,   Fbar = J^-T F,     Nbar  = Vmbar ydot + Fbar + Gbar,

all written here in the joint symbols q1.., qd1.. (ydot = J qd). The outputs are the
point outputs of ``armdyn.task_space``: ToolPosition, LinkPoint, PlanarPosition, and
Camera (the pinhole projection y = f [x_c / z_c, y_c / z_c] of the tool point).

The algebra runs on the trigonometric polynomials of ``armdyn.symbolic.algebra``. With
y = u / z (z = 1 for a position, the depth z_c for a camera), J = Jn / w with the
polynomial matrix Jn = z du/dq - u dz/dq and w = z^2. With D = det Jn and A = adj Jn,
J^-1 = w A / D (A Jn = D 1), J^-1 Jdot = (w A Jndot - D wdot 1) / (D w), and each term
is a polynomial over a power of D:

    Mbar  = w^2 A^T M A / D^2,    Gbar = w A^T G / D,    Fbar = w A^T F / D,
    Vmbar = w A^T (D w Vm - K) A / D^3,    Nbar = A^T (D w N - K qd) / D^2,

with K = M (w A Jndot - D wdot 1) and N = V + F + G. Each numerator is reduced
(s_i^2 = 1 - c_i^2), its common factors with D are cancelled, sums of angles are written
as the book does (c12), and short numerators go through SymPy's trigsimp. An arm whose
geometry is too large for the expansion to pay (a general spatial arm) keeps its terms
as exact products of these pieces, not expanded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import symengine as se
import sympy

from armdyn import inputs, kinematics
from armdyn.errors import ArgumentError, ModelError, SingularError
from armdyn.robot import Robot
from armdyn.symbolic import notebook
from armdyn.symbolic.algebra import number, transform
from armdyn.symbolic.codegen import count_operations
from armdyn.symbolic.derive import _Arm
from armdyn.task_space import Camera, LinkPoint, PlanarPosition, TaskOutput, ToolPose, ToolPosition

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from armdyn.symbolic.closed_form import ClosedForm

POINT_OUTPUTS = (ToolPosition, LinkPoint, PlanarPosition, Camera)
_SUPPORTED = "ToolPosition, LinkPoint, PlanarPosition and Camera, with as many rows as the arm has joints"
_EXPAND_LIMIT = 150  # operations in D, adj Jn and M up to which the terms are expanded and simplified (the book's arms)
_TRIGSIMP_LIMIT = 16  # operations in a numerator up to which SymPy's trigsimp is tried
_MATRICES = ("h", "J", "J_inv", "Mbar", "Vmbar", "Gbar", "Fbar", "Nbar")


def check_output(arm: Robot, output: object) -> TaskOutput:
    """``output`` checked as a point output with a square Jacobian for ``robot`` (Section 3.5).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : object
        The output given to ``derive``.

    Returns
    -------
    TaskOutput
        The output.

    Raises
    ------
    armdyn.ModelError
        When ``output`` has a number of rows other than ``robot.n``, or (LinkPoint) names no
        link of the arm.
    armdyn.ArgumentError
        When ``output`` is not one of the supported outputs, or is a ToolPose.
    """
    if isinstance(output, ToolPose):
        raise ArgumentError(
            f"closed-form task dynamics support {_SUPPORTED}; ToolPose is not supported (its rate [v; w] "
            "holds the angular velocity, the derivative of no h(q))"
        )
    if not isinstance(output, POINT_OUTPUTS):
        kind = repr(output) if isinstance(output, TaskOutput) else type(output).__name__
        raise ArgumentError(
            f"closed-form task dynamics support the outputs of armdyn.task_space {_SUPPORTED}; got {kind}"
        )
    if isinstance(output, LinkPoint):
        kinematics.link_index(arm, output.link)
    m = 2 if isinstance(output, Camera) else len(output._rows)
    if m != arm.n:
        raise ModelError(
            f"output {output!r} has {m} rows but arm '{arm.name}' has {arm.n} joints: closed-form task dynamics "
            f"need a square J (m = n); supported are {_SUPPORTED}"
        )
    return output


def _point(arm: _Arm, output: TaskOutput) -> tuple[list[se.Basic], se.Basic]:
    """(u, z) with y = u / z: the output's numerators and denominator, as trigonometric polynomials."""
    robot, world = arm.robot, arm.world_transforms()
    if isinstance(output, LinkPoint):
        T = world[kinematics.link_index(robot, output.link)]
    else:
        T = world[robot.tool_link] * transform(robot.tool)
    p = [T[r, 3] for r in range(3)]
    if not isinstance(output, Camera):
        assert isinstance(output, (ToolPosition, LinkPoint, PlanarPosition))  # the outputs check_output lets pass
        return [p[r] for r in output._rows], se.Integer(1)
    pose, f = transform(output.pose), number(output.focal_length)
    pc = [sum(pose[r, k] * (p[r] - pose[r, 3]) for r in range(3)) for k in range(3)]  # R_c^T (p - o_c)
    return [f * pc[0], f * pc[1]], pc[2]


def _adjugate(m: se.DenseMatrix) -> se.DenseMatrix:
    n = m.rows
    if n == 1:
        return se.DenseMatrix([[1]])

    def minor(i: int, j: int) -> se.Basic:
        rows, cols = [r for r in range(n) if r != i], [c for c in range(n) if c != j]
        return se.DenseMatrix(n - 1, n - 1, [m[r, c] for r in rows for c in cols]).det()

    return se.DenseMatrix(n, n, [(-1) ** (i + j) * minor(j, i) for i in range(n) for j in range(n)])


class TaskClosedForm:
    """The robot equation of an arm in the coordinates of an output y = h(q), as SymPy matrices.

    Made by ``derive(robot, output=...)`` (Section 3.5): Mbar yddot + Nbar = f, with
    every term written in the joint symbols ``q`` and ``qd`` (ydot = J qd). Entries are
    simplified (common factors cancelled, c12 for cos(q1 + q2)) for arms of the book's
    size; ``pretty`` and ``latex`` print them, ``compile`` evaluates them with NumPy.

    Parameters
    ----------
    form : ClosedForm
        The arm's closed form in joint coordinates.
    output : TaskOutput
        The output, checked by ``check_output``.

    Attributes
    ----------
    h : sympy.Matrix
        The output y = h(q), (n, 1).
    J, J_inv : sympy.Matrix
        The Jacobian dh/dq and its inverse, (n, n).
    det_J : sympy.Expr
        det J.
    Mbar, Vmbar : sympy.Matrix
        J^-T M J^-1 and J^-T (Vm - M J^-1 Jdot) J^-1, (n, n).
    Gbar, Fbar, Nbar : sympy.Matrix
        J^-T G, J^-T F and Nbar = Vmbar J qd + Fbar + Gbar, (n, 1).
    q, qd : sympy.Matrix
        The joint symbols, (n, 1).
    form : ClosedForm
        The joint-space closed form (M, Vm, G, F, ...).
    output : TaskOutput
        The output.
    expanded : bool
        Whether the terms were expanded and simplified (False for an arm too large for
        it, whose terms are exact but unexpanded products).

    Raises
    ------
    armdyn.ModelError
        When ``output`` is not supported (see ``check_output``).
    armdyn.SingularError
        When J is singular at every q (det J = 0).
    """

    def __init__(self, form: ClosedForm, output: TaskOutput) -> None:
        robot, raw = form.robot, form.raw
        self.form, self.output, self.robot = form, check_output(robot, output), robot
        self.q, self.qd = form.q, form.qd
        arm = _Arm(robot)
        reduce, diff, n = arm.algebra.reduce, arm.algebra.diff, robot.n

        def rate(e: se.Basic) -> se.Basic:
            return reduce(sum(diff(e, k) * raw.qd[k] for k in range(n)))

        u, z = _point(arm, self.output)
        u, z = [reduce(x) for x in u], reduce(z)
        Jn = se.DenseMatrix(n, n, [reduce(z * diff(u[i], j) - u[i] * diff(z, j)) for i in range(n) for j in range(n)])
        w = reduce(z * z)
        D = reduce(Jn.det())
        if D == 0:
            raise SingularError(
                f"output {output!r} has a singular J at every q of arm '{robot.name}' (det J = 0)", condition=np.inf
            )
        A = _adjugate(Jn).applyfunc(reduce)
        M, Vm = se.DenseMatrix(raw.M), se.DenseMatrix(raw.Vm)
        G, F = se.DenseMatrix(n, 1, raw.G), se.DenseMatrix(n, 1, raw.F)
        N = se.DenseMatrix(n, 1, [raw.V[k] + raw.F[k] + raw.G[k] for k in range(n)])
        size = sum(count_operations(x) for x in [D, *A, *M])
        self.expanded = size <= _EXPAND_LIMIT
        tidy = reduce if self.expanded else (lambda e: e)
        self._tidy = tidy
        self._sines = [(sympy.Symbol(c.name), sympy.Symbol(s.name)) for c, s in raw.trig.values()]

        def product(*factors: se.DenseMatrix) -> se.DenseMatrix:
            result = factors[0]
            for factor in factors[1:]:
                result = (result * factor).applyfunc(tidy)
            return result

        K = product(M, (A * Jn.applyfunc(rate) * w - se.eye(n) * (D * rate(w))).applyfunc(tidy))
        self.h = sympy.Matrix([self._fraction(x, z) for x in u])
        self.J = self._matrix(Jn, w)
        self.J_inv = self._matrix(A * w, D)
        self.det_J = self._fraction(D, w**n)
        self.Mbar = self._matrix(product(A.T, M, A) * (w * w), D**2)
        self.Vmbar = self._matrix(product(A.T, (Vm * (D * w) - K).applyfunc(tidy), A) * w, D**3)
        self.Gbar = self._matrix(product(A.T, G) * w, D)
        self.Fbar = self._matrix(product(A.T, F) * w, D)
        self.Nbar = self._matrix(product(A.T, (N * (D * w) - K * se.DenseMatrix(raw.qd)).applyfunc(tidy)), D**2)

    # ----- conversion to SymPy --------------------------------------------------------------------
    def _fraction(self, numerator: se.Basic, denominator: se.Basic) -> sympy.Expr:
        """numerator / denominator in SymPy: common factors cancelled, c12 collapsed, short ones trigsimp'd."""
        convert = self.form._sympy
        numerator = self._tidy(numerator)
        if not self.expanded:
            return convert(numerator, False) / convert(denominator, False)
        top, bottom = sympy.fraction(sympy.cancel(sympy.sympify(numerator) / sympy.sympify(denominator)))
        for c, s in self._sines:  # over s_i^k, c_i^2 = 1 - s_i^2 lets the sines cancel
            if bottom.has(s) and top.has(c):
                top, bottom = sympy.fraction(sympy.cancel(sympy.rem(top, c**2 + s**2 - 1, c) / bottom))
        top, bottom = convert(se.sympify(top)), convert(se.sympify(bottom))
        if 0 < sympy.count_ops(top) <= _TRIGSIMP_LIMIT:
            simpler = sympy.factor_terms(sympy.trigsimp(top))
            if sympy.count_ops(simpler) < sympy.count_ops(top) and _angles(simpler) <= _angles(top):
                top = simpler
        coefficient, bottom = bottom.as_coeff_Mul()
        value = top / coefficient / bottom
        if bottom != 1 and not bottom.is_Add and not bottom.has(sympy.sin, sympy.cos):
            value = sympy.expand(value)  # over a monomial such as r^2: term by term, as the book writes m2 + Jb s^2
        if not self.robot.is_symbolic:  # shown as decimals, as ClosedForm shows a numeric arm
            value = value.xreplace({r: sympy.Float(r) for r in value.atoms(sympy.Rational) if not r.is_Integer})
        return value

    def _matrix(self, numerators: se.DenseMatrix, denominator: se.Basic) -> sympy.Matrix:
        rows, cols = numerators.rows, numerators.cols
        return sympy.Matrix(rows, cols, [self._fraction(x, denominator) for x in numerators])

    # ----- printing -------------------------------------------------------------------------------
    def _shown(self) -> list[tuple[str, str, sympy.Matrix]]:
        """(plain label, LaTeX label, matrix in the book's notation) of each term."""
        n = self.robot.n
        dot = {self.qd[i]: sympy.Symbol(rf"\dot{{q}}_{{{i + 1}}}") for i in range(n)}
        joints = {self.q[i]: sympy.Symbol(f"q_{{{i + 1}}}") for i in range(n)}
        items = [
            ("y = h(q)", "y = h(q)", self.h),
            ("J(q)", "J(q)", self.J),
            ("J(q)^-1", "J(q)^{-1}", self.J_inv),
            ("Mbar(q)", r"\bar{M}(q)", self.Mbar),
            ("Vmbar(q, qd)", r"\bar{V}_m(q, \dot{q})", self.Vmbar),
            ("Gbar(q)", r"\bar{G}(q)", self.Gbar),
        ]
        if any(x != 0 for x in self.Fbar):
            items.append(("Fbar(q, qd)", r"\bar{F}(q, \dot{q})", self.Fbar))
        items.append(("Nbar(q, qd)", r"\bar{N}(q, \dot{q})", self.Nbar))
        shown = []
        for plain, label, m in items:
            shown.append((plain, label, m.applyfunc(lambda e: self.form._short(e).xreplace(dot).xreplace(joints))))
        return shown

    def latex(self) -> str:
        r"""The terms as LaTeX, in the book's notation (c_{12} = cos(q1 + q2)), one ``align*`` block.

        Returns
        -------
        str
            The equation Mbar yddot + Nbar = f, then h, J, J^-1, Mbar, Vmbar, Gbar, Fbar
            (when not zero) and Nbar; compiles with ``\usepackage{amsmath}``.
        """
        rows = [rf"{label} &= {sympy.latex(m, full_prec=False)}" for _, label, m in self._shown()]
        head = r"\[ \bar{M}(q)\,\ddot{y} + \bar{N}(q, \dot{q}) = f, \qquad \dot{y} = J(q)\,\dot{q} \]"
        return "\n".join([head, r"\begin{align*}", " \\\\\n".join(rows), r"\end{align*}"]) + "\n"

    def pretty(self, limit: int | None = 150) -> str:
        """The terms for the terminal (SymPy's pretty printer, c12 = cos(q1 + q2)).

        Parameters
        ----------
        limit : int or None, optional
            The widest drawing shown (default 150 characters); a wider term is named with
            its width. None draws every term.

        Returns
        -------
        str
            h, J, J^-1, Mbar, Vmbar, Gbar, Fbar (when not zero) and Nbar, one block each.
        """
        blocks = []
        for plain, _, m in self._shown():
            m = m.applyfunc(lambda e: e.xreplace({s: sympy.Symbol(_plain(s.name)) for s in e.free_symbols}))
            drawn = sympy.pretty(m, use_unicode=True, wrap_line=False, full_prec=False)
            width = max(len(line) for line in drawn.split("\n"))
            if limit is not None and width > limit:
                drawn = f"({width:,} characters wide: pretty(limit=None) draws it)"
            blocks.append(f"{plain} =\n{drawn}")
        return "\n\n".join(blocks)

    def __repr__(self) -> str:
        return f"TaskClosedForm('{self.robot.name}', {self.output!r}, n={self.robot.n})"

    def _repr_latex_(self) -> str:
        r"""The terms for a notebook: Mbar yddot + Nbar = f, then h, J, J^-1, Mbar, Vmbar, Gbar, Fbar (when
        not zero) and Nbar, in one ``$$\begin{aligned} ... \end{aligned}$$`` display of bounded size
        (armdyn.symbolic.notebook: long entries are named, not shown; ``latex`` gives them all)."""
        names = {"y = h(q)": "h", "J(q)": "J", "J(q)^-1": "(J^{-1})", "Mbar(q)": r"\bar{M}",
                 "Vmbar(q, qd)": r"(\bar{V}_m)", "Gbar(q)": r"\bar{G}", "Fbar(q, qd)": r"\bar{F}",
                 "Nbar(q, qd)": r"\bar{N}"}  # fmt: skip
        terms = [notebook.Term(label, names[plain], m, plain == "Mbar(q)") for plain, label, m in self._shown()]
        equation = r"\bar{M}(q)\,\ddot{y} + \bar{N}(q, \dot{q}) &= f, \qquad \dot{y} = J(q)\,\dot{q}"
        return notebook.display(equation, terms, "latex() gives every entry.")

    # ----- evaluation -----------------------------------------------------------------------------
    def compile(self, values: dict[Any, float] | None = None) -> CompiledTaskForm:
        """NumPy functions of the terms (SymPy's lambdify), for one state or a batch.

        Parameters
        ----------
        values : dict, optional
            Numeric values of the arm's symbolic parameters, keyed by symbol or by name;
            an arm with symbolic parameters needs one for each.

        Returns
        -------
        CompiledTaskForm
            Methods h(q), J(q), J_inv(q), Mbar(q), Vmbar(q, qd), Gbar(q), Fbar(q, qd) and
            Nbar(q, qd).

        Raises
        ------
        armdyn.ModelError
            When a symbolic parameter of the arm has no value in ``values``.
        """
        state = set(self.q) | set(self.qd)
        present = {s for name in _MATRICES for s in getattr(self, name).free_symbols} - state
        given = {str(k): float(v) for k, v in (values or {}).items()}
        missing = sorted(s.name for s in present if s.name not in given)
        if missing:
            raise ModelError(f"compile() needs numeric values for the parameters {missing}")
        return CompiledTaskForm(self, {s: given[s.name] for s in present})


class CompiledTaskForm:
    """NumPy functions of a TaskClosedForm's terms; made by ``TaskClosedForm.compile``.

    Each method takes joint positions q (and velocities qd), (n,) or a batch (..., n)
    whose shapes broadcast, evaluates state by state, and raises armdyn.ModelError for an
    invalid state. At a singular state (det J = 0) the terms are infinite or NaN.
    """

    def __init__(self, form: TaskClosedForm, values: dict[sympy.Symbol, float]) -> None:
        self.n = form.robot.n
        q, qd = list(form.q), list(form.qd)
        self._functions = {}
        for name in _MATRICES:
            term = getattr(form, name).xreplace(values)
            self._functions[name] = (sympy.lambdify([q, qd], term, modules="numpy", cse=True), term.shape)

    def _evaluate(self, name: str, *states: ArrayLike) -> np.ndarray:
        function, shape = self._functions[name]
        names = ("q", "qd")[: len(states)]
        batch, flat = inputs.batch_states(names, states, self.n)
        if len(flat) == 1:
            flat.append(np.zeros_like(flat[0]))
        out = np.empty((flat[0].shape[0], *shape))
        for b in range(out.shape[0]):
            out[b] = function(flat[0][b], flat[1][b])
        out = out[..., 0] if shape[1] == 1 else out
        return out.reshape(*batch, *out.shape[1:])

    def h(self, q: ArrayLike) -> np.ndarray:
        """y = h(q), (..., n)."""
        return self._evaluate("h", q)

    def J(self, q: ArrayLike) -> np.ndarray:
        """J(q), (..., n, n)."""
        return self._evaluate("J", q)

    def J_inv(self, q: ArrayLike) -> np.ndarray:
        """J(q)^-1, (..., n, n)."""
        return self._evaluate("J_inv", q)

    def Mbar(self, q: ArrayLike) -> np.ndarray:
        """Mbar(q) = J^-T M J^-1, (..., n, n)."""
        return self._evaluate("Mbar", q)

    def Vmbar(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """Vmbar(q, qd) = J^-T (Vm - M J^-1 Jdot) J^-1, (..., n, n)."""
        return self._evaluate("Vmbar", q, qd)

    def Gbar(self, q: ArrayLike) -> np.ndarray:
        """Gbar(q) = J^-T G, (..., n)."""
        return self._evaluate("Gbar", q)

    def Fbar(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """Fbar(q, qd) = J^-T F(qd), (..., n)."""
        return self._evaluate("Fbar", q, qd)

    def Nbar(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """Nbar(q, qd) = Vmbar J qd + Fbar + Gbar, (..., n)."""
        return self._evaluate("Nbar", q, qd)


def _angles(expr: sympy.Expr) -> set[sympy.Expr]:
    """The arguments of the cosines and sines in ``expr``."""
    return {f.args[0] for f in expr.atoms(sympy.cos, sympy.sin)}


def _plain(name: str) -> str:
    return name.replace("\\dot{q}_{", "qd").replace("_{", "").replace("}", "")
