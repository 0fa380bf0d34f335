"""Identification from logs: friction laws by variable projection, the whole workflow on simulated logs with
known truth, and on a real Panda's log against the model its authors published (Gaz et al. 2019)."""

from __future__ import annotations

import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import armdyn as ad
from armdyn.dynamics.regressor import parameters
from armdyn.identification.consistent import pseudo_inertia
from armdyn.identification.excitation import FourierTrajectory
from armdyn.identification.friction import FrictionLaw, fit_nonlinear, sigmoid_friction
from armdyn.identification.log import Log, read_gaz_panda
from armdyn.identification.workflow import identify_log, validate
from tests.helpers import URDFS, assert_one_error_line, invoke

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "panda-gaz2019"
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


def _sigmoid_arm(arm: ad.Robot, seed: int = 1) -> ad.Robot:
    """The arm with a sigmoid friction law per joint (amplitudes 0.5 to 2 N m), viscous friction kept."""
    rng = np.random.default_rng(seed)
    links = [
        dataclasses.replace(
            link,
            coulomb=(0.0, 0.0),
            sigmoid=(float(rng.uniform(0.5, 2.0)), float(rng.uniform(8, 30)), float(rng.uniform(-0.03, 0.03))),
        )
        for link in arm.without_motors().links
    ]
    return arm.replace(links)


def _simulated_log(
    arm: ad.Robot, seconds: float = 10.0, rate: float = 1000.0, noise: float = 0.01, seed: int = 0
) -> tuple[Log, np.ndarray]:
    """A log of the arm following a random Fourier series: time jittered by up to 0.5 ms, torques with
    noise of ``noise`` times each joint's rms torque; and the exact torques."""
    rng = np.random.default_rng(seed)
    n, harmonics = arm.n, 5
    lower, upper = np.array([link.limits for link in arm.links]).T
    limited = np.isfinite(lower) & np.isfinite(upper)
    q0 = np.where(limited, (np.where(limited, lower, 0) + np.where(limited, upper, 0)) / 2, 0.0)
    scale = 1.2 / harmonics
    trajectory = FourierTrajectory(
        seconds, q0, rng.normal(0, scale, (n, harmonics)), rng.normal(0, scale, (n, harmonics))
    )
    steps = int(seconds * rate)
    t = (np.arange(steps) + rng.uniform(-0.499, 0.499, steps)) / rate  # jitter up to half a step
    t[0] = 0.0
    q, qd, qdd = trajectory(t)
    exact = arm.inverse_dynamics(q, qd, qdd)
    tau = exact + noise * np.sqrt(np.mean(exact**2, axis=0)) * rng.standard_normal(exact.shape)
    return Log(t=t, q=q, qd=None, tau=tau, source="simulated"), exact


def _true_vector(model, arm: ad.Robot) -> np.ndarray:
    """The arm's own parameters in the model's full vector (rigid body, friction, Ia, offsets 0)."""
    n, per_joint = arm.n, model.columns.per_joint
    values = {"Fv": [], "A": [], "Ia": [], "offset": [], "Fc+": [], "Fc-": [], "Fs": []}
    for link in arm.links:
        values["Fv"].append(link.gear_ratio**2 * link.viscous)
        values["A"].append(link.sigmoid[0])
        values["Ia"].append(link.gear_ratio**2 * link.motor_inertia)
        values["offset"].append(0.0)
        values["Fc+"].append(abs(link.gear_ratio) * link.coulomb[0])
        values["Fc-"].append(abs(link.gear_ratio) * link.coulomb[1])
        values["Fs"].append(link.stribeck[0])
    extra = [values[name][j] for j in range(n) for name in per_joint]
    return np.concatenate([parameters(arm)[: 10 * n], extra])


# ----- friction laws ------------------------------------------------------------------------------------------
def test_variable_projection_recovers_a_sigmoid_law() -> None:
    rng = np.random.default_rng(3)
    n, rows = 2, 4000
    qd = rng.uniform(-1, 1, (rows, n))
    alpha, shift, amplitude = np.array([12.0, 25.0]), np.array([0.02, -0.03]), np.array([0.8, 1.5])
    other = rng.normal(size=(rows, n, 3))  # columns a rigid body would add, shared parameters
    theta = np.array([0.4, -1.0, 2.0])
    tau = other @ theta + amplitude * sigmoid_friction(qd, alpha, shift) + 0.3 * qd + 1e-3 * rng.normal(size=(rows, n))
    fixed = np.concatenate([other, np.stack([qd * (j == np.arange(n)) for j in range(n)], -1)], -1)
    law = fit_nonlinear("sigmoid", fixed.reshape(rows * n, -1), tau.reshape(-1), qd)
    assert law.nonlinear[:, 0] == pytest.approx(alpha, rel=0.05)
    assert law.nonlinear[:, 1] == pytest.approx(shift, abs=3e-3)


