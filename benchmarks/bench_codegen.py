"""Generated code for the robot equation (armdyn.symbolic.generate_code) beside the Robotics Toolbox's
symbolic RNE and SymPy's Kane method, measured in the same run on the same four arms.

    .venv/bin/python benchmarks/bench_codegen.py                  # a few minutes
    .venv/bin/python benchmarks/bench_codegen.py --arm puma560    # one arm
    .venv/bin/python benchmarks/bench_codegen.py --quick          # a smoke run, nothing written

Three parts, arm by arm (spatial3, puma560, stanford, panda7):

1. armdyn's generated code of the arm as the model gives it (with its friction and motor inertia): the time
   to trace and generate it (Python and C) and to compile it (Numba), its operation counts, and its speed
   beside the compiled recursive kernels, one state through the public call and a batch of 100,000 states;
2. tau's operation count after common-subexpression elimination on a rigid-body copy of the arm (no
   friction, no motor inertia), all counted by one counter, armdyn.symbolic.codegen.count_operations (the
   counter behind ClosedForm.operation_counts): armdyn's generated Python parsed line by line, the
   Toolbox's symbolic RNE and SymPy's Kane method, each peer's expressions put through SymEngine's cse;
3. the peers step by step, each in a subprocess with time limits (the script itself with --peer-worker):
   the time to derive tau, the time of the elimination, the count, and tau evaluated at a random state
   from the counted expressions, against armdyn's inverse_dynamics of the same rigid-body copy.

The peers are built from armdyn's own arm, the same kinematics, masses, centres of mass and inertias:
the Toolbox's DHRobot from the DH rows of the DH arms, and for the Panda (a URDF arm) a modified-DH
DHRobot whose rows come from armdyn's body frames; Kane's method from the body frames of the packed model
(every joint about or along its own z axis), one function for any arm. Symbolic q, qd, qdd; numeric
parameters. The Toolbox runs twice per arm: with the twists that are multiples of pi/2 given exactly (as
armdyn's tracer folds their sines and cosines) and with the floats the model holds. For the Panda, part 3
adds the Toolbox's Robot.rne on links made from the same body frames and on its own import of the URDF,
and part 3's notes Pinocchio's rnea of the URDF as a third party.

Prints Markdown tables and writes the same to results_codegen.md (timing and tables are
benchmarks/harness.py's); --arm and --quick runs write nothing.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import re
import sys
import sysconfig
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numba
import numpy as np
import symengine as se
import sympy
from harness import (
    Candidate,
    Report,
    Table,
    arguments,
    check,
    describe,
    emit,
    measure,
    parse,
    ratio,
    relative_error,
    run_worker,
    seconds,
    timed_step,
    us,
    version,
    wall,
)

import armdyn as ad
from armdyn.dynamics.packed import (
    FIRST_MOMENT,
    GRAVITY,
    HEADER,
    INERTIA,
    KIND,
    MASS,
    PARENT,
    POSITION,
    PRISMATIC_KIND,
    ROTATION,
    STRIDE,
)
from armdyn.symbolic import generate_code
from armdyn.symbolic.codegen import count_operations  # the counter behind ClosedForm.operation_counts

# ----- settings -------------------------------------------------------------------------------
CALLS, REPEATS = 2000, 15  # one state: calls per timed loop, timed loops per candidate
BATCH, BATCH_REPEATS = 100_000, 5  # batch: states, timed calls per candidate
TOLERANCE = 1e-12  # generated code vs kernel, relative to the largest entry
AGREE = 1e-9  # a peer's tau agrees with armdyn's below this relative error
SNAP = 1e-13  # a number within SNAP of 0 or +-1 is that number exactly, as armdyn's tracer folds it
SEED = 20240611
IMPORT_TIMEOUT = 120.0  # seconds for a worker to import its library
DERIVE_TIMEOUT = 900.0  # seconds for a peer to derive tau (flag --derive-timeout)
CSE_TIMEOUT = 300.0  # seconds for the elimination, and again for the evaluation (flag --cse-timeout)
WORKER_MEMORY = 8 << 30  # bytes of address space a worker may use
RESULTS = Path(__file__).with_name("results_codegen.md")
QUICK = {"CALLS": 50, "REPEATS": 3, "BATCH": 2000, "BATCH_REPEATS": 2}
QUICK_LIMITS = {"derive_timeout": 60.0, "cse_timeout": 30.0}  # --quick: at the most
SHARE = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share"  # example-robot-data's files
PANDA = SHARE / "example-robot-data/robots/panda_description/urdf/panda.urdf"
LOCKED = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}  # the Panda's fingers, locked
Symbols = tuple[tuple[sympy.Symbol, ...], tuple[sympy.Symbol, ...], tuple[sympy.Symbol, ...]]


# ----- the arms -------------------------------------------------------------------------------
def spatial3() -> ad.Robot:
    """A 3-joint spatial arm whose DH twists are the floats pi/2 and -pi/2."""
    rows = [
        dict(a=0.1, alpha=np.pi / 2, d=0.3, mass=1.0, com=[0.0, 0.05, 0.0], inertia=[0.01, 0.02, 0.015]),
        dict(a=0.4, alpha=0.0, mass=2.0, com=[-0.2, 0.0, 0.0], inertia=[0.01, 0.05, 0.05]),
        dict(a=0.0, alpha=-np.pi / 2, d=0.1, mass=0.5, com=[0.0, 0.0, 0.02], inertia=[0.002, 0.002, 0.001]),
    ]
    return ad.Robot.from_dh(rows, name="spatial3")


def panda7() -> ad.Robot:
    """The Franka Panda of example-robot-data, its fingers locked (merged into link 7), without friction."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(PANDA, locked=LOCKED)
    return arm.without_friction()


