"""Batch forward dynamics vectorized across states (aba_blocks) against the one-state articulated-body
kernel, RNEA, and the singular-state error of the one-state path."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import armdyn as ad
from armdyn.dynamics.aba import aba_batch
from armdyn.dynamics.aba_blocks import BLOCK, aba_blocks
from tests.helpers import URDFS
from tests.strategies import random_robot

SAME = 1e-12  # batch against one state: the same equations, rounded apart only by the order of operations
INVERSE = 1e-10  # RNEA of the result against tau
SHAPES = [(1,), (BLOCK - 1,), (BLOCK,), (BLOCK + 1,), (100,), (3, 5)]
# random trees and chains of revolute and prismatic joints, with friction and motors
RANDOM = [(seed, 1 + seed % 9, seed % 3 == 0) for seed in range(12)]


def urdf_arm(name: str) -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's mimic finger joint loads as an independent joint
        return ad.load_urdf(URDFS[name])


def states(arm: ad.Robot, shape: tuple[int, ...], seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random (q, qd, tau) of batch shape ``shape``; some rates exactly zero (Coulomb friction at rest)."""
    rng = np.random.default_rng(seed)
    q, qd = rng.uniform(-2.0, 2.0, (2, *shape, arm.n))
    qd.reshape(-1, arm.n)[::3, ::2] = 0.0
    return q, qd, rng.uniform(-5.0, 5.0, (*shape, arm.n))


def assert_batch_matches(arm: ad.Robot, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, qdd: np.ndarray) -> None:
    """qdd equals the one-state call state by state (to SAME relative to the batch's largest
    entry), and inverse dynamics of qdd gives tau back (to INVERSE relative to the largest torque)."""
    assert qdd.shape == np.broadcast_shapes(q.shape, qd.shape, tau.shape)
    q, qd, tau = (np.ascontiguousarray(np.broadcast_to(a, qdd.shape)) for a in (q, qd, tau))
    rows = zip(*(a.reshape(-1, arm.n) for a in (q, qd, tau)), strict=True)
    single = np.array([arm.forward_dynamics(*row) for row in rows])
    assert np.abs(qdd.reshape(single.shape) - single).max() <= SAME * np.abs(single).max()
    assert np.abs(arm.inverse_dynamics(q, qd, qdd) - tau).max() <= INVERSE * np.abs(tau).max()


@pytest.mark.parametrize("shape", SHAPES, ids=str)
@pytest.mark.parametrize(("seed", "n", "chain"), RANDOM)
def test_random_arms_batch_equals_one_state_calls(seed: int, n: int, chain: bool, shape: tuple[int, ...]) -> None:
    arm = random_robot(seed, n, chain=chain)
    q, qd, tau = states(arm, shape, seed)
    assert_batch_matches(arm, q, qd, tau, arm.forward_dynamics(q, qd, tau))


@pytest.mark.parametrize("shape", SHAPES, ids=str)
@pytest.mark.parametrize("name", sorted(URDFS))
def test_urdf_arms_batch_equals_one_state_calls(name: str, shape: tuple[int, ...]) -> None:
    arm = urdf_arm(name)
    q, qd, tau = states(arm, shape, 7)
    assert_batch_matches(arm, q, qd, tau, arm.forward_dynamics(q, qd, tau))


def test_batch_shapes_broadcast_and_out_is_filled() -> None:
    arm = random_robot(3, 7)
    q, qd, tau = states(arm, (3, 5), 3)
    expected = arm.forward_dynamics(q, qd, tau)
    out = np.empty((3, 5, arm.n))
    assert arm.forward_dynamics(q, qd, tau, out=out) is out
    np.testing.assert_array_equal(out, expected)
    flat = np.empty((15, arm.n))
    assert arm.forward_dynamics(q.reshape(15, -1), qd.reshape(15, -1), tau.reshape(15, -1), out=flat) is flat
    np.testing.assert_array_equal(flat, expected.reshape(15, -1))
    broadcast = arm.forward_dynamics(q, qd[0, 0], tau[:1])  # (3, 5, n) with (n,) and (1, 5, n)
    assert_batch_matches(arm, q, qd[0, 0], tau[:1], broadcast)
    with pytest.raises(ad.ModelError, match=r"out must be a writable C-contiguous float64 array of shape \(3, 5, 7\)"):
        arm.forward_dynamics(q, qd, tau, out=np.empty((15, arm.n)))


