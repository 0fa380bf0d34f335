"""The arm with its drives, compiled (Section 3.6; Merritt 1967): the full model's state
derivative under a drive-level control law (``closed_loop``), which the simulation's compiled stepper
integrates.

The state is x = [q, qd, q_M, qd_M, i, x_v, P_L] as ``armdyn.actuators.ActuatedArm`` orders it
(``state_derivative`` there is the NumPy version of ``full_rates``). The arm's mechanics
M qdd + Vm qd + F + G = tau carry the rigid drives' rotors and friction (the Link motor
convention, packed as usual); the joint torque is (K_M / r) i for a rigid DC drive, the shaft
torque K (r q_M - q) + B_s (r qd_M - qd) for a flexible one, and A P_L for a hydraulic one. The
drives' own equations are the armature L di/dt + R_a i + K_b qd_M = v, the flexible rotor
J_M qdd_M + B_M qd_M + F_M + r tau = K_M i, the valve tau_v dx_v/dt + x_v = K_v u, the load flow
(linear or square-root orifice) and the continuity equation Q_L = A qd + C_tp P_L + C dP_L/dt.

Limits (``full_rates`` and ``hold_limits``): each DC drive's amplifier is a saturated current loop. Its
voltage is the law's, clipped to +-V_max, while the current is inside +-i_max; at the limit, where
that voltage would push the current out, the amplifier applies the voltage that holds it,
v = R_a i + K_b qd_M (so di/dt = 0, the armature equation of the book's Section 3.6 unchanged). The
valve current is clipped to its limit, and the spool meets a hard stop at +-stroke: its rate is
zero there when pushed outward. Both are the projected dynamics of a state kept in a box (Dupuis and
Nagurney 1993): the rate is zeroed where it points out of the box, and ``hold_limits`` puts a state
that a finite RK4 step carried past a limit back on it, at every stage and every step, so that the
limits hold at every stage and every recorded sample. With the limits infinite both do nothing.

Control laws (row ``LAW`` of the gains, evaluated at every RK4 stage):

- ``DRIVE_PID``: independent joint control on each drive's input, on the drive's own coordinate:
  the motor angle of a DC drive (q / r when rigid, q_M when flexible), the joint of a hydraulic
  one: u = kp e + kv de/dt + ki z, dz/dt = e (the integral stops while the input is clipped in
  the error's direction, so that it does not wind up);
- ``CURRENT_COMPUTED_TORQUE``: computed torque tau_c = M(q) (qdd_d + kv de/dt + kp e + ki z) + N(q, qd)
  on the joints, turned into current commands i_c = r tau_c / K_M (held within the current limit),
  and the armature equation inverted for the voltage: v = R_a i + K_b qd_M + L w_c (i_c - i), so
  that di/dt = w_c (i_c - i) until the voltage limit is reached (rigid DC drives).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from armdyn.dynamics.aba import aba_one
from armdyn.dynamics.packed import N_JOINTS
from armdyn.dynamics.rnea import inverse_dynamics_one
from armdyn.dynamics.spatial import NUMBA_OPTIONS
from armdyn.dynamics.status import OK
from armdyn.trajectories import desired

(DRIVE_KIND, RATIO, TORQUE_CONSTANT, BACK_EMF, RESISTANCE, INDUCTANCE, INPUT_LIMIT, CURRENT_LIMIT, ROTOR_INERTIA,
 ROTOR_VISCOUS, COULOMB_POSITIVE, COULOMB_NEGATIVE, STIFFNESS, SHAFT_DAMPING, VALVE_TIME, VALVE_GAIN, FLOW_GAIN,
 PRESSURE_COEFFICIENT, AREA, LEAKAGE, CAPACITANCE, SUPPLY, SQRT_ORIFICE, SQRT_GAIN, STROKE, ANGLE_AT, SPEED_AT,
 CURRENT_AT, SPOOL_AT, PRESSURE_AT, DRIVE_ROWS) = range(31)  # fmt: skip
"""The rows of the drives' parameter array, (DRIVE_ROWS, n); the *_AT rows hold each joint's index into x (-1: none)."""

RIGID, FLEXIBLE, HYDRAULIC = 0, 1, 2
"""The values of row DRIVE_KIND."""

DRIVE_PID, CURRENT_COMPUTED_TORQUE = 0, 1
"""The control laws."""

KP, KV, KI, BANDWIDTH = range(4)
"""The rows of the gains, (4, n), of the drive laws and (KP, KV, KI) of the joint laws (armdyn.control.joint)."""


@njit(inline="always", **NUMBA_OPTIONS)
def _held(rate: float, value: float, limit: float) -> float:
    """The rate of a state held within +-limit: zero where it would leave the range (the rate projected
    onto the box the limits bound, Dupuis and Nagurney 1993)."""
    return 0.0 if (value >= limit and rate > 0) or (value <= -limit and rate < 0) else rate


@njit(inline="always", **NUMBA_OPTIONS)
def clipped(value: float, limit: float) -> float:
    return min(max(value, -limit), limit)


@njit(inline="always", **NUMBA_OPTIONS)
def hold_limits(drives: np.ndarray, x: np.ndarray) -> None:
    """Put each DC drive's current back within +-i_max and each spool within +-stroke, in place: the
    state projected onto the box its limits bound (the hard stops of the saturated current loop and of
    the spool; a NaN stays NaN, so that a run that blows up is still seen)."""
    for j in range(drives.shape[1]):
        hydraulic = drives[DRIVE_KIND, j] == HYDRAULIC
        at = int(drives[SPOOL_AT, j]) if hydraulic else int(drives[CURRENT_AT, j])
        limit = drives[STROKE, j] if hydraulic else drives[CURRENT_LIMIT, j]
        if x[at] > limit:
            x[at] = limit
        elif x[at] < -limit:
            x[at] = -limit


@njit(inline="always", **NUMBA_OPTIONS)
def joint_torques(drives: np.ndarray, x: np.ndarray, tau: np.ndarray) -> None:
    """tau_j = (K_M / r) i (rigid DC), K (r q_M - q) + B_s (r qd_M - qd) (flexible), A P_L (hydraulic)."""
    n = tau.shape[0]
    for j in range(n):
        kind = drives[DRIVE_KIND, j]
        if kind == RIGID:
            tau[j] = drives[TORQUE_CONSTANT, j] * x[int(drives[CURRENT_AT, j])] / drives[RATIO, j]
        elif kind == FLEXIBLE:
            r, angle, speed = drives[RATIO, j], x[int(drives[ANGLE_AT, j])], x[int(drives[SPEED_AT, j])]
            tau[j] = drives[STIFFNESS, j] * (r * angle - x[j]) + drives[SHAFT_DAMPING, j] * (r * speed - x[n + j])
        else:
            tau[j] = drives[AREA, j] * x[int(drives[PRESSURE_AT, j])]


@njit(inline="always", **NUMBA_OPTIONS)
def _load_flow(drives: np.ndarray, j: int, spool: float, pressure: float) -> float:
    """Q_L = K_q x_v - K_c P_L, or C_d w x_v sgn(drop) sqrt(|drop| / rho), drop = P_s - sgn(x_v) P_L
    (Merritt 1967; the flow reverses where the load drives P_L past the supply)."""
    if drives[SQRT_ORIFICE, j] != 0:
        drop = drives[SUPPLY, j] - np.sign(spool) * pressure
        return drives[SQRT_GAIN, j] * spool * np.sign(drop) * np.sqrt(abs(drop))
    return drives[FLOW_GAIN, j] * spool - drives[PRESSURE_COEFFICIENT, j] * pressure


@njit(inline="always", **NUMBA_OPTIONS)
def full_rates(model: np.ndarray, drives: np.ndarray, x: np.ndarray, u: np.ndarray, tau: np.ndarray,
               out: np.ndarray) -> int:  # fmt: skip
    """xdot of the full model under the law's inputs u, the joint torques in ``tau``; u is left as applied
    (clipped to its limit, or a DC drive's voltage that holds its current at the current limit);
    returns the status of the forward dynamics (0, or M singular)."""
    n = int(model[N_JOINTS])
    joint_torques(drives, x, tau)
    status = aba_one(model, x[:n], x[n : 2 * n], tau, out[n : 2 * n])
    for j in range(n):
        out[j] = x[n + j]
        kind, r = drives[DRIVE_KIND, j], drives[RATIO, j]
        u_j = clipped(u[j], drives[INPUT_LIMIT, j])
        u[j] = u_j
        if kind == HYDRAULIC:
            s, p = int(drives[SPOOL_AT, j]), int(drives[PRESSURE_AT, j])
            spool_rate = (drives[VALVE_GAIN, j] * u_j - x[s]) / drives[VALVE_TIME, j]
            out[s] = _held(spool_rate, x[s], drives[STROKE, j])
            flow = _load_flow(drives, j, x[s], x[p])
            out[p] = (flow - drives[AREA, j] * x[n + j] - drives[LEAKAGE, j] * x[p]) / drives[CAPACITANCE, j]
            continue
        c = int(drives[CURRENT_AT, j])
        current = x[c]
        rotor_speed = x[n + j] / r
        if kind == FLEXIBLE:
            a, w = int(drives[ANGLE_AT, j]), int(drives[SPEED_AT, j])
            rotor_speed = x[w]
            friction = drives[COULOMB_POSITIVE, j] if rotor_speed > 0 else 0.0
            friction = drives[COULOMB_NEGATIVE, j] if rotor_speed < 0 else friction
            out[a] = rotor_speed
            out[w] = (drives[TORQUE_CONSTANT, j] * current - drives[ROTOR_VISCOUS, j] * rotor_speed - friction
                      - r * tau[j]) / drives[ROTOR_INERTIA, j]  # fmt: skip
        rate = (u_j - drives[RESISTANCE, j] * current - drives[BACK_EMF, j] * rotor_speed) / drives[INDUCTANCE, j]
        out[c] = _held(rate, current, drives[CURRENT_LIMIT, j])
        if out[c] == 0.0 and rate != 0.0:  # the current loop holds the current at its limit: v = R_a i + K_b qd_M
            u[j] = drives[RESISTANCE, j] * current + drives[BACK_EMF, j] * rotor_speed
    return status


@njit(inline="always", **NUMBA_OPTIONS)
def _drive_coordinate(drives: np.ndarray, reference: np.ndarray, x: np.ndarray, j: int, n: int) -> tuple:
    """(e, de/dt) of joint j's drive on its own coordinate: the motor angle of a DC drive (q / r, or
    q_M when flexible), the joint of a hydraulic one."""
    kind, r = drives[DRIVE_KIND, j], drives[RATIO, j]
    if kind == HYDRAULIC:
        return reference[0, j] - x[j], reference[1, j] - x[n + j]
    if kind == FLEXIBLE:
        return reference[0, j] / r - x[int(drives[ANGLE_AT, j])], reference[1, j] / r - x[int(drives[SPEED_AT, j])]
    return (reference[0, j] - x[j]) / r, (reference[1, j] - x[n + j]) / r


@njit(**NUMBA_OPTIONS)
def current_computed_torque(
    model: np.ndarray,
    drives: np.ndarray,
    gains: np.ndarray,
    reference: np.ndarray,
    x: np.ndarray,
    z: np.ndarray,
    u: np.ndarray,
    zdot: np.ndarray,
    work: np.ndarray,
) -> int:
    """CURRENT_COMPUTED_TORQUE's voltages u and integrator rates; the status of the inverse dynamics.
    ``work`` holds 2 n numbers."""
    n = u.shape[0]
    command, tau_c = work[:n], work[n:]
    for j in range(n):
        e, de = reference[0, j] - x[j], reference[1, j] - x[n + j]
        command[j] = reference[2, j] + gains[KV, j] * de + gains[KP, j] * e + gains[KI, j] * z[j]
        zdot[j] = e
    status = inverse_dynamics_one(model, x[:n], x[n : 2 * n], command, tau_c)
    for j in range(n):
        r, c = drives[RATIO, j], int(drives[CURRENT_AT, j])
        i_c = clipped(r * tau_c[j] / drives[TORQUE_CONSTANT, j], drives[CURRENT_LIMIT, j])
        u[j] = (drives[RESISTANCE, j] * x[c] + drives[BACK_EMF, j] * x[n + j] / r
                + drives[INDUCTANCE, j] * gains[BANDWIDTH, j] * (i_c - x[c]))  # fmt: skip
    return status


@njit(inline="always", **NUMBA_OPTIONS)
def drive_inputs(model: np.ndarray, drives: np.ndarray, gains: np.ndarray, law: int, reference: np.ndarray,
                 x: np.ndarray, z: np.ndarray, u: np.ndarray, zdot: np.ndarray, work: np.ndarray) -> int:  # fmt: skip
    """The law's inputs u (before the limits) and the integrators' rates zdot; the status of the
    inverse dynamics (computed torque), else OK."""
    if law != DRIVE_PID:
        return current_computed_torque(model, drives, gains, reference, x, z, u, zdot, work)
    n = u.shape[0]
    for j in range(n):
        e, de = _drive_coordinate(drives, reference, x, j, n)
        u[j] = gains[KP, j] * e + gains[KV, j] * de + gains[KI, j] * z[j]
        wound = abs(u[j]) >= drives[INPUT_LIMIT, j] and u[j] * e > 0
        zdot[j] = 0.0 if wound else e
    return OK


@njit(inline="always", **NUMBA_OPTIONS)
def closed_loop(model: np.ndarray, drives: np.ndarray, gains: np.ndarray, law: int, kind: int, params: np.ndarray,
                q0: np.ndarray, t: float, y: np.ndarray, u: np.ndarray, tau: np.ndarray, reference: np.ndarray,
                work: np.ndarray, out: np.ndarray, fresh: bool = True) -> int:  # fmt: skip
    """d/dt of y = [x, z] (the full state and the integrators) at time t under the law; u and tau are
    left as applied there. ``fresh`` False reuses ``reference`` (the same t as the last call)."""
    size = y.shape[0] - u.shape[0]
    if fresh:
        desired(kind, params, t, q0, reference)
    status = drive_inputs(model, drives, gains, law, reference, y[:size], y[size:], u, out[size:], work)
    if status != OK:
        return status
    return full_rates(model, drives, y[:size], u, tau, out[:size])
