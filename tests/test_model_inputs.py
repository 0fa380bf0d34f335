"""The model constructors refuse bad input with an error naming the argument and the link.

Each case is a representative of a class the fuzzing layer (tests/test_fuzz.py) found: complex
values, huge Python ints, 1e300 and infinities, junk objects, wrong shapes, non-numeric dtypes,
NaN, and non-integer parent indices. The message must name the argument and, where there is
one, the link or joint; RuntimeWarning and ComplexWarning are errors here (pyproject.toml).
SymPy parameters stay accepted: the book's examples are built and derived symbolically.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
import sympy
from numpy.testing import assert_allclose

import armdyn as ad
from armdyn import ModelError

JOINT = ad.Joint()
BODY = ad.Inertial(1.0, [0.1, 0.0, 0.0], [0.01, 0.02, 0.02], "body")
DATES = np.full(3, "2020-01-01", dtype="datetime64[D]")


def link(**options: object) -> ad.Link:
    """A valid link 'wrist' with some arguments changed."""
    return ad.Link(**({"name": "wrist", "joint": JOINT, "inertial": BODY} | options))


def dh(**row: object) -> ad.Robot:
    """A two-joint arm from DH rows, the first row changed."""
    return ad.Robot.from_dh([{"a": 1.0, "mass": 1.0} | row, {"a": 0.5, "mass": 0.5}])


def planar(**options: object) -> ad.Robot:
    """The two-link planar arm rebuilt from its own links, with some constructor options."""
    return ad.Robot(list(ad.models.two_link_planar().links), **options)


def refused(build: Callable[[], object], match: str, error: type[Exception] = ModelError) -> None:
    with pytest.raises(error, match=match):
        build()


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"mass": 1 + 0j}, "link 'forearm': mass must be real"),
        ({"mass": 10**400}, "link 'forearm': mass must be a real number"),
        ({"mass": 1e300}, "link 'forearm': mass holds values of 1e\\+15 or more"),
        ({"mass": None}, "link 'forearm': mass must be a real number, got None"),
        ({"mass": [1.0]}, "link 'forearm': mass must be a number, got shape \\(1,\\)"),
        ({"mass": {"m": 1.0}}, "link 'forearm': mass must be"),
        ({"com": DATES}, "link 'forearm': centre of mass must be numbers"),
        ({"com": np.full(3, "x")}, "link 'forearm': centre of mass must be numbers"),
        ({"com": [0.0, 0.0, 1e300]}, "link 'forearm': centre of mass holds values"),
        ({"inertia": [0.01 + 1j, 0.02, 0.015]}, "link 'forearm': inertia must be real"),
        ({"inertia": [[0.01, 0], [0, 0.02, 0], [0, 0, 0.015]]}, "link 'forearm': inertia must be numbers"),
        ({"inertia": ["a", "b", "c"]}, "link 'forearm': inertia must be numbers"),
        ({"inertia": 0.01}, "link 'forearm': an inertia must be 3 moments"),
    ],
)
def test_inertial_names_the_argument_and_link(options: dict, match: str) -> None:
    refused(lambda: ad.Inertial(**({"mass": 1.0, "name": "forearm"} | options)), match)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"placement": np.eye(4, dtype=complex)}, "joint 'elbow': placement must be real"),
        ({"placement": np.full((4, 4), "x")}, "joint 'elbow': placement must be numbers"),
        ({"frame_offset": "abc"}, "joint 'elbow': frame_offset must be numbers"),
        ({"frame_offset": None}, "joint 'elbow': frame_offset must be numbers"),
        ({"axis": ["0", "0", "x"]}, "joint 'elbow': axis must be numbers"),
        ({"axis": ...}, "joint 'elbow': axis must be numbers"),
        ({"kind": 7}, "joint 'elbow': joint kind must be 'revolute' or 'prismatic', got 7"),
    ],
)
def test_joint_names_the_argument_and_joint(options: dict, match: str) -> None:
    refused(lambda: ad.Joint(**({"name": "elbow"} | options)), match)


def test_a_numeric_object_array_is_a_pose() -> None:
    """An object array of plain numbers (as a SymPy computation can leave) is taken as numbers."""
    joint = ad.Joint(placement=np.eye(4).astype(object))
    assert joint.placement.dtype == float


@pytest.mark.parametrize(
    ("options", "match", "error"),
    [
        ({"joint": None}, "link 'wrist': joint must be a Joint, got None", ModelError),
        ({"inertial": ad.models.two_link_planar()}, "link 'wrist': inertial must be an Inertial", ModelError),
        ({"parent": 0.5}, "link 'wrist': parent must be an integer, got 0.5", TypeError),
        ({"parent": np.nan}, "link 'wrist': parent must be an integer", TypeError),
        ({"parent": "base"}, "link 'wrist': parent must be an integer, got 'base'", TypeError),
        ({"parent": -2}, "link 'wrist': parent must be at least -1", ModelError),
        ({"viscous": 1 + 0j}, "link 'wrist': viscous friction B must be real", ModelError),
        ({"viscous": 10**400}, "link 'wrist': viscous friction B must be a real number", ModelError),
        ({"motor_inertia": None}, "link 'wrist': motor inertia Jm must be a real number", ModelError),
        ({"gear_ratio": 1e300}, "link 'wrist': gear ratio G holds values", ModelError),
        ({"gear_ratio": np.array([2.0, 2.0])}, "link 'wrist': gear ratio G must be a number", ModelError),
        ({"coulomb": 0.5}, "link 'wrist': Coulomb friction must be two finite numbers", ModelError),
        ({"coulomb": [0.2, None]}, "link 'wrist': Coulomb friction Tc must be finite", ModelError),
        ({"limits": DATES[:2]}, "link 'wrist': joint limits must be numbers", ModelError),
        ({"limits": [np.nan, 1.0]}, "link 'wrist': joint limits must not be NaN", ModelError),
        ({"limits": [-1.0, 1.0, 2.0]}, "link 'wrist': joint limits must be two numbers", ModelError),
        ({"limits": (np.inf, np.inf)}, "link 'wrist': joint limits must satisfy lower <= upper", ModelError),
    ],
)
def test_link_names_the_argument_and_link(options: dict, match: str, error: type[Exception]) -> None:
    refused(lambda: link(**options), match, error)


def test_an_infinite_limit_means_none() -> None:
    assert link(limits=(0, np.inf)).limits == (0.0, np.inf)
    assert link(limits=np.array([-np.inf, 1.0], dtype=np.float32)).limits == (-np.inf, 1.0)
    assert link(limits=(-1e16, 1e16)).limits == (-1e16, 1e16)  # as URDF files write "no limit"


@pytest.mark.parametrize(
    ("build", "match", "error"),
    [
        (lambda: ad.Robot(None), "links must be a sequence of Link objects, got None", ModelError),
        (lambda: ad.Robot("links"), "links must be a sequence of Link objects", ModelError),
        (lambda: ad.Robot([*ad.models.two_link_planar().links, None]), "links\\[2\\] is not a Link", ModelError),
        (lambda: ad.Robot([1, 2]), "links\\[0\\] is not a Link, got 1", ModelError),
        (lambda: planar(gravity=[0, 0, -9.81 + 1j]), "robot 'robot': gravity must be real", ModelError),
        (lambda: planar(gravity=["x", "y", "z"]), "gravity must be numbers", ModelError),
        (lambda: planar(base=np.full((4, 4), "x")), "robot 'robot': base must be numbers", ModelError),
        (lambda: planar(tool=np.eye(4, dtype=complex)), "robot 'robot': tool must be real", ModelError),
        (lambda: planar(tool_link=0.5), "robot 'robot': tool_link must be an integer, got 0.5", TypeError),
        (lambda: planar(configurations={"qa": [np.nan, 0.0]}), "configuration 'qa' must be finite", ModelError),
        (lambda: planar(configurations={1: [0.0, 0.0]}), "configuration name 1 is not free", ModelError),
        (lambda: planar(configurations=[("qa", [0.0, 0.0])]), "configurations must be a mapping", ModelError),
        (lambda: planar(configurations={"qa": [1j, 1j]}), "configuration 'qa' must be real", ModelError),
    ],
)
def test_robot_constructor_names_the_argument(build: Callable[[], object], match: str, error: type) -> None:
    refused(build, match, error)


def test_a_parent_changed_behind_the_links_back_is_refused() -> None:
    first, second = ad.models.two_link_planar().links
    bent = ad.Link(first.name, first.joint, first.inertial)
    object.__setattr__(bent, "parent", "base")  # what Link itself refuses
    refused(lambda: ad.Robot([bent, second]), "link 'theta1': parent index 'base' must name an earlier link")


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: dh(mass=1 + 0j), "link 'joint1': mass must be real"),
        (lambda: dh(mass=[0.5]), "link 'joint1': mass must be a number"),
        (lambda: dh(a=None), "link 'joint1': DH parameter a must be a real number, got None"),
        (lambda: dh(theta=np.inf), "link 'joint1': DH parameter theta must be finite"),
        (lambda: dh(alpha=1e300), "link 'joint1': DH parameter alpha holds values"),
        (lambda: dh(d=10**400), "link 'joint1': DH parameter d must be a real number"),
        (lambda: dh(com=[0.1 + 1e-20j, 0.0, 0.0]), "link 'joint1': centre of mass must be real"),
        (lambda: dh(Tc=0.5), "link 'joint1': Coulomb friction must be two finite numbers"),
        (lambda: dh(Tc=None), "link 'joint1': Coulomb friction Tc must be numbers, got None"),
        (lambda: dh(qlim=["x", "y"]), "link 'joint1': joint limits must be numbers"),
        (lambda: dh(G=1e300), "link 'joint1': gear ratio G holds values"),
        (lambda: dh(B="0.5"), "link 'joint1': viscous friction B must be a real number"),
        (lambda: dh(kind={"q": 1}), "joint 'joint1': joint kind must be 'revolute' or 'prismatic'"),
        (lambda: ad.Robot.from_dh(None), "a DH table must be a sequence of rows"),
        (lambda: ad.Robot.from_dh({"a": 1.0}), "a DH table must be a sequence of rows"),
        (lambda: ad.Robot.from_dh([{"a": 1.0}, None]), "DH table row 2 must be a mapping"),
        (lambda: ad.Robot.from_dh([{"a": 1.0}], convention=b"standard"), "DH convention must be"),
    ],
)
def test_from_dh_names_the_key_and_link(build: Callable[[], object], match: str) -> None:
    refused(build, match)


@pytest.mark.parametrize(
    ("build", "match", "error"),
    [
        (lambda arm: arm.with_payload(1 + 0j), "link 'theta2 payload': mass must be real", ModelError),
        (lambda arm: arm.with_payload(0.5, com=[0.0, 0.0, 10**400]), "payload': centre of mass must be", ModelError),
        (lambda arm: arm.with_payload(0.5, inertia="abc"), "payload': inertia must be numbers", ModelError),
        (lambda arm: arm.with_gravity([0.0, 0.0, 1e300]), "gravity holds values", ModelError),
        (lambda arm: arm.with_gravity(None), "gravity must be numbers, got None", ModelError),
        (lambda arm: arm.replace(links=[None]), "links\\[0\\] is not a Link", ModelError),
        (lambda arm: arm.replace(tool_link=1e-300), "tool_link must be an integer", TypeError),
        (lambda arm: arm.configuration({"q": 1.0}), "a configuration name must be a str", TypeError),
    ],
)
def test_variants_name_the_argument(build: Callable[[ad.Robot], object], match: str, error: type) -> None:
    arm = ad.models.two_link_planar()
    refused(lambda: build(arm), match, error)


@pytest.mark.parametrize(
    ("build", "match", "error"),
    [
        (lambda: ad.models.load(None), "the name of a built-in arm must be a str", TypeError),
        (lambda: ad.models.load({"q": 1.0}), "the name of a built-in arm must be a str", TypeError),
        (lambda: ad.models.two_link_planar(a1=None), "two_link_planar: length a1 must be a real number", ModelError),
        (lambda: ad.models.two_link_planar(a1=np.inf), "two_link_planar: length a1 must be finite", ModelError),
        (lambda: ad.models.two_link_planar(m2=-1.0), "two_link_planar: mass m2 must be at least 0", ModelError),
        (lambda: ad.models.two_link_planar(g=[9.8]), "two_link_planar: gravity g must be a number", ModelError),
        (lambda: ad.models.polar_rp(m=1 + 0j), "polar_rp: mass m must be real", ModelError),
        (lambda: ad.models.cylindrical(J=10**400), "cylindrical: inertia J must be a real number", ModelError),
        (lambda: ad.models.cylindrical(g=1e300), "cylindrical: gravity g holds values", ModelError),
    ],
)
def test_models_name_the_parameter(build: Callable[[], object], match: str, error: type) -> None:
    refused(build, match, error)


# ----- symbolic parameters are still accepted -------------------------------------------------
@pytest.mark.parametrize("factory", [ad.models.two_link_planar, ad.models.polar_rp, ad.models.cylindrical])
def test_the_books_examples_build_symbolically(factory: Callable[..., ad.Robot]) -> None:
    arm = factory(symbolic=True)
    assert arm.is_symbolic and arm.packed is None


def test_symbolic_parameters_pass_and_their_numbers_are_checked() -> None:
    m, a, g = sympy.symbols("m a g", positive=True)
    arm = ad.Robot.from_dh([{"a": a, "mass": m}, {"a": 1.0, "mass": 2.0}], gravity=[0, -g, 0])
    assert arm.is_symbolic and arm.links[0].inertial.mass == m
    refused(lambda: ad.Robot.from_dh([{"a": a, "alpha": np.nan}]), "DH parameter alpha must be finite")
    refused(lambda: ad.Inertial(m, [a, 0, np.inf], name="l"), "link 'l': centre of mass must be finite")
    refused(lambda: ad.Inertial(-1.0, [a, 0, 0], name="l"), "link 'l': mass must be non-negative")
    refused(lambda: planar(gravity=[0, -g, 1 + 0j]), "gravity must be real")


def test_symbolic_derivation_still_works() -> None:
    form = ad.symbolic.derive(ad.models.two_link_planar(symbolic=True))
    m1, m2, a1, a2 = sympy.symbols("m1 m2 a1 a2", positive=True)
    q2 = form.q[1]
    expected = (m1 + m2) * a1**2 + m2 * a2**2 + 2 * m2 * a1 * a2 * sympy.cos(q2)  # Example 3.2-2, M11
    assert sympy.simplify(form.M[0, 0] - expected) == 0


def test_numeric_values_of_unusual_types_give_the_same_arm() -> None:
    """Fractions, NumPy scalars and int arrays are numbers; the arm equals the plain float one."""
    from fractions import Fraction

    plain = dh(mass=0.5, com=[0.1, 0.0, 0.0], qlim=(-1.0, 1.0))
    unusual = dh(mass=Fraction(1, 2), com=np.array([0.1, 0, 0], dtype=np.float32), qlim=np.array([-1, 1]))
    q = np.array([0.3, -0.2])
    assert_allclose(unusual.inertia_matrix(q), plain.inertia_matrix(q), rtol=1e-6)
