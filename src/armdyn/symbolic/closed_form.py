"""ClosedForm: the robot equation of one arm in closed form, to read, print and run."""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np
import symengine as se
import sympy

from armdyn.errors import ModelError
from armdyn.robot import Robot
from armdyn.symbolic import codegen
from armdyn.symbolic.derive import Derivation, derive_raw

_COLLAPSE_LIMIT = 4  # joints up to which trigonometric products are collapsed (c1 c2 - s1 s2 -> c12)


def robot_symbols(robot: Robot) -> dict[str, sympy.Symbol]:
    """The SymPy symbols among the arm's parameters, by name (they keep their assumptions).

    Parameters
    ----------
    robot : Robot
        The arm: its gravity, mass properties, joint placements and frame offsets are searched.

    Returns
    -------
    dict of str to sympy.Symbol
        Each symbol found, by name.
    """
    found: dict[str, sympy.Symbol] = {}
    values = [robot.gravity]
    for link in robot.links:
        values += [link.inertial.mass, link.inertial.com, link.inertial.inertia]
        values += [link.joint.placement, link.joint.frame_offset]
    for value in values:
        for item in np.asarray(value, dtype=object).ravel():
            if isinstance(item, sympy.Basic):
                found.update({s.name: s for s in item.free_symbols})
    return found


