"""The arm-plus-actuator system in closed form: M', V', F', G' and K' (Section 3.6).

With a rigid DC motor drive on every joint and the armature inductance neglected, the arm
and its drives obey, in the link coordinates q with the rows in joint torques (as
``armdyn.actuators.ActuatedArm`` writes the reduced model),

    M'(q) qdd + V'(q, qd) qd + F'(qd) + G'(q) = K' v,
    M' = M + R^-2 J_M,   V' = Vm,   F' = F + R^-1 F_M(R^-1 qd) + R^-2 B qd,   G' = G,   K' = R^-1 K_M,

with R = diag r_i (q = R q_M), J_M = diag J_Mi, B = diag(B_Mi + K_bi K_Mi / R_ai),
K_M = diag(K_Mi / R_ai) and F_M the rotors' Coulomb friction at the rotor speed qd_M = R^-1 qd.
Multiplying row i by r_i^2 gives the book's printed form
(J_M + R^2 M) qdd + (B + R^2 Vm) qd + R F_M + R^2 F + R^2 G = R K_M v, and row i of it, with the
other joints' terms gathered in d_i, the book's independent-joint form
(J_Mi + r_i^2 m_ii) qdd_i + B_i qd_i + r_i F_Mi = (r_i K_Mi / R_ai) v_i - r_i^2 d_i.

``derive(robot, drives=[...])`` (or ``derive(actuated_arm)``) builds an ``ActuatedClosedForm``.
A drive is an ``armdyn.actuators.DCMotor`` (numbers), a ``SymbolicMotor`` whose parameters may
be SymPy expressions, or a dict of SymbolicMotor's fields; ``motor_symbols(n)`` makes n motors
of positive symbols J_M1, B_M1, K_M1, K_b1, R_a1, r1, ... for the README's example.
"""

from __future__ import annotations

import reprlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import sympy

from armdyn import inputs
from armdyn.errors import ArgumentError, ModelError
from armdyn.robot import Robot
from armdyn.symbolic import notebook

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from armdyn.actuators import ActuatedArm
    from armdyn.symbolic.closed_form import ClosedForm

__all__ = ["ActuatedClosedForm", "CompiledActuatedForm", "SymbolicMotor", "derive_actuated", "motor_symbols"]

_MATRICES = ("M", "Vm", "V", "G", "F", "K")


# ----- the drives ---------------------------------------------------------------------------------
def _parameter(value: object, what: str, where: str, rule: str) -> sympy.Expr:
    """A finite real number or a SymPy expression, as SymPy, checked against its sign rule where it can be told.

    ``rule`` is ">0", ">=0", "<=0" or "!=0". An integral number becomes a SymPy Integer, another
    number a Float; an expression is refused only when SymPy knows it breaks the rule.
    """
    if isinstance(value, sympy.Basic):
        expr = value
        if expr.is_real is False or expr.has(sympy.zoo, sympy.oo, -sympy.oo, sympy.nan):
            raise ModelError(f"{where}: {what} must be real, got {expr}")
        broken = {
            ">0": expr.is_positive is False,
            ">=0": expr.is_nonnegative is False,
            "<=0": expr.is_nonpositive is False,
            "!=0": expr.is_zero is True,
        }[rule]
        shown = str(expr)
    else:
        number = inputs.number(value, what, f" ({where})")
        expr = sympy.Integer(int(number)) if float(number).is_integer() else sympy.Float(number)
        broken = {">0": number <= 0, ">=0": number < 0, "<=0": number > 0, "!=0": number == 0}[rule]
        shown = f"{number:g}"
    if broken:
        words = {">0": "positive", ">=0": ">= 0", "<=0": "<= 0", "!=0": "non-zero"}[rule]
        raise ModelError(f"{where}: {what} must be {words}, got {shown}")
    return expr


