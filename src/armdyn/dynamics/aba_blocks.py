"""Batch forward dynamics vectorized across states: the articulated-body algorithm on blocks of states.

qdd = M(q)^-1 (tau - Vm(q, qd) qd - F(qd) - G(q)) by the articulated-body algorithm (Featherstone,
Rigid Body Dynamics Algorithms, 2008, 7.3) in the world frame: the equations of
aba.aba_core, for BLOCK states at a time. As in rnea_blocks, each quantity is a row of BLOCK
values (the state index innermost), so that a joint's step is one loop over the block's states
that LLVM turns into SIMD instructions; joint kinds are 0/1 factors (prism, rev = 1 - prism), so
the loop has no branches; sin/cos is spatial.sin_cos, a polynomial that vectorizes; blocks run in
parallel threads.

With S_i the joint's motion subspace in world coordinates, [z; p x z] (revolute) or [0; z]
(prismatic), z the joint axis and p the joint's origin:

    pass 1, root to leaves: v_i = v_p + S_i qd_i, c_i = v_i x S_i qd_i,
        I^A_i = I_i (the body's inertia in world coordinates), p^A_i = v_i x* I_i v_i;
    pass 2, leaves to root: U_i = I^A_i S_i, D_i = S_i^T U_i + G^2 Jm (the motor's
        reflected inertia, the armature), u_i = tau_i - F_i(qd_i) - S_i^T p^A_i,
        I^A_p += I^A_i - U_i U_i^T / D_i, p^A_p += p^A_i + I^A_i c_i + U_i (u_i - U_i^T c_i) / D_i;
    pass 3, root to leaves: a_i = a_p + c_i (a_base = [0; -g]),
        qdd_i = (u_i - U_i^T a_i) / D_i, a_i += S_i qdd_i.

In the world frame articulated inertias add up the tree without transforms; I^A is symmetric
and kept as its 21 upper-triangle entries. A pivot D_i not above the model's PIVOT_FLOOR means
M(q) is singular at that state: the state's qdd is then meaningless, and ``singular`` names the
first such joint, leaves first (the joint aba.aba_core returns).

A block's memory is one buffer with a slot of ABA_BLOCK_ROWS rows per joint and one for the base (pose the
identity, velocity zero, acceleration [0; -g]); a joint's step reads its parent's slot and
writes its own.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from armdyn.dynamics.friction import coulomb_torque, nonlinear_friction
from armdyn.dynamics.packed import (
    ARMATURE,
    COULOMB_NEG,
    COULOMB_POS,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    N_JOINTS,
    PARENT,
    PIVOT_FLOOR,
    POSITION,
    ROTATION,
    SIGMOID_AMPLITUDE,
    STRIBECK_FORCE,
    STRIDE,
    VISCOUS,
)
from armdyn.dynamics.rnea import BATCH_CHUNKS
from armdyn.dynamics.rnea_blocks import BLOCK  # one block size for both batch kernels
from armdyn.dynamics.spatial import NUMBA_OPTIONS, sin_cos

# A slot's rows: world pose R (9) and p (3), v, S, c (6 each), I^A (21, upper triangle row by row),
# p^A, U (6 each), D, u, a (6), the state's q, qd, tau, the result qdd, the pivot flag; then the body's
# mass, first moment (3) and inertia (6) and the joint's viscous friction, per state, so that the states
# of a block may be arms that differ in those (a payload, scaled masses or friction: run_blocks).
R_, P_, V_, S_, C_, IA_, PA_, U_, D_, VALUE_, A_, Q_, QD_, TAU_, QDD_, FLAG_, BODY_, VISCOUS_ = (
    0, 9, 12, 18, 24, 30, 51, 57, 63, 64, 65, 71, 72, 73, 74, 75, 76, 86,
)  # fmt: skip
ABA_BLOCK_ROWS = 87
LANE_FIELDS = (MASS, FIRST_MOMENT, FIRST_MOMENT + 1, FIRST_MOMENT + 2, INERTIA, INERTIA + 1, INERTIA + 2,
               INERTIA + 3, INERTIA + 4, INERTIA + 5, VISCOUS)  # fmt: skip
"""The offsets in a joint's packed row of the per-state rows BODY_ .. VISCOUS_."""

