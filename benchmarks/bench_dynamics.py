"""armdyn's dynamics side by side with Pinocchio (UR5, Panda) and the Robotics Toolbox (PUMA 560).

    .venv/bin/python benchmarks/bench_dynamics.py      # or: make bench

Four parts, all in this one process except the last:

1. one state per call: armdyn against pin.rnea / crba / computeGeneralizedGravity /
   computeCoriolisMatrix / aba, and against the Toolbox's rne / inertia / gravload / coriolis / accel;
2. a batch of 100,000 states: armdyn's (B, n) calls against pin.rneaInParallel / abaInParallel
   and against a Python loop over the one-state Pinocchio call;
3. the PUMA 560's Coriolis matrix, one state and a 50-state trajectory, armdyn against the Toolbox;
4. start-up: wall time of a fresh interpreter that imports armdyn and makes a first call.

Before anything is timed, armdyn's result is checked against the peer's on the same inputs
(relative to the largest entry, 1e-8), so a ratio never compares two different computations.
Times are medians over repeats; the candidates' repeats are interleaved so that machine noise
hits all of them alike (the timing, checking and tables are benchmarks/harness.py's). Prints plain
tables and writes the same as Markdown to results.md; --quick is a smoke run of every part with
few repeats and small batches, in well under a minute once Numba's cache is filled, and writes nothing.
"""

from __future__ import annotations

import subprocess
import sys
import sysconfig
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numba
import numpy as np
import pinocchio as pin
from harness import MILLISECOND, Candidate, Report, Table, arguments, check, describe, measure, ratio, us, wall

import armdyn as ad

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
STARTUP_RUNS = 3  # fresh interpreters per start-up script
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


# ----- 4. start-up ------------------------------------------------------------------------------
PRELUDE = "import armdyn, numpy as np; a = armdyn.models.puma560(); z = np.zeros(6)"
STARTUP = {
    "python -c pass": "pass",
    "import armdyn, numpy; puma560()": PRELUDE,
    "... + first inverse_dynamics(z, z, z)": PRELUDE + "; a.inverse_dynamics(z, z, z)",
    "... + first inertia_matrix(z)": PRELUDE + "; a.inertia_matrix(z)",
    "... + first gravity_vector(z)": PRELUDE + "; a.gravity_vector(z)",
    "... + first coriolis_matrix(z, z)": PRELUDE + "; a.coriolis_matrix(z, z)",
    "... + first forward_dynamics(z, z, z)": PRELUDE + "; a.forward_dynamics(z, z, z)",
}


def startup() -> list:
    """Median wall time of fresh interpreters, each script's first (untimed) run filling Numba's cache."""
    scripts = [partial(subprocess.run, [sys.executable, "-c", code], check=True) for code in STARTUP.values()]
    times = measure(*(Candidate(script, repeats=STARTUP_RUNS) for script in scripts), unit=MILLISECOND)
    medians = dict(zip(STARTUP, times, strict=True))
    base = medians["import armdyn, numpy; puma560()"]
    return [
        [label, f"{ms:,.0f}", f"{ms - base:+,.0f}" if label.startswith("...") else "-"] for label, ms in medians.items()
    ]


# ----- the run ----------------------------------------------------------------------------------


def warm_up(arms: Sequence[ad.Robot]) -> None:
    """Every function's first call, one state and a batch (Numba compiles or loads its cache)."""
    for arm in arms:
        for function in FUNCTIONS:
            for shape in ((arm.n,), (2, arm.n)):
                getattr(arm, function)(*[np.zeros(shape)] * len(ARGUMENTS[function]))


def header(source: tuple[str, str]) -> list[str]:
    toolbox = rtb.__version__ if rtb else f"not available ({TOOLBOX_MISSING})"
    versions = {
        "numba": numba.__version__,
        "numpy": np.__version__,
        "pinocchio": pin.__version__,
        "roboticstoolbox": toolbox,
    }
    return describe(source, versions, f", Pinocchio *InParallel threads {THREADS}") + [
        f"Every time is a median: one state {CALLS} calls x {REPEATS} repeats (Toolbox {TOOLBOX_CALLS} x "
        f"{TOOLBOX_REPEATS}, its coriolis {TOOLBOX_CORIOLIS_CALLS} x {TOOLBOX_REPEATS}), batch {BATCH_REPEATS} "
        "repeats; the candidates' repeats are interleaved. armdyn and the peer are checked to agree "
        f"(to {TOLERANCE:g} relative) on the same inputs before timing.",
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
    seconds = wall(partial(warm_up, [p.arm for p in pinned.values()] + [puma]))[1]
    report.note(
        f"armdyn's first calls in this process (compile or load machine code, untimed): {seconds:.1f} s", end="\n\n"
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

    report.show(
        Table(
            f"4. Start-up: a fresh interpreter (median wall milliseconds of {STARTUP_RUNS} runs, cache filled)",
            ["script", "ms", "first call, ms"],
            startup(),
            notes=[
                f"python -c with {sys.executable}; 'first call' is the time over importing armdyn and numpy "
                "and building the PUMA 560. Each script runs once untimed first (filling Numba's cache)."
            ],
            left=3,
        )
    )
    report.finish("parts 1-3 timed the version imported at the start, part 4 may have timed another (and compiled it).")


if __name__ == "__main__":
    main()
