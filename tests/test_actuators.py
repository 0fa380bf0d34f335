"""Actuator dynamics and the arm-plus-actuator system (armdyn.actuators, Section 3.6)."""

from __future__ import annotations

import dataclasses
import math

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armdyn as ad
from armdyn.actuators import DCMotor, Hydraulic, example_3_6_1, motor_drives, transfer_function, with_actuators

# The PUMA 560's motor electrics: representative values for its two motor sizes (joints 1-3 and
# 4-6), not published data; K_b = K_M in SI units.
PUMA_TORQUE_CONSTANT = [0.22, 0.22, 0.22, 0.075, 0.075, 0.075]  # N m/A
PUMA_RESISTANCE = [2.1, 2.1, 2.1, 6.7, 6.7, 6.7]  # ohm
PUMA_INDUCTANCE = [2e-3, 2e-3, 2e-3, 1e-3, 1e-3, 1e-3]  # H


def puma_drives(robot: ad.Robot, inductance_scale: float = 1.0, coulomb: bool = True) -> ad.actuators.ActuatedArm:
    """The arm with its motors moved into DC motor drives with the electrics above."""
    bare, drives = motor_drives(
        robot,
        PUMA_TORQUE_CONSTANT[: robot.n],
        PUMA_TORQUE_CONSTANT[: robot.n],
        PUMA_RESISTANCE[: robot.n],
        np.array(PUMA_INDUCTANCE[: robot.n]) * inductance_scale,
    )
    if not coulomb:
        drives = [dataclasses.replace(drive, coulomb=0.0) for drive in drives]
    return with_actuators(bare, drives)


@pytest.fixture(scope="module")
def puma() -> ad.Robot:
    return ad.models.puma560()


def one_link(inertia: float = 0.1) -> ad.Robot:
    """A rotor-like link turning about the vertical: inertia about the joint axis, no gravity torque."""
    return ad.Robot.from_dh([{"mass": 1.0, "inertia": [inertia, inertia, inertia]}], name="load")


def slide(mass: float = 50.0, viscous: float = 500.0) -> ad.Robot:
    """A horizontal slide: one prismatic joint, no gravity."""
    return ad.Robot.from_dh([{"kind": "P", "mass": mass, "B": viscous}], name="slide", gravity=[0.0, 0.0, 0.0])


def example_motor(**changes: object) -> DCMotor:
    """Example 3.6-1's motor: J_m = 0.1, b_m = 0.2, k_m = k'_m = 1, R = 5, L = 0.5, direct drive."""
    return dataclasses.replace(DCMotor(0.1, 0.2, 1.0, 1.0, 5.0, 0.5, 1.0, name="example"), **changes)


def servo_valve(**changes: object) -> Hydraulic:
    """A servo valve and a 36 mm piston, representative values: 70 bar supply, square-root orifice."""
    valve = Hydraulic(
        valve_time_constant=5e-3,
        valve_gain=0.1,
        flow_gain=None,
        pressure_coefficient=0.0,
        area=1e-3,
        leakage=1e-11,
        volume=2e-4,
        bulk_modulus=1.4e9,
        supply_pressure=7e6,
        orifice="sqrt",
        discharge_coefficient=0.61,
        orifice_width=2e-3,
        density=850.0,
        name="valve",
    )
    return dataclasses.replace(valve, **changes)


