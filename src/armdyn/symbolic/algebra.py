"""Trigonometric polynomials in SymEngine: the algebra of closed-form robot equations.

A revolute joint's angle enters the equations only through c_i = cos(q_i) and
s_i = sin(q_i). Taking c_i and s_i as independent symbols makes every quantity of the
robot equation a polynomial in them (and in q of prismatic joints, the velocities and
the parameters), which SymEngine multiplies and expands fast. Replacing s_i^2 by
1 - c_i^2 after each product keeps one canonical form (at most linear in each s_i), so
the expressions stay small and two equal expressions expand to the same terms.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import symengine as se

FLOAT_NOISE = 1e-14  # placement entries this close to 0 or +-1 are rounding noise (cos(pi/2) = 6e-17)


def number(value: object) -> se.Basic:
    """A SymEngine number or expression from a float, int or SymPy expression.

    Floats within FLOAT_NOISE of 0 or +-1 are taken as exact (the residue of cos(pi/2)
    and the like in numeric placements); integral floats become integers.
    """
    if isinstance(value, (bool, int, np.integer)):
        return se.Integer(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if abs(value) < FLOAT_NOISE:
            return se.Integer(0)
        if abs(abs(value) - 1.0) < FLOAT_NOISE:
            return se.Integer(1 if value > 0 else -1)
        if value.is_integer() and abs(value) < 2**53:
            return se.Integer(int(value))
        return se.RealDouble(value)
    return se.sympify(_exact(value))


def _exact(value: object) -> object:
    """A SymPy expression with its float noise removed (1.0*a1, from object-array products, is a1)."""
    import sympy

    value = sympy.sympify(value)
    floats = value.atoms(sympy.Float)
    if not floats:
        return value
    replacements = {}
    for f in floats:
        x = float(f)
        if abs(x) < FLOAT_NOISE:
            replacements[f] = sympy.Integer(0)
        elif abs(x - round(x)) < FLOAT_NOISE * max(1.0, abs(x)):
            replacements[f] = sympy.Integer(round(x))
    return value.xreplace(replacements)


def matrix(values: object) -> se.DenseMatrix:
    array = np.asarray(values, dtype=object)
    return se.DenseMatrix(array.shape[0], array.shape[1], [number(v) for v in array.ravel()])


class TrigAlgebra:
    """Reduction and differentiation for polynomials in (c_i, s_i) pairs and plain variables."""

    def __init__(self, pairs: dict[int, tuple[se.Symbol, se.Symbol]], prismatic: dict[int, se.Symbol]) -> None:
        self.pairs = pairs  # joint index -> (c_i, s_i) for revolute joints
        self.prismatic = prismatic  # joint index -> q_i for prismatic joints
        self._cosine_of = {s: c for c, s in pairs.values()}

    def reduce(self, expr: se.Basic) -> se.Basic:
        """Expand and replace s^k by s^(k mod 2) (1 - c^2)^(k div 2)."""
        expr = se.expand(expr)
        if not self._cosine_of or not expr.free_symbols & set(self._cosine_of):
            return expr
        terms = expr.args if isinstance(expr, se.Add) else (expr,)
        rewritten, changed = [], False
        for term in terms:
            factors = term.args if isinstance(term, se.Mul) else (term,)
            extra = None
            kept = []
            for factor in factors:
                if isinstance(factor, se.Pow) and factor.args[0] in self._cosine_of:
                    sine, power = factor.args[0], int(factor.args[1])
                    if power >= 2:
                        cosine = self._cosine_of[sine]
                        piece = (1 - cosine**2) ** (power // 2) * sine ** (power % 2)
                        extra = piece if extra is None else extra * piece
                        continue
                kept.append(factor)
            if extra is None:
                rewritten.append(term)
            else:
                changed = True
                rewritten.append(se.Mul(*kept) * extra)
        return se.expand(se.Add(*rewritten)) if changed else expr

    def diff(self, expr: se.Basic, joint: int) -> se.Basic:
        """d expr / d q_joint: -s dE/dc + c dE/ds for a revolute joint, dE/dq for a prismatic one."""
        if joint in self.pairs:
            c, s = self.pairs[joint]
            symbols = expr.free_symbols
            if c not in symbols and s not in symbols:
                return se.Integer(0)
            return self.reduce(-s * se.diff(expr, c) + c * se.diff(expr, s))
        q = self.prismatic[joint]
        return se.diff(expr, q) if q in expr.free_symbols else se.Integer(0)

    def reduce_matrix(self, m: se.DenseMatrix) -> se.DenseMatrix:
        return m.applyfunc(self.reduce)


def skew(v: Iterable[se.Basic]) -> se.DenseMatrix:
    x, y, z = v
    return se.DenseMatrix([[0, -z, y], [z, 0, -x], [-y, x, 0]])


def cross(a: list[se.Basic], b: list[se.Basic]) -> list[se.Basic]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
