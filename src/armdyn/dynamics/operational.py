"""Operational-space quantities of one state in one compiled pass (Khatib 1987; Section 3.5).

For an output made of rows of a frame's world Jacobian [v; w] (the tool point, the tool pose,
a link frame's origin, two of the tool's coordinates): J, M (CRBA), the Cholesky factors of M
and of J M^-1 J^T, and from them

    Lambda = (J M^-1 J^T)^-1,  Jbar = M^-1 J^T Lambda,  mu = Jbar^T Vm qd - Lambda Jdot qd,
    p = Jbar^T G,  friction = Jbar^T F,  Nproj = I - Jbar J.

The singularity test is certified without an SVD: with B = J J^T (m x m, Cholesky L),
lambda_min(B) >= det B / lambda_max^(m-1), so cond(J)^2 = cond(B) <= trace(B)^m / det(B). A
state passes when that bound is at most max_condition^2; any other state returns TASK_SINGULAR, and
the caller's general path decides with the exact condition number (and raises, or damps).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.aba import aba_one
from armdyn.dynamics.coriolis import coriolis_one
from armdyn.dynamics.crba import crba_one
from armdyn.dynamics.frames import WORLD, jacobian_dot_one, jacobian_one
from armdyn.dynamics.friction import friction_one
from armdyn.dynamics.linalg import cholesky, lu, lu_solve, lu_solve_transpose, solve_lower, solve_lower_transpose
from armdyn.dynamics.packed import N_JOINTS
from armdyn.dynamics.rnea import BATCH_CHUNKS, coriolis_vector_one, gravity_one, inverse_dynamics_one, nonlinear_one
from armdyn.dynamics.spatial import MATRIX, MODEL, NUMBA_OPTIONS, VECTOR, one_state, scratch
from armdyn.dynamics.status import BAD_ROWS, NOT_FINITE, NOT_SQUARE, OK, TASK_SINGULAR, WRONG_LENGTH, WRONG_SHAPE
from armdyn.inputs import LARGEST_STATE

ROW_INDICES = types.int64[::1]


@njit(inline="always", **NUMBA_OPTIONS)
def certified_regular(J: np.ndarray, limit: float, B: np.ndarray) -> bool:
    """cond(J) <= limit, certified by trace(J J^T)^m <= limit^2 det(J J^T) (module docstring)."""
    m, n = J.shape
    trace = 0.0
    for i in range(m):
        for k in range(i + 1):
            s = 0.0
            for j in range(n):
                s += J[i, j] * J[k, j]
            B[i, k] = s
        trace += B[i, i]
    if cholesky(B) >= 0:
        return False
    ratio = 1.0  # trace^m / det = prod of trace / L_ii^2, a factor per row so that neither overflows
    for i in range(m):
        ratio *= trace / (B[i, i] * B[i, i])
    return ratio <= limit * limit


@njit(inline="always", **NUMBA_OPTIONS)
def lambda_from(J: np.ndarray, M: np.ndarray, limit: float, Y: np.ndarray, B: np.ndarray, Lambda: np.ndarray) -> bool:
    """Lambda = (J M^-1 J^T)^-1 as (Y^T Y)^-1 with Y = L^-1 J^T, M = L L^T (factored in M);
    False when J is not certified regular (or M is not positive definite)."""
    m, n = J.shape
    if not certified_regular(J, limit, B) or cholesky(M) >= 0:
        return False
    for r in range(m):
        for j in range(n):
            Y[j, r] = J[r, j]
    solve_lower(M, Y)
    for r in range(m):  # B = Y^T Y = J M^-1 J^T, lower triangle
        for c in range(r + 1):
            s = 0.0
            for j in range(n):
                s += Y[j, r] * Y[j, c]
            B[r, c] = s
    if cholesky(B) >= 0:
        return False
    for r in range(m):  # Lambda <- L_B^-1, lower triangular
        for c in range(m):
            Lambda[r, c] = 0.0
        Lambda[r, r] = 1.0
    solve_lower(B, Lambda)
    for r in range(m):  # Lambda = L_B^-T L_B^-1 (column r of L_B^-1 is zero above row r)
        for c in range(r + 1):
            s = 0.0
            for k in range(r, m):
                s += Lambda[k, r] * Lambda[k, c]
            B[r, c] = s
    for r in range(m):
        for c in range(r + 1):
            Lambda[r, c] = B[r, c]
            Lambda[c, r] = B[r, c]
    return True


@njit(inline="always", **NUMBA_OPTIONS)
def rows_status(model: np.ndarray, rows: np.ndarray) -> int:
    """OK, or BAD_ROWS for rows that are not 1 to n indices among 0-5."""
    if not 0 < rows.shape[0] <= int(model[N_JOINTS]):
        return BAD_ROWS
    for r in range(rows.shape[0]):
        if not 0 <= rows[r] <= 5:
            return BAD_ROWS
    return OK


@njit(inline="always", **NUMBA_OPTIONS)
def select_rows(full: np.ndarray, rows: np.ndarray, J: np.ndarray) -> None:
    for r in range(rows.shape[0]):
        for j in range(full.shape[1]):
            J[r, j] = full[rows[r], j]


# The kinematics and dynamics come from the public one-state kernels (compiled once, shared):
# inlining them here would multiply the compilation time, for no measurable gain at run time.
@one_state(types.int64(MODEL, VECTOR, types.int64, ROW_INDICES, types.float64, MATRIX))
def lambda_one(
    model: np.ndarray, q: np.ndarray, target: int, rows: np.ndarray, limit: float, Lambda: np.ndarray
) -> int:
    """Lambda = (J M^-1 J^T)^-1 for one state; a status (TASK_SINGULAR: not certified regular)."""
    n, m = int(model[N_JOINTS]), rows.shape[0]
    status = rows_status(model, rows)
    if status == OK and (Lambda.shape[0] != m or Lambda.shape[1] != m):
        status = WRONG_SHAPE
    if status != OK:
        return status
    buffer = scratch(6 * n + 2 * m * n + n * n + m * m)
    full = buffer[: 6 * n].reshape(6, n)
    J = buffer[6 * n : 6 * n + m * n].reshape(m, n)
    Y = buffer[6 * n + m * n : 6 * n + 2 * m * n].reshape(n, m)
    M = buffer[6 * n + 2 * m * n : 6 * n + 2 * m * n + n * n].reshape(n, n)
    B = buffer[6 * n + 2 * m * n + n * n :].reshape(m, m)
    axes = np.int64(WORLD)  # not a literal 0: the kernels then reuse jacobian_one as the public calls compiled it
    status = jacobian_one(model, q, target, axes, full)
    if status == OK:
        status = crba_one(model, q, M)
    if status != OK:
        return status
    select_rows(full, rows, J)
    return OK if lambda_from(J, M, limit, Y, B, Lambda) else TASK_SINGULAR


@one_state(
    types.int64(MODEL, VECTOR, VECTOR, types.int64, ROW_INDICES, types.float64, *(MATRIX,) * 3, *(VECTOR,) * 3, MATRIX)
)
def operational_one(
    model: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    target: int,
    rows: np.ndarray,
    limit: float,
    J: np.ndarray,
    Lambda: np.ndarray,
    Jbar: np.ndarray,
    mu: np.ndarray,
    p: np.ndarray,
    friction: np.ndarray,
    Nproj: np.ndarray,
) -> int:
    """J, Lambda, Jbar, mu, p, friction and Nproj for one state; a status (TASK_SINGULAR: not certified)."""
    n, m = int(model[N_JOINTS]), rows.shape[0]
    status = rows_status(model, rows)
    if status == OK and (
        J.shape[0] != m or J.shape[1] != n or Lambda.shape[0] != m or Lambda.shape[1] != m
        or Jbar.shape[0] != n or Jbar.shape[1] != m or mu.shape[0] != m or p.shape[0] != m
        or friction.shape[0] != m or Nproj.shape[0] != n or Nproj.shape[1] != n
    ):  # fmt: skip
        status = WRONG_SHAPE
    if status != OK:
        return status
    buffer = scratch(6 * n + n * n + m * m + n * m + 3 * n + m)
    full = buffer[: 6 * n].reshape(6, n)
    M = buffer[6 * n : 6 * n + n * n].reshape(n, n)
    B = buffer[6 * n + n * n : 6 * n + n * n + m * m].reshape(m, m)
    at = 6 * n + n * n + m * m
    Y = buffer[at : at + n * m].reshape(n, m)
    coriolis, gravity = buffer[at + n * m : at + n * m + n], buffer[at + n * m + n : at + n * m + 2 * n]
    force, bias = buffer[at + n * m + 2 * n : at + n * m + 3 * n], buffer[at + n * m + 3 * n :]
    axes = np.int64(WORLD)  # not a literal 0: the kernels then reuse jacobian_one as the public calls compiled it
    status = jacobian_one(model, q, target, axes, full)
    if status == OK:
        status = crba_one(model, q, M)
    if status == OK:
        status = coriolis_vector_one(model, q, qd, coriolis)
    if status == OK:
        status = gravity_one(model, q, gravity)
    if status == OK:
        status = friction_one(model, qd, force)
    if status != OK:
        return status
    select_rows(full, rows, J)
    if not lambda_from(J, M, limit, Y, B, Lambda):
        return TASK_SINGULAR
    for r in range(n):  # Jbar = M^-1 J^T Lambda = L^-T (Y Lambda)
        for c in range(m):
            s = 0.0
            for k in range(m):
                s += Y[r, k] * Lambda[k, c]
            Jbar[r, c] = s
    solve_lower_transpose(M, Jbar)
    jacobian_dot_one(model, q, qd, target, axes, full)
    for r in range(m):
        s = 0.0
        for j in range(n):
            s += full[rows[r], j] * qd[j]
        bias[r] = s
    for c in range(m):
        sv, sg, sf, sb = 0.0, 0.0, 0.0, 0.0
        for j in range(n):
            sv += Jbar[j, c] * coriolis[j]
            sg += Jbar[j, c] * gravity[j]
            sf += Jbar[j, c] * force[j]
        for k in range(m):
            sb += Lambda[c, k] * bias[k]
        mu[c], p[c], friction[c] = sv - sb, sg, sf
    for r in range(n):
        for c in range(n):
            s = 0.0
            for k in range(m):
                s += Jbar[r, k] * J[k, c]
            Nproj[r, c] = (1.0 if r == c else 0.0) - s
    return OK


# ----- square outputs and the task-space forward dynamics, one kernel for each quantity's state --
TASK_LAMBDA, TASK_GRAVITY, TASK_FRICTION, TASK_FORCE, TASK_NONLINEAR, TASK_INVERSE, TASK_CORIOLIS, TASK_FORWARD = range(
    8
)
"""What ``task_one`` computes: Lambda (m <= n, out (m, m)); for m = n, J^-T times G, F(qd), v,
N - M J^-1 Jdot qd, or the inverse dynamics at qdd = J^-1 (v - Jdot qd) (out (1, n)); Vmbar
(out (n, n)); or yddot = J ABA(q, qd, J^T v) + Jdot qd (m <= n, out (1, m))."""


@njit(inline="always", **NUMBA_OPTIONS)
def row_times(full: np.ndarray, rows: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = (the rows of full) x."""
    for r in range(rows.shape[0]):
        s = 0.0
        for j in range(full.shape[1]):
            s += full[rows[r], j] * x[j]
        out[r] = s