ARMS: dict[str, Callable[[], ad.Robot]] = {
    "spatial3": spatial3,
    "puma560": ad.models.puma560,
    "stanford": ad.models.stanford,
    "panda7": panda7,
}


def rigid(arm: ad.Robot) -> ad.Robot:
    """The rigid-body copy the peers are compared on: no motor inertia, no friction."""
    return arm.without_motors().without_friction()


@dataclass(frozen=True)
class Body:
    """One joint of the packed model: its placement in the parent's body frame (the joint about or along
    its own z axis), and the body's mass, centre of mass and inertia about it, in its body frame."""

    parent: int
    prismatic: bool
    rotation: np.ndarray
    position: np.ndarray
    mass: float
    com: np.ndarray
    inertia: np.ndarray


def bodies(arm: ad.Robot) -> list[Body]:
    """The arm's joints and bodies as the packed model holds them (armdyn.dynamics.packed)."""
    result = []
    for i in range(arm.n):
        record = arm.packed[HEADER + STRIDE * i : HEADER + STRIDE * (i + 1)]
        mass, moment = float(record[MASS]), record[FIRST_MOMENT : FIRST_MOMENT + 3]
        xx, xy, xz, yy, yz, zz = record[INERTIA : INERTIA + 6]
        about_origin = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        com = moment / mass if mass > 0 else np.zeros(3)
        about_com = about_origin - mass * (com @ com * np.eye(3) - np.outer(com, com))
        rotation = record[ROTATION : ROTATION + 9].reshape(3, 3)
        prismatic = record[KIND] == PRISMATIC_KIND
        result.append(
            Body(int(record[PARENT]), prismatic, rotation, record[POSITION : POSITION + 3], mass, com, about_com)
        )
    return result


def snapped(x: float) -> float:
    """x, or exactly 0, 1 or -1 when within SNAP of one of them."""
    if abs(x) < SNAP:
        return 0.0
    return math.copysign(1.0, x) if abs(abs(x) - 1.0) < SNAP else float(x)


def angle(x: float, exact: bool) -> object:
    """An angle for the Toolbox: with ``exact``, a multiple of pi/2 within SNAP as SymPy's exact k pi/2."""
    quarter = round(x / (math.pi / 2))
    if exact and abs(x - quarter * math.pi / 2) < SNAP:
        return sympy.pi * quarter / 2
    return float(x)


def joint_symbols(n: int) -> Symbols:
    """Plain SymPy symbols q_i, qd_i, qdd_i."""
    return tuple(tuple(sympy.symbols(f"{name}_0:{n}")) for name in ("q", "qd", "qdd"))  # type: ignore[return-value]


# ----- counting and evaluating ----------------------------------------------------------------
def _converted(expr: sympy.Basic, args: list[se.Basic]) -> se.Basic:
    """One SymPy node as SymEngine, its arguments converted already; a float of integer value becomes that
    integer (1.0 x is x)."""
    if expr.is_Symbol:
        return se.Symbol(expr.name)
    if expr.is_Float:
        value = float(expr)
        return se.Integer(int(value)) if value.is_integer() else se.RealDouble(value)
    if expr.is_Rational:
        return se.Integer(int(expr.p)) / se.Integer(int(expr.q))
    if expr is sympy.pi:
        return se.pi
    build = {sympy.Add: se.Add, sympy.Mul: se.Mul, sympy.Pow: se.Pow, sympy.sin: se.sin, sympy.cos: se.cos}
    if expr.func not in build:
        raise TypeError(f"no SymEngine counterpart for {expr.func.__name__}")
    return build[expr.func](*args)


def to_symengine(exprs: Sequence[object]) -> list[se.Basic]:
    """SymPy expressions as SymEngine ones, each shared subexpression converted once (se.sympify walks the
    tree, which for a recursion's unexpanded output is exponentially larger than the expression graph)."""
    roots = [sympy.sympify(x) for x in exprs]
    done: dict[sympy.Basic, se.Basic] = {}
    for root in roots:
        stack = [root]
        while stack:
            expr = stack[-1]
            if expr in done:
                stack.pop()
                continue
            pending = [a for a in expr.args if a not in done]
            if pending:
                stack.extend(pending)
                continue
            stack.pop()
            done[expr] = _converted(expr, [done[a] for a in expr.args])
    return [done[root] for root in roots]


def eliminated(exprs: Sequence[object]) -> tuple[list[tuple[se.Symbol, se.Basic]], list[se.Basic]]:
    """SymEngine's common-subexpression elimination of SymPy expressions: (replacements, reduced)."""
    replacements, reduced = se.cse(to_symengine(exprs))
    return list(replacements), list(reduced)


def eliminated_and_counted(exprs: Sequence[object]) -> tuple[list, list, int]:
    """(replacements, reduced, operations) of SymEngine's elimination of SymPy expressions."""
    replacements, reduced = eliminated(exprs)
    return replacements, reduced, operations(replacements, reduced)


def operations(replacements: Sequence[tuple[se.Symbol, se.Basic]], reduced: Sequence[se.Basic]) -> int:
    """Operations of an eliminated form, all replacements and the reduced expressions, as armdyn counts."""
    return sum(count_operations(x) for _, x in replacements) + sum(count_operations(x) for x in reduced)


FUNCTIONS = {"sin": math.sin, "cos": math.cos}


