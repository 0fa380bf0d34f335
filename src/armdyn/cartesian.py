"""Task-space (Cartesian) dynamics: the robot equation in the coordinates of an output y = h(q).

BOOK.md section 6 (the book's section 3.5, Example 3.5-1) and Khatib 1987, "A unified
approach for motion and force control of robot manipulators: the operational space
formulation" (IEEE Journal of Robotics and Automation 3(1), 43-53).

An output is y = h(q) with ydot = J(q) qd and yddot = J qdd + Jdot qd; the generalized
forces relate as tau = J^T f. For a square nonsingular J (m = n), substituting
qdd = J^-1 (yddot - Jdot qd) in M qdd + N = tau and multiplying by J^-T gives

    Mbar yddot + Nbar = f,         Mbar  = J^-T M J^-1,
    Nbar  = J^-T (N - M J^-1 Jdot qd),   N = Vm qd + F + G,
    Vmbar = J^-T (Vm - M J^-1 Jdot) J^-1,   Gbar = J^-T G,

with Mbar_dot - 2 Vmbar skew-symmetric (BOOK.md section 6). For m < n (a redundant arm),
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

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numba.core.errors import NumbaError

from armdyn import inputs, kinematics
from armdyn.dynamics import operational as kernels
from armdyn.dynamics.api import _launch
from armdyn.dynamics.frames import TOOL
from armdyn.dynamics.operational import lambda_one, operational_one, task_batch, task_one
from armdyn.errors import ModelError
from armdyn.robot import Robot

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = [
    "DEFAULT_MAX_CONDITION",
    "Camera",
    "Circle",
    "ComputedTorque",
    "Line",
    "LinkPoint",
    "OperationalSpace",
    "OperationalSpaceControl",
    "Output",
    "PlanarPosition",
    "PoseLine",
    "TaskOutput",
    "ToolPose",
    "ToolPosition",
    "Tracking",
    "condition_number",
    "damped_inverse",
    "operational_coriolis",
    "operational_inertia",
    "operational_space",
    "task_coriolis",
    "task_force",
    "task_forward_dynamics",
    "task_friction",
    "task_gravity",
    "task_inertia",
    "task_inverse_dynamics",
    "task_nonlinear",
    "task_regressor",
]

DEFAULT_MAX_CONDITION = 1e8
"""The condition number of J above which a state counts as singular (without ``damping``)."""


# ----- argument checks ----------------------------------------------------------------------------
def _check_arm(arm: object) -> Robot:
    if not isinstance(arm, Robot):
        raise ModelError(f"arm must be an armdyn Robot, got {type(arm).__name__}")
    if arm.packed is None:
        raise ModelError(f"arm '{arm.name}' has symbolic parameters; task-space dynamics need numbers")
    return arm


def _check_output(output: object) -> TaskOutput:
    if not isinstance(output, TaskOutput):
        raise ModelError(
            "output must be a task output of armdyn.cartesian (ToolPosition, ToolPose, LinkPoint, "
            f"PlanarPosition, Camera or Output), got {type(output).__name__}"
        )
    return output


def _states(arm: Robot, names: tuple[str, ...], values: tuple[object, ...]) -> tuple[tuple[int, ...], list]:
    return inputs.batch_states(names, values, arm.n)


def _into(out: np.ndarray | None, value: np.ndarray) -> np.ndarray:
    """value, or value written into ``out`` (checked against its shape) when one is given."""
    if out is None:
        return value
    target = inputs.result(out, value.shape)
    target[...] = value
    return target


def _shaped(array: np.ndarray, batch: tuple[int, ...]) -> np.ndarray:
    """A (B, ...) result as (*batch, ...)."""
    return array.reshape(*batch, *array.shape[1:])


def _where(batch: tuple[int, ...], index: int) -> str:
    return f"at state {tuple(int(k) for k in np.unravel_index(index, batch))} " if batch else ""


def _mv(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix-vector product, (B, m, n) @ (B, n) -> (B, m)."""
    return np.einsum("bij,bj->bi", a, x)


