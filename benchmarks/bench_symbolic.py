"""armdyn's closed forms: derivation and code generation time, operation counts, the compiled closed form
against armdyn's recursive kernels, and the Robotics Toolbox's symbolic RNE for the PUMA 560.

    .venv/bin/python benchmarks/bench_symbolic.py                      # about 5 minutes
    .venv/bin/python benchmarks/bench_symbolic.py --skip-toolbox       # about 1 minute
    .venv/bin/python benchmarks/bench_symbolic.py --simplify-timeout 60
    .venv/bin/python benchmarks/bench_symbolic.py --quick              # a smoke run, Toolbox steps capped

Five parts, all in this one process except where said:

1. derivation: wall time of derive() for the book's three symbolic examples, the SCARA, the Stanford arm
   and the PUMA 560, twice each (the process's first call also warms SymEngine up), code generation
   (to_python + to_c), and a fresh interpreter that imports armdyn, derives the PUMA 560 and generates
   its code; Numba's compile time of the PUMA 560's closed form;
2. operation counts of M, Vm, G, tau before and after common-subexpression elimination (PUMA 560, Stanford);
3. the PUMA 560's compiled closed form against armdyn's recursive kernels, one state per call;
4. the same on a batch of 100,000 states;
5. the Toolbox's symbolic rne() for the PUMA 560, in subprocesses with time limits: the time to build
   tau, its size (sympy.count_ops of tau[0]; SymEngine's cse, counted as armdyn counts), a numeric check
   against armdyn, and sympy.simplify(tau[0]).

Before anything is timed, the closed form is checked against the kernels on the same inputs (relative to
the largest entry of each state, 1e-9). Times are medians over repeats; the candidates' repeats are
interleaved so that machine noise hits all of them alike (the timing, checking and tables are
benchmarks/harness.py's). Prints plain tables and writes the same as Markdown to results_symbolic.md;
--quick runs every part with few repeats, a small batch and short Toolbox limits, and writes nothing.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections.abc import Callable, Iterator, Sequence
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
from armdyn.symbolic import ClosedForm, derive
from armdyn.symbolic.codegen import count_operations  # the counter behind ClosedForm.operation_counts

# ----- settings -------------------------------------------------------------------------------
CALLS, REPEATS = 2000, 15  # one state: calls per timed loop, timed loops per candidate
BATCH, BATCH_REPEATS = 100_000, 9  # batch: states, timed calls per candidate
TOLERANCE = 1e-9  # closed form vs kernel, relative to the largest entry of each state
SEED = 20240611
REQUIREMENT = 30.0  # seconds: the PUMA 560's derivation plus code generation must stay under this
TOOLBOX_TIMEOUT = 300.0  # seconds for the Toolbox's symbolic rne() (flag --toolbox-timeout)
COUNT_TIMEOUT = 120.0  # seconds for each analysis of its result (flag --count-timeout)
SIMPLIFY_TIMEOUT = 180.0  # seconds for sympy.simplify(tau[0]) (flag --simplify-timeout)
BUILD_TIMEOUT = 120.0  # seconds for a worker to import the Toolbox and build the symbolic PUMA 560
WORKER_MEMORY = 8 << 30  # bytes of address space a Toolbox worker may use (simplify can grow without end)
RESULTS = Path(__file__).with_name("results_symbolic.md")
QUICK = {"CALLS": 50, "REPEATS": 3, "BATCH": 2000, "BATCH_REPEATS": 2}
QUICK_LIMITS = {"toolbox_timeout": 20.0, "count_timeout": 10.0, "simplify_timeout": 5.0}  # --quick: at the most
NEWLINE = "\n"

ARMS: dict[str, Callable[[], ad.Robot]] = {
    "two_link_planar(symbolic=True)": partial(ad.models.two_link_planar, symbolic=True),
    "polar_rp(symbolic=True)": partial(ad.models.polar_rp, symbolic=True),
    "cylindrical(symbolic=True)": partial(ad.models.cylindrical, symbolic=True),
    "scara()": ad.models.scara,
    "stanford()": ad.models.stanford,
    "puma560()": ad.models.puma560,
}
COUNTED = ("puma560()", "stanford()")  # arms whose operation counts are tabulated
FUNCTIONS = {  # closed-form function -> (armdyn kernel, state arguments, dimensions of one state's result)
    "M": ("inertia_matrix", ("q",), 2),
    "G": ("gravity_vector", ("q",), 1),
    "Vm": ("coriolis_matrix", ("q", "qd"), 2),
    "tau": ("inverse_dynamics", ("q", "qd", "qdd"), 1),
}


# ----- formats ----------------------------------------------------------------------------------
def count(value: int) -> str:
    return f"{value:,}"


# ----- 1. derivation and code generation --------------------------------------------------------
def derivation(forms: dict[str, ClosedForm]) -> tuple[list[list[str]], dict[str, float], dict[str, float]]:
    """Rows per arm: derive() twice, to_python, to_c; fills ``forms`` with the second derivation of each arm.
    Also returns, per arm, the first derive's seconds and the seconds of derivation plus code generation."""
    rows, firsts, totals = [], {}, {}
    for label, build in ARMS.items():
        arm = build()
        first = wall(partial(derive, arm))[1]
        form, second = wall(partial(derive, arm))
        python, python_s = wall(form.to_python)
        c, c_s = wall(form.to_c)
        forms[label] = form
        firsts[label], totals[label] = first, max(first, second) + python_s + c_s
        lines = f"{python.count(NEWLINE):,} / {c.count(NEWLINE):,}"
        rows.append(
            [
                label,
                str(arm.n),
                form.method,
                seconds(first),
                seconds(second),
                seconds(python_s),
                seconds(c_s),
                seconds(totals[label]),
                lines,
            ]
        )
        print(f"  derived {label}: {first:.2f} s, {second:.2f} s; code {python_s + c_s:.2f} s", flush=True)
    return rows, firsts, totals


