"""load_urdf: the example-robot-data arms against Pinocchio, hand-written URDF files, every error path."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from numpy.testing import assert_allclose, assert_array_equal

import armdyn as ad
from armdyn import ModelError, load_urdf
from tests.helpers import ROBOTS, URDFS, pin_q, pinocchio_pair

ALLEGRO = ROBOTS / "allegro_hand_description" / "urdf"
EXPECTED_N = {"panda.urdf": 9, "ur5_robot.urdf": 6}

# A valid, fully populated inertia (principal moments satisfy the triangle inequality)
GOOD_INERTIA = "ixx='0.02' iyy='0.03' izz='0.04' ixy='0.001' ixz='-0.002' iyz='0.0015'"
LIMIT = "<limit lower='-2' upper='2' effort='10' velocity='1'/>"


# ----- helpers to write small URDF files ---------------------------------------------------------------------
def _link(name: str, mass: float | str = 1.0, xyz: str = "0.01 0.02 0.03", rpy: str = "0.1 -0.2 0.3",
          inertia: str = GOOD_INERTIA, extra: str = "") -> str:  # fmt: skip
    return (
        f"<link name='{name}'><inertial><origin xyz='{xyz}' rpy='{rpy}'/><mass value='{mass}'/>"
        f"<inertia {inertia}/></inertial>{extra}</link>"
    )


def _joint(name: str, parent: str, child: str, kind: str = "revolute", xyz: str = "0.1 0.05 0.2",
           rpy: str = "0.3 0.1 -0.2", axis: str = "0 0 1", extra: str = LIMIT) -> str:  # fmt: skip
    return (
        f"<joint name='{name}' type='{kind}'><parent link='{parent}'/><child link='{child}'/>"
        f"<origin xyz='{xyz}' rpy='{rpy}'/><axis xyz='{axis}'/>{extra}</joint>"
    )


def _robot(*parts: str) -> str:
    return "<?xml version='1.0'?>\n<robot name='test'>\n" + "\n".join(parts) + "\n</robot>\n"


def _write(tmp_path: Path, text: str, name: str = "test.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _load_quiet(path: Path, strict: bool = True) -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_urdf(path, strict=strict)


def _pinocchio(path: Path, arm: ad.Robot) -> tuple[pin.Model, list[int]]:
    model = pin.buildModelFromUrdf(str(path))
    return model, [model.getJointId(name) for name in arm.joint_names]


def _assert_fk_matches_pinocchio(path: Path, arm: ad.Robot, count: int = 3, seed: int = 0) -> None:
    model, ids = _pinocchio(path, arm)
    data = model.createData()
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q = rng.uniform(-1.5, 1.5, arm.n)
        pin.forwardKinematics(model, data, pin_q(model, ids, q))
        transforms = arm.link_transforms(q)
        for i, joint_id in enumerate(ids):
            assert_allclose(transforms[i], data.oMi[joint_id].homogeneous, rtol=0, atol=1e-12)


def _assert_inertias_match_pinocchio(path: Path, arm: ad.Robot) -> None:
    model, ids = _pinocchio(path, arm)
    for link, joint_id in zip(arm.links, ids, strict=True):
        expected = model.inertias[joint_id]
        assert link.inertial.mass == pytest.approx(expected.mass, abs=1e-12), link.name
        assert_allclose(link.inertial.com, expected.lever, rtol=0, atol=1e-12, err_msg=link.name)
        assert_allclose(link.inertial.inertia, expected.inertia, rtol=0, atol=1e-12, err_msg=link.name)


# ----- Panda and UR5 against Pinocchio -----------------------------------------------------------------------
def test_joint_count_and_names_match_pinocchio(urdf_path: Path) -> None:
    arm, model, _, _, _ = pinocchio_pair(urdf_path)
    assert arm.n == EXPECTED_N[urdf_path.name]
    assert arm.n == model.nv == model.njoints - 1
    assert arm.joint_names == list(model.names)[1:]


def test_joint_kinds_match_pinocchio(urdf_path: Path) -> None:
    arm, model, _, _, _ = pinocchio_pair(urdf_path)
    letters = {"revolute": "R", "prismatic": "P"}
    for name, kind in zip(arm.joint_names, arm.kinds, strict=True):
        shortname = model.joints[model.getJointId(name)].shortname()
        assert shortname.startswith("JointModel" + letters[kind]), (name, kind, shortname)


def test_panda_fingers_are_prismatic() -> None:
    arm = _load_quiet(URDFS["panda"])
    assert arm.kinds == ["revolute"] * 7 + ["prismatic"] * 2
    assert arm.joint_names[7:] == ["panda_finger_joint1", "panda_finger_joint2"]
    assert_array_equal(arm.parents, [-1, 0, 1, 2, 3, 4, 5, 6, 6])  # both fingers hang from the hand
    assert not arm.is_chain


def test_ur5_is_an_all_revolute_chain() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no mimic joints, no odd inertias: no warning at all
        arm = load_urdf(URDFS["ur5"])
    assert arm.kinds == ["revolute"] * 6
    assert arm.is_chain


def test_panda_mimic_joint_warns() -> None:
    with pytest.warns(UserWarning, match=r"panda_finger_joint2") as record:
        arm = load_urdf(URDFS["panda"])
    assert any("mimic" in str(w.message) for w in record)
    assert not any("panda_finger_joint1" in str(w.message) for w in record)  # only the mimicking joint is named
    assert arm.n == 9  # loaded as an independent joint


def test_limits_and_damping_match_pinocchio(urdf_path: Path) -> None:
    arm, model, _, q_index, v_index = pinocchio_pair(urdf_path)
    assert_array_equal(arm.qlim[0], model.lowerPositionLimit[q_index])
    assert_array_equal(arm.qlim[1], model.upperPositionLimit[q_index])
    assert_allclose(arm.viscous_friction, model.damping[v_index], rtol=0, atol=1e-15)
    assert_allclose(arm.coulomb_friction[:, 0], model.friction[v_index], rtol=0, atol=1e-15)
    assert_allclose(arm.coulomb_friction[:, 1], -model.friction[v_index], rtol=0, atol=1e-15)


def test_total_mass_matches_pinocchio(urdf_path: Path) -> None:
    arm, model, _, _, _ = pinocchio_pair(urdf_path)
    total = sum(link.inertial.mass for link in arm.links)
    expected = sum(model.inertias[i].mass for i in range(1, model.njoints))  # moving joints only, not the universe
    assert total == pytest.approx(expected, rel=1e-14)
    assert total > 10.0  # both arms weigh well over 10 kg


def test_link_inertias_match_pinocchio(urdf_path: Path) -> None:
    """Mass, centre of mass and inertia about it, per moving joint: checks the merging of fixed-joint children."""
    arm = _load_quiet(urdf_path)
    _assert_inertias_match_pinocchio(urdf_path, arm)


# ----- small hand-written files --------------------------------------------------------------------------------
def test_continuous_joint_has_one_unlimited_coordinate(tmp_path: Path) -> None:
    path = _write(tmp_path, _robot(_link("base"), _link("arm"), _joint("spin", "base", "arm", "continuous", extra="")))
    arm = load_urdf(path)
    assert arm.n == 1
    assert arm.kinds == ["revolute"]
    assert_array_equal(arm.qlim, [[-np.inf], [np.inf]])
    _assert_fk_matches_pinocchio(path, arm)
    # one coordinate, the angle: a full turn comes back to the same pose, beyond +-pi is fine
    assert_allclose(arm.link_transforms([0.4 + 2 * np.pi]), arm.link_transforms([0.4]), atol=1e-12)


def test_continuous_joint_ignores_a_limit_element(tmp_path: Path) -> None:
    joint = _joint("spin", "base", "arm", "continuous", extra="<limit effort='1' velocity='1'/>")
    arm = load_urdf(_write(tmp_path, _robot(_link("base"), _link("arm"), joint)))
    assert_array_equal(arm.qlim, [[-np.inf], [np.inf]])


def test_prismatic_joint_with_limits(tmp_path: Path) -> None:
    limit = "<limit lower='-0.1' upper='0.3' effort='10' velocity='1'/>"
    joint = _joint("slide", "base", "carriage", "prismatic", axis="0 1 0", extra=limit)
    path = _write(tmp_path, _robot(_link("base"), _link("carriage"), joint))
    arm = load_urdf(path)
    assert arm.kinds == ["prismatic"]
    assert_array_equal(arm.qlim, [[-0.1], [0.3]])
    _assert_fk_matches_pinocchio(path, arm)
    # moving by dq translates the link along its own y axis, without rotating it
    t0, t1 = arm.link_transforms([0.0])[0], arm.link_transforms([0.25])[0]
    assert_allclose(t1[:3, :3], t0[:3, :3], atol=1e-15)
    assert_allclose(t1[:3, 3] - t0[:3, 3], 0.25 * t0[:3, 1], atol=1e-15)


def test_branching_tree(tmp_path: Path) -> None:
    """Two children of one link; the numbering is depth first, children in file order."""
    text = _robot(
        _link("root"),
        _link("trunk"),
        _link("left"),
        _link("right", mass=2.0),
        _link("left_tip", mass=0.5),
        _joint("j_trunk", "root", "trunk"),
        _joint("j_left", "trunk", "left", axis="1 0 0"),
        _joint("j_right", "trunk", "right", "prismatic", xyz="-0.1 0.2 0", axis="0 0.6 0.8"),
        _joint("j_left_tip", "left", "left_tip", "continuous", axis="0 1 0", extra=""),
    )
    path = _write(tmp_path, text)
    arm = load_urdf(path)
    assert arm.joint_names == ["j_trunk", "j_left", "j_left_tip", "j_right"]
    assert_array_equal(arm.parents, [-1, 0, 1, 0])
    assert not arm.is_chain
    assert_array_equal(arm.ancestors[3], [True, False, False, True])
    model, ids = _pinocchio(path, arm)
    for i, joint_id in enumerate(ids):  # same parent, by name
        parent = arm.parents[i]
        expected = model.names[model.parents[joint_id]]
        assert (arm.joint_names[parent] if parent >= 0 else "universe") == expected
    _assert_fk_matches_pinocchio(path, arm)
    _assert_inertias_match_pinocchio(path, arm)


def test_fixed_joints_are_merged_into_the_moving_parent(tmp_path: Path) -> None:
    """moving j1 -> b =fixed=> c =fixed=> e -> moving j2 -> d, a fixed sensor leaf on d, a fixed plate on the root."""
    text = _robot(
        _link("a", mass=5.0),
        _link("b", mass=1.0),
        _link("c", mass=0.7, xyz="0.05 -0.02 0.1", rpy="0.5 0.4 -0.3"),
        _link("e", mass=0.3, xyz="-0.03 0.01 0.02", rpy="-0.2 0.1 0.9"),
        _link("d", mass=1.2),
        _link("sensor", mass=0.2, xyz="0 0 0.01", rpy="0 0 0"),
        _link("plate", mass=3.0),
        _joint("j1", "a", "b"),
        _joint("f1", "b", "c", "fixed", xyz="0.2 0.1 -0.05", rpy="0.7 -0.3 0.2", extra=""),
        _joint("f2", "c", "e", "fixed", xyz="0.0 0.15 0.05", rpy="-0.4 0.2 0.6", extra=""),
        _joint("j2", "e", "d", axis="0 1 0"),
        _joint("f3", "d", "sensor", "fixed", extra=""),
        _joint("f0", "a", "plate", "fixed", extra=""),
    )
    path = _write(tmp_path, text)
    arm = load_urdf(path)
    assert arm.joint_names == ["j1", "j2"]
    assert_array_equal(arm.parents, [-1, 0])
    assert arm.links[0].inertial.mass == pytest.approx(1.0 + 0.7 + 0.3)
    assert arm.links[1].inertial.mass == pytest.approx(1.2 + 0.2)
    _assert_fk_matches_pinocchio(path, arm)
    _assert_inertias_match_pinocchio(path, arm)


def test_dynamics_damping_and_friction(tmp_path: Path) -> None:
    joint = _joint("j", "a", "b", extra=LIMIT + "<dynamics damping='0.5' friction='0.2'/>")
    arm = load_urdf(_write(tmp_path, _robot(_link("a"), _link("b"), joint)))
    assert_array_equal(arm.viscous_friction, [0.5])
    assert_array_equal(arm.coulomb_friction, [[0.2, -0.2]])


def test_no_dynamics_element_means_no_friction(tmp_path: Path) -> None:
    arm = load_urdf(_write(tmp_path, _robot(_link("a"), _link("b"), _joint("j", "a", "b"))))
    assert_array_equal(arm.viscous_friction, [0.0])
    assert_array_equal(arm.coulomb_friction, [[0.0, 0.0]])


def test_missing_package_mesh_is_ignored(tmp_path: Path) -> None:
    mesh = "<geometry><mesh filename='package://no_such_package/meshes/part.stl' scale='1 1 1'/></geometry>"
    visual = f"<visual><origin xyz='0 0 0'/>{mesh}</visual><collision>{mesh}</collision>"
    path = _write(tmp_path, _robot(_link("a", extra=visual), _link("b", extra=visual), _joint("j", "a", "b")))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arm = load_urdf(path)
    assert arm.n == 1
    assert arm.links[0].inertial.mass == 1.0


def test_link_without_inertial_is_massless(tmp_path: Path) -> None:
    """A kinematics-only file: M(q) = 0, loaded (strict or not) with a warning that names the joints."""
    path = _write(tmp_path, _robot("<link name='a'/>", "<link name='b'/>", _joint("j", "a", "b")))
    for strict in (True, False):
        with pytest.warns(UserWarning, match=r"\['j'\] move no mass.*kinematics-only"):
            arm = load_urdf(path, strict=strict)
    assert arm.links[0].inertial.mass == 0.0
    assert_array_equal(arm.links[0].inertial.inertia, np.zeros((3, 3)))
    assert not arm.has_dynamics


def test_non_unit_axis_warns_and_is_normalised(tmp_path: Path) -> None:
    path = _write(tmp_path, _robot(_link("a"), _link("b"), _joint("j", "a", "b", axis="0 0 2")))
    with pytest.warns(UserWarning, match=r"'j'.*not a unit vector"):
        arm = load_urdf(path)
    assert_allclose(arm.links[0].joint.axis, [0.0, 0.0, 1.0])


def test_gravity_option(tmp_path: Path) -> None:
    path = _write(tmp_path, _robot(_link("a"), _link("b"), _joint("j", "a", "b")))
    assert_array_equal(load_urdf(path).gravity, [0.0, 0.0, -9.81])
    assert_array_equal(load_urdf(path, gravity=(0.0, -9.8, 0.0)).gravity, [0.0, -9.8, 0.0])


# ----- error paths ------------------------------------------------------------------------------------------------
def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"nowhere\.urdf.*no such URDF file"):
        load_urdf(tmp_path / "nowhere.urdf")


def test_a_directory_is_not_a_file(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"no such URDF file"):
        load_urdf(tmp_path)


def test_malformed_xml_unclosed_tag(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _joint("j", "a", "b")).replace("</link>", "", 1)  # first <link> unclosed
    with pytest.raises(ModelError, match=r"malformed XML"):
        load_urdf(_write(tmp_path, text))


def test_malformed_xml_missing_closing_robot_tag(tmp_path: Path) -> None:
    """A file cut short (no </robot>) is malformed XML and must not load as if it were whole."""
    text = _robot(_link("a"), _link("b"), _joint("j", "a", "b")).replace("</robot>", "")
    with pytest.raises(ModelError, match=r"malformed XML"):
        load_urdf(_write(tmp_path, text))


def test_empty_file(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"malformed XML"):
        load_urdf(_write(tmp_path, ""))


def test_floating_joint(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _joint("free", "a", "b", "floating", extra=""))
    with pytest.raises(ModelError, match=r"joint 'free' is floating"):
        load_urdf(_write(tmp_path, text))


def test_planar_joint(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _joint("flat", "a", "b", "planar", extra=""))
    with pytest.raises(ModelError, match=r"joint 'flat' is planar"):
        load_urdf(_write(tmp_path, text))


def test_kinematic_loop(tmp_path: Path) -> None:
    """Link 'c' is the child of two joints."""
    text = _robot(
        _link("a"), _link("b"), _link("c"), _joint("j1", "a", "b"), _joint("j2", "a", "c"), _joint("j3", "b", "c")
    )
    with pytest.raises(ModelError, match=r"joint 'j3'.*link 'c' already has parent joint 'j2'.*loop"):
        load_urdf(_write(tmp_path, text))


def test_joints_forming_a_cycle_have_no_root(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _joint("j1", "a", "b"), _joint("j2", "b", "a"))
    with pytest.raises(ModelError, match=r"root link"):
        load_urdf(_write(tmp_path, text))


def test_joint_refers_to_undefined_link(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _joint("j1", "a", "b"), _joint("j2", "b", "ghost"))
    with pytest.raises(ModelError, match=r"joint 'j2' refers to link 'ghost'"):
        load_urdf(_write(tmp_path, text))


def test_negative_mass(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b", mass=-1.0), _joint("j", "a", "b"))
    with pytest.raises(ModelError, match=r"link 'b'.*mass must be non-negative"):
        load_urdf(_write(tmp_path, text))


def test_negative_mass_behind_a_fixed_joint(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _link("c", mass=-0.5), _joint("j", "a", "b"), _joint("f", "b", "c", "fixed"))
    with pytest.raises(ModelError, match=r"link 'c'.*mass must be non-negative"):
        load_urdf(_write(tmp_path, text))


def test_inertia_not_positive_semidefinite(tmp_path: Path) -> None:
    inertia = "ixx='-1' iyy='1' izz='1' ixy='0' ixz='0' iyz='0'"
    text = _robot(_link("a"), _link("b", inertia=inertia), _joint("j", "a", "b"))
    with pytest.raises(ModelError, match=r"link 'b'.*not positive semi-definite"):
        load_urdf(_write(tmp_path, text))


TRIANGLE_BREAKER = "ixx='1' iyy='1' izz='3' ixy='0' ixz='0' iyz='0'"


def test_triangle_inequality_rejected_by_default(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b", inertia=TRIANGLE_BREAKER, rpy="0 0 0"), _joint("j", "a", "b"))
    with pytest.raises(ModelError, match=r"link 'b'.*triangle inequality.*strict=False"):
        load_urdf(_write(tmp_path, text))


def test_triangle_inequality_accepted_with_strict_false(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b", inertia=TRIANGLE_BREAKER, rpy="0 0 0"), _joint("j", "a", "b"))
    with pytest.warns(UserWarning, match=r"link 'b'.*triangle inequality"):
        arm = load_urdf(_write(tmp_path, text), strict=False)
    assert_array_equal(arm.links[0].inertial.inertia, np.diag([1.0, 1.0, 3.0]))  # kept as given


def test_triangle_inequality_behind_a_fixed_joint(tmp_path: Path) -> None:
    text = _robot(
        _link("a"), _link("b"), _link("c", inertia=TRIANGLE_BREAKER), _joint("j", "a", "b"),
        _joint("f", "b", "c", "fixed", extra=""),
    )  # fmt: skip
    path = _write(tmp_path, text)
    with pytest.raises(ModelError, match=r"link 'c'.*strict=False"):
        load_urdf(path)
    with pytest.warns(UserWarning, match=r"link 'c'"):
        load_urdf(path, strict=False)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (_robot(_link("a"), _link("b"), _joint("j", "a", "b", "spherical", extra="")), "joint 'j' has unknown type"),
        (_robot(_link("a")), "no revolute, continuous or prismatic joint"),
        (_robot(_link("a"), _link("b"), _joint("f", "a", "b", "fixed", extra="")), "no revolute"),
        (_robot(_link("a"), _link("b")), r"one root link, found \['a', 'b'\]"),
        (_robot(_link("a"), _link("b"), _joint("j", "a", "b", axis="0 0 0")), "'j'.*axis.*no direction"),
        (
            _robot(_link("a"), _link("b"), _link("c"), _joint("j", "a", "b"), _joint("j", "b", "c")),
            "'j'.*unique",
        ),
        (
            _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra="<limit lower='1' upper='-1'/>")),
            "'j'.*lower <= upper",
        ),
        (
            _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra=LIMIT + "<dynamics damping='-1'/>")),
            "'j'.*viscous friction",
        ),
        (
            _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra=LIMIT + "<dynamics friction='-1'/>")),
            "'j'.*Coulomb friction",
        ),
    ],
    ids=[
        "unknown-type",
        "no-joint",
        "only-fixed",
        "two-roots",
        "zero-axis",
        "duplicate-joint",
        "bad-limits",
        "negative-damping",
        "negative-friction",
    ],
)
def test_other_invalid_models(tmp_path: Path, text: str, match: str) -> None:
    with pytest.raises(ModelError, match=match):
        load_urdf(_write(tmp_path, text))


def test_duplicate_link_names_are_rejected(tmp_path: Path) -> None:
    """Two different definitions of link 'b': urdfdom (and so Pinocchio) refuses the file; armdyn must not pick one."""
    text = _robot(_link("a"), _link("b", mass=1.0), _link("b", mass=9.0), _joint("j", "a", "b"))
    with pytest.raises(ModelError, match=r"'b'"):
        load_urdf(_write(tmp_path, text))


@pytest.mark.parametrize(
    "text",
    [
        "",
        "<robot name='t'><link name='a'>",
        "<not-a-robot/>",
        "plain text, not XML at all",
        _robot(_link("a"), _link("b", mass="heavy"), _joint("j", "a", "b")),
        _robot(_link("a"), _link("b"), _joint("j", "a", "b", xyz="0 zero 0")),
        _robot(_link("a"), _link("b"), _joint("j", "a", "b", axis="0 0")),
        _robot(_link("a"), _link("b", inertia=TRIANGLE_BREAKER.replace("'3'", "'x'")), _joint("j", "a", "b")),
        _robot(_link("a"), _link("b"), "<joint name='j' type='revolute'><child link='b'/></joint>"),
        _robot(_link("a"), _link("b"), "<joint type='revolute'><parent link='a'/><child link='b'/></joint>"),
    ],
    ids=[
        "empty",
        "unclosed",
        "wrong-root",
        "not-xml",
        "bad-mass",
        "bad-origin",
        "short-axis",
        "bad-inertia",
        "no-parent",
        "no-joint-name",
    ],
)
def test_no_raw_parser_exception_leaks(tmp_path: Path, text: str) -> None:
    """Whatever is wrong with the file, the caller sees a ModelError and nothing else."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ModelError) as info:
            load_urdf(_write(tmp_path, text))
    assert isinstance(info.value, ValueError)
    assert str(info.value)


