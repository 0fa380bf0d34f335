"""Forward kinematics, Jacobians and their derivatives: against Pinocchio, finite differences and hand derivations."""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose, assert_array_equal

import armdyn as ad
from armdyn import ModelError, Robot
from armdyn.model.joint import rot_x, rot_z, trans
from tests.helpers import URDFS, pinocchio_pair
from tests.strategies import random_robot, random_transform

STEP = 1e-6


@functools.cache
def _urdf_arm(name: str) -> Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ad.load_urdf(URDFS[name])


ARMS: dict[str, Callable[[], Robot]] = {
    "panda": lambda: _urdf_arm("panda"),
    "ur5": lambda: _urdf_arm("ur5"),
    "puma560": ad.models.puma560,
    "stanford": ad.models.stanford,
    "scara": ad.models.scara,
    "polar_rp": ad.models.polar_rp,
    "cylindrical": ad.models.cylindrical,
    "two_link_planar": ad.models.two_link_planar,
}

# A tool offset with a rotation and a translation, so that "tool" differs from the tool link's frame
TOOL = trans(0.05, -0.02, 0.12) @ rot_z(0.4) @ rot_x(-0.7)


def _arm(name: str, tool: bool = False) -> Robot:
    arm = ARMS[name]()
    return arm.replace(tool=TOOL) if tool else arm


