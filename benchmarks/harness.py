"""The one timing harness of the benchmark scripts (bench_dynamics.py, bench_simulation.py, bench_symbolic.py).

- Timing: a ``Candidate`` is a zero-argument call timed in loops of ``calls`` calls, ``repeats`` loops, each
  call covering ``states`` states. ``measure`` warms every candidate up with one call, then runs their timed
  loops interleaved (repeat 1 of every candidate, then repeat 2, ...) with the garbage collector off, so that
  machine noise hits all of them alike, and returns each one's median time per state; ``samples`` returns
  every loop's time. ``wall`` times one call; ``Spans`` times named functions of a module while in use.
- Checking: ``check`` refuses to time two computations that disagree (``relative_error`` above a tolerance).
- Reporting: ``Table`` formats as plain text and as Markdown; ``describe`` says which machine, versions and
  armdyn source ran; ``Report`` prints the header lines and tables as they come and writes them as Markdown.
- Workers: ``run_worker`` runs a step-by-step job in a subprocess (the script itself, dispatched by ``parse``),
  each step with a time limit; the worker reports its steps with ``emit`` and ``timed_step``. ``fresh_python``
  runs a short script in a fresh interpreter (its own environment, nothing imported first) and returns its
  wall time and what it reported on an ``EVENT`` line.

The scripts import this file by name (``from harness import ...``): Python puts the script's folder first
on sys.path.
"""

from __future__ import annotations

import argparse
import datetime
import gc
import hashlib
import importlib.metadata
import json
import os
import platform
import queue
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from types import ModuleType

import numba
import numpy as np

import armdyn as ad

SECOND, MILLISECOND, MICROSECOND = 1.0, 1e-3, 1e-6  # units of measure()'s results


# ----- timing -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Candidate:
    """A zero-argument call to time: ``calls`` calls per timed loop, ``repeats`` loops, ``states`` per call."""

    fn: Callable[[], object]
    calls: int = 1
    repeats: int = 1
    states: int = 1


def _loop_ns(fn: Callable[[], object], calls: int) -> int:
    start = time.perf_counter_ns()
    for _ in range(calls):
        fn()
    return time.perf_counter_ns() - start


def samples(*candidates: Candidate) -> list[list[float]]:
    """Seconds per state of every timed loop of each candidate, after one warm-up call each; the candidates'
    loops interleaved, the garbage collector off."""
    for candidate in candidates:
        candidate.fn()  # warm-up: armdyn compiles or loads its machine code on a first call
    loops: list[list[int]] = [[] for _ in candidates]
    collecting = gc.isenabled()
    gc.disable()
    try:
        for repeat in range(max(candidate.repeats for candidate in candidates)):
            for candidate, times in zip(candidates, loops, strict=True):
                if repeat < candidate.repeats:
                    times.append(_loop_ns(candidate.fn, candidate.calls))
    finally:
        if collecting:
            gc.enable()
    return [
        [ns / 1e9 / (candidate.calls * candidate.states) for ns in times]
        for candidate, times in zip(candidates, loops, strict=True)
    ]


def measure(*candidates: Candidate, unit: float = MICROSECOND) -> list[float]:
    """Median time per state of each candidate, in ``unit`` seconds (see samples)."""
    return [statistics.median(times) / unit for times in samples(*candidates)]


def wall(fn: Callable[[], object]) -> tuple[object, float]:
    """(result, seconds) of one call."""
    start = time.perf_counter()
    result = fn()
    return result, time.perf_counter() - start


class Spans:
    """Wraps named functions of a module in timers while in use (a name the module lacks is left out);
    ``spent`` holds the nanoseconds of each since it was last cleared."""

    def __init__(self, module: ModuleType, names: Iterable[str]) -> None:
        self.module, self.spent = module, {}
        self.originals = {name: getattr(module, name) for name in names if callable(getattr(module, name, None))}

    def _timer(self, name: str, original: Callable) -> Callable:
        def timed(*args: object, **kwargs: object) -> object:
            start = time.perf_counter_ns()
            try:
                return original(*args, **kwargs)
            finally:
                self.spent[name] = self.spent.get(name, 0) + time.perf_counter_ns() - start

        return timed

    def __enter__(self) -> Spans:
        for name, original in self.originals.items():
            setattr(self.module, name, self._timer(name, original))
        return self

    def __exit__(self, *exc: object) -> None:
        for name, original in self.originals.items():
            setattr(self.module, name, original)


# ----- checking ---------------------------------------------------------------------------------
def relative_error(ours: object, theirs: object, dims: int | None = None) -> float:
    """Largest difference relative to the largest entry of the reference ``theirs``: over the whole array,
    or with ``dims`` (1 for vectors, 2 for matrices: the trailing dimensions of one state's result) state by
    state, each relative to that state's largest entry."""
    ours, theirs = np.asarray(ours, dtype=float), np.asarray(theirs, dtype=float)
    if ours.shape != theirs.shape:
        raise AssertionError(f"shapes differ: {ours.shape} vs {theirs.shape}")
    states = () if dims is None else theirs.shape[: theirs.ndim - dims]
    error = np.abs(ours - theirs).reshape(*states, -1).max(axis=-1)
    scale = np.maximum(np.abs(theirs).reshape(*states, -1).max(axis=-1), 1e-300)
    return float(np.max(error / scale))


