"""Analytic derivatives of the inverse and forward dynamics against complex-step and Pinocchio."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import armdyn as ad
from armdyn.dynamics import lagrange
from armdyn.errors import ModelError
from tests.helpers import URDFS
from tests.strategies import random_robot, random_state


def complex_step(arm: ad.Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d tau/dq and d tau/dqd by complex-step differentiation of the Lagrange-Euler reference (exact to rounding):
    friction enters d tau/dqd through its viscous part only, Coulomb friction being constant off zero velocity."""
    bare, n, h = arm.without_friction(), arm.n, 1e-30
    d_q, d_qd = np.empty((n, n)), np.empty((n, n))
    for j in range(n):
        for target, matrix in ((0, d_q), (1, d_qd)):
            state = [q.astype(complex), qd.astype(complex), qdd.astype(complex)]
            state[target][j] += 1j * h
            matrix[:, j] = lagrange.inverse_dynamics(bare, *state).imag / h
    return d_q, d_qd + np.diag(arm.viscous_friction)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 6))
def test_inverse_dynamics_derivatives_equal_complex_step_on_random_trees(seed: int, n: int) -> None:
    """Random trees with revolute and prismatic joints along any axis, motors and friction."""
    arm = random_robot(seed, n)
    q, qd, qdd = random_state(arm, seed)
    d_q, d_qd = arm.inverse_dynamics_derivatives(q, qd, qdd)
    expected_q, expected_qd = complex_step(arm, q, qd, qdd)
    for got, expected in ((d_q, expected_q), (d_qd, expected_qd)):
        assert np.abs(got - expected).max() <= 1e-9 * max(1.0, np.abs(expected).max())


def test_a_batch_is_its_states_and_out_is_written() -> None:
    arm = ad.models.puma560()
    rng = np.random.default_rng(4)
    Q, QD, QDD = rng.uniform(-1, 1, (3, 2, 5, 6))
    d_q, d_qd = arm.inverse_dynamics_derivatives(Q, QD, QDD)
    assert d_q.shape == (2, 5, 6, 6)
    one_q, one_qd = arm.inverse_dynamics_derivatives(Q[1, 3], QD[1, 3], QDD[1, 3])
    assert np.array_equal(d_q[1, 3], one_q) and np.array_equal(d_qd[1, 3], one_qd)
    out = (np.empty((6, 6)), np.empty((6, 6)))
    written = arm.inverse_dynamics_derivatives(Q[0, 0], QD[0, 0], QDD[0, 0], out=out)
    assert written[0] is out[0] and np.array_equal(out[0], d_q[0, 0])
    forward = arm.forward_dynamics_derivatives(Q, QD, QDD, out=tuple(np.empty((2, 5, 6, 6)) for _ in range(3)))
    assert np.allclose(forward[2][0, 1], np.linalg.inv(arm.inertia_matrix(Q[0, 1])))


def test_one_state_out_goes_to_the_kernel_and_refuses_shared_memory() -> None:
    arm = ad.models.puma560()
    q, qd, tau = np.random.default_rng(5).uniform(-1, 1, (3, 6))
    fresh = arm.forward_dynamics_derivatives(q, qd, tau)
    out = [np.full((6, 6), np.nan) for _ in range(3)]
    written = arm.forward_dynamics_derivatives(q, qd, tau, out=out)
    assert all(w is o for w, o in zip(written, out, strict=True))
    for got, want in zip(out, fresh, strict=True):
        np.testing.assert_array_equal(got, want)
    pair = (np.full((6, 6), np.nan), np.full((6, 6), np.nan))
    arm.inverse_dynamics_derivatives(q, qd, tau, out=pair)
    for got, want in zip(pair, arm.inverse_dynamics_derivatives(q, qd, tau), strict=True):
        np.testing.assert_array_equal(got, want)
    block = np.zeros((3, 6, 6))
    with pytest.raises(ModelError, match="share memory"):
        arm.forward_dynamics_derivatives(q, qd, tau, out=(block[0], block[1], block[0]))
    states = np.zeros((7, 6))  # q is the first row, the output the next six: one span, apart
    apart = arm.inverse_dynamics_derivatives(states[0], qd, tau, out=(np.zeros((6, 6)), states[1:]))
    np.testing.assert_array_equal(apart[0], arm.inverse_dynamics_derivatives(np.zeros(6), qd, tau)[0])
    with pytest.raises(ModelError, match="shares memory with a state"):
        arm.inverse_dynamics_derivatives(states[1], qd, tau, out=(np.zeros((6, 6)), states[1:]))


