"""Table 3.3.1 in task coordinates (Section 3.5): ``check(arm, task=output)`` over the regular region.

Every row holds on the RR arm (PlanarPosition), the cylindrical arm (ToolPosition, Example 3.5-1), the
PUMA 560 (ToolPose, with friction) and the Panda (ToolPosition, redundant: Lambda); the bounds cover
direct evaluations on fresh random configurations of the region and equal the closed forms where known.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import brentq
from typer.testing import CliRunner

import armdyn as ad
from armdyn import task_space as ts
from armdyn.cli import app
from armdyn.properties import REGION_MAX_CONDITION, check, joint_ranges
from tests.helpers import URDFS

SQUARE_ROWS = {
    "symmetry", "positive definite", "inertia bounds", "norm bounds", "quadratic", "Coriolis bound",
    "Christoffel symmetry", "skew symmetry", "gravity bound", "linearity",
}  # fmt: skip
REDUNDANT_ROWS = {"symmetry", "positive definite", "inertia bounds", "norm bounds", "skew symmetry", "gravity bound"}


def _failing(report: ad.properties.Report) -> list:
    return [row for row in report.rows if not row.holds]


def _fresh(arm: ad.Robot, output: ts.TaskOutput, limit: float, count: int = 300, seed: int = 99) -> np.ndarray:
    """Random configurations of the arm's sampled ranges with cond J below ``limit``, drawn afresh."""
    low, high = np.array(joint_ranges(arm)).T
    q = np.random.default_rng(seed).uniform(low, high, (count, arm.n))
    return q[ts.condition_number(arm, output, q) < limit]


def _counts(report: ad.properties.Report) -> tuple[int, int]:
    kept, rejected = re.search(r"(\d+) of \d+ samples kept, (\d+) rejected", " ".join(report.notes)).groups()
    return int(kept), int(rejected)


def _assert_covers(report: ad.properties.Report, arm: ad.Robot, output: ts.TaskOutput, q: np.ndarray) -> None:
    """Mbar (Lambda), ||Vmbar||, ||Gbar|| (p) at the states q lie within the report's bounds."""
    b, slack = report.bounds, 1e-9
    square = output.jacobian(arm, q[0]).shape[0] == arm.n
    inertia = ts.task_inertia(arm, output, q) if square else ts.operational_inertia(arm, output, q)
    eig = np.linalg.eigvalsh(inertia)
    assert eig.min() >= b["mu1"] * (1 - slack) and eig.max() <= b["mu2"] * (1 + slack)
    ones = np.abs(inertia).sum(axis=-2).max(axis=-1)
    assert ones.min() >= b["m1"] * (1 - 1e-6) and ones.max() <= b["m2"] * (1 + 1e-6)
    if square:
        ydot = np.random.default_rng(7).normal(size=(len(q), arm.n))
        ydot /= np.linalg.norm(ydot, axis=-1, keepdims=True)
        qd = np.linalg.solve(output.jacobian(arm, q), ydot[..., None])[..., 0]
        Vmbar = ts.task_coriolis(arm, output, q, qd)
        assert np.linalg.norm(Vmbar, ord=2, axis=(-2, -1)).max() <= b["vb"] * (1 + slack)
        gravity = ts.task_gravity(arm, output, q)
    else:
        gravity = ts.operational_space(arm, output, q, np.zeros_like(q)).p
    assert np.linalg.norm(gravity, axis=-1).max() <= b["gb"] * (1 + slack)


# ----- the RR arm of Example 3.2-2, tool x, y --------------------------------------------------------
def test_rr_arm_rows_hold_and_the_bounds_are_the_closed_form_extremes_over_the_region() -> None:
    """Mbar = m2 I + m1 A^T A with A = J_elbow J^-1 of rank 1 (K = 1/2 m1 |v_elbow|^2 + 1/2 m2 |ydot|^2), so
    mu1 = m2 exactly; the largest eigenvalue and cond J depend on theta2 alone, and mu2 is the largest
    eigenvalue where cond J reaches max_condition (det J = a1 a2 sin theta2: singular at 0 and pi)."""
    arm, output, limit = ad.models.two_link_planar(2.0, 0.7, 1.0, 0.6), ts.PlanarPosition(), 50.0
    report = check(arm, samples=40, task=output, max_condition=limit)
    assert report.all_hold, _failing(report)
    assert {row.name for row in report.rows} == SQUARE_ROWS
    assert report.units == {"mu1": "kg", "mu2": "kg", "m1": "kg", "m2": "kg", "vb": "N/(m/s)^2", "gb": "N"}
    assert_allclose(report.bounds["mu1"], 0.7, rtol=1e-9)

    def cond(theta2: float) -> float:
        return float(ts.condition_number(arm, output, [0.3, theta2]))

    def largest(theta2: float) -> float:
        return float(np.linalg.eigvalsh(ts.task_inertia(arm, output, [0.3, theta2]))[-1])

    grid = np.linspace(1e-3, np.pi - 1e-3, 4001)
    best = grid[np.argmin([cond(t) for t in grid])]
    edges = [brentq(lambda t: cond(t) - limit, 1e-9, best), brentq(lambda t: cond(t) - limit, best, np.pi - 1e-9)]
    exact = max(largest(t) for t in edges)
    assert max(largest(t) for t in grid if cond(t) < limit) <= exact  # the supremum is on the region's edge
    assert_allclose(report.bounds["mu2"], exact, rtol=1e-6)
    _assert_covers(report, arm, output, _fresh(arm, output, limit))
    kept, rejected = _counts(report)
    assert kept + rejected == 40 and rejected > 0  # a whole turn of theta2 reaches both singularities