@dataclass(frozen=True)
class SymbolicMotor:
    """A rigid DC motor drive whose parameters may be SymPy expressions (Section 3.6).

    The counterpart of ``armdyn.actuators.DCMotor`` for closed forms: the parameters of the
    reduced model only (no inductance, limits or flexible shaft), each a finite real number or
    a SymPy expression. Numbers keep DCMotor's sign rules; an expression is refused only when
    SymPy can tell that it breaks them (a symbol made with ``positive=True`` never does). The
    gear follows the book, q = r q_M. The fields are stored as SymPy expressions (integral
    numbers as Integers, others as Floats).

    Parameters
    ----------
    rotor_inertia : float or sympy.Expr
        J_M, the rotor's inertia, >= 0.
    viscous : float or sympy.Expr
        B_M, the rotor's viscous friction, >= 0.
    torque_constant : float or sympy.Expr
        K_M, > 0.
    back_emf : float or sympy.Expr
        K_b, > 0.
    resistance : float or sympy.Expr
        R_a, the armature resistance, > 0.
    gear_ratio : float or sympy.Expr
        r with q = r q_M, non-zero.
    coulomb : float or sympy.Expr or (float or sympy.Expr, float or sympy.Expr), optional
        F_M, the rotor's Coulomb friction: a magnitude c >= 0 (F_M = c sgn(qd_M)) or a pair
        (Tc+, Tc-) with Tc+ >= 0 >= Tc- for positive and negative rotor velocity (default 0).
        Stored as the pair.
    name : str, optional
        The drive's name, used in messages (default "motor").

    Raises
    ------
    armdyn.ModelError
        When a parameter is neither a finite real number nor a SymPy expression, breaks its sign
        rule, or ``coulomb`` is neither one value nor a pair; the message names the drive.
    """

    rotor_inertia: Any
    viscous: Any
    torque_constant: Any
    back_emf: Any
    resistance: Any
    gear_ratio: Any
    coulomb: Any = 0
    name: str = "motor"

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ModelError(f"a drive's name must be a non-empty str, got {reprlib.repr(self.name)}")
        where = f"drive '{self.name}'"
        checked = {
            "rotor_inertia": _parameter(self.rotor_inertia, "rotor inertia J_M", where, ">=0"),
            "viscous": _parameter(self.viscous, "viscous friction B_M", where, ">=0"),
            "torque_constant": _parameter(self.torque_constant, "torque constant K_M", where, ">0"),
            "back_emf": _parameter(self.back_emf, "back-emf constant K_b", where, ">0"),
            "resistance": _parameter(self.resistance, "armature resistance R_a", where, ">0"),
            "gear_ratio": _parameter(self.gear_ratio, "gear ratio r", where, "!=0"),
        }
        coulomb = self.coulomb
        if isinstance(coulomb, (tuple, list, np.ndarray)):
            if len(coulomb) != 2:
                raise ModelError(
                    f"{where}: Coulomb friction must be a magnitude c >= 0 or a pair (Tc+, Tc-), "
                    f"got {reprlib.repr(coulomb)}"
                )
            pair = (
                _parameter(coulomb[0], "Coulomb friction Tc+", where, ">=0"),
                _parameter(coulomb[1], "Coulomb friction Tc-", where, "<=0"),
            )
        else:
            magnitude = _parameter(coulomb, "Coulomb friction c", where, ">=0")
            pair = (magnitude, -magnitude)
        checked["coulomb"] = pair
        for key, value in checked.items():
            object.__setattr__(self, key, value)

    @property
    def damping(self) -> sympy.Expr:
        """B = B_M + K_b K_M / R_a: the rotor's viscous friction and the back-emf damping."""
        return self.viscous + self.back_emf * self.torque_constant / self.resistance

    @property
    def gain(self) -> sympy.Expr:
        """K_M / R_a: the motor torque per volt with the inductance neglected."""
        return self.torque_constant / self.resistance