def value(expr: se.Basic, known: dict[str, float]) -> float:
    """A SymEngine expression evaluated in doubles, ``known`` giving its symbols' values by name."""
    if not expr.free_symbols:
        return float(expr)
    if expr.is_Symbol:
        return known[str(expr)]
    args = [value(a, known) for a in expr.args]
    if expr.is_Add:
        return math.fsum(args)
    if expr.is_Mul:
        return math.prod(args)
    if expr.is_Pow:
        return args[0] ** args[1]
    return FUNCTIONS[type(expr).__name__](*args)


def evaluate(
    program: Sequence[tuple[se.Symbol, se.Basic]], outputs: Sequence[se.Basic], state: list[float], n: int
) -> list[float]:
    """The outputs of straight-line code (assignments in order) at ``state`` = q, qd, qdd."""
    names = [f"{name}_{i}" for name in ("q", "qd", "qdd") for i in range(n)]
    known = dict(zip(names, state, strict=True))
    for symbol, expr in program:
        known[str(symbol)] = value(expr, known)
    return [value(x, known) for x in outputs]


ASSIGNMENT = re.compile(r"^    (x\d+) = (.+)$")
INPUT = re.compile(r"\b(q|qd|qdd)\[(\d+)\]")


def parsed_python(source: str) -> tuple[list[tuple[se.Symbol, se.Basic]], list[se.Basic]]:
    """armdyn's generated Python of tau as (assignments, outputs) in SymEngine, each ``xk = ...`` line one
    assignment whose ``xk`` stays a symbol."""
    program, outputs = [], []
    for line in source.split("\ndef ", 2)[1].splitlines()[1:]:
        text = INPUT.sub(r"\1_\2", line).replace("math.", "")
        assignment = ASSIGNMENT.match(text)
        if assignment:
            program.append((se.Symbol(assignment[1]), se.sympify(assignment[2])))
        elif text.startswith("    out["):
            outputs.append(se.sympify(text.split(" = ", 1)[1]))
    return program, outputs


# ----- the peers (run in workers) ---------------------------------------------------------------
def toolbox_dh(arm: ad.Robot, symbols: Symbols, exact: bool) -> list[object]:
    """The Toolbox's symbolic RNE (DHRobot.rne, which takes rne_python for symbols) of a standard-DH arm,
    the robot built from the arm's DH rows and link inertials."""
    import roboticstoolbox as rtb

    if arm.dh is None or arm.dh["convention"] != "standard" or not np.allclose(arm.base, np.eye(4)):
        raise ValueError(f"{arm.name}: not a standard-DH arm on an identity base")
    links = []
    for row, link in zip(arm.dh["rows"], arm.links, strict=True):
        body = link.inertial
        common = dict(
            a=row["a"],
            alpha=angle(row["alpha"], exact),
            m=body.mass,
            r=np.asarray(body.com, float),
            I=np.asarray(body.inertia, float),
            Jm=0.0,
            G=1.0,
            B=0.0,
            Tc=[0.0, 0.0],
        )
        if row["kind"] == "revolute":
            links.append(rtb.RevoluteDH(d=row["d"], offset=angle(row["theta"], exact), **common))
        else:
            links.append(rtb.PrismaticDH(theta=angle(row["theta"], exact), offset=row["d"], **common))
    robot = rtb.DHRobot(links, name=arm.name)
    return list(np.ravel(robot.rne(*symbols, gravity=arm.gravity)))


def modified_dh(body: Body, exact: bool) -> tuple[float, float, float, float]:
    """(alpha, a, theta, d) of a placement Rx(alpha) Tx(a) Tz(d) Rz(theta); ValueError for any other."""
    R = np.vectorize(snapped)(body.rotation) if exact else body.rotation
    p = np.vectorize(snapped)(body.position) if exact else body.position
    alpha, theta = math.atan2(-R[1, 2], R[2, 2]), math.atan2(-R[0, 1], R[0, 0])
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    a, d = p[0], -p[1] * sa + p[2] * ca
    a, d = (snapped(a), snapped(d)) if exact else (a, d)
    rebuilt = np.array([[ct, -st, 0.0], [ca * st, ca * ct, -sa], [sa * st, sa * ct, ca]])
    if not (np.allclose(rebuilt, R, rtol=0, atol=1e-12) and np.allclose([a, -d * sa, d * ca], p, rtol=0, atol=1e-12)):
        raise ValueError("a joint placement that modified DH cannot describe")
    return alpha, a, theta, d


def toolbox_mdh(arm: ad.Robot, symbols: Symbols, exact: bool) -> list[object]:
    """The Toolbox's symbolic RNE of a modified-DH DHRobot whose rows are read off armdyn's body frames
    (each body frame is then the link's modified-DH frame, so the inertials carry over unchanged)."""
    import roboticstoolbox as rtb

    links = []
    for body in bodies(arm):
        if body.parent != len(links) - 1:
            raise ValueError(f"{arm.name}: not a serial chain")
        alpha, a, theta, d = modified_dh(body, exact)
        common = dict(
            a=a, alpha=angle(alpha, exact), m=body.mass, r=body.com, I=body.inertia, Jm=0.0, G=1.0, B=0.0, Tc=[0.0, 0.0]
        )
        if body.prismatic:
            links.append(rtb.PrismaticMDH(theta=angle(theta, exact), offset=d, **common))
        else:
            links.append(rtb.RevoluteMDH(d=d, offset=angle(theta, exact), **common))
    robot = rtb.DHRobot(links, name=arm.name)
    return list(np.ravel(robot.rne(*symbols, gravity=arm.gravity)))


