"""Forward kinematics, the geometric Jacobian and its time derivative (Appendix A).

Every function takes one state q of shape (n,) or a batch (..., n) and works on the
whole batch at once with NumPy; the loop runs over the joints, never over states. Arguments
are checked first: a wrong type or shape is a ModelError (an ArgumentError, also a TypeError, for an arm
that is not an ArmModel) that names the argument.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from armdyn import inputs
from armdyn.errors import ModelError
from armdyn.model import ArmModel

FRAMES = ("base", "tool")


def check_arm(arm: object, numeric: bool = True, hint: str = "", name: str = "arm") -> None:
    """An ArgumentError naming the argument ``name`` unless ``arm`` is an arm (an ArmModel, e.g. a Robot), with
    numbers for parameters when ``numeric``.

    Parameters
    ----------
    arm : object
        What the caller was given as the arm.
    numeric : bool, optional
        Whether the arm's parameters must be numbers (default True): symbolic ones are refused.
    hint : str, optional
        Added to the message for a symbolic arm (where to go instead).
    name : str, optional
        The caller's name for the argument, for the message (default "robot").

    Raises
    ------
    armdyn.ArgumentError
        When ``arm`` is not an ArmModel, or is symbolic where numbers are needed (a ModelError and a TypeError).
    """
    inputs.arm_argument(arm, ArmModel, name=name, numeric=numeric, why=hint)


def _numbers(value: ArrayLike, name: str) -> np.ndarray:
    """A finite float (or complex) array of any shape, or a ModelError naming the argument."""
    if value is None or isinstance(value, (str, bytes, dict)):
        raise ModelError(f"{name} must be a number or an array of numbers, got {value!r}")
    try:
        array = np.asarray(value, dtype=complex if np.iscomplexobj(value) else float)
    except (TypeError, ValueError, ArithmeticError):  # ArithmeticError: ints too large, objects that fail
        raise ModelError(f"{name} must be a number or an array of numbers, got {type(value).__name__}") from None
    if not np.all(np.isfinite(array)):
        raise ModelError(f"{name} must be finite (it holds NaN or infinity)")
    return array


def link_index(arm: ArmModel, link: object) -> int:
    """The tool link for None, else ``link`` as the index of a link of the arm: an integer index, or the
    name of the joint that moves the link.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    link : int, str or None
        A link index (an int or NumPy integer, not a bool or a float), a joint's name (``arm.joint_names``),
        or None for the tool link.

    Returns
    -------
    int
        The link's index.

    Raises
    ------
    armdyn.ModelError
        When ``link`` is not an integer or a name, is out of range, or names no link of the arm (the message
        lists the links).
    """
    if link is None:
        return arm.tool_link
    names = arm.joint_names
    if isinstance(link, str):
        if link not in names:
            listed = ", ".join(f"{i} '{name}'" for i, name in enumerate(names))
            raise ModelError(
                f"link must be an integer link index (0..{arm.n - 1}) or None, got {link!r} (str), and "
                f"'{arm.name}' has no link '{link}' (its links: {listed})"
            )
        return names.index(link)
    if isinstance(link, (bool, np.bool_)) or not isinstance(link, (int, np.integer)):
        raise ModelError(
            f"link must be an integer link index (0..{arm.n - 1}) or None, got {link!r} ({type(link).__name__}); "
            "a joint's name is taken too"
        )
    if not 0 <= link < arm.n:
        raise ModelError(f"link index {link} is out of range for '{arm.name}' (0..{arm.n - 1}): it has no link {link}")
    return int(link)


def check_frame(frame: object) -> None:
    """A ModelError unless ``frame`` is "base" or "tool".

    Parameters
    ----------
    frame : object
        The frame argument given.

    Raises
    ------
    armdyn.ModelError
        When ``frame`` is not the string "base" or "tool".
    """
    if not (isinstance(frame, str) and frame in FRAMES):
        raise ModelError(f"frame must be 'base' or 'tool', got {frame!r}")


def as_state(arm: ArmModel, value: object, name: str = "q") -> np.ndarray:
    """A finite array of shape (..., n), or a ModelError naming the argument.

    Complex arrays stay complex: the Lagrange reference then takes complex-step derivatives.

    Parameters
    ----------
    arm : ArmModel
        The arm, for n and its name in the message.
    value : array_like
        The state, (n,) or a batch (..., n).
    name : str, optional
        The argument's name for the message (default "q").

    Returns
    -------
    numpy.ndarray
        ``value`` as a float (or complex) array of shape (..., n).

    Raises
    ------
    armdyn.ModelError
        When ``value`` is not numbers, does not end in n, or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters.
    """
    check_arm(arm, name="arm")
    return inputs.state(value, arm.n, name, f" for '{arm.name}'", complex_ok=True)


def as_states(arm: ArmModel, q: object, **rates: object) -> tuple[np.ndarray, ...]:
    """q and the named rates (qd, qdd) checked as by ``as_state``, and their batch shapes
    checked to broadcast together.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    **rates : array_like
        Further states by name (``qd=...``, ``qdd=...``), each (n,) or (..., n).

    Returns
    -------
    tuple of numpy.ndarray
        q and the rates in the order given, each as ``as_state`` returns it (not broadcast).

    Raises
    ------
    armdyn.ModelError
        When a state is not numbers of shape (..., n), holds NaN or infinity, or when the batch
        shapes do not broadcast together (the message names each argument's shape).
    """
    arrays = (as_state(arm, q), *(as_state(arm, value, name) for name, value in rates.items()))
    try:
        np.broadcast_shapes(*(array.shape[:-1] for array in arrays))
    except ValueError:
        names = ("q", *rates)
        shapes = ", ".join(f"{name} {array.shape}" for name, array in zip(names, arrays, strict=True))
        raise ModelError(f"the batch shapes of {shapes} do not broadcast together") from None
    return arrays


def skew(v: np.ndarray) -> np.ndarray:
    """The cross-product matrix [v]x of vectors v (..., 3) -> (..., 3, 3).

    Parameters
    ----------
    v : numpy.ndarray
        Vectors, (..., 3).

    Returns
    -------
    numpy.ndarray
        [v]x, (..., 3, 3), with [v]x u = v x u.

    Raises
    ------
    armdyn.ModelError
        When ``v`` is not numbers of shape (..., 3) or holds NaN or infinity.
    """
    return _skew(inputs.state(v, 3, "v", complex_ok=True))


def _skew(v: np.ndarray) -> np.ndarray:
    zero = np.zeros_like(v[..., 0])
    return np.stack(
        [
            np.stack([zero, -v[..., 2], v[..., 1]], -1),
            np.stack([v[..., 2], zero, -v[..., 0]], -1),
            np.stack([-v[..., 1], v[..., 0], zero], -1),
        ],
        -2,
    )


def joint_motion(revolute: bool, axis: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The 4x4 motion of a joint: rotation about (Rodrigues) or translation along its axis.

    Parameters
    ----------
    revolute : bool
        True for a rotation by q about ``axis``, False for a translation by q along it.
    axis : numpy.ndarray
        The unit axis, (3,).
    q : numpy.ndarray
        Joint values, any shape (...).

    Returns
    -------
    numpy.ndarray
        The homogeneous transforms, (..., 4, 4), of the dtype of ``q``.

    Raises
    ------
    armdyn.ModelError
        When ``revolute`` is not a bool, ``axis`` is not a finite unit 3-vector, or ``q`` is
        not numbers or holds NaN or infinity.
    """
    if not isinstance(revolute, (bool, np.bool_)):
        raise ModelError(f"revolute must be True or False, got {revolute!r}")
    axis = inputs.state(axis, 3, "axis")
    if axis.ndim != 1 or abs(np.linalg.norm(axis) - 1.0) > 1e-9:
        raise ModelError(f"axis must be a unit 3-vector, got {axis.tolist()}")
    return _joint_motion(bool(revolute), axis, _numbers(q, "q"))


def _joint_motion(revolute: bool, axis: np.ndarray, q: np.ndarray) -> np.ndarray:
    motion = np.zeros((*q.shape, 4, 4), dtype=q.dtype)
    motion[..., 3, 3] = 1.0
    if revolute:
        k = _skew(axis)
        s, c = np.sin(q)[..., None, None], np.cos(q)[..., None, None]
        motion[..., :3, :3] = np.eye(3) + s * k + (1.0 - c) * (k @ k)
    else:
        motion[..., :3, :3] = np.eye(3)
        motion[..., :3, 3] = q[..., None] * axis
    return motion


def joint_frames(arm: ArmModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(link frames T_i, joint frames) in the world, both (..., n, 4, 4).

    The joint frame of joint i is T_parent @ placement @ motion(q_i): its origin lies on
    the joint axis and it carries the axis as a constant vector.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).

    Returns
    -------
    links : numpy.ndarray
        The link frames T_i, (..., n, 4, 4).
    joints : numpy.ndarray
        The joint frames, (..., n, 4, 4).

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    q = as_state(arm, q)
    shape = q.shape[:-1] + (arm.n, 4, 4)
    links, joints = np.empty(shape, dtype=q.dtype), np.empty(shape, dtype=q.dtype)
    for i, link in enumerate(arm.links):
        parent = arm.base if link.parent < 0 else links[..., link.parent, :, :]
        joint = link.joint
        joints[..., i, :, :] = parent @ joint.placement @ _joint_motion(joint.is_revolute, joint.axis, q[..., i])
        links[..., i, :, :] = joints[..., i, :, :] @ joint.frame_offset
    return links, joints


def link_transforms(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """T_i(q), the pose of every link frame in the world, shape (..., n, 4, 4) (Appendix A).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).

    Returns
    -------
    numpy.ndarray
        T_i, (..., n, 4, 4): base @ the chain of placements, motions and frame offsets.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    return joint_frames(arm, q)[0]


def tool_pose(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """The tool pose T_tool_link(q) @ tool, shape (..., 4, 4).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).

    Returns
    -------
    numpy.ndarray
        The pose of the tool in the world, (..., 4, 4).

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    return link_transforms(arm, q)[..., arm.tool_link, :, :] @ arm.tool


def joint_axes(arm: ArmModel, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World axis z_j and origin o_j of every joint, each (..., n, 3).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    joints : numpy.ndarray
        The joint frames of ``joint_frames``, (..., n, 4, 4).

    Returns
    -------
    z : numpy.ndarray
        The unit joint axes in the world, (..., n, 3).
    o : numpy.ndarray
        The joint-frame origins in the world, (..., n, 3).

    Raises
    ------
    armdyn.ModelError
        When ``joints`` is not numbers of shape (..., n, 4, 4) or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters.
    """
    check_arm(arm, name="arm")
    joints = _numbers(joints, "joints")
    if joints.ndim < 3 or joints.shape[-3:] != (arm.n, 4, 4):
        raise ModelError(f"joints must have shape (..., {arm.n}, 4, 4) for '{arm.name}', got {joints.shape}")
    return _joint_axes(arm, joints)


def _joint_axes(arm: ArmModel, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    axes = np.stack([link.joint.axis for link in arm.links])
    return np.einsum("...jab,jb->...ja", joints[..., :3, :3], axes), joints[..., :3, 3]


def _target(arm: ArmModel, q: np.ndarray, link: int | str | None) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """Which link, its pose (tool applied for the tool link), and the joint axes/origins."""
    links, joints = joint_frames(arm, q)
    index = link_index(arm, link)
    pose = links[..., index, :, :] @ arm.tool if link is None else links[..., index, :, :]
    z, o = _joint_axes(arm, joints)
    return index, pose, z, o


def _columns(arm: ArmModel, z: np.ndarray, o: np.ndarray, point: np.ndarray, moves: np.ndarray) -> np.ndarray:
    """Geometric Jacobian columns for a point: [z x (p - o); z] (revolute), [z; 0] (prismatic)."""
    revolute = np.array([kind == "revolute" for kind in arm.kinds])
    linear = np.where(revolute[:, None], np.cross(z, point[..., None, :] - o), z)
    angular = np.where(revolute[:, None], z, 0.0)
    columns = np.concatenate([linear, angular], axis=-1) * moves[:, None]
    return np.swapaxes(columns, -1, -2)


def _in_frame(jac: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Express both 3-row blocks of a 6 x n matrix in a frame of the given world rotation."""
    rt = np.swapaxes(rotation, -1, -2)
    return np.concatenate([rt @ jac[..., :3, :], rt @ jac[..., 3:, :]], axis=-2)


def jacobian(arm: ArmModel, q: np.ndarray, frame: str = "base", link: int | str | None = None) -> np.ndarray:
    """The geometric Jacobian J(q), (..., 6, n): [v; w] = J qd, linear rows first.

    Column j is [z_j x (p - o_j); z_j] for a revolute joint and [z_j; 0] for a prismatic
    one (Appendix A), zero for joints that do not move the point.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    frame : str, optional
        "base" (default) expresses J in the world; "tool" in the moving frame itself.
    link : int or str, optional
        The link whose frame origin is the point, by index or by its joint's name; default (None) the tool.

    Returns
    -------
    numpy.ndarray
        J, (..., 6, n).

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity, when ``link``
        is not None or an integer index of a link (a float or a bool is refused), or when ``frame``
        is not "base" or "tool".
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    check_frame(frame)
    index, pose, z, o = _target(arm, q, link)
    jac = _columns(arm, z, o, pose[..., :3, 3], arm.ancestors[index])
    return _expressed(jac, pose, frame)


def _expressed(jac: np.ndarray, pose: np.ndarray, frame: str) -> np.ndarray:
    return jac if frame == "base" else _in_frame(jac, pose[..., :3, :3])


def jacobian_dot(
    arm: ArmModel, q: np.ndarray, qd: np.ndarray, frame: str = "base", link: int | str | None = None
) -> np.ndarray:
    """dJ/dt for the Jacobian of ``jacobian`` (same point and frame), (..., 6, n).

    For a revolute column d/dt [z x (p - o); z] = [zdot x (p - o) + z x (pdot - odot); zdot]
    and for a prismatic one d/dt [z; 0] = [zdot; 0], with zdot = w_j x z_j, w_j the angular
    velocity of the body carrying joint j's axis and odot the velocity of its origin.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n).
    frame : str, optional
        "base" (default) for the derivative of the world-frame Jacobian; "tool" for that of
        the Jacobian expressed in the moving frame.
    link : int or str, optional
        The link whose frame origin is the point, by index or by its joint's name; default (None) the tool.

    Returns
    -------
    numpy.ndarray
        dJ/dt, (..., 6, n).

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``qd`` is not numbers of shape (..., n) or holds NaN or infinity, when
        ``link`` is not None or an integer index of a link (a float or a bool is refused), or when ``frame``
        is not "base" or "tool".
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    check_frame(frame)
    q, qd = as_states(arm, q, qd=qd)
    index, pose, z, o = _target(arm, q, link)
    revolute = np.array([kind == "revolute" for kind in arm.kinds])
    strict = arm.ancestors & ~np.eye(arm.n, dtype=bool)
    rates = z * (qd[..., :, None] * revolute[:, None])  # each joint's angular velocity contribution
    omega_parent = np.einsum("jk,...ka->...ja", strict.astype(float), rates)
    zdot = np.cross(omega_parent, z)
    # velocity of joint origin o_j: columns of the joints that move it, evaluated at o_j
    lever = o[..., None, :, :] - o[..., :, None, :]  # [..., k, j] = o_j - o_k
    contrib = np.where(revolute[:, None, None], np.cross(z[..., :, None, :], lever), z[..., :, None, :])
    odot = np.einsum("jk,...kja,...k->...ja", strict.astype(float), contrib, qd)
    moves = arm.ancestors[index]
    point = pose[..., :3, 3]
    jac = _columns(arm, z, o, point, moves)
    pdot = np.einsum("...an,...n->...a", jac[..., :3, :], qd)
    lin = np.where(
        revolute[:, None],
        np.cross(zdot, point[..., None, :] - o) + np.cross(z, pdot[..., None, :] - odot),
        zdot,
    )
    ang = np.where(revolute[:, None], zdot, 0.0)
    jdot = np.swapaxes(np.concatenate([lin, ang], axis=-1) * moves[:, None], -1, -2)
    if frame == "base":
        return jdot
    omega = np.einsum("...an,...n->...a", jac[..., 3:, :], qd)
    w = _skew(omega)
    corrected = np.concatenate([jdot[..., :3, :] - w @ jac[..., :3, :], jdot[..., 3:, :] - w @ jac[..., 3:, :]], -2)
    return _in_frame(corrected, pose[..., :3, :3])


def twist_generators(arm: ArmModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(S_j, T_i): S_j the 4x4 world-frame generator of joint j, so that dT_i/dq_j = S_j T_i.

    S_j = [[z^, -z^ o], [0, 0]] for a revolute joint, [[0, z], [0, 0]] for a prismatic one.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).

    Returns
    -------
    generators : numpy.ndarray
        S_j, (..., n, 4, 4).
    links : numpy.ndarray
        The link frames T_i, (..., n, 4, 4).

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    links, joints = joint_frames(arm, q)
    z, o = _joint_axes(arm, joints)
    revolute = np.array([kind == "revolute" for kind in arm.kinds])
    generators = np.zeros((*z.shape[:-1], 4, 4), dtype=z.dtype)
    zhat = _skew(z)
    generators[..., :3, :3] = np.where(revolute[:, None, None], zhat, 0.0)
    generators[..., :3, 3] = np.where(revolute[:, None], -np.einsum("...ab,...b->...a", zhat, o), z)
    return generators, links


def link_transform_derivatives(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """dT_i/dq_j as the book uses it (3.2.18), shape (..., n, n, 4, 4) indexed [i, j].

    dT_i/dq_j = S_j T_i when joint j moves link i, and 0 otherwise (see
    ``twist_generators``).

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).

    Returns
    -------
    numpy.ndarray
        dT_i/dq_j, (..., n, n, 4, 4), indexed [..., i, j, :, :].

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    armdyn.ArgumentError
        When ``arm`` is not an arm (an ArmModel), or when it has symbolic (SymPy) parameters;
        numeric kinematics need numbers.
    """
    generators, links = twist_generators(arm, q)
    derivative = generators[..., None, :, :, :] @ links[..., :, None, :, :]
    return derivative * arm.ancestors[:, :, None, None]


def quaternion(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z) of a rotation matrix, as MJCF's ``quat`` and viser's ``wxyz`` read it.

    Shepperd's method (Shepperd 1978, "Quaternion from rotation matrix", J. Guidance and Control
    1(3)): the largest of 4w^2, 4x^2, 4y^2, 4z^2 (from the trace and the diagonal) is taken
    under the square root and the others follow from the off-diagonal sums and differences, so
    that no component is divided by a small number; w >= 0.

    Parameters
    ----------
    rotation : numpy.ndarray
        A rotation matrix, (3, 3) (the upper-left block of a 4x4 pose is taken as well).

    Returns
    -------
    tuple of float
        (w, x, y, z), of unit norm to rounding.
    """
    r = np.asarray(rotation, dtype=float)[:3, :3]
    squares = [1 + r[0, 0] + r[1, 1] + r[2, 2], 1 + r[0, 0] - r[1, 1] - r[2, 2]]
    squares += [1 - r[0, 0] + r[1, 1] - r[2, 2], 1 - r[0, 0] - r[1, 1] + r[2, 2]]
    largest = int(np.argmax(squares))
    s = 2 * np.sqrt(squares[largest])  # 4 times the largest component
    if largest == 0:
        q = (s / 4, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    elif largest == 1:
        q = ((r[2, 1] - r[1, 2]) / s, s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s)
    elif largest == 2:
        q = ((r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s)
    else:
        q = ((r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4)
    sign = -1.0 if q[0] < 0 else 1.0
    return (float(sign * q[0]), float(sign * q[1]), float(sign * q[2]), float(sign * q[3]))
