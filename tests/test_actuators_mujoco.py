"""armdyn's DC motor drive against MuJoCo's ``dcmotor`` actuator (Example 3.6-1, Section 3.6).

The same drive in both: a load inertia J_L on one hinge, no gravity, driven by Example 3.6-1's
motor (J_m = J_L = 0.1, b_m = 0.2, k_m = k'_m = 1, R = 5, L = 0.5) directly or behind a gear.

MuJoCo's ``dcmotor`` with ``inductance`` has one activation, the armature current i, with
L di/dt = v - R i - K omega, omega = gear qd the rotor speed (the actuator velocity), and the
joint torque gear K i; K = sqrt(Kt Ke) from ``motorconst="Kt Ke"``. The rotor's inertia and viscous
friction are the actuator's ``armature`` and ``damping``, both reflected to the joint times gear^2.
So MuJoCo's gear is armdyn's 1 / r (q = r q_M), and its current is armdyn's i.

Two details of MuJoCo's time stepping make its RK4 first order in the time step h on this
model: the dcmotor is always ``actearly`` (the force uses the current one step
ahead, i + psi di/dt with psi = (L/R)(1 - exp(-h R / L))), and the current is advanced with that
same exact-filter factor psi instead of h. Its RK4 run therefore differs from the exact response
by O(h); the comparison uses runs at h, h/2 and h/4 and Richardson extrapolation, which removes the
h and h^2 terms and leaves an O(h^3) difference of a few 1e-9 of each signal's range. Without
inductance (no activation) MuJoCo's RK4 is fourth order and matches armdyn's reduced model to
about 1e-12.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armdyn as ad
from armdyn.actuators import DCMotor, with_actuators

mujoco = pytest.importorskip("mujoco")

LOAD_INERTIA = 0.1  # J_L, kg m^2
VOLTAGE = 10.0  # the step, V
DURATION = 3.0  # s: about seven times the slow time constant 1 / 2.298
SAMPLE = 0.01  # s between compared samples
STEPS = (1e-3, 5e-4, 2.5e-4)  # MuJoCo time steps h, h/2, h/4
GEARS = [1.0, 10.0, -4.0]  # MuJoCo's gear = 1 / r


def example_motor(gear: float) -> DCMotor:
    """Example 3.6-1's motor behind the gear q = q_M / gear."""
    return DCMotor(0.1, 0.2, 1.0, 1.0, 5.0, 0.5, 1.0 / gear, name="Example 3.6-1 motor")


def armdyn_arm(motor: DCMotor) -> ad.actuators.ActuatedArm:
    """The load inertia on one joint about the vertical, without gravity, driven by the motor."""
    load = ad.Robot.from_dh([{"mass": 1.0, "inertia": [LOAD_INERTIA] * 3}], name="load", gravity=[0.0, 0.0, 0.0])
    return with_actuators(load, [motor])


def mujoco_model(motor: DCMotor, timestep: float, inductance: bool = True) -> mujoco.MjModel:
    """The same drive as MJCF: a hinge with the load inertia and a dcmotor with the rotor as armature."""
    electrics = f'inductance="{motor.inductance!r} 0"' if inductance else ""
    xml = f"""
    <mujoco model="Example 3.6-1">
      <option gravity="0 0 0" integrator="RK4" timestep="{timestep!r}"/>
      <worldbody>
        <body name="load">
          <joint name="hinge" type="hinge" axis="0 0 1"/>
          <inertial pos="0 0 0" mass="1" diaginertia="{LOAD_INERTIA!r} {LOAD_INERTIA!r} {LOAD_INERTIA!r}"/>
        </body>
      </worldbody>
      <actuator>
        <dcmotor name="motor" joint="hinge" gear="{1.0 / motor.gear_ratio!r}" resistance="{motor.resistance!r}"
                 motorconst="{motor.torque_constant!r} {motor.back_emf!r}" {electrics}
                 armature="{motor.rotor_inertia!r}" damping="{motor.viscous!r}"/>
      </actuator>
    </mujoco>
    """
    return mujoco.MjModel.from_xml_string(xml)


def mujoco_step_response(model: mujoco.MjModel) -> np.ndarray:
    """[q, qd, i] (i only with an activation) every SAMPLE seconds from rest under the voltage step."""
    data = mujoco.MjData(model)
    data.ctrl[0] = VOLTAGE
    steps, every = round(DURATION / model.opt.timestep), round(SAMPLE / model.opt.timestep)
    samples = [np.concatenate([data.qpos, data.qvel, data.act])]
    for k in range(1, steps + 1):
        mujoco.mj_step(model, data)
        if k % every == 0:
            samples.append(np.concatenate([data.qpos, data.qvel, data.act]))
    return np.array(samples)


def armdyn_step_response(rate, n_states: int) -> np.ndarray:
    """The same samples of x' = rate(x) from rest, integrated to 1e-12."""
    t = np.linspace(0.0, DURATION, round(DURATION / SAMPLE) + 1)
    solution = solve_ivp(
        lambda _, x: rate(x), (0.0, DURATION), np.zeros(n_states), method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t
    )
    assert solution.success, solution.message
    return solution.y.T


def relative_error(response: np.ndarray, exact: np.ndarray) -> np.ndarray:
    """The largest difference of each signal over the run, relative to the signal's largest magnitude."""
    return np.abs(response - exact).max(axis=0) / np.abs(exact).max(axis=0)


