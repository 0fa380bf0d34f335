"""Hostile values and the rule a fuzzed call is judged by (used by tests/test_fuzz.py).

A ``Value`` is what one argument receives, with what the call must then do:

- "same": a valid value, perhaps an unusual one (an int array, a list, a read-only or strided
  view, a batch): the call must return the result it returns for ``reference`` (a plain
  float64 array or the like);
- "either": the call may refuse it (ModelError or TypeError naming the argument, or a
  SimulationError for a run that stops) or return a finite result (equal to the result for
  ``reference`` when there is one);
- "bad": the call must refuse it with a ModelError or a TypeError (or, for a run that stops, a
  SimulationError) whose message names the argument.

Any other exception, a RuntimeWarning or ComplexWarning (made errors), a NaN or infinity in
a result, an input array changed by the call, or a message that does not name the argument
is a failure. ``fuzz`` runs one target under hypothesis and returns its failures instead of
stopping at the first, so one run lists every class of defect.
"""

from __future__ import annotations

import dataclasses
import json
import re
import sys
import warnings
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction

import numpy as np
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import armdyn as ad

NOTHING = object()  # no reference: nothing to compare a result with
COUNT = [0]  # cases tried in this process
FAILURES: list[dict] = []  # every failure found in this process
BEFORE_CASE: list[Callable[[int, str], bool]] = []  # hooks (the isolated runner's progress); False skips a case
Kinds = list  # of hypothesis strategies of Value, one per kind of value (see ``fuzz``)


def items_values(items: Sequence[Value]) -> Kinds:
    """Fixed values, each a kind of its own (a fresh copy of the Value at every draw)."""
    return [st.just(item).map(dataclasses.replace) for item in items]


def lazy(make: Callable[[], Value]) -> st.SearchStrategy[Value]:
    """A kind whose Value is made when drawn (a file written then, for instance)."""
    return st.just(None).map(lambda _: make())


# ----- values ---------------------------------------------------------------------------------


@dataclass
class Value:
    """One argument's value and what the call must do with it (see the module docstring)."""

    label: str
    value: object
    verdict: str  # "same", "either" or "bad"
    reference: object = NOTHING
    names: tuple[str, ...] = ()  # further words that name the offending argument in a message
    real_part: bool = False  # compare the real part of a complex result with the reference
    batch_others: bool = False  # the other state arguments become batches of 2 (a shape mismatch)
    is_out: bool = False  # the result must be this very array
    check: Callable[[object], str | None] | None = None  # a further test of a returned result


def _readonly(array: np.ndarray) -> np.ndarray:
    array = np.array(array)
    array.setflags(write=False)
    return array


class _Opaque:
    """An arbitrary object: no numbers, no sequence, no array interface."""

    def __repr__(self) -> str:
        return "<opaque object>"


def junk_values() -> list[tuple[str, object]]:
    """Objects that are no number, array or name at all."""
    return [
        ("None", None),
        ("dict", {"q": 1.0}),
        ("set", {1.0, 2.0}),
        ("object()", _Opaque()),
        ("str", "abc"),
        ("bytes", b"abc"),
        ("lambda", lambda *a: 0.0),
        ("Ellipsis", ...),
        ("module", np),
        ("type", float),
    ]


def state_values(
    base: np.ndarray,
    *,
    batch: bool = True,
    complex_ok: bool = False,
    bounded: bool = True,
    scalar_ok: bool = False,
) -> Kinds:
    """Values for an argument of shape (n,) or (..., n) whose valid value is ``base`` (n,), or
    (N, n) for sample arrays.

    ``batch``: further leading axes are valid; ``complex_ok``: complex values are kept (the
    Lagrange reference and kinematics, for complex-step derivatives); ``bounded``: values of
    1e15 or more in magnitude must be refused (joint positions); ``scalar_ok``: a number
    stands for that value in every entry.
    """
    base = np.asarray(base, dtype=float)
    return [_state_value(base, batch, complex_ok, bounded, scalar_ok, kind) for kind in STATE_KINDS]


_elementwise = np.vectorize(lambda f, x: f(x), otypes=[object])


def _entry(b: np.ndarray, i: int, value: object) -> list:
    """``b`` as nested lists with column i replaced by ``value``."""
    items = b.astype(object)
    items[..., i] = value
    return items.tolist()


