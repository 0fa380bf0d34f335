"""The linear parameterization tau = W phi, base parameters and identification."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

import armdyn as ad
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
