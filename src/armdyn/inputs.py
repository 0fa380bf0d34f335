"""The one place where an argument becomes a checked array, or a ModelError that names it.

One shape rule holds everywhere: a state argument is one state (n,) or a batch (..., n);
the batch shapes of several arguments broadcast together; ``out`` is a writable
C-contiguous float64 array of exactly the result's shape.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from armdyn import memory
from armdyn.errors import ArgumentError, ModelError

LARGEST_STATE = 1e15  # beyond this a joint angle's sine and cosine are no longer exact in float64


def arm_argument(value: object, kind: type, name: str = "arm", numeric: bool = False, why: str = "") -> None:
    """Refuse an arm argument of the wrong kind (one message and one class, ArgumentError, everywhere): not an
    instance of ``kind`` (Robot, ArmModel or ActuatedArm), or symbolic where ``numeric`` numbers are needed
    (``why`` says where to go instead)."""
    if not isinstance(value, kind):
        raise ArgumentError(f"{name} must be an armdyn {kind.__name__}, got {type(value).__name__}")
    if numeric and getattr(value, "is_symbolic", False):
        raise ArgumentError(
            f"{name} '{getattr(value, 'name', '')}' has symbolic (SymPy) parameters; numbers are needed here{why}"
        )


def state(
    value: object, n: int, name: str = "q", where: str = "", complex_ok: bool = False, bounded: bool = True
) -> np.ndarray:
    """A finite float array of shape (..., n), with ``bounded`` values below LARGEST_STATE in
    magnitude (complex kept when ``complex_ok``, for complex-step derivatives of the Lagrange
    reference), or a ModelError naming the argument."""
    if value is None or isinstance(value, (str, bytes, dict)):
        raise ModelError(f"{name} must be an array of numbers of shape ({n},) or (..., {n}){where}, got {value!r}")
    try:
        complex_input = np.iscomplexobj(value)  # type: ignore[arg-type]  # NumPy documents any object; its stub says array-like
        if complex_input and not complex_ok:
            raise ModelError(f"{name} must be real{where}; it is complex")
        dtype = getattr(value, "dtype", None)
        if dtype is not None and dtype.kind not in "biufc":
            raise TypeError(f"{name} holds {dtype} values, not numbers")
        array = np.asarray(np.asarray(value), dtype=complex if complex_input else float)  # no ndarray subclass
    except (TypeError, ValueError, ArithmeticError) as error:
        if isinstance(error, ModelError):
            raise
        raise ModelError(f"{name} must be an array of numbers of shape ({n},) or (..., {n}){where}") from None
    if array.ndim == 0 or array.shape[-1] != n:
        raise ModelError(f"{name} must have shape ({n},) or (..., {n}){where}, got {array.shape}")
    largest = _magnitude(array)
    if not math.isfinite(largest):
        raise ModelError(f"{name} must be finite (it holds NaN or infinity){where}")
    if largest >= LARGEST_STATE:
        if name == "q":
            raise ModelError(
                f"q holds values of {LARGEST_STATE:.0e} or more in magnitude{where}: angles that large have no "
                "exact sine or cosine in double precision; reduce them modulo 2 pi"
            )
        if bounded:
            raise ModelError(
                f"{name} holds values of {LARGEST_STATE:.0e} or more in magnitude{where}: beyond the range the "
                "dynamics are computed in (products of such values overflow)"
            )
    return array


SMALL_ARRAY = 4096  # values: below this, |array| as a temporary costs less than a second reduction


def _magnitude(array: np.ndarray) -> float:
    """The largest magnitude in the array (0 when empty), NaN or infinity where it holds one (NaN
    propagates through max and min). A large array is not given a temporary of its size: a
    stride-0 view of a billion states has no memory of its own."""
    if not array.size:
        return 0.0
    if array.size <= SMALL_ARRAY or np.iscomplexobj(array):
        return float(np.abs(array).max())
    low, high = float(array.min()), float(array.max())
    return math.nan if math.isnan(low) or math.isnan(high) else max(-low, high)


def thawed(*states: object) -> tuple | None:
    """Writable copies of the states when one is a read-only vector, one state (a named configuration such
    as arm.qn is read-only, and Numba types a read-only array apart, so a one-state kernel refuses it);
    None otherwise: the call then takes its general path (which copies a batch only where it can afford
    to: a read-only stride-0 view of a billion states is no state to copy here)."""
    frozen = [type(x) is np.ndarray and x.ndim == 1 and not x.flags.writeable for x in states]
    if not any(frozen):
        return None
    return tuple(np.array(x) if is_frozen else x for x, is_frozen in zip(states, frozen, strict=True))


def batch_states(
    names: Sequence[str], values: Sequence[object], n: int, where: str = ""
) -> tuple[tuple[int, ...], list[np.ndarray]]:
    """Check and broadcast state arguments; return the batch shape and each as a (B, n) C array.
    Every state is bounded by LARGEST_STATE (the sine and cosine of q must be exact, and
    products of larger rates overflow)."""
    arrays = [state(value, n, name, where) for name, value in zip(names, values, strict=True)]
    try:
        batch = np.broadcast_shapes(*(a.shape[:-1] for a in arrays))
    except ValueError:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(names, arrays, strict=True))
        raise ModelError(f"the batch shapes of {shapes} do not broadcast together") from None
    shape = (*batch, n)
    copies = sum(a.shape != shape or not a.flags.c_contiguous for a in arrays)
    if copies:  # the message is formatted only where copies are made
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(names, arrays, strict=True))
        memory.affordable(copies * math.prod(shape) * 8, f"a batch of {math.prod(batch):,} states ({shapes}){where}")
    flat = [
        np.require(np.asarray(a if a.shape == shape else np.broadcast_to(a, shape)), np.float64, ["C", "W"]).reshape(
            -1, n
        )
        for a in arrays
    ]
    return batch, flat


def result(out: object, shape: tuple[int, ...]) -> np.ndarray:
    """``out`` checked against the result's shape, or a new array when out is None."""
    if out is None:
        memory.affordable(math.prod(shape) * 8, f"a result of shape {shape}")
        return np.empty(shape)
    if not (
        isinstance(out, np.ndarray)
        and out.shape == shape
        and out.dtype == np.float64
        and out.flags.c_contiguous
        and out.flags.writeable
    ):
        got = getattr(out, "shape", type(out).__name__)
        if isinstance(out, np.ndarray):
            checks = (
                ("read-only", not out.flags.writeable),
                ("not C-contiguous", not out.flags.c_contiguous),
                (str(out.dtype), out.dtype != np.float64),
            )
            flaws = [name for name, flaw in checks if flaw]
            got = f"{', '.join(flaws)} array of shape {out.shape}" if flaws else f"shape {out.shape}"
        raise ModelError(f"out must be a writable C-contiguous float64 array of shape {shape}, got {got}")
    return out