# ----- the cylindrical arm of Exercise 3.2-3, tool position (Example 3.5-1) -------------------------
J_BASE, M1, M2 = 0.8, 2.0, 0.5


def _example_3_5_1(q: np.ndarray) -> np.ndarray:
    """Mbar = [[m2 + Jb s^2, -Jb s c, 0], [-Jb s c, m2 + Jb c^2, 0], [0, 0, m1 + m2]], Jb = J / r^2."""
    s, c, Jb = np.sin(q[..., 0]), np.cos(q[..., 0]), J_BASE / q[..., 2] ** 2
    Mbar = np.zeros((*q.shape[:-1], 3, 3))
    Mbar[..., 0, 0], Mbar[..., 1, 1], Mbar[..., 2, 2] = M2 + Jb * s**2, M2 + Jb * c**2, M1 + M2
    Mbar[..., 0, 1] = Mbar[..., 1, 0] = -Jb * s * c
    return Mbar


def test_cylindrical_arm_bounds_are_example_3_5_1_eigenvalues() -> None:
    """The eigenvalues of Example 3.5-1's Mbar are m2, m2 + J/r^2 and m1 + m2; cond J = max(r, 1) / min(r, 1)."""
    arm, output = ad.models.cylindrical(J_BASE, M1, M2), ts.ToolPosition()
    limits = [(-np.pi, np.pi), (-0.5, 0.5), (0.5, 1.5)]  # cond J <= 2: every sample is regular
    report = check(arm, samples=30, limits=limits, task=output)
    assert report.all_hold, _failing(report)
    assert {row.name for row in report.rows} == SQUARE_ROWS
    assert _counts(report) == (30, 0)
    assert_allclose(report.bounds["mu1"], M2, rtol=1e-9)
    assert_allclose(report.bounds["mu2"], M2 + J_BASE / 0.5**2, rtol=1e-6)  # at r = 0.5
    assert_allclose(report.bounds["gb"], (M1 + M2) * 9.8, rtol=1e-9)  # Gbar = J^-T G = [0, 0, (m1 + m2) g]
    q = np.random.default_rng(5).uniform(*np.array(limits).T, (50, 3))
    assert_allclose(ts.task_inertia(arm, output, q), _example_3_5_1(q), rtol=1e-9, atol=1e-12)
    eig = np.linalg.eigvalsh(_example_3_5_1(q))
    assert eig.min() >= report.bounds["mu1"] * (1 - 1e-9) and eig.max() <= report.bounds["mu2"] * (1 + 1e-9)
    _assert_covers(report, arm, output, q)


def test_cylindrical_arm_region_stops_at_the_condition_limit() -> None:
    """Over r in [0, 1], cond J = 1/r: the region is r > 1/max_condition, so mu2 = m2 + J max_condition^2, and
    the samples with r <= 1/max_condition are rejected (and counted in the notes)."""
    arm, output, limit = ad.models.cylindrical(J_BASE, M1, M2), ts.ToolPosition(), 20.0
    report = check(arm, samples=60, task=output, max_condition=limit)
    assert report.all_hold, _failing(report)
    assert report.max_condition == limit and report.task == "ToolPosition()"
    assert_allclose(report.bounds["mu1"], M2, rtol=1e-9)
    assert_allclose(report.bounds["mu2"], M2 + J_BASE * limit**2, rtol=1e-6)
    low, high = np.array(report.ranges).T
    r = np.random.default_rng(0).uniform(low, high, (60, 3))[:, 2]  # the configurations check drew (seed 0)
    assert _counts(report) == (int(np.sum(r > 1 / limit)), int(np.sum(r <= 1 / limit)))
    q = _fresh(arm, output, limit)
    assert q[:, 2].min() > 1 / limit
    _assert_covers(report, arm, output, q)