# ----- the Allegro hand: CAD inertias that break the triangle inequality ----------------------------------------
ALLEGRO_FILES = sorted(ALLEGRO.glob("*.urdf"))
ALLEGRO_BAD_LINKS = {"link_3.0", "link_7.0", "link_11.0", "link_15.0"}


def test_allegro_files_exist() -> None:
    assert [path.name for path in ALLEGRO_FILES] == ["allegro_left_hand.urdf", "allegro_right_hand.urdf"]


@pytest.mark.parametrize("path", ALLEGRO_FILES, ids=lambda path: path.stem)
def test_allegro_strict_load_fails(path: Path) -> None:
    with pytest.raises(ModelError, match=r"link 'link_(3|7|11|15)\.0'.*triangle inequality.*strict=False"):
        load_urdf(path)


@pytest.mark.parametrize("path", ALLEGRO_FILES, ids=lambda path: path.stem)
def test_allegro_loads_with_strict_false(path: Path) -> None:
    with pytest.warns(UserWarning, match=r"triangle inequality") as record:
        arm = load_urdf(path, strict=False)
    named = {str(w.message).split("'")[1] for w in record if "triangle inequality" in str(w.message)}
    assert named == ALLEGRO_BAD_LINKS
    assert arm.n == 16
    assert arm.kinds == ["revolute"] * 16
    assert np.count_nonzero(arm.parents == -1) == 4  # four fingers straight from the palm
    _assert_fk_matches_pinocchio(path, arm, count=2)
    _assert_inertias_match_pinocchio(path, arm)