def toolbox_ets(arm: ad.Robot, symbols: Symbols) -> list[object]:
    """The Toolbox's Robot.rne(symbolic=True) of a Robot whose links are armdyn's body frames: per link the
    fixed placement, then Rz(q) or tz(q) (entries within SNAP of 0 or +-1 made exact)."""
    import roboticstoolbox as rtb
    from spatialmath import SE3

    links: list = []
    for body in bodies(arm):
        placement = np.eye(4)
        placement[:3, :3], placement[:3, 3] = np.vectorize(snapped)(body.rotation), np.vectorize(snapped)(body.position)
        ets = rtb.ET.SE3(SE3(placement, check=False)) * (rtb.ET.tz() if body.prismatic else rtb.ET.Rz())
        parent = links[body.parent] if body.parent >= 0 else None
        links.append(
            rtb.Link(
                ets,
                name=f"link{len(links)}",
                parent=parent,
                m=body.mass,
                r=body.com,
                I=body.inertia,
                Jm=0.0,
                G=1.0,
                B=0.0,
                Tc=[0.0, 0.0],
            )
        )
    robot = rtb.Robot(links, name=arm.name)
    q, qd, qdd = (np.array(x, dtype=object) for x in symbols)
    return list(np.ravel(robot.rne(q, qd, qdd, symbolic=True, gravity=arm.gravity)))


def toolbox_urdf(arm: ad.Robot, symbols: Symbols) -> list[object]:
    """The Toolbox's Robot.rne(symbolic=True) of its own import of the Panda's URDF (the fingers are joints
    there: held at their locked values, at rest); tau of the arm's joints."""
    import roboticstoolbox as rtb
    import xacrodoc.packages

    xacrodoc.packages.update_package_cache({"example-robot-data": str(PANDA.parents[3])})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = rtb.Robot.URDF(str(PANDA))
    fingers = list(LOCKED.values())
    rest = [0.0] * len(fingers)
    q, qd, qdd = (np.array([*x, *extra], dtype=object) for x, extra in zip(symbols, (fingers, rest, rest), strict=True))
    return list(np.ravel(robot.rne(q, qd, qdd, symbolic=True, gravity=arm.gravity)))[: arm.n]


def exact_number(x: float) -> sympy.Expr:
    """A model number for SymPy: within SNAP of 0 or +-1 that integer, otherwise the float."""
    x = snapped(x)
    return sympy.Integer(int(x)) if x in (0.0, 1.0, -1.0) else sympy.Float(x)


def vector(frame: object, values: Sequence[float]) -> object:
    """The vector of components ``values`` (exact where within SNAP of 0 or +-1) in ``frame``."""
    return sum(exact_number(v) * e for v, e in zip(values, (frame.x, frame.y, frame.z), strict=True))


def kane(arm: ad.Robot, symbols: Symbols) -> list[object]:
    """tau = M(q) qdd - forcing(q, qd) of SymPy's KanesMethod for any armdyn arm, built from the packed
    model's body frames: per joint a frame fixed in the parent's body frame (the placement), the body's frame
    turned about (or its origin moved along) that frame's z axis, the body's mass and inertia at its centre
    of mass, and gravity on it."""
    from sympy.physics import mechanics as me

    n = arm.n
    q, u = me.dynamicsymbols(f"q0:{n}"), me.dynamicsymbols(f"u0:{n}")
    world, origin = me.ReferenceFrame("N"), me.Point("O")
    origin.set_vel(world, 0)
    gravity = vector(world, arm.packed[GRAVITY : GRAVITY + 3])
    frames, origins, rigid_bodies, loads = [], [], [], []
    for i, body in enumerate(bodies(arm)):
        parent, at = (world, origin) if body.parent < 0 else (frames[body.parent], origins[body.parent])
        frame, point = kane_joint(i, body, parent, at, world, q[i], u[i])
        frames.append(frame)
        origins.append(point)
        centre = point.locatenew(f"C{i}", vector(frame, body.com))
        centre.v2pt_theory(point, world, frame)
        I = [exact_number(x) for x in body.inertia.ravel()]
        dyadic = me.inertia(frame, I[0], I[4], I[8], I[1], I[5], I[2])
        mass = exact_number(body.mass)
        rigid_bodies.append(me.RigidBody(f"body{i}", centre, frame, mass, (dyadic, centre)))
        loads.append((centre, mass * gravity))
    method = me.KanesMethod(world, q_ind=q, u_ind=u, kd_eqs=[qi.diff() - ui for qi, ui in zip(q, u, strict=True)])
    method.kanes_equations(rigid_bodies, loads)
    accelerations = [ui.diff() for ui in u]
    tau = method.mass_matrix * sympy.Matrix(accelerations) - method.forcing
    plain = {}
    for plain_symbols, dynamic in zip(symbols, (q, u, accelerations), strict=True):
        plain.update(zip(dynamic, plain_symbols, strict=True))
    return [x.xreplace(plain) for x in tau]


def kane_joint(i: int, body: Body, parent: object, at: object, world: object, q: object, u: object) -> tuple:
    """(body frame, body origin) of joint i, with their velocities in the world frame."""
    from sympy.physics import mechanics as me

    joint = me.ReferenceFrame(f"J{i}")
    joint.orient_explicit(parent, sympy.Matrix(3, 3, [exact_number(x) for x in body.rotation.ravel()]))
    offset = vector(parent, body.position)
    if body.prismatic:
        point = at.locatenew(f"O{i}", offset + q * joint.z)
        point.set_vel(parent, u * joint.z)
        point.v1pt_theory(at, world, parent)
        return joint, point
    frame = me.ReferenceFrame(f"B{i}")
    frame.orient_axis(joint, joint.z, q)
    frame.set_ang_vel(joint, u * joint.z)
    point = at.locatenew(f"O{i}", offset)
    point.v2pt_theory(at, world, parent)
    return frame, point


