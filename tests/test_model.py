"""The arm model: inertials, joints, links, robots, the built-in arms, and every error path."""

from __future__ import annotations

import numpy as np
import pytest
import sympy
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn import ModelError
from armdyn.model.joint import dh_joint


# ----- Inertial -------------------------------------------------------------------------
def point_masses_body(masses: np.ndarray, points: np.ndarray) -> ad.Inertial:
    """The Inertial of a cloud of point masses, from first principles."""
    mass = masses.sum()
    com = masses @ points / mass
    d = points - com
    inertia = sum(m * ((r @ r) * np.eye(3) - np.outer(r, r)) for m, r in zip(masses, d, strict=True))
    return ad.Inertial(mass, com, inertia, "cloud")


def test_pseudo_inertia_is_the_second_moment_of_mass() -> None:
    rng = np.random.default_rng(1)
    masses, points = rng.uniform(0.1, 2, 7), rng.normal(size=(7, 3))
    body = point_masses_body(masses, points)
    homogeneous = np.hstack([points, np.ones((7, 1))])
    expected = sum(m * np.outer(r, r) for m, r in zip(masses, homogeneous, strict=True))  # (3.2.20)
    assert_allclose(body.pseudo_inertia(), expected, atol=1e-12)


def test_pseudo_inertia_layout_matches_the_book() -> None:
    """(3.2.27): diagonal (-Ixx+Iyy+Izz)/2 ..., products as they are, first moments m*c."""
    body = ad.Inertial(2.0, [0.1, -0.2, 0.3], [[1.0, 0.1, 0.05], [0.1, 1.2, -0.02], [0.05, -0.02, 0.9]], "b")
    inertia = body.inertia_about_origin()
    ixx, iyy, izz = np.diag(inertia)
    pseudo = body.pseudo_inertia()
    assert_allclose(np.diag(pseudo)[:3], [(-ixx + iyy + izz) / 2, (ixx - iyy + izz) / 2, (ixx + iyy - izz) / 2])
    assert_allclose(pseudo[0, 1], -inertia[0, 1])  # the book's Ixy is the product integral of x y dm
    assert_allclose(pseudo[:3, 3], 2.0 * np.array([0.1, -0.2, 0.3]))
    assert pseudo[3, 3] == 2.0


def test_inertia_about_origin_is_the_parallel_axis_theorem() -> None:
    body = ad.Inertial(3.0, [0.0, 0.0, 2.0], np.diag([1.0, 1.0, 0.5]), "b")
    assert_allclose(body.inertia_about_origin(), np.diag([13.0, 13.0, 0.5]))


def test_sum_of_bodies_matches_the_point_cloud() -> None:
    rng = np.random.default_rng(2)
    masses, points = rng.uniform(0.1, 2, 8), rng.normal(size=(8, 3))
    whole = point_masses_body(masses, points)
    parts = point_masses_body(masses[:4], points[:4]) + point_masses_body(masses[4:], points[4:])
    assert_allclose(parts.mass, whole.mass)
    assert_allclose(parts.com, whole.com)
    assert_allclose(parts.inertia, whole.inertia, atol=1e-12)


