"""Output files written whole or not at all.

A file is written to a temporary file beside it (same folder, so same file system), flushed to
the disk, then renamed onto its name (``os.replace``, atomic): a full disk, a kill or an error
half-way leaves the earlier file (or none), never a truncated or empty one. On a failure the
temporary file is removed and the OS error becomes a ModelError naming the file.
"""

from __future__ import annotations

import contextlib
import errno
import os
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from armdyn.errors import ModelError

__all__ = ["atomic_path", "atomic_write", "output_path", "write_text"]


def output_path(path: str | Path) -> Path:
    """``path`` as an output file, checked before any work: its folder exists and is a folder, and
    ``path`` is not a folder; else a ModelError naming it."""
    target = Path(path)
    folder = target.parent
    if not folder.exists():
        raise ModelError(f"{path}: the folder {folder} does not exist")
    if not folder.is_dir():
        raise ModelError(f"{path}: {folder} is not a folder")
    if target.is_dir():
        raise ModelError(f"{path} is a folder; give a file name")
    return target


def _reason(error: OSError) -> str:
    name = errno.errorcode.get(error.errno or 0)
    return f"{error.strerror} ({name})" if error.strerror and name else str(error)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary file beside ``path`` (ending in the same suffix, so that a writer that goes by
    the suffix writes the same format) to write in the block; when the block ends it is flushed
    to the disk and renamed onto ``path``, when the block fails it is removed.

    Raises
    ------
    ModelError
        When the folder of ``path`` does not exist, or the file cannot be written (a read-only
        folder, a full disk: the OS error is named).
    """
    target = output_path(path)
    temporary = target.with_name(f".{target.name}.{uuid.uuid4().hex[:12]}.tmp{target.suffix}")
    try:
        yield temporary
        with open(temporary, "rb") as written:
            os.fsync(written.fileno())
        os.replace(temporary, target)
    except BaseException as error:
        with contextlib.suppress(OSError):
            temporary.unlink()
        if isinstance(error, OSError):
            raise ModelError(f"could not write {path}: {_reason(error)}") from error
        raise


@contextlib.contextmanager
def atomic_write(path: str | Path, mode: str = "w", **options: Any) -> Iterator[IO[Any]]:
    """``open(path, mode, **options)`` written whole or not at all (see ``atomic_path``)."""
    with atomic_path(path) as temporary, open(temporary, mode, **options) as handle:
        yield handle


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path``, whole or not at all (see ``atomic_path``)."""
    with atomic_write(path, encoding="utf-8") as handle:
        handle.write(text)
