"""Generated code for the robot equation by a customized Newton-Euler recursion: tau, M, G and N as
straight-line code of named intermediate quantities, lean enough for 7-joint arms and beyond.

Khalil and Kleinfinger's customized Newton-Euler ("Minimum operations and minimum parameters of the
dynamic models of tree structure robots", IEEE J. Robotics and Automation 3(6), 1987; SYMORO): run
the recursive algorithm once on symbols, keep every intermediate quantity as a named variable instead
of expanding it into trigonometric polynomials, and let the zeros and ones of the model (DH twists of
0 and pi/2, zero offsets, centres of mass on an axis, symmetric inertias) remove the operations they
make trivial. Here the recursion runs on a tracing scalar (``Trace``): each operation on its operands
either folds (a product with 0 or 1, a sum with 0, constants with constants) or becomes one node of an
expression graph, and a node already in the graph is reused (common subexpressions are eliminated as
they arise, by value numbering). Nodes no output needs are dropped; what is left prints as one line per
operation, so no expression is deep enough to trouble Python's or Numba's compiler.

The recursions are the compiled kernels' (armdyn.dynamics.rnea, crba; Featherstone, Rigid Body
Dynamics Algorithms, 2008, 5.3 and 6.2), on the same packed model (BOOK.md section 5): joints along
their own z axes, friction and reflected motor inertia included. Rotation and position entries within
SNAP of 0 or +-1 are taken as exactly 0 or +-1 (a float twist of pi/2 has cosine 6e-17), and a mass
property below SNAP times the body's largest of its kind as 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from armdyn.dynamics.packed import (
    ARMATURE,
    COULOMB_NEG,
    COULOMB_POS,
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    N_JOINTS,
    PARENT,
    POSITION,
    ROTATION,
    STRIDE,
    VISCOUS,
)
from armdyn.errors import ModelError

SNAP = 1e-13
FUNCTIONS = ("tau", "M", "G", "N")
ARGUMENTS = {"tau": ("q", "qd", "qdd"), "M": ("q",), "G": ("q",), "N": ("q", "qd")}


class Graph:
    """An expression graph of scalar operations, each node once (value numbering).

    A node is (op, a, b): op "in" (an input, a = its name), "+", "-", "*" (a, b node ids), "+k", "*k"
    (a a node id, b a float constant: kept apart so that a constant 3.0 never matches node 3),
    "neg" (a), "sin", "cos" (a), "coulomb" (a the joint velocity's node, b the joint index)."""

    def __init__(self) -> None:
        self.nodes: list[tuple] = []
        self.number: dict[tuple, int] = {}

    def node(self, key: tuple) -> Trace:
        index = self.number.get(key)
        if index is None:
            index = self.number[key] = len(self.nodes)
            self.nodes.append(key)
        return Trace(self, index)

    def input(self, name: str) -> Trace:
        return self.node(("in", name, None))


Value = "Trace | float"


@dataclass(frozen=True)
class Trace:
    """A scalar of the recursion: a node of ``graph``. Arithmetic with floats and other Traces folds
    what is trivial and records the rest."""

    graph: Graph = field(repr=False, compare=False)
    index: int

    def __add__(self, other: object) -> Trace | float:
        return add(self, other)

    __radd__ = __add__

    def __sub__(self, other: object) -> Trace | float:
        return add(self, neg(other))

    def __rsub__(self, other: object) -> Trace | float:
        return add(other, neg(self))

    def __mul__(self, other: object) -> Trace | float:
        return mul(self, other)

    __rmul__ = __mul__

    def __neg__(self) -> Trace | float:
        return neg(self)


def _op(value: Trace) -> tuple:
    return value.graph.nodes[value.index]


def neg(x: Trace | float) -> Trace | float:
    """-x: a constant folds, -(-y) is y, -(a - b) is b - a."""
    if not isinstance(x, Trace):
        return -x
    op, a, b = _op(x)
    if op == "neg":
        return Trace(x.graph, a)
    if op == "-":
        return x.graph.node(("-", b, a))
    return x.graph.node(("neg", x.index, None))


def add(x: Trace | float, y: Trace | float) -> Trace | float:
    """x + y: 0 + y is y; x + (-y) is x - y; operands in a fixed order so that x + y and y + x are one node."""
    if not isinstance(x, Trace) and not isinstance(y, Trace):
        return x + y
    if not isinstance(x, Trace):
        x, y = y, x
    if not isinstance(y, Trace):
        if y == 0.0:
            return x
        return x.graph.node(("+k", x.index, float(y)))
    graph = x.graph
    x_negated, y_negated = _op(x)[0] == "neg", _op(y)[0] == "neg"
    if x_negated and y_negated:
        return neg(add(Trace(graph, _op(x)[1]), Trace(graph, _op(y)[1])))
    if y_negated:
        return graph.node(("-", x.index, _op(y)[1]))
    if x_negated:
        return graph.node(("-", y.index, _op(x)[1]))
    a, b = sorted((x.index, y.index))
    return graph.node(("+", a, b))


def mul(x: Trace | float, y: Trace | float) -> Trace | float:
    """x y: 0 y is 0, 1 y is y, -1 y is -y, (-a) c is a (-c); operands in a fixed order."""
    if not isinstance(x, Trace) and not isinstance(y, Trace):
        return x * y
    if not isinstance(x, Trace):
        x, y = y, x
    if not isinstance(y, Trace):
        if y == 0.0:
            return 0.0
        if y == 1.0:
            return x
        if y == -1.0:
            return neg(x)
        if _op(x)[0] == "neg":
            return mul(Trace(x.graph, _op(x)[1]), -y)
        return x.graph.node(("*k", x.index, float(y)))
    graph = x.graph
    sign = 1.0
    if _op(x)[0] == "neg":
        x, sign = Trace(graph, _op(x)[1]), -sign
    if _op(y)[0] == "neg":
        y, sign = Trace(graph, _op(y)[1]), -sign
    a, b = sorted((x.index, y.index))
    product = graph.node(("*", a, b))
    return product if sign > 0 else neg(product)


def snap(x: float) -> float:
    """x, or exactly 0, 1 or -1 when within SNAP of one of them."""
    if abs(x) < SNAP:
        return 0.0
    if abs(abs(x) - 1.0) < SNAP:
        return math.copysign(1.0, x)
    return float(x)


def snap_relative(values: Sequence[float]) -> tuple[float, ...]:
    """The values with those below SNAP times the largest set to exactly 0: rotating a body's mass
    properties into its joint frame leaves rounding noise (6e-20 for a product of inertia that is 0)."""
    scale = max((abs(float(v)) for v in values), default=0.0)
    return tuple(0.0 if abs(float(v)) < SNAP * scale else float(v) for v in values)


# ----- spatial algebra on lists of scalars (Featherstone 2008, chapter 2) -----------------------------


def cross(a: Sequence, b: Sequence) -> list:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def rotate_transposed(R: Sequence, u: Sequence) -> list:
    """R^T u for R given by rows."""
    return [R[0][c] * u[0] + R[1][c] * u[1] + R[2][c] * u[2] for c in range(3)]


def rotate(R: Sequence, u: Sequence) -> list:
    return [R[r][0] * u[0] + R[r][1] * u[1] + R[r][2] * u[2] for r in range(3)]


def motion_to_child(R: Sequence, p: Sequence, m: Sequence) -> list:
    """X m = [R^T w; R^T (u - p x w)] for a motion m = [w; u] in the parent's axes."""
    w, u = m[:3], m[3:]
    moved = [u[k] - c for k, c in enumerate(cross(p, w))]
    return rotate_transposed(R, w) + rotate_transposed(R, moved)


def force_to_parent(R: Sequence, p: Sequence, f: Sequence) -> list:
    """X^T f = [R n + p x (R g); R g] for a force f = [n; g] in the child's axes."""
    g = rotate(R, f[3:])
    n = rotate(R, f[:3])
    return [n[k] + c for k, c in enumerate(cross(p, g))] + g


def motion_cross_axis(m: Sequence, axis: int) -> list:
    """m x e_axis for a motion m = [w; u] and e_axis a unit motion vector (index 0..5)."""
    e = [0.0] * 6
    e[axis] = 1.0
    w, u, ew, eu = m[:3], m[3:], e[:3], e[3:]
    return cross(w, ew) + [a + b for a, b in zip(cross(w, eu), cross(u, ew), strict=True)]


def force_cross(v: Sequence, f: Sequence) -> list:
    """v x* f = [w x n + u x g; w x g] for v = [w; u], f = [n; g]."""
    w, u, n, g = v[:3], v[3:], f[:3], f[3:]
    return [a + b for a, b in zip(cross(w, n), cross(u, g), strict=True)] + cross(w, g)


@dataclass(frozen=True)
class Body:
    """One joint's constants from the packed model, snapped: placement (R rows, p), kind, inertia."""

    parent: int
    revolute: bool
    placement: tuple
    position: tuple
    mass: float
    first_moment: tuple
    inertia: tuple  # Ixx Ixy Ixz Iyy Iyz Izz about the body origin
    armature: float
    viscous: float
    coulomb: tuple

    def inertia_times(self, m: Sequence) -> list:
        """I m = [I_O w + h x u; m u - h x w] for m = [w; u]."""
        i0, i1, i2, i3, i4, i5 = self.inertia
        w, u, h = m[:3], m[3:], self.first_moment
        hu, hw = cross(h, u), cross(h, w)
        rows = ((i0, i1, i2), (i1, i3, i4), (i2, i4, i5))
        return [sum(rows[r][c] * w[c] for c in range(3)) + hu[r] for r in range(3)] + [
            self.mass * u[k] - hw[k] for k in range(3)
        ]


def bodies(model: np.ndarray) -> list[Body]:
    """The packed model's joints as Bodies."""
    out = []
    for i in range(int(model[N_JOINTS])):
        b = HEADER + STRIDE * i
        rows = tuple(tuple(snap(model[b + ROTATION + 3 * r + c]) for c in range(3)) for r in range(3))
        out.append(Body(
            parent=int(model[b + PARENT]), revolute=model[b + KIND] == 0.0, placement=rows,
            position=tuple(snap(model[b + POSITION + k]) for k in range(3)), mass=float(model[b + MASS]),
            first_moment=snap_relative(model[b + FIRST_MOMENT : b + FIRST_MOMENT + 3]),
            inertia=snap_relative(model[b + INERTIA : b + INERTIA + 6]), armature=float(model[b + ARMATURE]),
            viscous=float(model[b + VISCOUS]), coulomb=(float(model[b + COULOMB_POS]), float(model[b + COULOMB_NEG])),
        ))  # fmt: skip
    return out


def joint_transform(graph: Graph, body: Body, i: int) -> tuple[list, list]:
    """(R, p) of joint i in its parent's frame: R = P_R Rz(q_i), p = P_p (revolute); R = P_R, p = P_p + q_i P_R e_z."""
    P, p = body.placement, list(body.position)
    if body.revolute:
        c, s = (
            graph.node(("cos", graph.input(f"q[{i}]").index, None)),
            graph.node(("sin", graph.input(f"q[{i}]").index, None)),
        )
        R = [[P[r][0] * c + P[r][1] * s, P[r][1] * c - P[r][0] * s, P[r][2]] for r in range(3)]
        return R, p
    q = graph.input(f"q[{i}]")
    return [list(row) for row in P], [p[k] + q * P[k][2] for k in range(3)]


def newton_euler(graph: Graph, model: np.ndarray, velocity: bool, acceleration: bool, gravity: bool,
                 friction: bool) -> list:  # fmt: skip
    """tau of the recursive Newton-Euler algorithm on traced inputs q[i] (qd[i], qdd[i] where used):
    the parts selected by the flags, as rnea.rnea_core computes them."""
    arm = bodies(model)
    n = len(arm)
    g = [snap(model[GRAVITY + k]) for k in range(3)]
    v, a, f, frames = [None] * n, [None] * n, [None] * n, [None] * n
    for i, body in enumerate(arm):
        R, p = frames[i] = joint_transform(graph, body, i)
        axis = 2 if body.revolute else 5
        parent_v = v[body.parent] if body.parent >= 0 else [0.0] * 6
        parent_a = a[body.parent] if body.parent >= 0 else [0.0, 0.0, 0.0] + [-x if gravity else 0.0 for x in g]
        Xv = motion_to_child(R, p, parent_v)
        Xa = motion_to_child(R, p, parent_a)
        rate = graph.input(f"qd[{i}]") if velocity else 0.0
        accel = graph.input(f"qdd[{i}]") if acceleration else 0.0
        push = motion_cross_axis(Xv, axis)
        v[i] = [Xv[k] + (rate if k == axis else 0.0) for k in range(6)]
        a[i] = [Xa[k] + (accel if k == axis else 0.0) + push[k] * rate for k in range(6)]
        momentum = body.inertia_times(v[i])
        f[i] = [x + y for x, y in zip(body.inertia_times(a[i]), force_cross(v[i], momentum), strict=True)]
    tau = [0.0] * n
    for i in range(n - 1, -1, -1):
        body = arm[i]
        axis = 2 if body.revolute else 5
        value = f[i][axis]
        if acceleration:
            value = value + body.armature * graph.input(f"qdd[{i}]")
        if friction and velocity:
            rate = graph.input(f"qd[{i}]")
            value = value + body.viscous * rate
            if body.coulomb != (0.0, 0.0):
                value = value + graph.node(("coulomb", rate.index, i))
        tau[i] = value
        if body.parent >= 0:
            moved = force_to_parent(*frames[i], f[i])
            f[body.parent] = [x + y for x, y in zip(f[body.parent], moved, strict=True)]
    return tau


def composite_inertia_matrix(graph: Graph, model: np.ndarray) -> list:
    """M(q) by the composite-rigid-body algorithm (Featherstone 6.2) on traced q[i]: composite inertias
    (m, h, I_O) carried to each parent, M_ii = S^T I^c S + armature, then the column carried up the tree."""
    arm = bodies(model)
    n = len(arm)
    frames = [joint_transform(graph, body, i) for i, body in enumerate(arm)]
    composite = [[body.mass, *body.first_moment, *body.inertia] for body in arm]
    for i in range(n - 1, -1, -1):
        parent = arm[i].parent
        if parent >= 0:
            moved = carried_inertia(*frames[i], composite[i])
            composite[parent] = [x + y for x, y in zip(composite[parent], moved, strict=True)]
    M = [[0.0] * n for _ in range(n)]
    for i, body in enumerate(arm):
        mass, h, inertia = composite[i][0], composite[i][1:4], composite[i][4:]
        rigid = Body(-1, True, ((1, 0, 0), (0, 1, 0), (0, 0, 1)), (0, 0, 0), mass, tuple(h), tuple(inertia), 0, 0,
                     (0, 0))  # fmt: skip
        axis = 2 if body.revolute else 5
        unit = [1.0 if k == axis else 0.0 for k in range(6)]
        F = rigid.inertia_times(unit)
        M[i][i] = F[axis] + body.armature
        j = i
        while arm[j].parent >= 0:
            F = force_to_parent(*frames[j], F)
            j = arm[j].parent
            M[i][j] = M[j][i] = F[2 if arm[j].revolute else 5]
    return [x for row in M for x in row]


def carried_inertia(R: Sequence, p: Sequence, inertia: Sequence) -> list:
    """A rigid-body inertia (m, h, I_O) in a child's frame, expressed in its parent's:
    h' = R h + m p, I_O' = R I_O R^T - [Rh]x [p]x - [p]x [Rh]x - m [p]x [p]x (as add_inertia_to_parent)."""
    mass, h, (i0, i1, i2, i3, i4, i5) = inertia[0], inertia[1:4], inertia[4:]
    rh = rotate(R, h)
    rows = ((i0, i1, i2), (i1, i3, i4), (i2, i4, i5))
    A = [[sum(R[r][k] * rows[k][c] for k in range(3)) for c in range(3)] for r in range(3)]
    J = [[sum(A[r][k] * R[c][k] for k in range(3)) for c in range(3)] for r in range(3)]
    hp = rh[0] * p[0] + rh[1] * p[1] + rh[2] * p[2]
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
    moved = [mass] + [rh[k] + mass * p[k] for k in range(3)]
    for r, c in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)):
        # [a]x[b]x = b a^T - (a.b) 1
        shift = p[r] * rh[c] + p[c] * rh[r] - (2.0 * hp if r == c else 0.0)
        moved.append(J[r][c] - shift - mass * (p[r] * p[c] - (pp if r == c else 0.0)))
    return moved


