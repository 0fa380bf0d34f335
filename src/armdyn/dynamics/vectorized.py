"""Batch kernels vectorized across states: structure of arrays, blocks of states.

A batch of inverse dynamics is the same arithmetic on many states. Laid out with the
state index innermost (one row per quantity, one column per state of a block), the
loop over a block's states is straight-line arithmetic that LLVM turns into SIMD
instructions, and blocks run in parallel threads. Joint kinds become 0/1 factors so
that the vectorized loop has no branches, and sin/cos are computed by a polynomial
that vectorizes (libm's do not).
"""

from __future__ import annotations

import math

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


@njit(inline="always", **_OPTS)
def sin_cos(x: float) -> tuple[float, float]:
    """(sin x, cos x) to about one unit in the last place for |x| < 1e5, without branches."""
    k = math.floor(x * 0.6366197723675814 + 0.5)
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    z = r * r
    s = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    c = 1.0 - 0.5 * z + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    quadrant = int(k) & 3
    swap = (quadrant & 1) == 1
    sine = c if swap else s
    cosine = s if swap else c
    sine = -sine if quadrant >= 2 else sine
    cosine = -cosine if quadrant == 1 or quadrant == 2 else cosine
    return sine, cosine


@njit(inline="always", **_OPTS)
def _forward_block(
    m: np.ndarray, i: int, gin: np.ndarray, out: np.ndarray, vscale: float, ascale: float, gscale: float
) -> None:
    """One joint's forward step of RNEA for a block of states (see kernels.rnea_core).

    gin rows: 0-11 the parent's v and a (or zeros and -g for the root), 12-14 q, qd, qdd.
    out rows: R (9), p (3), v (6), a (6), f (6).
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
        qi = gin[12, s]
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
        wx, wy, wz, vx, vy, vz = gin[0, s], gin[1, s], gin[2, s], gin[3, s], gin[4, s], gin[5, s]
        ax, ay, az, lx, ly, lz = gin[6, s], gin[7, s], gin[8, s], gin[9, s], gin[10, s], gin[11, s]
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
        rate = vscale * gin[13, s]
        acc = ascale * gin[14, s]
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
        out[0, s], out[1, s], out[2, s], out[3, s], out[4, s], out[5, s] = r00, r01, p02, r10, r11, p12
        out[6, s], out[7, s], out[8, s], out[9, s], out[10, s], out[11, s] = r20, r21, p22, px, py, pz
        out[12, s], out[13, s], out[14, s], out[15, s], out[16, s], out[17, s] = Wx, Wy, Wz, Vx, Vy, Vz
        out[18, s], out[19, s], out[20, s], out[21, s], out[22, s], out[23, s] = Ax, Ay, Az, Lx, Ly, Lz
        out[24, s] = i0 * Ax + i1 * Ay + i2 * Az + hy * Lz - hz * Ly + Wy * kz - Wz * ky + Vy * llz - Vz * lly
        out[25, s] = i1 * Ax + i3 * Ay + i4 * Az + hz * Lx - hx * Lz + Wz * kx - Wx * kz + Vz * llx - Vx * llz
        out[26, s] = i2 * Ax + i4 * Ay + i5 * Az + hx * Ly - hy * Lx + Wx * ky - Wy * kx + Vx * lly - Vy * llx
        out[27, s] = mass * Lx - (hy * Az - hz * Ay) + Wy * llz - Wz * lly
        out[28, s] = mass * Ly - (hz * Ax - hx * Az) + Wz * llx - Wx * llz
        out[29, s] = mass * Lz - (hx * Ay - hy * Ax) + Wx * lly - Wy * llx


@njit(inline="always", **_OPTS)
def _force_to_parent_block(src: np.ndarray, out: np.ndarray) -> None:
    """X^T f for a block: src rows R (9), p (3), f (6) at 24-29 -> out rows 0-5."""
    for s in range(BLOCK):
        r00, r01, r02, r10, r11, r12 = src[0, s], src[1, s], src[2, s], src[3, s], src[4, s], src[5, s]
        r20, r21, r22, px, py, pz = src[6, s], src[7, s], src[8, s], src[9, s], src[10, s], src[11, s]
        nx, ny, nz, fx, fy, fz = src[24, s], src[25, s], src[26, s], src[27, s], src[28, s], src[29, s]
        Fx = r00 * fx + r01 * fy + r02 * fz
        Fy = r10 * fx + r11 * fy + r12 * fz
        Fz = r20 * fx + r21 * fy + r22 * fz
        out[0, s] = r00 * nx + r01 * ny + r02 * nz + py * Fz - pz * Fy
        out[1, s] = r10 * nx + r11 * ny + r12 * nz + pz * Fx - px * Fz
        out[2, s] = r20 * nx + r21 * ny + r22 * nz + px * Fy - py * Fx
        out[3, s], out[4, s], out[5, s] = Fx, Fy, Fz


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
        store = np.empty((n, 30, BLOCK))
        gin = np.zeros((15, BLOCK))
        out = np.empty((30, BLOCK))
        for i in range(n):
            parent = int(m[HEADER + STRIDE * i + PARENT])
            for s in range(size):
                gin[12, s] = q[first + s, i]
                gin[13, s] = qd[first + s, i]
                gin[14, s] = qdd[first + s, i]
            for s in range(size, BLOCK):
                gin[12, s] = 0.0
                gin[13, s] = 0.0
                gin[14, s] = 0.0
            if parent >= 0:
                for row in range(12):
                    for s in range(BLOCK):
                        gin[row, s] = store[parent, 12 + row, s]
            else:
                for row in range(12):
                    value = -gscale * m[GRAVITY + row - 9] if row >= 9 else 0.0
                    for s in range(BLOCK):
                        gin[row, s] = value
            _forward_block(m, i, gin, out, vscale, ascale, gscale)
            for row in range(30):
                for s in range(BLOCK):
                    store[i, row, s] = out[row, s]
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
                _force_to_parent_block(store[i], out)
                for row in range(6):
                    for s in range(BLOCK):
                        store[parent, 24 + row, s] += out[row, s]
