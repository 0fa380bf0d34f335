"""Analytic derivatives of the robot equation: d tau/dq, d tau/dqd (and M = d tau/dqdd) of the
inverse dynamics, and d qdd/dq, d qdd/dqd, d qdd/dtau of the forward dynamics (Carpentier and
Mansard, "Analytical Derivatives of Rigid Body Dynamics Algorithms", RSS 2018; Section 3.4).

World frame, joint k moving along S_k (a motion vector that depends on q through the joints
above k). Turning joint k moves its whole subtree rigidly: every vector attached to it is
carried by S_k x (a force by S_k x*), and the pairing S_j^T F_j is invariant under that carrying.
What is left over is the same for every body below k:

    dv_i/dq_k  = S_k x v_i + dV_k,                 dV_k = v_lambda(k) x S_k
    da_i/dq_k  = S_k x a_i + dA_k + dV_k x v_i,    dA_k = a_lambda(k) x S_k + v_lambda(k) x dV_k
    dv_i/dqd_k = S_k,  da_i/dqd_k = dAv_k + S_k x v_i,    dAv_k = v_k x S_k + dV_k = 2 dV_k

(a_0 = -g). For f_i = I_i a_i + v_i x* I_i v_i this gives, with D_i = (v_i x*) I_i - I_i (v_i x)
+ (I_i v_i) xbar* (twice the body Coriolis matrix B_i of coriolis.body_coriolis) and the
composites I^C_j, D^C_j, F^C_j summed over the subtree of j:

    d tau_j/dq_k  = S_j^T (S_k x* F^C_k + I^C_k dA_k + D^C_k dV_k)      k in the subtree of j
    d tau_j/dq_k  = (I^C_j S_j)^T dA_k + (D^C_j^T S_j)^T dV_k           k above j
    d tau_j/dqd_k = S_j^T (I^C_k dAv_k + D^C_k S_k)                      k in the subtree of j
    d tau_j/dqd_k = (I^C_j S_j)^T dAv_k + (D^C_j^T S_j)^T S_k           k above j
    M_jk = S_j^T I^C_k S_k                                              k in the subtree of j

(zero for joints on different branches): O(n d) work for depth d, a few dot products per pair.
The motor terms add the reflected inertia to M's diagonal and the viscous friction to d tau/dqd's;
the Coulomb law is constant away from zero velocity and adds d/dqd of its smoothed form
tanh(qd / eps) Tc where a smoothing eps > 0 is given (friction.smooth_coulomb); the Stribeck law
adds its slope (its sign smoothed alike) and the sigmoid law A alpha s (1 - s).

Forward dynamics: qdd = FD(q, qd, tau) by the articulated-body algorithm, then the derivatives
above at (q, qd, qdd) and one Cholesky factorization of M: d qdd/dq = -M^-1 d tau/dq,
d qdd/dqd = -M^-1 d tau/dqd (by triangular solves) and d qdd/dtau = M^-1.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.aba import aba_core
from armdyn.dynamics.coriolis import body_coriolis
from armdyn.dynamics.friction import exact_sign, sigmoid_slope, smooth_sign, stribeck_slope, stribeck_torque
from armdyn.dynamics.linalg import cholesky, cholesky_solve
from armdyn.dynamics.packed import (
    ABA_FIXED,
    ABA_JOINT,
    ARMATURE,
    COMPOSITE,
    COMPOSITE_BIAS,
    COULOMB_NEG,
    COULOMB_POS,
    DERIVATIVE_ACCELERATION,
    DERIVATIVE_BIAS,
    DERIVATIVE_COMPOSITE,
    DERIVATIVE_DA,
    DERIVATIVE_DAV,
    DERIVATIVE_DV,
    DERIVATIVE_FIXED,
    DERIVATIVE_FORCE,
    DERIVATIVE_JOINT,
    DERIVATIVE_LOCAL,
    DERIVATIVE_POSE,
    DERIVATIVE_SUBSPACE,
    DERIVATIVE_VELOCITY,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    MASS,
    N_JOINTS,
    PARENT,
    SPATIAL,
    STRIBECK_FORCE,
    STRIBECK_SPEED,
    STRIDE,
    TRANSFORM,
    VISCOUS,
)
from armdyn.dynamics.rnea import BATCH_CHUNKS
from armdyn.dynamics.spatial import (
    MATRIX,
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    add_inertia_to_parent,
    dot6,
    dot_with,
    joint_transform,
    motion_cross,
    one_state,
    rigid_times,
    scratch,
    states_status,
    world_motion_subspace,
    world_pose,
)
from armdyn.dynamics.status import OK, SHARED, SINGULAR, WRONG_SHAPE


@njit(inline="always", **NUMBA_OPTIONS)
def coulomb_slope(model: np.ndarray, j: int, rate: float, eps: float) -> float:
    """d Fd_j/dqd_j of the smoothed Coulomb law tanh(qd / eps) Tc (friction.smooth_coulomb); 0 for
    eps = 0, where the exact law is constant away from zero velocity."""
    if eps <= 0.0:
        return 0.0
    x = rate / eps
    if abs(x) >= 20.0:
        return 0.0
    slope = (1.0 - math.tanh(x) ** 2) / eps
    b = HEADER + STRIDE * j
    return slope * model[b + COULOMB_POS] if rate >= 0.0 else -slope * model[b + COULOMB_NEG]


@njit(inline="always", **NUMBA_OPTIONS)
def coulomb_smoothed_minus_exact(model: np.ndarray, j: int, rate: float, eps: float) -> float:
    """The smoothed Coulomb and Stribeck torque of joint j less the exact sign law's (0 for eps = 0)."""
    if eps <= 0.0:
        return 0.0
    b = HEADER + STRIDE * j
    smooth = smooth_sign(rate, eps)
    if rate > 0.0:
        difference = (smooth - 1.0) * model[b + COULOMB_POS]
        sign = 1.0
    elif rate < 0.0:
        difference = -(1.0 + smooth) * model[b + COULOMB_NEG]
        sign = -1.0
    else:
        return 0.0
    if model[b + STRIBECK_FORCE] != 0.0:
        difference += stribeck_torque(model[b + STRIBECK_FORCE], model[b + STRIBECK_SPEED], smooth - sign, rate)
    return difference


