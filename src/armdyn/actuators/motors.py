"""The armature-controlled DC motor behind a gear, with an optional flexible shaft (Lewis, Dawson and
Abdallah 2004, Section 3.6), its transfer function and Example 3.6-1."""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass

import numpy as np

from armdyn.actuators.checks import _coulomb, _drive_name, _limit, _non_negative, _positive, _value
from armdyn.errors import ArgumentError, ModelError


@dataclass(frozen=True)
class DCMotor:
    """An armature-controlled DC motor with a gear, optionally with a flexible shaft (Section 3.6).

    Electrical: L di/dt + R_a i + K_b qd_M = v; mechanical: J_M qdd_M + B_M qd_M + F_M + r tau =
    K_M i, with tau the torque (force) the gear delivers to the link. The gear follows the book:
    q = r q_M, so r < 1 for a reducing revolute gear, and r is in m/rad for a prismatic joint (a
    screw). This r is 1/G of the Robotics Toolbox's and of armdyn's Link (Jm, G) convention: a
    Toolbox motor with G = 62.6 is ``gear_ratio=1/62.6`` here; a negative ratio reverses the motor.

    With ``stiffness`` the shaft between the gear output and the link is a spring K and damper
    B_s: tau = K (r q_M - q) + B_s (r qd_M - qd) (the book's tau = B_s (qd_M - qd) + K (q_M - q)
    with the gear put in), and the motor angle q_M becomes a state of the full model.

    Parameters
    ----------
    rotor_inertia : float
        J_M, the rotor's inertia, kg m^2, >= 0 (> 0 with a flexible shaft).
    viscous : float
        B_M, the rotor's viscous friction, N m s/rad, >= 0.
    torque_constant : float
        K_M, N m/A, > 0.
    back_emf : float
        K_b, V s/rad, > 0 (equal to K_M in SI units for an ideal motor).
    resistance : float
        R_a, the armature resistance, ohm, > 0.
    inductance : float
        L, the armature inductance, H, >= 0 (the full model needs L > 0; L = 0 is the reduced
        model's assumption).
    gear_ratio : float
        r with q = r q_M: dimensionless for a revolute joint, m/rad for a prismatic one; finite
        and non-zero.
    voltage_limit : float, optional
        |v| <= voltage_limit, V (default math.inf: none). The input is clipped to it.
    current_limit : float, optional
        |i| <= current_limit, A (default math.inf: none). The amplifier is a saturated current loop:
        at the limit, where the voltage would push the current out, it applies the voltage that holds
        it, R_a i + K_b qd_M (di/dt = 0), and a simulation keeps the current within the limit at every
        RK4 stage (armdyn.dynamics.drives).
    coulomb : float or (float, float), optional
        F_M, Coulomb friction on the rotor, N m: a magnitude c (c for positive and -c for negative
        rotor velocity qd_M) or a pair (Tc+, Tc-) with Tc+ >= 0 >= Tc- (default 0).
    stiffness : float or None, optional
        K, the shaft's stiffness at the link side, N m/rad (N/m prismatic), > 0; None (default)
        for a rigid shaft.
    shaft_damping : float, optional
        B_s, the shaft's damping at the link side, N m s/rad (N s/m prismatic), >= 0 (default 0);
        only with ``stiffness``.
    name : str, optional
        The drive's name, used in messages (default "motor").

    Raises
    ------
    armdyn.ModelError
        When a parameter is not a finite real number (a limit may be math.inf) or breaks its sign
        rule: R_a > 0, L >= 0, J_M >= 0, B_M >= 0, K_M > 0, K_b > 0, r != 0, limits > 0,
        Tc+ >= 0 >= Tc-, K > 0, B_s >= 0; when ``shaft_damping`` is given without ``stiffness``,
        or a flexible shaft drives a rotor without inertia; the message names the drive and the rule.
    """

    rotor_inertia: float
    viscous: float
    torque_constant: float
    back_emf: float
    resistance: float
    inductance: float
    gear_ratio: float
    voltage_limit: float = math.inf
    current_limit: float = math.inf
    coulomb: float | tuple[float, float] = 0.0
    stiffness: float | None = None
    shaft_damping: float = 0.0
    name: str = "motor"

    def __post_init__(self) -> None:
        where = f"drive '{_drive_name(self.name)}'"
        checked = {
            "rotor_inertia": _non_negative(self.rotor_inertia, "rotor inertia J_M", where),
            "viscous": _non_negative(self.viscous, "viscous friction B_M", where, " (dissipative)"),
            "torque_constant": _positive(self.torque_constant, "torque constant K_M", where),
            "back_emf": _positive(self.back_emf, "back-emf constant K_b", where),
            "resistance": _positive(self.resistance, "armature resistance R_a", where),
            "inductance": _non_negative(self.inductance, "armature inductance L", where),
            "gear_ratio": _value(self.gear_ratio, "gear ratio r", where),
            "voltage_limit": _limit(self.voltage_limit, "voltage limit", where),
            "current_limit": _limit(self.current_limit, "current limit", where),
            "coulomb": _coulomb(self.coulomb, where),
            "shaft_damping": _non_negative(self.shaft_damping, "shaft damping B_s", where, " (dissipative)"),
        }
        if checked["gear_ratio"] == 0:
            raise ModelError(f"{where}: gear ratio r (q = r q_M) must be non-zero, got 0")
        if self.stiffness is not None:
            checked["stiffness"] = _positive(self.stiffness, "shaft stiffness K", where)
            if checked["rotor_inertia"] == 0:
                raise ModelError(f"{where}: a flexible shaft needs a rotor inertia J_M > 0 (the rotor is a body)")
        elif checked["shaft_damping"] != 0:
            raise ModelError(f"{where}: shaft damping B_s needs a shaft stiffness K (stiffness=...)")
        for key, value in checked.items():
            object.__setattr__(self, key, value)

    @property
    def flexible(self) -> bool:
        """True when the shaft is a spring (``stiffness`` given)."""
        return self.stiffness is not None


