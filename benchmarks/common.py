"""Helpers shared by the benchmark scripts: timing loops, number formats, the machine and the source."""

from __future__ import annotations

import hashlib
import importlib.metadata
import platform
import subprocess
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path

import armdyn as ad


def _loop_ns(fn: Callable[[], object], calls: int) -> int:
    start = time.perf_counter_ns()
    for _ in range(calls):
        fn()
    return time.perf_counter_ns() - start


def us(value: float) -> str:
    """Microseconds with about three significant digits."""
    if value >= 100:
        return f"{value:,.0f}"
    return f"{value:.1f}" if value >= 10 else f"{value:.3f}" if value < 1 else f"{value:.2f}"


def ratio(value: float) -> str:
    """A ratio with two decimals, or two significant digits when small."""
    if value >= 100:
        return f"{value:,.0f}"
    return f"{value:.2f}" if value >= 0.1 else f"{value:.2g}"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def source_state() -> tuple[str, str]:
    """(a hash of armdyn's installed source, its git commit and whether src/ has uncommitted changes)."""
    root = Path(ad.__file__).parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    try:
        git = partial(subprocess.run, capture_output=True, text=True, check=True, cwd=root)
        commit = git(["git", "rev-parse", "--short", "HEAD"]).stdout.strip()
        dirty = git(["git", "status", "--porcelain", "--", "."]).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return digest.hexdigest()[:12], "not a git checkout"
    return digest.hexdigest()[:12], f"git {commit}" + (" plus uncommitted changes" if dirty else "")


def version(distribution: str) -> str:
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"