FRESH = """
import time
start = time.perf_counter()
import armdyn as ad
from armdyn.symbolic import derive
imported = time.perf_counter()
form = derive(ad.models.puma560())
derived = time.perf_counter()
form.to_python(), form.to_c()
done = time.perf_counter()
print(imported - start, derived - imported, done - derived)
"""


def fresh_interpreter() -> tuple[float, list[float]]:
    """(wall seconds of a fresh interpreter, [import, derive, to_python + to_c] seconds measured inside it)."""
    run, elapsed = wall(
        partial(subprocess.run, [sys.executable, "-c", FRESH], capture_output=True, text=True, check=True)
    )
    return elapsed, [float(x) for x in run.stdout.split()]


def compilation(form: ClosedForm, n: int) -> tuple[object, list[list[str]]]:
    """Numba: form.compile(), then the first one-state and batch call of each function (the batch loop
    is compiled on its first call)."""
    compiled, compile_s = wall(form.compile)
    rows = [["form.compile()", seconds(compile_s)]]
    zeros = np.zeros(n)
    for name, (_, args, _) in FUNCTIONS.items():
        one = wall(partial(getattr(compiled, name), *[zeros] * len(args)))[1]
        batch = wall(partial(getattr(compiled, name), *[np.zeros((2, n))] * len(args)))[1]
        rows.append([f"first call of {name}: one state / batch of 2", f"{seconds(one)} / {seconds(batch)}"])
    return compiled, rows


# ----- 2. operation counts ----------------------------------------------------------------------
def operation_counts(forms: dict[str, ClosedForm]) -> list[list[str]]:
    rows = []
    for label in COUNTED:
        form = forms[label]
        before, after = form.operation_counts(cse=False), form.operation_counts(cse=True)
        for name in FUNCTIONS:
            reduction = ratio(after[name] / before[name]) if before[name] else "-"
            rows.append([label, name, count(before[name]), count(after[name]), reduction])
    return rows


# ----- 3 and 4. the compiled closed form against the kernels ------------------------------------
def random_state(rng: np.random.Generator, n: int, batch: tuple[int, ...] = ()) -> dict[str, np.ndarray]:
    q, qd, qdd = rng.uniform(-1.0, 1.0, (3, *batch, n))
    return {"q": q, "qd": qd, "qdd": qdd}


