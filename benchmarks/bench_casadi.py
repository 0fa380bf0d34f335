"""armdyn's CasADi functions (armdyn.symbolic.generate_code(..., backend="casadi")) beside adam's CasADi backend
(adam-robotics), on the UR5 and the Panda of example-robot-data.

    .venv/bin/python benchmarks/bench_casadi.py            # about a minute
    .venv/bin/python benchmarks/bench_casadi.py --quick    # a smoke run, nothing written

Three parts:

1. instruction counts (casadi.Function.n_instructions) of the mass matrix M, the bias (adam's bias_force; armdyn's
   N = V + G + F of the arm without friction, since adam has none) and the forward dynamics (armdyn's qdd; adam's
   Cholesky-free solve of its M, and its articulated-body algorithm, which is a floating-base one) on the UR5, the
   9-joint Panda and the 7-joint Panda (fingers locked at 0.02 m and merged into link 7). adam is given the URDF
   file, the joint names and armdyn's gravity (0, 0, -9.81); a fixed base is its base transform set to the
   identity and its base velocity to zero before the functions are built (numbers, not symbols). Each function
   of adam that builds is checked against armdyn's kernels at a random state (M to 1e-10) before anything is
   counted or timed; one that fails to build is recorded with its error.
2. the same optimal-control problem solved with adam's forward dynamics and with armdyn's: the UR5's minimum-effort
   point-to-point motion of examples/optimal_control.py (its ``point_to_point``: the same horizon, intervals,
   IPOPT options and first guess), each arm's qdd Function put through one RK4 step written once here. Timed:
   end to end (the functions built, the NLP and its solver built, the solve) and the solve alone, medians of
   REPEATS runs; IPOPT's iterations; the optima compared (the costs, the knots' states and the torques).
3. armdyn's construction time for the Panda: generate_code (every function, CasADi backend) and the functions.
4. JAX: the generated tau, M and qdd (backend="jax") jitted and vmapped over BATCH states of the 7-joint Panda on
   the CPU, beside armdyn's compiled batch calls (Numba, the fast path) on the same states; the compile time
   of each jitted function apart.

Prints Markdown tables and writes the same to results_casadi.md (harness.py's Report); --quick writes nothing.
"""

from __future__ import annotations

import importlib.util
import statistics
import sys
import tempfile
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import version
from pathlib import Path

import casadi
import numpy as np
from harness import Report, Table, arguments, describe, seconds

import armdyn as ad
from armdyn.symbolic import generate_code

ROBOTS = Path(sys.prefix).glob("lib/python*/site-packages/cmeel.prefix/share/example-robot-data/robots")
ROBOTS_DIR = next(iter(ROBOTS), Path("example-robot-data-not-found"))
UR5 = ROBOTS_DIR / "ur_description" / "urdf" / "ur5_robot.urdf"
PANDA = ROBOTS_DIR / "panda_description" / "urdf" / "panda.urdf"
LOCKED = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}  # the Panda's fingers, locked
GRAVITY = (0.0, 0.0, -9.81)
RESULTS = Path(__file__).with_name("results_casadi.md")
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "optimal_control.py"
SEED = 3
REPEATS, INTERVALS, BATCH = 3, 50, 100_000
QUICK = {"REPEATS": 1, "INTERVALS": 10, "BATCH": 1000}
# the UR5's problem: rest to rest in DURATION s, the torques within the URDF's effort limits
UR5_START = np.array([0.0, -1.5, 1.2, -1.2, -1.5, 0.0])
UR5_GOAL = np.array([1.4, -0.6, 0.3, -0.9, -1.0, 0.8])
UR5_LIMIT = np.array([150.0, 150.0, 150.0, 28.0, 28.0, 28.0])  # N m: the effort limits of ur5_robot.urdf
DURATION = 1.0


