"""Forward dynamics qdd = M^-1 (tau - N) by the articulated-body algorithm (Featherstone, Rigid
Body Dynamics Algorithms, 2008, 7.3), in the world frame.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.friction import joint_friction
from armdyn.dynamics.packed import (
    ABA_ACCELERATION,
    ABA_BIAS,
    ABA_FIXED,
    ABA_INERTIA,
    ABA_JOINT,
    ABA_LOCAL,
    ABA_MOMENTUM,
    ABA_PIVOT,
    ABA_POSE,
    ABA_SUBSPACE,
    ABA_U,
    ABA_VELOCITY,
    ARMATURE,
    ARTICULATED,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    MASS,
    N_JOINTS,
    PARENT,
    PIVOT_FLOOR,
    SPATIAL,
    STRIDE,
    TRANSFORM,
    workspace_size,
)
from armdyn.dynamics.rnea import BATCH_CHUNKS
from armdyn.dynamics.spatial import (
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    add_inertia_to_parent,
    dot6,
    joint_transform,
    motion_cross,
    one_state,
    rigid_times,
    scratch,
    states_status,
    world_motion_subspace,
    world_pose,
)
from armdyn.dynamics.status import OK, SINGULAR, WRONG_SHAPE


@njit(inline="always", **NUMBA_OPTIONS)
def aba_core(
    model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray
) -> int:
    """qdd = M^-1 (tau - Vm qd - F - G) by the articulated-body algorithm (Featherstone 7.3), in the
    world frame, where articulated inertias add up the tree without transforms.

    Pass 1: v_i = v_p + S_i qd_i, c_i = v_i x S_i qd_i, I^A_i = I_i, p^A_i = v_i x* I_i v_i.
    Pass 2 (leaves first): U = I^A S, D = S^T U + G^2 Jm, u = tau - F - S^T p^A;
    I^A_p += I^A - U U^T / D, p^A_p += p^A + (I^A - U U^T / D) c + U u / D.
    Pass 3: a = a_p + c (a_0 = -g), qdd = (u - U^T a) / D, a += S qdd.

    Returns -1, or the first joint (leaves first) whose pivot D is not above the model's
    PIVOT_FLOOR: M(q) is singular there and qdd is not computed.
    """
    n = int(model[N_JOINTS])
    local, pose, S, vel, bias = ABA_LOCAL * n, ABA_POSE * n, ABA_SUBSPACE * n, ABA_VELOCITY * n, ABA_BIAS * n
    IA, pA, U, acc, Du, tmp = (
        ABA_INERTIA * n,
        ABA_MOMENTUM * n,
        ABA_U * n,
        ABA_ACCELERATION * n,
        ABA_PIVOT * n,
        ABA_JOINT * n,
    )
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        s, v, c, ia = S + SPATIAL * i, vel + SPATIAL * i, bias + SPATIAL * i, IA + ARTICULATED * i
        joint_transform(model, i, q[i], work, local + TRANSFORM * i)
        world_pose(model, work, local + TRANSFORM * i, pose + TRANSFORM * parent, pose + TRANSFORM * i, parent >= 0)
        world_motion_subspace(model, i, work, pose + TRANSFORM * i, s)
        rate = qd[i]
        for k in range(6):
            work[tmp + k] = work[s + k] * rate
            work[v + k] = (work[vel + SPATIAL * parent + k] if parent >= 0 else 0.0) + work[tmp + k]
        motion_cross(work, v, tmp, c)
        # the body's inertia in world coordinates, 10 parameters at tmp + 6, then as 6x6
        work[tmp + 16] = model[b + MASS]
        for k in range(3):
            work[tmp + 17 + k] = model[b + FIRST_MOMENT + k]
        for k in range(6):
            work[tmp + 20 + k] = model[b + INERTIA + k]
        for k in range(10):
            work[tmp + 6 + k] = 0.0
        add_inertia_to_parent(work, pose + TRANSFORM * i, tmp + 16, tmp + 6)
        mass, hx, hy, hz = work[tmp + 6], work[tmp + 7], work[tmp + 8], work[tmp + 9]
        i0, i1, i2, i3, i4, i5 = (
            work[tmp + 10],
            work[tmp + 11],
            work[tmp + 12],
            work[tmp + 13],
            work[tmp + 14],
            work[tmp + 15],
        )
        rows = (
            (i0, i1, i2, 0.0, -hz, hy),
            (i1, i3, i4, hz, 0.0, -hx),
            (i2, i4, i5, -hy, hx, 0.0),
            (0.0, hz, -hy, mass, 0.0, 0.0),
            (-hz, 0.0, hx, 0.0, mass, 0.0),
            (hy, -hx, 0.0, 0.0, 0.0, mass),
        )
        for r in range(6):
            row = rows[r]
            for k in range(6):
                work[ia + SPATIAL * r + k] = row[k]
        rigid_times(work, tmp + 6, v, tmp + 16)  # momentum [k; l]; p^A = v x* [k; l] = [w x k + u x l; w x l]
        wx, wy, wz, ux, uy, uz = work[v], work[v + 1], work[v + 2], work[v + 3], work[v + 4], work[v + 5]
        kx, ky, kz, lx, ly, lz = (
            work[tmp + 16],
            work[tmp + 17],
            work[tmp + 18],
            work[tmp + 19],
            work[tmp + 20],
            work[tmp + 21],
        )
        p = pA + SPATIAL * i
        work[p] = wy * kz - wz * ky + uy * lz - uz * ly
        work[p + 1] = wz * kx - wx * kz + uz * lx - ux * lz
        work[p + 2] = wx * ky - wy * kx + ux * ly - uy * lx
        work[p + 3] = wy * lz - wz * ly
        work[p + 4] = wz * lx - wx * lz
        work[p + 5] = wx * ly - wy * lx
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        s, ia, p, u, c = S + SPATIAL * i, IA + ARTICULATED * i, pA + SPATIAL * i, U + SPATIAL * i, bias + SPATIAL * i
        for r in range(6):
            total = 0.0
            for k in range(6):
                total += work[ia + SPATIAL * r + k] * work[s + k]
            work[u + r] = total
        D = dot6(work, s, u) + model[b + ARMATURE]
        if not model[PIVOT_FLOOR] < D:
            return i
        value = tau[i] - joint_friction(model, i, qd[i]) - dot6(work, s, p)
        work[Du + 2 * i] = D
        work[Du + 2 * i + 1] = value
        parent = int(model[b + PARENT])
        if parent < 0:
            continue
        target, pt = IA + ARTICULATED * parent, pA + SPATIAL * parent
        uc = dot6(work, u, c) / D
        gain = value / D
        for r in range(6):
            ur = work[u + r] / D
            total = work[p + r] + work[u + r] * (gain - uc)
            for k in range(6):
                total += work[ia + SPATIAL * r + k] * work[c + k]
                work[target + SPATIAL * r + k] += work[ia + SPATIAL * r + k] - ur * work[u + k]
            work[pt + r] += total
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        a, s, c = acc + SPATIAL * i, S + SPATIAL * i, bias + SPATIAL * i
        for k in range(6):
            if parent >= 0:
                work[a + k] = work[acc + SPATIAL * parent + k] + work[c + k]
            else:
                work[a + k] = (-model[GRAVITY + k - 3] if k >= 3 else 0.0) + work[c + k]
        result = (work[Du + 2 * i + 1] - dot6(work, U + SPATIAL * i, a)) / work[Du + 2 * i]
        qdd[i] = result
        for k in range(6):
            work[a + k] += work[s + k] * result
    return -1


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR, VECTOR))
def aba_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray) -> int:
    """qdd for one state; the status of states_status, WRONG_SHAPE when qdd has the wrong length, or
    SINGULAR when M(q) is singular."""
    status = states_status(model, q, qd, tau, 3)
    if status == OK and qdd.shape[0] != int(model[N_JOINTS]):
        status = WRONG_SHAPE
    if status == OK and aba_core(model, scratch(ABA_JOINT * int(model[N_JOINTS]) + ABA_FIXED), q, qd, tau, qdd) >= 0:
        status = SINGULAR
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def aba_batch(
    model: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray, singular: np.ndarray
) -> None:
    """qdd for each row of (q, qd, tau), in parallel chunks; singular[s] is aba_core's joint
    where M is singular at state s (-1 where it is not)."""
    count = q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work = np.empty(workspace_size(int(model[N_JOINTS])))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            singular[s] = aba_core(model, work, q[s], qd[s], tau[s], qdd[s])