@njit(inline="always", **NUMBA_OPTIONS)
def nonlinear_slope(model: np.ndarray, j: int, rate: float, eps: float) -> float:
    """d/dqd_j of joint j's Stribeck law (its sign smoothed to tanh(qd / eps) for eps > 0, as
    friction.smooth_coulomb; the exact sign's slope is 0 away from rest) and its sigmoid law."""
    slope = sigmoid_slope(model, j, rate)
    b = HEADER + STRIDE * j
    force = model[b + STRIBECK_FORCE]
    if force != 0.0:
        if eps > 0.0:
            sign = smooth_sign(rate, eps)
            sign_slope = (1.0 - sign * sign) / eps if abs(rate / eps) < 20.0 else 0.0
        else:
            sign, sign_slope = exact_sign(rate), 0.0
        slope += stribeck_slope(force, model[b + STRIBECK_SPEED], sign, sign_slope, rate)
    return slope


@njit(inline="always", **NUMBA_OPTIONS)
def force_cross(work: np.ndarray, v: int, f: int, out: int) -> None:
    """out = v x* f for a motion v = [w; u] and a force f = [n; g]: [w x n + u x g; w x g]."""
    wx, wy, wz, ux, uy, uz = work[v], work[v + 1], work[v + 2], work[v + 3], work[v + 4], work[v + 5]
    nx, ny, nz, gx, gy, gz = work[f], work[f + 1], work[f + 2], work[f + 3], work[f + 4], work[f + 5]
    work[out] = wy * nz - wz * ny + uy * gz - uz * gy
    work[out + 1] = wz * nx - wx * nz + uz * gx - ux * gz
    work[out + 2] = wx * ny - wy * nx + ux * gy - uy * gx
    work[out + 3] = wy * gz - wz * gy
    work[out + 4] = wz * gx - wx * gz
    work[out + 5] = wx * gy - wy * gx