# The per-joint steps below are compiled as functions of their own, not inlined: inlined, both
# slots are offsets into one buffer, and LLVM, unable to group their accesses for its overlap
# checks, does not vectorize ("too many memory checks"); passed in, each slot is one pointer and
# one check of slot against slot suffices. Passes 1 and 2 are each two loops: in one, the values
# live at once outnumber the vector registers, and the spills made it 18% slower. Stores are
# written out row by row: a loop over a tuple's index stops LLVM vectorizing the states (rnea_blocks).


@njit(inline="always", **NUMBA_OPTIONS)
def block_slot(x: np.ndarray, j: int) -> np.ndarray:
    """Joint j's slot in a block's buffer (j = n: the base's), a view."""
    return x[j * ABA_BLOCK_ROWS * BLOCK : (j + 1) * ABA_BLOCK_ROWS * BLOCK]


@njit(**NUMBA_OPTIONS)
def _motion_joint(model: np.ndarray, i: int, x: np.ndarray, xp: np.ndarray) -> None:
    """Pass 1, kinematics, for joint i (its slot x, its parent's xp): world pose, S, v, c."""
    b = HEADER + STRIDE * i
    r = b + ROTATION
    prism = model[b + KIND]
    rev = 1.0 - prism
    m00, m01, m02, m10, m11, m12 = model[r], model[r + 1], model[r + 2], model[r + 3], model[r + 4], model[r + 5]
    m20, m21, m22 = model[r + 6], model[r + 7], model[r + 8]
    Px, Py, Pz = model[b + POSITION], model[b + POSITION + 1], model[b + POSITION + 2]
    for s in range(BLOCK):
        qi, rate = x[Q_ * BLOCK + s], x[QD_ * BLOCK + s]
        sn, cs = sin_cos(qi)
        c = rev * cs + prism  # prismatic: cos 1, sin 0, exactly (spatial.joint_transform)
        sn = rev * sn
        # the joint's transform R = P_R Rz(q), p = P_p + q P_R e_z (prismatic)
        l00, l01, l10, l11 = m00 * c + m01 * sn, m01 * c - m00 * sn, m10 * c + m11 * sn, m11 * c - m10 * sn
        l20, l21 = m20 * c + m21 * sn, m21 * c - m20 * sn
        lift = prism * qi
        lx, ly, lz = Px + lift * m02, Py + lift * m12, Pz + lift * m22
        # world pose R_w = R_wp R, p_w = p_wp + R_wp p (spatial.world_pose)
        a00, a01, a02 = xp[R_ * BLOCK + s], xp[(R_ + 1) * BLOCK + s], xp[(R_ + 2) * BLOCK + s]
        a10, a11, a12 = xp[(R_ + 3) * BLOCK + s], xp[(R_ + 4) * BLOCK + s], xp[(R_ + 5) * BLOCK + s]
        a20, a21, a22 = xp[(R_ + 6) * BLOCK + s], xp[(R_ + 7) * BLOCK + s], xp[(R_ + 8) * BLOCK + s]
        r02 = a00 * m02 + a01 * m12 + a02 * m22
        r12 = a10 * m02 + a11 * m12 + a12 * m22
        r22 = a20 * m02 + a21 * m12 + a22 * m22
        px = xp[P_ * BLOCK + s] + a00 * lx + a01 * ly + a02 * lz
        py = xp[(P_ + 1) * BLOCK + s] + a10 * lx + a11 * ly + a12 * lz
        pz = xp[(P_ + 2) * BLOCK + s] + a20 * lx + a21 * ly + a22 * lz
        x[R_ * BLOCK + s] = a00 * l00 + a01 * l10 + a02 * l20
        x[(R_ + 1) * BLOCK + s] = a00 * l01 + a01 * l11 + a02 * l21
        x[(R_ + 2) * BLOCK + s] = r02
        x[(R_ + 3) * BLOCK + s] = a10 * l00 + a11 * l10 + a12 * l20
        x[(R_ + 4) * BLOCK + s] = a10 * l01 + a11 * l11 + a12 * l21
        x[(R_ + 5) * BLOCK + s] = r12
        x[(R_ + 6) * BLOCK + s] = a20 * l00 + a21 * l10 + a22 * l20
        x[(R_ + 7) * BLOCK + s] = a20 * l01 + a21 * l11 + a22 * l21
        x[(R_ + 8) * BLOCK + s] = r22
        x[P_ * BLOCK + s] = px
        x[(P_ + 1) * BLOCK + s] = py
        x[(P_ + 2) * BLOCK + s] = pz
        # S = [z; p x z] or [0; z] (spatial.world_motion_subspace), z = R_w e_z
        s0, s1, s2 = rev * r02, rev * r12, rev * r22
        s3 = rev * (py * r22 - pz * r12) + prism * r02
        s4 = rev * (pz * r02 - px * r22) + prism * r12
        s5 = rev * (px * r12 - py * r02) + prism * r22
        # v = v_p + S qd, c = v x S qd (spatial.motion_cross)
        t0, t1, t2, t3, t4, t5 = s0 * rate, s1 * rate, s2 * rate, s3 * rate, s4 * rate, s5 * rate
        wx, wy, wz = xp[V_ * BLOCK + s] + t0, xp[(V_ + 1) * BLOCK + s] + t1, xp[(V_ + 2) * BLOCK + s] + t2
        ux, uy, uz = xp[(V_ + 3) * BLOCK + s] + t3, xp[(V_ + 4) * BLOCK + s] + t4, xp[(V_ + 5) * BLOCK + s] + t5
        x[V_ * BLOCK + s] = wx
        x[(V_ + 1) * BLOCK + s] = wy
        x[(V_ + 2) * BLOCK + s] = wz
        x[(V_ + 3) * BLOCK + s] = ux
        x[(V_ + 4) * BLOCK + s] = uy
        x[(V_ + 5) * BLOCK + s] = uz
        x[S_ * BLOCK + s] = s0
        x[(S_ + 1) * BLOCK + s] = s1
        x[(S_ + 2) * BLOCK + s] = s2
        x[(S_ + 3) * BLOCK + s] = s3
        x[(S_ + 4) * BLOCK + s] = s4
        x[(S_ + 5) * BLOCK + s] = s5
        x[C_ * BLOCK + s] = wy * t2 - wz * t1
        x[(C_ + 1) * BLOCK + s] = wz * t0 - wx * t2
        x[(C_ + 2) * BLOCK + s] = wx * t1 - wy * t0
        x[(C_ + 3) * BLOCK + s] = wy * t5 - wz * t4 + uy * t2 - uz * t1
        x[(C_ + 4) * BLOCK + s] = wz * t3 - wx * t5 + uz * t0 - ux * t2
        x[(C_ + 5) * BLOCK + s] = wx * t4 - wy * t3 + ux * t1 - uy * t0