@pytest.mark.parametrize(
    ("mass", "com", "inertia", "match"),
    [
        (-1.0, [0, 0, 0], np.eye(3), "mass must be non-negative"),
        (np.nan, [0, 0, 0], np.eye(3), "mass must be finite"),
        (1.0, [0, np.inf, 0], np.eye(3), "centre of mass must be finite"),
        (1.0, [0, 0, 0], [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "not symmetric"),
        (1.0, [0, 0, 0], np.diag([1.0, 1.0, -0.1]), "not positive semi-definite"),
        (1.0, [0, 0, 0], np.diag([1.0, 1.0, 3.0]), "triangle inequality.*strict=False"),
        (1.0, [0, 0], np.eye(3), "centre of mass"),
        (1.0, [0, 0, 0], np.eye(2), "inertia must be"),
    ],
)
def test_inertial_rejects_impossible_bodies(mass: float, com: list, inertia: object, match: str) -> None:
    with pytest.raises(ModelError, match=f"link 'forearm'.*{match}|{match}"):
        ad.Inertial(mass, com, inertia, "forearm")


def test_inertial_errors_name_the_link() -> None:
    with pytest.raises(ModelError, match="link 'forearm'"):
        ad.Inertial(-1.0, name="forearm")


def test_triangle_inequality_can_be_waived_with_a_warning() -> None:
    with pytest.warns(UserWarning, match="link 'hand'.*triangle inequality"):
        body = ad.Inertial(1.0, [0, 0, 0], np.diag([1.0, 1.0, 3.0]), "hand", strict=False)
    assert_allclose(np.diag(body.inertia), [1.0, 1.0, 3.0])  # used as given, not corrected


def test_inertia_vector_orders() -> None:
    six = ad.Inertial(1.0, inertia=[1.0, 2.0, 2.5, 0.1, 0.2, 0.3], name="b").inertia
    assert_allclose(six, [[1.0, 0.1, 0.3], [0.1, 2.0, 0.2], [0.3, 0.2, 2.5]])
    assert_allclose(ad.Inertial(1.0, inertia=[1.0, 2.0, 2.5], name="b").inertia, np.diag([1.0, 2.0, 2.5]))


def test_inertial_is_immutable() -> None:
    body = ad.Inertial(1.0, [0, 0, 1], np.eye(3), "b")
    with pytest.raises(ValueError, match="read-only"):
        body.com[0] = 5.0


# ----- Joint and Link ---------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"kind": "spherical"}, "unknown joint kind"),
        ({"axis": [0, 0, 2.0]}, "axis must be a unit 3-vector"),
        ({"axis": [0, 1]}, "axis must be a unit 3-vector"),
        ({"placement": np.eye(3)}, "placement must be a 4x4"),
        ({"placement": np.diag([2.0, 1, 1, 1])}, "not a rigid transform"),
        ({"frame_offset": np.full((4, 4), np.nan)}, "frame_offset must be finite"),
    ],
)
def test_joint_rejects_bad_geometry(kwargs: dict, match: str) -> None:
    with pytest.raises(ModelError, match=f"joint 'elbow'.*{match}"):
        ad.Joint(name="elbow", **kwargs)


def body(name: str = "l") -> ad.Inertial:
    return ad.Inertial(1.0, [0.1, 0, 0], np.eye(3) * 0.01, name)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"viscous": -0.1}, "viscous friction must be finite and >= 0"),
        ({"coulomb": (-0.1, -0.1)}, "Tc\\+ >= 0"),
        ({"coulomb": (0.1, 0.1)}, "Tc- <= 0"),
        ({"coulomb": (0.1,)}, "two finite numbers"),
        ({"motor_inertia": -1e-4}, "motor inertia Jm"),
        ({"gear_ratio": 0.0}, "gear ratio G must be finite and non-zero"),
        ({"limits": (1.0, -1.0)}, "lower <= upper"),
    ],
)
def test_link_rejects_bad_drives(kwargs: dict, match: str) -> None:
    with pytest.raises(ModelError, match=f"link 'wrist'.*{match}"):
        ad.Link("wrist", ad.Joint(), body(), **kwargs)


# ----- Robot ------------------------------------------------------------------------------
def two_links(**robot_options: object) -> ad.Robot:
    return ad.Robot([ad.Link("a", ad.Joint(), body()), ad.Link("b", ad.Joint(), body(), parent=0)], **robot_options)


def test_robot_structure() -> None:
    arm = two_links()
    assert arm.n == 2 and arm.joint_names == ["a", "b"] and arm.is_chain
    assert_allclose(arm.gravity, [0, 0, -9.81])
    assert arm.ancestors.tolist() == [[True, False], [True, True]]


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: ad.Robot([]), "at least one joint"),
        (lambda: ad.Robot([ad.Link("a", ad.Joint(), body(), parent=0)]), "link 'a': parent index 0"),
        (lambda: ad.Robot([ad.Link("a", ad.Joint(), body()), ad.Link("a", ad.Joint(), body())]), "link 'a'.*unique"),
        (lambda: two_links(gravity=[0, -9.8]), "gravity must be a 3-vector"),
        (lambda: two_links(gravity=[0, np.nan, 0]), "gravity must be finite"),
        (lambda: two_links(configurations={"home": [0.0]}), "configuration 'home' must have 2 values"),
        (lambda: two_links(tool_link=5), "tool_link 5"),
        (lambda: two_links(base=np.eye(3)), "base must be a finite 4x4"),
        (lambda: ad.Robot.from_dh([{"a": 1, "mass": 1, "bogus": 2}]), "unknown DH row keys"),
        (lambda: ad.Robot.from_dh([{"a": 1}], convention="craig"), "'standard' or 'modified'"),
        (lambda: ad.Robot.from_dh([{"a": 1, "mass": -2}]), "link 'joint1': mass must be non-negative"),
    ],
)
def test_robot_rejects_bad_models(build: object, match: str) -> None:
    with pytest.raises(ModelError, match=match):
        build()


