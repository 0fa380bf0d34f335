"""Mass properties of one link: mass, centre of mass, inertia; the pseudo-inertia matrix.

BOOK.md section 2 (3.2.20 to 3.2.27). Inertia tensors are given about the centre of
mass, expressed in the link frame, as URDF and the Robotics Toolbox give them.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from armdyn.errors import ModelError

_RELATIVE_TOLERANCE = 1e-9
_SMALLEST_LENGTH = 0.01  # m: the least size a link is taken to have when setting the tolerance


def _is_symbolic(*values: object) -> bool:
    """True when any value is a SymPy expression (symbolic parameters skip numeric checks)."""
    return any(np.asarray(v, dtype=object).dtype == object and _has_sympy(v) for v in values)


def _has_sympy(value: object) -> bool:
    items = np.asarray(value, dtype=object).ravel()
    return any(hasattr(item, "free_symbols") and not _is_plain_number(item) for item in items)


def _is_plain_number(item: object) -> bool:
    try:
        float(item)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True


def inertia_from_vector(values: object) -> np.ndarray:
    """A 3x3 inertia tensor from 3 principal moments, 6 values or a 3x3 matrix.

    Six values are [Ixx, Iyy, Izz, Ixy, Iyz, Ixz], the Robotics Toolbox order.

    Parameters
    ----------
    values : array_like
        3 moments (a diagonal tensor), 6 values or a 3x3 matrix.

    Returns
    -------
    numpy.ndarray
        The tensor, (3, 3) (a 3x3 input is returned as given).

    Raises
    ------
    armdyn.ModelError
        When ``values`` has another shape.
    """
    array = np.asarray(values)
    if array.shape == (3, 3):
        return array
    if array.shape == (3,):
        return np.diag(array)
    if array.shape == (6,):
        ixx, iyy, izz, ixy, iyz, ixz = array
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=array.dtype)
    raise ModelError(f"an inertia must be 3 moments, 6 values or a 3x3 matrix, got shape {array.shape}")


@dataclass(frozen=True, eq=False)
class Inertial:
    """Mass properties of a rigid link (BOOK.md section 2, 3.2.20 to 3.2.27).

    SymPy expressions are accepted as parameters (for closed-form work); numeric checks
    apply to numeric values only. ``a + b`` joins two bodies described in one frame.

    Parameters
    ----------
    mass : float, optional
        Mass (kg), finite and >= 0 (default 0).
    com : array_like, optional
        Centre of mass in the link frame (m), 3 values (default the origin).
    inertia : array_like, optional
        Inertia tensor about the centre of mass, axes of the link frame (kg m^2): 3 moments,
        6 values [Ixx Iyy Izz Ixy Iyz Ixz] or 3x3 (default zero).
    name : str, optional
        Names the link in error messages (default "link").
    strict : bool, optional
        True (default) refuses principal moments that break the triangle inequality; False
        accepts them with a warning, as CAD-exported URDFs sometimes carry. Negative mass,
        non-symmetric or indefinite tensors are always refused.

    Notes
    -----
    The symmetry, semi-definiteness and triangle-inequality tests allow rounding noise of
    ``tol = 1e-9 * max(max |I_ij|, m l^2)``, where ``l`` is the link's size: the distance
    from the link-frame origin to the centre of mass, taken as at least 1 cm. The floor
    ``m l^2`` lets a tensor that is zero up to noise pass (for instance zero moments with
    a product of inertia of 1e-20 kg m^2, as CAD exports write), while a genuinely
    indefinite tensor is refused: on a 1 kg link a principal moment of -1e-3 kg m^2 is far
    below the tolerance (1e-13 kg m^2 with the centre of mass at the origin, 1e-9 kg m^2
    with it 1 m away).

    Raises
    ------
    armdyn.ModelError
        When the mass is negative or not finite, the centre of mass is not 3 finite numbers,
        the inertia is not 3, 6 or 3x3 finite values, is not symmetric or not positive
        semi-definite, or (with ``strict``) its principal moments break the triangle
        inequality; the message names the link.
    """

    mass: object = 0.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    name: str = "link"
    strict: bool = True

    def __post_init__(self) -> None:
        symbolic = _is_symbolic(self.mass, self.com, self.inertia)
        dtype = object if symbolic else float
        try:
            com = np.array(self.com, dtype=dtype).reshape(3)
            inertia = np.array(inertia_from_vector(self.inertia), dtype=dtype)
        except (TypeError, ValueError) as error:
            if isinstance(error, ModelError):
                raise ModelError(f"link '{self.name}': {error}") from None
            raise ModelError(f"link '{self.name}': centre of mass must be 3 numbers ({error})") from None
        mass = self.mass if symbolic else float(self.mass)
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "com", com)
        object.__setattr__(self, "inertia", inertia)
        if symbolic:
            return
        com.setflags(write=False)
        inertia.setflags(write=False)
        self._validate()

    @property
    def is_symbolic(self) -> bool:
        return self.com.dtype == object

    def _validate(self) -> None:
        name, mass, inertia = self.name, self.mass, self.inertia
        if not np.isfinite(mass):
            raise ModelError(f"link '{name}': mass must be finite, got {mass}")
        if mass < 0:
            raise ModelError(f"link '{name}': mass must be non-negative, got {mass}")
        if not np.all(np.isfinite(self.com)):
            raise ModelError(f"link '{name}': centre of mass must be finite, got {self.com}")
        if not np.all(np.isfinite(inertia)):
            raise ModelError(f"link '{name}': inertia must be finite")
        tolerance = self._tolerance()
        if np.max(np.abs(inertia - inertia.T)) > tolerance:
            raise ModelError(f"link '{name}': inertia tensor is not symmetric:\n{inertia}")
        moments = np.linalg.eigvalsh(inertia)
        if moments[0] < -tolerance:
            raise ModelError(
                f"link '{name}': inertia tensor is not positive semi-definite (principal moments {moments}, "
                f"the smallest below -{tolerance:.3g} kg m^2, more than rounding noise): no rigid body has a "
                "negative moment of inertia; correct the tensor"
            )
        largest, others = moments[2], moments[0] + moments[1]
        if largest > others + tolerance:
            message = (
                f"link '{name}': principal moments {moments} break the triangle inequality "
                f"({moments[0]:.6g} + {moments[1]:.6g} < {largest:.6g}), which no rigid body can have"
            )
            if self.strict:
                raise ModelError(message + "; pass strict=False to load it anyway")
            warnings.warn(message + "; using the values as given", stacklevel=3)

    def _tolerance(self) -> float:
        """The rounding noise the validity tests allow (kg m^2): 1e-9 max(max |I_ij|, m l^2).

        ``l`` is the distance from the link-frame origin to the centre of mass, at least 1 cm
        (see the class Notes).
        """
        size = max(float(np.linalg.norm(self.com)), _SMALLEST_LENGTH)
        scale = max(float(np.max(np.abs(self.inertia))), self.mass * size**2)
        return _RELATIVE_TOLERANCE * max(scale, 1e-300)

    @property
    def first_moment(self) -> np.ndarray:
        """m c, the first moment of mass (3.2.25)."""
        return self.mass * self.com

    def inertia_about_origin(self) -> np.ndarray:
        """Inertia about the link-frame origin, by the parallel-axis theorem.

        Returns
        -------
        numpy.ndarray
            I + m ((c . c) I3 - c c^T), (3, 3), in link-frame axes.
        """
        c = self.com
        shift = (c @ c) * np.eye(3) - np.outer(c, c)
        return self.inertia + self.mass * shift

    def pseudo_inertia(self) -> np.ndarray:
        """The 4x4 pseudo-inertia matrix J = integral of r r^T dm, r = [x y z 1] (3.2.27).

        Returns
        -------
        numpy.ndarray
            J, (4, 4): the second moments, the first moment m c and the mass m.
        """
        inertia = self.inertia_about_origin()
        second_moment = np.trace(inertia) / 2 * np.eye(3) - inertia
        pseudo = np.empty((4, 4), dtype=self.com.dtype)
        pseudo[:3, :3] = second_moment
        pseudo[:3, 3] = pseudo[3, :3] = self.first_moment
        pseudo[3, 3] = self.mass
        return pseudo

    def transformed(self, transform: np.ndarray) -> Inertial:
        """The same body described in a frame F, given transform = pose of this frame in F.

        Parameters
        ----------
        transform : numpy.ndarray
            The pose of the body's current frame in F, a 4x4 homogeneous transform.

        Returns
        -------
        Inertial
            The body with its centre of mass and inertia expressed in F.
        """
        rotation, translation = transform[:3, :3], transform[:3, 3]
        return _trusted(self.mass, rotation @ self.com + translation, rotation @ self.inertia @ rotation.T, self.name)

    def __add__(self, other: Inertial) -> Inertial:
        """Two bodies rigidly joined, both described in the same frame (parallel-axis theorem)."""
        mass = self.mass + other.mass
        if mass == 0:
            return _trusted(0.0, np.zeros(3), self.inertia + other.inertia, self.name)
        com = (self.mass * self.com + other.mass * other.com) / mass

        def about(body: Inertial) -> np.ndarray:
            d = body.com - com
            return body.inertia + body.mass * ((d @ d) * np.eye(3) - np.outer(d, d))

        return _trusted(mass, com, about(self) + about(other), self.name)


def _trusted(mass: object, com: np.ndarray, inertia: np.ndarray, name: str) -> Inertial:
    """An Inertial derived from already validated ones (a rotation or a sum keeps validity)."""
    body = object.__new__(Inertial)
    for key, value in (("mass", mass), ("com", com), ("inertia", inertia), ("name", name), ("strict", False)):
        object.__setattr__(body, key, value)
    return body
