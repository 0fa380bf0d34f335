"""Drive-level laws (Section 3.6): independent joint PID on each drive's input and computed torque
through current commands; their compiled forms are in armdyn.dynamics.drives, which the simulation's
stepper evaluates at every RK4 stage. ``drive_law`` gives the stepper a law's code and gains."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from armdyn import inputs
from armdyn.actuators.arm import ActuatedArm
from armdyn.actuators.motors import DCMotor
from armdyn.dynamics import drives as compiled
from armdyn.errors import ArgumentError, ModelError

if TYPE_CHECKING:
    from armdyn.simulation import DrivenPlant


@dataclass(frozen=True)
class DrivePID:
    """Independent joint control on each drive's input (Section 3.6): u = kp e + kv de/dt + ki z,
    dz/dt = e, with e the error on the drive's own coordinate.

    For a DC drive u is the voltage and e the motor angle's error: (q_d - q) / r for a rigid
    shaft, q_d / r - q_M for a flexible one (the collocated motor angle). For a hydraulic drive u
    is the valve current and e the joint's error. Each drive sees only its own error; the coupling
    from the other joints acts as a disturbance (the book's d_i), which the integral removes at
    rest. The integral stops while the input is clipped at its limit in the error's direction
    (no wind-up). Gains in V (or A) per rad of the drive's coordinate, per rad/s, per rad s: with
    r = 1/62, 1 mrad at the joint is 62 mrad at the motor.

    Parameters
    ----------
    kp, kv : float or array_like
        The proportional and derivative gains, one value or one per joint, at least 0.
    ki : float or array_like, optional
        The integral gain (default 0: PD).
    """

    kp: object
    kv: object
    ki: object = 0.0

    def gains(self, n: int) -> np.ndarray:
        """(3, n): kp, kv and ki for n joints.

        Parameters
        ----------
        n : int
            The number of joints.

        Returns
        -------
        numpy.ndarray
            The gains, rows kp, kv, ki.

        Raises
        ------
        armdyn.ModelError
            When a gain is not one or n finite numbers at least 0.
        """
        named = ((self.kp, "kp"), (self.kv, "kv"), (self.ki, "ki"))
        return np.stack([inputs.gains(gain, name, n) for gain, name in named])

    def drive_law(self, arm: DrivenPlant) -> tuple[int, np.ndarray, np.ndarray | None]:
        """The compiled law's code, its gains (4, n: kp, kv, ki and an unused row) and no current loop.

        Parameters
        ----------
        arm : ActuatedArm or DrivenPlant
            The arm whose drives the law drives (its number of joints is read).

        Returns
        -------
        tuple
            (armdyn.dynamics.drives.DRIVE_PID, gains (4, n), None).

        Raises
        ------
        armdyn.ModelError
            When a gain is not one or n finite numbers at least 0.
        """
        return compiled.DRIVE_PID, np.vstack([self.gains(arm.n), np.zeros(arm.n)]), None

    def describe(self) -> str:
        """The law and its gains, for titles and reports.

        Returns
        -------
        str
            A short description.

        Raises
        ------
        None
            It only formats the gains.
        """
        kind = "PID" if np.any(np.asarray(self.ki, dtype=float) != 0) else "PD"
        integral = f", ki = {self.ki}" if kind == "PID" else ""
        return f"independent joint {kind} on the drives' inputs (kp = {self.kp}, kv = {self.kv}{integral})"


@dataclass(frozen=True)
class CurrentComputedTorque:
    """Computed torque turned into current commands through the motor model (Sections 3.4 and 3.6).

    The outer loop is the arm's computed torque on the joints, tau_c = M(q) (qdd_d + kv de/dt +
    kp e + ki z) + N(q, qd) with e = q_d - q, from the mechanical model (links and rotors); each
    rigid DC drive turns its torque into the current command i_c = r tau_c / K_M (held within the
    current limit), and the armature equation is inverted for the voltage,
    v = R_a i + K_b qd_M + L w_c (i_c - i), so that di/dt = w_c (i_c - i): the current follows its
    command with the bandwidth w_c until the voltage limit is reached. With w_c large against
    the arm's motion this is the torque-controlled arm of Chapter 4's computed torque.

    Parameters
    ----------
    kp, kv : float or array_like
        Joint gains (1/s^2, 1/s), one value or one per joint, at least 0.
    ki : float or array_like, optional
        Integral gain (1/s^3), default 0.
    bandwidth : float or array_like or None, optional
        w_c, the current loop's bandwidth (rad/s), > 0; None (default) takes each drive's R_a / L.
    """

    kp: object
    kv: object
    ki: object = 0.0
    bandwidth: object = None

    def gains(self, arm: ActuatedArm) -> np.ndarray:
        """(4, n): kp, kv, ki and w_c for the arm's joints.

        Parameters
        ----------
        arm : ActuatedArm
            The arm whose drives set the default bandwidth R_a / L.

        Returns
        -------
        numpy.ndarray
            The gains, rows kp, kv, ki, w_c.

        Raises
        ------
        armdyn.ModelError
            When a gain is not one or n finite numbers at least 0, or a bandwidth is not positive.
        """
        n = arm.n
        named = ((self.kp, "kp"), (self.kv, "kv"), (self.ki, "ki"))
        rows = [inputs.gains(gain, name, n) for gain, name in named]
        if self.bandwidth is None:
            rows.append(arm._R_a / arm._L)
        else:
            bandwidth = inputs.gains(self.bandwidth, "bandwidth", n)
            if np.any(bandwidth <= 0):
                raise ModelError(f"bandwidth (the current loop's, rad/s) must be positive, got {self.bandwidth}")
            rows.append(bandwidth)
        return np.stack(rows)

    def drive_law(self, arm: ActuatedArm) -> tuple[int, np.ndarray, np.ndarray | None]:
        """The compiled law's code, its gains (4, n: kp, kv, ki, w_c) and the current loops' bandwidths.

        Parameters
        ----------
        arm : ActuatedArm
            The arm, whose drives must all be rigid DC drives.

        Returns
        -------
        tuple
            (armdyn.dynamics.drives.CURRENT_COMPUTED_TORQUE, gains (4, n), w_c (n,)).

        Raises
        ------
        armdyn.ModelError
            When a drive is flexible or hydraulic, a gain is not one or n finite numbers at least 0, or a
            bandwidth is not positive.
        """
        others = [d.name for d in arm.drives if not (isinstance(d, DCMotor) and not d.flexible)]
        if others:
            raise ModelError(f"computed torque through current commands needs rigid DC drives; {others}{arm._where} "
                             "are flexible or hydraulic (use DrivePID)")  # fmt: skip
        gains = self.gains(arm)
        return compiled.CURRENT_COMPUTED_TORQUE, gains, gains[compiled.BANDWIDTH]

    def describe(self) -> str:
        """The law and its gains, for titles and reports.

        Returns
        -------
        str
            A short description.

        Raises
        ------
        None
            It only formats the gains.
        """
        loop = "R_a/L" if self.bandwidth is None else f"{self.bandwidth} rad/s"
        return (f"computed torque through current commands (kp = {self.kp}, kv = {self.kv}, ki = {self.ki}; "
                f"current loop {loop})")  # fmt: skip


VoltagePD = DrivePID
"""The PD on the motor voltages: DrivePID without the integral (kept as the book's name for it)."""


def drive_law(controller: object, arm: DrivenPlant) -> tuple[int, np.ndarray, np.ndarray | None]:
    """The compiled drive-level law of ``controller`` for ``arm`` (see ``DrivePID.drive_law``).

    Parameters
    ----------
    controller : DrivePID or CurrentComputedTorque
        The drive-level law.
    arm : ActuatedArm or DrivenPlant
        The arm with its drives (CurrentComputedTorque reads the motors of an armdyn ActuatedArm).

    Returns
    -------
    tuple
        (the law's code in armdyn.dynamics.drives, gains (4, n), the current loops' w_c (n,) or None).

    Raises
    ------
    armdyn.ArgumentError
        When the controller is not a drive-level law, or CurrentComputedTorque meets a plant that is not
        an ActuatedArm.
    armdyn.ModelError
        As the law's ``drive_law``.
    """
    if isinstance(controller, DrivePID):
        return controller.drive_law(arm)
    if not isinstance(controller, CurrentComputedTorque):
        raise ArgumentError("an arm with drives runs a drive-level law: controller must be an armdyn.control.DrivePID "
                            f"or CurrentComputedTorque, got {type(controller).__name__}")  # fmt: skip
    inputs.arm_argument(arm, ActuatedArm, "arm", why=" (computed torque through current commands)")
    assert isinstance(arm, ActuatedArm), "arm_argument refused any other plant"
    return controller.drive_law(arm)
