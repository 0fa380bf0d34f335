"""Task-space (Cartesian) dynamics: the robot equation in the coordinates of an output y = h(q).

Lewis, Dawson and Abdallah 2004, Section 3.5 (Example 3.5-1) and Khatib 1987, "A unified
approach for motion and force control of robot manipulators: the operational space
formulation" (IEEE Journal of Robotics and Automation 3(1), 43-53).

An output is y = h(q) with ydot = J(q) qd and yddot = J qdd + Jdot qd; the generalized
forces relate as tau = J^T f. For a square nonsingular J (m = n), substituting
qdd = J^-1 (yddot - Jdot qd) in M qdd + N = tau and multiplying by J^-T gives

    Mbar yddot + Nbar = f,         Mbar  = J^-T M J^-1,
    Nbar  = J^-T (N - M J^-1 Jdot qd),   N = Vm qd + F + G,
    Vmbar = J^-T (Vm - M J^-1 Jdot) J^-1,   Gbar = J^-T G,

with Mbar_dot - 2 Vmbar skew-symmetric (Section 3.5). For m < n (a redundant arm),
``operational_space`` gives Khatib's Lambda = (J M^-1 J^T)^-1, the dynamically consistent
inverse Jbar = M^-1 J^T Lambda, mu, p and the null-space projector.

Every inverse of J is applied with a linear solve, batched over the states. A state where
J is ill-conditioned (condition number above ``max_condition``, default
``DEFAULT_MAX_CONDITION`` = 1e8) raises a ModelError naming the state and its condition
number, unless ``damping`` is given: those states then use the damped least-squares
inverse J^T (J J^T + damping^2 I)^-1 (Nakamura and Hanafusa 1986; Wampler 1986) in place
of J^-1, and the results stay finite. States below the threshold are never damped
(``max_condition=1`` damps every state).

Outputs (each a small class with ``value``, ``jacobian``, ``jacobian_dot`` and ``bias`` =
Jdot qd, all batched over leading dimensions): ToolPosition, ToolPose, LinkPoint,
PlanarPosition, Camera, and Output for user callables.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

import numpy as np
from numba.core.errors import NumbaError

from armdyn import inputs
from armdyn.dynamics import operational as kernels
from armdyn.dynamics.api import _launch
from armdyn.dynamics.operational import lambda_one, task_batch, task_one
from armdyn.errors import ModelError, SingularError
from armdyn.robot import Robot
from armdyn.task_space.outputs import (
    _ROW_OUTPUTS,
    DEFAULT_MAX_CONDITION,
    TaskOutput,
    _check_arm,
    _check_output,
    _condition,
    _damping,
    _into,
    _mv,
    _Rows,
    _rows,
    _shaped,
    _states,
    _where,
)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


@dataclass
class _Task:
    """Checked states with J, which states are damped, and solves with J^-1 and J^-T."""

    batch: tuple[int, ...]
    states: list[np.ndarray]
    J: np.ndarray
    damped: np.ndarray  # bool (B,)
    damping: float

    def inverse(self, X: np.ndarray) -> np.ndarray:
        """J^-1 X for (B, n, k) X (damped states: J^T (J J^T + lambda^2 I)^-1 X)."""
        J, damped = self.J, self.damped
        result = np.empty((X.shape[0], J.shape[2], X.shape[2]))
        plain = ~damped
        if plain.any():
            result[plain] = np.linalg.solve(J[plain], X[plain])
        if damped.any():
            Jd = J[damped]
            A = Jd @ np.swapaxes(Jd, 1, 2) + self.damping**2 * np.eye(Jd.shape[1])
            result[damped] = np.swapaxes(Jd, 1, 2) @ np.linalg.solve(A, X[damped])
        return result

    def inverse_transpose(self, Y: np.ndarray) -> np.ndarray:
        """J^-T Y for (B, n, k) Y (damped states: (J J^T + lambda^2 I)^-1 J Y)."""
        J, damped = self.J, self.damped
        result = np.empty((Y.shape[0], J.shape[1], Y.shape[2]))
        plain = ~damped
        if plain.any():
            result[plain] = np.linalg.solve(np.swapaxes(J[plain], 1, 2), Y[plain])
        if damped.any():
            Jd = J[damped]
            A = Jd @ np.swapaxes(Jd, 1, 2) + self.damping**2 * np.eye(Jd.shape[1])
            result[damped] = np.linalg.solve(A, Jd @ Y[damped])
        return result


def _task(
    arm: object,
    output: object,
    names: tuple[str, ...],
    values: tuple[object, ...],
    damping: object,
    max_condition: object,
    square: bool,
) -> tuple[Robot, TaskOutput, _Task]:
    arm, output = _check_arm(arm), _check_output(output)
    lam = _damping(damping)
    limit = inputs.number(max_condition, "max_condition", minimum=1.0)
    batch, flat = _states(arm, names, values)
    J = output._jacobian(arm, flat[0])
    _rows(arm, output, J, square)
    cond = _condition(J)
    damped = ~(cond <= limit)
    if damped.any() and lam is None:
        index = int(np.flatnonzero(damped)[0])
        raise SingularError(
            f"J(q) of output {output!r} on arm '{arm.name}' is singular or ill-conditioned "
            f"{_where(batch, index)}(q = {np.array2string(flat[0][index], precision=4)}): its condition number "
            f"{cond[index]:.3g} exceeds max_condition = {limit:.3g}. Move away from the singularity, raise "
            "max_condition, or pass damping=... for a damped least-squares inverse",
            state=flat[0][index].copy(),
            condition=float(cond[index]),
        )
    return arm, output, _Task(batch, flat, J, damped, 0.0 if lam is None else lam)


# The compiled one-state path: the built-in row outputs, one state of float64 arrays, a float
# max_condition and no damping to check; anything else (or a state the kernel cannot certify
# regular) takes the general path, which checks the arguments and decides at singular states.
_NOT_ONE_STATE = (TypeError, ValueError, NumbaError)
_UNUSED = object()  # a state argument the quantity does not take (None is one the caller passed, to refuse)


def _compiled(
    arm: object, output: object, m: int | None, damping: object, limit: object
) -> tuple[int, np.ndarray] | None:
    """(target, rows) when the compiled one-state kernels may take the call (with m rows if given):
    only with arguments the general path would take too (a float max_condition from 1 to below
    infinity, damping None or a positive finite float); any other goes there to be checked."""
    if type(output) not in _ROW_OUTPUTS or not isinstance(arm, Robot) or type(limit) is not float:
        return None
    if not 1.0 <= limit < math.inf or (damping is not None and not (type(damping) is float and 0 < damping < math.inf)):
        return None
    spec = cast(_Rows, output)._compiled()  # one of _ROW_OUTPUTS
    return None if m is not None and spec[1].shape[0] != m else spec


def _kernel(
    arm: object,
    output: object,
    kind: int,
    damping: object,
    limit: object,
    matrix: bool,
    q: object,
    qd: object = _UNUSED,
    v: object = _UNUSED,
    v_name: str = "",
) -> np.ndarray | None:
    """The compiled route of a square quantity (operational.task_one, or task_batch for a batch):
    (n, n) when ``matrix``, else (n,); None when the general path must take the call: another
    output, an argument to check (a state passed as None among them), or a state the kernel
    cannot certify regular. A quantity that takes no qd (or no v) leaves it _UNUSED: the kernel
    then reads q in its place."""
    fast = _compiled(arm, output, getattr(arm, "n", None), damping, limit)
    if fast is None or q is None or qd is None or v is None:
        return None
    arm = cast(Robot, arm)  # _compiled takes a Robot only
    n = arm.n
    result = np.empty((n, n) if matrix else (1, n))
    try:
        status = task_one(arm.packed, q, q if qd is _UNUSED else qd, q if v is _UNUSED else v, *fast, limit, kind,
                          result)  # fmt: skip
        if status == 0:
            return result if matrix else result[0]
    except _NOT_ONE_STATE:
        if (states := inputs.thawed(q, qd, v)) is not None:
            q, qd, v = states
            return _kernel(arm, output, kind, damping, limit, matrix, q, qd, v, v_name)
    if arm.packed is None:
        return None
    named = [("q", q)] + ([("qd", qd)] if qd is not _UNUSED else []) + ([(v_name, v)] if v is not _UNUSED else [])
    try:
        batch, flat = inputs.batch_states([name for name, _ in named], [value for _, value in named], n)
    except ModelError:
        return None  # the general path names the argument
    q_flat = flat[0]
    qd_flat = flat[1] if qd is not _UNUSED else q_flat
    v_flat = flat[-1] if v is not _UNUSED else q_flat
    count = q_flat.shape[0]
    out, status = np.empty((count, *result.shape)), np.ones(count, dtype=np.int64)
    if count:
        _launch(task_batch, out.size, arm.packed, q_flat, qd_flat, v_flat, *fast, limit, kind, out, status)
    if status.any():
        return None
    return out.reshape(*batch, n, n) if matrix else out.reshape(*batch, n)


# ----- square outputs: Mbar, Vmbar, Gbar, Nbar (Section 3.5) --------------------------------
_T = np.swapaxes


def task_inertia(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Mbar = J^-T M J^-1, the inertia in the output's coordinates (Section 3.5).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    damping : float, optional
        lambda of the damped least-squares inverse used at the states whose J has a
        condition number above ``max_condition``; default None: such states raise.
    max_condition : float, optional
        The condition number above which J counts as singular (default 1e8).
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Mbar, symmetric, shape (..., n, n).

    Raises
    ------
    ModelError
        When an argument is invalid or m != n (an ArgumentError, also a TypeError, when ``arm``
        is not a numeric Robot or ``output`` not a task output).
    armdyn.SingularError
        When J is ill-conditioned at a state and no damping is given (the message names the
        state and the condition number; so do its ``state`` and ``condition``).
    """
    fast = _compiled(arm, output, getattr(arm, "n", None), damping, max_condition)
    if fast is not None:  # one state through the leaner kernel of Lambda
        result = np.empty((arm.n, arm.n))
        try:
            if lambda_one(arm.packed, q, *fast, max_condition, result) == 0:
                return _into(out, result)
        except _NOT_ONE_STATE:
            if (states := inputs.thawed(q)) is not None:
                return task_inertia(arm, output, *states, damping=damping, max_condition=max_condition, out=out)
    computed = _kernel(arm, output, kernels.TASK_LAMBDA, damping, max_condition, True, q)
    if computed is not None:  # at a regular state Mbar = Lambda = (J M^-1 J^T)^-1
        return _into(out, computed)
    arm, output, task = _task(arm, output, ("q",), (q,), damping, max_condition, square=True)
    M = arm.inertia_matrix(task.states[0])
    Mbar = task.inverse_transpose(_T(task.inverse_transpose(M), 1, 2))  # J^-T (J^-T M)^T, M symmetric
    return _into(out, _shaped(0.5 * (Mbar + _T(Mbar, 1, 2)), task.batch))


