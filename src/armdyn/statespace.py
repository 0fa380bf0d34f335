"""State-variable forms of the robot equation (BOOK.md section 5, the book's Section 3.4).

- position/velocity form, x = [q; qd]: xdot = f(x) + g(x) tau with
  f = [qd; -M^-1 N], g = [0; M^-1];
- feedback linearization: for an output y = h(q) with Jacobian J, the torque
  tau = M J^+ (u - Jdot qd) + N makes yddot = u (J^+ the pseudo-inverse when J is not
  square); for y = q it is computed-torque control, and u = M^-1 (tau - N) gives the
  Brunovsky form xdot = [[0, I], [0, 0]] x + [0; I] u;
- Hamiltonian form in (q, p), p = M qd: H = 1/2 p^T M^-1 p + P(q), qdot = M^-1 p,
  pdot = Vm^T qd - G - F + tau;
- linearization about (q0, qd0, tau0): A = [[0, I], [-M^-1 dID/dq, -M^-1 dID/dqd]],
  B = [0; M^-1], with dID/dq by complex-step differentiation of the Lagrange-Euler
  reference (exact to rounding, no step-size error) and dID/dqd = 2 Vm + Fv exactly
  (Vm is the Christoffel form, so d(Vm qd)/dqd = 2 Vm).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armdyn.dynamics import lagrange
from armdyn.errors import ModelError
from armdyn.robot import Robot


def _split(arm: Robot, x: object) -> tuple[np.ndarray, np.ndarray]:
    x = np.asarray(x, dtype=float)
    if x.ndim == 0 or x.shape[-1] != 2 * arm.n:
        raise ModelError(f"x must have shape (..., {2 * arm.n}) for '{arm.name}' (x = [q; qd]), got {x.shape}")
    return x[..., : arm.n], x[..., arm.n :]


def state_derivative(arm: Robot, x: object, tau: object) -> np.ndarray:
    """xdot = [qd; M^-1 (tau - N)] in the position/velocity form, batched (BOOK.md section 5).

    Parameters
    ----------
    arm : Robot
        The arm.
    x : array_like
        The state [q; qd], (2 n,) or a batch (..., 2 n).
    tau : array_like
        Joint torques, (n,) or a batch (..., n) broadcasting with x's.

    Returns
    -------
    numpy.ndarray
        xdot = [qd; qdd], (..., 2 n).

    Raises
    ------
    armdyn.ModelError
        When ``x`` does not end in 2 n, or when ``tau`` or the state is rejected by
        ``forward_dynamics`` (wrong shape, NaN or infinity, symbolic parameters).
    """
    q, qd = _split(arm, x)
    return np.concatenate([qd, arm.forward_dynamics(q, qd, tau)], -1)


def drift_and_input(arm: Robot, x: object) -> tuple[np.ndarray, np.ndarray]:
    """(f(x), g(x)) with xdot = f(x) + g(x) tau: f = [qd; -M^-1 N], g = [0; M^-1].

    The position/velocity form of BOOK.md section 5 (N = Vm qd + F + G), batched.

    Parameters
    ----------
    arm : Robot
        The arm.
    x : array_like
        The state [q; qd], (2 n,) or a batch (..., 2 n).

    Returns
    -------
    f : numpy.ndarray
        The drift, (..., 2 n).
    g : numpy.ndarray
        The input matrix, (..., 2 n, n).

    Raises
    ------
    armdyn.ModelError
        When ``x`` does not end in 2 n or holds NaN or infinity, or the arm has symbolic
        parameters.
    """
    q, qd = _split(arm, x)
    M = arm.inertia_matrix(q)
    N = arm.nonlinear_terms(q, qd)
    Minv = np.linalg.inv(M)
    f = np.concatenate([qd, -np.einsum("...ij,...j->...i", Minv, N)], -1)
    g = np.concatenate([np.zeros_like(Minv), Minv], -2)
    return f, g


def brunovsky(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the Brunovsky canonical form: n double integrators.

    xdot = A x + B u with A = [[0, I], [0, 0]], B = [0; I], the form feedback
    linearization gives (BOOK.md section 5).

    Parameters
    ----------
    n : int
        The number of joints.

    Returns
    -------
    A : numpy.ndarray
        (2 n, 2 n).
    B : numpy.ndarray
        (2 n, n).
    """
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    B = np.vstack([np.zeros((n, n)), np.eye(n)])
    return A, B


def linearizing_torque(
    arm: Robot,
    q: object,
    qd: object,
    u: object,
    output_jacobian: Callable[[np.ndarray], np.ndarray] | None = None,
    output_jacobian_dot_qd: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
) -> np.ndarray:
    """tau = M J^+ (u - Jdot qd) + N, so that yddot = u for y = h(q) (J = dh/dq).

    Without an output, y = q and tau = M u + N (computed torque). A non-square J uses
    the pseudo-inverse J^+ (for y of lower dimension the motion within J's null space is
    left to the dynamics). Feedback linearization, BOOK.md section 5.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, one state (n,).
    u : array_like
        The desired output acceleration yddot: (n,) without an output, else (m,).
    output_jacobian : callable, optional
        J(q) -> (m, n), the Jacobian of the output y = h(q); default None (y = q).
    output_jacobian_dot_qd : callable, optional
        (q, qd) -> Jdot qd, (m,); default zero.

    Returns
    -------
    numpy.ndarray
        tau, (n,).

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``qd`` is rejected by the dynamics (wrong shape, NaN or infinity,
        symbolic parameters).
    """
    q, qd, u = (np.asarray(v, dtype=float) for v in (q, qd, u))
    M, N = arm.inertia_matrix(q), arm.nonlinear_terms(q, qd)
    if output_jacobian is None:
        return M @ u + N
    J = np.asarray(output_jacobian(q), dtype=float)
    jdot_qd = np.zeros(J.shape[0]) if output_jacobian_dot_qd is None else output_jacobian_dot_qd(q, qd)
    return M @ (np.linalg.pinv(J) @ (u - jdot_qd)) + N


