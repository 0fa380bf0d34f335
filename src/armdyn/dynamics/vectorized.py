"""Batch kernels vectorized across states: structure of arrays, blocks of states.

A batch of inverse dynamics is the same arithmetic on many states. Laid out with the
state index innermost (one row per quantity, one column per state of a block), the
loop over a block's states is straight-line arithmetic that LLVM turns into SIMD
instructions, and blocks run in parallel threads. Joint kinds become 0/1 factors so
that the vectorized loop has no branches, and sin/cos are computed by a polynomial
that vectorizes (libm's do not).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from armdyn.dynamics.compiled import (
    ARMATURE,
    COULOMB_NEG,
    COULOMB_POS,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    PARENT,
    POSITION,
    ROTATION,
    STRIDE,
    VISCOUS,
)

BLOCK = 32
_OPTS = {"cache": True, "fastmath": {"contract"}, "error_model": "numpy", "boundscheck": False}

# pi/2 split in three parts for an exact range reduction (Cody and Waite), and the
# minimax coefficients of sin and cos on [-pi/4, pi/4] (Moshier, Cephes sin.c).
_PIO2_1, _PIO2_2, _PIO2_3 = 1.57079625129699707031e0, 7.54978941586159635335e-8, 5.39030285815811905290e-15
_S1, _S2, _S3 = -1.66666666666666307295e-1, 8.33333333332211858878e-3, -1.98412698295895385996e-4
_S4, _S5, _S6 = 2.75573136213857245213e-6, -2.50507477628578072866e-8, 1.58962301576546568060e-10
_C1, _C2, _C3 = 4.16666666666665929218e-2, -1.38888888888730564116e-3, 2.48015872888517045348e-5
_C4, _C5, _C6 = -2.75573141792967388112e-7, 2.08757008419747316778e-9, -1.13585365213876817300e-11
_ROUND = 6755399441055744.0  # 1.5 * 2**52: adding and subtracting it rounds to an integer


@njit(inline="always", **_OPTS)
def sin_cos(x: float) -> tuple[float, float]:
    """(sin x, cos x) to about one unit in the last place for |x| < 1e5, with selects, not branches."""
    k = (x * 0.6366197723675814 + _ROUND) - _ROUND  # nearest integer, in arithmetic
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    z = r * r
    s = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    c = 1.0 - 0.5 * z + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    quadrant = np.int64(k) & 3
    swap = (quadrant & 1) == 1
    sine = c if swap else s
    cosine = s if swap else c
    sine = -sine if quadrant >= 2 else sine
    cosine = -cosine if (quadrant == 1) | (quadrant == 2) else cosine
    return sine, cosine


@njit(inline="always", **_OPTS)
def _forward_block(m: np.ndarray, i: int, x: np.ndarray, vscale: float, ascale: float) -> None:
    """One joint's forward step of RNEA for a block of states (see kernels.rnea_core).

    x holds rows of BLOCK values. In: 0-11 the parent's v and a (or zeros and -g for the
    root), 12-14 q, qd, qdd. Out: 15-23 R, 24-26 p, 27-32 v, 33-38 a, 39-44 f. One flat
    buffer with rows at constant offsets lets LLVM see that the rows never overlap, so the
    loop over the block's states vectorizes.
    """
    b = HEADER + STRIDE * i
    r = b + ROTATION
    prism = m[b + KIND]
    rev = 1.0 - prism
    p00, p01, p02, p10, p11, p12 = m[r], m[r + 1], m[r + 2], m[r + 3], m[r + 4], m[r + 5]
    p20, p21, p22 = m[r + 6], m[r + 7], m[r + 8]
    Px, Py, Pz = m[b + POSITION], m[b + POSITION + 1], m[b + POSITION + 2]
    mass = m[b + MASS]
    hx, hy, hz = m[b + FIRST_MOMENT], m[b + FIRST_MOMENT + 1], m[b + FIRST_MOMENT + 2]
    k = b + INERTIA
    i0, i1, i2, i3, i4, i5 = m[k], m[k + 1], m[k + 2], m[k + 3], m[k + 4], m[k + 5]
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
        wx, wy, wz, vx, vy, vz = (
            x[0 * BLOCK + s],
            x[1 * BLOCK + s],
            x[2 * BLOCK + s],
            x[3 * BLOCK + s],
            x[4 * BLOCK + s],
            x[5 * BLOCK + s],
        )
        ax, ay, az, lx, ly, lz = (
            x[6 * BLOCK + s],
            x[7 * BLOCK + s],
            x[8 * BLOCK + s],
            x[9 * BLOCK + s],
            x[10 * BLOCK + s],
            x[11 * BLOCK + s],
        )
        tx = vx + wy * pz - wz * py
        ty = vy + wz * px - wx * pz
        tz = vz + wx * py - wy * px
        ux = lx + ay * pz - az * py
        uy = ly + az * px - ax * pz
        uz = lz + ax * py - ay * px
        Wx = r00 * wx + r10 * wy + r20 * wz
        Wy = r01 * wx + r11 * wy + r21 * wz
        Wz = p02 * wx + p12 * wy + p22 * wz
        Vx = r00 * tx + r10 * ty + r20 * tz
        Vy = r01 * tx + r11 * ty + r21 * tz
        Vz = p02 * tx + p12 * ty + p22 * tz
        Ax = r00 * ax + r10 * ay + r20 * az
        Ay = r01 * ax + r11 * ay + r21 * az
        Az = p02 * ax + p12 * ay + p22 * az
        Lx = r00 * ux + r10 * uy + r20 * uz
        Ly = r01 * ux + r11 * uy + r21 * uz
        Lz = p02 * ux + p12 * uy + p22 * uz
        rate = vscale * x[13 * BLOCK + s]
        acc = ascale * x[14 * BLOCK + s]
        Ax += rev * Wy * rate
        Ay -= rev * Wx * rate
        Az += rev * acc
        Lx += (rev * Vy + prism * Wy) * rate
        Ly -= (rev * Vx + prism * Wx) * rate
        Lz += prism * acc
        Wz += rev * rate
        Vz += prism * rate
        kx = i0 * Wx + i1 * Wy + i2 * Wz + hy * Vz - hz * Vy
        ky = i1 * Wx + i3 * Wy + i4 * Wz + hz * Vx - hx * Vz
        kz = i2 * Wx + i4 * Wy + i5 * Wz + hx * Vy - hy * Vx
        llx = mass * Vx - (hy * Wz - hz * Wy)
        lly = mass * Vy - (hz * Wx - hx * Wz)
        llz = mass * Vz - (hx * Wy - hy * Wx)
        (
            x[15 * BLOCK + s],
            x[16 * BLOCK + s],
            x[17 * BLOCK + s],
            x[18 * BLOCK + s],
            x[19 * BLOCK + s],
            x[20 * BLOCK + s],
        ) = r00, r01, p02, r10, r11, p12
        (
            x[21 * BLOCK + s],
            x[22 * BLOCK + s],
            x[23 * BLOCK + s],
            x[24 * BLOCK + s],
            x[25 * BLOCK + s],
            x[26 * BLOCK + s],
        ) = r20, r21, p22, px, py, pz
        (
            x[27 * BLOCK + s],
            x[28 * BLOCK + s],
            x[29 * BLOCK + s],
            x[30 * BLOCK + s],
            x[31 * BLOCK + s],
            x[32 * BLOCK + s],
        ) = Wx, Wy, Wz, Vx, Vy, Vz
        (
            x[33 * BLOCK + s],
            x[34 * BLOCK + s],
            x[35 * BLOCK + s],
            x[36 * BLOCK + s],
            x[37 * BLOCK + s],
            x[38 * BLOCK + s],
        ) = Ax, Ay, Az, Lx, Ly, Lz
        x[39 * BLOCK + s] = i0 * Ax + i1 * Ay + i2 * Az + hy * Lz - hz * Ly + Wy * kz - Wz * ky + Vy * llz - Vz * lly
        x[40 * BLOCK + s] = i1 * Ax + i3 * Ay + i4 * Az + hz * Lx - hx * Lz + Wz * kx - Wx * kz + Vz * llx - Vx * llz
        x[41 * BLOCK + s] = i2 * Ax + i4 * Ay + i5 * Az + hx * Ly - hy * Lx + Wx * ky - Wy * kx + Vx * lly - Vy * llx
        x[42 * BLOCK + s] = mass * Lx - (hy * Az - hz * Ay) + Wy * llz - Wz * lly
        x[43 * BLOCK + s] = mass * Ly - (hz * Ax - hx * Az) + Wz * llx - Wx * llz
        x[44 * BLOCK + s] = mass * Lz - (hx * Ay - hy * Ax) + Wx * lly - Wy * llx


@njit(inline="always", **_OPTS)
def _force_to_parent_block(x: np.ndarray) -> None:
    """X^T f for a block: rows R (0-8), p (9-11), f (12-17) -> rows 18-23."""
    for s in range(BLOCK):
        r00, r01, r02 = x[0 * BLOCK + s], x[1 * BLOCK + s], x[2 * BLOCK + s]
        r10, r11, r12 = x[3 * BLOCK + s], x[4 * BLOCK + s], x[5 * BLOCK + s]
        r20, r21, r22 = x[6 * BLOCK + s], x[7 * BLOCK + s], x[8 * BLOCK + s]
        px, py, pz = x[9 * BLOCK + s], x[10 * BLOCK + s], x[11 * BLOCK + s]
        nx, ny, nz = x[12 * BLOCK + s], x[13 * BLOCK + s], x[14 * BLOCK + s]
        fx, fy, fz = x[15 * BLOCK + s], x[16 * BLOCK + s], x[17 * BLOCK + s]
        Fx = r00 * fx + r01 * fy + r02 * fz
        Fy = r10 * fx + r11 * fy + r12 * fz
        Fz = r20 * fx + r21 * fy + r22 * fz
        x[18 * BLOCK + s] = r00 * nx + r01 * ny + r02 * nz + py * Fz - pz * Fy
        x[19 * BLOCK + s] = r10 * nx + r11 * ny + r12 * nz + pz * Fx - px * Fz
        x[20 * BLOCK + s] = r20 * nx + r21 * ny + r22 * nz + px * Fy - py * Fx
        x[21 * BLOCK + s] = Fx
        x[22 * BLOCK + s] = Fy
        x[23 * BLOCK + s] = Fz


@njit(parallel=True, **_OPTS)
def rnea_blocks(m: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, flags: int, tau: np.ndarray) -> None:
    """RNEA (kernels.rnea_core) over a (B, n) batch, BLOCK states at a time, blocks in parallel.

    flags as in kernels: 1 qdd, 2 gravity, 4 velocity, 8 friction.
    """
    count, n = q.shape[0], int(m[0])
    ascale = 1.0 if (flags & 1) != 0 else 0.0
    gscale = 1.0 if (flags & 2) != 0 else 0.0
    vscale = 1.0 if (flags & 4) != 0 else 0.0
    friction = (flags & 8) != 0
    blocks = (count + BLOCK - 1) // BLOCK
    for block in prange(blocks):
        first = block * BLOCK
        size = min(BLOCK, count - first)
        store = np.empty((n, 30, BLOCK))  # per joint: R, p, v, a, f
        x = np.zeros(45 * BLOCK)
        for i in range(n):
            parent = int(m[HEADER + STRIDE * i + PARENT])
            for s in range(size):
                x[12 * BLOCK + s] = q[first + s, i]
                x[13 * BLOCK + s] = qd[first + s, i]
                x[14 * BLOCK + s] = qdd[first + s, i]
            for row in range(12):
                if parent >= 0:
                    for s in range(BLOCK):
                        x[row * BLOCK + s] = store[parent, 12 + row, s]
                else:
                    value = -gscale * m[GRAVITY + row - 9] if row >= 9 else 0.0
                    for s in range(BLOCK):
                        x[row * BLOCK + s] = value
            _forward_block(m, i, x, vscale, ascale)
            for row in range(30):
                for s in range(BLOCK):
                    store[i, row, s] = x[(15 + row) * BLOCK + s]
        for i in range(n - 1, -1, -1):
            b = HEADER + STRIDE * i
            prism = m[b + KIND]
            armature = ascale * m[b + ARMATURE]
            for s in range(size):
                value = prism * store[i, 29, s] + (1.0 - prism) * store[i, 26, s] + armature * qdd[first + s, i]
                if friction:
                    rate = qd[first + s, i]
                    value += m[b + VISCOUS] * rate
                    if rate > 0.0:
                        value += m[b + COULOMB_POS]
                    elif rate < 0.0:
                        value += m[b + COULOMB_NEG]
                tau[first + s, i] = value
            parent = int(m[b + PARENT])
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
