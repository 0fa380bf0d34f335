"""The Christoffel-consistent Coriolis matrix Vm(q, qd) (3.3.48), in O(n d)
for depth d (Echeandia and Wensing, "Numerical methods to compute the Coriolis matrix and
Christoffel symbols for rigid-body systems", J. Comput. Nonlinear Dyn. 16, 2021, Algorithm 2).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.packed import (
    COMPOSITE,
    COMPOSITE_BIAS,
    CORIOLIS_BIAS,
    CORIOLIS_COMPOSITE,
    CORIOLIS_FIXED,
    CORIOLIS_JOINT,
    CORIOLIS_LOCAL,
    CORIOLIS_POSE,
    CORIOLIS_SUBSPACE,
    CORIOLIS_SUBSPACE_DOT,
    CORIOLIS_VELOCITY,
    FIRST_MOMENT,
    HEADER,
    INERTIA,
    MASS,
    N_JOINTS,
    PARENT,
    SPATIAL,
    STRIDE,
    TRANSFORM,
    workspace_size,
)
from armdyn.dynamics.rnea import BATCH_CHUNKS
from armdyn.dynamics.spatial import (
    MATRIX,
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    add_inertia_to_parent,
    dot_with,
    inertia_apply,
    joint_transform,
    motion_cross,
    one_state,
    scratch,
    states_status,
    world_motion_subspace,
    world_pose,
)
from armdyn.dynamics.status import OK, WRONG_SHAPE


@njit(inline="always", **NUMBA_OPTIONS)
def body_coriolis(work: np.ndarray, v: int, inertia: int, out: int) -> None:
    """The body Coriolis matrix B = 1/2 [(v x*) I + (I v) xbar* - I (v x)] (Echeandia and Wensing
    2021), with B v = v x* I v and B + B^T = dI/dt, which makes Mdot - 2 Vm skew.

    For I = (model, h, I_O) and v = [work; u] it reduces to B = [[B11, 0], [-[l]x, 0]] with
    l = m u + w x h, k = I_O w + h x u and
    B11 = 1/2 ([work]x I_O - I_O [work]x - h u^T - u h^T + 2 (u.h) 1 - [k]x).
    Stored as B11 (9, row major) then l (3).
    """
    wx, wy, wz, ux, uy, uz = work[v], work[v + 1], work[v + 2], work[v + 3], work[v + 4], work[v + 5]
    mass, hx, hy, hz = work[inertia], work[inertia + 1], work[inertia + 2], work[inertia + 3]
    i0, i1, i2 = work[inertia + 4], work[inertia + 5], work[inertia + 6]
    i3, i4, i5 = work[inertia + 7], work[inertia + 8], work[inertia + 9]
    kx = i0 * wx + i1 * wy + i2 * wz + hy * uz - hz * uy
    ky = i1 * wx + i3 * wy + i4 * wz + hz * ux - hx * uz
    kz = i2 * wx + i4 * wy + i5 * wz + hx * uy - hy * ux
    # W = [w]x I_O: column c is w x I_O[:, c]
    w00 = wy * i2 - wz * i1
    w10 = wz * i0 - wx * i2
    w20 = wx * i1 - wy * i0
    w01 = wy * i4 - wz * i3
    w11 = wz * i1 - wx * i4
    w21 = wx * i3 - wy * i1
    w02 = wy * i5 - wz * i4
    w12 = wz * i2 - wx * i5
    w22 = wx * i4 - wy * i2
    uh = ux * hx + uy * hy + uz * hz
    work[out] = w00 - hx * ux + uh
    work[out + 1] = 0.5 * (w01 + w10 - hx * uy - ux * hy + kz)
    work[out + 2] = 0.5 * (w02 + w20 - hx * uz - ux * hz - ky)
    work[out + 3] = 0.5 * (w10 + w01 - hy * ux - uy * hx - kz)
    work[out + 4] = w11 - hy * uy + uh
    work[out + 5] = 0.5 * (w12 + w21 - hy * uz - uy * hz + kx)
    work[out + 6] = 0.5 * (w20 + w02 - hz * ux - uz * hx + ky)
    work[out + 7] = 0.5 * (w21 + w12 - hz * uy - uz * hy - kx)
    work[out + 8] = w22 - hz * uz + uh
    work[out + 9] = mass * ux + wy * hz - wz * hy
    work[out + 10] = mass * uy + wz * hx - wx * hz
    work[out + 11] = mass * uz + wx * hy - wy * hx


@njit(inline="always", **NUMBA_OPTIONS)
def coriolis_core(model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray, C: np.ndarray) -> None:
    """The Christoffel-consistent Vm(q, qd) in O(n d), d the depth (Echeandia and Wensing 2021, Alg. 2).

    World frame: v_i = v_p + S_i qd_i, Sdot_i = v_i x S_i; composite I^c and B^c summed up the tree;
    for j and each ancestor i: C_ij = S_i^T (I^c_j Sdot_j + B^c_j S_j),
    C_ji = Sdot_i^T I^c_j S_j + S_i^T B^c_j^T S_j.
    Work per joint: local transform 12, world pose 12, S 6, Sdot 6, v 6, I^c 10, B^c 12.
    """
    n = int(model[N_JOINTS])
    local, pose, S, Sdot = CORIOLIS_LOCAL * n, CORIOLIS_POSE * n, CORIOLIS_SUBSPACE * n, CORIOLIS_SUBSPACE_DOT * n
    vel, IC, BC, tmp = CORIOLIS_VELOCITY * n, CORIOLIS_COMPOSITE * n, CORIOLIS_BIAS * n, CORIOLIS_JOINT * n
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        joint_transform(model, i, q[i], work, local + TRANSFORM * i)
        world_pose(model, work, local + TRANSFORM * i, pose + TRANSFORM * parent, pose + TRANSFORM * i, parent >= 0)
        world_motion_subspace(model, i, work, pose + TRANSFORM * i, S + SPATIAL * i)
        for k in range(6):
            work[vel + SPATIAL * i + k] = (work[vel + SPATIAL * parent + k] if parent >= 0 else 0.0) + work[
                S + SPATIAL * i + k
            ] * qd[i]
        motion_cross(work, vel + SPATIAL * i, S + SPATIAL * i, Sdot + SPATIAL * i)
        work[tmp] = model[b + MASS]
        for k in range(3):
            work[tmp + 1 + k] = model[b + FIRST_MOMENT + k]
        for k in range(6):
            work[tmp + 4 + k] = model[b + INERTIA + k]
        for k in range(10):
            work[IC + COMPOSITE * i + k] = 0.0
        add_inertia_to_parent(work, pose + TRANSFORM * i, tmp, IC + COMPOSITE * i)
        body_coriolis(work, vel + SPATIAL * i, IC + COMPOSITE * i, BC + COMPOSITE_BIAS * i)
        for j in range(n):
            C[i, j] = 0.0
    for j in range(n - 1, -1, -1):
        ic, bc, sj, dj = IC + COMPOSITE * j, BC + COMPOSITE_BIAS * j, S + SPATIAL * j, Sdot + SPATIAL * j
        mass, hx, hy, hz = work[ic], work[ic + 1], work[ic + 2], work[ic + 3]
        i0, i1, i2, i3, i4, i5 = work[ic + 4], work[ic + 5], work[ic + 6], work[ic + 7], work[ic + 8], work[ic + 9]
        ax, ay, az, sx, sy, sz = work[sj], work[sj + 1], work[sj + 2], work[sj + 3], work[sj + 4], work[sj + 5]
        dax, day, daz, dsx, dsy, dsz = work[dj], work[dj + 1], work[dj + 2], work[dj + 3], work[dj + 4], work[dj + 5]
        b00, b01, b02, b10, b11, b12 = work[bc], work[bc + 1], work[bc + 2], work[bc + 3], work[bc + 4], work[bc + 5]
        b20, b21, b22, lx, ly, lz = work[bc + 6], work[bc + 7], work[bc + 8], work[bc + 9], work[bc + 10], work[bc + 11]
        f2a, f2b, f2c, f2d, f2e, f2f = inertia_apply(
            (mass, hx, hy, hz, i0, i1, i2, i3, i4, i5), (ax, ay, az, sx, sy, sz)
        )  # F2 = I^c S
        # F1 = I^c Sdot + B^c S, B^c S = [B11 a; -l x a]
        f1a = i0 * dax + i1 * day + i2 * daz + hy * dsz - hz * dsy + b00 * ax + b01 * ay + b02 * az
        f1b = i1 * dax + i3 * day + i4 * daz + hz * dsx - hx * dsz + b10 * ax + b11 * ay + b12 * az
        f1c = i2 * dax + i4 * day + i5 * daz + hx * dsy - hy * dsx + b20 * ax + b21 * ay + b22 * az
        f1d = mass * dsx - (hy * daz - hz * day) - (ly * az - lz * ay)
        f1e = mass * dsy - (hz * dax - hx * daz) - (lz * ax - lx * az)
        f1f = mass * dsz - (hx * day - hy * dax) - (lx * ay - ly * ax)
        # F3 = B^c^T S = [B11^T a + l x s; 0]
        f3a = b00 * ax + b10 * ay + b20 * az + ly * sz - lz * sy
        f3b = b01 * ax + b11 * ay + b21 * az + lz * sx - lx * sz
        f3c = b02 * ax + b12 * ay + b22 * az + lx * sy - ly * sx
        C[j, j] = ax * f1a + ay * f1b + az * f1c + sx * f1d + sy * f1e + sz * f1f
        parent = int(model[HEADER + STRIDE * j + PARENT])
        i = parent
        while i >= 0:
            si, di = S + SPATIAL * i, Sdot + SPATIAL * i
            C[i, j] = dot_with(work, si, (f1a, f1b, f1c, f1d, f1e, f1f))
            C[j, i] = dot_with(work, di, (f2a, f2b, f2c, f2d, f2e, f2f)) + (
                work[si] * f3a + work[si + 1] * f3b + work[si + 2] * f3c
            )
            i = int(model[HEADER + STRIDE * i + PARENT])
        if parent >= 0:
            for k in range(10):
                work[IC + COMPOSITE * parent + k] += work[ic + k]
            for k in range(12):
                work[BC + COMPOSITE_BIAS * parent + k] += work[bc + k]


@one_state(types.int64(MODEL, VECTOR, VECTOR, MATRIX))
def coriolis_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, C: np.ndarray) -> int:
    """Vm(q, qd) for one state; the status of states_status, or WRONG_SHAPE when C is not (n, n)."""
    n = int(model[N_JOINTS])
    status = states_status(model, q, qd, qd, 2)
    if status == OK and (C.shape[0] != n or C.shape[1] != n):
        status = WRONG_SHAPE
    if status == OK:
        coriolis_core(model, scratch(CORIOLIS_JOINT * n + CORIOLIS_FIXED), q, qd, C)
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def coriolis_batch(model: np.ndarray, q: np.ndarray, qd: np.ndarray, C: np.ndarray) -> None:
    """Vm for each row of (q, qd), in parallel chunks."""
    count = q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work = np.empty(workspace_size(int(model[N_JOINTS])))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            coriolis_core(model, work, q[s], qd[s], C[s])