@njit(**NUMBA_OPTIONS)
def _inertia_joint(model: np.ndarray, i: int, x: np.ndarray) -> None:
    """Pass 1, inertias, for joint i (its slot x, pose and v set): I^A = the body's inertia in the
    world, p^A = v x* I v."""
    for s in range(BLOCK):
        mass, bhx = x[BODY_ * BLOCK + s], x[(BODY_ + 1) * BLOCK + s]
        bhy, bhz = x[(BODY_ + 2) * BLOCK + s], x[(BODY_ + 3) * BLOCK + s]
        b0, b1, b2 = x[(BODY_ + 4) * BLOCK + s], x[(BODY_ + 5) * BLOCK + s], x[(BODY_ + 6) * BLOCK + s]
        b3, b4, b5 = x[(BODY_ + 7) * BLOCK + s], x[(BODY_ + 8) * BLOCK + s], x[(BODY_ + 9) * BLOCK + s]
        r00, r01, r02 = x[R_ * BLOCK + s], x[(R_ + 1) * BLOCK + s], x[(R_ + 2) * BLOCK + s]
        r10, r11, r12 = x[(R_ + 3) * BLOCK + s], x[(R_ + 4) * BLOCK + s], x[(R_ + 5) * BLOCK + s]
        r20, r21, r22 = x[(R_ + 6) * BLOCK + s], x[(R_ + 7) * BLOCK + s], x[(R_ + 8) * BLOCK + s]
        px, py, pz = x[P_ * BLOCK + s], x[(P_ + 1) * BLOCK + s], x[(P_ + 2) * BLOCK + s]
        # spatial.add_inertia_to_parent onto zero: h' = R h + m p,
        # I' = R I R^T - [Rh]x [p]x - [p]x [Rh]x - m [p]x [p]x
        rh0 = r00 * bhx + r01 * bhy + r02 * bhz
        rh1 = r10 * bhx + r11 * bhy + r12 * bhz
        rh2 = r20 * bhx + r21 * bhy + r22 * bhz
        e00, e01, e02 = r00 * b0 + r01 * b1 + r02 * b2, r00 * b1 + r01 * b3 + r02 * b4, r00 * b2 + r01 * b4 + r02 * b5
        e10, e11, e12 = r10 * b0 + r11 * b1 + r12 * b2, r10 * b1 + r11 * b3 + r12 * b4, r10 * b2 + r11 * b4 + r12 * b5
        e20, e21, e22 = r20 * b0 + r21 * b1 + r22 * b2, r20 * b1 + r21 * b3 + r22 * b4, r20 * b2 + r21 * b4 + r22 * b5
        hp = rh0 * px + rh1 * py + rh2 * pz
        pp = px * px + py * py + pz * pz
        hx, hy, hz = rh0 + mass * px, rh1 + mass * py, rh2 + mass * pz
        i0 = e00 * r00 + e01 * r01 + e02 * r02 - (2.0 * px * rh0 - 2.0 * hp) - mass * (px * px - pp)
        i1 = e00 * r10 + e01 * r11 + e02 * r12 - (px * rh1 + py * rh0) - mass * (px * py)
        i2 = e00 * r20 + e01 * r21 + e02 * r22 - (px * rh2 + pz * rh0) - mass * (px * pz)
        i3 = e10 * r10 + e11 * r11 + e12 * r12 - (2.0 * py * rh1 - 2.0 * hp) - mass * (py * py - pp)
        i4 = e10 * r20 + e11 * r21 + e12 * r22 - (py * rh2 + pz * rh1) - mass * (py * pz)
        i5 = e20 * r20 + e21 * r21 + e22 * r22 - (2.0 * pz * rh2 - 2.0 * hp) - mass * (pz * pz - pp)
        # I^A = [[I_O, -[h]x], [[h]x, m 1]]
        x[IA_ * BLOCK + s] = i0
        x[(IA_ + 1) * BLOCK + s] = i1
        x[(IA_ + 2) * BLOCK + s] = i2
        x[(IA_ + 3) * BLOCK + s] = 0.0
        x[(IA_ + 4) * BLOCK + s] = -hz
        x[(IA_ + 5) * BLOCK + s] = hy
        x[(IA_ + 6) * BLOCK + s] = i3
        x[(IA_ + 7) * BLOCK + s] = i4
        x[(IA_ + 8) * BLOCK + s] = hz
        x[(IA_ + 9) * BLOCK + s] = 0.0
        x[(IA_ + 10) * BLOCK + s] = -hx
        x[(IA_ + 11) * BLOCK + s] = i5
        x[(IA_ + 12) * BLOCK + s] = -hy
        x[(IA_ + 13) * BLOCK + s] = hx
        x[(IA_ + 14) * BLOCK + s] = 0.0
        x[(IA_ + 15) * BLOCK + s] = mass
        x[(IA_ + 16) * BLOCK + s] = 0.0
        x[(IA_ + 17) * BLOCK + s] = 0.0
        x[(IA_ + 18) * BLOCK + s] = mass
        x[(IA_ + 19) * BLOCK + s] = 0.0
        x[(IA_ + 20) * BLOCK + s] = mass
        # momentum [k; l] = I v = [I_O w + h x u; m u - h x w] (spatial.rigid_times),
        # p^A = v x* [k; l] = [w x k + u x l; w x l]
        wx, wy, wz = x[V_ * BLOCK + s], x[(V_ + 1) * BLOCK + s], x[(V_ + 2) * BLOCK + s]
        ux, uy, uz = x[(V_ + 3) * BLOCK + s], x[(V_ + 4) * BLOCK + s], x[(V_ + 5) * BLOCK + s]
        kx = i0 * wx + i1 * wy + i2 * wz + hy * uz - hz * uy
        ky = i1 * wx + i3 * wy + i4 * wz + hz * ux - hx * uz
        kz = i2 * wx + i4 * wy + i5 * wz + hx * uy - hy * ux
        lx = mass * ux - (hy * wz - hz * wy)
        ly = mass * uy - (hz * wx - hx * wz)
        lz = mass * uz - (hx * wy - hy * wx)
        x[PA_ * BLOCK + s] = wy * kz - wz * ky + uy * lz - uz * ly
        x[(PA_ + 1) * BLOCK + s] = wz * kx - wx * kz + uz * lx - ux * lz
        x[(PA_ + 2) * BLOCK + s] = wx * ky - wy * kx + ux * ly - uy * lx
        x[(PA_ + 3) * BLOCK + s] = wy * lz - wz * ly
        x[(PA_ + 4) * BLOCK + s] = wz * lx - wx * lz
        x[(PA_ + 5) * BLOCK + s] = wx * ly - wy * lx


