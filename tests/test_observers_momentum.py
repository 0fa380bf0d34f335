"""The generalized-momentum observer: exact on sampled simulated data without friction, the external torque of a
push on a link recovered, detected, isolated and its force estimated; the real Panda log without false alarms."""

from __future__ import annotations

import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings

import armdyn as ad
from armdyn.control import ComputedTorque
from armdyn.observers.contact import Push, contact_link, estimate_force
from armdyn.observers.detection import Band, detect
from armdyn.observers.momentum import MomentumObserver, observe
from armdyn.trajectories import Sinusoid
from tests.helpers import URDFS
from tests.strategies import robots

WELL_CONDITIONED_PANDA = np.array([0.3, -0.4, 0.5, -2.0, 0.4, 1.6, 0.7])  # qr aligns joints 1 and 3: F not observable
SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "panda-gaz2019"


def _run(arm: ad.Robot, t_final: float, disturbance: object = None) -> object:
    q0 = arm.configuration("qn" if "qn" in arm.configurations else "qr")
    trajectory = Sinusoid(0.2 * np.ones(arm.n), 0.5, offset=q0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a contact runs simulate's Python loop: its speed warning
        return ad.simulate(arm, ComputedTorque(kp=100, kv=20), trajectory, t_final=t_final, dt=1e-3, q0=q0,
                           disturbance=disturbance)  # fmt: skip


def test_without_friction_the_sampled_observer_is_the_first_order_filter_of_the_external_torque() -> None:
    """r_k = tau_ext (1 - exp(-K t_k)) for a constant tau_ext, to the trapezoid rule's accuracy on the known terms
    (1e-5 of tau_ext at 1 kHz), with a torque held over each step as simulate's RK4 holds it."""
    arm = ad.models.puma560().without_friction()
    external = np.array([1.0, -2.0, 1.5, 0.3, -0.2, 0.1])
    result = _run(arm, 1.0, -external)
    gains = np.array([20.0, 50.0, 100.0, 200.0, 50.0, 50.0])
    r = observe(arm, result.t, result.q, result.qd, result.tau, gains=gains, held_torque=True)
    expected = external * (1 - np.exp(-np.outer(result.t, gains)))
    np.testing.assert_allclose(r, expected, atol=2e-5 * np.abs(external).max())


def test_one_sample_at_a_time_equals_the_whole_log() -> None:
    arm = ad.models.puma560()
    result = _run(arm, 0.3, -np.array([0.5, 1.0, -1.0, 0.1, 0.1, 0.0]))
    eps = result.info["coulomb_smoothing"]
    whole = observe(arm, result.t, result.q, result.qd, result.tau, gains=80.0, held_torque=True, coulomb_smoothing=eps)
    observer = MomentumObserver(arm, gains=80.0, held_torque=True, coulomb_smoothing=eps)
    one = np.array(
        [
            observer.step(t, q, qd, tau).copy()
            for t, q, qd, tau in zip(result.t, result.q, result.qd, result.tau, strict=True)
        ]
    )
    np.testing.assert_allclose(one, whole, rtol=1e-12, atol=1e-12)


def _filtered(t: np.ndarray, torque: np.ndarray, gains: float) -> np.ndarray:
    """K / (s + K) of a torque held over each step, sampled: what the observer's residual must equal."""
    out = np.zeros_like(torque)
    for k in range(1, t.shape[0]):
        a = np.exp(-gains * (t[k] - t[k - 1]))
        out[k] = a * out[k - 1] + (1 - a) * torque[k - 1]
    return out


@pytest.mark.parametrize("name", ["puma560", "panda_gaz2019"])
def test_a_push_on_link_4_is_recovered_detected_isolated_and_its_force_estimated(name: str) -> None:
    """20 N on link 4 from t = 2 s, the arm under computed torque along a sinusoid, friction included, the observer
    in simulate's compiled loop: the residual equals the first-order filter of J^T F to 1e-6, and J^T F itself to 1%
    of its size after five time constants (the filter's lag is the difference); detected within 5 ms; link 4 named
    and the force at the known point within 2% at every sample from then on."""
    arm = ad.models.load(name)
    q0 = arm.configuration("qn") if name == "puma560" else WELL_CONDITIONED_PANDA
    point = np.array([0.05, 0.02, 0.03])
    push = Push(arm, 3, point, [0.0, 12.0, 16.0], 2.0)
    gains = 500.0  # a time constant of 2 ms
    with warnings.catch_warnings():
        warnings.simplefilter("error", ad.simulation.PythonLoopWarning)  # contacts and observer run compiled
        result = ad.simulate(arm, ComputedTorque(kp=100, kv=20), Sinusoid(0.2 * np.ones(arm.n), 0.5, offset=q0),
                             t_final=2.6, dt=1e-3, q0=q0, disturbance=push,
                             observer=MomentumObserver(arm, gains))  # fmt: skip
    r, truth = result.residual, result.external_torque
    samples = zip(result.t, result.q, result.qd, strict=True)
    expected = np.array([push.external_torque(t, q, qd) for t, q, qd in samples])
    np.testing.assert_allclose(truth, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    size = np.abs(truth).max()
    np.testing.assert_allclose(r, _filtered(result.t, truth, gains), rtol=0, atol=1e-6 * size)
    settled = result.t >= 2.0 + 5 / gains
    assert np.abs(r[settled] - truth[settled]).max() <= 0.01 * size
    assert np.abs(r[result.t < 2.0]).max() < 1e-6 * size  # the exact model: rounding alone before the push
    band = Band.fixed(np.full(arm.n, 0.1))  # a band of 0.1 N m, as a joint torque sensor's noise would need
    watched = result.t > 0.1
    detection = detect(result.t[watched], r[watched], band)
    assert detection.time is not None and 2.0 <= detection.time <= 2.005
    bounds = np.vstack([band.lower, band.upper])
    assert all(contact_link(residual, bounds) == 3 for residual in r[settled])
    estimate = estimate_force(arm, result.q[settled], r[settled], 3, point)  # every settled sample, one call
    assert np.all(np.linalg.norm(estimate.force - push.force_vector, axis=-1) <= 0.02 * 20.0)


def test_a_sampled_log_of_the_same_run_meets_the_friction_reversal_between_samples() -> None:
    """The same push on the PUMA 560 observed from its 1 kHz samples alone (a log): exact without friction, but each
    reversal of a joint's velocity crosses the Coulomb law inside a step, which the trapezoid rule cannot see: its
    error there is a few percent of the push, where the observer inside the loop stays exact."""
    arm = ad.models.puma560()
    q0 = arm.configuration("qn")
    push = Push(arm, 3, np.array([0.05, 0.02, 0.03]), [0.0, 12.0, 16.0], 2.0)
    runs = {}
    for label, plant in (("friction", arm), ("none", arm.without_friction())):
        result = ad.simulate(plant, ComputedTorque(kp=100, kv=20), Sinusoid(0.2 * np.ones(6), 0.5, offset=q0),
                             t_final=2.6, dt=1e-3, q0=q0, observer=MomentumObserver(plant, 200.0),
                             disturbance=Push(plant, 3, push.point, push.force_vector, 2.0))  # fmt: skip
        sampled = observe(plant, result.t, result.q, result.qd, result.tau, 200.0, held_torque=True,
                          coulomb_smoothing=result.info["coulomb_smoothing"])  # fmt: skip
        size = np.abs(result.external_torque).max()
        runs[label] = (np.abs(sampled - result.residual).max() / size, np.abs(sampled - result.residual))
    assert runs["none"][0] < 1e-4
    assert 0.005 < runs["friction"][0] < 0.1


def test_the_observer_after_a_python_loop_runs_on_its_samples() -> None:
    arm = ad.models.two_link_planar()
    observer = MomentumObserver(arm, 80.0)

    def law(t: float, q: np.ndarray, qd: np.ndarray, *_: object) -> np.ndarray:
        return arm.gravity_vector(q) - 5.0 * qd

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ad.simulation.PythonLoopWarning)
        result = ad.simulate(arm, law, t_final=0.5, dt=1e-3, q0=[0.3, 0.2], disturbance=[0.5, -0.2],
                             observer=observer)  # fmt: skip
    expected = observe(arm, result.t, result.q, result.qd, result.tau, 80.0, held_torque=True,
                       coulomb_smoothing=result.info["coulomb_smoothing"])  # fmt: skip
    np.testing.assert_array_equal(result.residual, expected)
    assert result.info["observer"] == "on the samples after the run"
    np.testing.assert_allclose(result.residual[-1], [-0.5, 0.2], rtol=1e-4)


def test_an_observer_that_does_not_fit_the_run_is_refused() -> None:
    arm = ad.models.puma560()
    with pytest.raises(ad.ArgumentError, match=r"observer must be an armdyn\.observers\.momentum\.MomentumObserver"):
        ad.simulate(arm, t_final=0.01, observer=50.0)
    with pytest.raises(ad.ModelError, match="the observer's arm has 2 joints, the simulated arm 6"):
        ad.simulate(arm, t_final=0.01, observer=MomentumObserver(ad.models.two_link_planar()))
    with pytest.raises(ad.ArgumentError, match="observer"):
        ad.simulate(arm, t_final=0.01, runs=2, observer=MomentumObserver(arm))


@pytest.mark.slow
def test_the_real_panda_log_raises_no_false_alarm() -> None:
    """The model identified from the first 70% of the real Panda log; thresholds from the observer's residual there;
    the last 30% stays inside them."""
    if not SHARED.is_dir():
        pytest.skip(f"the real Panda log is not here ({SHARED}): it lives beside the repository, in ../shared")
    from armdyn.identification.log import read_gaz_panda
    from armdyn.identification.workflow import identify_log

    log = read_gaz_panda(SHARED)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prior = ad.load_urdf(URDFS["panda"], locked={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02})
    model = identify_log(prior, log, holdout=0.3)
    r = observe(model.arm, log.t, log.q, log.qd, log.tau - model.offsets, gains=10.0)
    cut = int(0.7 * log.samples)
    band = Band.from_residuals(r[int(0.05 * log.samples) : cut], quantile=0.999, margin=2.0)
    assert detect(log.t[cut:], r[cut:], band).time is None


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"gains": 0.0}, "gains must be positive"),
        ({"gains": [1.0, 2.0]}, "gains must be one positive number or 6"),
        ({"q": "nan"}, "q holds nan at sample 3, joint 2"),
        ({"tau": "short"}, "tau must have shape (10, 6)"),
        ({"t": "backwards"}, "t must increase"),
    ],
)
def test_bad_input_is_one_clear_error(change: dict, message: str) -> None:
    arm = ad.models.puma560()
    t, q = np.arange(10) * 1e-3, np.zeros((10, 6))
    args = {"t": t, "q": q, "qd": np.zeros((10, 6)), "tau": np.zeros((10, 6)), "gains": 50.0}
    if change.get("q") == "nan":
        args["q"] = q.copy()
        args["q"][3, 1] = np.nan
    elif change.get("tau") == "short":
        args["tau"] = np.zeros((9, 6))
    elif change.get("t") == "backwards":
        args["t"] = t[::-1].copy()
    else:
        args.update(change)
    with pytest.raises(ad.ModelError, match=message.replace("(", r"\(").replace(")", r"\)")):
        observe(arm, **args)