@dataclass
class GeneratedFunction:
    """One function of the robot equation as straight-line code: its graph, its outputs and what it costs."""

    name: str
    arguments: tuple[str, ...]
    graph: Graph
    outputs: list
    shape: tuple[int, ...]
    coulomb: list[tuple[float, float]]
    order: list[int] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.order = live_nodes(self.graph, self.outputs)

    def operation_counts(self) -> dict[str, int]:
        """Multiplications, additions (sums, differences and sign changes) and function calls
        (sin, cos, the Coulomb law) of the code."""
        counts = {"multiplications": 0, "additions": 0, "calls": 0}
        for index in self.order:
            op = self.graph.nodes[index][0]
            if op in ("*", "*k"):
                counts["multiplications"] += 1
            elif op in ("+", "-", "+k", "neg"):
                counts["additions"] += 1
            elif op in ("sin", "cos", "coulomb"):
                counts["calls"] += 1
        counts["total"] = sum(counts.values())
        return counts


def live_nodes(graph: Graph, outputs: list) -> list[int]:
    """The nodes the outputs need, in the graph's order (each after its operands)."""
    needed = set()
    stack = [x.index for x in outputs if isinstance(x, Trace)]
    while stack:
        index = stack.pop()
        if index in needed:
            continue
        needed.add(index)
        op, a, b = graph.nodes[index]
        if op in ("+", "-", "*"):
            stack.extend((a, b))
        elif op in ("+k", "*k", "neg", "sin", "cos", "coulomb"):
            stack.append(a)
    return sorted(needed)


