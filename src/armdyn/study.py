"""Monte Carlo studies of the arm under control: sampling, blocks, Dask, statistics.

A ``Study`` declares what is uncertain (payload, link masses, friction, the start) as
distributions, a controller that believes in the nominal arm, and a specification such as
"max_error_after < 1e-3". ``Study.run(runs, seed)`` draws the runs in fixed blocks: block b's
random stream is ``SeedSequence(seed, spawn_key=(b,))``, so a run's parameters, and therefore
its result, do not depend on how the blocks are spread over threads, processes or machines.
Each block is one compiled call of the many-runs path of ``simulate`` (``runs=``) on arrays
(``Setup``: the packed nominal arm, the law's gains, the path), never a pickled Robot. Blocks run
in this process by default; with
``scheduler="local-cluster"`` on a ``dask.distributed.LocalCluster``, or with an address on an
existing cluster (each worker one task thread, its Numba thread count set, its compiled-code cache
warmed before work is sent; a block lost with its worker is recomputed, to the same bits). With
``out=`` each block is written as it arrives (Parquet, one file per block) and a rerun skips
the blocks already there.

The estimate of P(spec holds) is k / N with the exact Clopper-Pearson interval (Clopper and
Pearson 1934); ``runs_needed`` gives Hoeffding's N >= ln(2 / delta) / (2 eps^2) for an accuracy eps
at confidence 1 - delta, whatever the probability (the statistical learning view of robust
control design, Koltchinskii et al. 1999, cited in the book's Chapter 3 references).
"""

from __future__ import annotations

import json
import math
import operator
import os
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn import control, inputs, trajectories
from armdyn.errors import ArgumentError, MissingDependencyError, ModelError
from armdyn.robot import Robot
from armdyn.simulation import SUMMARY_NAMES, Nominal, launch_many, law_table, nominal, vary_packed

if TYPE_CHECKING:
    from pandas import DataFrame

__all__ = ["Estimate", "Normal", "Requirement", "Study", "StudyResult", "Uniform", "clopper_pearson", "runs_needed"]

RUNS_PER_BLOCK = 1000
"""Runs per block: the unit of sampling, of work sent to a worker and of the files written."""


