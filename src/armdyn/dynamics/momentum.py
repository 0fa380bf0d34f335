"""The generalized momentum p = M qd, the term Vm^T(q, qd) qd and the gravity G(q) in one O(n) recursion.

The momentum observer (armdyn.observers.momentum) needs pdot = tau + Vm^T qd - G - F + tau_ext (Lewis, Dawson and
Abdallah 2004, eq. 3.3.1 and the skew property of Table 3.3.1; De Luca and Mattone, ICRA 2003). Forming M, the
Christoffel Vm and the two products costs O(n^2) to O(n^3); the three terms come instead from one forward and one
backward pass over the bodies (Featherstone, Rigid Body Dynamics Algorithms, 2008, chapters 2 and 5), in body
frames, each joint along its body z (S = e3 revolute, e6 prismatic; dynamics/spatial.py):

- forward: v_i = X_i v_parent + S qd_i, the body momentum h_i = I_i v_i; for the gravity, as in rnea.gravity_core,
  the linear acceleration l_i = R_i^T l_parent (l_root = -g, the same vector in each body's axes);
- backward: the subtree's momentum H_i = h_i + sum over the children of X^T H_child, and its mass and first moment
  (m_i, c_i) (c_i = m_i times the centre of mass, c_parent += R_i c_i + m_i p_i), whose gravity force in joint i's
  axes is Fg_i = [c_i x l_i; m_i l_i] (the sum over the subtree of X^T [c x l; m l]: every body feels the same l);
- p_i = S^T H_i + Ia_i qd_i (M holds the reflected motor inertia Ia on its diagonal), G_i = S^T Fg_i, and

      (Vm^T qd)_i = dK/dq_i = -S^T (v_i x* H_i),      v x* f = [w x n + u x f; w x f] for v = [w; u], f = [n; f].

The last is the identity Vm^T qd = dK/dq of the Christoffel Vm (Mdot = Vm + Vm^T, and Mdot qd = sum_i
qd_i dM/dq_i qd): differentiating v_k = X_k v_parent + S qd_k in q_i gives -(S x v_i) carried to each body k of the
subtree of i, so dK/dq_i = -H_i^T (S x v_i) = -S^T (v_i x* H_i) (S x S = 0 lets v_i stand for X_i v_parent).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from armdyn.dynamics.packed import (
    ARMATURE,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    MOMENTUM_ACCELERATION,
    MOMENTUM_BODY,
    MOMENTUM_JOINT,
    MOMENTUM_MASS,
    MOMENTUM_VELOCITY,
    N_JOINTS,
    PARENT,
    STRIDE,
)
from armdyn.dynamics.spatial import NUMBA_OPTIONS, add_force_to_parent, inertia_apply, joint_transform


@njit(inline="always", **NUMBA_OPTIONS)
def momentum_core(
    model: np.ndarray,
    work: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    p: np.ndarray,
    transposed: np.ndarray,
    G: np.ndarray,
) -> None:
    """p = M(q) qd, Vm^T(q, qd) qd and G(q) of one state in O(n), without M or Vm (see the module docstring).

    Parameters
    ----------
    model : numpy.ndarray
        The packed arm (dynamics/packed.py), read only.
    work : numpy.ndarray
        Scratch of at least MOMENTUM_JOINT * n values (packed.workspace_size(n) covers it): per joint, at
        MOMENTUM_JOINT * i, R, p | v | H | the subtree's (m, m c) | l.
    q, qd : numpy.ndarray
        The state, (n,).
    p, transposed, G : numpy.ndarray
        Outputs, (n,) each: the generalized momentum, Vm^T qd (= dK/dq) and the gravity torque.

    Returns
    -------
    None
        The outputs are written in place.
    """
    n = int(model[N_JOINTS])
    for i in range(n):
        b = HEADER + STRIDE * i
        parent = int(model[b + PARENT])
        o = MOMENTUM_JOINT * i
        joint_transform(model, i, q[i], work, o)
        r00, r01, r02, r10, r11, r12 = work[o], work[o + 1], work[o + 2], work[o + 3], work[o + 4], work[o + 5]
        r20, r21, r22, px, py, pz = work[o + 6], work[o + 7], work[o + 8], work[o + 9], work[o + 10], work[o + 11]
        if parent >= 0:
            s = MOMENTUM_JOINT * parent + MOMENTUM_VELOCITY
            wx, wy, wz, ux, uy, uz = work[s], work[s + 1], work[s + 2], work[s + 3], work[s + 4], work[s + 5]
            a = MOMENTUM_JOINT * parent + MOMENTUM_ACCELERATION
            lx, ly, lz = work[a], work[a + 1], work[a + 2]
        else:
            wx, wy, wz, ux, uy, uz = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            lx, ly, lz = -model[GRAVITY], -model[GRAVITY + 1], -model[GRAVITY + 2]
        # v = X v_parent + S qd: [R^T w; R^T (u + w x p)], then the joint's rate along its z
        tx, ty, tz = ux + wy * pz - wz * py, uy + wz * px - wx * pz, uz + wx * py - wy * px
        Wx, Wy, Wz = r00 * wx + r10 * wy + r20 * wz, r01 * wx + r11 * wy + r21 * wz, r02 * wx + r12 * wy + r22 * wz
        Ux, Uy, Uz = r00 * tx + r10 * ty + r20 * tz, r01 * tx + r11 * ty + r21 * tz, r02 * tx + r12 * ty + r22 * tz
        if model[b + KIND] != 0.0:
            Uz += qd[i]
        else:
            Wz += qd[i]
        m = b + INERTIA
        mass, hx, hy, hz = (
            model[b + MASS],
            model[b + FIRST_MOMENT],
            model[b + FIRST_MOMENT + 1],
            model[b + FIRST_MOMENT + 2],
        )
        body = (mass, hx, hy, hz, model[m], model[m + 1], model[m + 2], model[m + 3], model[m + 4], model[m + 5])
        v, k, c, a = o + MOMENTUM_VELOCITY, o + MOMENTUM_BODY, o + MOMENTUM_MASS, o + MOMENTUM_ACCELERATION
        work[v], work[v + 1], work[v + 2], work[v + 3], work[v + 4], work[v + 5] = Wx, Wy, Wz, Ux, Uy, Uz
        work[k], work[k + 1], work[k + 2], work[k + 3], work[k + 4], work[k + 5] = inertia_apply(
            body, (Wx, Wy, Wz, Ux, Uy, Uz)
        )
        work[c], work[c + 1], work[c + 2], work[c + 3] = mass, hx, hy, hz
        work[a] = r00 * lx + r10 * ly + r20 * lz
        work[a + 1] = r01 * lx + r11 * ly + r21 * lz
        work[a + 2] = r02 * lx + r12 * ly + r22 * lz
    for i in range(n - 1, -1, -1):
        b = HEADER + STRIDE * i
        o = MOMENTUM_JOINT * i
        v, k, c, a = o + MOMENTUM_VELOCITY, o + MOMENTUM_BODY, o + MOMENTUM_MASS, o + MOMENTUM_ACCELERATION
        wx, wy = work[v], work[v + 1]
        nx, ny, fx, fy = work[k], work[k + 1], work[k + 3], work[k + 4]
        # the subtree's gravity force in joint i's axes is Fg_i = [c x l; m l] for its mass m and first moment c
        if model[b + KIND] != 0.0:  # S = e6: the z of the linear parts
            p[i] = work[k + 5]
            transposed[i] = -(wx * fy - wy * fx)
            G[i] = work[c] * work[a + 2]
        else:  # S = e3: the z of the angular parts
            p[i] = work[k + 2]
            transposed[i] = -(wx * ny - wy * nx + work[v + 3] * fy - work[v + 4] * fx)
            G[i] = work[c + 1] * work[a + 1] - work[c + 2] * work[a]
        p[i] += model[b + ARMATURE] * qd[i]
        parent = int(model[b + PARENT])
        if parent >= 0:
            add_force_to_parent(work, o, work, k, work, MOMENTUM_JOINT * parent + MOMENTUM_BODY)
            # (m, c) to the parent: c' = R c + m p
            mass, cx, cy, cz = work[c], work[c + 1], work[c + 2], work[c + 3]
            d = MOMENTUM_JOINT * parent + MOMENTUM_MASS
            work[d] += mass
            work[d + 1] += work[o] * cx + work[o + 1] * cy + work[o + 2] * cz + mass * work[o + 9]
            work[d + 2] += work[o + 3] * cx + work[o + 4] * cy + work[o + 5] * cz + mass * work[o + 10]
            work[d + 3] += work[o + 6] * cx + work[o + 7] * cy + work[o + 8] * cz + mass * work[o + 11]
