"""The PUMA 560's robot equation at its nominal pose, one state and a batch.

Run: .venv/bin/python examples/puma560_dynamics.py
"""

import numpy as np

import armdyn as ad

arm = ad.models.puma560()
q, qd = arm.qn, np.array([0.1, 0.2, 0.8, 0.2, 0.5, 1.0])
np.set_printoptions(precision=4, suppress=True)

print("M(qn) =\n", arm.inertia_matrix(q))
print("G(qn) =", arm.gravity_vector(q))
print("Vm(qn, qd) qd =", arm.coriolis_matrix(q, qd) @ qd, "= V =", arm.coriolis_vector(q, qd))
S = arm.inertia_matrix_dot(q, qd) - 2 * arm.coriolis_matrix(q, qd)
print("largest |S + S^T| (S = Mdot - 2 Vm is skew):", np.abs(S + S.T).max())

tau = np.array([1.0, 3.2, 1.8, 0.1, 0.7, 4.6])
qdd = arm.forward_dynamics(q, qd, tau)
print("qdd =", qdd, " back to tau:", arm.inverse_dynamics(q, qd, qdd))

states = np.random.default_rng(0).uniform(-1, 1, (100_000, 6))
torques = arm.inverse_dynamics(states, states, states)  # one compiled call, vectorized across states
print("a batch of", len(states), "states ->", torques.shape)
