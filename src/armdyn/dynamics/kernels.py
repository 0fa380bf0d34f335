"""The compiled one-state kernels, for loops that call them many times (control, simulation).

A Robot method checks its arguments, allocates its result and raises a ModelError naming what
is wrong: about 0.25 us of a call that costs 0.6-0.9 us on a six-joint arm. A loop that calls
the same function thousands of times can hold the arm's compiled model and its result arrays
once and call a kernel directly, as Pinocchio's users hold a (model, data) pair::

    from armdyn.dynamics import kernels

    model, tau = arm.packed, np.empty(arm.n)
    for q, qd, qdd in samples:                       # each a C-contiguous float64 (n,) array
        status = kernels.inverse_dynamics(model, q, qd, qdd, tau)
        if status:                                   # the method says what is wrong
            arm.inverse_dynamics(q, qd, qdd)

Every kernel takes the model first, then C-contiguous float64 arrays (states of shape (n,), the
result last), writes the result and returns a status (armdyn.dynamics.status names them): OK (0)
when computed, WRONG_LENGTH + k (1-3) when state k (from 0) has the wrong length, NOT_FINITE + k
(11-13) when it holds NaN, infinity or a value of 1e15 or more, WRONG_SHAPE (4) when the result
array has the wrong shape, BAD_LINK (5) for a link index out of range, SINGULAR_STATUS (50) when
M(q) is singular (forward dynamics). Any other argument type raises
TypeError. Kernels never write the model; each call keeps its own scratch, so threads may call
them at once. The Robot method of the same name computes the same numbers bit for bit.
"""

from __future__ import annotations

from armdyn.dynamics.aba import aba_one as forward_dynamics
from armdyn.dynamics.coriolis import coriolis_one as coriolis_matrix
from armdyn.dynamics.crba import crba_one as inertia_matrix
from armdyn.dynamics.energy import energy_one as energies
from armdyn.dynamics.frames import LOCAL, TOOL, WORLD
from armdyn.dynamics.frames import jacobian_dot_one as jacobian_dot
from armdyn.dynamics.frames import jacobian_one as jacobian
from armdyn.dynamics.frames import pose_one as pose
from armdyn.dynamics.frames import transforms_one as link_transforms
from armdyn.dynamics.friction import friction_one as friction
from armdyn.dynamics.rnea import coriolis_vector_one as coriolis_vector
from armdyn.dynamics.rnea import gravity_one as gravity_vector
from armdyn.dynamics.rnea import inverse_dynamics_one as inverse_dynamics
from armdyn.dynamics.rnea import nonlinear_one as nonlinear_terms
from armdyn.dynamics.status import SINGULAR as SINGULAR_STATUS

__all__ = [
    "LOCAL",
    "SINGULAR_STATUS",
    "TOOL",
    "WORLD",
    "coriolis_matrix",
    "coriolis_vector",
    "energies",
    "forward_dynamics",
    "friction",
    "gravity_vector",
    "inertia_matrix",
    "inverse_dynamics",
    "jacobian",
    "jacobian_dot",
    "link_transforms",
    "nonlinear_terms",
    "pose",
]
