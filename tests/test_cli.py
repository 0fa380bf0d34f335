"""The command line's errors: one clean line on stderr and a non-zero exit code, never a traceback
(unless --debug), for every command; and the outputs of the commands that write files."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from tests.helpers import assert_one_error_line, exciting, invoke

ARMDYN = Path(sys.executable).parent / "armdyn"  # the script pip installed in the venv
HEADER = "q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2"


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
        (["simulate", "two_link_planar", "--period", "-0.01"], ["needs a positive sample period", "-0.01"]),
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
        ["simulate", "two_link_planar", "--t-final", "0.1", "--output", "{missing}/run"],
        ["check", "two_link_planar", "-o", "{missing}/table.csv"],
        ["show", "puma560", "-o", "{missing}/puma.md"],
        ["models", "-o", "{missing}/models.txt"],
    ],
    ids=["simulate --csv", "simulate --plot", "derive", "demo", "identify", "simulate -o", "check", "show", "models"],
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
@pytest.mark.slow
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


@pytest.mark.slow
def test_cli_script_debug_shows_the_traceback() -> None:
    run = subprocess.run(
        [str(ARMDYN), "--debug", "check", "puma560", "--samples", "2"], capture_output=True, text=True, timeout=600
    )
    assert run.returncode != 0
    assert "Traceback" in run.stderr and "ModelError" in run.stderr


# ----- arms from files, per-joint vectors, joint ranges ----------------------------------------------
UR5 = (
    Path(sys.executable).parent.parent
    / "lib/python3.11/site-packages/cmeel.prefix/share/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
)
UR5_KP, UR5_KV = [400.0, 400.0, 400.0, 50.0, 50.0, 50.0], [40.0, 40.0, 40.0, 14.0, 14.0, 14.0]
UR5_LIMIT, UR5_Q0 = [150.0, 150.0, 150.0, 28.0, 28.0, 28.0], [0.0, -1.5708, 1.5708, 0.0, 0.0, 0.0]


def rr_table(**extra: object) -> dict:
    """The RR arm of Example 3.2-2 as a DH table file's content (angles as text with pi)."""
    return {
        "name": "rr_file",
        "gravity": [0, -9.8, 0],
        "convention": "standard",
        "configurations": {"up": ["pi/2", 0]},
        "rows": [{"a": 1, "mass": 1, "name": "theta1"}, {"a": 1, "mass": 1, "name": "theta2"}],
        **extra,
    }


def last_row(path: Path) -> dict[str, float]:
    table = np.genfromtxt(path, delimiter=",", names=True)
    return {name: float(table[name][-1]) for name in table.dtype.names}