@dataclass(frozen=True)
class Peer:
    """A way to derive tau symbolically: its label, the module it needs, and the derivation."""

    label: str
    module: str
    derive: Callable[[ad.Robot, Symbols], list[object]]


PEERS = {
    "toolbox": Peer("Toolbox DHRobot.rne", "roboticstoolbox", partial(toolbox_dh, exact=True)),
    "toolbox-float": Peer("Toolbox DHRobot.rne, float twists", "roboticstoolbox", partial(toolbox_dh, exact=False)),
    "toolbox-mdh": Peer("Toolbox DHRobot.rne (modified DH)", "roboticstoolbox", partial(toolbox_mdh, exact=True)),
    "toolbox-mdh-float": Peer(
        "Toolbox DHRobot.rne (modified DH), float twists", "roboticstoolbox", partial(toolbox_mdh, exact=False)
    ),
    "toolbox-ets": Peer("Toolbox Robot.rne, links from armdyn's body frames", "roboticstoolbox", toolbox_ets),
    "toolbox-urdf": Peer("Toolbox Robot.rne, its own URDF import", "roboticstoolbox", toolbox_urdf),
    "kane": Peer("SymPy KanesMethod", "sympy.physics.mechanics", kane),
}


EXTRA_PEERS = {"panda7": ("toolbox-ets", "toolbox-urdf")}  # further Toolbox routes, part 3 only


def peers_for(name: str, arm: ad.Robot) -> dict[str, str]:
    """The peers run on an arm, by the column of part 2 they fill (the extra ones by their own key)."""
    if arm.dh is not None and arm.dh["convention"] == "standard":
        chosen = {"toolbox": "toolbox", "toolbox-float": "toolbox-float", "kane": "kane"}
    else:
        chosen = {"toolbox": "toolbox-mdh", "toolbox-float": "toolbox-mdh-float", "kane": "kane"}
    return chosen | {key: key for key in EXTRA_PEERS.get(name, ())}


def peer_worker(task: str, state: list[float]) -> None:
    """Runs in a subprocess (``task`` = "arm:peer"): derives tau, eliminates common subexpressions, counts,
    and evaluates the counted form at ``state``; one event per finished step."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (WORKER_MEMORY, WORKER_MEMORY))
    arm_name, key = task.split(":")
    peer = PEERS[key]
    emit("import", seconds=timed_step("import", partial(importlib.import_module, peer.module))[1])
    arm = rigid(ARMS[arm_name]())
    symbols = joint_symbols(arm.n)
    tau, derive_s = timed_step("derive", lambda: peer.derive(arm, symbols))
    emit("derive", seconds=derive_s)
    (replacements, reduced, count), cse_s = timed_step("cse", partial(eliminated_and_counted, tau))
    emit("cse", seconds=cse_s, operations=count, replacements=len(replacements))
    values, check_s = timed_step("check", lambda: evaluate(replacements, reduced, state, arm.n))
    emit("check", seconds=check_s, values=values)


# ----- the run --------------------------------------------------------------------------------
@dataclass
class ArmdynCounts:
    """armdyn's tau of the rigid-body copy: trace seconds, operation_counts, the same code parsed and counted
    by count_operations, its two-operand subtractions, and its evaluation."""

    trace_s: float
    counts: dict[str, int]
    assignments: int
    parsed: int
    subtractions: int
    evaluate_s: float
    error: float


def extras(arm: ad.Robot) -> str:
    """What the arm carries beyond its rigid bodies: motor inertia, viscous and Coulomb friction."""
    carried = {
        "motor inertia": np.any(arm.reflected_inertia),
        "viscous friction": np.any(arm.viscous_friction),
        "Coulomb friction": np.any(arm.coulomb_friction),
    }
    return ", ".join(name for name, present in carried.items() if present) or "none"


def generated(name: str, arm: ad.Robot, rng: np.random.Generator) -> tuple[list[str], int]:
    """Part 1: armdyn's generated code of the arm as the model gives it, beside the kernels; the row and
    tau's operation count."""
    code, generate_s = wall(partial(generate_code, arm))
    sources_s = wall(lambda: (code.python(), code.c()))[1]
    compiled, compile_s = wall(code.compile)
    counts = code.operation_counts()
    tau = counts["tau"]
    q, qd, qdd = rng.uniform(-1, 1, (3, arm.n))
    Q, QD, QDD = rng.uniform(-1, 1, (3, BATCH, arm.n))
    check(f"{name} tau", compiled.tau(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd), TOLERANCE)
    check(f"{name} M", compiled.M(q), arm.inertia_matrix(q), TOLERANCE)
    check(f"{name} batch tau", compiled.tau(Q, QD, QDD), arm.inverse_dynamics(Q, QD, QDD), TOLERANCE, dims=1)
    one = partial(Candidate, calls=CALLS, repeats=REPEATS)
    tau_us, kernel_us, m_us, kernel_m_us = measure(
        one(partial(compiled.tau, q, qd, qdd)),
        one(partial(arm.inverse_dynamics, q, qd, qdd)),
        one(partial(compiled.M, q)),
        one(partial(arm.inertia_matrix, q)),
    )
    batch = partial(Candidate, repeats=BATCH_REPEATS, states=BATCH)
    batch_us, kernel_batch_us = measure(
        batch(partial(compiled.tau, Q, QD, QDD)), batch(partial(arm.inverse_dynamics, Q, QD, QDD))
    )
    row = [
        name,
        str(arm.n),
        extras(arm),
        seconds(generate_s + sources_s),
        seconds(compile_s),
        f"{tau['total']:,} ({tau['multiplications']:,}, {tau['additions']:,}, {tau['calls']:,})",
        f"{counts['M']['total']:,}",
        f"{us(tau_us)} / {us(kernel_us)} = {ratio(tau_us / kernel_us)}",
        f"{us(m_us)} / {us(kernel_m_us)} = {ratio(m_us / kernel_m_us)}",
        f"{us(batch_us)} / {us(kernel_batch_us)} = {ratio(batch_us / kernel_batch_us)}",
    ]
    return row, tau["total"]


