"""Contacts on a link point: their simulation, and their isolation and identification from a residual.

A force F (world axes) at a point p fixed on link i acts on the joints as the external torque
tau_ext = J_p(q)^T F, J_p the linear rows of the point's geometric Jacobian (Lewis, Dawson and
Abdallah 2004, Section 3.2 and Appendix A). ``Push``, ``Impulse`` and ``Clamp`` are such forces as
functions of time or state, each a ``disturbance`` of ``armdyn.simulate`` (which integrates
M qdd + N + tau_d = tau, so that the contact enters as tau_d = -tau_ext). ``contact_link``,
``estimate_force`` and ``estimate_wrench`` go the other way, from a residual r = tau_ext (of a
momentum observer) to the link in contact and the force on it, as in Haddadin, De Luca and
Albu-Schaeffer, "Robot Collisions: A Survey on Detection, Isolation, and Identification", IEEE
T-RO 33(6), 2017, Sections IV-V.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import cast

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from armdyn import inputs
from armdyn.dynamics.packed import HEADER, KIND, LINK_POSITION, LINK_ROTATION, N_JOINTS, PARENT, STRIDE
from armdyn.dynamics.spatial import NUMBA_OPTIONS, joint_transform, world_pose
from armdyn.errors import ModelError
from armdyn.kinematics import _columns, _skew, _target, as_state, check_arm, link_index, link_transforms
from armdyn.model import ArmModel

__all__ = [
    "OBSERVABLE_CONDITION",
    "Clamp",
    "ContactObservabilityWarning",
    "ForceEstimate",
    "Impulse",
    "Push",
    "contact_link",
    "contacts_table",
    "estimate_force",
    "estimate_wrench",
    "point_jacobian",
]

OBSERVABLE_CONDITION = 1e3  # above this condition number of J_p^T the force is taken as not observable

# One contact as a row of simulate's compiled loop (contacts_table): a push (Push, and Impulse as a push of
# duration ``width``) or a clamp, its link and point, its force or spring, and a clamp's anchor once taken.
PUSH_KIND, CLAMP_KIND = 0.0, 1.0
(ROW_KIND, ROW_LINK, ROW_POINT, ROW_FORCE, ROW_START, ROW_DURATION, ROW_RISE, ROW_STIFFNESS, ROW_DAMPING, ROW_ANCHOR,
 ROW_ANCHORED, ROW_SIZE) = 0, 1, 2, 5, 8, 9, 10, 11, 12, 13, 16, 17  # fmt: skip


class ContactObservabilityWarning(UserWarning):
    """The contact force (or wrench) is not observable from the joints that move the point: fewer joints
    than unknowns, or J_p^T too ill-conditioned (condition number above OBSERVABLE_CONDITION)."""


def _point(value: object, name: str = "point") -> np.ndarray:
    return inputs.numbers(value, name, (3,), " (x, y, z in metres)")


def point_jacobian(arm: ArmModel, q: ArrayLike, link: int | str, point: ArrayLike) -> np.ndarray:
    """The geometric Jacobian of a point fixed on a link, (..., 6, n): [v_p; w] = J qd, world axes, linear rows first.

    From the Jacobian of the link frame's origin o (Appendix A) and the point's offset R p in the world:
    v_p = v_o + w x (R p), so Jv_p = Jv_o - [R p]x Jw and Jw is unchanged.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    link : int or str
        The link carrying the point, by index or name.
    point : array_like
        The point in the link's frame, (3,), metres.

    Returns
    -------
    numpy.ndarray
        J_p, (..., 6, n); the columns of joints that do not move the link are zero.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not finite numbers of shape (..., n), the link does not exist, or ``point`` is not
        three finite numbers.
    armdyn.ArgumentError
        When ``arm`` is not a numeric arm.
    """
    check_arm(arm)
    index = link_index(arm, link)
    offset = _point(point)
    q = as_state(arm, q)
    _, pose, z, o = _target(arm, q, index)  # as jacobian(arm, q, link=index): one pass over the chain for both
    origin = _columns(arm, z, o, pose[..., :3, 3], arm.ancestors[index])
    lever = pose[..., :3, :3] @ offset
    linear = origin[..., :3, :] - _skew(lever) @ origin[..., 3:, :]
    return np.concatenate([linear, origin[..., 3:, :]], axis=-2)


def _point_position(arm: ArmModel, q: np.ndarray, link: int, point: np.ndarray) -> np.ndarray:
    pose = link_transforms(arm, q)[..., link, :, :]
    return pose[..., :3, :3] @ point + pose[..., :3, 3]


def _time(value: object, name: str, where: str) -> float:
    return inputs.number(value, name, where)


def _duration(value: object, name: str, where: str) -> float:
    """A positive number of seconds, infinity allowed."""
    if not isinstance(value, (bool, np.bool_)) and isinstance(value, (int, float, np.number)) and value == math.inf:
        return math.inf
    result = inputs.number(value, name, where)
    if result <= 0:
        raise ModelError(f"{name} must be positive{where}, got {result:g}")
    return result


class _Contact:
    """What every contact shares: the arm, the link and point, tau_ext = J_p^T F, tau_d = -tau_ext."""

    arm: ArmModel
    link: int | str
    point: ArrayLike

    def _place(self, where: str) -> None:
        check_arm(self.arm)
        object.__setattr__(self, "link", link_index(self.arm, self.link))
        object.__setattr__(self, "point", _point(self.point, f"{where} point"))

    def force(self, t: float, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """F (3,), world axes, N (defined by each contact)."""
        raise NotImplementedError

    def external_torque(self, t: float, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """tau_ext = J_p(q)^T F(t, q, qd), (n,): the contact's torque on the joints.

        Parameters
        ----------
        t : float
            Time, s.
        q, qd : array_like
            Joint positions and velocities, (n,).

        Returns
        -------
        numpy.ndarray
            tau_ext, (n,).

        Raises
        ------
        armdyn.ModelError
            When q or qd is not n finite numbers.
        """
        q = as_state(self.arm, q)
        force = self.force(t, q, qd)
        if not np.any(force):  # no contact: no Jacobian needed
            return np.zeros(np.broadcast_shapes(q.shape, force.shape[:-1] + (1,)))
        linear = point_jacobian(self.arm, q, self.link, self.point)[..., :3, :]
        return np.einsum("...an,...a->...n", linear, force)

    def row(self) -> np.ndarray:
        """The contact as one row of ``contacts_table`` (the layout ROW_*)."""
        raise NotImplementedError

    def _row(self, kind: float) -> np.ndarray:
        row = np.zeros(ROW_SIZE)
        row[ROW_KIND], row[ROW_LINK] = kind, float(cast(int, self.link))
        row[ROW_POINT : ROW_POINT + 3] = np.asarray(self.point, dtype=float)
        return row

    def __call__(self, t: float, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """tau_d = -tau_ext, the disturbance of ``armdyn.simulate`` (M qdd + N + tau_d = tau).

        Parameters
        ----------
        t : float
            Time, s.
        q, qd : array_like
            Joint positions and velocities, (n,).

        Returns
        -------
        numpy.ndarray
            tau_d, (n,).

        Raises
        ------
        armdyn.ModelError
            When q or qd is not n finite numbers.
        """
        return -self.external_torque(t, q, qd)


def _force_vector(value: object, where: str) -> np.ndarray:
    return inputs.numbers(value, f"{where} force", (3,), " (Fx, Fy, Fz in newtons, world axes)")


@dataclass(frozen=True, eq=False)
class Push(_Contact):
    """A constant force F on a link point from ``start`` for ``duration`` seconds, reached linearly over ``rise``.

    F(t) = s(t) F with s = min(1, (t - start) / rise) (1 at once when rise = 0) for start <= t < start + duration,
    and 0 otherwise. Callable as the disturbance of ``armdyn.simulate``: tau_d = -J_p^T F.

    Parameters
    ----------
    arm : ArmModel
        The arm the contact acts on.
    link : int or str
        The link, by index or name.
    point : array_like
        The point in the link's frame, (3,), m.
    force_vector : array_like
        F, (3,), N, world axes (``force(t)`` is the force at time t).
    start : float
        When the push begins, s.
    duration : float, optional
        How long it lasts, s (default infinity).
    rise : float, optional
        The linear ramp's length, s, >= 0 (default 0: a step).

    Raises
    ------
    armdyn.ModelError
        When the link does not exist, the point or force is not three finite numbers, start is not finite,
        duration is not positive, or rise is negative.
    """

    arm: ArmModel
    link: int | str
    point: ArrayLike
    force_vector: ArrayLike
    start: float
    duration: float = math.inf
    rise: float = 0.0

    def __post_init__(self) -> None:
        self._place("Push")
        object.__setattr__(self, "force_vector", _force_vector(self.force_vector, "Push"))
        object.__setattr__(self, "start", _time(self.start, "start", " of Push"))
        object.__setattr__(self, "duration", _duration(self.duration, "duration", " of Push"))
        object.__setattr__(self, "rise", inputs.number(self.rise, "rise", " of Push", minimum=0.0))

    def force(self, t: float, q: ArrayLike | None = None, qd: ArrayLike | None = None) -> np.ndarray:
        """F(t), (3,), N, world axes (q and qd are not used).

        Parameters
        ----------
        t : float
            Time, s.
        q, qd : array_like, optional
            The state (unused: the push depends on time only).

        Returns
        -------
        numpy.ndarray
            F(t), (3,).

        Raises
        ------
        armdyn.ModelError
            When t is not a finite number.
        """
        t = _time(t, "t", " of Push.force")
        elapsed = t - self.start
        if elapsed < 0 or elapsed >= self.duration:
            return np.zeros(3)
        scale = 1.0 if self.rise == 0 else min(1.0, elapsed / self.rise)
        return scale * np.asarray(self.force_vector)

    def row(self) -> np.ndarray:
        """The push as one row of ``contacts_table``.

        Returns
        -------
        numpy.ndarray
            (ROW_SIZE,).
        """
        row = self._row(PUSH_KIND)
        row[ROW_FORCE : ROW_FORCE + 3] = np.asarray(self.force_vector)
        row[ROW_START], row[ROW_DURATION], row[ROW_RISE] = self.start, self.duration, self.rise
        return row


@dataclass(frozen=True, eq=False)
class Impulse(_Contact):
    """A rectangular force pulse: F on a link point for start <= t < start + width, 0 otherwise.

    Its impulse is F width (N s). Callable as the disturbance of ``armdyn.simulate``: tau_d = -J_p^T F.
    ``simulate``'s RK4 holds the disturbance over each step, so a width of a whole number of steps gives the
    exact impulse.

    Parameters
    ----------
    arm : ArmModel
        The arm the contact acts on.
    link : int or str
        The link, by index or name.
    point : array_like
        The point in the link's frame, (3,), m.
    force_vector : array_like
        F, (3,), N, world axes (``force(t)`` is the force at time t).
    start : float
        When the pulse begins, s.
    width : float
        Its length, s, > 0.

    Raises
    ------
    armdyn.ModelError
        When the link does not exist, the point or force is not three finite numbers, start is not finite, or
        width is not positive.
    """

    arm: ArmModel
    link: int | str
    point: ArrayLike
    force_vector: ArrayLike
    start: float
    width: float

    def __post_init__(self) -> None:
        self._place("Impulse")
        object.__setattr__(self, "force_vector", _force_vector(self.force_vector, "Impulse"))
        object.__setattr__(self, "start", _time(self.start, "start", " of Impulse"))
        width = inputs.number(self.width, "width", " of Impulse")
        if width <= 0:
            raise ModelError(f"width of Impulse must be positive, got {width:g}")
        object.__setattr__(self, "width", width)

    def force(self, t: float, q: ArrayLike | None = None, qd: ArrayLike | None = None) -> np.ndarray:
        """F(t), (3,), N, world axes (q and qd are not used).

        Parameters
        ----------
        t : float
            Time, s.
        q, qd : array_like, optional
            The state (unused).

        Returns
        -------
        numpy.ndarray
            F during the pulse, zeros outside it, (3,).

        Raises
        ------
        armdyn.ModelError
            When t is not a finite number.
        """
        t = _time(t, "t", " of Impulse.force")
        inside = self.start <= t < self.start + self.width
        return np.asarray(self.force_vector) if inside else np.zeros(3)

    def row(self) -> np.ndarray:
        """The pulse as one row of ``contacts_table``: a push of duration ``width``.

        Returns
        -------
        numpy.ndarray
            (ROW_SIZE,).
        """
        row = self._row(PUSH_KIND)
        row[ROW_FORCE : ROW_FORCE + 3] = np.asarray(self.force_vector)
        row[ROW_START], row[ROW_DURATION] = self.start, self.width
        return row


@dataclass(frozen=True, eq=False)
class Clamp(_Contact):
    """A spring-damper holding a link point where it was at ``start``: F = -K (p - anchor) - D v_p for t >= start.

    p and v_p = Jv_p qd are the point's world position and velocity. The anchor is given, or taken as the
    point's position at the first call at or after ``start`` (in ``armdyn.simulate``, the first step from
    ``start``) and kept: a new run needs a new Clamp (or ``reset()``).

    Parameters
    ----------
    arm : ArmModel
        The arm the contact acts on.
    link : int or str
        The link, by index or name.
    point : array_like
        The point in the link's frame, (3,), m.
    stiffness : float
        K, N/m, >= 0.
    damping : float
        D, N s/m, >= 0.
    start : float
        When the clamp takes hold, s.
    anchor : array_like, optional
        Where it holds the point, (3,), world, m (default: where the point is at ``start``).

    Raises
    ------
    armdyn.ModelError
        When the link does not exist, the point or anchor is not three finite numbers, stiffness or damping is
        negative, or start is not finite.
    """

    arm: ArmModel
    link: int | str
    point: ArrayLike
    stiffness: float
    damping: float
    start: float
    anchor: ArrayLike | None = None
    _held: dict = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        self._place("Clamp")
        object.__setattr__(self, "stiffness", inputs.number(self.stiffness, "stiffness", " of Clamp", minimum=0.0))
        object.__setattr__(self, "damping", inputs.number(self.damping, "damping", " of Clamp", minimum=0.0))
        object.__setattr__(self, "start", _time(self.start, "start", " of Clamp"))
        if self.anchor is not None:
            object.__setattr__(self, "anchor", _point(self.anchor, "anchor of Clamp"))
        self.reset()

    def reset(self) -> None:
        """Forget the anchor taken at the start of a run (a given anchor is kept).

        Returns
        -------
        None
        """
        self._held.clear()
        if self.anchor is not None:
            self._held["anchor"] = np.asarray(self.anchor)

    def force(self, t: float, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
        """F = -K (p - anchor) - D v_p from ``start`` on, zeros before, (3,), N, world axes.

        Parameters
        ----------
        t : float
            Time, s.
        q, qd : array_like
            Joint positions and velocities, (n,).

        Returns
        -------
        numpy.ndarray
            F, (3,).

        Raises
        ------
        armdyn.ModelError
            When t is not finite, or q or qd is not n finite numbers.
        """
        t = _time(t, "t", " of Clamp.force")
        q, qd = as_state(self.arm, q), as_state(self.arm, qd, "qd")
        if t < self.start:
            return np.zeros(q.shape[:-1] + (3,))
        position = _point_position(self.arm, q, int(self.link), np.asarray(self.point))
        anchor = self._held.setdefault("anchor", position.copy())
        velocity = point_jacobian(self.arm, q, self.link, self.point)[..., :3, :] @ qd[..., None]
        return -self.stiffness * (position - anchor) - self.damping * velocity[..., 0]

    def row(self) -> np.ndarray:
        """The clamp as one row of ``contacts_table`` (its anchor, when given or already taken).

        Returns
        -------
        numpy.ndarray
            (ROW_SIZE,).
        """
        row = self._row(CLAMP_KIND)
        row[ROW_START], row[ROW_STIFFNESS], row[ROW_DAMPING] = self.start, self.stiffness, self.damping
        if "anchor" in self._held:
            row[ROW_ANCHOR : ROW_ANCHOR + 3], row[ROW_ANCHORED] = self._held["anchor"], 1.0
        return row

    def take_anchor(self, row: np.ndarray) -> None:
        """Keep the anchor a compiled run took (``row`` as the run left it), as a call at ``start`` would.

        Parameters
        ----------
        row : numpy.ndarray
            The clamp's row after the run, (ROW_SIZE,).
        """
        if row[ROW_ANCHORED] and "anchor" not in self._held:
            self._held["anchor"] = np.array(row[ROW_ANCHOR : ROW_ANCHOR + 3])


def contacts_table(arm: ArmModel, disturbance: object) -> np.ndarray | None:
    """The contacts of a ``simulate`` disturbance as the rows of its compiled loop, or None when it is not contacts.

    Parameters
    ----------
    arm : ArmModel
        The simulated arm: every contact must act on it.
    disturbance : object
        A Push, Impulse or Clamp, or a list or tuple of them.

    Returns
    -------
    numpy.ndarray or None
        (C, ROW_SIZE), one row per contact; None when ``disturbance`` is something else.

    Raises
    ------
    armdyn.ModelError
        When a contact acts on another arm (one with other joints).
    """
    given = list(disturbance) if isinstance(disturbance, (list, tuple)) else [disturbance]
    if not given or not all(isinstance(item, _Contact) for item in given):
        return None
    items = cast(list[_Contact], given)
    for item in items:
        if item.arm is not arm and item.arm.n != arm.n:
            kind = type(item).__name__
            raise ModelError(f"the {kind} acts on an arm of {item.arm.n} joints, not the simulated arm's {arm.n}")
    return np.array([item.row() for item in items])


@njit(inline="always", **NUMBA_OPTIONS)
def _contact_force(row: np.ndarray, t: float, x: tuple, v: tuple) -> tuple[float, float, float]:
    """F (world) of one contact at time t, the point at x moving at v: the push's s(t) F, or the clamp's
    -K (x - anchor) - D v (its anchor taken at the first call from ``start`` on); zeros when inactive."""
    elapsed = t - row[ROW_START]
    if elapsed < 0.0 or (row[ROW_KIND] == PUSH_KIND and elapsed >= row[ROW_DURATION]):
        return 0.0, 0.0, 0.0
    if row[ROW_KIND] == PUSH_KIND:
        scale = 1.0 if row[ROW_RISE] == 0.0 else min(1.0, elapsed / row[ROW_RISE])
        return scale * row[ROW_FORCE], scale * row[ROW_FORCE + 1], scale * row[ROW_FORCE + 2]
    if row[ROW_ANCHORED] == 0.0:
        row[ROW_ANCHOR], row[ROW_ANCHOR + 1], row[ROW_ANCHOR + 2] = x
        row[ROW_ANCHORED] = 1.0
    stiffness, damping = row[ROW_STIFFNESS], row[ROW_DAMPING]
    return (
        -stiffness * (x[0] - row[ROW_ANCHOR]) - damping * v[0],
        -stiffness * (x[1] - row[ROW_ANCHOR + 1]) - damping * v[1],
        -stiffness * (x[2] - row[ROW_ANCHOR + 2]) - damping * v[2],
    )


@njit(inline="always", **NUMBA_OPTIONS)
def _point_column(model: np.ndarray, work: np.ndarray, j: int, x: tuple) -> tuple[float, float, float]:
    """Joint j's column of the point's linear Jacobian: z_j x (x - o_j) (revolute) or z_j (prismatic), with
    the body's world pose at work[24 j + 12:] (Lewis, Dawson and Abdallah 2004, Appendix A)."""
    o = 24 * j + 12
    zx, zy, zz = work[o + 2], work[o + 5], work[o + 8]
    if model[HEADER + STRIDE * j + KIND] != 0.0:
        return zx, zy, zz
    rx, ry, rz = x[0] - work[o + 9], x[1] - work[o + 10], x[2] - work[o + 11]
    return zy * rz - zz * ry, zz * rx - zx * rz, zx * ry - zy * rx


