"""Compiled kinematics: the pose of every link frame, the tool pose, the geometric Jacobian of
the tool or of a link frame's origin and its time derivative (Appendix A; Siciliano et al.,
Robotics: Modelling, Planning and Control, 2009, 3.1 and 3.4), one state or a batch.

The body frames are the joint frames of the packed model (packed.py): body i moves about or
along its own z axis, so z_i and o_i of the Jacobian are the third column and the origin of
its world pose B_i = B_parent P_i Rz(q_i). A link frame is B_i L_i, with L_i the link frame
(DH or URDF) in the body frame; the tool is B_k T with T the tool in body k's frame.
``armdyn.kinematics`` holds the NumPy versions, the readable reference the tests compare with.

A target is a link index, or TOOL (-1) for the tool. A frame is WORLD (0: rows in world axes)
or LOCAL (1: rows in the target frame's axes).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types

from armdyn.dynamics.packed import (
    HEADER,
    KIND,
    LINK_ROTATION,
    N_JOINTS,
    PARENT,
    STRIDE,
    TOOL_LINK,
    TOOL_ROTATION,
)
from armdyn.dynamics.spatial import (
    MATRIX,
    MODEL,
    NUMBA_OPTIONS,
    VECTOR,
    joint_transform,
    one_state,
    pose_product,
    scratch,
    states_status,
    world_pose,
)
from armdyn.dynamics.status import BAD_FRAME, BAD_LINK, OK, WRONG_SHAPE

TOOL, WORLD, LOCAL = -1, 0, 1
POSE = 12  # a world pose in the workspace: R (9, row-major) and p (3)
TRANSFORMS_CHUNKS = 64  # parallel chunks of a batch call
ARRAY3 = types.float64[:, :, ::1]
ARRAY4 = types.float64[:, :, :, ::1]


@njit(inline="always", **NUMBA_OPTIONS)
def body_poses(model: np.ndarray, q: np.ndarray, work: np.ndarray) -> None:
    """World poses of the body frames, B_i = B_parent (P_i Rz(q_i)), at work[12 i : 12 i + 12];
    work[12 n : 12 n + 12] is scratch for the local transform."""
    n = int(model[N_JOINTS])
    local = POSE * n
    for i in range(n):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        joint_transform(model, i, q[i], work, local)
        world_pose(model, work, local, POSE * parent, POSE * i, parent >= 0)


@njit(inline="always", **NUMBA_OPTIONS)
def target_pose(model: np.ndarray, work: np.ndarray, target: int, o: int) -> int:
    """The world pose of the target (a link frame, or the tool) at work[o:o+12]; returns the
    index of the body that carries it."""
    if target == TOOL:
        body = int(model[TOOL_LINK])
        pose_product(work, POSE * body, model, TOOL_ROTATION, work, o)
    else:
        body = target
        pose_product(work, POSE * body, model, HEADER + STRIDE * body + LINK_ROTATION, work, o)
    return body


@njit(inline="always", **NUMBA_OPTIONS)
def write_pose(work: np.ndarray, o: int, out: np.ndarray) -> None:
    """A 4 x 4 homogeneous matrix from the pose at work[o:o+12]."""
    for r in range(3):
        for c in range(3):
            out[r, c] = work[o + 3 * r + c]
        out[r, 3] = work[o + 9 + r]
        out[3, r] = 0.0
    out[3, 3] = 1.0


@njit(inline="always", **NUMBA_OPTIONS)
def jacobian_columns(model: np.ndarray, work: np.ndarray, body: int, point: int, out: np.ndarray) -> None:
    """out (6, n) = [z_j x (p - o_j); z_j] (revolute) or [z_j; 0] (prismatic) for the joints j
    that move ``body`` (its ancestors and itself), zero for the others; p at work[point:]."""
    n = int(model[N_JOINTS])
    for r in range(6):
        for j in range(n):
            out[r, j] = 0.0
    j = body
    while j >= 0:
        zx, zy, zz = work[POSE * j + 2], work[POSE * j + 5], work[POSE * j + 8]
        if model[HEADER + STRIDE * j + KIND] == 0.0:
            dx = work[point] - work[POSE * j + 9]
            dy = work[point + 1] - work[POSE * j + 10]
            dz = work[point + 2] - work[POSE * j + 11]
            out[0, j], out[1, j], out[2, j] = zy * dz - zz * dy, zz * dx - zx * dz, zx * dy - zy * dx
            out[3, j], out[4, j], out[5, j] = zx, zy, zz
        else:
            out[0, j], out[1, j], out[2, j] = zx, zy, zz
        j = int(model[HEADER + STRIDE * j + PARENT])


@njit(inline="always", **NUMBA_OPTIONS)
def rotate_rows_into(work: np.ndarray, pose: int, out: np.ndarray) -> None:
    """out (6, n): both 3-row blocks expressed in the axes of the pose's rotation R (R^T rows)."""
    for j in range(out.shape[1]):
        for block in range(0, 6, 3):
            x, y, z = out[block, j], out[block + 1, j], out[block + 2, j]
            for c in range(3):
                out[block + c, j] = work[pose + c] * x + work[pose + 3 + c] * y + work[pose + 6 + c] * z


