"""Inverse dynamics by the recursive Newton-Euler algorithm, and its parts (Featherstone,
Rigid Body Dynamics Algorithms, 2008, 5.3): tau = M qdd + Vm qd + F + G (+ J^T f_ext), and with
flags the Coriolis vector V = Vm qd, N = V + F + G, or G alone.

A one-state entry (``*_one``) checks its inputs and returns a status (spatial.states_status;
status.WRONG_SHAPE for an output of the wrong shape); a batch entry runs states in parallel chunks, each with
its own workspace (packed.workspace_size).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.friction import coulomb, nonlinear_friction
from armdyn.dynamics.packed import (
    ARMATURE,
    FIRST_MOMENT,
    GRAVITY,
    GRAVITY_ACCELERATION,
    GRAVITY_FORCE,
    GRAVITY_JOINT,
    GRAVITY_MOMENT,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    N_JOINTS,
    PARENT,
    POSITION,
    RNEA_FIXED,
    RNEA_FORCE,
    RNEA_JOINT,
    RNEA_VELOCITY,
    ROTATION,
    STRIDE,
    TOOL_LINK,
    TOOL_POSITION,
    TOOL_ROTATION,
    VISCOUS,
    workspace_size,
)
from armdyn.dynamics.spatial import (
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    add_force_to_parent,
    force_to_parent,
    joint_transform,
    newton_euler_step,
    one_state,
    scratch,
    sin_cos,
    states_status,
)
from armdyn.dynamics.status import OK, WRONG_SHAPE

WITH_QDD, WITH_GRAVITY, WITH_VELOCITY, WITH_FRICTION, WITH_WRENCH = 1, 2, 4, 8, 16
INVERSE_DYNAMICS = WITH_QDD | WITH_GRAVITY | WITH_VELOCITY | WITH_FRICTION
NONLINEAR = WITH_GRAVITY | WITH_VELOCITY | WITH_FRICTION
CORIOLIS = WITH_VELOCITY
GRAVITY_ONLY = WITH_GRAVITY
BATCH_CHUNKS = 64  # parallel chunks of a batch call, each with its own workspace


@njit(inline="always", **NUMBA_OPTIONS)
def rnea_core(
    model: np.ndarray,
    work: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    wrench: np.ndarray,
    flags: int,
    tau: np.ndarray,
) -> None:
    """tau = M qdd + Vm qd + F + G (+ J^T wrench), the parts selected by ``flags`` (Featherstone 5.3).

    Forward: v_i = X_i v_p + S qd_i, a_i = X_i a_p + S qdd_i + (X_i v_p) x S qd_i, a_0 = -g;
    f_i = I_i a_i + v_i x* I_i v_i. Backward: tau_i = S^T f_i (+ armature qdd_i, friction),
    f_p += X_i^T f_i. Written out in scalars: this is the hot loop of every simulation.
    Workspace per joint at work[RNEA_JOINT i:]: R (9), p (3), v (6), a (6), f (6); the tool
    wrench's transform after the last joint (RNEA_FIXED).
    """
    n = int(model[N_JOINTS])
    gscale = 1.0 if (flags & WITH_GRAVITY) != 0 else 0.0
    vscale = 1.0 if (flags & WITH_VELOCITY) != 0 else 0.0
    ascale = 1.0 if (flags & WITH_QDD) != 0 else 0.0
    gx, gy, gz = -gscale * model[GRAVITY], -gscale * model[GRAVITY + 1], -gscale * model[GRAVITY + 2]
    for i in range(n):
        b = HEADER + STRIDE * i
        r = b + ROTATION
        parent = int(model[b])
        p00, p01, p02 = model[r], model[r + 1], model[r + 2]
        p10, p11, p12 = model[r + 3], model[r + 4], model[r + 5]
        p20, p21, p22 = model[r + 6], model[r + 7], model[r + 8]
        px, py, pz = model[b + POSITION], model[b + POSITION + 1], model[b + POSITION + 2]
        qi = q[i]
        if model[b + KIND] == 0.0:
            s, c = sin_cos(qi)
            r00 = p00 * c + p01 * s
            r01 = p01 * c - p00 * s
            r10 = p10 * c + p11 * s
            r11 = p11 * c - p10 * s
            r20 = p20 * c + p21 * s
            r21 = p21 * c - p20 * s
            prism = 0.0
        else:
            r00, r01, r10, r11, r20, r21 = p00, p01, p10, p11, p20, p21
            px += qi * p02
            py += qi * p12
            pz += qi * p22
            prism = 1.0
        r02, r12, r22 = p02, p12, p22
        o = RNEA_JOINT * i
        work[o], work[o + 1], work[o + 2], work[o + 3], work[o + 4], work[o + 5] = r00, r01, r02, r10, r11, r12
        work[o + 6], work[o + 7], work[o + 8], work[o + 9], work[o + 10], work[o + 11] = r20, r21, r22, px, py, pz
        if parent >= 0:
            op = RNEA_JOINT * parent + RNEA_VELOCITY
            wx, wy, wz, vx, vy, vz = work[op], work[op + 1], work[op + 2], work[op + 3], work[op + 4], work[op + 5]
            ax, ay, az, lx, ly, lz = (
                work[op + 6],
                work[op + 7],
                work[op + 8],
                work[op + 9],
                work[op + 10],
                work[op + 11],
            )
        else:
            wx = wy = wz = vx = vy = vz = ax = ay = az = 0.0
            lx, ly, lz = gx, gy, gz
        k = b + INERTIA
        body = (
            model[b + MASS], model[b + FIRST_MOMENT], model[b + FIRST_MOMENT + 1], model[b + FIRST_MOMENT + 2],
            model[k], model[k + 1], model[k + 2], model[k + 3], model[k + 4], model[k + 5],
        )  # fmt: skip
        motion = newton_euler_step(
            (r00, r01, r02, r10, r11, r12, r20, r21, r22), (px, py, pz), (wx, wy, wz, vx, vy, vz),
            (ax, ay, az, lx, ly, lz), vscale * qd[i], ascale * qdd[i], prism, body,
        )  # fmt: skip
        for j in range(18):  # v, a, f
            work[o + RNEA_VELOCITY + j] = motion[j]
    if (flags & WITH_WRENCH) != 0:
        add_tool_wrench(model, work, RNEA_JOINT * int(model[TOOL_LINK]) + RNEA_FORCE, wrench, RNEA_JOINT * n)
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        o = RNEA_JOINT * i
        f = o + RNEA_FORCE
        nx, ny, nz, fx, fy, fz = work[f], work[f + 1], work[f + 2], work[f + 3], work[f + 4], work[f + 5]
        prism = model[b + KIND]
        value = prism * fz + (1.0 - prism) * nz + ascale * model[b + ARMATURE] * qdd[i]
        if (flags & WITH_FRICTION) != 0:
            value += model[b + VISCOUS] * qd[i]
            value += coulomb(model, i, qd[i])
            value += nonlinear_friction(model, i, qd[i])
        tau[i] = value
        parent = int(model[b])
        if parent >= 0:
            r00, r01, r02, r10, r11, r12 = work[o], work[o + 1], work[o + 2], work[o + 3], work[o + 4], work[o + 5]
            r20, r21, r22, px, py, pz = work[o + 6], work[o + 7], work[o + 8], work[o + 9], work[o + 10], work[o + 11]
            moved = force_to_parent(
                (r00, r01, r02, r10, r11, r12, r20, r21, r22), (px, py, pz), (nx, ny, nz), (fx, fy, fz)
            )
            op = RNEA_JOINT * parent + RNEA_FORCE
            for k in range(6):
                work[op + k] += moved[k]


@njit(inline="always", **NUMBA_OPTIONS)
def add_tool_wrench(model: np.ndarray, work: np.ndarray, f: int, wrench: np.ndarray, tmp: int) -> None:
    """The body of the tool link must also supply the wrench [force; moment] that the tool
    exerts on its surroundings, given in the tool frame about the tool point."""
    for k in range(9):
        work[tmp + k] = model[TOOL_ROTATION + k]
    for k in range(3):
        work[tmp + 9 + k] = model[TOOL_POSITION + k]
        work[tmp + 12 + k] = wrench[3 + k]  # moment
        work[tmp + 15 + k] = wrench[k]  # force
    add_force_to_parent(work, tmp, work, tmp + 12, work, f)


@njit(inline="always", **NUMBA_OPTIONS)
def rnea_checked(
    model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, flags: int, count: int, tau: np.ndarray
) -> int:
    """One state: check the first ``count`` states and tau's length, then the parts of tau that
    ``flags`` selects; returns the status (0 when computed)."""
    status = states_status(model, q, qd, qdd, count)
    if status == OK and tau.shape[0] != int(model[N_JOINTS]):
        status = WRONG_SHAPE
    if status == OK:
        rnea_core(model, scratch(RNEA_JOINT * int(model[N_JOINTS]) + RNEA_FIXED), q, qd, qdd, qd, flags, tau)
    return status


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR, VECTOR))
def inverse_dynamics_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, tau: np.ndarray) -> int:
    """tau = M qdd + Vm qd + F + G for one state."""
    return rnea_checked(model, q, qd, qdd, INVERSE_DYNAMICS, 3, tau)


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR))
def nonlinear_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """N = Vm qd + F + G for one state."""
    return rnea_checked(model, q, qd, qd, NONLINEAR, 2, out)


@one_state(types.int64(MODEL, VECTOR, VECTOR, VECTOR))
def coriolis_vector_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """V = Vm qd for one state."""
    return rnea_checked(model, q, qd, qd, CORIOLIS, 2, out)


@njit(parallel=True, **NUMBA_OPTIONS)
def rnea_batch(
    model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, wrench: np.ndarray, flags: int, tau: np.ndarray
) -> None:
    """Many states (B, n) at once, in parallel chunks; wrench (B, 6) or (1, 6) for all."""
    count = q.shape[0]
    chunks = min(count, BATCH_CHUNKS)
    for chunk in prange(chunks):
        work = np.empty(workspace_size(int(model[N_JOINTS])))
        for s in range(chunk * count // chunks, (chunk + 1) * count // chunks):
            e = s if wrench.shape[0] == count else 0
            rnea_core(model, work, q[s], qd[s], qdd[s], wrench[e], flags, tau[s])


@njit(inline="always", **NUMBA_OPTIONS)
def gravity_core(model: np.ndarray, work: np.ndarray, q: np.ndarray, G: np.ndarray) -> None:
    """G(q): RNEA with no motion (Featherstone 5.3). Each body's acceleration is then -g in its own
    axes, a_i = [0; R_i^T l_p], its force f_i = [h x l_i; m l_i]; tau_i = S^T f_i and
    f_p += X_i^T f_i. Workspace: GRAVITY_JOINT per joint: R, p | a | f."""
    n = int(model[N_JOINTS])
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        o = GRAVITY_JOINT * i
        joint_transform(model, i, q[i], work, o)
        if parent >= 0:
            op = GRAVITY_JOINT * parent + GRAVITY_ACCELERATION
            lx, ly, lz = work[op], work[op + 1], work[op + 2]
        else:
            lx, ly, lz = -model[GRAVITY], -model[GRAVITY + 1], -model[GRAVITY + 2]
        Lx = work[o] * lx + work[o + 3] * ly + work[o + 6] * lz
        Ly = work[o + 1] * lx + work[o + 4] * ly + work[o + 7] * lz
        Lz = work[o + 2] * lx + work[o + 5] * ly + work[o + 8] * lz
        mass, hx, hy, hz = (
            model[b + MASS],
            model[b + FIRST_MOMENT],
            model[b + FIRST_MOMENT + 1],
            model[b + FIRST_MOMENT + 2],
        )
        a, f = o + GRAVITY_ACCELERATION, o + GRAVITY_MOMENT
        work[a], work[a + 1], work[a + 2] = Lx, Ly, Lz
        work[f], work[f + 1], work[f + 2] = hy * Lz - hz * Ly, hz * Lx - hx * Lz, hx * Ly - hy * Lx
        work[f + 3], work[f + 4], work[f + 5] = mass * Lx, mass * Ly, mass * Lz
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        o = GRAVITY_JOINT * i
        G[i] = work[o + GRAVITY_FORCE + 2] if model[b + KIND] != 0.0 else work[o + GRAVITY_MOMENT + 2]
        parent = int(model[b + PARENT])
        if parent >= 0:
            add_force_to_parent(work, o, work, o + GRAVITY_MOMENT, work, GRAVITY_JOINT * parent + GRAVITY_MOMENT)


@one_state(types.int64(MODEL, VECTOR, VECTOR))
def gravity_one(model: np.ndarray, q: np.ndarray, out: np.ndarray) -> int:
    """G(q) for one state, by its own lean recursion."""
    status = states_status(model, q, q, q, 1)
    if status == OK and out.shape[0] != int(model[N_JOINTS]):
        status = WRONG_SHAPE
    if status == OK:
        gravity_core(model, scratch(GRAVITY_JOINT * int(model[N_JOINTS])), q, out)
    return status