# ----- 1. NaN or inf in the file never reaches the model ----------------------------------------------------------
def test_nan_in_fixed_joint_origin_is_refused(tmp_path: Path) -> None:
    """A NaN in a fixed joint's origin used to be merged into the parent body, which became NaN."""
    text = _robot(
        _link("a"), _link("b"), _link("c"), _joint("j", "a", "b"),
        _joint("f", "b", "c", "fixed", xyz="0 nan 0.1", extra=""),
    )  # fmt: skip
    with pytest.raises(ModelError, match=r"test\.urdf: joint 'f' \(fixed\): <origin> has a NaN or infinite"):
        load_urdf(_write(tmp_path, text))


def test_inf_in_fixed_joint_origin_before_a_moving_joint_names_the_fixed_joint(tmp_path: Path) -> None:
    """The fixed joint's placement is carried into the next moving joint's: the error names where it was written."""
    text = _robot(
        _link("a"), _link("b"), _link("c"), _joint("f", "a", "b", "fixed", rpy="0 inf 0", extra=""),
        _joint("j", "b", "c"),
    )  # fmt: skip
    with pytest.raises(ModelError, match=r"joint 'f' \(fixed\): <origin>"):
        load_urdf(_write(tmp_path, text))


NON_FINITE = {
    "joint-origin-xyz": (_robot(_link("a"), _link("b"), _joint("j", "a", "b", xyz="0 0 nan")), r"joint 'j'.*<origin>"),
    "joint-origin-rpy": (_robot(_link("a"), _link("b"), _joint("j", "a", "b", rpy="inf 0 0")), r"joint 'j'.*<origin>"),
    "axis": (_robot(_link("a"), _link("b"), _joint("j", "a", "b", axis="0 nan 1")), r"joint 'j'.*<axis>.*NaN or inf"),
    "axis-inf": (_robot(_link("a"), _link("b"), _joint("j", "a", "b", axis="0 0 inf")), r"joint 'j'.*<axis>"),
    "mass": (_robot(_link("a"), _link("b", mass="nan"), _joint("j", "a", "b")), r"link 'b'.*<mass> value is nan"),
    "mass-inf": (_robot(_link("a"), _link("b", mass="inf"), _joint("j", "a", "b")), r"link 'b'.*<mass> value is inf"),
    "inertia": (
        _robot(_link("a"), _link("b", inertia=GOOD_INERTIA.replace("'0.03'", "'nan'")), _joint("j", "a", "b")),
        r"link 'b'.*<inertia> holds NaN or infinite",
    ),
    "inertia-behind-fixed": (
        _robot(
            _link("a"),
            _link("b"),
            _link("c", inertia=GOOD_INERTIA.replace("'0.001'", "'-inf'")),
            _joint("j", "a", "b"),
            _joint("f", "b", "c", "fixed", extra=""),
        ),
        r"link 'c'.*<inertia> holds NaN or infinite",
    ),
    "inertial-origin": (
        _robot(_link("a"), _link("b", rpy="0 nan 0"), _joint("j", "a", "b")),
        r"link 'b': <inertial>: <origin> has a NaN",
    ),
    "limit-lower": (
        _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra="<limit lower='nan' upper='1'/>")),
        r"joint 'j': <limit> lower is nan",
    ),
    "limit-upper": (
        _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra="<limit lower='-1' upper='inf'/>")),
        r"joint 'j': <limit> upper is inf",
    ),
    "damping": (
        _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra=LIMIT + "<dynamics damping='inf'/>")),
        r"joint 'j': <dynamics> damping is inf",
    ),
    "friction": (
        _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra=LIMIT + "<dynamics friction='nan'/>")),
        r"joint 'j': <dynamics> friction is nan",
    ),
}