@pytest.mark.skipif(not UR5.is_file(), reason="example-robot-data is not installed")
def test_cli_takes_a_urdf_path_and_per_joint_gains(tmp_path: Path) -> None:
    from armdyn import control, trajectories

    gains = ["--kp", ",".join(map(str, UR5_KP)), "--kv", ",".join(map(str, UR5_KV))]
    start = ["--torque-limit", ",".join(map(str, UR5_LIMIT)), "--q0", ",".join(map(str, UR5_Q0))]
    result = invoke("simulate", UR5, *gains, *start, "--t-final", "0.3", "--strict", "-o", tmp_path / "run")
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    assert "shoulder_pan_joint" in result.stdout and "max |tau| (N m)" in result.stdout
    files = {path.name for path in (tmp_path / "run").iterdir()}
    assert files == {"ur5.png", "ur5.csv", "ur5-report.md"}
    # the same run through the library: the gains and limits went to their joints, the run started at q0
    arm = ad.load_urdf(UR5)
    desired = trajectories.Sinusoid(0.1, 0.5, [0.0, np.pi / 2] * 3, UR5_Q0)
    law = control.Saturated(control.ComputedTorque(np.array(UR5_KP), np.array(UR5_KV), 0.0), np.array(UR5_LIMIT))
    expected = ad.simulate(arm, law, desired, t_final=0.3, dt=1e-3, q0=UR5_Q0)
    final = last_row(tmp_path / "run" / "ur5.csv")
    np.testing.assert_allclose([final[f"q{i + 1}"] for i in range(6)], expected.q[-1], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose([final[f"tau{i + 1}"] for i in range(6)], expected.tau[-1], rtol=1e-9, atol=1e-9)
    uniform = invoke("simulate", UR5, "--kp", "400", "--kv", "40", "--q0", ",".join(map(str, UR5_Q0)),
                     "--t-final", "0.3", "--csv", tmp_path / "uniform.csv")  # fmt: skip
    assert uniform.exit_code == 0, uniform.output
    assert last_row(tmp_path / "uniform.csv")["tau6"] != pytest.approx(final["tau6"])  # one number: every joint
    shown = invoke("show", UR5, "--no-strict", "-o", tmp_path / "ur5.md")
    assert shown.exit_code == 0, shown.output
    assert "placement xyz (m)" in shown.stdout and "wrist_3_joint" in (tmp_path / "ur5.md").read_text()
    assert_one_error_line(invoke("simulate", UR5, "--kp", "400,400"), "--kp has 2 values", "6 joints")


def test_cli_takes_a_dh_table_file(tmp_path: Path) -> None:
    import json

    path = tmp_path / "rr.json"
    path.write_text(json.dumps(rr_table()))
    arm, book = ad.models.load_dh_file(path), ad.models.two_link_planar()
    q = np.random.default_rng(1).uniform(-3, 3, (5, 2))
    np.testing.assert_allclose(arm.inertia_matrix(q), book.inertia_matrix(q), atol=1e-12)
    np.testing.assert_allclose(arm.gravity_vector(q), book.gravity_vector(q), atol=1e-12)
    shown = invoke("show", path)
    assert shown.exit_code == 0, shown.output
    assert "rr_file" in shown.stdout and "up = [1.571, 0]" in shown.stdout
    held = ["--q0", "up", "--trajectory", "none", "--t-final", "0.2"]
    run = invoke("simulate", path, *held, "--csv", tmp_path / "r.csv")
    assert run.exit_code == 0, run.output
    final = last_row(tmp_path / "r.csv")
    assert final["q1"] == pytest.approx(np.pi / 2, abs=1e-6)  # held at the named start by computed torque
    checked = invoke("check", path, "--samples", "40", "--limits=-pi/2:pi/2")
    assert checked.exit_code == 0, checked.output
    assert "m1 = 4 kg m^2" in checked.stdout


@pytest.mark.parametrize(
    ("content", "fragments"),
    [
        ("{not json", ["line 1: not valid JSON"]),
        ('{"rows": [], "name": "x"}', ["'rows' must be a non-empty list"]),
        ('{"rows": [{"a": 1}], "colour": "red"}', ["unknown keys ['colour']"]),
        ('{"rows": [3]}', ["row 1: a row is a mapping"]),
        ('{"rows": [{"a": "one"}]}', ["row 1, a: 'one' is not a number"]),
        ('{"rows": [{"a": 1, "colour": 1}]}', ["unknown DH row keys ['colour']"]),
        ('{"rows": [{"a": 1, "mass": -1}]}', ["rr.json"]),
        ('"a string"', ["holds a list of rows"]),
    ],
)
def test_cli_bad_dh_table_files_are_one_error_line(tmp_path: Path, content: str, fragments: list[str]) -> None:
    path = tmp_path / "rr.json"
    path.write_text(content)
    assert_one_error_line(invoke("show", path), *fragments)


def test_cli_reads_a_dh_table_in_yaml(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("yaml")
    path = tmp_path / "rr.yaml"
    path.write_text("name: rr_yaml\ngravity: [0, -9.8, 0]\nrows:\n  - {a: 1, mass: 1, qlim: [-pi/2, pi/2]}\n"
                    "  - {a: 1, mass: 1, alpha: 0}\n")  # fmt: skip
    shown = invoke("show", path)
    assert shown.exit_code == 0, shown.output
    assert "rr_yaml" in shown.stdout and "-1.571" in shown.stdout
    monkeypatch.setitem(sys.modules, "yaml", None)  # PyYAML missing: a clear message, JSON still works
    assert_one_error_line(invoke("show", path), "reading YAML needs PyYAML", "JSON")


@pytest.mark.slow
def test_cli_check_limits_reproduce_example_3_3_1(tmp_path: Path) -> None:
    """Example 3.3-1 (Section 3.3): the RR arm, unit masses and lengths, |theta_i| <= pi/2: the
    1-norm bounds m1 = 4 and m2 = 7 (both attained), beside the book's values in the table."""
    import csv

    table = tmp_path / "table.csv"
    result = invoke("check", "two_link_planar", "--limits", "-1.5708:1.5708,-1.5708:1.5708", "-o", table)
    assert result.exit_code == 0, result.output
    rows = {row["property"]: row for row in csv.DictReader(table.open(encoding="utf-8"))}
    norm = rows["norm bounds"]

    def named(cell: str) -> dict[str, float]:
        return {key: float(value) for key, value in re.findall(r"(\w+) = (\S+)", cell)}

    computed, book = named(norm["bound (computed)"]), named(norm["book value"])
    assert book == {"m1": 4.0, "m2": 7.0}
    assert computed["m1"] == pytest.approx(4.0, abs=1e-4) and computed["m2"] == pytest.approx(7.0, abs=1e-4)
    assert "kg m^2" in norm["bound (computed)"] and norm["holds"] == "yes"
    assert named(rows["inertia bounds"]["book value"]) == pytest.approx({"mu1": 3 - np.sqrt(8), "mu2": 3 + np.sqrt(8)})
    assert named(rows["gravity bound"]["book value"]) == pytest.approx({"gb": 2 * 9.8 + 2 * 9.8})
    assert named(rows["gravity bound"]["bound (computed)"])["gb"] <= 39.2  # inside the book's conservative bound
    # pi written out, one pair for every joint: the exact range of the book, the library's bounds
    exact = invoke("check", "two_link_planar", "--limits=-pi/2:pi/2", "-o", tmp_path / "exact.md")
    assert exact.exit_code == 0, exact.output
    report = ad.properties.check(ad.models.two_link_planar(), limits=[(-np.pi / 2, np.pi / 2)] * 2)
    assert f"m1 = {report.bounds['m1']:.6g} kg m^2, m2 = {report.bounds['m2']:.6g} kg m^2" in exact.stdout
    assert report.bounds["m1"] == pytest.approx(4.0, abs=1e-9) and report.bounds["m2"] == pytest.approx(7.0, abs=1e-9)
    assert "| norm bounds |" in (tmp_path / "exact.md").read_text()
    # the arm's own limits (none: a whole turn) are not the book's range, and give no book values
    whole = invoke("check", "two_link_planar", "--samples", "60", "--limits", "arm", "-o", tmp_path / "whole.csv")
    assert whole.exit_code == 0, whole.output
    rows = {row["property"]: row for row in csv.DictReader((tmp_path / "whole.csv").open(encoding="utf-8"))}
    assert rows["norm bounds"]["book value"] == "" and named(rows["norm bounds"]["bound (computed)"])["m1"] < 3.9


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["check", "two_link_planar", "--limits", "1:0,0:1"], ["lower <= upper"]),
        (["check", "two_link_planar", "--limits", "1,2"], ["give lower:upper for each joint"]),
        (["check", "two_link_planar", "--limits", "0:1,0:1,0:1"], ["3 lower:upper pairs", "2 joints"]),
        (["check", "two_link_planar", "--limits", "0:x"], ["--limits: 'x' is not a number"]),
        (["check", "two_link_planar", "--limits", "0:inf"], ["finite"]),
        (["simulate", "two_link_planar", "--kp", "1,2,3"], ["--kp has 3 values", "2 joints"]),
        (["simulate", "two_link_planar", "--kv", "1,,2"], ["--kv '1,,2': give numbers separated by commas"]),
        (["simulate", "two_link_planar", "--kp", "0x10"], ["'0x10' is not a number"]),
        (["simulate", "two_link_planar", "--torque-limit", "5,-1"], ["torque limit must be positive"]),
        (["simulate", "two_link_planar", "--q0", "qn"], ["no configuration of that name", "qz, qh"]),
        (["simulate", "two_link_planar", "--qd0", "1,2,3"], ["--qd0 has 3 values"]),
        (["simulate", "puma560", "--q0", "qn", "--controller", "none", "--period", "0.01"], ["need a controller"]),
        (["derive", "two_link_planar", "--latex", "--code", "c"], ["--latex and --code c exclude each other"]),
        (["check", "two_link_planar", "-o", "table.xlsx"], ["must end in .csv, .md or .txt"]),
        (["show", "no/such/arm.urdf"], ["no such URDF file"]),
        (["show", "no/such/arm"], ["no such file", "a URDF file"]),
        (["show", "README.md"], ["an arm file must be a URDF (.urdf), an MJCF (.xml, .mjcf) or a DH table"]),
    ],
)
def test_cli_bad_vectors_ranges_and_files_are_one_error_line(args: list[str], fragments: list[str]) -> None:
    assert_one_error_line(invoke(*args), *fragments)


