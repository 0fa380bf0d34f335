"""Joints: a fixed placement followed by a motion about or along an axis.

A joint's link frame is  T_parent @ placement @ motion(q) @ frame_offset,  where
``placement`` locates the joint frame in the parent's link frame, the motion is a
rotation about (revolute) or translation along (prismatic) the unit ``axis`` of the
joint frame, and ``frame_offset`` carries the link frame to where the arm's convention
puts it (for standard Denavit-Hartenberg, Tx(a) Rx(alpha) after Rz(theta)). Appendix A
of the book; Craig (1986) for the modified convention.
"""

from __future__ import annotations

import reprlib
from dataclasses import dataclass, field

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.inertial import Scalar, parameter, parameter_array, real_array

REVOLUTE, PRISMATIC = "revolute", "prismatic"
_KIND_ALIASES = {"r": REVOLUTE, "revolute": REVOLUTE, "continuous": REVOLUTE, "p": PRISMATIC, "prismatic": PRISMATIC}


def _cos_sin(angle: Scalar) -> tuple[Scalar, Scalar]:
    if hasattr(angle, "free_symbols"):
        import sympy

        return sympy.cos(angle), sympy.sin(angle)
    return np.cos(angle), np.sin(angle)


def _homogeneous(rotation: object, translation: object) -> np.ndarray:
    rotation, translation = np.asarray(rotation), np.asarray(translation)
    dtype = object if object in (rotation.dtype, translation.dtype) else float
    transform = np.eye(4, dtype=dtype)
    transform[:3, :3] = rotation
    transform[:3, 3] = translation
    return transform


def rot_x(angle: Scalar) -> np.ndarray:
    """Rx(angle), the 4x4 rotation about x.

    Parameters
    ----------
    angle : float
        The angle (rad); a SymPy expression gives a SymPy (object) matrix.

    Returns
    -------
    numpy.ndarray
        The homogeneous transform, (4, 4).
    """
    c, s = _cos_sin(angle)
    return _homogeneous([[1, 0, 0], [0, c, -s], [0, s, c]], [0, 0, 0])


def rot_z(angle: Scalar) -> np.ndarray:
    """Rz(angle), the 4x4 rotation about z.

    Parameters
    ----------
    angle : float
        The angle (rad); a SymPy expression gives a SymPy (object) matrix.

    Returns
    -------
    numpy.ndarray
        The homogeneous transform, (4, 4).
    """
    c, s = _cos_sin(angle)
    return _homogeneous([[c, -s, 0], [s, c, 0], [0, 0, 1]], [0, 0, 0])


def trans(x: Scalar = 0, y: Scalar = 0, z: Scalar = 0) -> np.ndarray:
    """The 4x4 translation by (x, y, z).

    Parameters
    ----------
    x, y, z : float, optional
        The offsets (m, default 0); SymPy expressions give a SymPy (object) matrix.

    Returns
    -------
    numpy.ndarray
        The homogeneous transform, (4, 4).
    """
    return _homogeneous(np.eye(3), np.array([x, y, z], dtype=object if _any_symbolic(x, y, z) else float))


def _any_symbolic(*values: object) -> bool:
    return any(hasattr(v, "free_symbols") and not isinstance(v, (int, float)) for v in values)


def joint_kind(kind: str, where: str = "joint") -> str:
    """Normalise a joint kind name ('R', 'revolute', 'P', 'prismatic').

    Parameters
    ----------
    kind : str
        'R', 'revolute', 'continuous', 'P' or 'prismatic', in any case.
    where : str, optional
        What to name in the error message (default "joint").

    Returns
    -------
    str
        "revolute" or "prismatic".

    Raises
    ------
    armdyn.ModelError
        When ``kind`` is none of these (or not a string at all).
    """
    if not isinstance(kind, str):
        raise ModelError(f"{where}: joint kind must be 'revolute' or 'prismatic', got {reprlib.repr(kind)}")
    try:
        return _KIND_ALIASES[str(kind).lower()]
    except KeyError:
        raise ModelError(f"{where}: unknown joint kind '{kind}' (revolute or prismatic)") from None


