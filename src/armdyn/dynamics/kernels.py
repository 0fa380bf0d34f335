"""Numba kernels of the robot equation on kinematic trees.

Featherstone, Rigid Body Dynamics Algorithms (2008): RNEA (5.3), CRBA (6.2), ABA (7.3);
Echeandia and Wensing, "Numerical methods to compute the Coriolis matrix and Christoffel
symbols for rigid-body systems", J. Comput. Nonlinear Dyn. 16 (2021), Algorithm 2, for
the Christoffel-consistent Coriolis matrix.

Conventions. Every joint moves about/along the z axis of its body frame (compiled.py),
so S = e_3 (revolute) or e_6 (prismatic) in body coordinates. Spatial vectors are
[angular; linear]. A body's mass properties are (m, h = m c, I_O about the body origin).
Joint i's transform: R_i (body axes in parent coordinates) and p_i (body origin in the
parent). Motion vectors go parent -> child as w' = R^T w, v' = R^T (v + w x p); forces go
child -> parent as f = R f', n = R n' + p x (R f').

Each kernel reads the model buffer ``m`` and works in ``w`` from offset ``w0``; none
allocates in its loops. A one-state entry returns a status: 0, or which argument was
wrong (1, 2, 3 for the shape of q, qd, qdd/tau; 11, 12, 13 for a NaN or infinity there).
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
    TOOL_LINK,
    TOOL_POSITION,
    TOOL_ROTATION,
    VISCOUS,
)
from armdyn.dynamics.vectorized import sin_cos

WITH_QDD, WITH_GRAVITY, WITH_VELOCITY, WITH_FRICTION, WITH_WRENCH = 1, 2, 4, 8, 16
INVERSE_DYNAMICS = WITH_QDD | WITH_GRAVITY | WITH_VELOCITY | WITH_FRICTION
NONLINEAR = WITH_GRAVITY | WITH_VELOCITY | WITH_FRICTION
CORIOLIS = WITH_VELOCITY
GRAVITY_ONLY = WITH_GRAVITY

_OPTS = {"cache": True, "fastmath": {"contract"}, "error_model": "numpy", "boundscheck": False}


# ----- small pieces ------------------------------------------------------------------------
@njit(inline="always", **_OPTS)
def _check(x: np.ndarray, n: int, code: int) -> int:
    """0, or code when x has the wrong length, or code + 10 when it holds NaN or infinity."""
    if x.shape[0] != n:
        return code
    for k in range(n):
        if x[k] - x[k] != 0.0:  # NaN and infinity fail x - x == 0
            return code + 10
    return 0


@njit(inline="always", **_OPTS)
def _check_all(n: int, a: np.ndarray, b: np.ndarray, c: np.ndarray, count: int, out: np.ndarray) -> int:
    """The status of the first ``count`` state arguments (a, b, c) and of the output's length."""
    status = _check(a, n, 1)
    if status == 0 and count > 1:
        status = _check(b, n, 2)
    if status == 0 and count > 2:
        status = _check(c, n, 3)
    if status == 0 and out.shape[0] != n:
        status = 4
    return status


@njit(inline="always", **_OPTS)
def _joint_transform(m: np.ndarray, j: int, qj: float, w: np.ndarray, o: int) -> None:
    """R_j = P_R Rz(q) (revolute) or P_R (prismatic), p_j = P_p (+ q P_R e_z): w[o:o+9], w[o+9:o+12]."""
    b = HEADER + STRIDE * j
    r = b + ROTATION
    if m[b + KIND] == 0.0:
        s, c = sin_cos(qj)
        for row in range(3):
            x, y = m[r + 3 * row], m[r + 3 * row + 1]
            w[o + 3 * row] = x * c + y * s
            w[o + 3 * row + 1] = y * c - x * s
            w[o + 3 * row + 2] = m[r + 3 * row + 2]
        for k in range(3):
            w[o + 9 + k] = m[b + POSITION + k]
    else:
        for k in range(9):
            w[o + k] = m[r + k]
        for k in range(3):
            w[o + 9 + k] = m[b + POSITION + k] + qj * m[r + 3 * k + 2]


@njit(inline="always", **_OPTS)
def _friction(m: np.ndarray, j: int, qdj: float) -> float:
    """F_j(qd_j) = Fv qd + Fc+ (qd > 0) or Fc- (qd < 0) (3.3.2)."""
    b = HEADER + STRIDE * j
    f = m[b + VISCOUS] * qdj
    if qdj > 0.0:
        f += m[b + COULOMB_POS]
    elif qdj < 0.0:
        f += m[b + COULOMB_NEG]
    return f


@njit(inline="always", **_OPTS)
def _motion_to_child(w: np.ndarray, t: int, src: np.ndarray, s: int, dst: np.ndarray, d: int) -> None:
    """dst = X src for a motion vector: [R^T a; R^T (l + a x p)], transform at w[t:t+12]."""
    ax, ay, az = src[s], src[s + 1], src[s + 2]
    px, py, pz = w[t + 9], w[t + 10], w[t + 11]
    lx = src[s + 3] + ay * pz - az * py
    ly = src[s + 4] + az * px - ax * pz
    lz = src[s + 5] + ax * py - ay * px
    for k in range(3):
        dst[d + k] = w[t + k] * ax + w[t + 3 + k] * ay + w[t + 6 + k] * az
        dst[d + 3 + k] = w[t + k] * lx + w[t + 3 + k] * ly + w[t + 6 + k] * lz


@njit(inline="always", **_OPTS)
def _add_force_to_parent(w: np.ndarray, t: int, src: np.ndarray, s: int, dst: np.ndarray, d: int) -> None:
    """dst += X^T src for a force: [R n + p x (R f); R f], transform at w[t:t+12]."""
    fx = w[t] * src[s + 3] + w[t + 1] * src[s + 4] + w[t + 2] * src[s + 5]
    fy = w[t + 3] * src[s + 3] + w[t + 4] * src[s + 4] + w[t + 5] * src[s + 5]
    fz = w[t + 6] * src[s + 3] + w[t + 7] * src[s + 4] + w[t + 8] * src[s + 5]
    px, py, pz = w[t + 9], w[t + 10], w[t + 11]
    for k in range(3):
        dst[d + k] += w[t + 3 * k] * src[s] + w[t + 3 * k + 1] * src[s + 1] + w[t + 3 * k + 2] * src[s + 2]
    dst[d] += py * fz - pz * fy
    dst[d + 1] += pz * fx - px * fz
    dst[d + 2] += px * fy - py * fx
    dst[d + 3] += fx
    dst[d + 4] += fy
    dst[d + 5] += fz


