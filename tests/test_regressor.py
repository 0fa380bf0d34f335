"""The linear parameterization tau = W phi, base parameters and identification."""

from __future__ import annotations

import functools
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn.cli import app
from armdyn.control import ComputedTorque
from armdyn.dynamics import regressor as regressor_module
from armdyn.dynamics.regressor import parameter_names
from armdyn.identification import least_squares
from armdyn.identification.excitation import (
    FourierTrajectory,
    excitation_ranges,
    excitation_trajectory,
    identification_data,
)
from armdyn.identification.least_squares import FrictionMisfitWarning, PoorExcitationWarning
from tests.helpers import exciting, pinocchio_pair
from tests.strategies import random_robot, random_state


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 7))
def test_regressor_times_parameters_is_inverse_dynamics(seed: int, n: int) -> None:
    arm = random_robot(seed, n)
    q, qd, qdd = random_state(arm, seed)
    tau = arm.inverse_dynamics(q, qd, qdd)
    W = arm.regressor(q, qd, qdd)
    assert W.shape == (n, 14 * n)
    assert_allclose(W @ arm.parameters(), tau, rtol=0, atol=1e-10 * (1 + np.abs(tau).max()))


def test_regressor_is_batched() -> None:
    arm = ad.models.stanford()
    rng = np.random.default_rng(0)
    q, qd, qdd = (rng.uniform(-1, 1, (3, 4, 6)) for _ in range(3))
    W = arm.regressor(q, qd, qdd)
    assert W.shape == (3, 4, 6, 84)
    assert_allclose(W[2, 1], arm.regressor(q[2, 1], qd[2, 1], qdd[2, 1]), rtol=1e-14)
    assert_allclose(np.einsum("...ij,j->...i", W, arm.parameters()), arm.inverse_dynamics(q, qd, qdd), atol=1e-9)


def test_regressor_equals_pinocchio(urdf_path: object) -> None:
    import pinocchio as pin

    arm, model, data, qi, vi = pinocchio_pair(urdf_path)
    ids = [model.getJointId(name) for name in arm.joint_names]
    columns = np.concatenate([np.arange(10 * (j - 1), 10 * j) for j in ids])
    rng = np.random.default_rng(4)
    for _ in range(4):
        q, qd, qdd = rng.uniform(-2, 2, (3, arm.n))
        qp, vp, ap = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv)
        qp[qi], vp[vi], ap[vi] = q, qd, qdd
        expected = pin.computeJointTorqueRegressor(model, data, qp, vp, ap)[np.ix_(vi, columns)]
        assert_allclose(arm.regressor(q, qd, qdd)[:, : 10 * arm.n], expected, atol=1e-10)
        dynamic = np.concatenate([model.inertias[j].toDynamicParameters() for j in ids])
        assert_allclose(arm.parameters()[: 10 * arm.n], dynamic, atol=1e-12)


def test_base_parameter_count_equals_pinocchios_rank(urdf_path: object) -> None:
    import pinocchio as pin

    arm, model, data, qi, vi = pinocchio_pair(urdf_path)
    rng = np.random.default_rng(5)
    stacked = []
    for _ in range(150):
        qp, vp, ap = np.zeros(model.nq), np.zeros(model.nv), np.zeros(model.nv)
        qp[qi], vp[vi], ap[vi] = rng.uniform(-3, 3, (3, arm.n))
        stacked.append(pin.computeJointTorqueRegressor(model, data, qp, vp, ap).copy())
    rank = np.linalg.matrix_rank(np.vstack(stacked))
    assert len(ad.base_parameters(arm, drives=False)) == rank


def test_base_parameters_reproduce_tau() -> None:
    arm = ad.models.puma560()
    base = ad.base_parameters(arm)
    rng = np.random.default_rng(2)
    q, qd, qdd = rng.uniform(-2, 2, (3, 10, 6))
    assert_allclose(base.regressor(q, qd, qdd) @ base.phi, arm.inverse_dynamics(q, qd, qdd), atol=1e-9)
    assert base.regrouping.shape == (len(base), 84)
    assert_allclose(base.regrouping @ arm.parameters(), base.phi)
    assert all(isinstance(name, str) and name for name in base.names)
    names = parameter_names(arm)
    assert names[:10] == ["m1", "mx1", "my1", "mz1", "Ixx1", "Ixy1", "Iyy1", "Ixz1", "Iyz1", "Izz1"]
    assert names[60:64] == ["Fv1", "Fc+1", "Fc-1", "Ia1"]


