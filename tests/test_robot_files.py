"""Every URDF file of example-robot-data: it loads and its dynamics equal Pinocchio's, or it is refused for a named
reason, or it loads with a warning naming the joints that move no mass and no dynamics call returns NaN.

Each file is one test (parametrized by its path under the robots folder), loading the model once. Outcomes:

- (a) it loads with ``strict=False`` (warnings allowed: mimic joints, triangle inequality, non-unit axes) and its
  M(q), G(q), inverse dynamics (``without_friction()``) and forward dynamics equal Pinocchio's
  (``pin.buildModelFromUrdf``, fixed base) at 3 random states to 1e-9 relative. Joints are matched by name;
  Pinocchio's continuous joints take (cos, sin) (``tests.helpers.pin_q``).
- (b) it is refused with a ModelError whose message names the reason: ``REFUSED``.
- (c) it loads with a UserWarning naming the joints that move no mass (``SINGULAR``); M, G and inverse dynamics
  still equal Pinocchio's, and forward dynamics raises a ModelError or returns finite values, never NaN.

A file not listed in ``REFUSED`` or ``SINGULAR`` must be of kind (a), so a new file of example-robot-data is
checked against Pinocchio without touching this file.
"""

from __future__ import annotations

import warnings
import zlib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from armdyn import ModelError, load_urdf
from tests.helpers import ROBOTS, pin_q

ROBOT_FILES = sorted(path.relative_to(ROBOTS).as_posix() for path in ROBOTS.rglob("*.urdf"))
STATES = 3
RTOL = 1e-9
EPS = np.finfo(float).eps

