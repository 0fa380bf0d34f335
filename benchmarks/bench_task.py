"""armdyn's task-space dynamics side by side with the Robotics Toolbox (PUMA 560) and Pinocchio (PUMA 560, Panda).

    .venv/bin/python benchmarks/bench_task.py      # or: make bench

The task is the tool's full 6-D pose, y = [p; phi] with the rate ydot = [v; w] (armdyn's ToolPose: the
tool point's velocity and the tool's angular velocity, both in world axes). Four parts, in this one process:

1. equality, PUMA 560: the Toolbox's operational-space calls inertia_x, coriolis_x, gravload_x and
   accel_x against armdyn's task_inertia, task_coriolis, task_gravity and task_forward_dynamics at random
   well-conditioned states, first with the Toolbox's geometric Jacobian (representation=None: the same
   quantities as armdyn's), then with its default analytical Jacobian (representation="rpy/xyz": the same
   dynamics in other orientation coordinates);
2. timing, PUMA 560: those four pairs, one state per call and a batch of 1,000 states (armdyn's batched
   call against a Python loop over the Toolbox's one-state call);
3. timing, Lambda = (J M^-1 J^T)^-1 at one state: armdyn's operational_space (and, for the square PUMA,
   task_inertia) against a dense construction from Pinocchio's crba and frame Jacobian with NumPy, and on
   the Panda against Pinocchio's Delassus-matrix routines for a 6-D constraint on the same frame;
4. the targets: each ratio above against its goal.

Before anything is timed, armdyn's result is checked against the peer's on the same inputs (relative to the
largest entry, 1e-8), so a ratio never compares two different computations; a peer whose result is wrong
is timed but flagged. Times are medians over repeats, the candidates' repeats interleaved (the timing,
checking and tables are benchmarks/harness.py's). Prints plain tables and writes the same as Markdown to
results_task.md; --quick is a smoke run with few repeats and small batches that writes nothing.
"""

from __future__ import annotations

import dataclasses
import sysconfig
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

# armdyn first: it sets OMP_WAIT_POLICY=PASSIVE (unless set) before pinocchio loads the OpenMP runtime
# (see bench_dynamics.py).
import armdyn as ad

# isort: split
import numba
import numpy as np
import pinocchio as pin
from harness import (
    Candidate,
    Report,
    Table,
    arguments,
    check,
    describe,
    measure,
    ratio,
    relative_error,
    sci,
    us,
    wall,
)

from armdyn import task_space as ts

try:
    import roboticstoolbox as rtb
    from spatialmath.base import rotvelxform, tr2rpy
except Exception as error:  # an optional peer: its parts are skipped, the rest still runs
    rtb = None
    TOOLBOX_MISSING = f"{type(error).__name__}: {error}"
else:
    TOOLBOX_MISSING = ""

# ----- settings -------------------------------------------------------------------------------
CALLS, REPEATS = 500, 9  # armdyn, one state: calls per timed loop, timed loops
TOOLBOX_CALLS, TOOLBOX_REPEATS = 50, 9  # the Toolbox, one state; its coriolis_x is much slower (below)
TOOLBOX_CORIOLIS_CALLS = 10
PIN_CALLS = 2000  # Pinocchio, one state (timed loops: REPEATS)
BATCH, BATCH_REPEATS = 1000, 15  # armdyn's batched call: states, timed calls
TOOLBOX_BATCH_REPEATS = 3  # timed Python loops over BATCH states of the Toolbox's one-state call
CHECK_STATES = 20  # random states checked before timing (the first is the one timed)
MAX_CONDITION = 100.0  # states drawn until cond J is below this (well away from the PUMA's singularities)
MIN_COS_PITCH = 0.2  # and the RPY angles are away from their own singularity (pitch = +-90 degrees)
TOLERANCE = 1e-8
DELASSUS_MU = 1e-6  # the damping of computeDampedDelassusMatrixInverse (its benchmarks' value)
REPRESENTATION = "rpy/xyz"  # the Toolbox's default orientation coordinates
SEED = 20240612
TARGETS = {"toolbox": 100.0, "delassus": 2.0, "dense": 5.0}
RESULTS = Path(__file__).with_name("results_task.md")
QUICK = {  # --quick: the same parts, small
    "CALLS": 20,
    "REPEATS": 3,
    "TOOLBOX_CALLS": 3,
    "TOOLBOX_REPEATS": 2,
    "TOOLBOX_CORIOLIS_CALLS": 1,
    "PIN_CALLS": 50,
    "BATCH": 50,
    "BATCH_REPEATS": 3,
    "TOOLBOX_BATCH_REPEATS": 1,
    "CHECK_STATES": 4,
}

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
PANDA = ROBOTS / "panda_description" / "urdf" / "panda.urdf"
PANDA_LOCKED = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}  # the fingers, locked (7 joints)
POSE = ts.ToolPose()
OPERATIONAL = "armdyn operational_space(arm, ToolPose(), q, qd)"
LAMBDA_ONLY = "armdyn operational_inertia(arm, ToolPose(), q)"
DENSE = "Pinocchio dense: crba + computeFrameJacobian (LWA) + NumPy solve, inv"