def check(what: str, ours: object, theirs: object, tolerance: float, dims: int | None = None) -> float:
    """Refuse to time two computations that disagree; the relative error (see relative_error) otherwise."""
    try:
        error = relative_error(ours, theirs, dims)
    except AssertionError as problem:
        raise AssertionError(f"{what}: {problem}") from None
    if not error <= tolerance:
        raise AssertionError(f"{what}: the two differ by {error:.2e} (relative), more than {tolerance:g}")
    return error


# ----- number formats and tables ----------------------------------------------------------------
def us(value: float) -> str:
    """Microseconds with about three significant digits."""
    if value >= 100:
        return f"{value:,.0f}"
    return f"{value:.1f}" if value >= 10 else f"{value:.3f}" if value < 1 else f"{value:.2f}"


def ms(value: float) -> str:
    """Seconds shown as milliseconds, about three significant digits."""
    return us(value * 1e3)


def seconds(value: float) -> str:
    return f"{value:.3f}" if value < 1 else f"{value:.2f}" if value < 100 else f"{value:,.0f}"


def ratio(value: float) -> str:
    """A ratio with two decimals, or two significant digits when small."""
    if value >= 100:
        return f"{value:,.0f}"
    return f"{value:.2f}" if value >= 0.1 else f"{value:.2g}"


def sci(value: float) -> str:
    return f"{value:.1e}"


