"""Forward kinematics, the geometric Jacobian and its time derivative (Appendix A).

Every function takes one state q of shape (n,) or a batch (..., n) and works on the
whole batch at once with NumPy; the loop runs over the joints, never over states.
"""

from __future__ import annotations

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.robot import Robot


def as_state(robot: Robot, value: object, name: str = "q") -> np.ndarray:
    """A float array of shape (..., n), or a ModelError naming the argument.

    Complex arrays stay complex: the Lagrange reference then takes complex-step derivatives.
    """
    array = np.asarray(value, dtype=complex if np.iscomplexobj(value) else float)
    if array.ndim == 0 or array.shape[-1] != robot.n:
        raise ModelError(f"{name} must have shape (..., {robot.n}) for '{robot.name}', got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ModelError(f"{name} must be finite (it holds NaN or infinity)")
    return array


def skew(v: np.ndarray) -> np.ndarray:
    """The cross-product matrix [v]x of vectors v (..., 3) -> (..., 3, 3)."""
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
    """The 4x4 motion of a joint: rotation about (Rodrigues) or translation along its axis."""
    motion = np.zeros((*q.shape, 4, 4), dtype=q.dtype)
    motion[..., 3, 3] = 1.0
    if revolute:
        k = skew(axis)
        s, c = np.sin(q)[..., None, None], np.cos(q)[..., None, None]
        motion[..., :3, :3] = np.eye(3) + s * k + (1.0 - c) * (k @ k)
    else:
        motion[..., :3, :3] = np.eye(3)
        motion[..., :3, 3] = q[..., None] * axis
    return motion


def joint_frames(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(link frames T_i, joint frames) in the world, both (..., n, 4, 4).

    The joint frame of joint i is T_parent @ placement @ motion(q_i): its origin lies on
    the joint axis and it carries the axis as a constant vector.
    """
    q = as_state(robot, q)
    shape = q.shape[:-1] + (robot.n, 4, 4)
    links, joints = np.empty(shape, dtype=q.dtype), np.empty(shape, dtype=q.dtype)
    for i, link in enumerate(robot.links):
        parent = robot.base if link.parent < 0 else links[..., link.parent, :, :]
        joint = link.joint
        joints[..., i, :, :] = parent @ joint.placement @ joint_motion(joint.is_revolute, joint.axis, q[..., i])
        links[..., i, :, :] = joints[..., i, :, :] @ joint.frame_offset
    return links, joints


def link_transforms(robot: Robot, q: np.ndarray) -> np.ndarray:
    """T_i(q), the pose of every link frame in the world, shape (..., n, 4, 4)."""
    return joint_frames(robot, q)[0]


def tool_pose(robot: Robot, q: np.ndarray) -> np.ndarray:
    """The tool pose T_tool_link(q) @ tool, shape (..., 4, 4)."""
    return link_transforms(robot, q)[..., robot.tool_link, :, :] @ robot.tool


def joint_axes(robot: Robot, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World axis z_j and origin o_j of every joint, each (..., n, 3)."""
    axes = np.stack([link.joint.axis for link in robot.links])
    return np.einsum("...jab,jb->...ja", joints[..., :3, :3], axes), joints[..., :3, 3]


def _target(robot: Robot, q: np.ndarray, link: int | None) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """Which link, its pose (tool applied for the tool link), and the joint axes/origins."""
    links, joints = joint_frames(robot, q)
    index = robot.tool_link if link is None else int(link)
    if not 0 <= index < robot.n:
        raise ModelError(f"link index {link} is out of range for '{robot.name}' (0..{robot.n - 1})")
    pose = links[..., index, :, :] @ robot.tool if link is None else links[..., index, :, :]
    z, o = joint_axes(robot, joints)
    return index, pose, z, o


def _columns(robot: Robot, z: np.ndarray, o: np.ndarray, point: np.ndarray, moves: np.ndarray) -> np.ndarray:
    """Geometric Jacobian columns for a point: [z x (p - o); z] (revolute), [z; 0] (prismatic)."""
    revolute = np.array([kind == "revolute" for kind in robot.kinds])
    linear = np.where(revolute[:, None], np.cross(z, point[..., None, :] - o), z)
    angular = np.where(revolute[:, None], z, 0.0)
    columns = np.concatenate([linear, angular], axis=-1) * moves[:, None]
    return np.swapaxes(columns, -1, -2)


def _in_frame(jac: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Express both 3-row blocks of a 6 x n matrix in a frame of the given world rotation."""
    rt = np.swapaxes(rotation, -1, -2)
    return np.concatenate([rt @ jac[..., :3, :], rt @ jac[..., 3:, :]], axis=-2)


def jacobian(robot: Robot, q: np.ndarray, frame: str = "base", link: int | None = None) -> np.ndarray:
    """The geometric Jacobian J(q), (..., 6, n): [v; w] = J qd, linear rows first.

    Of the tool (default) or of link ``link``'s frame origin; expressed in the world
    ("base") or in the moving frame itself ("tool").
    """
    index, pose, z, o = _target(robot, q, link)
    jac = _columns(robot, z, o, pose[..., :3, 3], robot.ancestors[index])
    return _expressed(jac, pose, frame)


def _expressed(jac: np.ndarray, pose: np.ndarray, frame: str) -> np.ndarray:
    if frame == "base":
        return jac
    if frame == "tool":
        return _in_frame(jac, pose[..., :3, :3])
    raise ModelError(f"frame must be 'base' or 'tool', got '{frame}'")


def jacobian_dot(
    robot: Robot, q: np.ndarray, qd: np.ndarray, frame: str = "base", link: int | None = None
) -> np.ndarray:
    """dJ/dt for the Jacobian of ``jacobian`` (same point and frame), (..., 6, n).

    For a revolute column d/dt [z x (p - o); z] = [zdot x (p - o) + z x (pdot - odot); zdot]
    and for a prismatic one d/dt [z; 0] = [zdot; 0], with zdot = w_j x z_j, w_j the angular
    velocity of the body carrying joint j's axis and odot the velocity of its origin.
    """
    qd = as_state(robot, qd, "qd")
    index, pose, z, o = _target(robot, q, link)
    revolute = np.array([kind == "revolute" for kind in robot.kinds])
    strict = robot.ancestors & ~np.eye(robot.n, dtype=bool)
    rates = z * (qd[..., :, None] * revolute[:, None])  # each joint's angular velocity contribution
    omega_parent = np.einsum("jk,...ka->...ja", strict.astype(float), rates)
    zdot = np.cross(omega_parent, z)
    # velocity of joint origin o_j: columns of the joints that move it, evaluated at o_j
    lever = o[..., None, :, :] - o[..., :, None, :]  # [..., k, j] = o_j - o_k
    contrib = np.where(revolute[:, None, None], np.cross(z[..., :, None, :], lever), z[..., :, None, :])
    odot = np.einsum("jk,...kja,...k->...ja", strict.astype(float), contrib, qd)
    moves = robot.ancestors[index]
    point = pose[..., :3, 3]
    jac = _columns(robot, z, o, point, moves)
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
    if frame != "tool":
        raise ModelError(f"frame must be 'base' or 'tool', got '{frame}'")
    omega = np.einsum("...an,...n->...a", jac[..., 3:, :], qd)
    w = skew(omega)
    corrected = np.concatenate([jdot[..., :3, :] - w @ jac[..., :3, :], jdot[..., 3:, :] - w @ jac[..., 3:, :]], -2)
    return _in_frame(corrected, pose[..., :3, :3])


def twist_generators(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(S_j, T_i): S_j the 4x4 world-frame generator of joint j, so that dT_i/dq_j = S_j T_i.

    S_j = [[z^, -z^ o], [0, 0]] for a revolute joint, [[0, z], [0, 0]] for a prismatic one.
    """
    links, joints = joint_frames(robot, q)
    z, o = joint_axes(robot, joints)
    revolute = np.array([kind == "revolute" for kind in robot.kinds])
    generators = np.zeros((*z.shape[:-1], 4, 4), dtype=z.dtype)
    zhat = skew(z)
    generators[..., :3, :3] = np.where(revolute[:, None, None], zhat, 0.0)
    generators[..., :3, 3] = np.where(revolute[:, None], -np.einsum("...ab,...b->...a", zhat, o), z)
    return generators, links


def link_transform_derivatives(robot: Robot, q: np.ndarray) -> np.ndarray:
    """dT_i/dq_j as the book uses it (3.2.18), shape (..., n, n, 4, 4) indexed [i, j].

    dT_i/dq_j = S_j T_i when joint j moves link i, and 0 otherwise.
    """
    generators, links = twist_generators(robot, q)
    derivative = generators[..., None, :, :, :] @ links[..., :, None, :, :]
    return derivative * robot.ancestors[:, :, None, None]