def checked(arm: ad.Robot, compiled: object, state: dict[str, np.ndarray], what: str) -> Iterator[tuple]:
    """Per function: (name, kernel name, closed-form call, kernel call, their relative difference), the two
    calls zero-argument and checked to agree."""
    for name, (kernel_name, names, dims) in FUNCTIONS.items():
        args = [state[a] for a in names]
        closed, kernel = partial(getattr(compiled, name), *args), partial(getattr(arm, kernel_name), *args)
        error = check(f"PUMA 560 {what}{name}: closed form vs {kernel_name}", closed(), kernel(), TOLERANCE, dims)
        yield name, kernel_name, closed, kernel, error


def one_state(arm: ad.Robot, compiled: object, rng: np.random.Generator) -> list[list[str]]:
    rows = []
    for name, kernel_name, closed, kernel, error in checked(arm, compiled, random_state(rng, arm.n), ""):
        ours_out, theirs_out = np.empty_like(kernel()), np.empty_like(kernel())
        plain, with_out, reference, reference_out = measure(
            Candidate(closed, CALLS, REPEATS),
            Candidate(partial(closed, out=ours_out), CALLS, REPEATS),
            Candidate(kernel, CALLS, REPEATS),
            Candidate(partial(kernel, out=theirs_out), CALLS, REPEATS),
        )
        rows.append(
            [
                name,
                kernel_name,
                f"{error:.1e}",
                us(plain),
                us(with_out),
                us(reference),
                us(reference_out),
                ratio(plain / reference),
                ratio(with_out / reference_out),
            ]
        )
    return rows


def batch(arm: ad.Robot, compiled: object, rng: np.random.Generator) -> list[list[str]]:
    rows = []
    for name, kernel_name, closed, kernel, error in checked(
        arm, compiled, random_state(rng, arm.n, (BATCH,)), "batch "
    ):
        batched = partial(Candidate, calls=1, repeats=BATCH_REPEATS, states=BATCH)
        ours, theirs = measure(batched(closed), batched(kernel))
        rows.append([name, kernel_name, f"{error:.1e}", us(ours), us(theirs), ratio(ours / theirs)])
    return rows


# ----- 5. the Robotics Toolbox's symbolic RNE ---------------------------------------------------
def toolbox_worker(task: str, state: list[float]) -> None:
    """Runs in a subprocess: builds the Toolbox's symbolic tau, then one task; one line per finished step."""
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (WORKER_MEMORY, WORKER_MEMORY))

    def build() -> tuple:
        import roboticstoolbox as rtb
        from spatialmath.base import sym

        puma = rtb.models.DH.Puma560(symbolic=True)
        return puma, [sym.symbol(f"{name}_:6") for name in ("q", "qd", "qdd")]

    (puma, (q, qd, qdd)), build_s = timed_step("build", build)
    emit("build", seconds=build_s)
    tau, rne_s = timed_step("rne", lambda: puma.rne(q, qd, qdd, gravity=[0.0, 0.0, -9.81]))
    emit("rne", seconds=rne_s, entries=len(tau), kind=type(tau[0]).__name__)
    if task == "simplify":
        simple, simplify_s = timed_step("simplify", lambda: sympy.simplify(tau[0]))
        emit("simplify", seconds=simplify_s, count_ops=int(sympy.count_ops(simple)))
        return

    def cse() -> dict[str, int]:
        exprs = [se.sympify(x) for x in tau]
        replacements, reduced = se.cse(exprs)
        first, first_reduced = se.cse(exprs[:1])
        return {
            "tau0_before": count_operations(exprs[0]),
            "tau0_after": sum(count_operations(x) for _, x in first) + count_operations(first_reduced[0]),
            "tau_before": sum(count_operations(x) for x in exprs),
            "tau_after": sum(count_operations(x) for _, x in replacements) + sum(map(count_operations, reduced)),
        }

    counts, cse_s = timed_step("cse", cse)
    emit("cse", seconds=cse_s, **counts)
    symbols = [se.Symbol(str(s)) for s in (*q, *qd, *qdd)]
    values, evaluate_s = timed_step("evaluate", lambda: se.Lambdify(symbols, [se.sympify(x) for x in tau])(state))
    emit("evaluate", seconds=evaluate_s, values=[float(x) for x in np.ravel(values)])
    ops, count_s = timed_step("count_ops", lambda: sympy.count_ops(tau[0]))
    emit("count_ops", seconds=count_s, value=int(ops))


