"""armdyn simulate --task and armdyn task for a redundant arm: control in task coordinates from the command line."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import assert_one_error_line, invoke


@pytest.mark.slow
def test_simulate_a_planar_arm_on_a_task_circle(tmp_path: Path) -> None:
    """The RR arm's tool on a circle under task-space computed torque: the report's rows are the task coordinates,
    the CSV carries y, y_d and the task error, the figure is the task path, and the error is small after 1 s."""
    result = invoke("simulate", "two_link_planar", "--task", "planar", "--trajectory", "circle", "--amplitude", "0.2",
                    "--kp", "400", "--kv", "40", "--t-final", "1.5", "--q0", "0.3,1.2", "-o", tmp_path)  # fmt: skip
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "task-space computed torque on PlanarPosition" in text and "max |error| after 1 s (m)" in text
    rows = list(csv.reader((tmp_path / "two_link_planar.csv").open()))
    header, last = rows[0], np.array(rows[-1], dtype=float)
    errors = [header.index(f"task_e{i}") for i in (1, 2)]
    assert np.abs(last[errors]).max() < 1e-4
    assert (tmp_path / "two_link_planar.png").stat().st_size > 10_000


@pytest.mark.slow
def test_simulate_a_pose_line_and_an_operational_space_task(tmp_path: Path) -> None:
    """The Stanford arm's tool pose on a line with a turn (computed torque, m = n = 6), and the PUMA's tool point
    on a line under operational-space control (m = 3 < n = 6, the start as the null-space posture)."""
    pose = invoke("simulate", "stanford", "--q0", "0.3,-0.5,0.4,0.3,0.6,0.2", "--task", "pose", "--trajectory",
                  "line", "--move", "0.05,0,0.05", "--turn", "0,0,0.3", "--kp", "400", "--kv", "40", "--t-final",
                  "1.2", "--csv", tmp_path / "s.csv")  # fmt: skip
    assert pose.exit_code == 0, pose.output
    assert "rz" in pose.output
    point = invoke("simulate", "puma560", "--task", "position", "--controller", "operational-space", "--trajectory",
                   "line", "--t-final", "0.5", "--plot", tmp_path / "p.png")  # fmt: skip
    assert point.exit_code == 0, point.output
    assert "operational-space control on ToolPosition()" in " ".join(point.output.split())


def test_task_prints_lambda_for_a_redundant_output() -> None:
    result = invoke("task", "puma560", "-c", "position", "--q", "qn")
    assert result.exit_code == 0, result.output
    assert "Lambda = (J M^-1 J^T)^-1" in result.output and "m = 3 < n = 6" in result.output


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["--task", "sideways"], ["--task must be one of position, pose, planar"]),
        (["--task", "planar", "--trajectory", "sine"], ["--trajectory with --task must be line, circle or none"]),
        (["--task", "planar", "--controller", "pid"], ["--controller with --task must be computed-torque"]),
        (["--task", "planar", "--kp", "1,2"], ["--kp takes one number with --task"]),
        (["--task", "planar", "--trajectory", "line", "--move", "1,2"], ["--move takes three numbers"]),
        (["--task", "planar", "--period", "0.01"], ["--period and --torque-limit apply to joint-space control"]),
        (["--task", "planar", "--frequency", "0"], ["--frequency must be positive"]),
        (["--task", "position"], ["3 rows, more than the 2 joints"]),
    ],
)
def test_simulate_task_refuses_bad_options(args: list[str], fragments: list[str]) -> None:
    result = invoke("simulate", "two_link_planar", "--q0", "0.3,1.2", "--t-final", "0.01", *args)
    assert_one_error_line(result, *fragments)


def test_derive_in_task_coordinates_prints_example_3_5_1(tmp_path: Path) -> None:
    """armdyn derive cylindrical --task position: Mbar as the book writes it (J s1^2 / q3^2 + m2 ...), in LaTeX too."""
    result = invoke("derive", "cylindrical", "--task", "position")
    assert result.exit_code == 0, result.output
    assert "Mbar(q)" in result.output and "m₁ + m₂" in result.output
    latex = invoke("derive", "cylindrical", "--task", "position", "--latex", "-o", tmp_path / "mbar.tex")
    assert latex.exit_code == 0, latex.output
    assert "\\bar{M}(q)" in (tmp_path / "mbar.tex").read_text()
    assert_one_error_line(invoke("derive", "puma560", "--task", "pose"), "ToolPose is not supported")
    assert_one_error_line(invoke("derive", "cylindrical", "--task", "position", "--code", "c"), "--task and --code")


def test_task_at_a_singular_pose_advises_the_commands_own_options() -> None:
    """Before, the advice named the Python options (max_condition, damping=...) and the command had no
    --max-condition; now it names --max-condition and --damping, and both work (oracle: the damped value)."""
    import numpy as np

    import armdyn as ad
    from armdyn import task_space

    singular = invoke("task", "puma560", "--q", "qz", "--coordinates", "pose")
    assert singular.exit_code == 2
    assert "raise --max-condition, or give --damping VALUE" in singular.output
    assert "max_condition =" in singular.output and "damping=..." not in singular.output
    damped = invoke("task", "puma560", "--q", "qz", "--coordinates", "pose", "--damping", "0.01")
    assert damped.exit_code == 0, damped.output
    expected = task_space.task_gravity(ad.models.puma560(), task_space.ToolPose(), np.zeros(6), damping=0.01)
    assert f"{expected[2]:.6g}"[:5] in damped.output
    looser = invoke("task", "puma560", "--q", "qz", "--coordinates", "pose", "--max-condition", "1e14")
    assert looser.exit_code == 2 and "exceeds max_condition = 1e+14" in looser.output  # cond J is 1e17 there
