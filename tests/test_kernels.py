"""armdyn.dynamics.kernels: the one-state kernels called directly give the Robot methods' numbers
bit for bit, and a status instead of an error."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

import armdyn as ad
from armdyn.dynamics import kernels
from tests.strategies import random_robot


@pytest.mark.parametrize("arm", [ad.models.puma560(), random_robot(5, 5)], ids=["puma560", "random tree"])
def test_kernels_equal_the_methods(arm: ad.Robot) -> None:
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-1, 1, (3, arm.n))
    model, n = arm.packed, arm.n
    vector, matrix, six = np.empty(n), np.empty((n, n)), np.empty((6, n))
    cases = [
        (kernels.inverse_dynamics, (q, qd, qdd), vector, arm.inverse_dynamics(q, qd, qdd)),
        (kernels.forward_dynamics, (q, qd, qdd), vector, arm.forward_dynamics(q, qd, qdd)),
        (kernels.nonlinear_terms, (q, qd), vector, arm.nonlinear_terms(q, qd)),
        (kernels.coriolis_vector, (q, qd), vector, arm.coriolis_vector(q, qd)),
        (kernels.gravity_vector, (q,), vector, arm.gravity_vector(q)),
        (kernels.friction, (qd,), vector, arm.friction(qd)),
        (kernels.inertia_matrix, (q,), matrix, arm.inertia_matrix(q)),
        (kernels.coriolis_matrix, (q, qd), matrix, arm.coriolis_matrix(q, qd)),
        (kernels.energies, (q, qd), np.empty(2), arm.energies(q, qd)),
        (kernels.link_transforms, (q,), np.empty((n, 4, 4)), arm.link_transforms(q)),
        (kernels.pose, (q, kernels.TOOL), np.empty((4, 4)), arm.tool_pose(q)),
        (kernels.jacobian, (q, 1, kernels.LOCAL), six, arm.jacobian(q, "tool", link=1)),
        (kernels.jacobian_dot, (q, qd, kernels.TOOL, kernels.WORLD), six, arm.jacobian_dot(q, qd)),
    ]
    for kernel, args, out, expected in cases:
        assert kernel(model, *args, out) == 0
        assert_array_equal(out, expected)


def test_kernels_return_a_status_for_bad_input() -> None:
    arm = ad.models.puma560()
    model, q, tau = arm.packed, np.zeros(6), np.empty(6)
    assert kernels.inverse_dynamics(model, np.zeros(5), q, q, tau) == 1
    assert kernels.inverse_dynamics(model, q, np.full(6, np.nan), q, tau) == 12
    assert kernels.inverse_dynamics(model, q, q, q, np.empty(5)) == 4
    assert kernels.jacobian(model, q, 6, kernels.WORLD, np.empty((6, 6))) == 5
    polar = ad.models.polar_rp()
    assert kernels.forward_dynamics(polar.packed, np.zeros(2), np.zeros(2), np.zeros(2), np.empty(2)) == (
        kernels.SINGULAR_STATUS
    )
    with pytest.raises(TypeError):
        kernels.inverse_dynamics(model, [0.0] * 6, q, q, tau)