@st.composite
def _state_value(
    draw: st.DrawFn, base: np.ndarray, batch: bool, complex_ok: bool, bounded: bool, scalar_ok: bool, kind: str
) -> Value:
    n = base.shape[-1]
    batch_verdict = "same" if batch else "bad"
    i = draw(st.integers(0, n - 1))
    b = base.copy()
    other = base * 0.5 + 0.25
    column = np.arange(n) == i
    if kind == "list":
        return Value("list", b.tolist(), "same", b)
    if kind == "tuple of numpy scalars":
        return Value(kind, tuple(np.float64(x) for x in b) if b.ndim == 1 else tuple(b), "same", b)
    if kind == "int array":
        ints = np.round(b * draw(st.sampled_from([1, 2]))).astype(np.int64)
        return Value(kind, ints, "same", ints.astype(float))
    if kind == "int list":
        ints = np.round(b).astype(int)
        return Value(kind, ints.tolist(), "same", ints.astype(float))
    if kind == "uint8 array":
        ints = np.abs(np.round(b)).astype(np.uint8)
        return Value(kind, ints, "same", ints.astype(float))
    if kind == "float32 array":
        single = b.astype(np.float32)
        return Value(kind, single, "same", single.astype(float))
    if kind == "float16 array":
        half = b.astype(np.float16)
        return Value(kind, half, "same", half.astype(float))
    if kind == "longdouble array":
        return Value(kind, b.astype(np.longdouble), "same", b)
    if kind == "big-endian array":
        return Value(kind, b.astype(">f8"), "same", b)
    if kind == "strided view":
        return Value(kind, np.repeat(b, 2, axis=-1)[..., ::2], "same", b)
    if kind == "read-only array":
        return Value(kind, _readonly(b), "same", b)
    if kind == "negative zeros":
        zeros = np.where(np.arange(n) % 2 == 0, -0.0, b)
        return Value(kind, zeros, "same", zeros + 0.0)
    if kind == "subnormal":
        tiny = b.copy()
        tiny[..., i] = 5e-324
        return Value(kind, tiny, "same", tiny)
    if kind == "batch (2, n)":
        stack = np.stack([b, other])
        return Value(kind, stack, batch_verdict, stack)
    if kind == "Fortran-ordered batch":
        stack = np.stack([b, other])
        return Value(kind, np.asfortranarray(stack), batch_verdict, stack)
    if kind == "batch (2, 1, n)":
        stack = np.stack([b, other])[:, None]
        return Value(kind, stack, batch_verdict, stack)
    if kind == "batch (1, 1, n) nested list":
        return Value(kind, [[b.tolist()]], "same" if batch else "either", b[None, None] if batch else b)
    if kind == "empty batch (0, n)":
        return Value(kind, np.zeros((0, n)), batch_verdict if b.ndim == 1 else "bad", np.zeros((0, n)))
    if kind == "broadcast view (stride 0)":
        view = np.broadcast_to(b, (3, *b.shape))
        return Value(kind, view, batch_verdict, np.array(view))
    if kind == "batch with NaN in one state":
        stack = np.stack([b, other])
        stack[1, ..., i] = np.nan
        return Value(kind, stack, "bad")
    if kind == "mismatched batch (3, n) vs (2, n)":
        return Value(kind, np.stack([b, other, b]), "bad", batch_others=batch)
    if kind == "bool array":
        flags = np.broadcast_to(np.arange(n) % 2 == 0, b.shape).copy()
        return Value(kind, flags, "either", flags.astype(float))
    if kind == "object array of floats":
        return Value(kind, b.astype(object), "either", b)
    if kind == "Fraction list":
        fractions = _elementwise(lambda x: Fraction(round(x * 4), 4), b)
        return Value(kind, fractions.tolist(), "either", fractions.astype(float))
    if kind == "Decimal list":
        return Value(kind, _elementwise(lambda x: Decimal(repr(float(x))), b).tolist(), "either", b)
    if kind == "numeric str array":
        return Value(kind, _elementwise(lambda x: repr(float(x)), b).astype(str), "either", b)
    if kind == "bytes array":
        return Value(kind, _elementwise(lambda x: repr(float(x)).encode(), b).astype(bytes), "either", b)
    if kind == "bytearray":
        raw = bytearray(range(1, n + 1))
        return Value(kind, raw, "either" if b.ndim == 1 else "bad", np.arange(1.0, n + 1))
    if kind == "masked array (NaN masked)":
        data = b.copy()
        data[..., i] = np.nan
        return Value(kind, np.ma.masked_array(data, mask=np.isnan(data)), "either")
    if kind == "matrix (1, n)":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PendingDeprecationWarning)
            return Value(kind, np.asmatrix(b), "either", np.atleast_2d(b))
    if kind == "1e16 entry":
        big = b.copy()
        big[..., i] = draw(st.sampled_from([1e16, -1e16]))
        return Value(kind, big, "bad" if bounded else "either")
    if kind == "1e300 entry":
        big = b.copy()
        big[..., i] = draw(st.sampled_from([1e300, -1e300, np.finfo(float).max]))
        return Value(kind, big, "bad" if bounded else "either")
    if kind == "1e6 entry":
        big = b.copy()
        big[..., i] = 1e6
        return Value(kind, big, "either")
    if kind == "huge python int":
        return Value(kind, _entry(b, i, 10**400), "bad" if bounded else "either")
    if kind == "NaN entry":
        bad = b.copy()
        bad[..., i] = np.nan
        return Value(kind, bad, "bad")
    if kind == "inf entry":
        bad = b.copy()
        bad[..., i] = draw(st.sampled_from([np.inf, -np.inf]))
        return Value(kind, bad, "bad")
    if kind == "None entry in list":
        return Value(kind, _entry(b, i, None), "bad")
    if kind == "str entry in list":
        return Value(kind, _entry(b, i, "0.5"), "either", np.where(column, 0.5, b))
    if kind == "text entry in list":
        return Value(kind, _entry(b, i, "x"), "bad")
    if kind == "complex array":
        step = draw(st.sampled_from([1e-20, 1e-3, 1.0]))
        value = b + 1j * step * column
        if complex_ok:
            return Value(kind, value, "either", b if step <= 1e-20 else NOTHING, real_part=True)
        return Value(kind, value, "bad")
    if kind == "complex with zero imaginary part":
        return Value(kind, b.astype(complex), "either" if complex_ok else "bad", b, real_part=True)
    if kind == "list with a complex":
        items = b.astype(complex)
        items[..., i] += 1j
        return Value(kind, items.tolist(), "either" if complex_ok else "bad")
    if kind == "scalar":
        x = draw(st.sampled_from([0.5, 1, np.float64(0.5), True]))
        if not scalar_ok:
            return Value(f"scalar {x!r}", x, "bad")
        return Value(f"scalar {x!r}", x, "either" if x is True else "same", np.full(b.shape, float(x)))
    if kind == "0-d array":
        if scalar_ok:
            return Value(kind, np.array(0.5), "either", np.full(b.shape, 0.5))
        return Value(kind, np.array(0.5), "bad")
    if kind == "shape (n-1,)":
        return Value(kind, b[..., :-1], "bad")
    if kind == "shape (n+1,)":
        return Value(kind, np.concatenate([b, b[..., :1]], -1), "bad")
    if kind == "shape (2, n+1)":
        return Value(kind, np.zeros((2, n + 1)), "bad")
    if kind == "shape (n, 1)":  # for one vector (batch=False): a column is that vector, or refused
        return Value(kind, b[..., None], "bad" if batch else "either", b)
    if kind == "empty (0,)":
        return Value(kind, np.zeros(0), "bad")
    if kind == "empty list":
        return Value(kind, [], "bad")
    if kind == "ragged nested list":
        return Value(kind, [b.tolist(), b.tolist()[:-1]], "bad")
    if kind == "object array of str":
        return Value(kind, np.full(b.shape, "a", dtype=object), "bad")
    if kind == "text str array":
        return Value(kind, np.full(b.shape, "x"), "bad")
    if kind == "datetime64 array":
        return Value(kind, np.full(b.shape, "2020-01-01", dtype="datetime64[D]"), "bad")
    if kind == "generator":
        return Value(kind, (x for x in b), "either", b)
    if kind == "list of 1-element arrays":
        return Value(kind, [np.array([x]) for x in b.ravel()], "bad" if batch else "either", b)
    label, junk_value = draw(st.sampled_from(junk_values()))
    return Value(f"junk: {label}", junk_value, "bad")


