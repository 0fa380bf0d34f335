"""Closed-form derivation of the robot equation, by the book's route or recursively.

Both routes work on trigonometric polynomials (algebra.py):

- "lagrange", the book's own (Section 3.2): world transforms T_i, their partials
  dT_i/dq_j, the pseudo-inertia matrices J_i, the trace formula
  m_jk = sum_i tr(dT_i/dq_j J_i dT_i/dq_k^T) (3.2.30), the potential
  P = -sum_i g^T T_i J_i e4 (3.2.36) and G = dP/dq (3.2.43);
- "recursive", which scales to six joints and more: the composite-rigid-body
  algorithm for M (Featherstone 6.2), each composite inertia carried to the parent
  frame with the local transform only, so each expression involves only the joints
  between two links. "auto" takes it for every arm.

The arm's numbers enter exactly where the user wrote exact values (algebra.exact_float:
0.5 is 1/2, cos(pi/2) is 0), so both routes reach the same canonical polynomials, term
for term, with no round-off residue.

The Christoffel symbols v_ijk = 1/2 (dm_kj/dq_i + dm_ki/dq_j - dm_ij/dq_k) (3.3.47) give
Vm and the matrices V_k of Table 3.3.1; V = Vm qd; tau = M qdd + V + F + G.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import symengine as se

from armdyn.dynamics.friction import refuse_nonlinear_friction
from armdyn.errors import ModelError
from armdyn.robot import Robot
from armdyn.symbolic.algebra import TrigAlgebra, cross, matrix, number, skew, transform


@dataclass
class Derivation:
    """The raw closed form, as trigonometric polynomials (SymEngine)."""

    q: list[se.Symbol]
    qd: list[se.Symbol]
    qdd: list[se.Symbol]
    trig: dict[int, tuple[se.Symbol, se.Symbol]]
    M: list[list[se.Basic]]
    christoffel: list[list[list[se.Basic]]]  # [i][j][k] = v_ijk
    Vm: list[list[se.Basic]]
    V: list[se.Basic]
    G: list[se.Basic]
    F: list[se.Basic]
    tau: list[se.Basic]
    parameters: list[se.Symbol]  # the friction symbols added for friction="symbolic"


class _Arm:
    """The arm's geometry and mass properties in SymEngine, with its joint symbols."""

    def __init__(self, robot: Robot) -> None:
        n = robot.n
        self.robot = robot
        self.n = n
        self.q = [se.Symbol(f"q{i + 1}") for i in range(n)]
        self.qd = [se.Symbol(f"qd{i + 1}") for i in range(n)]
        self.qdd = [se.Symbol(f"qdd{i + 1}") for i in range(n)]
        self.trig = {
            i: (se.Symbol(f"c{i + 1}"), se.Symbol(f"s{i + 1}"))
            for i, link in enumerate(robot.links)
            if link.joint.is_revolute
        }
        prismatic = {i: self.q[i] for i in range(n) if i not in self.trig}
        self.algebra = TrigAlgebra(self.trig, prismatic)
        self.local = [self._local_transform(i) for i in range(n)]

    def _local_transform(self, i: int) -> se.DenseMatrix:
        """X_i = placement @ motion(q_i) @ frame_offset: link i in its parent link's frame."""
        joint = self.robot.links[i].joint
        axis = [number(a, geometric=True) for a in joint.axis]
        motion = se.eye(4)
        if i in self.trig:
            c, s = self.trig[i]
            k = skew(axis)
            rotation = se.eye(3) + k * s + (k * k) * (1 - c)
            for r in range(3):
                for col in range(3):
                    motion[r, col] = rotation[r, col]
        else:
            for r in range(3):
                motion[r, 3] = self.q[i] * axis[r]
        return self.algebra.reduce_matrix(transform(joint.placement) * motion * transform(joint.frame_offset))

    def world_transforms(self) -> list[se.DenseMatrix]:
        world: list[se.DenseMatrix] = []
        for i, link in enumerate(self.robot.links):
            parent = transform(self.robot.base) if link.parent < 0 else world[link.parent]
            world.append(self.algebra.reduce_matrix(parent * self.local[i]))
        return world

    def inertial(self, i: int) -> tuple[se.Basic, list[se.Basic], se.DenseMatrix]:
        """(m, h = m c, I_O about the link origin) of link i in its frame."""
        body = self.robot.links[i].inertial
        mass = number(body.mass)
        com = [number(x) for x in body.com]
        h = [mass * x for x in com]
        inertia = matrix(body.inertia) + (se.eye(3) * sum(x * x for x in com) - _outer(com, com)) * mass
        return mass, h, inertia.applyfunc(se.expand)

    def pseudo_inertia(self, i: int) -> se.DenseMatrix:
        """J_i = [[tr(I_O)/2 1 - I_O, m c], [m c^T, m]] (3.2.27)."""
        mass, h, inertia = self.inertial(i)
        second = se.eye(3) * ((inertia[0, 0] + inertia[1, 1] + inertia[2, 2]) / 2) - inertia
        J = se.zeros(4, 4)
        for r in range(3):
            for c in range(3):
                J[r, c] = se.expand(second[r, c])
            J[r, 3] = J[3, r] = h[r]
        J[3, 3] = mass
        return J

    def motion_subspace(self, i: int) -> list[se.Basic]:
        """S_i in link i's own frame: [a; o x a] (revolute) or [0; a] (prismatic), constants."""
        joint = self.robot.links[i].joint
        offset = transform(joint.frame_offset)
        rotation_t = offset[:3, :3].T
        a = list(rotation_t * matrix(np.reshape(joint.axis, (3, 1)), geometric=True))
        o = [-x for x in rotation_t * offset[:3, 3]]
        if i in self.trig:
            return [se.expand(x) for x in a + cross(o, a)]
        return [se.Integer(0)] * 3 + [se.expand(x) for x in a]

    def gravity(self) -> list[se.Basic]:
        return [number(g) for g in self.robot.gravity]