SUBTRACTION = re.compile(r"^    x\d+ = \S+ - [A-Za-z_]", re.MULTILINE)  # x - y of two variables or inputs


def armdyn_counts(arm: ad.Robot, state: list[float]) -> ArmdynCounts:
    """Part 2 for armdyn: tau of the rigid-body copy, counted both ways and evaluated from the parsed code."""
    code, trace_s = wall(partial(generate_code, arm, ["tau"]))
    source = code.python()
    program, outputs = parsed_python(source)
    values, evaluate_s = wall(partial(evaluate, program, outputs, state, arm.n))
    q, qd, qdd = np.reshape(state, (3, arm.n))
    return ArmdynCounts(
        trace_s,
        code.operation_counts()["tau"],
        len(program),
        operations(program, outputs),
        len(SUBTRACTION.findall(source)),
        evaluate_s,
        relative_error(values, arm.inverse_dynamics(q, qd, qdd)),
    )


def pinocchio_error(arm: ad.Robot, state: list[float]) -> float:
    """Pinocchio's rnea of the Panda's URDF, the fingers locked as panda7() locks them, against armdyn's tau of
    the rigid-body copy ``arm``: a third party on the URDF (gravity as armdyn's)."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(PANDA))
    locked = [model.getJointId(joint) for joint in LOCKED]
    q0 = pin.neutral(model)
    for joint, position in zip(locked, LOCKED.values(), strict=True):
        q0[model.joints[joint].idx_q] = position
    reduced = pin.buildReducedModel(model, locked, q0)
    reduced.gravity.linear[:] = arm.gravity
    q, qd, qdd = np.reshape(state, (3, arm.n))
    return relative_error(pin.rnea(reduced, reduced.createData(), q, qd, qdd), arm.inverse_dynamics(q, qd, qdd))


def run_peer(arm_name: str, key: str, state: list[float], args: argparse.Namespace) -> dict[str, dict]:
    """One peer on one arm in a worker (harness.run_worker), each step within its limit."""
    command = [sys.executable, __file__, "--peer-worker", f"{arm_name}:{key}", "--state", json.dumps(state)]
    phases = [
        ("import", IMPORT_TIMEOUT),
        ("derive", args.derive_timeout),
        ("cse", args.cse_timeout),
        ("check", args.cse_timeout),
    ]
    return run_worker(command, phases)


def outcome(result: dict) -> str:
    """A step's seconds, or what stopped it."""
    if "timeout" in result:
        return f"timeout ({result['timeout']:.0f} s)"
    if "error" in result:
        return "failed"
    if "skipped" in result:
        return "-"
    return seconds(result["seconds"])


def peer_error(result: dict[str, dict], reference: np.ndarray) -> float | None:
    """The relative error of a peer's evaluated tau against armdyn's, None when it did not get that far."""
    values = result["check"].get("values")
    return None if values is None else relative_error(values, reference)


def operations_cell(result: dict[str, dict], reference: np.ndarray) -> str:
    """Part 2's cell of a peer: its count (marked when its tau was not checked or disagrees), "timeout" or
    "failed"."""
    if "operations" not in result["cse"]:
        return "timeout" if any("timeout" in event for event in result.values()) else "failed"
    error = peer_error(result, reference)
    mark = " (not checked)" if error is None else " (tau disagrees)" if error > AGREE else ""
    return f"{result['cse']['operations']:,}{mark}"


def failures(arm_name: str, label: str, result: dict[str, dict]) -> list[str]:
    """Notes for the steps of a peer that failed."""
    return [f"{arm_name}, {label}, {step}: {event['error']}" for step, event in result.items() if "error" in event]


@dataclass
class Tables:
    """The run's tables, filled arm by arm."""

    generated: Table
    counts: Table
    steps: Table
    counter: Table


