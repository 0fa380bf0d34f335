"""The hydraulic drive: a servo valve and a piston (or rotary motor) after Merritt (1967), with the
linearized or the square-root orifice flow (Section 3.6)."""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass

import numpy as np

from armdyn.actuators.checks import _drive_name, _limit, _non_negative, _positive
from armdyn.errors import ArgumentError, ModelError


@dataclass(frozen=True)
class Hydraulic:
    """A servo valve and a piston (or rotary motor) after Merritt (1967) (Section 3.6).

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
        |x_v| <= stroke, m (default math.inf): a hard stop; the spool's rate is zero there when the valve
        pushes it outward, and a simulation keeps it within the stroke at every RK4 stage.
    name : str, optional
        The drive's name, used in messages (default "hydraulic").

    Raises
    ------
    armdyn.ModelError
        When a parameter is not a finite real number (a limit may be math.inf) or breaks its sign
        rule (tau_v, K_v, K_q, A, V_t, beta_e, P_s, C_d, w, rho and the limits > 0; K_c, C_tp >= 0),
        when ``orifice`` is neither "linear" nor "sqrt", when the square-root orifice lacks C_d, w
        or rho, or the linear one lacks K_q; the message names the drive and the rule.
    armdyn.ArgumentError
        When ``rotary`` is not a bool (a ModelError and a TypeError).
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
            raise ArgumentError(f"{where}: rotary must be True or False, got {reprlib.repr(self.rotary)}")
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
        C_d, w, rho = self.discharge_coefficient, self.orifice_width, self.density
        assert C_d is not None and w is not None and rho is not None  # the square-root orifice has them (checked)
        return C_d * w * math.sqrt(self.supply_pressure / rho)

    @property
    def capacitance(self) -> float:
        """V_t / (4 beta_e), m^3/Pa: the hydraulic capacitance of the continuity equation."""
        return self.volume / (4 * self.bulk_modulus)

    @property
    def total_coefficient(self) -> float:
        """K_ce = K_c + C_tp, m^3/(s Pa): the pressure coefficient of the reduced model."""
        return self.pressure_coefficient + self.leakage