# ----- bad inputs -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("changes", "rule"),
    [
        ({"resistance": -1.0}, "armature resistance R_a must be positive"),
        ({"resistance": 0.0}, "armature resistance R_a must be positive"),
        ({"inductance": -1e-3}, "armature inductance L must be >= 0"),
        ({"torque_constant": 0.0}, "torque constant K_M must be positive"),
        ({"back_emf": -0.1}, "back-emf constant K_b must be positive"),
        ({"rotor_inertia": -1.0}, "rotor inertia J_M must be >= 0"),
        ({"viscous": -1.0}, "viscous friction B_M must be >= 0"),
        ({"gear_ratio": 0.0}, "gear ratio r (q = r q_M) must be non-zero"),
        ({"gear_ratio": math.inf}, "gear ratio r must be finite"),
        ({"voltage_limit": 0.0}, "voltage limit must be positive"),
        ({"current_limit": -2.0}, "current limit must be positive"),
        ({"coulomb": (-0.1, 0.1)}, "Coulomb friction must be"),
        ({"stiffness": 0.0}, "shaft stiffness K must be positive"),
        ({"shaft_damping": 0.1}, "shaft damping B_s needs a shaft stiffness"),
        ({"stiffness": 2.0, "rotor_inertia": 0.0}, "a flexible shaft needs a rotor inertia"),
        ({"resistance": "five"}, "armature resistance R_a must be a number"),
    ],
)
def test_a_bad_dc_motor_is_refused_naming_the_drive(changes: dict, rule: str) -> None:
    with pytest.raises(ad.ModelError, match="drive 'example'") as error:
        example_motor(**changes)
    assert rule in str(error.value)


@pytest.mark.parametrize(
    ("changes", "rule"),
    [
        ({"volume": -1e-4}, "trapped volume V_t must be positive"),
        ({"bulk_modulus": 0.0}, "bulk modulus beta_e must be positive"),
        ({"leakage": -1e-12}, "leakage coefficient C_tp must be >= 0"),
        ({"valve_time_constant": 0.0}, "valve time constant tau_v must be positive"),
        ({"orifice": "turbulent"}, "orifice must be 'linear' or 'sqrt'"),
        ({"density": None}, "the square-root orifice needs the oil density rho"),
        ({"orifice": "linear"}, "the linear orifice needs the flow gain K_q"),
        ({"stroke": -1.0}, "valve stroke must be positive"),
    ],
)
def test_a_bad_hydraulic_drive_is_refused_naming_the_drive(changes: dict, rule: str) -> None:
    with pytest.raises(ad.ModelError, match="drive 'valve'") as error:
        servo_valve(**changes)
    assert rule in str(error.value)


def test_drives_that_do_not_fit_the_arm_are_refused(puma: ad.Robot) -> None:
    with pytest.raises(ad.ModelError, match=r"has 1 joints \['joint1'\]; 2 drives were given"):
        with_actuators(one_link(), [example_motor(), example_motor()])
    with pytest.raises(ad.ModelError, match=r"drive 'valve' is a piston .* cannot drive the revolute joint 'joint1'"):
        with_actuators(one_link(), [servo_valve()])
    with pytest.raises(ad.ModelError, match=r"drive 'valve' is a rotary motor .* prismatic joint 'joint1'"):
        with_actuators(slide(), [servo_valve(rotary=True)])
    with pytest.raises(ad.ModelError, match="must be a DCMotor or Hydraulic"):
        with_actuators(one_link(), [object()])
    with pytest.raises(TypeError, match="armdyn Robot"):
        with_actuators("puma560", [example_motor()])


def test_motors_already_on_the_arm_are_not_counted_twice(puma: ad.Robot) -> None:
    _, drives = motor_drives(puma, 0.2, 0.2, 2.0, 1e-3)
    with pytest.raises(ad.ModelError, match="already has motors") as error:
        with_actuators(puma, drives)
    assert "motor_drives" in str(error.value) and "without_motors()" in str(error.value)


def test_the_full_and_reduced_models_say_what_they_need() -> None:
    flexible = with_actuators(one_link(), [example_motor(stiffness=2.0)])
    with pytest.raises(ad.ModelError, match=r"does not exist: drives \['example'\] are flexible"):
        flexible.inertia_matrix([0.0])
    without_inductance = with_actuators(one_link(), [example_motor(inductance=0.0)])
    with pytest.raises(ad.ModelError, match=r"drives \['example'\] .* have no inductance"):
        without_inductance.state_derivative(np.zeros(3), [1.0])
    assert without_inductance.forward_dynamics([0.0], [0.0], [1.0]) == pytest.approx(1 / 0.2 * 1 / 5)
    rubbing = with_actuators(one_link(), [example_motor(coulomb=0.1)])
    with pytest.raises(ad.ModelError, match="Coulomb friction at zero velocity"):
        rubbing.linearize(np.zeros(3), [0.0])
    with pytest.raises(ad.ModelError, match=r"x must have shape \(3,\)"):
        rubbing.state_derivative(np.zeros(4), [1.0])


