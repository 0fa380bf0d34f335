"""This source tree against another checkout of armdyn, in one process with the calls interleaved.

    .venv/bin/python benchmarks/bench_checkouts.py OTHER_CHECKOUT [--repeats 15] [--quick]

OTHER_CHECKOUT is a folder holding src/armdyn (a git worktree of an earlier commit, say:
``git worktree add /tmp/before HEAD~5``). Its package is copied to a temporary folder as ``armdyn_other``
(every ``armdyn.`` import renamed) so that both versions live in this process; each scenario runs in both
first and must give the same numbers (bit for bit, or to 1e-14 relative), then the two are timed with their
loops interleaved (harness.samples) and the 10th percentiles compared. Scenarios: one 10 s run of the PUMA 560
under computed torque at 1 kHz; 1,000 closed-loop runs of the UR5 (1 s each); the PUMA 560 with its DC drives
under drive PID (1 s); one-state inverse dynamics, mass matrix and forward dynamics of the PUMA 560 and the
UR5. A ratio above 1 means this tree is slower.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import shutil
import sys
import sysconfig
import tempfile
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
from harness import Candidate, Table, samples

import armdyn as ad


def _renamed_copy(checkout: Path) -> ModuleType:
    """The other checkout's armdyn imported as armdyn_other."""
    source = checkout / "src" / "armdyn"
    if not (source / "__init__.py").exists():
        raise SystemExit(f"{checkout} holds no src/armdyn")
    folder = Path(tempfile.mkdtemp(prefix="armdyn-other-"))
    target = folder / "armdyn_other"
    shutil.copytree(source, target, ignore=shutil.ignore_patterns("__pycache__"))
    pattern = re.compile(r"\b(from|import) armdyn\b|\barmdyn\.")
    for path in target.rglob("*.py"):
        text = path.read_text()
        path.write_text(pattern.sub(lambda m: m.group(0).replace("armdyn", "armdyn_other"), text))
    sys.path.insert(0, str(folder))
    return importlib.import_module("armdyn_other")


def _first(package: ModuleType, *dotted: str) -> object:
    """The first of the dotted names that the package has (names moved between versions)."""
    for name in dotted:
        module_name, _, attribute = name.rpartition(".")
        try:
            module = importlib.import_module(f"{package.__name__}.{module_name}" if module_name else package.__name__)
        except ImportError:
            continue
        if hasattr(module, attribute):
            return getattr(module, attribute)
    raise AttributeError(f"{package.__name__} has none of {dotted}")


def _ur5(package: ModuleType) -> object:
    robots = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
    return package.load_urdf(robots / "ur_description" / "urdf" / "ur5_robot.urdf")


def scenarios(package: ModuleType, quick: bool) -> dict[str, tuple[Callable[[], object], int]]:
    """name -> (call, calls per timed loop) for one version of armdyn."""
    computed_torque = _first(package, "control.ComputedTorque")
    sinusoid = _first(package, "trajectories.Sinusoid")
    drive_pid = _first(package, "control.DrivePID", "actuators.DrivePID")
    puma, ur5 = package.models.puma560(), _ur5(package)
    driven = _first(package, "actuators.puma560_with_drives", "actuators.puma560")()
    runs = 100 if quick else 1000
    rng = np.random.default_rng(7)
    starts = rng.uniform(-0.2, 0.2, (runs, ur5.n))
    q, qd, qdd = rng.uniform(-1, 1, (3, puma.n))
    qu, qdu, qddu = rng.uniform(-1, 1, (3, ur5.n))
    many = getattr(package, "simulate_many", None)

    def ur5_runs() -> object:
        law, path = computed_torque(100.0, 20.0), sinusoid(0.1, 0.5)
        if many is not None:  # versions before simulate(..., runs=)
            return many(ur5, law, path, t_final=1.0, q0=starts, keep="summary").summaries
        return package.simulate(ur5, law, path, t_final=1.0, q0=starts, runs=runs).summaries

    def puma_run() -> object:
        return package.simulate(
            puma, computed_torque(100.0, 20.0), sinusoid(0.2, 0.5), t_final=2.0 if quick else 10.0
        ).q

    def drives_run() -> object:
        return package.simulate(driven, drive_pid(40.0, 1.0), sinusoid(0.1, 0.5), t_final=1.0).q

    return {
        "PUMA 560 computed torque, one run": (puma_run, 1),
        f"UR5, {runs} runs": (ur5_runs, 1),
        "PUMA 560 with DC drives, one run": (drives_run, 1),
        "PUMA 560 inverse dynamics, one state": (lambda: puma.inverse_dynamics(q, qd, qdd), 2000),
        "PUMA 560 mass matrix, one state": (lambda: puma.inertia_matrix(q), 2000),
        "PUMA 560 forward dynamics, one state": (lambda: puma.forward_dynamics(q, qd, qdd), 2000),
        "UR5 inverse dynamics, one state": (lambda: ur5.inverse_dynamics(qu, qdu, qddu), 2000),
        "UR5 mass matrix, one state": (lambda: ur5.inertia_matrix(qu), 2000),
        "UR5 forward dynamics, one state": (lambda: ur5.forward_dynamics(qu, qdu, qddu), 2000),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkout", type=Path, help="a folder holding the other version's src/armdyn")
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--quick", action="store_true", help="shorter runs, 3 repeats")
    options = parser.parse_args()
    other = _renamed_copy(options.checkout.resolve())
    repeats = 3 if options.quick else options.repeats
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    ours, theirs = scenarios(ad, options.quick), scenarios(other, options.quick)
    table = Table("This tree against the other checkout", ["scenario", "this tree", "other", "this / other", "equal"])
    for name, (call, calls) in ours.items():
        other_call = theirs[name][0]
        mine, previous = np.asarray(call()), np.asarray(other_call())
        scale = max(float(np.max(np.abs(previous))), 1e-300)
        equal = "bit for bit" if np.array_equal(mine, previous) else f"{np.max(np.abs(mine - previous)) / scale:.1e}"
        times = samples(Candidate(call, calls, repeats), Candidate(other_call, calls, repeats))
        p10 = [float(np.percentile(t, 10)) for t in times]
        unit, scale_to = ("us", 1e6) if calls > 1 else ("ms", 1e3)
        table.rows.append([name, f"{p10[0] * scale_to:.3f} {unit}", f"{p10[1] * scale_to:.3f} {unit}",
                           f"{p10[0] / p10[1]:.3f}", equal])  # fmt: skip
        print(table.rows[-1], flush=True)
    print(table.text())
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
