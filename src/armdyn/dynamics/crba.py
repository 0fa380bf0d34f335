"""The inertia matrix M(q) by the composite-rigid-body algorithm (Featherstone, Rigid Body
Dynamics Algorithms, 2008, 6.2), with the reflected motor inertia G^2 Jm on its diagonal.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.packed import (
    ARMATURE,
    COMPOSITE,
    FIRST_MOMENT,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    N_JOINTS,
    PARENT,
    RNEA_FIXED,
    RNEA_JOINT,
    STRIDE,
    TRANSFORM,
    workspace_size,
)
from armdyn.dynamics.rnea import BATCH_CHUNKS, NONLINEAR, rnea_core
from armdyn.dynamics.spatial import (
    MATRIX,
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    add_inertia_to_parent,
    force_to_parent,
    joint_transform,
    one_state,
    scratch,
    states_status,
)
from armdyn.dynamics.status import OK, WRONG_SHAPE


@njit(inline="always", **NUMBA_OPTIONS)
def crba_core(model: np.ndarray, work: np.ndarray, q: np.ndarray, M: np.ndarray) -> None:
    """M(q) by the composite-rigid-body algorithm (Featherstone 6.2), plus the armature diagonal.

    Composite inertias I^c_i = I_i + sum of children's; F = I^c_i S_i, M_ii = S_i^T F,
    then F is carried to each ancestor j: M_ij = M_ji = S_j^T F.
    """
    n = int(model[N_JOINTS])
    for i in range(n):
        joint_transform(model, i, q[i], work, TRANSFORM * i)
    crba_from_transforms(model, work, 0, TRANSFORM, TRANSFORM * n, M)


@njit(inline="always", **NUMBA_OPTIONS)
def crba_from_transforms(model: np.ndarray, work: np.ndarray, transforms: int, stride: int, composite: int,
                         M: np.ndarray) -> None:  # fmt: skip
    """CRBA given each joint's (R, p) at work[transforms + stride i:], composite inertias at work[composite:]."""
    n = int(model[N_JOINTS])
    for i in range(n):
        b = HEADER + STRIDE * i
        c = composite + COMPOSITE * i
        work[c] = model[b + MASS]
        for k in range(3):
            work[c + 1 + k] = model[b + FIRST_MOMENT + k]
        for k in range(6):
            work[c + 4 + k] = model[b + INERTIA + k]
        for j in range(n):
            M[i, j] = 0.0
    for i in range(n - 1, -1, -1):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        if parent >= 0:
            add_inertia_to_parent(
                work, transforms + stride * i, composite + COMPOSITE * i, composite + COMPOSITE * parent
            )
    for i in range(n):
        b = HEADER + STRIDE * i
        c = composite + COMPOSITE * i
        mass, hx, hy = work[c], work[c + 1], work[c + 2]
        if model[b + KIND] != 0.0:  # F = I^c e6 = [h x e3; m e3]
            nx, ny, nz, fx, fy, fz = hy, -hx, 0.0, 0.0, 0.0, mass
            M[i, i] = mass + model[b + ARMATURE]
        else:  # F = I^c e3 = [I_O e3; -h x e3]
            nx, ny, nz, fx, fy, fz = work[c + 6], work[c + 8], work[c + 9], -hy, hx, 0.0
            M[i, i] = work[c + 9] + model[b + ARMATURE]
        j = i
        parent = int(model[b + PARENT])
        while parent >= 0:  # F <- X_j^T F, carried to the parent: [R n + p x (R f); R f]
            t = transforms + stride * j
            r00, r01, r02, r10, r11, r12 = work[t], work[t + 1], work[t + 2], work[t + 3], work[t + 4], work[t + 5]
            r20, r21, r22, px, py, pz = work[t + 6], work[t + 7], work[t + 8], work[t + 9], work[t + 10], work[t + 11]
            nx, ny, nz, fx, fy, fz = force_to_parent(
                (r00, r01, r02, r10, r11, r12, r20, r21, r22), (px, py, pz), (nx, ny, nz), (fx, fy, fz)
            )
            j = parent
            bj = HEADER + STRIDE * j
            value = fz if model[bj + KIND] != 0.0 else nz
            M[i, j] = value
            M[j, i] = value
            parent = int(model[bj + PARENT])


@njit(inline="always", **NUMBA_OPTIONS)
def mass_matrix_and_bias(model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray, M: np.ndarray,
                         N: np.ndarray) -> None:  # fmt: skip
    """M(q) and N(q, qd) together: RNEA's joint transforms (the first TRANSFORM values of each
    RNEA_JOINT record) serve CRBA too, whose composite inertias follow RNEA's workspace (forward
    dynamics in a loop). Workspace: RNEA_JOINT + COMPOSITE per joint, RNEA_FIXED."""
    n = int(model[N_JOINTS])
    rnea_core(model, work, q, qd, qd, qd, NONLINEAR, N)
    crba_from_transforms(model, work, 0, RNEA_JOINT, RNEA_JOINT * n + RNEA_FIXED, M)


@one_state(types.int64(MODEL, VECTOR, MATRIX))
def crba_one(model: np.ndarray, q: np.ndarray, M: np.ndarray) -> int:
    """M(q) for one state; the status of states_status, or WRONG_SHAPE when M is not (n, n)."""
    n = int(model[N_JOINTS])
    status = states_status(model, q, q, q, 1)
    if status == OK and (M.shape[0] != n or M.shape[1] != n):
        status = WRONG_SHAPE
    if status == OK:
        crba_core(model, scratch((TRANSFORM + COMPOSITE) * n), q, M)
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def crba_batch(model: np.ndarray, q: np.ndarray, M: np.ndarray) -> None:
    """M(q) for each row of q (B, n), in parallel chunks."""
    count = q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work = np.empty(workspace_size(int(model[N_JOINTS])))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            crba_core(model, work, q[s], M[s])