@njit(inline="always", **_OPTS)
def _inertia_times(m: np.ndarray, j: int, v: np.ndarray, s: int, out: np.ndarray, o: int) -> None:
    """out = I_j v = [I_O a + h x l; m l - h x a] for v = [a; l]."""
    b = HEADER + STRIDE * j
    mass = m[b + MASS]
    hx, hy, hz = m[b + FIRST_MOMENT], m[b + FIRST_MOMENT + 1], m[b + FIRST_MOMENT + 2]
    i = b + INERTIA
    ax, ay, az, lx, ly, lz = v[s], v[s + 1], v[s + 2], v[s + 3], v[s + 4], v[s + 5]
    out[o] = m[i] * ax + m[i + 1] * ay + m[i + 2] * az + hy * lz - hz * ly
    out[o + 1] = m[i + 1] * ax + m[i + 3] * ay + m[i + 4] * az + hz * lx - hx * lz
    out[o + 2] = m[i + 2] * ax + m[i + 4] * ay + m[i + 5] * az + hx * ly - hy * lx
    out[o + 3] = mass * lx - (hy * az - hz * ay)
    out[o + 4] = mass * ly - (hz * ax - hx * az)
    out[o + 5] = mass * lz - (hx * ay - hy * ax)


# ----- RNEA: inverse dynamics and its parts -------------------------------------------------------
@njit(inline="always", **_OPTS)
def rnea_core(
    m: np.ndarray,
    w: np.ndarray,
    w0: int,
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
    Work space per joint at w[w0 + 30 i:]: R (9), p (3), v (6), a (6), f (6).
    """
    n = int(m[0])
    gscale = 1.0 if (flags & WITH_GRAVITY) != 0 else 0.0
    vscale = 1.0 if (flags & WITH_VELOCITY) != 0 else 0.0
    ascale = 1.0 if (flags & WITH_QDD) != 0 else 0.0
    gx, gy, gz = -gscale * m[GRAVITY], -gscale * m[GRAVITY + 1], -gscale * m[GRAVITY + 2]
    for i in range(n):
        b = HEADER + STRIDE * i
        r = b + ROTATION
        parent = int(m[b])
        p00, p01, p02 = m[r], m[r + 1], m[r + 2]
        p10, p11, p12 = m[r + 3], m[r + 4], m[r + 5]
        p20, p21, p22 = m[r + 6], m[r + 7], m[r + 8]
        px, py, pz = m[b + POSITION], m[b + POSITION + 1], m[b + POSITION + 2]
        qi = q[i]
        if m[b + KIND] == 0.0:
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
        o = w0 + 30 * i
        w[o], w[o + 1], w[o + 2], w[o + 3], w[o + 4], w[o + 5] = r00, r01, r02, r10, r11, r12
        w[o + 6], w[o + 7], w[o + 8], w[o + 9], w[o + 10], w[o + 11] = r20, r21, r22, px, py, pz
        if parent >= 0:
            op = w0 + 30 * parent + 12
            wx, wy, wz, vx, vy, vz = w[op], w[op + 1], w[op + 2], w[op + 3], w[op + 4], w[op + 5]
            ax, ay, az, lx, ly, lz = w[op + 6], w[op + 7], w[op + 8], w[op + 9], w[op + 10], w[op + 11]
        else:
            wx = wy = wz = vx = vy = vz = ax = ay = az = 0.0
            lx, ly, lz = gx, gy, gz
        # l + a x p, v + w x p
        tx = vx + wy * pz - wz * py
        ty = vy + wz * px - wx * pz
        tz = vz + wx * py - wy * px
        ux = lx + ay * pz - az * py
        uy = ly + az * px - ax * pz
        uz = lz + ax * py - ay * px
        Wx = r00 * wx + r10 * wy + r20 * wz
        Wy = r01 * wx + r11 * wy + r21 * wz
        Wz = r02 * wx + r12 * wy + r22 * wz
        Vx = r00 * tx + r10 * ty + r20 * tz
        Vy = r01 * tx + r11 * ty + r21 * tz
        Vz = r02 * tx + r12 * ty + r22 * tz
        Ax = r00 * ax + r10 * ay + r20 * az
        Ay = r01 * ax + r11 * ay + r21 * az
        Az = r02 * ax + r12 * ay + r22 * az
        Lx = r00 * ux + r10 * uy + r20 * uz
        Ly = r01 * ux + r11 * uy + r21 * uz
        Lz = r02 * ux + r12 * uy + r22 * uz
        rate = vscale * qd[i]
        acc = ascale * qdd[i]
        rev = 1.0 - prism
        # (X v_p) x S qd: revolute [W x e3; V x e3] qd, prismatic [0; W x e3] qd
        Ax += rev * Wy * rate
        Ay -= rev * Wx * rate
        Az += rev * acc
        Lx += (rev * Vy + prism * Wy) * rate
        Ly -= (rev * Vx + prism * Wx) * rate
        Lz += prism * acc
        Wz += rev * rate
        Vz += prism * rate
        w[o + 12], w[o + 13], w[o + 14], w[o + 15], w[o + 16], w[o + 17] = Wx, Wy, Wz, Vx, Vy, Vz
        w[o + 18], w[o + 19], w[o + 20], w[o + 21], w[o + 22], w[o + 23] = Ax, Ay, Az, Lx, Ly, Lz
        mass = m[b + MASS]
        hx, hy, hz = m[b + FIRST_MOMENT], m[b + FIRST_MOMENT + 1], m[b + FIRST_MOMENT + 2]
        k = b + INERTIA
        i0, i1, i2, i3, i4, i5 = m[k], m[k + 1], m[k + 2], m[k + 3], m[k + 4], m[k + 5]
        # momentum of v: kk = Io W + h x V ; ll = m V - h x W
        kx = i0 * Wx + i1 * Wy + i2 * Wz + hy * Vz - hz * Vy
        ky = i1 * Wx + i3 * Wy + i4 * Wz + hz * Vx - hx * Vz
        kz = i2 * Wx + i4 * Wy + i5 * Wz + hx * Vy - hy * Vx
        llx = mass * Vx - (hy * Wz - hz * Wy)
        lly = mass * Vy - (hz * Wx - hx * Wz)
        llz = mass * Vz - (hx * Wy - hy * Wx)
        # f = I a + v x* momentum
        w[o + 24] = i0 * Ax + i1 * Ay + i2 * Az + hy * Lz - hz * Ly + Wy * kz - Wz * ky + Vy * llz - Vz * lly
        w[o + 25] = i1 * Ax + i3 * Ay + i4 * Az + hz * Lx - hx * Lz + Wz * kx - Wx * kz + Vz * llx - Vx * llz
        w[o + 26] = i2 * Ax + i4 * Ay + i5 * Az + hx * Ly - hy * Lx + Wx * ky - Wy * kx + Vx * lly - Vy * llx
        w[o + 27] = mass * Lx - (hy * Az - hz * Ay) + Wy * llz - Wz * lly
        w[o + 28] = mass * Ly - (hz * Ax - hx * Az) + Wz * llx - Wx * llz
        w[o + 29] = mass * Lz - (hx * Ay - hy * Ax) + Wx * lly - Wy * llx
    if (flags & WITH_WRENCH) != 0:
        _add_tool_wrench(m, w, w0 + 30 * int(m[TOOL_LINK]) + 24, wrench, w0 + 30 * n)
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        o = w0 + 30 * i
        nx, ny, nz, fx, fy, fz = w[o + 24], w[o + 25], w[o + 26], w[o + 27], w[o + 28], w[o + 29]
        prism = m[b + KIND]
        value = prism * fz + (1.0 - prism) * nz + ascale * m[b + ARMATURE] * qdd[i]
        if (flags & WITH_FRICTION) != 0:
            d = qd[i]
            value += m[b + VISCOUS] * d
            if d > 0.0:
                value += m[b + COULOMB_POS]
            elif d < 0.0:
                value += m[b + COULOMB_NEG]
        tau[i] = value
        parent = int(m[b])
        if parent >= 0:
            r00, r01, r02, r10, r11, r12 = w[o], w[o + 1], w[o + 2], w[o + 3], w[o + 4], w[o + 5]
            r20, r21, r22, px, py, pz = w[o + 6], w[o + 7], w[o + 8], w[o + 9], w[o + 10], w[o + 11]
            Fx = r00 * fx + r01 * fy + r02 * fz
            Fy = r10 * fx + r11 * fy + r12 * fz
            Fz = r20 * fx + r21 * fy + r22 * fz
            op = w0 + 30 * parent + 24
            w[op] += r00 * nx + r01 * ny + r02 * nz + py * Fz - pz * Fy
            w[op + 1] += r10 * nx + r11 * ny + r12 * nz + pz * Fx - px * Fz
            w[op + 2] += r20 * nx + r21 * ny + r22 * nz + px * Fy - py * Fx
            w[op + 3] += Fx
            w[op + 4] += Fy
            w[op + 5] += Fz


@njit(inline="always", **_OPTS)
def _add_tool_wrench(m: np.ndarray, w: np.ndarray, f: int, wrench: np.ndarray, tmp: int) -> None:
    """The body of the tool link must also supply the wrench [force; moment] that the tool
    exerts on its surroundings, given in the tool frame about the tool point."""
    for k in range(9):
        w[tmp + k] = m[TOOL_ROTATION + k]
    for k in range(3):
        w[tmp + 9 + k] = m[TOOL_POSITION + k]
        w[tmp + 12 + k] = wrench[3 + k]  # moment
        w[tmp + 15 + k] = wrench[k]  # force
    _add_force_to_parent(w, tmp, w, tmp + 12, w, f)


_ONE_3 = "int64(float64[::1], float64[::1], float64[::1], float64[::1], float64[::1])"
_ONE_2 = "int64(float64[::1], float64[::1], float64[::1], float64[::1])"
_ONE_1 = "int64(float64[::1], float64[::1], float64[::1])"


@njit(_ONE_3, **_OPTS)
def rnea_one(m: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, tau: np.ndarray) -> int:
    """One state, checked: tau = M qdd + Vm qd + F + G; the buffer's scratch is the work space."""
    n = int(m[0])
    status = _check_all(n, q, qd, qdd, 3, tau)
    if status == 0:
        rnea_core(m, m, HEADER + STRIDE * n, q, qd, qdd, qd, INVERSE_DYNAMICS, tau)
    return status


@njit(_ONE_2, **_OPTS)
def nonlinear_one(m: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """N = Vm qd + F + G."""
    n = int(m[0])
    status = _check_all(n, q, qd, qd, 2, out)
    if status == 0:
        rnea_core(m, m, HEADER + STRIDE * n, q, qd, qd, qd, NONLINEAR, out)
    return status


@njit(_ONE_2, **_OPTS)
def coriolis_vector_one(m: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """V = Vm qd."""
    n = int(m[0])
    status = _check_all(n, q, qd, qd, 2, out)
    if status == 0:
        rnea_core(m, m, HEADER + STRIDE * n, q, qd, qd, qd, CORIOLIS, out)
    return status


@njit(inline="always", **_OPTS)
def gravity_core(m: np.ndarray, w: np.ndarray, w0: int, q: np.ndarray, G: np.ndarray) -> None:
    """G(q): RNEA with no motion. Each body's acceleration is then -g in its own axes, a_i = [0; R_i^T l_p],
    its force f_i = [h x l_i; m l_i]; tau_i = S^T f_i and f_p += X_i^T f_i (Featherstone 5.3)."""
    n = int(m[0])
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(m[b + PARENT])
        o = w0 + 21 * i
        _joint_transform(m, i, q[i], w, o)
        if parent >= 0:
            op = w0 + 21 * parent + 12
            lx, ly, lz = w[op], w[op + 1], w[op + 2]
        else:
            lx, ly, lz = -m[GRAVITY], -m[GRAVITY + 1], -m[GRAVITY + 2]
        Lx = w[o] * lx + w[o + 3] * ly + w[o + 6] * lz
        Ly = w[o + 1] * lx + w[o + 4] * ly + w[o + 7] * lz
        Lz = w[o + 2] * lx + w[o + 5] * ly + w[o + 8] * lz
        mass, hx, hy, hz = m[b + MASS], m[b + FIRST_MOMENT], m[b + FIRST_MOMENT + 1], m[b + FIRST_MOMENT + 2]
        w[o + 12], w[o + 13], w[o + 14] = Lx, Ly, Lz
        w[o + 15], w[o + 16], w[o + 17] = hy * Lz - hz * Ly, hz * Lx - hx * Lz, hx * Ly - hy * Lx
        w[o + 18], w[o + 19], w[o + 20] = mass * Lx, mass * Ly, mass * Lz
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        o = w0 + 21 * i
        G[i] = w[o + 20] if m[b + KIND] != 0.0 else w[o + 17]
        parent = int(m[b + PARENT])
        if parent >= 0:
            _add_force_to_parent(w, o, w, o + 15, w, w0 + 21 * parent + 15)


@njit(_ONE_1, **_OPTS)
def gravity_one(m: np.ndarray, q: np.ndarray, out: np.ndarray) -> int:
    """G(q)."""
    n = int(m[0])
    status = _check_all(n, q, q, q, 1, out)
    if status == 0:
        gravity_core(m, m, HEADER + STRIDE * n, q, out)
    return status


@njit(inline="always", **_OPTS)
def friction_core(m: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    for i in range(int(m[0])):
        out[i] = _friction(m, i, qd[i])


@njit(_ONE_1, **_OPTS)
def friction_one(m: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    """F(qd) = Fv qd + Fd(qd)."""
    n = int(m[0])
    status = _check_all(n, qd, qd, qd, 1, out)
    if status == 0:
        friction_core(m, qd, out)
    return status


@njit(parallel=True, **_OPTS)
def friction_batch(m: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    for s in prange(qd.shape[0]):
        friction_core(m, qd[s], out[s])


@njit(parallel=True, **_OPTS)
def rnea_batch(
    m: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, wrench: np.ndarray, flags: int, tau: np.ndarray
) -> None:
    """Many states (B, n) at once, in parallel chunks, each chunk with its own work space."""
    n, count = int(m[0]), q.shape[0]
    chunks = min(count, 64)
    for c in prange(chunks):
        w = np.empty(40 * n + 32)
        for s in range(c * count // chunks, (c + 1) * count // chunks):
            e = s if wrench.shape[0] == count else 0
            rnea_core(m, w, 0, q[s], qd[s], qdd[s], wrench[e], flags, tau[s])


# ----- CRBA: the inertia matrix ------------------------------------------------------------------
@njit(inline="always", **_OPTS)
def _add_inertia_to_parent(w: np.ndarray, t: int, src: int, dst: int) -> None:
    """Composite inertia: (m, h, I_O) of a child, moved into its parent's frame and added there.

    h' = R h + m p;  I_O' = R I_O R^T - [Rh]x [p]x - [p]x [Rh]x - m [p]x [p]x.
    """
    mass = w[src]
    rh0 = w[t] * w[src + 1] + w[t + 1] * w[src + 2] + w[t + 2] * w[src + 3]
    rh1 = w[t + 3] * w[src + 1] + w[t + 4] * w[src + 2] + w[t + 5] * w[src + 3]
    rh2 = w[t + 6] * w[src + 1] + w[t + 7] * w[src + 2] + w[t + 8] * w[src + 3]
    px, py, pz = w[t + 9], w[t + 10], w[t + 11]
    # R I R^T: I stored as Ixx Ixy Ixz Iyy Iyz Izz at src + 4
    i0, i1, i2, i3, i4, i5 = w[src + 4], w[src + 5], w[src + 6], w[src + 7], w[src + 8], w[src + 9]
    # A = R I (3x3), then (A R^T) upper triangle
    r00, r01, r02 = w[t], w[t + 1], w[t + 2]
    r10, r11, r12 = w[t + 3], w[t + 4], w[t + 5]
    r20, r21, r22 = w[t + 6], w[t + 7], w[t + 8]
    a00 = r00 * i0 + r01 * i1 + r02 * i2
    a01 = r00 * i1 + r01 * i3 + r02 * i4
    a02 = r00 * i2 + r01 * i4 + r02 * i5
    a10 = r10 * i0 + r11 * i1 + r12 * i2
    a11 = r10 * i1 + r11 * i3 + r12 * i4
    a12 = r10 * i2 + r11 * i4 + r12 * i5
    a20 = r20 * i0 + r21 * i1 + r22 * i2
    a21 = r20 * i1 + r21 * i3 + r22 * i4
    a22 = r20 * i2 + r21 * i4 + r22 * i5
    j00 = a00 * r00 + a01 * r01 + a02 * r02
    j01 = a00 * r10 + a01 * r11 + a02 * r12
    j02 = a00 * r20 + a01 * r21 + a02 * r22
    j11 = a10 * r10 + a11 * r11 + a12 * r12
    j12 = a10 * r20 + a11 * r21 + a12 * r22
    j22 = a20 * r20 + a21 * r21 + a22 * r22
    # - (hx px + px hx) - m px px, with [a]x[b]x = b a^T - (a.b) I
    hp = rh0 * px + rh1 * py + rh2 * pz
    pp = px * px + py * py + pz * pz
    w[dst] += mass
    w[dst + 1] += rh0 + mass * px
    w[dst + 2] += rh1 + mass * py
    w[dst + 3] += rh2 + mass * pz
    w[dst + 4] += j00 - (2.0 * px * rh0 - 2.0 * hp) - mass * (px * px - pp)
    w[dst + 5] += j01 - (px * rh1 + py * rh0) - mass * (px * py)
    w[dst + 6] += j02 - (px * rh2 + pz * rh0) - mass * (px * pz)
    w[dst + 7] += j11 - (2.0 * py * rh1 - 2.0 * hp) - mass * (py * py - pp)
    w[dst + 8] += j12 - (py * rh2 + pz * rh1) - mass * (py * pz)
    w[dst + 9] += j22 - (2.0 * pz * rh2 - 2.0 * hp) - mass * (pz * pz - pp)


@njit(inline="always", **_OPTS)
def crba_core(m: np.ndarray, w: np.ndarray, w0: int, q: np.ndarray, M: np.ndarray) -> None:
    """M(q) by the composite-rigid-body algorithm (Featherstone 6.2), plus the armature diagonal.

    Composite inertias I^c_i = I_i + sum of children's; F = I^c_i S_i, M_ii = S_i^T F,
    then F is carried to each ancestor j: M_ij = M_ji = S_j^T F.
    """
    n = int(m[0])
    for i in range(n):
        _joint_transform(m, i, q[i], w, w0 + 12 * i)
    crba_from_transforms(m, w, w0, 12, w0 + 12 * n, M)


@njit(inline="always", **_OPTS)
def mass_matrix_and_bias(m: np.ndarray, w: np.ndarray, w0: int, q: np.ndarray, qd: np.ndarray, M: np.ndarray,
                         N: np.ndarray) -> None:  # fmt: skip
    """M(q) and N(q, qd) together: RNEA's joint transforms serve CRBA too (forward dynamics in a loop)."""
    n = int(m[0])
    rnea_core(m, w, w0, q, qd, qd, qd, NONLINEAR, N)
    crba_from_transforms(m, w, w0, 30, w0 + 30 * n + 32, M)


@njit(inline="always", **_OPTS)
def crba_from_transforms(m: np.ndarray, w: np.ndarray, transforms: int, stride: int, composite: int,
                         M: np.ndarray) -> None:  # fmt: skip
    """CRBA given each joint's (R, p) at w[transforms + stride i:], composite inertias at w[composite:]."""
    n = int(m[0])
    for i in range(n):
        b = HEADER + STRIDE * i
        c = composite + 10 * i
        w[c] = m[b + MASS]
        for k in range(3):
            w[c + 1 + k] = m[b + FIRST_MOMENT + k]
        for k in range(6):
            w[c + 4 + k] = m[b + INERTIA + k]
        for j in range(n):
            M[i, j] = 0.0
    for i in range(n - 1, -1, -1):
        parent = int(m[HEADER + STRIDE * i + PARENT])
        if parent >= 0:
            _add_inertia_to_parent(w, transforms + stride * i, composite + 10 * i, composite + 10 * parent)
    for i in range(n):
        b = HEADER + STRIDE * i
        c = composite + 10 * i
        mass, hx, hy = w[c], w[c + 1], w[c + 2]
        if m[b + KIND] != 0.0:  # F = I^c e6 = [h x e3; m e3]
            nx, ny, nz, fx, fy, fz = hy, -hx, 0.0, 0.0, 0.0, mass
            M[i, i] = mass + m[b + ARMATURE]
        else:  # F = I^c e3 = [I_O e3; -h x e3]
            nx, ny, nz, fx, fy, fz = w[c + 6], w[c + 8], w[c + 9], -hy, hx, 0.0
            M[i, i] = w[c + 9] + m[b + ARMATURE]
        j = i
        parent = int(m[b + PARENT])
        while parent >= 0:  # F <- X_j^T F, carried to the parent: [R n + p x (R f); R f]
            t = transforms + stride * j
            r00, r01, r02, r10, r11, r12 = w[t], w[t + 1], w[t + 2], w[t + 3], w[t + 4], w[t + 5]
            r20, r21, r22, px, py, pz = w[t + 6], w[t + 7], w[t + 8], w[t + 9], w[t + 10], w[t + 11]
            Fx = r00 * fx + r01 * fy + r02 * fz
            Fy = r10 * fx + r11 * fy + r12 * fz
            Fz = r20 * fx + r21 * fy + r22 * fz
            Nx = r00 * nx + r01 * ny + r02 * nz + py * Fz - pz * Fy
            Ny = r10 * nx + r11 * ny + r12 * nz + pz * Fx - px * Fz
            Nz = r20 * nx + r21 * ny + r22 * nz + px * Fy - py * Fx
            nx, ny, nz, fx, fy, fz = Nx, Ny, Nz, Fx, Fy, Fz
            j = parent
            bj = HEADER + STRIDE * j
            value = fz if m[bj + KIND] != 0.0 else nz
            M[i, j] = value
            M[j, i] = value
            parent = int(m[bj + PARENT])


@njit("int64(float64[::1], float64[::1], float64[:, ::1])", **_OPTS)
def crba_one(m: np.ndarray, q: np.ndarray, M: np.ndarray) -> int:
    n = int(m[0])
    status = _check(q, n, 1)
    if status != 0 or M.shape[0] != n or M.shape[1] != n:
        return status if status != 0 else 4
    crba_core(m, m, HEADER + STRIDE * n, q, M)
    return 0


@njit(parallel=True, **_OPTS)
def crba_batch(m: np.ndarray, q: np.ndarray, M: np.ndarray) -> None:
    n, count = int(m[0]), q.shape[0]
    chunks = min(count, 64)
    for c in prange(chunks):
        w = np.empty(40 * n + 32)
        for s in range(c * count // chunks, (c + 1) * count // chunks):
            crba_core(m, w, 0, q[s], M[s])


# ----- world-frame kinematics (Coriolis matrix, energies) -------------------------------------------
@njit(inline="always", **_OPTS)
def _world_pose(m: np.ndarray, w: np.ndarray, local: int, parent_pose: int, pose: int, has_parent: bool) -> None:
    """Pose of a body in the world: R_w = R_wp R, p_w = p_wp + R_wp p (12 values at w[pose:])."""
    if not has_parent:
        for k in range(12):
            w[pose + k] = w[local + k]
        return
    for r in range(3):
        for c in range(3):
            w[pose + 3 * r + c] = (
                w[parent_pose + 3 * r] * w[local + c]
                + w[parent_pose + 3 * r + 1] * w[local + 3 + c]
                + w[parent_pose + 3 * r + 2] * w[local + 6 + c]
            )
        w[pose + 9 + r] = (
            w[parent_pose + 9 + r]
            + w[parent_pose + 3 * r] * w[local + 9]
            + w[parent_pose + 3 * r + 1] * w[local + 10]
            + w[parent_pose + 3 * r + 2] * w[local + 11]
        )


@njit(inline="always", **_OPTS)
def _motion_cross(w: np.ndarray, v: int, s: int, out: int) -> None:
    """out = v x s for motion vectors [w; u] x [a; l] = [w x a; w x l + u x a]."""
    wx, wy, wz, ux, uy, uz = w[v], w[v + 1], w[v + 2], w[v + 3], w[v + 4], w[v + 5]
    ax, ay, az, lx, ly, lz = w[s], w[s + 1], w[s + 2], w[s + 3], w[s + 4], w[s + 5]
    w[out] = wy * az - wz * ay
    w[out + 1] = wz * ax - wx * az
    w[out + 2] = wx * ay - wy * ax
    w[out + 3] = wy * lz - wz * ly + uy * az - uz * ay
    w[out + 4] = wz * lx - wx * lz + uz * ax - ux * az
    w[out + 5] = wx * ly - wy * lx + ux * ay - uy * ax


@njit(inline="always", **_OPTS)
def _body_coriolis(w: np.ndarray, v: int, inertia: int, out: int) -> None:
    """The body Coriolis matrix B = 1/2 [(v x*) I + (I v) xbar* - I (v x)] (Echeandia and Wensing
    2021), with B v = v x* I v and B + B^T = dI/dt, which makes Mdot - 2 Vm skew.

    For I = (m, h, I_O) and v = [w; u] it reduces to B = [[B11, 0], [-[l]x, 0]] with
    l = m u + w x h, k = I_O w + h x u and
    B11 = 1/2 ([w]x I_O - I_O [w]x - h u^T - u h^T + 2 (u.h) 1 - [k]x).
    Stored as B11 (9, row major) then l (3).
    """
    wx, wy, wz, ux, uy, uz = w[v], w[v + 1], w[v + 2], w[v + 3], w[v + 4], w[v + 5]
    mass, hx, hy, hz = w[inertia], w[inertia + 1], w[inertia + 2], w[inertia + 3]
    i0, i1, i2 = w[inertia + 4], w[inertia + 5], w[inertia + 6]
    i3, i4, i5 = w[inertia + 7], w[inertia + 8], w[inertia + 9]
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
    w[out] = w00 - hx * ux + uh
    w[out + 1] = 0.5 * (w01 + w10 - hx * uy - ux * hy + kz)
    w[out + 2] = 0.5 * (w02 + w20 - hx * uz - ux * hz - ky)
    w[out + 3] = 0.5 * (w10 + w01 - hy * ux - uy * hx - kz)
    w[out + 4] = w11 - hy * uy + uh
    w[out + 5] = 0.5 * (w12 + w21 - hy * uz - uy * hz + kx)
    w[out + 6] = 0.5 * (w20 + w02 - hz * ux - uz * hx + ky)
    w[out + 7] = 0.5 * (w21 + w12 - hz * uy - uz * hy - kx)
    w[out + 8] = w22 - hz * uz + uh
    w[out + 9] = mass * ux + wy * hz - wz * hy
    w[out + 10] = mass * uy + wz * hx - wx * hz
    w[out + 11] = mass * uz + wx * hy - wy * hx


@njit(inline="always", **_OPTS)
def _world_motion_subspace(m: np.ndarray, j: int, w: np.ndarray, pose: int, out: int) -> None:
    """S_j in world coordinates: [z; p x z] (revolute) or [0; z] (prismatic)."""
    zx, zy, zz = w[pose + 2], w[pose + 5], w[pose + 8]
    if m[HEADER + STRIDE * j + KIND] != 0.0:
        w[out], w[out + 1], w[out + 2], w[out + 3], w[out + 4], w[out + 5] = 0.0, 0.0, 0.0, zx, zy, zz
    else:
        px, py, pz = w[pose + 9], w[pose + 10], w[pose + 11]
        w[out], w[out + 1], w[out + 2] = zx, zy, zz
        w[out + 3] = py * zz - pz * zy
        w[out + 4] = pz * zx - px * zz
        w[out + 5] = px * zy - py * zx


@njit(inline="always", **_OPTS)
def _dot6(w: np.ndarray, a: int, b: int) -> float:
    return (
        w[a] * w[b]
        + w[a + 1] * w[b + 1]
        + w[a + 2] * w[b + 2]
        + w[a + 3] * w[b + 3]
        + w[a + 4] * w[b + 4]
        + (w[a + 5] * w[b + 5])
    )


@njit(inline="always", **_OPTS)
def coriolis_core(m: np.ndarray, w: np.ndarray, w0: int, q: np.ndarray, qd: np.ndarray, C: np.ndarray) -> None:
    """The Christoffel-consistent Vm(q, qd) in O(n d), d the depth (Echeandia and Wensing 2021, Alg. 2).

    World frame: v_i = v_p + S_i qd_i, Sdot_i = v_i x S_i; composite I^c and B^c summed up the tree;
    for j and each ancestor i: C_ij = S_i^T (I^c_j Sdot_j + B^c_j S_j),
    C_ji = Sdot_i^T I^c_j S_j + S_i^T B^c_j^T S_j.
    Work per joint: local transform 12, world pose 12, S 6, Sdot 6, v 6, I^c 10, B^c 12.
    """
    n = int(m[0])
    local, pose, S, Sdot, vel = w0, w0 + 12 * n, w0 + 24 * n, w0 + 30 * n, w0 + 36 * n
    IC, BC, tmp = w0 + 42 * n, w0 + 52 * n, w0 + 64 * n
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(m[b + PARENT])
        _joint_transform(m, i, q[i], w, local + 12 * i)
        _world_pose(m, w, local + 12 * i, pose + 12 * parent, pose + 12 * i, parent >= 0)
        _world_motion_subspace(m, i, w, pose + 12 * i, S + 6 * i)
        for k in range(6):
            w[vel + 6 * i + k] = (w[vel + 6 * parent + k] if parent >= 0 else 0.0) + w[S + 6 * i + k] * qd[i]
        _motion_cross(w, vel + 6 * i, S + 6 * i, Sdot + 6 * i)
        w[tmp] = m[b + MASS]
        for k in range(3):
            w[tmp + 1 + k] = m[b + FIRST_MOMENT + k]
        for k in range(6):
            w[tmp + 4 + k] = m[b + INERTIA + k]
        for k in range(10):
            w[IC + 10 * i + k] = 0.0
        _add_inertia_to_parent(w, pose + 12 * i, tmp, IC + 10 * i)
        _body_coriolis(w, vel + 6 * i, IC + 10 * i, BC + 12 * i)
        for j in range(n):
            C[i, j] = 0.0
    for j in range(n - 1, -1, -1):
        ic, bc, sj, dj = IC + 10 * j, BC + 12 * j, S + 6 * j, Sdot + 6 * j
        mass, hx, hy, hz = w[ic], w[ic + 1], w[ic + 2], w[ic + 3]
        i0, i1, i2, i3, i4, i5 = w[ic + 4], w[ic + 5], w[ic + 6], w[ic + 7], w[ic + 8], w[ic + 9]
        ax, ay, az, sx, sy, sz = w[sj], w[sj + 1], w[sj + 2], w[sj + 3], w[sj + 4], w[sj + 5]
        dax, day, daz, dsx, dsy, dsz = w[dj], w[dj + 1], w[dj + 2], w[dj + 3], w[dj + 4], w[dj + 5]
        b00, b01, b02, b10, b11, b12 = w[bc], w[bc + 1], w[bc + 2], w[bc + 3], w[bc + 4], w[bc + 5]
        b20, b21, b22, lx, ly, lz = w[bc + 6], w[bc + 7], w[bc + 8], w[bc + 9], w[bc + 10], w[bc + 11]
        # F2 = I^c S
        f2a = i0 * ax + i1 * ay + i2 * az + hy * sz - hz * sy
        f2b = i1 * ax + i3 * ay + i4 * az + hz * sx - hx * sz
        f2c = i2 * ax + i4 * ay + i5 * az + hx * sy - hy * sx
        f2d = mass * sx - (hy * az - hz * ay)
        f2e = mass * sy - (hz * ax - hx * az)
        f2f = mass * sz - (hx * ay - hy * ax)
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
        parent = int(m[HEADER + STRIDE * j + PARENT])
        i = parent
        while i >= 0:
            si, di = S + 6 * i, Sdot + 6 * i
            C[i, j] = (
                w[si] * f1a + w[si + 1] * f1b + w[si + 2] * f1c + w[si + 3] * f1d + w[si + 4] * f1e + w[si + 5] * f1f
            )
            C[j, i] = (
                w[di] * f2a + w[di + 1] * f2b + w[di + 2] * f2c + w[di + 3] * f2d + w[di + 4] * f2e + w[di + 5] * f2f
            ) + (w[si] * f3a + w[si + 1] * f3b + w[si + 2] * f3c)
            i = int(m[HEADER + STRIDE * i + PARENT])
        if parent >= 0:
            for k in range(10):
                w[IC + 10 * parent + k] += w[ic + k]
            for k in range(12):
                w[BC + 12 * parent + k] += w[bc + k]


@njit("int64(float64[::1], float64[::1], float64[::1], float64[:, ::1])", **_OPTS)
def coriolis_one(m: np.ndarray, q: np.ndarray, qd: np.ndarray, C: np.ndarray) -> int:
    n = int(m[0])
    status = _check(q, n, 1)
    if status == 0:
        status = _check(qd, n, 2)
    if status != 0 or C.shape[0] != n or C.shape[1] != n:
        return status if status != 0 else 4
    coriolis_core(m, m, HEADER + STRIDE * n, q, qd, C)
    return 0


@njit(parallel=True, **_OPTS)
def coriolis_batch(m: np.ndarray, q: np.ndarray, qd: np.ndarray, C: np.ndarray) -> None:
    n, count = int(m[0]), q.shape[0]
    chunks = min(count, 64)
    for c in prange(chunks):
        w = np.empty(70 * n + 32)
        for s in range(c * count // chunks, (c + 1) * count // chunks):
            coriolis_core(m, w, 0, q[s], qd[s], C[s])


# ----- ABA: forward dynamics -------------------------------------------------------------------
@njit(inline="always", **_OPTS)
def _rigid_times(w: np.ndarray, i: int, v: int, out: int) -> None:
    """out = I v for a rigid-body inertia (m, h, I_O) stored at w[i:i+10]: [I_O a + h x l; m l - h x a]."""
    mass, hx, hy, hz = w[i], w[i + 1], w[i + 2], w[i + 3]
    ax, ay, az, lx, ly, lz = w[v], w[v + 1], w[v + 2], w[v + 3], w[v + 4], w[v + 5]
    w[out] = w[i + 4] * ax + w[i + 5] * ay + w[i + 6] * az + hy * lz - hz * ly
    w[out + 1] = w[i + 5] * ax + w[i + 7] * ay + w[i + 8] * az + hz * lx - hx * lz
    w[out + 2] = w[i + 6] * ax + w[i + 8] * ay + w[i + 9] * az + hx * ly - hy * lx
    w[out + 3] = mass * lx - (hy * az - hz * ay)
    w[out + 4] = mass * ly - (hz * ax - hx * az)
    w[out + 5] = mass * lz - (hx * ay - hy * ax)


@njit(inline="always", **_OPTS)
def aba_core(
    m: np.ndarray, w: np.ndarray, w0: int, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray
) -> None:
    """qdd = M^-1 (tau - Vm qd - F - G) by the articulated-body algorithm (Featherstone 7.3), in the
    world frame, where articulated inertias add up the tree without transforms.

    Pass 1: v_i = v_p + S_i qd_i, c_i = v_i x S_i qd_i, I^A_i = I_i, p^A_i = v_i x* I_i v_i.
    Pass 2 (leaves first): U = I^A S, D = S^T U + G^2 Jm, u = tau - F - S^T p^A;
    I^A_p += I^A - U U^T / D, p^A_p += p^A + (I^A - U U^T / D) c + U u / D.
    Pass 3: a = a_p + c (a_0 = -g), qdd = (u - U^T a) / D, a += S qdd.
    """
    n = int(m[0])
    local, pose, S, vel, bias = w0, w0 + 12 * n, w0 + 24 * n, w0 + 30 * n, w0 + 36 * n
    IA, pA, U, acc, Du, tmp = w0 + 42 * n, w0 + 78 * n, w0 + 84 * n, w0 + 90 * n, w0 + 96 * n, w0 + 98 * n
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(m[b + PARENT])
        s, v, c, ia = S + 6 * i, vel + 6 * i, bias + 6 * i, IA + 36 * i
        _joint_transform(m, i, q[i], w, local + 12 * i)
        _world_pose(m, w, local + 12 * i, pose + 12 * parent, pose + 12 * i, parent >= 0)
        _world_motion_subspace(m, i, w, pose + 12 * i, s)
        rate = qd[i]
        for k in range(6):
            w[tmp + k] = w[s + k] * rate
            w[v + k] = (w[vel + 6 * parent + k] if parent >= 0 else 0.0) + w[tmp + k]
        _motion_cross(w, v, tmp, c)
        # the body's inertia in world coordinates, 10 parameters at tmp + 6, then as 6x6
        w[tmp + 16] = m[b + MASS]
        for k in range(3):
            w[tmp + 17 + k] = m[b + FIRST_MOMENT + k]
        for k in range(6):
            w[tmp + 20 + k] = m[b + INERTIA + k]
        for k in range(10):
            w[tmp + 6 + k] = 0.0
        _add_inertia_to_parent(w, pose + 12 * i, tmp + 16, tmp + 6)
        mass, hx, hy, hz = w[tmp + 6], w[tmp + 7], w[tmp + 8], w[tmp + 9]
        i0, i1, i2, i3, i4, i5 = w[tmp + 10], w[tmp + 11], w[tmp + 12], w[tmp + 13], w[tmp + 14], w[tmp + 15]
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
                w[ia + 6 * r + k] = row[k]
        _rigid_times(w, tmp + 6, v, tmp + 16)  # momentum [k; l]; p^A = v x* [k; l] = [w x k + u x l; w x l]
        wx, wy, wz, ux, uy, uz = w[v], w[v + 1], w[v + 2], w[v + 3], w[v + 4], w[v + 5]
        kx, ky, kz, lx, ly, lz = w[tmp + 16], w[tmp + 17], w[tmp + 18], w[tmp + 19], w[tmp + 20], w[tmp + 21]
        p = pA + 6 * i
        w[p] = wy * kz - wz * ky + uy * lz - uz * ly
        w[p + 1] = wz * kx - wx * kz + uz * lx - ux * lz
        w[p + 2] = wx * ky - wy * kx + ux * ly - uy * lx
        w[p + 3] = wy * lz - wz * ly
        w[p + 4] = wz * lx - wx * lz
        w[p + 5] = wx * ly - wy * lx
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        s, ia, p, u, c = S + 6 * i, IA + 36 * i, pA + 6 * i, U + 6 * i, bias + 6 * i
        for r in range(6):
            total = 0.0
            for k in range(6):
                total += w[ia + 6 * r + k] * w[s + k]
            w[u + r] = total
        D = _dot6(w, s, u) + m[b + ARMATURE]
        value = tau[i] - _friction(m, i, qd[i]) - _dot6(w, s, p)
        w[Du + 2 * i] = D
        w[Du + 2 * i + 1] = value
        parent = int(m[b + PARENT])
        if parent < 0:
            continue
        target, pt = IA + 36 * parent, pA + 6 * parent
        uc = _dot6(w, u, c) / D
        gain = value / D
        for r in range(6):
            ur = w[u + r] / D
            total = w[p + r] + w[u + r] * (gain - uc)
            for k in range(6):
                total += w[ia + 6 * r + k] * w[c + k]
                w[target + 6 * r + k] += w[ia + 6 * r + k] - ur * w[u + k]
            w[pt + r] += total
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(m[b + PARENT])
        a, s, c = acc + 6 * i, S + 6 * i, bias + 6 * i
        for k in range(6):
            if parent >= 0:
                w[a + k] = w[acc + 6 * parent + k] + w[c + k]
            else:
                w[a + k] = (-m[GRAVITY + k - 3] if k >= 3 else 0.0) + w[c + k]
        result = (w[Du + 2 * i + 1] - _dot6(w, U + 6 * i, a)) / w[Du + 2 * i]
        qdd[i] = result
        for k in range(6):
            w[a + k] += w[s + k] * result


@njit("int64(float64[::1], float64[::1], float64[::1], float64[::1], float64[::1])", **_OPTS)
def aba_one(m: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray) -> int:
    n = int(m[0])
    status = _check_all(n, q, qd, tau, 3, qdd)
    if status == 0:
        aba_core(m, m, HEADER + STRIDE * n, q, qd, tau, qdd)
    return status


@njit(parallel=True, **_OPTS)
def aba_batch(m: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray) -> None:
    n, count = int(m[0]), q.shape[0]
    chunks = min(count, 64)
    for c in prange(chunks):
        w = np.empty(160 * n + 64)
        for s in range(c * count // chunks, (c + 1) * count // chunks):
            aba_core(m, w, 0, q[s], qd[s], tau[s], qdd[s])


# ----- energies ----------------------------------------------------------------------------------
@njit(inline="always", **_OPTS)
def energy_core(m: np.ndarray, w: np.ndarray, w0: int, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    """out[0] = K = 1/2 sum v_i^T I_i v_i + 1/2 sum G^2 Jm qd^2; out[1] = P = -g . sum (m p_w + R_w h)."""
    n = int(m[0])
    local, pose, vel, tmp = w0, w0 + 12 * n, w0 + 24 * n, w0 + 30 * n
    kinetic = 0.0
    potential = 0.0
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(m[b + PARENT])
        t = local + 12 * i
        _joint_transform(m, i, q[i], w, t)
        _world_pose(m, w, t, pose + 12 * parent, pose + 12 * i, parent >= 0)
        v = vel + 6 * i
        if parent < 0:
            for k in range(6):
                w[v + k] = 0.0
        else:
            _motion_to_child(w, t, w, vel + 6 * parent, w, v)
        w[v + (5 if m[b + KIND] != 0.0 else 2)] += qd[i]
        _inertia_times(m, i, w, v, w, tmp)
        kinetic += 0.5 * (_dot6(w, v, tmp) + m[b + ARMATURE] * qd[i] * qd[i])
        o = pose + 12 * i
        mass = m[b + MASS]
        for r in range(3):
            moment = mass * w[o + 9 + r]
            for k in range(3):
                moment += w[o + 3 * r + k] * m[b + FIRST_MOMENT + k]
            potential -= m[GRAVITY + r] * moment
    out[0] = kinetic
    out[1] = potential


@njit("int64(float64[::1], float64[::1], float64[::1], float64[::1])", **_OPTS)
def energy_one(m: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> int:
    n = int(m[0])
    status = _check(q, n, 1)
    if status == 0:
        status = _check(qd, n, 2)
    if status != 0:
        return status
    energy_core(m, m, HEADER + STRIDE * n, q, qd, out)
    return 0


@njit(parallel=True, **_OPTS)
def energy_batch(m: np.ndarray, q: np.ndarray, qd: np.ndarray, out: np.ndarray) -> None:
    n, count = int(m[0]), q.shape[0]
    chunks = min(count, 64)
    for c in prange(chunks):
        w = np.empty(40 * n + 32)
        for s in range(c * count // chunks, (c + 1) * count // chunks):
            energy_core(m, w, 0, q[s], qd[s], out[s])
