"""Batch inverse dynamics vectorized across states: structure of arrays, blocks of states.

A batch of inverse dynamics is the same arithmetic on many states. Laid out with the
state index innermost (one row per quantity, one column per state of a block), the
loop over a block's states is straight-line arithmetic that LLVM turns into SIMD
instructions, and blocks run in parallel threads. Joint kinds become 0/1 factors so
that the vectorized loop has no branches, and sin/cos are computed by a polynomial
that vectorizes (libm's do not). The equations are rnea.rnea_core's.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from armdyn.dynamics.friction import coulomb, nonlinear_friction
from armdyn.dynamics.packed import (
    ARMATURE,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    N_JOINTS,
    PARENT,
    POSITION,
    ROTATION,
    SIGMOID_AMPLITUDE,
    STRIBECK_FORCE,
    STRIDE,
    VISCOUS,
)
from armdyn.dynamics.rnea import WITH_FRICTION, WITH_GRAVITY, WITH_QDD, WITH_VELOCITY
from armdyn.dynamics.spatial import NUMBA_OPTIONS, force_to_parent, newton_euler_step, sin_cos

BLOCK = 32  # states per block of both batch kernels: 16 measured slower on the UR5 and the Panda, 64 no faster


@njit(inline="always", **NUMBA_OPTIONS)
def _forward_block(model: np.ndarray, i: int, x: np.ndarray, vscale: float, ascale: float) -> None:
    """One joint's forward step of RNEA for a block of states (see rnea.rnea_core).

    x holds rows of BLOCK values. In: 0-11 the parent's v and a (or zeros and -g for the
    root), 12-14 q, qd, qdd. Out: 15-23 R, 24-26 p, 27-32 v, 33-38 a, 39-44 f. One flat
    buffer with rows at constant offsets lets LLVM see that the rows never overlap, so the
    loop over the block's states vectorizes.
    """
    b = HEADER + STRIDE * i
    r = b + ROTATION
    prism = model[b + KIND]
    rev = 1.0 - prism
    p00, p01, p02, p10, p11, p12 = model[r], model[r + 1], model[r + 2], model[r + 3], model[r + 4], model[r + 5]
    p20, p21, p22 = model[r + 6], model[r + 7], model[r + 8]
    Px, Py, Pz = model[b + POSITION], model[b + POSITION + 1], model[b + POSITION + 2]
    k = b + INERTIA
    body = (
        model[b + MASS], model[b + FIRST_MOMENT], model[b + FIRST_MOMENT + 1], model[b + FIRST_MOMENT + 2],
        model[k], model[k + 1], model[k + 2], model[k + 3], model[k + 4], model[k + 5],
    )  # fmt: skip
    for s in range(BLOCK):
        qi = x[12 * BLOCK + s]
        sn, cs = sin_cos(qi)
        c = rev * cs + prism
        sn = rev * sn
        r00 = p00 * c + p01 * sn
        r01 = p01 * c - p00 * sn
        r10 = p10 * c + p11 * sn
        r11 = p11 * c - p10 * sn
        r20 = p20 * c + p21 * sn
        r21 = p21 * c - p20 * sn
        lift = prism * qi
        px = Px + lift * p02
        py = Py + lift * p12
        pz = Pz + lift * p22
        parent_velocity = (x[0 * BLOCK + s], x[1 * BLOCK + s], x[2 * BLOCK + s], x[3 * BLOCK + s],
                           x[4 * BLOCK + s], x[5 * BLOCK + s])  # fmt: skip
        parent_acceleration = (x[6 * BLOCK + s], x[7 * BLOCK + s], x[8 * BLOCK + s], x[9 * BLOCK + s],
                               x[10 * BLOCK + s], x[11 * BLOCK + s])  # fmt: skip
        rotation = (r00, r01, p02, r10, r11, p12, r20, r21, p22)
        motion = newton_euler_step(
            rotation, (px, py, pz), parent_velocity, parent_acceleration, vscale * x[13 * BLOCK + s],
            ascale * x[14 * BLOCK + s], prism, body,
        )  # fmt: skip
        # stores written out: a loop over the tuple's index stopped LLVM vectorizing the states (1.7x slower)
        x[15 * BLOCK + s] = r00
        x[16 * BLOCK + s] = r01
        x[17 * BLOCK + s] = p02
        x[18 * BLOCK + s] = r10
        x[19 * BLOCK + s] = r11
        x[20 * BLOCK + s] = p12
        x[21 * BLOCK + s] = r20
        x[22 * BLOCK + s] = r21
        x[23 * BLOCK + s] = p22
        x[24 * BLOCK + s] = px
        x[25 * BLOCK + s] = py
        x[26 * BLOCK + s] = pz
        x[27 * BLOCK + s] = motion[0]
        x[28 * BLOCK + s] = motion[1]
        x[29 * BLOCK + s] = motion[2]
        x[30 * BLOCK + s] = motion[3]
        x[31 * BLOCK + s] = motion[4]
        x[32 * BLOCK + s] = motion[5]
        x[33 * BLOCK + s] = motion[6]
        x[34 * BLOCK + s] = motion[7]
        x[35 * BLOCK + s] = motion[8]
        x[36 * BLOCK + s] = motion[9]
        x[37 * BLOCK + s] = motion[10]
        x[38 * BLOCK + s] = motion[11]
        x[39 * BLOCK + s] = motion[12]
        x[40 * BLOCK + s] = motion[13]
        x[41 * BLOCK + s] = motion[14]
        x[42 * BLOCK + s] = motion[15]
        x[43 * BLOCK + s] = motion[16]
        x[44 * BLOCK + s] = motion[17]


@njit(inline="always", **NUMBA_OPTIONS)
def _force_to_parent_block(x: np.ndarray) -> None:
    """X^T f for a block: rows R (0-8), p (9-11), f (12-17) -> rows 18-23."""
    for s in range(BLOCK):
        r00, r01, r02 = x[0 * BLOCK + s], x[1 * BLOCK + s], x[2 * BLOCK + s]
        r10, r11, r12 = x[3 * BLOCK + s], x[4 * BLOCK + s], x[5 * BLOCK + s]
        r20, r21, r22 = x[6 * BLOCK + s], x[7 * BLOCK + s], x[8 * BLOCK + s]
        px, py, pz = x[9 * BLOCK + s], x[10 * BLOCK + s], x[11 * BLOCK + s]
        nx, ny, nz = x[12 * BLOCK + s], x[13 * BLOCK + s], x[14 * BLOCK + s]
        fx, fy, fz = x[15 * BLOCK + s], x[16 * BLOCK + s], x[17 * BLOCK + s]
        (
            x[18 * BLOCK + s],
            x[19 * BLOCK + s],
            x[20 * BLOCK + s],
            x[21 * BLOCK + s],
            x[22 * BLOCK + s],
            x[23 * BLOCK + s],
        ) = force_to_parent((r00, r01, r02, r10, r11, r12, r20, r21, r22), (px, py, pz), (nx, ny, nz), (fx, fy, fz))


@njit(inline="always", **NUMBA_OPTIONS)
def rnea_block(
    model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, flags: int, first: int, size: int,
    store: np.ndarray, x: np.ndarray, tau: np.ndarray,
) -> None:  # fmt: skip
    """RNEA (rnea.rnea_core) for the states first .. first + size - 1 of the (B, n) arrays, the state index
    innermost; scratch ``store`` (n, 30, BLOCK) and ``x`` (45 BLOCK, zeros before a first block).

    flags as in rnea: WITH_QDD, WITH_GRAVITY, WITH_VELOCITY, WITH_FRICTION.
    """
    n = int(model[N_JOINTS])
    ascale = 1.0 if (flags & WITH_QDD) != 0 else 0.0
    gscale = 1.0 if (flags & WITH_GRAVITY) != 0 else 0.0
    vscale = 1.0 if (flags & WITH_VELOCITY) != 0 else 0.0
    friction = (flags & WITH_FRICTION) != 0
    for i in range(n):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        for s in range(size):
            x[12 * BLOCK + s] = q[first + s, i]
            x[13 * BLOCK + s] = qd[first + s, i]
            x[14 * BLOCK + s] = qdd[first + s, i]
        for row in range(12):
            if parent >= 0:
                for s in range(BLOCK):
                    x[row * BLOCK + s] = store[parent, 12 + row, s]
            else:
                value = -gscale * model[GRAVITY + row - 9] if row >= 9 else 0.0
                for s in range(BLOCK):
                    x[row * BLOCK + s] = value
        _forward_block(model, i, x, vscale, ascale)
        for row in range(30):
            for s in range(BLOCK):
                store[i, row, s] = x[(15 + row) * BLOCK + s]
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        prism = model[b + KIND]
        armature = ascale * model[b + ARMATURE]
        nonlinear = friction and (model[b + STRIBECK_FORCE] != 0.0 or model[b + SIGMOID_AMPLITUDE] != 0.0)
        for s in range(size):
            value = prism * store[i, 29, s] + (1.0 - prism) * store[i, 26, s] + armature * qdd[first + s, i]
            if friction:
                value += model[b + VISCOUS] * qd[first + s, i]
                value += coulomb(model, i, qd[first + s, i])
            tau[first + s, i] = value
        if nonlinear:  # the Stribeck and sigmoid friction, a loop of its own (the one above stays as it is)
            for s in range(size):
                tau[first + s, i] += nonlinear_friction(model, i, qd[first + s, i])
        parent = int(model[b + PARENT])
        if parent >= 0:
            for row in range(12):
                for s in range(BLOCK):
                    x[row * BLOCK + s] = store[i, row, s]
            for row in range(6):
                for s in range(BLOCK):
                    x[(12 + row) * BLOCK + s] = store[i, 24 + row, s]
            _force_to_parent_block(x)
            for row in range(6):
                for s in range(BLOCK):
                    store[parent, 24 + row, s] += x[(18 + row) * BLOCK + s]


@njit(parallel=True, **NUMBA_OPTIONS)
def rnea_blocks(model: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, flags: int, tau: np.ndarray) -> None:
    """RNEA (rnea.rnea_core) over a (B, n) batch, BLOCK states at a time (rnea_block), blocks in parallel.

    flags as in rnea: WITH_QDD, WITH_GRAVITY, WITH_VELOCITY, WITH_FRICTION.
    """
    count, n = q.shape[0], int(model[N_JOINTS])
    blocks = (count + BLOCK - 1) // BLOCK
    for block in prange(blocks):
        first = block * BLOCK
        store = np.empty((n, 30, BLOCK))  # per joint: R, p, v, a, f
        x = np.zeros(45 * BLOCK)
        rnea_block(model, q, qd, qdd, flags, first, min(BLOCK, count - first), store, x, tau)