@pytest.mark.parametrize("gear", GEARS)
def test_the_compiled_dcmotor_carries_the_drive_parameters(gear: float) -> None:
    motor = example_motor(gear)
    model = mujoco_model(motor, STEPS[0])
    assert model.na == 1 and model.nu == 1
    assert model.actuator_dyntype[0] == mujoco.mjtDyn.mjDYN_DCMOTOR
    assert model.actuator_gaintype[0] == mujoco.mjtGain.mjGAIN_DCMOTOR
    assert model.actuator_biastype[0] == mujoco.mjtBias.mjBIAS_DCMOTOR
    K = math.sqrt(motor.torque_constant * motor.back_emf)  # MuJoCo's one motor constant
    assert model.actuator_gainprm[0, :2].tolist() == [motor.resistance, K]
    assert model.actuator_dynprm[0, 0] == pytest.approx(motor.inductance / motor.resistance, rel=1e-15)
    assert model.actuator_gear[0, 0] == gear and bool(model.actuator_actearly[0])
    # the reflected rotor: MuJoCo's J_L + gear^2 J_m is armdyn's M' = M + J_M / r^2
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    full = np.zeros((1, 1))
    mujoco.mj_fullM(model, data, full)
    assert full[0, 0] == pytest.approx(float(armdyn_arm(motor).inertia_matrix([0.0])[0, 0]), rel=1e-14)


@pytest.mark.parametrize("gear", GEARS)
def test_the_rates_agree_at_random_states(gear: float) -> None:
    """MuJoCo's di/dt is armdyn's; its qdd is armdyn's with the one-step-ahead (actearly) current."""
    motor = example_motor(gear)
    arm = armdyn_arm(motor)
    h = STEPS[0]
    model = mujoco_model(motor, h)
    data = mujoco.MjData(model)
    tau_e = motor.inductance / motor.resistance
    psi = tau_e * -math.expm1(-h / tau_e)
    rng = np.random.default_rng(3_6_1)
    for q, qd, i, v in zip(
        rng.uniform(-math.pi, math.pi, 20),
        rng.uniform(-5, 5, 20),
        rng.uniform(-2, 2, 20),
        rng.uniform(-24, 24, 20),
        strict=True,
    ):
        data.qpos[0], data.qvel[0], data.act[0], data.ctrl[0] = q, qd, i, v
        mujoco.mj_forward(model, data)
        di = arm.state_derivative([q, qd, i], [v])[2]
        ahead = i + psi * di
        assert data.act_dot[0] == pytest.approx(di, rel=1e-12, abs=1e-12)
        assert data.actuator_force[0] == pytest.approx(motor.torque_constant * ahead, rel=1e-12, abs=1e-12)
        assert data.qacc[0] == pytest.approx(arm.state_derivative([q, qd, ahead], [v])[1], rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("gear", GEARS)
def test_a_voltage_step_converges_to_armdyns_response(gear: float) -> None:
    """Angle, speed and current over 3 s: MuJoCo's RK4 runs approach armdyn's response at first order in h,
    and their Richardson extrapolation agrees with it to 2e-8 of each signal's range."""
    motor = example_motor(gear)
    arm = armdyn_arm(motor)
    exact = armdyn_step_response(lambda x: arm.state_derivative(x, [VOLTAGE]), 3)
    runs = [mujoco_step_response(mujoco_model(motor, h)) for h in STEPS]
    errors = [relative_error(run, exact) for run in runs]
    once = [2 * fine - coarse for coarse, fine in itertools.pairwise(runs)]
    twice = (4 * once[1] - once[0]) / 3
    print(
        f"gear {gear:g}: relative errors of [q, qd, i] at h = {STEPS[-1]:g}: {errors[-1]}; after one extrapolation: "
        f"{relative_error(once[1], exact)}; after two: {relative_error(twice, exact)}"
    )
    K, K_b, R, b_m = motor.torque_constant, motor.back_emf, motor.resistance, motor.viscous
    settled = motor.gear_ratio * K * VOLTAGE / (R * b_m + K * K_b)  # the steady speed, H(0) v at the joint
    assert exact[-1, 1] == pytest.approx(settled, rel=0.01)
    assert np.all(errors[-1] < 1e-3)
    for coarse, fine in itertools.pairwise(errors):
        assert np.all(np.abs(coarse / fine - 2.0) < 0.1)  # first order: half the step, half the error
    assert np.all(relative_error(once[1], exact) < 2e-6)
    assert np.all(relative_error(twice, exact) < 2e-8)


@pytest.mark.parametrize("gear", GEARS)
def test_without_inductance_rk4_matches_the_reduced_model(gear: float) -> None:
    """L = 0 in MuJoCo (no activation) is armdyn's reduced model (inductance neglected): fourth-order RK4
    at h = 1e-3 matches it to 1e-10."""
    motor = example_motor(gear)
    arm = armdyn_arm(motor)
    model = mujoco_model(motor, STEPS[0], inductance=False)
    assert model.na == 0
    exact = armdyn_step_response(lambda y: np.concatenate([y[1:], arm.forward_dynamics(y[:1], y[1:], [VOLTAGE])]), 2)
    errors = relative_error(mujoco_step_response(model), exact)
    print(f"gear {gear:g}: relative errors of [q, qd] without inductance: {errors}")
    assert np.all(errors < 1e-10)