def test_no_false_alarm_over_60_s_with_masses_10_percent_off() -> None:
    """The plant's links 10% heavier than the observer's model: thresholds from 10 s of collision-free motion, then
    60 s without an alarm (the model error repeats with the motion; the band holds it)."""
    arm = ad.models.puma560()
    heavier = [
        dataclasses.replace(link, inertial=ad.Inertial(1.1 * x.mass, x.com, 1.1 * x.inertia, x.name, False))
        for link, x in ((link, link.inertial) for link in arm.links)
    ]
    result = _run(arm.replace(heavier), 70.2)
    r = observe(arm, result.t, result.q, result.qd, result.tau, gains=50.0, held_torque=True,
                coulomb_smoothing=result.info["coulomb_smoothing"])  # fmt: skip
    first = (result.t > 0.2) & (result.t <= 10.2)
    band = Band.from_residuals(r[first], quantile=0.999, margin=2.0)
    later = result.t > 10.2
    assert np.abs(r[later]).max() > 1.0  # the model error is there, well above rounding
    assert detect(result.t[later], r[later], band).time is None


def test_the_sampled_observer_converges_to_the_continuous_one_at_first_order() -> None:
    """No external torque: the continuous observer's residual is 0; the sampled one's (friction's reversals integrated
    by the trapezoid rule) falls in proportion to the step."""
    arm = ad.models.puma560()
    errors = []
    for dt in (2e-3, 1e-3, 5e-4):
        q0 = arm.configuration("qn")
        result = ad.simulate(arm, ComputedTorque(kp=100, kv=20), Sinusoid(0.2 * np.ones(6), 0.5, offset=q0),
                             t_final=2.0, dt=dt, q0=q0)  # fmt: skip
        r = observe(arm, result.t, result.q, result.qd, result.tau, gains=50.0, held_torque=True,
                    coulomb_smoothing=result.info["coulomb_smoothing"])  # fmt: skip
        errors.append(np.sqrt(np.mean(r[result.t > 0.2] ** 2)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 0.85), orders


def test_cli_observe_detects_a_contact_in_a_log(tmp_path: Path) -> None:
    from tests.helpers import assert_one_error_line, invoke

    arm = ad.models.two_link_planar()
    external = np.array([0.0, 3.0])

    def contact(t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return -external if t >= 2.0 else np.zeros(2)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = ad.simulate(arm, ComputedTorque(kp=100, kv=20), Sinusoid([0.3, 0.3], 0.5), t_final=3.0, dt=1e-3,
                          disturbance=contact)  # fmt: skip
    path = tmp_path / "log.csv"
    table = np.column_stack([run.t, run.q, run.qd, run.tau])
    np.savetxt(path, table, delimiter=",", header="time,q1,q2,qd1,qd2,tau1,tau2", comments="")
    result = invoke(
        "observe", "two_link_planar", "--log", path, "--free", "0.5", "--gains", "100", "-o", tmp_path / "o"
    )
    assert result.exit_code == 0, result.output
    found = re.search(
        r"contact detected at t = ([0-9.]+) s on joint (\w+); the last link in contact: (\w+)", result.output
    )
    assert found is not None, result.output
    assert 2.0 <= float(found.group(1)) <= 2.01 and found.group(3) == arm.joint_names[1]
    for name in ("residuals.csv", "residuals.png", "report.md"):
        assert (tmp_path / "o" / name).is_file()
    assert_one_error_line(invoke("observe", "two_link_planar", "--log", path, "--free", "0.99", "-o", tmp_path / "p"),
                          "--free must be a share")  # fmt: skip
    assert_one_error_line(invoke("observe", "two_link_planar", "--log", path, "--gains", "-1", "-o", tmp_path / "p"),
                          "gains must be positive")  # fmt: skip


@pytest.mark.parametrize("name", ["puma560", "panda_gaz2019"])
def test_the_compiled_kernel_equals_the_readable_numpy_terms(name: str) -> None:
    """p = M qd and tau + Vm^T qd - G - F of the compiled loop against the NumPy reference, friction smoothed or not."""
    from armdyn.dynamics.friction import sign_law_table
    from armdyn.dynamics.packed import workspace_size
    from armdyn.observers.momentum import known_rate, momentum, momentum_and_rate

    arm = ad.models.load(name)
    rng = np.random.default_rng(0)
    n = arm.n
    work = np.empty(workspace_size(n))
    for eps in (None, np.full(n, 0.01)):
        for _ in range(10):
            q, qd, tau = rng.uniform(-1, 1, (3, n))
            qd[0] = 1e-3  # inside the smoothing
            p, rate = np.empty(n), np.empty(n)
            momentum_and_rate(arm.packed, sign_law_table(arm), np.zeros(n) if eps is None else eps, work, q, qd, tau,
                              p, rate)  # fmt: skip
            np.testing.assert_allclose(p, momentum(arm, q, qd), rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(rate, known_rate(arm, q, qd, tau, eps), rtol=1e-11, atol=1e-11)


def _terms(arm: ad.Robot, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """p, Vm^T qd and G of the O(n) recursion."""
    from armdyn.dynamics.momentum import momentum_core
    from armdyn.dynamics.packed import workspace_size

    p, transposed, G = np.empty(arm.n), np.empty(arm.n), np.empty(arm.n)
    momentum_core(arm.packed, np.empty(workspace_size(arm.n)), q, qd, p, transposed, G)
    return p, transposed, G


def _assert_terms_match(arm: ad.Robot, seed: int) -> None:
    """The recursion's p, Vm^T qd and G equal M qd, C^T qd (the Christoffel C) and G of the arm's own methods, to
    1e-10 of their size (of 1 for a term near zero, as C^T qd of one joint: both are rounding there)."""
    rng = np.random.default_rng(seed)
    for _ in range(5):
        q, qd = rng.uniform(-2, 2, (2, arm.n))
        p, transposed, G = _terms(arm, q, qd)
        expected = (arm.inertia_matrix(q) @ qd, arm.coriolis_matrix(q, qd).T @ qd, arm.gravity_vector(q))
        for value, truth in zip((p, transposed, G), expected, strict=True):
            np.testing.assert_allclose(value, truth, rtol=0, atol=1e-10 * max(np.abs(truth).max(), 1.0))


@pytest.mark.parametrize("name", ["puma560", "panda_gaz2019", "stanford", "scara"])
def test_the_recursion_equals_m_qd_c_transposed_qd_and_g_of_the_built_in_arms(name: str) -> None:
    """Revolute and prismatic joints (Stanford, SCARA); the PUMA's reflected motor inertias on M's diagonal."""
    arm = ad.models.load(name)
    if name == "puma560":
        assert np.abs(arm.reflected_inertia).max() > 0
    _assert_terms_match(arm, 1)


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_the_recursion_equals_m_qd_c_transposed_qd_and_g_of_urdf_arms(name: str) -> None:
    """The Panda's URDF with its two fingers free is a tree: the hand has two children (prismatic joints)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(URDFS[name])
    parents = [link.parent for link in arm.links]
    if name == "panda":
        assert len(parents) != len(set(parents))  # a branch
    _assert_terms_match(arm, 2)


@settings(max_examples=25, deadline=None)
@given(robots)
def test_the_recursion_equals_m_qd_c_transposed_qd_and_g_of_random_trees(arm: ad.Robot) -> None:
    """Random trees of revolute and prismatic joints with motors (reflected inertia) and any gravity."""
    _assert_terms_match(arm, 3)


def test_the_recursion_has_the_sign_of_dk_dq() -> None:
    """Vm^T qd = dK/dq (K = 1/2 qd^T M qd): against central differences of the kinetic energy."""
    arm = ad.models.puma560()
    rng = np.random.default_rng(4)
    q, qd = rng.uniform(-1, 1, (2, arm.n))
    h = 1e-6
    kinetic = [
        [0.5 * qd @ arm.inertia_matrix(q + s * h * np.eye(arm.n)[i]) @ qd for s in (1, -1)] for i in range(arm.n)
    ]
    derivative = np.array([(plus - minus) / (2 * h) for plus, minus in kinetic])
    np.testing.assert_allclose(_terms(arm, q, qd)[1], derivative, atol=1e-6 * np.abs(derivative).max())


def test_the_step_takes_lists_integers_and_strided_rows_as_arrays() -> None:
    """Lists, tuples, strided and read-only rows and an integer time take the converted path: the fast path's
    residual."""
    arm = ad.models.puma560()
    rng = np.random.default_rng(5)
    samples = rng.uniform(-1, 1, (4, 3, arm.n))
    fast, slow = MomentumObserver(arm, gains=30.0), MomentumObserver(arm, gains=30.0)
    wide = np.zeros((3, 2 * arm.n))
    for k, (q, qd, tau) in enumerate(samples):
        expected = fast.step(float(k) * 1e-3 if k else 0.0, q, qd, tau).copy()
        wide[:, ::2] = samples[k]
        t = 0 if k == 0 else k * 1e-3  # an integer first
        fixed = tau.copy()
        fixed.flags.writeable = False  # a read-only array: the compiled signature's arrays are writable ones
        got = slow.step(t, q.tolist(), wide[1, ::2], fixed if k % 2 else tuple(tau))
        np.testing.assert_array_equal(got, expected)
    assert np.abs(fast.residual).max() > 0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"q": [0.0] * 5}, "q must be 6 finite numbers"),
        ({"qd": np.full(7, 0.0)}, "qd must be 6 finite numbers"),
        ({"tau": np.array([0.0, np.nan, 0.0, 0.0, 0.0, 0.0])}, "tau must be 6 finite numbers"),
        ({"q": np.array([np.inf, 0.0, 0.0, 0.0, 0.0, 0.0])}, "q must be 6 finite numbers"),
        ({"qd": "fast"}, "qd must be 6 finite numbers"),
        ({"t": 0.001}, "t must increase: 0.001 is not after 0.001"),
        ({"t": 0.0005}, "t must increase"),
        ({"t": float("nan")}, "t must increase"),
        ({"t": "later"}, "t must be a number"),
    ],
)
def test_a_bad_step_is_one_clear_error_and_changes_nothing(change: dict, message: str) -> None:
    arm = ad.models.puma560()
    observer, twin = MomentumObserver(arm, gains=50.0), MomentumObserver(arm, gains=50.0)
    rng = np.random.default_rng(6)
    q, qd, tau = rng.uniform(-1, 1, (3, arm.n))
    for each in (observer, twin):
        each.step(0.0, q, qd, tau)
        each.step(1e-3, q + 1e-3, qd, tau)
    args = {"t": 2e-3, "q": q, "qd": qd, "tau": tau} | change
    with pytest.raises(ad.ModelError, match=re.escape(message)):
        observer.step(**args)
    np.testing.assert_array_equal(observer.step(2e-3, q, qd, tau), twin.step(2e-3, q, qd, tau))


def test_hold_replaces_the_held_torque_of_the_last_sample() -> None:
    """step(tau_a) then hold(tau_b) is step(tau_b): the held torque enters only the next step's integral."""
    arm = ad.models.puma560()
    rng = np.random.default_rng(7)
    q, qd, tau_a, tau_b = rng.uniform(-1, 1, (4, arm.n))
    held, direct = MomentumObserver(arm, held_torque=True), MomentumObserver(arm, held_torque=True)
    held.step(0.0, q, qd, tau_a)
    held.hold(tau_b)
    direct.step(0.0, q, qd, tau_b)
    np.testing.assert_allclose(held.step(1e-3, q + 1e-3, qd, tau_a), direct.step(1e-3, q + 1e-3, qd, tau_a),
                               rtol=1e-13, atol=1e-13)  # fmt: skip
    with pytest.raises(ad.ModelError, match="hold needs a sample first"):
        MomentumObserver(arm).hold(tau_a)
    with pytest.raises(ad.ModelError, match="tau must be 6 finite numbers"):
        held.hold([1.0, 2.0])


def test_the_decay_factor_from_a_reference_step_is_exp() -> None:
    """exp(-K dt) from exp(-K dt0) and the series of exp(-K (dt - dt0)): to rounding while K |dt - dt0| <= 1e-4."""
    from armdyn.observers.momentum import DECAY_SHIFT, _decay

    for gain, dt0 in ((1.0, 1e-3), (200.0, 1e-3), (5000.0, 2e-4)):
        for x in (0.0, 1e-9, -3e-7, DECAY_SHIFT, -DECAY_SHIFT):
            dt = dt0 + x / gain
            assert abs(_decay(np.exp(-gain * dt0), x) - np.exp(-gain * dt)) <= 4e-16


def test_the_log_equals_the_steps_across_the_log_blocks() -> None:
    """A log longer than one block of observe's parallel pass, with uneven steps: equal to the step loop to 1e-12."""
    from armdyn.observers.momentum import LOG_BLOCK

    arm = ad.models.panda_gaz2019()
    rng = np.random.default_rng(8)
    samples = LOG_BLOCK + 1000
    t = np.cumsum(rng.uniform(0.9e-3, 1.1e-3, samples))
    q = arm.configurations["qr"] + 0.3 * np.sin(np.outer(t, rng.uniform(0.5, 2.0, arm.n)))
    qd, tau = np.gradient(q, t, axis=0), rng.normal(size=(samples, arm.n))
    whole = observe(arm, t, q, qd, tau, gains=[20, 50, 50, 100, 100, 200, 200], coulomb_smoothing=0.01)
    observer = MomentumObserver(arm, gains=[20, 50, 50, 100, 100, 200, 200], coulomb_smoothing=0.01)
    steps = np.array([observer.step(t[k], q[k], qd[k], tau[k]).copy() for k in range(samples)])
    np.testing.assert_allclose(steps, whole, rtol=1e-12, atol=1e-12)


def test_reset_starts_the_observer_again() -> None:
    """After reset the same samples give the same residuals as a new observer (r = 0 at the first)."""
    arm = ad.models.panda_gaz2019()
    rng = np.random.default_rng(9)
    samples = rng.uniform(-1, 1, (5, 3, arm.n))
    observer = MomentumObserver(arm, gains=40.0)
    first = [observer.step(k * 1e-3, *sample).copy() for k, sample in enumerate(samples)]
    observer.reset()
    again = [observer.step(10.0 + k * 1e-3, *sample).copy() for k, sample in enumerate(samples)]
    assert np.abs(first[-1]).max() > 0 and not np.any(again[0])
    np.testing.assert_allclose(again, first, rtol=1e-9, atol=1e-12)
