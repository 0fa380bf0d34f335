"""The command line's errors: one clean line on stderr and a non-zero exit code, never a traceback
(unless --debug), for every command; and the outputs of the commands that write files."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import armdyn as ad
from armdyn.cli import app
from tests.test_regressor import exciting

ARMDYN = Path(sys.executable).parent / "armdyn"  # the script pip installed in the venv
HEADER = "q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2"


def assert_one_error_line(result: object, *fragments: str) -> str:
    """A non-zero exit with exactly one line on stderr, 'error: ...', containing the fragments."""
    assert result.exit_code != 0, result.output
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def invoke(*args: str) -> object:
    return CliRunner().invoke(app, [str(arg) for arg in args], prog_name="armdyn")


@pytest.fixture
def files(tmp_path: Path) -> Path:
    """CSV files that are not samples: ragged, empty, binary, a text value, no samples, all zeros."""
    (tmp_path / "ragged.csv").write_text(f"{HEADER}\n1,2,3,4,5,6,7,8\n1,2,3\n")
    (tmp_path / "empty.csv").write_text("")
    (tmp_path / "binary.csv").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "nul.csv").write_bytes(f"{HEADER}\n".encode() + b"\x00\x01\x02,3\n")
    (tmp_path / "text.csv").write_text(f"{HEADER}\n1,2,3,4,5,6,7,x\n")
    (tmp_path / "header.csv").write_text(f"{HEADER}\n")
    (tmp_path / "columns.csv").write_text("q1,q2\n1,2\n")
    (tmp_path / "zeros.csv").write_text(HEADER + "\n" + "0,0,0,0,0,0,0,0\n" * 50)
    return tmp_path


# ----- one error line for every kind of bad input -------------------------------------------------
@pytest.mark.parametrize(
    ("name", "fragments"),
    [
        ("ragged.csv", ["line 3: 3 values, but the header row has 8 columns"]),
        ("empty.csv", ["is empty", "q1, q2, qd1"]),
        ("binary.csv", ["is not a text CSV file"]),
        ("nul.csv", ["is not a text CSV file"]),
        ("text.csv", ["line 2, column tau2: 'x' is not a number"]),
        ("header.csv", ["has a header row but no samples"]),
        ("columns.csv", ["lacks the columns qd1, qd2"]),
        ("zeros.csv", ["do not excite the 13 base parameters", "rank 2 of 13"]),
        ("missing.csv", ["missing.csv: No such file or directory"]),
    ],
)
def test_cli_identify_on_a_bad_csv_is_one_error_line(files: Path, name: str, fragments: list[str]) -> None:
    assert_one_error_line(invoke("identify", "two_link_planar", files / name), *fragments)


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["check", "two_link_planar", "--samples", "2"], ["samples must be at least 4, got 2"]),
        (["check", "--samples", "2"], ["Missing argument 'name'", "armdyn check --help"]),
        (["check", "two_link_planar", "--samples", "abc"], ["Invalid value for '--samples'"]),
        (["check", "two_link_planar", "--seed", "-1"], ["seed must be at least 0"]),
        (["check", "nosuch"], ["no built-in arm named 'nosuch'", "puma560"]),
        (["show", "nosuch"], ["no built-in arm named 'nosuch'"]),
        (["identify", "nosuch", "x.csv"], ["no built-in arm named 'nosuch'"]),
        (["simulate", "nosuch"], ["no built-in arm named 'nosuch'"]),
        (["derive", "nosuch"], ["no built-in arm named 'nosuch'"]),
        (["derive", "scara", "--code", "fortran"], ["--code must be 'python' or 'c'"]),
        (["nosuchcommand"], ["No such command 'nosuchcommand'"]),
        (["simulate", "two_link_planar", "--dt", "-1"], ["dt must be"]),
        (["simulate", "two_link_planar", "--t-final", "abc"], ["Invalid value for '--t-final'"]),
        (["simulate", "two_link_planar", "--t-final", "nan"], ["t_final must be"]),
        (["simulate", "two_link_planar", "--kp", "-3", "--t-final", "0.1"], ["gain kp must be"]),
        (["simulate", "two_link_planar", "--controller", "magic"], ["--controller must be one of"]),
        (["simulate", "two_link_planar", "--trajectory", "zigzag"], ["--trajectory must be sine, quintic or none"]),
        (["simulate", "two_link_planar", "--trajectory", "quintic", "--frequency", "0"], ["--frequency must be"]),
        (["simulate", "two_link_planar", "--period", "-0.01"], ["positive, finite sample period"]),
        (["simulate", "two_link_planar", "--torque-limit", "nan"], ["torque limit must be positive"]),
        (["simulate", "two_link_planar", "--controller", "none", "--period", "0.1"], ["need a controller"]),
    ],
)
def test_cli_bad_arguments_are_one_error_line(args: list[str], fragments: list[str]) -> None:
    assert_one_error_line(invoke(*args), *fragments)


@pytest.mark.parametrize(
    "args",
    [
        ["simulate", "two_link_planar", "--t-final", "0.1", "--csv", "{missing}/run.csv"],
        ["simulate", "two_link_planar", "--t-final", "0.1", "--plot", "{missing}/run.png"],
        ["derive", "two_link_planar", "--output", "{missing}/rr.txt"],
        ["demo", "--output", "{missing}/deeper/out"],
        ["identify", "two_link_planar", "{files}/zeros.csv", "--output", "{missing}/estimates.csv"],
    ],
    ids=["simulate --csv", "simulate --plot", "derive", "demo", "identify"],
)
def test_cli_output_in_a_missing_folder_is_one_error_line(files: Path, args: list[str]) -> None:
    missing = files / "no" / "such"
    args = [arg.format(missing=missing, files=files) for arg in args]
    assert_one_error_line(invoke(*args), "does not exist")
    assert not (files / "no").exists()  # nothing is made on the way


def test_cli_output_that_is_a_folder_or_a_file_is_one_error_line(files: Path) -> None:
    assert_one_error_line(invoke("derive", "two_link_planar", "-o", files), "is a folder")
    assert_one_error_line(invoke("demo", "--output", files / "empty.csv"), "is a file, not a folder")


# ----- a diverging simulation -----------------------------------------------------------------------
def test_cli_diverging_simulation_exits_nonzero() -> None:
    result = invoke("simulate", "two_link_planar", "--dt", "0.5", "--kp", "1e6", "--t-final", "3")
    assert_one_error_line(result, "diverged")


def test_cli_simulation_errors_reach_the_user_as_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    import armdyn.simulation

    def diverging(*args: object, **kwargs: object) -> None:
        raise ad.ModelError("the simulation of 'two_link_planar' diverged at t = 1.2 s:\n  the state is not finite")

    monkeypatch.setattr(armdyn.simulation, "simulate", diverging)
    line = assert_one_error_line(invoke("simulate", "two_link_planar"), "diverged at t = 1.2 s")
    assert line == "error: the simulation of 'two_link_planar' diverged at t = 1.2 s: the state is not finite"


def test_cli_a_run_returned_with_a_non_finite_state_exits_nonzero(monkeypatch: pytest.MonkeyPatch) -> None:
    import armdyn.simulation

    real = armdyn.simulation.simulate

    def with_nan(*args: object, **kwargs: object) -> object:
        result = real(*args, **kwargs)
        result.q[len(result.t) // 2 :] = np.nan
        return result

    monkeypatch.setattr(armdyn.simulation, "simulate", with_nan)
    assert_one_error_line(invoke("simulate", "two_link_planar", "--t-final", "0.2"), "diverged", "t = 0.1 s")


# ----- --debug, warnings, internal errors -----------------------------------------------------------
def test_cli_debug_reraises() -> None:
    result = invoke("--debug", "check", "two_link_planar", "--samples", "2")
    assert isinstance(result.exception, ad.ModelError)
    assert "samples must be at least 4" in str(result.exception)
    assert result.exit_code != 0


def test_cli_internal_errors_are_one_line_too(monkeypatch: pytest.MonkeyPatch) -> None:
    import armdyn.properties

    def broken(*args: object, **kwargs: object) -> None:
        raise RuntimeError("a bug")

    monkeypatch.setattr(armdyn.properties, "check", broken)
    result = invoke("check", "two_link_planar")
    assert result.exit_code == 1
    assert_one_error_line(result, "internal error (RuntimeError: a bug)", "--debug")


def test_cli_warnings_are_one_line(tmp_path: Path) -> None:
    arm = ad.models.two_link_planar()
    q, qd, qdd = (1e-2 * x for x in exciting(2, 400))  # full rank, poorly conditioned
    path = tmp_path / "samples.csv"
    np.savetxt(path, np.hstack([q, qd, qdd, arm.inverse_dynamics(q, qd, qdd)]), delimiter=",", header=HEADER,
               comments="")  # fmt: skip
    result = invoke("identify", "two_link_planar", path)
    assert result.exit_code == 0, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("warning: the samples excite the base parameters"), lines


# ----- commands that write ------------------------------------------------------------------------
def test_cli_identify_writes_its_estimates(tmp_path: Path) -> None:
    arm = ad.models.two_link_planar()
    q, qd, qdd = exciting(2, 300)
    samples, estimates = tmp_path / "samples.csv", tmp_path / "estimates.csv"
    np.savetxt(samples, np.hstack([q, qd, qdd, arm.inverse_dynamics(q, qd, qdd)]), delimiter=",", header=HEADER,
               comments="")  # fmt: skip
    result = invoke("identify", "two_link_planar", samples, "-o", estimates)
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    table = np.genfromtxt(estimates, delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert len(table) == len(ad.base_parameters(arm))
    np.testing.assert_allclose(table["estimate"], table["model_value"], rtol=1e-8, atol=1e-8)


# ----- the installed script -----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["check", "puma560", "--samples", "2"], "samples must be at least 4"),
        (["show", "nosuch"], "no built-in arm named 'nosuch'"),
        (["identify", "two_link_planar", "{files}/empty.csv"], "is empty"),
        (["identify", "two_link_planar", "{files}/ragged.csv"], "line 3"),
        (["simulate", "two_link_planar", "--dt", "abc"], "Invalid value for '--dt'"),
        (["derive", "two_link_planar", "-o", "{files}/no/such.txt"], "does not exist"),
    ],
)
def test_cli_script_exit_codes_and_no_traceback(files: Path, args: list[str], fragment: str) -> None:
    run = subprocess.run(
        [str(ARMDYN), *(arg.format(files=files) for arg in args)], capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 2, (run.stdout, run.stderr)
    assert "Traceback" not in run.stderr + run.stdout
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], run.stderr


def test_cli_script_debug_shows_the_traceback() -> None:
    run = subprocess.run(
        [str(ARMDYN), "--debug", "check", "puma560", "--samples", "2"], capture_output=True, text=True, timeout=600
    )
    assert run.returncode != 0
    assert "Traceback" in run.stderr and "ModelError" in run.stderr