@njit(inline="always", **NUMBA_OPTIONS)
def inertia_and_coriolis_times(work: np.ndarray, ic: int, bc: int, m: int, d: int, out: int) -> None:
    """out = I^C m + 2 B^C d for a composite inertia at work[ic:] and B^C = [[B11, 0], [-[l]x, 0]]
    at work[bc:] (coriolis.body_coriolis): B^C d = [B11 a; -l x a] for d = [a; .]."""
    rigid_times(work, ic, m, out)
    ax, ay, az = work[d], work[d + 1], work[d + 2]
    lx, ly, lz = work[bc + 9], work[bc + 10], work[bc + 11]
    for r in range(3):
        work[out + r] += 2.0 * (work[bc + 3 * r] * ax + work[bc + 3 * r + 1] * ay + work[bc + 3 * r + 2] * az)
    work[out + 3] -= 2.0 * (ly * az - lz * ay)
    work[out + 4] -= 2.0 * (lz * ax - lx * az)
    work[out + 5] -= 2.0 * (lx * ay - ly * ax)


@njit(**NUMBA_OPTIONS)  # called, not inlined: the one-state and batch kernels share one compiled copy
def rnea_derivatives_core(model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                          eps: np.ndarray, dq: np.ndarray, dqd: np.ndarray, M: np.ndarray) -> None:  # fmt: skip
    """d tau/dq, d tau/dqd and M (written when M is (n, n)) at one state, by the module's recursion.

    Workspace (DERIVATIVE_JOINT per joint, DERIVATIVE_FIXED after): local and world transforms,
    S, dV, dA, dAv, v, a, I^C, B^C, F^C; then one inertia and three 6-vectors.
    """
    n = int(model[N_JOINTS])
    local, pose, S = DERIVATIVE_LOCAL * n, DERIVATIVE_POSE * n, DERIVATIVE_SUBSPACE * n
    dV, dA, dAv = DERIVATIVE_DV * n, DERIVATIVE_DA * n, DERIVATIVE_DAV * n
    vel, acc, IC = DERIVATIVE_VELOCITY * n, DERIVATIVE_ACCELERATION * n, DERIVATIVE_COMPOSITE * n
    BC, FC, tmp = DERIVATIVE_BIAS * n, DERIVATIVE_FORCE * n, DERIVATIVE_JOINT * n
    F2, F3, column = tmp + 10, tmp + 16, tmp + 22
    with_mass = M.shape[0] == n
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        s, v, a, dv = S + SPATIAL * i, vel + SPATIAL * i, acc + SPATIAL * i, dV + SPATIAL * i
        joint_transform(model, i, q[i], work, local + TRANSFORM * i)
        world_pose(model, work, local + TRANSFORM * i, pose + TRANSFORM * parent, pose + TRANSFORM * i, parent >= 0)
        world_motion_subspace(model, i, work, pose + TRANSFORM * i, s)
        if parent >= 0:
            vp, ap = vel + SPATIAL * parent, acc + SPATIAL * parent
            motion_cross(work, vp, s, dv)
            motion_cross(work, ap, s, dA + SPATIAL * i)
            motion_cross(work, vp, dv, tmp)
            for k in range(6):
                work[dA + SPATIAL * i + k] += work[tmp + k]
                work[v + k] = work[vp + k] + work[s + k] * qd[i]
                work[a + k] = work[ap + k] + work[s + k] * qdd[i] + work[dv + k] * qd[i]
        else:
            for k in range(6):
                work[tmp + k] = 0.0 if k < 3 else -model[GRAVITY + k - 3]  # a_0 = -g
                work[dv + k] = 0.0
            motion_cross(work, tmp, s, dA + SPATIAL * i)
            for k in range(6):
                work[v + k] = work[s + k] * qd[i]
                work[a + k] = work[tmp + k] + work[s + k] * qdd[i]
        for k in range(6):
            work[dAv + SPATIAL * i + k] = 2.0 * work[dv + k]
        # the body's inertia in the world, its Coriolis matrix and its force I a + v x* I v
        work[tmp] = model[b + MASS]
        for k in range(3):
            work[tmp + 1 + k] = model[b + FIRST_MOMENT + k]
        for k in range(6):
            work[tmp + 4 + k] = model[b + INERTIA + k]
        ic, fc = IC + COMPOSITE * i, FC + SPATIAL * i
        for k in range(10):
            work[ic + k] = 0.0
        add_inertia_to_parent(work, pose + TRANSFORM * i, tmp, ic)
        body_coriolis(work, v, ic, BC + COMPOSITE_BIAS * i)
        rigid_times(work, ic, v, F2)
        force_cross(work, v, F2, F3)
        rigid_times(work, ic, a, fc)
        for k in range(6):
            work[fc + k] += work[F3 + k]
        for k in range(n):
            dq[i, k] = 0.0
            dqd[i, k] = 0.0
            if with_mass:
                M[i, k] = 0.0
    for j in range(n - 1, -1, -1):
        b = HEADER + STRIDE * j
        ic, bc, sj, fc = IC + COMPOSITE * j, BC + COMPOSITE_BIAS * j, S + SPATIAL * j, FC + SPATIAL * j
        rigid_times(work, ic, sj, F2)  # I^C S_j
        ax, ay, az, sx, sy, sz = work[sj], work[sj + 1], work[sj + 2], work[sj + 3], work[sj + 4], work[sj + 5]
        lx, ly, lz = work[bc + 9], work[bc + 10], work[bc + 11]
        for r in range(3):  # D^C^T S_j = 2 [B11^T a + l x s; 0]
            work[F3 + r] = 2.0 * (work[bc + r] * ax + work[bc + 3 + r] * ay + work[bc + 6 + r] * az)
            work[F3 + 3 + r] = 0.0
        work[F3] += 2.0 * (ly * sz - lz * sy)
        work[F3 + 1] += 2.0 * (lz * sx - lx * sz)
        work[F3 + 2] += 2.0 * (lx * sy - ly * sx)
        f2 = (work[F2], work[F2 + 1], work[F2 + 2], work[F2 + 3], work[F2 + 4], work[F2 + 5])
        f3 = (work[F3], work[F3 + 1], work[F3 + 2], 0.0, 0.0, 0.0)
        inertia_and_coriolis_times(
            work, ic, bc, dA + SPATIAL * j, dV + SPATIAL * j, column
        )  # dF/dq_j less the carrying
        dq[j, j] = dot6(work, sj, column)
        force_cross(work, sj, fc, tmp)
        col_q = (work[column] + work[tmp], work[column + 1] + work[tmp + 1], work[column + 2] + work[tmp + 2],
                 work[column + 3] + work[tmp + 3], work[column + 4] + work[tmp + 4],
                 work[column + 5] + work[tmp + 5])  # fmt: skip
        inertia_and_coriolis_times(work, ic, bc, dAv + SPATIAL * j, sj, column)  # dF/dqd_j
        col_v = (work[column], work[column + 1], work[column + 2], work[column + 3], work[column + 4],
                 work[column + 5])  # fmt: skip
        dqd[j, j] += dot_with(work, sj, col_v) + model[b + VISCOUS] + coulomb_slope(model, j, qd[j], eps[j])
        dqd[j, j] += nonlinear_slope(model, j, qd[j], eps[j])
        if with_mass:
            M[j, j] = dot_with(work, sj, f2) + model[b + ARMATURE]
        i = int(model[b + PARENT])
        while i >= 0:
            si = S + SPATIAL * i
            dq[i, j] = dot_with(work, si, col_q)
            dq[j, i] = dot_with(work, dA + SPATIAL * i, f2) + dot_with(work, dV + SPATIAL * i, f3)
            dqd[i, j] = dot_with(work, si, col_v)
            dqd[j, i] = dot_with(work, dAv + SPATIAL * i, f2) + dot_with(work, si, f3)
            if with_mass:
                M[i, j] = M[j, i] = dot_with(work, si, f2)
            i = int(model[HEADER + STRIDE * i + PARENT])
        parent = int(model[b + PARENT])
        if parent >= 0:
            for k in range(10):
                work[IC + COMPOSITE * parent + k] += work[ic + k]
            for k in range(12):
                work[BC + COMPOSITE_BIAS * parent + k] += work[bc + k]
            for k in range(6):
                work[FC + SPATIAL * parent + k] += work[fc + k]


