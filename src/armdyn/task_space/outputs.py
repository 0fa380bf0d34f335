"""Task outputs y = h(q) with their Jacobians, Jdot and bias Jdot qd, the condition number of J
and the damped least-squares inverse (Section 3.5; Nakamura and Hanafusa 1986, Wampler 1986).

Outputs (each a small class with ``value``, ``jacobian``, ``jacobian_dot`` and ``bias`` =
Jdot qd, all batched over leading dimensions): ToolPosition, ToolPose, LinkPoint,
PlanarPosition, Camera, and Output for user callables.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, cast

import numpy as np

from armdyn import inputs, kinematics
from armdyn.dynamics.frames import TOOL
from armdyn.errors import ArgumentError, ModelError
from armdyn.robot import Robot

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


DEFAULT_MAX_CONDITION = 1e8
"""The condition number of J above which a state counts as singular (without ``damping``)."""


# ----- argument checks ----------------------------------------------------------------------------
def _check_arm(arm: object) -> Robot:
    inputs.arm_argument(arm, Robot, name="arm", numeric=True, why=" (task-space dynamics)")
    return cast(Robot, arm)


def _check_output(output: object) -> TaskOutput:
    if not isinstance(output, TaskOutput):
        raise ArgumentError(
            "output must be a task output of armdyn.task_space (ToolPosition, ToolPose, LinkPoint, "
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
    armdyn.ArgumentError
        When an argument given is not callable (a ModelError and a TypeError).
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
                raise ArgumentError(f"{name} must be a callable, got {type(function).__name__}")
        if not (jacobian_dot is None or callable(jacobian_dot)):
            raise ArgumentError(f"jacobian_dot must be a callable or None, got {type(jacobian_dot).__name__}")
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
