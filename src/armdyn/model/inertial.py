"""Mass properties of one link: mass, centre of mass, inertia; the pseudo-inertia matrix.

Lewis, Dawson and Abdallah 2004, Section 3.2, eqs. (3.2.20) to (3.2.27). Inertia tensors are given about the centre of
mass, expressed in the link frame, as URDF and the Robotics Toolbox give them.

The model classes check their parameters with the helpers here (``parameter``,
``parameter_array``, ``real_array``, ``real_number``, ``whole_number``): a number or array
that is not a finite real value below 1e15 in magnitude (joint limits: not NaN) is refused
with a ModelError naming it and the link or joint; SymPy expressions pass unchecked, for
closed-form work. They
follow the rules of armdyn.inputs.numbers, number and integer, which the model layer does
not import (it depends on numpy and armdyn.errors only).
"""

from __future__ import annotations

import reprlib
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeAlias, TypeVar

import numpy as np

from armdyn.errors import ModelError

if TYPE_CHECKING:
    from sympy import Expr

Scalar: TypeAlias = "float | Expr"  # a number parameter: a float, or a SymPy expression for closed-form work

_RELATIVE_TOLERANCE = 1e-9
_SMALLEST_LENGTH = 0.01  # m: the least size a link is taken to have when setting the tolerance
_LARGEST = 1e15  # armdyn.inputs.LARGEST_STATE: products of larger values overflow in the dynamics
_T = TypeVar("_T")


PARAMETER_ENTRIES = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))
"""The inertia entries among a body's ten parameters, in their order: Ixx, Ixy, Iyy, Ixz, Iyz, Izz."""


def _is_symbolic(*values: object) -> bool:
    """True when any value is or holds a SymPy expression (symbolic parameters skip numeric checks)."""
    return any(_has_sympy(v) for v in values)


def _has_sympy(value: object) -> bool:
    if isinstance(value, np.ndarray) and value.dtype != object:
        return False
    try:
        items = np.asarray(value, dtype=object).ravel()
    except (TypeError, ValueError):  # a ragged nest numpy cannot hold: no expression either way
        return False
    return any(hasattr(item, "free_symbols") and not _is_plain_number(item) for item in items)


def _is_plain_number(item: object) -> bool:
    try:
        float(item)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True


def _named(where: str, check: Callable[..., _T], *args: object, **options: object) -> _T:
    """``check(*args, **options)`` with ``where`` (the link or joint) put before its error message."""
    try:
        return check(*args, **options)
    except (ModelError, TypeError) as error:
        raise type(error)(f"{where}: {error}") from None


def real_array(value: object, name: str, where: str, bounds: bool = False, expected: str = "numbers") -> np.ndarray:
    """A finite real float array, every value below 1e15 in magnitude, or a ModelError naming
    ``name`` and ``where``. An object array of plain numbers counts as numbers (a SymPy
    computation can leave one). ``bounds`` takes values that are only compared, never
    multiplied (joint limits): +-inf (no bound) and any magnitude (URDF files write 1e16),
    never NaN. ``expected`` says what was wanted, in the message."""
    if isinstance(value, np.ndarray) and value.dtype == object:
        value = value.tolist()
    return _named(where, _numbers, value, name, bounds, expected)


def _numbers(value: object, name: str, bounds: bool, expected: str) -> np.ndarray:
    """The rule of armdyn.inputs.numbers: no None, text, mapping, set, complex or non-numeric dtype."""
    if value is None or isinstance(value, (str, bytes, dict, set)):
        raise ModelError(f"{name} must be {expected}, got {reprlib.repr(value)}")
    try:
        if np.iscomplexobj(value):  # type: ignore[arg-type]  # NumPy documents any object; its stub says array-like
            raise ModelError(f"{name} must be real; it is complex")
        dtype = getattr(value, "dtype", None)
        if dtype is not None and dtype.kind not in "biuf":
            raise TypeError(name)
        with np.errstate(over="raise"):  # a long double beyond float64 raises instead of becoming inf
            array = np.array(value, dtype=float)
    except (TypeError, ValueError, ArithmeticError) as error:
        if isinstance(error, ModelError):
            raise
        raise ModelError(f"{name} must be {expected}, got {reprlib.repr(value)}") from None
    if bounds:
        if np.isnan(array).any():
            raise ModelError(f"{name} must not be NaN (an infinite value means none)")
        return array
    if array.size and not np.all(np.isfinite(array)):
        raise ModelError(f"{name} must be finite (it holds NaN or infinity)")
    if array.size and np.abs(array).max() >= _LARGEST:
        raise ModelError(
            f"{name} holds values of {_LARGEST:.0e} or more in magnitude: beyond the range the dynamics are "
            "computed in (products of such values overflow)"
        )
    return array


def real_number(value: object, name: str, where: str, minimum: float | None = None) -> float:
    """A finite real number below 1e15 in magnitude (at least ``minimum`` when given), not a
    bool, as a float; or a ModelError naming ``name`` and ``where``."""
    if isinstance(value, (bool, np.bool_)):
        raise ModelError(f"{where}: {name} must be a number, got {value!r}")
    array = real_array(value, name, where, expected="a real number")
    if array.shape != ():
        raise ModelError(f"{where}: {name} must be a number, got shape {array.shape}")
    result = float(array)
    if minimum is not None and result < minimum:
        raise ModelError(f"{where}: {name} must be at least {minimum:g}, got {result:g}")
    return result