@njit(**NUMBA_OPTIONS)
def contact_torques(
    model: np.ndarray, contacts: np.ndarray, work: np.ndarray, t: float, q: np.ndarray, qd: np.ndarray,
    out: np.ndarray,
) -> None:  # fmt: skip
    """tau_ext = sum over the contacts of J_p(q)^T F(t, q, qd): simulate's compiled contacts.

    With the world pose (R_j, o_j) of every body, a point x on link i and the joint axes z_j = R_j e_3 of
    i's ancestors, J_p's column j is z_j x (x - o_j) for a revolute joint and z_j for a prismatic one
    (Lewis, Dawson and Abdallah 2004, Appendix A): tau_j = column_j . F, and the point's velocity is the
    sum of column_j qd_j. ``contacts`` rows as ``contacts_table`` writes them (a clamp's anchor is written
    into its row); ``work`` holds 24 n values.
    """
    n = int(model[N_JOINTS])
    for j in range(n):
        out[j] = 0.0
    if contacts.shape[0] == 0:
        return
    for j in range(n):
        parent = int(model[HEADER + STRIDE * j + PARENT])
        joint_transform(model, j, q[j], work, 24 * j)
        world_pose(model, work, 24 * j, 24 * parent + 12, 24 * j + 12, parent >= 0)
    for c in range(contacts.shape[0]):
        row = contacts[c]
        link = int(row[ROW_LINK])
        b, pose = HEADER + STRIDE * link, 24 * link + 12
        lever = (  # the point in the body frame
            model[b + LINK_POSITION] + model[b + LINK_ROTATION] * row[ROW_POINT]
            + model[b + LINK_ROTATION + 1] * row[ROW_POINT + 1] + model[b + LINK_ROTATION + 2] * row[ROW_POINT + 2],
            model[b + LINK_POSITION + 1] + model[b + LINK_ROTATION + 3] * row[ROW_POINT]
            + model[b + LINK_ROTATION + 4] * row[ROW_POINT + 1] + model[b + LINK_ROTATION + 5] * row[ROW_POINT + 2],
            model[b + LINK_POSITION + 2] + model[b + LINK_ROTATION + 6] * row[ROW_POINT]
            + model[b + LINK_ROTATION + 7] * row[ROW_POINT + 1] + model[b + LINK_ROTATION + 8] * row[ROW_POINT + 2],
        )  # fmt: skip
        x = (  # and in the world
            work[pose + 9] + work[pose] * lever[0] + work[pose + 1] * lever[1] + work[pose + 2] * lever[2],
            work[pose + 10] + work[pose + 3] * lever[0] + work[pose + 4] * lever[1] + work[pose + 5] * lever[2],
            work[pose + 11] + work[pose + 6] * lever[0] + work[pose + 7] * lever[1] + work[pose + 8] * lever[2],
        )
        vx = vy = vz = 0.0
        if row[ROW_KIND] == CLAMP_KIND:
            j = link
            while j >= 0:
                cx, cy, cz = _point_column(model, work, j, x)
                vx, vy, vz = vx + cx * qd[j], vy + cy * qd[j], vz + cz * qd[j]
                j = int(model[HEADER + STRIDE * j + PARENT])
        fx, fy, fz = _contact_force(row, t, x, (vx, vy, vz))
        if fx == 0.0 and fy == 0.0 and fz == 0.0:
            continue
        j = link
        while j >= 0:
            cx, cy, cz = _point_column(model, work, j, x)
            out[j] += cx * fx + cy * fy + cz * fz
            j = int(model[HEADER + STRIDE * j + PARENT])