@njit(inline="always", **NUMBA_OPTIONS)
def body_velocities(model: np.ndarray, qd: np.ndarray, work: np.ndarray, w: int) -> None:
    """The angular velocity w_i of every body and the velocity v_i of its origin, in world axes,
    at work[w + 6 i : w + 6 i + 6]: w_i = w_parent + qd_i z_i (revolute), v_i = v_parent +
    w_parent x (o_i - o_parent) (+ qd_i z_i, prismatic)."""
    n = int(model[N_JOINTS])
    for i in range(n):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        zx, zy, zz = work[POSE * i + 2], work[POSE * i + 5], work[POSE * i + 8]
        o = w + 6 * i
        if parent < 0:
            for k in range(6):
                work[o + k] = 0.0
        else:
            u = w + 6 * parent
            dx = work[POSE * i + 9] - work[POSE * parent + 9]
            dy = work[POSE * i + 10] - work[POSE * parent + 10]
            dz = work[POSE * i + 11] - work[POSE * parent + 11]
            work[o], work[o + 1], work[o + 2] = work[u], work[u + 1], work[u + 2]
            work[o + 3] = work[u + 3] + work[u + 1] * dz - work[u + 2] * dy
            work[o + 4] = work[u + 4] + work[u + 2] * dx - work[u] * dz
            work[o + 5] = work[u + 5] + work[u] * dy - work[u + 1] * dx
        k = 0 if model[HEADER + STRIDE * i + KIND] == 0.0 else 3
        work[o + k] += qd[i] * zx
        work[o + k + 1] += qd[i] * zy
        work[o + k + 2] += qd[i] * zz


@njit(inline="always", **NUMBA_OPTIONS)
def jacobian_dot_columns(
    model: np.ndarray, work: np.ndarray, body: int, point: int, w: int, out: np.ndarray
) -> tuple[float, float, float]:
    """out (6, n) = dJ/dt in world axes: for a joint j that moves the body, with zdot_j =
    w_parent x z_j and odot_j the velocity of o_j, [zdot_j x (p - o_j) + z_j x (pdot - odot_j);
    zdot_j] (revolute) or [zdot_j; 0] (prismatic); returns the target's w."""
    n = int(model[N_JOINTS])
    for r in range(6):
        for j in range(n):
            out[r, j] = 0.0
    # pdot = v_body + w_body x (p - o_body), w = w_body
    b = w + 6 * body
    wx, wy, wz = work[b], work[b + 1], work[b + 2]
    dx = work[point] - work[POSE * body + 9]
    dy = work[point + 1] - work[POSE * body + 10]
    dz = work[point + 2] - work[POSE * body + 11]
    px, py, pz = work[b + 3] + wy * dz - wz * dy, work[b + 4] + wz * dx - wx * dz, work[b + 5] + wx * dy - wy * dx
    j = body
    while j >= 0:
        parent = int(model[HEADER + STRIDE * j + PARENT])
        zx, zy, zz = work[POSE * j + 2], work[POSE * j + 5], work[POSE * j + 8]
        ax, ay, az = 0.0, 0.0, 0.0
        if parent >= 0:
            u = w + 6 * parent
            ax, ay, az = (
                work[u + 1] * zz - work[u + 2] * zy,
                work[u + 2] * zx - work[u] * zz,
                work[u] * zy - work[u + 1] * zx,
            )
        if model[HEADER + STRIDE * j + KIND] == 0.0:
            v = w + 6 * j
            ex = work[point] - work[POSE * j + 9]
            ey = work[point + 1] - work[POSE * j + 10]
            ez = work[point + 2] - work[POSE * j + 11]
            fx, fy, fz = px - work[v + 3], py - work[v + 4], pz - work[v + 5]
            out[0, j] = ay * ez - az * ey + zy * fz - zz * fy
            out[1, j] = az * ex - ax * ez + zz * fx - zx * fz
            out[2, j] = ax * ey - ay * ex + zx * fy - zy * fx
            out[3, j], out[4, j], out[5, j] = ax, ay, az
        else:
            out[0, j], out[1, j], out[2, j] = ax, ay, az
        j = parent
    return wx, wy, wz