def example() -> object:
    """examples/optimal_control.py as a module (its point_to_point, quintic_guess, IPOPT options)."""
    spec = importlib.util.spec_from_file_location("optimal_control", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("optimal_control", module)  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


# ----- the arms ------------------------------------------------------------------------------------------------------
@dataclass
class Arm:
    """An arm as armdyn reads it (without friction) and the URDF and joint names adam is given."""

    name: str
    arm: ad.Robot
    urdf: Path
    note: str = ""


def load(path: Path, locked: dict[str, float] | None = None) -> ad.Robot:
    """A URDF arm without its friction (adam has none), armdyn's gravity GRAVITY."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Panda's mimic finger joint
        return ad.load_urdf(path, gravity=GRAVITY, locked=locked).without_friction()


def arms(folder: Path) -> list[Arm]:
    """The UR5, the 9-joint Panda, the 7-joint Panda given to adam as example-robot-data's file (its 7 arm joints
    named), and the same 7-joint Panda given to adam as the URDF armdyn writes of it (fingers merged into link 7)."""
    panda7 = load(PANDA, LOCKED)
    written = folder / "panda7.urdf"
    panda7.to_urdf(written)
    return [
        Arm("UR5", load(UR5), UR5),
        Arm("Panda, 9 joints", load(PANDA), PANDA),
        Arm("Panda, 7 joints (its URDF)", panda7, PANDA, "example-robot-data's panda.urdf, the 7 arm joints named"),
        Arm("Panda, 7 joints (armdyn's URDF)", panda7, written, "the URDF armdyn writes of the locked arm"),
    ]


# ----- adam's and armdyn's functions ---------------------------------------------------------------------------------
def adam_functions(arm: Arm) -> dict[str, casadi.Function | str]:
    """adam's M, bias and forward dynamics (solve of M; its floating-base ABA) as casadi Functions of the joint
    states, the base fixed at the identity at rest; a function that fails to build is its error message."""
    from adam.casadi import KinDynComputations

    n = arm.arm.n
    q, qd, tau = (casadi.SX.sym(name, n) for name in ("q", "qd", "tau"))
    base, rest = casadi.DM.eye(4), casadi.DM.zeros(6)
    built: dict[str, casadi.Function | str] = {}
    try:
        adam = KinDynComputations(str(arm.urdf), list(arm.arm.joint_names), gravity=np.array([*GRAVITY, 0, 0, 0]))
    except Exception as error:  # recorded as the outcome
        return dict.fromkeys(("M", "bias", "qdd", "aba"), f"{type(error).__name__}: {error}")
    builders: dict[str, Callable[[], casadi.Function]] = {
        "M": lambda: casadi.Function("M", [q], [adam.mass_matrix(base, q)[6:, 6:]]),
        "bias": lambda: casadi.Function("h", [q, qd], [adam.bias_force(base, q, rest, qd)[6:]]),
        "qdd": lambda: casadi.Function(
            "qdd",
            [q, qd, tau],
            [casadi.solve(adam.mass_matrix(base, q)[6:, 6:], tau - adam.bias_force(base, q, rest, qd)[6:])],
        ),
        "aba": lambda: casadi.Function("aba", [q, qd, tau], [adam.aba(base, q, rest, qd, tau)[6:]]),
    }
    for name, build in builders.items():
        try:
            built[name] = build()
        except Exception as error:  # recorded as the outcome
            built[name] = f"{type(error).__name__}: {str(error).strip().splitlines()[-1]}"
    return built


def armdyn_functions(arm: ad.Robot) -> dict[str, casadi.Function]:
    """armdyn's M, N (the bias) and qdd."""
    code = generate_code(arm, ("M", "N", "qdd"), backend="casadi")
    return {"M": code.M, "bias": code.N, "qdd": code.qdd}


def reference(arm: ad.Robot, name: str, state: np.ndarray) -> np.ndarray:
    """armdyn's kernel for a function at state (q, qd, tau)."""
    q, qd, tau = state
    if name == "M":
        return arm.inertia_matrix(q)
    if name == "bias":
        return arm.nonlinear_terms(q, qd)
    return arm.forward_dynamics(q, qd, tau)


def checked(arm: ad.Robot, name: str, function: casadi.Function, state: np.ndarray) -> float:
    """The largest |function - armdyn's kernel| at a state (M, bias, qdd)."""
    arguments = state[: function.n_in()]
    value = np.asarray(function(*arguments)).reshape(reference(arm, name, state).shape)
    return float(np.abs(value - reference(arm, name, state)).max())