# ----- states ---------------------------------------------------------------------------------
@dataclass
class States:
    """Random states (B, n) away from singularities, with the task velocity J qd and a task force."""

    q: np.ndarray
    qd: np.ndarray
    f: np.ndarray
    ydot: np.ndarray

    @classmethod
    def draw(cls, arm: ad.Robot, rng: np.random.Generator, count: int, rpy: bool = False) -> States:
        """``count`` states with cond J < MAX_CONDITION; with ``rpy`` also away from the singularity of the
        tool's roll-pitch-yaw angles (the Toolbox's default orientation coordinates)."""
        q = np.empty((0, arm.n))
        while len(q) < count:
            x = rng.uniform(-1.0, 1.0, (2 * count, arm.n))
            keep = ts.condition_number(arm, POSE, x) < MAX_CONDITION
            if rpy:
                pitch = np.array([tr2rpy(pose, order="xyz")[1] for pose in arm.tool_pose(x)])
                keep &= np.cos(pitch) > MIN_COS_PITCH
            q = np.concatenate([q, x[keep]])
        q = q[:count]
        qd, f = rng.uniform(-1.0, 1.0, (2, count, arm.n))
        return cls(q, qd, f, np.einsum("bij,bj->bi", arm.jacobian(q, "base"), qd))

    def one(self, i: int = 0) -> dict[str, np.ndarray]:
        return {"q": self.q[i], "qd": self.qd[i], "f": self.f[i], "ydot": self.ydot[i]}


# ----- 1. the PUMA 560 against the Toolbox: the same quantities ---------------------------------
@dataclass(frozen=True)
class Pair:
    """An armdyn task-space function and the Toolbox call that computes the same quantity."""

    name: str  # armdyn's
    toolbox: str  # the Toolbox's method
    ours: Callable[[ad.Robot, dict], np.ndarray]  # (arm, states) -> result; states one (n,) or a batch (B, n)
    theirs: Callable[[object, dict, object], np.ndarray]  # (robot, one state, representation) -> result


PAIRS = [
    Pair(
        "task_inertia",
        "inertia_x",
        lambda arm, s: ts.task_inertia(arm, POSE, s["q"]),
        lambda robot, s, rep: robot.inertia_x(s["q"], representation=rep),
    ),
    Pair(
        "task_coriolis",
        "coriolis_x",
        lambda arm, s: ts.task_coriolis(arm, POSE, s["q"], s["qd"]),
        lambda robot, s, rep: robot.coriolis_x(s["q"], s["qd"], representation=rep),
    ),
    Pair(
        "task_gravity",
        "gravload_x",
        lambda arm, s: ts.task_gravity(arm, POSE, s["q"]),
        lambda robot, s, rep: robot.gravload_x(s["q"], representation=rep),
    ),
    Pair(
        "task_forward_dynamics",
        "accel_x",
        lambda arm, s: ts.task_forward_dynamics(arm, POSE, s["q"], s["qd"], s["f"]),
        lambda robot, s, rep: robot.accel_x(s["q"], s["ydot"], s["f"], representation=rep),
    ),
]


def rpy_rates(arm: ad.Robot, q: np.ndarray) -> np.ndarray:
    """T(q), 6x6, with [pdot; gammadot] = T [v; w]: gamma the tool's roll-pitch-yaw angles (xyz)."""
    gamma = tr2rpy(arm.tool_pose(q), order="xyz")
    return rotvelxform(gamma, representation=REPRESENTATION, inverse=True, full=True)


def rpy_rates_dot(arm: ad.Robot, q: np.ndarray, qd: np.ndarray, h: float = 1e-3) -> np.ndarray:
    """dT/dt along (q, qd): central differences in time, Richardson-extrapolated (error ~h^4)."""

    def central(step: float) -> np.ndarray:
        return (rpy_rates(arm, q + step * qd) - rpy_rates(arm, q - step * qd)) / (2 * step)

    return (4 * central(h / 2) - central(h)) / 3