@njit(**NUMBA_OPTIONS)
def _pivot_joint(model: np.ndarray, i: int, x: np.ndarray) -> None:
    """Pass 2 for joint i, its own part: U = I^A S, D = S^T U + armature, u = tau - F - S^T p^A,
    and the pivot flag (1 where D is not above the model's PIVOT_FLOOR, NaN included)."""
    b = HEADER + STRIDE * i
    armature, floor = model[b + ARMATURE], model[PIVOT_FLOOR]
    positive, negative = model[b + COULOMB_POS], model[b + COULOMB_NEG]
    nonlinear = model[b + STRIBECK_FORCE] != 0.0 or model[b + SIGMOID_AMPLITUDE] != 0.0
    for s in range(BLOCK):
        s0, s1, s2 = x[S_ * BLOCK + s], x[(S_ + 1) * BLOCK + s], x[(S_ + 2) * BLOCK + s]
        s3, s4, s5 = x[(S_ + 3) * BLOCK + s], x[(S_ + 4) * BLOCK + s], x[(S_ + 5) * BLOCK + s]
        a0, a1, a2 = x[IA_ * BLOCK + s], x[(IA_ + 1) * BLOCK + s], x[(IA_ + 2) * BLOCK + s]
        a3, a4, a5 = x[(IA_ + 3) * BLOCK + s], x[(IA_ + 4) * BLOCK + s], x[(IA_ + 5) * BLOCK + s]
        a6, a7, a8 = x[(IA_ + 6) * BLOCK + s], x[(IA_ + 7) * BLOCK + s], x[(IA_ + 8) * BLOCK + s]
        a9, a10, a11 = x[(IA_ + 9) * BLOCK + s], x[(IA_ + 10) * BLOCK + s], x[(IA_ + 11) * BLOCK + s]
        a12, a13, a14 = x[(IA_ + 12) * BLOCK + s], x[(IA_ + 13) * BLOCK + s], x[(IA_ + 14) * BLOCK + s]
        a15, a16, a17 = x[(IA_ + 15) * BLOCK + s], x[(IA_ + 16) * BLOCK + s], x[(IA_ + 17) * BLOCK + s]
        a18, a19, a20 = x[(IA_ + 18) * BLOCK + s], x[(IA_ + 19) * BLOCK + s], x[(IA_ + 20) * BLOCK + s]
        u0 = a0 * s0 + a1 * s1 + a2 * s2 + a3 * s3 + a4 * s4 + a5 * s5
        u1 = a1 * s0 + a6 * s1 + a7 * s2 + a8 * s3 + a9 * s4 + a10 * s5
        u2 = a2 * s0 + a7 * s1 + a11 * s2 + a12 * s3 + a13 * s4 + a14 * s5
        u3 = a3 * s0 + a8 * s1 + a12 * s2 + a15 * s3 + a16 * s4 + a17 * s5
        u4 = a4 * s0 + a9 * s1 + a13 * s2 + a16 * s3 + a18 * s4 + a19 * s5
        u5 = a5 * s0 + a10 * s1 + a14 * s2 + a17 * s3 + a19 * s4 + a20 * s5
        D = s0 * u0 + s1 * u1 + s2 * u2 + s3 * u3 + s4 * u4 + s5 * u5 + armature
        rate = x[QD_ * BLOCK + s]
        coulomb = coulomb_torque(positive, negative, rate)
        p0, p1, p2 = x[PA_ * BLOCK + s], x[(PA_ + 1) * BLOCK + s], x[(PA_ + 2) * BLOCK + s]
        p3, p4, p5 = x[(PA_ + 3) * BLOCK + s], x[(PA_ + 4) * BLOCK + s], x[(PA_ + 5) * BLOCK + s]
        spa = s0 * p0 + s1 * p1 + s2 * p2 + s3 * p3 + s4 * p4 + s5 * p5
        x[U_ * BLOCK + s] = u0
        x[(U_ + 1) * BLOCK + s] = u1
        x[(U_ + 2) * BLOCK + s] = u2
        x[(U_ + 3) * BLOCK + s] = u3
        x[(U_ + 4) * BLOCK + s] = u4
        x[(U_ + 5) * BLOCK + s] = u5
        x[D_ * BLOCK + s] = D
        x[VALUE_ * BLOCK + s] = x[TAU_ * BLOCK + s] - (x[VISCOUS_ * BLOCK + s] * rate + coulomb) - spa
        x[FLAG_ * BLOCK + s] = 0.0 if floor < D else 1.0
    if nonlinear:  # the Stribeck and sigmoid friction, a loop of its own (the one above stays as it vectorizes)
        for s in range(BLOCK):
            x[VALUE_ * BLOCK + s] -= nonlinear_friction(model, i, x[QD_ * BLOCK + s])