def test_base_parameters_at_rest_explain_a_joint_at_rest() -> None:
    """The SCARA's vertical prismatic joint has a constant gravity torque: with every joint moving,
    [qd > 0] + [qd < 0] = 1 and its Coulomb columns take the constant in (the set identify estimates from
    moving data); at_rest=True keeps it apart, so that W_base phi_base = tau at rest too."""
    arm = ad.models.scara()
    moving, resting = ad.base_parameters(arm), ad.base_parameters(arm, at_rest=True)
    assert len(resting) == len(moving) + 1
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.uniform(-1, 1, (3, 8, arm.n))
    for base in (moving, resting):
        assert_allclose(base.regressor(q, qd, qdd) @ base.phi, arm.inverse_dynamics(q, qd, qdd), atol=1e-9)
    qd[:, 2] = 0.0
    tau = arm.inverse_dynamics(q, qd, qdd)
    assert_allclose(resting.regressor(q, qd, qdd) @ resting.phi, tau, atol=1e-9)
    assert np.abs(moving.regressor(q, qd, qdd) @ moving.phi - tau)[:, 2].min() > 1e-3


def test_identification_recovers_the_puma560_from_noise_free_data() -> None:
    arm = ad.models.puma560()
    q, qd, qdd = exciting(6, 1500)
    result = ad.identify(arm, q, qd, qdd, arm.inverse_dynamics(q, qd, qdd))
    assert_allclose(result.phi, result.base.phi, rtol=1e-8, atol=1e-8)
    assert result.residual_rms < 1e-10


def test_identification_reports_sensible_errors_with_noise() -> None:
    arm = ad.models.puma560()
    q, qd, qdd = exciting(6, 3000, seed=3)
    tau = arm.inverse_dynamics(q, qd, qdd)
    noisy = tau + np.random.default_rng(7).normal(0.0, 0.02, tau.shape)
    result = ad.identify(arm, q, qd, qdd, noisy)
    error = np.abs(result.phi - result.base.phi)
    assert np.mean(error <= 3 * result.standard_errors) > 0.9  # about 99.7% for Gaussian errors
    assert abs(result.residual_rms - 0.02) < 0.002  # the residual reflects the noise level
    assert np.isfinite(result.condition_number) and result.condition_number > 1


def test_identification_checks_its_input() -> None:
    arm = ad.models.puma560()
    q = np.zeros((5, 6))
    with pytest.raises(ad.ModelError, match="needs more than"):
        ad.identify(arm, q, q, q, q)
    with pytest.raises(ad.ModelError, match="tau must have shape"):
        ad.identify(arm, q, q, q, np.zeros((5, 4)))


# ----- excitation, memory and arguments ---------------------------------------------------
@pytest.mark.slow
def test_identify_refuses_data_that_do_not_excite_the_parameters() -> None:
    warning = least_squares.PoorExcitationWarning
    poor, limit = least_squares.POOR_CONDITION, least_squares.MAX_CONDITION
    arm = ad.models.puma560()
    zeros = np.zeros((200, 6))
    with pytest.raises(ad.ModelError, match=r"do not excite the 58 base parameters.*rank 3 of 58"):
        ad.identify(arm, zeros, zeros, zeros, zeros)  # once: every estimate 0 +- 0
    q, qd, qdd = exciting(6, 400)
    tiny = [1e-5 * x for x in (q, qd, qdd)]  # full rank in exact arithmetic, not in floating point
    with pytest.raises(ad.ModelError, match=r"do not excite .*condition number"):
        ad.identify(arm, *tiny, arm.inverse_dynamics(*tiny))
    small = [1e-2 * x for x in (q, qd, qdd)]  # full rank, but a condition number near 1e9: a warning
    with pytest.warns(warning, match=r"poorly: .* condition number \d\.\d+e\+0[89]"):
        result = ad.identify(arm, *small, arm.inverse_dynamics(*small))
    assert poor < result.condition_number < limit
    with warnings.catch_warnings():
        warnings.simplefilter("error", warning)  # well excited: no warning
        result = ad.identify(arm, q, qd, qdd, arm.inverse_dynamics(q, qd, qdd))
    assert result.condition_number < poor
    assert np.all(result.standard_errors >= 0) and np.all(np.isfinite(result.standard_errors))


