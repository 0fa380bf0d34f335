"""armdyn's dynamics side by side with Pinocchio (UR5, Panda) and the Robotics Toolbox (PUMA 560).

    .venv/bin/python benchmarks/bench_dynamics.py      # or: make bench

Six parts, the first four in this one process, the last two in fresh interpreters:

1. one state per call: armdyn against pin.rnea / crba / computeGeneralizedGravity /
   computeCoriolisMatrix / aba, and against the Toolbox's rne / inertia / gravload / coriolis / accel;
2. a batch of 100,000 states: armdyn's (B, n) calls against pin.rneaInParallel / abaInParallel
   and against a Python loop over the one-state Pinocchio call;
3. the PUMA 560's Coriolis matrix, one state and a 50-state trajectory, armdyn against the Toolbox;
4. kinematics, one state per call: armdyn's tool_pose / jacobian / jacobian_dot / link_transforms against
   the sequences of Pinocchio calls that give the same (forwardKinematics, computeJointJacobians, ...);
5. thread spin: a single-threaded loop of one-state calls right after a two-thread batch call against the
   same loop after a rest, under armdyn's OpenMP wait policy and under OMP_WAIT_POLICY=ACTIVE;
6. start-up: import + load the UR5's URDF + first inverse dynamics in a fresh interpreter, armdyn with
   its kernel cache filled and empty, against Pinocchio's import + buildModelFromUrdf + first rnea.

Before anything is timed, armdyn's result is checked against the peer's on the same inputs
(relative to the largest entry, 1e-8; the kinematics to 1e-12), so a ratio never compares two
different computations.
Times are medians over repeats; the candidates' repeats are interleaved so that machine noise
hits all of them alike (the timing, checking and tables are benchmarks/harness.py's). Prints plain
tables and writes the same as Markdown to results.md; --quick is a smoke run of every part with
few repeats and small batches, in well under a minute once Numba's cache is filled, and writes nothing.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import sysconfig
import tempfile
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

# armdyn first: it sets OMP_WAIT_POLICY=PASSIVE (unless set) for the OpenMP runtime, which reads it once, when
# it loads; pinocchio loads that same runtime (libgomp) on import, so imported first it would start the runtime
# under its default policy (idle threads spin a few milliseconds) and this process would not run as armdyn's.
import armdyn as ad

# isort: split
import numba
import numpy as np
import pinocchio as pin
from harness import (
    EVENT,
    Candidate,
    Report,
    Table,
    arguments,
    check,
    describe,
    fresh_python,
    measure,
    ms,
    ratio,
    relative_error,
    seconds,
    us,
    wall,
)

try:
    import roboticstoolbox as rtb
except Exception as error:  # an optional peer: its columns are skipped, the rest still runs
    rtb = None
    TOOLBOX_MISSING = f"{type(error).__name__}: {error}"
else:
    TOOLBOX_MISSING = ""

# ----- settings -------------------------------------------------------------------------------
CALLS, REPEATS = 2000, 15  # one state: calls per timed loop, timed loops per candidate
TOOLBOX_CALLS, TOOLBOX_REPEATS = 200, 5  # the Toolbox is slower; its coriolis much slower (below)
TOOLBOX_CORIOLIS_CALLS = 20
BATCH, BATCH_REPEATS = 100_000, 9  # batch: states, timed calls per candidate
LOOP_STATES = 10_000  # a Python loop over the one-state Pinocchio call covers this many states, then is scaled
CHECK_STATES = 200  # batch results checked state by state against the one-state peer call
TRAJECTORY = 50  # states of the PUMA 560 Coriolis trajectory
THREADS = 2  # Pinocchio's *InParallel threads
KINEMATICS_TOLERANCE = 1e-12  # kinematics: armdyn and Pinocchio agree to rounding
KINEMATICS_CHECKS = 20  # kinematics: random states checked before timing (the first is the one timed)
SPIN_CALLS, SPIN_ROUNDS = 2000, 30  # thread spin: one-state calls per timed loop, rounds (medians over them)
SPIN_BATCH, SPIN_REST = 1000, 0.05  # thread spin: states of the batch call before each loop; seconds of rest
SPIN_LIMIT = 300.0  # seconds a thread-spin interpreter may take
STARTUP_RUNS = 3  # fresh interpreters per start-up script
STARTUP_LIMIT = 600.0  # seconds a start-up interpreter may take (an empty kernel cache: compiling)
TOLERANCE = 1e-8
SEED = 20240611
RESULTS = Path(__file__).with_name("results.md")
QUICK = {  # --quick: the same parts, small
    "CALLS": 50,
    "REPEATS": 3,
    "TOOLBOX_CALLS": 5,
    "TOOLBOX_REPEATS": 2,
    "TOOLBOX_CORIOLIS_CALLS": 2,
    "BATCH": 2000,
    "BATCH_REPEATS": 2,
    "LOOP_STATES": 200,
    "CHECK_STATES": 20,
    "KINEMATICS_CHECKS": 5,
    "SPIN_ROUNDS": 5,
    "STARTUP_RUNS": 1,
}

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
URDFS = {
    "UR5": ROBOTS / "ur_description" / "urdf" / "ur5_robot.urdf",
    "Panda": ROBOTS / "panda_description" / "urdf" / "panda.urdf",
}
FUNCTIONS = ("inverse_dynamics", "inertia_matrix", "gravity_vector", "coriolis_matrix", "forward_dynamics")


# ----- the arms ---------------------------------------------------------------------------------
@dataclass
class PinocchioArm:
    """One URDF loaded by both libraries, Pinocchio's joints mapped to armdyn's by name."""

    arm: ad.Robot
    model: pin.Model
    data: pin.Data
    iq: np.ndarray  # armdyn joint j is Pinocchio's q[iq[j]] and v[iv[j]]
    iv: np.ndarray
    pool: pin.ModelPool
    notes: list[str]

    @classmethod
    def load(cls, name: str, path: Path) -> PinocchioArm:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the Panda's mimic finger joint loads as an independent joint
            arm = ad.load_urdf(path)
        model = pin.buildModelFromUrdf(str(path))
        ids = [model.getJointId(joint) for joint in arm.joint_names]
        iq = np.array([model.joints[i].idx_q for i in ids])
        iv = np.array([model.joints[i].idx_v for i in ids])
        if not model.nq == model.nv == arm.n or sorted(iq) != list(range(arm.n)):
            raise AssertionError(f"{name}: Pinocchio's joints (nq {model.nq}, nv {model.nv}) do not map onto armdyn's")
        notes = []
        if np.any(arm.viscous_friction) or np.any(arm.coulomb_friction):
            # Pinocchio reads <dynamics damping friction> into model.damping / model.friction but its
            # rnea and aba never apply them; compare the same equations of motion.
            arm = arm.without_friction()
            notes.append(
                f"{name}: armdyn's arm without friction (arm.without_friction()), since pin.rnea and pin.aba "
                "ignore the URDF's <dynamics damping> that armdyn applies as viscous friction."
            )
        return cls(arm, model, model.createData(), iq, iv, pin.ModelPool(model, THREADS), notes)

    def q(self, x: np.ndarray) -> np.ndarray:
        """armdyn-ordered positions (..., n) in Pinocchio's order (..., nq), C-ordered."""
        result = np.zeros((*x.shape[:-1], self.model.nq))
        result[..., self.iq] = x
        return result

    def v(self, x: np.ndarray) -> np.ndarray:
        result = np.zeros((*x.shape[:-1], self.model.nv))
        result[..., self.iv] = x
        return result

    def vector(self, y: np.ndarray) -> np.ndarray:
        return np.array(y)[self.iv]

    def matrix(self, m: np.ndarray) -> np.ndarray:
        """A Pinocchio (nv, nv) matrix in armdyn's order; crba's is symmetrized from its upper triangle."""
        return np.array(m)[np.ix_(self.iv, self.iv)]

    def symmetric(self, m: np.ndarray) -> np.ndarray:
        upper = np.triu(m)
        return self.matrix(upper + np.triu(upper, 1).T)

    def columns(self, y: np.ndarray) -> np.ndarray:
        """A Pinocchio (nv, B) batch result as armdyn's (B, n)."""
        return np.asarray(y)[self.iv].T

    def jacobian(self, j: np.ndarray) -> np.ndarray:
        """A Pinocchio (6, nv) Jacobian with its columns in armdyn's joint order."""
        return np.asarray(j)[:, self.iv]


