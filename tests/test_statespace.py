"""State-variable forms: position/velocity, feedback linearization, Hamiltonian, linearization."""

from __future__ import annotations

import numpy as np
import pytest
import sympy
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn import statespace as ss
from armdyn.symbolic import derive
from tests.strategies import random_robot


def test_drift_and_input_give_the_state_derivative() -> None:
    arm = random_robot(4, 4)
    rng = np.random.default_rng(0)
    x, tau = rng.uniform(-1, 1, 8), rng.uniform(-1, 1, 4)
    f, g = ss.drift_and_input(arm, x)
    assert_allclose(f + g @ tau, ss.state_derivative(arm, x, tau), atol=1e-12)
    A, B = ss.brunovsky(3)
    assert A.shape == (6, 6) and B.shape == (6, 3) and A[:3, 3:].tolist() == np.eye(3).tolist()


def test_feedback_linearization_makes_the_output_a_double_integrator() -> None:
    arm = ad.models.two_link_planar()
    q, qd, u = np.array([0.4, 0.9]), np.array([0.3, -0.5]), np.array([1.5, -2.0])

    def jacobian(q: np.ndarray) -> np.ndarray:
        return arm.jacobian(q)[:2]  # the tip position in the plane

    def jdot_qd(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return arm.jacobian_dot(q, qd)[:2] @ qd

    tau = ss.linearizing_torque(arm, q, qd, u, jacobian, jdot_qd)
    qdd = arm.forward_dynamics(q, qd, tau)
    assert_allclose(jacobian(q) @ qdd + jdot_qd(q, qd), u, atol=1e-10)  # yddot = u
    assert_allclose(arm.forward_dynamics(q, qd, ss.linearizing_torque(arm, q, qd, u)), u, atol=1e-10)


def rk4(rate: object, x: np.ndarray, dt: float, steps: int) -> np.ndarray:
    for _ in range(steps):
        k1 = rate(x)
        k2 = rate(x + dt / 2 * k1)
        k3 = rate(x + dt / 2 * k2)
        k4 = rate(x + dt * k3)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def test_hamiltonian_and_position_velocity_forms_give_the_same_trajectory() -> None:
    arm = random_robot(8, 3, chain=True)
    n, tau = 3, np.array([0.5, -0.2, 0.1])
    q0, qd0 = np.array([0.2, -0.4, 0.3]), np.array([0.1, 0.5, -0.3])

    def hamiltonian(x: np.ndarray) -> np.ndarray:
        return np.concatenate(ss.hamiltonian_rates(arm, x[:n], x[n:], tau))

    x = rk4(lambda x: ss.state_derivative(arm, x, tau), np.concatenate([q0, qd0]), 1e-3, 500)
    p0 = arm.inertia_matrix(q0) @ qd0
    z = rk4(hamiltonian, np.concatenate([q0, p0]), 1e-3, 500)
    assert_allclose(z[:n], x[:n], atol=1e-9)
    assert_allclose(np.linalg.solve(arm.inertia_matrix(z[:n]), z[n:]), x[n:], atol=1e-9)
    bare = arm.without_friction()
    h0 = ss.hamiltonian(bare, q0, p0)
    assert_allclose(h0, bare.kinetic_energy(q0, qd0) + bare.potential_energy(q0), rtol=1e-12)


def test_linearization_equals_the_analytic_derivative_of_the_closed_form() -> None:
    arm = ad.models.two_link_planar(1.3, 0.8, 0.9, 1.1)
    form = derive(arm, friction=False)
    q, qd, tau = form.q, form.qd, sympy.Matrix(sympy.symbols("t1 t2"))
    qdd = form.M.LUsolve(tau - form.V - form.G)
    state = list(q) + list(qd)
    point = {q[0]: 0.3, q[1]: -0.7, qd[0]: 0.4, qd[1]: -0.2, tau[0]: 2.0, tau[1]: -1.0}
    exact = np.array(qdd.jacobian(state).subs(point).evalf(30), dtype=float)
    exact_b = np.array(qdd.jacobian(tau).subs(point).evalf(30), dtype=float)
    lin = ss.linearize(arm, [0.3, -0.7], [0.4, -0.2], [2.0, -1.0])
    assert_allclose(lin.A[2:], exact, rtol=1e-11, atol=1e-12)
    assert_allclose(lin.B[2:], exact_b, rtol=1e-11, atol=1e-12)
    assert_allclose(lin.A[:2], np.hstack([np.zeros((2, 2)), np.eye(2)]))


def test_linearization_of_a_friction_arm_and_its_state_space() -> None:
    arm = ad.models.puma560()
    with pytest.raises(ad.ModelError, match="not differentiable at zero velocity"):
        ss.linearize(arm, arm.qn, np.zeros(6), np.zeros(6))
    qd0 = np.array([0.1, 0.2, -0.3, 0.4, 0.5, -0.6])
    lin = ss.linearize(arm, arm.qn, qd0, np.ones(6))
    h = 1e-6
    x0 = np.concatenate([arm.qn, qd0])
    central = np.column_stack(
        [(ss.state_derivative(arm, x0 + h * e, np.ones(6)) - ss.state_derivative(arm, x0 - h * e, np.ones(6))) / (2 * h)
         for e in np.eye(12)]
    )  # fmt: skip
    assert_allclose(lin.A, central, atol=1e-6 * np.abs(central).max())
    system = lin.to_control()
    assert system.nstates == 12 and system.ninputs == 6


# ----- batches and arguments --------------------------------------------------------------
@pytest.mark.parametrize("batch", [(2,), (3,), (2, 4)], ids=["n states", "3 states", "2x4"])
def test_linearizing_torque_of_a_batch_has_the_batch_shape(batch: tuple[int, ...]) -> None:
    arm = ad.models.two_link_planar()  # n = 2: a batch of n states once gave (n, n, n)
    rng = np.random.default_rng(1)
    q, qd, u = rng.uniform(-1, 1, (3, *batch, 2))

    def jacobian(q: np.ndarray) -> np.ndarray:
        return arm.jacobian(q)[..., :2, :]

    def jdot_qd(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return np.einsum("...ij,...j->...i", arm.jacobian_dot(q, qd)[..., :2, :], qd)

    for output in ((), (jacobian, jdot_qd)):
        tau = ss.linearizing_torque(arm, q, qd, u, *output)
        assert tau.shape == (*batch, 2)
        for index in np.ndindex(batch):
            assert_allclose(tau[index], ss.linearizing_torque(arm, q[index], qd[index], u[index], *output), atol=1e-12)
    tau = ss.linearizing_torque(arm, q, qd, np.array([1.0, -2.0]))  # one u for every state
    assert_allclose(arm.forward_dynamics(q, qd, tau), np.broadcast_to([1.0, -2.0], (*batch, 2)), atol=1e-9)


def test_hamiltonian_forms_take_batches() -> None:
    arm = random_robot(3, 3, chain=True)
    rng = np.random.default_rng(2)
    q, p, tau = rng.uniform(-1, 1, (3, 4, 3))
    H = ss.hamiltonian(arm, q, p)
    qdot, pdot = ss.hamiltonian_rates(arm, q, p, tau)
    assert H.shape == (4,) and qdot.shape == pdot.shape == (4, 3)
    for i in range(4):
        assert_allclose(H[i], ss.hamiltonian(arm, q[i], p[i]), rtol=1e-12)
        assert_allclose(pdot[i], ss.hamiltonian_rates(arm, q[i], p[i], tau[i])[1], atol=1e-12)
    assert isinstance(ss.hamiltonian(arm, q[0], p[0]), float)
    x = np.concatenate([q, p], -1)
    assert ss.state_derivative(arm, x[0], tau).shape == (4, 6)  # one state, a batch of torques


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda arm: ss.state_derivative(arm, "x", [0, 0]), ad.ModelError, r"x must be an array of numbers"),
        (lambda arm: ss.state_derivative(arm, None, [0, 0]), ad.ModelError, r"x must be an array of numbers"),
        (lambda arm: ss.state_derivative(arm, [0, 0, 0], [0, 0]), ad.ModelError, r"x must have shape \(4,\)"),
        (lambda arm: ss.state_derivative(arm, [0] * 4, {"tau": 1}), ad.ModelError, "tau must be"),
        (lambda arm: ss.state_derivative("arm", [0] * 4, [0, 0]), TypeError, "arm must be an armdyn Robot"),
        (lambda arm: ss.drift_and_input(arm, {"x": 1}), ad.ModelError, "x must be an array of numbers"),
        (lambda arm: ss.drift_and_input(None, [0] * 4), TypeError, "arm must be an armdyn Robot"),
        (lambda arm: ss.brunovsky("3"), TypeError, "n must be an integer"),
        (lambda arm: ss.brunovsky(2.5), TypeError, "n must be an integer"),
        (lambda arm: ss.brunovsky(True), TypeError, "n must be an integer"),
        (lambda arm: ss.brunovsky(0), ad.ModelError, "n must be at least 1"),
        (lambda arm: ss.brunovsky(10**30), ad.ModelError, "n must be a number of joints for which A"),
        (lambda arm: ss.linearizing_torque(arm, "q", [0, 0], [0, 0]), ad.ModelError, "q must be an array"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], None, [0, 0]), ad.ModelError, "qd must be an array"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], [0, 0], {"u": 1}), ad.ModelError, "u must be an array"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], [0, 0], [0, 0, 0]), ad.ModelError, r"u must have shape"),
        (lambda arm: ss.linearizing_torque(arm, np.zeros((3, 2)), [0, 0], np.zeros((4, 2))), ad.ModelError,
         r"batch shapes of q \(3, 2\), qd \(2,\), u \(4, 2\)"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], [0, 0], [0, 0], "J"), TypeError,
         "output_jacobian must be a callable"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], [0, 0], [0, 0], lambda q: np.ones(2)), ad.ModelError,
         r"output_jacobian\(q\) must return an \(m, 2\) matrix"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], [0, 0], [0], lambda q: np.ones((1, 2)), lambda q, qd: "a"),
         ad.ModelError, r"output_jacobian_dot_qd\(q, qd\) must be"),
        (lambda arm: ss.linearizing_torque(arm, [0, 0], [0, 0], [0, 0], None, lambda q, qd: 0), ad.ModelError,
         "output_jacobian_dot_qd needs output_jacobian"),
        (lambda arm: ss.hamiltonian(arm, [0, 0], "p"), ad.ModelError, "p must be an array of numbers"),
        (lambda arm: ss.hamiltonian(arm, None, [0, 0]), ad.ModelError, "q must be an array of numbers"),
        (lambda arm: ss.hamiltonian_rates(arm, [0, 0], [0, 0], None), ad.ModelError, "tau must be an array"),
        (lambda arm: ss.hamiltonian_rates(arm, [0, 0], {"p": 0}, [0, 0]), ad.ModelError, "p must be an array"),
        (lambda arm: ss.linearize(arm, "q", [1, 1], [0, 0]), ad.ModelError, "q0 must be an array of numbers"),
        (lambda arm: ss.linearize(arm, [0, 0], None, [0, 0]), ad.ModelError, "qd0 must be an array of numbers"),
        (lambda arm: ss.linearize(arm, np.zeros((2, 2)), [1, 1], [0, 0]), ad.ModelError, "q0 must be one state"),
        (lambda arm: ss.linearize(arm, [0, 0], [1, 1], [0, None]), ad.ModelError, "tau0 must be finite"),
        (lambda arm: ss.linearize(3, [0, 0], [1, 1], [0, 0]), TypeError, "arm must be an armdyn Robot"),
    ],
)  # fmt: skip
def test_statespace_wrong_types_name_the_argument(call: object, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        call(ad.models.two_link_planar())
