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
    c, s = _cos_sin(angle)
    return _homogeneous([[1, 0, 0], [0, c, -s], [0, s, c]], [0, 0, 0])


def rot_z(angle: object) -> np.ndarray:
    c, s = _cos_sin(angle)
    return _homogeneous([[c, -s, 0], [s, c, 0], [0, 0, 1]], [0, 0, 0])


def trans(x: object = 0, y: object = 0, z: object = 0) -> np.ndarray:
    return _homogeneous(np.eye(3), np.array([x, y, z], dtype=object if _any_symbolic(x, y, z) else float))


def _any_symbolic(*values: object) -> bool:
    return any(hasattr(v, "free_symbols") and not isinstance(v, (int, float)) for v in values)


def joint_kind(kind: str, where: str = "joint") -> str:
    """Normalise a joint kind name ('R', 'revolute', 'P', 'prismatic')."""
    try:
        return _KIND_ALIASES[str(kind).lower()]
    except KeyError:
        raise ModelError(f"{where}: unknown joint kind '{kind}' (revolute or prismatic)") from None


@dataclass(frozen=True, eq=False)
class Joint:
    """A revolute or prismatic joint: fixed placement, unit axis, link-frame offset."""

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
                _check_rigid(value, f"joint '{self.name}': {key}")
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


def _check_rigid(transform: np.ndarray, where: str) -> None:
    rotation = transform[:3, :3]
    if np.max(np.abs(rotation @ rotation.T - np.eye(3))) > 1e-9 or np.linalg.det(rotation) < 0:
        raise ModelError(f"{where} is not a rigid transform (its rotation is not orthonormal)")
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
