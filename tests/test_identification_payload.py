"""Payload identification and drive gains from a known payload, against simulated data of known truth."""

from __future__ import annotations

import dataclasses
import functools
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn.dynamics.regressor import parameters
from armdyn.identification.excitation import excitation_trajectory, identification_data
from armdyn.identification.gains import GainEstimate, identify_gains, torques_from_currents
from armdyn.identification.payload import (
    PayloadEstimate,
    body_parameters,
    com_jacobian,
    identify_payload,
    inertia_jacobian,
    stacked_least_squares,
)
from tests.helpers import URDFS

# The tool: 2.6 kg, a cylinder 16 cm long and 4 cm in radius along the UR5's wrist_3 axis (y in the link
# frame, wrist_3_joint's axis in ur5_robot.urdf), mounted on the flange (tool0, 0.0823 m out along that axis)
# with its centre of mass 8 cm beyond it.
TOOL_MASS, RADIUS, LENGTH = 2.6, 0.04, 0.16
TOOL_COM = np.array([0.0, 0.0823 + 0.08, 0.0])
TOOL_INERTIA = np.diag(
    [
        TOOL_MASS * (3 * RADIUS**2 + LENGTH**2) / 12,
        TOOL_MASS * RADIUS**2 / 2,
        TOOL_MASS * (3 * RADIUS**2 + LENGTH**2) / 12,
    ]
)
NOISE = 0.01  # of each joint's torque (or current) rms


@functools.cache
def ur5() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ad.load_urdf(URDFS["ur5"])


@functools.cache
def ur5_with_tool() -> ad.Robot:
    return ur5().with_payload(TOOL_MASS, TOOL_COM, TOOL_INERTIA)


def random_states(arm: ad.Robot, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    lower, upper = arm.qlim
    q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), (samples, arm.n))
    return q, rng.uniform(-2, 2, (samples, arm.n)), rng.uniform(-5, 5, (samples, arm.n))


def noisy(values: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return values + rng.standard_normal(values.shape) * NOISE * np.sqrt(np.mean(values**2, axis=0))


def torque_run(arm: ad.Robot, samples: int, seed: int) -> tuple[np.ndarray, ...]:
    q, qd, qdd = random_states(arm, samples, seed)
    return q, qd, qdd, noisy(arm.inverse_dynamics(q, qd, qdd), seed + 1000)


def assert_tool_found(estimate: PayloadEstimate) -> None:
    assert abs(estimate.mass - TOOL_MASS) < 0.02 * TOOL_MASS
    assert np.linalg.norm(estimate.com - TOOL_COM) < 5e-3
    truth = body_parameters(TOOL_MASS, TOOL_COM, TOOL_INERTIA)
    assert np.all(np.abs(estimate.phi - truth) < 4.5 * estimate.standard_errors)  # honest standard errors
    assert np.all(np.abs(estimate.com - TOOL_COM) < 4.5 * estimate.com_standard_errors)
    assert np.all(np.abs(estimate.inertia - TOOL_INERTIA) < 4.5 * estimate.inertia_standard_errors)
    low, high = estimate.mass_interval
    assert low < estimate.mass < high
    assert_allclose(high - low, 2 * 1.959964 * estimate.mass_standard_error, rtol=1e-5)


def test_body_parameters_are_what_with_payload_adds_to_the_tool_link() -> None:
    arm, loaded = ur5(), ur5_with_tool()
    block = slice(10 * arm.tool_link, 10 * arm.tool_link + 10)
    added = parameters(loaded)[block] - parameters(arm)[block]
    assert_allclose(body_parameters(TOOL_MASS, TOOL_COM, TOOL_INERTIA), added, atol=1e-12)


def test_payload_from_an_unloaded_and_a_loaded_run() -> None:
    estimate = identify_payload(ur5(), torque_run(ur5(), 500, 1), torque_run(ur5_with_tool(), 500, 2))
    assert_tool_found(estimate)
    assert estimate.link == ur5().tool_link and estimate.samples == 1000
    assert estimate.base is not None and estimate.base_phi is not None
    # the arm's own base parameters come out alongside: they predict the unloaded arm's torques
    q, qd, qdd = random_states(ur5(), 50, 3)
    predicted = estimate.base.regressor(q, qd, qdd) @ estimate.base_phi
    exact = ur5().inverse_dynamics(q, qd, qdd)
    assert np.sqrt(np.mean((predicted - exact) ** 2)) < 0.02 * np.sqrt(np.mean(exact**2))


def test_payload_from_the_arms_model_and_a_loaded_run() -> None:
    estimate = identify_payload(ur5(), None, torque_run(ur5_with_tool(), 500, 4), link="wrist_3_joint")
    assert_tool_found(estimate)
    assert estimate.base is None and estimate.base_phi is None and estimate.samples == 500


def test_payload_along_an_excitation_trajectory() -> None:
    trajectory = excitation_trajectory(ur5(), period=10.0, harmonics=3, samples=60, iterations=1)
    runs = []
    for seed, arm in enumerate((ur5(), ur5_with_tool())):
        data = identification_data(arm, trajectory, dt=0.01, method="inverse_dynamics")
        runs.append(dataclasses.replace(data, tau=noisy(data.tau, seed)))  # an object with q, qd, qdd, tau
    assert_tool_found(identify_payload(ur5(), runs[0], runs[1]))
    assert_tool_found(identify_payload(ur5(), None, runs[1]))


def test_standard_errors_match_the_spread_over_repeated_runs() -> None:
    estimates = [identify_payload(ur5(), None, torque_run(ur5_with_tool(), 120, 10 + k)) for k in range(40)]
    masses = np.array([e.mass for e in estimates])
    coms = np.array([e.com for e in estimates])
    # 40 draws: the sample standard deviation is within about 11% (one sigma) of the true one
    assert 0.7 < np.std(masses, ddof=1) / np.mean([e.mass_standard_error for e in estimates]) < 1.4
    ratio = np.std(coms, axis=0, ddof=1) / np.mean([e.com_standard_errors for e in estimates], axis=0)
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio


def test_delta_method_jacobians_are_the_derivatives() -> None:
    phi = body_parameters(TOOL_MASS, TOOL_COM, TOOL_INERTIA) + np.linspace(0.01, 0.1, 10) * 1e-2

    def derived(values: np.ndarray) -> np.ndarray:
        estimate = PayloadEstimate(5, "tool", values, np.eye(10), 1.0, 0.0, 1, None, None)
        inertia = estimate.inertia
        return np.concatenate(
            [estimate.com, [inertia[r, c] for r, c in ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))]]
        )

    step = 1e-6
    numeric = np.column_stack([(derived(phi + step * e) - derived(phi - step * e)) / (2 * step) for e in np.eye(10)])
    analytic = np.vstack([com_jacobian(phi[0], phi[1:4]), inertia_jacobian(phi[0], phi[1:4])])
    assert_allclose(analytic, numeric, atol=1e-7)


