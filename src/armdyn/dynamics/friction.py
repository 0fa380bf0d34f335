"""F(qd) = Fv qd + Fd(qd) (3.3.2) plus the Stribeck and sigmoid laws: the one compiled home of the friction law.

Per joint, joint side: viscous Fv_j qd_j and Coulomb Fd_j = Tc+_j for qd_j > 0, Tc-_j for
qd_j < 0, 0 at rest (Tc- <= 0 <= Tc+); the Stribeck breakaway friction Fs_j exp(-(qd_j/vs_j)^2)
sgn(qd_j) (Armstrong-Helouvry, Dupont and Canudas de Wit, Automatica 30(7), 1994); and the
sigmoid law of Gaz, Cognetti, Oliva, Robuffo Giordano and De Luca (IEEE RA-L 4(4), 2019),
A_j / (1 + exp(-alpha_j (qd_j + shift_j))) - A_j / (1 + exp(-alpha_j shift_j)), smooth and zero
at rest. Simulation smooths the sign of the Coulomb and Stribeck laws through zero velocity
(``smooth_coulomb``: sgn(qd) becomes tanh(qd / eps)) so that a fixed-step integrator does not
chatter; the sigmoid law needs no smoothing. The NumPy mirrors at the end serve the pure-NumPy
callers (the Lagrange-Euler reference, the model-based controllers, the state-space forms).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.packed import (
    COULOMB_NEG,
    COULOMB_POS,
    HEADER,
    N_JOINTS,
    SIGMOID_AMPLITUDE,
    SIGMOID_REST,
    SIGMOID_SHIFT,
    SIGMOID_STEEPNESS,
    STRIBECK_FORCE,
    STRIBECK_SPEED,
    STRIDE,
    VISCOUS,
)
from armdyn.dynamics.spatial import MODEL, NUMBA_OPTIONS, VECTOR, one_state, states_status
from armdyn.dynamics.status import OK, WRONG_SHAPE
from armdyn.errors import ModelError

if TYPE_CHECKING:
    from armdyn.model import ArmModel


@njit(inline="always", **NUMBA_OPTIONS)
def coulomb_torque(positive: float, negative: float, rate: float) -> float:
    """Fd(qd) = Tc+ for qd > 0, Tc- for qd < 0, 0 at rest: the one compiled Coulomb law."""
    return positive if rate > 0.0 else (negative if rate < 0.0 else 0.0)


@njit(inline="always", **NUMBA_OPTIONS)
def smooth_sign(rate: float, eps: float) -> float:
    """tanh(qd / eps), the smoothed sign of the Coulomb law (eps > 0); +-1 from |qd / eps| = 20 on."""
    x = rate / eps
    return math.tanh(x) if abs(x) < 20.0 else (1.0 if x > 0.0 else -1.0)  # tanh(20) = 1 - 8e-18


@njit(inline="always", **NUMBA_OPTIONS)
def exact_sign(rate: float) -> float:
    """sgn(qd): 1, -1, or 0 at rest (the exact sign of the Coulomb and Stribeck laws)."""
    return 1.0 if rate > 0.0 else (-1.0 if rate < 0.0 else 0.0)


@njit(inline="always", **NUMBA_OPTIONS)
def logistic(x: float) -> float:
    """1 / (1 + exp(-x)) without overflow for any x (exp of a non-positive number only)."""
    if x >= 0.0:
        return 1.0 / (1.0 + math.exp(-x))
    e = math.exp(x)
    return e / (1.0 + e)


@njit(inline="always", **NUMBA_OPTIONS)
def coulomb(model: np.ndarray, j: int, rate: float) -> float:
    """Fd_j(qd_j) of the packed model."""
    b = HEADER + STRIDE * j
    return coulomb_torque(model[b + COULOMB_POS], model[b + COULOMB_NEG], rate)


@njit(inline="always", **NUMBA_OPTIONS)
def stribeck_torque(force: float, speed: float, sign: float, rate: float) -> float:
    """Fs exp(-(qd/vs)^2) times ``sign`` (sgn(qd), or its smoothed form); 0 for Fs = 0."""
    if force == 0.0:
        return 0.0
    x = rate / speed
    return force * math.exp(-x * x) * sign


@njit(inline="always", **NUMBA_OPTIONS)
def stribeck_slope(force: float, speed: float, sign: float, sign_slope: float, rate: float) -> float:
    """d/dqd of Fs exp(-(qd/vs)^2) s(qd) for a sign law s with value ``sign`` and slope ``sign_slope``."""
    if force == 0.0:
        return 0.0
    x = rate / speed
    decay = force * math.exp(-x * x)
    return decay * (sign_slope - 2.0 * x / speed * sign)


@njit(inline="always", **NUMBA_OPTIONS)
def sigmoid(model: np.ndarray, j: int, rate: float) -> float:
    """A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift)) of joint j (Gaz et al. 2019); 0 for A = 0."""
    b = HEADER + STRIDE * j
    amplitude = model[b + SIGMOID_AMPLITUDE]
    if amplitude == 0.0:
        return 0.0
    return (
        amplitude * logistic(model[b + SIGMOID_STEEPNESS] * (rate + model[b + SIGMOID_SHIFT])) - model[b + SIGMOID_REST]
    )


@njit(inline="always", **NUMBA_OPTIONS)
def sigmoid_slope(model: np.ndarray, j: int, rate: float) -> float:
    """d/dqd of the sigmoid law of joint j: A alpha s (1 - s), s the logistic at alpha (qd + shift)."""
    b = HEADER + STRIDE * j
    amplitude = model[b + SIGMOID_AMPLITUDE]
    if amplitude == 0.0:
        return 0.0
    steepness = model[b + SIGMOID_STEEPNESS]
    s = logistic(steepness * (rate + model[b + SIGMOID_SHIFT]))
    return amplitude * steepness * s * (1.0 - s)


@njit(inline="always", **NUMBA_OPTIONS)
def stribeck(model: np.ndarray, j: int, rate: float) -> float:
    """Fs_j exp(-(qd_j/vs_j)^2) sgn(qd_j) of the packed model (the exact sign)."""
    b = HEADER + STRIDE * j
    return stribeck_torque(model[b + STRIBECK_FORCE], model[b + STRIBECK_SPEED], exact_sign(rate), rate)


@njit(inline="always", **NUMBA_OPTIONS)
def nonlinear_friction(model: np.ndarray, j: int, rate: float) -> float:
    """The Stribeck and sigmoid friction of joint j (0 when it has neither)."""
    return stribeck(model, j, rate) + sigmoid(model, j, rate)


@njit(inline="always", **NUMBA_OPTIONS)
def joint_friction(model: np.ndarray, j: int, rate: float) -> float:
    """F_j(qd_j) = Fv_j qd_j + Fd_j(qd_j) + Stribeck_j(qd_j) + sigmoid_j(qd_j)."""
    return model[HEADER + STRIDE * j + VISCOUS] * rate + coulomb(model, j, rate) + nonlinear_friction(model, j, rate)


@njit(inline="always", **NUMBA_OPTIONS)
def smooth_coulomb(coulomb_table: np.ndarray, eps: np.ndarray, i: int, rate: float) -> float:
    """Fd_i plus the Stribeck friction, their sign smoothed: tanh(qd / eps_i) Tc+ for qd >= 0,
    -tanh(qd / eps_i) Tc- for qd < 0, plus Fs exp(-(qd/vs)^2) tanh(qd / eps_i); the exact laws for
    eps_i = 0. ``coulomb_table`` is (n, 4): Tc+, Tc-, Fs, vs per joint (``sign_law_table``)."""
    if eps[i] > 0.0:
        smooth = smooth_sign(rate, eps[i])
        value = smooth * coulomb_table[i, 0] if rate >= 0.0 else -smooth * coulomb_table[i, 1]
    else:
        smooth = exact_sign(rate)
        value = coulomb_torque(coulomb_table[i, 0], coulomb_table[i, 1], rate)
    if coulomb_table[i, 2] != 0.0:
        value += stribeck_torque(coulomb_table[i, 2], coulomb_table[i, 3], smooth, rate)
    return value


@njit(inline="always", **NUMBA_OPTIONS)
def friction_core(model: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    for i in range(int(model[N_JOINTS])):
        out[i] = joint_friction(model, i, qd[i])


@one_state(types.int64(MODEL, VECTOR, VECTOR))
def friction_one(model: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """F(qd) for one state; the status of states_status, or WRONG_SHAPE when out has the wrong length."""
    status = states_status(model, qd, qd, qd, 1)
    if status == OK and out.shape[0] != int(model[N_JOINTS]):
        status = WRONG_SHAPE
    if status == OK:
        friction_core(model, qd, out)
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def friction_batch(model: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    for s in prange(qd.shape[0]):
        friction_core(model, qd[s], out[s])


# ----- NumPy mirrors ---------------------------------------------------------------------------------
def sign_law_table(arm: ArmModel) -> np.ndarray:
    """(n, 4): |G| Tc+, |G| Tc-, Fs, vs per joint, the friction whose sign ``smooth_coulomb`` smooths.

    Parameters
    ----------
    arm : ArmModel
        A numeric arm.

    Returns
    -------
    numpy.ndarray
        The table, a new array.
    """
    return np.column_stack([arm.coulomb_friction, arm.stribeck_friction])


def coulomb_vector(coulomb_table: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Fd(qd) by the exact sign law, for NumPy arrays qd (..., n); coulomb_table (n, 2): Tc+, Tc-."""
    return np.where(qd > 0, coulomb_table[:, 0], np.where(qd < 0, coulomb_table[:, 1], 0.0))