def test_cli_simulate_starts_from_q0_and_qd0(tmp_path: Path) -> None:
    result = invoke("simulate", "puma560", "--q0", "qn", "--qd0", "0.1", "--controller", "none", "--trajectory",
                    "none", "--t-final", "0.01", "--dt", "0.001", "--csv", tmp_path / "free.csv")  # fmt: skip
    assert result.exit_code == 0, result.output
    table = np.genfromtxt(tmp_path / "free.csv", delimiter=",", names=True)
    qn = ad.models.puma560().configurations["qn"]
    np.testing.assert_allclose([table[f"q{i + 1}"][0] for i in range(6)], qn)
    np.testing.assert_allclose([table[f"qd{i + 1}"][0] for i in range(6)], 0.1)


# ----- outputs, version, progress, units -----------------------------------------------------------
def test_cli_version() -> None:
    result = invoke("--version")
    assert result.exit_code == 0 and result.stdout.strip() == f"armdyn {ad.__version__}"


def test_cli_writes_tables_by_suffix(tmp_path: Path) -> None:
    import csv

    for suffix in ("csv", "md", "txt"):
        result = invoke("show", "stanford", "-o", tmp_path / f"stanford.{suffix}")
        assert result.exit_code == 0, result.output
    text = (tmp_path / "stanford.csv").read_text(encoding="utf-8")
    rows = list(csv.reader(text.splitlines()))
    assert rows[0] == ["Denavit-Hartenberg parameters (standard)"]
    assert rows[1][:4] == ["joint", "kind", "theta (rad)", "d (m)"] and "q min (rad; m for P)" in rows[1]
    assert ["Configurations"] in rows and any(row[0].startswith("Dynamics (inertia") for row in rows if row)
    markdown = (tmp_path / "stanford.md").read_text(encoding="utf-8")
    assert "## Denavit-Hartenberg parameters (standard)" in markdown and "| mass (kg) |" in markdown
    assert "mass (kg)" in (tmp_path / "stanford.txt").read_text(encoding="utf-8")
    listed = invoke("models", "-o", tmp_path / "models.md")
    assert listed.exit_code == 0 and "| puma560 | RRRRRR | 6 |" in (tmp_path / "models.md").read_text()
    checked = invoke("check", "scara", "--samples", "20", "-o", tmp_path / "scara.csv")
    assert checked.exit_code == 0, checked.output
    header = next(csv.reader((tmp_path / "scara.csv").open(encoding="utf-8")))
    assert header == list(ad.properties.COLUMNS)


