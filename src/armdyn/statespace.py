"""State-variable forms of the robot equation (Lewis, Dawson and Abdallah 2004, Section 3.4).

- position/velocity form, x = [q; qd]: xdot = f(x) + g(x) tau with
  f = [qd; -M^-1 N], g = [0; M^-1];
- feedback linearization: for an output y = h(q) with Jacobian J, the torque
  tau = M J^+ (u - Jdot qd) + N makes yddot = u (J^+ the pseudo-inverse when J is not
  square); for y = q it is computed-torque control, and u = M^-1 (tau - N) gives the
  Brunovsky form xdot = [[0, I], [0, 0]] x + [0; I] u;
- Hamiltonian form in (q, p), p = M qd: H = 1/2 p^T M^-1 p + P(q), qdot = M^-1 p,
  pdot = Vm^T qd - G - F + tau;
- linearization about (q0, qd0, tau0): A = [[0, I], [-M^-1 dID/dq, -M^-1 dID/dqd]],
  B = [0; M^-1], with the analytic derivatives of the recursive Newton-Euler algorithm
  (Robot.forward_dynamics_derivatives; Carpentier and Mansard 2018), compiled.

Every function but ``linearize`` takes one state or a batch (leading axes (...)) and returns
the matching shape. Arguments are checked first (armdyn.inputs): a wrong type or shape is a
ModelError naming the argument, a wrong kind of arm or callable an ArgumentError (a ModelError and a TypeError).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import ArrayLike

from armdyn import inputs
from armdyn.dynamics.api import smoothing_per_joint
from armdyn.dynamics.friction import coulomb_vector, smooth_coulomb_vector, stribeck_vector
from armdyn.errors import ArgumentError, MissingDependencyError, ModelError
from armdyn.robot import Robot


def _check_arm(arm: object) -> None:
    inputs.arm_argument(arm, Robot, name="arm")


def _where(arm: Robot) -> str:
    return f" for '{arm.name}'"


def _states(arm: Robot, names: tuple[str, ...], values: tuple[object, ...]) -> list[np.ndarray]:
    """The arm checked, then each value as a finite float array (..., n), named in any error."""
    _check_arm(arm)
    return [inputs.state(value, arm.n, name, _where(arm)) for name, value in zip(names, values, strict=True)]


def _broadcast(*named: tuple[str, np.ndarray]) -> tuple[int, ...]:
    """The common batch shape of (name, array (..., k)) pairs, or a ModelError naming them."""
    try:
        return np.broadcast_shapes(*(array.shape[:-1] for _, array in named))
    except ValueError:
        shapes = ", ".join(f"{name} {array.shape}" for name, array in named)
        raise ModelError(f"the batch shapes of {shapes} do not broadcast together") from None


def _matvec(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.einsum("...ij,...j->...i", A, x)


def _x(arm: Robot, x: object) -> np.ndarray:
    """The arm checked, then the state x = [q; qd] as a finite float array (..., 2 n)."""
    _check_arm(arm)
    return inputs.state(x, 2 * arm.n, "x", f" for '{arm.name}' (x = [q; qd])")


def _split(arm: Robot, x: object) -> tuple[np.ndarray, np.ndarray]:
    x = _x(arm, x)
    return x[..., : arm.n], x[..., arm.n :]


def state_derivative(arm: Robot, x: ArrayLike, tau: ArrayLike) -> np.ndarray:
    """xdot = [qd; M^-1 (tau - N)] in the position/velocity form, batched (Section 3.4).

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
        When ``x`` is not numbers of shape (..., 2 n) or holds NaN or infinity, when ``tau``
        is not numbers of shape (..., n) or holds NaN or infinity, when the batch shapes of x
        and tau do not broadcast, or when the arm has symbolic parameters.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    x = _x(arm, x)
    # checked here so that a mismatch names x, not the q and qd forward_dynamics is given
    _broadcast(("x", x), ("tau", inputs.state(tau, arm.n, "tau", _where(arm))))
    q, qd = x[..., : arm.n], x[..., arm.n :]
    qdd = arm.forward_dynamics(q, qd, tau)
    return np.concatenate([np.broadcast_to(qd, qdd.shape), qdd], -1)