def worker(task: str, phases: Sequence[tuple[str, float]], state: list[float]) -> dict[str, dict]:
    """Run a Toolbox worker (this script with --toolbox-worker) through its phases (harness.run_worker)."""
    return run_worker([sys.executable, __file__, "--toolbox-worker", task, "--state", json.dumps(state)], phases)


def outcome(result: dict) -> str:
    if "timeout" in result:
        return f"did not finish in {result['timeout']:.0f} s"
    if "error" in result:
        return f"failed after {seconds(result.get('seconds', 0.0))} s: {result['error']}"
    if "skipped" in result:
        return f"not run ({result['skipped']})"
    return seconds(result["seconds"])


def toolbox(
    arm: ad.Robot, form: ClosedForm, derive_s: float, args: argparse.Namespace, rng: np.random.Generator
) -> list[Table]:
    state = random_state(rng, arm.n)
    flat = [float(x) for x in np.concatenate([state["q"], state["qd"], state["qdd"]])]
    print(f"  Toolbox worker 1: rne (limit {args.toolbox_timeout:.0f} s), analysis ...", flush=True)
    analysis = worker(
        "analyse",
        [
            ("build", BUILD_TIMEOUT),
            ("rne", args.toolbox_timeout),
            ("cse", args.count_timeout),
            ("evaluate", args.count_timeout),
            ("count_ops", args.count_timeout),
        ],
        flat,
    )
    print(f"  Toolbox worker 2: simplify (limit {args.simplify_timeout:.0f} s) ...", flush=True)
    simplify = worker(
        "simplify",
        [("build", BUILD_TIMEOUT), ("rne", args.toolbox_timeout), ("simplify", args.simplify_timeout)],
        flat,
    )

    steps = Table("5a. The Toolbox's symbolic RNE for the PUMA 560, step by step", ["step", "seconds", "result"])
    steps.rows.append(["import the Toolbox, Puma560(symbolic=True)", outcome(analysis["build"]), ""])
    rne = analysis["rne"]
    steps.rows.append(
        [
            "puma.rne(q, qd, qdd, gravity=[0, 0, -9.81])",
            outcome(rne),
            f"{rne['entries']} expressions ({rne['kind']})" if "entries" in rne else "",
        ]
    )
    cse = analysis["cse"]
    sizes = f"tau[0] {count(cse['tau0_before'])} -> {count(cse['tau0_after'])} ops" if "tau0_after" in cse else ""
    steps.rows.append(["SymEngine: convert tau, cse, count as armdyn counts", outcome(cse), sizes])
    evaluate = analysis["evaluate"]
    agreement = ""
    if "values" in evaluate:
        q, qd, qdd = state["q"], state["qd"], state["qdd"]
        coulomb = arm.friction(qd) - arm.viscous_friction * qd
        expected = arm.inverse_dynamics(q, qd, qdd) - coulomb
        error = relative_error(evaluate["values"], expected, 1)
        verdict = "agree" if error <= TOLERANCE else "DISAGREE"
        agreement = f"{verdict}: {error:.1e} relative to armdyn without Coulomb friction"
    steps.rows.append(["evaluate tau at a random state (se.Lambdify)", outcome(evaluate), agreement])
    ops = analysis["count_ops"]
    steps.rows.append(
        ["sympy.count_ops(tau[0])", outcome(ops), f"{count(ops['value'])} operations" if "value" in ops else ""]
    )
    simplified = simplify["simplify"]
    steps.rows.append(
        [
            "sympy.simplify(tau[0])",
            outcome(simplified),
            f"count_ops of the result {count(simplified['count_ops'])}" if "count_ops" in simplified else "",
        ]
    )
    steps.notes = [
        "Each worker is a fresh interpreter (the script itself with --toolbox-worker); a step that overruns "
        "its limit stops the worker. Worker 2 builds tau again before simplify "
        f"(its rne, seconds: {outcome(simplify['rne'])}).",
        f"Limits: rne {args.toolbox_timeout:.0f} s (--toolbox-timeout), each analysis {args.count_timeout:.0f} s "
        f"(--count-timeout), simplify {args.simplify_timeout:.0f} s (--simplify-timeout); "
        f"address space {WORKER_MEMORY >> 30} GiB per worker.",
        "The Toolbox's rne() routes symbolic models to rne_python(), which leaves out Coulomb friction when "
        "the call is symbolic; its motor inertia G^2 Jm and viscous friction are in. The check therefore "
        "compares with armdyn's inverse_dynamics minus armdyn's Coulomb friction.",
    ]

    armdyn_tau0 = form.raw.tau[0]
    replacements, reduced = se.cse([armdyn_tau0])
    armdyn_tau0_after = sum(count_operations(x) for _, x in replacements) + count_operations(reduced[0])
    before, after = form.operation_counts(cse=False), form.operation_counts(cse=True)
    sympy_ops, sympy_s = wall(lambda: sympy.count_ops(form.tau[0]))

    def get(event: dict, key: str) -> str:
        return count(event[key]) if key in event else outcome(event)

    compare = Table(
        "5b. The PUMA 560's tau: the Toolbox's symbolic RNE and armdyn's closed form",
        ["quantity", "Toolbox rne_python", "armdyn derive()"],
        [
            ["seconds to build the expressions", outcome(rne), seconds(derive_s)],
            ["tau[0]: sympy.count_ops", get(ops, "value"), count(int(sympy_ops))],
            ["tau[0]: operations (armdyn's counter)", get(cse, "tau0_before"), count(count_operations(armdyn_tau0))],
            ["tau[0]: operations after SymEngine cse", get(cse, "tau0_after"), count(armdyn_tau0_after)],
            ["tau (6 entries): operations", get(cse, "tau_before"), count(before["tau"])],
            ["tau (6 entries): operations after SymEngine cse", get(cse, "tau_after"), count(after["tau"])],
            ["sympy.simplify(tau[0])", outcome(simplified), "-"],
        ],
        notes=[
            "armdyn's counter (armdyn.symbolic.codegen.count_operations, behind form.operation_counts) counts "
            "k - 1 operations per k-term sum or product, one per function call, and |p| - 1 (at least 1) per "
            "integer power p; sympy.count_ops counts negations, subtractions and divisions separately. The "
            "Toolbox's expressions go through se.sympify first.",
            "armdyn's tau includes Coulomb friction (sign(qd) terms), the Toolbox's symbolic tau does not.",
            f"armdyn's sympy.count_ops(form.tau[0]) took {seconds(sympy_s)} s; the derive() time is that of "
            "part 1 (first call).",
        ],
    )
    return [steps, compare]


