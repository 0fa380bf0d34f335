"""Joints: a fixed placement followed by a motion about or along an axis.

A joint's link frame is  T_parent @ placement @ motion(q) @ frame_offset,  where
``placement`` locates the joint frame in the parent's link frame, the motion is a
rotation about (revolute) or translation along (prismatic) the unit ``axis`` of the
joint frame, and ``frame_offset`` carries the link frame to where the arm's convention
puts it (for standard Denavit-Hartenberg, Tx(a) Rx(alpha) after Rz(theta)). Appendix A
of the book; Craig (1986) for the modified convention.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from armdyn.errors import ModelError

REVOLUTE, PRISMATIC = "revolute", "prismatic"
_KIND_ALIASES = {"r": REVOLUTE, "revolute": REVOLUTE, "continuous": REVOLUTE, "p": PRISMATIC, "prismatic": PRISMATIC}


def _cos_sin(angle: object) -> tuple[object, object]:
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


def rot_x(angle: object) -> np.ndarray:
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


def rot_z(angle: object) -> np.ndarray:
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


def trans(x: object = 0, y: object = 0, z: object = 0) -> np.ndarray:
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
        When ``kind`` is none of these.
    """
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
        When the kind is unknown, ``placement`` or ``frame_offset`` is not a finite 4x4
        rigid homogeneous transform, or ``axis`` is not a unit 3-vector.
    """

    kind: str = REVOLUTE
    placement: np.ndarray = field(default_factory=lambda: np.eye(4))
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    frame_offset: np.ndarray = field(default_factory=lambda: np.eye(4))
    name: str = "joint"

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", joint_kind(self.kind, f"joint '{self.name}'"))
        for key in ("placement", "frame_offset"):
            value = np.asarray(getattr(self, key))
            if value.shape != (4, 4):
                raise ModelError(f"joint '{self.name}': {key} must be a 4x4 transform, got shape {value.shape}")
            if value.dtype != object:
                value = np.array(value, dtype=float)
                if not np.all(np.isfinite(value)):
                    raise ModelError(f"joint '{self.name}': {key} must be finite")
                check_rigid(value, f"joint '{self.name}': {key}")
                value.setflags(write=False)
            object.__setattr__(self, key, value)
        axis = np.array(self.axis, dtype=float).reshape(-1)
        norm = np.linalg.norm(axis) if axis.shape == (3,) else 0.0
        if axis.shape != (3,) or not np.isfinite(norm) or abs(norm - 1.0) > 1e-9:
            raise ModelError(f"joint '{self.name}': axis must be a unit 3-vector, got {self.axis}")
        axis.setflags(write=False)
        object.__setattr__(self, "axis", axis)

    @property
    def is_revolute(self) -> bool:
        return self.kind == REVOLUTE


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
    kind: str, a: object, alpha: object, d: object, theta: object, convention: str = "standard", name: str = "joint"
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
        When ``kind`` or ``convention`` is unknown.
    """
    kind = joint_kind(kind, f"joint '{name}'")
    revolute = kind == REVOLUTE
    if convention == "standard":
        placement = trans(z=d) @ rot_z(theta) if revolute else rot_z(theta) @ trans(z=d)
        offset = trans(x=a) @ rot_x(alpha)
    elif convention == "modified":
        placement = rot_x(alpha) @ trans(x=a) @ (trans(z=d) @ rot_z(theta) if revolute else rot_z(theta) @ trans(z=d))
        offset = np.eye(4)
    else:
        raise ModelError(f"joint '{name}': DH convention must be 'standard' or 'modified', got '{convention}'")
    return Joint(kind, placement, np.array([0.0, 0.0, 1.0]), offset, name)