def drift_and_input(arm: Robot, x: object) -> tuple[np.ndarray, np.ndarray]:
    """(f(x), g(x)) with xdot = f(x) + g(x) tau: f = [qd; -M^-1 N], g = [0; M^-1].

    The position/velocity form of Section 3.4 (N = Vm qd + F + G), batched.

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
        When ``x`` is not numbers of shape (..., 2 n) or holds NaN or infinity, or the arm
        has symbolic parameters.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    q, qd = _split(arm, x)
    M = arm.inertia_matrix(q)
    N = arm.nonlinear_terms(q, qd)
    Minv = np.linalg.inv(M)
    f = np.concatenate([qd, -_matvec(Minv, N)], -1)
    g = np.concatenate([np.zeros_like(Minv), Minv], -2)
    return f, g


def brunovsky(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the Brunovsky canonical form: n double integrators.

    xdot = A x + B u with A = [[0, I], [0, 0]], B = [0; I], the form feedback
    linearization gives (Section 3.4).

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

    Raises
    ------
    armdyn.ModelError
        When ``n`` is below 1, or so large that A would need more than 2 GiB.
    armdyn.ArgumentError
        When ``n`` is not an integer (a bool is not one).
    """
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
        raise ArgumentError(f"n must be an integer number of joints, got {n!r} ({type(n).__name__})")
    if n < 1:
        raise ModelError(f"n must be at least 1, got {n}")
    n = int(n)
    if 8 * (2 * n) ** 2 > 2**31:
        raise ModelError(f"n must be a number of joints for which A (2 n x 2 n) fits in memory, got {n}")
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
    left to the dynamics). Feedback linearization, Section 3.4.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, one state (n,) or a batch (..., n).
    u : array_like
        The desired output acceleration yddot: (n,) or (..., n) without an output, else (m,)
        or (..., m); its batch shape broadcasts with the states'.
    output_jacobian : callable, optional
        J(q) -> (m, n) for one state, (..., m, n) for a batch q: the Jacobian of the output
        y = h(q); default None (y = q).
    output_jacobian_dot_qd : callable, optional
        (q, qd) -> Jdot qd, (m,) or (..., m); default zero.

    Returns
    -------
    numpy.ndarray
        tau, (..., n): (n,) for one state.

    Raises
    ------
    armdyn.ModelError
        When ``q``, ``qd`` or ``u`` is not numbers of the shape above or holds NaN or
        infinity, when their batch shapes do not broadcast, when an output callable returns
        an array of the wrong shape or non-finite values, when ``output_jacobian_dot_qd`` is
        given without ``output_jacobian``, or when the arm has symbolic parameters.
    armdyn.ArgumentError
        When ``arm`` is not a Robot, or an output argument is neither None nor callable.
    """
    q, qd = _states(arm, ("q", "qd"), (q, qd))
    for name, function in (("output_jacobian", output_jacobian), ("output_jacobian_dot_qd", output_jacobian_dot_qd)):
        if function is not None and not callable(function):
            raise ArgumentError(f"{name} must be a callable or None, got {type(function).__name__}")
    if output_jacobian is None and output_jacobian_dot_qd is not None:
        raise ModelError("output_jacobian_dot_qd needs output_jacobian (without it the output is y = q)")
    M, N = arm.inertia_matrix(q), arm.nonlinear_terms(q, qd)
    if output_jacobian is None:
        u = inputs.state(u, arm.n, "u", _where(arm))
        _broadcast(("q", q), ("qd", qd), ("u", u))
        return _matvec(M, u) + N
    J = inputs.state(output_jacobian(q), arm.n, "output_jacobian(q)", _where(arm))
    if J.ndim < 2:
        raise ModelError(f"output_jacobian(q) must return an (m, {arm.n}) matrix (or a batch of them), got {J.shape}")
    m = J.shape[-2]
    u = inputs.state(u, m, "u", f" (the output has {m} components)")
    if output_jacobian_dot_qd is None:
        jdot_qd = np.zeros(m)
    else:
        jdot_qd = inputs.state(output_jacobian_dot_qd(q, qd), m, "output_jacobian_dot_qd(q, qd)")
    _broadcast(("q", q), ("qd", qd), ("u", u), ("output_jacobian(q)", J[..., 0]), ("Jdot qd", jdot_qd))
    return _matvec(M, _matvec(np.linalg.pinv(J), u - jdot_qd)) + N


def hamiltonian(arm: Robot, q: object, p: object) -> float:
    """H = 1/2 p^T M^-1 p + P(q), the total energy (Hamiltonian form, Section 3.4).

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, one state (n,) or a batch (..., n).
    p : array_like
        Generalized momenta p = M(q) qd, (n,) or (..., n), broadcasting with q.

    Returns
    -------
    float or numpy.ndarray
        H: a float for one state, (...) for a batch.

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``p`` is not numbers of shape (..., n) or holds NaN or infinity, when
        their batch shapes do not broadcast, or when the arm has symbolic parameters.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    q, p = _states(arm, ("q", "p"), (q, p))
    batch = _broadcast(("q", q), ("p", p))
    M = np.broadcast_to(arm.inertia_matrix(q), (*batch, arm.n, arm.n))
    p = np.broadcast_to(p, (*batch, arm.n))
    H = 0.5 * np.einsum("...i,...i->...", p, np.linalg.solve(M, p[..., None])[..., 0]) + arm.potential_energy(q)
    return float(H) if not batch else H


