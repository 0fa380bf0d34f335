"""Khatib's operational space of an output with m <= n: Lambda, Jbar, mu, p and the null-space
projector (Khatib 1987, "A unified approach for motion and force control of robot manipulators:
the operational space formulation", IEEE Journal of Robotics and Automation 3(1), 43-53;
Section 3.5)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from armdyn import inputs
from armdyn.dynamics.operational import lambda_one, operational_one
from armdyn.robot import Robot
from armdyn.task_space.outputs import DEFAULT_MAX_CONDITION, TaskOutput, _condition, _into, _mv, _shaped, _states
from armdyn.task_space.quantities import _NOT_ONE_STATE, _T, _compiled, _Task, _task

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


# ----- redundant outputs: Khatib's operational space ----------------------------------------------
@dataclass(frozen=True)
class OperationalSpace:
    """Khatib's operational-space quantities (Khatib 1987, sections III-IV) at one state or a batch.

    The task-space equation is Lambda yddot + mu + p + friction = f, and the joint forces
    tau = J^T f + Nproj^T tau_0 for any tau_0 leave yddot unchanged (for m = n, Nproj = 0
    and Lambda = Mbar, mu + p + friction = Nbar). ``operational_space`` makes one.

    Parameters
    ----------
    J : numpy.ndarray
        The output's Jacobian, (..., m, n).
    Lambda : numpy.ndarray
        (J M^-1 J^T)^-1, (..., m, m); at damped states (J M^-1 J^T + damping^2 I)^-1.
    Jbar : numpy.ndarray
        The dynamically consistent generalized inverse M^-1 J^T Lambda, (..., n, m).
    mu : numpy.ndarray
        The Coriolis and centrifugal force Jbar^T (Vm qd) - Lambda Jdot qd, (..., m)
        (Vm qd = arm.coriolis_vector: no friction, no gravity).
    p : numpy.ndarray
        The gravity force Jbar^T G, (..., m).
    friction : numpy.ndarray
        The friction force Jbar^T F(qd), (..., m).
    Nproj : numpy.ndarray
        The null-space projector I - Jbar J, (..., n, n).
    """

    J: np.ndarray
    Lambda: np.ndarray
    Jbar: np.ndarray
    mu: np.ndarray
    p: np.ndarray
    friction: np.ndarray
    Nproj: np.ndarray

    @cached_property
    def condition(self) -> np.ndarray:
        """The condition number of J, (...) (an SVD per state, made when first read)."""
        J = self.J
        return _condition(J.reshape(-1, *J.shape[-2:])).reshape(J.shape[:-2])


def operational_inertia(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Lambda = (J M^-1 J^T)^-1, the inertia an output with m <= n presents (Khatib 1987, eq. 12).

    For a square output at a regular state it equals Mbar = J^-T M J^-1 (``task_inertia``);
    for a redundant one it is the inertia felt at the task, not J^+T M J^+. One state of the
    built-in row outputs (ToolPosition, ToolPose, LinkPoint, PlanarPosition) is one compiled
    call (Cholesky factors of M and of J M^-1 J^T, no explicit inverse of M).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        The task output (m <= n).
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    damping : float, optional
        As for ``operational_space``.
    max_condition : float, optional
        As for ``operational_space``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Lambda, symmetric positive definite, (..., m, m).

    Raises
    ------
    ModelError
        As for ``operational_space``.
    """
    fast = _compiled(arm, output, None, damping, max_condition)
    if fast is not None:
        m = fast[1].shape[0]
        result = np.empty((m, m))
        try:
            if lambda_one(arm.packed, q, fast[0], fast[1], max_condition, result) == 0:
                return _into(out, result)
        except _NOT_ONE_STATE:
            if (states := inputs.thawed(q)) is not None:
                return operational_inertia(arm, output, *states, damping=damping, max_condition=max_condition, out=out)
    arm, output, task = _task(arm, output, ("q",), (q,), damping, max_condition, square=False)
    Lambda, _ = _lambda(arm, task)
    return _into(out, _shaped(Lambda, task.batch))


def _lambda(arm: Robot, task: _Task) -> tuple[np.ndarray, np.ndarray]:
    """Lambda and M^-1 J^T for the checked states, by solves."""
    J = task.J
    m = J.shape[1]
    Minv_JT = np.linalg.solve(arm.inertia_matrix(task.states[0]), _T(J, 1, 2))  # (B, n, m)
    Lambda_inv = J @ Minv_JT
    Lambda_inv = 0.5 * (Lambda_inv + _T(Lambda_inv, 1, 2))
    Lambda_inv[task.damped] += task.damping**2 * np.eye(m)
    Lambda = np.linalg.solve(Lambda_inv, np.broadcast_to(np.eye(m), Lambda_inv.shape))
    return 0.5 * (Lambda + _T(Lambda, 1, 2)), Minv_JT