def _state(arm: Robot, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A random (q, qd); prismatic coordinates kept positive and moderate."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-1.5, 1.5, arm.n)
    prismatic = np.array(arm.kinds) == "prismatic"
    q[prismatic] = rng.uniform(0.1, 0.6, prismatic.sum())
    return q, rng.uniform(-2.0, 2.0, arm.n)


def _skew_vector(m: np.ndarray) -> np.ndarray:
    return np.array([m[2, 1], m[0, 2], m[1, 0]])


# ----- forward kinematics against Pinocchio -----------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(5))
def test_link_transforms_match_pinocchio(urdf_path: Path, seed: int) -> None:
    arm, model, data, q_index, _ = pinocchio_pair(urdf_path)
    q, _ = _state(arm, seed)
    config = pin.neutral(model)
    config[q_index] = q
    pin.forwardKinematics(model, data, config)
    transforms = arm.link_transforms(q)
    assert transforms.shape == (arm.n, 4, 4)
    for i, name in enumerate(arm.joint_names):
        assert_allclose(transforms[i], data.oMi[model.getJointId(name)].homogeneous, rtol=0, atol=1e-12, err_msg=name)
    assert_allclose(arm.tool_pose(q), transforms[arm.tool_link] @ arm.tool, rtol=0, atol=0)


@pytest.mark.parametrize("seed", range(3))
def test_jacobians_match_pinocchio(urdf_path: Path, seed: int) -> None:
    arm, model, data, q_index, v_index = pinocchio_pair(urdf_path)
    q, _ = _state(arm, seed)
    config = pin.neutral(model)
    config[q_index] = q
    pin.computeJointJacobians(model, data, config)
    for i, name in enumerate(arm.joint_names):
        joint_id = model.getJointId(name)
        for frame, reference in (("base", pin.LOCAL_WORLD_ALIGNED), ("tool", pin.LOCAL)):
            expected = pin.getJointJacobian(model, data, joint_id, reference)[:, v_index]
            assert_allclose(arm.jacobian(q, frame, link=i), expected, rtol=0, atol=1e-12, err_msg=f"{name} {frame}")


@pytest.mark.parametrize("seed", range(3))
def test_jacobian_dot_matches_pinocchio(urdf_path: Path, seed: int) -> None:
    arm, model, data, q_index, v_index = pinocchio_pair(urdf_path)
    q, qd = _state(arm, seed)
    config, velocity = pin.neutral(model), np.zeros(model.nv)
    config[q_index], velocity[v_index] = q, qd
    pin.computeJointJacobiansTimeVariation(model, data, config, velocity)
    for i, name in enumerate(arm.joint_names):
        joint_id = model.getJointId(name)
        for frame, reference in (("base", pin.LOCAL_WORLD_ALIGNED), ("tool", pin.LOCAL)):
            expected = pin.getJointJacobianTimeVariation(model, data, joint_id, reference)[:, v_index]
            actual = arm.jacobian_dot(q, qd, frame, link=i)
            assert_allclose(actual, expected, rtol=0, atol=1e-12, err_msg=f"{name} {frame}")


# ----- against finite differences ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(ARMS))
@pytest.mark.parametrize("frame", ["base", "tool"])
def test_jacobian_dot_matches_finite_difference(name: str, frame: str) -> None:
    arm = _arm(name, tool=True)
    for seed in range(2):
        q, qd = _state(arm, seed)
        for link in [None, *range(arm.n)]:
            ahead = arm.jacobian(q + STEP * qd, frame, link)
            behind = arm.jacobian(q - STEP * qd, frame, link)
            expected = (ahead - behind) / (2 * STEP)
            actual = arm.jacobian_dot(q, qd, frame, link)
            assert actual.shape == (6, arm.n)
            scale = max(1.0, np.max(np.abs(expected)))
            assert_allclose(actual, expected, rtol=0, atol=1e-7 * scale, err_msg=f"link {link}")


@pytest.mark.parametrize("name", sorted(ARMS))
def test_jacobian_matches_finite_difference_of_the_pose(name: str) -> None:
    """J = [dp/dq; w] with [w]x = dR/dq R^T (base); the tool frame rotates both blocks by R^T."""
    arm = _arm(name, tool=True)
    q, _ = _state(arm, 3)
    for link in [None, *range(arm.n)]:

        def pose(x: np.ndarray, link: int | None = link) -> np.ndarray:
            return arm.tool_pose(x) if link is None else arm.link_transforms(x)[link]

        rotation = pose(q)[:3, :3]
        expected = np.zeros((6, arm.n))
        for j in range(arm.n):
            dq = np.zeros(arm.n)
            dq[j] = STEP
            derivative = (pose(q + dq) - pose(q - dq)) / (2 * STEP)
            expected[:3, j] = derivative[:3, 3]
            expected[3:, j] = _skew_vector(derivative[:3, :3] @ rotation.T)
        assert_allclose(arm.jacobian(q, "base", link), expected, rtol=0, atol=1e-8, err_msg=f"link {link}")
        in_tool = np.vstack([rotation.T @ expected[:3], rotation.T @ expected[3:]])
        assert_allclose(arm.jacobian(q, "tool", link), in_tool, rtol=0, atol=1e-8, err_msg=f"link {link}")


@pytest.mark.parametrize("name", sorted(ARMS))
def test_link_transform_derivatives_match_finite_difference(name: str) -> None:
    arm = _arm(name)
    q, _ = _state(arm, 4)
    derivatives = arm.link_transform_derivatives(q)
    assert derivatives.shape == (arm.n, arm.n, 4, 4)
    for j in range(arm.n):
        dq = np.zeros(arm.n)
        dq[j] = STEP
        expected = (arm.link_transforms(q + dq) - arm.link_transforms(q - dq)) / (2 * STEP)
        assert_allclose(derivatives[:, j], expected, rtol=0, atol=1e-8, err_msg=f"d/dq{j}")
    # exactly zero where joint j does not move link i
    assert_array_equal(derivatives[~arm.ancestors], 0.0)


def test_panda_fingers_do_not_move_each_other() -> None:
    arm = _arm("panda")
    q, _ = _state(arm, 5)
    derivatives = arm.link_transform_derivatives(q)
    assert_array_equal(derivatives[7, 8], 0.0)
    assert_array_equal(derivatives[8, 7], 0.0)
    jac = arm.jacobian(q, "base", link=7)
    assert_array_equal(jac[:, 8], 0.0)
    assert np.any(jac[:, 7] != 0.0)


# ----- batches -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["panda", "stanford"])
@pytest.mark.parametrize("batch", [(), (5,), (2, 3)], ids=["single", "5", "2x3"])
def test_batch_shapes_equal_per_state_results(name: str, batch: tuple[int, ...]) -> None:
    arm = _arm(name, tool=True)
    n = arm.n
    rng = np.random.default_rng(6)
    q = rng.uniform(-1.0, 1.0, batch + (n,))
    qd = rng.uniform(-1.0, 1.0, batch + (n,))
    outputs = {
        "link_transforms": (arm.link_transforms(q), (n, 4, 4), lambda x, v: arm.link_transforms(x)),
        "tool_pose": (arm.tool_pose(q), (4, 4), lambda x, v: arm.tool_pose(x)),
        "jacobian": (arm.jacobian(q), (6, n), lambda x, v: arm.jacobian(x)),
        "jacobian_tool_link2": (
            arm.jacobian(q, "tool", link=2),
            (6, n),
            lambda x, v: arm.jacobian(x, "tool", link=2),
        ),
        "jacobian_dot": (arm.jacobian_dot(q, qd), (6, n), lambda x, v: arm.jacobian_dot(x, v)),
        "jacobian_dot_tool": (
            arm.jacobian_dot(q, qd, "tool", link=1),
            (6, n),
            lambda x, v: arm.jacobian_dot(x, v, "tool", link=1),
        ),
        "derivatives": (
            arm.link_transform_derivatives(q),
            (n, n, 4, 4),
            lambda x, v: arm.link_transform_derivatives(x),
        ),
    }
    for key, (batched, shape, single) in outputs.items():
        assert batched.shape == batch + shape, key
        for index in np.ndindex(*batch):
            assert_allclose(batched[index], single(q[index], qd[index]), rtol=0, atol=1e-14, err_msg=f"{key} {index}")


def test_list_input_is_accepted() -> None:
    arm = ad.models.puma560()
    assert_array_equal(arm.link_transforms([0, 0, 0, 0, 0, 0]), arm.link_transforms(np.zeros(6)))


# ----- Denavit-Hartenberg: standard against modified ---------------------------------------------------------------
def _standard_to_modified(table: list[dict]) -> tuple[list[dict], np.ndarray]:
    """Craig's conversion: modified row i carries alpha_{i-1}, a_{i-1} of the standard table.

    Returns the modified table and the tool Tx(a_n) Rx(alpha_n) that the modified arm needs to end where the
    standard one does.
    """
    modified = []
    previous_a, previous_alpha = 0.0, 0.0
    for row in table:
        new = dict(row)
        new["a"], new["alpha"] = previous_a, previous_alpha
        previous_a, previous_alpha = row.get("a", 0.0), row.get("alpha", 0.0)
        modified.append(new)
    return modified, trans(x=previous_a) @ rot_x(previous_alpha)


PUMA_GEOMETRY = [
    {"d": 0.67183, "alpha": np.pi / 2},
    {"a": 0.4318},
    {"d": 0.15005, "a": 0.0203, "alpha": -np.pi / 2},
    {"d": 0.4318, "alpha": np.pi / 2},
    {"alpha": -np.pi / 2},
    {"d": 0.056},
]
# every parameter non-zero, offsets on theta and d, a prismatic joint, a non-zero last a and alpha
ODD_GEOMETRY = [
    {"d": 0.3, "a": 0.1, "alpha": 0.4, "theta": 0.2},
    {"kind": "P", "d": 0.05, "a": -0.2, "alpha": -1.1, "theta": 0.7},
    {"d": -0.1, "a": 0.25, "alpha": 0.9, "theta": -0.3},
    {"d": 0.12, "a": 0.15, "alpha": -0.6, "theta": 1.2},
]
PLANAR_GEOMETRY = [{"a": 1.0}, {"a": 0.7}]


@pytest.mark.parametrize("table", [PUMA_GEOMETRY, ODD_GEOMETRY, PLANAR_GEOMETRY], ids=["puma", "odd", "planar"])
def test_standard_and_modified_dh_agree(table: list[dict]) -> None:
    standard = Robot.from_dh(table, convention="standard")
    modified_table, tool = _standard_to_modified(table)
    modified = Robot.from_dh(modified_table, convention="modified", tool=tool)
    assert standard.dh["convention"] == "standard" and modified.dh["convention"] == "modified"
    rng = np.random.default_rng(7)
    for _ in range(4):
        q = rng.uniform(-1.5, 1.5, standard.n)
        assert_allclose(modified.tool_pose(q), standard.tool_pose(q), rtol=0, atol=1e-12)
        # link by link: the standard frame i sits at Tx(a_i) Rx(alpha_i) from the modified frame i
        standard_frames, modified_frames = standard.link_transforms(q), modified.link_transforms(q)
        for i, row in enumerate(table):
            offset = trans(x=row.get("a", 0.0)) @ rot_x(row.get("alpha", 0.0))
            assert_allclose(modified_frames[i] @ offset, standard_frames[i], rtol=0, atol=1e-12, err_msg=f"link {i}")
        for frame in ("base", "tool"):
            assert_allclose(modified.jacobian(q, frame), standard.jacobian(q, frame), rtol=0, atol=1e-12)


def test_modified_dh_without_tool_misses_the_last_offset() -> None:
    """Without the tool the modified arm ends at the last joint axis, a_n along x short of the standard one."""
    standard = Robot.from_dh(PLANAR_GEOMETRY, convention="standard")
    modified = Robot.from_dh(_standard_to_modified(PLANAR_GEOMETRY)[0], convention="modified")
    q = np.array([0.3, -0.8])
    gap = standard.tool_pose(q)[:3, 3] - modified.tool_pose(q)[:3, 3]
    assert_allclose(gap, 0.7 * np.array([np.cos(-0.5), np.sin(-0.5), 0.0]), atol=1e-14)


# ----- hand-derived forward kinematics -------------------------------------------------------------------------------
D1, A2, D3, A3, D4 = 0.67183, 0.4318, 0.15005, 0.0203, 0.4318


def test_puma560_dh_parameters() -> None:
    rows = ad.models.puma560().dh["rows"]
    assert rows[0]["d"] == pytest.approx(D1, abs=1e-12)
    assert rows[1]["a"] == A2
    assert (rows[2]["d"], rows[2]["a"]) == (D3, A3)
    assert rows[3]["d"] == D4


def test_puma560_at_qz() -> None:
    """At q = 0 every standard-DH A matrix is Tz(d) Tx(a) Rx(alpha): the alphas cancel pairwise.

    T1 = Tz(d1) Rx(90): z1 = -y0. T2 = T1 Tx(a2): origin (a2, 0, d1). T3 = T2 Tz(d3) Tx(a3) Rx(-90):
    d3 along z2 = -y0, a3 along x0, rotation back to identity: (a2 + a3, -d3, d1). T4 = T3 Tz(d4) Rx(90):
    (a2 + a3, -d3, d1 + d4); T5 = T4 Rx(-90), T6 = T5: identity rotation.
    """
    arm = ad.models.puma560()
    frames = arm.link_transforms(arm.qz)
    origins = [[0, 0, D1], [A2, 0, D1], [A2 + A3, -D3, D1], [A2 + A3, -D3, D1 + D4], [A2 + A3, -D3, D1 + D4]]
    for i, origin in enumerate(origins):
        assert_allclose(frames[i][:3, 3], origin, rtol=0, atol=1e-12, err_msg=f"link {i}")
    assert_allclose(frames[0][:3, :3], rot_x(np.pi / 2)[:3, :3], atol=1e-15)
    assert_allclose(frames[2][:3, :3], np.eye(3), atol=1e-15)
    expected = np.eye(4)
    expected[:3, 3] = [A2 + A3, -D3, D1 + D4]  # [0.4521, -0.15005, 1.10363]
    assert_allclose(arm.tool_pose(arm.qz), expected, rtol=0, atol=1e-12)


def test_puma560_at_qr() -> None:
    """q = (0, 90, -90, 0, 0, 0) deg, the arm pointing up.

    T2 = Tz(d1) Rx(90) Rz(90) Tx(a2): x2 = z0, so origin (0, 0, d1 + a2), z2 = -y0.
    A3 = Rz(-90) Tz(d3) Tx(a3) Rx(-90): x' = x0, d3 along -y0, a3 along x0, rotation back to identity:
    (a3, -d3, d1 + a2). T4 = T3 Tz(d4) Rx(90): (a3, -d3, d1 + a2 + d4); the wrist adds nothing.
    """
    arm = ad.models.puma560()
    frames = arm.link_transforms(arm.qr)
    assert_allclose(frames[1][:3, 3], [0, 0, D1 + A2], rtol=0, atol=1e-12)
    assert_allclose(frames[2][:3, 3], [A3, -D3, D1 + A2], rtol=0, atol=1e-12)
    expected = np.eye(4)
    expected[:3, 3] = [A3, -D3, D1 + A2 + D4]  # [0.0203, -0.15005, 1.53543]
    assert_allclose(arm.tool_pose(arm.qr), expected, rtol=0, atol=1e-12)


def test_two_link_planar_closed_form() -> None:
    a1, a2 = 0.8, 0.5
    arm = ad.models.two_link_planar(a1=a1, a2=a2)
    q1, q2 = 0.7, -1.9
    c1, s1, c12, s12 = np.cos(q1), np.sin(q1), np.cos(q1 + q2), np.sin(q1 + q2)
    pose = arm.tool_pose([q1, q2])
    assert_allclose(pose[:3, 3], [a1 * c1 + a2 * c12, a1 * s1 + a2 * s12, 0.0], atol=1e-15)
    assert_allclose(pose[:3, :3], rot_z(q1 + q2)[:3, :3], atol=1e-15)
    expected = np.array(
        [
            [-a1 * s1 - a2 * s12, -a2 * s12],
            [a1 * c1 + a2 * c12, a2 * c12],
            [0, 0],
            [0, 0],
            [0, 0],
            [1, 1],
        ]
    )
    assert_allclose(arm.jacobian([q1, q2]), expected, atol=1e-15)
    # d/dt of the closed form
    qd1, qd2 = 0.4, 1.3
    w1, w12 = qd1, qd1 + qd2
    expected_dot = np.zeros((6, 2))
    expected_dot[0] = [-a1 * c1 * w1 - a2 * c12 * w12, -a2 * c12 * w12]
    expected_dot[1] = [-a1 * s1 * w1 - a2 * s12 * w12, -a2 * s12 * w12]
    assert_allclose(arm.jacobian_dot([q1, q2], [qd1, qd2]), expected_dot, atol=1e-15)


def test_polar_and_cylindrical_closed_form() -> None:
    theta, r, h = 0.9, 1.7, 0.4
    polar = ad.models.polar_rp()
    assert_allclose(polar.tool_pose([theta, r])[:3, 3], [r * np.cos(theta), r * np.sin(theta), 0.0], atol=1e-15)
    jac = polar.jacobian([theta, r])
    assert_allclose(jac[:3], [[-r * np.sin(theta), np.cos(theta)], [r * np.cos(theta), np.sin(theta)], [0, 0]])
    assert_allclose(jac[3:], [[0, 0], [0, 0], [1, 0]], atol=0)
    cylinder = ad.models.cylindrical()
    position = cylinder.tool_pose([theta, h, r])[:3, 3]
    assert_allclose(position, [r * np.cos(theta), r * np.sin(theta), h], atol=1e-15)


def test_scara_closed_form() -> None:
    """x, y = a1 c1 + a2 c12, a1 s1 + a2 s12; alpha2 = pi makes the quill go down: z = d1 - d3."""
    arm = ad.models.scara()
    q1, q2, d3, q4 = 0.3, -0.6, 0.12, 1.1
    pose = arm.tool_pose([q1, q2, d3, q4])
    x = 0.325 * np.cos(q1) + 0.275 * np.cos(q1 + q2)
    y = 0.325 * np.sin(q1) + 0.275 * np.sin(q1 + q2)
    assert_allclose(pose[:3, 3], [x, y, 0.387 - d3], atol=1e-15)
    assert_allclose(pose[:3, 2], [0, 0, -1], atol=1e-15)
    assert_allclose(arm.jacobian([q1, q2, d3, q4])[:, 2], [0, 0, -1, 0, 0, 0], atol=1e-15)


def test_tool_jacobian_equals_tool_link_jacobian_without_tool() -> None:
    arm = ad.models.stanford()
    q, qd = _state(arm, 8)
    for frame in ("base", "tool"):
        assert_array_equal(arm.jacobian(q, frame), arm.jacobian(q, frame, link=arm.tool_link))
        assert_array_equal(arm.jacobian_dot(q, qd, frame), arm.jacobian_dot(q, qd, frame, link=arm.tool_link))


def test_base_transform_moves_everything() -> None:
    arm = ad.models.puma560()
    base = trans(0.3, -0.2, 0.5) @ rot_z(0.8)
    moved = arm.replace(base=base)
    q, qd = _state(arm, 9)
    assert_allclose(moved.link_transforms(q), base @ arm.link_transforms(q), atol=1e-14)
    rotation = np.kron(np.eye(2), base[:3, :3])
    assert_allclose(moved.jacobian(q), rotation @ arm.jacobian(q), atol=1e-14)
    assert_allclose(moved.jacobian(q, "tool"), arm.jacobian(q, "tool"), atol=1e-14)
    assert_allclose(moved.jacobian_dot(q, qd), rotation @ arm.jacobian_dot(q, qd), atol=1e-14)


# ----- errors ------------------------------------------------------------------------------------------------------
def _calls(arm: Robot, q: object) -> list[Callable[[], object]]:
    return [
        lambda: arm.link_transforms(q),
        lambda: arm.tool_pose(q),
        lambda: arm.jacobian(q),
        lambda: arm.jacobian_dot(q, np.zeros(6)),
        lambda: arm.link_transform_derivatives(q),
    ]


@pytest.mark.parametrize("q", [np.zeros(5), np.zeros(7), np.zeros((3, 5)), 0.0], ids=["5", "7", "3x5", "scalar"])
def test_q_with_the_wrong_length(q: object) -> None:
    arm = ad.models.puma560()
    for call in _calls(arm, q):
        with pytest.raises(ModelError, match=r"q must have shape \(6,\) or \(\.\.\., 6\) for 'puma560'"):
            call()


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_q_not_finite(bad: float) -> None:
    arm = ad.models.puma560()
    q = np.zeros((2, 6))
    q[1, 3] = bad
    for call in _calls(arm, q):
        with pytest.raises(ModelError, match=r"q must be finite"):
            call()


def test_qd_wrong_or_not_finite() -> None:
    arm = ad.models.puma560()
    with pytest.raises(ModelError, match=r"qd must have shape \(6,\) or \(\.\.\., 6\)"):
        arm.jacobian_dot(np.zeros(6), np.zeros(5))
    with pytest.raises(ModelError, match=r"qd must be finite"):
        arm.jacobian_dot(np.zeros(6), [0, 0, np.nan, 0, 0, 0])


@pytest.mark.parametrize("frame", ["world", "Base", "local", ""])
def test_unknown_frame(frame: str) -> None:
    arm = ad.models.puma560()
    with pytest.raises(ModelError, match=r"frame must be 'base' or 'tool'"):
        arm.jacobian(np.zeros(6), frame)
    with pytest.raises(ModelError, match=r"frame must be 'base' or 'tool'"):
        arm.jacobian_dot(np.zeros(6), np.zeros(6), frame)
    with pytest.raises(ModelError, match=r"frame must be 'base' or 'tool'"):
        arm.jacobian(np.zeros(6), frame, link=2)


@pytest.mark.parametrize("link", [6, 7, -1, -6])
def test_link_index_out_of_range(link: int) -> None:
    arm = ad.models.puma560()
    message = rf"link index {link} is out of range for 'puma560' \(0\.\.5\)"
    with pytest.raises(ModelError, match=message):
        arm.jacobian(np.zeros(6), link=link)
    with pytest.raises(ModelError, match=message):
        arm.jacobian_dot(np.zeros(6), np.zeros(6), link=link)


@pytest.mark.parametrize("link", [2.7, 2.0, np.float64(1.0), True, np.bool_(False), "2", [2]], ids=repr)
def test_non_integer_link_index_is_an_error(link: object) -> None:
    arm = ad.models.puma560()
    with pytest.raises(ModelError, match=r"link must be an integer link index \(0\.\.5\) or None, got"):
        arm.jacobian(np.zeros(6), link=link)
    with pytest.raises(ModelError, match=r"link must be an integer link index"):
        arm.jacobian_dot(np.zeros(6), np.zeros(6), link=link)


def test_numpy_integer_link_index_is_a_link_index() -> None:
    arm = ad.models.puma560()
    q = arm.qn
    for link in (np.int64(2), np.int32(2), np.uint8(2)):
        assert_array_equal(arm.jacobian(q, link=link), arm.jacobian(q, link=2))
        assert_array_equal(arm.jacobian_dot(q, q, link=link), arm.jacobian_dot(q, q, link=2))


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda arm: arm.jacobian("q"), ModelError, "q must be an array of numbers"),
        (lambda arm: arm.jacobian(None), ModelError, "q must be an array of numbers"),
        (lambda arm: arm.jacobian({"q": 1}), ModelError, "q must be an array of numbers"),
        (lambda arm: arm.link_transforms("abc"), ModelError, "q must be an array of numbers"),
        (lambda arm: arm.tool_pose(None), ModelError, "q must be an array of numbers"),
        (lambda arm: arm.link_transform_derivatives({}), ModelError, "q must be an array of numbers"),
        (lambda arm: arm.jacobian_dot(np.zeros(6), "qd"), ModelError, "qd must be an array of numbers"),
        (lambda arm: arm.jacobian(np.zeros(6), frame=None), ModelError, "frame must be 'base' or 'tool', got None"),
        (lambda arm: arm.jacobian(np.zeros(6), frame=["base"]), ModelError, "frame must be 'base' or 'tool'"),
        (lambda arm: arm.jacobian_dot(np.zeros(6), np.zeros(6), frame=np.array(["base", "tool"])), ModelError,
         "frame must be 'base' or 'tool'"),
        (lambda arm: ad.kinematics.jacobian("puma560", np.zeros(6)), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: ad.kinematics.link_transforms(None, np.zeros(6)), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: ad.kinematics.as_state({}, np.zeros(6)), TypeError, "arm must be an armdyn ArmModel"),
        (lambda arm: ad.models.two_link_planar(symbolic=True).jacobian([0, 0]), ModelError,
         "arm 'two_link_planar' has symbolic parameters; numeric dynamics and kinematics need numbers"),
        (lambda arm: ad.kinematics.jacobian(ad.models.two_link_planar(symbolic=True), [0, 0]), TypeError,
         "arm 'two_link_planar' has symbolic"),
        (lambda arm: ad.kinematics.joint_motion(True, [0, 0, 1], 10**400), ModelError, "q must be a number"),
        (lambda arm: ad.kinematics.twist_generators(arm, "q"), ModelError, "q must be an array of numbers"),
        (lambda arm: ad.kinematics.skew("v"), ModelError, "v must be an array of numbers"),
        (lambda arm: ad.kinematics.skew([1.0, 2.0]), ModelError, r"v must have shape \(3,\)"),
        (lambda arm: ad.kinematics.joint_motion("yes", [0, 0, 1], 0.1), ModelError, "revolute must be True or False"),
        (lambda arm: ad.kinematics.joint_motion(True, "z", 0.1), ModelError, "axis must be an array of numbers"),
        (lambda arm: ad.kinematics.joint_motion(True, [0, 0, 2], 0.1), ModelError, "axis must be a unit 3-vector"),
        (lambda arm: ad.kinematics.joint_motion(True, [0, 0, 1], "0.1"), ModelError, "q must be a number or an array"),
        (lambda arm: ad.kinematics.joint_motion(True, [0, 0, 1], None), ModelError, "q must be a number or an array"),
        (lambda arm: ad.kinematics.joint_axes(arm, "joints"), ModelError, "joints must be a number or an array"),
        (lambda arm: ad.kinematics.joint_axes(arm, np.zeros((5, 4, 4))), ModelError,
         r"joints must have shape \(\.\.\., 6, 4, 4\)"),
    ],
)  # fmt: skip
def test_kinematics_wrong_types_name_the_argument(call: object, error: type, message: str) -> None:
    with pytest.raises(error, match=message):
        call(ad.models.puma560())