def generate(model: np.ndarray, name: str) -> GeneratedFunction:
    """Trace one function of the robot equation ("tau", "M", "G" or "N") on the packed model."""
    if name not in FUNCTIONS:
        raise ModelError(f"generated code is for {', '.join(FUNCTIONS)}, got {name!r}")
    graph = Graph()
    n = int(model[N_JOINTS])
    if name == "M":
        outputs, shape = composite_inertia_matrix(graph, model), (n, n)
    else:
        flags = {"tau": (True, True, True, True), "G": (False, False, True, False), "N": (True, False, True, True)}
        outputs, shape = newton_euler(graph, model, *flags[name]), (n,)
    coulomb = [(float(model[HEADER + STRIDE * i + COULOMB_POS]), float(model[HEADER + STRIDE * i + COULOMB_NEG]))
               for i in range(n)]  # fmt: skip
    return GeneratedFunction(name, ARGUMENTS[name], graph, outputs, shape, coulomb)


# ----- printing ----------------------------------------------------------------------------------------


def statements(function: GeneratedFunction, literal: Callable[[float], str],
               call: Callable[[str, str], str], coulomb: Callable[[str, int], str]) -> tuple[list, list]:  # fmt: skip
    """(assignments, output expressions): one (variable, expression) per live node, named x0, x1, ...;
    inputs are referred to by name."""
    graph, names, lines = function.graph, {}, []
    for index in function.order:
        op, a, b = graph.nodes[index]
        if op == "in":
            names[index] = a
            continue
        left = names[a]
        if op in ("+", "-", "*"):
            text = f"{left} {op} {names[b]}"
        elif op == "*k":
            text = f"{left} * {literal(b)}"
        elif op == "+k":
            text = f"{left} + {literal(b)}" if b > 0 else f"{left} - {literal(-b)}"
        elif op == "neg":
            text = f"-{left}"
        elif op in ("sin", "cos"):
            text = call(op, left)
        else:
            text = coulomb(left, b)
        names[index] = f"x{len(lines)}"
        lines.append((names[index], text))
    outputs = [names[x.index] if isinstance(x, Trace) else literal(float(x)) for x in function.outputs]
    return lines, outputs