@njit(**NUMBA_OPTIONS)
def task_core(
    model: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    v: np.ndarray,
    target: int,
    rows: np.ndarray,
    limit: float,
    kind: int,
    out: np.ndarray,
    buffer: np.ndarray,
) -> int:
    """One state of ``kind`` (see TASK_LAMBDA...) into out; a status. ``buffer``: task_size(n) values."""
    n, m = int(model[N_JOINTS]), rows.shape[0]
    status = rows_status(model, rows)
    if status != OK:
        return status
    full = buffer[: 6 * n].reshape(6, n)
    J = buffer[6 * n : 6 * n + m * n].reshape(m, n)
    M = buffer[6 * n + m * n : 6 * n + m * n + n * n].reshape(n, n)
    A = buffer[6 * n + m * n + n * n : 6 * n + m * n + 2 * n * n].reshape(n, n)
    K = buffer[6 * n + m * n + 2 * n * n : 6 * n + m * n + 3 * n * n].reshape(n, n)
    at = 6 * n + m * n + 3 * n * n
    Y, B = buffer[at : at + n * m].reshape(n, m), buffer[at + n * m : at + n * m + m * m].reshape(m, m)
    at += n * m + m * m
    pivots, x, y = buffer[at : at + n], buffer[at + n : at + 2 * n], buffer[at + 2 * n : at + 3 * n]
    axes = np.int64(WORLD)  # not a literal 0: the kernels then reuse jacobian_one as the public calls compiled it
    status = jacobian_one(model, q, target, axes, full)
    if status != OK:
        return status
    select_rows(full, rows, J)
    if kind == TASK_LAMBDA:
        status = crba_one(model, q, M)
        return status if status != OK else OK if lambda_from(J, M, limit, Y, B, out) else TASK_SINGULAR
    if kind == TASK_FORWARD:  # yddot = J qdd + Jdot qd at qdd = ABA(q, qd, J^T f): no inverse of J
        for j in range(n):
            s = 0.0
            for r in range(m):
                s += J[r, j] * v[r]
            x[j] = s
        status = aba_one(model, q, qd, x, y)
        if status == OK:
            status = jacobian_dot_one(model, q, qd, target, axes, full)
        if status == OK:
            row_times(full, rows, qd, x)
            for r in range(m):
                s = x[r]
                for j in range(n):
                    s += J[r, j] * y[j]
                out[0, r] = s
        return status
    if m != n:
        return NOT_SQUARE
    if not certified_regular(J, limit, B):
        return TASK_SINGULAR
    for r in range(n):
        for c in range(n):
            A[r, c] = J[r, c]
    if not lu(A, pivots):
        return TASK_SINGULAR
    if kind == TASK_GRAVITY:
        status = gravity_one(model, q, x)
    elif kind == TASK_FRICTION:
        status = friction_one(model, qd, x)
    elif kind == TASK_FORCE:
        for i in range(n):
            if not abs(v[i]) < LARGEST_STATE:  # NaN, infinity or too large: the general path names it
                return NOT_FINITE + 1
            x[i] = v[i]
    elif kind == TASK_NONLINEAR:  # N - M J^-1 (Jdot qd)
        status = nonlinear_one(model, q, qd, x)
        if status == OK:
            status = crba_one(model, q, M)
        if status == OK:
            status = jacobian_dot_one(model, q, qd, target, axes, full)
        if status == OK:
            row_times(full, rows, qd, y)
            lu_solve(A, pivots, y)
            for i in range(n):
                s = x[i]
                for j in range(n):
                    s -= M[i, j] * y[j]
                x[i] = s
    elif kind == TASK_INVERSE:  # tau at qdd = J^-1 (v - Jdot qd)
        status = jacobian_dot_one(model, q, qd, target, axes, full)
        if status == OK:
            row_times(full, rows, qd, y)
            for r in range(n):
                y[r] = v[r] - y[r]
            lu_solve(A, pivots, y)
            status = inverse_dynamics_one(model, q, qd, y, x)
    else:  # TASK_CORIOLIS: J^-T (Vm - M J^-1 Jdot) J^-1
        status = coriolis_one(model, q, qd, K)
        if status == OK:
            status = crba_one(model, q, M)
        if status == OK:
            status = jacobian_dot_one(model, q, qd, target, axes, full)
        if status != OK:
            return status
        for c in range(n):  # K -= M (J^-1 Jdot), a column at a time
            for r in range(n):
                y[r] = full[rows[r], c]
            lu_solve(A, pivots, y)
            for i in range(n):
                s = 0.0
                for j in range(n):
                    s += M[i, j] * y[j]
                K[i, c] -= s
        for r in range(n):  # K <- K J^-1, a row at a time: (K J^-1)^T = J^-T K^T
            for c in range(n):
                y[c] = K[r, c]
            lu_solve_transpose(A, pivots, y)
            for c in range(n):
                K[r, c] = y[c]
        for c in range(n):  # out = J^-T K, a column at a time
            for r in range(n):
                y[r] = K[r, c]
            lu_solve_transpose(A, pivots, y)
            for r in range(n):
                out[r, c] = y[r]
        return OK
    if status == OK:
        lu_solve_transpose(A, pivots, x)
        for i in range(n):
            out[0, i] = x[i]
    return status


