"""The compiled kernels (RNEA, CRBA, Christoffel Coriolis, ABA, energies) against the
Lagrange-Euler reference, their identities, Pinocchio and the Robotics Toolbox."""

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

RELATIVE = 1e-10


def close(actual: np.ndarray, expected: np.ndarray, rtol: float = RELATIVE) -> None:
    """Equal to rtol relative to the size of the expected array (entries near zero included)."""
    assert_allclose(actual, expected, rtol=0, atol=rtol * (np.abs(expected).max() + 1e-300) + 1e-14)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 7))
def test_every_kernel_equals_the_lagrange_reference(seed: int, n: int) -> None:
    arm = random_robot(seed, n)
    q, qd, qdd = random_state(arm, seed)
    close(arm.inertia_matrix(q), lagrange.inertia_matrix(arm, q))
    close(arm.coriolis_matrix(q, qd), lagrange.coriolis_matrix(arm, q, qd))
    close(arm.coriolis_vector(q, qd), lagrange.coriolis_vector(arm, q, qd))
    close(arm.gravity_vector(q), lagrange.gravity_vector(arm, q))
    close(arm.friction(qd), lagrange.friction(arm, qd))
    close(
        arm.nonlinear_terms(q, qd),
        lagrange.coriolis_vector(arm, q, qd) + lagrange.friction(arm, qd) + lagrange.gravity_vector(arm, q),
    )
    close(arm.inverse_dynamics(q, qd, qdd), lagrange.inverse_dynamics(arm, q, qd, qdd))
    close(arm.inertia_matrix_dot(q, qd), lagrange.inertia_matrix_dot(arm, q, qd))
    close(np.array(arm.kinetic_energy(q, qd)), lagrange.kinetic_energy(arm, q, qd))
    close(np.array(arm.potential_energy(q)), lagrange.potential_energy(arm, q))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 7))
def test_the_robot_equation_identities(seed: int, n: int) -> None:
    arm = random_robot(seed, n)
    q, qd, qdd = random_state(arm, seed)
    M, Vm, F, G = arm.inertia_matrix(q), arm.coriolis_matrix(q, qd), arm.friction(qd), arm.gravity_vector(q)
    tau = arm.inverse_dynamics(q, qd, qdd)
    close(tau, M @ qdd + Vm @ qd + F + G)  # RNEA = M qdd + Vm qd + F + G
    close(arm.forward_dynamics(q, qd, tau), qdd)  # ABA inverts RNEA
    S = arm.inertia_matrix_dot(q, qd) - 2 * Vm
    assert np.abs(S + S.T).max() <= RELATIVE * (np.abs(Vm).max() + 1.0)  # Mdot - 2 Vm is skew
    x = np.random.default_rng(seed).uniform(-1, 1, n)
    close(arm.coriolis_matrix(q, x) @ qd, Vm @ x)  # Vm(q, x) y = Vm(q, y) x


def test_batches_are_one_call_and_match_single_states() -> None:
    arm = random_robot(5, 6)
    rng = np.random.default_rng(3)
    q, qd, qdd = (rng.uniform(-2, 2, (4, 3, 6)) for _ in range(3))
    tau = arm.inverse_dynamics(q, qd, qdd)
    results = {
        "inverse_dynamics": (tau, lambda i: arm.inverse_dynamics(q[i], qd[i], qdd[i])),
        "forward_dynamics": (arm.forward_dynamics(q, qd, tau), lambda i: arm.forward_dynamics(q[i], qd[i], tau[i])),
        "inertia_matrix": (arm.inertia_matrix(q), lambda i: arm.inertia_matrix(q[i])),
        "coriolis_matrix": (arm.coriolis_matrix(q, qd), lambda i: arm.coriolis_matrix(q[i], qd[i])),
        "gravity_vector": (arm.gravity_vector(q), lambda i: arm.gravity_vector(q[i])),
        "coriolis_vector": (arm.coriolis_vector(q, qd), lambda i: arm.coriolis_vector(q[i], qd[i])),
        "nonlinear_terms": (arm.nonlinear_terms(q, qd), lambda i: arm.nonlinear_terms(q[i], qd[i])),
        "friction": (arm.friction(qd), lambda i: arm.friction(qd[i])),
        "kinetic_energy": (arm.kinetic_energy(q, qd), lambda i: arm.kinetic_energy(q[i], qd[i])),
        "potential_energy": (arm.potential_energy(q), lambda i: arm.potential_energy(q[i])),
    }
    for name, (batch, single) in results.items():
        expected_shape = {"inertia_matrix": (4, 3, 6, 6), "coriolis_matrix": (4, 3, 6, 6)}.get(name, (4, 3, 6))
        if name.endswith("energy"):
            expected_shape = (4, 3)
        assert batch.shape == expected_shape, name
        for index in np.ndindex(4, 3):
            assert_allclose(batch[index], single(index), rtol=1e-13, atol=1e-13, err_msg=name)
    assert_allclose(tau[0], arm.inverse_dynamics(q[0], qd[0], qdd[0]), rtol=1e-14)


