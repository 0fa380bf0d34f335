"""armdyn show --actuators and armdyn simulate --actuators: the arm through its drives from the command line."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest

from tests.helpers import assert_one_error_line, invoke


def test_show_the_puma_motors_and_representative_hydraulic_drives(tmp_path: Path) -> None:
    """The PUMA's DC drives with their electrical (L/R_a) and mechanical time constants; a hydraulic arm's valves
    with the oil column's frequency; the tables also written to a file."""
    motors = invoke("show", "puma560", "--actuators", "dc", "-o", tmp_path / "puma.md")
    assert motors.exit_code == 0, motors.output
    text = " ".join(motors.output.split())
    assert "DC drives" in text and "motor q1" in text and "0.9524" in text  # L / R_a = 2 mH / 2.1 ohm, in ms
    assert "DC drives" in (tmp_path / "puma.md").read_text()
    valves = invoke("show", "polar_rp", "--actuators", "hydraulic")
    assert valves.exit_code == 0, valves.output
    assert "Hydraulic drives" in valves.output and "valve theta" in valves.output and "oil column" in valves.output
    flexible = invoke("show", "two_link_planar", "--actuators", "flexible")
    assert flexible.exit_code == 0 and "shaft K" in flexible.output


@pytest.mark.slow
@pytest.mark.parametrize(
    ("arm", "kind", "extra"),
    [
        ("puma560", "dc", ["--controller", "pid", "--ki", "20"]),
        ("puma560", "dc", ["--controller", "computed-torque"]),
        ("two_link_planar", "flexible", []),
        ("polar_rp", "hydraulic", []),
    ],
)
def test_simulate_through_the_drives(tmp_path: Path, arm: str, kind: str, extra: list[str]) -> None:
    """Each drive kind under its law: the report, the drives' table, the CSV with the inputs and drive states,
    and a figure; the tracking error after 1 s is that of the law (small for computed torque)."""
    result = invoke("simulate", arm, "--actuators", kind, *extra, "--t-final", "1.5", "-o", tmp_path)
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "drives (" in text and "RK4 steps per sample" in text
    rows = list(csv.reader((tmp_path / f"{arm}.csv").open()))
    header, table = rows[0], np.array(rows[1:], dtype=float)
    assert "v1" in header and any(re.fullmatch(r"(i|PL|qM)\d+", name) for name in header)  # named as tau1, v1
    errors = table[table[:, 0] >= 1.0][:, [k for k, name in enumerate(header) if re.fullmatch(r"e\d+", name)]]
    bound = 2e-3 if "computed-torque" in extra else 0.1
    assert np.abs(errors).max() < bound
    assert (tmp_path / f"{arm}.png").stat().st_size > 10_000
    states = {"dc": r"i\d+", "flexible": r"qM\d+", "hydraulic": r"PL\d+"}[kind]
    assert any(re.fullmatch(states, name) for name in header) and "max |P_L| (MPa)" in text


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["simulate", "puma560", "--actuators", "pneumatic"], "--actuators must be one of"),
        (["simulate", "puma560", "--actuators", "dc", "--controller", "pd-gravity"], "must be pid or computed-torque"),
        (["simulate", "polar_rp", "--actuators", "hydraulic", "--controller", "computed-torque"], "needs dc drives"),
        (["simulate", "puma560", "--actuators", "dc", "--method", "rk45"], "do not apply with --actuators"),
        (["simulate", "puma560", "--actuators", "dc", "--task", "position"], "do not apply with --actuators"),
        (["simulate", "puma560", "--actuators", "dc", "--kp", "-1"], "kp"),
        (["show", "puma560", "--actuators", "steam"], "--actuators must be one of"),
    ],
)
def test_bad_actuator_options_are_one_error_line(arguments: list[str], message: str) -> None:
    result = invoke(*arguments)
    assert_one_error_line(result, message)
