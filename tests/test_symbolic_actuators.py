"""Closed forms of the arm-plus-actuator system (Section 3.6): the RR arm with two symbolic
motors symbol for symbol, the book's row-scaled and independent-joint forms, numeric drives against
ActuatedArm, and the drives that are refused."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import sympy
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn.actuators import ActuatedArm, DCMotor, Hydraulic, motor_drives, with_actuators
from armdyn.symbolic import ActuatedClosedForm, ClosedForm, SymbolicMotor, derive, motor_symbols
from tests.strategies import random_robot

J_M1, J_M2, B_M1, B_M2, K_M1, K_M2, K_b1, K_b2, R_a1, R_a2, r1, r2, F_M1, F_M2 = sympy.symbols(
    "J_M1 J_M2 B_M1 B_M2 K_M1 K_M2 K_b1 K_b2 R_a1 R_a2 r1 r2 F_M1 F_M2", positive=True
)
qd1, qd2 = sympy.symbols("qd1 qd2")


def zero(matrix: sympy.Matrix) -> bool:
    """Every entry is zero, as SymPy proves it."""
    return all(sympy.simplify(sympy.expand(x)) == 0 for x in matrix)


@pytest.fixture(scope="module")
def arm() -> ClosedForm:
    return derive(ad.models.two_link_planar(symbolic=True))


@pytest.fixture(scope="module")
def rr() -> ActuatedClosedForm:
    return derive(ad.models.two_link_planar(symbolic=True), drives=motor_symbols(2))


# ----- the RR arm with two symbolic motors ---------------------------------------------------------
def test_motor_symbols_are_the_books_positive_symbols() -> None:
    first, second = motor_symbols(2)
    assert (first.rotor_inertia, first.viscous, first.torque_constant) == (J_M1, B_M1, K_M1)
    assert (first.back_emf, first.resistance, first.gear_ratio) == (K_b1, R_a1, r1)
    assert (second.rotor_inertia, second.gear_ratio, second.coulomb) == (J_M2, r2, (0, 0))
    assert motor_symbols(1, coulomb=True)[0].coulomb == (F_M1, -F_M1)
    assert first.damping == B_M1 + K_b1 * K_M1 / R_a1 and first.gain == K_M1 / R_a1


def test_inertia_is_the_arms_plus_the_reflected_rotors(rr: ActuatedClosedForm, arm: ClosedForm) -> None:
    assert arm.M + sympy.diag(J_M1 / r1**2, J_M2 / r2**2) == rr.M  # the arm's entries, symbol for symbol
    assert sympy.expand(rr.M[0, 0] - arm.M[0, 0]) == J_M1 / r1**2
    assert rr.M[0, 1] == arm.M[0, 1] and rr.M == rr.M.T


def test_coriolis_gravity_and_input_matrix(rr: ActuatedClosedForm, arm: ClosedForm) -> None:
    assert rr.Vm == arm.Vm and rr.V == arm.V and rr.G == arm.G
    assert sympy.diag(K_M1 / (r1 * R_a1), K_M2 / (r2 * R_a2)) == rr.K
    assert sympy.diag(J_M1, J_M2) == rr.J_M and sympy.diag(r1, r2) == rr.R
    assert sympy.diag(K_M1 / R_a1, K_M2 / R_a2) == rr.K_M


def test_friction_holds_the_damping_over_r_squared(rr: ActuatedClosedForm, arm: ClosedForm) -> None:
    assert sympy.zeros(2, 1) == arm.F
    B1, B2 = B_M1 + K_b1 * K_M1 / R_a1, B_M2 + K_b2 * K_M2 / R_a2
    assert sympy.diag(B1, B2) == rr.B
    assert zero(rr.F - sympy.Matrix([B1 * qd1 / r1**2, B2 * qd2 / r2**2]))
    with_coulomb = derive(ad.models.two_link_planar(symbolic=True), drives=motor_symbols(2, coulomb=True))
    expected = sympy.Matrix(
        [B1 * qd1 / r1**2 + F_M1 * sympy.sign(qd1) / r1, B2 * qd2 / r2**2 + F_M2 * sympy.sign(qd2) / r2]
    )
    assert zero(with_coulomb.F - expected)
    assert zero(with_coulomb.F_M - sympy.Matrix([F_M1 * sympy.sign(qd1), F_M2 * sympy.sign(qd2)]))


def test_the_books_row_scaled_form(rr: ActuatedClosedForm, arm: ClosedForm) -> None:
    """R^2 M' = J_M + R^2 M, and each row of M' qdd + V' qd + F' + G' = K' v times r_i^2 is the book's."""
    R, J_M = sympy.diag(r1, r2), sympy.diag(J_M1, J_M2)
    assert zero(R**2 * rr.M - (J_M + R**2 * arm.M))
    book = rr.book_form()
    assert zero(book["M"] - (J_M + R**2 * arm.M))
    assert zero(book["K"] - sympy.diag(r1 * K_M1 / R_a1, r2 * K_M2 / R_a2))
    reduced = rr.M * rr.qdd + rr.Vm * rr.qd + rr.F + rr.G - rr.K * rr.v
    printed = book["M"] * rr.qdd + book["V"] * rr.qd + book["F"] + book["G"] - book["K"] * rr.v
    assert zero(R**2 * reduced - printed)
    assert not book["M"].is_symmetric()  # r1 != r2: the row-scaled inertia is not symmetric