def test_friction_law_columns_are_the_arm_law() -> None:
    """The regressor's sigmoid column times A is what the arm's friction gives (one law everywhere)."""
    arm = _sigmoid_arm(ad.models.puma560())
    qd = np.random.default_rng(0).uniform(-2, 2, (50, arm.n))
    nonlinear = np.array([link.sigmoid[1:] for link in arm.links])
    law = FrictionLaw("sigmoid", nonlinear)
    linear = np.array([[link.viscous, link.sigmoid[0]] for link in arm.links])
    np.testing.assert_allclose(
        np.einsum("snk,nk->sn", law.columns(qd), linear), arm.friction(qd), rtol=1e-12, atol=1e-12
    )


def test_unknown_friction_law_is_refused() -> None:
    arm = ad.models.two_link_planar()
    log, _ = _simulated_log(arm, seconds=4)
    with pytest.raises(ad.ModelError, match="friction must be one of viscous, coulomb, stribeck, sigmoid"):
        identify_log(arm, log, friction="lugre")


# ----- simulated logs with known truth ------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("name", ["puma560", "panda"])
def test_simulated_log_gives_the_truth_within_three_standard_errors(name: str) -> None:
    if name == "panda":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            arm = _sigmoid_arm(ad.load_urdf(URDFS["panda"], locked=FINGERS))
    else:
        arm = _sigmoid_arm(ad.models.puma560())
    log, _ = _simulated_log(arm)
    model = identify_log(arm, log, friction="sigmoid", consistent=True)
    truth = model.regrouping @ _true_vector(model, arm)
    z = (model.phi_least_squares - truth) / model.standard_errors
    # honest standard errors: about 0.3% of the estimates beyond 3 of them, almost none beyond 4
    beyond = np.sum(np.abs(z) > 3)
    assert beyond <= max(2, 0.03 * len(z)) and np.max(np.abs(z)) < 4.5, (
        f"{beyond} of {len(z)} beyond 3, largest {np.max(np.abs(z)):.2f}"
    )
    assert np.sqrt(np.mean(z**2)) < 1.5
    nonlinear = np.array([link.sigmoid[1:] for link in arm.links])
    np.testing.assert_allclose(model.law.nonlinear[:, 0], nonlinear[:, 0], rtol=0.1)
    # the consistent estimate: every link physically realizable, torques as well explained (within 5%)
    n = arm.n
    eigenvalues = np.linalg.eigvalsh(pseudo_inertia(model.phi[: 10 * n].reshape(n, 10)))
    assert eigenvalues.min() >= -1e-9
    X = model.columns.matrix(arm, model.prepared.q, model.prepared.qd, model.prepared.qdd)
    unconstrained = np.sqrt(np.mean((X[..., model.keep] @ model.phi_least_squares - model.prepared.tau) ** 2))
    consistent = np.sqrt(np.mean((X @ model.phi - model.prepared.tau) ** 2))
    assert consistent <= 1.05 * unconstrained
    # the identified arm computes the model's torques with its own friction law
    identified = model.arm
    predicted = identified.inverse_dynamics(model.prepared.q, model.prepared.qd, model.prepared.qdd) + model.offsets
    np.testing.assert_allclose(
        predicted, model.predict(model.prepared.q, model.prepared.qd, model.prepared.qdd), atol=1e-9
    )


@pytest.mark.slow
def test_held_out_prediction_of_a_simulated_log() -> None:
    arm = _sigmoid_arm(ad.models.puma560())
    log, _ = _simulated_log(arm, seconds=12)
    model = identify_log(arm, log, holdout=0.3)
    held = log.split(0.7)[1]
    result = model.validate(held)
    truth = validate(arm.inverse_dynamics, held, model.prepared)  # the true arm: the noise (1%) and the filter's
    assert np.all(truth.normalized_rms < 0.015)
    assert np.all(result.normalized_rms < truth.normalized_rms + 0.01)  # within 1% of each joint's torque of it