def operational_space(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: tuple | OperationalSpace | None = None,
) -> OperationalSpace:
    """Lambda, Jbar, mu, p and the null-space projector of an output with m <= n (Khatib 1987).

    Lambda = (J M^-1 J^T)^-1, Jbar = M^-1 J^T Lambda, mu = Jbar^T Vm qd - Lambda Jdot qd,
    p = Jbar^T G, friction = Jbar^T F, Nproj = I - Jbar J; all by solves with M and with
    J M^-1 J^T (which is singular exactly when J is). One state of the built-in row outputs
    is one compiled call.

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        The task output (m <= n).
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.
    damping : float, optional
        At states whose J has a condition number above ``max_condition``, Lambda becomes
        (J M^-1 J^T + damping^2 I)^-1; default None: such states raise.
    max_condition : float, optional
        The condition number above which J counts as singular (default 1e8).
    out : tuple of seven numpy.ndarray or OperationalSpace, optional
        Where to write J, Lambda, Jbar, mu, p, friction and Nproj (in that order, or the arrays of an
        OperationalSpace of the same shapes): each C-contiguous float64 of its result's shape, no two
        sharing memory.

    Returns
    -------
    OperationalSpace
        The quantities, each with the batch shape in front (the arrays of ``out`` when given).

    Raises
    ------
    ModelError
        When an argument is invalid or m > n (an ArgumentError, also a TypeError, when ``arm``
        is not a numeric Robot or ``output`` not a task output).
    armdyn.SingularError
        When J is ill-conditioned at a state and no damping is given (the message names the
        state and the condition number; so do its ``state`` and ``condition``).
    """
    fast = _compiled(arm, output, None, damping, max_condition)
    if fast is not None:
        n, m = arm.n, fast[1].shape[0]
        parts = (np.empty((m, n)), np.empty((m, m)), np.empty((n, m)), np.empty(m), np.empty(m), np.empty(m),
                 np.empty((n, n)))  # fmt: skip
        try:
            if operational_one(arm.packed, q, qd, fast[0], fast[1], max_condition, *parts) == 0:
                return OperationalSpace(*parts) if out is None else _space_into(out, parts)
        except _NOT_ONE_STATE:
            if (states := inputs.thawed(q, qd)) is not None:
                return operational_space(arm, output, *states, damping=damping, max_condition=max_condition, out=out)
    arm, output, task = _task(arm, output, ("q", "qd"), (q, qd), damping, max_condition, square=False)
    fq, fqd = task.states
    J, n = task.J, arm.n
    Lambda, Minv_JT = _lambda(arm, task)
    Jbar = Minv_JT @ Lambda
    JbarT = _T(Jbar, 1, 2)
    mu = _mv(JbarT, arm.coriolis_vector(fq, fqd)) - _mv(Lambda, output._bias(arm, fq, fqd))
    p = _mv(JbarT, arm.gravity_vector(fq))
    friction = _mv(JbarT, arm.friction(fqd))
    Nproj = np.eye(n) - Jbar @ J
    b = task.batch
    shaped = tuple(_shaped(x, b) for x in (J, Lambda, Jbar, mu, p, friction, Nproj))
    return OperationalSpace(*shaped) if out is None else _space_into(out, shaped)


_SPACE_FIELDS = ("J", "Lambda", "Jbar", "mu", "p", "friction", "Nproj")


def _space_into(out: object, parts: tuple[np.ndarray, ...]) -> OperationalSpace:
    """The quantities written into ``out`` (seven arrays, or an OperationalSpace's), each checked."""
    arrays = tuple(getattr(out, name) for name in _SPACE_FIELDS) if isinstance(out, OperationalSpace) else out
    targets = inputs.results(arrays, [x.shape for x in parts], _SPACE_FIELDS)
    for target, value in zip(targets, parts, strict=True):
        target[...] = value
    return OperationalSpace(*targets)


def operational_coriolis(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: tuple | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """mu_x = Jbar^T Vm Jbar - Lambda Jdot Jbar and the null-space coupling (Jbar^T Vm - Lambda Jdot) N qd.

    With qd = Jbar ydot + Nproj qd, Khatib's mu splits as mu = mu_x ydot + coupling: mu_x is
    the operational-space Coriolis matrix, with Lambda_dot - 2 mu_x skew-symmetric even while
    the arm moves in its null space, and the coupling is the force that null-space motion
    exerts on the task (zero for m = n, where mu_x = Vmbar).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        The task output (m <= n) with a Jdot.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.
    damping : float, optional
        As for ``operational_space``.
    max_condition : float, optional
        As for ``operational_space``.
    out : tuple of two numpy.ndarray, optional
        Where to write mu_x and the coupling: each C-contiguous float64 of its result's shape, the two
        not sharing memory.

    Returns
    -------
    mu_x : numpy.ndarray
        Shape (..., m, m).
    coupling : numpy.ndarray
        Shape (..., m).

    Raises
    ------
    ModelError
        As for ``operational_space``.
    """
    space = operational_space(arm, output, q, qd, damping=damping, max_condition=max_condition)
    batch = space.Lambda.shape[:-2]
    fq, fqd = _states(arm, ("q", "qd"), (q, qd))[1]
    m = space.J.shape[-2]
    Jbar, Lambda, Nproj = (x.reshape(-1, *x.shape[-2:]) for x in (space.Jbar, space.Lambda, space.Nproj))
    K = _T(Jbar, 1, 2) @ arm.coriolis_matrix(fq, fqd) - Lambda @ output._jacobian_dot(arm, fq, fqd)  # (B, m, n)
    mu_x = (K @ Jbar).reshape(*batch, m, m)
    coupling = _mv(K, _mv(Nproj, fqd)).reshape(*batch, m)
    if out is None:
        return mu_x, coupling
    targets = inputs.results(out, [mu_x.shape, coupling.shape], ("mu_x", "coupling"))
    targets[0][...], targets[1][...] = mu_x, coupling
    return targets[0], targets[1]