def contact_link(residual: ArrayLike, band: ArrayLike) -> int | None:
    """The link in contact: the highest joint index whose residual leaves its band, or None (Haddadin et al. 2017).

    A force on link i moves only the residuals of the joints that move link i (tau_ext = J_p^T F has zeros
    elsewhere), so in a serial chain the highest joint outside its band is the last link in contact. armdyn
    numbers a parent before its children, so in a tree too it is the deepest joint outside its band.

    Parameters
    ----------
    residual : array_like
        r, (n,), the estimate of tau_ext.
    band : array_like
        The band inside which r counts as no contact: (n,) for |r| <= band, or (2, n) for
        lower <= r <= upper (rows lower, upper).

    Returns
    -------
    int or None
        The index of the link in contact, or None when every residual is inside its band.

    Raises
    ------
    armdyn.ModelError
        When the residual is not n finite numbers, the band is not of shape (n,) or (2, n), holds NaN, a
        negative half-width, or a lower bound above its upper bound.
    """
    r = inputs.vector(residual, "residual")
    n = r.shape[0]
    limits = inputs.numbers(band, "band")
    if limits.shape == (n,):
        if np.any(limits < 0):
            raise ModelError(f"band must be non-negative half-widths, got {limits.tolist()}")
        lower, upper = -limits, limits
    elif limits.shape == (2, n):
        lower, upper = limits
        if np.any(lower > upper):
            raise ModelError(f"band's lower row must not exceed its upper row (joints {np.flatnonzero(lower > upper)})")
    else:
        raise ModelError(f"band must have shape ({n},) or (2, {n}) for a residual of {n} joints, got {limits.shape}")
    outside = np.flatnonzero((r < lower) | (r > upper))
    return int(outside[-1]) if outside.size else None