def python_source(function: GeneratedFunction) -> str:
    """The function as Python: ``def tau(q, qd, qdd, out)`` writing out (flat), one operation per line."""
    table = function.coulomb

    def coulomb(rate: str, joint: int) -> str:
        plus, minus = table[joint]
        return f"({plus!r} if {rate} > 0.0 else ({minus!r} if {rate} < 0.0 else 0.0))"

    lines, outputs = statements(function, repr, lambda fn, x: f"math.{fn}({x})", coulomb)
    body = [f"    {name} = {text}" for name, text in lines]
    body += [f"    out[{k}] = {value}" for k, value in enumerate(outputs)]
    return f"def {function.name}({', '.join(function.arguments)}, out):\n" + "\n".join(body or ["    pass"]) + "\n"


def c_source(function: GeneratedFunction, prefix: str = "armdyn_") -> str:
    """The function as C99: ``void armdyn_tau(const double *q, ..., double *out)``, one operation per line."""
    table = function.coulomb

    def literal(x: float) -> str:
        return repr(float(x)) if math.isfinite(x) else ("INFINITY" if x > 0 else "-INFINITY")

    def coulomb(rate: str, joint: int) -> str:
        plus, minus = table[joint]
        return f"({rate} > 0.0 ? {literal(plus)} : ({rate} < 0.0 ? {literal(minus)} : 0.0))"

    lines, outputs = statements(function, literal, lambda fn, x: f"{fn}({x})", coulomb)
    arguments = ", ".join(f"const double *{a}" for a in function.arguments)
    body = [f"    const double {name} = {text};" for name, text in lines]
    body += [f"    out[{k}] = {value};" for k, value in enumerate(outputs)]
    return f"void {prefix}{function.name}({arguments}, double *out) {{\n" + "\n".join(body) + "\n}\n"