class ClosedForm:
    """M, Vm, V, G, F and tau of an arm as SymPy matrices, with the means to print and run them.

    ``q``, ``qd``, ``qdd`` are the joint symbols q1..qn, qd1..qdn, qdd1..qddn. Revolute
    angles enter through cos(q_i) and sin(q_i); for arms of up to four joints products are
    collapsed as the book writes them (cos(q1) cos(q2) - sin(q1) sin(q2) = cos(q1 + q2)).
    Made by ``derive``, which is the way to build one.

    Parameters
    ----------
    robot : Robot
        The arm.
    raw : Derivation
        The derivation (symengine expressions) that ``derive`` computed.
    friction : str or bool
        The friction mode the derivation used: True, False or "symbolic" (see ``derive``).
    method : str
        The method used, "lagrange" or "recursive".

    Attributes
    ----------
    M, Vm, V, G, F, tau : sympy.Matrix
        M(q), Vm(q, qd), V(q, qd) = Vm qd, G(q), F(qd) and
        tau = M qdd + V + F + G (BOOK.md section 1).
    q, qd, qdd : sympy.Matrix
        The joint symbols, (n, 1).
    """

    def __init__(self, robot: Robot, raw: Derivation, friction: str | bool, method: str) -> None:
        self.robot = robot
        self.raw = raw
        self.method = method
        self._friction = friction
        self._named = robot_symbols(robot)
        n = robot.n
        self.q = sympy.Matrix([sympy.Symbol(f"q{i + 1}") for i in range(n)])
        self.qd = sympy.Matrix([sympy.Symbol(f"qd{i + 1}") for i in range(n)])
        self.qdd = sympy.Matrix([sympy.Symbol(f"qdd{i + 1}") for i in range(n)])
        self._trig = {}
        for i, (c, s) in raw.trig.items():
            self._trig[c.name] = sympy.cos(self.q[i])
            self._trig[s.name] = sympy.sin(self.q[i])
        self.M = self._matrix(raw.M)
        self.Vm = self._matrix(raw.Vm)
        self.V = self._matrix([[x] for x in raw.V])
        self.G = self._matrix([[x] for x in raw.G])
        self.F = self._matrix([[x] for x in raw.F])
        self.tau = self._matrix([[x] for x in raw.tau])

    # ----- conversion to SymPy --------------------------------------------------------------------
    def _sympy(self, expr: se.Basic, collapse: bool = True) -> sympy.Expr:
        value = sympy.sympify(expr)
        names = {s: self._trig.get(s.name) or self._named.get(s.name) for s in value.free_symbols}
        value = value.xreplace({s: t for s, t in names.items() if t is not None})
        value = value.xreplace({s: sympy.Symbol(s.name) for s in value.free_symbols if s.name[:1] == "q"})
        if collapse and self.robot.n <= _COLLAPSE_LIMIT and value.has(sympy.sin, sympy.cos):
            value = sympy.factor_terms(sympy.trigsimp(value))
        return value

    def _matrix(self, rows: list[list[se.Basic]]) -> sympy.Matrix:
        return sympy.Matrix([[self._sympy(x) for x in row] for row in rows])

    # ----- the structure of Table 3.3.1 -------------------------------------------------------------
    @cached_property
    def V_i(self) -> list[sympy.Matrix]:
        """The symmetric matrices with V_k = qd^T V_k qd (3.3.23): [V_k]_ij = v_ijk."""
        n, v = self.robot.n, self.raw.christoffel
        return [sympy.Matrix([[self._sympy(v[i][j][k]) for j in range(n)] for i in range(n)]) for k in range(n)]

    @cached_property
    def S(self) -> sympy.Matrix:
        """Mdot - 2 Vm, skew symmetric (Table 3.3.1, property 4)."""
        Mdot = sympy.Matrix(self.M.shape[0], self.M.shape[1], lambda i, j: self._time_derivative(self.M[i, j]))
        return (Mdot - 2 * self.Vm).applyfunc(lambda e: sympy.factor_terms(sympy.trigsimp(sympy.expand(e))))

    def _time_derivative(self, expr: sympy.Expr) -> sympy.Expr:
        return sum(sympy.diff(expr, self.q[i]) * self.qd[i] for i in range(self.robot.n))

    @cached_property
    def _parameterization(self) -> tuple[sympy.Matrix, sympy.Matrix, list[float] | None]:
        from armdyn.symbolic.parameters import linear_parameterization

        return linear_parameterization(self)

    @property
    def W(self) -> sympy.Matrix:
        """The regressor W(q, qd, qdd) with tau = W phi (Table 3.3.1, property 9)."""
        return self._parameterization[0]

    @property
    def phi(self) -> sympy.Matrix:
        """The parameters of tau = W phi: masses, first moments, inertias, friction, motors."""
        return self._parameterization[1]

    @property
    def phi_values(self) -> list[float] | None:
        """Numeric values of phi for an arm with numeric parameters (None for a symbolic arm)."""
        return self._parameterization[2]

    # ----- printing -------------------------------------------------------------------------------
    def _short(self, expr: sympy.Expr) -> sympy.Expr:
        """cos(q1 + q2) -> c_{12}, sin(q2) -> s_{2}: the book's notation."""
        index = {q: i + 1 for i, q in enumerate(self.q)}
        replacements = {}
        for f in expr.atoms(sympy.cos, sympy.sin):
            terms = sympy.Add.make_args(f.args[0])
            if all(t in index for t in terms):
                label = "".join(str(index[t]) for t in sorted(terms, key=index.get))
                replacements[f] = sympy.Symbol(("c" if isinstance(f, sympy.cos) else "s") + f"_{{{label}}}")
        return expr.xreplace(replacements)

    def _display(self) -> list[tuple[str, sympy.Matrix]]:
        dot = {self.qd[i]: sympy.Symbol(rf"\dot{{q}}_{{{i + 1}}}") for i in range(self.robot.n)}
        ddot = {self.qdd[i]: sympy.Symbol(rf"\ddot{{q}}_{{{i + 1}}}") for i in range(self.robot.n)}
        joints = {self.q[i]: sympy.Symbol(f"q_{{{i + 1}}}") for i in range(self.robot.n)}
        items = [("M(q)", self.M), (r"V_m(q, \dot{q})", self.Vm), (r"V(q, \dot{q})", self.V), ("G(q)", self.G)]
        if any(x != 0 for x in self.F):
            items.append((r"F(\dot{q})", self.F))
        out = []
        for label, m in items:
            shown = m.applyfunc(lambda e: self._short(e).xreplace(dot).xreplace(ddot).xreplace(joints))
            out.append((label, shown))
        return out

    def latex(self) -> str:
        """The equations as LaTeX, in the book's layout: M(q) qdd + Vm qd + F + G = tau, then each term.

        cos(q1 + q2) is written c_{12}, sin(q2) s_{2}, as the book does.

        Returns
        -------
        str
            A display equation followed by an ``aligned`` block, one line per term.
        """
        lines = [r"M(q)\,\ddot{q} + V_m(q,\dot{q})\,\dot{q} + F(\dot{q}) + G(q) = \tau"]
        for label, m in self._display():
            lines.append(f"{label} &= {sympy.latex(m, mat_delim='[')}")
        body = " \\\\\n".join(lines[1:])
        return f"\\[ {lines[0]} \\]\n\\begin{{aligned}}\n{body}\n\\end{{aligned}}\n"

    def pretty(self) -> str:
        """The equations for the terminal (SymPy's pretty printer, c_12 = cos(q1 + q2)).

        Returns
        -------
        str
            M(q), Vm(q, qd), V(q, qd), G(q) and, when not zero, F(qd), one block each.
        """
        blocks = []
        for label, m in self._display():
            clean = label.replace("\\dot{q}", "qd").replace(r"\,", "").replace("_m", "m")
            shown = m.applyfunc(lambda e: e.xreplace({s: sympy.Symbol(_plain(s.name)) for s in e.free_symbols}))
            blocks.append(f"{clean} =\n{sympy.pretty(shown, use_unicode=True, wrap_line=False)}")
        return "\n\n".join(blocks)

    def __repr__(self) -> str:
        return f"ClosedForm('{self.robot.name}', n={self.robot.n}, method='{self.method}')"

    # ----- code -------------------------------------------------------------------------------------
    def operation_counts(self, cse: bool = True) -> dict[str, int]:
        """Arithmetic operations of M, Vm, G and tau, before (cse=False) or after common-subexpression elimination.

        Parameters
        ----------
        cse : bool, optional
            True (default) counts after common-subexpression elimination, False before.

        Returns
        -------
        dict of str to int
            The count for each of "M", "Vm", "G" and "tau".
        """
        return codegen.operation_counts(self.raw, cse)

    def to_python(self) -> str:
        """Python source (NumPy/Numba-ready) of M(q), Vm(q, qd), G(q), tau(q, qd, qdd), with CSE.

        Returns
        -------
        str
            A module defining M(q, out), Vm(q, qd, out), G(q, out) and tau(q, qd, qdd, out),
            each filling and returning ``out``; the arm's symbolic parameters follow ``out``
            as further arguments, in alphabetical order.
        """
        return codegen.python_source(self.raw, self._parameter_names())

    def to_c(self) -> str:
        """C99 source of the same four functions, with CSE.

        Returns
        -------
        str
            void functions M, Vm, G and tau taking ``const double *`` states and a ``double
            *out`` (matrices row major); the arm's symbolic parameters follow ``out`` as
            further ``double`` arguments, in alphabetical order.
        """
        return codegen.c_source(self.raw, self._parameter_names())

    def _parameter_names(self) -> list[str]:
        present = set()
        for value in (*self.raw.tau, *self.raw.G, *(x for row in self.raw.M for x in row)):
            present |= {s.name for s in value.free_symbols}
        state = {s.name for s in (*self.raw.q, *self.raw.qd, *self.raw.qdd)}
        trig = {s.name for pair in self.raw.trig.values() for s in pair}
        return sorted(present - state - trig)

    def compile(self, values: dict[Any, float] | None = None) -> codegen.CompiledClosedForm:
        """Numba-compiled M(q), Vm(q, qd), G(q), tau(q, qd, qdd), batched like the rest of armdyn.

        Parameters
        ----------
        values : dict, optional
            Numeric values of the arm's symbolic parameters, keyed by symbol or by name;
            an arm with symbolic parameters needs one for each.

        Returns
        -------
        CompiledClosedForm
            An object with methods M, Vm, G and tau, each taking one state (n,) or a batch
            (..., n) and an optional ``out`` array.

        Raises
        ------
        armdyn.ModelError
            When a symbolic parameter of the arm has no value in ``values``.
        """
        names = self._parameter_names()
        given = {str(k): float(v) for k, v in (values or {}).items()}
        missing = [name for name in names if name not in given]
        if missing:
            raise ModelError(f"compile() needs numeric values for the parameters {missing}")
        return codegen.compile_closed_form(self.raw, {name: given[name] for name in names})