def motor_symbols(n: int, coulomb: bool = False) -> list[SymbolicMotor]:
    """n DC motors with symbolic parameters J_Mi, B_Mi, K_Mi, K_bi, R_ai, r_i (Section 3.6).

    Every symbol is made with ``positive=True`` (so a gear ratio r_i > 0: a gear that reverses
    the motor needs a SymbolicMotor of one's own).

    Parameters
    ----------
    n : int
        The number of motors, one per joint, >= 1.
    coulomb : bool, optional
        True gives each rotor the symmetric Coulomb friction F_Mi sgn(qd_Mi) with a positive
        symbol F_Mi (default False: none).

    Returns
    -------
    list of SymbolicMotor
        Motor i (from 1) has J_Mi, B_Mi, K_Mi, K_bi, R_ai, ri (and F_Mi), and is named "motor i".

    Raises
    ------
    armdyn.ModelError
        When ``n`` is not a whole number >= 1.
    """
    n = inputs.integer(n, "the number of motors n", 1)
    motors = []
    for i in range(1, n + 1):
        J_M, B_M, K_M, K_b, R_a, r = sympy.symbols(f"J_M{i} B_M{i} K_M{i} K_b{i} R_a{i} r{i}", positive=True)
        friction = sympy.Symbol(f"F_M{i}", positive=True) if coulomb else 0
        motors.append(SymbolicMotor(J_M, B_M, K_M, K_b, R_a, r, friction, name=f"motor {i}"))
    return motors


def _motor(drive: object, joint: str) -> SymbolicMotor:
    """One drive as a SymbolicMotor: a rigid DCMotor's numbers, a SymbolicMotor, or a dict of its fields."""
    from armdyn.actuators import DCMotor, Hydraulic

    if isinstance(drive, SymbolicMotor):
        return drive
    if isinstance(drive, Hydraulic):
        raise ModelError(
            f"the drive of joint '{joint}' is hydraulic ('{drive.name}'): closed forms of hydraulic drives are not "
            "supported; use armdyn.actuators.with_actuators for its numeric model"
        )
    if isinstance(drive, DCMotor):
        if drive.flexible:
            raise ModelError(
                f"drive '{drive.name}' of joint '{joint}' has a flexible shaft: its motor angle is a state, so there "
                "is no reduced model M', V', F', G', K' to write in closed form"
            )
        return SymbolicMotor(
            drive.rotor_inertia,
            drive.viscous,
            drive.torque_constant,
            drive.back_emf,
            drive.resistance,
            drive.gear_ratio,
            drive.coulomb,
            name=drive.name,
        )
    if isinstance(drive, Mapping):
        known = {field.name for field in fields(SymbolicMotor)}
        unknown = sorted(str(key) for key in drive if key not in known)
        if unknown:
            raise ModelError(
                f"the drive of joint '{joint}' has unknown parameters {unknown}; a motor's parameters are "
                f"{sorted(known)}"
            )
        try:
            return SymbolicMotor(**drive)
        except TypeError:
            missing = sorted(key for key in known - {"coulomb", "name"} if key not in drive)
            raise ModelError(f"the drive of joint '{joint}' lacks the parameters {missing}") from None
    raise ArgumentError(
        f"the drive of joint '{joint}' must be a DCMotor, a SymbolicMotor or a dict of a SymbolicMotor's "
        f"parameters, got {reprlib.repr(drive)}"
    )


def checked_motors(arm: Robot, drives: object) -> list[SymbolicMotor]:
    """The drives as SymbolicMotors, one per joint of an arm without motors (Section 3.6).

    Parameters
    ----------
    arm : Robot
        The arm.
    drives : sequence
        One drive per joint: DCMotor (rigid), SymbolicMotor, or a dict of SymbolicMotor's fields.

    Returns
    -------
    list of SymbolicMotor
        The drives, in joint order.

    Raises
    ------
    armdyn.ModelError
        When the arm has motors of its own (Jm or G set), ``drives`` is not a sequence of as many
        drives as joints, or a drive is hydraulic, flexible, or not a drive at all.
    """
    where = f"robot '{arm.name}'"
    motors = [link.name for link in arm.links if link.motor_inertia != 0 or link.gear_ratio != 1]
    if motors:
        raise ModelError(
            f"{where} already has motors (Jm or G) on joints {motors}: with drives they would be counted twice. "
            "Move them into DC motor drives with armdyn.actuators.motor_drives(robot, ...), or drop them with "
            "robot.without_motors()"
        )
    if isinstance(drives, (str, bytes, Mapping)) or not isinstance(drives, Sequence):
        raise ArgumentError(f"drives must be a sequence of drives, one per joint, got {reprlib.repr(drives)}")
    if len(drives) != arm.n:
        raise ModelError(f"{where} has {arm.n} joints {arm.joint_names}; {len(drives)} drives were given")
    return [_motor(drive, link.name) for link, drive in zip(arm.links, drives, strict=True)]