@dataclass(frozen=True, eq=False)
class Joint:
    """A revolute or prismatic joint: fixed placement, unit axis, link-frame offset.

    The link frame is T_parent @ placement @ motion(q) @ frame_offset (Appendix A).

    Parameters
    ----------
    kind : str, optional
        "revolute" (default) or "prismatic" ('R', 'P' and 'continuous' are accepted).
    placement : array_like, optional
        The joint frame in the parent's link frame, a 4x4 rigid transform (default identity).
    axis : array_like, optional
        The unit axis of the motion in the joint frame (default z, [0, 0, 1]).
    frame_offset : array_like, optional
        The link frame in the moved joint frame, a 4x4 rigid transform (default identity).
    name : str, optional
        Names the joint in error messages (default "joint").

    Raises
    ------
    armdyn.ModelError
        When the kind is unknown, ``placement`` or ``frame_offset`` is not a finite real 4x4
        rigid homogeneous transform (SymPy entries are accepted), or ``axis`` is not a unit
        3-vector of real numbers; the message names the argument and the joint.
    """

    kind: str = REVOLUTE
    placement: np.ndarray = field(default_factory=lambda: np.eye(4))
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    frame_offset: np.ndarray = field(default_factory=lambda: np.eye(4))
    name: str = "joint"

    def __post_init__(self) -> None:
        where = f"joint '{self.name}'"
        object.__setattr__(self, "kind", joint_kind(self.kind, where))
        for key in ("placement", "frame_offset"):
            object.__setattr__(self, key, _pose(getattr(self, key), key, where))
        axis = real_array(self.axis, "axis", where).reshape(-1)  # a column (3, 1) is that axis
        norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
        if axis.shape != (3,) or abs(norm - 1.0) > 1e-9:
            raise ModelError(f"{where}: axis must be a unit 3-vector, got {reprlib.repr(self.axis)}")
        axis.setflags(write=False)
        object.__setattr__(self, "axis", axis)

    @property
    def is_revolute(self) -> bool:
        return self.kind == REVOLUTE


def _pose(value: object, key: str, where: str) -> np.ndarray:
    """A read-only 4x4 rigid transform (an object array when it holds SymPy expressions)."""
    pose = parameter_array(value, key, where)
    if pose.shape != (4, 4):
        raise ModelError(f"{where}: {key} must be a 4x4 transform, got shape {pose.shape}")
    if pose.dtype != object:
        check_rigid(pose, f"{where}: {key}")
    pose.setflags(write=False)
    return pose


def check_rigid(transform: np.ndarray, where: str) -> None:
    """Refuse a 4x4 that is not a pose: an orthonormal rotation of determinant +1, last row [0 0 0 1]."""
    rotation = transform[:3, :3]
    if np.max(np.abs(rotation @ rotation.T - np.eye(3))) > 1e-9 or np.linalg.det(rotation) < 0:
        raise ModelError(
            f"{where} is not a rigid transform (its rotation is not orthonormal with determinant +1): "
            "a pose cannot scale, shear or mirror; give lengths in the link geometry instead"
        )
    if np.max(np.abs(transform[3] - [0, 0, 0, 1])) > 0:
        raise ModelError(f"{where} is not a homogeneous transform (last row must be [0 0 0 1])")


def dh_joint(
    kind: str, a: Scalar, alpha: Scalar, d: Scalar, theta: Scalar, convention: str = "standard", name: str = "joint"
) -> Joint:
    """A joint from one Denavit-Hartenberg row (Appendix A).

    Standard: A = Rz(theta) Tz(d) Tx(a) Rx(alpha), the joint variable added to theta
    (revolute) or d (prismatic), moving about/along z_{i-1}.
    Modified (Craig): A = Rx(alpha) Tx(a) Rz(theta) Tz(d), moving about/along z_i.
    theta and d are the constant offsets of the joint variable.

    Parameters
    ----------
    kind : str
        'R' or 'revolute', 'P' or 'prismatic'.
    a, alpha, d, theta : float
        The DH parameters (m and rad); SymPy expressions are accepted.
    convention : str, optional
        'standard' (default) or 'modified' (Craig).
    name : str, optional
        Names the joint in error messages (default "joint").

    Returns
    -------
    Joint
        The joint, moving about or along z of its joint frame.

    Raises
    ------
    armdyn.ModelError
        When ``kind`` or ``convention`` is unknown, or a DH parameter is neither a finite real
        number nor a SymPy expression.
    """
    where = f"joint '{name}'"
    if not isinstance(convention, str) or convention not in ("standard", "modified"):
        raise ModelError(f"{where}: DH convention must be 'standard' or 'modified', got {reprlib.repr(convention)}")
    kind = joint_kind(kind, where)
    a, alpha, d, theta = dh_parameters(a, alpha, d, theta, where)
    revolute = kind == REVOLUTE
    if convention == "standard":
        placement = trans(z=d) @ rot_z(theta) if revolute else rot_z(theta) @ trans(z=d)
        offset = trans(x=a) @ rot_x(alpha)
    else:
        placement = rot_x(alpha) @ trans(x=a) @ (trans(z=d) @ rot_z(theta) if revolute else rot_z(theta) @ trans(z=d))
        offset = np.eye(4)
    return Joint(kind, placement, np.array([0.0, 0.0, 1.0]), offset, name)


def dh_parameters(
    a: object, alpha: object, d: object, theta: object, where: str
) -> tuple[Scalar, Scalar, Scalar, Scalar]:
    """The DH parameters (a, alpha, d, theta) checked: each a finite real float or a SymPy expression."""
    return (
        parameter(a, "DH parameter a", where),
        parameter(alpha, "DH parameter alpha", where),
        parameter(d, "DH parameter d", where),
        parameter(theta, "DH parameter theta", where),
    )
