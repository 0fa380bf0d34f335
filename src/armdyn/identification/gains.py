"""Drive gains from motor currents and a payload of known mass: the global identification of Gautier and Briot.

A drive's joint torque is its current times a gain (torque constant, gear ratio and efficiency
together): tau_j = g_j i_j. From currents alone the gains and the dynamic parameters are known
only up to one common scale (g and phi_b scaled together explain the same currents); a run with a
payload of known inertial parameters phi_K fixes it. Both runs stacked, the unknowns [g, phi_b]
solve (Gautier and Briot, "Global identification of joint drive gains and dynamic parameters of
robots", ASME J. Dyn. Syst. Meas. Control 136(5), 051025, 2014)::

    unloaded:  diag(i) g - W_b(q, qd, qdd) phi_b = 0
    loaded:    diag(i) g - W_b(q, qd, qdd) phi_b = W_K(q, qd, qdd) phi_K

with W_b the arm's base regressor and W_K the ten columns, in the full regressor W, of the link
carrying the payload (Table 3.3.1, property 9 of Lewis, Dawson and Abdallah 2004). Solved by
ordinary least squares or by total least squares (the smallest right singular vector of the
column-scaled [A, y], which also lets the currents' columns be noisy: the default, as ordinary
least squares is biased by the noise of the currents).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from armdyn import inputs
from armdyn.dynamics.regressor import BaseParameters, base_parameters
from armdyn.errors import ArgumentError, ModelError
from armdyn.identification.payload import (
    BODY,
    LEAST_SQUARES,
    body_parameters,
    run_arrays,
    run_regressor,
    stacked_least_squares,
)
from armdyn.kinematics import check_arm, link_index
from armdyn.model import ArmModel

CURRENT_FIELDS = ("q", "qd", "qdd", "current")


class CurrentSamples(Protocol):
    """Samples of one run with motor currents: anything with attributes q, qd, qdd and current, each (N, n).

    A tuple (q, qd, qdd, current) is taken as well.
    """

    q: object
    qd: object
    qdd: object
    current: object


def torques_from_currents(current: object, gains: object) -> np.ndarray:
    """Joint torques tau_j = g_j i_j from motor currents and current-to-torque gains.

    Each gain holds the motor's torque constant, the gear ratio and the efficiency, so that
    g_j i_j is the torque at joint j (N m, or N for a prismatic joint).

    Parameters
    ----------
    current : array_like
        Motor currents (A), (n,) or a batch (..., n).
    gains : array_like
        The gains g (N m/A or N/A), (n,), finite and non-zero.

    Returns
    -------
    numpy.ndarray
        tau, of the shape of ``current``.

    Raises
    ------
    armdyn.ModelError
        When ``gains`` is not n finite non-zero numbers, or ``current`` is not finite numbers of
        shape (..., n).
    """
    g = inputs.vector(gains, "gains")
    if np.any(g == 0):
        raise ModelError(f"gains must be non-zero (N m/A): gain {int(np.flatnonzero(g == 0)[0]) + 1} is 0")
    i = inputs.state(current, g.size, "current", f" for {g.size} gains")
    return i * g


@dataclass(frozen=True, eq=False)
class GainEstimate:
    """Drive gains and the arm's base parameters estimated together, with standard errors.

    Made by ``identify_gains``.

    Parameters
    ----------
    gains : numpy.ndarray
        The current-to-torque gains g (N m/A), (n,).
    base : BaseParameters
        The arm's base parameters estimated alongside.
    phi : numpy.ndarray
        Their estimate, (r,).
    covariance : numpy.ndarray
        The covariance of [g, phi], (n + r, n + r).
    condition_number : float
        The condition number of the stacked equations' matrix.
    residual_rms : float
        The root-mean-square equation residual (N m).
    samples : int
        The samples used, of both runs.
    method : str
        "ols" or "tls".
    """

    gains: np.ndarray
    base: BaseParameters
    phi: np.ndarray
    covariance: np.ndarray
    condition_number: float
    residual_rms: float
    samples: int
    method: str

    @property
    def gain_standard_errors(self) -> np.ndarray:
        """The standard errors of the gains (N m/A), (n,)."""
        n = self.gains.size
        return np.sqrt(np.diag(self.covariance)[:n])

    @property
    def standard_errors(self) -> np.ndarray:
        """The standard errors of the base parameters, (r,)."""
        n = self.gains.size
        return np.sqrt(np.diag(self.covariance)[n:])

    def torques(self, current: object) -> np.ndarray:
        """The joint torques of currents with the estimated gains, ``torques_from_currents(current, gains)``.

        Parameters
        ----------
        current : array_like
            Motor currents (A), (n,) or (..., n).

        Returns
        -------
        numpy.ndarray
            tau, of the shape of ``current``.

        Raises
        ------
        armdyn.ModelError
            When ``current`` is not finite numbers of shape (..., n).
        """
        return torques_from_currents(current, self.gains)


def _current_block(current: np.ndarray) -> np.ndarray:
    """diag(i) g as a matrix acting on g: row (k, j) holds i_kj in column j, (N n, n)."""
    samples, n = current.shape
    block = np.zeros((samples, n, n))
    block[:, np.arange(n), np.arange(n)] = current
    return block.reshape(-1, n)


def identify_gains(
    arm: ArmModel,
    unloaded: CurrentSamples | tuple,
    loaded: CurrentSamples | tuple,
    payload_mass: float,
    payload_com: object = (0.0, 0.0, 0.0),
    payload_inertia: object = None,
    link: int | str | None = None,
    method: str = "tls",
    drives: bool = True,
) -> GainEstimate:
    """Drive gains and base parameters from currents of an unloaded run and a run with a known payload.

    The global identification of Gautier and Briot (ASME J. Dyn. Syst. Meas. Control 136(5),
    2014): the unknowns [g, phi_b] of both runs stacked::

        [ diag(i_u)  -W_b(u) ] [ g     ]   [ 0                   ]
        [ diag(i_l)  -W_b(l) ] [ phi_b ] = [ W_K(l) phi_K         ]

    phi_K the known payload's ten parameters on link K (``body_parameters(payload_mass,
    payload_com, payload_inertia)``), W_K that link's columns of the regressor; by total ("tls",
    default) or ordinary ("ols") least squares (``stacked_least_squares``). The noise of the
    currents sits in the matrix, not the right-hand side, and ordinary least squares shrinks
    the gains by about the ratio of its variance to that of the currents' part the payload
    explains (about 1% for 1% current noise and a payload giving a tenth of the torques); total
    least squares does not. Standard errors come from each joint's own residual variance in each
    run (as ``armdyn.identify``). The unloaded run is needed: with the loaded run alone, the
    payload only changes the base parameters and the scale stays free. The
    payload's torques fix the scale of every gain, so they must be large against the noise at
    every joint (a heavy payload, moved fast).

    Parameters
    ----------
    arm : ArmModel
        The arm without the payload (its structure).
    unloaded : CurrentSamples or tuple
        The run without the payload: q, qd, qdd and current (A), each (N_u, n).
    loaded : CurrentSamples or tuple
        The run with the payload, likewise (N_l, n).
    payload_mass : float
        The payload's mass (kg), > 0.
    payload_com : array_like, optional
        Its centre of mass in the link's frame (m), default the origin.
    payload_inertia : array_like, optional
        Its inertia about its centre of mass, link axes: 3 moments, 6 values [Ixx Iyy Izz Ixy
        Iyz Ixz] or 3x3; default None, a point mass.
    link : int, str or None, optional
        The link carrying the payload, by index or name; default None, the arm's tool link.
    method : str, optional
        "tls" (default), total least squares, or "ols", ordinary least squares.
    drives : bool, optional
        True (default) also estimates the arm's friction and motor parameters; False only its
        rigid-body ones.

    Returns
    -------
    GainEstimate
        The gains and base parameters, their covariance and the condition number.

    Warns
    -----
    armdyn.dynamics.regressor.PoorExcitationWarning
        When the condition number of the stacked matrix is above POOR_CONDITION.

    Raises
    ------
    armdyn.ModelError
        When a run's arrays are not finite (N, n) numbers holding the same samples, the payload's
        mass is not positive or its mass properties are not a rigid body's, ``link`` names no
        link, ``method`` is unknown, there are too few samples, or the samples do not excite the
        unknowns (the rank and condition number are named).
    armdyn.ArgumentError
        When ``arm`` is not a numeric armdyn arm, a run is neither a tuple of four arrays nor has
        the four attributes, or ``drives`` is not a bool.
    """
    check_arm(arm, True)
    index = link_index(arm, link)
    mass = inputs.number(payload_mass, "payload_mass")
    if not mass > 0:
        raise ModelError(
            f"payload_mass must be positive (kg): the known payload fixes the scale of the gains, got {mass:g}"
        )
    known = body_parameters(mass, payload_com, payload_inertia)
    if method not in LEAST_SQUARES:
        raise ModelError(f"method must be one of {', '.join(LEAST_SQUARES)}, got {method!r}")
    if not isinstance(drives, (bool, np.bool_)):
        raise ArgumentError(f"drives must be True or False, got {drives!r}")
    if unloaded is None:
        raise ArgumentError("identify_gains needs the unloaded run: with the loaded run alone the scale is free")
    n = arm.n
    base = base_parameters(arm, drives=bool(drives))
    r = len(base)
    rows, rights, groups = [], [], []
    for number, (run, label) in enumerate(((unloaded, "the unloaded run"), (loaded, "the loaded run"))):
        q, qd, qdd, current = run_arrays(run, arm, label, CURRENT_FIELDS)
        W = run_regressor(arm, run, q, qd, qdd)
        rows.append(np.column_stack([_current_block(current), -W[..., base.columns].reshape(-1, r)]))
        payload = W[..., BODY * index : BODY * (index + 1)] @ known
        rights.append(payload.reshape(-1) if number else np.zeros(len(q) * n))
        groups.append(number * n + np.tile(np.arange(n), len(q)))
    A, y, group = np.vstack(rows), np.concatenate(rights), np.concatenate(groups)
    what = f"the {n} drive gains and the {r} base parameters of '{arm.name}'"
    fit = stacked_least_squares(A, y, group, what, method)
    return GainEstimate(
        fit.x[:n], base, fit.x[n:], fit.covariance, fit.condition_number, fit.residual_rms, len(A) // n, method
    )