# ----- distributions ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Uniform:
    """Uniform on [low, high] (low <= high; low == high is the constant).

    Parameters
    ----------
    low, high : float
        The bounds.
    """

    low: float
    high: float

    def __post_init__(self) -> None:
        low, high = inputs.number(self.low, "low"), inputs.number(self.high, "high")
        if low > high:
            raise ModelError(f"Uniform needs low <= high, got low = {low:g} > high = {high:g}")
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)

    def sample(self, rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        """Draws of the given shape from ``rng``.

        Parameters
        ----------
        rng : numpy.random.Generator
            The stream.
        shape : tuple of int
            The draws' shape.

        Returns
        -------
        numpy.ndarray
            The draws.

        Raises
        ------
        None
            Its parameters were checked when it was made.
        """
        return rng.uniform(self.low, self.high, shape)


@dataclass(frozen=True)
class Normal:
    """Normal with mean and standard deviation std >= 0, optionally truncated to [low, high] (by
    redrawing).

    Parameters
    ----------
    mean, std : float
        Its parameters.
    low, high : float, optional
        Truncation bounds (default none).
    """

    mean: float
    std: float
    low: float = -math.inf
    high: float = math.inf

    def __post_init__(self) -> None:
        mean, std = inputs.number(self.mean, "mean"), inputs.number(self.std, "std")
        if std < 0:
            raise ModelError(f"Normal needs std >= 0, got {std:g}")
        low, high = float(self.low), float(self.high)
        if not low < high or math.isnan(low) or math.isnan(high):
            raise ModelError(f"Normal needs low < high, got [{low:g}, {high:g}]")
        if std == 0 and not low <= mean <= high:
            raise ModelError(f"Normal with std 0 needs low <= mean <= high, got mean = {mean:g}")
        for key, value in (("mean", mean), ("std", std), ("low", low), ("high", high)):
            object.__setattr__(self, key, value)

    def sample(self, rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        """Draws of the given shape from ``rng`` (truncated draws are redrawn, at most 100 rounds).

        Parameters
        ----------
        rng : numpy.random.Generator
            The stream.
        shape : tuple of int
            The draws' shape.

        Returns
        -------
        numpy.ndarray
            The draws.

        Raises
        ------
        armdyn.ModelError
            When the truncation window holds almost none of the distribution.
        """
        draws = rng.normal(self.mean, self.std, shape)
        for _ in range(100):
            outside = (draws < self.low) | (draws > self.high)
            if not outside.any():
                return draws
            draws[outside] = rng.normal(self.mean, self.std, int(outside.sum()))
        raise ModelError(f"Normal({self.mean:g}, {self.std:g}) truncated to [{self.low:g}, {self.high:g}] holds "
                         "almost none of its mass")  # fmt: skip


Distribution = Uniform | Normal


def _distribution(value: object, name: str) -> Distribution | None:
    """None, a Uniform or Normal, or a number (a constant)."""
    if value is None or isinstance(value, (Uniform, Normal)):
        return value
    number = inputs.number(value, name)
    return Uniform(number, number)


# ----- the specification ------------------------------------------------------------------------------------
_OPERATORS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}
_PARAMETERS = ("payload", "mass_scale", "friction_scale")


@dataclass(frozen=True)
class Requirement:
    """A requirement a run meets or not: clauses "quantity op bound" joined by "and".

    Quantities: a summary of many runs of ``simulate`` (final_error, max_error_after, rms_error, max_tau,
    largest over the joints, or for one joint as "max_error_after q2"), or a sampled parameter
    (payload, mass_scale, friction_scale). Hyphens may stand for underscores, and
    "max-error-after-1s" sets the window's start to 1 s.

    Parameters
    ----------
    text : str
        E.g. "max_error_after < 1e-3", "max-error-after-0.5s<2e-3 and max_tau < 200".
    """

    text: str
    clauses: tuple = field(init=False)
    after: float | None = field(init=False)

    def __post_init__(self) -> None:
        if not isinstance(self.text, str) or not self.text.strip():
            raise ModelError(f"a spec must be text such as 'max_error_after < 1e-3', got {self.text!r}")
        clauses, after = [], None
        for part in re.split(r"\band\b", self.text):
            match = re.fullmatch(r"\s*([A-Za-z_][\w\-.]*(?:\s+\w+)?)\s*(<=|>=|<|>)\s*([-+0-9.eE]+)\s*", part)
            if match is None:
                raise ModelError(f"cannot read the spec clause {part.strip()!r}: write 'quantity < bound', e.g. "
                                 "'max_error_after < 1e-3'")  # fmt: skip
            name, op, bound = match.groups()
            window = re.fullmatch(r"max[-_]error[-_]after[-_]([0-9.]+)s", name.strip())
            if window is not None:
                after, name = float(window.group(1)), "max_error_after"
            quantity, _, joint = name.strip().replace("-", "_").partition(" ")
            if quantity not in (*SUMMARY_NAMES[:4], *_PARAMETERS):
                raise ModelError(f"the spec names an unknown quantity {quantity!r}: use one of "
                                 f"{', '.join((*SUMMARY_NAMES[:4], *_PARAMETERS))}")  # fmt: skip
            clauses.append((quantity if not joint else f"{quantity} {joint}", op, float(bound)))
        object.__setattr__(self, "clauses", tuple(clauses))
        object.__setattr__(self, "after", after)

    def holds(self, table: DataFrame) -> np.ndarray:
        """(N,) bool: the rows of a study's table (a DataFrame) that meet every clause (and finished).

        Parameters
        ----------
        table : pandas.DataFrame
            A study's per-run table.

        Returns
        -------
        numpy.ndarray
            True where the run meets the spec.

        Raises
        ------
        armdyn.ModelError
            When a clause names a joint the arm does not have.
        """
        result = np.asarray(table["finished"], dtype=bool).copy()
        for column, op, bound in self.clauses:
            if column not in table:
                raise ModelError(f"the spec names {column!r}, which this study has no column for")
            result &= _OPERATORS[op](np.asarray(table[column], dtype=float), bound)
        return result


# ----- statistics --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Estimate:
    """P(spec holds) from N runs: k / N with its Clopper-Pearson interval at ``confidence``.

    Parameters
    ----------
    successes, runs : int
        k and N.
    probability : float
        k / N.
    low, high : float
        The exact two-sided interval.
    confidence : float
        1 - delta.
    """

    successes: int
    runs: int
    probability: float
    low: float
    high: float
    confidence: float

    def __str__(self) -> str:
        return (f"P(spec) = {self.probability:.4f} ({self.successes} of {self.runs} runs), "
                f"{self.confidence:.0%} interval [{self.low:.4f}, {self.high:.4f}]")  # fmt: skip


def clopper_pearson(successes: int, runs: int, confidence: float = 0.95) -> Estimate:
    """The exact binomial interval (Clopper and Pearson 1934) for k successes in N runs.

    Parameters
    ----------
    successes, runs : int
        k and N, 0 <= k <= N, N >= 1.
    confidence : float, optional
        1 - delta, in (0, 1) (default 0.95).

    Returns
    -------
    Estimate
        k / N and the interval.

    Raises
    ------
    armdyn.ModelError
        When the counts or the confidence are out of range.
    """
    from scipy.stats import beta

    runs = inputs.integer(runs, "runs", 1)
    successes = inputs.integer(successes, "successes", 0, runs)
    confidence = _confidence(confidence)
    alpha = 1 - confidence
    low = 0.0 if successes == 0 else float(beta.ppf(alpha / 2, successes, runs - successes + 1))
    high = 1.0 if successes == runs else float(beta.ppf(1 - alpha / 2, successes + 1, runs - successes))
    return Estimate(successes, runs, successes / runs, low, high, confidence)


def runs_needed(accuracy: float, confidence: float = 0.95) -> int:
    """Hoeffding's sample size: N >= ln(2 / delta) / (2 eps^2) runs put k / N within eps of the
    probability with confidence 1 - delta, whatever the probability.

    Parameters
    ----------
    accuracy : float
        eps, in (0, 1).
    confidence : float, optional
        1 - delta, in (0, 1) (default 0.95).

    Returns
    -------
    int
        N.

    Raises
    ------
    armdyn.ModelError
        When eps or the confidence is out of range.
    """
    accuracy = inputs.number(accuracy, "accuracy")
    if not 0 < accuracy < 1:
        raise ModelError(f"accuracy must be in (0, 1), got {accuracy:g}")
    delta = 1 - _confidence(confidence)
    return math.ceil(math.log(2 / delta) / (2 * accuracy**2))


def _confidence(value: object) -> float:
    confidence = inputs.number(value, "confidence")
    if not 0 < confidence < 1:
        raise ModelError(f"confidence must be in (0, 1), got {confidence:g}")
    return confidence


# ----- the study ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Setup:
    """Everything a block needs, as arrays and small records: what a worker receives (no Robot).

    Attributes hold the nominal arm (``Nominal``), the law (kind, gains (4, n), hold, the belief's
    packed model and Coulomb), the path (kind, params (4, n)), the start, the timing and the
    declared distributions.
    """

    arm: Nominal
    joints: tuple
    law: tuple
    path: tuple
    q0: np.ndarray
    dt: float
    rows: int
    after_row: int
    payload: Distribution | None
    mass_error: Distribution | None
    friction_error: Distribution | None
    start_error: Distribution | None
    seed: int
    block: int
    runs: int


def run_block(setup: Setup, index: int, threads: int | None = None) -> DataFrame:
    """Block ``index`` of a study: its runs' parameters from SeedSequence(seed, spawn_key=(index,)),
    one compiled call of simulate's many-runs path (launch_many), and a DataFrame of the runs (run id,
    parameters, summaries, finished). The same block gives the same bits wherever it runs.

    Parameters
    ----------
    setup : Setup
        The study's arrays.
    index : int
        The block's number.
    threads : int, optional
        Numba threads for the call.

    Returns
    -------
    pandas.DataFrame
        One row per run of the block.

    Raises
    ------
    armdyn.ModelError
        When a sampled parameter breaks its rule (a negative payload or a mass scale <= 0).
    """
    import pandas

    first = index * setup.block
    count = min(setup.block, setup.runs - first)
    n = setup.q0.shape[0]
    rng = np.random.default_rng(np.random.SeedSequence(setup.seed, spawn_key=(index,)))
    # each quantity is drawn, in this order, whether declared or not: adding one keeps the others' draws
    draws = {name: (dist or Uniform(0.0, 0.0)).sample(rng, shape) for name, dist, shape in (
        ("payload", setup.payload, (count,)), ("mass_scale", setup.mass_error, (count, n)),
        ("friction_scale", setup.friction_error, (count, n)), ("start", setup.start_error, (count, n)))}  # fmt: skip
    scale = 1.0 + draws["mass_scale"] if setup.mass_error is not None else np.ones((count, n))
    friction = 1.0 + draws["friction_scale"] if setup.friction_error is not None else np.ones((count, n))
    if np.any(draws["payload"] < 0) or np.any(scale <= 0) or np.any(friction < 0):
        raise ModelError("a sampled payload is negative or a mass scale is not positive: bound the distributions")
    packed, coulomb = vary_packed(setup.arm, draws["payload"], np.zeros((count, 3)), np.zeros((count, 3)), scale,
                                  friction)  # fmt: skip
    kind, gains, hold, belief, belief_coulomb = setup.law
    zeros = np.zeros(count, dtype=np.int64)
    summaries, outcome, _ = launch_many(
        (packed, coulomb, np.arange(count, dtype=np.int64), np.zeros((count, n))),
        (belief[None], belief_coulomb[None], zeros, np.zeros(count, dtype=np.bool_)),
        (kind, np.ascontiguousarray(np.broadcast_to(gains, (count, 4, n))), hold),
        (setup.path[0], np.ascontiguousarray(np.broadcast_to(setup.path[1], (count, *setup.path[1].shape)))),
        (setup.q0 + draws["start"], np.zeros((count, n))),
        (setup.dt, setup.rows, 0, setup.after_row),
        threads,
    )  # fmt: skip
    columns: dict[str, np.ndarray] = {"run": np.arange(first, first + count), "payload": draws["payload"]}
    columns |= {"mass_scale": scale.mean(axis=1), "friction_scale": friction.mean(axis=1)}
    for k, name in enumerate(SUMMARY_NAMES[:4]):
        columns[name] = np.abs(summaries[:, k]).max(axis=1)
        columns |= {f"{name} {joint}": np.abs(summaries[:, k, j]) for j, joint in enumerate(setup.joints)}
    columns["finished"] = outcome[:, 0] < 0
    return pandas.DataFrame(columns)


@dataclass
class StudyResult:
    """A study's runs and its estimate.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per run: run id, sampled parameters, summaries, finished, and "holds".
    estimate : Estimate
        P(spec holds) with its interval.
    spec : Requirement
        The requirement.
    info : dict
        runs, seed, block, scheduler, blocks computed here (the others were read from ``out``),
        the dashboard link of a cluster.
    """

    table: DataFrame
    estimate: Estimate
    spec: Requirement
    info: dict

    def plot(self, path: str | Path | None = None) -> object:
        """Histograms of the spec's quantities over the runs, the bound marked, and the estimate in the title.

        Parameters
        ----------
        path : str or Path, optional
            Write the figure there (PNG).

        Returns
        -------
        matplotlib.figure.Figure
            The figure.

        Raises
        ------
        None
            It draws what the table holds.
        """
        from armdyn.plotting import plot_study

        return plot_study(self, path)


class Study:
    """A Monte Carlo study of a controlled arm under declared uncertainty (see the module docstring).

    Parameters
    ----------
    arm : Robot
        The nominal arm (numeric).
    controller : ComputedTorque, PDGravity or PID (or inside Digital or Saturated)
        The law; its model (the belief) is the nominal arm unless the controller names one.
    trajectory : Sinusoid, Quintic or None, optional
        The desired path (None holds the start).
    spec : str or Requirement, optional
        The requirement (default "max_error_after < 1e-3").
    t_final, dt, after : float, optional
        Each run's length, the RK4 step and the start of the "after" window (s); a spec's
        "max-error-after-Ts" sets ``after``.
    q0 : array_like, optional
        The nominal start (default the arm's qn or qz, else zeros).
    payload : Uniform, Normal or float, optional
        The payload's mass at the tool (kg), >= 0.
    mass_error, friction_error : Uniform, Normal or float, optional
        Relative errors of each link's mass properties and friction: the plant's are (1 + e) times the
        nominal, one draw per link.
    start_error : Uniform, Normal or float, optional
        An offset added to each joint's start (rad or m).
    block : int, optional
        Runs per block (default 1000).

    Raises
    ------
    armdyn.ModelError
        When a distribution is invalid or the spec unreadable.
    armdyn.ArgumentError
        When the arm is not a numeric Robot, the controller is not one of armdyn.control's laws, or
        the trajectory is not a Sinusoid or Quintic.
    """

    def __init__(
        self,
        arm: Robot,
        controller: object,
        trajectory: object = None,
        spec: str | Requirement = "max_error_after < 1e-3",
        t_final: float = 5.0,
        dt: float = 1e-3,
        after: float = 1.0,
        q0: object = None,
        payload: object = None,
        mass_error: object = None,
        friction_error: object = None,
        start_error: object = None,
        block: int = RUNS_PER_BLOCK,
    ) -> None:
        from armdyn.simulation import checked_times, packed_plants, step_count, unwrapped_law

        inputs.arm_argument(arm, Robot, "arm", numeric=True, why=" (a study runs compiled code)")
        n = arm.n
        self.arm, self.spec = arm, spec if isinstance(spec, Requirement) else Requirement(spec)
        self.t_final, self.dt = checked_times(t_final, dt)
        step_count(self.t_final, self.dt, n, False)  # refuses runs too long to record
        after = self.spec.after if self.spec.after is not None else inputs.number(after, "after", minimum=0.0)
        self.after = after
        law_spec, period, self.controller = unwrapped_law(controller, n)
        if law_spec is None or controller is None:
            raise ArgumentError("a study runs one of armdyn.control's laws (ComputedTorque, PDGravity, PID)")
        gains, hold = law_table(law_spec, period, self.dt, n)
        belief, belief_coulomb = packed_plants([law_spec.model if law_spec.model is not None else arm])
        path = trajectories.packed(trajectory, n)
        if path is None:
            raise ArgumentError("a study's trajectory must be None, an armdyn.trajectories.Sinusoid or a Quintic")
        start = q0 if q0 is not None else arm.configurations.get("qn", arm.configurations.get("qz", np.zeros(n)))
        start = inputs.numbers(start, "q0", (n,))
        self.trajectory = trajectory
        self.distributions = {name: _distribution(value, name) for name, value in (
            ("payload", payload), ("mass_error", mass_error), ("friction_error", friction_error),
            ("start_error", start_error))}  # fmt: skip
        self.block = inputs.integer(block, "block", 1)
        self._setup: dict[str, Any] = dict(arm=nominal(arm), joints=tuple(arm.joint_names),
                           law=(law_spec.kind, gains, hold, belief[0], belief_coulomb[0]), path=path, q0=start,
                           dt=self.dt, rows=round(self.t_final / self.dt) + 1,
                           after_row=math.ceil(after / self.dt - 1e-9), **self.distributions)  # fmt: skip

    def setup(self, runs: int, seed: int) -> Setup:
        """The arrays a block needs for ``runs`` runs from ``seed``.

        Parameters
        ----------
        runs : int
            N >= 1.
        seed : int
            The study's seed, >= 0.

        Returns
        -------
        Setup
            What workers receive.

        Raises
        ------
        armdyn.ModelError
            When runs or seed is out of range.
        """
        runs, seed = inputs.integer(runs, "runs", 1), inputs.integer(seed, "seed", 0)
        return Setup(seed=seed, block=self.block, runs=runs, **self._setup)

    def run(
        self,
        runs: int,
        seed: int = 0,
        scheduler: str | None = None,
        out: str | Path | None = None,
        confidence: float = 0.95,
        workers: int = 2,
        progress: Callable[[float], None] | None = None,
        timeout: float = 10.0,
    ) -> StudyResult:
        """Run the study: ``runs`` runs in blocks, locally or on Dask, and estimate P(spec holds).

        Parameters
        ----------
        runs : int
            N.
        seed : int, optional
            The seed (default 0); the same seed gives the same runs wherever they are computed.
        scheduler : None, "local-cluster" or str, optional
            None runs the blocks here (the compiled calls use every thread); "local-cluster"
            starts a dask.distributed LocalCluster of ``workers`` processes; "tcp://host:port"
            uses a running scheduler.
        out : str or Path, optional
            A folder for the blocks (Parquet) and the study's description; blocks found there
            are read, not recomputed.
        confidence : float, optional
            Of the interval (default 0.95).
        workers : int, optional
            The LocalCluster's processes (default 2).
        progress : callable, optional
            Called with the fraction of blocks done.
        timeout : float, optional
            Seconds to wait for a scheduler before giving up (default 10).

        Returns
        -------
        StudyResult
            The table of runs, the estimate and what ran where.

        Raises
        ------
        armdyn.ModelError
            When the arguments are out of range, ``out`` holds another study, the scheduler
            cannot be reached within ``timeout`` (nothing computed is lost: the blocks written to
            ``out`` stay).
        armdyn.MissingDependencyError
            When ``scheduler`` needs Dask, or ``out`` needs pyarrow (Parquet), and it is not installed
            (both come with armdyn's ``cluster`` extra).
        """
        import pandas

        from armdyn import memory

        setup = self.setup(runs, seed)
        columns = 6 + 4 * (len(setup.joints) + 1)
        memory.affordable(8.0 * setup.runs * columns + 8.0 * min(setup.block, setup.runs) * 30 * len(setup.joints),
                          f"the table of {setup.runs} runs")  # fmt: skip
        blocks = math.ceil(setup.runs / setup.block)
        if out is not None:
            _parquet_writer()
        folder = _study_folder(out, self, setup) if out is not None else None
        done = {b: pandas.read_parquet(_block_file(folder, b)) for b in range(blocks)
                if folder is not None and _block_file(folder, b).exists()}  # fmt: skip
        todo = [b for b in range(blocks) if b not in done]
        info = {"runs": setup.runs, "seed": setup.seed, "block": setup.block, "scheduler": scheduler or "local",
                "computed": len(todo), "read": len(done)}  # fmt: skip

        def arrived(index: int, table: DataFrame) -> None:
            done[index] = table
            if folder is not None:
                _write_block(folder, index, table)
            if progress is not None:
                progress(len(done) / blocks)

        if scheduler is None or scheduler == "local":
            for index in todo:
                arrived(index, run_block(setup, index))
        else:
            info |= _on_dask(setup, todo, scheduler, workers, timeout, arrived)
        table = pandas.concat([done[b] for b in range(blocks)], ignore_index=True)
        table["holds"] = self.spec.holds(table)
        estimate = clopper_pearson(int(table["holds"].sum()), len(table), confidence)
        return StudyResult(table, estimate, self.spec, info)


def _parquet_writer() -> None:
    """A MissingDependencyError unless pyarrow, which reads and writes the blocks, is installed."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MissingDependencyError("pyarrow", "cluster", needed_by="armdyn.Study.run(out=...)") from None


def _block_file(folder: Path, index: int) -> Path:
    return folder / f"block-{index:06d}.parquet"


def _write_block(folder: Path, index: int, table: DataFrame) -> None:
    """Write a block atomically: a file that exists is a whole block."""
    target = _block_file(folder, index)
    partial = target.with_suffix(".partial")
    table.to_parquet(partial, index=False)
    os.replace(partial, target)


def _study_folder(out: str | Path, study: Study, setup: Setup) -> Path:
    """The study's folder, made if missing; a ModelError when it holds another study's blocks."""
    folder = Path(out)
    description = {"arm": study.arm.name, "spec": study.spec.text, "seed": setup.seed, "block": setup.block,
                   "runs": setup.runs, "t_final": study.t_final, "dt": study.dt, "after": study.after,
                   "controller": control.describe_controller(study.controller),
                   "trajectory": trajectories.describe_trajectory(study.trajectory),
                   "distributions": {k: repr(v) for k, v in study.distributions.items()}}  # fmt: skip
    if folder.exists() and not folder.is_dir():
        raise ModelError(f"out {folder} is a file, not a folder")
    folder.mkdir(parents=False, exist_ok=True)
    stamp = folder / "study.json"
    if stamp.exists():
        previous = json.loads(stamp.read_text())
        if previous != description:
            changed = sorted(k for k in description if previous.get(k) != description[k])
            raise ModelError(f"{folder} holds another study (it differs in {', '.join(changed)}): give another out")
    else:
        stamp.write_text(json.dumps(description, indent=1))
    return folder


def _warm(threads: int) -> str:
    """On a worker: set Numba's thread count and load (or compile) the study's kernels once."""
    import numba

    from armdyn import models
    from armdyn.simulation import simulate

    numba.set_num_threads(threads)
    simulate(models.two_link_planar(), control.PDGravity(1.0, 1.0), None, t_final=0.002, runs=1)
    return "warm"


def _on_dask(setup: Setup, todo: list[int], scheduler: str, workers: int, timeout: float,
             arrived: Callable[[int, DataFrame], None]) -> dict:  # fmt: skip
    """The blocks ``todo`` on a Dask cluster: one task per block, each worker one task thread with
    one Numba thread, its kernels warmed first; lost blocks are recomputed by Dask (retries)."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise MissingDependencyError(
            "dask.distributed", "cluster", needed_by="armdyn.Study.run(scheduler=...)"
        ) from None
    cluster = None
    if scheduler == "local-cluster":
        workers = inputs.integer(workers, "workers", 1, 4 * (os.cpu_count() or 1), " (4 per core)")
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                               env={"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"})  # fmt: skip
        address = cluster.scheduler_address
    elif isinstance(scheduler, str) and re.fullmatch(r"(tcp|tls)://[\w.\-]+:\d+", scheduler):
        address = scheduler
    else:
        raise ModelError(f"scheduler must be None, 'local', 'local-cluster' or an address tcp://host:port, got "
                         f"{scheduler!r}")  # fmt: skip
    try:
        client = Client(address, timeout=f"{timeout}s")
    except (OSError, TimeoutError) as error:
        if cluster is not None:
            cluster.close()
        raise ModelError(f"cannot reach the Dask scheduler at {address} within {timeout:g} s ({error}); nothing "
                         "was lost: the blocks already written stay in out") from None  # fmt: skip
    try:
        link = client.dashboard_link
        client.run(_warm, 1)  # every worker loads its compiled kernels before work arrives
        shared = client.scatter(setup, broadcast=True)
        futures = {client.submit(run_block, shared, index, 1, key=f"armdyn-block-{setup.seed}-{index}",
                                 retries=3): index for index in todo}  # fmt: skip
        for future in as_completed(futures):
            arrived(futures[future], future.result())
        return {"dashboard": link, "workers": len(client.scheduler_info()["workers"])}
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