def pinocchio_calls(p: PinocchioArm, args: dict[str, tuple]) -> dict[str, tuple[str, Callable, Callable]]:
    """Per armdyn function: (peer label, zero-argument peer call, converter of its result to armdyn's order)."""
    m, d = p.model, p.data
    q, qd, qdd, tau = p.q(args["q"]), p.v(args["qd"]), p.v(args["qdd"]), p.v(args["tau"])
    return {
        "inverse_dynamics": ("pin.rnea", partial(pin.rnea, m, d, q, qd, qdd), p.vector),
        "inertia_matrix": ("pin.crba", partial(pin.crba, m, d, q), p.symmetric),
        "gravity_vector": ("pin.computeGeneralizedGravity", partial(pin.computeGeneralizedGravity, m, d, q), p.vector),
        "coriolis_matrix": ("pin.computeCoriolisMatrix", partial(pin.computeCoriolisMatrix, m, d, q, qd), p.matrix),
        "forward_dynamics": ("pin.aba", partial(pin.aba, m, d, q, qd, tau), p.vector),
    }


def toolbox_calls(puma: object, args: dict[str, tuple]) -> dict[str, tuple[str, Callable, Callable]]:
    q, qd, qdd, tau = args["q"], args["qd"], args["qdd"], args["tau"]
    return {
        "inverse_dynamics": ("puma.rne", partial(puma.rne, q, qd, qdd), np.asarray),
        "inertia_matrix": ("puma.inertia", partial(puma.inertia, q), np.asarray),
        "gravity_vector": ("puma.gravload", partial(puma.gravload, q), np.asarray),
        "coriolis_matrix": ("puma.coriolis", partial(puma.coriolis, q, qd), np.asarray),
        "forward_dynamics": ("puma.accel", partial(puma.accel, q, qd, tau), np.asarray),
    }