def _outer(a: list[se.Basic], b: list[se.Basic]) -> se.DenseMatrix:
    return se.DenseMatrix([[x * y for y in b] for x in a])


# ----- the inertia matrix ---------------------------------------------------------------------------
def inertia_matrix_lagrange(arm: _Arm, world: list[se.DenseMatrix]) -> list[list[se.Basic]]:
    """m_jk = sum_i trace(dT_i/dq_j J_i (dT_i/dq_k)^T) (3.2.30, 3.2.31)."""
    n, A = arm.n, arm.algebra
    ancestors = arm.robot.ancestors
    partials = {
        (i, j): world[i].applyfunc(lambda e, j=j: A.diff(e, j)) for i in range(n) for j in range(n) if ancestors[i, j]
    }
    M = [[se.Integer(0)] * n for _ in range(n)]
    for j in range(n):
        for k in range(j, n):
            total = se.Integer(0)
            for i in range(n):
                if ancestors[i, j] and ancestors[i, k]:
                    product = partials[i, j] * arm.pseudo_inertia(i) * partials[i, k].T
                    total += product[0, 0] + product[1, 1] + product[2, 2] + product[3, 3]
            M[j][k] = M[k][j] = A.reduce(total)
    return M


def _carry_inertia(
    A: TrigAlgebra, X: se.DenseMatrix, body: tuple[se.Basic, list[se.Basic], se.DenseMatrix]
) -> tuple[se.Basic, list[se.Basic], se.DenseMatrix]:
    """(m, h, I_O) in the parent's frame: h' = R h + m p, I' = R I R^T - [Rh][p] - [p][Rh] - m [p][p]."""
    mass, h, inertia = body
    R = X[:3, :3]
    p = [X[0, 3], X[1, 3], X[2, 3]]
    rh = list(R * se.DenseMatrix(3, 1, h))
    P, H = skew(p), skew(rh)
    moved = R * inertia * R.T - H * P - P * H - P * P * mass
    return mass, [A.reduce(rh[k] + mass * p[k]) for k in range(3)], moved.applyfunc(A.reduce)


def inertia_matrix_recursive(arm: _Arm) -> list[list[se.Basic]]:
    """M by the composite-rigid-body algorithm in link frames (Featherstone 6.2)."""
    n, A = arm.n, arm.algebra
    composite = [arm.inertial(i) for i in range(n)]
    for i in range(n - 1, -1, -1):
        parent = arm.robot.links[i].parent
        if parent >= 0:
            mass, h, inertia = _carry_inertia(A, arm.local[i], composite[i])
            pm, ph, pi = composite[parent]
            composite[parent] = (pm + mass, [ph[k] + h[k] for k in range(3)], (pi + inertia).applyfunc(se.expand))
    M = [[se.Integer(0)] * n for _ in range(n)]
    for i in range(n):
        mass, h, inertia = composite[i]
        S = arm.motion_subspace(i)
        a, l = S[:3], S[3:]
        torque = [A.reduce(x) for x in list(inertia * se.DenseMatrix(3, 1, a))]
        torque = [torque[k] + cross(h, l)[k] for k in range(3)]
        force = [mass * l[k] - cross(h, a)[k] for k in range(3)]
        M[i][i] = A.reduce(sum(x * y for x, y in zip(S, torque + force, strict=True)))
        j, parent = i, arm.robot.links[i].parent
        while parent >= 0:
            R = arm.local[j][:3, :3]
            p = [arm.local[j][0, 3], arm.local[j][1, 3], arm.local[j][2, 3]]
            rf = [A.reduce(x) for x in R * se.DenseMatrix(3, 1, force)]
            rn = list(R * se.DenseMatrix(3, 1, torque))
            torque = [A.reduce(rn[k] + cross(p, rf)[k]) for k in range(3)]
            force = rf
            j = parent
            Sj = arm.motion_subspace(j)
            M[i][j] = M[j][i] = A.reduce(sum(x * y for x, y in zip(Sj, torque + force, strict=True)))
            parent = arm.robot.links[j].parent
    return M