def _plain(name: str) -> str:
    return name.replace("\\dot{q}_{", "qd").replace("\\ddot{q}_{", "qdd").replace("_{", "").replace("}", "")


def derive(robot: Robot, method: str = "auto", friction: str | bool = True) -> ClosedForm:
    """The closed-form robot equation of ``robot`` (numeric, symbolic or mixed parameters).

    M(q) qdd + Vm(q, qd) qd + F(qd) + G(q) = tau (BOOK.md sections 1 and 4), with the
    reflected motor inertias G^2 Jm on the diagonal of M.

    Parameters
    ----------
    robot : Robot
        The arm; its parameters may be numbers, SymPy expressions, or both.
    method : str, optional
        "lagrange" (the book's trace formula with pseudo-inertia matrices), "recursive"
        (composite rigid bodies, for larger arms) or "auto" (default: Lagrange up to three
        joints).
    friction : str or bool, optional
        True (default) for the arm's own friction, False for none, "symbolic" for new
        symbols v_i (viscous) and k_i (Coulomb), F_i = v_i qd_i + k_i sgn(qd_i).

    Returns
    -------
    ClosedForm
        M, Vm, V, G, F and tau as SymPy matrices, with printing and code generation.

    Raises
    ------
    armdyn.ModelError
        When ``method`` is not "auto", "lagrange" or "recursive".
    """
    raw = derive_raw(robot, method, friction)
    chosen = method if method != "auto" else ("lagrange" if robot.n <= 3 else "recursive")
    return ClosedForm(robot, raw, friction, chosen)
