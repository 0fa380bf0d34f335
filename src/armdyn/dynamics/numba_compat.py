"""Every use of Numba's private internals in armdyn, in one place, checked against the Numba
versions they were written for.

armdyn relies on two private parts of Numba:

- the dispatcher's ``_compile_for_args``, ``_search_new_conversions``, ``_explain_matching_error``
  and ``_can_compile``, which ``one_state_dispatcher`` overrides so that a one-state kernel
  compiles its one signature at its first call and refuses any other argument types at once;
- the cache's locator classes (``caching._CacheLocator`` and the list of locators of
  ``CacheImpl``, ``_CacheImpl`` before Numba 0.62), which cache.py extends.

Neither is a public interface, so each Numba release may change them. Importing this module
checks the installed Numba against SUPPORTED (the range the test suite has run on, and the
range pyproject.toml pins): outside it, a RuntimeWarning says which version is installed and
which are supported; a missing internal raises ImportError naming it.
"""

from __future__ import annotations

import threading
import warnings
from types import MethodType
from typing import TYPE_CHECKING, Any

import numba
from numba.core import caching
from numba.core.dispatcher import Dispatcher

if TYPE_CHECKING:
    from numba.core.typing.templates import Signature

SUPPORTED = ((0, 60), (0, 69))
"""Numba versions armdyn is tested with: from the first (inclusive) to the second (exclusive)."""

_DISPATCHER_INTERNALS = ("_compile_for_args", "_search_new_conversions", "_explain_matching_error", "_can_compile")


def numba_version(text: str = numba.__version__) -> tuple[int, int]:
    """(major, minor) of a Numba version string such as '0.68.1' or '0.69.0rc1'."""
    major, minor = text.split(".")[:2]
    return int(major), int("".join(ch for ch in minor if ch.isdigit()) or 0)


def check_version(text: str = numba.__version__) -> bool:
    """True when Numba ``text`` is in SUPPORTED; else warn (RuntimeWarning) and return False."""
    low, high = SUPPORTED
    if low <= numba_version(text) < high:
        return True
    warnings.warn(
        f"armdyn is tested with Numba {low[0]}.{low[1]} to {high[0]}.{high[1] - 1}.x, and Numba {text} is "
        "installed: armdyn's one-state kernels and kernel cache use Numba internals that may have changed "
        f"(armdyn.dynamics.numba_compat); install numba>={low[0]}.{low[1]},<{high[0]}.{high[1]}",
        RuntimeWarning,
        stacklevel=2,
    )
    return False


def _require(owner: object, name: str) -> Any:
    if not hasattr(owner, name):
        raise ImportError(
            f"Numba {numba.__version__} has no {getattr(owner, '__name__', owner)}.{name}, which armdyn's compiled "
            f"kernels rely on (armdyn.dynamics.numba_compat); install numba>={SUPPORTED[0][0]}.{SUPPORTED[0][1]},"
            f"<{SUPPORTED[1][0]}.{SUPPORTED[1][1]}"
        )
    return getattr(owner, name)


check_version()
CacheImpl = getattr(caching, "CacheImpl", None) or _require(caching, "_CacheImpl")  # renamed in Numba 0.62
CacheLocator = _require(caching, "_CacheLocator")
_require(CacheImpl, "_locator_classes")
for _name in _DISPATCHER_INTERNALS[:3]:
    _require(Dispatcher, _name)


def one_state_dispatcher(dispatcher: Dispatcher, signature: Signature) -> Dispatcher:
    """``dispatcher`` made to compile (or load from the cache) only ``signature``, at its first call,
    and to refuse any other argument types with a TypeError at once.

    Numba calls ``_compile_for_args`` only when no compiled version matches the arguments;
    here it compiles the one signature and hands the call back to the dispatcher, which then
    runs it or raises TypeError, at once: no conversion of other types is searched, and the
    message does not type every argument (Numba's would cost about 60 us on a batch, which
    every batch call would pay before its general path).
    """
    first_call = threading.Lock()  # two threads' first calls: one compiles, the other waits and runs it
    name = getattr(dispatcher.py_func, "__name__", "kernel")

    def compile_signature(self: Dispatcher, *args: object, **kwargs: object) -> Dispatcher:
        with first_call:
            if self._can_compile:  # type: ignore[attr-defined]  # a Numba internal, not in its stubs
                self.compile(signature)
                self.disable_compile()
        return self

    def no_conversion(self: Dispatcher, *args: object, **kwargs: object) -> bool:
        return False  # the signature's types exactly: Numba would otherwise convert a bool or a float to an int

    message = f"{name} takes only the types of its signature {signature}"

    def refuse(self: Dispatcher, *args: object, **kwargs: object) -> None:
        # Numba's own message types every argument (about 60 us for a batch): the api's general path,
        # which every refused call takes next, names what is wrong
        raise TypeError(message)

    # Numba internals, not in its stubs (see the module docstring)
    dispatcher._compile_for_args = MethodType(compile_signature, dispatcher)  # type: ignore[attr-defined]
    dispatcher._search_new_conversions = MethodType(no_conversion, dispatcher)  # type: ignore[attr-defined]
    dispatcher._explain_matching_error = MethodType(refuse, dispatcher)  # type: ignore[attr-defined]
    return dispatcher


__all__ = ["SUPPORTED", "CacheImpl", "CacheLocator", "check_version", "numba_version", "one_state_dispatcher"]
