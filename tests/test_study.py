"""Monte Carlo studies: reproducible blocks, the estimate's coverage, resuming from disk, Dask with a lost worker."""

from __future__ import annotations

import math
import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from armdyn.dynamics.cache import compiles
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


def _kernel_compiles() -> tuple[int, int]:
    """On a worker: (signatures loaded from the cache, signatures compiled) over every armdyn kernel it holds."""
    import sys

    from numba.core.dispatcher import Dispatcher

    kernels = [value for name, module in list(sys.modules.items()) if name.startswith("armdyn")
               for value in vars(module).values() if isinstance(value, Dispatcher)]  # fmt: skip
    return (sum(sum(k.stats.cache_hits.values()) for k in kernels),
            sum(sum(k.stats.cache_misses.values()) for k in kernels))  # fmt: skip


def test_a_one_run_block_calls_the_kernel_a_full_block_compiled() -> None:
    """A block of one run (a study's last, or the workers' warm-up) passes the same argument types as a full
    block: nothing is compiled again (a one-run broadcast once passed read-only, another signature)."""
    setup = rr_study(block=20, t_final=0.05, after=0.02).setup(40, seed=1)
    from armdyn.simulation import run_many

    full = run_block(setup, 0)
    signatures = list(run_many.signatures)
    with compiles() as compiled:
        one = run_block(replace(setup, runs=1, block=1), 0)
    assert compiled == [] and run_many.signatures == signatures  # neither compiled nor loaded from the cache
    assert one["run"].tolist() == [0] and one["finished"].all() and len(full) == 20
    assert one["payload"].iloc[0] == full["payload"].iloc[0]  # the block's stream: the first draw is the same


@pytest.mark.parametrize(
    ("scheduler", "shares"),
    [("local-cluster", True), ("tcp://127.0.0.1:8786", True), ("tcp://localhost:8786", True),
     ("tls://10.0.0.5:8786", False), ("tcp://cluster.example.org:8786", False)],
)  # fmt: skip
def test_only_workers_on_this_machine_are_taken_to_share_its_kernel_cache(scheduler: str, shares: bool) -> None:
    from armdyn.study import _shares_cache

    assert _shares_cache(scheduler) is shares


@pytest.mark.slow
def test_dask_workers_load_the_parents_compiled_kernels_and_compile_nothing() -> None:
    """A study run here fills the kernel cache; the same study on two fresh worker processes then compiles
    nothing, there or here: the warm-up compiles no function (Numba's compile events) and, after the blocks, every
    armdyn kernel a worker holds was loaded from the cache (the dispatchers' cache statistics)."""
    distributed = pytest.importorskip("distributed")
    study = rr_study(block=25, t_final=0.2, after=0.1)
    local = study.run(100, seed=4)
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
        compiles() as here,
    ):
        remote = study.run(100, seed=4, scheduler=cluster.scheduler_address)
        with distributed.Client(cluster) as client:
            counts = client.run(_kernel_compiles)
    pd.testing.assert_frame_equal(remote.table, local.table, check_exact=True)
    assert len(remote.info["compiled_on_workers"]) == 2 and set(remote.info["compiled_on_workers"].values()) == {0}
    assert here == []  # nor here: the warm-up's one-run block has the types of the blocks run before
    assert len(counts) == 2
    for loaded, compiled in counts.values():
        assert loaded > 0 and compiled == 0


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


# ----- the store: fingerprints, checked blocks, damaged files --------------------------------------------------
def small_study(**options: object) -> Study:
    """rr_study with very short runs and small blocks: a store's tests write many blocks."""
    return rr_study(**({"t_final": 0.05, "after": 0.02, "block": 10} | options))