def hamiltonian_rates(arm: Robot, q: object, p: object, tau: object) -> tuple[np.ndarray, np.ndarray]:
    """(qdot, pdot): qdot = dH/dp = M^-1 p, pdot = -dH/dq + tau = Vm^T qd - G - F + tau.

    The Hamiltonian form of Section 3.4, friction included.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, one state (n,) or a batch (..., n).
    p : array_like
        Generalized momenta p = M(q) qd, (n,) or (..., n).
    tau : array_like
        Joint torques, (n,) or (..., n); the batch shapes of q, p and tau broadcast.

    Returns
    -------
    qdot : numpy.ndarray
        (..., n).
    pdot : numpy.ndarray
        (..., n).

    Raises
    ------
    armdyn.ModelError
        When ``q``, ``p`` or ``tau`` is not numbers of shape (..., n) or holds NaN or
        infinity, when their batch shapes do not broadcast, or when the arm has symbolic
        parameters.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    q, p, tau = _states(arm, ("q", "p", "tau"), (q, p, tau))
    batch = _broadcast(("q", q), ("p", p), ("tau", tau))
    M = np.broadcast_to(arm.inertia_matrix(q), (*batch, arm.n, arm.n))
    qd = np.linalg.solve(M, np.broadcast_to(p, (*batch, arm.n))[..., None])[..., 0]
    Vm = arm.coriolis_matrix(q, qd)
    pdot = np.einsum("...ji,...j->...i", Vm, qd) - arm.gravity_vector(q) - arm.friction(qd) + tau
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
        armdyn.MissingDependencyError
            When python-control is not installed (the ``control`` extra).
        """
        try:
            import control
        except ImportError:
            raise MissingDependencyError("control", "control", "Linearization.to_control") from None
        return control.ss(self.A, self.B, np.eye(self.A.shape[0]), np.zeros(self.B.shape))