# ----- the optimal-control problem -----------------------------------------------------------------------------------
def rk4(qdd: casadi.Function) -> casadi.Function:
    """One RK4 step (x, tau, dt) -> x_next of xdot = [qd; qdd(q, qd, tau)], tau held: the one integrator both
    dynamics are put through."""
    n = qdd.size1_in(0)
    x, tau, dt = casadi.SX.sym("x", 2 * n), casadi.SX.sym("tau", n), casadi.SX.sym("dt")

    def rate(state: casadi.SX) -> casadi.SX:
        return casadi.vertcat(state[n:], qdd(state[:n], state[n:], tau))

    k1 = rate(x)
    k2 = rate(x + dt / 2 * k1)
    k3 = rate(x + dt / 2 * k2)
    k4 = rate(x + dt * k3)
    return casadi.Function("step", [x, tau, dt], [x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])


@dataclass
class Solved:
    """One end-to-end solve: the motion (the example's Motion) and the seconds to build the functions."""

    motion: object
    functions_seconds: float

    @property
    def total(self) -> float:
        return self.functions_seconds + self.motion.build_seconds + self.motion.solve_seconds


def solve(build_qdd: Callable[[], casadi.Function], arm: ad.Robot, intervals: int, module: object) -> Solved:
    """The UR5 problem end to end: build the qdd Function, put it through rk4, build and solve the NLP (the
    example's point_to_point, its IPOPT options and quintic first guess)."""
    started = time.perf_counter()
    step = rk4(build_qdd())
    functions = time.perf_counter() - started
    guess = module.quintic_guess(UR5_START, UR5_GOAL, DURATION, intervals, arm)
    return Solved(module.point_to_point(step, UR5_START, UR5_GOAL, UR5_LIMIT, DURATION, intervals, guess), functions)


def adam_qdd(arm: Arm) -> casadi.Function:
    """adam's forward dynamics of the fixed-base arm by a solve of its M, built from the URDF."""
    from adam.casadi import KinDynComputations

    n = arm.arm.n
    q, qd, tau = (casadi.SX.sym(name, n) for name in ("q", "qd", "tau"))
    base, rest = casadi.DM.eye(4), casadi.DM.zeros(6)
    adam = KinDynComputations(str(arm.urdf), list(arm.arm.joint_names), gravity=np.array([*GRAVITY, 0, 0, 0]))
    M, h = adam.mass_matrix(base, q)[6:, 6:], adam.bias_force(base, q, rest, qd)[6:]
    return casadi.Function("qdd", [q, qd, tau], [casadi.solve(M, tau - h)])


def armdyn_qdd(arm: ad.Robot) -> casadi.Function:
    """armdyn's forward dynamics, generated from the arm."""
    return generate_code(arm, ("qdd",), backend="casadi").qdd


def compare(ours: Solved, theirs: Solved) -> dict[str, float]:
    """How far apart two optima are: the costs (relative), the knots' states and the torques (largest |.|)."""
    a, b = ours.motion, theirs.motion
    return {
        "cost": abs(a.cost - b.cost) / abs(b.cost),
        "states": float(np.abs(a.x - b.x).max()),
        "torques": float(np.abs(a.tau - b.tau).max()),
    }


# ----- the report ----------------------------------------------------------------------------------------------------
def count(function: casadi.Function | str | None) -> str:
    if function is None:
        return "-"
    return "fails" if isinstance(function, str) else f"{function.n_instructions():,}"


def ratio(ours: casadi.Function, theirs: casadi.Function | str | None) -> str:
    if not isinstance(theirs, casadi.Function):
        return "-"
    return f"{ours.n_instructions() / theirs.n_instructions():.2f}"