# ----- the public object -----------------------------------------------------------------------------------


class GeneratedCode:
    """The robot equation of one numeric arm as generated code: tau(q, qd, qdd), M(q), G(q) and
    N(q, qd) = Vm qd + F + G, each straight-line code of named intermediate quantities from the
    customized Newton-Euler (tau, G, N) and composite-rigid-body (M) recursions.

    Make one with ``armdyn.symbolic.generate_code(arm)``. ``python()`` and ``c()`` give the source,
    ``operation_counts()`` what it costs, ``compile()`` Numba functions of one state or a batch.

    Parameters
    ----------
    robot : Robot
        The numeric arm the code is for.
    functions : dict of str to GeneratedFunction
        The traced functions by name ("tau", "M", "G", "N").
    """

    def __init__(self, robot: object, functions: dict[str, GeneratedFunction]) -> None:
        self.robot = robot
        self.functions = functions

    def __repr__(self) -> str:
        return f"GeneratedCode('{self.robot.name}', n={self.robot.n}, functions={tuple(self.functions)})"

    def operation_counts(self) -> dict[str, dict[str, int]]:
        """What each function computes.

        Returns
        -------
        dict of str to dict
            Per function: "multiplications", "additions" (with subtractions and sign changes),
            "calls" (sin, cos, the Coulomb law) and their "total".
        """
        return {name: function.operation_counts() for name, function in self.functions.items()}

    def python(self) -> str:
        """Python source of every function, one operation per line.

        Returns
        -------
        str
            ``import math``, then ``def tau(q, qd, qdd, out)`` and the others, each writing ``out``
            (flat: M row by row).
        """
        return "import math\n\n\n" + "\n\n".join(python_source(f) for f in self.functions.values())

    def c(self, prefix: str = "armdyn_") -> str:
        """C99 source of every function, one operation per line.

        Parameters
        ----------
        prefix : str, optional
            Put before each function's name (default "armdyn_": ``armdyn_tau``).

        Returns
        -------
        str
            ``#include <math.h>``, then ``void armdyn_tau(const double *q, const double *qd,
            const double *qdd, double *out)`` and the others (M row by row into out).
        """
        header = f"/* {self.robot.name}: the robot equation, generated by armdyn */\n#include <math.h>\n\n"
        return header + "\n".join(c_source(f, prefix) for f in self.functions.values())

    def compile(self) -> CompiledCode:
        """The functions compiled by Numba (a few seconds for a 7-joint arm).

        Returns
        -------
        CompiledCode
            Its methods take one state (n,) or a batch (..., n).
        """
        return CompiledCode(self)


