"""Monte Carlo studies: reproducible blocks, the estimate's coverage, resuming from disk, Dask with a lost worker."""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from armdyn.errors import ModelError
from armdyn.study import Normal, Requirement, Study, Uniform, clopper_pearson, run_block, runs_needed


def rr_study(spec: str = "max_error_after < 2e-3", **options: object) -> Study:
    """The two-link arm under computed torque believing in the nominal arm, with an uncertain payload and link
    masses: short runs, so that many fit in a test."""
    arm = ad.models.two_link_planar()
    settings = {"t_final": 0.3, "after": 0.2, "payload": Uniform(0.0, 2.0), "mass_error": Uniform(-0.2, 0.2),
                "block": 50} | options  # fmt: skip
    return Study(arm, control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 1.0, 0.0, [0.3, 0.6]), spec=spec,
                 q0=[0.3, 0.6], **settings)  # fmt: skip


def test_a_block_is_the_same_wherever_and_in_whatever_order_it_runs() -> None:
    study = rr_study()
    setup = study.setup(200, seed=7)
    forward = [run_block(setup, b) for b in range(4)]
    backward = [run_block(setup, b, threads=1) for b in reversed(range(4))][::-1]
    for a, b in zip(forward, backward, strict=True):
        pd.testing.assert_frame_equal(a, b, check_exact=True)
    result = study.run(200, seed=7)
    pd.testing.assert_frame_equal(result.table.drop(columns="holds"), pd.concat(forward, ignore_index=True))
    other = study.run(200, seed=8).table
    assert not np.array_equal(other["payload"], result.table["payload"])
    assert result.table["run"].tolist() == list(range(200)) and result.table["finished"].all()


def test_the_runs_match_simulate_with_the_sampled_plant() -> None:
    """A study's run is simulate on the sampled plant: the payload drawn for run 3, simulated alone, gives its
    max error after the window."""
    study = rr_study(mass_error=None)
    table = study.run(10, seed=1).table
    arm = ad.models.two_link_planar()
    row = table.iloc[3]
    single = ad.simulate(arm.with_payload(row["payload"]), control.ComputedTorque(100.0, 20.0, model=arm),
                         tr.Sinusoid(0.1, 1.0, 0.0, [0.3, 0.6]), t_final=0.3, q0=[0.3, 0.6])  # fmt: skip
    late = single.t >= 0.2 - 1e-12
    assert row["max_error_after"] == pytest.approx(np.abs(single.error[late]).max(), rel=1e-12)


def test_the_interval_covers_a_known_probability_at_its_confidence() -> None:
    """The spec "payload < 1.2" holds with probability exactly 0.6 for a payload uniform on [0, 2]: over 40
    seeds the 95 % Clopper-Pearson interval of 200 runs covers 0.6 at least 35 times (expected 38 or more)."""
    study = rr_study("payload < 1.2", t_final=0.002, after=0.0, mass_error=None, block=200)
    covered = sum(
        result.estimate.low <= 0.6 <= result.estimate.high for result in (study.run(200, seed=s) for s in range(40))
    )
    assert covered >= 35


def test_statistics_against_their_formulas() -> None:
    assert runs_needed(0.01, 0.95) == math.ceil(math.log(40) / (2 * 1e-4))
    none = clopper_pearson(0, 10)
    assert none.low == 0.0 and none.high == pytest.approx(1 - 0.025 ** (1 / 10), rel=1e-9)
    all_ = clopper_pearson(10, 10)
    assert all_.high == 1.0 and all_.low == pytest.approx(0.025 ** (1 / 10), rel=1e-9)
    half = clopper_pearson(50, 100)
    assert half.low < 0.5 < half.high and half.high - 0.5 == pytest.approx(0.5 - half.low, rel=1e-9)


def test_an_interrupted_study_resumes_without_redoing_a_block(tmp_path: Path) -> None:
    study = rr_study(block=25)
    whole = study.run(100, seed=3)
    out = tmp_path / "study"

    def interrupt_after_two(fraction: float) -> None:
        if fraction >= 0.5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        study.run(100, seed=3, out=out, progress=interrupt_after_two)
    written = sorted(p.name for p in out.glob("block-*.parquet"))
    assert written == ["block-000000.parquet", "block-000001.parquet"]
    stamps = {p: p.stat().st_mtime_ns for p in out.glob("block-*.parquet")}
    resumed = study.run(100, seed=3, out=out)
    assert resumed.info["computed"] == 2 and resumed.info["read"] == 2
    assert all(p.stat().st_mtime_ns == stamp for p, stamp in stamps.items())
    pd.testing.assert_frame_equal(resumed.table, whole.table)
    assert str(resumed.estimate) == str(whole.estimate)
    with pytest.raises(ModelError, match="holds another study"):
        study.run(100, seed=4, out=out)