def task_coriolis(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Vmbar = J^-T (Vm - M J^-1 Jdot) J^-1, with Mbar_dot - 2 Vmbar skew (Section 3.5).

    Vmbar ydot = J^-T (Vm qd - M J^-1 Jdot qd): the Coriolis and centrifugal part of Nbar.

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n) with a Jdot (an Output needs ``jacobian_dot``).
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Vmbar, shape (..., n, n).

    Raises
    ------
    ModelError
        As for ``task_inertia``, and when qd is invalid.
    """
    result = _kernel(arm, output, kernels.TASK_CORIOLIS, damping, max_condition, True, q, qd)
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q", "qd"), (q, qd), damping, max_condition, square=True)
    fq, fqd = task.states
    M, Vm = arm.inertia_matrix(fq), arm.coriolis_matrix(fq, fqd)
    K = Vm - M @ task.inverse(output._jacobian_dot(arm, fq, fqd))
    return _into(out, _shaped(task.inverse_transpose(_T(task.inverse_transpose(_T(K, 1, 2)), 1, 2)), task.batch))


def task_gravity(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Gbar = J^-T G (Section 3.5).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Gbar, shape (..., n).

    Raises
    ------
    ModelError
        As for ``task_inertia``.
    """
    result = _kernel(arm, output, kernels.TASK_GRAVITY, damping, max_condition, False, q)
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q",), (q,), damping, max_condition, square=True)
    G = arm.gravity_vector(task.states[0])
    return _into(out, _shaped(task.inverse_transpose(G[:, :, None])[:, :, 0], task.batch))