# ----- outputs ------------------------------------------------------------------------------------
class TaskOutput:
    """A task output y = h(q): its value, Jacobian J = dh/dq (as the rate ydot = J qd),
    Jdot and the bias Jdot qd, for one state (n,) or a batch (..., n).

    Subclasses implement ``_value``, ``_jacobian`` and ``_jacobian_dot`` on (B, n) arrays
    of checked states.
    """

    def value(self, arm: Robot, q: ArrayLike) -> np.ndarray:
        """y = h(q).

        Parameters
        ----------
        arm : Robot
            The arm.
        q : array_like
            Joint positions, (n,) or a batch (..., n).

        Returns
        -------
        numpy.ndarray
            y, shape (..., k) (k = m except for ToolPose, see there).

        Raises
        ------
        ModelError
            When ``arm`` is not a numeric Robot or q is invalid.
        """
        arm = _check_arm(arm)
        batch, (flat,) = _states(arm, ("q",), (q,))
        return _shaped(self._value(arm, flat), batch)

    def error(self, arm: Robot, q: ArrayLike, y_d: ArrayLike) -> np.ndarray:
        """e = y_d - h(q), the task error a controller drives to zero; for ToolPose the
        orientation part is the rotation vector of R_d R^T (see there).

        Parameters
        ----------
        arm : Robot
            The arm.
        q : array_like
            Joint positions, (n,) or a batch (..., n).
        y_d : array_like
            The desired output, (k,) or the batch's (..., k), as ``value`` gives it.

        Returns
        -------
        numpy.ndarray
            e, shape (..., m).

        Raises
        ------
        ModelError
            When ``arm``, q or y_d is invalid (y_d of the wrong length or batch names both).
        """
        arm = _check_arm(arm)
        batch, (flat,) = _states(arm, ("q",), (q,))
        y = self._value(arm, flat)
        desired = inputs.numbers(y_d, "y_d")
        if desired.shape[-1:] != y.shape[-1:] or (desired.ndim > 1 and desired.shape[:-1] != batch):
            raise ModelError(f"y_d of output {self!r} must have shape {y.shape[-1:]} or {(*batch, y.shape[-1])}, "
                             f"got {desired.shape}")  # fmt: skip
        desired = np.broadcast_to(desired, y.shape)
        return _shaped(self._difference(arm, flat, desired, y), batch)

    def _difference(self, arm: Robot, q: np.ndarray, y_d: np.ndarray, y: np.ndarray) -> np.ndarray:
        return y_d - y

    def jacobian(self, arm: Robot, q: ArrayLike) -> np.ndarray:
        """J(q), with ydot = J qd.

        Parameters
        ----------
        arm : Robot
            The arm.
        q : array_like
            Joint positions, (n,) or a batch (..., n).

        Returns
        -------
        numpy.ndarray
            J, shape (..., m, n).

        Raises
        ------
        ModelError
            When ``arm`` is not a numeric Robot or q is invalid.
        """
        arm = _check_arm(arm)
        batch, (flat,) = _states(arm, ("q",), (q,))
        return _shaped(self._jacobian(arm, flat), batch)

    def jacobian_dot(self, arm: Robot, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """dJ/dt along the motion (q, qd).

        Parameters
        ----------
        arm : Robot
            The arm.
        q, qd : array_like
            Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.

        Returns
        -------
        numpy.ndarray
            Jdot, shape (..., m, n).

        Raises
        ------
        ModelError
            When ``arm`` is not a numeric Robot, a state is invalid, or (Output) no
            ``jacobian_dot`` callable was given.
        """
        arm = _check_arm(arm)
        batch, (fq, fqd) = _states(arm, ("q", "qd"), (q, qd))
        return _shaped(self._jacobian_dot(arm, fq, fqd), batch)

    def bias(self, arm: Robot, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """Jdot qd, the output's acceleration at qdd = 0.

        Parameters
        ----------
        arm : Robot
            The arm.
        q, qd : array_like
            Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.

        Returns
        -------
        numpy.ndarray
            Jdot qd, shape (..., m).

        Raises
        ------
        ModelError
            When ``arm`` is not a numeric Robot or a state is invalid.
        """
        arm = _check_arm(arm)
        batch, (fq, fqd) = _states(arm, ("q", "qd"), (q, qd))
        return _shaped(self._bias(arm, fq, fqd), batch)

    # on checked (B, n) arrays
    def _value(self, arm: Robot, q: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _jacobian(self, arm: Robot, q: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _jacobian_dot(self, arm: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def _bias(self, arm: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return _mv(self._jacobian_dot(arm, q, qd), qd)


class _Rows(TaskOutput):
    """Rows of the world Jacobian [v; w] of a link frame origin (None: the tool point)."""

    _rows: tuple[int, ...] = (0, 1, 2)

    def _link(self, arm: Robot) -> int | None:
        return None

    def _compiled(self) -> tuple[int, np.ndarray]:
        """(target, rows) for the compiled one-state kernels (the kernel checks the target)."""
        rows = self.__dict__.get("_row_array")
        if rows is None:
            rows = self.__dict__["_row_array"] = np.array(self._rows, dtype=np.int64)
        return getattr(self, "link", TOOL), rows

    def _position(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        link = self._link(arm)
        if link is None:
            return arm.tool_pose(q)[:, :3, 3]
        return arm.link_transforms(q)[:, link, :3, 3]

    def _value(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        return self._position(arm, q)[:, list(self._rows)]

    def _jacobian(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        return arm.jacobian(q, "base", self._link(arm))[:, list(self._rows), :]

    def _jacobian_dot(self, arm: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return arm.jacobian_dot(q, qd, "base", self._link(arm))[:, list(self._rows), :]


class ToolPosition(_Rows):
    """The tool point's world position p (m = 3): rows 0-2 of the world Jacobian.

    Takes no parameters.
    """

    def __repr__(self) -> str:
        return "ToolPosition()"


class ToolPose(_Rows):
    """The tool's position and orientation (m = 6), with the rate ydot = [v; w].

    The orientation rate is the angular velocity w in world axes, not the derivative of
    any three orientation numbers, so Mbar, Vmbar and Nbar are with respect to the twist
    coordinates [v; w] (Khatib 1987, section III: the "generalized" velocities). ``value``
    returns [p; phi] with phi the rotation vector (axis times angle, in [0, pi]) of the
    tool's world rotation R; its derivative is not w except at R = I. ``error`` therefore
    takes the orientation error as the rotation vector of R_d R^T, the rotation (world axes)
    that carries R onto R_d, whose rate is w_d - w to first order (Siciliano et al. 2009,
    3.7.3): a pose task's controllers use it.

    Takes no parameters.
    """

    _rows = (0, 1, 2, 3, 4, 5)

    def _value(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        from scipy.spatial.transform import Rotation

        pose = arm.tool_pose(q)
        result = np.empty((q.shape[0], 6))
        result[:, :3] = pose[:, :3, 3]
        if q.shape[0]:
            result[:, 3:] = Rotation.from_matrix(pose[:, :3, :3]).as_rotvec()
        return result

    def _difference(self, arm: Robot, q: np.ndarray, y_d: np.ndarray, y: np.ndarray) -> np.ndarray:
        from scipy.spatial.transform import Rotation

        result = y_d - y
        if q.shape[0]:
            R, R_d = arm.tool_pose(q)[:, :3, :3], Rotation.from_rotvec(np.array(y_d[:, 3:])).as_matrix()
            result[:, 3:] = Rotation.from_matrix(R_d @ np.swapaxes(R, 1, 2)).as_rotvec()
        return result

    def __repr__(self) -> str:
        return "ToolPose()"


class LinkPoint(_Rows):
    """The world position of a link frame's origin (m = 3).

    Parameters
    ----------
    link : int
        The link's index (checked against the arm when used).

    Raises
    ------
    ModelError
        When ``link`` is not a non-negative integer.
    """

    def __init__(self, link: int) -> None:
        if isinstance(link, (bool, np.bool_)) or not isinstance(link, (int, np.integer)) or link < 0:
            raise ModelError(f"link must be a non-negative integer link index, got {link!r}")
        self.link = int(link)

    def _link(self, arm: Robot) -> int | None:
        return kinematics.link_index(arm, self.link)

    def __repr__(self) -> str:
        return f"LinkPoint({self.link})"


class PlanarPosition(_Rows):
    """Two of the tool point's world coordinates (m = 2), for planar arms.

    Parameters
    ----------
    axes : tuple of int, optional
        The two distinct world axes (0 = x, 1 = y, 2 = z) kept; default (0, 1).

    Raises
    ------
    ModelError
        When ``axes`` is not two distinct integers among 0, 1, 2.
    """

    def __init__(self, axes: tuple[int, int] = (0, 1)) -> None:
        try:
            chosen = tuple(axes)
        except TypeError:
            chosen = ()
        if (
            len(chosen) != 2
            or any(isinstance(a, (bool, np.bool_)) or not isinstance(a, (int, np.integer)) for a in chosen)
            or any(a not in (0, 1, 2) for a in chosen)
            or chosen[0] == chosen[1]
        ):
            raise ModelError(f"axes must be two distinct world axes among 0, 1, 2, got {axes!r}")
        self._rows = tuple(int(a) for a in chosen)

    def __repr__(self) -> str:
        return f"PlanarPosition(axes={self._rows})"


class Camera(TaskOutput):
    """Pinhole image coordinates of the tool point (m = 2), Appendix A, Example A.3-3.

    With p_c = R_c^T (p - o_c) = [x_c, y_c, z_c] the tool point in the camera frame
    (world pose ``pose`` = [[R_c, o_c], [0, 1]], optical axis z_c), the output is
    y = [u, v] = f [x_c / z_c, y_c / z_c]. With P = dy/dp_c = (f / z_c) [[1, 0, -x_c/z_c],
    [0, 1, -y_c/z_c]], J = P R_c^T J_v and Jdot = Pdot R_c^T J_v + P R_c^T Jdot_v, so the
    bias Jdot qd holds the projection's second-order term Pdot pdot_c.

    Parameters
    ----------
    focal_length : float
        f, positive (image units per metre of depth ratio, e.g. pixels).
    pose : array_like
        The camera's world pose, a 4x4 homogeneous transform with a proper rotation.

    Raises
    ------
    ModelError
        When ``focal_length`` is not a positive number or ``pose`` is not a rigid transform.
    """

    def __init__(self, focal_length: float, pose: ArrayLike) -> None:
        self.focal_length = inputs.number(focal_length, "focal_length")
        if not self.focal_length > 0:
            raise ModelError(f"focal_length must be positive, got {self.focal_length:g}")
        T = inputs.numbers(pose, "pose", (4, 4))
        R = T[:3, :3]
        if (
            not np.allclose(T[3], [0, 0, 0, 1], atol=1e-12)
            or not np.allclose(R.T @ R, np.eye(3), atol=1e-9)
            or np.linalg.det(R) <= 0
        ):
            raise ModelError("pose must be a rigid transform [[R, o], [0, 0, 0, 1]] with R a proper rotation")
        self.pose = T

    def __repr__(self) -> str:
        return f"Camera(focal_length={self.focal_length:g}, pose=...)"

    def _camera_point(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        R, o = self.pose[:3, :3], self.pose[:3, 3]
        pc = (arm.tool_pose(q)[:, :3, 3] - o) @ R  # R^T (p - o), row-wise
        depth = pc[:, 2]
        bad = ~(depth > 1e-9)
        if bad.any():
            index = int(np.flatnonzero(bad)[0])
            raise ModelError(
                f"the tool point is not in front of the camera at state {index} of the batch "
                f"(depth z_c = {depth[index]:.3g}): its image coordinates are undefined"
            )
        return pc

    def _projection(self, pc: np.ndarray) -> np.ndarray:
        f, x, y, z = self.focal_length, pc[:, 0], pc[:, 1], pc[:, 2]
        P = np.zeros((pc.shape[0], 2, 3))
        P[:, 0, 0] = P[:, 1, 1] = f / z
        P[:, 0, 2] = -f * x / z**2
        P[:, 1, 2] = -f * y / z**2
        return P

    def _value(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        pc = self._camera_point(arm, q)
        return self.focal_length * pc[:, :2] / pc[:, 2:3]

    def _jacobian(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        pc = self._camera_point(arm, q)
        Jc = self.pose[:3, :3].T @ arm.jacobian(q)[:, :3, :]  # R^T J_v
        return self._projection(pc) @ Jc

    def _jacobian_dot(self, arm: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        pc = self._camera_point(arm, q)
        Rt = self.pose[:3, :3].T
        Jc = Rt @ arm.jacobian(q)[:, :3, :]
        Jc_dot = Rt @ arm.jacobian_dot(q, qd)[:, :3, :]
        vc = _mv(Jc, qd)  # pdot_c
        f, x, y, z = self.focal_length, pc[:, 0], pc[:, 1], pc[:, 2]
        xd, yd, zd = vc[:, 0], vc[:, 1], vc[:, 2]
        P_dot = np.zeros((q.shape[0], 2, 3))
        P_dot[:, 0, 0] = P_dot[:, 1, 1] = -f * zd / z**2
        P_dot[:, 0, 2] = -f * xd / z**2 + 2 * f * x * zd / z**3
        P_dot[:, 1, 2] = -f * yd / z**2 + 2 * f * y * zd / z**3
        return P_dot @ Jc + self._projection(pc) @ Jc_dot


class Output(TaskOutput):
    """A user-defined output from callables of one state each (called state by state).

    Parameters
    ----------
    h : callable
        h(q) -> y, (k,) for q of shape (n,).
    J : callable
        J(q) -> (m, n), with ydot = J qd.
    bias : callable, optional
        bias(q, qd) -> Jdot qd, (m,). Default: ``jacobian_dot(q, qd) @ qd``.
    jacobian_dot : callable, optional
        jacobian_dot(q, qd) -> Jdot, (m, n); needed by ``task_coriolis`` and, without
        ``bias``, by everything that needs Jdot qd.

    Raises
    ------
    ModelError
        When an argument given is not callable.
    """

    def __init__(
        self,
        h: Callable[[np.ndarray], ArrayLike],
        J: Callable[[np.ndarray], ArrayLike],
        bias: Callable[[np.ndarray, np.ndarray], ArrayLike] | None = None,
        jacobian_dot: Callable[[np.ndarray, np.ndarray], ArrayLike] | None = None,
    ) -> None:
        for name, function, optional in (("h", h, False), ("J", J, False), ("bias", bias, True)):
            if not (callable(function) or (optional and function is None)):
                raise ModelError(f"{name} must be a callable, got {type(function).__name__}")
        if not (jacobian_dot is None or callable(jacobian_dot)):
            raise ModelError(f"jacobian_dot must be a callable or None, got {type(jacobian_dot).__name__}")
        self.h, self.J, self._bias_function, self._jacobian_dot_function = h, J, bias, jacobian_dot

    def __repr__(self) -> str:
        return f"Output(h={getattr(self.h, '__name__', self.h)!r})"

    @staticmethod
    def _call(function: Callable, name: str, args: tuple, shape: tuple[int, ...] | None) -> np.ndarray:
        try:
            result = np.asarray(function(*args), dtype=float)
        except ModelError:
            raise
        except (TypeError, ValueError, ArithmeticError) as error:
            raise ModelError(f"output's {name} failed: {error}") from None
        if (shape is not None and result.shape != shape) or result.ndim == 0:
            raise ModelError(f"output's {name} must return shape {shape}, got {result.shape}")
        if not np.all(np.isfinite(result)):
            raise ModelError(f"output's {name} returned NaN or infinity at q = {args[0]}")
        return result

    def _rows_of(self, arm: Robot, q: np.ndarray) -> int:
        first = self._call(self.J, "J", (q[0].copy(),), None)
        if first.ndim != 2 or first.shape[1] != arm.n:
            raise ModelError(f"output's J must return shape (m, {arm.n}), got {first.shape}")
        return first.shape[0]

    def _value(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        if not q.shape[0]:
            return np.empty((0, 0))
        first = self._call(self.h, "h", (q[0].copy(),), None)
        if first.ndim != 1:
            raise ModelError(f"output's h must return a 1-D array, got shape {first.shape}")
        return np.stack([first] + [self._call(self.h, "h", (x.copy(),), first.shape) for x in q[1:]])

    def _jacobian(self, arm: Robot, q: np.ndarray) -> np.ndarray:
        if not q.shape[0]:
            return np.empty((0, 0, arm.n))
        m = self._rows_of(arm, q)
        return np.stack([self._call(self.J, "J", (x.copy(),), (m, arm.n)) for x in q])

    def _jacobian_dot(self, arm: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        if self._jacobian_dot_function is None:
            raise ModelError("output has no jacobian_dot callable: give Output(..., jacobian_dot=...) for Jdot")
        if not q.shape[0]:
            return np.empty((0, 0, arm.n))
        m = self._rows_of(arm, q)
        function = self._jacobian_dot_function
        return np.stack(
            [self._call(function, "jacobian_dot", (x.copy(), v.copy()), (m, arm.n)) for x, v in zip(q, qd, strict=True)]
        )

    def _bias(self, arm: Robot, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        if self._bias_function is None:
            return super()._bias(arm, q, qd)
        if not q.shape[0]:
            return np.empty((0, 0))
        m = self._rows_of(arm, q)
        function = self._bias_function
        return np.stack([self._call(function, "bias", (x.copy(), v.copy()), (m,)) for x, v in zip(q, qd, strict=True)])


_ROW_OUTPUTS = (ToolPosition, ToolPose, LinkPoint, PlanarPosition)


# ----- conditioning and the (damped) inverse ------------------------------------------------------
def _condition(J: np.ndarray) -> np.ndarray:
    """sigma_max / sigma_min of each (m, n) J with m <= n; inf for a rank-deficient one, never NaN."""
    if J.shape[0] == 0:
        return np.empty(0)
    s = np.linalg.svd(J, compute_uv=False)
    largest, smallest = s[:, 0], s[:, -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.where(smallest > 0, largest / np.where(smallest > 0, smallest, 1.0), np.inf)
    return np.where(largest > 0, cond, np.inf)


def condition_number(arm: Robot, output: TaskOutput, q: ArrayLike) -> np.ndarray:
    """The condition number sigma_max / sigma_min of the output's J(q) (inf when singular).

    Parameters
    ----------
    arm : Robot
        The arm.
    output : TaskOutput
        The task output.
    q : array_like
        Joint positions, (n,) or a batch (..., n).

    Returns
    -------
    numpy.ndarray
        The condition numbers, shape (...) (a 0-d array for one state).

    Raises
    ------
    ModelError
        When an argument is invalid or the output has more rows than the arm has joints.
    """
    arm, output = _check_arm(arm), _check_output(output)
    batch, (flat,) = _states(arm, ("q",), (q,))
    J = output._jacobian(arm, flat)
    _rows(arm, output, J, square=False)
    return _condition(J).reshape(batch)


def damped_inverse(J: ArrayLike, damping: float) -> np.ndarray:
    """The damped least-squares inverse J^T (J J^T + damping^2 I)^-1, by a linear solve.

    Parameters
    ----------
    J : array_like
        Jacobians, (m, n) or a batch (..., m, n).
    damping : float
        lambda, positive.

    Returns
    -------
    numpy.ndarray
        The inverse, (..., n, m).

    Raises
    ------
    ModelError
        When J is not a finite real array of two or more dimensions or damping is not positive.
    """
    matrix = inputs.numbers(J, "J")
    if matrix.ndim < 2:
        raise ModelError(f"J must have shape (m, n) or (..., m, n), got {matrix.shape}")
    lam = _damping(damping)
    if lam is None:
        raise ModelError("damping must be a positive number, got None")
    A = matrix @ np.swapaxes(matrix, -1, -2) + lam**2 * np.eye(matrix.shape[-2])
    return np.swapaxes(np.linalg.solve(A, matrix), -1, -2)  # (A^-1 J)^T = J^T A^-1, A symmetric


def _damping(damping: object) -> float | None:
    if damping is None:
        return None
    value = inputs.number(damping, "damping")
    if not value > 0:
        raise ModelError(f"damping must be a positive number (or None), got {value:g}")
    return value


def _rows(arm: Robot, output: TaskOutput, J: np.ndarray, square: bool) -> int:
    m = J.shape[1] if J.ndim == 3 else 0
    if m > arm.n:
        raise ModelError(f"output {output!r} has {m} rows, more than the {arm.n} joints of arm '{arm.name}'")
    if square and m != arm.n:
        raise ModelError(
            f"output {output!r} has {m} rows but arm '{arm.name}' has {arm.n} joints: the square task-space "
            "dynamics need m = n (use operational_space for m < n)"
        )
    return m


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
        raise ModelError(
            f"J(q) of output {output!r} on arm '{arm.name}' is singular or ill-conditioned "
            f"{_where(batch, index)}(q = {np.array2string(flat[0][index], precision=4)}): its condition number "
            f"{cond[index]:.3g} exceeds max_condition = {limit:.3g}. Move away from the singularity, raise "
            "max_condition, or pass damping=... for a damped least-squares inverse"
        )
    return arm, output, _Task(batch, flat, J, damped, 0.0 if lam is None else lam)


# The compiled one-state path: the built-in row outputs, one state of float64 arrays, a float
# max_condition and no damping to check; anything else (or a state the kernel cannot certify
# regular) takes the general path, which checks the arguments and decides at singular states.
_NOT_ONE_STATE = (TypeError, ValueError, NumbaError)


def _compiled(arm: object, output: object, m: int | None, damping: object, limit: object) -> tuple | None:
    """(target, rows) when the compiled one-state kernels may take the call (with m rows if given)."""
    if type(output) not in _ROW_OUTPUTS or not isinstance(arm, Robot) or type(limit) is not float:
        return None
    if damping is not None and not (type(damping) is float and damping > 0):
        return None
    spec = output._compiled()
    return None if m is not None and spec[1].shape[0] != m else spec


def _kernel(
    arm: object,
    output: object,
    kind: int,
    damping: object,
    limit: object,
    matrix: bool,
    q: object,
    qd: object = None,
    v: object = None,
    v_name: str = "",
) -> np.ndarray | None:
    """The compiled route of a square quantity (operational.task_one, or task_batch for a batch):
    (n, n) when ``matrix``, else (n,); None when the general path must take the call: another
    output, an argument to check, or a state the kernel cannot certify regular."""
    fast = _compiled(arm, output, getattr(arm, "n", None), damping, limit)
    if fast is None:
        return None
    n = arm.n
    result = np.empty((n, n) if matrix else (1, n))
    try:
        status = task_one(arm.packed, q, q if qd is None else qd, q if v is None else v, *fast, limit, kind, result)
        if status == 0:
            return result if matrix else result[0]
    except _NOT_ONE_STATE:
        if (states := inputs.thawed(q, qd, v)) is not None:
            return _kernel(arm, output, kind, damping, limit, matrix, *states, v_name)
    if arm.packed is None:
        return None
    named = [("q", q)] + ([("qd", qd)] if qd is not None else []) + ([(v_name, v)] if v is not None else [])
    try:
        batch, flat = inputs.batch_states([name for name, _ in named], [value for _, value in named], n)
    except ModelError:
        return None  # the general path names the argument
    q_flat = flat[0]
    qd_flat = flat[1] if qd is not None else q_flat
    v_flat = flat[-1] if v is not None else q_flat
    count = q_flat.shape[0]
    out, status = np.empty((count, *result.shape)), np.ones(count, dtype=np.int64)
    if count:
        _launch(task_batch, out.size, arm.packed, q_flat, qd_flat, v_flat, *fast, limit, kind, out, status)
    if status.any():
        return None
    return out.reshape(*batch, n, n) if matrix else out.reshape(*batch, n)


# ----- square outputs: Mbar, Vmbar, Gbar, Nbar (BOOK.md section 6) --------------------------------
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
    """Mbar = J^-T M J^-1, the inertia in the output's coordinates (BOOK.md section 6).

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
        When an argument is invalid, m != n, or J is ill-conditioned at a state and no
        damping is given (the message names the state and the condition number).
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
    result = _kernel(arm, output, kernels.LAMBDA, damping, max_condition, True, q)
    if result is not None:  # at a regular state Mbar = Lambda = (J M^-1 J^T)^-1
        return _into(out, result)
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
    """Vmbar = J^-T (Vm - M J^-1 Jdot) J^-1, with Mbar_dot - 2 Vmbar skew (BOOK.md section 6).

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
    result = _kernel(arm, output, kernels.CORIOLIS, damping, max_condition, True, q, qd)
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
    """Gbar = J^-T G (BOOK.md section 6).

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
    result = _kernel(arm, output, kernels.GRAVITY, damping, max_condition, False, q)
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
    """Nbar = J^-T (N - M J^-1 Jdot qd), N = Vm qd + F + G (BOOK.md section 6).

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
    result = _kernel(arm, output, kernels.NONLINEAR, damping, max_condition, False, q, qd)
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
    """Fbar = J^-T F(qd), the friction in output coordinates (BOOK.md section 6).

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
    result = _kernel(arm, output, kernels.FRICTION, damping, max_condition, False, q, qd)
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
    """Wbar = J^-T W(q, qd, qdd) at qdd = J^-1 (yddot - Jdot qd): f = Wbar phi (BOOK.md section 6).

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
    result = _kernel(arm, output, kernels.FORCE, damping, max_condition, False, q, None, tau, "tau")
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
            if task_one(arm.packed, q, qd, padded, fast[0], fast[1], 1.0, kernels.FORWARD, result) == 0:
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
    result = _kernel(arm, output, kernels.INVERSE, damping, max_condition, False, q, qd, yddot, "yddot")
    if result is not None:
        return _into(out, result)
    arm, output, task = _task(arm, output, ("q", "qd", "yddot"), (q, qd, yddot), damping, max_condition, True)
    fq, fqd, acc = task.states
    qdd = task.inverse((acc - output._bias(arm, fq, fqd))[:, :, None])[:, :, 0]
    tau = arm.inverse_dynamics(fq, fqd, qdd)
    return _into(out, _shaped(task.inverse_transpose(tau[:, :, None])[:, :, 0], task.batch))


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

    Returns
    -------
    OperationalSpace
        The quantities, each with the batch shape in front.

    Raises
    ------
    ModelError
        When an argument is invalid, m > n, or J is ill-conditioned at a state and no
        damping is given (the message names the state and the condition number).
    """
    fast = _compiled(arm, output, None, damping, max_condition)
    if fast is not None:
        n, m = arm.n, fast[1].shape[0]
        parts = (np.empty((m, n)), np.empty((m, m)), np.empty((n, m)), np.empty(m), np.empty(m), np.empty(m),
                 np.empty((n, n)))  # fmt: skip
        try:
            if operational_one(arm.packed, q, qd, fast[0], fast[1], max_condition, *parts) == 0:
                return OperationalSpace(*parts)
        except _NOT_ONE_STATE:
            if (states := inputs.thawed(q, qd)) is not None:
                return operational_space(arm, output, *states, damping=damping, max_condition=max_condition)
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
    return OperationalSpace(*(_shaped(x, b) for x in (J, Lambda, Jbar, mu, p, friction, Nproj)))


def operational_coriolis(
    arm: Robot,
    output: TaskOutput,
    q: ArrayLike,
    qd: ArrayLike,
    *,
    damping: float | None = None,
    max_condition: float = DEFAULT_MAX_CONDITION,
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
    return mu_x, _mv(K, _mv(Nproj, fqd)).reshape(*batch, m)


# ----- control in task coordinates ------------------------------------------------------------------
@dataclass(frozen=True)
class Circle:
    """A circle in task coordinates (Example 4.2-1): y_d = c + r [cos wt, sin wt] in the first
    two coordinates, w = 2 pi / period, with its velocity and acceleration; a third coordinate
    of the centre, if given, is held (a circle parallel to the x-y plane, for ToolPosition).

    Parameters
    ----------
    centre : sequence of 2 or 3 float
        The centre c (m).
    radius : float
        The radius r (m), at least 0.
    period : float
        The time of one turn (s), positive.
    """

    centre: tuple[float, ...]
    radius: float
    period: float

    def __post_init__(self) -> None:
        centre = inputs.numbers(self.centre, "centre", None, " of a Circle")
        if centre.shape not in ((2,), (3,)):
            raise ModelError(f"centre of a Circle must have 2 or 3 coordinates, got shape {centre.shape}")
        object.__setattr__(self, "centre", tuple(centre))
        object.__setattr__(self, "radius", inputs.number(self.radius, "radius", " of a Circle", minimum=0.0))
        if not inputs.number(self.period, "period", " of a Circle") > 0:
            raise ModelError(f"period of a Circle must be positive, got {self.period!r}")

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y_d, yd_d, ydd_d) at time t (s), each of the centre's length.

        Parameters
        ----------
        t : float
            The time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The desired position, velocity and acceleration.

        Raises
        ------
        armdyn.ModelError
            When ``t`` is not a finite number.
        """
        w = 2.0 * np.pi / self.period
        angle = w * inputs.number(t, "t")
        ring, turn = np.zeros(len(self.centre)), np.zeros(len(self.centre))
        ring[:2], turn[:2] = (np.cos(angle), np.sin(angle)), (-np.sin(angle), np.cos(angle))
        return np.array(self.centre) + self.radius * ring, self.radius * w * turn, -self.radius * w * w * ring


def _quintic(t: float, start_time: float, duration: float) -> tuple[float, float, float]:
    """s(t) = 10 u^3 - 15 u^4 + 6 u^5, u = (t - t0) / T held in [0, 1], with its first two rates."""
    u = min(max((t - start_time) / duration, 0.0), 1.0)
    s = u**3 * (10.0 - 15.0 * u + 6.0 * u * u)
    if u in (0.0, 1.0):
        return s, 0.0, 0.0
    return s, 30.0 * u * u * (1.0 - u) ** 2 / duration, 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / duration**2


@dataclass(frozen=True)
class Line:
    """A straight line in task coordinates with a quintic time law: y_d = a + s(t) (b - a),
    s = 10 u^3 - 15 u^4 + 6 u^5, u = (t - start_time) / duration held in [0, 1], so the motion
    starts and stops with zero velocity and acceleration.

    Parameters
    ----------
    start, end : sequence of float
        The end points a and b, of the output's length m (m for positions).
    duration : float
        The time of the motion (s), positive.
    start_time : float, optional
        When the motion starts (s); default 0. Before it y_d = a, after it y_d = b.
    """

    start: tuple[float, ...]
    end: tuple[float, ...]
    duration: float
    start_time: float = 0.0

    def __post_init__(self) -> None:
        start = inputs.numbers(self.start, "start", None, " of a Line")
        end = inputs.numbers(self.end, "end", None, " of a Line")
        if start.ndim != 1 or end.shape != start.shape or not start.size:
            raise ModelError(f"start and end of a Line must be two points of one length, got shapes {start.shape} "
                             f"and {end.shape}")  # fmt: skip
        object.__setattr__(self, "start", tuple(start))
        object.__setattr__(self, "end", tuple(end))
        if not inputs.number(self.duration, "duration", " of a Line") > 0:
            raise ModelError(f"duration of a Line must be positive, got {self.duration!r}")
        object.__setattr__(self, "start_time", inputs.number(self.start_time, "start_time", " of a Line"))

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y_d, yd_d, ydd_d) at time t (s), each (m,).

        Parameters
        ----------
        t : float
            The time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The desired position, velocity and acceleration.

        Raises
        ------
        armdyn.ModelError
            When ``t`` is not a finite number.
        """
        s, sd, sdd = _quintic(inputs.number(t, "t"), self.start_time, self.duration)
        a, b = np.array(self.start), np.array(self.end)
        return a + s * (b - a), sd * (b - a), sdd * (b - a)


def _pose(pose: object, name: str) -> np.ndarray:
    """A checked 4 x 4 homogeneous pose: finite, a proper rotation to 1e-6, last row [0, 0, 0, 1]."""
    T = inputs.numbers(pose, name, (4, 4), " of a PoseLine")
    R = T[:3, :3]
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0 or np.abs(T[3] - [0, 0, 0, 1]).max() > 0:
        raise ModelError(f"{name} of a PoseLine must be a homogeneous pose: a rotation (R R^T = I, det R = 1) and "
                         "the last row [0, 0, 0, 1]")  # fmt: skip
    return T


@dataclass(frozen=True)
class PoseLine:
    """A tool pose path for ToolPose: the position on the straight line from the start pose to the
    end pose, the rotation about one fixed world axis, both with the quintic law of ``Line``.

    R_d(t) = exp(s(t) [u]x) R_a with u the rotation vector of R_b R_a^T; the angular velocity is
    sdot u and the angular acceleration sddot u (world axes). Gives (y_d, yd_d, ydd_d) in ToolPose's
    coordinates: y_d = [p; rotation vector of R_d], yd_d = [v; w], ydd_d = [a; alpha].

    Parameters
    ----------
    start, end : array_like
        The 4 x 4 homogeneous start and end poses (e.g. from ``arm.tool_pose(q)``).
    duration : float
        The time of the motion (s), positive.
    start_time : float, optional
        When the motion starts (s); default 0.
    """

    start: np.ndarray
    end: np.ndarray
    duration: float
    start_time: float = 0.0

    def __post_init__(self) -> None:
        from scipy.spatial.transform import Rotation

        start, end = _pose(self.start, "start"), _pose(self.end, "end")
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "end", end)
        if not inputs.number(self.duration, "duration", " of a PoseLine") > 0:
            raise ModelError(f"duration of a PoseLine must be positive, got {self.duration!r}")
        object.__setattr__(self, "start_time", inputs.number(self.start_time, "start_time", " of a PoseLine"))
        object.__setattr__(self, "_axis", Rotation.from_matrix(end[:3, :3] @ start[:3, :3].T).as_rotvec())

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(y_d, yd_d, ydd_d) at time t (s), each (6,).

        Parameters
        ----------
        t : float
            The time (s).

        Returns
        -------
        tuple of numpy.ndarray
            The desired pose [p; rotation vector], twist [v; w] and its rate.

        Raises
        ------
        armdyn.ModelError
            When ``t`` is not a finite number.
        """
        from scipy.spatial.transform import Rotation

        s, sd, sdd = _quintic(inputs.number(t, "t"), self.start_time, self.duration)
        a, b, u = self.start[:3, 3], self.end[:3, 3], self._axis
        R = Rotation.from_rotvec(s * u).as_matrix() @ self.start[:3, :3]
        y = np.concatenate([a + s * (b - a), Rotation.from_matrix(R).as_rotvec()])
        return y, np.concatenate([sd * (b - a), sd * u]), np.concatenate([sdd * (b - a), sdd * u])


def _desired(path: Callable, t: float, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """path(t), checked: three arrays of m finite values."""
    try:
        parts = tuple(path(t))
    except TypeError as error:
        raise ModelError(f"path(t) must return (y_d, yd_d, ydd_d): {error}") from None
    if len(parts) != 3:
        raise ModelError(f"path(t) must return three arrays (y_d, yd_d, ydd_d), got {len(parts)} items at t = {t:g}")
    return tuple(inputs.numbers(part, name, (m,), f" from path(t) at t = {t:g}")
                 for part, name in zip(parts, ("y_d", "yd_d", "ydd_d"), strict=True))  # fmt: skip


@dataclass(frozen=True)
class Tracking:
    """The task-space record of a run under a task-space controller (``Result.task``).

    Parameters
    ----------
    output : str
        The output's description, e.g. "ToolPose()".
    y : numpy.ndarray
        The output at every sample, (T, k) as ``TaskOutput.value`` gives it.
    y_d : numpy.ndarray
        The desired output, (T, k).
    error : numpy.ndarray
        The task error e = y_d - y (ToolPose: its orientation part as in ``TaskOutput.error``), (T, m).
    """

    output: str
    y: np.ndarray
    y_d: np.ndarray
    error: np.ndarray


class ComputedTorque:
    """Computed-torque control in task coordinates (BOOK.md section 6):
    tau = J^T (Mbar (yddot_d + Kv edot + Kp e) + Nbar), e = y_d - y, edot = yd_d - J qd.

    It decouples the task coordinates into double integrators with PD feedback, for a square,
    nonsingular J (a singular J is a ModelError, see ``task_inertia``). Computed as
    J^T (Lambda a + mu + p + friction) from ``operational_space`` (one compiled call for the
    built-in outputs), which is the same for m = n. For ToolPose the orientation error is the
    rotation vector of R_d R^T (``TaskOutput.error``) and the rates are [v; w]. A controller for
    ``armdyn.simulate``: ``path(t)`` gives (y_d, yd_d, ydd_d) (a Circle, Line or PoseLine); the
    model is ``model`` or, inside simulate, the plant; simulate's Result then carries the task
    error (``Result.task``).

    Parameters
    ----------
    output : TaskOutput
        The task coordinates y = h(q), with m = n.
    path : callable
        t -> (y_d, yd_d, ydd_d), e.g. a Circle, Line or PoseLine.
    kp, kv : float
        The proportional and derivative gains (1/s^2, 1/s).
    model : Robot, optional
        The arm the law computes with; default the plant ``simulate`` passes.
    """

    square = True

    def __init__(self, output: TaskOutput, path: Callable, kp: float, kv: float, model: Robot | None = None) -> None:
        self.output = _check_output(output)
        if not callable(path) or isinstance(path, type):
            raise ModelError(f"path must be a callable t -> (y_d, yd_d, ydd_d), got {path!r}")
        self.path = path
        self.kp = inputs.number(kp, "kp", minimum=0.0)
        self.kv = inputs.number(kv, "kv", minimum=0.0)
        self.model = None if model is None else _check_arm(model)

    def _arm(self, plant: Robot | None) -> Robot:
        arm = self.model if self.model is not None else plant
        if arm is None:
            raise ModelError(f"{type(self).__name__} needs a model of the arm (model=...) outside simulate()")
        return arm

    def _task_force(self, arm: Robot, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[OperationalSpace, np.ndarray]:
        """The operational space at (q, qd) and f = Lambda (yddot_d + kv edot + kp e) + mu + p + friction."""
        space = operational_space(arm, self.output, q, qd)
        m = space.J.shape[-2]
        if self.square and m != arm.n:
            raise ModelError(f"{type(self).__name__} needs a square output (m = n = {arm.n}); {self.output!r} has "
                             f"{m} rows: use OperationalSpaceControl for a redundant arm")  # fmt: skip
        y_d, yd_d, ydd_d = _desired(self.path, t, len(self.output.value(arm, q)))
        e, edot = self.output.error(arm, q, y_d), yd_d[:m] - space.J @ qd if len(yd_d) == m else None
        if edot is None:
            raise ModelError(f"path(t) must give a velocity and an acceleration of {m} values for {self.output!r}")
        force = space.Lambda @ (ydd_d + self.kv * edot + self.kp * e) + space.mu + space.p + space.friction
        return space, force

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray, *joint_reference: object, plant: Robot | None = None
    ) -> np.ndarray:
        """The torque at time t for the state (q, qd); the joint-space reference simulate passes
        is not used.

        Parameters
        ----------
        t : float
            The time (s).
        q, qd : numpy.ndarray
            The joint positions and velocities, (n,).
        *joint_reference : object
            simulate's joint-space reference (q_d, qd_d, qdd_d, e_int), ignored.
        plant : Robot, optional
            The arm simulated, used when the law has no model of its own.

        Returns
        -------
        numpy.ndarray
            tau, (n,).

        Raises
        ------
        armdyn.ModelError
            When there is no arm to compute with, J is singular, the output is not square, or
            the path gives values of the wrong length.
        """
        space, force = self._task_force(self._arm(plant), t, q, qd)
        return space.J.T @ force

    def tracking(self, arm: Robot, t: np.ndarray, q: np.ndarray) -> Tracking:
        """The task-space record of a run: y, y_d and e at the times t.

        Parameters
        ----------
        arm : Robot
            The plant (used when the law has no model of its own).
        t : numpy.ndarray
            The times, (T,).
        q : numpy.ndarray
            The joint positions, (T, n).

        Returns
        -------
        Tracking
            The output, its desired value and the task error at every sample.

        Raises
        ------
        armdyn.ModelError
            When there is no arm, or the path gives values of the wrong length.
        """
        arm = self._arm(arm)
        y = self.output.value(arm, q)
        k = y.shape[-1]
        y_d = np.array([_desired(self.path, float(time), k)[0] for time in t]).reshape(len(t), k)
        return Tracking(repr(self.output), y, y_d, self.output.error(arm, q, y_d))

    def describe(self) -> str:
        """The law and its gains, for titles and reports.

        Returns
        -------
        str
            A short description.

        Raises
        ------
        None
            It only formats the gains.
        """
        return f"task-space computed torque on {self.output!r} (kp = {self.kp:g}, kv = {self.kv:g})"


class OperationalSpaceControl(ComputedTorque):
    """Operational-space control of a redundant arm (Khatib 1987): the task by computed torque
    in task coordinates, a joint posture in the null space,
    tau = J^T (Lambda (yddot_d + kv edot + kp e) + mu + p + friction) + Nproj^T tau_0,
    tau_0 = M (kp0 (q_0 - q) - kv0 qd), e = y_d - y, edot = yd_d - J qd.

    The null-space torque leaves the task acceleration unchanged (J M^-1 Nproj^T = 0: the
    generalized inverse is dynamically consistent), so the task error obeys
    edd + kv ed + kp e = 0 whatever the posture does. A controller for ``armdyn.simulate``,
    whose Result then carries the task error (``Result.task``).

    Parameters
    ----------
    output : TaskOutput
        The task coordinates (m <= n): ToolPosition, ToolPose (orientation error as in
        ``TaskOutput.error``), LinkPoint, PlanarPosition or an Output.
    path : callable
        t -> (y_d, yd_d, ydd_d), e.g. a Line or PoseLine.
    kp, kv : float
        The task gains (1/s^2, 1/s).
    posture : callable or array_like
        The joint posture q_0: a fixed (n,) configuration or a callable t -> q_0(t).
    kp0, kv0 : float
        The posture gains (1/s^2, 1/s).
    model : Robot, optional
        The arm the law computes with; default the plant ``simulate`` passes.
    """

    square = False

    def __init__(
        self,
        output: TaskOutput,
        path: Callable,
        kp: float,
        kv: float,
        posture: object,
        kp0: float,
        kv0: float,
        model: Robot | None = None,
    ) -> None:
        super().__init__(output, path, kp, kv, model)
        self.posture = posture if callable(posture) else inputs.numbers(posture, "posture")
        self.kp0 = inputs.number(kp0, "kp0", minimum=0.0)
        self.kv0 = inputs.number(kv0, "kv0", minimum=0.0)

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray, *joint_reference: object, plant: Robot | None = None
    ) -> np.ndarray:
        """The torque at time t for the state (q, qd); simulate's joint reference is not used.

        Parameters
        ----------
        t : float
            The time (s).
        q, qd : numpy.ndarray
            The joint positions and velocities, (n,).
        *joint_reference : object
            simulate's joint-space reference, ignored.
        plant : Robot, optional
            The arm simulated, used when the law has no model of its own.

        Returns
        -------
        numpy.ndarray
            tau, (n,).

        Raises
        ------
        armdyn.ModelError
            When there is no arm to compute with, J is singular, the path gives values of the
            wrong length, or the posture has the wrong length.
        """
        arm = self._arm(plant)
        space, force = self._task_force(arm, t, q, qd)
        target = np.asarray(self.posture(t) if callable(self.posture) else self.posture, dtype=float)
        if target.shape != q.shape:
            raise ModelError(f"posture must have {q.shape[0]} values, got shape {target.shape}")
        tau_0 = arm.inertia_matrix(q) @ (self.kp0 * (target - q) - self.kv0 * qd)
        return space.J.T @ force + space.Nproj.T @ tau_0

    def describe(self) -> str:
        """The law and its gains, for titles and reports.

        Returns
        -------
        str
            A short description.

        Raises
        ------
        None
            It only formats the gains.
        """
        return (
            f"operational-space control on {self.output!r} (kp = {self.kp:g}, kv = {self.kv:g}; "
            f"posture kp0 = {self.kp0:g}, kv0 = {self.kv0:g})"
        )
