"""Actuator dynamics and the arm-plus-actuator system (BOOK.md section 7, the book's Section 3.6).

Drives:

- ``DCMotor``: an armature-controlled DC motor behind a gear q = r q_M (the book's ratio r,
  which is 1/G of the Robotics Toolbox's and of armdyn's Link convention), with an optional
  flexible shaft (a spring and damper between the gear output and the link);
- ``Hydraulic``: a servo valve and a piston (or rotary motor) after Merritt (1967), with the
  linearized or the square-root orifice flow.

``with_actuators(robot, drives)`` joins them to an arm as an ``ActuatedArm``:

- the reduced model (inductance, valve dynamics and oil compressibility neglected), written
  in the link coordinates q as joint torques (each row multiplied by r_i^-2 from the book's
  printed form, see ActuatedArm):

      M'(q) qdd + V'(q, qd) qd + F'(qd) + G'(q) = K' v
      M' = M + R^-2 J_M,   V' = Vm,   F' = F + R^-1 F_M + R^-2 B qd,   G' = G,   K' = R^-1 K_M

  with B = diag(B_Mi + K_bi K_Mi / R_ai) and K_M = diag(K_Mi / R_ai); a hydraulic joint adds the
  damping A^2 / (K_c + C_tp) and the gain A K_q K_v / (K_c + C_tp);
- the full model, third order in the electrics: states [q, qd, q_M, qd_M, i, x_v, P_L]
  (motor angles for the flexible drives, currents for the DC drives, valve positions and load
  pressures for the hydraulic ones), ``state_derivative``, ``linearize`` and ``to_control``.

Units are SI: rad, m, s, A, V, Pa, m^3. Every array method takes one state or a batch
(leading axes) and returns the matching shape; the batch goes to the Robot's batched kernels
in one call.
"""

from __future__ import annotations

import dataclasses
import math
import reprlib
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armdyn import inputs
from armdyn.errors import ModelError
from armdyn.model.arm import Link
from armdyn.robot import Robot

__all__ = [
    "ActuatedArm",
    "CurrentComputedTorque",
    "DCMotor",
    "DrivePID",
    "DriveRecord",
    "Hydraulic",
    "VoltagePD",
    "example_3_6_1",
    "motor_drives",
    "puma560",
    "representative_drives",
    "rk4_step",
    "simulate",
    "transfer_function",
    "with_actuators",
]

_STEP = float(np.finfo(float).eps) ** (1 / 3)
"""The relative step of the central differences in ``ActuatedArm.linearize``."""


# ----- checks of drive parameters -----------------------------------------------------------------
def _drive_name(name: object) -> str:
    if not isinstance(name, str) or not name:
        raise ModelError(f"a drive's name must be a non-empty str, got {reprlib.repr(name)}")
    return name


def _value(value: object, what: str, where: str) -> float:
    """A finite real number or a ModelError naming the quantity and the drive."""
    return inputs.number(value, what, f" ({where})")


def _positive(value: object, what: str, where: str, why: str = "") -> float:
    number = _value(value, what, where)
    if not number > 0:
        raise ModelError(f"{where}: {what} must be positive{why}, got {number:g}")
    return number


def _non_negative(value: object, what: str, where: str, why: str = "") -> float:
    number = _value(value, what, where)
    if number < 0:
        raise ModelError(f"{where}: {what} must be >= 0{why}, got {number:g}")
    return number


def _limit(value: object, what: str, where: str) -> float:
    """A positive limit; infinity (the default) for none."""
    if isinstance(value, (int, float, np.floating)) and not isinstance(value, bool) and value == math.inf:
        return math.inf
    return _positive(value, what, where, " (math.inf for none)")


def _coulomb(value: object, where: str) -> tuple[float, float]:
    """(Tc+, Tc-) from a magnitude c >= 0 (meaning (c, -c)) or a pair with Tc+ >= 0 >= Tc-."""
    array = inputs.numbers(value, "Coulomb friction", where=f" ({where})")
    if array.shape == () and array >= 0:
        array = np.array([array, -array])
    if array.shape != (2,) or array[0] < 0 or array[1] > 0:
        raise ModelError(
            f"{where}: Coulomb friction must be a magnitude c >= 0 or a pair (Tc+, Tc-) with Tc+ >= 0 >= Tc-, "
            f"got {reprlib.repr(value)}"
        )
    return float(array[0]), float(array[1])