def test_log_of_currents_needs_gains() -> None:
    arm = ad.models.two_link_planar()
    log, _ = _simulated_log(arm, seconds=4)
    currents = dataclasses.replace(log, tau=None, current=log.tau / 2.0)
    with pytest.raises(ad.ModelError, match="motor currents, not torques: give the current-to-torque gains"):
        identify_log(arm, currents)
    with pytest.raises(ad.ModelError, match="gains must be 2 finite non-zero numbers"):
        identify_log(arm, currents, gains=[1.0, 0.0])
    model = identify_log(arm, currents, gains=[2.0, 2.0], friction="viscous", consistent=False)
    plain = identify_log(arm, log, friction="viscous", consistent=False)
    np.testing.assert_allclose(model.phi_least_squares, plain.phi_least_squares, rtol=1e-9, atol=1e-12)


def test_holdout_is_a_share() -> None:
    arm = ad.models.two_link_planar()
    log, _ = _simulated_log(arm, seconds=4)
    with pytest.raises(ad.ModelError, match="holdout must be a share"):
        identify_log(arm, log, holdout=0.95)


# ----- the real Panda log (Gaz et al. 2019) -------------------------------------------------------------------
@pytest.fixture(scope="module")
def panda_log() -> Log:
    if not SHARED.is_dir():
        pytest.skip(f"the real Panda log is not here ({SHARED}): it lives beside the repository, in ../shared")
    return read_gaz_panda(SHARED)