def test_apply_puts_the_estimated_payload_on_the_arm() -> None:
    q, qd, qdd = random_states(ur5(), 200, 5)
    exact = (q, qd, qdd, ur5_with_tool().inverse_dynamics(q, qd, qdd))  # noise-free: the estimate is the truth
    estimate = identify_payload(ur5(), None, exact)
    carried = estimate.apply(ur5())
    assert isinstance(carried, ad.Robot)
    assert_allclose(carried.links[-1].inertial.mass, ur5().links[-1].inertial.mass + TOOL_MASS)
    assert_allclose(carried.inverse_dynamics(q, qd, qdd), exact[3], atol=1e-9)
    point = estimate.apply(ur5(), inertia=False)
    expected = ur5().with_payload(TOOL_MASS, TOOL_COM)
    assert_allclose(point.inverse_dynamics(q, qd, qdd), expected.inverse_dynamics(q, qd, qdd), atol=1e-9)


def test_apply_refuses_an_estimated_inertia_no_rigid_body_has() -> None:
    phi = body_parameters(TOOL_MASS, TOOL_COM, TOOL_INERTIA)
    phi[4] -= 0.01  # Ixx about the origin: the moments about the centre of mass break the triangle inequality
    estimate = PayloadEstimate(5, "wrist_3_joint", phi, np.eye(10) * 1e-8, 1.0, 0.0, 1, None, None)
    with pytest.raises(ad.ModelError, match=r"estimated inertia .* is not a rigid body's.*inertia=False"):
        estimate.apply(ur5())
    assert_allclose(
        estimate.apply(ur5(), inertia=False).links[-1].inertial.mass, ur5().links[-1].inertial.mass + TOOL_MASS
    )


# --- error paths


def test_too_little_excitation_is_refused_naming_the_condition_number() -> None:
    q, qd, qdd, tau = torque_run(ur5_with_tool(), 100, 7)
    still = (np.repeat(q[:1], 100, 0), np.repeat(qd[:1], 100, 0), np.repeat(qdd[:1], 100, 0), tau)
    with pytest.raises(ad.ModelError, match=r"do not excite the 10 parameters of a payload.*condition number"):
        identify_payload(ur5(), None, still)
    with pytest.raises(ad.ModelError, match=r"condition number"):
        identify_payload(ur5(), torque_run(ur5(), 100, 8), still)