@dataclass(frozen=True)
class ForceEstimate:
    """A contact force (or wrench) estimated from a residual.

    Parameters
    ----------
    force : numpy.ndarray
        F, (..., 3), N, world axes.
    moment : numpy.ndarray or None
        The moment about the point, (..., 3), N m, world axes (``estimate_wrench``), or None.
    condition : numpy.ndarray
        The condition number of J_p^T restricted to ``joints`` (inf when fewer joints than unknowns), (...).
    joints : tuple of int
        The joints used: those that move the point.
    link : int
        The link carrying the point.
    position : numpy.ndarray
        The point in the world, (..., 3), m.
    observable : numpy.ndarray
        Whether the estimate is determined: enough joints and a condition number at most OBSERVABLE_CONDITION.
    """

    force: np.ndarray
    moment: np.ndarray | None
    condition: np.ndarray
    joints: tuple[int, ...]
    link: int
    position: np.ndarray
    observable: np.ndarray


def _damped_solve(matrix: np.ndarray, rhs: np.ndarray, damping: float) -> tuple[np.ndarray, np.ndarray]:
    """x = (A^T A + damping^2 I)^-1 A^T b by the SVD of A (..., k, m), and A's condition number (inf when k < m)."""
    u, s, vt = np.linalg.svd(matrix, full_matrices=False)
    denominator = s**2 + damping**2
    gain = np.divide(s, denominator, out=np.zeros_like(s), where=denominator > 0)
    x = np.einsum("...ia,...i,...ki,...k->...a", vt, gain, u, rhs)
    m = matrix.shape[-1]
    if matrix.shape[-2] < m:
        return x, np.full(matrix.shape[:-2], np.inf)
    with np.errstate(divide="ignore"):
        condition = np.where(s[..., -1] > 0, s[..., 0] / np.where(s[..., -1] > 0, s[..., -1], 1.0), np.inf)
    return x, condition