def results(
    out: object, shapes: Sequence[tuple[int, ...]], names: Sequence[str], states: Sequence[np.ndarray] = ()
) -> list[np.ndarray]:
    """``out`` as one result array per shape (None: new ones): a tuple (or list) of len(shapes) arrays, each
    checked as ``result`` does, none sharing memory with another (the second result would overwrite the
    first) or with a state it is computed from (``states``, as the kernel reads them), or a ModelError
    naming the result (``names``, one per shape)."""
    if out is None:
        return [result(None, shape) for shape in shapes]
    count = len(shapes)
    if not isinstance(out, (tuple, list)) or len(out) != count:
        got = f"{len(out)} items" if isinstance(out, (tuple, list)) else type(out).__name__
        raise ModelError(f"out must be None or a tuple of {count} arrays ({', '.join(names)}), got {got}")
    arrays = [result(part, shape) for part, shape in zip(out, shapes, strict=True)]
    for i, array in enumerate(arrays):
        for j in range(i):
            if np.shares_memory(array, arrays[j]):
                raise ModelError(
                    f"out: the arrays for {names[j]} and {names[i]} share memory; each result needs an array of its "
                    "own (the second would overwrite the first)"
                )
        for state in states:
            if np.shares_memory(array, state):
                raise ModelError(
                    f"out: the array for {names[i]} shares memory with a state it is computed from; give it an "
                    "array of its own (or pass a copy of the state)"
                )
    return arrays


def wrenches(f_ext: object, batch: tuple[int, ...]) -> np.ndarray:
    """A tool wrench [force; moment] (6,) or one per state (..., 6), as a (B, 6) C array."""
    try:
        if np.iscomplexobj(f_ext):  # type: ignore[arg-type]  # NumPy documents any object; its stub says array-like
            raise TypeError("complex")
        dtype = getattr(f_ext, "dtype", None)
        if dtype is not None and dtype.kind not in "biuf":
            raise TypeError("not numbers")
        wrench = np.asarray(f_ext, dtype=float)
    except (TypeError, ValueError, ArithmeticError):
        raise ModelError("f_ext must be a wrench [force; moment] of 6 real numbers") from None
    if wrench.ndim == 0 or wrench.shape[-1] != 6 or not np.all(np.isfinite(wrench)):
        raise ModelError(f"f_ext must be a finite wrench [force; moment] of shape (..., 6), got {wrench.shape}")
    if wrench.ndim > 1 and wrench.shape[:-1] != batch:
        raise ModelError(f"f_ext batch shape {wrench.shape[:-1]} does not match the states' {batch}")
    return np.require(np.broadcast_to(wrench, (*batch, 6)), np.float64, ["C", "W"]).reshape(-1, 6)


