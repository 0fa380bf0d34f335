"""Small things a newcomer trips on, each with what it should have been."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from tests.helpers import invoke


def test_a_misspelt_name_suggests_the_right_one() -> None:
    with pytest.raises(AttributeError, match="did you mean 'simulate'"):
        ad.simulte  # noqa: B018
    with pytest.raises(AttributeError, match="did you mean 'load_urdf'"):
        ad.lod_urdf  # noqa: B018


def test_a_runs_count_that_is_not_an_integer_is_a_model_error() -> None:
    """The README promises ModelError for bad input: ArgumentError is one (and a TypeError)."""
    from armdyn.study import Study

    study = Study(ad.models.two_link_planar(), control.PDGravity(10.0, 1.0), t_final=0.2,
                  spec="max-error-after-0.1s<1e-3")  # fmt: skip
    with pytest.raises(ad.ModelError, match=r"runs must be an integer, got 1000\.0"):
        study.run(1e3)  # type: ignore[arg-type]


def test_the_csv_of_a_run_with_drives_names_its_columns_as_the_others(tmp_path: Path) -> None:
    """Before, the drives' states were named "i q1" (with a space) beside tau1 and v1; the oracle for the
    values is the drive record itself."""
    driven = ad.actuators.puma560_with_drives()
    run = ad.simulate(driven, control.DrivePID(20.0, 0.5), tr.Sinusoid(0.05, 0.5), t_final=0.05)
    run.to_csv(tmp_path / "run.csv")
    with open(tmp_path / "run.csv", newline="") as handle:
        rows = list(csv.reader(handle))
    header = rows[0]
    assert not [name for name in header if " " in name]
    assert {"tau1", "v1", "i1", "i6"} <= set(header)
    column = np.array([float(row[header.index("i3")]) for row in rows[1:]])
    np.testing.assert_array_equal(column, run.drives.x[:, run.drives.names.index("i q3")])


def test_show_prints_zero_friction_as_zero_not_minus_zero() -> None:
    shown = invoke("show", "two_link_planar")
    assert shown.exit_code == 0 and "-0 " not in shown.output and "/ -0" not in shown.output


def test_the_drive_report_names_the_current_limit_beside_the_peak_current() -> None:
    shown = invoke("simulate", "puma560", "--actuators", "dc", "--t-final", "0.2")
    assert shown.exit_code == 0, shown.output
    assert "i limit (A)" in shown.output
    limits = [drive.current_limit for drive in ad.actuators.puma560_with_drives().drives]
    line = next(line for line in shown.output.splitlines() if "motor q1" in line)
    assert f" {limits[0]:.4g} " in line