STATE_KINDS = [
    "list",
    "tuple of numpy scalars",
    "int array",
    "int list",
    "uint8 array",
    "float32 array",
    "float16 array",
    "longdouble array",
    "big-endian array",
    "strided view",
    "read-only array",
    "negative zeros",
    "subnormal",
    "batch (2, n)",
    "Fortran-ordered batch",
    "batch (2, 1, n)",
    "batch (1, 1, n) nested list",
    "empty batch (0, n)",
    "broadcast view (stride 0)",
    "batch with NaN in one state",
    "mismatched batch (3, n) vs (2, n)",
    "bool array",
    "object array of floats",
    "Fraction list",
    "Decimal list",
    "numeric str array",
    "bytes array",
    "bytearray",
    "masked array (NaN masked)",
    "matrix (1, n)",
    "1e16 entry",
    "1e300 entry",
    "1e6 entry",
    "huge python int",
    "NaN entry",
    "inf entry",
    "None entry in list",
    "str entry in list",
    "text entry in list",
    "complex array",
    "complex with zero imaginary part",
    "list with a complex",
    "scalar",
    "0-d array",
    "shape (n-1,)",
    "shape (n+1,)",
    "shape (2, n+1)",
    "shape (n, 1)",
    "empty (0,)",
    "empty list",
    "ragged nested list",
    "object array of str",
    "text str array",
    "datetime64 array",
    "generator",
    "list of 1-element arrays",
    "junk",
]


def out_values(shape: tuple[int, ...], risky: bool = False) -> Kinds:
    """Values for ``out=`` where the result has ``shape``. ``risky`` adds the buffers that a
    compiled kernel writing without checks would corrupt (read-only memory of a bytes object)."""
    size = int(np.prod(shape))
    kinds = list(OUT_KINDS) + (["frombuffer of bytes (read-only memory)"] if risky else [])

    return [_out_value(shape, kind, size) for kind in kinds]