def polar_states(shape: tuple[int, ...], singular: list[tuple[int, ...]]) -> tuple[np.ndarray, ...]:
    """States of the polar RP arm (M = diag(m r^2, m)), singular (r = q[1] = 0) at the given indices."""
    rng = np.random.default_rng(1)
    q = np.stack([rng.uniform(-2, 2, shape), rng.uniform(0.2, 1.5, shape)], axis=-1)
    for index in singular:
        q[index][1] = 0.0
    return q, rng.uniform(-1, 1, q.shape), rng.uniform(-3, 3, q.shape)


def test_a_singular_state_raises_the_one_state_error_naming_it() -> None:
    polar = ad.models.polar_rp()
    q, qd, tau = polar_states((4, 10), [(3, 7)])  # state 37 of 40: in the second block
    with pytest.raises(ad.ModelError) as one:
        polar.forward_dynamics(q[3, 7], qd[3, 7], tau[3, 7])
    with pytest.raises(ad.ModelError) as batch:
        polar.forward_dynamics(q, qd, tau)
    message = str(one.value)
    assert re.search(r"M\(q\) of 'polar_rp' is singular \(q = .*joint 'theta'", message)
    assert str(batch.value) == message.replace("is singular (", "is singular at state (3, 7) (")
    with pytest.raises(ad.ModelError, match=r"singular at state \(1, 2\) .*joint 'theta'"):  # the first of two
        polar.forward_dynamics(*polar_states((4, 10), [(1, 2), (3, 7)]))
    with pytest.raises(ad.ModelError, match=r"singular at state \(0,\) .*joint 'theta'"):
        polar.forward_dynamics(*polar_states((1,), [(0,)]))
    out = np.empty((4, 10, 2))
    with pytest.raises(ad.ModelError, match=r"singular at state \(3, 7\)"):
        polar.forward_dynamics(q, qd, tau, out=out)


def test_a_massless_leaf_is_named_in_a_batch() -> None:
    arm = ad.Robot.from_dh([{"a": 1.0, "mass": 1.0, "com": [-0.5, 0, 0], "inertia": [0.1, 0.1, 0.1]}, {"a": 0.5}])
    with pytest.raises(ad.ModelError, match=r"singular at state \(0,\) .*joint 'joint2'"):
        arm.forward_dynamics(np.zeros((40, 2)), np.zeros((40, 2)), np.zeros((40, 2)))


@pytest.mark.parametrize("arm", [ad.models.polar_rp(), random_robot(11, 5)], ids=["polar", "random"])
def test_kernel_flags_the_joint_of_aba_core_and_keeps_other_states_exact(arm: ad.Robot) -> None:
    """Per state, the flagged joint is the one the one-state kernel stops at, and a singular state
    (NaN and infinity in its lanes) leaves the other states of its block as they are alone."""
    count = 2 * BLOCK + 5
    q, qd, tau = states(arm, (count,), 5)
    if arm.name == "polar_rp":
        q[:, 1] = np.where(np.arange(count) % 7 == 3, 0.0, q[:, 1] + 2.5)
    blocks, flags = np.empty((count, arm.n)), np.full(count, -2)
    aba_blocks(arm.packed, q, qd, tau, blocks, flags)
    one, expected = np.empty((count, arm.n)), np.full(count, -2)
    aba_batch(arm.packed, q, qd, tau, one, expected)
    np.testing.assert_array_equal(flags, expected)
    fine = expected < 0
    assert fine.any()
    assert np.abs(blocks[fine] - one[fine]).max() <= SAME * np.abs(one[fine]).max()