@njit(inline="always", **NUMBA_OPTIONS)
def local_derivative(out: np.ndarray, jac: np.ndarray, wx: float, wy: float, wz: float) -> None:
    """out = dJ/dt - [w]x J per 3-row block (world axes), before rotating into the target's
    axes: d/dt (R^T J) = R^T (dJ/dt - [w]x J)."""
    for j in range(out.shape[1]):
        for block in range(0, 6, 3):
            x, y, z = jac[block, j], jac[block + 1, j], jac[block + 2, j]
            out[block, j] -= wy * z - wz * y
            out[block + 1, j] -= wz * x - wx * z
            out[block + 2, j] -= wx * y - wy * x


@njit(inline="always", **NUMBA_OPTIONS)
def transforms_core(model: np.ndarray, q: np.ndarray, work: np.ndarray, out: np.ndarray) -> None:
    """out (n, 4, 4): the world pose of every link frame."""
    n = int(model[N_JOINTS])
    body_poses(model, q, work)
    link_pose = POSE * (n + 1)
    for i in range(n):
        pose_product(work, POSE * i, model, HEADER + STRIDE * i + LINK_ROTATION, work, link_pose)
        write_pose(work, link_pose, out[i])


@njit(inline="always", **NUMBA_OPTIONS)
def pose_core(model: np.ndarray, q: np.ndarray, target: int, work: np.ndarray, out: np.ndarray) -> None:
    """out (4, 4): the world pose of the target."""
    n = int(model[N_JOINTS])
    body_poses(model, q, work)
    target_pose(model, work, target, POSE * (n + 1))
    write_pose(work, POSE * (n + 1), out)


@njit(inline="always", **NUMBA_OPTIONS)
def jacobian_core(model: np.ndarray, q: np.ndarray, target: int, frame: int, work: np.ndarray, out: np.ndarray) -> None:
    """out (6, n): the geometric Jacobian of the target's origin, [v; w] = J qd."""
    n = int(model[N_JOINTS])
    body_poses(model, q, work)
    pose = POSE * (n + 1)
    body = target_pose(model, work, target, pose)
    jacobian_columns(model, work, body, pose + 9, out)
    if frame == LOCAL:
        rotate_rows_into(work, pose, out)


@njit(inline="always", **NUMBA_OPTIONS)
def jacobian_dot_core(
    model: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    target: int,
    frame: int,
    work: np.ndarray,
    jac: np.ndarray,
    out: np.ndarray,
) -> None:
    """out (6, n): dJ/dt of the target's Jacobian, in world or local axes (``jac``, (6, n), is
    scratch for J, needed in local axes only)."""
    n = int(model[N_JOINTS])
    body_poses(model, q, work)
    pose = POSE * (n + 1)
    body = target_pose(model, work, target, pose)
    velocities = POSE * (n + 2)
    body_velocities(model, qd, work, velocities)
    wx, wy, wz = jacobian_dot_columns(model, work, body, pose + 9, velocities, out)
    if frame == LOCAL:
        jacobian_columns(model, work, body, pose + 9, jac)
        local_derivative(out, jac, wx, wy, wz)
        rotate_rows_into(work, pose, out)


@njit(inline="always", **NUMBA_OPTIONS)
def frames_workspace_size(n: int) -> int:
    """Scratch values for one state: the body poses, two more poses and the body velocities."""
    return POSE * (n + 2) + 6 * n


@njit(inline="always", **NUMBA_OPTIONS)
def target_status(model: np.ndarray, target: int, frame: int) -> int:
    """OK, or BAD_LINK for a target that is neither TOOL nor a link index, BAD_FRAME for an unknown frame."""
    if target < TOOL or target >= int(model[N_JOINTS]):
        return BAD_LINK
    return OK if frame in (WORLD, LOCAL) else BAD_FRAME


@one_state(types.int64(MODEL, VECTOR, ARRAY3))
def transforms_one(model: np.ndarray, q: np.ndarray, out: np.ndarray) -> int:
    """Every link frame's world pose for one state; a status (spatial.states_status, WRONG_SHAPE: out)."""
    n = int(model[N_JOINTS])
    status = states_status(model, q, q, q, 1)
    if status == OK and (out.shape[0] != n or out.shape[1] != 4 or out.shape[2] != 4):
        status = WRONG_SHAPE
    if status == OK:
        transforms_core(model, q, scratch(frames_workspace_size(n)), out)
    return status


