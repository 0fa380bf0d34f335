"""ClosedForm: the robot equation of one arm in closed form, to read, print and run."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import symengine as se
import sympy

from armdyn import inputs
from armdyn.errors import ArgumentError, ModelError
from armdyn.robot import Robot
from armdyn.symbolic import codegen, notebook
from armdyn.symbolic.algebra import collapse_sums
from armdyn.symbolic.derive import Derivation, derive_raw

if TYPE_CHECKING:
    from armdyn.actuators import ActuatedArm
    from armdyn.symbolic.actuated import ActuatedClosedForm
    from armdyn.symbolic.task import TaskClosedForm
    from armdyn.task_space import TaskOutput

_DERIVED = 0.5  # the share of derive's progress taken by the derivation, before the conversion to SymPy
_FACTOR_LIMIT = 4  # joints up to which common factors are taken out (a2 m2 (a1 c2 + a2)); slow for six


def robot_symbols(arm: Robot) -> dict[str, sympy.Symbol]:
    """The SymPy symbols among the arm's parameters, by name (they keep their assumptions).

    Parameters
    ----------
    arm : Robot
        The arm: its gravity, mass properties, joint placements and frame offsets are searched.

    Returns
    -------
    dict of str to sympy.Symbol
        Each symbol found, by name.
    """
    found: dict[str, sympy.Symbol] = {}
    values: list[object] = [arm.gravity]
    for link in arm.links:
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
    angles enter through cos(q_i) and sin(q_i); products are collapsed as the book writes
    them (cos(q1) cos(q2) - sin(q1) sin(q2) = cos(q1 + q2), see
    ``armdyn.symbolic.algebra.collapse_sums``), and for arms of up to four joints common
    factors are taken out (a2 m2 (a1 c2 + a2)). Made by ``derive``, which is the way to
    build one. ``pretty``, ``latex`` and ``latex_document`` print the equations, ``save``
    writes them (or code) to a file, ``to_python``, ``to_c`` and ``compile`` give code.

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
    progress : callable, optional
        Called as progress(fraction, stage) before each matrix is converted to SymPy
        (``derive`` passes its own).

    Attributes
    ----------
    M, Vm, V, G, F, tau : sympy.Matrix
        M(q), Vm(q, qd), V(q, qd) = Vm qd, G(q), F(qd) and
        tau = M qdd + V + F + G (3.3.1).
    q, qd, qdd : sympy.Matrix
        The joint symbols, (n, 1).
    """

    M: sympy.Matrix
    Vm: sympy.Matrix
    V: sympy.Matrix
    G: sympy.Matrix
    F: sympy.Matrix
    tau: sympy.Matrix

    def __init__(
        self,
        robot: Robot,
        raw: Derivation,
        friction: str | bool,
        method: str,
        progress: Callable[[float, str], object] | None = None,
    ) -> None:
        self.robot = robot
        self.raw = raw
        self.method = method
        self._friction = friction
        self._named = robot_symbols(robot)
        n = robot.n
        self.q = sympy.Matrix([sympy.Symbol(f"q{i + 1}") for i in range(n)])
        self.qd = sympy.Matrix([sympy.Symbol(f"qd{i + 1}") for i in range(n)])
        self.qdd = sympy.Matrix([sympy.Symbol(f"qdd{i + 1}") for i in range(n)])
        self._trig_kind: dict[str, tuple[str | None, tuple[int, ...]]] = {}
        for i, (c, s) in raw.trig.items():
            self._trig_kind[c.name], self._trig_kind[s.name] = ("c", (i,)), ("s", (i,))
        parts = [("M", raw.M), ("Vm", raw.Vm), ("V", [[x] for x in raw.V]), ("G", [[x] for x in raw.G])]
        parts += [("F", [[x] for x in raw.F]), ("tau", [[x] for x in raw.tau])]
        done, total = 0, sum(len(rows) * len(rows[0]) for _, rows in parts)
        for name, rows in parts:
            if progress is not None:
                progress(_DERIVED + (1 - _DERIVED) * done / total, f"SymPy form of {name}")
            setattr(self, name, self._matrix(rows))
            done += len(rows) * len(rows[0])
        if progress is not None:
            progress(1.0, "done")

    # ----- conversion to SymPy --------------------------------------------------------------------
    def _sympy(self, expr: se.Basic, collapse: bool = True) -> sympy.Expr:
        names: dict[str, tuple[str, tuple[int, ...]]] = {}
        if collapse:
            expr, names = collapse_sums(expr, self.raw.trig)
        q = self.raw.q
        trig = {}  # in SymEngine, which is fast, before the one conversion to SymPy
        for symbol in expr.free_symbols:
            kind, joints = names.get(symbol.name) or self._trig_kind.get(symbol.name, (None, ()))
            if kind is not None:
                angle = se.Add(*(q[j] for j in joints))
                trig[symbol] = se.cos(angle) if kind == "c" else se.sin(angle)
        if trig:
            expr = expr.xreplace(trig)
        if not self.robot.is_symbolic:  # exact inside, shown as the decimals the arm was given in
            expr = _as_doubles(expr)
        value = sympy.sympify(expr)
        named = {s: self._named[s.name] for s in value.free_symbols if s.name in self._named}
        if named:  # the arm's own symbols, with their assumptions
            value = value.xreplace(named)
        return sympy.factor_terms(value) if collapse and self.robot.n <= _FACTOR_LIMIT else value

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
        separator = "," if self.robot.n >= 10 else ""
        replacements = {}
        for f in expr.atoms(sympy.cos, sympy.sin):
            terms = sympy.Add.make_args(f.args[0])
            if all(t in index for t in terms):
                label = separator.join(str(index[t]) for t in sorted(terms, key=lambda t: index[t]))
                replacements[f] = sympy.Symbol(("c" if isinstance(f, sympy.cos) else "s") + f"_{{{label}}}")
        return expr.xreplace(replacements)

    def _display(self) -> list[_Shown]:
        """M, Vm, V, G and (when not zero) F in the book's notation, with their raw entries."""
        n = self.robot.n
        dot = {self.qd[i]: sympy.Symbol(rf"\dot{{q}}_{{{i + 1}}}") for i in range(n)}
        ddot = {self.qdd[i]: sympy.Symbol(rf"\ddot{{q}}_{{{i + 1}}}") for i in range(n)}
        joints = {self.q[i]: sympy.Symbol(f"q_{{{i + 1}}}") for i in range(n)}
        raw = self.raw
        items = [
            ("M(q)", "M", "M", self.M, raw.M),
            (r"V_m(q, \dot{q})", "V_m", "Vm", self.Vm, raw.Vm),
            (r"V(q, \dot{q})", "V", "V", self.V, [[x] for x in raw.V]),
            ("G(q)", "G", "G", self.G, [[x] for x in raw.G]),
        ]
        if any(x != 0 for x in self.F):
            items.append((r"F(\dot{q})", "F", "F", self.F, [[x] for x in raw.F]))
        out = []
        for label, entry, plain, m, rows in items:
            shown = m.applyfunc(lambda e: self._short(e).xreplace(dot).xreplace(ddot).xreplace(joints))
            out.append(_Shown(label, entry, plain, shown, rows))
        return out

    def _entry_label(self, shown: _Shown, i: int, j: int) -> str:
        index = f"{i + 1}" if shown.matrix.shape[1] == 1 else f"{i + 1}{j + 1}"
        if self.robot.n >= 10 and shown.matrix.shape[1] > 1:
            index = f"{i + 1},{j + 1}"
        if shown.entry == "V_m":
            return f"(V_m)_{{{index}}}"
        return f"{shown.entry}_{{{index}}}"

    def latex(self, width: int = 100) -> str:
        r"""The equations as LaTeX, in the book's layout: M(q) qdd + Vm qd + F + G = tau, then each term.

        cos(q1 + q2) is written c_{12}, sin(q2) s_{2}, as the book does. Every formula is in
        a display (``\[ ... \]`` or ``align*``), so the text compiles inside a document
        with ``\usepackage{amsmath}`` (``latex_document`` gives a complete one). A term whose
        entries are all short is one matrix, in an ``aligned`` block; otherwise each entry
        is its own equation, broken over lines of about ``width`` characters, with
        ``\allowdisplaybreaks`` needed for page breaks in long ones (M is symmetric, so only
        its upper triangle is written).

        Parameters
        ----------
        width : int, optional
            The longest line of a broken entry, in characters of LaTeX source (default 100);
            a line holds at least one term.

        Returns
        -------
        str
            The LaTeX text: a display equation, then one block per term.
        """
        lines = [r"\[ M(q)\,\ddot{q} + V_m(q,\dot{q})\,\dot{q} + F(\dot{q}) + G(q) = \tau \]"]
        compact, long = [], []
        for shown in self._display():
            entries = [[sympy.latex(shown.matrix[i, j], full_prec=False) for j in range(shown.matrix.shape[1])]
                       for i in range(shown.matrix.shape[0])]  # fmt: skip
            longest_row = max(sum(len(x) + 3 for x in row) for row in entries)
            if max(len(x) for row in entries for x in row) <= _COMPACT_ENTRY and longest_row <= _COMPACT_ROW:
                compact.append(f"{shown.label} &= {_latex_matrix(entries)}")
            else:
                long.append((shown, entries))
        if compact:
            lines += [r"\[ \begin{aligned}", " \\\\\n".join(compact), r"\end{aligned} \]"]
        for shown, entries in long:
            rows = []
            for i, row in enumerate(entries):
                for j, text in enumerate(row):
                    if shown.entry == "M" and j < i:
                        continue
                    label = self._entry_label(shown, i, j)
                    if len(text) <= width:
                        rows.append(f"{label} &= {text}")
                    else:
                        broken = _broken_terms(shown.matrix[i, j], width)
                        rows.append(f"{label} &= " + " \\\\\n&\\quad ".join(broken))
            if shown.entry == "M":
                rows.append(r"M_{ij} &= M_{ji} \quad (i > j)")
            lines += [rf"% {shown.plain}, entry by entry", r"\begin{align*}", " \\\\\n".join(rows), r"\end{align*}"]
        return "\n".join(lines) + "\n"

    def latex_document(self, width: int = 100) -> str:
        r"""A complete LaTeX document of the equations, ready for ``pdflatex``.

        An ``article`` with the ``amsmath`` and ``geometry`` packages and
        ``\allowdisplaybreaks`` (long entries break across pages), a title naming the arm
        and the notation, and ``latex(width)`` as its body.

        Parameters
        ----------
        width : int, optional
            Passed to ``latex``: the longest line of a broken entry (default 100).

        Returns
        -------
        str
            The .tex source.
        """
        name = _latex_text(self.robot.name)
        notation = r"$c_{12} = \cos(q_1 + q_2)$, $s_{2} = \sin(q_2)$"
        return "\n".join(
            [
                r"\documentclass[10pt]{article}",
                r"\usepackage[margin=2cm]{geometry}",
                r"\usepackage{amsmath}",
                r"\allowdisplaybreaks",
                r"\begin{document}",
                rf"\section*{{The robot equation of {name}}}",
                rf"Derived in closed form by armdyn ({_latex_text(self.method)} method); {notation}.",
                "",
                self.latex(width),
                r"\end{document}",
                "",
            ]
        )

    def pretty(self, limit: int | None = 150) -> str:
        """The equations for the terminal (SymPy's pretty printer, c_12 = cos(q1 + q2)).

        A term whose matrix drawing is at most ``limit`` characters wide is drawn as one
        matrix. Otherwise its entries are drawn one by one, and an entry longer than
        ``limit`` characters (as plain text) is summarised: its operation count and length,
        and a note that ``save`` writes it in full (the PUMA 560's full form is some
        250,000 characters).

        Parameters
        ----------
        limit : int or None, optional
            The widest matrix and the longest entry drawn (default 150 characters); None
            draws every term as one matrix, in full.

        Returns
        -------
        str
            M(q), Vm(q, qd), V(q, qd), G(q) and, when not zero, F(qd), one block each.
        """
        blocks, summarised = [], 0
        for shown in self._display():
            clean = shown.label.replace("\\dot{q}", "qd").replace(r"\,", "").replace("_m", "m")
            m = shown.matrix.applyfunc(lambda e: e.xreplace({s: sympy.Symbol(_plain(s.name)) for s in e.free_symbols}))
            sizes = [[len(str(m[i, j])) for j in range(m.shape[1])] for i in range(m.shape[0])]
            if limit is None or max(x for row in sizes for x in row) <= limit:  # else too wide: no need to draw
                drawn = sympy.pretty(m, use_unicode=True, wrap_line=False, full_prec=False)
                if limit is None or max(len(line) for line in drawn.split("\n")) <= limit:
                    blocks.append(f"{clean} =\n{drawn}")
                    continue
            lines = [f"{clean}, entry by entry:"]
            for i in range(m.shape[0]):
                for j in range(m.shape[1]):
                    if shown.entry == "M" and j < i:
                        continue
                    label = f"{shown.plain}[{i + 1}]" if m.shape[1] == 1 else f"{shown.plain}[{i + 1},{j + 1}]"
                    if sizes[i][j] <= limit:
                        drawn = sympy.pretty(m[i, j], use_unicode=True, wrap_line=False, full_prec=False).split("\n")
                        middle = len(drawn) // 2
                        pad = " " * (len(label) + 3)
                        lines += [(f"{label} = " if k == middle else pad) + text for k, text in enumerate(drawn)]
                    else:
                        summarised += 1
                        operations = codegen.count_operations(shown.raw[i][j])
                        lines.append(f"{label} = ... ({operations:,} operations, {sizes[i][j]:,} characters)")
            if shown.entry == "M":
                lines.append("M[i,j] = M[j,i] for i > j")
            blocks.append("\n".join(lines))
        if summarised:
            blocks.append(
                f"{summarised} entries longer than {limit} characters are summarised: form.save('file.tex') "
                "(or .txt, .py, .c) writes them in full, and pretty(limit=None) draws them."
            )
        return "\n\n".join(blocks)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the full equations to a file, in the form its suffix names.

        ".tex": ``latex_document()``; ".txt": ``pretty(limit=None)``; ".py": ``to_python()``;
        ".c": ``to_c()`` (the definitions); ".h": ``to_c_header()`` (their declarations). The text is UTF-8.

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (replaced if it exists).

        Returns
        -------
        pathlib.Path
            The path written.

        Raises
        ------
        armdyn.ModelError
            When the suffix is none of .tex, .txt, .py, .c and .h, the folder does not
            exist, or the path is a folder.
        """
        target = Path(path)
        writers = {
            ".tex": self.latex_document,
            ".txt": lambda: self.pretty(limit=None),
            ".py": self.to_python,
            ".c": self.to_c,
            ".h": self.to_c_header,
        }
        writer = writers.get(target.suffix.lower())
        if writer is None:
            raise ModelError(f"save: cannot tell the form from the suffix of '{target}' (use .tex, .txt, .py or .c)")
        if not target.parent.is_dir():
            raise ModelError(f"save: the folder '{target.parent}' does not exist")
        if target.is_dir():
            raise ModelError(f"save: '{target}' is a folder")
        target.write_text(writer(), encoding="utf-8")
        return target

    def __repr__(self) -> str:
        return f"ClosedForm('{self.robot.name}', n={self.robot.n}, method='{self.method}')"

    def _repr_latex_(self) -> str:
        r"""The equations for a notebook: M qdd + Vm qd + F + G = tau, then M, Vm, V, G and (when not
        zero) F, in one ``$$\begin{aligned} ... \end{aligned}$$`` display of bounded size
        (armdyn.symbolic.notebook: long entries are named, not shown; ``latex`` gives them all)."""
        terms = [
            notebook.Term(
                shown.label, "(V_m)" if shown.entry == "V_m" else shown.entry, shown.matrix, shown.entry == "M"
            )
            for shown in self._display()
        ]
        equation = r"M(q)\,\ddot{q} + V_m(q,\dot{q})\,\dot{q} + F(\dot{q}) + G(q) &= \tau"
        return notebook.display(equation, terms, "latex() gives every entry; save('file.tex') writes a document.")

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
            as further arguments, in alphabetical order (a name that is no identifier as one
            made of it, named in a comment: ``codegen.identifiers``).
        """
        return codegen.python_source(self.raw, self._parameter_names())

    def to_c(self, prefix: str = "armdyn_") -> str:
        """C99 source of the same four functions, with CSE: their definitions (``to_c_header`` declares them).

        Parameters
        ----------
        prefix : str, optional
            Put before each function's name (default "armdyn_": ``armdyn_M``), as generate_code's C names
            its functions: empty or the start of a C identifier.

        Returns
        -------
        str
            void functions prefix + M, Vm, G and tau taking ``const double *`` states and a ``double
            *out`` (matrices row major); the arm's symbolic parameters follow ``out`` as
            further ``double`` arguments, in alphabetical order (named as in ``to_python``).
            It compiles under -Wall -Wextra -Werror (an argument a function never reads is
            marked ``(void)``).

        Raises
        ------
        armdyn.ModelError
            When ``prefix`` is not empty or the start of a C identifier.
        """
        return codegen.c_source(self.raw, self._parameter_names(), codegen.c_prefix(prefix))

    def to_c_header(self, prefix: str = "armdyn_") -> str:
        """A C header declaring the functions ``to_c(prefix)`` defines, between an include guard.

        Parameters
        ----------
        prefix : str, optional
            As ``to_c``'s.

        Returns
        -------
        str
            The four declarations; a program includes it and links ``to_c``'s source.

        Raises
        ------
        armdyn.ModelError
            When ``prefix`` is not empty or the start of a C identifier.
        """
        prefix = codegen.c_prefix(prefix)
        declarations = codegen.c_declarations(self._parameter_names(), prefix)
        return codegen.c_header(declarations, codegen.header_guard(self.robot.name, prefix),
                                f"{self.robot.name}: M, Vm, G and tau in closed form, declarations")  # fmt: skip

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
            When a symbolic parameter of the arm has no value in ``values`` or one that is not a finite
            real number, when the closed form holds NaN or infinity, or when it is too deep for Python's
            compiler (a 7-joint arm's: ``generate_code`` is the route there).
        """
        names = self._parameter_names()
        if values is not None and not isinstance(values, dict):
            raise ArgumentError(f"values must be a dict of parameter values, got {type(values).__name__}")
        given = {str(k): v for k, v in (values or {}).items()}
        missing = [name for name in names if name not in given]
        if missing:
            raise ModelError(f"compile() needs numeric values for the parameters {missing}")
        numbers = {name: inputs.number(given[name], f"values[{name!r}]", " (a parameter of the closed form)")
                   for name in names}  # fmt: skip
        return codegen.compile_closed_form(self.raw, numbers)


_COMPACT_ENTRY, _COMPACT_ROW = 100, 200  # LaTeX characters: a term with entries and rows this short is one matrix


@dataclass
class _Shown:
    """One term of the equation as printed: its labels, its entries shown and raw."""

    label: str  # LaTeX of the term, "M(q)"
    entry: str  # LaTeX of an entry's name, "M" (M_{12})
    plain: str  # plain name, "M" (M[1,2])
    matrix: sympy.Matrix  # the entries in the book's notation
    raw: list[list[se.Basic]]  # the same entries as SymEngine polynomials


def _latex_matrix(entries: list[list[str]]) -> str:
    """A bracketed matrix, one row per source line."""
    rows = " \\\\\n".join(" & ".join(row) for row in entries)
    return "\\left[\\begin{matrix}\n" + rows + "\n\\end{matrix}\\right]"


def _broken_terms(expr: sympy.Expr, width: int) -> list[str]:
    """The expanded terms of ``expr`` in LaTeX, joined by + and -, as lines of about ``width`` characters."""
    lines, current = [], ""
    for k, term in enumerate(sympy.expand(expr).as_ordered_terms()):
        text = sympy.latex(term, full_prec=False)
        if k > 0:
            text = f"- {text[1:].lstrip()}" if text.startswith("-") else f"+ {text}"
        if current and len(current) + 1 + len(text) > width:
            lines.append(current)
            current = text
        else:
            current = f"{current} {text}" if current else text
    lines.append(current)
    return lines


def _latex_text(text: str) -> str:
    """Plain text for LaTeX's text mode (two_link_planar -> two\\_link\\_planar)."""
    special = {"\\": r"\textbackslash{}", "{": r"\{", "}": r"\}", "$": r"\$", "&": r"\&", "#": r"\#",
               "^": r"\^{}", "_": r"\_", "~": r"\~{}", "%": r"\%"}  # fmt: skip
    return "".join(special.get(ch, ch) for ch in text)


def _as_doubles(expr: se.Basic) -> se.Basic:
    """``expr`` with its constants that are not integers (109/400, sqrt(2)/4) as doubles."""
    if not expr.free_symbols:
        return expr if expr.is_Integer else se.RealDouble(float(expr))
    if isinstance(expr, se.Mul):
        constant = [a for a in expr.args if not a.free_symbols]
        rest = [_as_doubles(a) for a in expr.args if a.free_symbols]
        return se.Mul(*([_as_doubles(se.Mul(*constant))] if constant else []), *rest)
    if isinstance(expr, se.Piecewise):  # args (value, condition, value, condition, ...)
        args = expr.args
        return se.Piecewise(*((_as_doubles(args[k]), args[k + 1]) for k in range(0, len(args), 2)))
    if not expr.args:
        return expr
    return expr.func(*(_as_doubles(a) for a in expr.args))


def _plain(name: str) -> str:
    return name.replace("\\dot{q}_{", "qd").replace("\\ddot{q}_{", "qdd").replace("_{", "").replace("}", "")


def derive(
    arm: Robot | ActuatedArm,
    method: str = "auto",
    friction: str | bool = True,
    progress: Callable[[float, str], object] | None = None,
    output: TaskOutput | None = None,
    drives: Sequence[object] | None = None,
) -> ClosedForm | TaskClosedForm | ActuatedClosedForm:
    """The closed-form robot equation of ``robot`` (numeric, symbolic or mixed parameters).

    M(q) qdd + Vm(q, qd) qd + F(qd) + G(q) = tau (3.3.1; Examples 3.2-1 and 3.2-2), with the
    reflected motor inertias G^2 Jm on the diagonal of M. Numeric parameters are taken as
    the exact values they were written as (0.5 = 1/2, cos(pi/2) = 0, cos(pi/4) = sqrt(2)/2;
    see ``armdyn.symbolic.algebra.exact_float``), so the algebra cancels exactly and no
    round-off terms appear; a numeric arm's coefficients are shown as decimals.

    With ``drives`` (or an ActuatedArm), the arm-plus-actuator system
    M' qdd + V' qd + F' + G' = K' v instead (Section 3.6; see
    ``armdyn.symbolic.actuated``).

    The closed form expands every term into trigonometric polynomials: what reading, LaTeX and
    the book's examples need. For code of a numeric arm, ``generate_code`` (the customized
    Newton-Euler route, armdyn.symbolic.newton_euler) gives straight-line code whose cost grows
    linearly with the joints; use it for arms of more than a few joints.

    Parameters
    ----------
    arm : Robot or ActuatedArm
        The arm; its parameters may be numbers, SymPy expressions, or both. An
        ``armdyn.actuators.ActuatedArm`` gives the closed form of the arm with its drives.
    method : str, optional
        "lagrange" (the book's trace formula with pseudo-inertia matrices), "recursive"
        (composite rigid bodies) or "auto" (default, the recursive route for any arm:
        both give the same polynomials, and the recursion is the faster).
    friction : str or bool, optional
        True (default) for the arm's own friction, False for none, "symbolic" for new
        symbols v_i (viscous) and k_i (Coulomb), F_i = v_i qd_i + k_i sgn(qd_i). The
        arm's own Coulomb law is k sgn(qd) when symmetric, else a Piecewise: Tc+ for
        qd > 0, Tc- for qd < 0, 0 at rest. An arm's own Stribeck or sigmoid friction is
        not supported (a ModelError; derive with friction=False).
    progress : callable, optional
        Called as progress(fraction, stage) as the derivation proceeds: the fraction done
        (0 to 1) and the stage starting ("kinematics", "inertia matrix", "gravity",
        "Christoffel symbols", "Coriolis matrix", "tau", then "SymPy form of M" and so
        on, and "task space" with ``output``), last with (1.0, "done").
    output : TaskOutput, optional
        An output y = h(q) of ``armdyn.task_space`` (ToolPosition, LinkPoint,
        PlanarPosition or Camera, with as many rows as the arm has joints): the result is
        then the equation in its coordinates, Mbar yddot + Nbar = f (Section 3.5).
        Default None, the joint-space equation.
    drives : sequence, optional
        One DC motor drive per joint of an arm without motors of its own: a rigid
        ``armdyn.actuators.DCMotor``, an ``armdyn.symbolic.SymbolicMotor`` (parameters may
        be SymPy expressions; ``armdyn.symbolic.motor_symbols`` makes them) or a dict of
        its fields. Default None, the arm alone.

    Returns
    -------
    ClosedForm or TaskClosedForm or ActuatedClosedForm
        M, Vm, V, G, F and tau as SymPy matrices, with printing and code generation; with
        ``output``, a TaskClosedForm (armdyn.symbolic.task) of h, J, Mbar, Vmbar, Gbar,
        Fbar and Nbar; with ``drives`` or an ActuatedArm, an ActuatedClosedForm
        (armdyn.symbolic.actuated) of M', V', G', F' and K'.

    Raises
    ------
    armdyn.ModelError
        When ``method`` is not "auto", "lagrange" or "recursive", or ``output`` is not a
        supported output with m = n (ToolPose and outputs of other sizes are not); with
        drives, when ``output`` is given too, the arm has motors of its own, the number of
        drives is not the number of joints, or a drive is hydraulic (not supported),
        flexible or not a drive; with friction=True, when a link has Stribeck or sigmoid
        friction (the message names the link and the law).
    """
    from armdyn.actuators import ActuatedArm

    if drives is not None or isinstance(arm, ActuatedArm):
        from armdyn.symbolic.actuated import derive_actuated

        if output is not None:
            raise ModelError("derive: task coordinates (output=...) of an arm with drives are not supported")
        return derive_actuated(arm, drives, method, friction, progress, derive)
    chosen = "recursive" if method == "auto" else method
    if output is not None:
        from armdyn.symbolic.task import TaskClosedForm, check_output

        check_output(arm, output)
    share = 1.0 if output is None else 0.8  # of the progress, the joint-space form's share
    inner = outer = None
    if progress is not None:

        def inner(fraction: float, stage: str) -> None:
            if stage != "done":
                progress(share * _DERIVED * fraction, stage)

        def outer(fraction: float, stage: str) -> None:
            if stage != "done" or output is None:
                progress(share * fraction, stage)

    raw = derive_raw(arm, chosen, friction, inner)
    form = ClosedForm(arm, raw, friction, chosen, outer)
    if output is None:
        return form
    if progress is not None:
        progress(share, "task space")
    task = TaskClosedForm(form, output)
    if progress is not None:
        progress(1.0, "done")
    return task