@pytest.mark.parametrize(
    ("change", "part"),
    [
        ({"arm": ad.models.two_link_planar().with_payload(0.5)}, "arm"),
        ({"q0": [0.3, 0.7]}, "start"),
        ({"controller": control.ComputedTorque(90.0, 20.0)}, "controller"),
        ({"controller": control.ComputedTorque(100.0, 20.0, model=ad.models.two_link_planar().with_payload(1))},
         "controller"),
        ({"trajectory": tr.Sinusoid(0.2, 1.0, 0.0, [0.3, 0.6])}, "trajectory"),
        ({"spec": "max_error_after < 1"}, "criteria"),
        ({"mass_error": Uniform(-0.1, 0.2)}, "sampling"),
        ({"dt": 5e-4}, "timing"),
        ({"block": 5}, "block"),
    ],
)  # fmt: skip
def test_a_resume_into_the_folder_of_a_changed_study_is_refused_naming_the_part(
    tmp_path: Path, change: dict, part: str
) -> None:
    """The folder of one study refuses another that differs in one part (the arm's model under the same name,
    the start, the controller's gains or model...), naming the part; the changed study in a fresh folder gives
    the fresh run's table (not the first study's runs)."""
    arm = ad.models.two_link_planar()
    settings = {"arm": arm, "controller": control.ComputedTorque(100.0, 20.0),
                "trajectory": tr.Sinusoid(0.1, 1.0, 0.0, [0.3, 0.6]), "spec": "max_error_after < 2e-3",
                "q0": [0.3, 0.6], "t_final": 0.05, "after": 0.02, "payload": Uniform(0.0, 2.0),
                "mass_error": Uniform(-0.2, 0.2), "block": 10}  # fmt: skip
    first = Study(**settings).run(20, seed=1, out=tmp_path / "s")
    changed = Study(**(settings | change))
    with pytest.raises(ModelError, match=rf"holds another study \(it differs in [\w, ]*\b{part}\b"):
        changed.run(20, seed=1, out=tmp_path / "s")
    fresh = changed.run(20, seed=1).table
    pd.testing.assert_frame_equal(changed.run(20, seed=1, out=tmp_path / "t").table, fresh)
    assert not fresh.equals(first.table)
    again = Study(**settings).run(20, seed=1, out=tmp_path / "s")
    assert again.info["read"] == 2 and again.info["computed"] == 0
    pd.testing.assert_frame_equal(again.table, first.table)


def test_study_json_holds_the_fingerprint_and_its_parts(tmp_path: Path) -> None:
    """study.json: the SHA-256 of its parts' hashes (recomputed here), with the armdyn version among them."""
    import hashlib
    import json

    study = small_study()
    result = study.run(20, seed=2, out=tmp_path / "s")
    stored = json.loads((tmp_path / "s" / "study.json").read_text())
    assert stored["fingerprint"] == result.info["fingerprint"]
    assert hashlib.sha256(json.dumps(stored["parts"], sort_keys=True).encode()).hexdigest() == stored["fingerprint"]
    assert {"arm", "start", "controller", "trajectory", "criteria", "sampling", "seed", "block", "version"} <= set(
        stored["parts"]
    )
    assert not list((tmp_path / "s").glob(".*.partial"))