def test_the_independent_joint_form_is_a_row_of_the_books(rr: ActuatedClosedForm) -> None:
    """(J_Mi + r_i^2 m_ii) qdd_i + B_i qd_i + r_i F_Mi = (r_i K_Mi / R_ai) v_i - r_i^2 d_i."""
    book = rr.book_form()
    printed = book["M"] * rr.qdd + book["V"] * rr.qd + book["F"] + book["G"] - book["K"] * rr.v
    for i, equation in enumerate(rr.independent_joint()):
        d = sympy.Symbol(f"d_{i + 1}")
        assert equation.lhs.coeff(rr.qdd[i]) == rr.motors[i].rotor_inertia + rr.R[i, i] ** 2 * rr.arm.M[i, i]
        assert zero(sympy.Matrix([(equation.lhs - equation.rhs).subs(d, rr.d[i]) - printed[i]]))


def test_printing(rr: ActuatedClosedForm) -> None:
    text = rr.pretty(independent=True)
    for label in ("M'(q) =", "V'(q, qd) = Vm =", "G'(q) =", "F'(qd) =", "K' =", "independent joints:"):
        assert label in text
    assert "c₁₂" in text and "cos" not in text
    latex = rr.latex(independent=True)
    assert r"\intertext" in latex and "c_{12}" in latex and r"\dot{q}_{1}" in latex
    assert "independent" not in rr.pretty(limit=None) and repr(rr) == "ActuatedClosedForm('two_link_planar', n=2)"
    assert "characters wide" in rr.pretty(limit=20)


# ----- numeric drives against ActuatedArm ----------------------------------------------------------
def puma_like_rr() -> ActuatedArm:
    """The RR arm driven by the PUMA 560's motors 2 and 3 (Jm, B, Tc, G of Corke's table; K_M, R_a representative)."""
    robot = ad.models.two_link_planar(m1=17.4, m2=4.8, a1=0.4318, a2=0.4318)
    drives = [
        DCMotor(200e-6, 0.817e-3, 0.22, 0.22, 2.1, 2e-3, 1 / 107.815, coulomb=(0.126, -0.071), name="motor 2"),
        DCMotor(200e-6, 1.38e-3, 0.22, 0.22, 2.1, 2e-3, -1 / 53.7063, coulomb=(0.132, -0.105), name="motor 3"),
    ]
    return with_actuators(robot, drives)


def random_chain(seed: int) -> ActuatedArm:
    """A random 3-joint chain whose motors (gear ratios of either sign) are moved into drives."""
    robot = random_robot(seed, 3, chain=True)
    return with_actuators(*motor_drives(robot, [0.22, 0.1, 0.3], [0.2, 0.1, 0.25], [2.1, 3.0, 6.7], 1e-3))


def assert_matches(compiled: object, actuated: ActuatedArm, seed: int) -> None:
    """The compiled closed form equals ActuatedArm's reduced model at random states (one and a batch)."""
    rng = np.random.default_rng(seed)
    q, qd, qdd = rng.uniform(-2, 2, (3, 5, actuated.n))
    for value, expected in (
        (compiled.M(q), actuated.inertia_matrix(q)),
        (compiled.Vm(q, qd), actuated.coriolis_matrix(q, qd)),
        (compiled.G(q), actuated.gravity_vector(q)),
        (compiled.F(qd), actuated.friction(qd)),
        (compiled.K(), actuated.input_matrix()),
        (compiled.inverse_dynamics(q, qd, qdd), actuated.inverse_dynamics(q, qd, qdd)),
        (compiled.M(q[0]), actuated.inertia_matrix(q[0])),
    ):
        assert value.shape == expected.shape
        assert_allclose(value, expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max())


@pytest.mark.slow
@pytest.mark.parametrize("make", [puma_like_rr, lambda: random_chain(1), lambda: random_chain(2)])
def test_numeric_drives_equal_actuated_arm(make: object) -> None:
    actuated = make()
    form = derive(actuated)
    assert isinstance(form, ActuatedClosedForm) and not form.M.free_symbols - set(form.q)
    assert_matches(form.compile(), actuated, 3)


def test_drives_as_a_robot_and_a_list_are_the_same_form() -> None:
    actuated = puma_like_rr()
    assert derive(actuated.robot, drives=list(actuated.drives)).M == derive(actuated).M


