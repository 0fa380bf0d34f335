"""Actuator dynamics and the arm-plus-actuator system (Lewis, Dawson and Abdallah 2004, Section 3.6).

Drives:

- ``DCMotor``: an armature-controlled DC motor behind a gear q = r q_M (the book's ratio r,
  which is 1/G of the Robotics Toolbox's and of armdyn's Link convention), with an optional
  flexible shaft (a spring and damper between the gear output and the link);
- ``Hydraulic``: a servo valve and a piston (or rotary motor) after Merritt (1967), with the
  linearized or the square-root orifice flow.

``with_actuators(arm, drives)`` joins them to an arm as an ``ActuatedArm``:

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
import os
import reprlib
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from armdyn import inputs
from armdyn.actuators import packing
from armdyn.actuators.hydraulics import Hydraulic
from armdyn.actuators.motors import DCMotor
from armdyn.errors import MissingDependencyError, ModelError
from armdyn.model.arm import Link
from armdyn.robot import Robot

_STEP = float(np.finfo(float).eps) ** (1 / 3)
"""The relative step of the central differences in ``ActuatedArm.linearize``."""

Drive = DCMotor | Hydraulic


# ----- the equations, one each ------------------------------------------------------------------------
def _armature_rate(
    v: np.ndarray, i: np.ndarray, w_M: np.ndarray, L: np.ndarray, R_a: np.ndarray, K_b: np.ndarray
) -> np.ndarray:
    """di/dt from L di/dt + R_a i + K_b qd_M = v (Section 3.6)."""
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
    """qdd_M from J_M qdd_M + B_M qd_M + F_M + r tau = K_M i (Section 3.6)."""
    return (K_M * i - B_M * w_M - F_M - r * tau) / J_M


def _shaft_torque(
    q: np.ndarray, qd: np.ndarray, q_M: np.ndarray, w_M: np.ndarray, r: np.ndarray, K: np.ndarray, B_s: np.ndarray
) -> np.ndarray:
    """tau = K (r q_M - q) + B_s (r qd_M - qd): the flexible shaft (Section 3.6)."""
    return K * (r * q_M - q) + B_s * (r * w_M - qd)


def _valve_rate(u: np.ndarray, x_v: np.ndarray, tau_v: np.ndarray, K_v: np.ndarray) -> np.ndarray:
    """dx_v/dt from tau_v dx_v/dt + x_v = K_v i (Merritt 1967; Section 3.6)."""
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
    """The rate of a state held within +-limit: zero where it would leave the range (the projected
    dynamics of a state kept in a box, Dupuis and Nagurney 1993)."""
    return np.where(((value >= limit) & (rate > 0)) | ((value <= -limit) & (rate < 0)), 0.0, rate)


def _rotor_friction(w_M: np.ndarray, positive: np.ndarray, negative: np.ndarray) -> np.ndarray:
    """Coulomb friction on a rotor: Tc+ for qd_M > 0, Tc- for qd_M < 0, 0 at rest."""
    return np.where(w_M > 0, positive, np.where(w_M < 0, negative, 0.0))


# ----- the arm-plus-actuator system ----------------------------------------------------------------------
def _orifice_gain(drive: Drive) -> float:
    """C_d w / sqrt(rho) of a hydraulic drive's square-root orifice (Merritt 1967); 0 for any other drive."""
    if not (isinstance(drive, Hydraulic) and drive.orifice == "sqrt"):
        return 0.0
    c_d, w, rho = drive.discharge_coefficient, drive.orifice_width, drive.density
    assert c_d is not None and w is not None and rho is not None, "Hydraulic requires them with orifice='sqrt'"
    return c_d * w / math.sqrt(rho)


def _joint_sense(coulomb: tuple[float, float], r: float) -> tuple[float, float]:
    """Rotor Coulomb friction (Tc+, Tc-) for positive and negative rotor velocity, as the Link's pair for
    positive and negative joint velocity (they swap, with their signs, when r < 0). Its own inverse."""
    return coulomb if r > 0 else (-coulomb[1], -coulomb[0])


