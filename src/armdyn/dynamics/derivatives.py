"""Analytic derivatives of the inverse dynamics: d tau / dq and d tau / dqd, by differentiating the
recursive Newton-Euler algorithm along with it (Carpentier and Mansard, "Analytical Derivatives of
Rigid Body Dynamics Algorithms", RSS 2018, in body coordinates; BOOK.md section 5's RNEA).

The RNEA in spatial vectors (Featherstone 2008, 5.3), joint i moving along S (e_z of its frame):

    v_i = X_i v_p + S qd_i,   a_i = X_i a_p + S qdd_i + v_i x S qd_i,   f_i = I_i a_i + v_i x* I_i v_i
    F_i = f_i + sum over children c of X_c^T F_c,   tau_i = S^T F_i (+ armature qdd_i + friction)

Only X_i depends on q, and only on q_i: dX_i/dq_i = -(S x) X_i, so dX_i/dq_i u = (X_i u) x S. The
derivatives follow the same two passes, for every direction k at once (dv[i, k] = dv_i/dq_k):

    dv_i = X_i dv_p + [i = k] (X_i v_p) x S
    da_i = X_i da_p + [i = k] (X_i a_p) x S + dv_i x S qd_i
    df_i = I_i da_i + dv_i x* I_i v_i + v_i x* I_i dv_i
    dF_p += X_i^T dF_i + [i = k] X_i^T (S x* F_i),   dtau_i = S^T dF_i

and for qd: dv_i = X_i dv_p + [i = k] S, da_i = X_i da_p + dv_i x S qd_i + [i = k] v_i x S, the
force and backward terms as above without the [i = k] transform terms; the viscous friction adds
its coefficient to the diagonal (Coulomb friction is constant away from zero velocity).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from armdyn.dynamics.packed import (
    FIRST_MOMENT,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    N_JOINTS,
    POSITION,
    ROTATION,
    STRIDE,
    VISCOUS,
)
from armdyn.dynamics.rnea import inverse_dynamics_one
from armdyn.dynamics.spatial import NUMBA_OPTIONS


@njit(inline="always", **NUMBA_OPTIONS)
def _cross_motion(v: np.ndarray, u: np.ndarray, out: np.ndarray) -> None:
    """out = v x u for motion vectors [angular; linear] (Featherstone's crm(v) u)."""
    out[0] = v[1] * u[2] - v[2] * u[1]
    out[1] = v[2] * u[0] - v[0] * u[2]
    out[2] = v[0] * u[1] - v[1] * u[0]
    out[3] = v[1] * u[5] - v[2] * u[4] + v[4] * u[2] - v[5] * u[1]
    out[4] = v[2] * u[3] - v[0] * u[5] + v[5] * u[0] - v[3] * u[2]
    out[5] = v[0] * u[4] - v[1] * u[3] + v[3] * u[1] - v[4] * u[0]


@njit(inline="always", **NUMBA_OPTIONS)
def _cross_force(v: np.ndarray, f: np.ndarray, out: np.ndarray) -> None:
    """out = v x* f for a motion vector v and a force vector f (Featherstone's crf(v) f)."""
    out[0] = v[1] * f[2] - v[2] * f[1] + v[4] * f[5] - v[5] * f[4]
    out[1] = v[2] * f[0] - v[0] * f[2] + v[5] * f[3] - v[3] * f[5]
    out[2] = v[0] * f[1] - v[1] * f[0] + v[3] * f[4] - v[4] * f[3]
    out[3] = v[1] * f[5] - v[2] * f[4]
    out[4] = v[2] * f[3] - v[0] * f[5]
    out[5] = v[0] * f[4] - v[1] * f[3]


@njit(**NUMBA_OPTIONS)
def _joint_frames(model: np.ndarray, q: np.ndarray, X: np.ndarray, inertia: np.ndarray, S: np.ndarray) -> None:
    """X_i (6, 6) from the parent's to joint i's coordinates, I_i (6, 6) about the body origin and S_i (6,)."""
    n = int(model[N_JOINTS])
    R = np.empty((3, 3))
    for i in range(n):
        b = HEADER + STRIDE * i
        for r in range(3):
            for c in range(3):
                R[r, c] = model[b + ROTATION + 3 * r + c]
        px, py, pz = model[b + POSITION], model[b + POSITION + 1], model[b + POSITION + 2]
        S[i, :] = 0.0
        if model[b + KIND] == 0.0:
            c, s = np.cos(q[i]), np.sin(q[i])
            for r in range(3):
                first, second = R[r, 0], R[r, 1]
                R[r, 0] = first * c + second * s
                R[r, 1] = second * c - first * s
            S[i, 2] = 1.0
        else:
            px, py, pz = px + q[i] * R[0, 2], py + q[i] * R[1, 2], pz + q[i] * R[2, 2]
            S[i, 5] = 1.0
        # X = [R^T, 0; -R^T [p]x, R^T]: the child's axes, the child's origin
        for r in range(3):
            for c in range(3):
                X[i, r, c] = X[i, 3 + r, 3 + c] = R[c, r]
                X[i, r, 3 + c] = 0.0
            # row r of -R^T [p]x: -(column r of R) x p ... written as -(R^T [p]x)[r, :]
            a0, a1, a2 = R[0, r], R[1, r], R[2, r]
            X[i, 3 + r, 0] = -(a1 * pz - a2 * py)
            X[i, 3 + r, 1] = -(a2 * px - a0 * pz)
            X[i, 3 + r, 2] = -(a0 * py - a1 * px)
        m = model[b + MASS]
        hx, hy, hz = model[b + FIRST_MOMENT], model[b + FIRST_MOMENT + 1], model[b + FIRST_MOMENT + 2]
        k = b + INERTIA
        body = inertia[i]
        body[0, 0], body[0, 1], body[0, 2] = model[k], model[k + 1], model[k + 2]
        body[1, 0], body[1, 1], body[1, 2] = model[k + 1], model[k + 3], model[k + 4]
        body[2, 0], body[2, 1], body[2, 2] = model[k + 2], model[k + 4], model[k + 5]
        # [[I_O, [h]x], [-[h]x, m 1]]
        body[0, 3], body[0, 4], body[0, 5] = 0.0, -hz, hy
        body[1, 3], body[1, 4], body[1, 5] = hz, 0.0, -hx
        body[2, 3], body[2, 4], body[2, 5] = -hy, hx, 0.0
        body[3, 0], body[3, 1], body[3, 2] = 0.0, hz, -hy
        body[4, 0], body[4, 1], body[4, 2] = -hz, 0.0, hx
        body[5, 0], body[5, 1], body[5, 2] = hy, -hx, 0.0
        for r in range(3):
            for c in range(3):
                body[3 + r, 3 + c] = m if r == c else 0.0


@njit(inline="always", **NUMBA_OPTIONS)
def _times(A: np.ndarray, u: np.ndarray, out: np.ndarray) -> None:
    """out = A u for a 6 x 6 matrix (written out: no temporary, no BLAS call)."""
    for r in range(6):
        total = 0.0
        for c in range(6):
            total += A[r, c] * u[c]
        out[r] = total


@njit(inline="always", **NUMBA_OPTIONS)
def _add_transposed(A: np.ndarray, u: np.ndarray, out: np.ndarray) -> None:
    """out += A^T u for a 6 x 6 matrix."""
    for c in range(6):
        total = 0.0
        for r in range(6):
            total += A[r, c] * u[r]
        out[c] += total


@njit(**NUMBA_OPTIONS)
def rnea_derivatives_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, dq: np.ndarray,
                         dqd: np.ndarray) -> int:  # fmt: skip
    """d tau/dq and d tau/dqd (n, n) of tau = M qdd + Vm qd + F + G at one state (the module's
    recursion); 0, or the status of the inverse dynamics (a state that is not finite).

    Only directions k that are joint i or an ancestor of it move body i (``moves``), so the forward
    pass skips the others."""
    n = int(model[N_JOINTS])
    tau = np.empty(n)
    status = inverse_dynamics_one(model, q, qd, qdd, tau)  # checks the state
    if status != 0:
        return status
    X, inertia, S = np.empty((n, 6, 6)), np.empty((n, 6, 6)), np.empty((n, 6))
    _joint_frames(model, q, X, inertia, S)
    moves = np.zeros((n, n), dtype=np.bool_)
    for i in range(n):
        moves[i, i] = True
        parent = int(model[HEADER + STRIDE * i])
        if parent >= 0:
            for k in range(n):
                moves[i, k] = moves[i, k] or moves[parent, k]
    v, a, F = np.zeros((n, 6)), np.zeros((n, 6)), np.zeros((n, 6))
    dv, da, dF = np.zeros((2, n, n, 6)), np.zeros((2, n, n, 6)), np.zeros((2, n, n, 6))
    base_v, base_a = np.zeros(6), np.zeros(6)
    base_a[3], base_a[4], base_a[5] = -model[1], -model[2], -model[3]  # a_0 = -g
    Xv, Xa, work, other, momentum, dmomentum, push = (np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6),
                                                      np.empty(6), np.empty(6))  # fmt: skip
    for i in range(n):
        parent = int(model[HEADER + STRIDE * i])
        _times(X[i], v[parent] if parent >= 0 else base_v, Xv)
        _times(X[i], a[parent] if parent >= 0 else base_a, Xa)
        _cross_motion(Xv, S[i], push)  # (X v_p) x S: also v_i x S, as S x S = 0
        for r in range(6):
            v[i, r] = Xv[r] + S[i, r] * qd[i]
            a[i, r] = Xa[r] + S[i, r] * qdd[i] + push[r] * qd[i]
        _times(inertia[i], v[i], momentum)
        _cross_force(v[i], momentum, other)
        _times(inertia[i], a[i], work)
        for r in range(6):
            F[i, r] = work[r] + other[r]
        for w in range(2):  # w = 0: d/dq, w = 1: d/dqd
            for k in range(n):
                if not moves[i, k]:
                    continue
                tangent, rate = dv[w, i, k], da[w, i, k]
                if parent >= 0 and k != i:
                    _times(X[i], dv[w, parent, k], tangent)
                    _times(X[i], da[w, parent, k], rate)
                elif k == i:
                    if parent >= 0:
                        _times(X[i], dv[w, parent, k], tangent)
                        _times(X[i], da[w, parent, k], rate)
                    if w == 0:
                        _cross_motion(Xa, S[i], work)
                        for r in range(6):
                            tangent[r] += push[r]
                            rate[r] += work[r]
                    else:
                        for r in range(6):
                            tangent[r] += S[i, r]
                            rate[r] += push[r]
                _cross_motion(tangent, S[i], work)
                for r in range(6):
                    rate[r] += work[r] * qd[i]
                _times(inertia[i], tangent, dmomentum)
                _cross_force(tangent, momentum, work)
                _cross_force(v[i], dmomentum, other)
                _times(inertia[i], rate, dF[w, i, k])
                for r in range(6):
                    dF[w, i, k, r] += work[r] + other[r]
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        parent = int(model[b])
        axis = 2 if model[b + KIND] == 0.0 else 5  # S = e_axis
        for k in range(n):
            dq[i, k] = dF[0, i, k, axis]
            dqd[i, k] = dF[1, i, k, axis]
        dqd[i, i] += model[b + VISCOUS]
        if parent >= 0:
            _add_transposed(X[i], F[i], F[parent])
            _cross_force(S[i], F[i], work)
            _add_transposed(X[i], work, dF[0, parent, i])
            for w in range(2):
                for k in range(n):
                    _add_transposed(X[i], dF[w, i, k], dF[w, parent, k])
    return 0


@njit(parallel=True, **NUMBA_OPTIONS)
def rnea_derivatives_batch(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray, DQ: np.ndarray,
                           DQD: np.ndarray, status: np.ndarray) -> None:  # fmt: skip
    """rnea_derivatives_one over the rows of (B, n) states, in parallel; status (B,) per state."""
    for s in prange(Q.shape[0]):
        status[s] = rnea_derivatives_one(model, Q[s], QD[s], QDD[s], DQ[s], DQD[s])