@njit(inline="always", **NUMBA_OPTIONS)
def derivatives_workspace(n: int) -> int:
    """Scratch values of forward_dynamics_derivatives_core for n joints: the larger of the two
    recursions' workspaces, then tau (n), qdd (n) and a Cholesky factor of M (n * n)."""
    return max(ABA_JOINT * n + ABA_FIXED, DERIVATIVE_JOINT * n + DERIVATIVE_FIXED) + 2 * n + n * n


@njit(**NUMBA_OPTIONS)  # called, not inlined: the one-state and batch kernels share one compiled copy
def forward_dynamics_derivatives_core(model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray,
                                      tau: np.ndarray, eps: np.ndarray, dq: np.ndarray, dqd: np.ndarray,
                                      dtau: np.ndarray) -> int:  # fmt: skip
    """d qdd/dq, d qdd/dqd and d qdd/dtau = M^-1 at one state (the module docstring's last paragraph).

    Returns -1, or the joint where M(q) is singular (nothing written then)."""
    n = int(model[N_JOINTS])
    base = derivatives_workspace(n) - 2 * n - n * n
    torque, qdd = work[base : base + n], work[base + n : base + 2 * n]
    factor = work[base + 2 * n : base + 2 * n + n * n].reshape((n, n))
    for k in range(n):  # the plant's Coulomb law: the smoothed one where eps > 0
        torque[k] = tau[k] - coulomb_smoothed_minus_exact(model, k, qd[k], eps[k])
    singular = aba_core(model, work, q, qd, torque, qdd)
    if singular >= 0:
        return singular
    rnea_derivatives_core(model, work, q, qd, qdd, eps, dq, dqd, dtau)
    for r in range(n):  # M (in dtau), its lower triangle
        for c in range(r + 1):
            factor[r, c] = dtau[r, c]
    singular = cholesky(factor)
    if singular >= 0:
        return singular
    for r in range(n):
        for c in range(n):
            dq[r, c] = -dq[r, c]
            dqd[r, c] = -dqd[r, c]
            dtau[r, c] = 1.0 if r == c else 0.0
    cholesky_solve(factor, dq)
    cholesky_solve(factor, dqd)
    cholesky_solve(factor, dtau)
    return -1