@st.composite
def _out_value(draw: st.DrawFn, shape: tuple[int, ...], kind: str, size: int) -> Value:
    if kind == "None":
        return Value(kind, None, "same", None)
    if kind == "exact (NaN-filled)":
        return Value(kind, np.full(shape, np.nan), "same", None, is_out=True)
    if kind == "shape minus one":
        return Value(kind, np.empty((*shape[:-1], shape[-1] - 1)), "bad")
    if kind == "shape plus one":
        return Value(kind, np.empty((*shape[:-1], shape[-1] + 1)), "bad")
    if kind == "extra leading axis (1, ...)":
        return Value(kind, np.empty((1, *shape)), "bad")
    if kind == "flat":
        return Value(kind, np.empty(size), "bad" if len(shape) > 1 else "same", None, is_out=len(shape) == 1)
    if kind == "much too small (1,)":
        return Value(kind, np.empty(1), "bad")
    if kind == "much too large (1000,)":
        return Value(kind, np.empty(1000), "bad")
    if kind == "0-d":
        return Value(kind, np.empty(()), "bad")
    if kind == "float32":
        return Value(kind, np.empty(shape, dtype=np.float32), "bad")
    if kind == "int64":
        return Value(kind, np.empty(shape, dtype=np.int64), "bad")
    if kind == "complex128":
        return Value(kind, np.empty(shape, dtype=complex), "bad")
    if kind == "big-endian float64":
        return Value(kind, np.empty(shape, dtype=">f8"), "bad")
    if kind == "strided view":
        return Value(kind, np.empty((*shape[:-1], 2 * shape[-1]))[..., ::2], "bad")
    if kind == "transposed (Fortran)":
        if len(shape) < 2:
            return Value(kind, np.empty((*shape, 2))[..., 0], "bad")
        return Value(kind, np.empty(shape[::-1]).T, "bad")
    if kind == "read-only":
        return Value(kind, _readonly(np.zeros(shape)), "bad")
    if kind == "list":
        return Value(kind, np.zeros(shape).tolist(), "bad")
    if kind == "frombuffer of bytes (read-only memory)":
        return Value(kind, np.frombuffer(bytes(8 * size), dtype=float).reshape(shape), "bad")
    label, junk_value = draw(st.sampled_from([j for j in junk_values() if j[0] != "None"]))
    return Value(f"junk: {label}", junk_value, "bad")


OUT_KINDS = [
    "None",
    "exact (NaN-filled)",
    "shape minus one",
    "shape plus one",
    "extra leading axis (1, ...)",
    "flat",
    "much too small (1,)",
    "much too large (1000,)",
    "0-d",
    "float32",
    "int64",
    "complex128",
    "big-endian float64",
    "strided view",
    "transposed (Fortran)",
    "read-only",
    "list",
    "junk",
]


def scalar_values(
    valid: Sequence[float],
    rule: Callable[[float], str],
    *,
    none: str = "bad",
    integer: bool = False,
    extra: Sequence[tuple[str, object, str]] = (),
    complex_verdict: str = "bad",
    arrays_ok: bool = False,
) -> Kinds:
    """Values for a number argument. ``rule(x)`` says what a plain float x is ("same", "either",
    "bad"); ``none`` what None is; ``integer``: the argument is a count (floats are then
    "either" at best: refused, or taken as the whole number they equal); ``extra``: further
    (label, value, verdict) triples; ``arrays_ok``: arrays of such numbers are valid too (a
    result of their shape)."""
    kinds = [_scalar_value(valid, rule, none, integer, complex_verdict, arrays_ok, kind) for kind in SCALAR_KINDS]
    kinds += [_scalar_value(valid, rule, none, integer, complex_verdict, arrays_ok, y) for y in SPECIALS]
    return kinds + items_values(
        [Value(label, v, verdict, v if verdict == "same" else NOTHING) for label, v, verdict in extra]
    )


@st.composite
def _scalar_value(
    draw: st.DrawFn,
    valid: Sequence[float],
    rule: Callable[[float], str],
    none: str,
    integer: bool,
    complex_verdict: str,
    arrays_ok: bool,
    kind: str | float,
) -> Value:
    x = draw(st.sampled_from(list(valid)))
    if kind == "valid":
        return Value(f"valid {x!r}", x, "same", x)
    if not isinstance(kind, str):  # a special float
        y = kind
        verdict = rule(y)
        if integer and verdict == "same":  # a float for a count: refused, or taken as its whole number
            verdict = "either"
        whole = integer and verdict != "bad" and np.isfinite(y)
        return Value(f"float {y!r}", y, verdict, int(y) if whole else y)
    if kind == "numpy float64":
        return Value(kind, np.float64(x), "same" if not integer else "either", x)
    if kind == "numpy float32":
        return Value(kind, np.float32(x), "either", float(np.float32(x)))
    if kind in ("numpy int64", "python int") and np.isfinite(x):
        whole = round(x)
        return Value(kind, np.int64(whole) if kind == "numpy int64" else whole, rule(float(whole)), whole)
    if kind == "bool":
        flag = draw(st.booleans())
        return Value(f"bool {flag}", flag, "either" if rule(float(flag)) != "bad" else "bad", int(flag))
    if kind == "0-d array":
        return Value(kind, np.array(x), "same" if arrays_ok else "either", np.array(x) if arrays_ok else x)
    if kind == "one-element list":
        return Value(kind, [x], "same" if arrays_ok else "either", np.array([x]) if arrays_ok else x)
    if kind == "two-element array":
        return Value(kind, np.array([x, x]), "same" if arrays_ok else "either", np.array([x, x]))
    if kind == "complex":
        return Value(kind, complex(x, draw(st.sampled_from([0.0, 1.0]))), complex_verdict)
    if kind == "numeric str":
        return Value(kind, repr(x), "either", x)
    if kind == "Fraction":
        fraction = Fraction(x).limit_denominator(1000)
        return Value(kind, fraction, "either", float(fraction))
    if kind == "Decimal":
        return Value(kind, Decimal(repr(x)), "either", x)
    if kind == "huge python int":
        return Value(kind, 10**400, "bad" if rule(1e300) == "bad" else "either")
    if kind == "None":
        return Value(kind, None, none, None if none == "same" else NOTHING)
    if kind in ("numpy int64", "python int"):
        return Value(f"valid {x!r}", x, "same", x)
    label, junk_value = draw(st.sampled_from([j for j in junk_values() if j[0] != "None"]))
    return Value(f"junk: {label}", junk_value, "bad")