# ----- a square pose output with friction, a redundant output ----------------------------------------
def test_puma_tool_pose_rows_hold_with_friction_in_output_units() -> None:
    arm, output = ad.models.puma560(), ts.ToolPose()
    report = check(arm, samples=12, task=output)
    assert report.all_hold, _failing(report)
    assert {row.name for row in report.rows} == (SQUARE_ROWS - {"Christoffel symmetry"}) | {"friction bound",
                                                                                             "dissipation"}  # fmt: skip
    notes = " ".join(report.notes)
    assert "not a Christoffel form" in notes and "mixes units" in notes
    assert set(report.units.values()) == {"output units"}
    assert report.bounds["v"] > 0 and report.bounds["k"] > 0
    q = _fresh(arm, output, REGION_MAX_CONDITION, count=40)
    rng = np.random.default_rng(3)
    ydot = rng.normal(size=(len(q), 6)) * rng.uniform(0, 5, (len(q), 1))
    F = ts.task_friction(arm, output, q, np.linalg.solve(output.jacobian(arm, q), ydot[..., None])[..., 0])
    rhs = report.bounds["v"] * np.linalg.norm(ydot, axis=-1) + report.bounds["k"]
    assert np.all(np.linalg.norm(F, axis=-1) <= rhs)


def test_a_non_christoffel_task_coriolis_matrix_fails_the_skew_row(monkeypatch: pytest.MonkeyPatch) -> None:
    """Vmbar + u w^T with w orthogonal to ydot: the same Vmbar ydot, but Mbar_dot - 2 Vmbar is not skew (and
    likewise for mu_x of a redundant output)."""

    def perturbed(function: object, square: bool) -> object:
        def call(arm: ad.Robot, output: ts.TaskOutput, q: np.ndarray, qd: np.ndarray, **options: object) -> object:
            result = function(arm, output, q, qd, **options)
            matrix = result if square else result[0]
            ydot = np.einsum("...ij,...j->...i", output.jacobian(arm, q), qd)
            w = np.ones_like(ydot) - (np.sum(ydot, -1) / np.sum(ydot * ydot, -1))[..., None] * ydot
            u = np.roll(ydot, 1, axis=-1) * np.abs(matrix).max(axis=(-2, -1))[..., None]
            matrix = matrix + np.einsum("...i,...j->...ij", u, w)
            return matrix if square else (matrix, result[1])

        return call

    arm = ad.models.puma560()
    assert check(arm, samples=8, task=ts.ToolPose(), only="skew").all_hold
    assert check(arm, samples=8, task=ts.ToolPosition(), only="skew").all_hold
    monkeypatch.setattr(ts, "task_coriolis", perturbed(ts.task_coriolis, True))
    monkeypatch.setattr(ts, "operational_coriolis", perturbed(ts.operational_coriolis, False))
    assert not check(arm, samples=8, task=ts.ToolPose(), only="skew").row("skew symmetry").holds
    assert not check(arm, samples=8, task=ts.ToolPosition(), only="skew").row("skew symmetry").holds


def _panda() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        locked = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
        return ad.load_urdf(URDFS["panda"], locked=locked).without_friction()


@pytest.mark.slow
def test_panda_tool_position_lambda_rows_hold_and_square_only_rows_are_skipped_with_a_note() -> None:
    arm, output = _panda(), ts.ToolPosition()
    report = check(arm, samples=16, task=output)
    assert report.all_hold, _failing(report)
    assert {row.name for row in report.rows} == REDUNDANT_ROWS
    assert report.row("inertia bounds").statement.startswith("mu1 I <= Lambda(q)")
    assert "Lambda_dot - 2 mu_x" in report.row("skew symmetry").statement
    notes = " ".join(report.notes)
    assert "redundant" in notes and "defined for square outputs (m = n) only" in notes
    assert "the Coriolis, friction and linearity rows are skipped" in notes
    _assert_covers(report, arm, output, _fresh(arm, output, REGION_MAX_CONDITION, count=30))
    inertia_only = check(arm, samples=8, task=output, only="inertia")
    assert "skipped" not in " ".join(inertia_only.notes)
    two = check(arm, samples=8, task=output, only=("inertia", "linearity", "friction"))
    assert "the friction and linearity rows are skipped" in " ".join(two.notes)


def test_camera_output_is_labelled_in_image_units() -> None:
    """Example A.3-3: the RR arm seen from overhead, y = image coordinates (m = n = 2)."""
    pose = np.array([[1.0, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]])
    arm, output = ad.models.two_link_planar(), ts.Camera(800.0, pose)
    report = check(arm, samples=16, task=output, only=("inertia", "gravity"))
    assert report.all_hold, _failing(report)
    assert report.units["mu1"] == "J s^2/u^2" and report.units["gb"] == "J/u"
    assert any("image unit" in note for note in report.notes)