def _estimate(
    arm: ArmModel, q: ArrayLike, residual: ArrayLike, link: int | str, point: ArrayLike, damping: float, rows: int
) -> ForceEstimate:
    check_arm(arm)
    index = link_index(arm, link)
    lam = inputs.number(damping, "damping", minimum=0.0)
    q = as_state(arm, q)
    r = inputs.state(residual, arm.n, "residual", f" for '{arm.name}'")
    jac = point_jacobian(arm, q, index, point)[..., :rows, :]
    joints = tuple(int(j) for j in np.flatnonzero(arm.ancestors[index]))
    shape = np.broadcast_shapes(q.shape[:-1], r.shape[:-1])
    transposed = np.broadcast_to(np.swapaxes(jac[..., joints], -1, -2), (*shape, len(joints), rows))
    x, condition = _damped_solve(transposed, np.broadcast_to(r[..., joints], (*shape, len(joints))), lam)
    observable = condition <= OBSERVABLE_CONDITION
    if not np.all(observable):
        what = "force" if rows == 3 else "wrench"
        why = (
            f"only {len(joints)} joints move the point, fewer than the {rows} unknowns"
            if len(joints) < rows
            else f"J_p^T is ill-conditioned there (condition {np.max(condition):.3g} > {OBSERVABLE_CONDITION:g})"
        )
        warnings.warn(
            f"the contact {what} on link {index} '{arm.joint_names[index]}' of '{arm.name}' is not observable: {why}",
            ContactObservabilityWarning,
            stacklevel=3,
        )
    position = _point_position(arm, q, index, _point(point))
    return ForceEstimate(x[..., :3], x[..., 3:] if rows == 6 else None, condition, joints, index, position, observable)