def test_too_few_samples_are_refused() -> None:
    q, qd, qdd, tau = torque_run(ur5_with_tool(), 1, 9)
    with pytest.raises(ad.ModelError, match=r"need more than 10 equations, got 6"):
        identify_payload(ur5(), None, (q, qd, qdd, tau))


def test_bad_runs_are_refused_naming_the_run_and_the_array() -> None:
    q, qd, qdd, tau = torque_run(ur5_with_tool(), 50, 11)
    unloaded = torque_run(ur5(), 50, 12)
    with pytest.raises(ad.ModelError, match=r"tau must have shape \(6,\) or \(\.\.\., 6\) in the loaded run"):
        identify_payload(ur5(), unloaded, (q, qd, qdd, tau[:, :5]))
    with pytest.raises(ad.ModelError, match=r"must hold the same samples.*tau \(49, 6\)"):
        identify_payload(ur5(), unloaded, (q, qd, qdd, tau[:49]))
    bad = tau.copy()
    bad[3, 2] = np.nan
    with pytest.raises(ad.ModelError, match=r"tau must be finite .* in the unloaded run"):
        identify_payload(ur5(), (q, qd, qdd, bad), (q, qd, qdd, tau))
    with pytest.raises(ad.ModelError, match=r"samples of shape \(N, 6\)"):
        identify_payload(ur5(), None, (q[0], qd[0], qdd[0], tau[0]))
    with pytest.raises(ad.ArgumentError, match=r"tuple \(q, qd, qdd, tau\), got a tuple of 3"):
        identify_payload(ur5(), None, (q, qd, qdd))
    with pytest.raises(ad.ArgumentError, match=r"has no qdd, tau"):
        identify_payload(ur5(), None, dataclasses.make_dataclass("Run", ["q", "qd"])(q, qd))


def test_bad_link_and_confidence_are_refused() -> None:
    run = torque_run(ur5_with_tool(), 50, 13)
    with pytest.raises(ad.ModelError, match=r"link index 6 is out of range for 'ur5.*' \(0..5\)"):
        identify_payload(ur5(), None, run, link=6)
    with pytest.raises(ad.ModelError, match=r"has no link 'flange'"):
        identify_payload(ur5(), None, run, link="flange")
    with pytest.raises(ad.ModelError, match=r"link must be an integer link index"):
        identify_payload(ur5(), None, run, link=2.0)  # type: ignore[arg-type]
    with pytest.raises(ad.ModelError, match=r"confidence must be a probability"):
        identify_payload(ur5(), None, run, confidence=1.5)
    with pytest.raises(ad.ArgumentError, match=r"arm"):
        identify_payload("ur5", None, run)  # type: ignore[arg-type]


def test_an_estimate_without_positive_mass_has_no_centre_of_mass() -> None:
    estimate = PayloadEstimate(5, "tool", np.r_[-0.1, np.zeros(9)], np.eye(10) * 1e-4, 1.0, 0.0, 1, None, None)
    with pytest.raises(ad.ModelError, match=r"estimated mass is -0.1 .* not positive"):
        _ = estimate.com
    with pytest.raises(ad.ModelError, match=r"not positive"):
        estimate.apply(ur5())


def test_apply_refuses_another_link_than_the_tool_link() -> None:
    estimate = identify_payload(ur5(), None, torque_run(ur5_with_tool(), 200, 14))
    other = ur5().replace(tool_link=4)
    with pytest.raises(ad.ModelError, match=r"identified on link 5 .* tool link of 'ur5.*' is link 4"):
        estimate.apply(other)


def test_least_squares_refuses_an_unknown_method() -> None:
    A = np.random.default_rng(0).standard_normal((20, 3))
    with pytest.raises(ad.ModelError, match=r"method must be 'ols' or 'tls'"):
        stacked_least_squares(A, A @ np.ones(3), np.zeros(20, dtype=int), "x", method="lasso")


def test_total_least_squares_solves_an_exact_system() -> None:
    A = np.random.default_rng(1).standard_normal((30, 4))
    x = np.array([1.0, -2.0, 0.5, 3.0])
    estimate = stacked_least_squares(A, A @ x, np.arange(30) % 3, "x", method="tls")
    assert_allclose(estimate.x, x, rtol=1e-9)


# --- drive gains from a known payload (Gautier and Briot 2014), PUMA 560

GAINS = np.array([2.5, 3.0, 1.5, 0.5, 0.8, 1.2])  # N m/A, joint side
PAYLOAD_MASS, PAYLOAD_COM = 3.0, np.array([0.08, 0.04, 0.06])
PAYLOAD_INERTIA = np.diag([0.02, 0.02, 0.03])