def test_robot_is_immutable() -> None:
    arm = two_links()
    with pytest.raises(ValueError, match="read-only"):
        arm.gravity[2] = 0.0
    with pytest.raises(AttributeError):
        arm.links = ()


def test_with_payload_adds_to_the_tool_link() -> None:
    arm = ad.models.puma560()
    loaded = arm.with_payload(2.0, [0, 0, 0.1]).with_payload(1.0, [0, 0, 0.1])
    last, new_last = arm.links[-1].inertial, loaded.links[-1].inertial
    assert_allclose(new_last.mass, last.mass + 3.0)
    assert_allclose(new_last.first_moment, last.first_moment + 3.0 * np.array([0, 0, 0.1]))
    assert arm.links[-1].inertial.mass == 0.09  # the original is untouched
    with pytest.raises(ModelError, match="mass must be non-negative"):
        arm.with_payload(-1.0)


def test_friction_and_motors_are_referred_to_the_joint() -> None:
    arm = ad.models.puma560()
    G = np.array([-62.6111, 107.815, -53.7063, 76.0364, 71.923, 76.686])
    assert_allclose(arm.reflected_inertia, G**2 * np.array([200e-6] * 3 + [33e-6] * 3))
    assert_allclose(arm.viscous_friction[0], G[0] ** 2 * 1.48e-3)
    assert_allclose(arm.coulomb_friction[0], np.abs(G[0]) * np.array([0.395, -0.435]))
    bare = arm.without_friction()
    assert np.all(bare.viscous_friction == 0) and np.all(bare.coulomb_friction == 0)
    assert_allclose(bare.reflected_inertia, arm.reflected_inertia)
    no_motors = arm.without_motors()
    assert np.all(no_motors.reflected_inertia == 0)
    assert_allclose(no_motors.viscous_friction, arm.viscous_friction)  # friction stays, at the joint side
    assert_allclose(no_motors.coulomb_friction, arm.coulomb_friction)


def test_named_configurations() -> None:
    puma = ad.models.puma560()
    assert_allclose(puma.qn, [0, np.pi / 4, -np.pi, 0, np.pi / 4, 0])
    assert_allclose(puma.configuration("qr"), [0, np.pi / 2, -np.pi / 2, 0, 0, 0])
    assert set(puma.configurations) == {"qz", "qr", "qs", "qn"}
    with pytest.raises(ModelError, match="no configuration 'qq'"):
        puma.configuration("qq")
    with pytest.raises(AttributeError):
        _ = puma.qq


# ----- Denavit-Hartenberg -----------------------------------------------------------------
def test_standard_dh_joint_reproduces_the_dh_matrix() -> None:
    """A = Rz(theta) Tz(d) Tx(a) Rx(alpha), Appendix A."""
    a, alpha, d, offset, q = 0.3, 0.7, 0.2, 0.1, 0.9
    joint = dh_joint("R", a, alpha, d, offset)
    th = q + offset
    expected = np.array(
        [
            [np.cos(th), -np.sin(th) * np.cos(alpha), np.sin(th) * np.sin(alpha), a * np.cos(th)],
            [np.sin(th), np.cos(th) * np.cos(alpha), -np.cos(th) * np.sin(alpha), a * np.sin(th)],
            [0, np.sin(alpha), np.cos(alpha), d],
            [0, 0, 0, 1],
        ]
    )
    arm = ad.Robot([ad.Link("j", joint, body())])
    assert_allclose(arm.link_transforms([q])[0], expected, atol=1e-15)


def test_modified_dh_joint_reproduces_craigs_matrix() -> None:
    """A = Rx(alpha) Tx(a) Rz(theta) Tz(d) (Craig 1986)."""
    a, alpha, d, q = 0.3, 0.7, 0.2, 0.9
    joint = dh_joint("R", a, alpha, d, 0.0, "modified")
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(q), np.sin(q)
    expected = np.array(
        [[ct, -st, 0, a], [st * ca, ct * ca, -sa, -sa * d], [st * sa, ct * sa, ca, ca * d], [0, 0, 0, 1]]
    )
    arm = ad.Robot([ad.Link("j", joint, body())])
    assert_allclose(arm.link_transforms([q])[0], expected, atol=1e-15)