def test_symbolic_motors_on_a_numeric_arm_evaluate_as_dc_motors() -> None:
    """A gear ratio of unknown sign (a real symbol) given a negative value, asymmetric Coulomb friction."""
    actuated = puma_like_rr()
    r = sympy.Symbol("r", real=True)
    Tp, Tn = sympy.symbols("Tp Tn")
    motors = [
        {"rotor_inertia": J_M1, "viscous": B_M1, "torque_constant": K_M1, "back_emf": K_b1, "resistance": R_a1,
         "gear_ratio": r1, "coulomb": (0.126, -0.071)},
        SymbolicMotor(J_M2, B_M2, K_M2, K_b2, R_a2, r, (Tp, Tn)),
    ]  # fmt: skip
    form = derive(actuated.robot, drives=motors)
    assert form.F[1].has(sympy.Piecewise)
    first, second = actuated.drives
    values = {J_M1: first.rotor_inertia, B_M1: first.viscous, K_M1: first.torque_constant, K_b1: first.back_emf,
              R_a1: first.resistance, r1: first.gear_ratio, "J_M2": second.rotor_inertia, "B_M2": second.viscous,
              "K_M2": second.torque_constant, "K_b2": second.back_emf, "R_a2": second.resistance,
              "r": second.gear_ratio, "Tp": second.coulomb[0], "Tn": second.coulomb[1]}  # fmt: skip
    assert_matches(form.compile(values), actuated, 4)
    with pytest.raises(ad.ModelError, match=r"numeric values for the parameters \['Tn', 'Tp'\]"):
        form.compile({k: v for k, v in values.items() if k not in ("Tp", "Tn")})


# ----- refused ------------------------------------------------------------------------------------
def servo_valve() -> Hydraulic:
    return Hydraulic(5e-3, 1e-3, 1.0, 1e-11, 1e-4, 1e-12, 1e-4, 1e9, 7e6, rotary=True, name="valve")


def test_a_hydraulic_drive_is_refused() -> None:
    robot = ad.models.two_link_planar()
    drives = [puma_like_rr().drives[0], servo_valve()]
    with pytest.raises(ad.ModelError, match="closed forms of hydraulic drives are not supported"):
        derive(robot, drives=drives)
    with pytest.raises(ad.ModelError, match="closed forms of hydraulic drives are not supported"):
        derive(with_actuators(robot, drives))


def test_a_wrong_number_of_drives_is_refused() -> None:
    robot = ad.models.two_link_planar(symbolic=True)
    with pytest.raises(ad.ModelError, match=r"has 2 joints .*; 3 drives were given"):
        derive(robot, drives=motor_symbols(3))
    with pytest.raises(ad.ModelError, match="drives must be a sequence"):
        derive(robot, drives=motor_symbols(1)[0])


@pytest.mark.parametrize(
    ("drives", "message"),
    [
        ([dataclasses.replace(puma_like_rr().drives[0], stiffness=100.0)] * 2, "flexible shaft"),
        ([{"rotor_inertia": 1.0}] * 2, r"lacks the parameters \['back_emf'"),
        ([{**dataclasses.asdict(motor_symbols(1)[0]), "inductance": 1.0}] * 2, r"unknown parameters \['inductance'\]"),
        (["motor", "motor"], "must be a DCMotor, a SymbolicMotor or a dict"),
    ],
)
def test_what_is_not_a_rigid_dc_drive_is_refused(drives: list[object], message: str) -> None:
    with pytest.raises(ad.ModelError, match=message):
        derive(ad.models.two_link_planar(), drives=drives)


def test_bad_motor_parameters_are_refused() -> None:
    negative = sympy.Symbol("R", negative=True)
    with pytest.raises(ad.ModelError, match="armature resistance R_a must be positive"):
        SymbolicMotor(J_M1, B_M1, K_M1, K_b1, negative, r1)
    with pytest.raises(ad.ModelError, match="armature resistance R_a must be positive, got -2"):
        SymbolicMotor(J_M1, B_M1, K_M1, K_b1, -2.0, r1)
    with pytest.raises(ad.ModelError, match="gear ratio r must be non-zero"):
        SymbolicMotor(J_M1, B_M1, K_M1, K_b1, R_a1, 0)
    with pytest.raises(ad.ModelError, match="Coulomb friction Tc- must be <= 0"):
        SymbolicMotor(J_M1, B_M1, K_M1, K_b1, R_a1, r1, (F_M1, F_M1))
    with pytest.raises(ad.ModelError, match="rotor inertia J_M"):
        SymbolicMotor("J", B_M1, K_M1, K_b1, R_a1, r1)
    with pytest.raises(ad.ModelError, match="number of motors"):
        motor_symbols(0)


def test_arms_with_motors_and_other_combinations_are_refused() -> None:
    puma = ad.models.puma560()
    with pytest.raises(ad.ModelError, match="already has motors"):
        derive(puma, drives=motor_symbols(6))
    actuated = puma_like_rr()
    with pytest.raises(ad.ModelError, match="carries its drives"):
        derive(actuated, drives=list(actuated.drives))
    with pytest.raises(ad.ModelError, match=r"output=.* not supported"):
        derive(actuated, output=ad.task_space.ToolPosition())
    assert isinstance(derive(ad.models.two_link_planar(symbolic=True)), ClosedForm)  # no drives: the arm alone