def in_rpy_rates(arm: ad.Robot, s: dict) -> dict[str, Callable[[], np.ndarray]]:
    """armdyn's quantities carried to the Toolbox's default coordinates: ydot_a = T ydot, f = T^T f_a, so
    Mbar_a = T^-T Mbar T^-1, Gbar_a = T^-T Gbar, Vmbar_a = T^-T (Vmbar - Mbar T^-1 Tdot) T^-1 and
    yddot_a = T yddot + Tdot ydot (the Toolbox's accel_x takes ydot_a and f_a)."""
    q, qd = s["q"], s["qd"]
    T = rpy_rates(arm, q)
    Ti = np.linalg.inv(T)
    Tdot = rpy_rates_dot(arm, q, qd)
    Mbar = ts.task_inertia(arm, POSE, q)

    def accel() -> np.ndarray:
        yddot = ts.task_forward_dynamics(arm, POSE, q, qd, T.T @ s["f"])
        return T @ yddot + Tdot @ s["ydot"]

    return {
        "task_inertia": lambda: Ti.T @ Mbar @ Ti,
        "task_coriolis": lambda: Ti.T @ (ts.task_coriolis(arm, POSE, q, qd) - Mbar @ Ti @ Tdot) @ Ti,
        "task_gravity": lambda: Ti.T @ ts.task_gravity(arm, POSE, q),
        "task_forward_dynamics": accel,
    }


def toolbox_default_state(arm: ad.Robot, s: dict) -> dict[str, np.ndarray]:
    """The state in the Toolbox's default coordinates: ydot_a = T ydot; the force f_a is the same numbers."""
    return {**s, "ydot": rpy_rates(arm, s["q"]) @ s["ydot"]}


JOINT_SPACE = {  # armdyn method -> (Toolbox method, state arguments)
    "inertia_matrix": ("inertia", ("q",)),
    "coriolis_matrix": ("coriolis", ("q", "qd")),
    "gravity_vector": ("gravload", ("q",)),
    "forward_dynamics": ("accel", ("q", "qd", "f")),
}


def equality(arm: ad.Robot, robot: object, states: States) -> list[list[str]]:
    """Rows: the largest relative difference over the states, for the joint-space terms (the two models),
    the task-space pairs with the geometric Jacobian (checked), and with the Toolbox's default."""
    rows = []
    singles = [states.one(i) for i in range(len(states.q))]
    for name, (method, names) in JOINT_SPACE.items():
        error = max(
            check(
                f"PUMA 560 {name}: armdyn vs the Toolbox's {method}",
                getattr(arm, name)(*(s[k] for k in names)),
                getattr(robot, method)(*(s[k] for k in names)),
                TOLERANCE,
            )
            for s in singles
        )
        rows.append(["joint space", name, f"puma.{method}(...)", sci(error), "the same model: checked"])
    for pair in PAIRS:
        error = max(
            check(
                f"PUMA 560 {pair.name}: armdyn vs {pair.toolbox}(representation=None)",
                pair.ours(arm, s),
                pair.theirs(robot, s, None),
                TOLERANCE,
            )
            for s in singles
        )
        call = f"puma.{pair.toolbox}(..., representation=None)"
        rows.append(["geometric J", pair.name, call, sci(error), "the same quantity: checked"])
    for pair in PAIRS:
        direct, converted = 0.0, 0.0
        for s in singles:
            theirs = pair.theirs(robot, toolbox_default_state(arm, s), REPRESENTATION)
            direct = max(direct, relative_error(pair.ours(arm, s), theirs))
            converted = max(converted, relative_error(in_rpy_rates(arm, s)[pair.name](), theirs))
        call = f'puma.{pair.toolbox}(...) (representation="{REPRESENTATION}")'
        rows.append(["default", pair.name, call, sci(direct), f"{sci(converted)} after carrying armdyn's to RPY rates"])
    return rows


# ----- 2. the PUMA 560 against the Toolbox: time --------------------------------------------------
def _toolbox_loop(pair: Pair, robot: object, singles: list[dict]) -> None:
    for s in singles:
        pair.theirs(robot, s, None)