def test_batches_broadcast_and_accept_lists() -> None:
    arm = ad.models.puma560()
    q = np.tile(arm.qn, (5, 1))
    tau = arm.inverse_dynamics(q, np.zeros(6), [0.0] * 6)  # one qd and qdd for all five states
    assert tau.shape == (5, 6)
    assert_allclose(tau, np.tile(arm.gravity_vector(arm.qn), (5, 1)), atol=1e-12)
    assert_allclose(arm.gravity_vector(list(arm.qn)), arm.gravity_vector(arm.qn), atol=1e-12)
    assert arm.inverse_dynamics(np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 6))).shape == (0, 6)
    assert isinstance(arm.kinetic_energy(arm.qn, np.ones(6)), float)


def test_out_arrays_are_filled_in_place() -> None:
    arm = ad.models.puma560()
    out = np.empty(6)
    result = arm.inverse_dynamics(arm.qn, np.ones(6), np.ones(6), out=out)
    assert result is out
    M = np.empty((6, 6))
    assert arm.inertia_matrix(arm.qn, out=M) is M
    batch = np.empty((3, 6))
    assert arm.forward_dynamics(np.zeros((3, 6)), np.zeros((3, 6)), np.zeros((3, 6)), out=batch) is batch
    with pytest.raises(ad.ModelError, match=r"out must be a writable C-contiguous float64 array of shape \(3, 6\)"):
        arm.inverse_dynamics(np.zeros((3, 6)), np.zeros((3, 6)), np.zeros((3, 6)), out=np.empty((6,)))
    with pytest.raises(ad.ModelError, match=r"out must be a writable C-contiguous float64 array of shape \(6, 6\)"):
        arm.inertia_matrix(arm.qn, out=np.empty((5, 5)))


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda a: a.inverse_dynamics(np.zeros(5), np.zeros(6), np.zeros(6)), r"q must have shape \(6,\)"),
        (lambda a: a.inverse_dynamics(np.zeros(6), np.zeros(7), np.zeros(6)), r"qd must have shape \(6,\)"),
        (lambda a: a.inverse_dynamics(np.zeros(6), np.zeros(6), np.zeros(2)), r"qdd must have shape \(6,\)"),
        (lambda a: a.inverse_dynamics(np.zeros(6), np.zeros(6), np.full(6, np.inf)), "qdd must be finite"),
        (lambda a: a.forward_dynamics(np.zeros(6), np.zeros(6), np.zeros(4)), r"tau must have shape \(6,\)"),
        (lambda a: a.forward_dynamics(np.full(6, np.nan), np.zeros(6), np.zeros(6)), "q must be finite"),
        (lambda a: a.inertia_matrix(np.zeros(3)), r"q must have shape \(6,\)"),
        (lambda a: a.coriolis_matrix(np.zeros(6), [np.nan] * 6), "qd must be finite"),
        (lambda a: a.gravity_vector(np.zeros((2, 5))), r"q must have shape \(6,\) or \(\.\.\., 6\)"),
        (lambda a: a.kinetic_energy(np.zeros(6), np.zeros(3)), r"qd must have shape"),
        (lambda a: a.inverse_dynamics(np.zeros((2, 6)), np.zeros((3, 6)), np.zeros(6)), "do not broadcast"),
        (lambda a: a.inverse_dynamics(np.zeros(6), np.zeros(6), np.zeros(6), f_ext=[1, 2]), "f_ext must be"),
        (lambda a: a.inverse_dynamics("abc", np.zeros(6), np.zeros(6)), "q must be an array of numbers"),
    ],
)
def test_bad_inputs_name_the_argument(call: object, match: str) -> None:
    with pytest.raises(ad.ModelError, match=match):
        call(ad.models.puma560())


def test_symbolic_arms_have_no_numeric_kernels() -> None:
    arm = ad.models.two_link_planar(symbolic=True)
    with pytest.raises(ad.ModelError, match="symbolic parameters"):
        arm.inertia_matrix([0.0, 0.0])