@pytest.mark.slow
def test_regressor_is_computed_in_chunks_with_bounded_memory() -> None:
    arm = ad.models.puma560()
    q, qd, qdd = np.random.default_rng(3).uniform(-1, 1, (3, 20_000, 6))
    arm.regressor(q[:10], qd[:10], qdd[:10])
    tracemalloc.start()
    try:
        W = arm.regressor(q, qd, qdd)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert W.shape == (20_000, 6, 84)
    assert peak < W.nbytes + 16 * regressor_module.CHUNK_BYTES  # once 5 times W's size
    for i in (0, 4_999, 19_999):  # block boundaries and the last state
        assert_allclose(W[i], arm.regressor(q[i], qd[i], qdd[i]), rtol=1e-14, atol=1e-14)
    assert_allclose(np.einsum("...ij,j->...i", W, arm.parameters()), arm.inverse_dynamics(q, qd, qdd), atol=1e-9)


def test_a_regressor_too_large_for_memory_is_refused_beforehand(tmp_path: object, monkeypatch: object) -> None:
    arm = ad.models.puma560()
    q = np.random.default_rng(4).uniform(-1, 1, (1_000, 6))
    monkeypatch.setattr(regressor_module, "MEMORY_LIMIT", 2**20)  # 1 MiB
    with pytest.raises(ad.ModelError, match=r"1000 states of 'puma560' needs 3\.85 MiB .* limit of 1 MiB"):
        arm.regressor(q, q, q)
    out = np.memmap(tmp_path / "W.dat", dtype=np.float64, mode="w+", shape=(1_000, 6, 84))
    assert arm.regressor(q, q, q, out=out) is out  # out= writes where the caller says, whatever its size
    assert_allclose(out[500], arm.regressor(q[500], q[500], q[500]), rtol=1e-14, atol=1e-14)
    with pytest.raises(ad.ModelError, match=r"out must be a writable C-contiguous float64 array of shape"):
        arm.regressor(q, q, q, out=np.empty((1_000, 6, 83)))
    monkeypatch.setattr(regressor_module, "MEMORY_LIMIT", None)
    assert regressor_module._memory_limit() >= 2**30  # half the machine's memory


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda arm: arm.regressor("q", [0] * 6, [0] * 6), ad.ModelError, "q must be an array of numbers"),
        (lambda arm: arm.regressor([0] * 6, None, [0] * 6), ad.ModelError, "qd must be an array of numbers"),
        (lambda arm: arm.regressor([0] * 6, [0] * 6, {"a": 1}), ad.ModelError, "qdd must be an array of numbers"),
        (lambda arm: arm.regressor([0j] * 6, [0] * 6, [0] * 6), ad.ModelError, "q must be real"),
        (lambda arm: arm.regressor(np.zeros((3, 6)), np.zeros((4, 6)), [0] * 6), ad.ModelError,
         r"batch shapes of q \(3, 6\), qd \(4, 6\)"),
        (lambda arm: regressor_module.regressor("puma560", [0] * 6, [0] * 6, [0] * 6), TypeError,
         "arm must be an armdyn ArmModel"),
        (lambda arm: regressor_module.parameters(None), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: parameter_names({}), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: regressor_module.body_regressor("w", [0] * 3, [0] * 3, [0] * 3), ad.ModelError,
         "w must be an array of numbers"),
        (lambda arm: regressor_module.body_regressor([0] * 3, [0] * 3, [0] * 2, [0] * 3), ad.ModelError,
         r"alpha must have shape \(3,\)"),
        (lambda arm: ad.base_parameters(arm, samples="200"), TypeError, "samples must be an integer"),
        (lambda arm: ad.base_parameters(arm, samples=0), ad.ModelError, "samples must be at least 1"),
        (lambda arm: ad.base_parameters(arm, seed=1.5), TypeError, "seed must be an integer"),
        (lambda arm: ad.base_parameters(arm, tolerance="small"), ad.ModelError, "tolerance must be"),
        (lambda arm: ad.base_parameters(arm, tolerance=2.0), ad.ModelError, r"tolerance must be one number in \(0"),
        (lambda arm: ad.base_parameters(arm, drives="yes"), TypeError, "drives must be True or False"),
        (lambda arm: ad.base_parameters(arm, at_rest=1), TypeError, "at_rest must be True or False"),
        (lambda arm: ad.base_parameters(None), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: ad.base_parameters(arm).regressor("q", [0] * 6, [0] * 6), ad.ModelError, "q must be an array"),
        (lambda arm: ad.identify(arm, "q", *[np.zeros((20, 6))] * 3), ad.ModelError, "q must be an array of numbers"),
        (lambda arm: ad.identify(arm, *[np.zeros((20, 6))] * 3, None), ad.ModelError, "tau must be an array"),
        (lambda arm: ad.identify(arm, np.zeros((20, 6)), np.zeros(6), np.zeros((20, 6)), np.zeros((20, 6))),
         ad.ModelError, r"q, qd, qdd and tau must hold the same samples"),
        (lambda arm: ad.identify(arm, *[np.zeros((20, 6))] * 4, drives=1), TypeError, "drives must be True or False"),
        (lambda arm: ad.identify("arm", *[np.zeros((20, 6))] * 4), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: ad.identify(ad.models.two_link_planar(symbolic=True), *[np.zeros((20, 2))] * 4), TypeError,
         "arm 'two_link_planar' has symbolic"),
        (lambda arm: regressor_module.parameters(ad.models.polar_rp(symbolic=True)), TypeError, "has symbolic"),
    ],
)  # fmt: skip
def test_regressor_wrong_types_name_the_argument(call: object, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        call(ad.models.puma560())


# ----- identification as a workflow: excitation, data the regressor explains, honest errors ----------
@functools.cache
def puma_excitation() -> FourierTrajectory:
    """The PUMA 560's excitation trajectory of the round trip (a few seconds to optimize)."""
    return excitation_trajectory(ad.models.puma560(), samples=50, iterations=20, seed=0)


@pytest.mark.slow
def test_identification_round_trip_recovers_the_puma560_base_parameters() -> None:
    start = time.perf_counter()
    arm = ad.models.puma560()
    trajectory = puma_excitation()
    assert trajectory.condition_number < 100  # the command line's sine trajectories: 2.1e4
    data = identification_data(arm, trajectory, dt=5e-3, noise=0.5, seed=1)  # simulated, computed torque
    assert data.method == "simulate" and data.q.shape == (2001, 6)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoorExcitationWarning)
        warnings.simplefilter("error", FrictionMisfitWarning)
        result = ad.identify(arm, data.q, data.qd, data.qdd, data.tau)
        exact = ad.identify(arm, data.q, data.qd, data.qdd, data.tau_exact)
    # the simulated torques are W phi to rounding: friction is the regressor's sign law
    assert exact.residual_rms < 1e-10
    assert_allclose(exact.phi, exact.base.phi, rtol=1e-8, atol=1e-8)
    z = result.normalized_errors
    assert result.condition_number < 100
    assert np.mean(np.abs(z) <= 3) >= 0.9  # 99.7% for honest standard errors
    assert np.abs(z).max() < 4.5
    assert 0.7 < np.std(z) < 1.4 and abs(np.mean(z)) < 0.5  # standardized errors of about unit variance
    assert abs(result.residual_rms - 0.5) < 0.02
    assert time.perf_counter() - start < 60  # about 5 s on one free core


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::armdyn.simulation.PythonLoopWarning")
def test_simulated_smoothed_friction_is_warned_of_and_left_out_by_a_velocity_band() -> None:
    arm = ad.models.puma560()
    trajectory = puma_excitation()
    q0, qd0, _ = trajectory(0.0)
    run = ad.simulate(arm, ComputedTorque(100, 20), trajectory, t_final=trajectory.period, dt=5e-3, q0=q0, qd0=qd0)
    tau = run.tau + np.random.default_rng(2).normal(0.0, 0.5, run.tau.shape)
    with pytest.warns(FrictionMisfitWarning, match=r"near zero velocity do not follow the Coulomb sign law.*'q1'"):
        biased = ad.identify(arm, run.q, run.qd, run.qdd, tau)
    assert np.abs(biased.normalized_errors).max() > 10  # the bias the issue reported, now with a warning
    # simulate's smoothing eps is at most 0.041 rad/s here (Tc dt / M_ii): 0.5 rad/s is 12 eps
    with warnings.catch_warnings():
        warnings.simplefilter("error", FrictionMisfitWarning)
        banded = ad.identify(arm, run.q, run.qd, run.qdd, tau, velocity_band=0.5)
    assert 0.3 * run.q.size < banded.left_out < 0.6 * run.q.size
    assert np.mean(np.abs(banded.normalized_errors) <= 3) >= 0.9
    assert np.abs(banded.normalized_errors).max() < 4.5