@one_state(types.int64(MODEL, VECTOR, types.int64, MATRIX))
def pose_one(model: np.ndarray, q: np.ndarray, target: int, out: np.ndarray) -> int:
    """The target's world pose for one state; a status."""
    status = states_status(model, q, q, q, 1)
    if status == OK:
        status = target_status(model, target, WORLD)
    if status == OK and (out.shape[0] != 4 or out.shape[1] != 4):
        status = WRONG_SHAPE
    if status == OK:
        pose_core(model, q, target, scratch(frames_workspace_size(int(model[N_JOINTS]))), out)
    return status


@one_state(types.int64(MODEL, VECTOR, types.int64, types.int64, MATRIX))
def jacobian_one(model: np.ndarray, q: np.ndarray, target: int, frame: int, out: np.ndarray) -> int:
    """The target's Jacobian for one state; a status."""
    n = int(model[N_JOINTS])
    status = states_status(model, q, q, q, 1)
    if status == OK:
        status = target_status(model, target, frame)
    if status == OK and (out.shape[0] != 6 or out.shape[1] != n):
        status = WRONG_SHAPE
    if status == OK:
        jacobian_core(model, q, target, frame, scratch(frames_workspace_size(n)), out)
    return status


@one_state(types.int64(MODEL, VECTOR, VECTOR, types.int64, types.int64, MATRIX))
def jacobian_dot_one(model: np.ndarray, q: np.ndarray, qd: np.ndarray, target: int, frame: int, out: np.ndarray) -> int:
    """dJ/dt of the target's Jacobian for one state; a status."""
    n = int(model[N_JOINTS])
    status = states_status(model, q, qd, qd, 2)
    if status == OK:
        status = target_status(model, target, frame)
    if status == OK and (out.shape[0] != 6 or out.shape[1] != n):
        status = WRONG_SHAPE
    if status == OK:
        jacobian_dot_core(model, q, qd, target, frame, scratch(frames_workspace_size(n)), np.empty((6, n)), out)
    return status


@njit(parallel=True, **NUMBA_OPTIONS)
def transforms_batch(model: np.ndarray, q: np.ndarray, out: np.ndarray) -> None:
    """Every link frame's world pose for each state: q (B, n) -> out (B, n, 4, 4)."""
    states = q.shape[0]
    chunks = min(TRANSFORMS_CHUNKS, states)
    for chunk in prange(chunks):
        work = np.empty(frames_workspace_size(q.shape[1]))
        for s in range(chunk * states // chunks, (chunk + 1) * states // chunks):
            transforms_core(model, q[s], work, out[s])


@njit(parallel=True, **NUMBA_OPTIONS)
def pose_batch(model: np.ndarray, q: np.ndarray, target: int, out: np.ndarray) -> None:
    """The target's world pose for each state: q (B, n) -> out (B, 4, 4)."""
    states = q.shape[0]
    chunks = min(TRANSFORMS_CHUNKS, states)
    for chunk in prange(chunks):
        work = np.empty(frames_workspace_size(q.shape[1]))
        for s in range(chunk * states // chunks, (chunk + 1) * states // chunks):
            pose_core(model, q[s], target, work, out[s])


@njit(parallel=True, **NUMBA_OPTIONS)
def jacobian_batch(model: np.ndarray, q: np.ndarray, target: int, frame: int, out: np.ndarray) -> None:
    """The target's Jacobian for each state: q (B, n) -> out (B, 6, n)."""
    states = q.shape[0]
    chunks = min(TRANSFORMS_CHUNKS, states)
    for chunk in prange(chunks):
        work = np.empty(frames_workspace_size(q.shape[1]))
        for s in range(chunk * states // chunks, (chunk + 1) * states // chunks):
            jacobian_core(model, q[s], target, frame, work, out[s])


@njit(parallel=True, **NUMBA_OPTIONS)
def jacobian_dot_batch(
    model: np.ndarray, q: np.ndarray, qd: np.ndarray, target: int, frame: int, out: np.ndarray
) -> None:
    """dJ/dt of the target's Jacobian for each state: q, qd (B, n) -> out (B, 6, n)."""
    states = q.shape[0]
    chunks = min(TRANSFORMS_CHUNKS, states)
    for chunk in prange(chunks):
        work, jac = np.empty(frames_workspace_size(q.shape[1])), np.empty((6, q.shape[1]))
        for s in range(chunk * states // chunks, (chunk + 1) * states // chunks):
            jacobian_dot_core(model, q[s], qd[s], target, frame, work, jac, out[s])