def whole_number(value: object, name: str, where: str, minimum: int) -> int:
    """An int (or NumPy integer, not a bool) of at least ``minimum``: the rule of armdyn.inputs.integer."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{where}: {name} must be an integer, got {reprlib.repr(value)} ({type(value).__name__})")
    if value < minimum:
        raise ModelError(f"{where}: {name} must be at least {minimum}, got {value}")
    return int(value)


def parameter_array(value: object, name: str, where: str) -> np.ndarray:
    """An array parameter: ``real_array``, or an object array when it holds SymPy expressions
    (its plain numbers checked all the same)."""
    if not _is_symbolic(value):
        return real_array(value, name, where)
    try:
        array = np.array(value, dtype=object)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: {name} must be an array of numbers or SymPy expressions") from None
    for item in array.ravel():
        if not _is_symbolic(item):
            real_number(item, name, where)
    return array


def parameter(value: object, name: str, where: str, minimum: float | None = None) -> Scalar:
    """A number parameter: a SymPy expression as given, else a finite real float (at least
    ``minimum`` when given), or a ModelError naming ``name`` and ``where``."""
    if _is_symbolic(value):
        return value
    return real_number(value, name, where, minimum)


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
        When ``values`` has another shape (or is no array at all).
    """
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):  # a ragged nest
        array = np.empty(0)
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
    """Mass properties of a rigid link (Section 3.2, eqs. (3.2.20) to (3.2.27)).

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
        When the mass is not a finite real number or is negative, the centre of mass is not
        3 finite real numbers, the inertia is not 3, 6 or 3x3 finite real values, is not
        symmetric or not positive semi-definite, or (with ``strict``) its principal moments
        break the triangle inequality; the message names the argument and the link. Numbers
        of 1e15 or more in magnitude are refused (products of them overflow).
    """

    mass: Scalar = 0.0
    com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    name: str = "link"
    strict: bool = True

    def __post_init__(self) -> None:
        where = f"link '{self.name}'"
        mass = parameter(self.mass, "mass", where)
        com = parameter_array(self.com, "centre of mass", where)
        if com.shape != (3,):
            raise ModelError(f"{where}: centre of mass must be 3 numbers, got shape {com.shape}")
        inertia = _named(where, inertia_from_vector, parameter_array(self.inertia, "inertia", where))
        symbolic = _is_symbolic(mass, com, inertia)
        if not _is_symbolic(mass) and mass < 0:
            raise ModelError(f"{where}: mass must be non-negative, got {mass}")
        if symbolic:  # one dtype for the three, so that sums and products stay symbolic
            com, inertia = com.astype(object), inertia.astype(object)
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
        """The rules of a rigid body for a numeric tensor: symmetric, positive semi-definite, triangle inequality."""
        name, inertia = self.name, self.inertia
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

    def parameters(self) -> np.ndarray:
        """The body's ten inertial parameters [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], the inertia
        about the frame origin: the body's columns of the regressor W (Table 3.3.1, property 9).

        Returns
        -------
        numpy.ndarray
            (10,).
        """
        inertia = self.inertia_about_origin()
        return np.array([self.mass, *self.first_moment, *(inertia[r, c] for r, c in PARAMETER_ENTRIES)], dtype=float)

    @classmethod
    def from_parameters(cls, phi10: object, name: str = "link", strict: bool = True) -> Inertial:
        """The body of ten inertial parameters (the inverse of ``parameters``): c = h / m (the origin for a
        massless body) and the inertia about c, I_O - m ((c . c) 1 - c c^T).

        Parameters
        ----------
        phi10 : array_like
            [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], (10,).
        name : str, optional
            Names the body in error messages.
        strict : bool, optional
            As Inertial's (triangle inequality refused, or only warned of).

        Returns
        -------
        Inertial

        Raises
        ------
        armdyn.ModelError
            When phi10 is not ten finite numbers, or the body they make is not physical (see Inertial).
        """
        phi = real_array(phi10, "phi10", name)
        if phi.shape != (10,):
            raise ModelError(f"{name}: phi10 must be 10 numbers, got shape {phi.shape}")
        mass, first_moment = float(phi[0]), phi[1:4]
        origin = np.empty((3, 3))
        for k, (r, c) in enumerate(PARAMETER_ENTRIES):
            origin[r, c] = origin[c, r] = phi[4 + k]
        com = first_moment / mass if mass > 0 else np.zeros(3)
        about_com = origin - mass * ((com @ com) * np.eye(3) - np.outer(com, com))
        return cls(mass, com, (about_com + about_com.T) / 2, name, strict)

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


def _trusted(mass: Scalar, com: np.ndarray, inertia: np.ndarray, name: str) -> Inertial:
    """An Inertial derived from already validated ones (a rotation or a sum keeps validity)."""
    body = object.__new__(Inertial)
    for key, value in (("mass", mass), ("com", com), ("inertia", inertia), ("name", name), ("strict", False)):
        object.__setattr__(body, key, value)
    return body