def counts_table(arms_: list[Arm], rng: np.random.Generator) -> Table:
    """Part 1: instruction counts, every function checked against armdyn's kernels first."""
    table = Table("Instruction counts (casadi.Function.n_instructions)",
                  ["arm", "n", "M armdyn", "M adam", "ratio", "bias armdyn (N)", "bias adam", "ratio",
                   "qdd armdyn", "qdd adam (solve)", "ratio", "adam ABA (floating base)"], left=1)  # fmt: skip
    failures, errors = [], []
    for entry in arms_:
        arm, n = entry.arm, entry.arm.n
        ours, theirs = armdyn_functions(arm), adam_functions(entry)
        state = rng.uniform(-1.0, 1.0, (3, n))
        for name in ("M", "bias", "qdd"):
            error = checked(arm, name, ours[name], state)
            assert error < 1e-10, f"{entry.name}: armdyn's {name} differs from its kernel by {error:.1e}"
            if isinstance(theirs[name], casadi.Function):
                error = checked(arm, name, theirs[name], state)
                assert error < 1e-10, f"{entry.name}: adam's {name} differs from armdyn's by {error:.1e}"
                errors.append(f"{entry.name} {name} {error:.0e}")
            else:
                failures.append(f"{entry.name}: adam's {name} fails to build: {theirs[name]}")
        aba = theirs["aba"]
        aba_note = count(aba)
        if isinstance(aba, casadi.Function):
            gap = checked(arm, "qdd", aba, state)
            aba_note += f" (differs from the fixed-base qdd by {gap:.1e})" if gap > 1e-8 else ""
        table.rows.append(
            [
                entry.name,
                str(n),
                count(ours["M"]),
                count(theirs["M"]),
                ratio(ours["M"], theirs["M"]),
                count(ours["bias"]),
                count(theirs["bias"]),
                ratio(ours["bias"], theirs["bias"]),
                count(ours["qdd"]),
                count(theirs["qdd"]),
                ratio(ours["qdd"], theirs["qdd"]),
                aba_note,
            ]
        )
    table.notes = [
        "The arms without friction (arm.without_friction(): adam models none), gravity (0, 0, -9.81) in both; "
        "adam's functions for a fixed base: its base transform the identity and its base velocity zero, as "
        "numbers, before the Function is built (its own mass_matrix_fun(), with a symbolic base, is larger).",
        "armdyn's bias is N(q, qd) = V + G; adam's is bias_force (the joint rows). armdyn's qdd is its generated "
        "forward dynamics; adam's 'solve' is casadi.solve(M, tau - h) on its M and bias. adam's aba is the "
        "floating-base articulated-body algorithm: with the base free it is not the fixed-base arm's qdd, so it "
        "is counted, not used.",
        "Checked before counting, at a random state, against armdyn's kernels (inertia_matrix, nonlinear_terms, "
        "forward_dynamics): largest differences " + ", ".join(errors) + ".",
        *failures,
    ]
    return table


def ocp_table(module: object) -> Table:
    """Part 2: the UR5 problem solved with each dynamics, REPEATS times each, interleaved."""
    entry = Arm("UR5", load(UR5), UR5)
    runs: dict[str, list[Solved]] = {"armdyn": [], "adam": []}
    builders = {"armdyn": lambda: armdyn_qdd(entry.arm), "adam": lambda: adam_qdd(entry)}
    for _ in range(REPEATS):
        for name, build in builders.items():
            runs[name].append(solve(build, entry.arm, INTERVALS, module))
    gaps = compare(runs["armdyn"][0], runs["adam"][0])
    table = Table(f"The UR5's minimum-effort motion, {INTERVALS} intervals in {DURATION:g} s, by multiple shooting "
                  "with IPOPT", ["dynamics", "qdd instructions", "IPOPT iterations", "status", "cost (N^2 m^2 s)",
                  "end to end (s)", "solve alone (s)", "per iteration (ms)"])  # fmt: skip
    medians = {}
    for name, solved in runs.items():
        first = solved[0].motion
        total = statistics.median(run.total for run in solved)
        alone = statistics.median(run.motion.solve_seconds for run in solved)
        medians[name] = (total, alone)
        instructions = (armdyn_qdd(entry.arm) if name == "armdyn" else adam_qdd(entry)).n_instructions()
        table.rows.append(
            [
                name,
                f"{instructions:,}",
                str(first.iterations),
                first.status,
                f"{first.cost:.6f}",
                seconds(total),
                seconds(alone),
                f"{1e3 * alone / max(first.iterations, 1):.1f}",
            ]
        )
    table.notes = [
        f"adam over armdyn: end to end {medians['adam'][0] / medians['armdyn'][0]:.2f}x, the solve alone "
        f"{medians['adam'][1] / medians['armdyn'][1]:.2f}x (medians of {REPEATS} runs, interleaved).",
        "One problem builder (examples/optimal_control.py's point_to_point: knots and torques as variables, "
        "minimum sum |tau|^2 h, rest to rest, |tau| within the URDF's effort limits 150/150/150/28/28/28 N m) and "
        "one RK4 step written here around each qdd Function; the same quintic first guess and IPOPT options "
        "(tol 1e-8, exact Hessian by CasADi); the UR5 without friction in both.",
        f"The optima: costs {gaps['cost']:.1e} apart (relative), knots' states {gaps['states']:.1e}, torques "
        f"{gaps['torques']:.1e} (largest absolute differences).",
        "End to end: the qdd Function built from the arm (armdyn: generate_code; adam: KinDynComputations from "
        "the URDF, M, bias and the solve), the RK4 step, the NLP and IPOPT built, then solved.",
    ]
    return table