_NOT_SEMIDEFINITE = r"link '{}'.*inertia tensor is not positive semi-definite"
_NO_MOVING_JOINT = r"no revolute, continuous or prismatic joint"
# (b) refused, with what the message must say
REFUSED = {
    "hector_description/robots/quadrotor_base.urdf": _NO_MOVING_JOINT,  # a free-flying body: nothing but fixed joints
    "iris_description/robots/iris_simple.urdf": _NO_MOVING_JOINT,
    "romeo_description/urdf/romeo_laas_small.urdf": _NOT_SEMIDEFINITE.format("body"),  # moments -0.021, 0.052, 0.099
    "tiago_description/robots/tiago.urdf": _NOT_SEMIDEFINITE.format("base_antenna_left_link"),  # ixy > ixx, iyy
    "tiago_description/robots/tiago_dual.urdf": _NOT_SEMIDEFINITE.format("base_antenna_left_link"),
    "tiago_description/robots/tiago_no_hand.urdf": _NOT_SEMIDEFINITE.format("base_antenna_left_link"),
    "ur_description/urdf/ur3.urdf": r"<robot> element has no name",  # an empty xacro leftover; Pinocchio refuses it
}
# (c) loaded with a warning naming the joints that move no mass: romeo's fingers and hands are massless links
_ROMEO_HAND = ["Hand", *(f"Finger{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3) if (i, j) != (1, 1))]
SINGULAR = {
    "romeo_description/urdf/romeo.urdf": {
        side + joint for side in "LR" for joint in [*_ROMEO_HAND, "Thumb1", "Thumb2", "Thumb3"]
    },
}


def test_the_robots_folder_is_walked() -> None:
    assert len(ROBOT_FILES) >= 60
    assert set(REFUSED) <= set(ROBOT_FILES)
    assert set(SINGULAR) <= set(ROBOT_FILES)
    assert len(SINGULAR["romeo_description/urdf/romeo.urdf"]) == 24


class _Pinocchio:
    """Pinocchio's model of the file, with armdyn's joint order: q as Pinocchio wants it, results in armdyn's order."""

    def __init__(self, path: Path, joint_names: list[str]) -> None:
        self.model = pin.buildModelFromUrdf(str(path))
        self.data = self.model.createData()
        self.ids = [self.model.getJointId(name) for name in joint_names]
        self.v = np.array([self.model.joints[i].idx_v for i in self.ids])
        assert self.model.nv == len(joint_names), "every Pinocchio joint is an armdyn joint"

    def _q(self, q: np.ndarray) -> np.ndarray:
        return pin_q(self.model, self.ids, q)

    def _v(self, values: np.ndarray) -> np.ndarray:
        full = np.zeros(self.model.nv)
        full[self.v] = values
        return full

    def inertia_matrix(self, q: np.ndarray) -> np.ndarray:
        upper = pin.crba(self.model, self.data, self._q(q)).copy()  # the upper triangle is filled
        return (np.triu(upper) + np.triu(upper, 1).T)[np.ix_(self.v, self.v)]

    def gravity_vector(self, q: np.ndarray) -> np.ndarray:
        return pin.computeGeneralizedGravity(self.model, self.data, self._q(q))[self.v].copy()

    def inverse_dynamics(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        return pin.rnea(self.model, self.data, self._q(q), self._v(qd), self._v(qdd))[self.v].copy()

    def forward_dynamics(self, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        return pin.aba(self.model, self.data, self._q(q), self._v(qd), self._v(tau))[self.v].copy()


def _assert_close(actual: np.ndarray, expected: np.ndarray, what: str, rtol: float = RTOL) -> None:
    """max |actual - expected| <= rtol max |expected| (plus 1e-14 of absolute slack for results that are zero)."""
    assert np.all(np.isfinite(actual)), f"{what}: armdyn returns non-finite values"
    error, scale = float(np.max(np.abs(actual - expected))), float(np.max(np.abs(expected)))
    assert error <= rtol * scale + 1e-14, f"{what}: differs from Pinocchio by {error:.3g} (largest entry {scale:.3g})"


def _states(n: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(STATES):
        yield tuple(rng.uniform(-1.5, 1.5, n) for _ in range(4))  # q, qd, qdd, tau


@pytest.mark.parametrize("relative", ROBOT_FILES)
def test_robot_file(relative: str) -> None:
    path = ROBOTS / relative
    if relative in REFUSED:  # (b)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(ModelError, match=REFUSED[relative]) as info:
                load_urdf(path, strict=False)
        assert path.name in str(info.value)
        return
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        arm = load_urdf(path, strict=False)
    massless = [str(w.message) for w in record if "move no mass" in str(w.message)]
    expected = [name for name in arm.joint_names if name in SINGULAR.get(relative, ())]
    if relative in SINGULAR:  # (c)
        assert len(massless) == 1
        assert f"joints {expected} move no mass" in massless[0]
        with pytest.raises(ModelError, match=r"strict=False"), warnings.catch_warnings():  # refused by default
            warnings.simplefilter("ignore")
            load_urdf(path)
    else:  # (a)
        assert not massless, massless
    arm = arm.without_friction()
    reference = _Pinocchio(path, arm.joint_names)
    for k, (q, qd, qdd, tau) in enumerate(_states(arm.n, seed=zlib.crc32(relative.encode()))):
        inertia = reference.inertia_matrix(q)
        _assert_close(arm.inertia_matrix(q), inertia, f"M at state {k}")
        _assert_close(arm.gravity_vector(q), reference.gravity_vector(q), f"G at state {k}")
        _assert_close(arm.inverse_dynamics(q, qd, qdd), reference.inverse_dynamics(q, qd, qdd), f"tau at state {k}")
        if relative in SINGULAR:
            try:
                qdd_found = arm.forward_dynamics(q, qd, tau)
            except ModelError as error:  # the singular pivot is named
                assert any(f"'{name}'" in str(error) for name in expected), str(error)
                continue
            assert np.all(np.isfinite(qdd_found)), f"forward dynamics at state {k} returns {qdd_found}"
            continue
        # Any backward-stable solver is only as accurate as cond(M) eps: iCub's M reaches cond 7e8 (a massless
        # link carrying a point mass near its axis), where armdyn and Pinocchio both stand 1e-9 from a direct solve
        rtol = max(RTOL, 10 * EPS * np.linalg.cond(inertia))
        _assert_close(arm.forward_dynamics(q, qd, tau), reference.forward_dynamics(q, qd, tau), f"qdd at {k}", rtol)