# ----- the report, the defaults, the errors ----------------------------------------------------------
def test_the_report_names_the_output_and_region_and_joint_space_is_unchanged() -> None:
    from rich.console import Console

    arm = ad.models.two_link_planar()
    task = check(arm, samples=10, task=ts.PlanarPosition())
    title = task.title()
    assert "in task coordinates PlanarPosition(axes=(0, 1))" in title and "cond J < 1000" in title
    assert task.max_condition == REGION_MAX_CONDITION
    console = Console(width=200, record=True)
    console.print(task.table())
    assert "task coordinates" in console.export_text()
    _, rows = task.records()
    assert len(rows) == len(task.rows) and "kg" in rows[2][3]
    assert any("passivity is not checked" in note for note in task.notes)
    joint = check(arm, samples=10)
    assert joint.task is None and joint.max_condition is None
    assert joint.title().startswith("Table 3.3.1 for two_link_planar, joint ranges")
    assert "passivity" in {row.name for row in joint.rows}


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"task": "position"}, "task must be a task output of armdyn.task_space .*got str"),
        ({"task": ad.models.scara()}, "task must be a task output .*got Robot"),
        ({"task": ts.PlanarPosition(), "max_condition": 1.0}, "max_condition must be greater than 1"),
        ({"task": ts.PlanarPosition(), "max_condition": 0.5}, "max_condition must be greater than 1"),
        ({"task": ts.PlanarPosition(), "max_condition": 1e9}, "at most 1e\\+08"),
        ({"task": ts.PlanarPosition(), "max_condition": np.nan}, "max_condition must be finite"),
        ({"task": ts.PlanarPosition(), "max_condition": "big"}, "max_condition must be a number"),
        ({"task": ts.PlanarPosition(), "max_condition": True}, "max_condition must be a number"),
        ({"max_condition": 100.0}, "max_condition applies to task coordinates only"),
        ({"task": ts.ToolPose()}, "6 rows, more than the 2 joints"),
        ({"task": ts.PlanarPosition(), "limits": [(-1, 1), (0, 0)]}, r"only 0 of 20 sampled .* singular"),
        ({"task": ts.PlanarPosition(), "limits": [(-1, 1), (0, 1e-4)]}, r"only 0 of 20 .*max_condition = 1000"),
    ],
)
def test_task_errors_are_model_errors_that_say_why(options: dict, message: str) -> None:
    with pytest.raises(ad.ModelError, match=message):
        check(ad.models.two_link_planar(), samples=20, **options)


# ----- the command line ------------------------------------------------------------------------------
@pytest.mark.slow
def test_check_command_in_task_coordinates(tmp_path: object) -> None:
    runner = CliRunner()
    table = tmp_path / "task.md"
    args = ["check", "two_link_planar", "--task", "planar", "--samples", "12", "--limits=-pi/2:pi/2", "-o", table]
    result = runner.invoke(app, [str(arg) for arg in args])
    assert result.exit_code == 0, result.output
    assert "all properties hold" in result.stdout and "in task coordinates of PlanarPosition" in result.stdout
    text = table.read_text(encoding="utf-8")
    assert "in task coordinates PlanarPosition(axes=(0, 1))" in text and "kg" in text
    assert "Example 3.3-1" not in result.stdout  # the book's joint-space values are not task-space references
    narrow = runner.invoke(app, ["check", "two_link_planar", "--task", "planar", "--samples", "8",
                                 "--max-condition", "5"])  # fmt: skip
    assert narrow.exit_code == 0, narrow.output
    assert "cond J(q) < max_condition = 5," in narrow.stdout
    pose = runner.invoke(app, ["check", "puma560", "--task", "pose", "--samples", "6"])
    assert pose.exit_code == 0, pose.output
    assert "[v; w]" in pose.stdout  # the notes print as written, not as rich markup
    for argv, fragment in [
        (["--task", "nosuch"], "--task must be one of position, pose, planar, got 'nosuch'"),
        (["--max-condition", "10"], "--max-condition applies to task coordinates only"),
        (["--task", "position"], "3 rows, more than the 2 joints"),
        (["--task", "planar", "--max-condition", "1"], "max_condition must be greater than 1"),
    ]:
        failed = runner.invoke(app, ["check", "two_link_planar", "--samples", "8", *argv])
        lines = failed.stderr.strip().splitlines()
        assert failed.exit_code == 2 and len(lines) == 1 and fragment in lines[0], failed.stderr