# ----- the reduced model -------------------------------------------------------------------------------
def test_reduced_model_of_the_puma_keeps_table_3_3_1(puma: ad.Robot) -> None:
    arm = puma_drives(puma)
    rng = np.random.default_rng(1)
    q = rng.uniform(*puma.qlim, (50, 6))
    qd, x = rng.normal(size=(2, 50, 6))
    M = arm.inertia_matrix(q)
    assert np.allclose(M, puma.inertia_matrix(q), rtol=1e-14, atol=1e-14)  # the motors moved, not added
    assert np.abs(M - np.swapaxes(M, -1, -2)).max() == 0
    assert np.linalg.eigvalsh(M)[:, 0].min() > 0.1
    S = arm.inertia_matrix_dot(q, qd) - 2 * arm.coriolis_matrix(q, qd)
    assert np.abs(np.einsum("...i,...ij,...j->...", x, S, x)).max() < 1e-13 * np.abs(S).max()
    assert np.abs(S + np.swapaxes(S, -1, -2)).max() < 1e-13 * np.abs(S).max()
    # the book's printed form is these rows times r_i^2: R^2 M' = J_M + R^2 M
    r = np.array([drive.gear_ratio for drive in arm.drives])
    J_M = np.diag([drive.rotor_inertia for drive in arm.drives])
    book = J_M + r[:, None] ** 2 * arm.robot.inertia_matrix(q)
    assert np.allclose(r[:, None] ** 2 * M, book, rtol=1e-13, atol=1e-16)
    assert np.abs(book - np.swapaxes(book, -1, -2)).max() > 1e-4  # with unequal ratios it is not symmetric
    # F' = F + the back-emf damping G^2 K_b K_M / R_a; K' = G K_M / R_a
    back_emf = np.array(PUMA_TORQUE_CONSTANT) ** 2 / np.array(PUMA_RESISTANCE) / r**2
    assert np.allclose(arm.friction(qd), puma.friction(qd) + back_emf * qd, rtol=1e-13)
    assert np.allclose(np.diag(arm.input_matrix()), np.array(PUMA_TORQUE_CONSTANT) / np.array(PUMA_RESISTANCE) / r)
    # inverse and forward dynamics, batched
    v = rng.normal(size=(50, 6)) * 10
    qdd = arm.forward_dynamics(q, qd, v)
    assert qdd.shape == (50, 6)
    assert np.allclose(arm.inverse_dynamics(q, qd, qdd), v, rtol=1e-9, atol=1e-9)
    torque = v @ arm.input_matrix()
    assert np.allclose(qdd, arm.reduced_robot().forward_dynamics(q, qd, torque), rtol=1e-10, atol=1e-10)
    assert np.allclose(qdd[7], arm.forward_dynamics(q[7], qd[7], v[7]))


def test_properties_check_runs_on_the_actuated_puma(puma: ad.Robot) -> None:
    report = ad.properties.check(puma_drives(puma), samples=100)
    assert report.all_hold
    names = {row.name for row in report.rows}
    assert names >= {"symmetry", "positive definite", "skew symmetry", "Christoffel symmetry", "friction bound",
                     "dissipation", "gravity bound", "linearity", "passivity"}  # fmt: skip
    assert "reduced arm-plus-actuator model" in report.notes[0]
    assert "reduced arm-plus-actuator model" in report.title()