def _damage(folder: Path) -> dict[int, str]:
    """Damage blocks 1 to 5 of a folder of six blocks in five ways; the kind of damage per block."""
    import json

    blocks = sorted(folder.glob("block-*.parquet"))
    data = blocks[1].read_bytes()
    blocks[1].write_bytes(data[: len(data) // 2])  # truncated
    blocks[2].write_bytes(b"")  # empty
    blocks[3].write_bytes(blocks[0].read_bytes())  # a copy of block 0, its record too
    (folder / "block-000003.json").write_text((folder / "block-000000.json").read_text())
    data = bytearray(blocks[4].read_bytes())
    data[len(data) // 3] ^= 0x01  # one bit of one byte
    blocks[4].write_bytes(bytes(data))
    short = pd.read_parquet(blocks[5]).iloc[:-1]  # a row missing, its record rewritten to match the file
    short.to_parquet(blocks[5], index=False)
    record = json.loads((folder / "block-000005.json").read_text())
    import hashlib

    record["sha256"] = hashlib.sha256(blocks[5].read_bytes()).hexdigest()
    (folder / "block-000005.json").write_text(json.dumps(record))
    return {1: "checksum", 2: "checksum", 3: "does not describe block 3", 4: "checksum", 5: "holds 9 rows"}


def test_damaged_blocks_are_reported_and_recomputed_or_refused(tmp_path: Path) -> None:
    """A truncated, an empty, a copied, a flipped-byte and a short block are each named in a warning and
    computed again: the table equals the uninterrupted run's. With damaged="refuse" the first is refused."""
    from armdyn.study import DamagedBlockWarning

    study = small_study()
    whole = study.run(60, seed=4)
    study.run(60, seed=4, out=tmp_path / "s")
    kinds = _damage(tmp_path / "s")
    with pytest.raises(ModelError, match=r"block-000001.parquet is damaged .*checksum"):
        study.run(60, seed=4, out=tmp_path / "s", damaged="refuse")
    with pytest.warns(DamagedBlockWarning) as caught:
        resumed = study.run(60, seed=4, out=tmp_path / "s")
    messages = [str(w.message) for w in caught]
    for index, kind in kinds.items():
        assert any(f"block-{index:06d}.parquet" in m and kind in m for m in messages), (index, messages)
    assert len(messages) == 5 and resumed.info["computed"] == 5 and resumed.info["read"] == 1
    pd.testing.assert_frame_equal(resumed.table, whole.table, check_exact=True)
    clean = study.run(60, seed=4, out=tmp_path / "s")  # everything was written again, whole
    assert clean.info["read"] == 6
    pd.testing.assert_frame_equal(clean.table, whole.table, check_exact=True)


def test_a_block_without_its_record_or_a_record_without_its_block(tmp_path: Path) -> None:
    """A record whose block never arrived (a kill between the two renames) is recomputed silently; a block
    without its record is reported."""
    from armdyn.study import DamagedBlockWarning

    study = small_study()
    whole = study.run(30, seed=5, out=tmp_path / "s")
    (tmp_path / "s" / "block-000001.parquet").unlink()
    (tmp_path / "s" / "block-000002.json").unlink()
    with pytest.warns(DamagedBlockWarning, match="block-000002.parquet is damaged .*no record") as caught:
        resumed = study.run(30, seed=5, out=tmp_path / "s")
    assert len(caught) == 1 and resumed.info["computed"] == 2
    pd.testing.assert_frame_equal(resumed.table, whole.table, check_exact=True)


def test_duplicated_or_missing_run_ranges_are_found_before_the_table_is_assembled() -> None:
    from armdyn.study import _check_ranges

    study = small_study()
    setup = study.setup(30, seed=1)
    blocks = {b: run_block(setup, b) for b in range(3)}
    _check_ranges(blocks, setup, 3)
    with pytest.raises(ModelError, match="10 runs duplicated, 10 runs missing"):
        _check_ranges(blocks | {2: blocks[1]}, setup, 3)
    with pytest.raises(ModelError, match=r"blocks missing \[1\]"):
        _check_ranges({0: blocks[0], 2: blocks[2]}, setup, 3)


def test_a_damaged_study_json_is_written_again_unless_the_blocks_are_another_studys(tmp_path: Path) -> None:
    """An empty or truncated study.json (a kill during a write by an older version, or a damaged disk) does
    not make the study unfinishable: it is written again with a warning and the blocks are checked; but when
    a block's record names another study, the folder is refused."""
    from armdyn.study import DamagedBlockWarning

    study = small_study()
    whole = study.run(30, seed=6, out=tmp_path / "s")
    text = (tmp_path / "s" / "study.json").read_text()
    for damaged in ("", text[: len(text) // 2], "[1, 2]"):
        (tmp_path / "s" / "study.json").write_text(damaged)
        with pytest.warns(DamagedBlockWarning, match="study.json was damaged"):
            resumed = study.run(30, seed=6, out=tmp_path / "s")
        assert resumed.info["read"] == 3
        pd.testing.assert_frame_equal(resumed.table, whole.table, check_exact=True)
        assert (tmp_path / "s" / "study.json").read_text() == text
    (tmp_path / "s" / "study.json").write_text("")
    with pytest.raises(ModelError, match=r"study\.json is damaged and block-000000\.json belongs to another study"):
        small_study(payload=Uniform(0.0, 1.0)).run(30, seed=6, out=tmp_path / "s")


def test_an_empty_error_window_is_refused() -> None:
    """A spec on the error after t with t >= t_final has no sample to judge: refused (it counted every run as a
    pass), while a window of the last samples and a spec without a window are accepted."""
    with pytest.raises(ModelError, match=r"window is empty; give after < t_final"):
        rr_study("max-error-after-0.5s < 1e-3")
    with pytest.raises(ModelError, match=r"after 0.3 s, but the runs end at t_final = 0.3 s"):
        rr_study("max_error_after q2 < 1e-3", after=0.3)
    late = rr_study("max_error_after < 1e-3", after=0.2999, block=10).run(10, seed=1)  # the last sample only
    assert (late.table["max_error_after"] == late.table["final_error"]).all()
    assert rr_study("payload < 1.2", after=0.5).run(10).estimate.runs == 10


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"progress": 5}, "progress must be None or a function"),
        ({"timeout": math.nan}, "timeout must be finite"),
        ({"timeout": 0.0}, "timeout must be a positive"),
        ({"damaged": "ignore"}, "damaged must be 'recompute' or 'refuse'"),
        ({"out": Path("/no/such/folder/study")}, r"the folder /no/such/folder it goes in does not exist"),
        ({"out": 5}, "out must be a folder"),
    ],
)
def test_bad_run_arguments_are_model_errors(arguments: dict, message: str) -> None:
    with pytest.raises(ModelError, match=message):
        small_study().run(10, **arguments)


@pytest.mark.skipif(not Path("/sys/kernel").is_dir(), reason="needs Linux's read-only /sys")
def test_an_out_folder_that_cannot_be_written_is_a_model_error() -> None:
    with pytest.raises(ModelError, match=r"out /sys/armdyn-study: cannot make the folder"):
        small_study().run(10, out="/sys/armdyn-study")


@pytest.mark.parametrize("spec", ["max_error_after < 1e-3e5", "max-error-after-1.2.3s < 1", "max_tau < 1-2"])
def test_a_spec_bound_that_is_not_a_number_is_a_model_error(spec: str) -> None:
    from tests.helpers import assert_one_error_line, invoke

    with pytest.raises(ModelError, match="that is not a number"):
        Requirement(spec)
    assert_one_error_line(invoke("study", "two_link_planar", "--runs", "10", "--spec", spec), "not a number")


def test_a_worker_whose_environment_changed_numba_num_threads_still_compiles() -> None:
    """A dask.distributed Nanny applies its env after the worker imported Numba: a NUMBA_NUM_THREADS there made
    every later compile fail ("Cannot set NUMBA_NUM_THREADS", the study's own LocalCluster did this). The
    worker's thread setting now keeps the pool Numba started with: a fresh function compiles and runs; the old
    setting fails on the same worker."""
    distributed = pytest.importorskip("distributed")
    from armdyn.study import _worker_threads

    def old_setting() -> str:
        import numba

        numba.set_num_threads(1)
        try:
            return str(numba.njit(lambda x: x + 1)(1))
        except RuntimeError as error:
            return str(error)

    def new_setting() -> tuple[int, int]:
        import numba

        _worker_threads(1)
        return numba.njit(lambda x: x + 2)(1), numba.get_num_threads()

    environment = {"NUMBA_NUM_THREADS": "1"}
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  env=environment) as cluster, distributed.Client(cluster) as client:  # fmt: skip
        started = client.run(lambda: __import__("numba").config.NUMBA_NUM_THREADS)
        (before,) = client.run(old_setting).values()
        (after,) = client.run(new_setting).values()
    if next(iter(started.values())) > 1:  # on one core, the Nanny's value is the value Numba started with
        assert "Cannot set NUMBA_NUM_THREADS" in before
    assert after == (3, 1)


def test_a_study_names_its_controller_and_a_normal_its_bounds() -> None:
    arm = ad.models.two_link_planar()
    with pytest.raises(ad.ArgumentError, match=r"^controller must be one of armdyn.control's laws.*got NoneType"):
        Study(arm, None)
    with pytest.raises(ModelError, match=r"low = 0.9, high = 1 holds almost none of its mass"):
        Normal(0.0, 0.1, 0.9, 1.0)  # 1e-19 of its mass: refused when made, not at the first draw
    with pytest.raises(ModelError, match=r"^low must be a number"):
        Normal(0.0, 0.1, 10**400, 10**401)
    truncated = Normal(0.0, 0.1, 0.3, 1.0)  # 0.13% of its mass: made, but 100 rounds of redrawing may not do
    with pytest.raises(ModelError, match=r"^payload: Normal\(0, 0.1\) truncated to low = 0.3"):
        truncated.sample(np.random.default_rng(0), (10**5,), "payload")
    assert Normal(0.0, 0.1, -0.1, 0.1).sample(np.random.default_rng(0), (1000,)).max() <= 0.1