def linearize(arm: Robot, q0: object, qd0: object, tau0: object, coulomb_smoothing: object = None) -> Linearization:
    """A, B of the position/velocity form about (q0, qd0, tau0) (see the module docstring).

    A = [[0, I], [-M^-1 dID/dq, -M^-1 dID/dqd]], B = [0; M^-1] (Section 3.4), with
    the analytic derivatives of the recursive Newton-Euler algorithm
    (``Robot.forward_dynamics_derivatives``).

    Parameters
    ----------
    arm : Robot
        The arm.
    q0, qd0, tau0 : array_like
        The operating point: joint positions, velocities and torques, (n,) each.
    coulomb_smoothing : float or array_like, optional
        eps >= 0 of the smoothed Coulomb law tanh(qd / eps) Tc (as ``simulate`` uses it), one
        for all joints or one per joint; None or 0: the exact sign law.

    Returns
    -------
    Linearization
        A, B and the operating point.

    Raises
    ------
    armdyn.ModelError
        When q0, qd0 or tau0 is not n finite numbers (one state, not a batch), or when a
        joint with Coulomb friction and no smoothing has zero velocity in qd0 (the exact law
        is not differentiable there).
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    names = ("q0", "qd0", "tau0")
    q0, qd0, tau0 = (v.copy() for v in _states(arm, names, (q0, qd0, tau0)))
    n = arm.n
    for name, value in zip(names, (q0, qd0, tau0), strict=True):
        if value.shape != (n,):
            raise ModelError(f"{name} must be one state of {n} values{_where(arm)}, got shape {value.shape}")
    if coulomb_smoothing is not None:
        coulomb_smoothing = smoothing_per_joint(arm, coulomb_smoothing)
    _check_differentiable(arm, qd0, coulomb_smoothing)
    d_q, d_qd, d_tau = arm.forward_dynamics_derivatives(q0, qd0, tau0, coulomb_smoothing=coulomb_smoothing)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = d_q
    A[n:, n:] = d_qd
    B = np.vstack([np.zeros((n, n)), d_tau])
    return Linearization(A, B, q0, qd0, tau0)


def _check_differentiable(arm: Robot, qd: np.ndarray, coulomb_smoothing: object) -> None:
    """A ModelError when a joint with the exact Coulomb or Stribeck law (no smoothing) is at zero velocity."""
    eps = np.zeros(arm.n) if coulomb_smoothing is None else np.broadcast_to(np.asarray(coulomb_smoothing), (arm.n,))
    for law, table in (("Coulomb", arm.coulomb_friction), ("Stribeck", arm.stribeck_friction[:, :1])):
        stuck = (qd == 0) & (table != 0).any(axis=1) & ~(eps > 0)
        if np.any(stuck):
            joint = arm.joint_names[int(np.flatnonzero(stuck)[0])]
            raise ModelError(f"{law} friction of joint '{joint}' is not differentiable at zero velocity; linearize "
                             "elsewhere, or give coulomb_smoothing > 0")  # fmt: skip


def _rates_and_jacobians(
    arm: Robot, x: np.ndarray, tau: np.ndarray, coulomb_smoothing: object
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """f(x, tau) = [qd; FD(q, qd, tau)] and its Jacobians df/dx (2n, 2n), df/dtau (2n, n), analytic;
    the Coulomb law smoothed with eps where ``coulomb_smoothing`` gives one."""
    n = arm.n
    q, qd = x[:n], x[n:]
    torque = tau  # the exact law's torque that gives the smoothed plant's qdd
    if coulomb_smoothing is not None:
        eps, table = np.broadcast_to(np.asarray(coulomb_smoothing, float), (n,)), arm.coulomb_friction
        torque = tau - smooth_coulomb_vector(table, eps, qd) + coulomb_vector(table, qd)
        stribeck = arm.stribeck_friction
        if np.any(stribeck[:, 0] != 0):  # the Stribeck law's sign smoothed alike
            torque = torque - stribeck_vector(stribeck, qd, eps) + stribeck_vector(stribeck, qd)
    qdd = arm.forward_dynamics(q, qd, torque)
    d_q, d_qd, d_tau = arm.forward_dynamics_derivatives(q, qd, tau, coulomb_smoothing=coulomb_smoothing)
    jacobian = np.zeros((2 * n, 2 * n))
    jacobian[:n, n:] = np.eye(n)
    jacobian[n:, :n], jacobian[n:, n:] = d_q, d_qd
    return np.concatenate([qd, qdd]), jacobian, np.vstack([np.zeros((n, n)), d_tau])


def rk4_step(
    arm: Robot, q: object, qd: object, tau: object, dt: float, coulomb_smoothing: object = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One RK4 step of xdot = f(x, tau) (tau held), with its exact derivatives (A_d, B_d).

    x+ = x + dt/6 (k1 + 2 k2 + 2 k3 + k4), k1 = f(x), k2 = f(x + dt/2 k1), k3 = f(x + dt/2 k2),
    k4 = f(x + dt k3) (the book's TRESP, as simulate runs it; the Coulomb law smoothed as simulate
    smooths it when ``coulomb_smoothing`` gives eps); A_d and B_d
    follow the stages by the chain rule through the analytic Jacobians of f (Section 3.4,
    Carpentier and Mansard 2018): the derivative of the step itself, as MPC needs it.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd, tau : array_like
        The state and the torque held over the step, (n,) each.
    dt : float
        The step (s), > 0.
    coulomb_smoothing : float or array_like, optional
        eps >= 0 of the smoothed Coulomb law, one for all joints or one per joint; None: the
        exact sign law (not differentiable at zero velocity).

    Returns
    -------
    tuple of numpy.ndarray
        x+ (2n,), A_d = dx+/dx (2n, 2n), B_d = dx+/dtau (2n, n).

    Raises
    ------
    armdyn.ModelError
        When an argument is not one finite state of n values or dt is not positive, or M(q)
        is singular at a stage.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    _check_arm(arm)
    q, qd, tau = _states(arm, ("q", "qd", "tau"), (q, qd, tau))
    n = arm.n
    if q.shape != (n,) or qd.shape != (n,) or tau.shape != (n,):
        raise ModelError(f"rk4_step takes one state of {n} values{_where(arm)}")
    dt = inputs.number(dt, "dt")
    if not dt > 0:
        raise ModelError(f"dt must be positive, got {dt:g}")
    x = np.concatenate([q, qd])
    if coulomb_smoothing is not None:
        coulomb_smoothing = smoothing_per_joint(arm, coulomb_smoothing)
    identity = np.eye(2 * n)
    slopes: list[np.ndarray] = []
    d_x: list[np.ndarray] = []
    d_tau: list[np.ndarray] = []
    for fraction in (0.0, 0.5, 0.5, 1.0):
        if slopes:
            point = x + fraction * dt * slopes[-1]
            entry_x = identity + fraction * dt * d_x[-1]  # d(point)/dx
            entry_tau = fraction * dt * d_tau[-1]
        else:
            point, entry_x, entry_tau = x, identity, np.zeros((2 * n, n))
        rate, jacobian, input_jacobian = _rates_and_jacobians(arm, point, tau, coulomb_smoothing)
        slopes.append(rate)
        d_x.append(jacobian @ entry_x)
        d_tau.append(jacobian @ entry_tau + input_jacobian)
    weights = (1.0, 2.0, 2.0, 1.0)
    step = x + dt / 6 * sum(w * k for w, k in zip(weights, slopes, strict=True))
    A_d = identity + dt / 6 * sum(w * k for w, k in zip(weights, d_x, strict=True))
    B_d = cast(np.ndarray, dt / 6 * sum(w * k for w, k in zip(weights, d_tau, strict=True)))  # a sum of 4 arrays
    return step, A_d, B_d