@dataclass
class Table:
    title: str
    headers: Sequence[str]
    rows: list[list[str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    left: int = 1  # columns aligned left in Markdown; the others are numbers

    def text(self) -> str:
        widths = [max(len(row[i]) for row in [self.headers, *self.rows]) for i in range(len(self.headers))]

        def line(cells: Sequence[str]) -> str:
            return "  ".join(cell.ljust(width) for cell, width in zip(cells, widths, strict=True)).rstrip()

        rule = "  ".join("-" * width for width in widths)
        body = [self.title, "=" * len(self.title), line(self.headers), rule, *map(line, self.rows)]
        return "\n".join(body + [f"  * {note}" for note in self.notes]) + "\n"

    def markdown(self) -> str:
        body = [f"## {self.title}", "", "| " + " | ".join(self.headers) + " |"]
        body.append("|" + "|".join("---" if i < self.left else "---:" for i in range(len(self.headers))) + "|")
        body += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in self.rows]
        if self.notes:
            body += ["", *(f"- {note}" for note in self.notes)]
        return "\n".join(body) + "\n"


# ----- the machine and the source ---------------------------------------------------------------
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


def describe(source: tuple[str, str], versions: dict[str, str], threads: str = "") -> list[str]:
    """The header lines every script starts with: date, machine, versions (armdyn's first, Python's last),
    armdyn's source; ``threads`` is added to the line of the machine."""
    listed = ", ".join(f"{name} {value}" for name, value in {"armdyn": ad.__version__, **versions}.items())
    return [
        f"Date: {datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}",
        f"CPU: {cpu_model()}, {os.cpu_count()} logical cores; Numba threads {numba.get_num_threads()}{threads}",
        f"Versions: {listed}, Python {platform.python_version()}",
        f"armdyn source: {source[1]}, source hash {source[0]}",
        "The machine is shared and noisy: absolute times move from run to run; the ratios are what matter.",
    ]


def arguments(doc: str, skip_toolbox: str = "") -> argparse.ArgumentParser:
    """A command line with the --quick flag every script takes; with ``skip_toolbox`` (its help) also
    --skip-toolbox, and the hidden --state that a script's own Toolbox worker is given."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="a smoke run: few repeats, small batches, short time limits; results file not written",
    )
    if skip_toolbox:
        parser.add_argument("--skip-toolbox", action="store_true", help=skip_toolbox)
        parser.add_argument("--state", help=argparse.SUPPRESS)
    return parser


def parse(
    parser: argparse.ArgumentParser, worker_flag: str, worker: Callable[[argparse.Namespace], object]
) -> argparse.Namespace:
    """The command line's options; when the option ``worker_flag`` is set, the script was started as its own
    worker (see run_worker): then it runs ``worker`` and exits."""
    args = parser.parse_args()
    if getattr(args, worker_flag):
        worker(args)
        raise SystemExit(0)
    return args


class Report:
    """The run's header lines and tables, printed as they come; ``finish`` writes them as Markdown to
    ``path`` (None: a --quick run, nothing written)."""

    def __init__(self, title: str, path: Path | None) -> None:
        self.title, self.path = title, path
        self.started = time.perf_counter()
        self.source = source_state()
        self.lines: list[str] = []
        self.tables: list[Table] = []

    @classmethod
    def begin(
        cls,
        args: argparse.Namespace,
        title: str,
        path: Path,
        settings: dict[str, object],
        quick: dict[str, object],
        limits: dict[str, float] | None = None,
    ) -> Report:
        """The run's report. With --quick, first the script's ``quick`` values replace its ``settings`` (its
        module's globals()) and its time-limit options in ``args`` are capped at ``limits``."""
        if args.quick:
            settings.update(quick)
            for name, limit in (limits or {}).items():
                setattr(args, name, min(getattr(args, name), limit))
        return cls(title, None if args.quick else path)

    def note(self, *lines: str, end: str = "\n") -> None:
        self.lines += lines
        print("\n".join(lines), end=end, flush=True)

    def show(self, table: Table) -> None:
        self.tables.append(table)
        print(table.text(), flush=True)

    def finish(self, if_changed: str) -> str:
        """Warns (``if_changed`` says what it means) when armdyn's source changed during the run; returns
        the Markdown, written to ``path`` unless it is None."""
        elapsed = time.perf_counter() - self.started
        now = source_state()[0]
        if now != self.source[0]:
            self.note(
                f"WARNING: armdyn's source changed during the run (hash {self.source[0]} at the start, {now} at "
                f"the end): {if_changed}"
            )
        head = [f"# {self.title}", "", *(f"- {line}" for line in self.lines), f"- Run time {elapsed:.0f} s.", ""]
        markdown = "\n".join(head + [table.markdown() for table in self.tables])
        if self.path is None:
            print(f"Total run time {elapsed:.0f} s; --quick: nothing written")
        else:
            print(f"Total run time {elapsed:.0f} s; written to {self.path}")
            self.path.write_text(markdown)
        return markdown


# ----- workers in subprocesses ------------------------------------------------------------------
EVENT = "@@event "  # prefix of a worker's result lines on its stdout


def emit(step: str, **values: object) -> None:
    """In a worker: report a finished step (read by run_worker)."""
    print(EVENT + json.dumps({"step": step, **values}), flush=True)


def timed_step(step: str, fn: Callable[[], object]) -> tuple[object, float]:
    """In a worker: (result, seconds) of one call; if it raises, whatever it raises (MemoryError too), the
    error is reported as the step's event and the worker exits."""
    start = time.perf_counter()
    try:
        result = fn()
    except BaseException as error:
        emit(step, error=f"{type(error).__name__}: {error}"[:300], seconds=time.perf_counter() - start)
        raise SystemExit(1) from None
    return result, time.perf_counter() - start


def run_worker(command: Sequence[str], phases: Sequence[tuple[str, float]]) -> dict[str, dict]:
    """Start a worker; wait for each phase in turn at most its limit, and stop the worker when one overruns.

    Result per phase: the worker's event, {"timeout": limit}, {"error": ...} or {"skipped": ...}."""
    results: dict[str, dict] = {}
    with tempfile.TemporaryFile(mode="w+") as stderr:
        process = subprocess.Popen(list(command), stdout=subprocess.PIPE, stderr=stderr, text=True)
        lines: queue.Queue[str | None] = queue.Queue()

        def read() -> None:
            for line in process.stdout:
                if line.startswith(EVENT):
                    lines.put(line[len(EVENT) :])
            lines.put(None)

        threading.Thread(target=read, daemon=True).start()
        stopped = ""
        try:
            for phase, limit in phases:
                if stopped:
                    results[phase] = {"skipped": stopped}
                    continue
                deadline = time.monotonic() + limit
                while phase not in results:
                    try:
                        line = lines.get(timeout=max(deadline - time.monotonic(), 0.0))
                    except queue.Empty:
                        results[phase] = {"timeout": limit}
                        stopped = f"the worker was stopped after {phase}"
                        break
                    if line is None:
                        process.wait()
                        stderr.seek(0)
                        tail = " ".join(stderr.read().strip().splitlines()[-3:])[-300:]
                        results[phase] = {"error": f"worker exited with code {process.returncode}: {tail}"}
                        stopped = f"the worker failed in {phase}"
                        break
                    event = json.loads(line)
                    results[event["step"]] = event
                if "error" in results[phase]:
                    stopped = stopped or f"the worker failed in {phase}"
        finally:
            if process.poll() is None:
                process.kill()
            process.wait()
    return results


def fresh_python(code: str, env: Mapping[str, str] | None = None, timeout: float | None = None) -> tuple[float, dict]:
    """Run ``python -c code`` in a fresh interpreter (this one's executable) with the environment ``env``
    (None: this process's). Returns its wall seconds, from start to exit, and the JSON object of the last line
    it printed that starts with EVENT ({} if none).

    Raises RuntimeError, with the end of its stderr, when it exits with an error, and
    subprocess.TimeoutExpired (after stopping it) when it runs past ``timeout`` seconds."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", code],
        env=None if env is None else dict(env),
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    elapsed = time.perf_counter() - start
    if done.returncode:
        tail = " ".join(done.stderr.strip().splitlines()[-3:])[-300:]
        raise RuntimeError(f"exited with code {done.returncode}: {tail}")
    events = [line[len(EVENT) :] for line in done.stdout.splitlines() if line.startswith(EVENT)]
    return elapsed, json.loads(events[-1]) if events else {}