def new_tables() -> Tables:
    """The run's four tables, empty."""
    return Tables(
        Table(
            "1. armdyn's generated code, arms as the models give them",
            [
                "arm",
                "n",
                "beyond rigid bodies",
                "trace + generate s",
                "compile s",
                "tau ops (mul, add, calls)",
                "M ops",
                "tau one state us: generated / kernel = ratio",
                "M one state us: generated / kernel = ratio",
                f"tau batch of {BATCH:,}, us per state: generated / kernel = ratio",
            ],
        ),
        Table(
            "2. tau's operations after common-subexpression elimination, rigid-body arms, one counter",
            [
                "arm",
                "armdyn, arm as given (operation_counts)",
                "armdyn (operation_counts: mul, add, calls)",
                "armdyn (count_operations)",
                "Toolbox RNE",
                "Toolbox RNE, float twists",
                "SymPy Kane",
                "Toolbox / armdyn",
                "Kane / armdyn",
            ],
        ),
        Table(
            "3. Deriving tau, step by step (rigid-body arms; peers in subprocesses)",
            [
                "arm",
                "method",
                "derive s",
                "CSE s",
                "replacements",
                "tau ops",
                "evaluate s",
                "relative error vs armdyn's inverse_dynamics",
            ],
            left=2,
        ),
        Table(
            "2b. The counter on armdyn's own generated Python (rigid-body arms)",
            [
                "arm",
                "assignments",
                "operation_counts total",
                "count_operations of the parsed lines",
                "two-operand subtractions",
                "difference",
            ],
        ),
    )


def measure_arm(name: str, args: argparse.Namespace, rng: np.random.Generator, tables: Tables) -> list[str]:
    """All three parts for one arm, rows added to ``tables``; returns notes on failed peer steps."""
    arm = ARMS[name]()
    row, default_total = generated(name, arm, rng)
    tables.generated.rows.append(row)
    copy = rigid(arm)
    state = [float(x) for x in rng.uniform(-1, 1, 3 * arm.n)]
    q, qd, qdd = np.reshape(state, (3, arm.n))
    reference = copy.inverse_dynamics(q, qd, qdd)
    ours = armdyn_counts(copy, state)
    print(f"  {name}: generated code measured; armdyn's tau {ours.parsed:,} operations", flush=True)
    tables.counter.rows.append(counter_row(name, ours))
    tables.steps.rows.append(
        [
            name,
            "armdyn generate_code(arm, ['tau'])",
            seconds(ours.trace_s),
            "-",
            f"{ours.assignments:,}",
            f"{ours.parsed:,}",
            seconds(ours.evaluate_s),
            f"{ours.error:.1e}",
        ]
    )
    cells, notes = {}, []
    for column, key in peers_for(name, arm).items():
        peer = PEERS[key]
        if args.skip_toolbox and peer.module == "roboticstoolbox":
            cells[column] = "not run"
            continue
        print(f"  {name}: {peer.label} ...", flush=True)
        result = run_peer(name, key, state, args)
        cells[column] = operations_cell(result, reference)
        tables.steps.rows.append(step_row(name, peer.label, result, reference))
        notes += failures(name, peer.label, result)
    tables.counts.rows.append(counts_row(name, default_total, ours, cells))
    if name == "panda7":
        error = pinocchio_error(copy, state)
        notes.append(
            f"panda7: Pinocchio's rnea of the same URDF, fingers locked at 0.02 m (buildReducedModel), against "
            f"armdyn's inverse_dynamics at the same state: relative error {error:.1e}."
        )
    return notes


def step_row(name: str, label: str, result: dict[str, dict], reference: np.ndarray) -> list[str]:
    """Part 3's row of one peer."""
    cse = result["cse"]
    error = peer_error(result, reference)
    verdict = "-" if error is None else f"{error:.1e}" + ("" if error <= AGREE else " (disagrees)")
    return [
        name,
        label,
        outcome(result["derive"]),
        outcome(cse),
        f"{cse['replacements']:,}" if "replacements" in cse else "-",
        f"{cse['operations']:,}" if "operations" in cse else "-",
        outcome(result["check"]),
        verdict,
    ]


def counts_row(name: str, default_total: int, ours: ArmdynCounts, cells: dict[str, str]) -> list[str]:
    """Part 2's row of one arm."""
    c = ours.counts

    def against(column: str) -> str:
        count = cells.get(column, "-").split(" ")[0].replace(",", "")
        return ratio(int(count) / ours.parsed) if count.isdigit() else "-"

    return [
        name,
        f"{default_total:,}",
        f"{c['total']:,} ({c['multiplications']:,}, {c['additions']:,}, {c['calls']:,})",
        f"{ours.parsed:,}",
        cells.get("toolbox", "-"),
        cells.get("toolbox-float", "-"),
        cells.get("kane", "-"),
        against("toolbox"),
        against("kane"),
    ]


def counter_row(name: str, ours: ArmdynCounts) -> list[str]:
    """Part 2b's row: count_operations on the parsed code against operation_counts."""
    difference = ours.parsed - ours.counts["total"]
    explained = "= the subtractions" if difference == ours.subtractions else "NOT the subtractions"
    return [
        name,
        f"{ours.assignments:,}",
        f"{ours.counts['total']:,}",
        f"{ours.parsed:,}",
        f"{ours.subtractions:,}",
        f"{difference:+,} ({explained})",
    ]


def header(source: tuple[str, str], args: argparse.Namespace) -> list[str]:
    """The report's first lines."""
    toolbox = "skipped (--skip-toolbox)" if args.skip_toolbox else version("roboticstoolbox-python")
    versions = {
        "sympy": sympy.__version__,
        "symengine": se.__version__,
        "numba": numba.__version__,
        "numpy": np.__version__,
        "roboticstoolbox": toolbox,
        "spatialmath": version("spatialmath-python"),
    }
    return describe(source, versions) + [
        f"Evaluation times are medians: one state {CALLS} calls x {REPEATS} repeats, a batch of {BATCH:,} states "
        f"{BATCH_REPEATS} repeats; generated code and kernel interleaved, checked to agree (to {TOLERANCE:g} "
        "relative to the largest entry) before timing.",
        f"Peer limits: derive {args.derive_timeout:.0f} s (--derive-timeout), elimination and evaluation "
        f"{args.cse_timeout:.0f} s each (--cse-timeout), address space {WORKER_MEMORY >> 30} GiB per worker.",
    ]