SCALAR_KINDS = [
    "valid",
    "numpy float64",
    "numpy float32",
    "numpy int64",
    "python int",
    "bool",
    "0-d array",
    "one-element list",
    "two-element array",
    "complex",
    "numeric str",
    "Fraction",
    "Decimal",
    "huge python int",
    "None",
    "junk",
]
SPECIALS = [np.nan, np.inf, -np.inf, 0.0, -1.0, -1e-300, 1e-300, 1e16, 1e300, -1e300, 0.5, 3.0]


def positive(x: float) -> str:
    """A rule: positive and finite (huge values may be refused or must give finite results)."""
    if not np.isfinite(x) or x <= 0:
        return "bad"
    return "either" if x >= 1e15 or x <= 1e-200 else "same"


def non_negative(x: float) -> str:
    if not np.isfinite(x) or x < 0:
        return "bad"
    return "either" if x >= 1e15 or 0 < x <= 1e-200 else "same"


def finite(x: float) -> str:
    if not np.isfinite(x):
        return "bad"
    return "either" if abs(x) >= 1e15 else "same"


def none_is_valid(kinds: Kinds) -> Kinds:
    """The kinds with None made a valid value (the default of the parameter)."""

    def valid(value: Value) -> Value:
        return dataclasses.replace(value, verdict="same", reference=None) if value.value is None else value

    return [kind.map(valid) for kind in kinds]


def relabel(kinds: Kinds, verdicts: dict[str, str]) -> Kinds:
    """The kinds with the verdict of each label in ``verdicts`` replaced ("either" keeps no
    reference; a value the function treats otherwise than the generic rule says)."""

    def changed(value: Value) -> Value:
        verdict = verdicts.get(value.label)
        if verdict is None or verdict == value.verdict:
            return value
        reference = value.reference if verdict == "same" else NOTHING if verdict == "either" else value.reference
        return dataclasses.replace(value, verdict=verdict, reference=reference, batch_others=False)

    return [kind.map(changed) for kind in kinds]


def choice_values(
    valid: Sequence[object], bad: Sequence[object], either: Sequence[object] = (), junk: str = "bad"
) -> Kinds:
    """Values for an argument taking one of a few names or flags; ``junk``: what junk objects
    are ("either" for a free label such as a name)."""
    items = [Value(f"valid {v!r}", v, "same", v) for v in valid]
    items += [Value(f"{v!r}"[:40], v, "bad") for v in bad]
    items += [Value(f"{v!r}"[:40], v, "either") for v in either]
    items += [Value(f"junk: {label}", value, junk) for label, value in junk_values() if label not in ("str", "None")]
    return items_values(items)


# ----- the rule -------------------------------------------------------------------------------


@dataclass
class Arg:
    """One parameter of a target: a valid default for an arm, and the values to try."""

    default: Callable[[object], object]
    values: Callable[[object], Kinds] | None  # the kinds of values to try (None: never corrupted)
    names: tuple[str, ...] = ()  # words besides the parameter's own name that name it in a message
    state: bool = False  # a state argument (made a batch of 2 for a mismatched batch elsewhere)
    alone: bool = False  # corrupted only on its own (out=: its valid shape depends on the others)
    sample: int | None = None  # sweep only this many of its kinds, drawn by hypothesis (for slow targets)


@dataclass
class Target:
    """A callable of the public surface: ``call(arm, **kwargs)``, its parameters, the arms to try."""

    name: str
    call: Callable[..., object]
    args: dict[str, Arg]
    arms: Sequence[tuple[str, object]] = (("-", None),)
    view: Callable[[object], object] | None = None  # what of a result is compared (default: all its numbers)
    sweeps: int = 1  # hypothesis examples, each a sweep over every parameter and kind of value
    corrupt_two: bool = True
    combos: int = 25  # cases per example with two parameters corrupted at once