@pytest.mark.slow
def test_excitation_trajectory_keeps_the_limits_and_is_a_trajectory() -> None:
    arm = ad.models.puma560()
    trajectory = puma_excitation()
    lower, upper = excitation_ranges(arm)
    t = np.linspace(0.0, trajectory.period, 20_001)
    q, qd, qdd = trajectory(t)
    assert q.shape == qd.shape == qdd.shape == (20_001, 6)
    assert np.all(q >= lower) and np.all(q <= upper)
    assert_allclose(np.gradient(q, t, axis=0)[1:-1], qd[1:-1], atol=1e-5)
    assert_allclose(np.gradient(qd, t, axis=0)[1:-1], qdd[1:-1], atol=1e-5)
    assert_allclose(q[0], q[-1], atol=1e-12)  # periodic
    W = ad.base_parameters(arm).regressor(*trajectory(trajectory.sample_times(50)))
    assert_allclose(np.linalg.cond(W.reshape(-1, W.shape[-1])), trajectory.condition_number, rtol=1e-6)
    # a scalar time gives one state; the series is Swevers' form
    one = trajectory(1.25)
    w = trajectory.frequency * np.arange(1, trajectory.harmonics + 1)
    expected = trajectory.q0 + (trajectory.a / w * np.sin(w * 1.25) - trajectory.b / w * np.cos(w * 1.25)).sum(-1)
    assert_allclose(one[0], expected, rtol=1e-14)
    # velocity limits, and a start: a planar arm (fast)
    planar = ad.models.two_link_planar()
    limited = excitation_trajectory(planar, period=4.0, harmonics=3, velocity_limits=[1.0, 0.5], iterations=30)
    q, qd, _ = limited(np.linspace(0.0, 4.0, 8001))
    assert np.abs(qd).max(0)[0] <= 1.0 and np.abs(qd).max(0)[1] <= 0.5
    assert np.all(q >= -np.pi) and np.all(q <= np.pi)  # no limits: a whole turn
    rough = excitation_trajectory(planar, period=4.0, harmonics=3, iterations=1, seed=4)
    better = excitation_trajectory(planar, period=4.0, harmonics=3, start=rough, iterations=30)
    assert better.condition_number <= rough.condition_number