# ----- gravity, Christoffel symbols, friction ----------------------------------------------------------
def gravity_vector(arm: _Arm, world: list[se.DenseMatrix]) -> list[se.Basic]:
    """G_j = dP/dq_j with P = -sum_i g^T (m_i p_i + R_i h_i) (3.2.35, 3.2.43)."""
    g = arm.gravity()
    P = se.Integer(0)
    for i, T in enumerate(world):
        mass, h, _ = arm.inertial(i)
        for r in range(3):
            P -= g[r] * (mass * T[r, 3] + T[r, 0] * h[0] + T[r, 1] * h[1] + T[r, 2] * h[2])
    P = arm.algebra.reduce(P)
    return [arm.algebra.diff(P, j) for j in range(arm.n)]


def christoffel(arm: _Arm, M: list[list[se.Basic]]) -> list[list[list[se.Basic]]]:
    """v_ijk = 1/2 (dm_kj/dq_i + dm_ki/dq_j - dm_ij/dq_k) (3.3.47)."""
    n, A = arm.n, arm.algebra
    dM = [[[A.diff(M[j][k], l) for k in range(n)] for j in range(n)] for l in range(n)]  # [l][j][k]
    return [[[A.reduce((dM[i][k][j] + dM[j][k][i] - dM[k][i][j]) / 2) for k in range(n)] for j in range(n)]
            for i in range(n)]  # fmt: skip


def coulomb_law(rate: se.Symbol, positive: se.Basic, negative: se.Basic) -> se.Basic:
    """Tc+ for rate > 0, Tc- for rate < 0 and 0 at rest, as the numeric kernels compute it.

    A symmetric law (Tc- = -Tc+) is written k sgn(rate); an asymmetric one as the
    Piecewise the user gave, never through sgn^2.
    """
    if positive == -negative:
        return positive * se.sign(rate)
    return se.Piecewise((positive, se.Gt(rate, 0)), (negative, se.Lt(rate, 0)), (se.Integer(0), True))


def friction(arm: _Arm, mode: str | bool) -> tuple[list[se.Basic], list[se.Symbol]]:
    """F(qd) = Fv qd + Fd(qd); the arm's own values, none, or new symbols v_i, k_i (F = v qd + k sgn(qd)).
    An arm's own Stribeck or sigmoid friction is refused (a ModelError naming the link)."""
    n, robot = arm.n, arm.robot
    if mode == "symbolic":
        symbols, F = [], []
        for i in range(n):
            k, v = se.Symbol(f"k{i + 1}"), se.Symbol(f"v{i + 1}")
            symbols += [k, v]
            F.append(v * arm.qd[i] + k * se.sign(arm.qd[i]))
        return F, symbols
    if not mode:
        return [se.Integer(0)] * n, []
    refuse_nonlinear_friction(robot, "the closed form")
    viscous, coulomb = robot.viscous_friction, robot.coulomb_friction
    F = []
    for i in range(n):
        law = coulomb_law(arm.qd[i], number(coulomb[i, 0]), number(coulomb[i, 1]))
        F.append(number(viscous[i]) * arm.qd[i] + law)
    return F, []


STAGES = (  # (stage, fraction of derive_raw's work done when it starts)
    ("kinematics", 0.0),
    ("inertia matrix", 0.1),
    ("gravity", 0.5),
    ("Christoffel symbols", 0.55),
    ("Coriolis matrix", 0.8),
    ("tau", 0.9),
)


def derive_raw(
    robot: Robot,
    method: str = "auto",
    with_friction: str | bool = True,
    progress: Callable[[float, str], object] | None = None,
) -> Derivation:
    """The closed form of ``robot`` as trigonometric polynomials (see the module docstring).

    ``progress``, when given, is called as progress(fraction, stage) at the start of each
    stage of STAGES and with (1.0, "done") at the end.
    """
    if method == "auto":
        method = "recursive"
    if method not in ("lagrange", "recursive"):
        raise ModelError(f"method must be 'auto', 'lagrange' or 'recursive', got '{method}'")
    report = dict(STAGES)

    def stage(name: str) -> None:
        if progress is not None:
            progress(report.get(name, 1.0), name)

    stage("kinematics")
    arm = _Arm(robot)
    A, n = arm.algebra, robot.n
    world = arm.world_transforms()
    stage("inertia matrix")
    M = inertia_matrix_lagrange(arm, world) if method == "lagrange" else inertia_matrix_recursive(arm)
    armature = robot.reflected_inertia
    for i in range(n):
        if armature[i] != 0:
            M[i][i] = M[i][i] + number(armature[i])
    stage("gravity")
    G = gravity_vector(arm, world)
    stage("Christoffel symbols")
    v = christoffel(arm, M)
    stage("Coriolis matrix")
    Vm = [[A.reduce(sum(v[i][j][k] * arm.qd[i] for i in range(n))) for j in range(n)] for k in range(n)]
    V = [A.reduce(sum(Vm[k][j] * arm.qd[j] for j in range(n))) for k in range(n)]
    stage("tau")
    F, parameters = friction(arm, with_friction)
    tau = [A.reduce(sum(M[k][j] * arm.qdd[j] for j in range(n)) + V[k] + G[k]) + F[k] for k in range(n)]
    stage("done")
    return Derivation(arm.q, arm.qd, arm.qdd, arm.trig, M, v, Vm, V, G, F, tau, parameters)
