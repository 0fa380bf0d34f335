"""Table 3.3.1: the properties hold on every arm, fail on broken ones, and the bounds are exact."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import minimize_scalar
from typer.testing import CliRunner

import armdyn as ad
from armdyn.cli import app
from armdyn.properties import check, inertia_bounds, joint_ranges
from tests.helpers import ROBOTS, URDFS
from tests.strategies import random_robot

BOOK_RANGE = [(-np.pi / 2, np.pi / 2)] * 2  # Example 3.3-1: |theta_i| <= pi/2


@pytest.mark.slow
@pytest.mark.parametrize("name", ad.models.names())
def test_every_built_in_arm_has_the_properties(name: str) -> None:
    report = check(ad.models.load(name), samples=100)
    assert report.all_hold, [row for row in report.rows if not row.holds]
    assert set(report.bounds) >= {"mu1", "mu2", "vb", "gb", "v", "k"}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_trees_have_the_properties(seed: int) -> None:
    report = check(random_robot(seed, 5), samples=60)
    assert report.all_hold, [row for row in report.rows if not row.holds]


def test_rr_arm_bounds_are_the_exact_extremes_of_example_3_3_1() -> None:
    arm = ad.models.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
    report = check(arm, limits=BOOK_RANGE)
    b = report.bounds
    # exact extremes from the closed form: M = [[3 + 2 c2, 1 + c2], [1 + c2, 1]], extremes at theta2 = 0
    assert_allclose(b["mu1"], 3 - np.sqrt(8), atol=1e-6)
    assert_allclose(b["mu2"], 3 + np.sqrt(8), atol=1e-6)
    assert_allclose([b["m1"], b["m2"]], [4.0, 7.0], atol=1e-6)  # the book's ||M||_1 bounds, both attained
    assert_allclose(b["gb"], 9.8 * np.sqrt(10.0), atol=1e-6)  # ||G|| largest at theta = 0
    # vb: the largest 2-norm of Vm = s2 [[-x2, -(x1 + x2)], [x1, 0]] over unit x, at |s2| = 1

    def vm_norm(t: float) -> float:
        x1, x2 = np.cos(t), np.sin(t)
        return -np.linalg.norm([[-x2, -(x1 + x2)], [x1, 0.0]], 2)

    exact_vb = -minimize_scalar(vm_norm, bounds=(0, np.pi), method="bounded", options={"xatol": 1e-12}).fun
    grid = max(-vm_norm(t) for t in np.linspace(0, np.pi, 20001))
    assert exact_vb >= grid - 1e-9
    assert_allclose(b["vb"], exact_vb, atol=1e-6)
    # inside the book's conservative bounds: ||M||_1 in [4, 7], mu2 <= 7, gb <= (m1 + m2) g a1 + 2 m2 g a2
    assert b["m1"] >= 4.0 and b["m2"] <= 7.0 and b["mu2"] <= 7.0
    assert b["gb"] <= 2 * 9.8 + 2 * 9.8
    assert inertia_bounds(arm, limits=BOOK_RANGE) == pytest.approx((3 - np.sqrt(8), 3 + np.sqrt(8)), abs=1e-6)


def _same_arm(cls: type, arm: ad.Robot) -> ad.Robot:
    """The arm as an instance of a test subclass of Robot (a Robot never changes once made)."""
    options = {"name": arm.name, "gravity": arm.gravity, "base": arm.base, "tool": arm.tool}
    return cls(arm.links, tool_link=arm.tool_link, configurations=arm.configurations, **options)


class _NotChristoffel(ad.Robot):
    def coriolis_matrix(self, q: np.ndarray, qd: np.ndarray, out: None = None) -> np.ndarray:
        """Vm + u w^T with w orthogonal to qd: the same V = Vm qd, but not the Christoffel form."""
        qd = np.asarray(qd, dtype=float)
        ones = np.ones_like(qd)
        w = ones - (np.sum(ones * qd, -1) / (np.sum(qd * qd, -1) + 1e-300))[..., None] * qd
        return super().coriolis_matrix(q, qd) + np.einsum("...i,...j->...ij", np.roll(qd, 1, axis=-1), w)


class _Indefinite(ad.Robot):
    def inertia_matrix(self, q: np.ndarray, out: None = None) -> np.ndarray:
        return -super().inertia_matrix(q)  # forced past validation, in this test only


def test_a_non_christoffel_factorization_fails_the_skew_row() -> None:
    arm = _same_arm(_NotChristoffel, ad.models.puma560())
    report = check(arm, samples=40, only=("coriolis", "skew"))
    assert not report.row("skew symmetry").holds
    assert not report.all_hold


def test_an_indefinite_inertia_fails_the_positive_definite_row() -> None:
    arm = _same_arm(_Indefinite, ad.models.scara())
    report = check(arm, samples=30, only=("inertia",))
    assert not report.row("positive definite").holds
    assert not report.all_hold


def test_prismatic_bounds_are_given_over_the_range() -> None:
    report = check(ad.models.polar_rp(m=1.0), samples=80)
    assert report.all_hold
    assert any("depend on q" in note for note in report.notes)
    assert report.ranges[1] == (0.1, 1.5)
    assert_allclose(report.bounds["mu2"], 1.5**2, atol=1e-6)  # M = diag(m r^2, m), r <= 1.5 m
    assert_allclose(report.bounds["mu1"], 0.1**2, atol=1e-6)


def test_check_command() -> None:
    result = CliRunner().invoke(app, ["check", "two_link_planar", "--samples", "50"])
    assert result.exit_code == 0 and "all properties hold" in result.output and "mu1" in result.output


@pytest.mark.slow
def test_identify_command(tmp_path: object) -> None:
    from tests.helpers import exciting

    arm = ad.models.puma560()
    q, qd, qdd = exciting(6, 400)
    tau = arm.inverse_dynamics(q, qd, qdd)
    header = ",".join(f"{p}{i + 1}" for p in ("q", "qd", "qdd", "tau") for i in range(6))
    path = tmp_path / "samples.csv"
    np.savetxt(path, np.hstack([q, qd, qdd, tau]), delimiter=",", header=header, comments="")
    result = CliRunner().invoke(app, ["identify", "puma560", str(path)])
    assert result.exit_code == 0, result.output
    assert "Identified base parameters" in result.output


# ----- arguments --------------------------------------------------------------------------
def test_check_only_unknown_name_is_an_error_and_a_bare_string_is_one_name() -> None:
    arm = ad.models.two_link_planar()
    with pytest.raises(ad.ModelError, match=r"unknown groups \['intertia'\].*'inertia', 'coriolis', 'skew'"):
        check(arm, samples=10, only=["intertia"])
    with pytest.raises(ad.ModelError, match="unknown groups"):
        check(arm, samples=10, only="intertia")
    with pytest.raises(ad.ModelError, match="at least one group"):
        check(arm, samples=10, only=[])
    one = check(arm, samples=10, only="inertia")  # one name, not the letters i, n, e, r, t, i, a
    assert [row.name for row in one.rows] == ["symmetry", "positive definite", "inertia bounds", "norm bounds"]
    assert set(one.bounds) == {"mu1", "mu2", "m1", "m2"}
    two = check(arm, samples=10, only=("gravity", "skew"))
    assert {row.name for row in two.rows} == {"gravity bound", "skew symmetry"}


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda arm: check("puma560"), TypeError, "arm must be an armdyn Robot"),
        (lambda arm: check(None), TypeError, "arm must be an armdyn Robot"),
        (lambda arm: check(arm, samples="300"), TypeError, "samples must be an integer"),
        (lambda arm: check(arm, samples=30.5), TypeError, "samples must be an integer"),
        (lambda arm: check(arm, samples=None), TypeError, "samples must be an integer"),
        (lambda arm: check(arm, samples=2), ad.ModelError, "samples must be at least 4"),
        (lambda arm: check(arm, seed="a"), TypeError, "seed must be an integer"),
        (lambda arm: check(arm, seed=-1), ad.ModelError, "seed must be at least 0"),
        (lambda arm: check(arm, only=3), TypeError, "only must be a group name"),
        (lambda arm: check(arm, only={"inertia": True}), TypeError, "only must be a group name"),
        (lambda arm: check(arm, only=[None]), ad.ModelError, "unknown groups"),
        (lambda arm: check(arm, limits="ab"), ad.ModelError, "limits must be"),
        (lambda arm: check(arm, limits={"a": 1}), ad.ModelError, "limits must be"),
        (lambda arm: check(arm, limits=5), ad.ModelError, "limits must"),
        (lambda arm: check(arm, limits=[(0, 1)]), ad.ModelError, r"limits must be 2 finite \(lower, upper\) pairs"),
        (lambda arm: check(arm, limits=[(1, 0), (0, 1)]), ad.ModelError, "lower <= upper"),
        (lambda arm: check(arm, limits=[(0, np.nan), (0, 1)]), ad.ModelError, "limits must be finite"),
        (lambda arm: inertia_bounds(arm, samples="many"), TypeError, "samples must be an integer"),
        (lambda arm: inertia_bounds([1, 2]), TypeError, "arm must be an armdyn Robot"),
        (lambda arm: joint_ranges(arm, prismatic_span="x"), ad.ModelError, "prismatic_span must be"),
        (lambda arm: joint_ranges(arm, prismatic_span=0), ad.ModelError, "prismatic_span must be one positive"),
        (lambda arm: joint_ranges({}, None), TypeError, "arm must be an armdyn Robot"),
    ],
)
def test_properties_wrong_types_name_the_argument(call: object, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        call(ad.models.two_link_planar())


# ----- passivity: the energy balance on real arms ----------------------------------------------------------
EXAMPLE_ARMS = {
    "panda": "panda_description/urdf/panda.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "z1": "z1_description/urdf/z1.urdf",
    "xarm7": "xarm_description/urdf/xarm7.urdf",
    "so100": "so_arm_description/urdf/so100.urdf",
}


def _with_viscous(arm: ad.Robot, viscous: float) -> ad.Robot:
    """The arm with every joint's viscous coefficient set to ``viscous``, a negative one forced past the
    validation (which refuses it as not dissipative), in this test only."""
    links = [dataclasses.replace(link) for link in arm.links]
    for link in links:
        object.__setattr__(link, "viscous", viscous)
    return arm.replace(links)


class _Injecting(ad.Robot):
    def forward_dynamics(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, out: None = None) -> np.ndarray:
        """The accelerations under tau + 0.5 qd: a hidden drive that feeds energy in (0.5 qd^T qd W)."""
        return super().forward_dynamics(q, qd, np.asarray(tau) + 0.5 * np.asarray(qd))


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(EXAMPLE_ARMS))
def test_check_command_holds_on_example_robot_data_arms(name: str) -> None:
    """The 9-joint Panda, Kinova, Unitree Z1, xArm7 and SO-100 (before: passivity NO, or the command died on
    'qd holds values of 1e+15' for the last three): every row is evaluated and holds, exit status 0."""
    path = ROBOTS / EXAMPLE_ARMS[name]
    if not path.is_file():
        pytest.skip("example-robot-data is not installed")
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 0, result.output
    assert "all properties hold" in result.stdout and "passivity" in result.stdout and "NO" not in result.stdout


@pytest.mark.slow
def test_check_holds_on_the_seven_joint_panda_of_the_model_page() -> None:
    if not URDFS["panda"].is_file():
        pytest.skip("example-robot-data is not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        panda7 = ad.load_urdf(URDFS["panda"], tool_link="panda_hand_tcp",
                              locked={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02})  # fmt: skip
    report = check(panda7)
    assert report.all_hold, [row for row in report.rows if not row.holds]
    lossless, friction = report.row("passivity"), report.row("passivity with friction")
    assert lossless.worst < 1e-9  # before: 4.8e-6 from fixed-step RK4, reported as a violation
    assert friction.worst < 0  # the URDF's damping dissipates: H(T) - H(0) - W = - dissipated work < 0


def test_passivity_dissipated_work_is_the_closed_form_and_a_negative_viscous_law_fails() -> None:
    """One joint (the RR arm with its elbow locked) under tau = M A w^2 cos(w t) + F + G moves as
    q0 + A (1 - cos w t) exactly, so the work friction c qd dissipates over 1 s is c A^2 w^2 / 2
    (A = 0.3 rad, w = 2 pi): the row's margin H(T) - H(0) - W is minus that, and for c < 0 (energy
    injected) it is positive and the row fails, while the lossless row still holds."""
    rr = ad.models.two_link_planar()
    one = rr.reduced({rr.joint_names[1]: 0.3})
    exact = 0.5 * 0.3**2 * (2 * np.pi) ** 2 / 2
    passive = check(_with_viscous(one, 0.5), only="passivity")
    assert passive.all_hold
    assert_allclose(passive.row("passivity with friction").worst, -exact, rtol=1e-8)
    injecting = check(_with_viscous(one, -0.5), only="passivity")
    assert injecting.row("passivity").holds  # the arm itself, without friction, is passive
    row = injecting.row("passivity with friction")
    assert not row.holds and not injecting.all_hold
    assert_allclose(row.worst, exact, rtol=1e-8)
    assert "dissipated -0.8883 J" in row.how


def test_passivity_fails_on_a_negative_viscous_law_of_a_six_joint_arm() -> None:
    """The issue's case on a full arm: the PUMA 560 with viscous friction -0.2 N m s/rad on every joint."""
    report = check(_with_viscous(ad.models.puma560(), -0.2), only="passivity")
    assert not report.row("passivity with friction").holds and report.row("passivity").holds
    assert report.row("passivity with friction").worst > 0.01  # joules injected, far above the tolerance