def test_tool_wrench_adds_the_jacobian_transpose() -> None:
    arm = random_robot(9, 5)
    q, qd, qdd = random_state(arm, 9)
    wrench = np.array([1.0, -2.0, 0.5, 0.3, 0.2, -0.1])
    extra = arm.inverse_dynamics(q, qd, qdd, f_ext=wrench) - arm.inverse_dynamics(q, qd, qdd)
    close(extra, arm.jacobian(q, frame="tool").T @ wrench)
    batch = arm.inverse_dynamics(np.stack([q, q]), qd, qdd, f_ext=np.stack([wrench, 2 * wrench]))
    close(batch[1] - arm.inverse_dynamics(q, qd, qdd), 2 * extra)


# ----- the Robotics Toolbox's published PUMA 560 values --------------------------------------
def test_puma560_matches_the_toolbox() -> None:
    puma = ad.models.puma560()
    qn, zero, one = puma.qn, np.zeros(6), np.ones(6)
    assert_allclose(puma.gravity_vector(qn), [0, 31.6399, 6.0351, 0, 0.0283, 0], atol=1e-4)
    M = puma.inertia_matrix(qn)
    assert_allclose(np.diag(M), [3.6594, 4.4137, 0.9378, 0.1925, 0.1713, 0.1941], atol=1e-4)
    toolbox_M = [
        [3.6594, -0.4044, 0.1006, -0.0025, 0.0000, -0.0000],
        [-0.4044, 4.4137, 0.3509, 0.0000, 0.0024, 0.0000],
        [0.1006, 0.3509, 0.9378, 0.0000, 0.0015, 0.0000],
        [-0.0025, 0.0000, 0.0000, 0.1925, 0.0000, 0.0000],
        [0.0000, 0.0024, 0.0015, 0.0000, 0.1713, 0.0000],
        [-0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.1941],
    ]
    assert_allclose(M, toolbox_M, atol=1e-4)
    qd, tau = [0.1, 0.2, 0.8, 0.2, 0.5, 1.0], [1.0, 3.2, 1.8, 0.1, 0.7, 4.6]
    assert_allclose(
        puma.forward_dynamics(qn, np.array(qd), np.array(tau)),
        [-7.4102, -9.8432, -10.9694, -4.4314, -0.9881, 21.0228],
        atol=1e-4,
    )
    rne = [
        (zero, one, None, [3.35311, 36.0025, 7.42596, 0.190043, 0.203441, 0.194133]),
        (one, one, None, [32.4952, 60.867, 17.7436, 1.45452, 1.29911, 0.713781]),
        (one, zero, None, [29.1421, 56.5044, 16.3528, 1.26448, 1.12392, 0.519648]),
        (zero, zero, [1, 2, 3, 1, 2, 3], [0.642756, 29.0866, 4.70321, 2.82843, -1.97175, 3]),
    ]
    for qd_, qdd_, wrench, expected in rne:
        assert_allclose(puma.inverse_dynamics(qn, qd_, qdd_, f_ext=wrench), expected, rtol=2e-5, atol=1e-5)
    assert_allclose(puma.with_gravity([0, 0, 0]).inverse_dynamics(qn, one, one),
                    [32.4952, 29.2271, 11.7085, 1.45452, 1.27086, 0.713781], rtol=2e-5, atol=1e-5)  # fmt: skip


def test_puma560_coriolis_vector_matches_the_toolbox_coriolis() -> None:
    """The Toolbox's C(q, qd) is another factorisation, but C qd = V is unique."""
    puma = ad.models.puma560()
    qd = np.array([1.0, 2, 3, 1, 2, 3])
    toolbox_C = np.array(
        [
            [-0.1735, -2.0494, -0.1178, -0.0002, -0.0045, 0.0001],
            [0.6274, 1.1572, 1.9287, -0.0015, -0.0003, -0.0000],
            [-0.3608, -0.7734, -0.0018, -0.0009, -0.0064, -0.0000],
            [0.0011, 0.0005, -0.0001, 0.0002, 0.0002, -0.0001],
            [-0.0002, 0.0028, 0.0046, -0.0002, -0.0000, -0.0000],
            [0.0001, 0.0000, 0.0000, 0.0000, 0.0000, 0],
        ]
    )
    assert_allclose(puma.coriolis_vector(puma.qn, qd), toolbox_C @ qd, atol=2e-3)