def _rotor_friction(qd: sympy.Symbol, motor: SymbolicMotor) -> sympy.Expr:
    """r^-1 F_M(qd / r): the rotor's Coulomb friction as a joint torque (Tc+ for qd_M > 0, Tc- for qd_M < 0)."""
    positive, negative = motor.coulomb
    r = motor.gear_ratio
    if positive == 0 and negative == 0:
        return sympy.Integer(0)
    if r.is_positive or r.is_negative:  # in the joint's sense: the pair swaps, with its signs, when r < 0
        if r.is_negative:
            positive, negative = -negative, -positive
        rate, positive, negative, scale = qd, positive / abs(r), negative / abs(r), 1
    else:
        rate, scale = qd / r, 1 / r
    if positive == -negative:
        return scale * positive * sympy.sign(rate)
    law = sympy.Piecewise((positive, rate > 0), (negative, rate < 0), (0, True))
    return scale * law


# ----- the closed form -----------------------------------------------------------------------------
class ActuatedClosedForm:
    """M', V', F', G' and K' of an arm with a rigid DC motor on every joint, as SymPy matrices (Section 3.6).

    Made by ``derive(robot, drives=[...])`` or ``derive(actuated_arm)``:
    M' qdd + V' qd + F' + G' = K' v in the link coordinates, rows in joint torques, with
    M' = M + R^-2 J_M, V' = Vm, F' = F + R^-1 F_M + R^-2 B qd, G' = G and K' = R^-1 K_M (see the
    module docstring). M', V' and G' are the arm's closed-form matrices with the drives' terms
    added, so the arm's entries appear symbol for symbol. ``book_form`` gives the book's
    row-scaled form, ``independent_joint`` the independent-joint equations, ``pretty`` and
    ``latex`` print the terms, and ``compile`` evaluates them with NumPy.

    Parameters
    ----------
    form : ClosedForm
        The arm's own closed form (M, Vm, G and its joint friction F).
    motors : sequence of SymbolicMotor
        One drive per joint, in joint order.

    Attributes
    ----------
    M, Vm, V, G, F, K : sympy.Matrix
        M'(q), V'(q, qd) = Vm, V' qd, G'(q) (n, 1), F'(qd) (n, 1) and the input matrix K'.
    J_M, R, B, K_M : sympy.Matrix
        The drives' diagonal matrices: diag J_Mi, diag r_i, diag(B_Mi + K_bi K_Mi / R_ai),
        diag(K_Mi / R_ai).
    F_M : sympy.Matrix
        The rotors' Coulomb friction F_Mi at the rotor speed qd_i / r_i, (n, 1).
    q, qd, qdd : sympy.Matrix
        The joint symbols, (n, 1).
    v : sympy.Matrix
        The input voltages, symbols v_1, ..., v_n, (n, 1).
    arm : ClosedForm
        The arm's own closed form.
    motors : tuple of SymbolicMotor
        The drives.

    Raises
    ------
    armdyn.ModelError
        When there are not as many motors as the arm has joints.
    """

    def __init__(self, form: ClosedForm, motors: Sequence[SymbolicMotor]) -> None:
        robot = form.robot
        n = robot.n
        if len(motors) != n:
            raise ModelError(f"robot '{robot.name}' has {n} joints; {len(motors)} motors were given")
        self.arm, self.robot, self.motors = form, robot, tuple(motors)
        self.q, self.qd, self.qdd = form.q, form.qd, form.qdd
        self.v = sympy.Matrix([sympy.Symbol(f"v_{i + 1}") for i in range(n)])
        r = [motor.gear_ratio for motor in self.motors]
        self.R = sympy.diag(*r)
        self.J_M = sympy.diag(*(motor.rotor_inertia for motor in self.motors))
        self.B = sympy.diag(*(motor.damping for motor in self.motors))
        self.K_M = sympy.diag(*(motor.gain for motor in self.motors))
        friction = [_rotor_friction(self.qd[i], motor) for i, motor in enumerate(self.motors)]
        self.F_M = sympy.Matrix([r[i] * friction[i] for i in range(n)])
        self.M = form.M + sympy.diag(*(motor.rotor_inertia / motor.gear_ratio**2 for motor in self.motors))
        self.Vm, self.V, self.G = form.Vm, form.V, form.G
        self.F = form.F + sympy.Matrix(
            [self.motors[i].damping * self.qd[i] / r[i] ** 2 + friction[i] for i in range(n)]
        )
        self.K = sympy.diag(*(motor.gain / motor.gear_ratio for motor in self.motors))

    # ----- the book's forms ---------------------------------------------------------------------
    def book_form(self) -> dict[str, sympy.Matrix]:
        """The book's printed form, each row i multiplied by r_i^2 (Section 3.6).

        (J_M + R^2 M) qdd + (B + R^2 Vm) qd + R F_M + R^2 F + R^2 G = R K_M v: the same equation
        as M' qdd + V' qd + F' + G' = K' v (R^2 M' = J_M + R^2 M, and so on), symmetric in its
        inertia only when all the r_i are equal.

        Returns
        -------
        dict of str to sympy.Matrix
            "M": J_M + R^2 M, "V": B + R^2 Vm (the matrix multiplying qd), "F": R F_M + R^2 F,
            "G": R^2 G, "K": R K_M; F, G (n, 1), the others (n, n).
        """
        R2 = self.R**2
        return {
            "M": self.J_M + R2 * self.arm.M,
            "V": self.B + R2 * self.Vm,
            "F": self.R * self.F_M + R2 * self.arm.F,
            "G": R2 * self.G,
            "K": self.R * self.K_M,
        }

    @property
    def d(self) -> sympy.Matrix:
        """The coupling d_i = sum_{j != i} m_ij qdd_j + (Vm qd)_i + F_i + G_i of the independent-joint form."""
        n, M = self.robot.n, self.arm.M
        return sympy.Matrix(
            [
                sum((M[i, j] * self.qdd[j] for j in range(n) if j != i), sympy.Integer(0))
                + self.V[i]
                + self.arm.F[i]
                + self.G[i]
                for i in range(n)
            ]
        )

    def independent_joint(self) -> list[sympy.Eq]:
        """The book's independent-joint equations, one per joint (Section 3.6).

        (J_Mi + r_i^2 m_ii) qdd_i + B_i qd_i + r_i F_Mi = (r_i K_Mi / R_ai) v_i - r_i^2 d_i, with
        d_i a symbol d_i standing for the coupling from the other joints (``d`` gives it); row i
        of ``book_form``, exactly (m_ii is the arm's m_ii(q), not an average).

        Returns
        -------
        list of sympy.Eq
            The n equations, in the symbols qdd_i, qd_i, v_i and d_i.
        """
        M, out = self.arm.M, []
        for i, motor in enumerate(self.motors):
            r = motor.gear_ratio
            left = (motor.rotor_inertia + r**2 * M[i, i]) * self.qdd[i] + motor.damping * self.qd[i] + self.F_M[i] * r
            right = r * motor.gain * self.v[i] - r**2 * sympy.Symbol(f"d_{i + 1}")
            out.append(sympy.Eq(left, right, evaluate=False))
        return out

    # ----- printing -------------------------------------------------------------------------------
    def _terms(self, independent: bool) -> list[tuple[str, str, Any]]:
        """(plain label, LaTeX label, matrix or equations) of each term, in the order printed."""
        items: list[tuple[str, str, Any]] = [
            ("M'(q)", "M'(q)", self.M),
            ("V'(q, qd) = Vm", r"V'(q, \dot{q}) = V_m(q, \dot{q})", self.Vm),
            ("G'(q)", "G'(q)", self.G),
            ("F'(qd)", r"F'(\dot{q})", self.F),
            ("K'", "K'", self.K),
        ]
        if independent:
            items.append(("independent joints", "", self.independent_joint()))
        return items

    def _notation(self, expr: sympy.Basic, latex: bool) -> sympy.Basic:
        """c12 for cos(q1 + q2), and in LaTeX the dotted joint rates."""
        expr = self.arm._short(expr)
        if not latex:
            return expr.xreplace(
                {s: sympy.Symbol(s.name.replace("_{", "").replace("}", "")) for s in expr.free_symbols}
            )
        n = self.robot.n
        names = {self.q[i]: f"q_{{{i + 1}}}" for i in range(n)}
        names |= {self.qd[i]: rf"\dot{{q}}_{{{i + 1}}}" for i in range(n)}
        names |= {self.qdd[i]: rf"\ddot{{q}}_{{{i + 1}}}" for i in range(n)}
        return expr.xreplace({symbol: sympy.Symbol(name) for symbol, name in names.items()})

    def pretty(self, limit: int | None = 150, independent: bool = False) -> str:
        """The terms for the terminal (SymPy's pretty printer, c12 = cos(q1 + q2)) (Section 3.6).

        Parameters
        ----------
        limit : int or None, optional
            The widest drawing shown (default 150 characters); a wider term is named with its
            width. None draws every term.
        independent : bool, optional
            Also draw the independent-joint equations (default False).

        Returns
        -------
        str
            M', V' = Vm, G', F', K' (and the independent-joint equations), one block each.
        """
        blocks = []
        for plain, _, term in self._terms(independent):
            if isinstance(term, list):
                drawn = "\n".join(
                    sympy.pretty(self._notation(eq, False), use_unicode=True, wrap_line=False, full_prec=False)
                    for eq in term
                )
            else:
                shown = term.applyfunc(lambda e: self._notation(e, False))
                drawn = sympy.pretty(shown, use_unicode=True, wrap_line=False, full_prec=False)
            width = max(len(line) for line in drawn.split("\n"))
            if limit is not None and width > limit:
                drawn = f"({width:,} characters wide: pretty(limit=None) draws it)"
            blocks.append(f"{plain} =\n{drawn}" if not isinstance(term, list) else f"{plain}:\n{drawn}")
        return "\n\n".join(blocks)

    def latex(self, independent: bool = False) -> str:
        r"""The terms as LaTeX, c_{12} = cos(q1 + q2), one ``align*`` block (Section 3.6).

        Parameters
        ----------
        independent : bool, optional
            Also write the independent-joint equations (default False).

        Returns
        -------
        str
            The equation M' qdd + V' qd + F' + G' = K' v, then M', V', G', F', K' (and the
            independent-joint equations); compiles with ``\usepackage{amsmath}``.
        """
        rows = []
        for _, label, term in self._terms(independent):
            if isinstance(term, list):
                equations = [
                    sympy.latex(self._notation(eq, True), full_prec=False).replace("=", "&=", 1) for eq in term
                ]
                rows += [rf"\intertext{{The independent joints:}} {equations[0]}", *equations[1:]]
            else:
                shown = term.applyfunc(lambda e: self._notation(e, True))
                rows.append(rf"{label} &= {sympy.latex(shown, full_prec=False)}")
        head = r"\[ M'(q)\,\ddot{q} + V'(q, \dot{q})\,\dot{q} + F'(\dot{q}) + G'(q) = K' v \]"
        return "\n".join([head, r"\begin{align*}", " \\\\\n".join(rows), r"\end{align*}"]) + "\n"

    def __repr__(self) -> str:
        return f"ActuatedClosedForm('{self.robot.name}', n={self.robot.n})"

    def _repr_latex_(self) -> str:
        r"""The terms for a notebook: M' qdd + V' qd + F' + G' = K' v, then M', V' = Vm, G', F' and K',
        in one ``$$\begin{aligned} ... \end{aligned}$$`` display of bounded size
        (armdyn.symbolic.notebook: long entries are named, not shown; ``latex`` gives them all)."""
        terms = []
        for plain, label, term in self._terms(False):
            entry = plain.split("(")[0].split(" ")[0]  # M', V', G', F', K'
            shown = term.applyfunc(lambda e: self._notation(e, True))
            terms.append(notebook.Term(label, entry, shown, entry == "M'"))
        equation = r"M'(q)\,\ddot{q} + V'(q, \dot{q})\,\dot{q} + F'(\dot{q}) + G'(q) &= K' v"
        return notebook.display(equation, terms, "latex() gives every entry.")

    # ----- evaluation -----------------------------------------------------------------------------
    def compile(self, values: dict[Any, float] | None = None) -> CompiledActuatedForm:
        """NumPy functions of M', V', G', F' and K' (SymPy's lambdify), for one state or a batch.

        Parameters
        ----------
        values : dict, optional
            Numeric values of the symbolic parameters (the arm's and the motors'), keyed by
            symbol or by name; needed for each one present.

        Returns
        -------
        CompiledActuatedForm
            Methods M(q), Vm(q, qd), V(q, qd), G(q), F(qd), K() and inverse_dynamics(q, qd, qdd).

        Raises
        ------
        armdyn.ModelError
            When a symbolic parameter has no value in ``values``.
        """
        state = set(self.q) | set(self.qd)
        present = {s for name in _MATRICES for s in getattr(self, name).free_symbols} - state
        given = {str(k): float(v) for k, v in (values or {}).items()}
        missing = sorted(s.name for s in present if s.name not in given)
        if missing:
            raise ModelError(f"compile() needs numeric values for the parameters {missing}")
        return CompiledActuatedForm(self, {s: given[s.name] for s in present})