@pytest.mark.parametrize(("text", "match"), list(NON_FINITE.values()), ids=list(NON_FINITE))
def test_nan_or_inf_anywhere_that_reaches_the_model_is_refused(tmp_path: Path, text: str, match: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for strict in (True, False):
            with pytest.raises(ModelError, match=f"test\\.urdf: .*{match}.*finite"):
                load_urdf(_write(tmp_path, text), strict=strict)


# ----- 2. <limit> without lower or upper: 0, as the URDF specification and Pinocchio say -------------------------
@pytest.mark.parametrize(
    ("limit", "expected"),
    [
        ("<limit upper='1.5' effort='1' velocity='1'/>", (0.0, 1.5)),
        ("<limit lower='-0.7' effort='1' velocity='1'/>", (-0.7, 0.0)),
        ("<limit effort='1' velocity='1'/>", (0.0, 0.0)),
    ],
    ids=["no-lower", "no-upper", "neither"],
)
@pytest.mark.parametrize("kind", ["revolute", "prismatic"])
def test_limit_without_upper_or_lower_defaults_to_zero(tmp_path: Path, kind: str, limit: str, expected: tuple) -> None:
    path = _write(tmp_path, _robot(_link("a"), _link("b"), _joint("j", "a", "b", kind, extra=limit)))
    arm = load_urdf(path)
    assert_array_equal(arm.qlim[:, 0], expected)
    model = pin.buildModelFromUrdf(str(path))
    assert_array_equal([model.lowerPositionLimit[0], model.upperPositionLimit[0]], expected)


def test_limit_with_only_a_positive_lower_breaks_lower_le_upper(tmp_path: Path) -> None:
    """upper defaults to 0, so lower='0.5' alone gives lower > upper: refused, not swapped or widened."""
    joint = _joint("j", "a", "b", extra="<limit lower='0.5' effort='1' velocity='1'/>")
    with pytest.raises(ModelError, match=r"'j'.*lower <= upper"):
        load_urdf(_write(tmp_path, _robot(_link("a"), _link("b"), joint)))


def test_robot_element_without_name_is_refused_with_the_reason(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _joint("j", "a", "b")).replace("<robot name='test'>", "<robot>")
    with pytest.raises(ModelError, match=r"<robot> element has no name.*add name="):
        load_urdf(_write(tmp_path, text))


# ----- 3. inertia rounding noise passes, a genuinely indefinite tensor does not --------------------------------------
NOISE_INERTIA = "ixx='0' iyy='0' izz='0' ixy='0' ixz='1.35525e-20' iyz='0'"  # iCub's l_ankle_2


@pytest.mark.parametrize("strict", [True, False])
def test_inertia_rounding_noise_is_not_an_indefinite_tensor(tmp_path: Path, strict: bool) -> None:
    """iCub's l_ankle_2: all zero but ixz = 1.36e-20. The tolerance used to scale with the tensor's own largest
    entry (1.36e-20 itself), so the eigenvalue -1.36e-20 was fatal; a floor of 1e-9 m l^2 lets it pass."""
    text = _robot(
        _link("a"), _link("b", mass=0.2675, xyz="0.008 0 0.0553", rpy="0 0 0", inertia=NOISE_INERTIA),
        _joint("j", "a", "b", axis="1 0 0"),
    )  # fmt: skip
    path = _write(tmp_path, text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arm = load_urdf(path, strict=strict)
    assert_array_equal(arm.links[0].inertial.inertia[0, 2], 1.35525e-20)  # kept as given
    _assert_inertias_match_pinocchio(path, arm)


def test_inertia_tolerance_floor_is_tied_to_mass_and_size() -> None:
    rotation = np.array([[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]])
    # a genuinely indefinite tensor: principal moment -1e-3 kg m^2 on a 1 kg link, centre of mass anywhere
    for com in ([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [3.0, 0.0, 0.0]):
        indefinite = rotation @ np.diag([-1e-3, 0.5, 0.5]) @ rotation.T
        with pytest.raises(ModelError, match=r"link 'l'.*not positive semi-definite.*correct the tensor"):
            ad.Inertial(1.0, com, indefinite, "l", strict=False)
    # the same moment is refused on a 1 g link with only 1e-6 elsewhere: the floor does not hide it
    with pytest.raises(ModelError, match=r"not positive semi-definite"):
        ad.Inertial(1e-3, [0, 0, 0.1], np.diag([-1e-3, 1e-6, 1e-6]), "l")
    # noise far below 1e-9 m l^2 passes, in any orientation, and is kept as given
    noise = rotation @ np.array([[0.0, 0.0, 1e-17], [0.0, 0.0, 0.0], [1e-17, 0.0, 0.0]]) @ rotation.T
    body = ad.Inertial(1.0, [0.0, 0.0, 0.0], noise, "l")
    assert_array_equal(body.inertia, noise)
    # a massless link has no floor beyond its own largest entry
    with pytest.raises(ModelError, match=r"not positive semi-definite"):
        ad.Inertial(0.0, [0.0, 0.0, 0.0], noise, "l")


ICUB = sorted((ROBOTS / "icub_description" / "robots").glob("*.urdf"))


@pytest.mark.parametrize("path", ICUB, ids=lambda path: path.stem)
def test_icub_files_load(path: Path) -> None:
    """Both iCub files were refused (rounding noise on l_ankle_2); they load, as in Pinocchio, strict or not."""
    for strict in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            arm = load_urdf(path, strict=strict)
    assert arm.n == pin.buildModelFromUrdf(str(path)).nv
    _assert_inertias_match_pinocchio(path, arm)
    _assert_fk_matches_pinocchio(path, arm, count=1)


# ----- 4. joints that move no mass: M(q) singular for every q ---------------------------------------------------------
_POINT_MASS = "ixx='0' iyy='0' izz='0' ixy='0' ixz='0' iyz='0'"
SINGULAR_ARMS = {
    # a massless leaf: nothing moves about 'j2'
    "massless-leaf": (
        _robot(_link("a"), _link("b"), "<link name='c'/>", _joint("j1", "a", "b"), _joint("j2", "b", "c")),
        ["j2"],
    ),
    # a point mass on its own joint's axis (behind a fixed joint, so merged first)
    "point-mass-on-axis": (
        _robot(
            _link("a"),
            _link("b"),
            "<link name='c'/>",
            _link("d", xyz="0 0 0.3", rpy="0 0 0", inertia=_POINT_MASS),
            _joint("j1", "a", "b"),
            _joint("j2", "b", "c", xyz="0.2 0 0", rpy="0 0 0", axis="0 0 1"),
            _joint("f", "c", "d", "fixed", xyz="0 0 0.1", rpy="0 0 0", extra=""),
        ),
        ["j2"],
    ),
    # two coincident axes with a massless link between: j3 repeats j2's motion (each diagonal entry is positive)
    "repeated-axis": (
        _robot(
            _link("a"),
            _link("b"),
            "<link name='c'/>",
            _link("d"),
            _joint("j1", "a", "b", axis="1 0 0"),
            _joint("j2", "b", "c", xyz="0 0 0.3", rpy="0 0 0", axis="0 0 1"),
            _joint("j3", "c", "d", xyz="0 0 0.2", rpy="0 0 0", axis="0 0 1"),
        ),
        ["j3"],
    ),
}


@pytest.mark.parametrize(("text", "joints"), list(SINGULAR_ARMS.values()), ids=list(SINGULAR_ARMS))
def test_massless_joints_make_the_inertia_matrix_singular(tmp_path: Path, text: str, joints: list[str]) -> None:
    path = _write(tmp_path, text)
    named = re.escape(f"joints {joints} move no mass")
    with pytest.raises(ModelError, match=f"{named}.*singular.*strict=False"):
        load_urdf(path)
    with pytest.warns(UserWarning, match=named) as record:
        arm = load_urdf(path, strict=False)
    assert sum("move no mass" in str(w.message) for w in record) == 1
    q = np.random.default_rng(3).uniform(-2, 2, (5, arm.n))
    assert np.all(np.abs(np.linalg.eigvalsh(arm.inertia_matrix(q))[:, 0]) < 1e-12)  # singular wherever one looks
    assert np.all(np.isfinite(arm.inverse_dynamics(q, q, q)))


def test_point_mass_off_its_axis_is_not_singular(tmp_path: Path) -> None:
    """The same leaf as above, 5 cm off the axis of 'j2': M(q) is positive definite, no warning."""
    text = _robot(
        _link("a"), _link("b"), "<link name='c'/>", _link("d", xyz="0.05 0 0.3", rpy="0 0 0", inertia=_POINT_MASS),
        _joint("j1", "a", "b"), _joint("j2", "b", "c", xyz="0.2 0 0", rpy="0 0 0", axis="0 0 1"),
        _joint("f", "c", "d", "fixed", xyz="0 0 0.1", rpy="0 0 0", extra=""),
    )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arm = load_urdf(_write(tmp_path, text))
    assert np.all(np.isfinite(arm.forward_dynamics([0.3, -0.2], [0.1, 0.2], [0.5, 0.1])))


def test_configuration_dependent_singularity_is_not_flagged(tmp_path: Path) -> None:
    """A polar arm (Example 3.2-1): a point mass on a prismatic joint is singular only at r = 0, inside its limits."""
    text = _robot(
        _link("a"), "<link name='b'/>", _link("c", xyz="0 0 0", rpy="0 0 0", inertia=_POINT_MASS),
        _joint("theta", "a", "b", xyz="0 0 0", rpy="0 0 0", axis="0 0 1"),
        _joint("r", "b", "c", "prismatic", xyz="0 0 0", rpy="0 0 0", axis="1 0 0",
               extra="<limit lower='-1' upper='1' effort='1' velocity='1'/>"),
    )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arm = load_urdf(_write(tmp_path, text))
    assert np.linalg.det(arm.inertia_matrix([0.4, 0.0])) == pytest.approx(0.0, abs=1e-15)  # singular at r = 0
    assert np.linalg.det(arm.inertia_matrix([0.4, 0.5])) > 0.2


ROMEO = ROBOTS / "romeo_description" / "urdf" / "romeo.urdf"


def test_romeo_massless_fingers_refused_by_default_and_warned_with_strict_false() -> None:
    fingers = {f"{side}{name}" for side in "LR" for name in ["Hand", "Thumb1", "Thumb2", "Thumb3"]}
    fingers |= {f"{side}Finger{i}{j}" for side in "LR" for i in (1, 2, 3) for j in (1, 2, 3) if (i, j) != (1, 1)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its mimic joints
        with pytest.raises(ModelError, match=r"romeo\.urdf: joints \[.*\] move no mass.*strict=False") as info:
            load_urdf(ROMEO)
    assert {name for name in fingers if f"'{name}'" in str(info.value)} == fingers
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        arm = load_urdf(ROMEO, strict=False)
    (message,) = [str(w.message) for w in record if "move no mass" in str(w.message)]
    assert re.match(r"romeo\.urdf: joints \['LHand', 'LFinger12'.* move no mass", message)
    assert all(issubclass(w.category, UserWarning) for w in record)
    assert set(re.findall(r"'(\w+)'", message)) == fingers  # exactly the 24 joints, nothing more
    assert arm.n == 55


LOAD_PROBE = """
import json, sys
from numba.core import event
from numba.core.dispatcher import Dispatcher
compiled = []
class Listener(event.Listener):
    def on_start(self, e):
        compiled.append(e.data["dispatcher"].py_func.__qualname__)
    def on_end(self, e):
        pass
event.register("numba:compile", Listener())
import armdyn
arms = [armdyn.load_urdf(path) for path in sys.argv[1:]]
kernels = [value for name, module in list(sys.modules.items()) if name.startswith("armdyn")
           for value in vars(module).values() if isinstance(value, Dispatcher)]
print(json.dumps({"compiled": compiled, "kernels": len(kernels), "n": [arm.n for arm in arms],
                  "loaded": sum(len(kernel.overloads) for kernel in kernels)}))
"""


def test_loading_an_arm_compiles_and_loads_no_kernel(tmp_path: Path) -> None:
    """A fresh interpreter with an empty kernel cache loads the UR5 and the Panda: Numba compiles nothing and
    no armdyn kernel holds a compiled signature (none was loaded from the cache either), and the cache stays
    empty; the massless-joint check works in NumPy."""
    paths = [str(URDFS["ur5"]), str(URDFS["panda"])]
    environment = {key: value for key, value in os.environ.items() if not key.startswith("NUMBA_CACHE")}
    environment |= {"NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    done = subprocess.run([sys.executable, "-c", LOAD_PROBE, *paths], capture_output=True, text=True,
                          env=environment, timeout=120)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["n"] == [6, 9] and result["kernels"] > 20
    assert result["compiled"] == [] and result["loaded"] == 0
    assert not [path for path in (tmp_path / "cache").rglob("*") if path.suffix in (".nbi", ".nbc")]


@pytest.mark.parametrize("text", [text for text, _ in SINGULAR_ARMS.values()], ids=list(SINGULAR_ARMS))
def test_the_massless_check_factors_the_inertia_matrix_the_kernels_compute(tmp_path: Path, text: str) -> None:
    """The check's M (Lagrange-Euler, NumPy) is the compiled kernels' M (the composite-rigid-body algorithm)."""
    from armdyn.dynamics import lagrange

    with pytest.warns(UserWarning, match="move no mass"):
        arm = load_urdf(_write(tmp_path, text), strict=False)
    q = np.random.default_rng(5).uniform(-2, 2, (4, arm.n))
    assert_allclose(lagrange.inertia_matrix(arm, q), arm.inertia_matrix(q), rtol=0, atol=1e-13)


def test_strict_governs_both_the_triangle_inequality_and_massless_joints(tmp_path: Path) -> None:
    text = _robot(
        _link("a"), _link("b", inertia=TRIANGLE_BREAKER, rpy="0 0 0"), "<link name='c'/>",
        _joint("j1", "a", "b"), _joint("j2", "b", "c"),
    )  # fmt: skip
    path = _write(tmp_path, text)
    with pytest.raises(ModelError, match=r"triangle inequality"):  # the first rule met stops the strict load
        load_urdf(path)
    with pytest.warns(UserWarning) as record:
        load_urdf(path, strict=False)
    messages = " | ".join(str(w.message) for w in record)
    assert "link 'b'" in messages and "triangle inequality" in messages
    assert "joints ['j2'] move no mass" in messages


# ----- locked joints and the tool link (reduced models, as pin.buildReducedModel) ------------------------------
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


def _assert_relative(actual: np.ndarray, expected: np.ndarray, tolerance: float, what: str) -> None:
    """max |actual - expected| <= tolerance max |expected|."""
    error = np.max(np.abs(np.asarray(actual) - expected))
    assert error <= tolerance * np.max(np.abs(expected)), f"{what}: {error:.3e} against {np.max(np.abs(expected)):.3e}"


def _pinocchio_reduced(path: Path, locked: dict[str, float]) -> pin.Model:
    """Pinocchio's model of ``path`` with the ``locked`` joints fixed at their values."""
    full = pin.buildModelFromUrdf(str(path))
    q_lock = pin.neutral(full)
    for name, value in locked.items():
        joint = full.joints[full.getJointId(name)]
        q_lock[joint.idx_q : joint.idx_q + joint.nq] = (np.cos(value), np.sin(value)) if joint.nq == 2 else value
    return pin.buildReducedModel(full, [full.getJointId(name) for name in locked], q_lock)


def _assert_reduced_matches_pinocchio(path: Path, arm: ad.Robot, locked: dict[str, float], tool: str) -> None:
    """M, G, inverse and forward dynamics (no friction: Pinocchio ignores URDF damping), every joint frame and the
    tool pose (Pinocchio's frame of the URDF link ``tool``) at random states, to 1e-12 of the largest entry."""
    model = _pinocchio_reduced(path, locked)
    data = model.createData()
    assert arm.n == model.nv
    assert arm.joint_names == list(model.names)[1:]
    ids = list(range(1, model.njoints))
    bare = arm.without_friction()
    rng = np.random.default_rng(7)
    lower, upper = np.maximum(arm.qlim[0], -3.0), np.minimum(arm.qlim[1], 3.0)
    for _ in range(10):
        q, qd, qdd = rng.uniform(lower, upper), rng.uniform(-2, 2, arm.n), rng.uniform(-3, 3, arm.n)
        tau, config = rng.uniform(-20, 20, arm.n), pin_q(model, ids, q)
        _assert_relative(bare.inertia_matrix(q), pin.crba(model, data, config), 1e-12, "M")
        _assert_relative(bare.gravity_vector(q), pin.computeGeneralizedGravity(model, data, config), 1e-12, "G")
        _assert_relative(bare.inverse_dynamics(q, qd, qdd), pin.rnea(model, data, config, qd, qdd), 1e-12, "tau")
        _assert_relative(bare.forward_dynamics(q, qd, tau), pin.aba(model, data, config, qd, tau), 1e-12, "qdd")
        pin.framesForwardKinematics(model, data, config)
        assert_allclose(arm.link_transforms(q), [data.oMi[i].homogeneous for i in range(1, model.njoints)], atol=1e-12)
        expected = data.oMf[model.getFrameId(tool, pin.BODY)].homogeneous
        assert_allclose(arm.tool_pose(q), expected, rtol=0, atol=1e-12, err_msg=tool)


@pytest.mark.parametrize("tool", ["panda_hand_tcp", "panda_hand"])
def test_panda_reduced_to_seven_joints_equals_pinocchio(tool: str) -> None:
    """The two fingers locked at 2 cm, the tool on the hand (or its TCP): Pinocchio's reduced model, to 1e-12."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the mimic joint is locked: no warning
        arm = load_urdf(URDFS["panda"], tool_link=tool, locked=FINGERS)
    assert arm.n == 7
    assert arm.kinds == ["revolute"] * 7
    assert arm.is_chain
    assert arm.tool_link == 6
    full = _load_quiet(URDFS["panda"])
    assert sum(link.inertial.mass for link in arm.links) == pytest.approx(
        sum(link.inertial.mass for link in full.links)
    )
    assert_array_equal(arm.qlim, full.qlim[:, :7])
    assert_array_equal(arm.viscous_friction, full.viscous_friction[:7])
    _assert_reduced_matches_pinocchio(URDFS["panda"], arm, FINGERS, tool)


def test_panda_locked_in_mid_chain_equals_pinocchio() -> None:
    """Locking an elbow re-attaches the joints below it: their placements pass through the locked joint."""
    locked = {"panda_joint4": -1.2, "panda_finger_joint1": 0.01, "panda_finger_joint2": 0.035}
    arm = load_urdf(URDFS["panda"], tool_link="panda_hand_tcp", locked=locked)
    assert arm.joint_names == [f"panda_joint{i}" for i in (1, 2, 3, 5, 6, 7)]
    _assert_reduced_matches_pinocchio(URDFS["panda"], arm, locked, "panda_hand_tcp")


def test_locked_branches_and_a_merged_tool_link_equal_pinocchio(tmp_path: Path) -> None:
    """A tree: the locked 'j_left' keeps its child joint 'j_left_tip'; the tool link 'sensor' hangs by a fixed joint
    from 'left', so its frame ends in the body of 'j_trunk'; a locked continuous joint takes any value."""
    text = _robot(
        _link("root"), _link("trunk"), _link("left", mass=0.8), _link("right", mass=2.0), _link("left_tip", mass=0.5),
        _link("sensor", mass=0.1), _link("spinner", mass=0.4),
        _joint("j_trunk", "root", "trunk"),
        _joint("j_left", "trunk", "left", axis="1 0 0"),
        _joint("j_right", "trunk", "right", "prismatic", xyz="-0.1 0.2 0", axis="0 0.6 0.8"),
        _joint("j_left_tip", "left", "left_tip", "continuous", axis="0 1 0", extra=""),
        _joint("f_sensor", "left", "sensor", "fixed", xyz="0.03 0.02 0.1", rpy="0.4 -0.1 0.7", extra=""),
        _joint("j_spin", "right", "spinner", "continuous", axis="0 0 1", extra=""),
    )  # fmt: skip
    path = _write(tmp_path, text)
    locked = {"j_left": 0.7, "j_spin": 5.0}
    arm = load_urdf(path, tool_link="sensor", locked=locked)
    assert arm.joint_names == ["j_trunk", "j_left_tip", "j_right"]
    assert_array_equal(arm.parents, [-1, 0, 0])
    assert arm.tool_link == 0
    _assert_reduced_matches_pinocchio(path, arm, locked, "sensor")


def test_loading_locked_is_reducing_the_loaded_arm() -> None:
    """load_urdf(path, tool_link=t, locked=L) is load_urdf(path, tool_link=t).reduced(L): the same packed model,
    tool and limits. By default the tool stays where it was, on the right finger's frame (at 2 cm), now on link 7."""
    direct = load_urdf(URDFS["panda"], tool_link="panda_hand_tcp", locked=FINGERS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the mimic joint
        reduced = load_urdf(URDFS["panda"], tool_link="panda_hand_tcp").reduced(FINGERS)
    assert isinstance(reduced, ad.Robot)
    assert reduced.description == "URDF panda.urdf; locked panda_finger_joint1=0.02, panda_finger_joint2=0.02"
    for name in ("packed", "qlim", "tool", "tool_link", "gravity"):
        assert_array_equal(getattr(reduced, name), getattr(direct, name), err_msg=name)
    full = _load_quiet(URDFS["panda"])
    default = load_urdf(URDFS["panda"], locked=FINGERS)
    assert default.tool_link == 6
    assert_array_equal(default.tool, full.reduced(FINGERS).tool)
    q = np.random.default_rng(2).uniform(-1.0, 1.0, 7)
    assert_allclose(default.tool_pose(q), full.tool_pose([*q, 0.02, 0.02]), rtol=0, atol=1e-15)


def test_reduced_equals_the_full_arm_held_at_the_locked_values() -> None:
    """PUMA 560 with q3 locked: M, G and tau are the full arm's with that row (and column) removed; the reduced arm
    keeps the other joints' motors and friction, its named configurations, and drops the DH table."""
    puma = ad.models.puma560()
    arm = puma.reduced({"q3": 0.5})
    assert arm.joint_names == ["q1", "q2", "q4", "q5", "q6"]
    assert arm.dh is None and puma.dh is not None
    assert_array_equal(arm.qn, np.delete(puma.qn, 2))
    assert_array_equal(arm.reflected_inertia, np.delete(puma.reflected_inertia, 2))
    rng = np.random.default_rng(4)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2, 2, (3, 5))
        full_q, full_qd, full_qdd = (np.insert(x, 2, v) for x, v in ((q, 0.5), (qd, 0.0), (qdd, 0.0)))
        keep = [0, 1, 3, 4, 5]
        assert_allclose(arm.inertia_matrix(q), puma.inertia_matrix(full_q)[np.ix_(keep, keep)], rtol=1e-13, atol=1e-13)
        assert_allclose(arm.gravity_vector(q), puma.gravity_vector(full_q)[keep], rtol=1e-13, atol=1e-12)
        tau = puma.inverse_dynamics(full_q, full_qd, full_qdd)[keep]
        assert_allclose(arm.inverse_dynamics(q, qd, qdd), tau, rtol=1e-13, atol=1e-12)
        assert_allclose(arm.tool_pose(q), puma.tool_pose(full_q), rtol=0, atol=1e-15)


def test_locking_massless_joints_lets_a_strict_load_succeed(tmp_path: Path) -> None:
    """A massless leaf joint makes M singular (refused with strict); locked, it is a fixed joint and the arm loads."""
    text = _robot(_link("a"), _link("b"), "<link name='c'/>", _joint("j1", "a", "b"), _joint("j2", "b", "c"))
    path = _write(tmp_path, text)
    with pytest.raises(ModelError, match=r"joints \['j2'\] move no mass"):
        load_urdf(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        arm = load_urdf(path, locked={"j2": 0.3}, tool_link="c")
    assert arm.joint_names == ["j1"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        full = load_urdf(path, strict=False)
    assert_allclose(arm.tool_pose([0.4]), full.tool_pose([0.4, 0.3]), rtol=0, atol=1e-15)


def test_a_mimic_joint_left_free_still_warns() -> None:
    with pytest.warns(UserWarning, match=r"mimic joints \['panda_finger_joint2'\]"):
        arm = load_urdf(URDFS["panda"], locked={"panda_finger_joint1": 0.01})
    assert arm.n == 8


LOCK_ERRORS = {
    "unknown joint": ({"panda_finger_joint3": 0.0}, None, r"panda\.urdf: .*cannot lock joint 'panda_finger_joint3': "
                      r"the file has no such joint \(its moving joints: \['panda_joint1'"),
    "fixed joint": ({"panda_hand_joint": 0.0}, None, r"lock joint 'panda_hand_joint': it is fixed, already fixed"),
    "above the limit": ({"panda_finger_joint1": 0.05}, None,
                        r"panda\.urdf: robot 'panda': joint 'panda_finger_joint1' cannot be locked at 0\.05 m: "
                        r"outside its limits \[0, 0\.04\]"),
    "below the limit": ({"panda_joint4": 0.0}, None, r"joint 'panda_joint4' cannot be locked at 0 rad: outside its "
                        r"limits \[-3\.0718, -0\.0698\]"),
    "NaN": ({"panda_joint1": float("nan")}, None, r"'panda_joint1' must be locked at a finite real number, got nan"),
    "infinite": ({"panda_joint1": np.inf}, None, r"joint 'panda_joint1' must be locked at a finite real number"),
    "a string": ({"panda_joint1": "0.1"}, None, r"'panda_joint1' must be locked at a finite real number, got '0.1'"),
    "complex": ({"panda_joint1": 0.1 + 0j}, None, r"finite real number"),
    "a bool": ({"panda_joint1": True}, None, r"finite real number"),
    "an array": ({"panda_joint1": np.array([0.1])}, None, r"finite real number"),
    "None": ({"panda_joint1": None}, None, r"finite real number, got None"),
    "not a mapping": (["panda_finger_joint1"], None, r"locked must be a mapping of joint name to value"),
    "every joint": ({f"panda_joint{i}": 0.0 for i in range(1, 8)} | {"panda_joint4": -1.0} | FINGERS, None,
                    r"locking every joint \(.*\) leaves no joint to move"),
    "tool link unknown": (None, "panda_gripper", r"tool_link 'panda_gripper' is not a link of the file \(its links: "
                          r"\['panda_link0'"),
    "tool link is a joint": (None, "panda_joint1", r"tool_link 'panda_joint1' is not a link of the file"),
    "tool link not a name": (None, 3, r"tool_link 3 is not a link of the file"),
    "tool link is the root": (None, "panda_link0", r"tool_link 'panda_link0' is fixed to the root link 'panda_link0' "
                              r"\(no moving joint between them\)"),
}  # fmt: skip


@pytest.mark.parametrize(("locked", "tool", "match"), list(LOCK_ERRORS.values()), ids=list(LOCK_ERRORS))
def test_locked_joints_and_tool_link_errors(locked: object, tool: object, match: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the mimic joint, when left free
        with pytest.raises(ModelError, match=match):
            load_urdf(URDFS["panda"], locked=locked, tool_link=tool)


def test_locking_the_only_joints_above_the_tool_welds_it_to_the_base(tmp_path: Path) -> None:
    text = _robot(_link("a"), _link("b"), _link("c"), _joint("j1", "a", "b"), _joint("j2", "a", "c"))
    path = _write(tmp_path, text)
    with pytest.raises(ModelError, match=r"test\.urdf: robot 'test': locking \['j1'\] welds the tool \(on link 'j1'\) "
                       r"to the base: no moving joint is left between them"):  # fmt: skip
        load_urdf(path, locked={"j1": 0.1}, tool_link="b")
    assert load_urdf(path, locked={"j1": 0.1}, tool_link="c").joint_names == ["j2"]


def test_reduced_errors_name_the_joint_and_the_rule() -> None:
    puma = ad.models.puma560()
    with pytest.raises(ModelError, match=r"robot 'puma560': cannot lock joint 'q7': no such joint \(the joints: "):
        puma.reduced({"q7": 0.0})
    with pytest.raises(ModelError, match=r"joint 'q2' cannot be locked at 4 rad: outside its limits \[-0\.785398, "):
        puma.reduced({"q2": 4.0})
    with pytest.raises(ModelError, match=r"locked must be a mapping"):
        puma.reduced([("q2", 0.1)])
    symbolic = ad.models.two_link_planar(symbolic=True)
    assert symbolic.reduced({"theta1": 0.3}).n == 1  # SymPy parameters pass into the placements
    with pytest.raises(ModelError, match=r"moves the tool onto link 'theta1' through symbolic \(SymPy\) parameters"):
        symbolic.reduced({"theta2": 0.3})


# ----- 5. the file is read with lxml alone: no mesh or scene-graph library, the URDF specification's defaults -------
@pytest.mark.slow
def test_loading_a_urdf_imports_no_mesh_library() -> None:
    """load_urdf reads the XML itself: yourdfpy (and trimesh, which it imports, 0.75 s of start-up) stay out."""
    code = (
        "import sys, armdyn; armdyn.load_urdf(sys.argv[1]); "
        "print(sorted(name for name in ('yourdfpy', 'trimesh') if name in sys.modules))"
    )
    run = subprocess.run(
        [sys.executable, "-c", code, str(URDFS["ur5"])], capture_output=True, text=True, timeout=600, check=False
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip().splitlines()[-1] == "[]", run.stdout


@pytest.mark.parametrize("axis", ["", "<axis/>"], ids=["no-axis-element", "axis-without-xyz"])
@pytest.mark.parametrize("kind", ["revolute", "continuous", "prismatic"])
def test_omitted_axis_is_x_as_the_specification_says(tmp_path: Path, kind: str, axis: str) -> None:
    joint = _joint("j", "a", "b", kind).replace("<axis xyz='0 0 1'/>", axis)
    path = _write(tmp_path, _robot(_link("a"), _link("b"), joint))
    arm = load_urdf(path)
    assert_array_equal(arm.links[0].joint.axis, [1.0, 0.0, 0.0])
    if axis:  # urdfdom, and so Pinocchio, reads an <axis> without xyz as 0 0 0: armdyn keeps the default, 1 0 0
        return
    model = pin.buildModelFromUrdf(str(path))
    assert model.joints[1].shortname() in ("JointModelRX", "JointModelPX", "JointModelRUBX")
    _assert_fk_matches_pinocchio(path, arm)


RPY = ["0 0 0", "0.3 0 0", "0 -0.4 0", "0 0 2.9", "0.3 0.1 -0.2", "-3.0 1.5707963267948966 0.7", "6.5 -2.2 -4.1"]


def test_rpy_joint_placements_match_pinocchio(tmp_path: Path) -> None:
    """rpy is roll, pitch, yaw about the fixed axes: R = Rz(yaw) Ry(pitch) Rx(roll); a fixed joint's is carried into
    the next moving joint's placement, as Pinocchio merges it."""
    names = [f"l{i}" for i in range(len(RPY) + 2)]
    joints = [
        _joint(f"j{i}", names[i], names[i + 1], xyz=f"0.1 {-0.05 * i} 0.2", rpy=rpy, axis="0 1 0")
        for i, rpy in enumerate(RPY)
    ]
    joints.append(_joint("f", names[-2], names[-1], "fixed", rpy="0.5 -0.6 0.7", extra=""))
    joints.append(_joint("last", names[-1], "tip", rpy="-0.2 0.9 1.3"))
    path = _write(tmp_path, _robot(*(_link(name) for name in [*names, "tip"]), *joints))
    arm = load_urdf(path)
    model, ids = _pinocchio(path, arm)
    for link, joint_id in zip(arm.links, ids, strict=True):
        assert_allclose(link.joint.placement, model.jointPlacements[joint_id].homogeneous, rtol=0, atol=1e-14)
    roll, pitch, yaw = 0.3, 0.1, -0.2  # j4, written out: a rotation about x, then y, then z, all fixed axes
    c, s = np.cos, np.sin
    rx = np.array([[1, 0, 0], [0, c(roll), -s(roll)], [0, s(roll), c(roll)]])
    ry = np.array([[c(pitch), 0, s(pitch)], [0, 1, 0], [-s(pitch), 0, c(pitch)]])
    rz = np.array([[c(yaw), -s(yaw), 0], [s(yaw), c(yaw), 0], [0, 0, 1]])
    assert_allclose(arm.links[4].joint.placement[:3, :3], rz @ ry @ rx, rtol=0, atol=1e-15)
    _assert_fk_matches_pinocchio(path, arm)


def test_origin_without_rpy_or_xyz_and_inertial_without_origin(tmp_path: Path) -> None:
    """Each of xyz and rpy is 0 0 0 when absent, an absent <origin> the identity, in joints and inertials alike."""
    joint = _joint("j", "a", "b").replace("<origin xyz='0.1 0.05 0.2' rpy='0.3 0.1 -0.2'/>", "<origin xyz='0 0 1'/>")
    joint2 = _joint("k", "b", "c").replace("<origin xyz='0.1 0.05 0.2' rpy='0.3 0.1 -0.2'/>", "<origin rpy='0 0 1'/>")
    joint3 = _joint("m", "c", "d").replace("<origin xyz='0.1 0.05 0.2' rpy='0.3 0.1 -0.2'/>", "")
    link = _link("d").replace("<origin xyz='0.01 0.02 0.03' rpy='0.1 -0.2 0.3'/>", "")
    path = _write(tmp_path, _robot(_link("a"), _link("b"), _link("c"), link, joint, joint2, joint3))
    arm = load_urdf(path)
    assert_array_equal(arm.links[0].joint.placement, [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]])
    assert_array_equal(arm.links[1].joint.placement[:3, 3], [0.0, 0.0, 0.0])
    assert_array_equal(arm.links[2].joint.placement, np.eye(4))
    assert_array_equal(arm.links[2].inertial.com, [0.0, 0.0, 0.0])
    _assert_fk_matches_pinocchio(path, arm)
    _assert_inertias_match_pinocchio(path, arm)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            _robot(_link("a"), _link("b", mass="heavy"), _joint("j", "a", "b")),
            r"test\.urdf: link 'b': <inertial><mass> value is 'heavy', not a number",
        ),
        (
            _robot(_link("a"), _link("b", inertia=GOOD_INERTIA.replace("'0.03'", "'x'")), _joint("j", "a", "b")),
            r"test\.urdf: link 'b': <inertial><inertia> iyy is 'x', not a number",
        ),
        (
            _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra="<limit lower='-1' upper='one'/>")),
            r"test\.urdf: joint 'j': <limit> upper is 'one', not a number",
        ),
        (
            _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra="<limit effort='ten' velocity='1'/>")),
            r"test\.urdf: joint 'j': <limit> effort is 'ten', not a number",
        ),
        (
            _robot(_link("a"), _link("b"), _joint("j", "a", "b", extra=LIMIT + "<mimic joint='x' multiplier='2x'/>")),
            r"test\.urdf: joint 'j': <mimic> multiplier is '2x', not a number",
        ),
        (
            _robot(_link("a"), _link("b"), "<joint name='j' type='revolute'><child link='b'/></joint>"),
            r"test\.urdf: not a valid URDF: joint 'j' has no <parent> element",
        ),
        (
            _robot(_link("a"), _link("b"), "<joint name='j' type='revolute'><parent link='a'/></joint>"),
            r"test\.urdf: not a valid URDF: joint 'j' has no <child> element",
        ),
        (
            _robot(_link("a"), "<link/>", _joint("j", "a", "b")),
            r"test\.urdf: not a valid URDF: the <link> element on line 4 has no name",
        ),
        (
            _robot(_link("a"), _link("b"), "<joint type='revolute'><parent link='a'/><child link='b'/></joint>"),
            r"test\.urdf: not a valid URDF: the <joint> element on line 5 has no name",
        ),
    ],
    ids=["mass", "inertia", "limit", "effort", "mimic", "no-parent", "no-child", "unnamed-link", "unnamed-joint"],
)
def test_what_is_not_a_urdf_is_named(tmp_path: Path, text: str, match: str) -> None:
    with pytest.raises(ModelError, match=match):
        load_urdf(_write(tmp_path, text))