@njit(**NUMBA_OPTIONS)
def _carry_joint(x: np.ndarray, xp: np.ndarray) -> None:
    """Pass 2 for one joint, into its parent's slot xp: I^A_p += I^A - U U^T / D and
    p^A_p += p^A + U (u / D - U^T c / D) + I^A c, divided and summed in aba_core's order so that
    both round alike."""
    for s in range(BLOCK):
        D, value = x[D_ * BLOCK + s], x[VALUE_ * BLOCK + s]
        u0, u1, u2 = x[U_ * BLOCK + s], x[(U_ + 1) * BLOCK + s], x[(U_ + 2) * BLOCK + s]
        u3, u4, u5 = x[(U_ + 3) * BLOCK + s], x[(U_ + 4) * BLOCK + s], x[(U_ + 5) * BLOCK + s]
        c0, c1, c2 = x[C_ * BLOCK + s], x[(C_ + 1) * BLOCK + s], x[(C_ + 2) * BLOCK + s]
        c3, c4, c5 = x[(C_ + 3) * BLOCK + s], x[(C_ + 4) * BLOCK + s], x[(C_ + 5) * BLOCK + s]
        a0, a1, a2 = x[IA_ * BLOCK + s], x[(IA_ + 1) * BLOCK + s], x[(IA_ + 2) * BLOCK + s]
        a3, a4, a5 = x[(IA_ + 3) * BLOCK + s], x[(IA_ + 4) * BLOCK + s], x[(IA_ + 5) * BLOCK + s]
        a6, a7, a8 = x[(IA_ + 6) * BLOCK + s], x[(IA_ + 7) * BLOCK + s], x[(IA_ + 8) * BLOCK + s]
        a9, a10, a11 = x[(IA_ + 9) * BLOCK + s], x[(IA_ + 10) * BLOCK + s], x[(IA_ + 11) * BLOCK + s]
        a12, a13, a14 = x[(IA_ + 12) * BLOCK + s], x[(IA_ + 13) * BLOCK + s], x[(IA_ + 14) * BLOCK + s]
        a15, a16, a17 = x[(IA_ + 15) * BLOCK + s], x[(IA_ + 16) * BLOCK + s], x[(IA_ + 17) * BLOCK + s]
        a18, a19, a20 = x[(IA_ + 18) * BLOCK + s], x[(IA_ + 19) * BLOCK + s], x[(IA_ + 20) * BLOCK + s]
        g = value / D - (u0 * c0 + u1 * c1 + u2 * c2 + u3 * c3 + u4 * c4 + u5 * c5) / D
        xp[PA_ * BLOCK + s] += x[PA_ * BLOCK + s] + u0 * g + a0 * c0 + a1 * c1 + a2 * c2 + a3 * c3 + a4 * c4 + a5 * c5
        xp[(PA_ + 1) * BLOCK + s] += (x[(PA_ + 1) * BLOCK + s] + u1 * g + a1 * c0 + a6 * c1 + a7 * c2 + a8 * c3
                                      + a9 * c4 + a10 * c5)  # fmt: skip
        xp[(PA_ + 2) * BLOCK + s] += (x[(PA_ + 2) * BLOCK + s] + u2 * g + a2 * c0 + a7 * c1 + a11 * c2 + a12 * c3
                                      + a13 * c4 + a14 * c5)  # fmt: skip
        xp[(PA_ + 3) * BLOCK + s] += (x[(PA_ + 3) * BLOCK + s] + u3 * g + a3 * c0 + a8 * c1 + a12 * c2 + a15 * c3
                                      + a16 * c4 + a17 * c5)  # fmt: skip
        xp[(PA_ + 4) * BLOCK + s] += (x[(PA_ + 4) * BLOCK + s] + u4 * g + a4 * c0 + a9 * c1 + a13 * c2 + a16 * c3
                                      + a18 * c4 + a19 * c5)  # fmt: skip
        xp[(PA_ + 5) * BLOCK + s] += (x[(PA_ + 5) * BLOCK + s] + u5 * g + a5 * c0 + a10 * c1 + a14 * c2 + a17 * c3
                                      + a19 * c4 + a20 * c5)  # fmt: skip
        w0, w1, w2, w3, w4, w5 = u0 / D, u1 / D, u2 / D, u3 / D, u4 / D, u5 / D
        xp[IA_ * BLOCK + s] += a0 - w0 * u0
        xp[(IA_ + 1) * BLOCK + s] += a1 - w0 * u1
        xp[(IA_ + 2) * BLOCK + s] += a2 - w0 * u2
        xp[(IA_ + 3) * BLOCK + s] += a3 - w0 * u3
        xp[(IA_ + 4) * BLOCK + s] += a4 - w0 * u4
        xp[(IA_ + 5) * BLOCK + s] += a5 - w0 * u5
        xp[(IA_ + 6) * BLOCK + s] += a6 - w1 * u1
        xp[(IA_ + 7) * BLOCK + s] += a7 - w1 * u2
        xp[(IA_ + 8) * BLOCK + s] += a8 - w1 * u3
        xp[(IA_ + 9) * BLOCK + s] += a9 - w1 * u4
        xp[(IA_ + 10) * BLOCK + s] += a10 - w1 * u5
        xp[(IA_ + 11) * BLOCK + s] += a11 - w2 * u2
        xp[(IA_ + 12) * BLOCK + s] += a12 - w2 * u3
        xp[(IA_ + 13) * BLOCK + s] += a13 - w2 * u4
        xp[(IA_ + 14) * BLOCK + s] += a14 - w2 * u5
        xp[(IA_ + 15) * BLOCK + s] += a15 - w3 * u3
        xp[(IA_ + 16) * BLOCK + s] += a16 - w3 * u4
        xp[(IA_ + 17) * BLOCK + s] += a17 - w3 * u5
        xp[(IA_ + 18) * BLOCK + s] += a18 - w4 * u4
        xp[(IA_ + 19) * BLOCK + s] += a19 - w4 * u5
        xp[(IA_ + 20) * BLOCK + s] += a20 - w5 * u5