def _short(value: object, limit: int = 110) -> str:
    if isinstance(value, np.ndarray):
        text = np.array2string(value, threshold=8, precision=4, separator=", ")
        flags = [] if value.flags.writeable else ["read-only"]
        if value.ndim and not value.flags.c_contiguous:
            flags.append("not C-contiguous")
        text = f"np.array({text}, dtype={value.dtype}{''.join(', ' + f for f in flags)})"
    else:
        text = repr(value)
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def names_argument(message: str, names: Sequence[str]) -> bool:
    """Whether ``message`` names one of ``names``: a short name (q, a, G) must stand as a name
    (followed by must/holds/has/is/of/=/(/:/, or quoted), a longer one as a whole word."""
    for name in names:
        if not name:
            continue
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
            if name.lower() in message.lower():
                return True
            continue
        if len(name) <= 2:
            quoted = re.search(rf"['\"`]{re.escape(name)}['\"`]", message)
            standing = re.search(
                rf"(?<![\w.'-]){re.escape(name)}(?=\s+(?:must|holds|has|is|of|does|and)\b|\s*[=:(\[,/])",
                message,
            )
            if quoted or standing:
                return True
        elif re.search(rf"(?<![A-Za-z0-9_]){re.escape(name)}(?![A-Za-z0-9_])", message, re.IGNORECASE):
            return True
    return False


def _numbers(result: object, depth: int = 0) -> list[tuple[str, np.ndarray, bool]]:
    """The numbers in a result, as (where, array, infinity allowed) triples."""
    if depth > 4 or result is None or isinstance(result, (str, bytes, bool)):
        return []
    if isinstance(result, (int, float, complex, np.number)):
        return [("value", np.asarray(result), False)]
    if isinstance(result, np.ndarray):
        if result.dtype.kind in "biufc":
            return [("array", np.asarray(result), False)]
        return [(f"array of dtype {result.dtype} (not numbers)", np.array([np.nan]), False)]
    if isinstance(result, ad.ArmModel):
        if result.is_symbolic:
            return []
        found = [("qlim", np.asarray(result.qlim), True), ("gravity", result.gravity, False)]
        found += [("base", result.base, False), ("tool", result.tool, False)]
        if isinstance(result, ad.Robot):
            z = np.zeros(result.n)
            found += [("packed model", result.packed, False)]
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)
                found += [("its M(0)", result.inertia_matrix(z), False)]
                found += [("its tau(0, 1, 1)", result.inverse_dynamics(z, z + 1, z + 1), False)]
        return found
    if isinstance(result, (tuple, list)):
        return [item for element in result for item in _numbers(element, depth + 1)]
    if isinstance(result, dict):
        return [item for element in result.values() for item in _numbers(element, depth + 1)]
    if dataclasses.is_dataclass(result):
        found = []
        for f in dataclasses.fields(result):
            value = getattr(result, f.name)
            if f.name in ("limits",):
                found.append((f.name, np.asarray(value, dtype=float), True))
            elif f.name not in ("arm", "robot", "name", "info", "model"):
                found += [(f"{f.name}.{w}", a, inf) for w, a, inf in _numbers(value, depth + 1)]
        return found
    if hasattr(result, "t") and hasattr(result, "q") and hasattr(result, "tau"):  # a simulation Result
        return [(k, np.asarray(getattr(result, k)), False) for k in ("t", "q", "qd", "qdd", "tau")]
    return []


def _finite(numbers: list[tuple[str, np.ndarray, bool]]) -> str | None:
    for where, array, infinity in numbers:
        if array.dtype.kind not in "biufc" or not array.size:
            continue
        bad = np.isnan(array) if infinity else ~np.isfinite(array)
        if np.any(bad):
            return where
    return None


def _same(a: list, b: list, real_part: bool) -> str | None:
    if len(a) != len(b):
        return f"{len(a)} numbers where the reference has {len(b)}"
    for (where, x, _), (_, y, _) in zip(a, b, strict=True):
        if x.shape != y.shape:
            return f"{where}: shape {x.shape} where the reference has {y.shape}"
        if real_part:
            x, y = np.real(x), np.real(y)
        if x.size and x.dtype.kind in "biufc" and y.dtype.kind in "biufc":
            scale = 1e-9 * max(1.0, float(np.max(np.abs(np.where(np.isfinite(y), y, 0)), initial=0)))
            if not np.allclose(x, y, rtol=1e-9, atol=scale):
                return f"{where}: {_short(x, 60)} where the reference gives {_short(y, 60)}"
    return None


def _call(target: Target, arm: object, kwargs: dict) -> tuple[str, object]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        try:
            return "ok", target.call(arm, **kwargs)
        except (RuntimeWarning, np.exceptions.ComplexWarning) as warning:
            return "warning", warning
        except (Exception, SystemExit) as error:
            return "raised", error