class CompiledCode:
    """Generated code compiled by Numba: ``tau(q, qd, qdd)``, ``M(q)``, ``G(q)``, ``N(q, qd)``, each for one
    state or a batch (leading axes), with ``out=``, as the Robot's methods.

    Parameters
    ----------
    code : GeneratedCode
        The code to compile.
    """

    def __init__(self, code: GeneratedCode) -> None:
        import numba

        from armdyn.symbolic.codegen import batch_loop

        self.n = n = code.robot.n
        self.shapes = {name: f.shape for name, f in code.functions.items()}
        self.arguments = {name: f.arguments for name, f in code.functions.items()}
        self._one, self._batch = {}, {}
        vector, matrix = "float64[::1]", "float64[:, ::1]"
        for name, function in code.functions.items():
            namespace: dict[str, object] = {"math": math, "LARGEST": LARGEST}
            exec(compile(python_source(function), f"<armdyn generated {name}>", "exec"), namespace)
            arity = len(function.arguments)
            inner = numba.njit(f"void({', '.join([vector] * (arity + 1))})", fastmath={"contract"},
                               error_model="numpy")(namespace[name])  # fmt: skip
            self._batch[name] = batch_loop(inner, arity)
            namespace["inner"] = inner
            exec(compile(checked_entry(function, n), f"<armdyn generated {name}, checked>", "exec"), namespace)
            result = matrix if len(function.shape) == 2 else vector
            self._one[name] = numba.njit(f"int64({', '.join([vector] * arity)}, {result})",
                                         error_model="numpy")(namespace["checked"])  # fmt: skip

    def tau(self, q: object, qd: object, qdd: object, out: np.ndarray | None = None) -> np.ndarray:
        """tau = M qdd + Vm qd + F + G.

        Parameters
        ----------
        q, qd, qdd : array_like
            Joint positions, velocities and accelerations, (n,) or a batch (..., n).
        out : numpy.ndarray, optional
            Where to write the result: C-contiguous float64 of the result's shape.

        Returns
        -------
        numpy.ndarray
            tau, (..., n).

        Raises
        ------
        armdyn.ModelError
            When a state or ``out`` is invalid, or the code has no such function.
        """
        if out is None and "tau" in self._one:
            result = np.empty(self.n)
            try:  # one plain state straight to the checked entry (C-contiguous float64 only)
                if self._one["tau"](q, qd, qdd, result) == 0:
                    return result
            except TypeError:
                pass
        return self._call("tau", (q, qd, qdd), out)

    def M(self, q: object, out: np.ndarray | None = None) -> np.ndarray:
        """The inertia matrix M(q).

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or a batch (..., n).
        out : numpy.ndarray, optional
            Where to write the result: C-contiguous float64 of the result's shape.

        Returns
        -------
        numpy.ndarray
            M, (..., n, n).

        Raises
        ------
        armdyn.ModelError
            When a state or ``out`` is invalid, or the code has no such function.
        """
        if out is None and "M" in self._one:
            result = np.empty((self.n, self.n))
            try:
                if self._one["M"](q, result) == 0:
                    return result
            except TypeError:
                pass
        return self._call("M", (q,), out)

    def G(self, q: object, out: np.ndarray | None = None) -> np.ndarray:
        """The gravity vector G(q).

        Parameters
        ----------
        q : array_like
            Joint positions, (n,) or a batch (..., n).
        out : numpy.ndarray, optional
            Where to write the result: C-contiguous float64 of the result's shape.

        Returns
        -------
        numpy.ndarray
            G, (..., n).

        Raises
        ------
        armdyn.ModelError
            When a state or ``out`` is invalid, or the code has no such function.
        """
        return self._call("G", (q,), out)

    def N(self, q: object, qd: object, out: np.ndarray | None = None) -> np.ndarray:
        """N(q, qd) = Vm qd + F + G.

        Parameters
        ----------
        q, qd : array_like
            Joint positions, and velocities, (n,) or a batch (..., n).
        out : numpy.ndarray, optional
            Where to write the result: C-contiguous float64 of the result's shape.

        Returns
        -------
        numpy.ndarray
            N, (..., n).

        Raises
        ------
        armdyn.ModelError
            When a state or ``out`` is invalid, or the code has no such function.
        """
        return self._call("N", (q, qd), out)

    def _call(self, name: str, states: tuple, out: np.ndarray | None) -> np.ndarray:
        from armdyn import inputs

        if name not in self._one:
            raise ModelError(f"this code has no {name}: generate it with functions including '{name}'")
        shape = self.shapes[name]
        if out is None:
            result = np.empty(shape)
            try:
                if self._one[name](*states, result) == 0:
                    return result
            except TypeError:
                pass
        batch, flat = inputs.batch_states(self.arguments[name], states, self.n)
        result = inputs.result(out, (*batch, *shape))
        if flat[0].shape[0]:
            self._batch[name](*flat, result.reshape(-1, int(np.prod(shape))))
        return result