NOTES_GENERATED = [
    "trace + generate: generate_code(arm) (tau, M, G, N) plus python() and c(); compile: code.compile() "
    "(Numba). The ratios are generated code time / kernel time (below 1: the generated code is faster); "
    "the kernels are arm.inverse_dynamics and arm.inertia_matrix, the batch both Numba-parallel over states.",
]
NOTES_COUNTS = [
    "Rigid-body copies: arm.without_motors().without_friction(). 'armdyn, arm as given' is tau's "
    "operation_counts total for the arm of table 1, with what it carries beyond rigid bodies (none for "
    "spatial3 and panda7: there the two armdyn figures are of the same code).",
    "One counter for all (armdyn.symbolic.codegen.count_operations): k - 1 operations per k-term sum or "
    "product, one per function call, |p| - 1 (at least 1) per integer power p, summed over every replacement "
    "and reduced expression of SymEngine's cse. A subtraction x - y is a sum with a product (-1) y: two "
    "operations where operation_counts counts one (table 2b). armdyn (count_operations) is armdyn's "
    "generated Python parsed line by line into SymEngine, each xk kept a symbol: the like-with-like figure.",
    "Toolbox RNE: its symbolic rne (rne_python): the DH arms as DHRobot from their DH rows, the Panda as a "
    "modified-DH DHRobot from armdyn's body frames; twists and angle offsets within 1e-13 of a multiple of "
    "pi/2 given as SymPy's exact multiples of pi (cos 0 and 1 exact, as armdyn's tracer folds them). Float "
    "twists: the same with the angles as the floats the model holds (cos(pi/2) = 6.1e-17 stays in).",
    "SymPy Kane: KanesMethod built from the packed model's body frames (one function for any arm), numbers "
    "within 1e-13 of 0 or +-1 made exact; tau = mass_matrix qdd - forcing.",
    "Peers' SymPy expressions go to SymEngine node by node (each shared subexpression once; a float of "
    "integer value becomes that integer), then se.cse. Ratios: the peer's count / armdyn (count_operations).",
]
NOTES_STEPS = [
    "derive: from armdyn's arm to SymPy expressions of tau (building the Toolbox robot or the Kane model "
    "included, importing the library not); CSE: conversion to SymEngine, se.cse and counting; replacements: "
    "the eliminated subexpressions (armdyn: the assignments of its generated code, numbered while traced).",
    "evaluate: the counted form evaluated in doubles at one random state (armdyn: its parsed Python), compared "
    "with inverse_dynamics of the same rigid-body copy, relative to the largest entry.",
    "Toolbox DHRobot.rne (modified DH): the Panda's rows read off armdyn's body frames (the column 'Toolbox "
    "RNE' of part 2). Toolbox Robot.rne, links from armdyn's body frames: the Toolbox's other RNE (spatial "
    "vectors, Robot.rne(symbolic=True)) on links made of each joint's fixed placement followed by Rz(q).",
    "Toolbox Robot.rne, its own URDF import: rtb.Robot.URDF of the same panda.urdf, where the fingers are "
    "prismatic joints, held at 0.02 m and at rest. Its tau differs from armdyn's and Pinocchio's (below) by "
    "about 1e-3; with the fingers' masses set to zero in the URDF it agreed with armdyn's to 5e-16 when this "
    "benchmark was written (not re-run here): the difference comes with the finger bodies, which hang off the "
    "fixed link panda_hand.",
]
NOTES_COUNTER = [
    "difference = count_operations of the parsed lines - operation_counts total; operation_counts counts a "
    "subtraction x - y once, count_operations twice (a sum and a product by -1); negation -x is one operation "
    "for both, and x - 0.5 parses as a sum with a constant, one operation for both.",
]


def show(report: Report, table: Table) -> None:
    """Print a table as Markdown and keep it for the results file."""
    report.tables.append(table)
    print(table.markdown(), flush=True)


def main() -> None:
    parser = arguments(__doc__, skip_toolbox="leave out the Robotics Toolbox's columns")
    parser.add_argument("--arm", choices=list(ARMS), action="append", help="run this arm only (repeatable)")
    parser.add_argument("--derive-timeout", type=float, default=DERIVE_TIMEOUT, help="seconds for a peer's tau")
    parser.add_argument("--cse-timeout", type=float, default=CSE_TIMEOUT, help="seconds for its cse, its check")
    parser.add_argument("--peer-worker", help=argparse.SUPPRESS)
    args = parse(parser, "peer_worker", lambda args: peer_worker(args.peer_worker, json.loads(args.state)))
    title = "armdyn generated code beside the Robotics Toolbox's symbolic RNE and SymPy's Kane method"
    report = Report.begin(args, title, None if args.arm else RESULTS, globals(), QUICK, QUICK_LIMITS)
    report.note(*header(report.source, args), end="\n\n")
    rng = np.random.default_rng(SEED)
    tables, notes = new_tables(), []
    for name in args.arm or ARMS:
        notes += measure_arm(name, args, rng, tables)
    tables.generated.notes, tables.counts.notes = NOTES_GENERATED, NOTES_COUNTS
    tables.steps.notes, tables.counter.notes = NOTES_STEPS + notes, NOTES_COUNTER
    for table in (tables.generated, tables.counts, tables.counter, tables.steps):
        show(report, table)
    report.finish("the workers may have run another version than this process.")


if __name__ == "__main__":
    main()