@njit(inline="always", **NUMBA_OPTIONS)
def task_size(n: int, m: int) -> int:
    return 6 * n + 2 * m * n + 3 * n * n + m * m + 3 * n


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR, types.int64, ROW_INDICES, types.float64, types.int64, MATRIX))
def task_one(
    model: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    v: np.ndarray,
    target: int,
    rows: np.ndarray,
    limit: float,
    kind: int,
    out: np.ndarray,
) -> int:
    """One state of ``kind`` (TASK_LAMBDA ... TASK_FORWARD) into out; a status (TASK_SINGULAR: the general path
    decides). The caller gives out the kind's shape and v of n values (of which TASK_FORWARD reads m)."""
    n = int(model[N_JOINTS])
    if qd.shape[0] != n or v.shape[0] != n:
        return WRONG_LENGTH + 1
    return task_core(model, q, qd, v, target, rows, limit, kind, out, scratch(task_size(n, rows.shape[0])))


@njit(parallel=True, **NUMBA_OPTIONS)
def task_batch(
    model: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    v: np.ndarray,
    target: int,
    rows: np.ndarray,
    limit: float,
    kind: int,
    out: np.ndarray,
    status: np.ndarray,
) -> None:
    """Many states (B, n) of ``kind`` into out (B, r, c), each state's status into status (B,)."""
    count = q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    n = int(model[N_JOINTS])
    for chunk in prange(chunks):
        buffer = np.empty(task_size(n, rows.shape[0]))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            status[s] = task_core(model, q[s], qd[s], v[s], target, rows, limit, kind, out[s], buffer)