@pytest.mark.slow
def test_cli_demo_writes_its_figures(demo_run: tuple) -> None:
    demo, folder = demo_run
    assert demo.exit_code == 0, demo.output
    assert {p.name for p in folder.iterdir()} == {"demo.png", "demo.csv", "demo.gif", "demo-drives.png"}


def test_cli_tables_carry_units() -> None:
    shown = invoke("show", "puma560")
    for heading in ("theta (rad)", "a (m)", "mass (kg)", "c.o.m. (m)", "Jm (kg m^2)", "B (N m/(rad/s))"):
        assert heading in shown.stdout, heading
    assert "q min (rad; m for P)" in invoke("show", "scara").stdout
    checked = invoke("check", "polar_rp", "--samples", "30")
    assert "mu1 = " in checked.stdout and "kg m^2 or kg" in checked.stdout and "N m or N" in checked.stdout
    run = invoke("simulate", "scara", "--t-final", "0.05")
    assert "final q (rad; m for P)" in run.stdout and "max |tau| (N m; N for P)" in run.stdout


def test_cli_report_columns_each_mean_one_thing() -> None:
    from armdyn.properties import COLUMNS, Row

    report = ad.properties.check(ad.models.scara(), samples=30)
    columns, rows = report.records()
    assert columns == list(COLUMNS)
    cells = {row[0]: dict(zip(columns, row, strict=True)) for row in rows}
    for name in ("symmetry", "skew symmetry", "linearity", "passivity"):  # identities: a relative residual only
        assert cells[name]["bound (computed)"] == cells[name]["extreme sampled"] == ""
        assert cells[name]["residual or margin"].endswith("(relative)")
    gravity = cells["gravity bound"]
    assert gravity["bound (computed)"].startswith("gb = ") and gravity["residual or margin"] == ""
    assert cells["friction bound"]["residual or margin"].endswith("N m or N")  # a margin, lhs - rhs <= 0
    assert " to " in cells["inertia bounds"]["extreme sampled"]  # both sides sampled
    assert report.units["vb"] == "N m/(rad/s)^2 or N/(m/s)^2"
    old = Row("x", "x = x", True, 0.0, None, "by eye")  # the fields of before, positionally
    assert (old.unit, old.measure, old.names, old.lowest) == ("", "extreme", (), None)
    assert report.row("gravity bound").worst <= report.row("gravity bound").bound  # worst and bound kept


