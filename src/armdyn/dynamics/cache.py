"""Where Numba caches the compiled kernels: a folder named by a hash of every armdyn source
file that holds compiled code.

Numba's own cache checks only the source file of each function, but the kernels inline
helpers from other files (spatial.py, friction.py, ...): change one of those and the
cached kernels would go on running the old machine code. Here every compiled function of
armdyn is cached in ``kernels-<hash>``, the hash taken over all those files together, so
a change to any of them starts a fresh cache (and the stale folders beside it are removed).

The folder is ``__pycache__`` inside the installed package when it can be written, else the
user's cache folder (``$XDG_CACHE_HOME/armdyn`` or ``~/.cache/armdyn``); with Numba's
NUMBA_CACHE_DIR set, that folder. When none can be written (a read-only install and a
read-only home), the kernels are compiled in memory, for this process only, with one
RuntimeWarning; a damaged cache file is removed and its kernel compiled again, with a
RuntimeWarning (numba_compat.GuardedCache). ``compiles()`` names the functions Numba compiles (rather
than loads from the cache) while a block of code runs: how a Dask worker shows it found its kernels cached.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FunctionType

from numba.core import config, event

from armdyn.dynamics.numba_compat import GuardedLocator, install_locator

PACKAGE = Path(__file__).resolve().parent.parent
PREFIX = "kernels-"


def sources_hash(package: Path = PACKAGE) -> str:
    """A hash of the package's Python files that hold compiled code (path and content)."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        text = path.read_bytes()
        if b"njit" in text:
            digest.update(path.relative_to(package).as_posix().encode() + b"\0" + text + b"\0")
    return digest.hexdigest()[:16]


def candidates(stamp: str, package: Path = PACKAGE) -> list[Path]:
    """The folders for kernels compiled from sources with this hash, in the order they are tried."""
    cache_dir = config.CACHE_DIR  # type: ignore[attr-defined]  # Numba sets its config from the environment at run time
    if cache_dir:
        return [Path(cache_dir) / "armdyn" / f"{PREFIX}{stamp}"]
    folders = [package / "__pycache__" / f"{PREFIX}{stamp}"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    if os.path.isabs(base):  # no home folder: no user cache
        folders.append(Path(base) / "armdyn" / f"{PREFIX}{stamp}")
    return folders


def writable(folder: Path) -> bool:
    """True when ``folder`` exists or can be made, and a file can be written in it (tried, as Numba
    does: a permission bit says nothing to root, nor on a read-only file system)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def cache_folder(stamp: str, package: Path = PACKAGE) -> Path | None:
    """The folder for kernels compiled from sources with this hash: the first of ``candidates``
    that can be written, or None when none can (the kernels are then compiled in memory)."""
    return next((folder for folder in candidates(stamp, package) if writable(folder)), None)


def remove_stale(folder: Path) -> None:
    """Remove the cache folders of earlier sources beside ``folder``."""
    for sibling in folder.parent.glob(f"{PREFIX}*"):
        if sibling != folder and sibling.is_dir():
            shutil.rmtree(sibling, ignore_errors=True)


STAMP = sources_hash()
FOLDER = cache_folder(STAMP)
_warned = False


def warn_in_memory(reason: str) -> None:
    """The one warning (per process) that armdyn's kernels are compiled in memory, not cached."""
    global _warned
    if not _warned:
        _warned = True
        warnings.warn(
            f"armdyn's compiled-code cache: {reason}; the kernels are compiled in memory, for this process "
            "only (set NUMBA_CACHE_DIR to a writable folder to keep them)",
            RuntimeWarning,
            stacklevel=3,
        )


class KernelCacheLocator(GuardedLocator):
    """Numba cache locator for armdyn's own compiled functions (see the module docstring)."""

    def __init__(self, py_func: FunctionType, py_file: str) -> None:
        self._lineno = py_func.__code__.co_firstlineno
        self.in_memory = FOLDER is None
        where = FOLDER or candidates(STAMP)[0]  # the path is never used in memory
        self._path = str(where / Path(py_file).resolve().relative_to(PACKAGE).parent)

    def get_cache_path(self) -> str:
        return self._path

    def get_source_stamp(self) -> str:
        return STAMP

    def get_disambiguator(self) -> str:
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func: FunctionType, py_file: str) -> KernelCacheLocator | None:
        if not Path(py_file).resolve().is_relative_to(PACKAGE):
            return None  # not armdyn's: Numba's own locators decide
        locator = cls(py_func, py_file)
        if not locator.in_memory:
            try:
                locator.ensure_cache_path()
            except OSError as error:
                locator.in_memory = True
                warn_in_memory(f"{locator.get_cache_path()} cannot be written ({error})")
        return locator


class _CompileListener(event.Listener):
    """Numba's "numba:compile" events, which a dispatcher sends only when it compiles (a signature it
    loads from the cache sends none): the compiled functions' qualified names."""

    def __init__(self) -> None:
        self.names: list[str] = []

    def on_start(self, event: event.Event) -> None:
        function = getattr(event.data.get("dispatcher"), "py_func", None)
        self.names.append(f"{getattr(function, '__module__', '?')}.{getattr(function, '__qualname__', '?')}")

    def on_end(self, event: event.Event) -> None:
        pass


@contextmanager
def compiles() -> Iterator[list[str]]:
    """The functions Numba compiles (not loads from its cache) in this process while the block runs: a list,
    filled as they compile, of their qualified names (armdyn's kernels, and Numba's own helpers they need).
    Empty when every kernel called was loaded from the cache (or already in memory)."""
    listener = _CompileListener()
    with event.install_listener("numba:compile", listener):
        yield listener.names


def install() -> None:
    """Put the locator first in Numba's list (once), clear out stale kernel folders, and warn (once)
    when no folder can be written."""
    install_locator(KernelCacheLocator)
    if FOLDER is None:
        warn_in_memory("none of " + ", ".join(map(str, candidates(STAMP))) + " can be written")
    elif FOLDER.parent.is_dir():
        remove_stale(FOLDER)