def test_visual_and_collision_elements_are_not_read(tmp_path: Path) -> None:
    """Meshes and shapes never reach the model: a missing mesh or a malformed shape does not stop the load."""
    extra = (
        "<visual><geometry><mesh filename='package://nowhere/none.stl'/></geometry><material name='m'>"
        "<color rgba='red'/></material></visual><collision><geometry><box size='a b c'/></geometry></collision>"
    )
    path = _write(tmp_path, _robot(_link("a"), _link("b", extra=extra), _joint("j", "a", "b")))
    assert load_urdf(path).n == 1


def test_an_inertia_missing_a_moment_is_refused_not_invented(tmp_path: Path) -> None:
    """The specification requires all six <inertia> attributes; a missing moment is not taken as 1."""
    xml = (
        "<robot name='r'><link name='base'/><link name='l1'><inertial><mass value='1'/>"
        "<inertia ixx='0.02' iyy='0.03' ixy='0' ixz='0' iyz='0'/></inertial></link>"
        "<joint name='j1' type='revolute'><parent link='base'/><child link='l1'/><axis xyz='0 0 1'/>"
        "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>"
    )
    path = tmp_path / "missing.urdf"
    path.write_text(xml)
    with pytest.raises(ModelError, match=r"link 'l1'.*<inertial><inertia> lacks izz; the URDF specification requires"):
        ad.load_urdf(path)