# ----- Pinocchio on real URDFs ---------------------------------------------------------------
def test_kernels_equal_pinocchio(urdf_path: object) -> None:
    import pinocchio as pin

    arm, model, data, qi, vi = pinocchio_pair(urdf_path)
    arm = arm.without_friction()
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, qdd = (rng.uniform(-2, 2, arm.n) for _ in range(3))
        qp, vp, ap = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv)
        qp[qi], vp[vi], ap[vi] = q, qd, qdd
        cols = np.ix_(vi, vi)
        M = pin.crba(model, data, qp)
        close(arm.inertia_matrix(q), (np.triu(M) + np.triu(M, 1).T)[cols], 1e-9)
        close(arm.coriolis_matrix(q, qd), pin.computeCoriolisMatrix(model, data, qp, vp)[cols], 1e-9)
        close(arm.gravity_vector(q), pin.computeGeneralizedGravity(model, data, qp)[vi], 1e-9)
        tau = pin.rnea(model, data, qp, vp, ap)[vi]
        close(arm.inverse_dynamics(q, qd, qdd), tau, 1e-9)
        taup = np.zeros(model.nv)
        taup[vi] = tau
        close(arm.forward_dynamics(q, qd, tau), pin.aba(model, data, qp, vp, taup)[vi], 1e-9)
        close(np.array(arm.kinetic_energy(q, qd)), np.array(pin.computeKineticEnergy(model, data, qp, vp)), 1e-9)


def test_vectorizable_sin_cos_is_accurate() -> None:
    from armdyn.dynamics.spatial import sin_cos

    for x in np.concatenate([np.linspace(-100, 100, 20001), [0.0, np.pi / 4, np.pi / 2, np.pi, -np.pi / 2]]):
        s, c = sin_cos(x)
        assert abs(s - np.sin(x)) <= 4e-16 and abs(c - np.cos(x)) <= 4e-16


def test_vectorized_batch_equals_the_one_state_kernel() -> None:
    arm = random_robot(21, 7)
    rng = np.random.default_rng(2)
    q, qd, qdd = (rng.uniform(-3, 3, (77, 7)) for _ in range(3))  # not a whole number of blocks
    batch = arm.inverse_dynamics(q, qd, qdd)
    for k in (0, 31, 32, 76):
        close(batch[k], arm.inverse_dynamics(q[k], qd[k], qdd[k]), 1e-13)


@pytest.mark.parametrize("n", [3, 60])
def test_one_state_scratch_on_the_stack_or_the_heap_gives_the_batch_result(n: int) -> None:
    """A one-state kernel keeps its scratch on the stack up to spatial.STACK_SCRATCH values and on
    the heap beyond (a 60-joint arm); either way it equals the batch kernels, which use the heap."""
    from armdyn.dynamics.packed import ABA_JOINT
    from armdyn.dynamics.spatial import STACK_SCRATCH

    assert (ABA_JOINT * n > STACK_SCRATCH) == (n == 60)
    arm = random_robot(11, n)
    rng = np.random.default_rng(n)
    q, qd, qdd = rng.uniform(-1, 1, (3, 2, n))
    for name, args in [
        ("inverse_dynamics", (q, qd, qdd)),
        ("forward_dynamics", (q, qd, qdd)),
        ("inertia_matrix", (q,)),
        ("coriolis_matrix", (q, qd)),
        ("gravity_vector", (q,)),
        ("energies", (q, qd)),
        ("jacobian_dot", (q, qd)),
    ]:
        method = getattr(arm, name)
        batch = method(*args)
        for s in range(2):
            assert_allclose(method(*(a[s] for a in args)), batch[s], rtol=1e-13, atol=1e-13, err_msg=name)


def test_small_batches_run_on_the_calling_thread_and_leave_the_thread_count() -> None:
    """A batch below api.SERIAL_WORK result values runs on one thread (waking the idle threads
    costs more than the work), a larger one on all; either way the thread count is restored
    and the numbers are those of the one-state calls."""
    from armdyn.dynamics import api

    arm = ad.models.puma560()
    threads = ad.threads()
    for states in (3, api.SERIAL_WORK // arm.n + 1):
        q = np.random.default_rng(states).uniform(-1, 1, (states, arm.n))
        tau = arm.inverse_dynamics(q, q, q)
        assert ad.threads() == threads
        assert_allclose(tau[-1], arm.inverse_dynamics(q[-1], q[-1], q[-1]), rtol=1e-13, atol=1e-12)
