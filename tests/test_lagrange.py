"""The Lagrange-Euler reference against the book's closed forms, its own identities, and Pinocchio."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn.dynamics import lagrange
from tests.helpers import pinocchio_pair
from tests.strategies import random_robot, random_state

RNG = np.random.default_rng(7)
STATES = [tuple(RNG.uniform(-2, 2, 3) for _ in range(3)) for _ in range(5)]
TIGHT = {"rtol": 1e-12, "atol": 1e-12}


# ----- Examples 3.2-1, 3.2-2 and Exercise 3.2-3: the closed forms ---------------------------
@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize(("m1", "m2", "a1", "a2"), [(1.0, 1.0, 1.0, 1.0), (2.5, 0.7, 0.8, 1.3)])
def test_two_link_planar_equals_example_3_2_2(state: tuple, m1: float, m2: float, a1: float, a2: float) -> None:
    g = 9.8
    arm = ad.models.two_link_planar(m1, m2, a1, a2, g)
    (t1, t2), (d1, d2), _ = (s[:2] for s in state)
    q, qd = np.array([t1, t2]), np.array([d1, d2])
    c1, c2, s2, c12 = np.cos(t1), np.cos(t2), np.sin(t2), np.cos(t1 + t2)
    M = np.array(
        [
            [(m1 + m2) * a1**2 + m2 * a2**2 + 2 * m2 * a1 * a2 * c2, m2 * a2**2 + m2 * a1 * a2 * c2],
            [m2 * a2**2 + m2 * a1 * a2 * c2, m2 * a2**2],
        ]
    )
    V = np.array([-m2 * a1 * a2 * (2 * d1 * d2 + d2**2) * s2, m2 * a1 * a2 * d1**2 * s2])
    G = np.array([(m1 + m2) * g * a1 * c1 + m2 * g * a2 * c12, m2 * g * a2 * c12])
    Vm = m2 * a1 * a2 * s2 * np.array([[-d2, -(d1 + d2)], [d1, 0.0]])
    S = (2 * d1 + d2) * m2 * a1 * a2 * s2 * np.array([[0.0, 1.0], [-1.0, 0.0]])
    V1 = -m2 * a1 * a2 * s2 * np.array([[0.0, 1.0], [1.0, 1.0]])
    V2 = m2 * a1 * a2 * s2 * np.array([[1.0, 0.0], [0.0, 0.0]])
    assert_allclose(lagrange.inertia_matrix(arm, q), M, **TIGHT)
    assert_allclose(lagrange.coriolis_vector(arm, q, qd), V, **TIGHT)
    assert_allclose(lagrange.gravity_vector(arm, q), G, **TIGHT)
    assert_allclose(lagrange.coriolis_matrix(arm, q, qd), Vm, **TIGHT)
    assert_allclose(lagrange.inertia_matrix_dot(arm, q, qd) - 2 * lagrange.coriolis_matrix(arm, q, qd), S, **TIGHT)
    christoffel = lagrange.christoffel_symbols(arm, q)  # V_k = [v_ijk]_ij (Table 3.3.1)
    assert_allclose(christoffel[:, :, 0], V1, **TIGHT)
    assert_allclose(christoffel[:, :, 1], V2, **TIGHT)


@pytest.mark.parametrize("state", STATES)
def test_polar_arm_equals_example_3_2_1(state: tuple) -> None:
    m, g = 1.7, 9.8
    arm = ad.models.polar_rp(m, g)
    (theta, r), (thd, rd), _ = (s[:2] for s in state)
    q, qd = np.array([theta, r]), np.array([thd, rd])
    assert_allclose(lagrange.inertia_matrix(arm, q), np.diag([m * r**2, m]), **TIGHT)
    assert_allclose(lagrange.coriolis_vector(arm, q, qd), [2 * m * r * rd * thd, -m * r * thd**2], **TIGHT)
    assert_allclose(lagrange.gravity_vector(arm, q), [m * g * r * np.cos(theta), m * g * np.sin(theta)], **TIGHT)


@pytest.mark.parametrize("state", STATES)
def test_cylindrical_arm_equals_exercise_3_2_3(state: tuple) -> None:
    J, m1, m2, g = 0.6, 1.3, 2.1, 9.8
    arm = ad.models.cylindrical(J, m1, m2, g)
    (theta, h, r), (thd, hd, rd), _ = state
    q, qd = np.array([theta, h, r]), np.array([thd, hd, rd])
    assert_allclose(lagrange.inertia_matrix(arm, q), np.diag([J + m2 * r**2, m1 + m2, m2]), **TIGHT)
    assert_allclose(lagrange.coriolis_vector(arm, q, qd), [2 * m2 * r * rd * thd, 0.0, -m2 * r * thd**2], **TIGHT)
    assert_allclose(lagrange.gravity_vector(arm, q), [0.0, (m1 + m2) * g, 0.0], **TIGHT)


# ----- the Robotics Toolbox's published PUMA 560 values ----------------------------------------
def test_puma560_gravity_at_qn_equals_the_toolbox() -> None:
    puma = ad.models.puma560()
    assert_allclose(lagrange.gravity_vector(puma, puma.qn), [0, 31.6399, 6.0351, 0, 0.0283, 0], atol=1e-4)


def test_puma560_inertia_and_accel_at_qn_equal_the_toolbox() -> None:
    puma = ad.models.puma560()
    M = lagrange.inertia_matrix(puma, puma.qn)
    assert_allclose(np.diag(M), [3.6594, 4.4137, 0.9378, 0.1925, 0.1713, 0.1941], atol=1e-4)
    assert_allclose(M[0, 1:4], [-0.4044, 0.1006, -0.0025], atol=1e-4)
    qd = np.array([0.1, 0.2, 0.8, 0.2, 0.5, 1.0])
    tau = np.array([1.0, 3.2, 1.8, 0.1, 0.7, 4.6])
    qdd = np.linalg.solve(M, tau - lagrange.inverse_dynamics(puma, puma.qn, qd, np.zeros(6)))
    assert_allclose(qdd, [-7.4102, -9.8432, -10.9694, -4.4314, -0.9881, 21.0228], atol=1e-4)


def test_puma560_inverse_dynamics_equals_the_toolbox_rne() -> None:
    puma = ad.models.puma560()
    zero, one = np.zeros(6), np.ones(6)
    cases = [
        (zero, one, [3.35311, 36.0025, 7.42596, 0.190043, 0.203441, 0.194133]),
        (one, one, [32.4952, 60.867, 17.7436, 1.45452, 1.29911, 0.713781]),
        (one, zero, [29.1421, 56.5044, 16.3528, 1.26448, 1.12392, 0.519648]),
    ]
    for qd, qdd, expected in cases:
        assert_allclose(lagrange.inverse_dynamics(puma, puma.qn, qd, qdd), expected, rtol=2e-5, atol=1e-5)


# ----- identities on random trees (hypothesis) -----------------------------------------------
def finite_difference(f: object, q: np.ndarray, direction: np.ndarray, h: float = 1e-6) -> np.ndarray:
    return (f(q + h * direction) - f(q - h * direction)) / (2 * h)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 6))
def test_inertia_matrix_is_symmetric_positive_definite(seed: int, n: int) -> None:
    arm = random_robot(seed, n)
    q, _, _ = random_state(arm, seed)
    M = lagrange.inertia_matrix(arm, q)
    assert_allclose(M, M.T, rtol=0, atol=1e-13 * np.abs(M).max())
    assert np.linalg.eigvalsh(M)[0] > 0


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 6))
def test_christoffel_identities_on_random_trees(seed: int, n: int) -> None:
    arm = random_robot(seed, n)
    q, qd, x = random_state(arm, seed)
    Mdot = lagrange.inertia_matrix_dot(arm, q, qd)
    scale = np.abs(Mdot).max() + 1.0
    assert_allclose(Mdot, finite_difference(lambda p: lagrange.inertia_matrix(arm, p), q, qd), atol=1e-6 * scale)
    S = Mdot - 2 * lagrange.coriolis_matrix(arm, q, qd)
    assert_allclose(S, -S.T, atol=1e-12 * scale)  # property 4
    assert_allclose(  # property 5: Vm(q, x) y = Vm(q, y) x
        lagrange.coriolis_matrix(arm, q, x) @ qd,
        lagrange.coriolis_matrix(arm, q, qd) @ x,
        atol=1e-12 * scale * np.abs(x).max(),
    )
    # (3.2.42): V = Mdot qd - 1/2 d/dq (qd^T M qd)
    grad = np.array([finite_difference(lambda p: qd @ lagrange.inertia_matrix(arm, p) @ qd, q, e) for e in np.eye(n)])
    assert_allclose(lagrange.coriolis_vector(arm, q, qd), Mdot @ qd - 0.5 * grad, atol=1e-6 * scale)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 6))
def test_gravity_is_the_gradient_of_potential_energy(seed: int, n: int) -> None:
    arm = random_robot(seed, n)
    q, _, _ = random_state(arm, seed)
    grad = np.array([finite_difference(lambda p: lagrange.potential_energy(arm, p), q, e) for e in np.eye(n)])
    assert_allclose(lagrange.gravity_vector(arm, q), grad, atol=1e-6 * (np.abs(grad).max() + 1))


def test_batches_match_single_states() -> None:
    arm = random_robot(3, 5)
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-2, 2, (2, 3, 5)) for _ in range(3))
    tau = lagrange.inverse_dynamics(arm, q, qd, qdd)
    M = lagrange.inertia_matrix(arm, q)
    assert tau.shape == (2, 3, 5) and M.shape == (2, 3, 5, 5)
    for index in np.ndindex(2, 3):
        assert_allclose(tau[index], lagrange.inverse_dynamics(arm, q[index], qd[index], qdd[index]), rtol=1e-14)
        assert_allclose(M[index], lagrange.inertia_matrix(arm, q[index]), rtol=1e-14)
    assert lagrange.kinetic_energy(arm, q, qd).shape == (2, 3)
    assert lagrange.potential_energy(arm, q).shape == (2, 3)


def test_friction_follows_the_toolbox_convention() -> None:
    """F = G^2 B qd + |G| Tc+ (qd > 0) or |G| Tc- (qd < 0), and 0 Coulomb at rest."""
    link = ad.Link("j", ad.Joint(), ad.Inertial(1.0, name="j"), viscous=3.0, coulomb=(2.0, -1.0), gear_ratio=2.0)
    arm = ad.Robot([link])
    assert_allclose(lagrange.friction(arm, [[1.0], [-1.0], [0.0]]), [[16.0], [-14.0], [0.0]])


def test_bad_states_are_refused() -> None:
    arm = ad.models.puma560()
    with pytest.raises(ad.ModelError, match=r"q must have shape \(6,\) or \(\.\.\., 6\)"):
        lagrange.inertia_matrix(arm, np.zeros(5))
    with pytest.raises(ad.ModelError, match="qd must be finite"):
        lagrange.coriolis_matrix(arm, np.zeros(6), [0, 0, np.nan, 0, 0, 0])


# ----- Pinocchio on real URDFs ------------------------------------------------------------
def test_lagrange_equals_pinocchio(urdf_path: object) -> None:
    import pinocchio as pin

    arm, model, data, qi, vi = pinocchio_pair(urdf_path)
    arm = arm.without_friction()
    rng = np.random.default_rng(11)
    for _ in range(3):
        q, qd, qdd = (rng.uniform(-1.5, 1.5, arm.n) for _ in range(3))
        qp, vp, ap = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv)
        qp[qi], vp[vi], ap[vi] = q, qd, qdd
        M = pin.crba(model, data, qp)
        M = np.triu(M) + np.triu(M, 1).T
        cols = np.ix_(vi, vi)
        assert_allclose(lagrange.inertia_matrix(arm, q), M[cols], rtol=1e-10, atol=1e-12)
        assert_allclose(lagrange.gravity_vector(arm, q), pin.computeGeneralizedGravity(model, data, qp)[vi], atol=1e-10)
        C = pin.computeCoriolisMatrix(model, data, qp, vp)
        assert_allclose(lagrange.coriolis_matrix(arm, q, qd), C[cols], atol=1e-10)
        assert_allclose(lagrange.inverse_dynamics(arm, q, qd, qdd), pin.rnea(model, data, qp, vp, ap)[vi], atol=1e-10)
