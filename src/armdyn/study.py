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
existing cluster (each worker one task thread, its Numba thread count set within the pool Numba started
with, its kernels loaded before work is sent: a one-run block of the study, the blocks' own argument types,
run first in this process when the workers share its machine and cache, so that they load what it compiled
and compile nothing themselves, ``info["compiled_on_workers"]``); a block lost with its worker is recomputed, to
the same bits, and when every worker is lost the set-up is scattered again to those that come back).

With ``out=`` the folder is a store that a crash cannot corrupt: study.json holds the study's fingerprint
(the SHA-256 of the arm's packed model and gravity, the start, the controller and its model, the path,
the timing, the criteria, the sampling, the seed, the block size, the number of runs and armdyn's
version, and of each part), and each block is a Parquet file with a record (its run range, row count,
the file's SHA-256 and the fingerprint). Every file is written to a temporary file in the folder,
fsynced and renamed, the record before its block. A rerun reads the blocks that match their record
and computes the others: one that is missing, or whose record is missing, was never finished; one
that does not match its record (truncated, altered, another block's copy) is reported with a
``DamagedBlockWarning`` and computed again (or refused, ``damaged="refuse"``). A rerun with another
fingerprint is refused, naming the parts that differ. A damaged study.json is written again (with a
warning) when no block record there names another study, else refused: remove the folder.

The estimate of P(spec holds) is k / N with the exact Clopper-Pearson interval (Clopper and
Pearson 1934); ``runs_needed`` gives Hoeffding's N >= ln(2 / delta) / (2 eps^2) for an accuracy eps
at confidence 1 - delta, whatever the probability (the statistical learning view of robust
control design, Koltchinskii et al. 1999, cited in the book's Chapter 3 references).
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import operator
import os
import re
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn import control, inputs, trajectories
from armdyn.errors import ArgumentError, MissingDependencyError, ModelError
from armdyn.robot import Robot
from armdyn.simulation import SUMMARY_NAMES, Nominal, launch_many, law_table, nominal, vary_packed

if TYPE_CHECKING:
    from pandas import DataFrame

__all__ = [
    "DamagedBlockWarning",
    "Estimate",
    "Normal",
    "Requirement",
    "Study",
    "StudyResult",
    "Uniform",
    "clopper_pearson",
    "fingerprint",
    "runs_needed",
]

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

    def sample(self, rng: np.random.Generator, shape: tuple[int, ...], name: str = "") -> np.ndarray:
        """Draws of the given shape from ``rng``.

        Parameters
        ----------
        rng : numpy.random.Generator
            The stream.
        shape : tuple of int
            The draws' shape.
        name : str, optional
            The argument the distribution was given as, for a message.

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
        low, high = (_bound(value, name) for value, name in ((self.low, "low"), (self.high, "high")))
        if not low < high or math.isnan(low) or math.isnan(high):
            raise ModelError(f"Normal needs low < high, got [{low:g}, {high:g}]")
        if std == 0 and not low <= mean <= high:
            raise ModelError(f"Normal with std 0 needs low <= mean <= high, got mean = {mean:g}")
        if std > 0 and _mass(mean, std, low, high) < 1e-6:
            raise ModelError(f"Normal({mean:g}, {std:g}) truncated to low = {low:g}, high = {high:g} holds almost none "
                             "of its mass (below 1e-6): widen low and high or move the mean between them")  # fmt: skip
        for key, value in (("mean", mean), ("std", std), ("low", low), ("high", high)):
            object.__setattr__(self, key, value)

    def sample(self, rng: np.random.Generator, shape: tuple[int, ...], name: str = "") -> np.ndarray:
        """Draws of the given shape from ``rng`` (truncated draws are redrawn, at most 100 rounds).

        Parameters
        ----------
        rng : numpy.random.Generator
            The stream.
        shape : tuple of int
            The draws' shape.
        name : str, optional
            The argument the distribution was given as, for a message.

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
        raise ModelError(f"{name + ': ' if name else ''}Normal({self.mean:g}, {self.std:g}) truncated to low = "
                         f"{self.low:g}, high = {self.high:g} holds almost none of its mass: widen low and high or "
                         "move the mean between them")  # fmt: skip


Distribution = Uniform | Normal


def _mass(mean: float, std: float, low: float, high: float) -> float:
    """The probability a Normal(mean, std) draw falls in [low, high]."""
    scale = std * math.sqrt(2.0)
    return 0.5 * (math.erf((high - mean) / scale) - math.erf((low - mean) / scale))


def _bound(value: object, name: str) -> float:
    """A truncation bound: a real number or an infinity (no bound), or a ModelError naming it."""
    if isinstance(value, (float, np.floating)) and math.isinf(value):
        return float(value)
    return inputs.number(value, name)


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
                after, name = _spec_number(window.group(1), part, "the window's start"), "max_error_after"
            quantity, _, joint = name.strip().replace("-", "_").partition(" ")
            if quantity not in (*SUMMARY_NAMES[:4], *_PARAMETERS):
                raise ModelError(f"the spec names an unknown quantity {quantity!r}: use one of "
                                 f"{', '.join((*SUMMARY_NAMES[:4], *_PARAMETERS))}")  # fmt: skip
            clauses.append((quantity if not joint else f"{quantity} {joint}", op, _spec_number(bound, part, "bound")))
        object.__setattr__(self, "clauses", tuple(clauses))
        object.__setattr__(self, "after", after)

    @property
    def windowed(self) -> bool:
        """True when a clause reads the error after the window's start (max_error_after)."""
        return any(column.startswith("max_error_after") for column, _, _ in self.clauses)

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


def _spec_number(text: str, clause: str, what: str) -> float:
    """A number of a spec clause, or a ModelError naming the clause."""
    try:
        return float(text)
    except ValueError:
        raise ModelError(f"the spec clause {clause.strip()!r} has a {what} {text!r} that is not a number, e.g. "
                         "'max_error_after < 1e-3'") from None  # fmt: skip


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
    draws = {name: (dist or Uniform(0.0, 0.0)).sample(rng, shape, argument) for name, argument, dist, shape in (
        ("payload", "payload", setup.payload, (count,)), ("mass_scale", "mass_error", setup.mass_error, (count, n)),
        ("friction_scale", "friction_error", setup.friction_error, (count, n)),
        ("start", "start_error", setup.start_error, (count, n)))}  # fmt: skip
    scale = 1.0 + draws["mass_scale"] if setup.mass_error is not None else np.ones((count, n))
    friction = 1.0 + draws["friction_scale"] if setup.friction_error is not None else np.ones((count, n))
    if np.any(draws["payload"] < 0) or np.any(scale <= 0) or np.any(friction < 0):
        raise ModelError("a sampled payload is negative or a mass scale is not positive: bound the distributions")
    packed, coulomb = vary_packed(setup.arm, draws["payload"], np.zeros((count, 3)), np.zeros((count, 3)), scale,
                                  friction)  # fmt: skip
    kind, gains, hold, belief, belief_coulomb = setup.law
    zeros = np.zeros(count, dtype=np.int64)
    # writeable copies whatever the count and wherever the set-up came from (a one-run broadcast is already
    # contiguous and would pass read-only, as could an array a worker received: another signature, compiled again)
    summaries, outcome, _ = launch_many(
        (packed, coulomb, np.arange(count, dtype=np.int64), np.zeros((count, n))),
        (belief[None].copy(), belief_coulomb[None].copy(), zeros, np.zeros(count, dtype=np.bool_)),
        (kind, np.broadcast_to(gains, (count, 4, n)).copy(), hold),
        (setup.path[0], np.broadcast_to(setup.path[1], (count, *setup.path[1].shape)).copy()),
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
        the dashboard link of a cluster, and ``compiled_on_workers``: each worker's count of the functions
        Numba compiled (not loaded from its cache) while it warmed up, 0 when it found the kernels cached.
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
        if self.spec.windowed and not after < self.t_final:
            raise ModelError(f"the spec {self.spec.text!r} reads the error after {after:g} s, but the runs end at "
                             f"t_final = {self.t_final:g} s: the window is empty; give after < t_final")  # fmt: skip
        self.after = after
        law_spec, period, self.controller = unwrapped_law(controller, n)
        if law_spec is None or controller is None:
            raise ArgumentError("controller must be one of armdyn.control's laws (ComputedTorque, PDGravity, PID, "
                                "in Digital or Saturated): a study runs one, got "
                                f"{type(controller).__name__}")  # fmt: skip
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
        damaged: str = "recompute",
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
            A folder for the blocks (Parquet, each with a record of its runs and checksum) and the
            study's fingerprint (study.json, written atomically); blocks found there that match their
            record are read, not recomputed. A folder holding another study is refused.
        confidence : float, optional
            Of the interval (default 0.95).
        workers : int, optional
            The LocalCluster's processes (default 2).
        progress : callable, optional
            Called with the fraction of blocks done.
        timeout : float, optional
            Seconds to wait for a scheduler (or for a lost cluster's workers to come back) before giving up
            (default 10).
        damaged : {"recompute", "refuse"}, optional
            What a resume does with a block in ``out`` that does not match its record (truncated, empty,
            altered, another block's copy): compute it again with a ``DamagedBlockWarning`` naming it
            (default), or raise a ModelError naming it.

        Returns
        -------
        StudyResult
            The table of runs, the estimate and what ran where.

        Raises
        ------
        armdyn.ModelError
            When the arguments are out of range, ``out`` holds another study (the message names the
            parts that differ) or cannot be written, a block is damaged and ``damaged="refuse"``, the
            scheduler cannot be reached within ``timeout`` (nothing computed is lost: the blocks written
            to ``out`` stay), or its workers are lost DASK_ROUNDS times in a row or none comes back
            within ``timeout``.
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
        if progress is not None and not callable(progress):
            raise ArgumentError(f"progress must be None or a function of the fraction done, got {progress!r}")
        timeout = inputs.number(timeout, "timeout")
        if not timeout > 0:
            raise ModelError(f"timeout must be a positive number of seconds, got {timeout:g}")
        if damaged not in ("recompute", "refuse"):
            raise ModelError(f"damaged must be 'recompute' or 'refuse', got {damaged!r}")
        blocks = math.ceil(setup.runs / setup.block)
        identity = fingerprint(self, setup)
        if out is not None:
            _parquet_writer()
        folder = _study_folder(out, self, setup, identity) if out is not None else None

        def expected(index: int) -> dict:
            first = index * setup.block
            return {"index": index, "first": first, "count": min(setup.block, setup.runs - first),
                    "fingerprint": identity[0]}  # fmt: skip

        done: dict[int, DataFrame] = {}
        for b in range(blocks if folder is not None else 0):
            table, problem = _read_block(folder, b, expected(b))  # type: ignore[arg-type]
            if problem is not None:
                where = f"{_block_file(folder, b)}"  # type: ignore[arg-type]
                if damaged == "refuse":
                    raise ModelError(f"the study's block {where} is damaged ({problem}): remove it to compute it "
                                     "again, or run with damaged='recompute'")  # fmt: skip
                warnings.warn(f"the study's block {where} is damaged ({problem}): it is computed again",
                              DamagedBlockWarning, stacklevel=2)  # fmt: skip
            elif table is not None:
                done[b] = table
        todo = [b for b in range(blocks) if b not in done]
        info = {"runs": setup.runs, "seed": setup.seed, "block": setup.block, "scheduler": scheduler or "local",
                "computed": len(todo), "read": len(done), "fingerprint": identity[0]}  # fmt: skip

        def arrived(index: int, table: DataFrame) -> None:
            if folder is not None:  # written before counted: a block interrupted while written is not done
                _write_block(folder, index, table, expected(index))
            done[index] = table
            if progress is not None:
                progress(len(done) / blocks)

        if scheduler is None or scheduler == "local":
            try:
                for index in todo:
                    arrived(index, run_block(setup, index))
            except KeyboardInterrupt:  # Ctrl-C: seen when the block under way ends; the blocks done are kept
                raise _interrupted(folder, done, blocks) from None
        else:
            info |= _on_dask(setup, todo, scheduler, workers, timeout, identity[0][:16], arrived)
        _check_ranges(done, setup, blocks)
        table = pandas.concat([done[b] for b in range(blocks)], ignore_index=True)
        table["holds"] = self.spec.holds(table)
        estimate = clopper_pearson(int(table["holds"].sum()), len(table), confidence)
        return StudyResult(table, estimate, self.spec, info)


def _interrupted(folder: Path | None, done: dict[int, DataFrame], blocks: int) -> KeyboardInterrupt:
    """The KeyboardInterrupt (armdyn.simulation.RunInterrupted) of a study stopped by Ctrl-C: what was done,
    how to resume, and the runs done (a DataFrame, in ``result``)."""
    import pandas

    from armdyn.simulation import RunInterrupted

    if folder is not None:
        resume = f"the blocks done are in {folder}: run the same study with the same out= (--out) to resume"
    else:
        resume = "give out= (--out) to keep the blocks done and resume"
    table = pandas.concat([done[b] for b in sorted(done)], ignore_index=True) if done else None
    return RunInterrupted(f"the study was interrupted after {len(done)} of {blocks} blocks; {resume}", table)


def _parquet_writer() -> None:
    """A MissingDependencyError unless pyarrow, which reads and writes the blocks, is installed."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MissingDependencyError("pyarrow", "cluster", needed_by="armdyn.Study.run(out=...)") from None


# ----- the store: a folder of checked blocks ------------------------------------------------------------------
STORE_FORMAT = 2
"""The layout of a study's folder: study.json (format, fingerprint and its parts), and per block a Parquet
file with a record (block-XXXXXX.json: run range, rows, the file's SHA-256, the study's fingerprint)."""


class DamagedBlockWarning(UserWarning):
    """A block in a study's folder did not match its record and is computed again."""


def _feed(digest: Any, value: object) -> None:
    """Feed a value to a SHA-256, each kind tagged, arrays by dtype, shape and bytes, floats by their bits."""
    if value is None or isinstance(value, (bool, np.bool_, int, np.integer, str)):
        digest.update(f"{type(value).__name__}:{value!r};".encode())
    elif isinstance(value, (float, np.floating)):
        digest.update(b"f:" + np.float64(value).tobytes())
    elif isinstance(value, np.ndarray):
        digest.update(f"a:{value.dtype.str}:{value.shape};".encode() + np.ascontiguousarray(value).tobytes())
    elif isinstance(value, (tuple, list)):
        digest.update(f"t{len(value)}(".encode())
        for item in value:
            _feed(digest, item)
        digest.update(b")")
    elif hasattr(value, "__dataclass_fields__"):
        digest.update(f"d:{type(value).__name__}(".encode())
        for name in value.__dataclass_fields__:  # type: ignore[attr-defined]
            _feed(digest, (name, getattr(value, name)))
        digest.update(b")")
    else:
        raise TypeError(f"cannot fingerprint a {type(value).__name__}")


def _hash(value: object) -> str:
    digest = hashlib.sha256()
    _feed(digest, value)
    return digest.hexdigest()


def fingerprint(study: Study, setup: Setup) -> tuple[str, dict[str, str]]:
    """The study's identity: the SHA-256 of everything that decides its runs, and of each part (arm, start,
    controller, trajectory, timing, criteria, sampling, seed, block, runs, version), so that a resume into a
    folder of another study is refused by naming what differs.

    Parameters
    ----------
    study : Study
        The study.
    setup : Setup
        Its arrays for a number of runs and a seed.

    Returns
    -------
    tuple of str and dict
        The fingerprint (hex) and the hash of each part.

    Raises
    ------
    None
        Every part is made of arrays, numbers and text.
    """
    import armdyn

    parts = {
        "arm": _hash((setup.arm, np.asarray(study.arm.gravity, dtype=float), setup.joints)),
        "start": _hash(setup.q0),
        "controller": _hash(setup.law),
        "trajectory": _hash(setup.path),
        "timing": _hash((setup.dt, setup.rows)),
        "criteria": _hash((study.spec.clauses, study.after, setup.after_row)),
        "sampling": _hash((setup.payload, setup.mass_error, setup.friction_error, setup.start_error)),
        "seed": _hash(setup.seed),
        "block": _hash(setup.block),
        "runs": _hash(setup.runs),
        "version": _hash(armdyn.__version__),
    }
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest(), parts


def _block_file(folder: Path, index: int) -> Path:
    return folder / f"block-{index:06d}.parquet"


def _record_file(folder: Path, index: int) -> Path:
    return folder / f"block-{index:06d}.json"


def _sync_folder(folder: Path) -> None:
    """fsync a folder, so that a rename in it survives a crash (where the system allows it)."""
    try:
        handle = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(handle)
    except OSError:
        pass
    finally:
        os.close(handle)


def _partial(target: Path) -> Path:
    return target.with_name(f".{target.name}.partial")


def _write_atomically(target: Path, data: bytes) -> None:
    """Write a file whole or not at all: a temporary file in the same folder, flushed, fsynced, renamed.
    ARMDYN_STUDY_WRITE_PAUSE (seconds, for fault-injection tests) holds each write half done that long."""
    partial = _partial(target)
    try:
        with open(partial, "wb") as handle:
            handle.write(data[: len(data) // 2])
            handle.flush()
            if os.environ.get("ARMDYN_STUDY_WRITE_PAUSE"):
                time.sleep(float(os.environ["ARMDYN_STUDY_WRITE_PAUSE"]))
            handle.write(data[len(data) // 2 :])
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(partial, target)
    except OSError as error:
        partial.unlink(missing_ok=True)
        raise ModelError(f"out {target.parent}: cannot write {target.name} ({error.strerror or error})") from None
    _sync_folder(target.parent)


def _write_block(folder: Path, index: int, table: DataFrame, record: dict) -> None:
    """Write a block and its record: the record (run range, rows, the file's SHA-256) first, then the file by
    an atomic rename, so that a file that exists with its record is a whole block."""
    buffer = io.BytesIO()
    table.to_parquet(buffer, index=False)
    data = buffer.getvalue()
    record = record | {"rows": len(table), "sha256": hashlib.sha256(data).hexdigest()}
    _write_atomically(_record_file(folder, index), json.dumps(record, indent=1).encode())
    _write_atomically(_block_file(folder, index), data)


def _read_block(folder: Path, index: int, expected: dict) -> tuple[DataFrame | None, str | None]:
    """Block ``index`` from the folder when it matches its record and ``expected`` (index, first run, count,
    fingerprint): (table, None); (None, None) when it was never written; (None, what is wrong) when damaged."""
    import pandas

    file, record_file = _block_file(folder, index), _record_file(folder, index)
    if not file.exists():
        return None, None
    try:
        record = json.loads(record_file.read_text())
    except FileNotFoundError:
        return None, f"it has no record ({record_file.name}) of its runs and checksum"
    except (OSError, ValueError):
        return None, f"its record {record_file.name} is unreadable"
    if not isinstance(record, dict) or any(record.get(key) != value for key, value in expected.items()):
        return None, (f"its record {record_file.name} does not describe block {index} of this study (runs "
                      f"{expected['first']} to {expected['first'] + expected['count'] - 1})")  # fmt: skip
    try:
        data = file.read_bytes()
    except OSError as error:
        return None, f"it cannot be read ({error.strerror or error})"
    if hashlib.sha256(data).hexdigest() != record.get("sha256"):
        return None, f"its checksum does not match its record (truncated or altered: {len(data)} bytes)"
    try:
        table = pandas.read_parquet(io.BytesIO(data))
    except Exception as error:  # any reader error means the same: recompute the block
        return None, f"it is not a readable Parquet file ({type(error).__name__})"
    runs = np.arange(expected["first"], expected["first"] + expected["count"])
    if len(table) != expected["count"] or "run" not in table or not np.array_equal(table["run"], runs):
        return None, f"it holds {len(table)} rows, not runs {runs[0]} to {runs[-1]}"
    return table, None


def _check_ranges(done: dict[int, DataFrame], setup: Setup, blocks: int) -> None:
    """A ModelError when the blocks' runs are not each of 0..runs-1 once, in order (duplicated or missing)."""
    missing = [b for b in range(blocks) if b not in done]
    runs = np.concatenate([np.asarray(done[b]["run"]) for b in range(blocks) if b in done])
    if missing or not np.array_equal(runs, np.arange(setup.runs)):
        values, counts = np.unique(runs, return_counts=True)
        lost = np.setdiff1d(np.arange(setup.runs), values)
        raise ModelError(f"the study's blocks do not hold runs 0 to {setup.runs - 1} once each: blocks missing "
                         f"{missing}, {int((counts > 1).sum())} runs duplicated, {lost.size} runs missing")  # fmt: skip


def _describe(study: Study, setup: Setup) -> dict:
    """What a reader of study.json needs to know what the study is (the fingerprint decides)."""
    return {"arm": study.arm.name, "spec": study.spec.text, "seed": setup.seed, "block": setup.block,
            "runs": setup.runs, "t_final": study.t_final, "dt": study.dt, "after": study.after,
            "controller": control.describe_controller(study.controller),
            "trajectory": trajectories.describe_trajectory(study.trajectory),
            "distributions": {k: repr(v) for k, v in study.distributions.items()}}  # fmt: skip


def _study_folder(out: object, study: Study, setup: Setup, identity: tuple[str, dict[str, str]]) -> Path:
    """The study's folder, made if missing, its study.json written atomically; a ModelError when it holds
    another study (naming the parts that differ). A damaged study.json (unreadable) is written again, with a
    warning, when no block record there names another study; else a ModelError."""
    if not isinstance(out, (str, os.PathLike)):
        raise ArgumentError(f"out must be a folder (a str or Path), got {type(out).__name__}")
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise ModelError(f"out {folder} is a file, not a folder")
    if not folder.absolute().parent.is_dir():
        raise ModelError(f"out {folder}: the folder {folder.absolute().parent} it goes in does not exist")
    try:
        folder.mkdir(exist_ok=True)
    except OSError as error:
        raise ModelError(f"out {folder}: cannot make the folder ({error.strerror or error})") from None
    for leftover in folder.glob(".*.partial"):  # a write that a kill interrupted
        leftover.unlink(missing_ok=True)
    code, parts = identity
    stamp = folder / "study.json"
    document = {"format": STORE_FORMAT, "fingerprint": code, "parts": parts, "study": _describe(study, setup)}
    if not stamp.exists():
        _write_atomically(stamp, json.dumps(document, indent=1).encode())
        return folder
    try:
        previous = json.loads(stamp.read_text())
        previous_code, previous_parts = previous["fingerprint"], dict(previous["parts"])
    except (OSError, ValueError, TypeError, KeyError):
        foreign = sorted(p.name for p in folder.glob("block-*.json") if _record_names_another(p, code))
        if foreign:
            raise ModelError(f"{folder}/study.json is damaged and {foreign[0]} belongs to another study: remove "
                             f"the folder (or give another out) to start again") from None  # fmt: skip
        warnings.warn(f"{folder}/study.json was damaged (unreadable); it is written again and the blocks are "
                      "checked one by one", DamagedBlockWarning, stacklevel=3)  # fmt: skip
        _write_atomically(stamp, json.dumps(document, indent=1).encode())
        return folder
    if previous_code != code:
        changed = sorted(k for k in parts if previous_parts.get(k) != parts[k]) or ["its format"]
        raise ModelError(f"{folder} holds another study (it differs in {', '.join(changed)}): give another out, "
                         "or remove the folder to start again")  # fmt: skip
    return folder


def _record_names_another(record_file: Path, code: str) -> bool:
    """True when a block's record is readable and names a fingerprint other than ``code``."""
    try:
        record = json.loads(record_file.read_text())
    except (OSError, ValueError):
        return False
    return isinstance(record, dict) and record.get("fingerprint") != code


def _worker_threads(threads: int) -> None:
    """Numba's thread count on a worker, within the pool it started with; never a change of NUMBA_NUM_THREADS
    after start-up. A worker whose environment got another NUMBA_NUM_THREADS after Numba started (a
    dask.distributed Nanny applies its ``env`` after the process imported Numba) would refuse every later
    compile ("Cannot set NUMBA_NUM_THREADS"): its environment is given back the pool's size."""
    import numba

    started = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # Numba sets its config at run time
    if os.environ.get("NUMBA_NUM_THREADS", str(started)) != str(started):
        os.environ["NUMBA_NUM_THREADS"] = str(started)
    numba.set_num_threads(max(1, min(threads, started)))


def _warm(setup: Setup, threads: int | None = None) -> list[str]:
    """Load (or compile) the kernels of the study's blocks once: a block of one run of ``setup`` (the blocks'
    own argument types, so the kernels the blocks call and no others), on a worker after setting its Numba
    thread count (``threads``; None: this process, its threads as they are). The functions Numba compiled
    instead of loading from its cache (armdyn.dynamics.cache.compiles): none when the cache held them."""
    from armdyn.dynamics.cache import compiles

    if threads is not None:
        _worker_threads(threads)
    with compiles() as compiled:
        run_block(replace(setup, runs=1, block=1), 0, threads)
    return compiled


def _shares_cache(scheduler: str) -> bool:
    """True when the scheduler's workers run on this machine (a local cluster, a loopback address), where they
    find this process's compiled-code cache."""
    host = "localhost" if scheduler == "local-cluster" else scheduler.split("://", 1)[1].rsplit(":", 1)[0]
    return host in ("localhost", "::1", "[::1]") or host.startswith("127.")


def _remote_block(setup: Setup, index: int) -> DataFrame:
    """A block on a worker, with one Numba thread (a worker that just restarted was not warmed)."""
    _worker_threads(1)
    return run_block(setup, index, 1)


DASK_ROUNDS = 4
"""Rounds of a Dask study in a row in which no block arrived (workers lost) before it gives up."""


def _lost(error: BaseException) -> bool:
    """True when a Dask task failed because its worker or its scattered data was lost (not its own error)."""
    from concurrent.futures import CancelledError as FutureCancelled

    from distributed import KilledWorker
    from distributed.comm import CommClosedError

    return isinstance(error, (KilledWorker, CommClosedError, FutureCancelled))


def _on_dask(setup: Setup, todo: list[int], scheduler: str, workers: int, timeout: float, key: str,
             arrived: Callable[[int, DataFrame], None]) -> dict:  # fmt: skip
    """The blocks ``todo`` on a Dask cluster: one task per block, each worker one task thread with one Numba
    thread, its kernels warmed first (``_warm``: here too when the workers share this machine's kernel cache,
    so that they load rather than compile them). A block lost with its worker is retried by Dask; when every worker is
    lost (and the scattered set-up with them), the set-up is scattered again to the workers that come back and
    the blocks not yet arrived are sent again, up to DASK_ROUNDS rounds in a row without a block, then a
    ModelError (the blocks that arrived stay in out)."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise MissingDependencyError(
            "dask.distributed", "cluster", needed_by="armdyn.Study.run(scheduler=...)"
        ) from None
    cluster = None
    if scheduler == "local-cluster":
        workers = inputs.integer(workers, "workers", 1, 4 * (os.cpu_count() or 1), " (4 per core)")
    elif not (isinstance(scheduler, str) and re.fullmatch(r"(tcp|tls)://[\w.\-]+:\d+", scheduler)):
        raise ModelError(f"scheduler must be None, 'local', 'local-cluster' or an address tcp://host:port, got "
                         f"{scheduler!r}")  # fmt: skip
    if scheduler == "local-cluster":
        # no NUMBA_NUM_THREADS here: the Nanny sets its env after the worker imported Numba (see _worker_threads)
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                               env={"OMP_NUM_THREADS": "1"})  # fmt: skip
        address = cluster.scheduler_address
    else:
        address = scheduler
    try:
        client = Client(address, timeout=f"{timeout}s")
    except (OSError, TimeoutError) as error:
        if cluster is not None:
            cluster.close()
        raise ModelError(f"cannot reach the Dask scheduler at {address} within {timeout:g} s ({error}); nothing "
                         "was lost: the blocks already written stay in out") from None  # fmt: skip
    try:
        link = client.dashboard_link
        remaining, idle, attempt, compiled = list(todo), 0, 0, {}
        if remaining and _shares_cache(scheduler):  # compiled once here, then loaded by every worker from the cache
            _warm(setup)
        while remaining:
            if idle >= DASK_ROUNDS:
                raise ModelError(f"the Dask workers were lost {idle} times in a row before blocks "
                                      f"{remaining[:5]} arrived; the blocks that arrived stay in out")  # fmt: skip
            attempt += 1
            try:
                client.wait_for_workers(1, timeout=timeout)
                # every worker loads the blocks' compiled kernels before work arrives (compiles them when the
                # cache it sees lacks them: a remote worker's first study)
                compiled = client.run(_warm, replace(setup, runs=1, block=1), 1)
                shared = client.scatter(setup, broadcast=True)
            except Exception as error:  # workers lost while starting: the next round
                if isinstance(error, TimeoutError) and not client.scheduler_info()["workers"]:
                    raise ModelError(f"no Dask worker came back within {timeout:g} s; the blocks that "
                                          "arrived stay in out") from None  # fmt: skip
                idle += 1
                continue
            futures = {client.submit(_remote_block, shared, index, key=f"armdyn-block-{key}-{index}-{attempt}",
                                     retries=3): index for index in remaining}  # fmt: skip
            arrivals = 0
            for future in as_completed(futures):
                try:
                    table = future.result()
                except Exception as error:  # a block's own error is raised; a lost one retried
                    if not _lost(error):
                        raise
                    continue
                arrived(futures[future], table)
                remaining.remove(futures[future])
                arrivals += 1
            idle = 0 if arrivals else idle + 1
        return {"dashboard": link, "workers": len(client.scheduler_info()["workers"]), "rounds": attempt,
                "compiled_on_workers": {worker: len(names) for worker, names in compiled.items()}}  # fmt: skip
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