def test_public_helpers_still_compute() -> None:
    assert_allclose(ad.kinematics.skew([1.0, 2.0, 3.0]) @ [4.0, 5.0, 6.0], np.cross([1, 2, 3], [4, 5, 6]))
    motion = ad.kinematics.joint_motion(True, [0, 0, 1], np.array([0.0, np.pi / 2]))
    assert motion.shape == (2, 4, 4)
    assert_allclose(motion[1, :3, :3], rot_z(np.pi / 2)[:3, :3], atol=1e-15)
    arm = ad.models.puma560()
    _, joints = ad.kinematics.joint_frames(arm, arm.qn)
    z, o = ad.kinematics.joint_axes(arm, joints)
    assert z.shape == o.shape == (6, 3)


# ----- the compiled kinematics against the NumPy reference ------------------------------------------
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), n=st.integers(1, 7), base=st.booleans())
def test_compiled_kinematics_equal_the_numpy_reference(seed: int, n: int, base: bool) -> None:
    """Every link pose, the tool pose, and the Jacobian and its derivative of the tool and of each
    link, in world and local axes, on random trees with a base and a tool: to 1e-13."""
    from armdyn import kinematics
    from armdyn.dynamics import api

    arm = random_robot(seed, n)
    if base:
        arm = arm.replace(base=random_transform(np.random.default_rng(seed + 1)))
    rng = np.random.default_rng(seed)
    q, qd = rng.uniform(-3, 3, arm.n), rng.uniform(-3, 3, arm.n)
    assert_allclose(api.link_transforms(arm, q), kinematics.link_transforms(arm, q), rtol=0, atol=1e-13)
    assert_allclose(api.tool_pose(arm, q), kinematics.tool_pose(arm, q), rtol=0, atol=1e-13)
    for link in (None, *range(arm.n)):
        for frame in ("base", "tool"):
            expected = kinematics.jacobian(arm, q, frame, link)
            assert_allclose(api.jacobian(arm, q, frame, link), expected, rtol=0, atol=1e-13)
            expected = kinematics.jacobian_dot(arm, q, qd, frame, link)
            assert_allclose(api.jacobian_dot(arm, q, qd, frame, link), expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["ur5", "panda", "puma560", "polar_rp"])
