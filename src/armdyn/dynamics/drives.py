"""The arm driven by DC motors with their electrics, compiled (BOOK.md section 7): the state
derivative of x = [q, qd, i] and a fixed-step RK4 run under independent-joint voltage PD control.

The arm's mechanics M qdd + Vm qd + F + G = tau carry the rotors and their friction (the Link
motor convention, packed as usual); each drive adds tau_j = (K_Mj / r_j) i_j and its armature
L_j di_j/dt + R_aj i_j + K_bj qd_j / r_j = v_j, with v clipped to the voltage limit and i held
within the current limit (armdyn.actuators.ActuatedArm.state_derivative is the NumPy version).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from armdyn.dynamics.aba import aba_one
from armdyn.dynamics.packed import N_JOINTS
from armdyn.dynamics.spatial import NUMBA_OPTIONS
from armdyn.trajectories import desired

RATIO, TORQUE_CONSTANT, BACK_EMF, RESISTANCE, INDUCTANCE, VOLTAGE_LIMIT, CURRENT_LIMIT = range(7)
"""The rows of the drives' parameter array, (7, n)."""


@njit(**NUMBA_OPTIONS)
def dc_rates(model: np.ndarray, drives: np.ndarray, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> int:
    """xdot of x = [q, qd, i] under the voltages v; the status of the forward dynamics (0, or M singular)."""
    n = int(model[N_JOINTS])
    tau = np.empty(n)
    for j in range(n):
        tau[j] = drives[TORQUE_CONSTANT, j] * x[2 * n + j] / drives[RATIO, j]
    status = aba_one(model, x[:n], x[n : 2 * n], tau, out[n : 2 * n])
    for j in range(n):
        out[j] = x[n + j]
        limit = drives[VOLTAGE_LIMIT, j]
        voltage = min(max(v[j], -limit), limit)
        current = x[2 * n + j]
        rotor_speed = x[n + j] / drives[RATIO, j]
        rate = (voltage - drives[RESISTANCE, j] * current - drives[BACK_EMF, j] * rotor_speed) / drives[INDUCTANCE, j]
        held = drives[CURRENT_LIMIT, j]
        out[2 * n + j] = 0.0 if (current >= held and rate > 0) or (current <= -held and rate < 0) else rate
    return status


@njit(inline="always", **NUMBA_OPTIONS)
def voltage_pd(gains: np.ndarray, ratios: np.ndarray, reference: np.ndarray, x: np.ndarray, v: np.ndarray) -> None:
    """v = kp (q_Md - q_M) + kv (qd_Md - qd_M), q_M = q / r: independent joint control on each motor's
    voltage, on the motor's own angle (BOOK.md section 7)."""
    n = v.shape[0]
    for j in range(n):
        error = (reference[0, j] - x[j]) / ratios[j]
        rate = (reference[1, j] - x[n + j]) / ratios[j]
        v[j] = gains[0, j] * error + gains[1, j] * rate


@njit(**NUMBA_OPTIONS)
def run_voltage_pd(
    model: np.ndarray,
    drives: np.ndarray,
    gains: np.ndarray,
    kind: int,
    params: np.ndarray,
    q0: np.ndarray,
    x: np.ndarray,
    h: float,
    substeps: int,
    first: int,
    last: int,
    times: np.ndarray,
    states: np.ndarray,
    voltages: np.ndarray,
    accelerations: np.ndarray,
    references: np.ndarray,
) -> int:
    """RK4 from sample ``first`` to ``last`` (exclusive), ``substeps`` steps of h between samples, the
    controller evaluated at every stage; records each sample. Returns -1, or the sample where M(q)
    was singular or the state stopped being finite."""
    n, size = int(model[N_JOINTS]), x.shape[0]
    k1, k2, k3, k4, stage = np.empty(size), np.empty(size), np.empty(size), np.empty(size), np.empty(size)
    v, reference = np.empty(n), np.empty((3, n))
    for sample in range(first, last):
        t = sample * substeps * h
        desired(kind, params, t, q0, reference)
        voltage_pd(gains, drives[RATIO], reference, x, v)
        times[sample] = t
        states[sample] = x
        voltages[sample] = v
        references[sample] = reference[0]
        if dc_rates(model, drives, x, v, k1) != 0:
            return sample
        accelerations[sample] = k1[n : 2 * n]
        for j in range(size):
            if not np.isfinite(x[j]):
                return sample
        if sample == states.shape[0] - 1:
            break
        for step in range(substeps):
            s = t + step * h
            if step > 0:
                desired(kind, params, s, q0, reference)
                voltage_pd(gains, drives[RATIO], reference, x, v)
                if dc_rates(model, drives, x, v, k1) != 0:
                    return sample
            for j in range(size):
                stage[j] = x[j] + 0.5 * h * k1[j]
            desired(kind, params, s + 0.5 * h, q0, reference)
            voltage_pd(gains, drives[RATIO], reference, stage, v)
            if dc_rates(model, drives, stage, v, k2) != 0:
                return sample
            for j in range(size):
                stage[j] = x[j] + 0.5 * h * k2[j]
            voltage_pd(gains, drives[RATIO], reference, stage, v)
            if dc_rates(model, drives, stage, v, k3) != 0:
                return sample
            for j in range(size):
                stage[j] = x[j] + h * k3[j]
            desired(kind, params, s + h, q0, reference)
            voltage_pd(gains, drives[RATIO], reference, stage, v)
            if dc_rates(model, drives, stage, v, k4) != 0:
                return sample
            for j in range(size):
                x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
    return -1
