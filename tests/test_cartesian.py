"""Task-space dynamics (Section 3.5, Khatib 1987) against Pinocchio, closed forms and properties."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn import task_space as ts
from armdyn.control import OperationalSpaceControl, TaskComputedTorque
from armdyn.errors import ModelError
from armdyn.trajectories import Circle, Line, PoseLine
from tests import strategies
from tests.helpers import URDFS, has_section, module_items, pinocchio_pair, undocumented

SEEDS = range(5)


def _ur5() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ad.load_urdf(URDFS["ur5"]).without_friction()


def _regular_states(arm: ad.Robot, output: ts.TaskOutput, seed: int, count: int = 4, limit: float = 1e3):
    """Random (q, qd) with cond J below ``limit`` (away from singularities)."""
    rng = np.random.default_rng(seed)
    found = []
    while len(found) < count:
        q, qd = rng.uniform(-2, 2, arm.n), rng.uniform(-2, 2, arm.n)
        if ts.condition_number(arm, output, q) < limit:
            found.append((q, qd))
    return np.array([s[0] for s in found]), np.array([s[1] for s in found])


def _close(actual: np.ndarray, expected: np.ndarray, rtol: float) -> None:
    """Equal to rtol relative to the largest entry of expected (a norm-wise relative test)."""
    assert_allclose(actual, expected, rtol=rtol, atol=rtol * max(np.abs(expected).max(), 1e-300))


# ----- UR5 against a dense construction from Pinocchio ---------------------------------------------
def _pinocchio_task(q: np.ndarray, qd: np.ndarray):
    """Mbar, Nbar, Gbar of the UR5 tool frame (Pinocchio's "wrist_3_link") from dense inverses."""
    _, model, data, q_index, v_index = pinocchio_pair(URDFS["ur5"])
    config, velocity = pin.neutral(model), np.zeros(model.nv)
    config[q_index], velocity[v_index] = q, qd
    frame = model.getFrameId("wrist_3_link")
    M = pin.crba(model, data, config)
    M = (np.triu(M) + np.triu(M, 1).T)[np.ix_(v_index, v_index)]
    J = pin.computeFrameJacobian(model, data, config, frame, pin.LOCAL_WORLD_ALIGNED)[:, v_index]
    pin.computeJointJacobiansTimeVariation(model, data, config, velocity)
    pin.updateFramePlacements(model, data)
    Jdot = pin.getFrameJacobianTimeVariation(model, data, frame, pin.LOCAL_WORLD_ALIGNED)[:, v_index]
    N = pin.nonLinearEffects(model, data, config, velocity)[v_index]
    G = pin.computeGeneralizedGravity(model, data, config)[v_index]
    pose = data.oMf[frame].homogeneous.copy()
    Ji = np.linalg.inv(J)
    return Ji.T @ M @ Ji, Ji.T @ (N - M @ Ji @ Jdot @ qd), Ji.T @ G, pose


@pytest.mark.parametrize("seed", SEEDS)
def test_ur5_tool_pose_matches_pinocchio(seed: int) -> None:
    arm, output = _ur5(), ts.ToolPose()
    qs, qds = _regular_states(arm, output, seed)
    Mbar, Nbar, Gbar = (
        ts.task_inertia(arm, output, qs),
        ts.task_nonlinear(arm, output, qs, qds),
        ts.task_gravity(arm, output, qs),
    )
    for k, (q, qd) in enumerate(zip(qs, qds, strict=True)):
        M_ref, N_ref, G_ref, pose = _pinocchio_task(q, qd)
        assert_allclose(arm.tool_pose(q), pose, rtol=0, atol=1e-12)  # the same tool frame
        _close(Mbar[k], M_ref, 1e-9)
        _close(Nbar[k], N_ref, 1e-9)
        _close(Gbar[k], G_ref, 1e-9)
        # one state at a time equals the batch
        assert_allclose(ts.task_inertia(arm, output, q), Mbar[k], rtol=1e-13, atol=1e-13 * np.abs(Mbar[k]).max())


@pytest.mark.parametrize("seed", SEEDS)
def test_ur5_lambda_equals_mbar_and_inverse_dynamics_reproduces_rnea(seed: int) -> None:
    arm, output = _ur5(), ts.ToolPose()
    qs, qds = _regular_states(arm, output, seed)
    yddot = np.random.default_rng(seed + 100).normal(size=qs.shape)
    Mbar, Nbar = ts.task_inertia(arm, output, qs), ts.task_nonlinear(arm, output, qs, qds)
    space = ts.operational_space(arm, output, qs, qds)
    _close(space.Lambda, Mbar, 1e-9)
    _close(space.mu + space.p + space.friction, Nbar, 1e-9)
    assert np.abs(space.Nproj).max() < 1e-9  # no null space for a square J
    f = ts.task_inverse_dynamics(arm, output, qs, qds, yddot)
    _close(f, np.einsum("bij,bj->bi", Mbar, yddot) + Nbar, 1e-9)
    J = output.jacobian(arm, qs)
    qdd = np.linalg.solve(J, (yddot - output.bias(arm, qs, qds))[..., None])[..., 0]
    tau = arm.inverse_dynamics(qs, qds, qdd)
    _close(np.einsum("bji,bj->bi", J, f), tau, 1e-9)  # tau = J^T f
    _close(ts.task_force(arm, output, qs, tau), f, 1e-9)
    _close(ts.task_forward_dynamics(arm, output, qs, qds, f), yddot, 1e-8)


# ----- the skew property ---------------------------------------------------------------------------
def _skew_defect(arm: ad.Robot, output: ts.TaskOutput, q: np.ndarray, qd: np.ndarray) -> float:
    """max |x^T (Mbar_dot - 2 Vmbar) x| / (|x|^2 |Vmbar|) over random x, and the symmetric part's size."""
    h = 2e-4  # truncation ~h^4 and rounding ~eps/h both near 1e-11 relative
    Mb = [ts.task_inertia(arm, output, q + k * h * qd) for k in (-2, -1, 1, 2)]
    Mbar_dot = (Mb[0] - 8 * Mb[1] + 8 * Mb[2] - Mb[3]) / (12 * h)  # fourth order along the motion
    Vmbar = ts.task_coriolis(arm, output, q, qd)
    S = Mbar_dot - 2 * Vmbar
    scale = max(np.abs(Vmbar).max(), np.abs(Mbar_dot).max())
    x = np.random.default_rng(0).normal(size=(20, arm.n))
    quadratic = np.abs(np.einsum("ki,ij,kj->k", x, S, x)) / np.einsum("ki,ki->k", x, x)
    return max(quadratic.max(), np.abs(S + S.T).max()) / scale


@pytest.mark.parametrize("seed", SEEDS)
def test_skew_property_ur5_tool_pose(seed: int) -> None:
    arm, output = _ur5(), ts.ToolPose()
    qs, qds = _regular_states(arm, output, seed, count=2, limit=100)
    for q, qd in zip(qs, qds, strict=True):
        assert _skew_defect(arm, output, q, qd) < 1e-8


@pytest.mark.parametrize("seed", SEEDS)
def test_skew_property_random_chain_tool_position(seed: int) -> None:
    arm, output = strategies.random_robot(seed, 3, chain=True), ts.ToolPosition()
    qs, qds = _regular_states(arm, output, seed, count=2, limit=100)
    for q, qd in zip(qs, qds, strict=True):
        assert _skew_defect(arm, output, q, qd) < 1e-8
        # Vmbar ydot is the velocity part of Nbar
        Nbar = ts.task_nonlinear(arm, output, q, qd)
        Gbar = ts.task_gravity(arm, output, q)
        Fbar = ts.task_force(arm, output, q, arm.friction(qd))
        ydot = output.jacobian(arm, q) @ qd
        _close(ts.task_coriolis(arm, output, q, qd) @ ydot + Gbar + Fbar, Nbar, 1e-9)


@pytest.mark.parametrize("seed", SEEDS)
def test_friction_and_regressor_in_task_coordinates(seed: int) -> None:
    """Fbar = J^-T F, Vmbar ydot + Fbar + Gbar = Nbar and Wbar phi = Mbar yddot + Nbar (random chain, friction)."""
    arm, output = strategies.random_robot(seed, 3, chain=True), ts.ToolPosition()
    qs, qds = _regular_states(arm, output, seed, count=3, limit=100)
    yddot = np.random.default_rng(seed).normal(size=qs.shape)
    J = output.jacobian(arm, qs)
    Fbar = ts.task_friction(arm, output, qs, qds)
    _close(np.einsum("bji,bj->bi", J, Fbar), arm.friction(qds), 1e-10)
    ydot = np.einsum("bij,bj->bi", J, qds)
    Vmbar_ydot = np.einsum("bij,bj->bi", ts.task_coriolis(arm, output, qs, qds), ydot)
    Nbar = ts.task_nonlinear(arm, output, qs, qds)
    _close(Vmbar_ydot + Fbar + ts.task_gravity(arm, output, qs), Nbar, 1e-9)
    Wbar = ts.task_regressor(arm, output, qs, qds, yddot)
    assert Wbar.shape == (3, 3, len(arm.parameters()))
    f = np.einsum("bij,bj->bi", ts.task_inertia(arm, output, qs), yddot) + Nbar
    _close(Wbar @ arm.parameters(), f, 1e-9)
    _close(Wbar[1] @ arm.parameters(), ts.task_inverse_dynamics(arm, output, qs[1], qds[1], yddot[1]), 1e-9)


def test_redundant_skew_property_holds_with_null_space_motion() -> None:
    """Panda tool position (m = 3 < n = 7): Lambda_dot - 2 mu_x is skew while the arm also moves in its
    null space, and mu = mu_x ydot + coupling with the coupling (Jbar^T Vm - Lambda Jdot) N qd."""
    arm, _, _ = _panda_reduced()
    output = ts.ToolPosition()
    qs, qds = _regular_states(arm, output, 11, count=2, limit=100)
    for q, qd in zip(qs, qds, strict=True):
        space = ts.operational_space(arm, output, q, qd)
        assert np.abs(space.Nproj @ qd).max() > 0.1 * np.abs(qd).max()  # a real null-space motion
        mu_x, coupling = ts.operational_coriolis(arm, output, q, qd)
        _close(mu_x @ (space.J @ qd) + coupling, space.mu, 1e-9)
        h = 2e-4
        L = [ts.operational_space(arm, output, q + k * h * qd, qd).Lambda for k in (-2, -1, 1, 2)]
        Lambda_dot = (L[0] - 8 * L[1] + 8 * L[2] - L[3]) / (12 * h)
        S = Lambda_dot - 2 * mu_x
        assert np.abs(S + S.T).max() < 1e-8 * max(np.abs(Lambda_dot).max(), np.abs(mu_x).max())
    ur5, pose = _ur5(), ts.ToolPose()
    q1, qd1 = _regular_states(ur5, pose, 1, 1)
    mu_x, coupling = ts.operational_coriolis(ur5, pose, q1, qd1)
    _close(mu_x, ts.task_coriolis(ur5, pose, q1, qd1), 1e-9)  # m = n: mu_x = Vmbar, no null space
    assert np.abs(coupling).max() < 1e-9 * np.abs(mu_x).max()


# ----- outputs: Jacobians and biases by finite differences ----------------------------------------
def _tilted_camera() -> ts.Camera:
    from scipy.spatial.transform import Rotation

    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_rotvec([0.3, -2.8, 0.2]).as_matrix()
    pose[:3, 3] = [0.2, -0.1, 2.5]
    return ts.Camera(800.0, pose)


OUTPUTS = {
    "tool_position": ts.ToolPosition(),
    "link_point": ts.LinkPoint(3),
    "planar": ts.PlanarPosition((0, 2)),
    "camera": _tilted_camera(),
}


@pytest.mark.parametrize("name", sorted(OUTPUTS))
def test_jacobian_and_bias_match_finite_differences(name: str) -> None:
    arm, output = _ur5(), OUTPUTS[name]
    rng = np.random.default_rng(7)
    q, qd = rng.uniform(-1, 1, arm.n), rng.uniform(-1, 1, arm.n)
    if name == "camera":
        q = np.array([0.1, -1.2, 1.0, -0.5, 0.3, 0.2])
        assert (output.value(arm, q) != 0).all()
    h = 1e-4
    J = output.jacobian(arm, q)
    numeric = np.stack(
        [
            (
                -output.value(arm, q + 2 * h * e)
                + 8 * output.value(arm, q + h * e)
                - 8 * output.value(arm, q - h * e)
                + output.value(arm, q - 2 * h * e)
            )
            / (12 * h)
            for e in np.eye(arm.n)
        ],
        axis=-1,
    )
    _close(J, numeric, 1e-7)
    Jdot = (
        -output.jacobian(arm, q + 2 * h * qd)
        + 8 * output.jacobian(arm, q + h * qd)
        - 8 * output.jacobian(arm, q - h * qd)
        + output.jacobian(arm, q - 2 * h * qd)
    ) / (12 * h)
    _close(output.jacobian_dot(arm, q, qd), Jdot, 1e-7)
    _close(output.bias(arm, q, qd), Jdot @ qd, 1e-7)
    # batches
    qs, qds = np.stack([q, q + 0.1]), np.stack([qd, -qd])
    assert_allclose(output.jacobian(arm, qs)[0], J, rtol=1e-14, atol=1e-14 * np.abs(J).max())
    assert output.bias(arm, qs, qds).shape == (2, J.shape[0])


def test_tool_pose_value_and_rates() -> None:
    arm, output = _ur5(), ts.ToolPose()
    q = np.linspace(-1, 1, 6)
    y = output.value(arm, q)
    assert_allclose(y[:3], arm.tool_pose(q)[:3, 3])
    from scipy.spatial.transform import Rotation

    assert_allclose(Rotation.from_rotvec(y[3:]).as_matrix(), arm.tool_pose(q)[:3, :3], atol=1e-12)
    assert_allclose(output.jacobian(arm, q), arm.jacobian(q))


# ----- the polar arm under an overhead camera (Example 3.2-1, Example A.3-3) -----------------------
def test_polar_arm_camera_is_a_point_mass_in_image_coordinates() -> None:
    """Camera on the axis normal to the arm's plane, at depth H with f = H: y = [-r s, r c] (Example A.3-3).

    The arm is a point mass m, so in image coordinates (scaled by f / H = 1) Mbar = m I,
    Vmbar = 0, and Gbar = [-m g, 0] (gravity -g y world appears along -u).
    """
    m, g, H = 2.5, 9.8, 3.0
    arm = ad.models.polar_rp(m=m, g=g)
    pose = np.eye(4)
    pose[:3, :3] = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # x_c = -y, y_c = x, z_c = z
    pose[:3, 3] = [0.0, 0.0, -H]
    camera = ts.Camera(H, pose)
    rng = np.random.default_rng(3)
    q = np.column_stack([rng.uniform(-3, 3, 6), rng.uniform(0.2, 1.5, 6)])
    qd = rng.uniform(-2, 2, q.shape)
    theta, r = q[:, 0], q[:, 1]
    assert_allclose(camera.value(arm, q), np.column_stack([-r * np.sin(theta), r * np.cos(theta)]), atol=1e-14)
    J = np.stack([[-r * np.cos(theta), -np.sin(theta)], [-r * np.sin(theta), np.cos(theta)]]).transpose(2, 0, 1)
    assert_allclose(camera.jacobian(arm, q), J, atol=1e-14)
    assert_allclose(ts.task_inertia(arm, camera, q), np.broadcast_to(m * np.eye(2), (6, 2, 2)), atol=1e-12)
    assert_allclose(ts.task_coriolis(arm, camera, q, qd), 0, atol=1e-12)
    assert_allclose(ts.task_gravity(arm, camera, q), np.broadcast_to([-m * g, 0.0], (6, 2)), atol=1e-12)
    assert_allclose(ts.task_nonlinear(arm, camera, q, qd), np.broadcast_to([-m * g, 0.0], (6, 2)), atol=1e-11)


def test_cylindrical_arm_example_3_5_1() -> None:
    """Example 3.5-1: y = [r c, r s, h] of the cylindrical arm, J and Mbar in closed form (Jbar = J / r^2)."""
    Jb, m1, m2, g = 2.0, 1.5, 0.7, 9.8
    arm, output = ad.models.cylindrical(J=Jb, m1=m1, m2=m2, g=g), ts.ToolPosition()
    rng = np.random.default_rng(5)
    q = np.column_stack([rng.uniform(-3, 3, 5), rng.uniform(-1, 1, 5), rng.uniform(0.3, 1.5, 5)])
    theta, r = q[:, 0], q[:, 2]
    c, s, z = np.cos(theta), np.sin(theta), np.zeros(5)
    J = np.stack([[-r * s, z, c], [r * c, z, s], [z, z + 1, z]]).transpose(2, 0, 1)
    assert_allclose(output.jacobian(arm, q), J, atol=1e-14)
    jbar = Jb / r**2
    Mbar = np.stack(
        [[m2 + jbar * s**2, -jbar * s * c, z], [-jbar * s * c, m2 + jbar * c**2, z], [z, z, z + m1 + m2]]
    ).transpose(2, 0, 1)
    assert_allclose(ts.task_inertia(arm, output, q), Mbar, rtol=1e-12, atol=1e-12)
    assert_allclose(ts.task_gravity(arm, output, q), np.broadcast_to([0, 0, (m1 + m2) * g], (5, 3)), atol=1e-12)


# ----- singularities --------------------------------------------------------------------------------
def test_stretched_two_link_arm_is_singular_unless_damped() -> None:
    arm, output = ad.models.two_link_planar(), ts.PlanarPosition()
    q, qd = np.array([0.3, 0.0]), np.array([0.5, -0.2])
    for call in (
        lambda **k: ts.task_inertia(arm, output, q, **k),
        lambda **k: ts.task_coriolis(arm, output, q, qd, **k),
        lambda **k: ts.task_nonlinear(arm, output, q, qd, **k),
        lambda **k: ts.task_gravity(arm, output, q, **k),
        lambda **k: ts.task_inverse_dynamics(arm, output, q, qd, np.ones(2), **k),
        lambda **k: ts.operational_space(arm, output, q, qd, **k),
    ):
        with pytest.raises(ModelError, match="condition number"):
            call()
        result = call(damping=0.01)
        values = result.Lambda if isinstance(result, ts.OperationalSpace) else result
        assert np.all(np.isfinite(values))
    with pytest.raises(ModelError, match=r"at state \(1,\).*condition number"):
        ts.task_inertia(arm, output, np.array([[0.3, 1.0], [0.3, 0.0]]))
    # near but not at the singularity: finite, and damping leaves regular states untouched
    regular = np.array([0.3, 1.0])
    assert_allclose(ts.task_inertia(arm, output, regular, damping=0.01), ts.task_inertia(arm, output, regular))
    assert np.isinf(ts.condition_number(arm, output, q)) or ts.condition_number(arm, output, q) > 1e15
    with pytest.raises(ModelError, match="condition number"):
        ts.task_inertia(arm, output, regular, max_condition=1.5)


def test_damped_inverse() -> None:
    J = np.array([[1.0, 0.0], [0.0, 0.0]])
    assert_allclose(ts.damped_inverse(J, 0.1), [[1 / 1.01, 0.0], [0.0, 0.0]])
    J = np.random.default_rng(0).normal(size=(3, 2, 4))
    expected = np.swapaxes(J, 1, 2) @ np.linalg.inv(J @ np.swapaxes(J, 1, 2) + 0.04 * np.eye(2))
    assert_allclose(ts.damped_inverse(J, 0.2), expected, rtol=1e-12)


# ----- redundancy -----------------------------------------------------------------------------------
def test_operational_space_redundant_ur5_position() -> None:
    arm, output = _ur5(), ts.ToolPosition()
    qs, qds = _regular_states(arm, output, 11, count=3)
    space = ts.operational_space(arm, output, qs, qds)
    M, J = arm.inertia_matrix(qs), output.jacobian(arm, qs)
    Lambda = np.linalg.inv(J @ np.linalg.solve(M, np.swapaxes(J, 1, 2)))
    _close(space.Lambda, Lambda, 1e-9)
    _close(J @ space.Jbar, np.broadcast_to(np.eye(3), (3, 3, 3)), 1e-9)
    assert np.abs(J @ space.Nproj).max() < 1e-9
    # the task equation: with tau = J^T f + Nproj^T tau0, yddot = Lambda^-1 (f - mu - p - friction)
    rng = np.random.default_rng(1)
    f, tau0 = rng.normal(size=(3, 3)), rng.normal(size=(3, 6))
    tau = np.einsum("bji,bj->bi", J, f) + np.einsum("bji,bj->bi", space.Nproj, tau0)
    yddot = np.einsum("bij,bj->bi", J, arm.forward_dynamics(qs, qds, tau)) + output.bias(arm, qs, qds)
    expected = np.linalg.solve(space.Lambda, (f - space.mu - space.p - space.friction)[..., None])[..., 0]
    _close(yddot, expected, 1e-8)
    _close(
        ts.task_forward_dynamics(arm, output, qs, qds, f),
        np.linalg.solve(space.Lambda, (f - space.mu - space.p)[..., None])[..., 0],
        1e-8,
    )


def test_user_output_equals_builtin() -> None:
    arm = _ur5()
    builtin = ts.ToolPosition()
    user = ts.Output(
        lambda q: arm.tool_pose(q)[:3, 3],
        lambda q: arm.jacobian(q)[:3],
        jacobian_dot=lambda q, qd: arm.jacobian_dot(q, qd)[:3],
    )
    qs, qds = _regular_states(arm, builtin, 2, count=2)
    space_b, space_u = ts.operational_space(arm, builtin, qs, qds), ts.operational_space(arm, user, qs, qds)
    assert_allclose(space_u.Lambda, space_b.Lambda)
    assert_allclose(space_u.mu, space_b.mu)
    assert_allclose(user.value(arm, qs), builtin.value(arm, qs))


# ----- arguments --------------------------------------------------------------------------------------
def test_bad_arguments_are_named() -> None:
    arm, output = ad.models.two_link_planar(), ts.PlanarPosition()
    q = np.array([0.3, 1.0])
    cases = [
        (lambda: ts.task_inertia("arm", output, q), "arm"),
        (lambda: ts.task_inertia(arm, "output", q), "output"),
        (lambda: ts.task_inertia(arm, output, [1.0, 2.0, 3.0]), "q"),
        (lambda: ts.task_nonlinear(arm, output, q, [np.nan, 0.0]), "qd"),
        (lambda: ts.task_force(arm, output, q, "tau"), "tau"),
        (lambda: ts.task_inverse_dynamics(arm, output, q, q, [1.0]), "yddot"),
        (lambda: ts.task_forward_dynamics(arm, output, q, q, [1.0, 2.0, 3.0]), "f"),
        (lambda: ts.task_inertia(arm, output, q, damping=-1.0), "damping"),
        (lambda: ts.task_inertia(arm, output, q, max_condition=0.5), "max_condition"),
        (lambda: ts.task_inertia(arm, ts.ToolPosition(), q), "rows"),
        (lambda: ts.task_inertia(ad.models.two_link_planar(symbolic=True), output, q), "symbolic"),
        (lambda: ts.Camera(-1.0, np.eye(4)), "focal_length"),
        (lambda: ts.Camera(1.0, np.ones((4, 4))), "pose"),
        (lambda: ts.Camera(1.0, np.eye(3)), "pose"),
        (lambda: ts.PlanarPosition((0, 0)), "axes"),
        (lambda: ts.PlanarPosition("xy"), "axes"),
        (lambda: ts.LinkPoint(-1), "link"),
        (lambda: ts.LinkPoint(5).jacobian(arm, q), "link"),
        (lambda: ts.Output(1, lambda q: q), "h"),
        (lambda: ts.Output(lambda q: q, lambda q: np.eye(3)).jacobian(arm, q), "J"),
        (lambda: ts.task_coriolis(arm, ts.Output(lambda q: q, lambda q: np.eye(2)), q, q), "jacobian_dot"),
        (lambda: ts.damped_inverse(np.eye(2), 0.0), "damping"),
        (lambda: ts.damped_inverse([1.0, 2.0], 0.1), "J"),
        (lambda: ts.Camera(1.0, np.eye(4)).value(arm, q), "camera"),
    ]
    for call, name in cases:
        with pytest.raises(ModelError, match=name):
            call()


def test_public_callables_are_documented() -> None:
    """The numpydoc rules of tests/test_docstrings.py, applied to armdyn.task_space (not yet in its walk)."""
    items = list(module_items(ts))
    assert any(item.label.endswith("task_inertia") for item in items)
    for item in items:
        if item.signature is not None:
            assert not undocumented(item), item.label
        if item.needs_returns:
            assert has_section(item.docstring, "Returns"), item.label
        if not isinstance(item.target, type):  # every function and method says what it raises
            assert has_section(item.docstring, "Raises"), item.label


# ----- the Panda (7 joints, 6-D pose): operational space against Pinocchio ----------------------------
def _panda_reduced() -> tuple[ad.Robot, pin.Model, int]:
    """The Panda with its fingers locked (7 joints) in both libraries, and Pinocchio's frame at armdyn's tool."""
    locked = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(URDFS["panda"], locked=locked).without_friction()
    full = pin.buildModelFromUrdf(str(URDFS["panda"]))
    q_lock = pin.neutral(full)
    for name, value in locked.items():
        q_lock[full.joints[full.getJointId(name)].idx_q] = value
    model = pin.buildReducedModel(full, [full.getJointId(name) for name in locked], q_lock)
    assert arm.joint_names == list(model.names)[1:]
    data, q = model.createData(), np.linspace(-0.5, 0.5, 7)
    pin.framesForwardKinematics(model, data, q)
    tool = arm.tool_pose(q)
    frames = [k for k in range(model.nframes) if np.allclose(data.oMf[k].homogeneous, tool, atol=1e-12)]
    assert frames, "no Pinocchio frame at armdyn's tool"
    return arm, model, frames[0]


def test_panda_operational_space_matches_pinocchio() -> None:
    """Lambda = (J M^-1 J^T)^-1, mu = Jbar^T C qd - Lambda Jdot qd and p = Jbar^T G of the Panda's 6-D tool
    pose equal a dense construction from Pinocchio's M, frame Jacobian and its time variation to 1e-9."""
    arm, model, frame = _panda_reduced()
    data = model.createData()
    output = ts.ToolPose()
    qs, qds = _regular_states(arm, output, 3)
    space = ts.operational_space(arm, output, qs, qds)
    for k, (q, qd) in enumerate(zip(qs, qds, strict=True)):
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        J = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)
        pin.computeJointJacobiansTimeVariation(model, data, q, qd)
        pin.updateFramePlacements(model, data)
        Jdot = pin.getFrameJacobianTimeVariation(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        G = pin.computeGeneralizedGravity(model, data, q)
        Cqd = pin.nonLinearEffects(model, data, q, qd) - G
        Minv_JT = np.linalg.solve(M, J.T)
        Lambda = np.linalg.inv(J @ Minv_JT)
        Jbar = Minv_JT @ Lambda
        _close(space.Lambda[k], Lambda, 1e-9)
        _close(space.Jbar[k], Jbar, 1e-9)
        _close(space.mu[k], Jbar.T @ Cqd - Lambda @ Jdot @ qd, 1e-9)
        _close(space.p[k], Jbar.T @ G, 1e-9)
        _close(space.Nproj[k], np.eye(7) - Jbar @ J, 1e-9)
        # null-space motion leaves the task still: J N = 0, so qdd + N z moves y the same
        assert np.abs(J @ space.Nproj[k]).max() < 1e-9 * np.abs(J).max()


@pytest.mark.parametrize(
    "output", [ts.ToolPose(), ts.ToolPosition(), ts.LinkPoint(4), ts.PlanarPosition((1, 2))], ids=repr
)
def test_compiled_one_state_path_equals_the_batch_path(output: ts.TaskOutput) -> None:
    """One state of a built-in row output runs a compiled kernel; a batch runs NumPy's solves: equal to 1e-12,
    on the Panda (7 joints) and on a 3-joint random chain, and a near-singular state still raises."""
    panda, _, _ = _panda_reduced()
    for arm in (panda, strategies.random_robot(4, 3, chain=True)):
        if (isinstance(output, ts.LinkPoint) and arm.n < 5) or output.jacobian(arm, np.zeros(arm.n)).shape[0] > arm.n:
            continue
        qs, qds = _regular_states(arm, output, 2, count=3, limit=1e3)
        batch = ts.operational_space(arm, output, qs, qds)
        Lambdas = ts.operational_inertia(arm, output, qs)
        for k in range(3):
            one = ts.operational_space(arm, output, qs[k], qds[k])
            for name in ("J", "Lambda", "Jbar", "mu", "p", "friction"):
                _close(getattr(one, name), getattr(batch, name)[k], 1e-12)
            assert_allclose(one.Nproj, batch.Nproj[k], atol=1e-12)  # zero for m = n
            _close(ts.operational_inertia(arm, output, qs[k]), Lambdas[k], 1e-12)
            assert one.condition == pytest.approx(batch.condition[k], rel=1e-12)
            if Lambdas.shape[-1] == arm.n:
                _close(ts.task_inertia(arm, output, qs[k]), ts.task_inertia(arm, output, qs)[k], 1e-12)
    stretched = ad.models.two_link_planar()
    with pytest.raises(ModelError, match="condition number"):
        ts.operational_inertia(stretched, ts.PlanarPosition(), np.array([0.3, 1e-12]))
    with pytest.raises(ModelError, match="condition number"):
        ts.task_inertia(stretched, ts.PlanarPosition(), np.array([0.3, 1e-12]))
    assert np.isfinite(ts.operational_inertia(stretched, ts.PlanarPosition(), np.array([0.3, 0.0]), damping=0.01)).all()


# ----- computed torque in task coordinates ---------------------------------------------------------------
@pytest.mark.slow
def test_rr_arm_tracks_the_circle_of_example_4_2_1_under_task_space_computed_torque() -> None:
    """The RR arm (a1 = a2 = 2 m) from 2 cm off the circle: path error below 1e-4 m after 1 s at a 1 ms step,
    and the law's torque equals J^T (Mbar (yddot_d + kv edot + kp e) + Nbar) formed from the task quantities."""
    from armdyn import trajectories
    from armdyn.simulation import PythonLoopWarning

    arm = ad.models.two_link_planar(1.0, 1.0, 2.0, 2.0)
    circle, output = Circle((2.0, 1.0), 0.5, 2.0), ts.PlanarPosition()
    joint_path = trajectories.CartesianCircle(2.0, 2.0, (2.0, 1.0), 0.5, 2.0)
    q0, qd0, _ = joint_path(0.0)
    law = TaskComputedTorque(output, circle, 400.0, 40.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        result = ad.simulate(arm, law, joint_path, t_final=1.5, dt=1e-3, q0=q0 + [0.02, -0.02], qd0=qd0)
    desired = np.array([circle(t)[0] for t in result.t])
    error = np.linalg.norm(output.value(arm, result.q) - desired, axis=1)
    assert error[0] > 0.03 and error[result.t >= 1.0].max() < 1e-4
    q, qd, t = result.q[100], result.qd[100], result.t[100]
    y_d, yd_d, ydd_d = circle(t)
    J = output.jacobian(arm, q)
    command = ydd_d + 40.0 * (yd_d - J @ qd) + 400.0 * (y_d - output.value(arm, q))
    expected = J.T @ (ts.task_inertia(arm, output, q) @ command + ts.task_nonlinear(arm, output, q, qd))
    assert_allclose(law(t, q, qd, plant=arm), expected, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: TaskComputedTorque(ts.ToolPosition(), Circle((0, 0), 1, 1), 1, 1)(0.0, np.ones(6), np.ones(6),
                                                                                    plant=ad.models.puma560()),
         "needs a square output"),
        (lambda: TaskComputedTorque(ts.PlanarPosition(), Circle((0, 0), 1, 1), 1, 1)(
            0.0, np.ones(3), np.ones(3), plant=ad.models.cylindrical()), "needs a square output"),
        (lambda: TaskComputedTorque(ts.PlanarPosition(), Line((0, 0, 0), (1, 1, 1), 1), 1, 1)(
            0.0, np.ones(2), np.ones(2), plant=ad.models.two_link_planar()), r"y_d must .* from path\(t\)"),
        (lambda: TaskComputedTorque(ts.PlanarPosition(), lambda t: (1, 2), 1, 1)(
            0.0, np.ones(2), np.ones(2), plant=ad.models.two_link_planar()), "three arrays"),
        (lambda: Line((0, 0), (1, 1, 1), 1), "start and end of a Line"),
        (lambda: Line((0, 0), (1, 1), 0), "duration of a Line must be positive"),
        (lambda: PoseLine(np.eye(4), 2 * np.eye(4), 1), "homogeneous pose"),
        (lambda: PoseLine(np.eye(4), np.eye(3), 1), "end"),
        (lambda: ts.ToolPose().error(ad.models.puma560(), np.zeros(6), np.zeros(5)), "y_d of output"),
        (lambda: TaskComputedTorque(ts.PlanarPosition(), "circle", 1, 1), "path must be a callable"),
        (lambda: TaskComputedTorque(ts.PlanarPosition(), Circle((0, 0), 1, 1), -1, 1), "kp must be at least 0"),
        (lambda: Circle((0, 0, 0, 0), 1, 1), "centre"),
        (lambda: Circle((0, 0), 1, 0), "period of a Circle must be positive"),
        (lambda: TaskComputedTorque(ts.PlanarPosition(), Circle((0, 0), 1, 1), 1, 1)(0.0, np.zeros(2), np.zeros(2)),
         "needs a model of the arm"),
    ],
)  # fmt: skip
def test_task_space_control_arguments_are_checked(build: object, message: str) -> None:
    with pytest.raises(ModelError, match=message):
        build()


