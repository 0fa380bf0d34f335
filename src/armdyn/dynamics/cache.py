"""Where Numba caches the compiled kernels: a folder named by a hash of every armdyn source
file that holds compiled code.

Numba's own cache checks only the source file of each function, but the kernels inline
helpers from other files (spatial.py, friction.py, ...): change one of those and the
cached kernels would go on running the old machine code. Here every compiled function of
armdyn is cached in ``kernels-<hash>``, the hash taken over all those files together, so
a change to any of them starts a fresh cache (and the stale folders beside it are removed).

The folder is ``__pycache__`` inside the installed package when writable, else the
user's cache folder (``$XDG_CACHE_HOME/armdyn`` or ``~/.cache/armdyn``); with Numba's
NUMBA_CACHE_DIR set, that folder.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path
from types import FunctionType

from numba.core import config

from armdyn.dynamics.numba_compat import CacheImpl, CacheLocator

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


def cache_folder(stamp: str, package: Path = PACKAGE) -> Path:
    """The folder for kernels compiled from sources with this hash."""
    cache_dir = config.CACHE_DIR  # type: ignore[attr-defined]  # Numba sets its config from the environment at run time
    if cache_dir:
        return Path(cache_dir) / "armdyn" / f"{PREFIX}{stamp}"
    in_tree = package / "__pycache__"
    if os.access(package, os.W_OK) and (not in_tree.exists() or os.access(in_tree, os.W_OK)):
        return in_tree / f"{PREFIX}{stamp}"
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "armdyn" / f"{PREFIX}{stamp}"


def remove_stale(folder: Path) -> None:
    """Remove the cache folders of earlier sources beside ``folder``."""
    for sibling in folder.parent.glob(f"{PREFIX}*"):
        if sibling != folder and sibling.is_dir():
            shutil.rmtree(sibling, ignore_errors=True)


STAMP = sources_hash()
FOLDER = cache_folder(STAMP)


class KernelCacheLocator(CacheLocator):
    """Numba cache locator for armdyn's own compiled functions (see the module docstring)."""

    def __init__(self, py_func: FunctionType, py_file: str) -> None:
        self._lineno = py_func.__code__.co_firstlineno
        self._path = str(FOLDER / Path(py_file).resolve().relative_to(PACKAGE).parent)

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
        try:
            locator.ensure_cache_path()
        except OSError:
            return None
        return locator


def install() -> None:
    """Put the locator first in Numba's list (once), and clear out stale kernel folders."""
    if KernelCacheLocator not in CacheImpl._locator_classes:
        CacheImpl._locator_classes.insert(0, KernelCacheLocator)
        if FOLDER.parent.is_dir():
            remove_stale(FOLDER)
