"""F(qd) = Fv qd + Fd(qd) (3.3.2): the one compiled home of the friction law.

Per joint, joint side: viscous Fv_j qd_j and Coulomb Fd_j = Tc+_j for qd_j > 0, Tc-_j for
qd_j < 0, 0 at rest (Tc- <= 0 <= Tc+). Simulation smooths the Coulomb step through zero
velocity (``smooth_coulomb``) so that a fixed-step integrator does not chatter.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.packed import COULOMB_NEG, COULOMB_POS, HEADER, N_JOINTS, STRIDE, VISCOUS
from armdyn.dynamics.spatial import MODEL, NUMBA_OPTIONS, VECTOR, one_state, states_status
from armdyn.dynamics.status import OK, WRONG_SHAPE


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
def coulomb(model: np.ndarray, j: int, rate: float) -> float:
    """Fd_j(qd_j) of the packed model."""
    b = HEADER + STRIDE * j
    return coulomb_torque(model[b + COULOMB_POS], model[b + COULOMB_NEG], rate)


@njit(inline="always", **NUMBA_OPTIONS)
def joint_friction(model: np.ndarray, j: int, rate: float) -> float:
    """F_j(qd_j) = Fv_j qd_j + Fd_j(qd_j)."""
    return model[HEADER + STRIDE * j + VISCOUS] * rate + coulomb(model, j, rate)


@njit(inline="always", **NUMBA_OPTIONS)
def smooth_coulomb(coulomb_table: np.ndarray, eps: np.ndarray, i: int, rate: float) -> float:
    """Fd_i smoothed: tanh(qd / eps_i) Tc+ for qd >= 0, -tanh(qd / eps_i) Tc- for qd < 0; the exact
    law for eps_i = 0. ``coulomb_table`` is (n, 2): Tc+, Tc- per joint."""
    if eps[i] > 0.0:
        smooth = smooth_sign(rate, eps[i])
        return smooth * coulomb_table[i, 0] if rate >= 0.0 else -smooth * coulomb_table[i, 1]
    return coulomb_torque(coulomb_table[i, 0], coulomb_table[i, 1], rate)


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


def coulomb_vector(coulomb_table: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Fd(qd) by the exact sign law, for NumPy arrays qd (..., n); coulomb_table (n, 2): Tc+, Tc-."""
    return np.where(qd > 0, coulomb_table[:, 0], np.where(qd < 0, coulomb_table[:, 1], 0.0))


def smooth_coulomb_vector(coulomb_table: np.ndarray, eps: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """``smooth_coulomb`` for NumPy arrays qd (..., n): the law the simulated plant follows."""
    smooth = np.tanh(qd / np.where(eps > 0, eps, 1.0))
    smoothed = np.where(qd >= 0, smooth * coulomb_table[:, 0], -smooth * coulomb_table[:, 1])
    return np.where(eps > 0, smoothed, coulomb_vector(coulomb_table, qd))