def test_compiled_kinematics_batches_and_out(name: str) -> None:
    """A batch is one compiled call equal to the one-state calls; out= receives the result."""
    from armdyn.dynamics import api

    arm = ARMS[name]()
    rng = np.random.default_rng(3)
    q, qd = rng.uniform(-2, 2, (3, 2, arm.n)), rng.uniform(-2, 2, (2, arm.n))
    cases = [
        (api.link_transforms, (q,), {}, (arm.n, 4, 4)),
        (api.tool_pose, (q,), {}, (4, 4)),
        (api.jacobian, (q,), {"frame": "tool", "link": arm.n - 1}, (6, arm.n)),
        (api.jacobian_dot, (q, qd), {"frame": "base"}, (6, arm.n)),
    ]
    for function, states, options, shape in cases:
        batch = function(arm, *states, **options)
        assert batch.shape == (3, 2, *shape)
        for index in np.ndindex(3, 2):
            one = function(arm, *(s[index[-s.ndim + 1 :]] if s.ndim == 2 else s[index] for s in states), **options)
            assert_array_equal(batch[index], one)
        out = np.empty((3, 2, *shape))
        assert function(arm, *states, **options, out=out) is out
        assert_array_equal(out, batch)
        with pytest.raises(ModelError, match="out must be"):
            function(
                arm, *(s[0, 0] if s.ndim == 3 else s[0] for s in states), **options, out=np.empty(shape[::-1] + (1,))
            )
