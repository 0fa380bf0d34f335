"""Checks of drive parameters: each a number of the right sign, or a ModelError naming it (an ArgumentError
for a name that is not a str)."""

from __future__ import annotations

import math
import reprlib

import numpy as np

from armdyn import inputs
from armdyn.errors import ArgumentError, ModelError


def _drive_name(name: object) -> str:
    if not isinstance(name, str) or not name:
        error = ModelError if isinstance(name, str) else ArgumentError  # an empty name, or no str at all
        raise error(f"a drive's name must be a non-empty str, got {reprlib.repr(name)}")
    return name


def _value(value: object, what: str, where: str) -> float:
    """A finite real number or a ModelError naming the quantity and the drive."""
    return inputs.number(value, what, f" ({where})")


def _positive(value: object, what: str, where: str, why: str = "") -> float:
    number = _value(value, what, where)
    if not number > 0:
        raise ModelError(f"{where}: {what} must be positive{why}, got {number:g}")
    return number


def _non_negative(value: object, what: str, where: str, why: str = "") -> float:
    number = _value(value, what, where)
    if number < 0:
        raise ModelError(f"{where}: {what} must be >= 0{why}, got {number:g}")
    return number


def _limit(value: object, what: str, where: str) -> float:
    """A positive limit; infinity (the default) for none."""
    if isinstance(value, (int, float, np.floating)) and not isinstance(value, bool) and value == math.inf:
        return math.inf
    return _positive(value, what, where, " (math.inf for none)")


def _coulomb(value: object, where: str) -> tuple[float, float]:
    """(Tc+, Tc-) from a magnitude c >= 0 (meaning (c, -c)) or a pair with Tc+ >= 0 >= Tc-."""
    array = inputs.numbers(value, "Coulomb friction", where=f" ({where})")
    if array.shape == () and array >= 0:
        array = np.array([array, -array])
    if array.shape != (2,) or array[0] < 0 or array[1] > 0:
        raise ModelError(
            f"{where}: Coulomb friction must be a magnitude c >= 0 or a pair (Tc+, Tc-) with Tc+ >= 0 >= Tc-, "
            f"got {reprlib.repr(value)}"
        )
    return float(array[0]), float(array[1])
