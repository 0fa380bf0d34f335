"""Representative drives for an arm: DC motors or valves sized from the torques and speeds its links
need over sampled configurations (Section 3.6)."""

from __future__ import annotations

import dataclasses
import math
import reprlib

import numpy as np

from armdyn import inputs
from armdyn.actuators.arm import ActuatedArm, _joint_sense, with_actuators
from armdyn.actuators.hydraulics import Hydraulic
from armdyn.actuators.motors import DCMotor
from armdyn.errors import ModelError
from armdyn.model.arm import Link
from armdyn.robot import Robot

_KINDS = ("dc", "flexible", "hydraulic")
_SUPPLY = 21e6  # Pa: a common industrial supply pressure


def _configurations(arm: Robot, samples: int = 256) -> np.ndarray:
    """Configurations drawn within the joint limits (+-pi, +-0.5 m where unlimited), seeded."""
    rng = np.random.default_rng(0)
    limits = np.array([link.limits for link in arm.links], dtype=float)
    span = np.where(np.array(arm.kinds) == "revolute", np.pi, 0.5)
    low, high = (
        np.where(np.isfinite(limits[:, 0]), limits[:, 0], -span),
        np.where(np.isfinite(limits[:, 1]), limits[:, 1], span),
    )
    return rng.uniform(low, high, (samples, arm.n))


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


def representative_drives(arm: Robot, kind: str = "dc") -> ActuatedArm:
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
    arm : Robot
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
    armdyn.ArgumentError
        When ``arm`` is not a Robot (a ModelError and a TypeError).
    """
    inputs.arm_argument(arm, Robot, name="arm")
    if kind not in _KINDS:
        raise ModelError(f"kind must be one of {', '.join(_KINDS)}, got {reprlib.repr(kind)}")
    samples = _configurations(arm)
    loads = np.abs(arm.gravity_vector(samples)).max(axis=0)
    revolute = [k == "revolute" for k in arm.kinds]
    names = arm.joint_names
    if kind == "hydraulic":
        bare_robot = arm.replace([dataclasses.replace(link, motor_inertia=0.0, gear_ratio=1.0)
                                    for link in arm.links])  # fmt: skip
        inertia = np.diagonal(bare_robot.inertia_matrix(samples), axis1=-2, axis2=-1).mean(axis=0)
        valves = [_representative_valve(revolute[j], loads[j], max(inertia[j], 1e-3), f"valve {names[j]}")
                  for j in range(arm.n)]  # fmt: skip
        return with_actuators(bare_robot, valves)
    drives = [_representative_motor(link, revolute[j], loads[j], f"motor {names[j]}")
              for j, link in enumerate(arm.links)]  # fmt: skip
    bare = [
        dataclasses.replace(link, motor_inertia=0.0, gear_ratio=1.0, viscous=0.0, coulomb=(0.0, 0.0))
        if link.gear_ratio != 1.0
        else dataclasses.replace(link, motor_inertia=0.0)
        for link in arm.links
    ]
    bare_robot = arm.replace(bare)
    if kind == "flexible":
        inertia = np.diagonal(bare_robot.inertia_matrix(samples), axis1=-2, axis2=-1).mean(axis=0)
        rotors = np.array([drive.rotor_inertia / drive.gear_ratio**2 for drive in drives])
        inertia = np.where(inertia > 1e-9 * rotors, inertia, rotors)  # a link that moves no inertia of its own
        stiffness = (2 * math.pi * 10.0) ** 2 * inertia
        drives = [dataclasses.replace(drive, stiffness=K, shaft_damping=2 * 0.05 * math.sqrt(K * m))
                  for drive, K, m in zip(drives, stiffness, inertia, strict=True)]  # fmt: skip
    return with_actuators(bare_robot, drives)