def test_forward_dynamics_derivatives_equal_central_differences_of_aba() -> None:
    arm = ad.models.stanford()
    rng = np.random.default_rng(2)
    q, qd, tau = rng.uniform(-1, 1, (3, 6)) + [0, 0, 0.8, 0, 0, 0]
    d_q, d_qd, d_tau = arm.forward_dynamics_derivatives(q, qd, tau)
    for variable, got in ((0, d_q), (1, d_qd), (2, d_tau)):
        expected = np.empty((6, 6))
        for j in range(6):
            h = 1e-6
            plus, minus = [q.copy(), qd.copy(), tau.copy()], [q.copy(), qd.copy(), tau.copy()]
            plus[variable][j] += h
            minus[variable][j] -= h
            expected[:, j] = (arm.forward_dynamics(*plus) - arm.forward_dynamics(*minus)) / (2 * h)
        assert np.abs(got - expected).max() <= 1e-7 * np.abs(expected).max()


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_pinocchio_rnea_and_aba_derivatives(robot: str) -> None:
    """computeRNEADerivatives and computeABADerivatives of Pinocchio on the same URDF, without friction (which
    Pinocchio's derivatives leave out)."""
    pin = pytest.importorskip("pinocchio")
    path = URDFS[robot]
    arm = ad.load_urdf(path).without_friction() if robot != "panda" else _panda(path)
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-1.5, 1.5, (3, arm.n))
        d_q, d_qd = arm.inverse_dynamics_derivatives(q, qd, qdd)
        pin.computeRNEADerivatives(model, data, q, qd, qdd)
        for got, expected in ((d_q, data.dtau_dq), (d_qd, data.dtau_dv)):
            assert np.abs(got - expected).max() <= 1e-9 * np.abs(expected).max()
        tau = arm.inverse_dynamics(q, qd, qdd)
        forward = arm.forward_dynamics_derivatives(q, qd, tau)
        pin.computeABADerivatives(model, data, q, qd, tau)
        for got, expected in zip(forward, (data.ddq_dq, data.ddq_dv, data.Minv), strict=True):
            assert np.abs(got - expected).max() <= 1e-9 * np.abs(expected).max()


def _panda(path: object) -> ad.Robot:
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its mimic finger joint is loaded as an independent joint
        return ad.load_urdf(path).without_friction()


def test_bad_states_and_outs_are_model_errors() -> None:
    arm = ad.models.two_link_planar()
    with pytest.raises(ModelError, match="qd"):
        arm.inverse_dynamics_derivatives([0.0, 0.0], [np.nan, 0.0], [0.0, 0.0])
    with pytest.raises(ModelError, match="out must be"):
        arm.inverse_dynamics_derivatives([0.0, 0.0], [0.0, 0.0], [0.0, 0.0], out=np.empty((2, 2)))
    with pytest.raises(ModelError, match="singular"):
        ad.models.polar_rp().forward_dynamics_derivatives([0.0, 0.0], [0.0, 0.0], [0.0, 0.0])


@pytest.mark.parametrize("name", ad.models.names())
def test_linearize_equals_the_complex_step_route(name: str) -> None:
    """statespace.linearize (analytic derivatives) equals the former route: dID/dq by complex step through the
    Lagrange-Euler reference, dID/dqd = 2 Vm + Fv, to 1e-10 relative, on every built-in arm."""
    arm = ad.models.load(name)
    rng = np.random.default_rng(7)
    q0 = np.asarray(arm.configurations.get("qn", arm.configurations.get("qz", np.zeros(arm.n))), float)
    q0 = q0 + rng.uniform(-0.3, 0.3, arm.n)
    qd0, tau0 = rng.uniform(0.2, 1.0, arm.n), rng.uniform(-1, 1, arm.n)
    new = ad.statespace.linearize(arm, q0, qd0, tau0)
    qdd0 = arm.forward_dynamics(q0, qd0, tau0)
    d_q = complex_step(arm, q0, qd0, qdd0)[0]
    d_qd = 2 * arm.coriolis_matrix(q0, qd0) + np.diag(arm.viscous_friction)
    inverse = np.linalg.inv(arm.inertia_matrix(q0))
    n = arm.n
    for got, expected in ((new.A[n:, :n], -inverse @ d_q), (new.A[n:, n:], -inverse @ d_qd), (new.B[n:], inverse)):
        assert np.abs(got - expected).max() <= 1e-10 * max(1.0, np.abs(expected).max())