class ActuatedArm:
    """An arm with a drive on every joint: the arm-plus-actuator system (Section 3.6).

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
    voltage (valve current) limit, the current and the spool are held within theirs (a saturated
    current loop and the spool's hard stop: at a limit the rate that points out is zero; see
    ``state_derivative``).

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
        move them into drives), or not as many drives as joints; when a drive is not a DCMotor or
        Hydraulic, or a hydraulic drive cannot drive its joint (a rotary motor on a prismatic joint,
        a piston on a revolute one); the message names the drive and the joint.
    armdyn.ArgumentError
        When ``robot`` is not a Robot, or has symbolic parameters.
    """

    def __init__(self, robot: Robot, drives: Sequence[Drive]) -> None:
        inputs.arm_argument(robot, Robot, "robot", numeric=True, why=" (the arm-plus-actuator model)")
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
        self._sqrt_gain = np.array([_orifice_gain(d) for d in drives])
        self._stroke = vector(Hydraulic, "stroke", math.inf)
        self._u_max = np.array([d.voltage_limit if isinstance(d, DCMotor) else d.current_limit for d in drives])

    def _link(self, j: int, reduced: bool) -> Link:
        """Joint j's Link with its drive folded in: a rigid DC drive as the Link's motor (Jm = J_M, G = 1/r,
        motor-side B and Tc, plus the back-emf damping K_b K_M / R_a in the reduced model); a hydraulic
        drive's damping A^2 / K_ce in the reduced model; a flexible drive not at all (its rotor is a state)."""
        link, drive = self.robot.links[j], self.drives[j]
        if isinstance(drive, DCMotor) and not drive.flexible:
            r = drive.gear_ratio
            pair = drive.coulomb
            assert isinstance(pair, tuple), "DCMotor keeps its Coulomb friction as the pair (Tc+, Tc-)"
            motor = _joint_sense(pair, r)
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
        to the joint friction (Section 3.6). ``armdyn.properties.check`` evaluates Table 3.3.1
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

    def inertia_matrix(self, q: ArrayLike) -> np.ndarray:
        """M'(q) = M(q) + R^-2 J_M (Section 3.6, in joint torques).

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

    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """V'(q, qd) = Vm(q, qd), the Christoffel form: M'dot - 2 V' is skew (Section 3.6).

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

    def inertia_matrix_dot(self, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
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

    def gravity_vector(self, q: ArrayLike) -> np.ndarray:
        """G'(q) = G(q) (Section 3.6, in joint torques).

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

    def friction(self, qd: ArrayLike) -> np.ndarray:
        """F'(qd) = F(qd) + R^-1 F_M(qd / r) + R^-2 B qd, B = B_M + K_b K_M / R_a (Section 3.6).

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

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> np.ndarray:
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

    def forward_dynamics(self, q: ArrayLike, qd: ArrayLike, v: ArrayLike) -> np.ndarray:
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

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> float | np.ndarray:
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

    def potential_energy(self, q: ArrayLike) -> float | np.ndarray:
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

    def initial_state(self, q: ArrayLike, qd: ArrayLike | None = None) -> np.ndarray:
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

    def _split(self, x: ArrayLike) -> dict[str, np.ndarray]:
        x = inputs.state(x, self.n_states, "x", f"{self._where} (x = [{', '.join(self.state_names)}])")
        return {key: x[..., part] for key, part in self._slices.items()}

    def _check_full(self) -> None:
        missing = [self.drives[j].name for j in self._dc if self._L[j] == 0]
        if missing:
            raise ModelError(
                f"drives {missing}{self._where} have no inductance (L = 0): their currents are not states of the "
                "full model; give L > 0, or use the reduced model (forward_dynamics)"
            )

    def state_derivative(self, x: ArrayLike, v: ArrayLike) -> np.ndarray:
        """xdot of the full model, x = [q, qd, q_M, qd_M, i, x_v, P_L] (see ``state_names``), batched.

        The arm: M qdd + Vm qd + F + G = tau (with the rigid drives' rotors and friction folded into
        M and F, as in the Link convention), tau = (K_M / r) i for a rigid DC drive, the shaft torque
        K (r q_M - q) + B_s (r qd_M - qd) for a flexible one and A P_L for a hydraulic one; the
        rotors of flexible drives J_M qdd_M + B_M qd_M + F_M + r tau = K_M i; the armatures
        L di/dt + R_a i + K_b qd_M = v; the valves and the continuity equation of Merritt (1967)
        (Section 3.6). v is clipped to the voltage (valve current) limits, and the currents
        and spools are held within theirs: at a limit the rate that points out is zero (the
        amplifier's current loop applies R_a i + K_b qd_M there; the spool meets its stop), the
        projected dynamics of a state kept in a box (Dupuis and Nagurney 1993). A state past a
        limit is not moved back here; ``simulate`` does that at every RK4 stage.

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

    def stored_energy(self, x: ArrayLike) -> float | np.ndarray:
        """K + P + 1/2 sum L i^2 + 1/2 sum K (r q_M - q)^2 + 1/2 sum (V_t / (4 beta_e)) P_L^2.

        The links' and rotors' kinetic energy, the potential energy, the armatures' magnetic
        energy, the shafts' elastic energy and the oil's compression energy: what the full model
        stores, so that d/dt of it is the power supplied, sum v i + sum P_L Q_L, less the power
        dissipated (Section 3.6).

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

    def linearize(self, x0: ArrayLike, v0: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
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

    def to_control(self, x0: ArrayLike, v0: ArrayLike) -> object:
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
            As ``linearize``.
        armdyn.MissingDependencyError
            When python-control is not installed.
        """
        try:
            import control
        except ImportError:
            raise MissingDependencyError(
                "control", "control", needed_by="armdyn.actuators.ActuatedArm.to_control"
            ) from None
        A, B = self.linearize(x0, v0)
        return control.ss(A, B, np.eye(self.n_states), np.zeros(B.shape))

    # ----- what the simulation's stepper takes of a plant with drives (armdyn.simulation.DrivenPlant) ---------
    def packed_drives(self) -> np.ndarray:
        """The drives' parameters packed for the compiled model (armdyn.dynamics.drives), (ROWS, n).

        Returns
        -------
        numpy.ndarray
            One row per parameter, one column per joint, with each joint's indices into the state.

        Raises
        ------
        armdyn.ModelError
            When a DC drive has no inductance (its current is then not a state of the full model).
        """
        self._check_full()
        return packing.packed_drives(self)

    def stable_step(self, q: ArrayLike, bandwidth: ArrayLike | None = None) -> float:
        """The RK4 step (s) that resolves the drives' fast dynamics near q (``armdyn.actuators.stable_step``).

        Parameters
        ----------
        q : array_like
            One configuration, (n,).
        bandwidth : array_like or None, optional
            The current loops' w_c (n values), when a law closes them.

        Returns
        -------
        float
            The step, s (math.inf when nothing is fast).

        Raises
        ------
        armdyn.ModelError
            When q is not one configuration.
        armdyn.SingularError
            When M(q) is singular (or too ill-conditioned) at q.
        """
        return packing.stable_step(self, q, bandwidth)

    def drive_record(self, states: np.ndarray, applied: np.ndarray) -> packing.DriveRecord:
        """What the drives did during a run, from its full states (T, n_states) and inputs applied (T, n).

        Parameters
        ----------
        states : numpy.ndarray
            The full state at every sample.
        applied : numpy.ndarray
            The inputs applied at every sample (after their limits).

        Returns
        -------
        DriveRecord
            The states with the currents, spools and load pressures picked out.

        Raises
        ------
        None
            It only slices the states.
        """
        return packing.drive_record(self, states, applied)

    def to_mjcf(self, path: str | os.PathLike[str] | None = None) -> str:
        """The arm with its drives as MuJoCo MJCF text, written to ``path`` when given (``armdyn.io.mjcf_out.to_mjcf``).

        Each rigid DC drive becomes a ``dcmotor`` actuator (gear 1/r, resistance, motor constants,
        inductance, rotor armature and damping, voltage range), whose control is the voltage
        (Section 3.6); a drive without a MuJoCo counterpart gets no actuator, with a warning.

        Parameters
        ----------
        path : str or os.PathLike, optional
            The file to write.

        Returns
        -------
        str
            The MJCF; MuJoCo's M(q) is this arm's M'(q) = M(q) + R^-2 J_M.

        Raises
        ------
        armdyn.ModelError
            For a path that cannot be written.
        """
        from armdyn.io.mjcf_out import to_mjcf

        return to_mjcf(self, path)

    def __repr__(self) -> str:
        kinds = ", ".join(type(drive).__name__ for drive in self.drives)
        return f"ActuatedArm('{self.name}', n={self.n}, drives=[{kinds}])"


def _checked_drives(arm: Robot, drives: object) -> tuple[Drive, ...]:
    """The drives, one per joint, each able to drive its joint, on an arm without motors."""
    where = f"robot '{arm.name}'"
    motors = [link.name for link in arm.links if link.motor_inertia != 0 or link.gear_ratio != 1]
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
    if len(drives) != arm.n:
        raise ModelError(f"drives must be one per joint: {where} has {arm.n} joints {arm.joint_names}; "
                         f"{len(drives)} drives were given")  # fmt: skip
    for link, drive in zip(arm.links, drives, strict=True):
        if not isinstance(drive, (DCMotor, Hydraulic)):
            raise ModelError(f"drives: the drive of joint '{link.name}' must be a DCMotor or Hydraulic, got {drive!r}")
        if isinstance(drive, Hydraulic) and drive.rotary != (link.kind == "revolute"):
            actuator = "a rotary motor" if drive.rotary else "a piston (linear)"
            fit = "rotary=False, a piston" if link.kind == "prismatic" else "rotary=True, a rotary motor"
            raise ModelError(
                f"drives: drive '{drive.name}' is {actuator} and cannot drive the {link.kind} joint '{link.name}' "
                f"(it needs {fit})"
            )
    return tuple(drives)


def with_actuators(arm: Robot, drives: Sequence[Drive]) -> ActuatedArm:
    """The arm-plus-actuator system: ``robot`` with a drive on every joint (Section 3.6).

    Parameters
    ----------
    arm : Robot
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
    return ActuatedArm(arm, drives)


def motor_drives(
    arm: Robot,
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
    ``with_actuators(*motor_drives(arm, ...))`` has M' = arm's M, and F' = arm's F plus the
    back-emf damping G^2 K_b K_M / R_a.

    Parameters
    ----------
    arm : Robot
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
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    inputs.arm_argument(arm, Robot, "arm")
    n = arm.n

    def per_joint(value: object, name: str) -> np.ndarray:
        if isinstance(value, (int, float, np.floating)) and value == math.inf:
            return np.full(n, math.inf)
        array = np.atleast_1d(inputs.numbers(value, name, where=f" for '{arm.name}'"))
        if array.ndim != 1 or array.size not in (1, n):
            raise ModelError(f"{name} must be one value or {n} values (one per joint) for '{arm.name}'")
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
    for j, link in enumerate(arm.links):
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
        for link in arm.links
    ]
    return arm.replace(bare), drives


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


def puma560_with_drives() -> ActuatedArm:
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
