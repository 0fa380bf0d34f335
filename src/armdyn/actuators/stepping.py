"""The arm with its drives integrated by compiled RK4 under a drive-level law (BOOK.md section 7)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from armdyn import inputs
from armdyn.actuators.motors import DCMotor
from armdyn.errors import ModelError

if TYPE_CHECKING:
    from armdyn.actuators.arm import ActuatedArm
    from armdyn.control.drives import CurrentComputedTorque, DrivePID


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


def _drive_table(arm: ActuatedArm) -> np.ndarray:
    """The drives' parameters packed for armdyn.dynamics.drives, (ROWS, n), with each joint's indices into x."""
    from armdyn.dynamics import drives as packed

    table = np.zeros((packed.ROWS, arm.n))
    kind = np.where(arm._is_dc, np.where(arm._rigid, packed.RIGID, packed.FLEXIBLE), packed.HYDRAULIC)
    rows = {
        packed.KIND: kind, packed.RATIO: arm._r, packed.TORQUE_CONSTANT: arm._K_M, packed.BACK_EMF: arm._K_b,
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


def stable_step(arm: ActuatedArm, q: object, bandwidth: object = None) -> float:
    """The RK4 step (s) that resolves the drives' fast dynamics near q: 0.5 / lambda for the fastest real
    pole and 0.15 / w for the fastest lightly damped oscillation.

    The real poles: the armatures R_a / L (or the current loops' w_c), the valves 1 / tau_v, each
    hydraulic joint's pressure pole K_ce / C and each joint's viscous b / m. The oscillations: each
    flexible shaft's sqrt(K / m') + B_s / m' (1/m' = 1/m + r^2 / J_M) and each hydraulic joint's
    oil column sqrt(A^2 / (C m)) (Merritt 1967), with m = 1 / (M(q)^-1)_jj the smallest inertia
    the joint's drive meets (BOOK.md section 7). At these steps RK4 (stable to about 2.8 / lambda)
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
        When q is not one configuration, or M(q) is singular.
    """
    q = inputs.state(q, arm.n, "q", arm._where)
    if q.shape != (arm.n,):
        raise ModelError(f"stable_step takes one configuration of {arm.n} values{arm._where}")
    inertia = arm._mechanical.inertia_matrix(q)
    if not np.linalg.cond(inertia) < 1e12:
        raise ModelError(f"M(q) is singular at q = {np.array2string(q, precision=6)}{arm._where}: the drives' time "
                         "constants need the inertia they move (start elsewhere)")  # fmt: skip
    mobility = np.diag(np.linalg.inv(inertia))  # 1/m_j
    d, f, h = arm._dc, arm._flex, arm._hyd
    electrical = arm._R_a[d] / arm._L[d] if bandwidth is None else np.maximum(arm._R_a / arm._L, bandwidth)[d]
    shaft = mobility[f] + arm._r[f] ** 2 / arm._J_M[f]
    real = [electrical, 1 / arm._tau_v[h], arm._K_ce[h] / arm._C[h], arm._mechanical.viscous_friction * mobility]
    shafts = arm._B_s[f] * shaft + np.sqrt(arm._K[f] * shaft)
    columns = np.sqrt(arm._A[h] ** 2 / arm._C[h] * mobility[h])
    fastest = [max((float(np.max(rates)) for rates in group if rates.size), default=0.0)
               for group in (real, [shafts, columns])]  # fmt: skip
    return min(0.5 / fastest[0] if fastest[0] > 0 else math.inf, 0.15 / fastest[1] if fastest[1] > 0 else math.inf)


def simulate(
    arm: ActuatedArm,
    controller: DrivePID | CurrentComputedTorque,
    trajectory: object = None,
    t_final: float = 5.0,
    dt: float = 1e-3,
    q0: object = None,
    qd0: object = None,
    step: float | None = None,
) -> object:
    """The arm driven through its drives' dynamics under a drive-level law (BOOK.md section 7).

    Integrates the full model x = [q, qd, q_M, qd_M, i, x_v, P_L] (and the law's integrators) by
    RK4 in one compiled call, the law evaluated at every stage, the inputs clipped to their limits
    and the currents and spools held within theirs. The drives are stiff (L/R is about a
    millisecond, an oil column rings at hundreds of hertz), and the method stays explicit RK4 with
    the step chosen from them (``stable_step`` at the start: half of L/R for a DC motor), so the run
    records every ``dt`` while integrating as finely as stability and accuracy need (``info["substeps"]``).
    ``armdyn.simulate(actuated_arm, ...)`` comes here.

    Parameters
    ----------
    arm : ActuatedArm
        The arm with its drives (DC drives need L > 0).
    controller : DrivePID or CurrentComputedTorque
        The law: PD/PID on each drive's input (any drives), or computed torque through current
        commands (rigid DC drives).
    trajectory : Sinusoid, Quintic or None, optional
        The desired joint path (armdyn.trajectories); None holds the start.
    t_final, dt : float, optional
        The run's length and the sample period (s).
    q0, qd0 : array_like, optional
        The start (default zeros); the drives start at rest relative to the links (``initial_state``).
    step : float or None, optional
        The largest RK4 step (s); None (default) takes it from the drives' time constants.

    Returns
    -------
    armdyn.simulation.Result
        Times, q, qd, qdd, the joint torques the drives deliver, q_d, and ``drives`` (a DriveRecord:
        the full state, the inputs applied, the currents, spools and load pressures).

    Raises
    ------
    armdyn.ModelError
        When a DC drive has no inductance, the controller is neither law (or computed torque meets
        a flexible or hydraulic drive), the trajectory is not one the compiled loop runs, an
        argument is invalid, or M(q) becomes singular or the state not finite during the run (the
        message says when).
    """
    from armdyn import trajectories
    from armdyn.control.drives import CurrentComputedTorque, DrivePID
    from armdyn.dynamics import drives as packed
    from armdyn.simulation import Result, _seconds

    if not callable(getattr(arm, "_check_full", None)):  # ActuatedArm (its module imports this one)
        raise ModelError(f"arm must be an ActuatedArm (armdyn.actuators.with_actuators), got {type(arm).__name__}")
    arm._check_full()
    n = arm.n
    if isinstance(controller, DrivePID):
        law, gains, bandwidth = packed.DRIVE_PID, np.vstack([controller.gains(n), np.zeros(n)]), None
    elif isinstance(controller, CurrentComputedTorque):
        others = [d.name for d in arm.drives if not (isinstance(d, DCMotor) and not d.flexible)]
        if others:
            raise ModelError(f"computed torque through current commands needs rigid DC drives; {others}{arm._where} "
                             "are flexible or hydraulic (use DrivePID)")  # fmt: skip
        law, gains = packed.CURRENT_COMPUTED_TORQUE, controller.gains(arm)
        bandwidth = gains[packed.BANDWIDTH]
    else:
        raise ModelError("controller must be an armdyn.control.DrivePID or CurrentComputedTorque, "
                         f"got {type(controller).__name__}")  # fmt: skip
    t_final, dt = _seconds(t_final, dt)
    spec = trajectories.packed(trajectory, n)
    if spec is None:
        raise ModelError("trajectory must be None, an armdyn.trajectories.Sinusoid or a Quintic")
    start = np.zeros(n) if q0 is None else inputs.state(q0, n, "q0", arm._where)
    rates = np.zeros(n) if qd0 is None else inputs.state(qd0, n, "qd0", arm._where)
    if start.shape != (n,) or rates.shape != (n,):
        raise ModelError(f"q0 and qd0 must be one state of {n} values{arm._where}")
    longest = stable_step(arm, start, bandwidth)
    if step is not None:
        longest = inputs.number(step, "step")
        if not (0 < longest < math.inf):
            raise ModelError(f"step must be a positive number of seconds, got {step}")
    samples, substeps = round(t_final / dt) + 1, max(1, math.ceil(dt / longest - 1e-9))
    x = arm.initial_state(start, rates)
    y = np.concatenate([x, np.zeros(n)])
    times, states = np.empty(samples), np.empty((samples, arm.n_states))
    applied, torques = np.empty((samples, n)), np.empty((samples, n))
    accelerations, references = np.empty((samples, n)), np.empty((samples, n))
    stopped = packed.run_drives(arm._mechanical.packed, _drive_table(arm), gains, law, spec[0], spec[1], start, y,
                                dt / substeps, substeps, times, states, applied, torques, accelerations,
                                references)  # fmt: skip
    if stopped >= 0:
        raise ModelError(f"the run{arm._where} stopped at t = {stopped * dt:.6g} s: M(q) became singular or the state "
                         "not finite (lower the gains, give a smaller step=, or check the drives' limits)")  # fmt: skip
    q, qd = states[:, :n], states[:, n : 2 * n]
    mechanical = arm._mechanical
    info = {"method": "rk4 (compiled, with the drives' dynamics)", "dt": dt, "substeps": substeps,
            "step": dt / substeps, "controller": controller.describe(),
            "trajectory": trajectories.describe_trajectory(trajectory)}  # fmt: skip
    desired_path = references if trajectory is not None else None
    result = Result(times, q, qd, accelerations, torques, desired_path, arm.robot, info,
                    lambda: mechanical.kinetic_energy(q, qd) + mechanical.potential_energy(q))  # fmt: skip
    part = arm._slices
    hydraulic = arm._hyd.size > 0
    result.drives = DriveRecord(arm.state_names, states, applied, states[:, part["i"]],
                                states[:, part["xv"]] if hydraulic else None,
                                states[:, part["PL"]] if hydraulic else None)  # fmt: skip
    return result