def smooth_coulomb_vector(coulomb_table: np.ndarray, eps: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """``smooth_coulomb`` for NumPy arrays qd (..., n): the law the simulated plant follows."""
    smooth = np.tanh(qd / np.where(eps > 0, eps, 1.0))
    smoothed = np.where(qd >= 0, smooth * coulomb_table[:, 0], -smooth * coulomb_table[:, 1])
    return np.where(eps > 0, smoothed, coulomb_vector(coulomb_table, qd))


def stribeck_vector(stribeck_table: np.ndarray, qd: np.ndarray, eps: np.ndarray | None = None) -> np.ndarray:
    """Fs exp(-(qd/vs)^2) sgn(qd) for NumPy arrays qd (..., n), the sign smoothed to tanh(qd / eps) where
    eps > 0 is given (as ``smooth_coulomb``); stribeck_table (n, 2): Fs, vs per joint."""
    force, speed = stribeck_table[:, 0], np.where(stribeck_table[:, 0] > 0, stribeck_table[:, 1], 1.0)
    sign = np.where(qd > 0, 1.0, np.where(qd < 0, -1.0, 0.0))  # complex qd: NumPy's ordering, as coulomb_vector
    if eps is not None:
        sign = np.where(eps > 0, np.tanh(qd / np.where(eps > 0, eps, 1.0)), sign)
    return force * np.exp(-((qd / speed) ** 2)) * sign


def logistic_vector(x: np.ndarray) -> np.ndarray:
    """1 / (1 + exp(-x)) elementwise without overflow (exp of a number of non-positive real part only);
    complex x (a complex step) is kept."""
    positive = np.real(x) >= 0
    e = np.exp(np.where(positive, -x, x))
    return np.where(positive, 1.0 / (1.0 + e), e / (1.0 + e))


def sigmoid_vector(sigmoid_table: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift)) (Gaz et al. 2019) for NumPy arrays
    qd (..., n); sigmoid_table (n, 3): A, alpha, shift per joint."""
    amplitude, steepness, shift = sigmoid_table[:, 0], sigmoid_table[:, 1], sigmoid_table[:, 2]
    return amplitude * (logistic_vector(steepness * (qd + shift)) - logistic_vector(steepness * shift))


def friction_vector(arm: ArmModel, qd: np.ndarray, eps: np.ndarray | None = None) -> np.ndarray:
    """F(qd) = Fv qd + Fd(qd) + Stribeck + sigmoid for NumPy arrays qd (..., n), the sign of the Coulomb and
    Stribeck laws smoothed where eps > 0 is given (the law simulate's plant follows).

    Parameters
    ----------
    arm : ArmModel
        A numeric arm.
    qd : numpy.ndarray
        Joint velocities, (..., n).
    eps : numpy.ndarray, optional
        Smoothing per joint (n,), >= 0; None (default) for the exact sign law.

    Returns
    -------
    numpy.ndarray
        F(qd), (..., n).
    """
    table = arm.coulomb_friction
    sign_law = coulomb_vector(table, qd) if eps is None else smooth_coulomb_vector(table, eps, qd)
    value = arm.viscous_friction * qd + sign_law
    stribeck_table, sigmoid_table = arm.stribeck_friction, arm.sigmoid_friction
    if np.any(stribeck_table[:, 0] != 0):
        value = value + stribeck_vector(stribeck_table, qd, eps)
    if np.any(sigmoid_table[:, 0] != 0):
        value = value + sigmoid_vector(sigmoid_table, qd)
    return value


def refuse_nonlinear_friction(arm: ArmModel, what: str) -> None:
    """A ModelError naming the first link with Stribeck or sigmoid friction, for ``what`` (a closed form or
    generated code, written for viscous and Coulomb friction only).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    what : str
        What refuses it, for the message.

    Raises
    ------
    armdyn.ModelError
        When a link has Stribeck (Fs > 0) or sigmoid (A > 0) friction.
    """
    for link in arm.links:
        for law, value in (("Stribeck", link.stribeck), ("sigmoid", link.sigmoid)):
            if value[0] != 0:
                raise ModelError(
                    f"link '{link.name}': {what} supports viscous and Coulomb friction only, not its {law} friction "
                    f"{tuple(value)}; derive without friction (friction=False) or give the link none"
                )
