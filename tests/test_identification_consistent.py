"""Physically consistent estimation: pseudo-inertia, per-link consistency, the semidefinite program on
torques simulated from the PUMA 560 and the 7-joint Panda (known truth), its bounds, prior and error paths."""

from __future__ import annotations

import time
import warnings
from functools import cache

import numpy as np
import pytest
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn import ModelError
from armdyn.dynamics.regressor import base_parameters, identify, parameters, regressor
from armdyn.identification.consistent import (
    ConsistentEstimate,
    bounds_from_prior,
    consistent_estimate,
    link_consistency,
    pseudo_inertia,
)
from tests.helpers import URDFS

FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


@cache
def _panda() -> ad.Robot:
    return ad.load_urdf(URDFS["panda"], tool_link="panda_hand_tcp", locked=FINGERS)


@cache
def _puma() -> ad.Robot:
    return ad.models.load("puma560")


def _samples(arm: ad.Robot, samples: int, noise: object, seed: int = 0) -> tuple[np.ndarray, ...]:
    """Random states within the joint limits; torques with noise * (each joint's RMS torque) Gaussian noise."""
    rng = np.random.default_rng(seed)
    lower, upper = arm.qlim
    lower, upper = np.where(np.isfinite(lower), lower, -np.pi), np.where(np.isfinite(upper), upper, np.pi)
    q = rng.uniform(lower, upper, (samples, arm.n))
    qd, qdd = rng.uniform(-2, 2, (2, samples, arm.n))
    tau = arm.inverse_dynamics(q, qd, qdd)
    sigma = np.asarray(noise) * np.sqrt(np.mean(tau**2, axis=0))
    return q, qd, qdd, tau + rng.normal(size=tau.shape) * sigma


def _stacked(arm: ad.Robot, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, ...]:
    W = regressor(arm, q, qd, qdd)
    return W.reshape(-1, W.shape[-1]), tau.reshape(-1)


# ----- pseudo-inertia and the consistency table ----------------------------------------------------------------
def test_pseudo_inertia_equals_the_links_own() -> None:
    """J from the ten parameters equals Inertial.pseudo_inertia (integral of [r 1][r 1]^T dm), per link and batched."""
    arm = _panda()
    phi = parameters(arm)[: 10 * arm.n].reshape(arm.n, 10)
    expected = np.array([link.inertial.pseudo_inertia() for link in arm.links])
    assert_allclose(pseudo_inertia(phi), expected, rtol=0, atol=1e-15)
    assert_allclose(pseudo_inertia(phi[2]), expected[2], rtol=0, atol=1e-15)
    assert pseudo_inertia(np.broadcast_to(phi, (3, arm.n, 10))).shape == (3, arm.n, 4, 4)


def test_pseudo_inertia_of_a_point_mass() -> None:
    """A point mass m at c: J = m [c 1][c 1]^T, rank one."""
    m, c = 2.0, np.array([0.1, -0.2, 0.3])
    inertia = m * ((c @ c) * np.eye(3) - np.outer(c, c))
    phi = [m, *(m * c), inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2], inertia[1, 2], inertia[2, 2]]
    assert_allclose(pseudo_inertia(phi), m * np.outer([*c, 1], [*c, 1]), rtol=0, atol=1e-15)


@pytest.mark.parametrize("bad", [np.zeros(9), np.zeros((3, 11)), 1.0, [np.nan] * 10, "mass"])
def test_pseudo_inertia_refuses_bad_parameters(bad: object) -> None:
    with pytest.raises(ModelError, match="phi10"):
        pseudo_inertia(bad)


def test_link_consistency_of_the_panda_and_the_published_puma() -> None:
    """The Panda's URDF links are consistent, with the principal moments of their inertia about the centre of
    mass; the PUMA 560's published link 1 (no mass, one moment) and link 3 are not."""
    panda = link_consistency(parameters(_panda())[:70])
    assert panda["consistent"].all() and panda["triangle"].all()
    assert list(panda.columns[:6]) == ["mass", "J_eig1", "J_eig2", "J_eig3", "J_eig4", "J_min"]
    moments = np.array([np.linalg.eigvalsh(link.inertial.inertia) for link in _panda().links])
    assert_allclose(panda[["I1", "I2", "I3"]].to_numpy(), moments, rtol=1e-9, atol=1e-12)
    assert_allclose(panda["mass"], [link.inertial.mass for link in _panda().links])
    puma = link_consistency(parameters(_puma())[:60].reshape(6, 10))
    assert puma["consistent"].tolist() == [False, True, False, True, True, True]
    assert puma.loc[3, "J_min"] < -1e-3 and not puma.loc[1, "triangle"]  # link 1: m = 0, moments (0, 0.35, 0)