@njit(**NUMBA_OPTIONS)
def _acceleration_joint(x: np.ndarray, xp: np.ndarray) -> None:
    """Pass 3 for one joint: a = a_p + c, qdd = (u - U^T a) / D, a += S qdd."""
    for s in range(BLOCK):
        e0 = xp[A_ * BLOCK + s] + x[C_ * BLOCK + s]
        e1 = xp[(A_ + 1) * BLOCK + s] + x[(C_ + 1) * BLOCK + s]
        e2 = xp[(A_ + 2) * BLOCK + s] + x[(C_ + 2) * BLOCK + s]
        e3 = xp[(A_ + 3) * BLOCK + s] + x[(C_ + 3) * BLOCK + s]
        e4 = xp[(A_ + 4) * BLOCK + s] + x[(C_ + 4) * BLOCK + s]
        e5 = xp[(A_ + 5) * BLOCK + s] + x[(C_ + 5) * BLOCK + s]
        ua = (x[U_ * BLOCK + s] * e0 + x[(U_ + 1) * BLOCK + s] * e1 + x[(U_ + 2) * BLOCK + s] * e2
              + x[(U_ + 3) * BLOCK + s] * e3 + x[(U_ + 4) * BLOCK + s] * e4 + x[(U_ + 5) * BLOCK + s] * e5)  # fmt: skip
        qdd = (x[VALUE_ * BLOCK + s] - ua) / x[D_ * BLOCK + s]
        x[QDD_ * BLOCK + s] = qdd
        x[A_ * BLOCK + s] = e0 + x[S_ * BLOCK + s] * qdd
        x[(A_ + 1) * BLOCK + s] = e1 + x[(S_ + 1) * BLOCK + s] * qdd
        x[(A_ + 2) * BLOCK + s] = e2 + x[(S_ + 2) * BLOCK + s] * qdd
        x[(A_ + 3) * BLOCK + s] = e3 + x[(S_ + 3) * BLOCK + s] * qdd
        x[(A_ + 4) * BLOCK + s] = e4 + x[(S_ + 4) * BLOCK + s] * qdd
        x[(A_ + 5) * BLOCK + s] = e5 + x[(S_ + 5) * BLOCK + s] * qdd


