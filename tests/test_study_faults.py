"""Faults injected into studies: a study process killed with SIGKILL at random times and resumed, Dask workers
killed (one, then all), a cluster whose workers never come back. The oracle is the uninterrupted run's table."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from armdyn.errors import ModelError
from armdyn.study import Study, Uniform

RUNS, BLOCK, SEED = 600, 4, 11

SCRIPT = f"""
import sys
import armdyn as ad
from armdyn import control, trajectories as tr
from armdyn.study import Study, Uniform

def study():
    return Study(ad.models.two_link_planar(), control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 1.0, 0.0,
                 [0.3, 0.6]), spec="max_error_after < 2e-3", q0=[0.3, 0.6], t_final=0.02, after=0.01,
                 payload=Uniform(0.0, 2.0), mass_error=Uniform(-0.2, 0.2), block={BLOCK})

if __name__ == "__main__":
    result = study().run({RUNS}, seed={SEED}, out=sys.argv[1])
    result.table.to_parquet(sys.argv[2])
"""


def fault_study() -> Study:
    """The script's study, made here: the oracle's table."""
    return Study(ad.models.two_link_planar(), control.ComputedTorque(100.0, 20.0),
                 tr.Sinusoid(0.1, 1.0, 0.0, [0.3, 0.6]), spec="max_error_after < 2e-3", q0=[0.3, 0.6],
                 t_final=0.02, after=0.01, payload=Uniform(0.0, 2.0), mass_error=Uniform(-0.2, 0.2),
                 block=BLOCK)  # fmt: skip


def _partials(folder: Path) -> list[str]:
    """The half-written files in the folder (a write under way, or one a kill interrupted)."""
    try:
        return [entry.name for entry in os.scandir(folder) if entry.name.endswith(".partial")]
    except FileNotFoundError:
        return []


def _kill_when(process: subprocess.Popen, folder: Path, ready: object, delay: float, limit: float = 60.0) -> bool:
    """SIGKILL the process ``delay`` s after ``ready(partials)`` first holds; False when it ended before."""
    start = time.monotonic()
    while process.poll() is None and time.monotonic() - start < limit:
        if ready(_partials(folder)):  # type: ignore[operator]
            time.sleep(delay)
            process.send_signal(signal.SIGKILL)
            process.wait()
            return True
        time.sleep(0.001)
    process.wait(timeout=limit)
    return False


@pytest.mark.slow
def test_a_study_killed_at_random_times_and_resumed_gives_the_uninterrupted_table(tmp_path: Path) -> None:
    """A study of 150 blocks in a subprocess, SIGKILLed at least 20 times (first while study.json is written,
    then while a block's record or its Parquet file is written, or at a random time once blocks are being
    written), resumed each time: it ends with the uninterrupted run's table, bit for bit, no resume ever found
    a damaged block, and each kind of kill left a half-written file behind (so it hit a write)."""
    script, folder, final = tmp_path / "study_script.py", tmp_path / "store", tmp_path / "final.parquet"
    script.write_text(SCRIPT)
    environment = os.environ | {"ARMDYN_STUDY_WRITE_PAUSE": "0.01", "PYTHONPATH": os.pathsep.join(sys.path)}
    rng = random.Random(2026)
    kinds = [lambda names: any(n.startswith(".study.json") for n in names)]
    kinds += [lambda names: any(n.startswith(".block-") and n.endswith(".json.partial") for n in names),
              lambda names: any(n.startswith(".block-") and n.endswith(".parquet.partial") for n in names),
              lambda names: any(n.startswith(".block-") for n in names)] * 10  # fmt: skip
    hit, errors = [], []
    for kill, ready in enumerate(kinds):
        process = subprocess.Popen([sys.executable, str(script), str(folder), str(final)], env=environment,
                                   stderr=subprocess.PIPE, text=True)  # fmt: skip
        delay = rng.uniform(0.0, 0.15) if kill % 3 == 0 and kill else rng.uniform(0.0, 0.005)
        if not _kill_when(process, folder, ready, delay):
            errors.append(process.stderr.read() if process.stderr else "")
            break
        errors.append(process.stderr.read() if process.stderr else "")
        hit.append((kill, _partials(folder)))
    assert len(hit) >= 20, f"only {len(hit)} kills before the study ended"
    left = [name for _, names in hit for name in names]
    assert any(n.startswith(".study.json") for n in left) and any(n.endswith(".json.partial") for n in left)
    assert any(n.endswith(".parquet.partial") for n in left)
    finish = subprocess.run([sys.executable, str(script), str(folder), str(final)], env=environment,
                            capture_output=True, text=True, timeout=300)  # fmt: skip
    assert finish.returncode == 0, finish.stderr
    assert not any("damaged" in text for text in (*errors, finish.stderr)), (errors, finish.stderr)
    whole = fault_study().run(RUNS, seed=SEED)
    pd.testing.assert_frame_equal(pd.read_parquet(final), whole.table, check_exact=True)
    read = fault_study().run(RUNS, seed=SEED, out=folder)
    assert read.info["computed"] == 0 and read.info["read"] == RUNS // BLOCK


def _dask_study() -> Study:
    return Study(ad.models.two_link_planar(), control.ComputedTorque(100.0, 20.0),
                 tr.Sinusoid(0.1, 1.0, 0.0, [0.3, 0.6]), spec="max_error_after < 2e-3", q0=[0.3, 0.6],
                 t_final=0.3, after=0.2, payload=Uniform(0.0, 2.0), mass_error=Uniform(-0.2, 0.2),
                 block=10)  # fmt: skip


@pytest.mark.slow
def test_a_dask_study_survives_one_worker_then_all_workers_killed(tmp_path: Path) -> None:
    """Two workers: one killed at a random moment, later both (the scattered set-up is lost with them; it
    ended with FutureCancelledError): the set-up is scattered again to the restarted workers, and the table
    written to out equals the local run's, bit for bit."""
    distributed = pytest.importorskip("distributed")
    study = _dask_study()
    local = study.run(120, seed=9)
    rng = random.Random(7)
    one, every = rng.uniform(0.05, 0.3), rng.uniform(0.4, 0.7)
    killed: list[str] = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:  # fmt: skip

        def kill(fraction: float) -> None:
            if not killed and fraction >= one:
                next(iter(cluster.workers.values())).process.process.kill()
                killed.append("one")
            elif killed == ["one"] and fraction >= every:
                for worker in list(cluster.workers.values()):
                    worker.process.process.kill()
                killed.append("all")

        remote = study.run(120, seed=9, scheduler=cluster.scheduler_address, out=tmp_path / "s", progress=kill)
    assert killed == ["one", "all"] and remote.info["rounds"] >= 2
    pd.testing.assert_frame_equal(remote.table, local.table, check_exact=True)
    read = study.run(120, seed=9, out=tmp_path / "s")
    assert read.info["read"] == 12
    pd.testing.assert_frame_equal(read.table, local.table, check_exact=True)


@pytest.mark.slow
def test_a_cluster_whose_workers_never_come_back_is_a_clear_error() -> None:
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=0, processes=True, dashboard_address=":0") as cluster:
        start = time.perf_counter()
        with pytest.raises(ModelError, match=r"no Dask worker came back within 2 s"):
            _dask_study().run(20, seed=1, scheduler=cluster.scheduler_address, timeout=2.0)
    assert time.perf_counter() - start < 30