@pytest.mark.slow
def test_identify_standard_errors_follow_each_joints_noise() -> None:
    """Noise of 1 N m on the base joint and 5 mN m on the wrist: each joint's own residual variance
    keeps every parameter's standardized error near unit variance; the pooled variance made the
    wrist parameters' standard errors about ten times too large and others twice too small."""
    arm = ad.models.puma560()
    q, qd, qdd = exciting(6, 1500, seed=3)
    tau = arm.inverse_dynamics(q, qd, qdd)
    sigma = np.array([1.0, 0.5, 0.3, 0.02, 0.01, 0.005])
    rng = np.random.default_rng(11)
    base = ad.base_parameters(arm)
    W = base.regressor(q, qd, qdd).reshape(-1, len(base))
    pooled_scale = np.sqrt(np.diag(np.linalg.inv(W.T @ W)) * W.shape[0] / (W.shape[0] - len(base)))
    z, pooled = [], []
    for _ in range(20):
        result = ad.identify(arm, q, qd, qdd, tau + rng.standard_normal(tau.shape) * sigma)
        z.append(result.normalized_errors)
        pooled.append((result.phi - result.base.phi) / (result.residual_rms * pooled_scale))
    spread, pooled_spread = np.std(z, axis=0), np.std(pooled, axis=0)
    assert 0.85 < np.std(z) < 1.15
    assert spread.min() > 0.45 and spread.max() < 1.7, (spread.min(), spread.max())  # 20 draws each
    assert pooled_spread.min() < 0.3 and pooled_spread.max() > 1.7  # what the pooled variance gave