@njit(inline="always", **NUMBA_OPTIONS)
def base_slot(model: np.ndarray, x: np.ndarray) -> None:
    """The base's slot: pose the identity, velocity zero, acceleration [0; -g] (gravity as an
    acceleration of the base, Featherstone 5.3). Its other rows only collect what the root
    joints carry to their parent in pass 2, and are never read."""
    for row in range(ABA_BLOCK_ROWS):
        value = 0.0
        if row == R_ or row == R_ + 4 or row == R_ + 8:
            value = 1.0
        elif A_ + 3 <= row < A_ + 6:
            value = -model[GRAVITY + row - A_ - 3]
        for s in range(BLOCK):
            x[row * BLOCK + s] = value


@njit(inline="always", **NUMBA_OPTIONS)
def aba_block(model: np.ndarray, x: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, first: int,
               size: int, qdd: np.ndarray, singular: np.ndarray) -> None:  # fmt: skip
    """The three passes for the states first .. first + size - 1 of the batch, in the buffer x. The
    rows of a last, partial block's missing states repeat its first state, so that they stay finite."""
    n = int(model[N_JOINTS])
    for i in range(n):
        o = i * ABA_BLOCK_ROWS * BLOCK
        for s in range(BLOCK):
            e = first + (s if s < size else 0)
            x[o + Q_ * BLOCK + s] = q[e, i]
            x[o + QD_ * BLOCK + s] = qd[e, i]
            x[o + TAU_ * BLOCK + s] = tau[e, i]
    for i in range(n):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        _motion_joint(model, i, block_slot(x, i), block_slot(x, parent if parent >= 0 else n))
        _inertia_joint(model, i, block_slot(x, i))
    for i in range(n - 1, -1, -1):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        _pivot_joint(model, i, block_slot(x, i))
        _carry_joint(block_slot(x, i), block_slot(x, parent if parent >= 0 else n))
    for i in range(n):
        parent = int(model[HEADER + STRIDE * i + PARENT])
        _acceleration_joint(block_slot(x, i), block_slot(x, parent if parent >= 0 else n))
    for s in range(size):
        joint = -1
        for i in range(n):
            o = i * ABA_BLOCK_ROWS * BLOCK
            qdd[first + s, i] = x[o + QDD_ * BLOCK + s]
            if x[o + FLAG_ * BLOCK + s] != 0.0:
                joint = i  # the last flagged is the first leaves first, where aba_core stops
        singular[first + s] = joint