def construction_table() -> Table:
    """Part 3: armdyn's generation and Function construction for the Panda."""
    table = Table("armdyn's construction time (generate_code with the CasADi backend)",
                  ["arm", "functions", "seconds", "instructions"])  # fmt: skip
    names = ("tau", "M", "G", "N", "Vm", "Wb", "qdd", "step")
    for label, arm in (("Panda, 7 joints", load(PANDA, LOCKED)), ("Panda, 9 joints", load(PANDA))):
        started = time.perf_counter()
        code = generate_code(arm, names, backend="casadi")
        spent = time.perf_counter() - started
        total = sum(code.instruction_counts().values())
        table.rows.append([label, ", ".join(names), seconds(spent), f"{total:,}"])
    table.notes = ["Tracing, generation and the casadi.Function construction of every function, in one call "
                   "(without friction; the base regressor Wb includes the base-parameter reduction)."]  # fmt: skip
    return table


def jax_table() -> Table:
    """Part 4: the JAX functions jitted and vmapped over BATCH states beside armdyn's batch calls."""
    import jax

    from armdyn.symbolic.backends import JIT_OPTIONS

    arm = load(PANDA, LOCKED)
    code = generate_code(arm, ["tau", "M", "qdd"], backend="jax")
    rng = np.random.default_rng(SEED)
    q, qd, qdd = rng.uniform(-1.0, 1.0, (3, BATCH, arm.n))
    tau = arm.inverse_dynamics(q, qd, qdd)
    headers = ["function", "JAX compile (s)", "JAX (ms)", "armdyn (ms)", "JAX / armdyn", "largest difference"]
    table = Table(f"JAX on the CPU: {BATCH:,} states of the 7-joint Panda, jit(vmap(f)) beside armdyn's batch call",
                  headers)  # fmt: skip
    cases = (("tau", (q, qd, qdd), lambda: arm.inverse_dynamics(q, qd, qdd)),
             ("M", (q,), lambda: arm.inertia_matrix(q)),
             ("qdd", (q, qd, tau), lambda: arm.forward_dynamics(q, qd, tau)))  # fmt: skip
    for name, states, ours in cases:
        function = jax.jit(jax.vmap(getattr(code, name)), compiler_options=JIT_OPTIONS)
        start = time.perf_counter()
        theirs = np.asarray(function(*states).block_until_ready())
        compile_time = time.perf_counter() - start
        difference = float(np.abs(theirs - ours()).max())
        jax_times, our_times = [], []
        for _ in range(REPEATS + 2):
            start = time.perf_counter()
            function(*states).block_until_ready()
            jax_times.append(time.perf_counter() - start)
            start = time.perf_counter()
            ours()
            our_times.append(time.perf_counter() - start)
        jax_ms, our_ms = statistics.median(jax_times) * 1e3, statistics.median(our_times) * 1e3
        table.rows.append([name, f"{compile_time:.1f}", f"{jax_ms:.1f}", f"{our_ms:.1f}", f"{jax_ms / our_ms:.1f}",
                           f"{difference:.1e}"])  # fmt: skip
    table.notes.append("jax.jit(..., compiler_options=armdyn.symbolic.backends.JIT_OPTIONS): XLA's loop fusion off "
                       "(fused, its CPU code recomputes shared nodes of the large scalar graph); float64; medians, "
                       "the calls interleaved. The JAX functions are for interoperability (jit, vmap, grad); "
                       "armdyn's compiled batch calls stay the fast path.")  # fmt: skip
    return table


def main() -> None:
    args = arguments(__doc__).parse_args()
    report = Report.begin(args, "armdyn's CasADi functions beside adam's", RESULTS, globals(), QUICK)
    versions = {"casadi": casadi.__version__, "adam-robotics": version("adam-robotics"), "numpy": np.__version__}
    report.note(*describe(report.source, versions), end="\n\n")
    module = example()
    with tempfile.TemporaryDirectory() as folder:
        report.show(counts_table(arms(Path(folder)), np.random.default_rng(SEED)))
    report.show(ocp_table(module))
    report.show(construction_table())
    report.show(jax_table())
    report.finish("the counts and times may mix two versions of armdyn.")


if __name__ == "__main__":
    main()