def test_link_consistency_flags_impossible_bodies() -> None:
    """A negative mass and principal moments breaking the triangle inequality (1 + 1 < 3) are inconsistent."""
    good = [1.0, 0, 0, 0, 0.2, 0, 0.2, 0, 0, 0.2]
    negative = [-1.0, 0, 0, 0, 0.2, 0, 0.2, 0, 0, 0.2]
    triangle = [1.0, 0, 0, 0, 1.0, 0, 1.0, 0, 0, 3.0]
    table = link_consistency([good, negative, triangle])
    assert table["consistent"].tolist() == [True, False, False]
    assert table["triangle"].tolist() == [True, False, False]
    assert np.isnan(table.loc[2, "I1"])
    with pytest.raises(ModelError, match=r"phi_links must have shape \(L, 10\)"):
        link_consistency(np.zeros(15))
    with pytest.raises(ModelError, match="tolerance"):
        link_consistency(good, tolerance=-1)


# ----- the semidefinite program on simulated data --------------------------------------------------------------
def test_well_excited_panda_gives_least_squares_base_parameters_with_consistent_links() -> None:
    """2,000 random states of the Panda, 2% torque noise: every link consistent, the residual RMS that of least
    squares (within 5%), and the base parameters those of ``identify`` (within 1% of a standard error) and so
    within 4.5 standard errors of the truth."""
    arm = _panda()
    q, qd, qdd, tau = _samples(arm, 2000, 0.02)
    W, y = _stacked(arm, q, qd, qdd, tau)
    estimate = consistent_estimate(W, y, arm.n)
    assert isinstance(estimate, ConsistentEstimate)
    assert estimate.status == "optimal" and estimate.solver == "CLARABEL"
    assert estimate.consistency["consistent"].all()
    assert estimate.consistency["J_min"].min() >= -1e-8
    assert estimate.ls_rms <= estimate.residual_rms <= 1.05 * estimate.ls_rms
    assert_allclose(estimate.residual_rms, np.sqrt(np.mean((W @ estimate.phi - y) ** 2)), rtol=1e-8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ls = identify(arm, q, qd, qdd, tau)
    assert_allclose(estimate.ls_rms, ls.residual_rms, rtol=1e-8)
    base = estimate.base(ls.base)
    assert np.max(np.abs(base - ls.phi) / ls.standard_errors) < 0.01
    assert np.max(np.abs(base - ls.base.phi) / ls.standard_errors) < 4.5
    assert_allclose(estimate.base(ls.base.regrouping), base)
    assert estimate.link_parameters.shape == (7, 10) and estimate.extra.shape == (28,)


def test_puma_estimate_is_consistent_though_the_published_model_is_not() -> None:
    """The PUMA 560 (friction and motor inertia as the 24 extra columns), 1% noise: the published model's links
    1 and 3 are inconsistent, the estimate's are all consistent, at a residual within 5% of least squares, and
    its rigid base parameters are those of the published model to a few standard errors."""
    arm = _puma()
    q, qd, qdd, tau = _samples(arm, 2000, 0.01, seed=1)
    W, y = _stacked(arm, q, qd, qdd, tau)
    estimate = consistent_estimate(W, y, arm.n)
    assert (estimate.consistency["J_min"] >= -1e-8).all()
    assert estimate.residual_rms <= 1.05 * estimate.ls_rms
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ls = identify(arm, q, qd, qdd, tau)
    assert np.max(np.abs(estimate.base(ls.base) - ls.base.phi) / ls.standard_errors) < 10


def test_few_noisy_samples_give_inconsistent_least_squares_and_a_consistent_estimate() -> None:
    """20 samples, 5% noise (10% on the wrist): least squares (the same objective without the constraints) makes
    links physically impossible; the semidefinite program keeps every pseudo-inertia positive semi-definite."""
    arm = _panda()
    noise = [0.05] * 5 + [0.1, 0.1]
    W, y = _stacked(arm, *_samples(arm, 20, noise, seed=3))
    estimate = consistent_estimate(W, y, arm.n, prior=parameters(arm), regularization=1e-6)
    unconstrained = link_consistency(estimate.unconstrained_phi[:70])
    assert not unconstrained["consistent"].all()
    assert unconstrained["J_min"].min() < -1e-2
    assert estimate.consistency["consistent"].all()
    assert estimate.consistency["J_min"].min() >= -1e-8
    assert estimate.residual_rms >= estimate.ls_rms


def test_huge_regularization_returns_the_prior() -> None:
    """A consistent prior (the Panda's links 20% heavier, friction 0.01) with regularization 1e9: the estimate is
    the prior, not the truth the data come from."""
    arm = _panda()
    W, y = _stacked(arm, *_samples(arm, 300, 0.01))
    prior = parameters(arm)
    prior[:70] *= 1.2
    prior[70::4] = 0.01
    estimate = consistent_estimate(W, y, arm.n, prior=prior, regularization=1e9)
    assert_allclose(estimate.phi, prior, rtol=1e-5, atol=1e-7)
    loose = consistent_estimate(W, y, arm.n, prior=prior, regularization=1e-9)
    assert np.max(np.abs(loose.phi - prior)) > 0.1


def test_mass_bounds_are_respected() -> None:
    """Masses bounded to within 5% of a prior 30% too light: the data pull them up, they stop at the bounds."""
    arm = _panda()
    W, y = _stacked(arm, *_samples(arm, 500, 0.01))
    truth = parameters(arm)
    bounds = bounds_from_prior(0.7 * truth, arm.n, mass_tolerance=0.05)
    assert_allclose(bounds, np.column_stack([0.665 * truth[:70:10], 0.735 * truth[:70:10]]))
    free = consistent_estimate(W, y, arm.n)
    estimate = consistent_estimate(W, y, arm.n, mass_bounds=bounds)
    mass = estimate.phi[:70:10]
    assert np.all(mass >= bounds[:, 0] - 1e-7) and np.all(mass <= bounds[:, 1] + 1e-7)
    assert np.any(free.phi[:70:10] > bounds[:, 1] + 0.1)  # without bounds some mass is well above them
    assert estimate.consistency["consistent"].all()
    assert estimate.residual_rms > free.residual_rms
    partial = consistent_estimate(W, y, arm.n, mass_bounds=[None] * 6 + [(2.0, None)])
    assert partial.phi[60] >= 2.0 - 1e-7


def test_extra_bounds_and_weights() -> None:
    """Viscous friction and motor inertia kept >= 0; weights w equal rows scaled by sqrt(w)."""
    arm = _puma()
    W, y = _stacked(arm, *_samples(arm, 300, 0.02, seed=2))
    bounds = [(0.0, None), None, None, (0.0, np.inf)] * arm.n
    estimate = consistent_estimate(W, y, arm.n, extra_bounds=bounds)
    assert np.all(estimate.extra[0::4] >= -1e-9) and np.all(estimate.extra[3::4] >= -1e-9)
    weights = np.random.default_rng(0).uniform(0.5, 2.0, len(y))
    weighted = consistent_estimate(W, y, arm.n, weights=weights)
    root = np.sqrt(weights)
    scaled = consistent_estimate(W * root[:, None], y * root, arm.n)
    assert_allclose(weighted.residual_rms**2 * weights.sum(), scaled.residual_rms**2 * len(y), rtol=1e-6)
    assert_allclose(weighted.ls_rms**2 * weights.sum(), scaled.ls_rms**2 * len(y), rtol=1e-8)


def test_base_mapping_with_drives_false() -> None:
    """base() over the 10 n rigid columns (drives=False) maps the truth of noise-free data to its base parameters."""
    arm = _panda()
    q, qd, qdd, _ = _samples(arm, 300, 0.0)
    W = regressor(arm, q, qd, qdd)[..., :70].reshape(-1, 70)
    rigid = base_parameters(arm, drives=False)
    y = W @ parameters(arm)[:70]
    estimate = consistent_estimate(W, y, arm.n)
    assert_allclose(estimate.base(rigid), rigid.phi, rtol=1e-6, atol=1e-7)
    with pytest.raises(ModelError, match="at most 70 columns"):
        estimate.base(np.zeros((3, 98)))


# ----- bad input -----------------------------------------------------------------------------------------------
@cache
def _small() -> tuple[np.ndarray, np.ndarray]:
    arm = _panda()
    return _stacked(arm, *_samples(arm, 50, 0.01))


def test_infeasible_mass_bounds_are_refused() -> None:
    W, y = _small()
    with pytest.raises(ModelError, match=r"mass_bounds of link 3: lower bound 2 is above upper bound 1: infeasible"):
        consistent_estimate(W, y, 7, mass_bounds=[None, None, (2.0, 1.0), None, None, None, None])
    with pytest.raises(ModelError, match=r"mass_bounds of link 1: the upper bound -1 kg is below the margin 0"):
        consistent_estimate(W, y, 7, mass_bounds=np.array([[-2.0, -1.0]] + [[np.nan, np.nan]] * 6))
    with pytest.raises(ModelError, match=r"upper bound 0.001 kg is below the margin 0.01"):
        consistent_estimate(W, y, 7, mass_bounds=[(0, 1e-3)] + [None] * 6, margin=0.01)
    with pytest.raises(ModelError, match=r"extra_bounds of extra column 2: lower bound 1 is above upper bound 0"):
        consistent_estimate(W, y, 7, extra_bounds=[None, (1.0, 0.0)] + [None] * 26)
    with pytest.raises(ModelError, match=r"mass_bounds must hold one pair \(lower, upper\) per link, 7 of them"):
        consistent_estimate(W, y, 7, mass_bounds=[(0, 1)] * 6)
    with pytest.raises(ModelError, match="mass_bounds of link 1 must be a pair"):
        consistent_estimate(W, y, 7, mass_bounds=[(0, 1, 2)] + [None] * 6)


def test_margin_is_kept() -> None:
    """J_i >= margin 1: every pseudo-inertia eigenvalue at least the margin."""
    W, y = _small()
    estimate = consistent_estimate(W, y, 7, margin=1e-3)
    assert estimate.consistency["J_min"].min() >= 1e-3 - 1e-9


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda W, y: (np.where(np.arange(W.size).reshape(W.shape) == 5 * 98 + 3, np.nan, W), y, {}),
         r"W holds NaN or infinity at row 5, column 3"),
        (lambda W, y: (W[:, :60], y, {}), r"at least 70 columns for 7 links"),
        (lambda W, y: (W, y[:-1], {}), r"y must hold one torque per row of W, shape \(350,\)"),
        (lambda W, y: (W, np.where(np.arange(y.size) == 7, np.inf, y), {}), r"y holds NaN or infinity at index \(7,\)"),
        (lambda W, y: (W, y, {"weights": -np.ones(y.size)}), r"weights must be >= 0: row 0"),
        (lambda W, y: (W, y, {"weights": np.zeros(y.size)}), r"weights must not all be 0"),
        (lambda W, y: (W, y, {"weights": np.ones(3)}), r"weights must hold one weight per row"),
        (lambda W, y: (W, y, {"regularization": 1.0}), r"regularization > 0 pulls toward a prior"),
        (lambda W, y: (W, y, {"regularization": -1.0}), r"regularization must be a finite number >= 0"),
        (lambda W, y: (W, y, {"prior": np.zeros(70)}), r"prior must hold one value per column of W, shape \(98,\)"),
        (lambda W, y: (W, y, {"links": 0}), r"links must be an integer >= 1"),
        (lambda W, y: (W, y, {"links": 7.0}), r"links must be an integer >= 1"),
        (lambda W, y: (W, y, {"margin": np.nan}), r"margin must be a finite number >= 0"),
        (lambda W, y: (W, y, {"solver": "NO_SUCH_SOLVER"}), r"failed with solver NO_SUCH_SOLVER"),
    ],
)  # fmt: skip
def test_bad_input_is_refused(change: object, message: str) -> None:
    W, y = _small()
    W, y, options = change(W, y)  # type: ignore[operator]
    options = {"links": 7, **options}
    with pytest.raises(ModelError, match=message):
        consistent_estimate(W, y, **options)