# ----- the full model ---------------------------------------------------------------------------------
def mixed_arm() -> ad.actuators.ActuatedArm:
    """An RRP arm: a rigid geared DC motor, a flexible one, and a hydraulic piston with a linear orifice."""
    robot = ad.Robot.from_dh(
        [
            {"a": 0.5, "mass": 2.0, "com": [-0.25, 0, 0], "inertia": [0.01, 0.05, 0.05], "B": 0.1},
            {"a": 0.4, "alpha": math.pi / 2, "mass": 1.5, "com": [-0.2, 0, 0], "inertia": [0.01, 0.03, 0.03]},
            {"kind": "P", "mass": 1.0, "inertia": [0.01, 0.01, 0.01], "B": 5.0},
        ],
        name="rrp",
    )
    drives = [
        DCMotor(2e-4, 1e-3, 0.2, 0.2, 2.0, 2e-3, -1 / 50, name="geared"),
        DCMotor(3e-4, 2e-3, 0.2, 0.2, 2.0, 2e-3, 1 / 30, stiffness=300.0, shaft_damping=0.5, name="flexible"),
        servo_valve(orifice="linear", flow_gain=0.1, pressure_coefficient=1e-11, volume=1e-3),
    ]
    return with_actuators(robot, drives)


def test_state_derivative_is_batched_and_linearize_matches_it() -> None:
    arm = mixed_arm()
    assert arm.state_names == ["q joint1", "q joint2", "q joint3", "qd joint1", "qd joint2", "qd joint3",
                               "qM joint2", "qdM joint2", "i joint1", "i joint2", "xv joint3", "PL joint3"]  # fmt: skip
    rng = np.random.default_rng(2)
    scale = np.array([1, 1, 0.1, 1, 1, 0.1, 30, 30, 5, 5, 1e-4, 1e5])
    x = rng.normal(size=(4, 3, arm.n_states)) * scale
    v = rng.normal(size=(3, 3)) * [10, 10, 1e-3]
    rates = arm.state_derivative(x, v)
    assert rates.shape == (4, 3, arm.n_states)
    for index in np.ndindex(4, 3):
        assert np.array_equal(rates[index], arm.state_derivative(x[index], v[index[1]]))
    x0, v0 = x[0, 0], v[0]
    A, B = arm.linearize(x0, v0)
    dx, dv = 1e-6 * scale * rng.normal(size=arm.n_states), 1e-6 * np.array([10, 10, 1e-3])
    predicted = arm.state_derivative(x0, v0) + A @ dx + B @ dv
    assert np.allclose(arm.state_derivative(x0 + dx, v0 + dv), predicted, rtol=1e-9, atol=1e-9 * np.abs(predicted))
    system = arm.to_control(x0, v0)
    assert np.array_equal(system.A, A) and system.nstates == arm.n_states


def test_limits_clip_the_input_and_hold_the_current() -> None:
    arm = with_actuators(one_link(), [example_motor(voltage_limit=24.0, current_limit=3.0)])
    x = np.array([0.0, 0.0, 1.0])
    assert np.array_equal(arm.state_derivative(x, [100.0]), arm.state_derivative(x, [24.0]))
    at_limit = np.array([0.0, 0.0, 3.0])
    assert arm.state_derivative(at_limit, [24.0])[2] == 0.0
    assert arm.state_derivative(at_limit, [-24.0])[2] < 0.0
    assert arm.forward_dynamics([0.0], [0.0], [100.0]) == pytest.approx(3.0 * 1.0 / 0.2)


def simulate(rate, y0: np.ndarray, T: float, method: str, rtol: float, atol: object, t_eval=None):
    solution = solve_ivp(rate, (0.0, T), y0, method=method, rtol=rtol, atol=atol, t_eval=t_eval)
    assert solution.success, solution.message
    return solution