def random_state(rng: np.random.Generator, n: int, batch: tuple[int, ...] = ()) -> dict[str, np.ndarray]:
    q, qd, qdd, tau = rng.uniform(-1.0, 1.0, (4, *batch, n))
    return {"q": q, "qd": qd, "qdd": qdd, "tau": tau}


ARGUMENTS = {
    "inverse_dynamics": ("q", "qd", "qdd"),
    "inertia_matrix": ("q",),
    "gravity_vector": ("q",),
    "coriolis_matrix": ("q", "qd"),
    "forward_dynamics": ("q", "qd", "tau"),
}


# ----- 1. one state -----------------------------------------------------------------------------
def one_state(robot: str, arm: ad.Robot, peers: dict, state: dict, peer_timing: dict[str, tuple[int, int]]) -> list:
    """Rows: armdyn (plain and with out=) against the peer, for each function, checked first."""
    rows = []
    for function in FUNCTIONS:
        label, peer, convert = peers[function]
        args = tuple(state[name] for name in ARGUMENTS[function])
        method = getattr(arm, function)
        ours = method(*args)
        check(f"{robot} {function}: armdyn vs {label}", ours, convert(peer()), TOLERANCE)
        out = np.empty_like(ours)
        calls, repeats = peer_timing.get(function, (CALLS, REPEATS))
        plain, with_out, theirs = measure(
            Candidate(partial(method, *args), CALLS, REPEATS),
            Candidate(partial(method, *args, out=out), CALLS, REPEATS),
            Candidate(peer, calls, repeats),
        )
        rows.append([robot, function, label, us(plain), us(with_out), us(theirs), ratio(plain / theirs)])
    return rows


# ----- 2. a batch -------------------------------------------------------------------------------
def _pin_loop(algorithm: Callable, model: pin.Model, data: pin.Data, arrays: Sequence[np.ndarray]) -> None:
    for row in zip(*arrays, strict=True):
        algorithm(model, data, *row)


def batch(robot: str, p: PinocchioArm, rng: np.random.Generator, notes: list[str]) -> list:
    """Rows: microseconds per state of armdyn's (B, n) calls, Pinocchio's parallel calls and a loop over pin."""
    arm, state = p.arm, random_state(rng, p.arm.n, (BATCH,))
    pinned = {"q": p.q(state["q"]), "qd": p.v(state["qd"]), "qdd": p.v(state["qdd"]), "tau": p.v(state["tau"])}
    rows = []
    for function, algorithm in (("inverse_dynamics", "rnea"), ("inertia_matrix", "crba"), ("forward_dynamics", "aba")):
        names = ARGUMENTS[function]
        args, theirs = [state[name] for name in names], [pinned[name] for name in names]
        method, single = getattr(arm, function), getattr(pin, algorithm)
        ours = method(*args)
        convert = p.symmetric if algorithm == "crba" else p.vector
        for i in range(CHECK_STATES):
            check(
                f"{robot} batch {function}: armdyn vs pin.{algorithm}",
                ours[i],
                convert(single(p.model, p.data, *(a[i] for a in theirs))),
                TOLERANCE,
            )
        out = np.empty_like(ours)
        batched = partial(Candidate, calls=1, repeats=BATCH_REPEATS, states=BATCH)
        # label -> (candidate, the armdyn label it is compared with, or None for armdyn itself)
        candidates = {
            f"armdyn {function}({', '.join(n.upper() for n in names)})": (batched(partial(method, *args)), None),
            "armdyn, out=": (batched(partial(method, *args, out=out)), None),
        }
        plain, preallocated = list(candidates)
        parallel = getattr(pin, f"{algorithm}InParallel", None)
        if parallel is None:
            note = f"pinocchio {pin.__version__} has no {algorithm}InParallel: {function} is compared with the loop."
            if note not in notes:
                notes.append(note)
        else:
            columns = [a.T for a in theirs]  # (nq, B) Fortran-ordered views of the (B, nq) arrays: no copy
            check(
                f"{robot} batch {function}: armdyn vs pin.{algorithm}InParallel",
                ours,
                p.columns(parallel(THREADS, p.pool, *columns)),
                TOLERANCE,
            )
            target = np.empty((p.model.nv, BATCH), order="F")
            parallel(THREADS, p.pool, *columns, target)
            what = f"{robot} batch {function}: armdyn vs pin.{algorithm}InParallel(out)"
            check(what, ours, p.columns(target), TOLERANCE)
            call = partial(parallel, THREADS, p.pool, *columns)
            candidates[f"pin.{algorithm}InParallel({THREADS}, pool, ...)"] = (batched(call), plain)
            candidates[f"pin.{algorithm}InParallel(..., out)"] = (batched(partial(call, target)), preallocated)
        loop = partial(_pin_loop, single, p.model, p.data, [a[:LOOP_STATES] for a in theirs])
        looped = Candidate(loop, calls=1, repeats=BATCH_REPEATS, states=LOOP_STATES)
        candidates[f"loop over pin.{algorithm} ({LOOP_STATES:,} states, scaled)"] = (looped, plain)
        times = dict(zip(candidates, measure(*(c for c, _ in candidates.values())), strict=True))
        for label, (_, reference) in candidates.items():
            speed = ratio(times[label] / times[reference]) if reference else "-"
            rows.append([robot, function, label, us(times[label]), speed])
    return rows