class CompiledActuatedForm:
    """NumPy functions of an ActuatedClosedForm's terms; made by ``ActuatedClosedForm.compile``.

    Each method takes joint positions q and velocities qd, (n,) or a batch (..., n) whose
    shapes broadcast, evaluates state by state, and raises armdyn.ModelError for an invalid
    state.

    Parameters
    ----------
    form : ActuatedClosedForm
        The closed form.
    values : dict of sympy.Symbol to float
        The value of each symbolic parameter present.
    """

    def __init__(self, form: ActuatedClosedForm, values: dict[sympy.Symbol, float]) -> None:
        self.n = form.robot.n
        q, qd = list(form.q), list(form.qd)
        self._functions: dict[str, tuple[Callable[..., Any], tuple[int, ...]]] = {}
        for name in _MATRICES:
            term = getattr(form, name).xreplace(values)
            self._functions[name] = (sympy.lambdify([q, qd], term, modules="numpy", cse=True), term.shape)

    def _evaluate(self, name: str, names: tuple[str, ...], *states: ArrayLike) -> np.ndarray:
        function, shape = self._functions[name]
        batch, flat = inputs.batch_states(names, states, self.n)
        zeros = np.zeros_like(flat[0])
        q = flat[names.index("q")] if "q" in names else zeros
        qd = flat[names.index("qd")] if "qd" in names else zeros
        out = np.empty((q.shape[0], *shape))
        for b in range(out.shape[0]):
            out[b] = np.asarray(function(q[b], qd[b]), dtype=float)
        out = out[..., 0] if shape[1] == 1 else out
        return out.reshape(*batch, *out.shape[1:])

    def M(self, q: ArrayLike) -> np.ndarray:
        """M'(q) = M + R^-2 J_M, (..., n, n).

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n, n).
        """
        return self._evaluate("M", ("q",), q)

    def Vm(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """V'(q, qd) = Vm, (..., n, n).

        Parameters
        ----------
        q, qd : array_like
            Joint positions and velocities, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n, n).
        """
        return self._evaluate("Vm", ("q", "qd"), q, qd)

    def V(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """V' qd = Vm qd, (..., n).

        Parameters
        ----------
        q, qd : array_like
            Joint positions and velocities, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n).
        """
        return self._evaluate("V", ("q", "qd"), q, qd)

    def G(self, q: ArrayLike) -> np.ndarray:
        """G'(q) = G, (..., n).

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n).
        """
        return self._evaluate("G", ("q",), q)

    def F(self, qd: ArrayLike) -> np.ndarray:
        """F'(qd) = F + R^-1 F_M + R^-2 B qd, (..., n).

        Parameters
        ----------
        qd : array_like
            Joint velocities, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n).
        """
        return self._evaluate("F", ("qd",), qd)

    def K(self) -> np.ndarray:
        """K' = R^-1 K_M, the input matrix, (n, n).

        Returns
        -------
        numpy.ndarray
            (n, n), diagonal.
        """
        function, _ = self._functions["K"]
        zeros = np.zeros(self.n)
        return np.asarray(function(zeros, zeros), dtype=float)

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> np.ndarray:
        """v = K'^-1 (M' qdd + V' qd + F' + G'): the voltages that give qdd, (..., n).

        Parameters
        ----------
        q, qd, qdd : array_like
            Joint positions, velocities and accelerations, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n).

        Raises
        ------
        armdyn.ModelError
            When a state is not finite numbers of shape (..., n), or the batch shapes do not broadcast.
        """
        batch, (q, qd, qdd) = inputs.batch_states(("q", "qd", "qdd"), (q, qd, qdd), self.n)
        torque = np.einsum("bij,bj->bi", self.M(q), qdd) + self.V(q, qd) + self.F(qd) + self.G(q)
        return (torque / np.diag(self.K())).reshape(*batch, self.n)


def derive_actuated(
    arm: Robot | ActuatedArm,
    drives: Sequence[object] | None = None,
    method: str = "auto",
    friction: str | bool = True,
    progress: Callable[[float, str], object] | None = None,
    joint_space: Callable[..., object] | None = None,
) -> ActuatedClosedForm:
    """The arm-plus-actuator system in closed form: ``derive``'s route for drives (Section 3.6).

    Parameters
    ----------
    arm : Robot or ActuatedArm
        The arm without motors of its own (Jm = 0, G = 1: its friction is the joint friction
        F), or an ``armdyn.actuators.ActuatedArm``, which carries its drives.
    drives : sequence, optional
        One drive per joint of ``robot``: a rigid ``armdyn.actuators.DCMotor``, a
        ``SymbolicMotor`` (``motor_symbols`` makes them) or a dict of SymbolicMotor's fields.
        None (default) for an ActuatedArm.
    method : str, optional
        The derivation of the arm's terms, as ``derive`` takes it (default "auto").
    friction : str or bool, optional
        The arm's joint friction F, as ``derive`` takes it (default True); the drives' friction
        is added to it.
    progress : callable, optional
        As ``derive``'s, for the arm's derivation.

    joint_space : callable, optional
        The joint-space derivation, derive(robot, method, friction, progress) -> ClosedForm;
        ``armdyn.symbolic.derive`` passes itself; None raises (call ``derive`` instead).
    Returns
    -------
    ActuatedClosedForm
        M', V', G', F' and K'.

    Raises
    ------
    armdyn.ModelError
        When an ActuatedArm is given drives too, a Robot is given none, the arm has motors of its
        own, the number of drives is not the number of joints, a drive is hydraulic (closed forms
        of hydraulic drives are not supported), flexible, or not a drive, or ``derive`` refuses
        ``method``.
    armdyn.ArgumentError
        When ``robot`` is neither a Robot nor an ActuatedArm (a ModelError and a TypeError).
    """
    from armdyn.actuators import ActuatedArm

    if joint_space is None:
        raise ModelError(
            "derive_actuated needs the joint-space derivation: call armdyn.symbolic.derive(robot, drives=...)"
        )
    if isinstance(arm, ActuatedArm):
        if drives is not None:
            raise ModelError("derive: an ActuatedArm carries its drives; drives=... is for a Robot")
        drives = arm.drives
        arm = arm.robot
    elif not isinstance(arm, Robot):
        raise ArgumentError(f"robot must be an armdyn Robot or ActuatedArm, got {type(arm).__name__}")
    elif drives is None:
        raise ModelError(f"derive: robot '{arm.name}' needs drives=[...], one per joint")
    motors = checked_motors(arm, drives)
    form = cast("ClosedForm", joint_space(arm, method, friction, progress))  # a Robot's, in joint space
    return ActuatedClosedForm(form, motors)
