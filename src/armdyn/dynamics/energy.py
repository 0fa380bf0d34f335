"""Kinetic and potential energy, K = 1/2 qd^T M qd and P = -sum m_i g^T p_ci (Lewis, Dawson and Abdallah 2004, eqs.
3.2.29 and 3.2.35), from the link velocities and centres of mass.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.packed import (
    ARMATURE,
    ENERGY_FIXED,
    ENERGY_JOINT,
    ENERGY_LOCAL,
    ENERGY_POSE,
    ENERGY_VELOCITY,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    KIND,
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
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    dot6,
    inertia_times,
    joint_transform,
    motion_to_child,
    one_state,
    scratch,
    states_status,
    world_pose,
)
from armdyn.dynamics.status import OK, WRONG_SHAPE


@njit(inline="always", **NUMBA_OPTIONS)
def energy_core(model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    """out[0] = K = 1/2 sum v_i^T I_i v_i + 1/2 sum G^2 Jm qd^2; out[1] = P = -g . sum (m p_w + R_w h)."""
    n = int(model[N_JOINTS])
    local, pose, vel, tmp = ENERGY_LOCAL * n, ENERGY_POSE * n, ENERGY_VELOCITY * n, ENERGY_JOINT * n
    kinetic = 0.0
    potential = 0.0
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        t = local + TRANSFORM * i
        joint_transform(model, i, q[i], work, t)
        world_pose(model, work, t, pose + TRANSFORM * parent, pose + TRANSFORM * i, parent >= 0)
        v = vel + SPATIAL * i
        if parent < 0:
            for k in range(6):
                work[v + k] = 0.0
        else:
            motion_to_child(work, t, work, vel + SPATIAL * parent, work, v)
        work[v + (5 if model[b + KIND] != 0.0 else 2)] += qd[i]
        inertia_times(model, i, work, v, work, tmp)
        kinetic += 0.5 * (dot6(work, v, tmp) + model[b + ARMATURE] * qd[i] * qd[i])
        o = pose + TRANSFORM * i
        mass = model[b + MASS]
        for r in range(3):
            moment = mass * work[o + 9 + r]
            for k in range(3):
                moment += work[o + 3 * r + k] * model[b + FIRST_MOMENT + k]
            potential -= model[GRAVITY + r] * moment
    out[0] = kinetic
    out[1] = potential


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR))
def energy_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """(K, P) for one state into out (2,); the status of states_status, or WRONG_SHAPE when out is not (2,)."""
    status = states_status(model, q, qd, qd, 2)
    if status == OK and out.shape[0] != 2:
        status = WRONG_SHAPE
    if status == OK:
        energy_core(model, scratch(ENERGY_JOINT * int(model[N_JOINTS]) + ENERGY_FIXED), q, qd, out)
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def energy_batch(model: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    """(K, P) for each row of (q, qd), in parallel chunks."""
    count = q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work = np.empty(workspace_size(int(model[N_JOINTS])))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            energy_core(model, work, q[s], qd[s], out[s])