def test_the_rk4_step_and_its_derivatives() -> None:
    """statespace.rk4_step takes simulate's compiled RK4 step (the same state to rounding), and its (A_d, B_d)
    equal central differences of that compiled step to 1e-7 relative (the differences' own error)."""
    arm = ad.models.puma560().without_friction()
    rng = np.random.default_rng(11)
    q, qd, tau = rng.uniform(-1, 1, (3, 6))
    dt = 1e-2

    def compiled_step(x: np.ndarray, torque: np.ndarray) -> np.ndarray:
        run = ad.simulate(arm, None, None, t_final=dt, dt=dt, q0=x[:6], qd0=x[6:], disturbance=-torque)
        return np.concatenate([run.q[-1], run.qd[-1]])

    x = np.concatenate([q, qd])
    step, A_d, B_d = ad.statespace.rk4_step(arm, q, qd, tau, dt)
    assert np.abs(step - compiled_step(x, tau)).max() < 1e-14
    h = 1e-6
    for matrix, size, vary in ((A_d, 12, lambda e: (x + e, tau)), (B_d, 6, lambda e: (x, tau + e))):
        expected = np.empty_like(matrix)
        for j in range(size):
            e = np.zeros(size)
            e[j] = h
            expected[:, j] = (compiled_step(*vary(e)) - compiled_step(*vary(-e))) / (2 * h)
        assert np.abs(matrix - expected).max() <= 1e-7 * np.abs(expected).max()
    with pytest.raises(ModelError, match="dt must be positive"):
        ad.statespace.rk4_step(arm, q, qd, tau, 0.0)
    with pytest.raises(ModelError, match="one state"):
        ad.statespace.rk4_step(arm, np.zeros((2, 6)), qd, tau, dt)


def _reference_rates(arm: ad.Robot, x: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """xdot = [qd; M^-1 (tau - N)] by the Lagrange-Euler reference, complex-safe (an arm without friction)."""
    n = arm.n
    q, qd = x[:n], x[n:]
    bias = lagrange.inverse_dynamics(arm, q, qd, np.zeros(n, dtype=x.dtype))
    gravity = lagrange.inverse_dynamics(arm, q, np.zeros(n, dtype=x.dtype), np.zeros(n, dtype=x.dtype))
    M = np.column_stack([lagrange.inverse_dynamics(arm, q, np.zeros(n, dtype=x.dtype), e) - gravity
                         for e in np.eye(n, dtype=x.dtype)])  # fmt: skip
    return np.concatenate([qd, np.linalg.solve(M, tau - bias)])


@pytest.mark.slow
def test_the_rk4_step_derivatives_equal_complex_step_through_the_reference_step() -> None:
    """(A_d, B_d) of statespace.rk4_step equal complex-step derivatives of the same RK4 step taken with the
    Lagrange-Euler reference, to 1e-10 relative (and the step itself equals the compiled one, test above)."""
    arm = ad.models.puma560().without_friction()
    rng = np.random.default_rng(12)
    q, qd, tau = rng.uniform(-1, 1, (3, 6))
    dt, h = 2e-2, 1e-30

    def reference_step(x: np.ndarray, torque: np.ndarray) -> np.ndarray:
        k1 = _reference_rates(arm, x, torque)
        k2 = _reference_rates(arm, x + dt / 2 * k1, torque)
        k3 = _reference_rates(arm, x + dt / 2 * k2, torque)
        k4 = _reference_rates(arm, x + dt * k3, torque)
        return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    x = np.concatenate([q, qd]).astype(complex)
    step, A_d, B_d = ad.statespace.rk4_step(arm, q, qd, tau, dt)
    assert np.abs(step - reference_step(x, tau.astype(complex)).real).max() < 1e-12
    for matrix, size, vary in ((A_d, 12, lambda e: (x + e, tau.astype(complex))), (B_d, 6, lambda e: (x, tau + e))):
        expected = np.column_stack([reference_step(*vary(1j * h * e)).imag / h for e in np.eye(size)])
        assert np.abs(matrix - expected).max() <= 1e-10 * np.abs(expected).max()


def test_smoothed_coulomb_friction_enters_both_derivatives() -> None:
    """With coulomb_smoothing = eps, d tau/dqd gains the slope of tanh(qd / eps) Tc (complex step of that law), and
    the forward-dynamics derivatives are those of the plant that follows it (central differences)."""
    arm = ad.models.puma560()
    assert np.any(arm.coulomb_friction != 0)
    rng = np.random.default_rng(13)
    q, qdd, tau = rng.uniform(-1, 1, (3, 6))
    qd = rng.uniform(-0.02, 0.02, 6)  # inside the smoothing band, where the slope is large
    eps, table = 0.01, arm.coulomb_friction
    exact_q, exact_qd = arm.inverse_dynamics_derivatives(q, qd, qdd)
    d_q, d_qd = arm.inverse_dynamics_derivatives(q, qd, qdd, coulomb_smoothing=eps)
    slope = np.array([smooth_law(table, eps, qd + 1j * 1e-30 * e).imag / 1e-30 for e in np.eye(6)]).T
    assert np.array_equal(d_q, exact_q)
    assert np.abs(d_qd - (exact_qd + slope)).max() <= 1e-12 * np.abs(d_qd).max()
    assert np.abs(np.diag(slope)).min() > 1.0

    def plant(q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        exact = np.where(qd > 0, table[:, 0], np.where(qd < 0, table[:, 1], 0.0))
        return arm.forward_dynamics(q, qd, tau - smooth_law(table, eps, qd) + exact)

    forward = arm.forward_dynamics_derivatives(q, qd, tau, coulomb_smoothing=[eps] * 6)
    for variable, got in enumerate(forward):
        expected = np.empty((6, 6))
        for j in range(6):
            step = 1e-7
            plus, minus = [q.copy(), qd.copy(), tau.copy()], [q.copy(), qd.copy(), tau.copy()]
            plus[variable][j] += step
            minus[variable][j] -= step
            expected[:, j] = (plant(*plus) - plant(*minus)) / (2 * step)
        assert np.abs(got - expected).max() <= 1e-6 * np.abs(expected).max()
    with pytest.raises(ModelError, match="coulomb_smoothing"):
        arm.inverse_dynamics_derivatives(q, qd, qdd, coulomb_smoothing=-1.0)
    with pytest.raises(ModelError, match="coulomb_smoothing"):
        arm.forward_dynamics_derivatives(q, qd, tau, coulomb_smoothing=[0.1, 0.1])


def smooth_law(table: np.ndarray, eps: float, qd: np.ndarray) -> np.ndarray:
    """tanh(qd / eps) Tc+ for qd >= 0, -tanh(qd / eps) Tc- below (friction.smooth_coulomb), complex-safe."""
    smooth = np.tanh(qd / eps)
    return np.where(qd.real >= 0, smooth * table[:, 0], -smooth * table[:, 1])


def test_the_kernel_gives_M_with_the_derivatives() -> None:
    """The recursion yields M(q) on the way (d tau/dqdd); the kernel writes it when asked."""
    from armdyn.dynamics.derivatives import rnea_derivatives_one

    arm = ad.models.stanford()
    rng = np.random.default_rng(14)
    q, qd, qdd = rng.uniform(-1, 1, (3, 6))
    d_q, d_qd, M = np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6))
    assert rnea_derivatives_one(arm.packed, q, qd, qdd, np.zeros(6), d_q, d_qd, M) == 0
    assert np.abs(M - arm.inertia_matrix(q)).max() <= 1e-13 * np.abs(M).max()
    assert rnea_derivatives_one(arm.packed, q, qd, qdd, np.zeros(5), d_q, d_qd, M) == 4