def test_cli_progress_shows_on_stderr_when_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    quiet = invoke("simulate", "two_link_planar", "--t-final", "0.2")
    assert quiet.exit_code == 0 and quiet.stderr == ""  # stderr is no terminal here: nothing shown
    shown = invoke("--progress", "simulate", "two_link_planar", "--t-final", "0.2", "--method", "rk45")
    assert shown.exit_code == 0, shown.output
    assert "simulating 0.2 s of two_link_planar (rk45)" in shown.stderr and "100%" in shown.stderr
    assert "two_link_planar: rk45" in shown.stdout and "simulating" not in shown.stdout
    assert invoke("--no-progress", "simulate", "two_link_planar", "--t-final", "0.2").stderr == ""

    checked = invoke("--progress", "check", "two_link_planar", "--samples", "10")
    assert checked.exit_code == 0, checked.output
    assert "checking Table 3.3.1 on two_link_planar" in checked.stderr


# ----- task coordinates ------------------------------------------------------------------------------
def test_cli_task_prints_the_task_space_equation(tmp_path: Path) -> None:
    from armdyn import task_space

    result = invoke("task", "two_link_planar", "-c", "planar", "--q", "0.3,1.2", "--qd", "0.5,-0.2",
                    "-o", tmp_path / "task.csv")  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "cond J = 3.728" in result.stdout
    arm, output = ad.models.two_link_planar(), task_space.PlanarPosition()
    q, qd = np.array([0.3, 1.2]), np.array([0.5, -0.2])
    Mbar, Nbar = task_space.task_inertia(arm, output, q), task_space.task_nonlinear(arm, output, q, qd)
    text = (tmp_path / "task.csv").read_text()
    assert f"{Mbar[1, 1]:.6g}" in text and f"{Nbar[1]:.6g}" in text
    damped = invoke("task", "two_link_planar", "-c", "planar", "--q", "0.3,0", "--damping", "0.01")
    assert damped.exit_code == 0 and "damping 0.01" in damped.stdout


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["task", "two_link_planar", "-c", "planar", "--q", "0.3,0"], ["singular or ill-conditioned", "max_condition"]),
        (["task", "two_link_planar", "-c", "sideways"], ["--coordinates must be one of position, pose, planar"]),
        (["task", "two_link_planar", "-c", "pose"], ["6 rows, more than the 2 joints"]),
    ],
)
def test_cli_task_errors_are_one_line(args: list[str], fragments: list[str]) -> None:
    assert_one_error_line(invoke(*args), *fragments)