def test_prismatic_dh_joint_moves_along_z() -> None:
    arm = ad.Robot.from_dh([{"kind": "P", "theta": 0.3, "a": 0.1, "d": 0.05, "mass": 1}])
    T = arm.link_transforms([0.4])[0]
    assert_allclose(T[2, 3], 0.45)
    assert_allclose(T[:2, 3], 0.1 * np.array([np.cos(0.3), np.sin(0.3)]))


# ----- the built-in arms ------------------------------------------------------------------
def test_catalog_lists_and_loads_every_arm() -> None:
    assert set(ad.models.names()) >= {"two_link_planar", "polar_rp", "cylindrical", "puma560", "stanford", "scara"}
    for name in ad.models.names():
        arm = ad.models.load(name)
        assert arm.name == name and arm.has_dynamics
    with pytest.raises(ModelError, match="no built-in arm named 'r2d2'"):
        ad.models.load("r2d2")


def test_puma560_as_published() -> None:
    puma = ad.models.puma560()
    assert puma.n == 6 and puma.kinds == ["revolute"] * 6 and puma.dh["convention"] == "standard"
    assert [link.inertial.mass for link in puma.links] == [0, 17.4, 4.8, 0.82, 0.34, 0.09]
    assert_allclose(puma.links[1].inertial.com, [-0.3638, 0.006, 0.2275])
    assert_allclose(np.rad2deg(puma.qlim[1]), [160, 225, 45, 170, 100, 266])


def test_stanford_has_its_prismatic_third_joint() -> None:
    arm = ad.models.stanford()
    assert arm.kinds[2] == "prismatic" and arm.n == 6
    assert_allclose(arm.reflected_inertia, [0.953, 2.193, 0.782, 0.106, 0.097, 0.020])


def test_scara_is_rrpr() -> None:
    assert ad.models.scara().kinds == ["revolute", "revolute", "prismatic", "revolute"]


@pytest.mark.parametrize(
    ("factory", "symbols"),
    [
        (ad.models.two_link_planar, {"m1", "m2", "a1", "a2", "g"}),
        (ad.models.polar_rp, {"m", "g"}),
        (ad.models.cylindrical, {"J", "m1", "m2", "g"}),
    ],
)
def test_book_examples_accept_symbols(factory: object, symbols: set) -> None:
    arm = factory(symbolic=True)
    assert arm.is_symbolic
    found = set()
    for link in arm.links:
        found |= {str(s) for s in sympy.sympify(link.inertial.mass).free_symbols}
        found |= {str(s) for item in link.joint.frame_offset.ravel() for s in sympy.sympify(item).free_symbols}
        found |= {str(s) for item in link.inertial.inertia.ravel() for s in sympy.sympify(item).free_symbols}
    found |= {str(s) for item in arm.gravity for s in sympy.sympify(item).free_symbols}
    assert found == symbols


def test_puma560_configurations_lie_within_its_limits_as_the_toolbox_gives_them() -> None:
    """Issue: qn (q3 = pi) lay outside q3's limit of +-2.356, and joints 2-4 differed from the Toolbox."""
    puma = ad.models.puma560()
    deg = np.pi / 180
    toolbox = np.array([[-160, 160], [-45, 225], [-225, 45], [-110, 170], [-100, 100], [-266, 266]]) * deg
    np.testing.assert_allclose(puma.qlim.T, toolbox)
    np.testing.assert_allclose(puma.qn, [0, np.pi / 4, -np.pi, 0, np.pi / 4, 0])
    for name, q in puma.configurations.items():
        assert np.all(puma.qlim[0] <= q) and np.all(q <= puma.qlim[1]), name


def test_an_inertial_from_its_ten_parameters_is_itself() -> None:
    for link in ad.models.puma560().links + ad.models.panda_gaz2019().links:
        body = link.inertial
        back = ad.Inertial.from_parameters(body.parameters(), body.name, strict=False)
        assert back.mass == pytest.approx(body.mass, abs=1e-15)
        np.testing.assert_allclose(back.com, body.com if body.mass > 0 else np.zeros(3), atol=1e-14)
        np.testing.assert_allclose(back.inertia, body.inertia, atol=1e-14)
    with pytest.raises(ad.ModelError, match="phi10 must be 10 numbers"):
        ad.Inertial.from_parameters(np.zeros(9))