_DEFAULT_RESULTS: dict[tuple, tuple[str, object]] = {}  # the result of a target's valid defaults, per arm


def _identical(a: object, b: object) -> bool:
    """Whether a reference is the default value itself (then the default's result serves)."""
    if a is b or (type(a) is type(b) and isinstance(a, (str, int, float)) and a == b):
        return True
    if isinstance(a, np.ndarray) and isinstance(b, np.ndarray):
        return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b))
    return False


def _snapshot(kwargs: dict, skip: set[str]) -> dict[str, np.ndarray]:
    return {
        k: np.array(v, copy=True)
        for k, v in kwargs.items()
        if k not in skip and isinstance(v, np.ndarray) and v.dtype.kind in "biufc" and v.size <= 10**6
    }


def evaluate(target: Target, arm_label: str, arm: object, corrupted: dict[str, Value]) -> list[dict]:
    """Run one case and judge it by the rule; the failures found (none when it passes)."""
    COUNT[0] += 1
    labels = ", ".join(f"{k}: {v.label}" for k, v in corrupted.items())
    for hook in BEFORE_CASE:
        if hook(COUNT[0], f"{target.name} [{arm_label}] {labels}") is False:
            return []
    kwargs = {k: a.default(arm) for k, a in target.args.items()}
    others = [k for k, a in target.args.items() if a.state and k not in corrupted]
    for k, v in list(corrupted.items()):
        if v.batch_others and not others:  # no other state to mismatch: a valid batch of 3
            corrupted[k] = dataclasses.replace(v, verdict="same", reference=np.array(v.value), batch_others=False)
    if any(v.batch_others for v in corrupted.values()):
        for k in others:
            kwargs[k] = np.stack([np.asarray(kwargs[k], dtype=float)] * 2)
    reference = dict(kwargs)
    comparable = True
    for k, v in corrupted.items():
        kwargs[k] = v.value
        if v.reference is NOTHING:
            comparable = False
        else:
            reference[k] = v.reference
    verdicts = {v.verdict for v in corrupted.values()}
    verdict = "bad" if "bad" in verdicts else "either" if "either" in verdicts else "same"
    names = [n for k, v in corrupted.items() for n in (k, *target.args[k].names, *v.names)]
    names += [f"'{v.value}'" for v in corrupted.values() if isinstance(v.value, str)]  # the value quoted
    names += [v.value for v in corrupted.values() if isinstance(v.value, str) and len(v.value) >= 3]
    before = _snapshot(kwargs, {k for k, v in corrupted.items() if v.is_out} | {"out"})
    outcome, result = _call(target, arm, kwargs)
    failures = []

    culprits = [f"{k}: {v.label}" for k, v in corrupted.items() if v.verdict != "same"]
    culprit = " + ".join(v.split(": ", 1)[1] for v in culprits) or " + ".join(v.label for v in corrupted.values())

    def fail(kind: str, detail: str) -> None:
        call = ", ".join(f"{k}={_short(v.value)}" for k, v in corrupted.items())
        failures.append(
            {
                "target": target.name,
                "arm": arm_label,
                "args": sorted(corrupted),
                "labels": labels,
                "kind": kind,
                "culprit": culprit,
                "detail": " ".join(detail.split())[:300],
                "repro": f"{target.name} on {arm_label}: {call}",
            }
        )

    independent = any(not _identical(v.value, v.reference) for v in corrupted.values())  # a reference of its own
    expected: tuple[str, object] | None = None
    if comparable and verdict != "bad" and (outcome == "ok" or verdict == "same"):
        defaults = all(_identical(reference[k], target.args[k].default(arm)) for k in corrupted)
        key = (target.name, arm_label, tuple(sorted(kwargs.keys())))
        if defaults and key in _DEFAULT_RESULTS:
            expected = _DEFAULT_RESULTS[key]
        else:
            expected = _call(target, arm, reference)
            if defaults and not any(v.batch_others for v in corrupted.values()):
                _DEFAULT_RESULTS[key] = expected
    if outcome == "warning":
        fail(f"{type(result).__name__} (made an error)", str(result))
    elif outcome == "raised":
        message = str(result)
        if not isinstance(result, (ad.ModelError, ad.SimulationError, TypeError)):
            fail(f"raised {type(result).__name__}", message or repr(result))
        elif verdict == "same" and not (expected is not None and expected[0] == "raised" and independent):
            fail("refused a valid value", f"{type(result).__name__}: {message}")
        elif verdict != "same" and not names_argument(message, names):
            fail(f"{type(result).__name__} does not name the argument", message)
    else:
        try:
            numbers = _numbers(result if target.view is None else target.view(result))
        except Exception as error:  # a returned arm whose own dynamics fail
            numbers = None
            fail("returned something unusable", f"{type(error).__name__}: {error}")
        if numbers is not None:
            where = _finite(numbers)
            if verdict == "bad":
                fail("accepted a bad value", f"returned {_short(result)}")
            elif where is not None:
                fail("non-finite result (NaN or infinity)", f"{where} of {_short(result)}")
            elif expected is not None:
                if expected[0] != "ok":
                    fail("accepted what its float equivalent refuses", f"reference: {expected[1]!r}")
                else:
                    real = any(v.real_part for v in corrupted.values())
                    try:
                        reference_result = expected[1] if target.view is None else target.view(expected[1])
                        difference = _same(numbers, _numbers(reference_result), real)
                    except Exception as error:
                        difference = f"the reference result is unusable: {error!r}"
                    if difference:
                        fail("wrong result", difference)
            for v in corrupted.values():
                if v.is_out and result is not v.value:
                    fail("out= not used", f"returned a new array instead of out ({v.label})")
                problem = v.check(result) if v.check is not None and not failures else None
                if problem:
                    fail("wrong result", problem)
    for k, snapshot in before.items():
        after = kwargs[k]
        changed = isinstance(after, np.ndarray) and after.shape == snapshot.shape
        if changed and not np.array_equal(after, snapshot, equal_nan=True):
            fail("modified its input", f"argument {k} was changed by the call")
    FAILURES.extend(failures)
    return failures