def gains(value: object, name: str, n: int) -> np.ndarray:
    """A non-negative scalar or n values, as (n,)."""
    array = vector(value, name)
    if array.shape[0] not in (1, n) or np.any(array < 0):
        raise ModelError(f"gain {name} must be a non-negative scalar or {n} values, got {value!r}")
    return np.broadcast_to(array, (n,)).copy()


def vector(value: object, name: str) -> np.ndarray:
    """A finite number or 1-D array of numbers, as a 1-D float array."""
    try:
        dtype = getattr(value, "dtype", None)
        if dtype is not None and dtype.kind not in "biuf":
            raise TypeError(f"{name} holds {dtype} values, not numbers")
        array = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError, ArithmeticError):
        raise ModelError(f"{name} must be a finite number or a 1-D array, got {value!r}") from None
    if array.ndim != 1 or not np.all(np.isfinite(array)):
        raise ModelError(f"{name} must be a finite number or a 1-D array, got {value!r}")
    return array


def integer(value: object, name: str, minimum: int, maximum: int | None = None, why: str = "") -> int:
    """An int (or NumPy integer, not a bool) from ``minimum`` to ``maximum``, or an error naming
    it (``why`` says what the maximum protects)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ArgumentError(f"{name} must be an integer, got {_shown(value)} ({type(value).__name__})")
    if value < minimum:
        raise ModelError(f"{name} must be at least {minimum}, got {_shown(value)}")
    if maximum is not None and value > maximum:
        raise ModelError(f"{name} must be at most {maximum:,}{why}, got {_shown(value)}")
    return int(value)


def numbers(value: object, name: str, shape: tuple[int, ...] | None = None, where: str = "") -> np.ndarray:
    """A finite real float array (of ``shape`` when given), every value below LARGEST_STATE in
    magnitude, or a ModelError naming the argument. For model parameters: lengths, masses,
    inertias, limits, gains, gravity."""
    expected = "a number" if shape == () else f"an array of numbers of shape {shape}" if shape else "numbers"
    if value is None or isinstance(value, (str, bytes, dict, set)):
        raise ModelError(f"{name} must be {expected}{where}, got {_shown(value)}")
    try:
        if np.iscomplexobj(value):  # type: ignore[arg-type]  # NumPy documents any object; its stub says array-like
            raise ModelError(f"{name} must be real{where}; it is complex")
        dtype = getattr(value, "dtype", None)
        if dtype is not None and dtype.kind not in "biuf":
            raise TypeError(f"{name} holds {dtype} values")
        array = np.array(value, dtype=float)
    except (TypeError, ValueError, ArithmeticError) as error:
        if isinstance(error, ModelError):
            raise
        raise ModelError(f"{name} must be {expected}{where}, got {_shown(value)}") from None
    if shape is not None and array.shape != shape:
        raise ModelError(f"{name} must be {expected}{where}, got shape {array.shape}")
    largest = _magnitude(array)
    if not math.isfinite(largest):
        raise ModelError(f"{name} must be finite{where} (it holds NaN or infinity)")
    if largest >= LARGEST_STATE:
        raise ModelError(
            f"{name} holds values of {LARGEST_STATE:.0e} or more in magnitude{where}: beyond the range the "
            "dynamics are computed in (products of such values overflow)"
        )
    return array


def number(value: object, name: str, where: str = "", minimum: float | None = None) -> float:
    """A finite real number (at least ``minimum`` when given) as a float, or a ModelError naming it."""
    if isinstance(value, (bool, np.bool_)):
        raise ModelError(f"{name} must be a number{where}, got {value!r}")
    result = float(numbers(value, name, (), where))
    if minimum is not None and result < minimum:
        raise ModelError(f"{name} must be at least {minimum:g}{where}, got {result:g}")
    return result


def _shown(value: object, width: int = 60) -> str:
    """A value's repr for a message, shortened to ``width`` characters."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def without_read_only(value: object) -> Any:
    """``value`` with every read-only array in it (at any depth of tuples) copied.

    Numba compiles a kernel once more for each argument that is read-only where it was writable before (a
    broadcast q0, a frozen table, a result's arrays); the kernels never write these arguments, so a copy
    changes nothing but the compile.

    Parameters
    ----------
    value : object
        An array, a tuple (of tuples) of arrays and other values, or anything else.

    Returns
    -------
    object
        The same structure, its read-only arrays copied, everything else as given.
    """
    if isinstance(value, tuple):
        return tuple(without_read_only(item) for item in value)
    if isinstance(value, np.ndarray) and not value.flags.writeable:
        return np.array(value)
    return value