def task_nonlinear(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Nbar = J^-T (N - M J^-1 Jdot qd), N = Vm qd + F + G (Section 3.5).

    Friction included: Nbar = Vmbar ydot + Fbar + Gbar.

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Nbar, shape (..., n).

    Raises
    ------
    ModelError
        As for ``task_inertia``, and when qd is invalid.
    """
    result = _kernel(arm, output, kernels.TASK_NONLINEAR, damping, max_condition, False, q, qd)
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q", "qd"), (q, qd), damping, max_condition, square=True)
    fq, fqd = task.states
    M, N = arm.inertia_matrix(fq), arm.nonlinear_terms(fq, fqd)
    a = task.inverse(output._bias(arm, fq, fqd)[:, :, None])
    return _into(out, _shaped(task.inverse_transpose(N[:, :, None] - M @ a)[:, :, 0], task.batch))


def task_friction(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Fbar = J^-T F(qd), the friction in output coordinates (Section 3.5).

    With qd = J^-1 ydot, the viscous part J^-T Fv J^-1 ydot couples the outputs even when
    Fv is diagonal.

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Fbar, shape (..., n).

    Raises
    ------
    ModelError
        As for ``task_inertia``, and when qd is invalid.
    """
    result = _kernel(arm, output, kernels.TASK_FRICTION, damping, max_condition, False, q, qd)
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q", "qd"), (q, qd), damping, max_condition, square=True)
    F = arm.friction(task.states[1])
    return _into(out, _shaped(task.inverse_transpose(F[:, :, None])[:, :, 0], task.batch))


def task_regressor(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    yddot: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Wbar = J^-T W(q, qd, qdd) at qdd = J^-1 (yddot - Jdot qd): f = Wbar phi (Section 3.5).

    The linear parameterization in output coordinates: Mbar yddot + Nbar = Wbar phi with
    phi = arm.parameters(), the same parameters as the joint-space tau = W phi.

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q, qd, yddot : array_like
        Joint positions, velocities and the output's acceleration, (n,) or a batch (..., n);
        the batch shapes broadcast.
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        Wbar, shape (..., n, p) with p = len(arm.parameters()).

    Raises
    ------
    ModelError
        As for ``task_inertia``, and when qd or yddot is invalid.
    """
    arm, output, task = _task(arm, output, ("q", "qd", "yddot"), (q, qd, yddot), damping, max_condition, True)
    fq, fqd, acc = task.states
    qdd = task.inverse((acc - output._bias(arm, fq, fqd))[:, :, None])[:, :, 0]
    return _into(out, _shaped(task.inverse_transpose(arm.regressor(fq, fqd, qdd)), task.batch))


def task_force(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    tau: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """f = J^-T tau, the output-space force equivalent to joint forces tau (tau = J^T f).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q, tau : array_like
        Joint positions and joint forces, (n,) or a batch (..., n); the batch shapes broadcast.
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        f, shape (..., n).

    Raises
    ------
    ModelError
        As for ``task_inertia``, and when tau is invalid.
    """
    result = _kernel(arm, output, kernels.TASK_FORCE, damping, max_condition, False, q, _UNUSED, tau, "tau")
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q", "tau"), (q, tau), damping, max_condition, square=True)
    return _into(out, _shaped(task.inverse_transpose(task.states[1][:, :, None])[:, :, 0], task.batch))


def task_forward_dynamics(
    arm: Robot, output: TaskOutput, q: ArrayLike, qd: ArrayLike, f: ArrayLike, *, out: np.ndarray | None = None
) -> np.ndarray:
    """yddot under the output-space force f: qdd = forward_dynamics(q, qd, J^T f), yddot = J qdd + Jdot qd.

    Equal to Mbar^-1 (f - Nbar) for a square nonsingular J, but computed without inverting
    J (only J^T f is needed), so it holds for any output with m <= n and at singular states.

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        The task output (m <= n).
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n).
    f : array_like
        The output-space force, (m,) or a batch (..., m); the batch shapes broadcast.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        yddot, shape (..., m).

    Raises
    ------
    ModelError
        When an argument is invalid, or M(q) is singular at a state.
    """
    fast = _compiled(arm, output, None, None, 1.0)  # J^T f needs no inverse of J: no singularity test
    if fast is not None and type(f) is np.ndarray and f.shape == fast[1].shape and f.dtype == np.float64:
        padded, result = np.zeros(arm.n), np.empty((1, arm.n))
        padded[: f.shape[0]] = f
        try:
            if task_one(arm.packed, q, qd, padded, fast[0], fast[1], 1.0, kernels.TASK_FORWARD, result) == 0:
                return _into(out, result[0, : f.shape[0]])
        except _NOT_ONE_STATE:
            if (states := inputs.thawed(q, qd, f)) is not None:
                return task_forward_dynamics(arm, output, *states, out=out)
    arm, output = _check_arm(arm), _check_output(output)
    states, (fq, fqd) = _states(arm, ("q", "qd"), (q, qd))
    J = output._jacobian(arm, fq)
    m = _rows(arm, output, J, square=False)
    force = inputs.state(f, m, "f")
    try:
        batch = np.broadcast_shapes(states, force.shape[:-1])
    except ValueError:
        raise ModelError(f"the batch shape of f {force.shape} does not broadcast with the states' {states}") from None
    if batch != states:  # f adds batch dimensions: the states broadcast to them
        n = arm.n
        fq = np.broadcast_to(fq.reshape(*states, n), (*batch, n)).reshape(-1, n).copy()
        fqd = np.broadcast_to(fqd.reshape(*states, n), (*batch, n)).reshape(-1, n).copy()
        J = output._jacobian(arm, fq)
    force = np.broadcast_to(force, (*batch, m)).reshape(-1, m)
    tau = np.einsum("bmi,bm->bi", J, force)
    qdd = arm.forward_dynamics(fq, fqd, tau)
    return _into(out, _shaped(_mv(J, qdd) + output._bias(arm, fq, fqd), batch))


def task_inverse_dynamics(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    yddot: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """f = Mbar yddot + Nbar, computed as J^-T RNEA(q, qd, J^-1 (yddot - Jdot qd)).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        A square output (m = n).
    q, qd, yddot : array_like
        Joint positions, velocities and the output's acceleration, (n,) or a batch (..., n);
        the batch shapes broadcast.
    damping : float, optional
        As for ``task_inertia``.
    max_condition : float, optional
        As for ``task_inertia``.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        f, shape (..., n).

    Raises
    ------
    ModelError
        As for ``task_inertia``, and when qd or yddot is invalid.
    """
    result = _kernel(arm, output, kernels.TASK_INVERSE, damping, max_condition, False, q, qd, yddot, "yddot")
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q", "qd", "yddot"), (q, qd, yddot), damping, max_condition, True)
    fq, fqd, acc = task.states
    qdd = task.inverse((acc - output._bias(arm, fq, fqd))[:, :, None])[:, :, 0]
    tau = arm.inverse_dynamics(fq, fqd, qdd)
    return _into(out, _shaped(task.inverse_transpose(tau[:, :, None])[:, :, 0], task.batch))