@njit(inline="always", **NUMBA_OPTIONS)
def lane_parameters(model: np.ndarray, x: np.ndarray, lane: int) -> None:
    """Every joint's per-state rows (LANE_FIELDS) of state ``lane`` of the block in x, from a packed model."""
    for i in range(int(model[N_JOINTS])):
        b, o = HEADER + STRIDE * i, i * ABA_BLOCK_ROWS * BLOCK
        for k in range(len(LANE_FIELDS)):
            x[o + (BODY_ + k) * BLOCK + lane] = model[b + LANE_FIELDS[k]]


@njit(parallel=True, **NUMBA_OPTIONS)
def aba_blocks(
    model: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray, singular: np.ndarray
) -> None:
    """qdd for each row of a (B, n) batch (q, qd, tau), BLOCK states at a time, in parallel chunks of
    blocks, each chunk with its own buffer; singular[s] is the joint where M(q) is singular at state
    s (aba.aba_core's: the first leaves first whose pivot is not above PIVOT_FLOOR), -1 where it is
    not."""
    count, n = q.shape[0], int(model[N_JOINTS])
    blocks = (count + BLOCK - 1) // BLOCK
    chunks = min(blocks, BATCH_CHUNKS)
    for chunk in prange(chunks):
        x = np.empty((n + 1) * ABA_BLOCK_ROWS * BLOCK)
        base_slot(model, block_slot(x, n))
        for lane in range(BLOCK):
            lane_parameters(model, x, lane)
        for block in range(chunk * blocks // chunks, (chunk + 1) * blocks // chunks):
            first = block * BLOCK
            aba_block(model, x, q, qd, tau, first, min(BLOCK, count - first), qdd, singular)