@pytest.mark.slow
def test_reduced_model_is_the_limit_of_the_full_one_as_L_goes_to_0(puma: ad.Robot) -> None:
    q0, T = puma.qn, 0.2
    reduced = puma_drives(puma, coulomb=False)
    v = reduced.inverse_dynamics(q0, np.zeros(6), np.zeros(6)) + [10.0, -10.0, 10.0, 5.0, -5.0, 5.0]

    def slow(t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate([y[6:], reduced.forward_dynamics(y[:6], y[6:], v)])

    end = simulate(slow, np.concatenate([q0, np.zeros(6)]), T, "DOP853", 1e-10, 1e-12).y[:6, -1]
    moved = np.abs(end - q0).max()
    errors = []
    for scale in (1.0, 0.1, 0.01):
        full = puma_drives(puma, inductance_scale=scale, coulomb=False)
        x0 = full.initial_state(q0)
        x0[12:] = v / np.array(PUMA_RESISTANCE)  # the reduced model's current at rest
        solution = simulate(lambda t, x, full=full: full.state_derivative(x, v), x0, T, "Radau", 1e-9, 1e-11)
        errors.append(np.abs(solution.y[:6, -1] - end).max() / moved)
    print("relative error of the full model at L x 1, 0.1, 0.01:", ", ".join(f"{e:.2e}" for e in errors))
    assert moved > 0.05
    assert errors[0] < 0.05
    assert errors[1] < 0.2 * errors[0] and errors[2] < 0.2 * errors[1]  # O(L): ten times smaller per step
    assert errors[2] < 1e-3


@pytest.mark.slow
def test_energy_balance_with_electrics_on_the_puma(puma: ad.Robot) -> None:
    """v^T i = d/dt (K + P + 1/2 L i^2) + R i^2 + B_M qd_M^2 along a run, to 1e-6 relative."""
    arm = puma_drives(puma, coulomb=False)
    q0 = puma.qn
    v = arm.inverse_dynamics(q0, np.zeros(6), np.zeros(6)) + [10.0, -10.0, 10.0, 5.0, -5.0, 5.0]
    R_a, L = np.array(PUMA_RESISTANCE), np.array(PUMA_INDUCTANCE)
    r = np.array([drive.gear_ratio for drive in arm.drives])
    B_M = np.array([drive.viscous for drive in arm.drives])

    def rate(t: float, y: np.ndarray) -> np.ndarray:
        x = y[:18]
        qd, i = x[6:12], x[12:18]
        supplied, resistive, viscous = v @ i, R_a @ i**2, B_M @ (qd / r) ** 2
        return np.concatenate([arm.state_derivative(x, v), [supplied, resistive + viscous]])

    def stored(x: np.ndarray) -> float:  # the PUMA with its motors: links and rotors; magnetic energy
        return puma.kinetic_energy(x[:6], x[6:12]) + puma.potential_energy(x[:6]) + 0.5 * L @ x[12:18] ** 2

    y0 = np.concatenate([arm.initial_state(q0), [0.0, 0.0]])
    end = simulate(rate, y0, 0.2, "DOP853", 1e-12, 1e-12).y[:, -1]
    supplied, lost = end[18], end[19]
    gained = stored(end[:18]) - stored(y0[:18])
    print(f"PUMA: supplied {supplied:.6g} J, lost {lost:.6g} J, stored {gained:.6g} J, "
          f"balance {abs(supplied - lost - gained) / supplied:.2e}")  # fmt: skip
    assert supplied > 1.0 and lost > 0.5 and abs(gained) > 0.01
    assert abs(supplied - lost - gained) < 1e-6 * supplied
    assert arm.stored_energy(end[:18]) - arm.stored_energy(y0[:18]) == pytest.approx(gained, rel=1e-12)


@pytest.mark.slow
def test_energy_balance_of_flexible_and_hydraulic_drives() -> None:
    """sum v i + P_L Q_L = d/dt stored energy + the losses of every resistor, damper and leak."""
    arm = mixed_arm()
    geared, flexible, valve = arm.drives
    v = np.array([4.0, -3.0, 2e-3])
    friction = arm.robot  # its joint friction: B = 0.1, 0, 5.0 at the joints

    def rate(t: float, y: np.ndarray) -> np.ndarray:
        x = y[: arm.n_states]
        qd, w_M, i, x_v, P_L = x[3:6], x[7], x[8:10], x[10], x[11]
        Q_L = valve.flow_gain * x_v - valve.pressure_coefficient * P_L
        supplied = v[:2] @ i + P_L * Q_L
        losses = (
            geared.resistance * i[0] ** 2 + flexible.resistance * i[1] ** 2
            + geared.viscous * (qd[0] / geared.gear_ratio) ** 2 + flexible.viscous * w_M**2
            + flexible.shaft_damping * (flexible.gear_ratio * w_M - qd[1]) ** 2
            + valve.leakage * P_L**2 + qd @ friction.friction(qd)
        )  # fmt: skip
        return np.concatenate([arm.state_derivative(x, v), [supplied, losses]])

    y0 = np.concatenate([arm.initial_state([0.3, -0.5, 0.0]), [0.0, 0.0]])
    end = simulate(rate, y0, 0.2, "DOP853", 1e-11, 1e-13).y[:, -1]
    gained = arm.stored_energy(end[: arm.n_states]) - arm.stored_energy(y0[: arm.n_states])
    supplied, lost = end[-2], end[-1]
    print(f"RRP: supplied {supplied:.6g} J, lost {lost:.6g} J, stored {gained:.6g} J, "
          f"balance {abs(supplied - lost - gained) / supplied:.2e}")  # fmt: skip
    assert supplied > 0.1 and lost > 0.05
    assert abs(supplied - lost - gained) < 1e-6 * supplied


# ----- Example 3.6-1 ---------------------------------------------------------------------------------------
def test_example_3_6_1_poles_and_python_control() -> None:
    numerator, denominator = example_3_6_1()
    assert np.allclose(numerator, [10.0]) and np.allclose(denominator, [1.0, 11.0, 20.0])
    poles = np.sort(np.roots(denominator).real)
    assert poles == pytest.approx([-(11 + math.sqrt(41)) / 2, -(11 - math.sqrt(41)) / 2], rel=1e-14)
    assert np.round(poles, 3).tolist() == [-8.702, -2.298]
    s = control.tf("s")
    L, R, J, b, k_m, k_b = 0.5, 5.0, 0.1 + 0.1, 0.2, 1.0, 1.0
    book = k_m / ((L * s + R) * (J * s + b) + k_m * k_b)
    ours = control.tf(numerator, denominator)
    points = np.array([0.0, 0.1j, 1 + 2j, 5j, 30j, -1 + 0.5j])
    assert np.allclose(ours(points), book(points), rtol=1e-14)
    # the linearization of the one-motor arm: state [q, qd, i], output qd
    arm = with_actuators(one_link(0.1), [example_motor()])
    system = arm.to_control(np.zeros(3), [0.0])
    speed = control.ss(system.A, system.B, system.C[[1]], system.D[[1]])
    assert np.allclose(speed(points[1:]).ravel(), book(points[1:]), rtol=1e-9)
    eigenvalues = np.sort(np.linalg.eigvals(system.A).real)  # the poles and the position's integrator
    assert eigenvalues == pytest.approx([*poles, 0.0], rel=1e-8, abs=1e-9)


def test_example_3_6_1_with_a_flexible_shaft() -> None:
    numerator, denominator = example_3_6_1(flexible=True)
    assert len(denominator) == 5 and len(numerator) == 2  # fourth order, one zero
    # the same system written by hand: states [i, w_m, twist = th_m - th_L, w_L], output w_L
    L, R, k_m, k_b, J_m, b_m, J_L, k, b = 0.5, 5.0, 1.0, 1.0, 0.1, 0.2, 0.1, 2.0, 0.2
    A = [[-R / L, -k_b / L, 0, 0],
         [k_m / J_m, -(b_m + b) / J_m, -k / J_m, b / J_m],
         [0, 1, 0, -1],
         [0, b / J_L, k / J_L, -b / J_L]]  # fmt: skip
    by_hand = control.ss(A, [[1 / L], [0], [0], [0]], [[0, 0, 0, 1]], 0)
    ours = control.tf(numerator, denominator)
    points = np.array([0.0, 0.1j, 1 + 2j, 5j, 30j])
    assert np.allclose(ours(points), by_hand(points).ravel(), rtol=1e-12)
    arm = with_actuators(one_link(0.1), [example_motor(stiffness=2.0, shaft_damping=0.2)])
    system = arm.to_control(np.zeros(5), [0.0])
    load_speed = control.ss(system.A, system.B, system.C[[1]], 0)
    assert np.allclose(load_speed(points[1:]).ravel(), ours(points[1:]), rtol=1e-9)
    eigenvalues = np.linalg.eigvals(system.A)
    assert np.sort_complex(eigenvalues[np.abs(eigenvalues) > 1e-9]) == pytest.approx(
        np.sort_complex(np.roots(denominator)), rel=1e-7
    )


def test_transfer_function_with_a_gear_matches_the_linearization() -> None:
    motor = example_motor(gear_ratio=-0.05, stiffness=40.0, shaft_damping=0.3)
    numerator, denominator = transfer_function(motor, load_inertia=0.1, load_damping=0.05)
    link = ad.Robot.from_dh([{"mass": 1.0, "inertia": [0.1, 0.1, 0.1], "B": 0.05}])
    system = with_actuators(link, [motor]).to_control(np.zeros(5), [0.0])
    speed = control.ss(system.A, system.B, system.C[[1]], 0)
    points = np.array([0.2j, 1 + 1j, 8j])
    assert np.allclose(speed(points).ravel(), control.tf(numerator, denominator)(points), rtol=1e-9)


# ----- a voltage step on a PUMA joint motor ----------------------------------------------------------------------
@pytest.mark.slow
def test_voltage_step_on_the_puma_waist_motor_has_the_motor_time_constants(puma: ad.Robot) -> None:
    """Joint 1 (vertical axis) with joints 2 to 6 locked: a constant inertia, so the motor and load
    are second order: (L s + R)(J s + B_M) + K_M K_b with J = J_M + r^2 M_11 at the rotor."""
    waist = puma.reduced({"q2": math.pi / 4, "q3": -math.pi, "q4": 0.0, "q5": math.pi / 4, "q6": 0.0})
    arm = puma_drives(waist, coulomb=False)
    (motor,) = arm.drives
    r, K, K_b, R, L = motor.gear_ratio, motor.torque_constant, motor.back_emf, motor.resistance, motor.inductance
    J = motor.rotor_inertia + r**2 * float(arm.robot.inertia_matrix([0.0])[0, 0])
    b = motor.viscous
    p_fast, p_slow = np.sort(np.roots([L * J, L * b + R * J, R * b + K * K_b]).real)
    tau_e, tau_m = L / R, J * R / (K * K_b)
    damped = J * R / (K * K_b + R * b)  # tau_m with the rotor's own viscous friction B_M
    print(f"tau_e = {tau_e:.4g} s, -1/p_fast = {-1 / p_fast:.4g} s; tau_m = {tau_m:.4g} s, "
          f"J R / (K_M K_b + R B_M) = {damped:.4g} s, -1/p_slow = {-1 / p_slow:.4g} s")  # fmt: skip
    assert -1 / p_fast == pytest.approx(tau_e, rel=0.05) and -1 / p_slow == pytest.approx(damped, rel=0.05)
    assert -1 / p_slow == pytest.approx(tau_m, rel=0.15)

    def step(t: np.ndarray, numerator: np.ndarray) -> np.ndarray:
        """Step response of polyval(numerator, s) / (L J (s - p_fast)(s - p_slow)), times the voltage."""
        terms = [np.polyval(numerator, p) * np.exp(p * t) / (p * (p - other))
                 for p, other in ((p_fast, p_slow), (p_slow, p_fast))]  # fmt: skip
        return V / (L * J) * (np.polyval(numerator, 0.0) / (p_fast * p_slow) + terms[0] + terms[1])

    V, t = 10.0, np.linspace(0.0, 5 * tau_m, 400)
    solution = simulate(lambda _, x: arm.state_derivative(x, [V]), np.zeros(3), t[-1], "Radau", 1e-11, 1e-13, t)
    speed, current = step(t, np.array([r * K])), step(t, np.array([J, b]))
    assert np.abs(solution.y[1] - speed).max() < 1e-7 * np.abs(speed).max()
    assert np.abs(solution.y[2] - current).max() < 1e-7 * np.abs(current).max()
    # the current peaks after a few electrical time constants, the speed settles after a few mechanical ones
    assert 1.5 * tau_e < t[np.argmax(current)] < 10 * tau_e
    assert speed[np.searchsorted(t, damped)] / speed[-1] == pytest.approx(1 - math.exp(-1), abs=0.03)


# ----- hydraulics ------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_a_small_valve_step_follows_the_linearized_merritt_model() -> None:
    """The square-root orifice against the null linearization (K_q = C_d w sqrt(P_s / rho), K_c = 0): the
    departure, mostly the pressure coefficient C_d w |x_v| / (2 sqrt(rho P_s)) the null model lacks, is
    first order in the step and vanishes with it."""
    arm = with_actuators(slide(), [servo_valve()])
    assert arm.state_names == ["q joint1", "qd joint1", "xv joint1", "PL joint1"]
    linear = arm.to_control(np.zeros(4), [0.0])
    t = np.linspace(0.0, 0.06, 601)
    errors = []
    for amplitude in (2e-5, 2e-4):  # valve current, A: spool openings of 2 and 20 micrometres
        expected = np.asarray(control.forced_response(linear, t, amplitude * np.ones_like(t)).states)
        solution = simulate(lambda _, x, u=amplitude: arm.state_derivative(x, [u]), np.zeros(4), t[-1], "Radau",
                            1e-10, [1e-12, 1e-12, 1e-14, 1e-4], t)  # fmt: skip
        errors.append(max(np.abs(solution.y[k] - expected[k]).max() / np.abs(expected[k]).max() for k in (1, 3)))
        assert np.abs(expected[1]).max() > 0.5 * 0.111 * 0.1 * amplitude / 1e-3  # it moves: K_q K_v i / A
    print(f"relative departure from the linearized model: {errors[0]:.2e} (20 um), {errors[1]:.2e} (200 um)")
    assert errors[1] < 5e-3
    assert 5 < errors[1] / errors[0] < 15


def test_the_linear_orifice_is_exactly_the_linearized_model() -> None:
    valve = servo_valve(orifice="linear", flow_gain=0.111, pressure_coefficient=1e-11)
    arm = with_actuators(slide(), [valve])
    A, B = arm.linearize(np.zeros(4), [0.0])
    m, b, C = 50.0, 500.0, valve.capacitance
    exact = [[0, 1, 0, 0], [0, -b / m, 0, valve.area / m], [0, 0, -1 / valve.valve_time_constant, 0],
             [0, -valve.area / C, valve.flow_gain / C, -valve.total_coefficient / C]]  # fmt: skip
    assert np.allclose(A, exact, rtol=1e-9, atol=1e-9)
    assert np.allclose(B.ravel(), [0, 0, valve.valve_gain / valve.valve_time_constant, 0], rtol=1e-9)
    # the reduced model: damping A^2 / K_ce and gain A K_q K_v / K_ce
    K_ce = valve.total_coefficient
    assert arm.friction([0.01]) == pytest.approx(b * 0.01 + valve.area**2 / K_ce * 0.01, rel=1e-12)
    assert arm.input_matrix()[0, 0] == pytest.approx(valve.area * valve.flow_gain * valve.valve_gain / K_ce)


def test_actuators_is_a_lazy_module_of_armdyn() -> None:
    assert ad.actuators.DCMotor is DCMotor


def test_a_list_of_drives_that_is_not_one_per_joint_is_refused_naming_drives() -> None:
    arm = ad.models.two_link_planar()
    motor = DCMotor(2e-4, 1e-3, 0.2, 0.2, 2.0, 2e-3, 0.02)
    for drives, rule in (([motor], "one per joint"), ([motor, None], "must be a DCMotor or Hydraulic")):
        with pytest.raises(ad.ModelError, match=rf"^drives(:| must) .*{rule}"):
            with_actuators(arm, drives)