def hamiltonian(arm: Robot, q: object, p: object) -> float:
    """H = 1/2 p^T M^-1 p + P(q), the total energy (Hamiltonian form, BOOK.md section 5).

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, one state (n,).
    p : array_like
        Generalized momenta p = M(q) qd, (n,).

    Returns
    -------
    float
        H.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is rejected by the dynamics (wrong shape, NaN or infinity, symbolic
        parameters).
    """
    q, p = np.asarray(q, dtype=float), np.asarray(p, dtype=float)
    return float(0.5 * p @ np.linalg.solve(arm.inertia_matrix(q), p) + arm.potential_energy(q))


def hamiltonian_rates(arm: Robot, q: object, p: object, tau: object) -> tuple[np.ndarray, np.ndarray]:
    """(qdot, pdot): qdot = dH/dp = M^-1 p, pdot = -dH/dq + tau = Vm^T qd - G - F + tau.

    The Hamiltonian form of BOOK.md section 5, friction included.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, one state (n,).
    p : array_like
        Generalized momenta p = M(q) qd, (n,).
    tau : array_like
        Joint torques, (n,).

    Returns
    -------
    qdot : numpy.ndarray
        (n,).
    pdot : numpy.ndarray
        (n,).

    Raises
    ------
    armdyn.ModelError
        When ``q`` is rejected by the dynamics (wrong shape, NaN or infinity, symbolic
        parameters).
    """
    q, p, tau = (np.asarray(v, dtype=float) for v in (q, p, tau))
    qd = np.linalg.solve(arm.inertia_matrix(q), p)
    pdot = arm.coriolis_matrix(q, qd).T @ qd - arm.gravity_vector(q) - arm.friction(qd) + tau
    return qd, pdot


@dataclass
class Linearization:
    """xdot ~ A (x - x0) + B (tau - tau0) about the operating point (q0, qd0, tau0).

    Made by ``linearize``.

    Parameters
    ----------
    A : numpy.ndarray
        (2 n, 2 n).
    B : numpy.ndarray
        (2 n, n).
    q0, qd0, tau0 : numpy.ndarray
        The operating point, (n,) each.
    """

    A: np.ndarray
    B: np.ndarray
    q0: np.ndarray
    qd0: np.ndarray
    tau0: np.ndarray

    def to_control(self) -> object:
        """A python-control StateSpace (the optional ``control`` extra), outputs x.

        Returns
        -------
        control.StateSpace
            ss(A, B, I, 0): the full state x - x0 as output.

        Raises
        ------
        armdyn.ModelError
            When python-control is not installed.
        """
        try:
            import control
        except ImportError:
            raise ModelError("to_control() needs python-control: pip install 'armdyn[control]'") from None
        return control.ss(self.A, self.B, np.eye(self.A.shape[0]), np.zeros(self.B.shape))


def linearize(arm: Robot, q0: object, qd0: object, tau0: object) -> Linearization:
    """A, B of the position/velocity form about (q0, qd0, tau0) (see the module docstring).

    A = [[0, I], [-M^-1 dID/dq, -M^-1 dID/dqd]], B = [0; M^-1] (BOOK.md section 5), with
    dID/dq by complex-step differentiation of the Lagrange-Euler reference and
    dID/dqd = 2 Vm + Fv.

    Parameters
    ----------
    arm : Robot
        The arm.
    q0, qd0, tau0 : array_like
        The operating point: joint positions, velocities and torques, (n,) each.

    Returns
    -------
    Linearization
        A, B and the operating point.

    Raises
    ------
    armdyn.ModelError
        When q0, qd0 or tau0 does not have n values, or when a joint with Coulomb friction
        has zero velocity in qd0 (not differentiable there).
    """
    q0, qd0, tau0 = (np.asarray(v, dtype=float).copy() for v in (q0, qd0, tau0))
    n = arm.n
    if any(v.shape != (n,) for v in (q0, qd0, tau0)):
        raise ModelError(f"q0, qd0 and tau0 must each have {n} values")
    if np.any(qd0 == 0) and np.any(arm.coulomb_friction[qd0 == 0] != 0):
        raise ModelError("Coulomb friction is not differentiable at zero velocity; linearize elsewhere")
    qdd0 = arm.forward_dynamics(q0, qd0, tau0)
    M = arm.inertia_matrix(q0)
    bare = arm.without_friction()
    step = 1e-30
    d_tau_dq = np.empty((n, n))
    for j in range(n):
        q = q0.astype(complex)
        q[j] += 1j * step
        d_tau_dq[:, j] = lagrange.inverse_dynamics(bare, q, qd0.astype(complex), qdd0.astype(complex)).imag / step
    d_tau_dqd = 2 * arm.coriolis_matrix(q0, qd0) + np.diag(arm.viscous_friction)
    Minv = np.linalg.inv(M)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -Minv @ d_tau_dq
    A[n:, n:] = -Minv @ d_tau_dqd
    B = np.vstack([np.zeros((n, n)), Minv])
    return Linearization(A, B, q0, qd0, tau0)