def estimate_force(
    arm: ArmModel, q: ArrayLike, residual: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0),
    damping: float = 1e-6,
) -> ForceEstimate:  # fmt: skip
    """The contact force F at a link point from the residual r = J_p^T F (Haddadin et al. 2017, Section V).

    Only the joints that move the point (the link's chain) are used: A = J_p^T restricted to them ((k, 3), the
    linear rows), and F = (A^T A + lambda^2 I)^-1 A^T r, the damped pseudo-inverse (lambda = ``damping``),
    exact for lambda = 0 and A of full rank. A ContactObservabilityWarning is given when fewer than 3 joints
    move the point or A's condition number exceeds OBSERVABLE_CONDITION (1e3).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    residual : array_like
        r, the external torque estimate, (n,) or (..., n).
    link : int or str
        The link in contact, by index or name.
    point : array_like, optional
        The contact point in the link's frame, (3,), m (default its origin).
    damping : float, optional
        lambda >= 0, N m per N (default 1e-6).

    Returns
    -------
    ForceEstimate
        The force (..., 3), its condition number, the joints used, the point in the world.

    Raises
    ------
    armdyn.ModelError
        When q or the residual is not finite numbers of shape (..., n), the batches do not broadcast, the link
        does not exist, the point is not three finite numbers, or the damping is negative.
    armdyn.ArgumentError
        When ``arm`` is not a numeric arm.
    """
    return _estimate(arm, q, residual, link, point, damping, 3)