# ----- 3. the PUMA 560's Coriolis matrix --------------------------------------------------------
def puma_coriolis(arm: ad.Robot, puma: object, rng: np.random.Generator) -> list:
    rows = []
    one, trajectory = random_state(rng, arm.n), random_state(rng, arm.n, (TRAJECTORY,))
    for label, state, states in (("one state", one, 1), (f"trajectory of {TRAJECTORY} states", trajectory, TRAJECTORY)):
        q, qd = state["q"], state["qd"]
        check(
            f"PUMA 560 coriolis, {label}: armdyn vs puma.coriolis",
            arm.coriolis_matrix(q, qd),
            puma.coriolis(q, qd),
            TOLERANCE,
        )
        calls = TOOLBOX_CORIOLIS_CALLS if states == 1 else 1
        ours, theirs = measure(
            Candidate(
                partial(arm.coriolis_matrix, q, qd), calls=max(CALLS // states, 1), repeats=REPEATS, states=states
            ),
            Candidate(partial(puma.coriolis, q, qd), calls=calls, repeats=TOOLBOX_REPEATS, states=states),
        )
        rows.append([label, us(ours), us(theirs), ratio(theirs / ours)])
    return rows


# ----- 4. kinematics ---------------------------------------------------------------------------
KINEMATICS = {  # armdyn call -> (method, its state arguments, its keyword arguments)
    "tool_pose(q)": ("tool_pose", ("q",), {}),
    'jacobian(q, "base")': ("jacobian", ("q",), {"frame": "base"}),
    'jacobian(q, "tool")': ("jacobian", ("q",), {"frame": "tool"}),
    'jacobian_dot(q, qd, "base")': ("jacobian_dot", ("q", "qd"), {"frame": "base"}),
    'jacobian_dot(q, qd, "tool")': ("jacobian_dot", ("q", "qd"), {"frame": "tool"}),
    "link_transforms(q)": ("link_transforms", ("q",), {}),
}
# armdyn's frames: "base" is world axes at the target's origin, "tool" the target's own axes
REFERENCES = {"base": (pin.LOCAL_WORLD_ALIGNED, "LWA"), "tool": (pin.LOCAL, "LOCAL")}


def tool_frame(p: PinocchioArm, rng: np.random.Generator) -> int:
    """The id of Pinocchio's frame placed where armdyn's tool is, at a random state (of the frames there, the
    last body frame: a joint's frame and its child link's coincide)."""
    x = rng.uniform(-1.0, 1.0, p.arm.n)
    pin.framesForwardKinematics(p.model, p.data, p.q(x))
    pose = p.arm.tool_pose(x)
    matches = [
        i for i in range(len(p.model.frames)) if relative_error(pose, p.data.oMf[i].homogeneous) <= KINEMATICS_TOLERANCE
    ]
    if not matches:
        raise AssertionError("no Pinocchio frame is placed where armdyn's tool is")
    bodies = [i for i in matches if p.model.frames[i].type == pin.FrameType.BODY]
    return (bodies or matches)[-1]


def _frame_pose(m: pin.Model, d: pin.Data, frame: int, q: np.ndarray) -> pin.SE3:
    pin.forwardKinematics(m, d, q)
    pin.updateFramePlacements(m, d)
    return d.oMf[frame]


def _one_frame_pose(m: pin.Model, d: pin.Data, frame: int, q: np.ndarray) -> pin.SE3:
    pin.forwardKinematics(m, d, q)
    return pin.updateFramePlacement(m, d, frame)


def _joint_poses(m: pin.Model, d: pin.Data, joints: Sequence[int], q: np.ndarray) -> list:
    pin.forwardKinematics(m, d, q)
    return [d.oMi[j] for j in joints]


def _frame_jacobian(m: pin.Model, d: pin.Data, frame: int, ref: object, q: np.ndarray) -> np.ndarray:
    pin.computeJointJacobians(m, d, q)
    pin.updateFramePlacements(m, d)
    return pin.getFrameJacobian(m, d, frame, ref)


def _frame_jacobian_only(m: pin.Model, d: pin.Data, frame: int, ref: object, q: np.ndarray) -> np.ndarray:
    pin.computeJointJacobians(m, d, q)
    return pin.getFrameJacobian(m, d, frame, ref)


def _frame_jacobian_dot(m: pin.Model, d: pin.Data, frame: int, ref: object, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    pin.computeJointJacobiansTimeVariation(m, d, q, v)
    pin.updateFramePlacements(m, d)
    return pin.getFrameJacobianTimeVariation(m, d, frame, ref)


def _homogeneous(pose: pin.SE3) -> np.ndarray:
    return pose.homogeneous


def _homogeneous_all(poses: Sequence[pin.SE3]) -> np.ndarray:
    return np.array([pose.homogeneous for pose in poses])


def pinocchio_kinematics(p: PinocchioArm, frame: int, state: dict) -> dict[str, list[tuple[str, Callable, Callable]]]:
    """Per armdyn call (a key of KINEMATICS): Pinocchio's routes to the same result, each (label, zero-argument
    call of every Pinocchio function a user calls for it, converter of its result to armdyn's form)."""
    m, d = p.model, p.data
    q, v = p.q(state["q"]), p.v(state["qd"])
    joints = [m.getJointId(name) for name in p.arm.joint_names]  # a URDF link's frame is its parent joint's
    routes = {
        "tool_pose(q)": [
            ("forwardKinematics + updateFramePlacements + oMf[f]", partial(_frame_pose, m, d, frame, q), _homogeneous),
            ("forwardKinematics + updateFramePlacement(f)", partial(_one_frame_pose, m, d, frame, q), _homogeneous),
        ],
        "link_transforms(q)": [
            ("forwardKinematics + oMi[j] of each link", partial(_joint_poses, m, d, joints, q), _homogeneous_all),
        ],
    }
    for axes, (ref, short) in REFERENCES.items():
        routes[f'jacobian(q, "{axes}")'] = [
            (
                f"computeJointJacobians + updateFramePlacements + getFrameJacobian(f, {short})",
                partial(_frame_jacobian, m, d, frame, ref, q),
                p.jacobian,
            ),
            (
                f"computeJointJacobians + getFrameJacobian(f, {short})",
                partial(_frame_jacobian_only, m, d, frame, ref, q),
                p.jacobian,
            ),
            (
                f"computeFrameJacobian(q, f, {short})",
                partial(pin.computeFrameJacobian, m, d, q, frame, ref),
                p.jacobian,
            ),
        ]
        routes[f'jacobian_dot(q, qd, "{axes}")'] = [
            (
                "computeJointJacobiansTimeVariation + updateFramePlacements + "
                f"getFrameJacobianTimeVariation(f, {short})",
                partial(_frame_jacobian_dot, m, d, frame, ref, q, v),
                p.jacobian,
            ),
        ]
    return routes


def kinematics(robot: str, p: PinocchioArm, frame: int, rng: np.random.Generator) -> list:
    """Rows: armdyn (plain and with out=) against each Pinocchio route, checked first on KINEMATICS_CHECKS
    random states; the ratio is against the fastest route, the others' in parentheses."""
    arm = p.arm
    states = [random_state(rng, arm.n) for _ in range(KINEMATICS_CHECKS)]
    for state in states:
        routes = pinocchio_kinematics(p, frame, state)
        for call, (name, names, options) in KINEMATICS.items():
            ours = getattr(arm, name)(*(state[n] for n in names), **options)
            for label, peer, convert in routes[call]:
                check(f"{robot} {call}: armdyn vs {label}", ours, convert(peer()), KINEMATICS_TOLERANCE)
    state, rows = states[0], []
    routes = pinocchio_kinematics(p, frame, state)
    for call, (name, names, options) in KINEMATICS.items():
        method, args = getattr(arm, name), [state[n] for n in names]
        ours = method(*args, **options)
        out = np.empty_like(ours)
        check(f"{robot} {call}: armdyn out= vs armdyn", method(*args, out=out, **options), ours, 0.0)
        plain, with_out, *theirs = measure(
            Candidate(partial(method, *args, **options), CALLS, REPEATS),
            Candidate(partial(method, *args, out=out, **options), CALLS, REPEATS),
            *(Candidate(peer, CALLS, REPEATS) for _, peer, _ in routes[call]),
        )
        for i, ((label, _, _), time) in enumerate(zip(routes[call], theirs, strict=True)):
            speed = ratio(plain / time)
            first = i == 0
            rows.append(
                [
                    robot if first else "",
                    call if first else "",
                    label,
                    us(plain) if first else "",
                    us(with_out) if first else "",
                    us(time),
                    speed if time == min(theirs) else f"({speed})",
                ]
            )
    return rows


# ----- 5. thread spin ---------------------------------------------------------------------------
# A fresh interpreter (the OpenMP runtime reads OMP_WAIT_POLICY once, when it loads): a single-threaded loop of
# one-state inverse dynamics right after a batch call on THREADS threads, against the same loop after the same
# batch call and a rest; also the process's CPU time during the rest (threads spinning while nothing runs).
SPIN_SCRIPT = """
import gc, json, os, statistics, time
{first}
import numba
import numpy as np
import armdyn

arm = armdyn.load_urdf({urdf!r})
armdyn.set_threads(min({threads}, numba.config.NUMBA_NUM_THREADS))
rng = np.random.default_rng(0)
Q = rng.uniform(-1.0, 1.0, ({batch}, arm.n))
q, qd, qdd = rng.uniform(-1.0, 1.0, (3, arm.n))


def loop():
    start = time.perf_counter_ns()
    for _ in range({calls}):
        arm.inverse_dynamics(q, qd, qdd)
    return (time.perf_counter_ns() - start) / 1e9


arm.inverse_dynamics(Q, Q, Q)
loop()
after_batch, after_rest, cpu = [], [], []
gc.disable()
for _ in range({rounds}):
    arm.inverse_dynamics(Q, Q, Q)
    after_batch.append(loop())
    arm.inverse_dynamics(Q, Q, Q)
    start = time.process_time()
    time.sleep({rest})
    cpu.append(time.process_time() - start)
    after_rest.append(loop())
values = {{
    "after_batch": statistics.median(after_batch),
    "after_rest": statistics.median(after_rest),
    "cpu": statistics.median(cpu),
    "layer": numba.threading_layer(),
    "threads": armdyn.threads(),
    "policy": os.environ.get("OMP_WAIT_POLICY", "unset"),
}}
print({event!r} + json.dumps(values))
"""
SPIN_SETTINGS = {  # label -> (OMP_WAIT_POLICY in the interpreter's environment or None for unset, first import)
    "OMP_WAIT_POLICY unset: armdyn's default (it sets PASSIVE)": (None, ""),
    "OMP_WAIT_POLICY=ACTIVE": ("ACTIVE", ""),
    "unset, but pinocchio imported before armdyn": (None, "import pinocchio"),
}


def thread_spin(notes: list[str]) -> list:
    rows = []
    code = partial(
        SPIN_SCRIPT.format,
        urdf=str(URDFS["UR5"]),
        threads=THREADS,
        batch=SPIN_BATCH,
        calls=SPIN_CALLS,
        rounds=SPIN_ROUNDS,
        rest=SPIN_REST,
        event=EVENT,
    )
    for label, (policy, first) in SPIN_SETTINGS.items():
        env = {name: value for name, value in os.environ.items() if name != "OMP_WAIT_POLICY"}
        if policy is not None:
            env["OMP_WAIT_POLICY"] = policy
        try:
            values = fresh_python(code(first=first), env, SPIN_LIMIT)[1]
        except (RuntimeError, subprocess.TimeoutExpired) as error:
            rows.append([label, f"failed: {error}"[:200], "", "", "", ""])
            continue
        batch, rest = values["after_batch"], values["after_rest"]
        rows.append([label, values["policy"], ms(batch), ms(rest), ratio(batch / rest), ms(values["cpu"])])
        note = f"Numba's threading layer: {values['layer']}, batch calls on {values['threads']} threads."
        if note not in notes:
            notes.append(note)
    return rows


# ----- 6. start-up ------------------------------------------------------------------------------
# Each script times its own steps; EVENT marks the line with their seconds.
ARMDYN_STARTUP = """
import time
start = time.perf_counter()
import armdyn
imported = time.perf_counter()
arm = armdyn.load_urdf({urdf!r})
loaded = time.perf_counter()
import numpy as np
z = np.zeros(arm.n)
arm.inverse_dynamics(z, z, z)
called = time.perf_counter()
import json
print({event!r} + json.dumps({{"import": imported - start, "load": loaded - imported, "call": called - loaded}}))
"""
PINOCCHIO_STARTUP = """
import time
start = time.perf_counter()
import pinocchio
imported = time.perf_counter()
model = pinocchio.buildModelFromUrdf({urdf!r})
data = model.createData()
loaded = time.perf_counter()
import numpy as np
z = np.zeros(model.nq)
pinocchio.rnea(model, data, z, z, z)
called = time.perf_counter()
import json
print({event!r} + json.dumps({{"import": imported - start, "load": loaded - imported, "call": called - loaded}}))
"""
PINOCCHIO = "Pinocchio: import pinocchio, buildModelFromUrdf + createData, first rnea"
STARTUP = {  # label -> (script, with an empty kernel cache)
    "python -c pass": ("pass", False),
    PINOCCHIO: (PINOCCHIO_STARTUP, False),
    "armdyn, kernel cache filled: import armdyn, load_urdf, first inverse_dynamics": (ARMDYN_STARTUP, False),
    "armdyn, empty kernel cache (a fresh NUMBA_CACHE_DIR): the same": (ARMDYN_STARTUP, True),
}


def _start(code: str, cold: bool) -> tuple[float, dict]:
    """fresh_python(code), with NUMBA_CACHE_DIR a fresh empty folder when ``cold``."""
    if not cold:
        return fresh_python(code, timeout=STARTUP_LIMIT)
    with tempfile.TemporaryDirectory(prefix="armdyn-cold-") as folder:
        return fresh_python(code, {**os.environ, "NUMBA_CACHE_DIR": folder}, STARTUP_LIMIT)


def startup() -> list:
    """Median seconds of STARTUP_RUNS fresh interpreters per script, their runs interleaved, after one untimed
    run of each script with a filled cache (filling it, and the OS's file cache)."""
    urdf = str(URDFS["UR5"])
    scripts = {label: (code.format(urdf=urdf, event=EVENT), cold) for label, (code, cold) in STARTUP.items()}
    results: dict[str, list[tuple[float, dict]]] = {label: [] for label in scripts}
    failed: dict[str, str] = {}
    for run in range(-1, STARTUP_RUNS):  # run -1: untimed
        for label, (code, cold) in scripts.items():
            if label in failed or (run < 0 and cold):
                continue
            try:
                result = _start(code, cold)
            except (RuntimeError, subprocess.TimeoutExpired) as error:
                failed[label] = f"failed: {error}"[:200]
                continue
            if run >= 0:
                results[label].append(result)
    medians: dict[str, dict[str, float]] = {}  # label -> {"wall": s, and the script's own steps: s}
    for label, runs in results.items():
        if label not in failed:
            medians[label] = {"wall": statistics.median(wall_time for wall_time, _ in runs)}
            for step in ("import", "load", "call"):
                if all(step in values for _, values in runs):
                    medians[label][step] = statistics.median(values[step] for _, values in runs)
    reference = medians.get(PINOCCHIO, {}).get("wall")
    rows = []
    for label in scripts:
        if label in failed:
            rows.append([label, failed[label], "", "", "", "", ""])
            continue
        times = medians[label]
        steps = [times[step] for step in ("import", "load", "call") if step in times]
        split = [ms(step) for step in steps] if len(steps) == 3 else ["-"] * 3
        outside = ms(times["wall"] - sum(steps)) if len(steps) == 3 else "-"
        versus = ratio(times["wall"] / reference) if reference and label.startswith("armdyn") else "-"
        rows.append([label, seconds(times["wall"]), *split, outside, versus])
    return rows


# ----- the run ----------------------------------------------------------------------------------


def warm_up(arms: Sequence[ad.Robot]) -> None:
    """Every function's first call, one state and a batch, and the kinematics' with one state (Numba compiles
    or loads its cache)."""
    for arm in arms:
        for function in FUNCTIONS:
            for shape in ((arm.n,), (2, arm.n)):
                getattr(arm, function)(*[np.zeros(shape)] * len(ARGUMENTS[function]))
        for name, names, options in KINEMATICS.values():
            getattr(arm, name)(*[np.zeros(arm.n)] * len(names), **options)


def header(source: tuple[str, str]) -> list[str]:
    toolbox = rtb.__version__ if rtb else f"not available ({TOOLBOX_MISSING})"
    versions = {
        "numba": numba.__version__,
        "numpy": np.__version__,
        "pinocchio": pin.__version__,
        "roboticstoolbox": toolbox,
    }
    policy = os.environ.get("OMP_WAIT_POLICY", "unset")
    return describe(source, versions, f", Pinocchio *InParallel threads {THREADS}, OMP_WAIT_POLICY {policy}") + [
        f"Every time is a median: one state {CALLS} calls x {REPEATS} repeats (Toolbox {TOOLBOX_CALLS} x "
        f"{TOOLBOX_REPEATS}, its coriolis {TOOLBOX_CORIOLIS_CALLS} x {TOOLBOX_REPEATS}), batch {BATCH_REPEATS} "
        "repeats; the candidates' repeats are interleaved. armdyn and the peer are checked to agree "
        f"(to {TOLERANCE:g} relative, the kinematics to {KINEMATICS_TOLERANCE:g} on {KINEMATICS_CHECKS} states) "
        "on the same inputs before timing.",
    ]


def main() -> None:
    args = arguments(__doc__).parse_args()
    report = Report.begin(args, "armdyn dynamics benchmarks", RESULTS, globals(), QUICK)
    rng = np.random.default_rng(SEED)
    report.note(*header(report.source))

    pinned = {name: PinocchioArm.load(name, path) for name, path in URDFS.items()}
    puma = ad.models.puma560()
    toolbox = rtb.models.DH.Puma560() if rtb else None
    if toolbox is None:
        print(f"NOTE: the Robotics Toolbox is not available ({TOOLBOX_MISSING}); its columns are skipped.")
    elapsed = wall(partial(warm_up, [p.arm for p in pinned.values()] + [puma]))[1]
    report.note(
        f"armdyn's first calls in this process (compile or load machine code, untimed): {elapsed:.1f} s", end="\n\n"
    )

    single = Table(
        "1. One state per call (microseconds per call)",
        ["robot", "function", "peer", "armdyn", "armdyn out=", "peer", "armdyn/peer"],
        notes=[note for p in pinned.values() for note in p.notes],
        left=3,
    )
    for name, p in pinned.items():
        state = random_state(rng, p.arm.n)
        single.rows += one_state(name, p.arm, pinocchio_calls(p, state), state, {})
    if toolbox is not None:
        state = random_state(rng, puma.n)
        timing = {f: (TOOLBOX_CALLS, TOOLBOX_REPEATS) for f in FUNCTIONS}
        timing["coriolis_matrix"] = (TOOLBOX_CORIOLIS_CALLS, TOOLBOX_REPEATS)
        single.rows += one_state("PUMA 560", puma, toolbox_calls(toolbox, state), state, timing)
    else:
        single.notes.append("PUMA 560 rows skipped: the Robotics Toolbox is not available.")
    single.notes += [
        "armdyn/peer < 1: armdyn is faster. Pinocchio's calls return views of its Data (no allocation); "
        "'armdyn out=' writes into a preallocated array likewise.",
        "pin.crba is symmetrized from its upper triangle before the check.",
        "PUMA 560: armdyn's model and the Toolbox's both include motor inertia and friction.",
    ]
    report.show(single)

    many = Table(
        f"2. A batch of {BATCH:,} states (microseconds per state)",
        ["robot", "function", "implementation", "us/state", "peer/armdyn"],
        notes=[
            "peer/armdyn > 1: armdyn has the higher throughput. Each Pinocchio row is compared with the armdyn row "
            "of the same form (out= with out=, the loop with the plain call).",
            f"Pinocchio's parallel calls take (nq, B) arrays: the transposes Q.T of C-ordered (B, nq) arrays, "
            f"Fortran-ordered views, are passed without a copy; results come back as (nv, B). They take a "
            f"pin.ModelPool(model, {THREADS}), not (model, data).",
        ],
        left=3,
    )
    for name, p in pinned.items():
        many.rows += batch(name, p, rng, many.notes)
    report.show(many)

    if toolbox is not None:
        coriolis = Table(
            "3. PUMA 560 Coriolis matrix, armdyn vs the Toolbox (microseconds per state)",
            ["states", "armdyn coriolis_matrix", "puma.coriolis", "Toolbox/armdyn"],
            notes=[
                "puma.coriolis copies the robot without friction on every call (nofriction), which dominates "
                "its one-state time; on a trajectory that copy is shared by all states.",
            ],
            left=3,
        )
        coriolis.rows = puma_coriolis(puma, toolbox, rng)
        report.show(coriolis)

    frames = {name: tool_frame(p, rng) for name, p in pinned.items()}
    motion = Table(
        "4. Kinematics, one state per call (microseconds per call)",
        ["robot", "armdyn", "Pinocchio route", "armdyn", "armdyn out=", "Pinocchio", "armdyn/Pinocchio"],
        notes=[
            "armdyn/Pinocchio < 1: armdyn is faster. The ratio is armdyn's plain call against the fastest "
            "Pinocchio route; in parentheses, against the slower routes. Each route is every call a user makes: "
            "pin.<function>(model, data, ...) in turn, and reading data.oMf / data.oMi (SE3 objects, views of "
            "Pinocchio's Data, where armdyn returns 4x4 arrays).",
            "f: Pinocchio's frame placed where armdyn's tool is (found by comparing the poses at a random state): "
            + ", ".join(f"{name} '{pinned[name].model.frames[f].name}'" for name, f in frames.items())
            + ". armdyn's tool is the last link of the chain it loads; the Panda loads with its two finger joints "
            "(9 joints, as in parts 1 and 2), so its tool is the right finger.",
            'LWA: pin.LOCAL_WORLD_ALIGNED, the axes of armdyn\'s "base"; LOCAL: the frame\'s own, armdyn\'s "tool". '
            "Pinocchio's Jacobian columns are put in armdyn's joint order before the checks.",
            "Pinocchio 4's getFrameJacobian needs only computeJointJacobians (its docstring); "
            "getFrameJacobianTimeVariation's asks for updateFramePlacements as well.",
            "link_transforms: a URDF link's frame is its parent joint's, data.oMi of that joint.",
        ],
        left=3,
    )
    for name, p in pinned.items():
        motion.rows += kinematics(name, p, frames[name], rng)
    report.show(motion)

    spin = Table(
        f"5. Thread spin: a one-state loop right after a batch call (UR5, {SPIN_CALLS:,} inverse_dynamics calls)",
        ["setting", "policy", "loop after batch ms", "loop after rest ms", "after batch/after rest", "CPU in rest ms"],
        notes=[
            f"A fresh interpreter per setting (the OpenMP runtime reads OMP_WAIT_POLICY once, when it loads). Each of "
            f"{SPIN_ROUNDS} rounds: a batch inverse_dynamics call ({SPIN_BATCH:,} states, {THREADS} threads) then the "
            f"timed loop; the same batch call, {SPIN_REST * 1e3:.0f} ms of rest, the timed loop. Medians over the "
            "rounds. 'CPU in rest': the process's CPU time during the rest, the idle batch threads spinning.",
            "after batch/after rest near 1: the batch threads leave the cores to the single-threaded work that "
            "follows. 'policy' is the environment variable as the interpreter saw it after importing armdyn; with "
            "pinocchio imported first, the runtime had already started without it.",
        ],
        left=2,
    )
    spin.rows = thread_spin(spin.notes)
    report.show(spin)

    report.show(
        Table(
            f"6. Start-up: a fresh interpreter (medians of {STARTUP_RUNS} run{'s' if STARTUP_RUNS > 1 else ''})",
            ["script (UR5)", "wall s", "import ms", "load ms", "first call ms", "start + exit ms", "wall/Pinocchio's"],
            startup(),
            notes=[
                f"{sys.executable} -c script. 'wall s': the interpreter's whole run, from start to exit; import, "
                "load and first call: each script's own steps, timed inside it; 'start + exit': the rest of the wall "
                "time (the interpreter's start, and its exit with the libraries' clean-up).",
                "Each script with a filled kernel cache runs once untimed first (filling armdyn's kernel cache, and "
                "the OS's file cache). The empty-cache runs compile armdyn's kernels (and write them to that folder), "
                "as the first run after installing armdyn or changing its source does.",
            ],
            left=1,
        )
    )
    report.finish(
        "parts 1-4 timed the version imported at the start; parts 5 and 6 ran fresh interpreters, which may have "
        "imported another (and compiled it)."
    )


if __name__ == "__main__":
    main()