def test_passivity_finds_energy_injected_by_the_forward_dynamics() -> None:
    """A forward dynamics that adds 0.5 qd to tau while friction() reports none: the lossless balance
    W = H(T) - H(0) breaks by the work 0.5 integral qd^T qd dt, found though no friction law shows it."""
    arm = _same_arm(_Injecting, ad.models.two_link_planar())
    row = check(arm, only="passivity").row("passivity")
    assert not row.holds and row.worst > 1e-3
    assert check(ad.models.two_link_planar(), only="passivity").row("passivity").worst < 1e-9


def test_a_row_that_cannot_be_evaluated_is_reported_and_the_others_kept(monkeypatch: pytest.MonkeyPatch) -> None:
    import armdyn.properties as properties

    def diverges(*args: object) -> None:
        raise ad.ModelError("qd holds values of 1e+15 or more")

    arm = ad.models.two_link_planar()
    whole = check(arm, samples=30)
    monkeypatch.setattr(properties, "_passivity_rows", diverges)
    report = check(arm, samples=30)
    row = report.row("passivity")
    assert not row.holds and row.unchecked == "qd holds values of 1e+15 or more" and report.unchecked == [row]
    assert not report.all_hold
    kept = [r for r in whole.rows if not r.name.startswith("passivity")]
    assert [(r.name, r.holds, r.worst) for r in report.rows[:-1]] == [(r.name, r.holds, r.worst) for r in kept]
    assert report.records()[1][-1][2] == "not checked"
    assert report.records()[1][-1][-1] == "could not be checked: qd holds values of 1e+15 or more"
    result = CliRunner().invoke(app, ["check", "two_link_planar", "--samples", "30"])
    assert result.exit_code == 1
    assert "could not be checked: passivity: qd holds values of 1e+15 or more" in result.stdout
    assert "gravity bound" in result.stdout and "skew symmetry" in result.stdout
    assert "all properties checked hold" in result.stdout


def test_check_command_only_selects_rows() -> None:
    runner = CliRunner()
    result = runner.invoke(app, ["check", "two_link_planar", "--only", "passivity, skew"])
    assert result.exit_code == 0, result.output
    assert "skew symmetry" in result.stdout and "passivity" in result.stdout
    assert "gravity bound" not in result.stdout and "positive definite" not in result.stdout
    failed = runner.invoke(app, ["check", "two_link_planar", "--only", "passivity,skw"])
    lines = failed.stderr.strip().splitlines()
    assert failed.exit_code == 2 and len(lines) == 1, failed.stderr
    assert "--only names unknown groups 'skw': give some of inertia, coriolis, skew" in lines[0]
