"""Ctrl-C stops a long run within a fraction of a second and keeps what was computed: simulate raises
RunInterrupted (a KeyboardInterrupt) holding the run so far; the command line writes it, says so and exits
130; a study stops after its block under way and says how to resume."""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from armdyn.simulation import RunInterrupted, in_chunks

ARMDYN = [sys.executable, "-c", "from armdyn.cli import main; main()"]


def test_chunks_do_not_change_a_run_and_an_interrupt_keeps_the_rows_done() -> None:
    """A run reported in chunks (progress) equals the run without; Ctrl-C between chunks gives the rows done."""
    puma = ad.models.puma560()
    law, path = control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 0.5, 0.0, puma.configuration("qn"))
    fractions: list[float] = []
    chunked = ad.simulate(puma, law, path, t_final=3.0, q0=puma.configuration("qn"), progress=fractions.append)
    whole = ad.simulate(puma, law, path, t_final=3.0, q0=puma.configuration("qn"))
    np.testing.assert_array_equal(chunked.q, whole.q)
    assert fractions[-1] == 1.0 and all(b > a for a, b in itertools.pairwise(fractions))
    calls: list[tuple[int, int]] = []

    def advance(first: int, last: int) -> bool:
        calls.append((first, last))
        if len(calls) == 3:
            raise KeyboardInterrupt
        return True

    with pytest.raises(RunInterrupted, match="interrupted after") as stopped:
        in_chunks(advance, 10**6, None, lambda rows: rows)
    assert stopped.value.result == calls[1][1]  # the rows of the chunks that ended before Ctrl-C
    assert isinstance(stopped.value, KeyboardInterrupt)


def _interrupted(argv: list[str], wait: float, env: dict[str, str]) -> tuple[int, str, float]:
    """Run a command, send SIGINT after ``wait`` s: (exit code, stderr, seconds from SIGINT to its first line)."""
    # the child starts with Ctrl-C's default action even where this process ignores it (a shell's background
    # job, without job control, ignores SIGINT and its children inherit that; Python then installs no handler)
    process = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # fmt: skip
    time.sleep(wait)
    sent = time.perf_counter()
    process.send_signal(signal.SIGINT)
    assert process.stderr is not None
    first = process.stderr.readline()
    answered = time.perf_counter() - sent
    rest, _ = process.communicate(timeout=120)[1], None
    return process.wait(), first + (rest or ""), answered


@pytest.mark.slow
def test_ctrl_c_stops_simulate_within_a_second_and_writes_the_run_so_far(tmp_path: Path) -> None:
    """Oracle: the CSV's last row equals a fresh run of the same arm to that time."""
    env = {**os.environ, "PYTHONPATH": str(Path(ad.__file__).parents[1])}
    warm = [*ARMDYN, "simulate", "puma560", "--actuators", "dc", "--t-final", "0.01"]  # compiled before the clock runs
    subprocess.run(warm, env=env, check=True, capture_output=True)
    table = tmp_path / "part.csv"
    code, stderr, answered = _interrupted(
        [*ARMDYN, "simulate", "puma560", "--actuators", "dc", "--t-final", "8000", "--csv", str(table)], 5.0, env
    )
    assert code == 130, stderr
    assert answered < 1.0, f"the interrupt was answered after {answered:.2f} s"
    assert "interrupted at t = " in stderr and "hold the run up to then" in stderr, stderr
    with open(table, "rb") as handle:
        header = handle.readline().decode().strip().split(",")
        handle.seek(-4096, os.SEEK_END)
        last = np.array(handle.read().decode().strip().splitlines()[-1].split(","), dtype=float)
    t_last = last[0]
    assert t_last > 0.1
    from typer.testing import CliRunner

    from armdyn.cli import app

    fresh = tmp_path / "fresh.csv"
    CliRunner().invoke(app, ["simulate", "puma560", "--actuators", "dc", "--t-final", f"{t_last:.12g}", "--csv",
                             str(fresh)])  # fmt: skip
    with open(fresh, "rb") as handle:
        handle.seek(-4096, os.SEEK_END)
        expected = np.array(handle.read().decode().strip().splitlines()[-1].split(","), dtype=float)
    q = [k for k, name in enumerate(header) if name.startswith("q") and name[1:].isdigit()]
    np.testing.assert_allclose(last[q], expected[q], rtol=0, atol=1e-12)


@pytest.mark.slow
def test_ctrl_c_stops_a_study_after_its_block_and_says_how_to_resume(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(Path(ad.__file__).parents[1])}
    folder = tmp_path / "study"
    argv = [*ARMDYN, "study", "two_link_planar", "--runs", "4000000", "--block", "2000", "--t-final", "1.0",
            "--spec", "max-error-after-0.1s<1e-3", "--out", str(folder)]  # fmt: skip
    code, stderr, _ = _interrupted(argv, 8.0, env)
    assert code == 130, stderr
    assert "the study was interrupted after" in stderr and f"the blocks done are in {folder}" in stderr, stderr
    done = int(stderr.split("interrupted after ")[1].split(" of ")[0])
    assert done <= len(list(folder.glob("block-*.parquet"))) <= done + 1  # Ctrl-C may fall between write and count
    assert not [p for p in folder.iterdir() if p.name.startswith(".")], "a temporary file was left"


def test_a_compile_announces_itself_once_where_no_spinner_shows(capsys: pytest.CaptureFixture[str]) -> None:
    """With stderr a log or a pipe (as under CI or `make run > log`), the first compile prints one line."""
    from armdyn import cli

    listener = cli._Compiling()
    announced, cli._activity.announced = cli._activity.announced, False
    try:
        for _ in range(3):
            listener.on_start(None)
            listener.on_end(None)
    finally:
        cli._activity.announced = announced
    lines = capsys.readouterr().err.splitlines()
    assert lines == [cli.COMPILING_LINE]
