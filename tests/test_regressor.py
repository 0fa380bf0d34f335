"""The linear parameterization tau = W phi, base parameters and identification."""

from __future__ import annotations

import tracemalloc
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn.dynamics import regressor as regressor_module
from armdyn.dynamics.regressor import parameter_names
from tests.conftest import pinocchio_pair
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


def exciting(n: int, samples: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 10, samples, endpoint=False)[:, None, None]
    k = np.arange(1, 6)[None, None, :] * 2 * np.pi / 10
    a, b = rng.normal(0, 0.1, (2, 1, n, 5))
    return (
        (a * np.sin(k * t) + b * np.cos(k * t)).sum(-1),
        (k * (a * np.cos(k * t) - b * np.sin(k * t))).sum(-1),
        (-(k**2) * (a * np.sin(k * t) + b * np.cos(k * t))).sum(-1),
    )


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
def test_identify_refuses_data_that_do_not_excite_the_parameters() -> None:
    warning = regressor_module.PoorExcitationWarning
    poor, limit = regressor_module.POOR_CONDITION, regressor_module.MAX_CONDITION
    arm = ad.models.puma560()
    zeros = np.zeros((200, 6))
    with pytest.raises(ad.ModelError, match=r"do not excite the 58 base parameters.*rank 3 of 58"):
        ad.identify(arm, zeros, zeros, zeros, zeros)  # once: every estimate 0 +- 0
    q, qd, qdd = exciting(6, 400)
    tiny = [1e-5 * x for x in (q, qd, qdd)]  # full rank in exact arithmetic, not in floating point
    with pytest.raises(ad.ModelError, match=r"do not excite .*condition number"):
        ad.identify(arm, *tiny, arm.inverse_dynamics(*tiny))
    small = [1e-2 * x for x in (q, qd, qdd)]  # full rank, but a condition number near 1e9: a warning
    with pytest.warns(warning, match=r"poorly: .* condition number 1\.\d+e\+09"):
        result = ad.identify(arm, *small, arm.inverse_dynamics(*small))
    assert poor < result.condition_number < limit
    with warnings.catch_warnings():
        warnings.simplefilter("error", warning)  # well excited: no warning
        result = ad.identify(arm, q, qd, qdd, arm.inverse_dynamics(q, qd, qdd))
    assert result.condition_number < poor
    assert np.all(result.standard_errors >= 0) and np.all(np.isfinite(result.standard_errors))


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
         "robot must be an armdyn arm"),
        (lambda arm: regressor_module.parameters(None), TypeError, "robot must be an armdyn arm"),
        (lambda arm: parameter_names({}), TypeError, "robot must be an armdyn arm"),
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
        (lambda arm: ad.base_parameters(None), TypeError, "robot must be an armdyn arm"),
        (lambda arm: ad.base_parameters(arm).regressor("q", [0] * 6, [0] * 6), ad.ModelError, "q must be an array"),
        (lambda arm: ad.identify(arm, "q", *[np.zeros((20, 6))] * 3), ad.ModelError, "q must be an array of numbers"),
        (lambda arm: ad.identify(arm, *[np.zeros((20, 6))] * 3, None), ad.ModelError, "tau must be an array"),
        (lambda arm: ad.identify(arm, np.zeros((20, 6)), np.zeros(6), np.zeros((20, 6)), np.zeros((20, 6))),
         ad.ModelError, r"q, qd, qdd and tau must hold the same samples"),
        (lambda arm: ad.identify(arm, *[np.zeros((20, 6))] * 4, drives=1), TypeError, "drives must be True or False"),
        (lambda arm: ad.identify("arm", *[np.zeros((20, 6))] * 4), TypeError, "robot must be an armdyn arm"),
        (lambda arm: ad.identify(ad.models.two_link_planar(symbolic=True), *[np.zeros((20, 2))] * 4), TypeError,
         "robot 'two_link_planar' has symbolic"),
        (lambda arm: regressor_module.parameters(ad.models.polar_rp(symbolic=True)), TypeError, "has symbolic"),
    ],
)  # fmt: skip
def test_regressor_wrong_types_name_the_argument(call: object, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        call(ad.models.puma560())