def checked_entry(function: GeneratedFunction, n: int) -> str:
    """Source of ``checked(*states, out)``: lengths, finiteness and magnitude of every state and the
    shape of out checked (status 1, 2, 3 / 11, 12, 13 / 4, as the kernels' entries), then the code."""
    matrix = len(function.shape) == 2
    shape = f"out.shape[0] != {n} or out.shape[1] != {n}" if matrix else f"out.shape[0] != {n}"
    args = function.arguments
    lines = [f"def checked({', '.join(args)}, out):", f"    if {shape}:", "        return 4"]
    for code, arg in enumerate(args, 1):
        lines += [f"    if {arg}.shape[0] != {n}:", f"        return {code}", f"    for k in range({n}):",
                  f"        if not abs({arg}[k]) < LARGEST:", f"            return {code + 10}"]  # fmt: skip
    target = f"out.reshape({n * n})" if matrix else "out"
    lines += [f"    inner({', '.join(args)}, {target})", "    return 0"]
    return "\n".join(lines) + "\n"


LARGEST = 1e15


def generate_code(robot: object, functions: Sequence[str] = FUNCTIONS) -> GeneratedCode:
    """Generated code for the robot equation of a numeric arm, by a customized Newton-Euler recursion
    (Khalil and Kleinfinger 1987; the module docstring): tau, M, G and N as straight-line code whose
    cost grows linearly with the joints (M: with their number of pairs).

    Parameters
    ----------
    robot : Robot
        An arm with numeric parameters (``Robot.packed`` not None).
    functions : sequence of str, optional
        Which of "tau", "M", "G", "N" to generate (default all).

    Returns
    -------
    GeneratedCode
        Its ``python()``, ``c()``, ``operation_counts()`` and ``compile()``.

    Raises
    ------
    armdyn.ModelError
        When the arm has symbolic parameters or a function name is unknown.
    """
    packed = getattr(robot, "packed", None)
    if packed is None:
        raise ModelError(f"generate_code needs an arm with numeric parameters; '{getattr(robot, 'name', robot)}' "
                         "has symbols (use derive for closed forms in symbols)")  # fmt: skip
    names = [functions] if isinstance(functions, str) else list(functions)
    unknown = [f for f in names if f not in FUNCTIONS]
    if unknown or not names:
        raise ModelError(f"functions must be some of {FUNCTIONS}, got {names}")
    return GeneratedCode(robot, {name: generate(packed, name) for name in names})
