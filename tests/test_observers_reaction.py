"""Reactions to a detected collision, the observer running beside the task controller in the same simulation: the
push on link 4 detected within 5 ms; "stop" holds the arm, "gravity" yields, "reflex" retracts further."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import armdyn as ad
from armdyn.control import ComputedTorque
from armdyn.observers.contact import Push
from armdyn.observers.detection import Band
from armdyn.observers.reaction import ReactiveController
from armdyn.trajectories import Sinusoid

POINT, FORCE = np.array([0.05, 0.02, 0.03]), np.array([0.0, 12.0, 16.0])


def _react(strategy: str) -> tuple[ReactiveController, object, np.ndarray]:
    arm = ad.models.puma560()
    q0 = arm.configuration("qn")
    push = Push(arm, 3, POINT, FORCE, 0.5)
    controller = ReactiveController(ComputedTorque(kp=100, kv=20), arm, Band.fixed(np.full(6, 1.0)), strategy=strategy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # simulate's Python loop: its speed warning
        result = ad.simulate(arm, controller, Sinusoid(0.2 * np.ones(6), 0.5, offset=q0), t_final=0.9, dt=1e-3, q0=q0,
                             disturbance=push)  # fmt: skip
    T = arm.link_transforms(result.q)[:, 3]
    along = (T[:, :3, :3] @ POINT + T[:, :3, 3]) @ FORCE / np.linalg.norm(FORCE)
    return controller, result, along


@pytest.fixture(scope="module")
def runs() -> dict[str, tuple[ReactiveController, object, np.ndarray]]:
    return {strategy: _react(strategy) for strategy in ("stop", "gravity", "reflex")}


def test_the_push_is_detected_within_5_ms_and_the_residual_recorded(runs: dict) -> None:
    for controller, result, _ in runs.values():
        assert controller.detected_at is not None and 0.5 <= controller.detected_at <= 0.505
        t, r = controller.record
        np.testing.assert_array_equal(t, result.t)
        assert np.abs(r[t < 0.5]).max() < 1.0 and np.abs(r[t > 0.6]).max() > 1.0


def test_stop_holds_the_arm_gravity_yields_and_reflex_retracts_further(runs: dict) -> None:
    stop = runs["stop"]
    late = stop[1].t > stop[0].detected_at + 0.2
    assert np.abs(stop[1].qd[late]).max() < 0.2
    k = int(np.searchsorted(stop[1].t, stop[0].detected_at))
    moved = {name: run[2][-1] - run[2][k] for name, run in runs.items()}
    assert moved["stop"] < 0.05 < moved["gravity"] < moved["reflex"]


def test_gravity_compensation_after_the_detection() -> None:
    controller, result, _ = _react("gravity")
    after = result.t > controller.detected_at + 0.002
    arm = controller.arm
    expected = arm.gravity_vector(result.q[after]) + arm.friction(result.qd[after])
    np.testing.assert_allclose(result.tau[after], expected, atol=0.05 * np.abs(expected).max())


def test_bad_reactions_are_refused() -> None:
    arm = ad.models.puma560()
    with pytest.raises(ad.ModelError, match="strategy must be one of stop, gravity, reflex"):
        ReactiveController(ComputedTorque(kp=100, kv=20), arm, Band.fixed(np.ones(6)), strategy="run")
    with pytest.raises(ad.ModelError, match=r"band must be an armdyn\.observers\.detection\.Band of 6 joints"):
        ReactiveController(ComputedTorque(kp=100, kv=20), arm, Band.fixed(np.ones(3)))
    with pytest.raises(ad.ModelError, match="reaction_gains of 'stop' must be 2 positive numbers"):
        ReactiveController(ComputedTorque(kp=100, kv=20), arm, Band.fixed(np.ones(6)), reaction_gains=(1.0,))