def toolbox_timing(arm: ad.Robot, robot: object, rng: np.random.Generator) -> tuple[list[list[str]], dict]:
    """Rows: one state and a batch, armdyn against the Toolbox, per pair; and the ratios by pair."""
    one = States.draw(arm, rng, 1).one()
    batch = States.draw(arm, rng, BATCH)
    arrays = {"q": batch.q, "qd": batch.qd, "f": batch.f}
    singles = [batch.one(i) for i in range(BATCH)]
    rows, ratios = [], {}
    for pair in PAIRS:
        ours_batch = pair.ours(arm, arrays)
        for i in range(0, BATCH, max(BATCH // CHECK_STATES, 1)):
            check(
                f"PUMA 560 {pair.name}, batch state {i}", ours_batch[i], pair.theirs(robot, singles[i], None), TOLERANCE
            )
        calls = TOOLBOX_CORIOLIS_CALLS if pair.toolbox == "coriolis_x" else TOOLBOX_CALLS
        ours, theirs = measure(
            Candidate(partial(pair.ours, arm, one), CALLS, REPEATS),
            Candidate(partial(pair.theirs, robot, one, None), calls, TOOLBOX_REPEATS),
        )
        ours_many, theirs_many = measure(
            Candidate(partial(pair.ours, arm, arrays), 1, BATCH_REPEATS, BATCH),
            Candidate(partial(_toolbox_loop, pair, robot, singles), 1, TOOLBOX_BATCH_REPEATS, BATCH),
        )
        ratios[pair.name] = (theirs / ours, theirs_many / ours_many)
        rows.append(
            [
                pair.name,
                f"puma.{pair.toolbox}",
                us(ours),
                us(theirs),
                ratio(theirs / ours),
                us(ours_many),
                us(theirs_many),
                ratio(theirs_many / ours_many),
            ]
        )
    return rows, ratios


# ----- 3. Lambda against Pinocchio ----------------------------------------------------------------
def pinocchio_model(arm: ad.Robot) -> tuple[pin.Model, int]:
    """A Pinocchio model of an armdyn chain (joints, bodies, gravity, motor inertia as armature) and the
    id of a frame at armdyn's tool.

    armdyn's link frame is T_parent @ placement @ motion(q) @ frame_offset; Pinocchio's joint frame is put
    after the motion, so a joint sits at frame_offset(parent) @ placement in its parent's joint frame, and
    a body's inertia (given in its link frame) at frame_offset in its own."""
    model = pin.Model()
    model.gravity = pin.Motion(np.array(arm.gravity, dtype=float), np.zeros(3))
    ids: list[int] = []
    for link in arm.links:
        joint = link.joint
        before = np.array(arm.base if link.parent < 0 else arm.links[link.parent].joint.frame_offset, dtype=float)
        axis = np.array(joint.axis, dtype=float)
        kind = pin.JointModelRevoluteUnaligned if joint.is_revolute else pin.JointModelPrismaticUnaligned
        parent = 0 if link.parent < 0 else ids[link.parent]
        placement = pin.SE3(before @ np.array(joint.placement, dtype=float))
        ids.append(model.addJoint(parent, kind(axis), placement, joint.name))
        body = link.inertial
        inertia = pin.Inertia(float(body.mass), np.array(body.com, dtype=float), np.array(body.inertia, dtype=float))
        model.appendBodyToJoint(ids[-1], inertia, pin.SE3(np.array(joint.frame_offset, dtype=float)))
    model.armature = np.array(arm.reflected_inertia, dtype=float)
    carrier = arm.tool_link
    tool = np.array(arm.links[carrier].joint.frame_offset, dtype=float) @ np.array(arm.tool, dtype=float)
    frame = model.addFrame(pin.Frame("tool", ids[carrier], 0, pin.SE3(tool), pin.FrameType.OP_FRAME))
    return model, frame


def panda() -> tuple[ad.Robot, pin.Model, int]:
    """The Panda with its fingers locked (7 joints) in both libraries, and Pinocchio's frame at armdyn's
    tool (of the frames there, the last: the body frame of the right finger)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the mimic finger joint loads as an independent joint
        arm = ad.load_urdf(PANDA, locked=PANDA_LOCKED).without_friction()
    full = pin.buildModelFromUrdf(str(PANDA))
    q_lock = pin.neutral(full)
    for name, value in PANDA_LOCKED.items():
        q_lock[full.joints[full.getJointId(name)].idx_q] = value
    model = pin.buildReducedModel(full, [full.getJointId(name) for name in PANDA_LOCKED], q_lock)
    if arm.joint_names != list(model.names)[1:]:
        raise AssertionError("Panda: Pinocchio's joints are not armdyn's, in the same order")
    data, q = model.createData(), np.linspace(-0.5, 0.5, arm.n)
    pin.framesForwardKinematics(model, data, q)
    tool = arm.tool_pose(q)
    frames = [k for k in range(model.nframes) if relative_error(tool, data.oMf[k].homogeneous) <= 1e-12]
    if not frames:
        raise AssertionError("Panda: no Pinocchio frame at armdyn's tool")
    return arm, model, frames[-1]


def dense_lambda(model: pin.Model, data: pin.Data, frame: int, q: np.ndarray) -> np.ndarray:
    """Lambda = (J M^-1 J^T)^-1 in world axes: crba, the frame Jacobian (LOCAL_WORLD_ALIGNED), NumPy."""
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    J = pin.computeFrameJacobian(model, data, q, frame, pin.LOCAL_WORLD_ALIGNED)
    return np.linalg.inv(J @ np.linalg.solve(M, J.T))


def delassus_lambda(model: pin.Model, data: pin.Data, q: np.ndarray, constraints: tuple) -> np.ndarray:
    """Lambda in the frame's own axes: the inverse of Pinocchio's Delassus matrix J M^-1 J^T."""
    return np.linalg.inv(pin.computeDelassusMatrix(model, data, q, *constraints))


def frame_constraint(model: pin.Model, frame: int) -> tuple:
    """(models, datas) of a 6-D rigid constraint on the frame, in its LOCAL axes."""
    placed = model.frames[frame]
    constraint = pin.RigidConstraintModel(
        pin.ContactType.CONTACT_6D, model, placed.parentJoint, placed.placement, pin.ReferenceFrame.LOCAL
    )
    models, datas = pin.StdVec_RigidConstraintModel(), pin.StdVec_RigidConstraintData()
    models.append(constraint)
    datas.append(constraint.createData())
    return models, datas


def local_axes(arm: ad.Robot, q: np.ndarray, Lambda: np.ndarray) -> np.ndarray:
    """A world-axes 6x6 task matrix in the tool's own axes: X Lambda X^T, X = diag(R^T, R^T)."""
    R = arm.tool_pose(q)[:3, :3]
    X = np.zeros((6, 6))
    X[:3, :3] = X[3:, 3:] = R.T
    return X @ Lambda @ X.T


def operational_lambda(arm: ad.Robot, s: dict) -> ts.OperationalSpace:
    return ts.operational_space(arm, POSE, s["q"], s["qd"])


@dataclass(frozen=True)
class Route:
    """A computation of Lambda at one state: ``call(s)`` gives its zero-argument call, ``result(s)`` its
    Lambda in world axes, or in the tool's own axes (``local``), damped by DELASSUS_MU (``damped``)."""

    call: Callable[[dict], Callable[[], object]]
    result: Callable[[dict], np.ndarray]
    calls: int
    local: bool = False
    damped: bool = False


def reference(arm: ad.Robot, route: Route, s: dict) -> np.ndarray:
    """armdyn's Lambda in the route's axes, damped as the route is."""
    if route.damped:  # (J M^-1 J^T + mu I)^-1 at every state
        space = ts.operational_space(arm, POSE, s["q"], s["qd"], damping=DELASSUS_MU**0.5, max_condition=1.0)
    else:
        space = operational_lambda(arm, s)
    return local_axes(arm, s["q"], space.Lambda) if route.local else space.Lambda


def lambda_rows(
    robot: str, arm: ad.Robot, model: pin.Model, frame: int, rng: np.random.Generator, delassus: bool
) -> tuple[list[list[str]], dict]:
    """Rows: armdyn's one-state operational_space (and task_inertia for a square task) against Pinocchio's
    routes to Lambda, each checked against armdyn's operational_space first; and the times by label."""
    data = model.createData()
    ours = OPERATIONAL
    routes = {
        ours: Route(lambda s: partial(operational_lambda, arm, s), lambda s: operational_lambda(arm, s).Lambda, CALLS),
    }
    if hasattr(ts, "operational_inertia"):  # Lambda alone
        routes[LAMBDA_ONLY] = Route(
            lambda s: partial(ts.operational_inertia, arm, POSE, s["q"]),
            lambda s: ts.operational_inertia(arm, POSE, s["q"]),
            CALLS,
        )
    if arm.n == 6:
        routes["armdyn task_inertia(arm, ToolPose(), q)"] = Route(
            lambda s: partial(ts.task_inertia, arm, POSE, s["q"]), lambda s: ts.task_inertia(arm, POSE, s["q"]), CALLS
        )
    dense = partial(dense_lambda, model, data, frame)
    routes[DENSE] = Route(lambda s: partial(dense, s["q"]), lambda s: dense(s["q"]), PIN_CALLS)
    if delassus:
        constraints = frame_constraint(model, frame)
        inverse = partial(delassus_lambda, model, data, constraints=constraints)
        routes["Pinocchio computeDelassusMatrix (6-D, LOCAL) + NumPy inv"] = Route(
            lambda s: partial(inverse, s["q"]), lambda s: inverse(s["q"]), PIN_CALLS, local=True
        )

        def damped(q: np.ndarray) -> np.ndarray:
            return pin.computeDampedDelassusMatrixInverse(model, data, q, *constraints, DELASSUS_MU)

        routes[f"Pinocchio computeDampedDelassusMatrixInverse (6-D, LOCAL, mu={DELASSUS_MU:g})"] = Route(
            lambda s: partial(damped, s["q"]), lambda s: damped(s["q"]), PIN_CALLS, local=True, damped=True
        )
    states = States.draw(arm, rng, CHECK_STATES)
    singles = [states.one(i) for i in range(CHECK_STATES)]
    errors, wrong, notes = {}, {}, []
    for label, route in routes.items():
        errors[label] = max(relative_error(route.result(s), reference(arm, route, s)) for s in singles)
        if not errors[label] <= TOLERANCE:
            scalar = all(np.allclose(route.result(s), np.eye(6) / DELASSUS_MU, rtol=1e-12, atol=0) for s in singles)
            wrong[label] = "returns (1/mu) I at every state" if scalar else f"differs by {errors[label]:.1e}"
            notes.append(f"{robot}: {label} {wrong[label]}; timed, but it is not Lambda.")
    one = singles[0]
    labels = list(routes)
    candidates = [Candidate(routes[label].call(one), routes[label].calls, REPEATS) for label in labels]
    times = dict(zip(labels, measure(*candidates), strict=True))
    batch = States.draw(arm, rng, BATCH)
    batch_time = measure(
        Candidate(partial(ts.operational_space, arm, POSE, batch.q, batch.qd), 1, BATCH_REPEATS, BATCH)
    )[0]
    rows = []
    for label in labels:
        status = f"wrong: {wrong[label]}" if label in wrong else "checked"
        error = "-" if label == ours else sci(errors[label])
        rows.append([robot, label, us(times[label]), ratio(times[ours] / times[label]), error, status])
    rows.append([robot, f"armdyn operational_space, a batch of {BATCH:,} (per state)", us(batch_time), "", "", ""])
    return rows, {"times": times, "wrong": wrong, "notes": notes}


# ----- the run ----------------------------------------------------------------------------------
def header(source: tuple[str, str]) -> list[str]:
    toolbox = rtb.__version__ if rtb else f"not available ({TOOLBOX_MISSING})"
    versions = {"numba": numba.__version__, "numpy": np.__version__, "pinocchio": pin.__version__}
    versions["roboticstoolbox"] = toolbox
    return describe(source, versions) + [
        f"Every time is a median: one state armdyn {CALLS} calls x {REPEATS} repeats (Toolbox {TOOLBOX_CALLS} x "
        f"{TOOLBOX_REPEATS}, its coriolis_x {TOOLBOX_CORIOLIS_CALLS} x {TOOLBOX_REPEATS}; Pinocchio {PIN_CALLS} x "
        f"{REPEATS}), batch of {BATCH:,} states armdyn {BATCH_REPEATS} repeats, the Toolbox's loop "
        f"{TOOLBOX_BATCH_REPEATS}; the candidates' repeats are interleaved. armdyn and the peer are checked to "
        f"agree (to {TOLERANCE:g} relative) on {CHECK_STATES} random states before timing, states drawn with "
        f"cond J < {MAX_CONDITION:g}.",
    ]


def verdict(value: float, goal: float, at_least: bool) -> str:
    met = value >= goal if at_least else value <= goal
    return "met" if met else "not met"


def main() -> None:
    args = arguments(__doc__).parse_args()
    report = Report.begin(args, "armdyn task-space dynamics benchmarks", RESULTS, globals(), QUICK)
    rng = np.random.default_rng(SEED)
    report.note(*header(report.source))
    puma = ad.models.puma560()
    robot = rtb.models.DH.Puma560() if rtb else None
    targets = Table("4. Targets", ["what", "goal", "value", "status"], left=1)

    def warm_up() -> None:
        states = States.draw(puma, rng, 2)
        for s in (states.one(), {"q": states.q, "qd": states.qd, "f": states.f}):
            for pair in PAIRS:
                pair.ours(puma, s)
            operational_lambda(puma, s)

    elapsed = wall(warm_up)[1]
    report.note(
        f"armdyn's first calls in this process (compile or load machine code, untimed): {elapsed:.1f} s", end="\n\n"
    )

    if robot is None:
        report.note(f"The Robotics Toolbox is not available ({TOOLBOX_MISSING}): parts 1 and 2 skipped.", end="\n\n")
    else:
        first = States.draw(puma, rng, CHECK_STATES, rpy=True)
        same = Table(
            f"1. PUMA 560, 6-D tool pose: armdyn against the Toolbox (largest relative difference over {CHECK_STATES} "
            "states)",
            ["Toolbox Jacobian", "armdyn", "Toolbox", "difference", "note"],
            equality(puma, robot, first),
            notes=[
                "The models: armdyn's models.puma560() and the Toolbox's DH.Puma560() are the same arm (Armstrong/"
                "Corke): gravity [0, 0, -9.81], motor inertia G^2 Jm on the diagonal of M in both, and viscous and "
                "Coulomb friction in both; the joint-space rows check that, so nothing is removed or aligned.",
                "Difference: max |armdyn - Toolbox| / max |Toolbox| per state, the largest over the states.",
                "armdyn's ToolPose is the twist [v; w], both in world axes: v the tool point's velocity, w the angular "
                "velocity (Khatib's generalized coordinates). With representation=None the Toolbox uses its geometric "
                "Jacobian jacob0 (the same [v; w] in world axes) and jacob0_dot from its Hessian hessian0: the same "
                "quantities, agreeing to rounding. coriolis_x is the matrix J^-T C J^-1 - Mx Jdot J^-1, armdyn's "
                "task_coriolis Vmbar (not Vmbar ydot), and takes (q, qd); accel_x takes the task velocity ydot = J qd "
                "(it solves qd = J^-1 ydot) and the wrench f, and includes friction and gravity, like armdyn's "
                "task_forward_dynamics(arm, ToolPose(), q, qd, f).",
                f'The Toolbox\'s default, representation="{REPRESENTATION}", is not wrong but another quantity: its '
                "analytical Jacobian Ja = T J takes the orientation rows to roll-pitch-yaw angle rates (T = "
                "diag(I, A(gamma)), A from spatialmath's rotvelxform), so inertia_x is T^-T Mbar T^-1, gravload_x "
                "T^-T Gbar, coriolis_x T^-T (Vmbar - Mbar T^-1 Tdot) T^-1, and accel_x(q, T ydot, f_a) is "
                "T yddot + Tdot ydot, yddot armdyn's under the wrench T^T f_a. The last column compares the Toolbox "
                "with armdyn's results carried there (Tdot by Richardson-extrapolated central differences in time): "
                "inertia_x and gravload_x agree to rounding; coriolis_x and accel_x only to 1e-9 to 1e-7, because "
                "with a representation the Toolbox's jacob0_dot is a first-order forward difference of Ja "
                "(spatialmath numhess, step 1e-8), exact only "
                "for representation=None.",
            ],
            left=3,
        )
        report.show(same)
        timing_rows, ratios = toolbox_timing(puma, robot, rng)
        report.show(
            Table(
                "2. PUMA 560, 6-D tool pose: time, armdyn against the Toolbox (microseconds per state)",
                [
                    "armdyn",
                    "Toolbox (representation=None)",
                    "armdyn 1 state",
                    "Toolbox 1 state",
                    "Toolbox/armdyn",
                    f"armdyn batch of {BATCH:,}",
                    f"Toolbox loop of {BATCH:,}",
                    "Toolbox/armdyn",
                ],
                timing_rows,
                notes=[
                    "Toolbox/armdyn > 1: armdyn is faster. One state: one call each. Batch: armdyn's one call on "
                    f"({BATCH:,}, 6) arrays, per state, against a Python loop of the Toolbox's one-state call over "
                    "the same states (its own trajectory form, (m, 6) arrays, is the same loop inside).",
                    "accel_x is given the task velocity J qd of each state, computed beforehand (untimed).",
                ],
                left=2,
            )
        )
        for name, (single, many) in ratios.items():
            goal = TARGETS["toolbox"]
            targets.rows.append(
                [f"PUMA {name}, one state: Toolbox/armdyn", f">= {goal:g}", ratio(single), verdict(single, goal, True)]
            )
            targets.rows.append(
                [f"PUMA {name}, batch: Toolbox/armdyn", f">= {goal:g}", ratio(many), verdict(many, goal, True)]
            )

    lambdas = Table(
        "3. Lambda = (J M^-1 J^T)^-1 of the 6-D tool pose, one state (microseconds per call)",
        ["robot", "computation", "us", "armdyn operational_space/this", "difference", "check"],
        left=2,
    )
    puma_model, puma_frame = pinocchio_model(puma)
    data = puma_model.createData()
    joint_check = States.draw(puma, rng, CHECK_STATES)
    for i in range(CHECK_STATES):
        q = joint_check.q[i]
        M = pin.crba(puma_model, data, q)
        check("PUMA 560: pin.crba vs armdyn", np.triu(M) + np.triu(M, 1).T, puma.inertia_matrix(q), TOLERANCE)
        pin.framesForwardKinematics(puma_model, data, q)
        check(
            "PUMA 560: Pinocchio's tool frame vs armdyn's", data.oMf[puma_frame].homogeneous, puma.tool_pose(q), 1e-12
        )
    rows, puma_results = lambda_rows("PUMA 560", puma, puma_model, puma_frame, rng, delassus=False)
    lambdas.rows += rows
    arm, model, frame = panda()
    rows, panda_results = lambda_rows("Panda", arm, model, frame, rng, delassus=True)
    lambdas.rows += rows
    lambdas.notes += [
        "armdyn operational_space/this > 1: this is faster than armdyn's one-state operational_space, which "
        "computes all of Khatib's quantities (its OperationalSpace: "
        + ", ".join(field.name for field in dataclasses.fields(ts.OperationalSpace))
        + "), not Lambda alone"
        + ("; operational_inertia computes Lambda alone." if hasattr(ts, "operational_inertia") else "."),
        "Difference: the largest relative difference from armdyn's Lambda over the checked states (in the tool's "
        "own axes, X Lambda X^T with X = diag(R^T, R^T), for Pinocchio's LOCAL constraint; for the damped "
        "inverse, from armdyn's damped Lambda = (J M^-1 J^T + mu I)^-1: operational_space with damping = "
        "sqrt(mu) and max_condition = 1).",
        "PUMA 560 in Pinocchio: a model built joint by joint from armdyn's puma560() (its DH frames, masses, "
        "inertias, gravity; motor inertia G^2 Jm as model.armature, which crba adds), checked against armdyn's M "
        "and tool pose. Panda: the URDF in both, fingers locked at 0.02 m (pin.buildReducedModel, armdyn's "
        "load_urdf(locked=...)), 7 joints; Pinocchio's frame at armdyn's tool: "
        f"'{model.frames[frame].name}'.",
        "The dense route symmetrizes crba's upper triangle, then Lambda = inv(J @ solve(M, J.T)).",
        *puma_results["notes"],
        *panda_results["notes"],
    ]
    if any("I/mu" in text for text in panda_results["wrong"].values()):
        lambdas.notes.append(
            "computeDampedDelassusMatrixInverse from Python: the binding calls the C++ function with its default "
            "Pv=true (the PV-OSIMr passes), which needs pinocchio::initPvDelassus(model, data, constraints) on the "
            "Data first; pinocchio's Python module does not expose that, so the Data's constraint bookkeeping stays "
            "empty, the Delassus part comes out zero and the result is (1/mu) I. Its time is that of an incomplete "
            "computation; computeDelassusMatrix (the EFPA passes, no initialisation needed) plus a 6x6 inverse is "
            "the working Delassus route."
        )
    report.show(lambdas)

    times, wrong = panda_results["times"], panda_results["wrong"]
    for ours in (label for label in (OPERATIONAL, LAMBDA_ONLY) if label in times):
        short = ours.split("(")[0]
        for label in (label for label in times if "Delassus" in label):
            value = times[ours] / times[label]
            name = label.split(" (")[0].replace("Pinocchio ", "")
            flag = " (its result is wrong)" if label in wrong else ""
            goal = TARGETS["delassus"]
            targets.rows.append(
                [f"Panda: {short} / {name}{flag}", f"<= {goal:g}", ratio(value), verdict(value, goal, False)]
            )
        value = times[DENSE] / times[ours]
        goal = TARGETS["dense"]
        targets.rows.append(
            [f"Panda: Pinocchio dense / {short}", f">= {goal:g}", ratio(value), verdict(value, goal, True)]
        )
    targets.notes.append("Each value is a ratio of the times in parts 2 and 3; 'status' compares it with the goal.")
    report.show(targets)
    report.finish("the parts ran on the armdyn imported at the start; a later run times the new source.")


if __name__ == "__main__":
    main()