def test_identification_data_by_inverse_dynamics_and_with_noise_on_q() -> None:
    arm = ad.models.two_link_planar()
    trajectory = FourierTrajectory(4.0, [0.1, -0.2], [[0.3, 0.1], [-0.2, 0.4]], [[0.0, 0.2], [0.1, -0.1]])
    data = identification_data(arm, trajectory, dt=0.01, noise=[0.1, 0.0], position_noise=1e-3, seed=5,
                               method="inverse_dynamics")  # fmt: skip
    assert data.t.shape == (401,) and data.t[-1] == pytest.approx(4.0)
    q, qd, qdd = trajectory(data.t)
    assert_allclose(data.qd, qd) and assert_allclose(data.qdd, qdd)
    assert_allclose(data.tau_exact, arm.inverse_dynamics(q, qd, qdd), atol=1e-12)
    assert 0.08 < np.std(data.tau[:, 0] - data.tau_exact[:, 0]) < 0.12
    assert_allclose(data.tau[:, 1], data.tau_exact[:, 1])  # no noise on joint 2
    assert 8e-4 < np.std(data.q - q) < 1.2e-3
    again = identification_data(arm, trajectory, dt=0.01, noise=[0.1, 0.0], position_noise=1e-3, seed=5,
                                method="inverse_dynamics")  # fmt: skip
    assert_allclose(again.tau, data.tau)  # the seed fixes the noise
    simulated = identification_data(arm, trajectory, dt=0.01)
    assert simulated.method == "simulate"
    assert_allclose(simulated.q, q, atol=1e-2)  # tracked closely from the trajectory's own start


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda arm: excitation_trajectory("arm"), "arm must be an armdyn ArmModel"),
        (lambda arm: excitation_trajectory(ad.models.two_link_planar(symbolic=True)), "has symbolic"),
        (lambda arm: excitation_trajectory(arm, period=0), "period must be a positive finite number"),
        (lambda arm: excitation_trajectory(arm, period="10"), "period must be a positive number"),
        (lambda arm: excitation_trajectory(arm, harmonics=0), "harmonics must be at least 1"),
        (lambda arm: excitation_trajectory(arm, harmonics=2.5), "harmonics must be an integer"),
        (lambda arm: excitation_trajectory(arm, samples=5), r"samples must give more equations than the 58"),
        (lambda arm: excitation_trajectory(arm, seed=-1), "seed must be at least 0"),
        (lambda arm: excitation_trajectory(arm, iterations=0), "iterations must be at least 1"),
        (lambda arm: excitation_trajectory(arm, velocity_limits=[1, 2]), "velocity_limits must be one number or 6"),
        (lambda arm: excitation_trajectory(arm, velocity_limits=0), "velocity_limits must be positive"),
        (lambda arm: excitation_trajectory(arm, drives="yes"), "drives must be True or False"),
        (lambda arm: excitation_trajectory(arm, start="sine"), "start must be a FourierTrajectory"),
        (lambda arm: excitation_trajectory(arm, harmonics=2, start=FourierTrajectory(10.0, [0] * 6, [[1]] * 6,
                                                                                     [[0]] * 6)),
         "start has 6 joints, 1 harmonics"),
        (lambda arm: FourierTrajectory(-1.0, [0], [[1]], [[0]]), "period must be a positive finite number"),
        (lambda arm: FourierTrajectory(1.0, [0, 0], [[1]], [[0]]), r"a must have shape \(2, H\)"),
        (lambda arm: FourierTrajectory(1.0, [0], [[1]], [[0, 1]]), "a and b must have the same shape"),
        (lambda arm: FourierTrajectory(1.0, [0], [[np.nan]], [[0]]), "a must be finite"),
        (lambda arm: FourierTrajectory(1.0, [0], [[1]], [[0]])("t"), "t must be a time"),
        (lambda arm: FourierTrajectory(1.0, [0], [[1]], [[0]])(0.0, 2), "has 1 joints, not 2"),
        (lambda arm: identification_data(arm.without_friction(), "path", 1.0), "trajectory must be callable"),
        (lambda arm: identification_data(arm, lambda t: (t, t, t)), "t_final is needed"),
        (lambda arm: identification_data(arm, puma_like(), t_final=-1), "t_final must be a positive finite"),
        (lambda arm: identification_data(arm, puma_like(), dt=2.0, t_final=1.0), "dt must not exceed t_final"),
        (lambda arm: identification_data(arm, puma_like(), noise=-0.1), "noise must be non-negative"),
        (lambda arm: identification_data(arm, puma_like(), position_noise=[1, 2]), "position_noise must be one"),
        (lambda arm: identification_data(arm, puma_like(), seed=1.5), "seed must be an integer"),
        (lambda arm: identification_data(arm, puma_like(), method="euler"), "method must be one of simulate"),
        (lambda arm: identification_data(arm, puma_like(), method="inverse_dynamics", controller=ComputedTorque(1, 1)),
         "controller is for method='simulate'"),
        (lambda arm: identification_data(arm.links, puma_like()), "arm must be an armdyn Robot"),
        (lambda arm: ad.identify(arm, *[np.zeros((20, 6))] * 4, velocity_band=-1.0), "velocity_band must be a finite"),
        (lambda arm: ad.identify(arm, *[np.zeros((20, 6))] * 4, velocity_band="0.1"), "velocity_band must be a number"),
        (lambda arm: ad.identify(arm, *exciting(6, 20), np.zeros((20, 6)), velocity_band=10.0),
         r"needs more than 58 joint equations .* got 0 from 20 samples \(120 left out by velocity_band = 10\)"),
    ],
)  # fmt: skip
def test_excitation_and_identification_data_check_their_arguments(call: object, message: str) -> None:
    with pytest.raises(ad.ModelError, match=message):
        call(ad.models.puma560())


