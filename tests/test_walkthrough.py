"""A new user's session, through the installed ``armdyn`` command only, as the README tells it:
check the UR5 from its URDF over a joint range, simulate it under per-joint gains writing a
plot and a CSV, then identify its base parameters from generated data and write the estimates.
Each step's files are read back and judged as a user would judge them."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow

ARMDYN = Path(sys.executable).parent / "armdyn"  # the script pip installed in the venv
UR5 = (
    Path(sys.executable).parent.parent
    / "lib/python3.11/site-packages/cmeel.prefix/share/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
)
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]


def armdyn(*args: object, cwd: Path) -> subprocess.CompletedProcess:
    """One command as a user types it; it must succeed and print nothing on stderr."""
    run = subprocess.run([str(ARMDYN), *map(str, args)], capture_output=True, text=True, timeout=600, cwd=cwd)
    assert run.returncode == 0, (run.stdout, run.stderr)
    assert run.stderr == "", run.stderr
    return run


@pytest.mark.skipif(not UR5.is_file(), reason="example-robot-data is not installed")
def test_a_new_users_session_through_the_command_line(tmp_path: Path) -> None:
    # 1. the properties of Table 3.3.1 over |q_i| <= pi/2, with the table written as Markdown
    limits = ",".join(["-pi/2:pi/2"] * 6)
    checked = armdyn("check", UR5, "--limits", limits, "--samples", "40", "-o", "ur5-check.md", cwd=tmp_path)
    assert "all properties hold" in checked.stdout
    table = (tmp_path / "ur5-check.md").read_text()
    for prop in ("symmetry", "skew symmetry", "gravity bound", "passivity"):
        assert prop in table
    assert "kg m^2" in table and "N m" in table  # bounds carry units
    assert "[-1.571, 1.571]" in checked.stdout  # the range the user asked for, not the arm's own

    # 2. computed torque with per-joint gains: a figure, a CSV of the run and a report
    gains = ["--kp", "400,400,400,50,50,50", "--kv", "40,40,40,14,14,14"]
    simulated = armdyn("simulate", UR5, *gains, "--t-final", "0.5", "-o", "run", cwd=tmp_path)
    assert {path.name for path in (tmp_path / "run").iterdir()} == {"ur5.png", "ur5.csv", "ur5-report.md"}
    assert all(joint in simulated.stdout for joint in JOINTS)
    assert (tmp_path / "run" / "ur5.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    run = np.genfromtxt(tmp_path / "run" / "ur5.csv", delimiter=",", names=True)
    assert run["t"][0] == 0.0 and run["t"][-1] == pytest.approx(0.5)
    assert np.all(np.isfinite(run["q6"])) and np.all(np.isfinite(run["tau1"]))
    errors = np.array([run[f"e{i}"][-1] for i in range(1, 7)])
    assert np.max(np.abs(errors)) < 0.05  # computed torque converges within half a second

    # 3. identification from data the command generates: every estimate within its error bars
    identified = armdyn(
        "identify", UR5, "--generate", "--noise", "0.05", "--period", "4", "--harmonics", "3", "--dt", "0.002",
        "-o", "ur5-estimates.csv", cwd=tmp_path,
    )  # fmt: skip
    assert "cond(W)" in identified.stdout
    estimates = np.genfromtxt(tmp_path / "ur5-estimates.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    assert len(estimates) > 30  # the UR5's base parameters, with friction and armature
    deviation = np.abs(estimates["estimate"] - estimates["model_value"]) / estimates["standard_error"]
    assert np.mean(deviation < 3.0) > 0.97  # about 99.7% of honest 3-sigma intervals hold