# ----- the drives -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class DCMotor:
    """An armature-controlled DC motor with a gear, optionally with a flexible shaft (BOOK.md section 7).

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
        |i| <= current_limit, A (default math.inf: none): the amplifier holds the current there.
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


@dataclass(frozen=True)
class Hydraulic:
    """A servo valve and a piston (or rotary motor) after Merritt (1967) (BOOK.md section 7).

    Valve: tau_v xd_v + x_v = K_v i. Load flow: Q_L = K_q x_v - K_c P_L (``orifice="linear"``)
    or the square-root orifice of a critically centred four-way valve,
    Q_L = C_d w x_v sqrt((P_s - sgn(x_v) P_L) / rho) (``orifice="sqrt"``). Continuity:
    Q_L = A qd + C_tp P_L + (V_t / (4 beta_e)) dP_L/dt. The actuator pushes the link with the
    force A P_L (a piston on a prismatic joint) or the torque D_m P_L (a rotary motor,
    ``rotary=True``, on a revolute joint); it drives its joint directly, without a gear. Load
    pressure plays the role of the DC motor's armature current.

    Parameters
    ----------
    valve_time_constant : float
        tau_v, s, > 0.
    valve_gain : float
        K_v, spool position per valve current, m/A, > 0.
    flow_gain : float or None
        K_q, m^2/s (flow per spool position), > 0: the linearized flow gain, used by the linear
        orifice and by the reduced model. None with ``orifice="sqrt"`` takes its null value
        C_d w sqrt(P_s / rho) (``linearized_flow_gain`` gives the value used).
    pressure_coefficient : float
        K_c, the flow-pressure coefficient, m^3/(s Pa), >= 0 (Merritt's null value for an ideal
        critically centred valve is 0).
    area : float
        A, the piston area, m^2, or with ``rotary`` the motor displacement D_m, m^3/rad; > 0.
    leakage : float
        C_tp, the total leakage coefficient, m^3/(s Pa), >= 0.
    volume : float
        V_t, the total trapped volume of both chambers, m^3, > 0.
    bulk_modulus : float
        beta_e, the effective bulk modulus of the oil, Pa, > 0.
    supply_pressure : float
        P_s, Pa, > 0.
    rotary : bool, optional
        False (default) for a piston on a prismatic joint, True for a rotary motor on a
        revolute joint.
    orifice : str, optional
        "linear" (default) or "sqrt".
    discharge_coefficient : float, optional
        C_d, > 0; needed (only) with ``orifice="sqrt"``.
    orifice_width : float, optional
        w, the area gradient of the spool's port, m, > 0; with ``orifice="sqrt"``.
    density : float, optional
        rho, the oil's density, kg/m^3, > 0; with ``orifice="sqrt"``.
    current_limit : float, optional
        |i| <= current_limit for the valve current, A (default math.inf): the input is clipped.
    stroke : float, optional
        |x_v| <= stroke, m (default math.inf): the spool stops there.
    name : str, optional
        The drive's name, used in messages (default "hydraulic").

    Raises
    ------
    armdyn.ModelError
        When a parameter is not a finite real number (a limit may be math.inf) or breaks its sign
        rule (tau_v, K_v, K_q, A, V_t, beta_e, P_s, C_d, w, rho and the limits > 0; K_c, C_tp >= 0),
        when ``orifice`` is neither "linear" nor "sqrt", when the square-root orifice lacks C_d, w
        or rho, or the linear one lacks K_q; the message names the drive and the rule.
    """

    valve_time_constant: float
    valve_gain: float
    flow_gain: float | None
    pressure_coefficient: float
    area: float
    leakage: float
    volume: float
    bulk_modulus: float
    supply_pressure: float
    rotary: bool = False
    orifice: str = "linear"
    discharge_coefficient: float | None = None
    orifice_width: float | None = None
    density: float | None = None
    current_limit: float = math.inf
    stroke: float = math.inf
    name: str = "hydraulic"

    def __post_init__(self) -> None:
        where = f"drive '{_drive_name(self.name)}'"
        if not isinstance(self.rotary, (bool, np.bool_)):
            raise ModelError(f"{where}: rotary must be True or False, got {reprlib.repr(self.rotary)}")
        if self.orifice not in ("linear", "sqrt"):
            raise ModelError(f"{where}: orifice must be 'linear' or 'sqrt', got {reprlib.repr(self.orifice)}")
        checked: dict[str, object] = {
            "valve_time_constant": _positive(self.valve_time_constant, "valve time constant tau_v", where),
            "valve_gain": _positive(self.valve_gain, "valve gain K_v", where),
            "pressure_coefficient": _non_negative(self.pressure_coefficient, "flow-pressure coefficient K_c", where),
            "area": _positive(self.area, "displacement D_m" if self.rotary else "piston area A", where),
            "leakage": _non_negative(self.leakage, "leakage coefficient C_tp", where),
            "volume": _positive(self.volume, "trapped volume V_t", where),
            "bulk_modulus": _positive(self.bulk_modulus, "bulk modulus beta_e", where),
            "supply_pressure": _positive(self.supply_pressure, "supply pressure P_s", where),
            "current_limit": _limit(self.current_limit, "valve current limit", where),
            "stroke": _limit(self.stroke, "valve stroke", where),
            "rotary": bool(self.rotary),
        }
        if self.orifice == "sqrt":
            for key, what in (
                ("discharge_coefficient", "discharge coefficient C_d"),
                ("orifice_width", "orifice area gradient w"),
                ("density", "oil density rho"),
            ):
                value = getattr(self, key)
                if value is None:
                    raise ModelError(f"{where}: the square-root orifice needs the {what} ({key}=...)")
                checked[key] = _positive(value, what, where)
        if self.flow_gain is not None:
            checked["flow_gain"] = _positive(self.flow_gain, "flow gain K_q", where)
        elif self.orifice == "linear":
            raise ModelError(f"{where}: the linear orifice needs the flow gain K_q (flow_gain=...)")
        for key, value in checked.items():
            object.__setattr__(self, key, value)

    @property
    def linearized_flow_gain(self) -> float:
        """K_q, m^2/s: ``flow_gain``, or for the square-root orifice without one its null value
        C_d w sqrt(P_s / rho) (Merritt 1967)."""
        if self.flow_gain is not None:
            return self.flow_gain
        return self.discharge_coefficient * self.orifice_width * math.sqrt(self.supply_pressure / self.density)

    @property
    def capacitance(self) -> float:
        """V_t / (4 beta_e), m^3/Pa: the hydraulic capacitance of the continuity equation."""
        return self.volume / (4 * self.bulk_modulus)

    @property
    def total_coefficient(self) -> float:
        """K_ce = K_c + C_tp, m^3/(s Pa): the pressure coefficient of the reduced model."""
        return self.pressure_coefficient + self.leakage


Drive = DCMotor | Hydraulic


# ----- the equations, one each ------------------------------------------------------------------------
def _armature_rate(
    v: np.ndarray, i: np.ndarray, w_M: np.ndarray, L: np.ndarray, R_a: np.ndarray, K_b: np.ndarray
) -> np.ndarray:
    """di/dt from L di/dt + R_a i + K_b qd_M = v (BOOK.md section 7)."""
    return (v - R_a * i - K_b * w_M) / L


def _rotor_acceleration(
    i: np.ndarray,
    w_M: np.ndarray,
    tau: np.ndarray,
    J_M: np.ndarray,
    B_M: np.ndarray,
    F_M: np.ndarray,
    K_M: np.ndarray,
    r: np.ndarray,
) -> np.ndarray:
    """qdd_M from J_M qdd_M + B_M qd_M + F_M + r tau = K_M i (BOOK.md section 7)."""
    return (K_M * i - B_M * w_M - F_M - r * tau) / J_M


def _shaft_torque(
    q: np.ndarray, qd: np.ndarray, q_M: np.ndarray, w_M: np.ndarray, r: np.ndarray, K: np.ndarray, B_s: np.ndarray
) -> np.ndarray:
    """tau = K (r q_M - q) + B_s (r qd_M - qd): the flexible shaft (BOOK.md section 7)."""
    return K * (r * q_M - q) + B_s * (r * w_M - qd)


def _valve_rate(u: np.ndarray, x_v: np.ndarray, tau_v: np.ndarray, K_v: np.ndarray) -> np.ndarray:
    """dx_v/dt from tau_v dx_v/dt + x_v = K_v i (Merritt 1967; BOOK.md section 7)."""
    return (K_v * u - x_v) / tau_v


def _load_flow(
    x_v: np.ndarray,
    P_L: np.ndarray,
    K_q: np.ndarray,
    K_c: np.ndarray,
    orifice: np.ndarray,
    P_s: np.ndarray,
    sqrt_gain: np.ndarray,
) -> np.ndarray:
    """Q_L = K_q x_v - K_c P_L, or C_d w x_v sqrt((P_s - sgn(x_v) P_L) / rho) where ``orifice`` is True
    (``sqrt_gain`` = C_d w / sqrt(rho); where the load drives the pressure past the supply, the drop
    changes sign and the flow reverses: sgn(drop) sqrt(|drop|)) (Merritt 1967)."""
    drop = P_s - np.sign(x_v) * P_L
    return np.where(orifice, sqrt_gain * x_v * np.sign(drop) * np.sqrt(np.abs(drop)), K_q * x_v - K_c * P_L)


def _pressure_rate(
    Q_L: np.ndarray, qd: np.ndarray, P_L: np.ndarray, A: np.ndarray, C_tp: np.ndarray, C: np.ndarray
) -> np.ndarray:
    """dP_L/dt from Q_L = A qd + C_tp P_L + (V_t / (4 beta_e)) dP_L/dt, C = V_t / (4 beta_e) (Merritt 1967)."""
    return (Q_L - A * qd - C_tp * P_L) / C


def _held(rate: np.ndarray, value: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """The rate of a state held within +-limit: zero where it would leave the range."""
    return np.where(((value >= limit) & (rate > 0)) | ((value <= -limit) & (rate < 0)), 0.0, rate)


def _rotor_friction(w_M: np.ndarray, positive: np.ndarray, negative: np.ndarray) -> np.ndarray:
    """Coulomb friction on a rotor: Tc+ for qd_M > 0, Tc- for qd_M < 0, 0 at rest."""
    return np.where(w_M > 0, positive, np.where(w_M < 0, negative, 0.0))


# ----- the arm-plus-actuator system ----------------------------------------------------------------------
def _joint_sense(coulomb: tuple[float, float], r: float) -> tuple[float, float]:
    """Rotor Coulomb friction (Tc+, Tc-) for positive and negative rotor velocity, as the Link's pair for
    positive and negative joint velocity (they swap, with their signs, when r < 0). Its own inverse."""
    return coulomb if r > 0 else (-coulomb[1], -coulomb[0])


class ActuatedArm:
    """An arm with a drive on every joint: the arm-plus-actuator system (BOOK.md section 7).

    Made by ``with_actuators``. A user treats it like an arm: the reduced model's
    ``inertia_matrix``, ``coriolis_matrix``, ``gravity_vector``, ``friction``, ``input_matrix``,
    ``inverse_dynamics`` (q, qd, qdd -> v) and ``forward_dynamics`` (q, qd, v -> qdd), and the full
    model's ``state_derivative``, ``linearize`` and ``to_control``, each batched over leading axes.
    The input v holds one value per joint: volts for a DC motor, the valve current (A) for a
    hydraulic drive.

    The reduced model is written in the link coordinates q with the rows in joint torques:
    M' = M + R^-2 J_M, the Christoffel V' = Vm, F' = F + R^-1 F_M + R^-2 B qd, G' = G, K' = R^-1 K_M
    (B = diag(B_Mi + K_bi K_Mi / R_ai), K_M = diag(K_Mi / R_ai)). With q = r q_M the kinetic
    energy is 1/2 qd^T M qd + 1/2 sum J_Mi (qd_i / r_i)^2 = 1/2 qd^T M' qd, so the rows are the
    energy-conjugate forces of q (K' v is a joint torque) and every property of Table 3.3.1 holds
    (``armdyn.properties.check`` runs on it). The book prints
    (J_M + R^2 M) qdd + (B + R^2 Vm) qd + R F_M + R^2 F + R^2 G = R K_M v: the same equation with
    each row i multiplied by r_i^2 (R^2 M' = J_M + R^2 M), which is symmetric only when all the
    r_i are equal; the congruent form R M' R = J_M + R M R is the inertia in the
    motor coordinates q_M. The damping B is kept with the friction, not in V', so that
    M'dot - 2 V' stays skew (with B in V' it is S - 2 B, only dissipative). A hydraulic joint adds
    the damping A^2 / K_ce and the gain A K_q K_v / K_ce (K_ce = K_c + C_tp). ``reduced_robot()``
    is the reduced model as a Robot whose links carry the DC drives as Link motors (Jm, G). The
    reduced model needs rigid shafts (and K_ce > 0).

    The full model has the state x = [q, qd, q_M, qd_M, i, x_v, P_L] (``state_names``): q_M and
    qd_M for the flexible drives, in joint order, i for the DC drives, x_v and P_L for the
    hydraulic ones. Limits act there and in ``forward_dynamics``: the input is clipped to the
    voltage (valve current) limit, the current and the spool are held within theirs.

    Parameters
    ----------
    robot : Robot
        The arm, without motors (every link's Jm = 0 and G = 1): its own friction is the joint
        friction F, which the drives' friction adds to.
    drives : sequence of DCMotor or Hydraulic
        One drive per joint, in joint order.

    Attributes
    ----------
    robot : Robot
        The arm as given.
    drives : tuple of DCMotor or Hydraulic
        The drives.
    n : int
        The number of joints.
    n_states : int
        The length of the full model's state.

    Raises
    ------
    armdyn.ModelError
        When the arm has motors (Jm or G set: they would be counted twice; the message says how to
        move them into drives), symbolic parameters, or not as many drives as joints; when a drive
        is not a DCMotor or Hydraulic, or a hydraulic drive cannot drive its joint (a rotary motor
        on a prismatic joint, a piston on a revolute one); the message names the drive and the
        joint.
    TypeError
        When ``robot`` is not a Robot.
    """

    def __init__(self, robot: Robot, drives: Sequence[Drive]) -> None:
        if not isinstance(robot, Robot):
            raise TypeError(f"robot must be an armdyn Robot, got {type(robot).__name__}")
        self.robot, self.drives, self.n, self.name = robot, _checked_drives(robot, drives), robot.n, robot.name
        self._where = f" for '{robot.name}' with actuators"
        self._parameters()
        self._mechanical = robot.replace([self._link(j, reduced=False) for j in range(self.n)])
        flexible = [drive.name for drive in self.drives if isinstance(drive, DCMotor) and drive.flexible]
        stiff = [drive.name for drive in self.drives if isinstance(drive, Hydraulic) and drive.total_coefficient == 0]
        self._reduced, self._why_not_reduced = None, ""
        if flexible:
            self._why_not_reduced = f"drives {flexible} are flexible (their motor angles are states)"
        elif stiff:
            self._why_not_reduced = (
                f"hydraulic drives {stiff} have K_c + C_tp = 0, so with the oil incompressible their flow fixes "
                "the joint speed (no reduced torque equation)"
            )
        else:
            self._reduced = robot.replace(
                [self._link(j, reduced=True) for j in range(self.n)],
                name=f"{robot.name} (reduced arm-plus-actuator model)",
                description=f"{robot.description}; drives: " + ", ".join(drive.name for drive in self.drives),
            )
        f, d, h = self._flex.size, self._dc.size, self._hyd.size
        self.n_states = 2 * self.n + 2 * f + d + 2 * h
        sizes = {"q": self.n, "qd": self.n, "qM": f, "qdM": f, "i": d, "xv": h, "PL": h}
        edges = np.cumsum([0, *sizes.values()])
        self._slices = {key: slice(edges[k], edges[k + 1]) for k, key in enumerate(sizes)}

    # ----- construction ---------------------------------------------------------------------------------
    def _parameters(self) -> None:
        """Per-joint parameter vectors (neutral values where a joint's drive has no such parameter) and
        the index arrays of the flexible, DC and hydraulic drives."""
        drives, n = self.drives, self.n
        dc = np.array([isinstance(drive, DCMotor) for drive in drives])
        flex = np.array([isinstance(drive, DCMotor) and drive.flexible for drive in drives])
        self._is_dc = dc
        self._dc, self._flex, self._hyd = np.flatnonzero(dc), np.flatnonzero(flex), np.flatnonzero(~dc)
        self._rigid = dc & ~flex

        def vector(kind: type, key: str, neutral: float) -> np.ndarray:
            return np.array([float(getattr(d, key)) if isinstance(d, kind) else neutral for d in drives])

        self._r = vector(DCMotor, "gear_ratio", 1.0)
        self._J_M, self._B_M = vector(DCMotor, "rotor_inertia", 1.0), vector(DCMotor, "viscous", 0.0)
        self._K_M, self._K_b = vector(DCMotor, "torque_constant", 0.0), vector(DCMotor, "back_emf", 0.0)
        self._R_a, self._L = vector(DCMotor, "resistance", 1.0), vector(DCMotor, "inductance", 1.0)
        self._i_max = vector(DCMotor, "current_limit", math.inf)
        coulomb = np.array([d.coulomb if isinstance(d, DCMotor) else (0.0, 0.0) for d in drives]).reshape(n, 2)
        self._Tc_pos, self._Tc_neg = coulomb.T
        self._K = np.array([d.stiffness if isinstance(d, DCMotor) and d.flexible else 0.0 for d in drives])
        self._B_s = vector(DCMotor, "shaft_damping", 0.0)
        self._tau_v, self._K_v = vector(Hydraulic, "valve_time_constant", 1.0), vector(Hydraulic, "valve_gain", 0.0)
        self._K_q, self._K_c = (
            vector(Hydraulic, "linearized_flow_gain", 0.0),
            vector(Hydraulic, "pressure_coefficient", 0.0),
        )
        self._A, self._C_tp = vector(Hydraulic, "area", 0.0), vector(Hydraulic, "leakage", 0.0)
        self._C = np.array([d.capacitance if isinstance(d, Hydraulic) else 1.0 for d in drives])
        self._K_ce = np.array([d.total_coefficient if isinstance(d, Hydraulic) else 1.0 for d in drives])
        self._P_s = vector(Hydraulic, "supply_pressure", 1.0)
        self._sqrt = np.array([isinstance(d, Hydraulic) and d.orifice == "sqrt" for d in drives])
        self._sqrt_gain = np.array(
            [
                d.discharge_coefficient * d.orifice_width / math.sqrt(d.density)
                if isinstance(d, Hydraulic) and d.orifice == "sqrt"
                else 0.0
                for d in drives
            ]
        )
        self._stroke = vector(Hydraulic, "stroke", math.inf)
        self._u_max = np.array([d.voltage_limit if isinstance(d, DCMotor) else d.current_limit for d in drives])

    def _link(self, j: int, reduced: bool) -> Link:
        """Joint j's Link with its drive folded in: a rigid DC drive as the Link's motor (Jm = J_M, G = 1/r,
        motor-side B and Tc, plus the back-emf damping K_b K_M / R_a in the reduced model); a hydraulic
        drive's damping A^2 / K_ce in the reduced model; a flexible drive not at all (its rotor is a state)."""
        link, drive = self.robot.links[j], self.drives[j]
        if isinstance(drive, DCMotor) and not drive.flexible:
            r = drive.gear_ratio
            motor = _joint_sense(drive.coulomb, r)
            viscous = drive.viscous + link.viscous * r**2
            if reduced:
                viscous += drive.back_emf * drive.torque_constant / drive.resistance
            coulomb = (link.coulomb[0] * abs(r) + motor[0], link.coulomb[1] * abs(r) + motor[1])
            return dataclasses.replace(
                link, motor_inertia=drive.rotor_inertia, gear_ratio=1 / r, viscous=viscous, coulomb=coulomb
            )
        if isinstance(drive, Hydraulic) and reduced:
            return dataclasses.replace(link, viscous=link.viscous + drive.area**2 / drive.total_coefficient)
        return link

    def mechanical_robot(self) -> Robot:
        """The links with the rigid DC drives' rotors, gears and friction as Link motors, without the electrics.

        The mechanics M qdd + Vm qd + F + G = tau that the drives' joint torques act on in the full
        model (the flexible drives' rotors and the hydraulic drives are not in it): driving it with
        the torques a current loop delivers is the torque-controlled arm of Chapter 4.

        Returns
        -------
        Robot
            The arm with Jm = J_M, G = 1/r and the motor-side B and Tc of its rigid DC drives.

        Raises
        ------
        None
            It returns the model the full model is built on.
        """
        return self._mechanical

    # ----- the reduced model ---------------------------------------------------------------------------
    def reduced_robot(self) -> Robot:
        """The reduced model as a Robot: M' = M + R^-2 J_M, V' = Vm, F', G' = G, torque K' v.

        The rigid DC drives become the links' motors (Jm = J_M, G = 1/r, viscous B_M + K_b K_M / R_a
        and Coulomb friction on the motor side) and the hydraulic drives add the damping A^2 / K_ce
        to the joint friction (BOOK.md section 7). ``armdyn.properties.check`` evaluates Table 3.3.1
        on it.

        Returns
        -------
        Robot
            The arm whose robot equation is the reduced model with tau = K' v.

        Raises
        ------
        armdyn.ModelError
            When a drive is flexible (its motor angle is a state: there is no reduced robot
            equation in q alone), or a hydraulic drive has K_c + C_tp = 0.
        """
        if self._reduced is None:
            raise ModelError(
                f"the reduced model{self._where} does not exist: {self._why_not_reduced}; use state_derivative"
            )
        return self._reduced

    def inertia_matrix(self, q: object) -> np.ndarray:
        """M'(q) = M(q) + R^-2 J_M (BOOK.md section 7, in joint torques).

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n, n).

        Raises
        ------
        armdyn.ModelError
            When q is invalid (see Robot.inertia_matrix) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().inertia_matrix(q)

    def coriolis_matrix(self, q: object, qd: object) -> np.ndarray:
        """V'(q, qd) = Vm(q, qd), the Christoffel form: M'dot - 2 V' is skew (BOOK.md section 7).

        Parameters
        ----------
        q, qd : array_like
            Joint positions and velocities, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n, n).

        Raises
        ------
        armdyn.ModelError
            When a state is invalid (see Robot.coriolis_matrix) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().coriolis_matrix(q, qd)

    def inertia_matrix_dot(self, q: object, qd: object) -> np.ndarray:
        """dM'/dt = V' + V'^T (the drives' inertias are constant).

        Parameters
        ----------
        q, qd : array_like
            Joint positions and velocities, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n, n).

        Raises
        ------
        armdyn.ModelError
            When a state is invalid (see Robot.inertia_matrix_dot) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().inertia_matrix_dot(q, qd)

    def gravity_vector(self, q: object) -> np.ndarray:
        """G'(q) = G(q) (BOOK.md section 7, in joint torques).

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n).

        Raises
        ------
        armdyn.ModelError
            When q is invalid (see Robot.gravity_vector) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().gravity_vector(q)

    def friction(self, qd: object) -> np.ndarray:
        """F'(qd) = F(qd) + R^-1 F_M(qd / r) + R^-2 B qd, B = B_M + K_b K_M / R_a (BOOK.md section 7).

        A hydraulic joint's share of R^-2 B qd is A^2 qd / K_ce.

        Parameters
        ----------
        qd : array_like
            Joint velocities, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n).

        Raises
        ------
        armdyn.ModelError
            When qd is invalid (see Robot.friction) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().friction(qd)

    def input_matrix(self) -> np.ndarray:
        """K' = diag(K_Mi / (r_i R_ai)) (DC) or diag(A_i K_qi K_vi / K_cei) (hydraulic): torque = K' v.

        Returns
        -------
        numpy.ndarray
            (n, n), diagonal.

        Raises
        ------
        armdyn.ModelError
            When there is no reduced model (see reduced_robot).
        """
        self.reduced_robot()
        return np.diag(self._gain)

    @property
    def _gain(self) -> np.ndarray:
        return np.where(self._is_dc, self._K_M / (self._R_a * self._r), self._A * self._K_q * self._K_v / self._K_ce)

    def inverse_dynamics(self, q: object, qd: object, qdd: object) -> np.ndarray:
        """v = K'^-1 (M' qdd + V' qd + F' + G'): the inputs that give qdd (limits not applied).

        Parameters
        ----------
        q, qd, qdd : array_like
            Joint positions, velocities and accelerations, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            v, (..., n): volts for DC drives, valve currents (A) for hydraulic ones.

        Raises
        ------
        armdyn.ModelError
            When a state is invalid (see Robot.inverse_dynamics) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().inverse_dynamics(q, qd, qdd) / self._gain

    def forward_dynamics(self, q: object, qd: object, v: object) -> np.ndarray:
        """qdd of the reduced model under the inputs v, with the drives' limits.

        The joint torque of a DC drive is (K_M / r) i with the steady current
        i = (v - K_b qd / r) / R_a (held within the current limit), of a hydraulic drive A P_L with
        P_L = (K_q x_v - A qd) / K_ce, x_v = K_v i (held within the stroke); v is clipped to the
        voltage (valve current) limits first. Within the limits this is M'^-1 (K' v - V' qd - F' - G').

        Parameters
        ----------
        q, qd : array_like
            Joint positions and velocities, (n,) or (..., n).
        v : array_like
            Inputs, (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            qdd, (..., n).

        Raises
        ------
        armdyn.ModelError
            When a state or v is invalid (see Robot.forward_dynamics), their batch shapes do not
            broadcast, or there is no reduced model (see reduced_robot).
        """
        self.reduced_robot()
        qd, v = inputs.state(qd, self.n, "qd", self._where), inputs.state(v, self.n, "v", self._where)
        try:
            np.broadcast_shapes(qd.shape, v.shape)
        except ValueError:
            raise ModelError(f"the batch shapes of qd {qd.shape} and v {v.shape} do not broadcast") from None
        u = np.clip(v, -self._u_max, self._u_max)
        current = np.clip((u - self._K_b * qd / self._r) / self._R_a, -self._i_max, self._i_max)
        x_v = np.clip(self._K_v * u, -self._stroke, self._stroke)
        P_L = (self._K_q * x_v - self._A * qd) / self._K_ce
        tau = np.where(self._is_dc, self._K_M * current / self._r, self._A * P_L)
        return self._mechanical.forward_dynamics(q, qd, tau)

    def kinetic_energy(self, q: object, qd: object) -> float | np.ndarray:
        """1/2 qd^T M'(q) qd: the links' and the rotors' kinetic energy.

        Parameters
        ----------
        q, qd : array_like
            Joint positions and velocities, (n,) or (..., n).

        Returns
        -------
        float or numpy.ndarray
            A float for one state, (...) for a batch.

        Raises
        ------
        armdyn.ModelError
            When a state is invalid (see Robot.kinetic_energy) or there is no reduced model (see reduced_robot).
        """
        return self.reduced_robot().kinetic_energy(q, qd)

    def potential_energy(self, q: object) -> float | np.ndarray:
        """P(q), the arm's potential energy.

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or (..., n).

        Returns
        -------
        float or numpy.ndarray
            A float for one state, (...) for a batch.

        Raises
        ------
        armdyn.ModelError
            When q is invalid (see Robot.potential_energy).
        """
        return self.robot.potential_energy(q)

    # ----- the full model -------------------------------------------------------------------------------
    @property
    def state_names(self) -> list[str]:
        """The full model's state, by name: 'q j', 'qd j', 'qM j', 'qdM j', 'i j', 'xv j', 'PL j' for joint j."""
        names = self.robot.joint_names
        groups = {
            "q": range(self.n),
            "qd": range(self.n),
            "qM": self._flex,
            "qdM": self._flex,
            "i": self._dc,
            "xv": self._hyd,
            "PL": self._hyd,
        }
        return [f"{key} {names[j]}" for key, joints in groups.items() for j in joints]

    def initial_state(self, q: object, qd: object = None) -> np.ndarray:
        """x with the drives at rest relative to the links: q_M = q / r, qd_M = qd / r, i = x_v = P_L = 0.

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or (..., n).
        qd : array_like, optional
            Joint velocities, broadcasting with q (default zero).

        Returns
        -------
        numpy.ndarray
            (..., n_states).

        Raises
        ------
        armdyn.ModelError
            When q or qd is not finite numbers of shape (..., n), or their batch shapes do not broadcast.
        """
        q = inputs.state(q, self.n, "q", self._where)
        qd = np.zeros(self.n) if qd is None else inputs.state(qd, self.n, "qd", self._where)
        try:
            q, qd = np.broadcast_arrays(q, qd)
        except ValueError:
            raise ModelError(f"the batch shapes of q {q.shape} and qd {qd.shape} do not broadcast") from None
        f = self._flex
        extra = self.n_states - 2 * self.n - 2 * f.size
        rotors = [q[..., f] / self._r[f], qd[..., f] / self._r[f]]
        return np.concatenate([q, qd, *rotors, np.zeros((*q.shape[:-1], extra))], -1)

    def _split(self, x: object) -> dict[str, np.ndarray]:
        x = inputs.state(x, self.n_states, "x", f"{self._where} (x = [{', '.join(self.state_names)}])")
        return {key: x[..., part] for key, part in self._slices.items()}

    def _check_full(self) -> None:
        missing = [self.drives[j].name for j in self._dc if self._L[j] == 0]
        if missing:
            raise ModelError(
                f"drives {missing}{self._where} have no inductance (L = 0): their currents are not states of the "
                "full model; give L > 0, or use the reduced model (forward_dynamics)"
            )

    def state_derivative(self, x: object, v: object) -> np.ndarray:
        """xdot of the full model, x = [q, qd, q_M, qd_M, i, x_v, P_L] (see ``state_names``), batched.

        The arm: M qdd + Vm qd + F + G = tau (with the rigid drives' rotors and friction folded into
        M and F, as in the Link convention), tau = (K_M / r) i for a rigid DC drive, the shaft torque
        K (r q_M - q) + B_s (r qd_M - qd) for a flexible one and A P_L for a hydraulic one; the
        rotors of flexible drives J_M qdd_M + B_M qd_M + F_M + r tau = K_M i; the armatures
        L di/dt + R_a i + K_b qd_M = v; the valves and the continuity equation of Merritt (1967)
        (BOOK.md section 7). v is clipped to the voltage (valve current) limits, and the currents
        and spools are held within theirs.

        Parameters
        ----------
        x : array_like
            The state, (n_states,) or (..., n_states).
        v : array_like
            The inputs, (n,) or (..., n), broadcasting with x: volts, or valve currents (A).

        Returns
        -------
        numpy.ndarray
            xdot, (..., n_states).

        Raises
        ------
        armdyn.ModelError
            When x or v is not finite numbers of its shape, their batch shapes do not broadcast,
            a DC drive has no inductance, or M(q) is singular.
        """
        self._check_full()
        s = self._split(x)
        u = np.clip(inputs.state(v, self.n, "v", self._where), -self._u_max, self._u_max)
        try:
            batch = np.broadcast_shapes(s["q"].shape[:-1], u.shape[:-1])
        except ValueError:
            raise ModelError(f"the batch shapes of x and v {u.shape} do not broadcast") from None
        q, qd = (np.broadcast_to(s[key], (*batch, self.n)) for key in ("q", "qd"))
        u = np.broadcast_to(u, (*batch, self.n))
        f, d, h, rigid = self._flex, self._dc, self._hyd, self._rigid
        q_M, w_M = (np.broadcast_to(s[key], (*batch, f.size)) for key in ("qM", "qdM"))
        i, x_v, P_L = (
            np.broadcast_to(s[key], (*batch, size)) for key, size in (("i", d.size), ("xv", h.size), ("PL", h.size))
        )
        current = np.zeros((*batch, self.n))
        current[..., d] = i
        tau = np.where(rigid, self._K_M * current / self._r, 0.0)
        tau[..., f] = _shaft_torque(q[..., f], qd[..., f], q_M, w_M, self._r[f], self._K[f], self._B_s[f])
        tau[..., h] = self._A[h] * P_L
        # one state as a batch of one: the batch kernel either way, so one state rounds as in a batch
        qdd = self._mechanical.forward_dynamics(q[None], qd[None], tau[None])[0] if not batch else (
            self._mechanical.forward_dynamics(q, qd, tau))  # fmt: skip
        F_M = _rotor_friction(w_M, self._Tc_pos[f], self._Tc_neg[f])
        wd_M = _rotor_acceleration(
            current[..., f], w_M, tau[..., f], self._J_M[f], self._B_M[f], F_M, self._K_M[f], self._r[f]
        )
        rotor_speed = qd / self._r
        rotor_speed[..., f] = w_M
        di = _armature_rate(u[..., d], i, rotor_speed[..., d], self._L[d], self._R_a[d], self._K_b[d])
        di = _held(di, i, self._i_max[d])
        dx_v = _held(_valve_rate(u[..., h], x_v, self._tau_v[h], self._K_v[h]), x_v, self._stroke[h])
        Q_L = _load_flow(x_v, P_L, self._K_q[h], self._K_c[h], self._sqrt[h], self._P_s[h], self._sqrt_gain[h])
        dP_L = _pressure_rate(Q_L, qd[..., h], P_L, self._A[h], self._C_tp[h], self._C[h])
        return np.concatenate([qd, qdd, w_M, wd_M, di, dx_v, dP_L], -1)

    def stored_energy(self, x: object) -> float | np.ndarray:
        """K + P + 1/2 sum L i^2 + 1/2 sum K (r q_M - q)^2 + 1/2 sum (V_t / (4 beta_e)) P_L^2.

        The links' and rotors' kinetic energy, the potential energy, the armatures' magnetic
        energy, the shafts' elastic energy and the oil's compression energy: what the full model
        stores, so that d/dt of it is the power supplied, sum v i + sum P_L Q_L, less the power
        dissipated (BOOK.md section 7).

        Parameters
        ----------
        x : array_like
            The state, (n_states,) or (..., n_states).

        Returns
        -------
        float or numpy.ndarray
            J: a float for one state, (...) for a batch.

        Raises
        ------
        armdyn.ModelError
            When x is not finite numbers of shape (..., n_states).
        """
        s = self._split(x)
        f, d, h = self._flex, self._dc, self._hyd
        q, qd, q_M, w_M = s["q"], s["qd"], s["qM"], s["qdM"]
        energy = self._mechanical.kinetic_energy(q, qd) + self._mechanical.potential_energy(q)
        twist = self._r[f] * q_M - q[..., f]
        energy = energy + 0.5 * np.sum(self._J_M[f] * w_M**2 + self._K[f] * twist**2, axis=-1)
        energy = energy + 0.5 * np.sum(self._L[d] * s["i"] ** 2, axis=-1)
        energy = energy + 0.5 * np.sum(self._C[h] * s["PL"] ** 2, axis=-1)
        return float(energy) if np.ndim(energy) == 0 else energy

    def _scales(self) -> tuple[np.ndarray, np.ndarray]:
        """Typical sizes of the states and inputs, for the difference steps: 1 rad (m) and 1 rad/s (m/s)
        at the joints, 1 / |r| at the rotors, 1 A, A / K_q for a spool (the opening that moves the
        actuator at unit speed), P_s for a load pressure; 1 V, A / (K_q K_v) for a valve current."""
        f, h = self._flex, self._hyd
        rotor = 1 / np.abs(self._r[f])
        opening = self._A[h] / self._K_q[h]
        states = np.concatenate([np.ones(2 * self.n), rotor, rotor, np.ones(self._dc.size), opening, self._P_s[h]])
        controls = np.ones(self.n)
        controls[h] = opening / self._K_v[h]
        return states, controls

    def _check_smooth(self, x0: np.ndarray, v0: np.ndarray) -> None:
        """A ModelError where state_derivative is not differentiable at (x0, v0): Coulomb friction at zero
        velocity, a limit reached, a square-root orifice closed against a load pressure."""
        s = self._split(x0)
        f, d, h = self._flex, self._dc, self._hyd
        reasons = []
        coulomb = np.abs(self._mechanical.coulomb_friction).max(axis=1) > 0
        if np.any(coulomb & (s["qd"] == 0)) or np.any((self._Tc_pos[f] - self._Tc_neg[f] > 0) & (s["qdM"] == 0)):
            reasons.append("Coulomb friction at zero velocity")
        if np.any(np.abs(v0) >= self._u_max):
            reasons.append("an input at its voltage (valve current) limit")
        if np.any(np.abs(s["i"]) >= self._i_max[d]) or np.any(np.abs(s["xv"]) >= self._stroke[h]):
            reasons.append("a current or spool at its limit")
        if np.any(self._sqrt[h] & (s["xv"] == 0) & (s["PL"] != 0)):
            reasons.append("a square-root orifice closed (x_v = 0) against a load pressure")
        if reasons:
            raise ModelError(
                f"the full model{self._where} is not differentiable at this point ({'; '.join(reasons)}); "
                "linearize elsewhere"
            )

    def linearize(self, x0: object, v0: object) -> tuple[np.ndarray, np.ndarray]:
        """(A, B) with xdot ~ A (x - x0) + B (v - v0): the full model linearized about (x0, v0).

        By central differences of ``state_derivative`` in one batched call: the step of state j is
        eps^(1/3) max(|x0_j|, s_j) with s_j its typical size (1 rad or m, 1 rad/s or m/s, 1 / |r|
        at a rotor, 1 A, A / K_q at a spool, P_s at a load pressure; 1 V or A / (K_q K_v) for an
        input), so the error is O(step^2) relative: about 1e-10 for smooth dynamics, and exact up
        to rounding for the parts that are linear (the drives' equations).

        Parameters
        ----------
        x0 : array_like
            The operating state, (n_states,).
        v0 : array_like
            The operating inputs, (n,).

        Returns
        -------
        A : numpy.ndarray
            (n_states, n_states).
        B : numpy.ndarray
            (n_states, n).

        Raises
        ------
        armdyn.ModelError
            When x0 or v0 is not one finite state of its size, a DC drive has no inductance, or the
            model is not differentiable at the point: Coulomb friction at zero velocity, an input,
            current or spool at its limit, a square-root orifice closed against a load pressure.
        """
        self._check_full()
        x0 = inputs.state(x0, self.n_states, "x0", self._where)
        v0 = inputs.state(v0, self.n, "v0", self._where)
        if x0.ndim != 1 or v0.ndim != 1:
            raise ModelError(f"linearize takes one state: x0 {x0.shape} and v0 {v0.shape}, not batches")
        self._check_smooth(x0, v0)
        m, n = self.n_states, self.n
        states, controls = self._scales()
        hx = (x0 + _STEP * np.maximum(np.abs(x0), states)) - x0
        hv = (v0 + _STEP * np.maximum(np.abs(v0), controls)) - v0
        X = np.concatenate([x0 + np.diag(hx), x0 - np.diag(hx), np.broadcast_to(x0, (2 * n, m))])
        V = np.concatenate([np.broadcast_to(v0, (2 * m, n)), v0 + np.diag(hv), v0 - np.diag(hv)])
        rates = self.state_derivative(X, V)
        A = (rates[:m] - rates[m : 2 * m]).T / (2 * hx)
        B = (rates[2 * m : 2 * m + n] - rates[2 * m + n :]).T / (2 * hv)
        return A, B

    def to_control(self, x0: object, v0: object) -> object:
        """The linearization about (x0, v0) as a python-control StateSpace, outputs the full state.

        Parameters
        ----------
        x0 : array_like
            The operating state, (n_states,).
        v0 : array_like
            The operating inputs, (n,).

        Returns
        -------
        control.StateSpace
            ss(A, B, I, 0) of ``linearize``: input v - v0, output x - x0.

        Raises
        ------
        armdyn.ModelError
            As ``linearize``, or when python-control is not installed.
        """
        try:
            import control
        except ImportError:
            raise ModelError("to_control() needs python-control: pip install 'armdyn[control]'") from None
        A, B = self.linearize(x0, v0)
        return control.ss(A, B, np.eye(self.n_states), np.zeros(B.shape))

    def _simulate(self, *arguments: object) -> object:
        return simulate(self, *arguments)

    def __repr__(self) -> str:
        kinds = ", ".join(type(drive).__name__ for drive in self.drives)
        return f"ActuatedArm('{self.name}', n={self.n}, drives=[{kinds}])"


def _checked_drives(robot: Robot, drives: object) -> tuple[Drive, ...]:
    """The drives, one per joint, each able to drive its joint, on an arm without motors."""
    where = f"robot '{robot.name}'"
    if robot.is_symbolic:
        raise ModelError(f"{where} has symbolic parameters: the arm-plus-actuator model needs numbers")
    motors = [link.name for link in robot.links if link.motor_inertia != 0 or link.gear_ratio != 1]
    if motors:
        raise ModelError(
            f"{where} already has motors (Jm or G) on joints {motors}: with drives they would be counted twice. "
            "Move them into DC motor drives with armdyn.actuators.motor_drives(robot, ...), or drop them with "
            "robot.without_motors() (its friction stays at the joint side)"
        )
    if drives is None or isinstance(drives, (str, bytes, DCMotor, Hydraulic)) or not isinstance(drives, Sequence):
        raise ModelError(
            f"drives must be a sequence of DCMotor or Hydraulic, one per joint, got {reprlib.repr(drives)}"
        )
    if len(drives) != robot.n:
        raise ModelError(f"{where} has {robot.n} joints {robot.joint_names}; {len(drives)} drives were given")
    for link, drive in zip(robot.links, drives, strict=True):
        if not isinstance(drive, (DCMotor, Hydraulic)):
            raise ModelError(f"the drive of joint '{link.name}' must be a DCMotor or Hydraulic, got {drive!r}")
        if isinstance(drive, Hydraulic) and drive.rotary != (link.kind == "revolute"):
            actuator = "a rotary motor" if drive.rotary else "a piston (linear)"
            fit = "rotary=False, a piston" if link.kind == "prismatic" else "rotary=True, a rotary motor"
            raise ModelError(
                f"drive '{drive.name}' is {actuator} and cannot drive the {link.kind} joint '{link.name}' "
                f"(it needs {fit})"
            )
    return tuple(drives)


def with_actuators(robot: Robot, drives: Sequence[Drive]) -> ActuatedArm:
    """The arm-plus-actuator system: ``robot`` with a drive on every joint (BOOK.md section 7).

    Parameters
    ----------
    robot : Robot
        The arm, without motors (Jm = 0, G = 1 on every link); ``motor_drives`` moves an arm's
        motors into drives.
    drives : sequence of DCMotor or Hydraulic
        One drive per joint, in joint order.

    Returns
    -------
    ActuatedArm
        The arm with its drives: the reduced and the full model.

    Raises
    ------
    armdyn.ModelError
        As ActuatedArm: motors already on the arm, a joint count that does not match, a drive that
        cannot drive its joint.
    TypeError
        When ``robot`` is not a Robot.
    """
    return ActuatedArm(robot, drives)


def motor_drives(
    robot: Robot,
    torque_constant: object,
    back_emf: object,
    resistance: object,
    inductance: object,
    voltage_limit: object = math.inf,
    current_limit: object = math.inf,
) -> tuple[Robot, list[DCMotor]]:
    """The arm's motors (Jm, G, B, Tc of its links) moved into DC motor drives with the given electrics.

    Each link's Link motor becomes a DCMotor with J_M = Jm, r = 1/G, B_M = B and the Coulomb
    friction Tc (motor side, the pair swapped with its signs when G < 0, so that the friction at
    the joint is unchanged); the arm keeps its links without motor or friction. So
    ``with_actuators(*motor_drives(robot, ...))`` has M' = robot's M, and F' = robot's F plus the
    back-emf damping G^2 K_b K_M / R_a.

    Parameters
    ----------
    robot : Robot
        The arm with its motors (e.g. ``armdyn.models.puma560()``).
    torque_constant, back_emf, resistance, inductance : float or array_like
        K_M (N m/A), K_b (V s/rad), R_a (ohm), L (H): one value for every joint or n values.
    voltage_limit, current_limit : float or array_like, optional
        Limits, one or n values (default math.inf: none).

    Returns
    -------
    tuple of (Robot, list of DCMotor)
        The arm without motors and friction, and one drive per joint, named "motor <joint>".

    Raises
    ------
    armdyn.ModelError
        When a value is not one or n numbers, or a drive's parameter breaks its rule (see DCMotor).
    TypeError
        When ``robot`` is not a Robot.
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be an armdyn Robot, got {type(robot).__name__}")
    n = robot.n

    def per_joint(value: object, name: str) -> np.ndarray:
        if isinstance(value, (int, float, np.floating)) and value == math.inf:
            return np.full(n, math.inf)
        array = np.atleast_1d(inputs.numbers(value, name, where=f" for '{robot.name}'"))
        if array.ndim != 1 or array.size not in (1, n):
            raise ModelError(f"{name} must be one value or {n} values (one per joint) for '{robot.name}'")
        return np.broadcast_to(array, (n,))

    electrics = [
        per_joint(value, name)
        for value, name in (
            (torque_constant, "torque_constant"),
            (back_emf, "back_emf"),
            (resistance, "resistance"),
            (inductance, "inductance"),
            (voltage_limit, "voltage_limit"),
            (current_limit, "current_limit"),
        )
    ]
    drives = []
    for j, link in enumerate(robot.links):
        r = 1 / link.gear_ratio
        K_M, K_b, R_a, L, v_max, i_max = (float(values[j]) for values in electrics)
        drives.append(
            DCMotor(
                link.motor_inertia,
                link.viscous,
                K_M,
                K_b,
                R_a,
                L,
                r,
                v_max,
                i_max,
                _joint_sense(link.coulomb, r),
                name=f"motor {link.name}",
            )
        )
    bare = [
        dataclasses.replace(link, motor_inertia=0.0, gear_ratio=1.0, viscous=0.0, coulomb=(0.0, 0.0))
        for link in robot.links
    ]
    return robot.replace(bare), drives


# ----- built-in drives -----------------------------------------------------------------------------------
PUMA560_ELECTRICS = {
    "torque_constant": (0.22, 0.22, 0.22, 0.075, 0.075, 0.075),
    "back_emf": (0.22, 0.22, 0.22, 0.075, 0.075, 0.075),
    "resistance": (2.1, 2.1, 2.1, 6.7, 6.7, 6.7),
    "inductance": (2e-3, 2e-3, 2e-3, 1e-3, 1e-3, 1e-3),
    "voltage_limit": 40.0,
    "current_limit": (8.0, 8.0, 8.0, 4.0, 4.0, 4.0),
}
"""The PUMA 560's motor electrics, per joint (K_M N m/A, K_b V s/rad, R_a ohm, L H, limits V and A):
representative values for its two motor sizes (joints 1-3 and 4-6), not published data (no
source with all of them for this arm could be confirmed); K_b = K_M in SI units."""


def puma560() -> ActuatedArm:
    """The PUMA 560 (armdyn.models.puma560: Armstrong, Khatib and Burdick 1986 and Corke's motor
    inertias, gears and friction) with its motors as DC drives and representative electrics
    (``PUMA560_ELECTRICS``, stated as such: not published data).

    Returns
    -------
    ActuatedArm
        Six rigid DC drives, named "motor joint1" ... "motor joint6".

    Raises
    ------
    armdyn.ModelError
        Never for the built-in data.
    """
    from armdyn import models

    return with_actuators(*motor_drives(models.puma560(), **PUMA560_ELECTRICS))


_KINDS = ("dc", "flexible", "hydraulic")
_SUPPLY = 21e6  # Pa: a common industrial supply pressure


def _configurations(robot: Robot, samples: int = 256) -> np.ndarray:
    """Configurations drawn within the joint limits (+-pi, +-0.5 m where unlimited), seeded."""
    rng = np.random.default_rng(0)
    limits = np.array([link.limits for link in robot.links], dtype=float)
    span = np.where(np.array(robot.kinds) == "revolute", np.pi, 0.5)
    low, high = (
        np.where(np.isfinite(limits[:, 0]), limits[:, 0], -span),
        np.where(np.isfinite(limits[:, 1]), limits[:, 1], span),
    )
    return rng.uniform(low, high, (samples, robot.n))


def _representative_motor(link: Link, revolute: bool, load: float, name: str) -> DCMotor:
    """A DC motor and gear for a joint that must hold ``load`` (N m or N): the link's own gear and its
    friction (G, B, Tc) where it has one, else a 50:1 gear (a 10 mm-lead screw on a prismatic joint);
    the link's rotor Jm (with G = 1, Jm is the rotor seen at the joint: J_M = r^2 Jm), else 1e-4 kg m^2;
    K_M = K_b = 0.2, R_a = 2, L = 2e-3; the current limit three times the holding current (at least 5 A), the
    voltage limit that current through R_a plus the back-emf at 2 rad/s (m/s)."""
    geared = link.gear_ratio != 1.0
    r = 1 / link.gear_ratio if geared else (1 / 50 if revolute else 0.01 / (2 * math.pi))
    rotor = link.motor_inertia * (1.0 if geared else r**2)  # without a gear Jm is seen at the joint
    rotor = rotor if rotor > 0 else 1e-4
    K_M, R_a = 0.2, 2.0
    current = max(5.0, 3 * load * abs(r) / K_M)
    voltage = R_a * current + K_M * 2.0 / abs(r)
    coulomb = _joint_sense(link.coulomb, r) if geared else (0.0, 0.0)
    viscous = link.viscous if geared else 0.0
    return DCMotor(rotor, viscous, K_M, K_M, R_a, 2e-3, r, voltage, current, coulomb, name=name)


def _representative_valve(revolute: bool, load: float, inertia: float, name: str) -> Hydraulic:
    """A servo valve and actuator that hold ``load`` at a quarter of the 21 MPa supply: a rotary motor on a
    revolute joint, a piston on a prismatic one, moving at 1 rad/s (0.5 m/s) at full spool opening
    (1 mm, 10 mA); square-root orifice, 5 ms valve, oil at 1.4 GPa and 850 kg/m^3, the trapped volume
    that of a half-turn (a 0.4 m stroke). A cross-port bypass sets the leakage C_tp (and K_c) for a
    damping ratio of 0.3 of the oil column on ``inertia``: zeta_h = (K_ce / A) sqrt(beta_e m / V_t)
    (Merritt 1967), without which the column rings."""
    area = max(4 * load, 50.0) / _SUPPLY  # D_m (m^3/rad) or A (m^2)
    speed, opening = (1.0, 1e-3) if revolute else (0.5, 1e-3)
    K_q = area * speed / opening
    width = K_q / (0.61 * math.sqrt(_SUPPLY / 850.0))
    volume = area * (math.pi if revolute else 0.4)
    leakage = 0.3 * area * math.sqrt(volume / (1.4e9 * inertia)) / 2  # K_c + C_tp, half each
    return Hydraulic(5e-3, 0.1, None, leakage, area, leakage, volume, 1.4e9, _SUPPLY, rotary=revolute, orifice="sqrt",
                     discharge_coefficient=0.61, orifice_width=width, density=850.0, current_limit=0.01,
                     stroke=opening, name=name)  # fmt: skip


def representative_drives(robot: Robot, kind: str = "dc") -> ActuatedArm:
    """The arm with a representative drive on every joint, sized from its gravity load (stated as such:
    not a product's data).

    ``kind`` "dc": a rigid DC motor per joint, with the link's own gear and friction (G, B, Tc)
    where it has a gear (else a 50:1 gear, or a 10 mm-lead screw on a prismatic joint, the joint
    friction staying at the joint) and its rotor Jm (without a gear, Jm is taken as seen at the
    joint, J_M = r^2 Jm; else 1e-4 kg m^2), K_M = K_b = 0.2 N m/A, R_a = 2 ohm,
    L = 2 mH, the current limit three times what holds the largest gravity torque (at least 5 A).
    "flexible": the same motors behind shafts whose spring puts the joint's locked-rotor
    resonance at 10 Hz (K = (2 pi 10)^2 m_j, m_j the mean of M_jj over the configurations, or the
    rotor's J_M / r^2 where the link moves no inertia) with 5 % damping. "hydraulic": a servo valve
    with a rotary motor (revolute joints) or a piston (prismatic ones) that holds four times the
    gravity load at the 21 MPa supply (Merritt 1967's square-root orifice), with a bypass leakage
    that damps the oil column on the joint's mean inertia to a ratio of 0.3. The gravity
    torque's peak is taken over 256 configurations drawn within the joint limits (seeded).

    Parameters
    ----------
    robot : Robot
        The arm (its motors, where it has them, become the DC drives).
    kind : str, optional
        "dc" (default), "flexible" or "hydraulic".

    Returns
    -------
    ActuatedArm
        The arm, without its own motors and friction where they moved into the drives.

    Raises
    ------
    armdyn.ModelError
        When ``kind`` is not one of the three, or the arm has symbolic parameters.
    TypeError
        When ``robot`` is not a Robot.
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be an armdyn Robot, got {type(robot).__name__}")
    if kind not in _KINDS:
        raise ModelError(f"kind must be one of {', '.join(_KINDS)}, got {reprlib.repr(kind)}")
    samples = _configurations(robot)
    loads = np.abs(robot.gravity_vector(samples)).max(axis=0)
    revolute = [k == "revolute" for k in robot.kinds]
    names = robot.joint_names
    if kind == "hydraulic":
        bare_robot = robot.replace([dataclasses.replace(link, motor_inertia=0.0, gear_ratio=1.0)
                                    for link in robot.links])  # fmt: skip
        inertia = np.diagonal(bare_robot.inertia_matrix(samples), axis1=-2, axis2=-1).mean(axis=0)
        drives = [_representative_valve(revolute[j], loads[j], max(inertia[j], 1e-3), f"valve {names[j]}")
                  for j in range(robot.n)]  # fmt: skip
        return with_actuators(bare_robot, drives)
    drives = [_representative_motor(link, revolute[j], loads[j], f"motor {names[j]}")
              for j, link in enumerate(robot.links)]  # fmt: skip
    bare = [
        dataclasses.replace(link, motor_inertia=0.0, gear_ratio=1.0, viscous=0.0, coulomb=(0.0, 0.0))
        if link.gear_ratio != 1.0
        else dataclasses.replace(link, motor_inertia=0.0)
        for link in robot.links
    ]
    bare_robot = robot.replace(bare)
    if kind == "flexible":
        inertia = np.diagonal(bare_robot.inertia_matrix(samples), axis1=-2, axis2=-1).mean(axis=0)
        rotors = np.array([drive.rotor_inertia / drive.gear_ratio**2 for drive in drives])
        inertia = np.where(inertia > 1e-9 * rotors, inertia, rotors)  # a link that moves no inertia of its own
        stiffness = (2 * math.pi * 10.0) ** 2 * inertia
        drives = [dataclasses.replace(drive, stiffness=K, shaft_damping=2 * 0.05 * math.sqrt(K * m))
                  for drive, K, m in zip(drives, stiffness, inertia, strict=True)]  # fmt: skip
    return with_actuators(bare_robot, drives)


# ----- Example 3.6-1 ----------------------------------------------------------------------------------------
def transfer_function(motor: DCMotor, load_inertia: float, load_damping: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """H(s) = qd(s) / v(s): one DC motor driving an inertia through its gear (BOOK.md section 7).

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
        When ``motor`` is not a DCMotor, or the load's inertia is not positive or its damping negative.
    """
    if not isinstance(motor, DCMotor):
        raise ModelError(f"motor must be a DCMotor, got {reprlib.repr(motor)}")
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
    = 10 / ((s + 2.298)(s + 8.702)), the book's 10 / ((s + 2.3)(s + 8.7)) (BOOK.md section 7).
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


# ----- simulation with the drives ---------------------------------------------------------------------
@dataclass(frozen=True)
class DrivePID:
    """Independent joint control on each drive's input (BOOK.md section 7): u = kp e + kv de/dt + ki z,
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
    """Computed torque turned into current commands through the motor model (BOOK.md sections 5 and 7).

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


def rk4_step(arm: ActuatedArm, q: object, bandwidth: object = None) -> float:
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
        raise ModelError(f"rk4_step takes one configuration of {arm.n} values{arm._where}")
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
    the step chosen from them (``rk4_step`` at the start: half of L/R for a DC motor), so the run
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
    from armdyn.dynamics import drives as packed
    from armdyn.simulation import Result, _seconds

    if not isinstance(arm, ActuatedArm):
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
        raise ModelError("controller must be an armdyn.actuators.DrivePID or CurrentComputedTorque, "
                         f"got {type(controller).__name__}")  # fmt: skip
    t_final, dt = _seconds(t_final, dt)
    spec = trajectories.packed(trajectory, n)
    if spec is None:
        raise ModelError("trajectory must be None, an armdyn.trajectories.Sinusoid or a Quintic")
    start = np.zeros(n) if q0 is None else inputs.state(q0, n, "q0", arm._where)
    rates = np.zeros(n) if qd0 is None else inputs.state(qd0, n, "qd0", arm._where)
    if start.shape != (n,) or rates.shape != (n,):
        raise ModelError(f"q0 and qd0 must be one state of {n} values{arm._where}")
    longest = rk4_step(arm, start, bandwidth)
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
            "trajectory": trajectories.describe(trajectory)}  # fmt: skip
    desired_path = references if trajectory is not None else None
    result = Result(times, q, qd, accelerations, torques, desired_path, arm.robot, info,
                    lambda: mechanical.kinetic_energy(q, qd) + mechanical.potential_energy(q))  # fmt: skip
    part = arm._slices
    hydraulic = arm._hyd.size > 0
    result.drives = DriveRecord(arm.state_names, states, applied, states[:, part["i"]],
                                states[:, part["xv"]] if hydraulic else None,
                                states[:, part["PL"]] if hydraulic else None)  # fmt: skip
    return result
