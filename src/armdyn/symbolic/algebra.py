"""Trigonometric polynomials in SymEngine: the algebra of closed-form robot equations.

A revolute joint's angle enters the equations only through c_i = cos(q_i) and
s_i = sin(q_i). Taking c_i and s_i as independent symbols makes every quantity of the
robot equation a polynomial in them (and in q of prismatic joints, the velocities and
the parameters), which SymEngine multiplies and expands fast. Replacing s_i^2 by
1 - c_i^2 after each product keeps one canonical form (at most linear in each s_i), so
the expressions stay small and two equal expressions expand to the same terms.

That holds only if the numbers are exact: a float 0.1 times 0.1 minus 0.01 leaves 1e-18,
and cos(pi/2) = 6e-17 in a DH twist leaves terms in joints that have no business there.
So the arm's floats are read as the exact values the user wrote (``exact_float``:
decimals, small fractions, and in rotations the cosines of multiples of pi/12), the
algebra runs in exact rationals, and only the printing and the generated code go back to
doubles. ``collapse_sums`` then writes c1 c2 - s1 s2 as c12 for printing.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from fractions import Fraction

import numpy as np
import symengine as se

FLOAT_NOISE = 1e-14  # placement entries this close to 0 or +-1 are rounding noise (cos(pi/2) = 6e-17)
DECIMAL_DIGITS = 12  # a float within SNAP_ULPS of a decimal this short is that decimal, as the user wrote it
SNAP_ULPS = 4
SMALL_DENOMINATOR = 1000  # a float within SNAP_ULPS of p/q with q up to this is p/q (1/3)
# Irrational factors of cos and sin of multiples of pi/12 (cos(pi/4) = sqrt(2)/2, cos(pi/12) = (sqrt(6) + sqrt(2))/4)
# and of their products, recognised in rotations and placements: x = (short decimal) * factor.
_TRIG_FACTORS = (se.sqrt(2), se.sqrt(3), se.sqrt(6), se.sqrt(6) + se.sqrt(2), se.sqrt(6) - se.sqrt(2))
_TRIG_DIGITS = 8  # the decimal in front of an irrational factor is at most this long


def _decimal(value: float, digits: int = DECIMAL_DIGITS) -> se.Basic | None:
    """The decimal of at most ``digits`` significant digits within SNAP_ULPS of ``value``, exact, or None."""
    text = f"{value:.{digits}g}"
    if abs(float(text) - value) > SNAP_ULPS * math.ulp(value):
        return None
    fraction = Fraction(text)
    return se.Integer(fraction.numerator) / se.Integer(fraction.denominator)


def exact_float(value: float, geometric: bool = False) -> se.Basic:
    """A float as an exact SymEngine number when it is one a user writes, else a RealDouble.

    0, +-1 and integers are exact; so is a decimal of up to DECIMAL_DIGITS significant
    digits (0.5, 0.4318, 9.81: the float within SNAP_ULPS units in the last place is taken
    for that decimal, which is what the user wrote, and rounds back to the same float), and
    so is a fraction p/q with q up to SMALL_DENOMINATOR (1/3).
    With ``geometric`` (the entries of rotations and placements) a product of a short
    decimal and sqrt(2), sqrt(3), sqrt(6) or sqrt(6) +- sqrt(2) is recognised too, so the
    cosines and sines of multiples of pi/12 (cos(pi/4) = sqrt(2)/2) are exact, and entries
    within FLOAT_NOISE of 0 or +-1 (cos(pi/2) = 6e-17) are 0 or +-1.
    """
    if abs(value) < FLOAT_NOISE:
        return se.Integer(0)
    if abs(abs(value) - 1.0) < FLOAT_NOISE:
        return se.Integer(1 if value > 0 else -1)
    if value.is_integer() and abs(value) < 2**53:
        return se.Integer(int(value))
    if not math.isfinite(value):
        return se.RealDouble(value)
    found = _decimal(value)
    if found is not None:
        return found
    fraction = Fraction(value).limit_denominator(SMALL_DENOMINATOR)
    if abs(float(fraction) - value) <= SNAP_ULPS * math.ulp(value):  # 1/3, 2/7
        return se.Integer(fraction.numerator) / se.Integer(fraction.denominator)
    if geometric:
        for factor in _TRIG_FACTORS:
            scaled = _decimal(value / float(factor), _TRIG_DIGITS)
            if scaled is not None and abs(float(scaled * factor) - value) <= SNAP_ULPS * math.ulp(value):
                return se.expand(scaled * factor)
    return se.RealDouble(value)


def number(value: object, geometric: bool = False) -> se.Basic:
    """A SymEngine number or expression from a float, int or SymPy expression.

    Floats are made exact where the user wrote an exact value (see ``exact_float``), so the
    algebra cancels exactly and no round-off terms (1e-17 c1 s1) appear; integral floats
    become integers. In SymPy expressions, floats are made exact the same way.
    """
    if isinstance(value, (bool, int, np.integer)):
        return se.Integer(int(value))
    if isinstance(value, (float, np.floating)):
        return exact_float(float(value), geometric)
    return se.sympify(_exact(value, geometric))


def _exact(value: object, geometric: bool = False) -> object:
    """A SymPy expression with its floats made exact (1.0*a1, from object-array products, is a1; 0.5*m is m/2)."""
    import sympy

    expr = sympy.sympify(value)
    floats = expr.atoms(sympy.Float)
    if not floats:
        return expr
    replacements = {}
    for f in floats:
        exact = exact_float(float(f), geometric)
        if not isinstance(exact, se.RealDouble):
            replacements[f] = sympy.sympify(exact)
    return expr.xreplace(replacements)


def matrix(values: object, geometric: bool = False) -> se.DenseMatrix:
    """A SymEngine matrix of ``number`` entries from a 2-D array."""
    array = np.asarray(values, dtype=object)
    return se.DenseMatrix(array.shape[0], array.shape[1], [number(v, geometric) for v in array.ravel()])


def transform(values: object) -> se.DenseMatrix:
    """A 4x4 homogeneous transform with exact entries where the user's values were exact.

    The rotation's entries are taken with ``geometric`` snapping (cos(pi/2) = 0,
    cos(pi/4) = sqrt(2)/2); a translation entry that is rounding noise relative to the
    largest one (d cos(pi/2) = 6e-17 d) is 0, and a product of a decimal and a cosine
    (d sin(pi/4)) is recognised as such.
    """
    array = np.asarray(values, dtype=object)
    result = matrix(array, geometric=True)
    column = array[:3, 3]
    if all(isinstance(x, (float, int, np.floating, np.integer)) for x in column):
        scale = max(1.0, *(abs(float(x)) for x in column))
        for r in range(3):
            if abs(float(column[r])) < FLOAT_NOISE * scale:
                result[r, 3] = se.Integer(0)
    return result


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


def collapse_sums(
    expr: se.Basic, pairs: dict[int, tuple[se.Symbol, se.Symbol]]
) -> tuple[se.Basic, dict[str, tuple[str, tuple[int, ...]]]]:
    """Write products of cosines and sines of joint angles as the cosine and sine of their sum.

    c_A c_B - s_A s_B = c_{A+B} and s_A c_B + c_A s_B = s_{A+B} (the book's c12 = cos(q1 + q2)),
    applied to pairs of terms whose other factors and coefficients match, until none is left.
    Fast (it works on the polynomial's terms, where SymPy's trigsimp searches), and exact.

    Parameters
    ----------
    expr : symengine.Basic
        A polynomial in the (c_i, s_i) of ``pairs`` and other symbols.
    pairs : dict of int to (Symbol, Symbol)
        Joint index to its (c_i, s_i) symbols.

    Returns
    -------
    symengine.Basic
        The expression with new symbols for the cosines and sines of sums.
    dict of str to (str, tuple of int)
        Each new symbol's name to ("c" or "s", the joint indices summed).
    """
    kind_of: dict[se.Basic, tuple[str, tuple[int, ...]]] = {}
    for i, (c, s) in pairs.items():
        kind_of[c], kind_of[s] = ("c", (i,)), ("s", (i,))
    expr = se.expand(expr)
    if not expr.free_symbols & kind_of.keys():
        return expr, {}
    poly: dict[tuple, se.Basic] = {}
    for term in expr.args if isinstance(expr, se.Add) else (expr,):
        trig, rest = [], []
        for factor in term.args if isinstance(term, se.Mul) else (term,):
            base, power = factor, 1
            if isinstance(factor, se.Pow) and factor.args[0] in kind_of and factor.args[1].is_Integer:
                base, power = factor.args[0], int(factor.args[1])
            if base in kind_of and power > 0:
                trig += [kind_of[base]] * power
            else:
                rest.append(factor)
        key = tuple(sorted(trig))
        poly[key] = poly.get(key, se.Integer(0)) + se.Mul(*rest)

    def without(mono: tuple, *atoms: tuple) -> list:
        kept = list(mono)
        for atom in atoms:
            kept.remove(atom)
        return kept

    def add(mono: list, coefficient: se.Basic) -> None:
        key = tuple(sorted(mono))
        total = se.expand(poly.get(key, se.Integer(0)) + coefficient)
        if total == 0:
            poly.pop(key, None)
        else:
            poly[key] = total

    changed = True
    while changed:
        changed = False
        for mono in sorted(poly):
            if mono not in poly:
                continue
            k = poly[mono]
            atoms = sorted(set(mono))
            for x, a in enumerate(atoms):
                for b in atoms[x + 1 :]:
                    if set(a[1]) & set(b[1]):
                        continue
                    rest = without(mono, a, b)
                    union = tuple(sorted(a[1] + b[1]))
                    if a[0] == b[0]:  # c_A c_B with -s_A s_B, or s_A s_B with -c_A c_B
                        other = "s" if a[0] == "c" else "c"
                        partner = tuple(sorted([*rest, (other, a[1]), (other, b[1])]))
                        target, sign = ("c", union), (1 if a[0] == "c" else -1)
                    else:  # s_A c_B with c_A s_B
                        partner = tuple(sorted([*rest, (b[0], a[1]), (a[0], b[1])]))
                        target, sign = ("s", union), None
                    if partner not in poly:
                        continue
                    wanted = se.expand(poly[partner] + k) if sign is not None else se.expand(poly[partner] - k)
                    if wanted != 0:
                        continue
                    del poly[mono], poly[partner]
                    add([*rest, target], k if sign is None else sign * k)
                    changed = True
                    break
                else:
                    continue
                break
    names: dict[str, tuple[str, tuple[int, ...]]] = {}
    symbols: dict[tuple[str, tuple[int, ...]], se.Basic] = {value: key for key, value in kind_of.items()}
    terms = []
    for mono, coefficient in poly.items():
        factors = []
        for atom in mono:
            if atom not in symbols:
                name = f"{atom[0]}({'+'.join(str(i + 1) for i in atom[1])})"
                symbols[atom] = se.Symbol(name)
                names[name] = atom
            factors.append(symbols[atom])
        terms.append(coefficient * se.Mul(*factors))
    return se.Add(*terms), names