def puma_like() -> FourierTrajectory:
    return FourierTrajectory(1.0, [0.0] * 6, [[0.1]] * 6, [[0.0]] * 6)


@pytest.mark.slow
def test_cli_identify_generates_its_samples(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    estimates = tmp_path / "estimates.csv"
    args = ["identify", "two_link_planar", "--generate", "--noise", "0.05", "--seed", "2", "--period", "4",
            "--harmonics", "3", "--dt", "0.004", "-o", str(estimates)]  # fmt: skip
    result = CliRunner().invoke(app, args, prog_name="armdyn")
    assert result.exit_code == 0, result.output
    assert "cond(W) =" in result.stdout and "std. error" in result.stdout
    assert "base parameters within 3 standard errors of the model values" in result.stdout
    table = np.genfromtxt(estimates, delimiter=",", names=True, dtype=None, encoding="utf-8")
    arm = ad.models.two_link_planar()
    assert len(table) == len(ad.base_parameters(arm))
    z = (table["estimate"] - table["model_value"]) / table["standard_error"]
    assert np.all(np.abs(z) < 4.5) and np.all(table["standard_error"] > 0)


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["identify", "two_link_planar"], "give a CSV file of samples"),
        (["identify", "two_link_planar", "x.csv", "--generate"], "not both"),
        (["identify", "two_link_planar", "x.csv", "--noise", "0.2", "--seed", "3"], "--noise, --seed go with"),
        (["identify", "two_link_planar", "--generate", "--noise", "-1"], "--noise must be a finite number >= 0"),
        (["identify", "two_link_planar", "--generate", "--harmonics", "0"], "harmonics must be at least 1"),
        (["identify", "two_link_planar", "--generate", "--velocity-band", "-1"], "--velocity-band must be a"),
        (["identify", "two_link_planar", "--generate", "--period", "0"], "period must be a positive finite number"),
    ],
)  # fmt: skip
def test_cli_identify_needs_a_csv_file_or_generate(args: list[str], fragment: str) -> None:
    from typer.testing import CliRunner

    result = CliRunner().invoke(app, args, prog_name="armdyn")
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], result.stderr