@pytest.mark.slow
def test_real_panda_log_is_predicted_at_least_as_well_as_the_published_model(panda_log: Log) -> None:
    """Identify from the first 70% of a real Panda's samples, predict the last 30%: every joint's torque rms
    at most that of the model Gaz et al. published (built here from their published parameters)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prior = ad.load_urdf(URDFS["panda"], locked=FINGERS)
    model = identify_log(prior, panda_log, friction="sigmoid", holdout=0.3)
    held = panda_log.split(0.7)[1]
    ours = model.validate(held)
    published = validate(ad.models.panda_gaz2019().inverse_dynamics, held, model.prepared)
    assert np.all(ours.rms <= published.rms), f"ours {ours.rms.round(3)}, published {published.rms.round(3)}"
    eigenvalues = np.linalg.eigvalsh(pseudo_inertia(model.phi[:70].reshape(7, 10)))
    assert np.all(eigenvalues.min(axis=1) >= -1e-9), "7 of 7 links physically consistent"


# ----- the command line ---------------------------------------------------------------------------------------
@pytest.fixture
def log_csv(tmp_path: Path) -> Path:
    """A simulated two-link log as a CSV file of time, positions and torques (the reader's default names)."""
    arm = ad.models.two_link_planar()
    log, _ = _simulated_log(arm, seconds=6)
    path = tmp_path / "log.csv"
    table = np.column_stack([log.t, log.q, log.tau])
    np.savetxt(path, table, delimiter=",", header="time,q1,q2,tau1,tau2", comments="")
    return path


def test_cli_identifies_from_a_log_and_writes_the_report_and_the_arm(log_csv: Path, tmp_path: Path) -> None:
    out = tmp_path / "ident"
    result = invoke("identify", "two_link_planar", "--log", log_csv, "--holdout", "0.3", "--friction", "viscous",
                    "--reference", "two_link_planar", "-o", out)  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "two_link_planar rms" in result.output and "Held-out samples" in result.output
    for name in ("report.md", "report.html", "validation_torques.png", "validation_residuals.png"):
        assert (out / name).is_file(), name
    identified = ad.load_arm(out / "identified.json")
    truth = ad.models.two_link_planar()
    q = np.array([[0.3, -0.4], [1.0, 0.2]])
    np.testing.assert_allclose(identified.gravity_vector(q), truth.gravity_vector(q), rtol=0.02, atol=0.02)
    in_mujoco = ad.load_mjcf(out / "identified.xml", tool_link="tool")  # the same arm, for MuJoCo
    np.testing.assert_allclose(in_mujoco.inverse_dynamics(q, q, q), identified.inverse_dynamics(q, q, q), rtol=1e-12)
    assert "Physical consistency of each link" in (out / "report.md").read_text()


@pytest.mark.parametrize(
    ("extra", "fragments"),
    [
        (["--generate"], ["without a samples CSV file and without --generate"]),
        (["--current"], ["--current needs the current-to-torque gains"]),
        (["--current", "--gains", "1,1"], ["the log holds torques; leave out --current"]),
        (["--holdout", "0.95"], ["--holdout must be a share between 0 and 0.9"]),
        (["--lock", "q1=0"], ["--lock takes joints of a URDF or MJCF file"]),
        (["--columns", "t"], ["--columns 't': give name=value pairs"]),
        (["--friction", "lugre"], ["friction must be one of"]),
    ],
)
def test_cli_identify_log_errors_are_one_line(
    log_csv: Path, tmp_path: Path, extra: list[str], fragments: list[str]
) -> None:
    assert_one_error_line(
        invoke("identify", "two_link_planar", "--log", log_csv, "-o", tmp_path / "o", *extra), *fragments
    )


def test_cli_identify_log_needs_an_output_folder_and_log_options_need_a_log(log_csv: Path) -> None:
    assert_one_error_line(invoke("identify", "two_link_planar", "--log", log_csv), "give the folder with -o DIR")
    assert_one_error_line(
        invoke("identify", "two_link_planar", "--generate", "--holdout", "0.3"), "--holdout goes with --log"
    )


@pytest.mark.slow
def test_cli_on_the_real_panda_log(panda_log: Log, tmp_path: Path) -> None:
    result = invoke("identify", URDFS["panda"], "--lock", "panda_finger_joint1=0.02,panda_finger_joint2=0.02", "--log",
                    SHARED, "--holdout", "0.3", "--reference", "panda_gaz2019", "-o", tmp_path / "panda")  # fmt: skip
    assert result.exit_code == 0, result.output
    changes = [float(x) for x in re.findall(r"([+-]\d+\.\d)%", result.output)]
    assert len(changes) == 7 and max(changes) <= 0.0, result.output


@pytest.mark.slow
def test_cli_gains_from_a_payload_run_then_identification_from_currents(tmp_path: Path) -> None:
    """Two logs of motor currents (gains 0.5 to 3 N m/A), one with a 3 kg payload off the wrist's axis: the gains
    within 2% (Gautier and Briot 2014), the Coulomb steps filtered as the currents were."""
    arm = ad.models.puma560()
    gains = np.array([0.5, 1.2, 3.0, 0.8, 2.0, 1.5])
    com = [0.05, 0.03, 0.08]
    names = ",".join(f"q{j + 1}" for j in range(6)) + "," + ",".join(f"i{j + 1}" for j in range(6))
    for label, truth, seed in (("unloaded", arm, 1), ("loaded", arm.with_payload(3.0, com), 2)):
        log, _ = _simulated_log(truth, seed=seed)
        table = np.column_stack([log.t, log.q, log.tau / gains])
        np.savetxt(tmp_path / f"{label}.csv", table, delimiter=",", header="time," + names, comments="")
    result = invoke("identify", "puma560", "--log", tmp_path / "unloaded.csv", "--current", "--gains-from-payload",
                    tmp_path / "loaded.csv", "3.0", "--payload-com", "0.05,0.03,0.08", "--friction", "coulomb",
                    "-o", tmp_path / "out")  # fmt: skip
    assert result.exit_code == 0, result.output
    found = re.search(r"gains from the payload run \(N m/A\): (.*)", result.output)
    assert found is not None
    estimated = np.array([float(x) for x in found.group(1).split(",")])
    np.testing.assert_allclose(estimated, gains, rtol=0.02)


def test_a_log_that_does_not_excite_the_parameters_is_refused_naming_the_condition_number() -> None:
    arm = ad.models.two_link_planar()
    log, _ = _simulated_log(arm, seconds=4)
    still = dataclasses.replace(log, q=np.column_stack([log.q[:, 0], np.full(log.samples, 0.3)]))
    with pytest.raises(ad.ModelError, match=r"do not excite the .* condition number"):
        identify_log(arm, still, friction="viscous")


def test_mass_bounds_hold_in_the_consistent_estimate(log_csv: Path, tmp_path: Path) -> None:
    arm = ad.models.two_link_planar()
    log, _ = _simulated_log(arm, seconds=6)
    heavier = [ad.Inertial(1.5 * x.mass, x.com, 1.5 * x.inertia, x.name) for x in (link.inertial for link in arm.links)]
    wrong = arm.replace([dataclasses.replace(link, inertial=i) for link, i in zip(arm.links, heavier, strict=True)])
    model = identify_log(wrong, log, friction="viscous", mass_tolerance=0.1)
    masses = model.phi[: 10 * arm.n : 10]
    prior = np.array([link.inertial.mass for link in wrong.links])
    assert np.all(masses >= 0.9 * prior - 1e-6) and np.all(masses <= 1.1 * prior + 1e-6)
    result = invoke("identify", "two_link_planar", "--log", log_csv, "--friction", "viscous", "--mass-tolerance",
                    "0.05", "-o", tmp_path / "o")  # fmt: skip
    assert result.exit_code == 0, result.output
