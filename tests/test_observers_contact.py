"""Contacts on a link point: the point Jacobian against finite differences, Push / Impulse / Clamp in simulate
against the equation of motion, and force estimation and isolation against the exact J_p^T F."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

import armdyn as ad
from armdyn import ModelError
from armdyn.control import ComputedTorque
from armdyn.kinematics import jacobian, link_transforms
from armdyn.observers.contact import (
    Clamp,
    ContactObservabilityWarning,
    ForceEstimate,
    Impulse,
    Push,
    contact_link,
    estimate_force,
    estimate_wrench,
    point_jacobian,
)
from armdyn.trajectories import Sinusoid

POINT = np.array([0.05, 0.1, 0.02])  # off every joint axis of both arms
FORCE = np.array([3.0, -5.0, 20.0])
ARMS = {"puma560": ad.models.puma560, "panda": ad.models.panda_gaz2019}


@functools.cache
def _arm(name: str) -> ad.Robot:
    return ARMS[name]()


def _configuration(arm: ad.Robot) -> np.ndarray:
    """A configuration away from the arms' singular ones (the Panda's qr and qz align joints 1 and 3)."""
    return arm.configuration("qn") if "qn" in arm.configurations else np.array([0.3, -0.4, 0.5, -2.0, 0.4, 1.6, 0.7])


def _position(arm: ad.Robot, q: np.ndarray, link: int, point: np.ndarray) -> np.ndarray:
    pose = link_transforms(arm, q)[..., link, :, :]
    return pose[..., :3, :3] @ point + pose[..., :3, 3]


@pytest.mark.parametrize("name", sorted(ARMS))
def test_point_jacobian_matches_finite_differences_of_the_point(name: str) -> None:
    arm, rng, step = _arm(name), np.random.default_rng(7), 1e-6
    for link in range(arm.n):
        q = rng.uniform(-1.5, 1.5, arm.n)
        jac = point_jacobian(arm, q, link, POINT)
        columns = [
            (_position(arm, q + step * e, link, POINT) - _position(arm, q - step * e, link, POINT)) / (2 * step)
            for e in np.eye(arm.n)
        ]
        assert_allclose(jac[:3], np.stack(columns, axis=1), atol=1e-8)
        assert_array_equal(jac[3:], jacobian(arm, q, link=link)[3:])  # the angular rows are the link's
        assert_array_equal(jac[:, ~arm.ancestors[link]], 0.0)  # joints that do not move the link


def test_point_jacobian_of_a_batch_equals_each_state_and_takes_names() -> None:
    arm = _arm("panda")
    q = np.random.default_rng(1).uniform(-1, 1, (4, arm.n))
    batch = point_jacobian(arm, q, "q4", POINT)
    assert batch.shape == (4, 6, arm.n)
    for k in range(4):
        assert_allclose(batch[k], point_jacobian(arm, q[k], 3, POINT), rtol=0, atol=1e-15)
    assert_allclose(point_jacobian(arm, q[0], 3, np.zeros(3)), jacobian(arm, q[0], link=3), atol=1e-15)


@pytest.mark.parametrize("name", sorted(ARMS))
def test_push_torque_is_the_transposed_jacobian_and_the_disturbance_its_negative(name: str) -> None:
    arm = _arm(name)
    q, qd = _configuration(arm), np.linspace(-0.5, 0.5, arm.n)
    push = Push(arm, 3, POINT, FORCE, start=2.0, rise=0.1)
    jv = point_jacobian(arm, q, 3, POINT)[:3]
    assert_array_equal(push.force(1.999, q, qd), 0.0)
    assert_allclose(push.force(2.05, q, qd), 0.5 * FORCE, rtol=1e-12)  # halfway up the ramp
    assert_array_equal(push.force(2.5, q, qd), FORCE)
    assert_allclose(push.external_torque(2.5, q, qd), jv.T @ FORCE, rtol=1e-13)
    assert_array_equal(push(2.5, q, qd), -push.external_torque(2.5, q, qd))
    assert_array_equal(push.external_torque(1.0, q, qd), np.zeros(arm.n))
    assert_array_equal(push.external_torque(2.5, q, qd)[4:], 0.0)  # joints beyond link 4 feel nothing
    ended = Push(arm, "q4", POINT, FORCE, start=2.0, duration=0.5)
    assert_array_equal(ended.force(2.49, q, qd), FORCE)
    assert_array_equal(ended.force(2.5, q, qd), 0.0)


def test_impulse_is_a_rectangular_pulse() -> None:
    arm = _arm("puma560")
    q, qd = _configuration(arm), np.zeros(arm.n)
    pulse = Impulse(arm, 3, POINT, FORCE, start=0.5, width=0.01)
    times = np.array([0.499, 0.5, 0.505, 0.5099, 0.51, 1.0])
    inside = np.array([np.any(pulse.force(t, q, qd)) for t in times])
    assert_array_equal(inside, [False, True, True, True, False, False])
    assert_allclose(pulse.external_torque(0.505, q, qd), point_jacobian(arm, q, 3, POINT)[:3].T @ FORCE, rtol=1e-13)


def test_clamp_holds_the_point_where_it_was_at_start() -> None:
    arm = _arm("puma560")
    q0, rng = _configuration(arm), np.random.default_rng(3)
    clamp = Clamp(arm, 3, POINT, stiffness=1e4, damping=50.0, start=1.0)
    assert_array_equal(clamp.force(0.5, q0 + 0.1, np.ones(arm.n)), 0.0)  # before start: nothing, no anchor taken
    assert_array_equal(clamp.force(1.0, q0, np.zeros(arm.n)), 0.0)  # the anchor is where the point is now
    q, qd = q0 + rng.uniform(-0.01, 0.01, arm.n), rng.uniform(-0.2, 0.2, arm.n)
    velocity = point_jacobian(arm, q, 3, POINT)[:3] @ qd
    expected = -1e4 * (_position(arm, q, 3, POINT) - _position(arm, q0, 3, POINT)) - 50.0 * velocity
    assert_allclose(clamp.force(1.5, q, qd), expected, rtol=1e-12)
    assert_allclose(clamp(1.5, q, qd), -point_jacobian(arm, q, 3, POINT)[:3].T @ expected, rtol=1e-12)
    clamp.reset()  # a new run: the anchor is taken again
    assert_array_equal(clamp.force(2.0, q, np.zeros(arm.n)), 0.0)
    given = Clamp(arm, 3, POINT, 1e4, 0.0, 0.0, anchor=_position(arm, q0, 3, POINT))
    assert_allclose(given.force(0.0, q, qd), -1e4 * (_position(arm, q, 3, POINT) - _position(arm, q0, 3, POINT)))


def _run(arm: ad.Robot, t_final: float, disturbance: object = None) -> ad.simulation.Result:
    q0 = _configuration(arm)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ad.simulation.PythonLoopWarning)
        return ad.simulate(
            arm, ComputedTorque(kp=100, kv=20), Sinusoid(0.2, 0.5, offset=q0), t_final=t_final, dt=1e-3, q0=q0,
            disturbance=disturbance, coulomb_smoothing=0,
        )  # fmt: skip


@pytest.mark.parametrize(
    ("name", "t_final", "start"),
    [("puma560", 3.0, 2.0), ("panda", 0.5, 0.3)],
)
def test_push_in_simulate_enters_the_equation_of_motion(name: str, t_final: float, start: float) -> None:
    """Under computed torque along a sinusoid, a 20 N push on link 4 from ``start``: the run equals the one
    without it until then and differs after, and M qdd + N - tau equals J_p^T F at every sample of the push."""
    arm = _arm(name)
    push = Push(arm, 3, POINT, [0.0, 0.0, 20.0], start=start)
    pushed, free = _run(arm, t_final, push), _run(arm, t_final)
    before, after = pushed.t < start, pushed.t >= start
    assert_allclose(pushed.q[before], free.q[before], rtol=0, atol=1e-12)
    assert np.abs(pushed.q[after][-1] - free.q[after][-1]).max() > 1e-4
    tau_ext = np.array([push.external_torque(t, q, qd) for t, q, qd in zip(pushed.t, pushed.q, pushed.qd, strict=True)])
    assert_array_equal(tau_ext[before], 0.0)
    assert np.abs(tau_ext[after]).max() > 1.0
    balance = arm.inverse_dynamics(pushed.q, pushed.qd, pushed.qdd) - pushed.tau
    assert_allclose(balance, tau_ext, rtol=0, atol=1e-9 * np.abs(tau_ext).max())


@pytest.mark.parametrize("name", sorted(ARMS))
def test_estimate_force_recovers_the_exact_force(name: str) -> None:
    arm = _arm(name)
    q = _configuration(arm)
    residual = point_jacobian(arm, q, 3, POINT)[:3].T @ FORCE
    with warnings.catch_warnings():
        warnings.simplefilter("error", ContactObservabilityWarning)
        estimate = estimate_force(arm, q, residual, 3, POINT)
        exact = estimate_force(arm, q, residual, "q4", POINT, damping=0.0)
    assert isinstance(estimate, ForceEstimate)
    assert_allclose(estimate.force, FORCE, rtol=0, atol=1e-9 * np.linalg.norm(FORCE))
    assert_allclose(exact.force, FORCE, rtol=0, atol=1e-12 * np.linalg.norm(FORCE))
    assert estimate.joints == (0, 1, 2, 3) and estimate.link == 3 and estimate.moment is None
    assert 1.0 <= estimate.condition < 1e3 and estimate.observable
    transposed = point_jacobian(arm, q, 3, POINT)[:3, :4].T
    assert_allclose(estimate.condition, np.linalg.cond(transposed), rtol=1e-10)
    assert_allclose(estimate.position, _position(arm, q, 3, POINT), rtol=1e-14)


def test_estimate_force_of_a_log_in_one_call() -> None:
    arm = _arm("panda")
    q = _configuration(arm) + np.random.default_rng(5).uniform(-0.2, 0.2, (50, arm.n))
    forces = np.random.default_rng(6).normal(0, 10, (50, 3))
    residual = np.einsum("kan,ka->kn", point_jacobian(arm, q, 3, POINT)[:, :3], forces)
    estimate = estimate_force(arm, q, residual, 3, POINT, damping=0.0)
    assert estimate.force.shape == (50, 3) and estimate.condition.shape == (50,)
    assert_allclose(estimate.force, forces, rtol=0, atol=1e-10)


def test_estimate_wrench_needs_six_joints_and_recovers_the_wrench() -> None:
    arm = _arm("panda")
    q = _configuration(arm)
    wrench = np.r_[FORCE, 1.0, -2.0, 0.5]
    residual = point_jacobian(arm, q, 6, POINT).T @ wrench
    estimate = estimate_wrench(arm, q, residual, 6, POINT, damping=0.0)
    assert_allclose(np.r_[estimate.force, estimate.moment], wrench, rtol=0, atol=1e-10)
    with pytest.warns(ContactObservabilityWarning, match="4 joints move the point, fewer than the 6"):
        partial = estimate_wrench(arm, q, point_jacobian(arm, q, 3, POINT).T @ wrench, 3, POINT)
    assert partial.condition == np.inf and not partial.observable


def test_a_force_on_the_second_link_is_not_observable() -> None:
    arm = _arm("puma560")
    q = _configuration(arm)
    with pytest.warns(ContactObservabilityWarning, match="only 2 joints move the point"):
        estimate = estimate_force(arm, q, point_jacobian(arm, q, 1, POINT)[:3].T @ FORCE, 1, POINT)
    residual = point_jacobian(arm, q, 1, POINT)[:3].T @ FORCE
    assert_allclose(point_jacobian(arm, q, 1, POINT)[:3].T @ estimate.force, residual, atol=1e-9)  # fits r
    panda = _arm("panda")  # at q2 = 0 the Panda's joints 1 and 3 are aligned: J_p^T of link 3 loses rank
    with pytest.warns(ContactObservabilityWarning, match="ill-conditioned"):
        aligned = estimate_force(panda, np.zeros(panda.n), np.ones(panda.n), 2, POINT)
    assert aligned.condition > 1e3 and not aligned.observable


@pytest.mark.parametrize("name", sorted(ARMS))
def test_isolation_names_the_pushed_link(name: str) -> None:
    arm = _arm(name)
    q, rng = _configuration(arm), np.random.default_rng(11)
    noise = rng.uniform(-0.01, 0.01, arm.n)
    residual = point_jacobian(arm, q, 3, POINT)[:3].T @ FORCE + noise
    assert contact_link(residual, np.full(arm.n, 0.05)) == 3
    assert contact_link(residual, np.stack([np.full(arm.n, -0.05), np.full(arm.n, 0.05)])) == 3
    assert contact_link(noise, np.full(arm.n, 0.05)) is None
    assert contact_link(residual, np.full(arm.n, 1e3)) is None
    assert contact_link(residual, np.r_[np.zeros(arm.n - 1), 1.0]) == arm.n - 2  # the last joint's band holds it


def test_bad_input_is_refused_with_a_clear_message() -> None:
    arm = _arm("puma560")
    q = _configuration(arm)
    with pytest.raises(ModelError, match=r"no link 'elbow' \(its links: 0 'q1', 1 'q2'"):
        Push(arm, "elbow", POINT, FORCE, 1.0)
    with pytest.raises(ModelError, match="has no link 6"):
        estimate_force(arm, q, np.zeros(arm.n), 6)
    with pytest.raises(ModelError, match="has no link 9"):
        point_jacobian(arm, q, 9, POINT)
    with pytest.raises(ModelError, match=r"Push force must be an array of numbers of shape \(3,\)"):
        Push(arm, 3, POINT, [1.0, 2.0], 1.0)
    with pytest.raises(ModelError, match=r"Impulse force must be .*got shape \(2, 3\)"):
        Impulse(arm, 3, POINT, np.ones((2, 3)), 1.0, 0.01)
    with pytest.raises(ModelError, match="Push point must be"):
        Push(arm, 3, [0.1, 0.2], FORCE, 1.0)
    with pytest.raises(ModelError, match="finite"):
        Push(arm, 3, POINT, [np.nan, 0, 0], 1.0)
    with pytest.raises(ModelError, match="duration must be positive"):
        Push(arm, 3, POINT, FORCE, 1.0, duration=0.0)
    with pytest.raises(ModelError, match="rise must be at least 0"):
        Push(arm, 3, POINT, FORCE, 1.0, rise=-0.1)
    with pytest.raises(ModelError, match="width of Impulse must be positive"):
        Impulse(arm, 3, POINT, FORCE, 1.0, 0.0)
    with pytest.raises(ModelError, match="stiffness must be at least 0"):
        Clamp(arm, 3, POINT, -1.0, 0.0, 1.0)
    with pytest.raises(ModelError, match=r"band must have shape \(6,\) or \(2, 6\).*got \(5,\)"):
        contact_link(np.zeros(6), np.ones(5))
    with pytest.raises(ModelError, match="band must have shape"):
        contact_link(np.zeros(6), np.ones((3, 6)))
    with pytest.raises(ModelError, match="non-negative"):
        contact_link(np.zeros(6), -np.ones(6))
    with pytest.raises(ModelError, match="lower row must not exceed"):
        contact_link(np.zeros(6), np.stack([np.ones(6), np.zeros(6)]))
    with pytest.raises(ModelError, match="residual must have shape"):
        estimate_force(arm, q, np.zeros(5), 3)
    with pytest.raises(ModelError, match="damping must be at least 0"):
        estimate_force(arm, q, np.zeros(arm.n), 3, damping=-1.0)
    with pytest.raises(ModelError, match="q must"):
        Push(arm, 3, POINT, FORCE, 0.0).external_torque(1.0, np.zeros(5), np.zeros(5))


@pytest.mark.parametrize("name", ["puma560", "panda", "stanford"])
def test_the_compiled_contacts_equal_the_transposed_jacobian_law(name: str) -> None:
    """simulate's compiled J_p^T F of a push with a ramp, a pulse and a clamp (its anchor taken at the first call from
    its start), against each contact's own external_torque; the Stanford arm has a prismatic joint."""
    from armdyn.dynamics.packed import workspace_size
    from armdyn.observers.contact import contact_torques, contacts_table

    arm = _arm(name) if name in ARMS else ad.models.load(name)
    rng = np.random.default_rng(5)
    last = arm.n - 1
    contacts = [Push(arm, 3, POINT, FORCE, 0.5, rise=0.1), Impulse(arm, 2, -POINT, FORCE, 0.6, 0.01),
                Clamp(arm, last, POINT, 500.0, 20.0, 0.2)]  # fmt: skip
    table = contacts_table(arm, contacts)
    q, qd = rng.uniform(-1, 1, (2, arm.n))
    out, work = np.empty(arm.n), np.empty(workspace_size(arm.n))
    for t in (0.1, 0.3, 0.55, 0.605, 1.0):
        contact_torques(arm.packed, table, work, t, q, qd, out)
        expected = sum(contact.external_torque(t, q, qd) for contact in contacts)
        assert_allclose(out, expected, rtol=0, atol=1e-13 * max(1.0, np.abs(expected).max()))
        q = q + 0.01 * rng.standard_normal(arm.n)  # the clamp pulls back to where the point was at 0.3 s