@functools.cache
def puma() -> ad.Robot:
    return ad.models.load("puma560")


@functools.cache
def current_runs(samples: int = 600) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    loaded_arm = puma().with_payload(PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA)
    runs = []
    for seed, arm in enumerate((puma(), loaded_arm)):
        q, qd, qdd = random_states(arm, samples, 20 + seed)
        current = noisy(arm.inverse_dynamics(q, qd, qdd) / GAINS, 30 + seed)
        runs.append((q, qd, qdd, current))
    return runs[0], runs[1]


@pytest.mark.parametrize("method", ["tls", "ols"])
def test_gains_from_a_run_with_a_known_payload(method: str) -> None:
    unloaded, loaded = current_runs()
    estimate = identify_gains(puma(), unloaded, loaded, PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA, method=method)
    assert isinstance(estimate, GainEstimate) and estimate.method == method
    assert np.all(np.abs(estimate.gains / GAINS - 1) < 0.02), estimate.gains / GAINS - 1
    if method == "tls":  # ordinary least squares is biased low by the noise of the currents (see identify_gains)
        assert np.all(np.abs(estimate.gains - GAINS) < 4.5 * estimate.gain_standard_errors)
    # the base parameters come out on the torque scale: they predict the arm's torques
    q, qd, qdd = random_states(puma(), 50, 40)
    exact = puma().inverse_dynamics(q, qd, qdd)
    predicted = estimate.base.regressor(q, qd, qdd) @ estimate.phi
    assert np.sqrt(np.mean((predicted - exact) ** 2)) < 0.03 * np.sqrt(np.mean(exact**2))
    assert_allclose(estimate.torques(unloaded[3]), unloaded[3] * estimate.gains)


def test_torques_from_currents_multiplies_each_joint_by_its_gain() -> None:
    current = np.arange(12.0).reshape(2, 6) - 5
    assert_allclose(torques_from_currents(current, GAINS), current * GAINS[None, :])
    assert_allclose(torques_from_currents(current[0], GAINS), current[0] * GAINS)
    with pytest.raises(ad.ModelError, match=r"gain 3 is 0"):
        torques_from_currents(current, [1.0, 2.0, 0.0, 1.0, 1.0, 1.0])
    with pytest.raises(ad.ModelError, match=r"current must have shape \(5,\) or \(\.\.\., 5\) for 5 gains"):
        torques_from_currents(current, GAINS[:5])
    with pytest.raises(ad.ModelError, match=r"gains must be a finite number"):
        torques_from_currents(current, [1.0, np.nan, 1.0, 1.0, 1.0, 1.0])


def test_gains_refuse_a_payload_without_mass_and_bad_shapes() -> None:
    unloaded, loaded = current_runs()
    for mass in (0.0, -3.0):
        with pytest.raises(ad.ModelError, match=r"payload_mass must be positive"):
            identify_gains(puma(), unloaded, loaded, mass)
    with pytest.raises(ad.ModelError, match=r"payload_mass must be finite"):
        identify_gains(puma(), unloaded, loaded, float("nan"))
    with pytest.raises(ad.ModelError, match=r"link 'payload': inertia tensor is not positive semi-definite"):
        identify_gains(puma(), unloaded, loaded, 3.0, payload_inertia=[1.0, -1.0, 1.0])
    q, qd, qdd, current = loaded
    with pytest.raises(ad.ModelError, match=r"current must have shape \(6,\) or \(\.\.\., 6\) in the loaded run"):
        identify_gains(puma(), unloaded, (q, qd, qdd, current[:, :5]), 3.0)
    with pytest.raises(ad.ArgumentError, match=r"tuple \(q, qd, qdd, current\) or have attributes"):
        identify_gains(puma(), unloaded, dataclasses.make_dataclass("Run", ["q", "qd", "qdd", "tau"])(*loaded), 3.0)
    with pytest.raises(ad.ModelError, match=r"method must be one of ols, tls"):
        identify_gains(puma(), unloaded, loaded, 3.0, method="ml")
    with pytest.raises(ad.ArgumentError, match=r"needs the unloaded run"):
        identify_gains(puma(), None, loaded, 3.0)  # type: ignore[arg-type]


def test_gains_refuse_runs_that_do_not_excite_them() -> None:
    loaded = current_runs()[1]
    still = tuple(np.repeat(array[:1], 600, 0) for array in loaded)
    with pytest.raises(ad.ModelError, match=r"do not excite the 6 drive gains and the \d+ base parameters.*condition"):
        identify_gains(puma(), still, still, 3.0)