# ----- Example 3.6-1 ----------------------------------------------------------------------------------------
def transfer_function(motor: DCMotor, load_inertia: float, load_damping: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """H(s) = qd(s) / v(s): one DC motor driving an inertia through its gear (Section 3.6).

    Rigid shaft (Example 3.6-1): H = r K_M / ((L s + R_a)(J s + b) + K_M K_b) with the inertia and
    damping at the rotor J = J_M + r^2 J_L, b = B_M + r^2 b_L. Flexible shaft (K, B_s at the link
    side): with P = J_L s^2 + (b_L + B_s) s + K and Q = (J_M s + B_M) P + r^2 (B_s s + K)(J_L s + b_L),
    H = r K_M (B_s s + K) / ((L s + R_a) Q + K_M K_b P), fourth order. Coulomb friction and the
    limits are left out (they are not linear).

    Parameters
    ----------
    motor : DCMotor
        The motor, its gear and shaft.
    load_inertia : float
        J_L, the load's inertia about the joint, kg m^2 (kg prismatic), > 0.
    load_damping : float, optional
        b_L, the load's viscous friction at the joint, >= 0 (default 0).

    Returns
    -------
    tuple of numpy.ndarray
        (numerator, denominator): polynomial coefficients in s, highest power first, the
        denominator monic (as ``control.tf`` takes them).

    Raises
    ------
    armdyn.ModelError
        When the load's inertia is not positive or its damping negative.
    armdyn.ArgumentError
        When ``motor`` is not a DCMotor (a ModelError and a TypeError).
    """
    if not isinstance(motor, DCMotor):
        raise ArgumentError(f"motor must be a DCMotor, got {reprlib.repr(motor)}")
    J_L = _positive(load_inertia, "load inertia J_L", f"load of drive '{motor.name}'")
    b_L = _non_negative(load_damping, "load damping b_L", f"load of drive '{motor.name}'")
    r, J_M, B_M, K_M, K_b = motor.gear_ratio, motor.rotor_inertia, motor.viscous, motor.torque_constant, motor.back_emf
    electrical = np.array([motor.inductance, motor.resistance])
    if not motor.flexible:
        rotor = np.array([J_M + r**2 * J_L, B_M + r**2 * b_L])
        numerator, denominator = np.array([r * K_M]), np.polyadd(np.polymul(electrical, rotor), [K_M * K_b])
    else:
        shaft = np.array([motor.shaft_damping, motor.stiffness])
        P = np.array([J_L, b_L + motor.shaft_damping, motor.stiffness])
        Q = np.polyadd(np.polymul([J_M, B_M], P), r**2 * np.polymul(shaft, [J_L, b_L]))
        numerator = r * K_M * shaft
        denominator = np.polyadd(np.polymul(electrical, Q), K_M * K_b * P)
    denominator = np.trim_zeros(denominator, "f")
    return numerator / denominator[0], denominator / denominator[0]


def example_3_6_1(flexible: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Example 3.6-1: a DC motor driving a load, H(s) = k_m / ((L s + R)(J s + b_m) + k_m k'_m).

    J_m = J_L = 0.1 (so J = J_m + J_L = 0.2), b_m = 0.2 on the motor, k_m = k'_m = 1, L = 0.5,
    R = 5, direct drive: H = 1 / (0.1 s^2 + 1.1 s + 2) = 10 / (s^2 + 11 s + 20)
    = 10 / ((s + 2.298)(s + 8.702)), the book's 10 / ((s + 2.3)(s + 8.7)) (Section 3.6).
    ``flexible``: the shaft is a spring k = 2 with damping b = 0.2 between motor and load, and
    H, from voltage to load speed, is fourth order (see ``transfer_function``).

    Parameters
    ----------
    flexible : bool, optional
        The flexible-shaft case (default False).

    Returns
    -------
    tuple of numpy.ndarray
        (numerator, denominator), highest power first, the denominator monic.

    Raises
    ------
    armdyn.ModelError
        Never for these numbers (``transfer_function``'s checks).
    """
    shaft = {"stiffness": 2.0, "shaft_damping": 0.2} if flexible else {}
    motor = DCMotor(0.1, 0.2, 1.0, 1.0, 5.0, 0.5, 1.0, **shaft, name="Example 3.6-1 motor")
    return transfer_function(motor, load_inertia=0.1)