def test_contacts_in_simulate_run_compiled_and_equal_the_python_loop() -> None:
    """A push, a pulse and a clamp, given as a list, run in the compiled loop (no PythonLoopWarning) and give the run
    the Python loop gives with the same law as a function; their torque is recorded and the clamp keeps its anchor."""
    arm = _arm("puma560")
    q0 = _configuration(arm)

    def contacts() -> list:
        return [Push(arm, 3, POINT, FORCE, 0.1, rise=0.05), Impulse(arm, 2, POINT, FORCE, 0.2, 0.01),
                Clamp(arm, 5, POINT, 2e3, 50.0, 0.25)]  # fmt: skip

    compiled_contacts, python_contacts = contacts(), contacts()
    run = functools.partial(ad.simulate, arm, ComputedTorque(kp=100, kv=20), Sinusoid(0.2, 0.5, offset=q0),
                            t_final=0.4, dt=1e-3, q0=q0)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error", ad.simulation.PythonLoopWarning)
        compiled = run(disturbance=compiled_contacts)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ad.simulation.PythonLoopWarning)
        python = run(disturbance=lambda t, q, qd: sum(c(t, q, qd) for c in python_contacts))
    assert compiled.info["method"] == "rk4 (compiled)" and python.info["method"] == "rk4 (Python)"
    assert_allclose(compiled.q, python.q, rtol=0, atol=1e-11)
    expected = [sum(c.external_torque(t, q, qd) for c in python_contacts) for t, q, qd in
                zip(python.t, python.q, python.qd, strict=True)]  # fmt: skip
    assert_allclose(compiled.external_torque, expected, rtol=0, atol=1e-9)
    assert_allclose(compiled_contacts[2]._held["anchor"], python_contacts[2]._held["anchor"], rtol=0, atol=1e-12)
    assert np.abs(compiled.external_torque[compiled.t >= 0.25]).max() > 0.1  # the clamp holds


def test_contacts_of_another_arm_or_with_many_runs_are_refused() -> None:
    arm = _arm("puma560")
    with pytest.raises(ModelError, match="acts on an arm of 2 joints, not the simulated arm's 6"):
        ad.simulate(arm, t_final=0.01, disturbance=Push(ad.models.two_link_planar(), 1, POINT, FORCE, 0.0))
    with pytest.raises(ad.ArgumentError, match=r"contacts \(Push, Impulse, Clamp\) apply to one run"):
        ad.simulate(arm, ComputedTorque(100, 20), t_final=0.01, runs=2, disturbance=Push(arm, 3, POINT, FORCE, 0.0))