@pytest.mark.slow
def test_a_study_on_a_dask_cluster_that_loses_a_worker_gives_the_local_result() -> None:
    """Two worker processes; one is killed as soon as the first block arrives; Dask recomputes what it held
    and the table equals the local run's, bit for bit."""
    distributed = pytest.importorskip("distributed")
    study = rr_study(block=20)
    local = study.run(200, seed=5)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  env={"NUMBA_NUM_THREADS": "1"}) as cluster:  # fmt: skip
        killed = []

        def kill_one(fraction: float) -> None:
            if not killed:
                worker = next(iter(cluster.workers.values()))
                killed.append(worker)
                worker.process.process.kill()  # the worker's process dies with what it holds

        remote = study.run(200, seed=5, scheduler=cluster.scheduler_address, progress=kill_one)
    assert killed and remote.info["scheduler"].startswith("tcp://")
    pd.testing.assert_frame_equal(remote.table, local.table, check_exact=True)


@pytest.mark.slow
def test_the_local_cluster_scheduler_and_an_unreachable_one() -> None:
    pytest.importorskip("distributed")
    study = rr_study(block=50)
    local = study.run(100, seed=2)
    clustered = study.run(100, seed=2, scheduler="local-cluster", workers=2)
    pd.testing.assert_frame_equal(clustered.table, local.table, check_exact=True)
    assert clustered.info["workers"] == 2 and "dashboard" in clustered.info
    start = time.perf_counter()
    with pytest.raises(ModelError, match="cannot reach the Dask scheduler"):
        study.run(100, seed=2, scheduler="tcp://127.0.0.1:9", timeout=2.0)
    assert time.perf_counter() - start < 30


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Uniform(2.0, 1.0), "low <= high"),
        (lambda: Normal(0.0, -1.0), "std >= 0"),
        (lambda: Normal(0.0, 1.0, low=5.0, high=1.0), "low < high"),
        (lambda: Requirement("max_torque < 3"), "unknown quantity 'max_torque'"),
        (lambda: Requirement("the error is small"), "cannot read the spec clause"),
        (lambda: rr_study("max_error_after q7 < 1").run(10), "no column"),
        (lambda: rr_study(payload=Normal(-5.0, 0.1)).run(10), "negative"),
        (lambda: rr_study().run(0), "runs must be at least 1"),
        (lambda: rr_study().run(10, scheduler="somewhere"), "scheduler must be"),
        (lambda: Study(ad.models.two_link_planar(), lambda *a: 0, None), "armdyn.control's laws"),
    ],
)
def test_bad_input_is_a_model_error(make: object, message: str) -> None:
    with pytest.raises(ModelError, match=message):
        make()


def test_specs_read_the_cli_form_and_joints() -> None:
    spec = Requirement("max-error-after-0.5s<1e-3 and max_tau <= 200 and rms_error q2 < 1")
    assert spec.after == 0.5
    assert spec.clauses == (("max_error_after", "<", 1e-3), ("max_tau", "<=", 200.0), ("rms_error q2", "<", 1.0))
    result = rr_study("max-error-after-0.1s < 1").run(20)
    assert result.table["holds"].all() and result.estimate.probability == 1.0


def test_the_study_command(tmp_path: Path) -> None:
    """armdyn study: the estimate with its interval and Hoeffding's sample size, a figure, blocks on disk read
    back by a rerun, and one error line for a spec it cannot read."""
    from tests.helpers import assert_one_error_line, invoke

    line = ["study", "two_link_planar", "--runs", "120", "--block", "50", "--t-final", "0.3", "--payload", "0:2",
            "--mass-error", "10%", "--spec", "max-error-after-0.2s<3e-3", "--seed", "4"]  # fmt: skip
    first = invoke(*line, "--out", tmp_path / "blocks", "--plot", tmp_path / "study.png")
    assert first.exit_code == 0, first.output
    text = " ".join(first.output.split())
    assert "P(spec holds)" in text and "Clopper-Pearson" in text and "18445" in text and "3 / 0" in text
    assert (tmp_path / "study.png").stat().st_size > 10_000 and len(list((tmp_path / "blocks").glob("*.parquet"))) == 3
    again = invoke(*line, "--out", tmp_path / "blocks")
    assert again.exit_code == 0 and "0 / 3" in " ".join(again.output.split())
    probability = re.search(r"P\(spec holds\)\W+([0-9.]+)", first.output).group(1)
    assert probability in again.output
    assert_one_error_line(invoke("study", "two_link_planar", "--spec", "speed < 3"), "unknown quantity")