def test_a_singular_state_in_a_batch_is_named() -> None:
    arm = ad.models.polar_rp()
    q = np.array([[0.0, 1.0], [0.0, 0.0]])
    with pytest.raises(ModelError, match=r"singular at state \(1,\)"):
        arm.forward_dynamics_derivatives(q, np.zeros((2, 2)), np.zeros((2, 2)))


def test_the_rk4_step_with_smoothed_coulomb_friction_is_simulates_step() -> None:
    """rk4_step(coulomb_smoothing=eps) takes the step simulate takes with that smoothing, and its derivatives
    equal central differences of simulate's step; linearize at rest needs the smoothing."""
    arm = ad.models.puma560()
    rng = np.random.default_rng(15)
    q, tau = rng.uniform(-1, 1, (2, 6))
    qd = rng.uniform(-0.01, 0.01, 6)
    dt, eps = 5e-3, 0.02

    def compiled_step(x: np.ndarray) -> np.ndarray:
        run = ad.simulate(arm, None, None, t_final=dt, dt=dt, q0=x[:6], qd0=x[6:], disturbance=-tau,
                          coulomb_smoothing=eps)  # fmt: skip
        return np.concatenate([run.q[-1], run.qd[-1]])

    x = np.concatenate([q, qd])
    step, A_d, _ = ad.statespace.rk4_step(arm, q, qd, tau, dt, coulomb_smoothing=eps)
    assert np.abs(step - compiled_step(x)).max() < 1e-13
    h = 1e-7
    expected = np.column_stack([(compiled_step(x + h * e) - compiled_step(x - h * e)) / (2 * h) for e in np.eye(12)])
    assert np.abs(A_d - expected).max() <= 1e-6 * np.abs(expected).max()
    with pytest.raises(ModelError, match="not differentiable at zero velocity"):
        ad.statespace.linearize(arm, q, np.zeros(6), tau)
    smoothed = ad.statespace.linearize(arm, q, np.zeros(6), tau, coulomb_smoothing=eps)
    slope = np.diag(arm.coulomb_friction[:, 0] / eps)  # tanh'(0) Tc+ / eps
    inverse = np.linalg.inv(arm.inertia_matrix(q))
    exact_qd = 2 * arm.coriolis_matrix(q, np.zeros(6)) + np.diag(arm.viscous_friction)
    assert np.allclose(smoothed.A[6:, 6:], -inverse @ (exact_qd + slope), rtol=1e-10, atol=1e-12)