@njit(inline="always", **NUMBA_OPTIONS)
def shapes_status(model: np.ndarray, eps: np.ndarray, dq: np.ndarray, dqd: np.ndarray, third: np.ndarray,
                  third_optional: bool) -> int:  # fmt: skip
    """WRONG_SHAPE when eps is not (n,) or an output is not (n, n) (the third
    may be (0, 0) when optional), else OK."""
    n = int(model[N_JOINTS])
    if eps.shape[0] != n or dq.shape[0] != n or dq.shape[1] != n or dqd.shape[0] != n or dqd.shape[1] != n:
        return WRONG_SHAPE
    if not (third.shape[0] == n and third.shape[1] == n) and not (third_optional and third.shape[0] == 0):
        return WRONG_SHAPE
    return OK


@njit(inline="always", **NUMBA_OPTIONS)
def spans_overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the memory spans of two contiguous arrays overlap (an empty array overlaps nothing)."""
    if a.size == 0 or b.size == 0:
        return False
    start_a, start_b = a.ctypes.data, b.ctypes.data
    return start_a < start_b + b.nbytes and start_b < start_a + a.nbytes


@njit(inline="always", **NUMBA_OPTIONS)
def outputs_status(q: np.ndarray, qd: np.ndarray, third_state: np.ndarray, dq: np.ndarray, dqd: np.ndarray,
                   third: np.ndarray) -> int:  # fmt: skip
    """SHARED when an output's span overlaps another output's or a state's, else OK: the kernels read the
    states while they write, so results given by the caller (``out=``) must stand apart."""
    outputs = (dq, dqd, third)
    for k in range(3):
        for state in (q, qd, third_state):
            if spans_overlap(outputs[k], state):
                return SHARED
        for j in range(k):
            if spans_overlap(outputs[k], outputs[j]):
                return SHARED
    return OK


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR, VECTOR, MATRIX, MATRIX, MATRIX))
def rnea_derivatives_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, eps: np.ndarray,
                         dq: np.ndarray, dqd: np.ndarray, M: np.ndarray) -> int:  # fmt: skip
    """d tau/dq, d tau/dqd and (when M is (n, n), not (0, 0)) M at one state; the status of
    states_status, or WRONG_SHAPE for an eps or output of the wrong shape."""
    status = states_status(model, q, qd, qdd, 3)
    if status == OK:
        status = shapes_status(model, eps, dq, dqd, M, True)
    if status == OK:
        status = outputs_status(q, qd, qdd, dq, dqd, M)
    if status == OK:
        n = int(model[N_JOINTS])
        rnea_derivatives_core(model, scratch(DERIVATIVE_JOINT * n + DERIVATIVE_FIXED), q, qd, qdd, eps, dq, dqd, M)
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def rnea_derivatives_batch(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray, eps: np.ndarray,
                           DQ: np.ndarray, DQD: np.ndarray) -> None:  # fmt: skip
    """d tau/dq and d tau/dqd for each row of (B, n) states, in parallel chunks."""
    count, n = Q.shape[0], int(model[N_JOINTS])
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work, no_mass = np.empty(DERIVATIVE_JOINT * n + DERIVATIVE_FIXED), np.empty((0, 0))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            rnea_derivatives_core(model, work, Q[s], QD[s], QDD[s], eps, DQ[s], DQD[s], no_mass)


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR, VECTOR, MATRIX, MATRIX, MATRIX))
def forward_dynamics_derivatives_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray,
                                     eps: np.ndarray, dq: np.ndarray, dqd: np.ndarray,
                                     dtau: np.ndarray) -> int:  # fmt: skip
    """d qdd/dq, d qdd/dqd, d qdd/dtau at one state; the status of states_status, WRONG_SHAPE for an eps or
    output of the wrong shape, or SINGULAR when M(q) is singular."""
    status = states_status(model, q, qd, tau, 3)
    if status == OK:
        status = shapes_status(model, eps, dq, dqd, dtau, False)
    if status == OK:
        status = outputs_status(q, qd, tau, dq, dqd, dtau)
    if status == OK:
        work = scratch(derivatives_workspace(int(model[N_JOINTS])))
        if forward_dynamics_derivatives_core(model, work, q, qd, tau, eps, dq, dqd, dtau) >= 0:
            status = SINGULAR
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def forward_dynamics_derivatives_batch(model: np.ndarray, Q: np.ndarray, QD: np.ndarray, TAU: np.ndarray,
                                       eps: np.ndarray, DQ: np.ndarray, DQD: np.ndarray, DTAU: np.ndarray,
                                       singular: np.ndarray) -> None:  # fmt: skip
    """The forward-dynamics derivatives for each row of (B, n) states, in parallel chunks; singular[s]
    is the joint where M is singular at state s (-1 where it is not)."""
    count = Q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work = np.empty(derivatives_workspace(int(model[N_JOINTS])))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            singular[s] = forward_dynamics_derivatives_core(model, work, Q[s], QD[s], TAU[s], eps, DQ[s], DQD[s],
                                                            DTAU[s])  # fmt: skip