def fuzz(target: Target, sweeps: int | None = None) -> list[dict]:
    """Try ``target`` reproducibly and return every failure.

    Each hypothesis example sweeps every parameter in turn: on an arm hypothesis picks, the
    parameter gets each kind of value its Arg lists (hypothesis drawing the details: which
    entry is NaN, which number, which arm), the others their valid defaults; then
    ``target.combos`` cases corrupt two parameters at once. ``sweeps`` examples are run.
    """
    found: list[dict] = []
    names = [k for k in target.args if target.args[k].values is not None]
    together = [k for k in names if not target.args[k].alone]
    arms = st.sampled_from(list(target.arms))
    cache: dict[tuple[str, int], tuple[Kinds, st.SearchStrategy[Value]]] = {}

    def kinds_of(name: str, arm: object) -> tuple[Kinds, st.SearchStrategy[Value]]:
        """The kinds of value for a parameter on an arm, and any one of them (made once: hypothesis
        validates a strategy when first drawn from)."""
        if (name, id(arm)) not in cache:
            kinds = target.args[name].values(arm)
            cache[name, id(arm)] = kinds, st.one_of(kinds)
        return cache[name, id(arm)]

    @settings(
        max_examples=sweeps or target.sweeps,
        deadline=None,
        derandomize=True,
        database=None,
        phases=[Phase.explicit, Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(data=st.data())
    def run(data: st.DataObject) -> None:
        if not names:
            label, arm = data.draw(arms)
            found.extend(evaluate(target, label, arm, {}))
        for name in names:
            label, arm = data.draw(arms)
            kinds = kinds_of(name, arm)[0]
            size = target.args[name].sample
            if size is not None and size < len(kinds):
                chosen = st.lists(st.integers(0, len(kinds) - 1), min_size=size, max_size=size, unique=True)
                kinds = [kinds[i] for i in sorted(data.draw(chosen))]
            for kind in kinds:
                found.extend(evaluate(target, label, arm, {name: data.draw(kind)}))
        for _ in range(target.combos if target.corrupt_two and len(together) >= 2 else 0):
            label, arm = data.draw(arms)
            keys = data.draw(st.lists(st.sampled_from(together), min_size=2, max_size=2, unique=True))
            found.extend(evaluate(target, label, arm, {k: data.draw(kinds_of(k, arm)[1]) for k in keys}))

    run()
    return found


def grouped(failures: Sequence[dict]) -> str:
    """The failures as classes (kind, value): a count, the targets and one reproduction each."""
    classes: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for failure in failures:
        classes[(failure["kind"], failure.get("culprit", failure["labels"]))].append(failure)
    lines = []
    for (kind, label), items in sorted(classes.items()):
        items.sort(key=lambda f: (len(f["args"]), len(f["repro"])))  # the simplest reproduction first
        targets = sorted({f["target"] for f in items})
        lines.append(f"- {kind} [{label}] x{len(items)} in {', '.join(targets)[:200]}")
        lines.append(f"    e.g. {items[0]['repro']}")
        lines.append(f"    -> {items[0]['detail']}")
    return "\n".join(lines)


# ----- the isolated runner: risky cases in a child interpreter ---------------------------------


def child_main(group: str, skip: int) -> None:
    """Run the risky targets of ``group`` (tests.test_fuzz.RISKY), skipping the first ``skip``
    cases (those before a crash); print each case before it runs, each failure, and a last line."""
    import resource

    from tests import test_fuzz

    limit = test_fuzz.CHILD_MEMORY  # a huge allocation then fails at once instead of exhausting the machine
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    def progress(index: int, label: str) -> bool:
        if index <= skip:
            return False
        print("CASE", index, label, flush=True)
        return True

    BEFORE_CASE.append(progress)
    for target in test_fuzz.RISKY[group]():
        for failure in fuzz(target):
            print("FAIL", json.dumps(failure), flush=True)
    print("DONE", COUNT[0], flush=True)
    sys.stdout.flush()
