"""The arm with its drives as the compiled stepper takes it (Lewis, Dawson and Abdallah 2004,
Section 3.6): the drives' parameters packed,
the RK4 step their time constants allow, and the record of what they did during a run."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from armdyn import inputs
from armdyn.errors import ModelError, SingularError

if TYPE_CHECKING:
    from armdyn.actuators.arm import ActuatedArm


@dataclass(frozen=True)
class DriveRecord:
    """What the drives did during a run (``Result.drives``), time first.

    Parameters
    ----------
    names : list of str
        The full model's state names (``ActuatedArm.state_names``).
    x : numpy.ndarray
        The full state at every sample, (T, n_states).
    v : numpy.ndarray
        The inputs applied (after the limits), (T, n): volts, or valve amperes.
    i : numpy.ndarray
        The armature currents of the DC drives, (T, number of DC drives), A.
    spool : numpy.ndarray or None, optional
        The spool positions x_v of the hydraulic drives, (T, number of hydraulic drives), m.
    pressure : numpy.ndarray or None, optional
        Their load pressures P_L, (T, number of hydraulic drives), Pa.
    """

    names: list
    x: np.ndarray
    v: np.ndarray
    i: np.ndarray
    spool: np.ndarray | None = None
    pressure: np.ndarray | None = None


def packed_drives(arm: ActuatedArm) -> np.ndarray:
    """The drives' parameters packed for armdyn.dynamics.drives, (ROWS, n), with each joint's indices into x."""
    from armdyn.dynamics import drives as packed

    table = np.zeros((packed.DRIVE_ROWS, arm.n))
    kind = np.where(arm._is_dc, np.where(arm._rigid, packed.RIGID, packed.FLEXIBLE), packed.HYDRAULIC)
    rows = {
        packed.DRIVE_KIND: kind, packed.RATIO: arm._r, packed.TORQUE_CONSTANT: arm._K_M, packed.BACK_EMF: arm._K_b,
        packed.RESISTANCE: arm._R_a, packed.INDUCTANCE: arm._L, packed.INPUT_LIMIT: arm._u_max,
        packed.CURRENT_LIMIT: arm._i_max, packed.ROTOR_INERTIA: arm._J_M, packed.ROTOR_VISCOUS: arm._B_M,
        packed.COULOMB_POSITIVE: arm._Tc_pos, packed.COULOMB_NEGATIVE: arm._Tc_neg, packed.STIFFNESS: arm._K,
        packed.SHAFT_DAMPING: arm._B_s, packed.VALVE_TIME: arm._tau_v, packed.VALVE_GAIN: arm._K_v,
        packed.FLOW_GAIN: arm._K_q, packed.PRESSURE_COEFFICIENT: arm._K_c, packed.AREA: arm._A,
        packed.LEAKAGE: arm._C_tp, packed.CAPACITANCE: arm._C, packed.SUPPLY: arm._P_s,
        packed.SQRT_ORIFICE: arm._sqrt, packed.SQRT_GAIN: arm._sqrt_gain, packed.STROKE: arm._stroke,
    }  # fmt: skip
    for row, values in rows.items():
        table[row] = values
    for row, key, joints in ((packed.ANGLE_AT, "qM", arm._flex), (packed.SPEED_AT, "qdM", arm._flex),
                             (packed.CURRENT_AT, "i", arm._dc), (packed.SPOOL_AT, "xv", arm._hyd),
                             (packed.PRESSURE_AT, "PL", arm._hyd)):  # fmt: skip
        table[row] = -1
        table[row, joints] = np.arange(arm._slices[key].start, arm._slices[key].stop)
    return table


def stable_step(arm: ActuatedArm, q: ArrayLike, bandwidth: ArrayLike | None = None) -> float:
    """The RK4 step (s) that resolves the drives' fast dynamics near q: 0.5 / lambda for the fastest real
    pole and 0.15 / w for the fastest lightly damped oscillation.

    The real poles: the armatures R_a / L (or the current loops' w_c), the valves 1 / tau_v, each
    hydraulic joint's pressure pole K_ce / C and each joint's viscous b / m. The oscillations: each
    flexible shaft's sqrt(K / m') + B_s / m' (1/m' = 1/m + r^2 / J_M) and each hydraulic joint's
    oil column sqrt(A^2 / (C m)) (Merritt 1967), with m = 1 / (M(q)^-1)_jj the smallest inertia
    the joint's drive meets (Section 3.6). At these steps RK4 (stable to about 2.8 / lambda)
    keeps a first-order transient to about 1e-4 per time constant and an oscillation's phase to
    about 1e-5 per step. ``simulate`` takes its step from here at the start.

    Parameters
    ----------
    arm : ActuatedArm
        The arm with its drives.
    q : array_like
        One configuration, (n,).
    bandwidth : array_like or None, optional
        The current loops' w_c (n values), when a law closes them.

    Returns
    -------
    float
        The step, s (math.inf when nothing is fast: no drive dynamics).

    Raises
    ------
    armdyn.ModelError
        When q is not one configuration.
    armdyn.SingularError
        When M(q) is singular (or too ill-conditioned) at q.
    """
    q = inputs.state(q, arm.n, "q", arm._where)
    if q.shape != (arm.n,):
        raise ModelError(
            f"q must be one configuration of {arm.n} values for stable_step{arm._where}, got shape {q.shape}"
        )
    inertia = arm._mechanical.inertia_matrix(q)
    condition = float(np.linalg.cond(inertia))
    if not condition < 1e12:
        raise SingularError(f"M(q) is singular at q = {np.array2string(q, precision=6)}{arm._where}: the drives' "
                            "time constants need the inertia they move (start elsewhere)", state=q,
                            condition=condition)  # fmt: skip
    mobility = np.diag(np.linalg.inv(inertia))  # 1/m_j
    d, f, h = arm._dc, arm._flex, arm._hyd
    if bandwidth is not None:
        bandwidth = inputs.numbers(bandwidth, "bandwidth", None, arm._where)
        if bandwidth.shape not in ((), (arm.n,)):
            raise ModelError(f"bandwidth must be one number or one per joint ({arm.n}){arm._where}, got shape "
                             f"{bandwidth.shape}")  # fmt: skip
        bandwidth = np.broadcast_to(bandwidth, (arm.n,))
        if not np.all(bandwidth > 0):
            raise ModelError(f"bandwidth must be positive (rad/s, one per joint){arm._where}, got {bandwidth}")
    electrical = arm._R_a[d] / arm._L[d] if bandwidth is None else np.maximum(arm._R_a / arm._L, bandwidth)[d]
    shaft = mobility[f] + arm._r[f] ** 2 / arm._J_M[f]
    real = [electrical, 1 / arm._tau_v[h], arm._K_ce[h] / arm._C[h], arm._mechanical.viscous_friction * mobility]
    shafts = arm._B_s[f] * shaft + np.sqrt(arm._K[f] * shaft)
    columns = np.sqrt(arm._A[h] ** 2 / arm._C[h] * mobility[h])
    fastest = [max((float(np.max(rates)) for rates in group if rates.size), default=0.0)
               for group in (real, [shafts, columns])]  # fmt: skip
    return min(0.5 / fastest[0] if fastest[0] > 0 else math.inf, 0.15 / fastest[1] if fastest[1] > 0 else math.inf)


def drive_record(arm: ActuatedArm, states: np.ndarray, applied: np.ndarray) -> DriveRecord:
    """The DriveRecord of a run from its full states (T, n_states) and the inputs applied (T, n)."""
    part = arm._slices
    hydraulic = arm._hyd.size > 0
    return DriveRecord(arm.state_names, states, applied, states[:, part["i"]],
                       states[:, part["xv"]] if hydraulic else None,
                       states[:, part["PL"]] if hydraulic else None)  # fmt: skip