@pytest.mark.slow
def test_panda_operational_space_control_keeps_the_tool_on_its_line_while_the_posture_moves() -> None:
    """Khatib's controller on the 7-joint Panda: the tool follows a straight line while a posture task swings
    joint 3 in the null space; the task error is the same as with a still posture (dynamic consistency)."""
    from armdyn.simulation import PythonLoopWarning

    arm, _, _ = _panda_reduced()
    output = ts.ToolPosition()
    start = np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8])
    y0, direction = output.value(arm, start), np.array([0.0, 1.0, 0.0])

    def line(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        w = np.pi
        return (
            y0 + 0.05 * np.sin(w * t) * direction,
            0.05 * w * np.cos(w * t) * direction,
            (-0.05 * w * w * np.sin(w * t) * direction),
        )

    def swing(t: float) -> np.ndarray:
        return start + np.array([0.0, 0.0, 0.4 * np.sin(2.0 * t), 0.0, 0.0, 0.0, 0.0])

    # rk45 evaluates the law continuously: a torque held over a fixed step lets the null-space motion leak into the
    # task at O(dt) (3e-5 m at 1 ms), which is the integration's, not the law's
    moving_start = np.linalg.lstsq(output.jacobian(arm, start), line(0.0)[1], rcond=None)[0]  # on the path at t = 0
    runs = {}
    for name, posture in (("swinging", swing), ("still", start)):
        law = OperationalSpaceControl(output, line, 400.0, 40.0, posture, 100.0, 20.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PythonLoopWarning)
            result = ad.simulate(arm, law, None, t_final=1.0, dt=1e-3, q0=start, qd0=moving_start, method="rk45")
        desired = np.array([line(t)[0] for t in result.t])
        runs[name] = (output.value(arm, result.q) - desired, result.q)
    (moving_error, moving_q), (still_error, _) = runs["swinging"], runs["still"]
    assert np.abs(moving_q[:, 2] - start[2]).max() > 0.2  # the posture task did move joint 3
    assert np.abs(still_error).max() < 1e-4 and np.abs(moving_error).max() < 1e-4
    assert np.abs(moving_error - still_error).max() < 1e-6


# ----- paths, pose tasks, the task record ------------------------------------------------------------
def test_line_and_pose_line_rates_are_the_derivatives_of_their_positions() -> None:
    """Line: quintic, at rest at both ends; PoseLine: [v; w] is the rate of [p; R] (w from dR/dt R^T)."""
    from scipy.spatial.transform import Rotation

    line = Line((0.0, 1.0, 2.0), (1.0, 1.0, 0.0), 2.0, start_time=0.5)
    assert_allclose(line(0.0)[0], [0, 1, 2]) and assert_allclose(line(3.0)[0], [1, 1, 0])
    assert_allclose(line(0.5)[1:], 0.0, atol=1e-15) and assert_allclose(line(2.5)[1:], 0.0, atol=1e-15)
    start, end = np.eye(4), np.eye(4)
    start[:3, :3], start[:3, 3] = Rotation.from_rotvec([0.2, -0.4, 0.1]).as_matrix(), [0.4, 0.1, 0.5]
    end[:3, :3], end[:3, 3] = Rotation.from_rotvec([-1.0, 0.5, 2.0]).as_matrix(), [0.1, -0.3, 0.7]
    pose = PoseLine(start, end, 1.5)
    assert_allclose(Rotation.from_rotvec(pose(2.0)[0][3:]).as_matrix(), end[:3, :3], atol=1e-12)
    h = 1e-6
    for t in (0.3, 0.75, 1.2):
        for path in (line, pose):
            (y0, _, _), (_, yd, ydd), (y1, _, _) = path(t - h), path(t), path(t + h)
            assert_allclose((y1[:3] - y0[:3]) / (2 * h), yd[:3], atol=1e-7)
            assert_allclose((path(t + h)[1] - path(t - h)[1]) / (2 * h), ydd, atol=1e-6)
        R0, R, R1 = (Rotation.from_rotvec(pose(s)[0][3:]).as_matrix() for s in (t - h, t, t + h))
        W = (R1 - R0) / (2 * h) @ R.T
        assert_allclose([W[2, 1], W[0, 2], W[1, 0]], pose(t)[1][3:], atol=1e-7)


@pytest.mark.slow
def test_ur5_tracks_a_pose_line_under_task_space_computed_torque() -> None:
    """ToolPose (m = n = 6): from 0.05 rad off in each joint, the tool pose converges onto a PoseLine (position
    and orientation, the orientation error the rotation vector of R_d R^T), and Result.task records it."""
    from armdyn.simulation import PythonLoopWarning

    arm, output = _ur5(), ts.ToolPose()
    q_start, q_end = np.array([0.3, -1.2, 1.4, -1.6, -1.5, 0.4]), np.array([0.8, -1.0, 1.1, -1.3, -1.2, 0.9])
    path = PoseLine(arm.tool_pose(q_start), arm.tool_pose(q_end), 1.0, start_time=0.2)
    law = TaskComputedTorque(output, path, 400.0, 40.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        result = ad.simulate(arm, law, None, t_final=1.5, dt=1e-3, q0=q_start + 0.05)
    track = result.task
    assert track.output == "ToolPose()" and track.error.shape == (len(result.t), 6)
    size = np.linalg.norm(track.error, axis=1)
    assert size[0] > 0.05 and size[result.t >= 1.0].max() < 1e-4
    # the record's error is the law's: position difference and the rotation vector of R_d R^T
    k = 700
    assert_allclose(track.error[k], output.error(arm, result.q[k], path(result.t[k])[0]), atol=1e-14)
    assert_allclose(arm.tool_pose(result.q[-1]), arm.tool_pose(q_end), atol=1e-4)


def test_result_carries_and_writes_the_task_record(tmp_path) -> None:
    """A task-space run's Result: task y, y_d, error; to_csv and to_npz write them; plot_task draws the path."""
    from armdyn.simulation import PythonLoopWarning

    arm, output = ad.models.two_link_planar(1.0, 1.0, 2.0, 2.0, g=9.8), ts.PlanarPosition()
    q0 = np.array([0.3, 1.2])
    y0 = output.value(arm, q0)
    law = TaskComputedTorque(output, Line(y0, y0 + [0.3, -0.2], 0.2), 400.0, 40.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        result = ad.simulate(arm, law, None, t_final=0.3, dt=1e-3, q0=q0)
    assert_allclose(result.task.y, output.value(arm, result.q))
    assert_allclose(result.task.y_d[-1], y0 + [0.3, -0.2])
    assert np.abs(result.task.error).max() < 2e-3  # it starts on the line; the held torque lags it by O(dt)
    result.to_csv(tmp_path / "run.csv")
    header = (tmp_path / "run.csv").read_text().splitlines()[0].split(",")
    assert header[-6:] == ["y1", "y2", "y_d1", "y_d2", "task_e1", "task_e2"]
    result.to_npz(tmp_path / "run.npz")
    assert_allclose(np.load(tmp_path / "run.npz")["task_error"], result.task.error)
    result.plot_task(tmp_path / "task.png")
    assert (tmp_path / "task.png").stat().st_size > 10_000
    plain = ad.simulate(arm, None, None, t_final=0.01, dt=1e-3)
    assert plain.task is None
    with pytest.raises(ModelError, match="no task-space record"):
        plain.plot_task()


def test_puma_with_its_wrist_aligned_is_singular_unless_damped() -> None:
    """q5 = 0 aligns the PUMA 560's joints 4 and 6: the tool pose's J loses rank; every call names the
    condition number, damping gives finite results, and the forward dynamics need no inverse."""
    arm, output = ad.models.puma560(), ts.ToolPose()
    q, qd = np.array([0.2, -0.5, 0.3, 0.4, 0.0, -0.2]), np.full(6, 0.3)
    assert ts.condition_number(arm, output, q) > 1e12
    calls = {
        "task_inertia": lambda **k: ts.task_inertia(arm, output, q, **k),
        "task_coriolis": lambda **k: ts.task_coriolis(arm, output, q, qd, **k),
        "task_gravity": lambda **k: ts.task_gravity(arm, output, q, **k),
        "task_nonlinear": lambda **k: ts.task_nonlinear(arm, output, q, qd, **k),
        "operational_space": lambda **k: ts.operational_space(arm, output, q, qd, **k).Lambda,
        "operational_inertia": lambda **k: ts.operational_inertia(arm, output, q, **k),
        "batch": lambda **k: ts.task_inertia(arm, output, np.stack([q + 0.3, q]), **k),
    }
    for name, call in calls.items():
        with pytest.raises(ModelError, match="condition number"):
            call()
        assert np.isfinite(call(damping=1e-3)).all(), name
    assert np.isfinite(ts.task_forward_dynamics(arm, output, q, qd, np.ones(6))).all()


def test_out_receives_the_result_and_a_wrong_out_is_refused() -> None:
    arm, output = ad.models.puma560(), ts.ToolPose()
    q, qd = np.array([0.1, 0.7, -2.5, 0.3, 0.6, 0.2]), np.full(6, 0.2)
    qs = np.stack([q, q + 0.1])
    for call, shape in (
        (lambda out: ts.task_inertia(arm, output, q, out=out), (6, 6)),
        (lambda out: ts.task_inertia(arm, output, qs, out=out), (2, 6, 6)),
        (lambda out: ts.task_coriolis(arm, output, q, qd, out=out), (6, 6)),
        (lambda out: ts.task_gravity(arm, output, qs, out=out), (2, 6)),
        (lambda out: ts.task_nonlinear(arm, output, q, qd, out=out), (6,)),
        (lambda out: ts.task_friction(arm, output, q, qd, out=out), (6,)),
        (lambda out: ts.task_force(arm, output, q, qd, out=out), (6,)),
        (lambda out: ts.task_inverse_dynamics(arm, output, q, qd, qd, out=out), (6,)),
        (lambda out: ts.task_forward_dynamics(arm, output, q, qd, qd, out=out), (6,)),
        (lambda out: ts.task_regressor(arm, output, q, qd, qd, out=out), (6, 6 * 14)),
        (lambda out: ts.operational_inertia(arm, ts.ToolPosition(), qs, out=out), (2, 3, 3)),
    ):
        out = np.empty(shape)
        assert call(out) is out
        assert_allclose(out, call(None))
        with pytest.raises(ModelError, match="out must be a writable C-contiguous float64 array"):
            call(np.empty((3, *shape)))


# ----- the skew property on random trees, with an analytic Mbar_dot -----------------------------------
def _tree_output(arm: ad.Robot, q: np.ndarray) -> ts.Output:
    """A square output of a random tree: n rows, chosen greedily for rank at q, among the position rows of
    every link frame's origin (each branch's joints move only their own branch's points)."""
    candidates = [(link, row) for link in range(arm.n) for row in range(3)]
    chosen: list[tuple[int, int]] = []
    for link, row in candidates:
        trial = [*chosen, (link, row)]
        rows = np.array([arm.jacobian(q, link=k)[r] for k, r in trial])
        if np.linalg.matrix_rank(rows, tol=1e-3) == len(trial):
            chosen = trial
        if len(chosen) == arm.n:
            break

    def stack(matrices: dict) -> np.ndarray:
        return np.array([matrices[k][r] for k, r in chosen])

    links = sorted({k for k, _ in chosen})
    return ts.Output(
        lambda x: np.array([arm.link_transforms(x)[k, r, 3] for k, r in chosen]),
        lambda x: stack({k: arm.jacobian(x, link=k) for k in links}),
        jacobian_dot=lambda x, v: stack({k: arm.jacobian_dot(x, v, link=k) for k in links}),
    )


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 5))
def test_skew_property_on_random_trees_with_square_outputs(seed: int, n: int) -> None:
    """Mbar_dot - 2 Vmbar is skew to 1e-10 relative, with Mbar_dot = J^-T Mdot J^-1 - Mbar Jdot J^-1 -
    (Mbar Jdot J^-1)^T exact (from the arm's Mdot and Jdot): trees with friction and motors."""
    arm = strategies.random_robot(seed, n)
    rng = np.random.default_rng(seed)
    q, qd = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n)
    output = _tree_output(arm, q)
    J = output.jacobian(arm, q)
    assume(J.shape == (n, n) and np.linalg.cond(J) < 1e3)
    Ji = np.linalg.inv(J)
    Mbar = ts.task_inertia(arm, output, q)
    K = Mbar @ output.jacobian_dot(arm, q, qd) @ Ji
    Mbar_dot = Ji.T @ arm.inertia_matrix_dot(q, qd) @ Ji - K - K.T
    Vmbar = ts.task_coriolis(arm, output, q, qd)
    S = Mbar_dot - 2 * Vmbar
    assert np.abs(S + S.T).max() <= 1e-10 * max(np.abs(Mbar_dot).max(), np.abs(Vmbar).max())