def estimate_wrench(
    arm: ArmModel, q: ArrayLike, residual: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0),
    damping: float = 1e-6,
) -> ForceEstimate:  # fmt: skip
    """The contact wrench (F, moment about the point) from r = J_p^T [F; m] (Haddadin et al. 2017, Section V).

    As ``estimate_force`` with the whole point Jacobian (6 rows): A = J_p^T restricted to the joints that move
    the point, (k, 6); a ContactObservabilityWarning when k < 6 or A's condition number exceeds 1e3 (the
    condition mixes newtons and newton metres, so it depends on the lever lengths).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    residual : array_like
        r, the external torque estimate, (n,) or (..., n).
    link : int or str
        The link in contact, by index or name.
    point : array_like, optional
        The point in the link's frame, (3,), m (default its origin).
    damping : float, optional
        lambda >= 0 (default 1e-6).

    Returns
    -------
    ForceEstimate
        With ``force`` and ``moment`` (..., 3) each, world axes.

    Raises
    ------
    armdyn.ModelError
        When q or the residual is not finite numbers of shape (..., n), the batches do not broadcast, the link
        does not exist, the point is not three finite numbers, or the damping is negative.
    armdyn.ArgumentError
        When ``arm`` is not a numeric arm.
    """
    return _estimate(arm, q, residual, link, point, damping, 6)