# ----- the run ----------------------------------------------------------------------------------


def header(source: tuple[str, str], args: argparse.Namespace) -> list[str]:
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
        f"Evaluation times are medians: one state {CALLS} calls x {REPEATS} repeats, batch {BATCH_REPEATS} repeats; "
        "the candidates' repeats are interleaved. The closed form and the kernel are checked to agree "
        f"(to {TOLERANCE:g} relative to the largest entry, state by state) on the same inputs before timing.",
    ]


def main() -> None:
    parser = arguments(__doc__, skip_toolbox="leave out part 5 (the Robotics Toolbox)")
    parser.add_argument("--toolbox-timeout", type=float, default=TOOLBOX_TIMEOUT, help="seconds for its rne()")
    parser.add_argument(
        "--count-timeout", type=float, default=COUNT_TIMEOUT, help="seconds for each analysis of its tau"
    )
    parser.add_argument(
        "--simplify-timeout", type=float, default=SIMPLIFY_TIMEOUT, help="seconds for sympy.simplify(tau[0])"
    )
    parser.add_argument("--toolbox-worker", choices=("analyse", "simplify"), help=argparse.SUPPRESS)
    args = parse(parser, "toolbox_worker", lambda args: toolbox_worker(args.toolbox_worker, json.loads(args.state)))
    report = Report.begin(args, "armdyn closed-form benchmarks", RESULTS, globals(), QUICK, QUICK_LIMITS)
    rng = np.random.default_rng(SEED)
    report.note(*header(report.source, args), end="\n\n")

    forms: dict[str, ClosedForm] = {}
    rows, firsts, totals = derivation(forms)
    fresh_s, inside = fresh_interpreter()
    puma_form = forms["puma560()"]
    puma = puma_form.robot
    compiled, compile_rows = compilation(puma_form, puma.n)
    verdict = "met" if max(totals["puma560()"], inside[1] + inside[2]) < REQUIREMENT else "NOT MET"
    report.show(
        Table(
            "1a. Derivation and code generation (wall seconds)",
            ["arm", "n", "method", "derive 1st", "derive 2nd", "to_python", "to_c", "derive+code", "lines py / C"],
            rows,
            notes=[
                "derive 1st is the first derive() of that arm in this process (the very first, two_link_planar, "
                "also warms SymEngine up); derive 2nd a fresh derive() of the same arm. derive+code is the slower "
                "of the two plus to_python and to_c (each runs its own common-subexpression elimination).",
                "friction=True (the arm's own friction) and motor inertia, as derive() defaults; the three book "
                "examples carry SymPy symbols as parameters, the other arms numbers.",
                f"Requirement, the PUMA 560 with its full parameter set, derivation plus code generation under "
                f"{REQUIREMENT:.0f} s: {verdict} ({totals['puma560()']:.1f} s in this process; "
                f"{inside[1] + inside[2]:.1f} s in a fresh interpreter, see 1b).",
            ],
            left=3,
        )
    )
    report.show(
        Table(
            "1b. PUMA 560: a fresh interpreter, and Numba compilation (wall seconds)",
            ["step", "seconds"],
            [
                ["fresh interpreter: import armdyn", seconds(inside[0])],
                ["fresh interpreter: derive(puma560())", seconds(inside[1])],
                ["fresh interpreter: to_python() + to_c()", seconds(inside[2])],
                ["fresh interpreter: whole run (python -c, wall)", seconds(fresh_s)],
                *compile_rows,
            ],
            notes=[
                "form.compile() substitutes the parameters, generates Python and compiles the four one-state "
                "functions with Numba (eagerly, with signatures); each batch loop (parallel) is compiled on "
                "its first batch call. Nothing is cached between processes."
            ],
        )
    )
    report.show(
        Table(
            "2. Operation counts before and after common-subexpression elimination",
            ["arm", "function", "before CSE", "after CSE", "after/before"],
            operation_counts(forms),
            notes=["form.operation_counts(cse=False) and (cse=True); SymEngine's cse over all entries of a function."],
            left=2,
        )
    )
    report.show(
        Table(
            "3. PUMA 560, one state per call: compiled closed form vs recursive kernel (microseconds per call)",
            ["function", "kernel", "max rel. error", "closed", "closed out=", "kernel", "kernel out=", "ratio", "out="],
            one_state(puma, compiled, rng),
            notes=[
                "ratio = closed-form time / kernel time (below 1: the closed form is faster); out= writes into a "
                "preallocated array in both.",
                "The PUMA 560 with motor inertia and friction; M(q) = arm.inertia_matrix, G = gravity_vector, "
                "Vm = coriolis_matrix, tau = inverse_dynamics.",
            ],
            left=2,
        )
    )
    report.show(
        Table(
            f"4. PUMA 560, a batch of {BATCH:,} states (microseconds per state)",
            ["function", "kernel", "max rel. error", "closed form", "kernel", "ratio"],
            batch(puma, compiled, rng),
            notes=[
                "(B, n) arrays, C-ordered; both sides run Numba-parallel loops over the states "
                f"({numba.get_num_threads()} threads). ratio = closed-form time / kernel time."
            ],
            left=2,
        )
    )
    if args.skip_toolbox:
        report.note("Part 5 (the Robotics Toolbox's symbolic RNE) skipped: --skip-toolbox.")
    else:
        for table in toolbox(puma, puma_form, firsts["puma560()"], args, rng):
            report.show(table)

    report.finish("the subprocesses may have run another version than this process.")


if __name__ == "__main__":
    main()
