"""Every use of Numba's private internals in armdyn, in one place, checked against the Numba
versions they were written for.

armdyn relies on two private parts of Numba:

- the dispatcher's ``_compile_for_args``, ``_search_new_conversions``, ``_explain_matching_error``
  and ``_can_compile``, which ``one_state_dispatcher`` overrides so that a one-state kernel
  compiles its one signature at its first call and refuses any other argument types at once;
- the cache's locator classes (``caching._CacheLocator`` and the list of locators of
  ``CacheImpl``, ``_CacheImpl`` before Numba 0.62), which cache.py extends, and the cache
  class the dispatchers build (``dispatcher.FunctionCache``), which GuardedCache replaces so
  that the cache of armdyn's kernels can never stop a compile.

Neither is a public interface, so each Numba release may change them. Importing this module
checks the installed Numba against SUPPORTED (the range the test suite has run on, and the
range pyproject.toml pins): outside it, a RuntimeWarning says which version is installed and
which are supported; a missing internal raises ImportError naming it.
"""

from __future__ import annotations

import glob
import sys
import threading
import warnings
from pathlib import Path
from types import FunctionType, MethodType
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
_DISPATCHER_MODULE = sys.modules[Dispatcher.__module__]
_require(_DISPATCHER_MODULE, "FunctionCache")  # the cache class Dispatcher.enable_caching builds
for _name in ("load_overload", "save_overload", "disable"):
    _require(caching.FunctionCache, _name)


class GuardedLocator(caching._CacheLocator):  # checked above, as CacheLocator
    """A cache locator whose functions are cached by GuardedCache; ``in_memory`` when its folder
    cannot be written (the functions are then compiled in memory, for this process only)."""

    in_memory = False


class GuardedCache(caching.FunctionCache):
    """Numba's function cache, made unable to stop a compile for the functions of a GuardedLocator:

    - with the locator ``in_memory``, the cache is disabled: nothing is read or written;
    - a cache entry that cannot be read (a truncated or damaged index or data file: an
      UnpicklingError, EOFError, ...) is removed (the function's index and data files) with a
      RuntimeWarning, and the function compiles again (and is saved afresh);
    - an entry that cannot be written (a full disk, a folder made read-only) disables the cache
      for the function, with a RuntimeWarning (once per process).

    Other functions' caches behave as Numba's own.
    """

    _save_warned = False

    def __init__(self, py_func: FunctionType) -> None:
        super().__init__(py_func)
        locator = self._impl.locator
        self._guarded = isinstance(locator, GuardedLocator)
        if self._guarded and locator.in_memory:
            self.disable()

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        if not self._guarded:
            return super().load_overload(sig, target_context)
        try:
            return super().load_overload(sig, target_context)
        except Exception as error:  # any damage: pickle raises many kinds
            removed = self._remove_entry()
            warnings.warn(
                f"armdyn's compiled-code cache: the cached {self._py_func.__qualname__} could not be read "
                f"({type(error).__name__}: {error}); removed {', '.join(removed) or 'nothing'} in "
                f"{self._cache_path}, compiling it again",
                RuntimeWarning,
                stacklevel=2,
            )
            return None

    def save_overload(self, sig: Any, data: Any) -> None:
        if not self._guarded:
            return super().save_overload(sig, data)
        try:
            super().save_overload(sig, data)
        except Exception as error:  # an unwritable or full folder, or a damaged index that could not be removed
            self.disable()
            if not GuardedCache._save_warned:
                GuardedCache._save_warned = True
                warnings.warn(
                    f"armdyn's compiled-code cache: could not write to {self._cache_path} "
                    f"({type(error).__name__}: {error}); the kernels that cannot be saved are compiled in "
                    "memory, for this process only",
                    RuntimeWarning,
                    stacklevel=2,
                )
        return None

    def _remove_entry(self) -> list[str]:
        """Remove the function's index and data files (every signature's); the names removed."""
        removed = []
        for path in sorted(Path(self._cache_path).glob(glob.escape(self._impl.filename_base) + ".*")):
            if path.suffix in (".nbi", ".nbc"):
                try:
                    path.unlink()
                except OSError:
                    continue
                removed.append(path.name)
        return removed


def install_locator(locator: type[GuardedLocator]) -> None:
    """Put ``locator`` first in Numba's list of cache locators, and make the dispatchers build their
    caches as GuardedCache (once: again does nothing)."""
    if locator not in CacheImpl._locator_classes:
        CacheImpl._locator_classes.insert(0, locator)
    setattr(_DISPATCHER_MODULE, "FunctionCache", GuardedCache)  # noqa: B010 - a module attribute mypy does not know


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


__all__ = [
    "SUPPORTED",
    "CacheImpl",
    "CacheLocator",
    "GuardedCache",
    "GuardedLocator",
    "check_version",
    "install_locator",
    "numba_version",
    "one_state_dispatcher",
]