def test_bounds_from_prior_refuses_bad_input() -> None:
    prior = parameters(_panda())
    with pytest.raises(ModelError, match="mass_tolerance must be below 1"):
        bounds_from_prior(prior, 7, mass_tolerance=1.0)
    with pytest.raises(ModelError, match="prior must hold at least 80 values for 8 links"):
        bounds_from_prior(prior[:70], 8)
    with pytest.raises(ModelError, match="prior mass of link 1 is negative"):
        bounds_from_prior(-prior, 7)


# ----- speed (measured, not asserted) --------------------------------------------------------------------------
@pytest.mark.slow
def test_time_of_20000_samples_of_the_panda() -> None:
    """20,000 samples x 7 joints (140,000 rows, 98 columns): print the time of the reduction and the solve."""
    arm = _panda()
    q, qd, qdd, tau = _samples(arm, 20_000, 0.01)
    W, y = _stacked(arm, q, qd, qdd, tau)
    consistent_estimate(W[:1000], y[:1000], arm.n)  # cvxpy's import and first compilation apart
    start = time.perf_counter()
    estimate = consistent_estimate(W, y, arm.n)
    total = time.perf_counter() - start
    print(
        f"\n20,000 x 7 rows: total {total:.3f} s (reduction {estimate.reduce_time:.3f} s, "
        f"solve {estimate.solve_time:.3f} s); RMS {estimate.residual_rms:.6g} vs least squares {estimate.ls_rms:.6g}"
    )
    assert estimate.consistency["consistent"].all()
