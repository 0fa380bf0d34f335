"""The properties of the robot equation (Table 3.3.1, Lewis, Dawson and Abdallah 2004): checks and bounds.

Every bound is computed: the quantity is evaluated on random samples of the joint range
(the arm's limits; the whole circle for revolute joints without limits; a span from the
lower limit for prismatic joints without limits, where bounds depend on q), and the
extremes are then refined by a bounded local optimizer (scipy.optimize, L-BFGS-B) started
from the best samples. The report says for each bound how it was found.

With ``check(..., task=output)`` the properties are evaluated in the coordinates y = h(q) of
a task output of ``armdyn.task_space`` (Section 3.5): Mbar = J^-T M J^-1, Vmbar, Fbar,
Gbar and Wbar for a square output (m = n), Khatib's Lambda = (J M^-1 J^T)^-1 and mu_x for a
redundant one (m < n). These grow without bound as J(q) approaches a singularity, so the
bounds are computed over the regular part of the joint ranges only: the sampled
configurations whose condition number of J is below ``max_condition`` (default
REGION_MAX_CONDITION = 1e3); the extremes are refined by SLSQP under the same constraint.
"""

from __future__ import annotations

import html
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from armdyn import actuators, inputs, task_space
from armdyn.errors import ArgumentError, ModelError, SimulationError
from armdyn.robot import Robot

TOLERANCE = 1e-9
GROUPS = ("inertia", "coriolis", "skew", "friction", "gravity", "linearity", "passivity")
"""The groups of properties ``check`` evaluates; ``only`` picks some of them by name."""


def _check_robot(arm: object) -> None:
    inputs.arm_argument(arm, Robot, name="arm")


def _groups(only: object) -> set[str]:
    """The groups named by ``only``: None for all, one name, or a sequence of names."""
    if only is None:
        return set(GROUPS)
    valid = ", ".join(repr(group) for group in GROUPS)
    if isinstance(only, str):
        names = [only]
    elif isinstance(only, (bytes, Mapping)) or not isinstance(only, Iterable):
        raise ArgumentError(f"only must be a group name or a sequence of group names ({valid}), got {only!r}")
    else:
        names = list(only)
    if not names:
        raise ModelError(f"only must name at least one group ({valid}), got {only!r}")
    unknown = [name for name in names if not (isinstance(name, str) and name in GROUPS)]
    if unknown:
        raise ModelError(f"only names unknown groups {unknown}; the groups are {valid}")
    return set(names)


COLUMNS = (
    "property", "statement", "holds", "bound (computed)", "book value", "extreme sampled", "residual or margin", "how",
)  # fmt: skip
"""The columns of ``Report.records`` and ``Report.table``; each means one thing (see ``Report.records``)."""

_LEGEND = (
    "residual: the largest relative error of an identity (0 is exact); "
    "margin: the largest lhs - rhs of an inequality found (<= 0 where it holds)"
)

MEASURES = ("extreme", "residual", "margin")
"""What a Row's ``worst`` is (see Row)."""


@dataclass
class Row:
    """One property: its statement, whether it holds, the worst value found and the bound.

    Parameters
    ----------
    name : str
        The property's short name, e.g. "skew symmetry".
    statement : str
        What it states, e.g. "Mdot - 2 Vm is skew: x^T (Mdot - 2 Vm) x = 0".
    holds : bool
        Whether it held on every sample.
    worst : float
        The worst value found; ``measure`` says what it is.
    bound : float or None
        The computed bound, None for an identity.
    how : str
        How the value was found (samples, refinement).
    unit : str, optional
        The unit of the property's quantity: of ``worst`` (unless it is a relative
        residual), ``lowest`` and ``bound`` (default "": a relative or pure number).
    measure : str, optional
        What ``worst`` is (MEASURES): "extreme" (default), the extreme of the bounded
        quantity found on the samples; "residual", the largest relative residual of an
        identity (0 is exact); "margin", the largest excess lhs - rhs of an inequality
        found (<= 0 where it holds), in ``unit`` (relative when ``unit`` is "").
    names : tuple of str, optional
        The names, in ``Report.bounds``, of the bounds this row computed (e.g. ("mu1", "mu2")).
    lowest : float or None, optional
        For a quantity bounded on both sides, the smallest value sampled (``worst`` is then
        the largest).
    unchecked : str or None, optional
        Why the property could not be checked (its evaluation raised), None (default) when it
        was; an unchecked row does not hold, and ``worst`` is then NaN.
    """

    name: str
    statement: str
    holds: bool
    worst: float
    bound: float | None
    how: str
    unit: str = ""
    measure: str = "extreme"
    names: tuple[str, ...] = ()
    lowest: float | None = None
    unchecked: str | None = None


def _quantity(value: float, unit: str, digits: int) -> str:
    """A number with its unit, e.g. "5.828 kg m^2"."""
    text = f"{value:.{digits}g}"
    return f"{text} {unit}" if unit else text


@dataclass
class Report:
    """The properties of Table 3.3.1 for one arm over a joint range (Section 3.3).

    Parameters
    ----------
    arm : str
        The arm's name.
    rows : list of Row
        One row per property checked.
    bounds : dict of str to float
        The computed bounds by name: mu1, mu2 (3.3.6), m1, m2, vb, v, k, gb, for the groups
        checked.
    ranges : list of (float, float)
        The (lower, upper) range sampled for each joint.
    notes : list of str, optional
        Remarks on the report (for example that prismatic joints make bounds depend on q).
    units : dict of str to str, optional
        The unit of each bound in ``bounds``, e.g. {"mu1": "kg m^2"}.
    references : dict of str to float, optional
        Values to compare the computed bounds with, by the same names: the book's (e.g.
        Example 3.3-1's m1 = 4, m2 = 7); shown in the table's "book value" column. Empty
        unless the caller sets them.
    task : str or None, optional
        For a report in task coordinates (``check(..., task=output)``, Section 3.5), the
        output's repr, e.g. "ToolPosition()"; None (default) for joint coordinates.
    max_condition : float or None, optional
        For a report in task coordinates, the condition number of J below which the sampled
        configurations were kept: the bounds hold over that region of ``ranges``; else None.
    """

    arm: str
    rows: list[Row]
    bounds: dict[str, float]
    ranges: list[tuple[float, float]]
    notes: list[str] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)
    references: dict[str, float] = field(default_factory=dict)
    task: str | None = None
    max_condition: float | None = None

    @property
    def all_hold(self) -> bool:
        """Whether every row was checked and holds."""
        return all(row.holds for row in self.rows)

    @property
    def unchecked(self) -> list[Row]:
        """The rows that could not be checked (their evaluation raised; ``Row.unchecked`` says why)."""
        return [row for row in self.rows if row.unchecked is not None]

    def row(self, name: str) -> Row:
        """The row of one property, by name.

        Parameters
        ----------
        name : str
            The property's short name, e.g. "positive definite".

        Returns
        -------
        Row
            Its row.

        Raises
        ------
        KeyError
            When the report has no row of that name.
        """
        for row in self.rows:
            if row.name == name:
                return row
        raise KeyError(name)

    def _named(self, values: Mapping[str, float], names: Sequence[str], digits: int) -> str:
        return ", ".join(
            f"{name} = {_quantity(values[name], self.units.get(name, ''), digits)}" for name in names if name in values
        )

    def records(self, digits: int = 4) -> tuple[list[str], list[list[str]]]:
        """The table as text: the column names (COLUMNS) and one row of cells per property.

        Each column means one thing, every number carrying its unit: "bound (computed)", the
        bounds computed for the property, by name (``bounds``); "book value", the reference
        values for them (``references``, often none); "extreme sampled", the extreme of the
        bounded quantity on the samples (lowest to largest when bounded on both sides);
        "residual or margin", the largest relative residual of an identity (0 is exact) or
        the largest excess lhs - rhs of an inequality (<= 0 where it holds). A row that could not
        be checked says "not checked" under "holds" and "could not be checked: <reason>" under "how".

        Parameters
        ----------
        digits : int, optional
            Significant digits of the numbers (default 4).

        Returns
        -------
        tuple of (list of str, list of list of str)
            The column names and the rows.
        """
        rows = []
        for row in self.rows:
            bound = self._named(self.bounds, row.names, digits)
            if not bound and row.bound is not None:
                bound = _quantity(row.bound, row.unit, digits)
            extreme = residual = ""
            if row.unchecked is not None:
                pass
            elif row.measure == "extreme":
                extreme = _quantity(row.worst, row.unit, digits)
                if row.lowest is not None:
                    extreme = f"{_quantity(row.lowest, row.unit, digits)} to {extreme}"
            elif row.measure == "residual" or not row.unit:
                residual = f"{row.worst:.3g} (relative)"
            else:
                residual = _quantity(row.worst, row.unit, 3)
            holds = "not checked" if row.unchecked is not None else "yes" if row.holds else "NO"
            references = self._named(self.references, row.names, digits)
            rows.append([row.name, row.statement, holds, bound, references, extreme, residual, row.how])
        return list(COLUMNS), rows

    def title(self, digits: int = 4) -> str:
        """The report's title: the arm, the coordinates and the region the bounds hold over.

        Parameters
        ----------
        digits : int, optional
            Significant digits of the joint ranges (default 4).

        Returns
        -------
        str
            E.g. "Table 3.3.1 for two_link_planar, joint ranges [-3.142, 3.142], [-3.142, 3.142]";
            in task coordinates also the output and the condition-number limit of the region.
        """
        ranges = ", ".join(f"[{lo:.{digits}g}, {hi:.{digits}g}]" for lo, hi in self.ranges)
        if self.task is None:
            return f"Table 3.3.1 for {self.arm}, joint ranges {ranges}"
        region = "" if self.max_condition is None else f" where cond J < {self.max_condition:g}"
        return f"Table 3.3.1 for {self.arm} in task coordinates {self.task}, joint ranges {ranges}{region}"

    def table(self) -> object:
        """A rich Table of the report (the columns of ``records``), titled by ``title``.

        Returns
        -------
        rich.table.Table
            One line per property: statement, whether it holds, the computed bounds, the
            book's values, the extreme sampled, the residual or margin, and how.
        """
        from rich.table import Table

        table = Table(
            title=self.title(),
            caption=_LEGEND,
        )
        columns, rows = self.records()
        for column in columns:
            table.add_column(column, overflow="fold")
        for cells in rows:
            cells[2] = "[green]yes[/green]" if cells[2] == "yes" else "[red]NO[/red]"
            table.add_row(*cells)
        return table

    def _repr_html_(self) -> str:
        """The report as an HTML table for notebooks: the columns of ``records``, one row per property
        ("holds" in green or red), titled by ``title``, with the notes below; every text escaped."""
        columns, rows = self.records()
        head = "".join(f'<th style="text-align:left">{html.escape(column)}</th>' for column in columns)
        body = []
        for cells in rows:
            colour = "green" if cells[2] == "yes" else "red"
            styles = ["text-align:left"] * len(cells)
            styles[2] += f";color:{colour};font-weight:bold"
            body.append(
                "<tr>"
                + "".join(
                    f'<td style="{style}">{html.escape(cell)}</td>' for cell, style in zip(cells, styles, strict=True)
                )
                + "</tr>"
            )
        items = "".join(f"<li>{html.escape(note)}</li>" for note in [_LEGEND, *self.notes])
        return (
            f'<div class="armdyn-report"><table class="armdyn-properties"><caption>{html.escape(self.title())}'
            f"</caption><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table><ul>{items}</ul></div>"
        )


def _si(arm: Robot, revolute: str, prismatic: str) -> str:
    """The unit of a quantity of the arm: ``revolute`` for revolute joints, ``prismatic`` for prismatic ones."""
    kinds = set(arm.kinds)
    if kinds == {"revolute"}:
        return revolute
    if kinds == {"prismatic"}:
        return prismatic
    return f"{revolute} or {prismatic}"


def joint_ranges(
    arm: Robot, limits: Sequence[tuple[float, float]] | None = None, prismatic_span: float = 1.0
) -> list[tuple[float, float]]:
    """The range sampled for each joint (see the module docstring).

    The arm's limits where both are finite; otherwise the whole circle for a revolute
    joint, and for a prismatic joint a span of ``prismatic_span`` from its finite limit
    (or centred on 0 when it has none).

    Parameters
    ----------
    arm : Robot
        The arm.
    limits : sequence of (float, float), optional
        (lower, upper) per joint, to use instead of the arm's own.
    prismatic_span : float, optional
        Length of the range of a prismatic joint without two finite limits (default 1.0).

    Returns
    -------
    list of (float, float)
        (lower, upper) for each joint.

    Raises
    ------
    armdyn.ModelError
        When ``limits`` is not n finite (lower, upper) pairs with lower <= upper, or when
        ``prismatic_span`` is not one positive finite number.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    """
    _check_robot(arm)
    span = inputs.vector(prismatic_span, "prismatic_span")
    if span.shape != (1,) or span[0] <= 0:
        raise ModelError(f"prismatic_span must be one positive finite number, got {prismatic_span!r}")
    prismatic_span = float(span[0])
    if limits is not None:
        pairs = inputs.state(limits, 2, "limits")
        if pairs.shape != (arm.n, 2) or np.any(pairs[:, 0] > pairs[:, 1]):
            raise ModelError(
                f"limits must be {arm.n} finite (lower, upper) pairs with lower <= upper, got {pairs.tolist()}"
            )
        return [(float(lo), float(hi)) for lo, hi in pairs]
    ranges = []
    for (lower, upper), kind in zip(arm.qlim.T, arm.kinds, strict=True):
        if np.isfinite(lower) and np.isfinite(upper):
            ranges.append((float(lower), float(upper)))
        elif kind == "revolute":
            ranges.append((-np.pi, np.pi))
        elif np.isfinite(lower):
            ranges.append((float(lower), float(lower) + prismatic_span))
        elif np.isfinite(upper):
            ranges.append((float(upper) - prismatic_span, float(upper)))
        else:
            ranges.append((-prismatic_span / 2, prismatic_span / 2))
    return ranges


def _extreme(
    f: Callable[[np.ndarray], float], starts: np.ndarray, values: np.ndarray, bounds: list, largest: bool
) -> tuple[float, str]:
    """Refine the extreme of f from the best sampled points with L-BFGS-B; (value, how)."""
    sign = -1.0 if largest else 1.0
    best = sign * values.min() if not largest else values.max()
    order = np.argsort(sign * values)[:3]
    for start in starts[order]:
        result = minimize(lambda x: sign * f(x), start, method="L-BFGS-B", bounds=bounds)
        if result.success or result.status == 2:
            value = sign * result.fun
            best = max(best, value) if largest else min(best, value)
    how = f"{len(values)} samples, refined by L-BFGS-B from the best 3"
    return float(best), how


def _unit(x: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(x)
    return x / norm if norm > 0 else x


def inertia_bounds(arm: Robot, samples: int = 400, seed: int = 0, limits: Sequence | None = None) -> tuple:
    """(mu1, mu2) with mu1 I <= M(q) <= mu2 I over the joint range (3.3.6).

    The smallest and largest eigenvalues of M(q) over random samples of the joint range,
    refined by L-BFGS-B (see the module docstring); ``check`` restricted to "inertia".

    Parameters
    ----------
    arm : Robot
        The arm.
    samples : int, optional
        Number of random joint configurations (default 400, at least 4).
    seed : int, optional
        Seed of the random generator (default 0).
    limits : sequence of (float, float), optional
        (lower, upper) per joint, to use instead of the arm's own (see ``joint_ranges``).

    Returns
    -------
    tuple of float
        (mu1, mu2).

    Raises
    ------
    armdyn.ModelError
        When ``samples`` is below 4, ``seed`` is negative or ``limits`` is invalid (see
        ``joint_ranges``), or when the arm has symbolic parameters.
    armdyn.ArgumentError
        When ``arm`` is not a Robot.
    TypeError
        When ``samples`` or ``seed`` is not an integer.
    """
    report = check(arm, samples=samples, seed=seed, limits=limits, only=("inertia",))
    return report.bounds["mu1"], report.bounds["mu2"]


MAX_CHECK_SAMPLES = 1_000_000
"""The most random configurations ``check`` samples: beyond it a check takes minutes and the
sampled extremes no longer change."""

REGION_MAX_CONDITION = 1e3
"""The condition number of J(q) below which ``check(..., task=...)`` keeps a sampled configuration
by default: the task-space bounds hold over that regular region of the joint ranges."""

MIN_REGULAR = 4
"""The fewest regular samples (cond J(q) below ``max_condition``) ``check(..., task=...)`` computes
bounds from."""

FD_TOLERANCE = 1e-6
"""The relative tolerance of the task-space skew-symmetry row, whose Mbar_dot (Lambda_dot) is a
4th-order central difference along the motion (rounding-limited rows use TOLERANCE); both scale
with cond J / REGION_MAX_CONDITION where the region is worse conditioned than the default."""


def check(
    arm: Robot,
    samples: int = 300,
    seed: int = 0,
    limits: Sequence[tuple[float, float]] | None = None,
    only: Sequence[str] | None = None,
    *,
    task: task_space.TaskOutput | None = None,
    max_condition: float | None = None,
) -> Report:
    """Evaluate the properties of Table 3.3.1 on ``robot`` (see the module docstring).

    Every bound is computed on random samples of the joint range, its extremes refined by
    L-BFGS-B. Passivity is the energy balance integral qd^T tau dt = H(T) - H(0) + dissipated
    work, H = K + P (Table 3.3.1), evaluated along 1 s of the arm's motion under torques scaled
    to it, the inverse dynamics of accelerations a(t) = A w^2 cos(w t): the motion is integrated by scipy's DOP853 at
    relative tolerances 1e-7 and 1e-10 (PASSIVITY_RTOL), K and P are the exact energies at the
    states reached, and the difference of the two runs' balances estimates the integration
    error, ten times which (at least PASSIVITY_FLOOR of the energy that flows) is the rows'
    tolerance: integration error is not reported as a violation, and a violation (a friction
    law that injects energy) is.

    A group whose evaluation raises on the arm (a motion that cannot be integrated, a task
    output that cannot give J_dot) gives a row that does not hold and says "could not be
    checked: <reason>" (``Row.unchecked``, ``Report.unchecked``); the other groups' rows are
    still evaluated.

    With ``task``, the properties are those of the robot equation in the output's coordinates
    (Section 3.5), Mbar yddot + Nbar = f with Mbar = J^-T M J^-1. They are evaluated
    over the regular part of the joint ranges: the sampled configurations whose condition
    number of J(q) is below ``max_condition`` (the bounds blow up at a singularity), the
    extremes refined by SLSQP under the same constraint; ``Report.notes`` says how many
    samples were rejected and ``Report.title`` names the output and the region. For a square
    output (m = n) the rows are: Mbar symmetric, positive definite, mu1 I <= Mbar <= mu2 I and
    m1 <= ||Mbar||_1 <= m2; Vmbar(q, s ydot) s ydot quadratic in s, ||Vmbar|| <= vb ||ydot||
    and Christoffel symmetry; Mbar_dot - 2 Vmbar skew (Mbar_dot by a 4th-order central
    difference along the motion, so the row's tolerance is FD_TOLERANCE); when the arm has
    friction ||Fbar|| <= v ||ydot|| + k and ydot^T Fbar >= 0; ||Gbar|| <= gb; and
    Mbar yddot + Nbar = Wbar phi with phi = robot.parameters(). For a redundant output
    (m < n), Khatib's Lambda = (J M^-1 J^T)^-1 takes the place of Mbar, Lambda_dot - 2 mu_x
    (``task_space.operational_coriolis``) that of Mbar_dot - 2 Vmbar and p = Jbar^T G that of
    Gbar; Vmbar, Fbar and Wbar are defined for square outputs only, so the Coriolis, friction
    and linearity rows are skipped with the reason in the notes. Passivity is not checked in
    task coordinates (the power ydot^T f equals qd^T tau). The units are the output's: kg and
    N for a position output, "output units" where the coordinates mix units (ToolPose) or
    have their own (Camera, Output).

    An ``armdyn.actuators.ActuatedArm`` is checked through its reduced model (its
    ``reduced_robot()``, Section 3.6), and ``Report.notes`` says so.

    Parameters
    ----------
    arm : Robot or armdyn.actuators.ActuatedArm
        The arm, or an arm with its drives.
    samples : int, optional
        Number of random joint configurations (default 300, from 4 to MAX_CHECK_SAMPLES = 1,000,000).
    seed : int, optional
        Seed of the random generator (default 0).
    limits : sequence of (float, float), optional
        (lower, upper) per joint to use instead of the arm's own (see ``joint_ranges``).
    only : str or sequence of str, optional
        Restrict to some groups, for speed: one name or several of "inertia", "coriolis",
        "skew", "friction", "gravity", "linearity", "passivity" (GROUPS); default None, all.
    task : armdyn.task_space.TaskOutput, optional
        Evaluate the properties in the coordinates of this output (ToolPosition, ToolPose,
        LinkPoint, PlanarPosition, Camera or Output, with m <= n rows); default None: in joint
        coordinates.
    max_condition : float, optional
        With ``task``: the condition number of J(q) below which a sampled configuration is
        kept (the region the bounds hold over); greater than 1, default
        REGION_MAX_CONDITION = 1e3. Only with ``task``.

    Returns
    -------
    Report
        One Row per property, with the computed bounds and the ranges sampled.

    Raises
    ------
    armdyn.ModelError
        When ``samples`` is below 4 or above MAX_CHECK_SAMPLES, ``seed`` is negative, ``limits`` is not
        n finite (lower, upper) pairs with lower <= upper, ``only`` is empty or names a group not in
        GROUPS (the message lists them), or when the arm has symbolic parameters. With ``task``:
        when it is not a task output of armdyn.task_space or has more rows than the arm has
        joints, when ``max_condition`` is not a finite number greater than 1 (or is given
        without ``task``), or when fewer than MIN_REGULAR samples have cond J(q) below it (the
        ranges are singular or nearly so almost everywhere). An output that cannot give what a
        row needs (an Output without ``jacobian_dot`` for the Coriolis and skew rows, a Camera
        the tool point passes behind) gives rows that could not be checked, not an error. For an
        ActuatedArm, when a drive is flexible (no reduced model).
    armdyn.ArgumentError
        When ``arm`` is not a Robot (or ActuatedArm), ``only`` is neither a string nor a sequence of them, or
        ``task`` is not a task output (an ArgumentError is a ModelError and a TypeError).
    TypeError
        When ``samples`` or ``seed`` is not an integer.
    """
    notes: list[str] = []
    if isinstance(arm, actuators.ActuatedArm):
        notes.append(
            "evaluated on the reduced arm-plus-actuator model (Section 3.6, inductance neglected) in joint "
            "torques: M' = M + R^-2 J_M, V' = Vm, F' = F + R^-1 F_M + R^-2 B qd, G' = G, input K' v"
        )
        arm = arm.reduced_robot()
    inputs.arm_argument(arm, Robot, "arm", numeric=True, why=" (the properties are evaluated numerically)")
    samples = inputs.integer(samples, "samples", 4, MAX_CHECK_SAMPLES, " (each sample is evaluated and refined)")
    seed = inputs.integer(seed, "seed", 0)
    groups = _groups(only)
    n = arm.n
    ranges = joint_ranges(arm, limits)
    if task is not None or max_condition is not None:
        report = _check_task(arm, task, max_condition, samples, seed, ranges, groups)
        report.notes[:0] = notes
        return report
    box = [(lo, hi) for lo, hi in ranges]
    rng = np.random.default_rng(seed)
    low, high = np.array(ranges).T
    q = rng.uniform(low, high, (samples, n))
    x = np.array([_unit(v) for v in rng.normal(size=(samples, n))])
    y = np.array([_unit(v) for v in rng.normal(size=(samples, n))])
    rows: list[Row] = []
    bounds: dict[str, float] = {}
    torque = _si(arm, "N m", "N")
    prismatic = [i for i, kind in enumerate(arm.kinds) if kind == "prismatic"]
    if prismatic:
        notes.append(
            "the arm has prismatic joints, so its bounds depend on q; they hold over the range "
            + ", ".join(f"q{i + 1} in [{ranges[i][0]:.3g}, {ranges[i][1]:.3g}]" for i in prismatic)
        )

    evaluations: dict[str, Callable[[], None]] = {
        "inertia": lambda: _inertia_rows(arm, q, box, rows, bounds),
        "coriolis": lambda: _coriolis_rows(arm, q, x, y, box, rows, bounds, groups),
        "friction": lambda: _friction_rows(arm, x, rng, rows, bounds),
        "gravity": lambda: _gravity_row(arm, q, box, rows, bounds),
        "linearity": lambda: _linearity_row(arm, q, rng, rows),
        "passivity": lambda: _passivity_rows(arm, ranges, rows),
    }
    for group, evaluate in evaluations.items():
        named = [name for name in ((group, "skew") if group == "coriolis" else (group,)) if name in groups]
        if named:
            _guarded(named, evaluate, rows)
    inertia = _si(arm, "kg m^2", "kg")
    units = {"mu1": inertia, "mu2": inertia, "m1": inertia, "m2": inertia,
             "vb": _si(arm, "N m/(rad/s)^2", "N/(m/s)^2"), "v": _si(arm, "N m/(rad/s)", "N/(m/s)"), "k": torque,
             "gb": torque}  # fmt: skip
    return Report(arm.name, rows, bounds, ranges, notes, {key: unit for key, unit in units.items() if key in bounds})


GROUP_STATEMENTS = {
    "inertia": "M(q) symmetric, positive definite and bounded",
    "coriolis": "V(q, qd) quadratic in qd and bounded; Vm Christoffel symmetric",
    "skew": "Mdot - 2 Vm is skew",
    "friction": "F(qd) bounded and dissipative",
    "gravity": "||G(q)|| <= gb",
    "linearity": "the robot equation is linear in the parameters",
    "passivity": "integral qd^T tau dt >= H(T) - H(0)",
}
"""What each group of GROUPS states, for the row that says it could not be checked."""


def _guarded(groups: Sequence[str], evaluate: Callable[[], None], rows: list[Row]) -> None:
    """Evaluate the rows of some groups; if that raises, one row per group saying it could not be checked
    and why, so that a group that cannot be evaluated on an arm never discards the others (a
    KeyboardInterrupt still stops the check)."""
    try:
        evaluate()
    except Exception as error:  # any failure of a group's evaluation is reported in its rows
        reason = str(error) if isinstance(error, ModelError) else f"{type(error).__name__}: {error}"
        for group in groups:
            rows.append(Row(group, GROUP_STATEMENTS[group], False, float("nan"), None,
                            f"could not be checked: {reason}", unchecked=reason))  # fmt: skip


def _inertia_rows(arm: Robot, q: np.ndarray, box: list, rows: list[Row], bounds: dict[str, float]) -> None:
    unit = _si(arm, "kg m^2", "kg")
    M = arm.inertia_matrix(q)
    scale = np.abs(M).max()
    asymmetry = np.abs(M - np.swapaxes(M, -1, -2)).max() / scale
    rows.append(Row("symmetry", "M(q) = M(q)^T", asymmetry < TOLERANCE, asymmetry, None, f"{len(q)} samples", unit,
                    "residual"))  # fmt: skip
    eig = np.linalg.eigvalsh(0.5 * (M + np.swapaxes(M, -1, -2)))

    def smallest(p: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(arm.inertia_matrix(p))[0])

    def largest(p: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(arm.inertia_matrix(p))[-1])

    mu1, how1 = _extreme(smallest, q, eig[:, 0], box, False)
    mu2, how2 = _extreme(largest, q, eig[:, -1], box, True)
    bounds["mu1"], bounds["mu2"] = mu1, mu2
    rows.append(Row("positive definite", "M(q) > 0", mu1 > 0, eig[:, 0].min(), mu1, how1, unit, "extreme", ("mu1",)))
    rows.append(Row("inertia bounds", "mu1 I <= M(q) <= mu2 I, (1/mu2) I <= M^-1 <= (1/mu1) I",
                    mu1 > 0 and mu1 <= eig[:, 0].min() + 1e-12 and eig[:, -1].max() <= mu2 + 1e-12,
                    eig[:, -1].max(), mu2, how2, unit, "extreme", ("mu1", "mu2"), eig[:, 0].min()))  # fmt: skip
    ones = np.abs(M).sum(axis=-2).max(axis=-1)  # induced 1-norm: the largest column sum

    def norm1(p: np.ndarray) -> float:
        return float(np.abs(arm.inertia_matrix(p)).sum(axis=0).max())

    m1, _ = _extreme(norm1, q, ones, box, False)
    m2, how = _extreme(norm1, q, ones, box, True)
    bounds["m1"], bounds["m2"] = m1, m2
    rows.append(Row("norm bounds", "m1 <= ||M(q)||_1 <= m2 (induced 1-norm)", 0 < m1 <= m2, ones.max(), m2, how, unit,
                    "extreme", ("m1", "m2"), ones.min()))  # fmt: skip


def _coriolis_rows(
    arm: Robot, q: np.ndarray, x: np.ndarray, y: np.ndarray, box: list, rows: list[Row], bounds: dict, groups: set
) -> None:
    n = arm.n
    torque = _si(arm, "N m", "N")
    Vm = arm.coriolis_matrix(q, x)
    V = arm.coriolis_vector(q, x)
    scale = np.abs(Vm).max() + 1e-300
    if "coriolis" in groups:
        stretched = arm.coriolis_vector(q, 2.5 * x)
        quadratic = np.abs(stretched - 6.25 * V).max() / (6.25 * np.abs(V).max() + 1e-300)
        rows.append(Row("quadratic", "V(q, s qd) = s^2 V(q, qd)", quadratic < TOLERANCE, quadratic, None,
                        f"{len(q)} samples, s = 2.5", torque, "residual"))  # fmt: skip
        norms = np.linalg.norm(Vm, ord=2, axis=(-2, -1))

        def vm_norm(p: np.ndarray) -> float:
            return float(np.linalg.norm(arm.coriolis_matrix(p[:n], _unit(p[n:])), ord=2))

        starts = np.hstack([q, x])
        vb, how = _extreme(vm_norm, starts, norms, box + [(-1.0, 1.0)] * n, True)
        bounds["vb"] = vb
        v_ratio = np.linalg.norm(V, axis=-1)  # |x| = 1
        holds = bool(np.all(v_ratio <= vb * (1 + 1e-9)) and np.all(norms <= vb * (1 + 1e-9)))
        rows.append(Row("Coriolis bound", "||V|| <= vb ||qd||^2 and ||Vm(q, qd)||_2 <= vb ||qd||", holds,
                        norms.max(), vb, how + ", ||qd|| = 1", _si(arm, "N m/(rad/s)^2", "N/(m/s)^2"), "extreme",
                        ("vb",)))  # fmt: skip
        symmetric = (
            np.abs(
                np.einsum("...ij,...j->...i", arm.coriolis_matrix(q, x), y)
                - np.einsum("...ij,...j->...i", arm.coriolis_matrix(q, y), x)
            ).max()
            / scale
        )
        rows.append(Row("Christoffel symmetry", "Vm(q, x) y = Vm(q, y) x", symmetric < TOLERANCE, symmetric, None,
                        f"{len(q)} samples", torque, "residual"))  # fmt: skip
    if "skew" in groups:
        S = arm.inertia_matrix_dot(q, x) - 2 * Vm
        skew = np.abs(S + np.swapaxes(S, -1, -2)).max() / scale
        rows.append(Row("skew symmetry", "Mdot - 2 Vm is skew: x^T (Mdot - 2 Vm) x = 0", skew < TOLERANCE, skew, None,
                        f"{len(q)} samples", torque, "residual"))  # fmt: skip


def _bounded_friction(arm: Robot) -> np.ndarray:
    """max |F_i - Fv_i qd_i| per joint: the Coulomb step's larger side, plus the Stribeck Fs and the sigmoid's A
    (|A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift))| < A)."""
    return np.abs(arm.coulomb_friction).max(axis=1) + arm.stribeck_friction[:, 0] + arm.sigmoid_friction[:, 0]


def _has_friction(arm: Robot) -> bool:
    """True when the arm has any friction (viscous, Coulomb, Stribeck or sigmoid)."""
    laws = (arm.viscous_friction, arm.coulomb_friction, arm.stribeck_friction[:, 0], arm.sigmoid_friction[:, 0])
    return bool(any(np.any(law) for law in laws))


def _friction_rows(arm: Robot, x: np.ndarray, rng: np.random.Generator, rows: list[Row], bounds: dict) -> None:
    speeds = x * rng.uniform(0.0, 5.0, (len(x), 1))
    F = arm.friction(speeds)
    v = float(np.max(arm.viscous_friction, initial=0.0))
    k = float(np.linalg.norm(_bounded_friction(arm)))
    bounds["v"], bounds["k"] = v, k
    lhs = np.linalg.norm(F, axis=-1)
    rhs = v * np.linalg.norm(speeds, axis=-1) + k
    rows.append(Row("friction bound", "||Fv qd + Fd|| <= v ||qd|| + k", bool(np.all(lhs <= rhs * (1 + 1e-12) + 1e-15)),
                    float((lhs - rhs).max()), None, "v = max Fv_ii, k = ||max |Fd_i|||, on samples",
                    _si(arm, "N m", "N"), "margin", ("v", "k")))  # fmt: skip
    power = np.einsum("...i,...i->...", speeds, F)
    rows.append(Row("dissipation", "qd^T F(qd) >= 0", bool(np.all(power >= -1e-12)), float(power.min()), 0.0,
                    f"{len(x)} samples", "W"))  # fmt: skip


PASSIVITY_DURATION = 1.0
"""The length in seconds of the motion ``check`` evaluates the energy balance along."""

PASSIVITY_RTOL = (1e-7, 1e-10)
"""The relative tolerances of the two integrations of the passivity rows: the balance is taken from
the tighter one, and the difference of the two estimates its integration error."""

PASSIVITY_FLOOR = 1e-9
"""The smallest tolerance of the passivity rows, relative to the energy that flows: rounding over
the run's steps, below which the two integrations cannot tell a balance from zero."""


def _gravity_row(arm: Robot, q: np.ndarray, box: list, rows: list[Row], bounds: dict[str, float]) -> None:
    torque = _si(arm, "N m", "N")
    norms = np.linalg.norm(arm.gravity_vector(q), axis=-1)
    gb, how = _extreme(lambda p: float(np.linalg.norm(arm.gravity_vector(p))), q, norms, box, True)
    bounds["gb"] = gb
    rows.append(Row("gravity bound", "||G(q)|| <= gb", bool(np.all(norms <= gb * (1 + 1e-12))), norms.max(), gb,
                    how, torque, "extreme", ("gb",)))  # fmt: skip


def _linearity_row(arm: Robot, q: np.ndarray, rng: np.random.Generator, rows: list[Row]) -> None:
    qd, qdd = rng.uniform(-2, 2, (2, *q.shape))
    W = arm.regressor(q, qd, qdd)
    tau = arm.inverse_dynamics(q, qd, qdd)
    error = np.abs(W @ arm.parameters() - tau).max() / (np.abs(tau).max() + 1e-300)
    rows.append(Row("linearity", "M qdd + Vm qd + F + G = W(q, qd, qdd) phi", error < 1e-10, error, None,
                    f"{len(q)} samples, recursive regressor", _si(arm, "N m", "N"), "residual"))  # fmt: skip


def _passivity_motion(robot: Robot, ranges: list[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The start q0, amplitudes A and angular frequencies w of the motion the passivity rows drive.

    Each joint starts at rest at 40% of its range (in a range wider than a turn, at the point
    nearest 0 that leaves room for the motion) and follows q0 + A (1 - cos w t):
    A is a tenth of its range (at most 0.3 rad or m), w = 2 pi (1 + 0.37 (i mod 8)) rad/s.
    """
    low, high = np.array(ranges).T
    amplitude = np.minimum(0.1 * (high - low), 0.3)
    # in a range wider than a turn (limits of 1e16 stand for none), start at the point nearest 0 instead
    q0 = np.where(high - low <= 2 * np.pi, low + 0.4 * (high - low), np.clip(0.0, low, high - 2 * amplitude))
    omega = 2 * np.pi * (1.0 + 0.37 * (np.arange(robot.n) % 8))
    return q0, amplitude, omega


def _energy_balance(
    arm: Robot, q0: np.ndarray, amplitude: np.ndarray, omega: np.ndarray, rtol: float
) -> tuple[float, float, float]:
    """The work supplied W = integral qd^T tau dt, the change of the total energy H = K + P, and the
    largest energy that flows, along the arm's motion under tau = M(q) a(t) + Vm(q, qd) qd + F(qd) + G(q).

    The torque is scaled to the arm: it is the inverse dynamics of a(t) = A w^2 cos(w t), so every
    joint, heavy or light, moves about q0 + A (1 - cos w t), and no light distal link is thrown
    to speeds the step cannot follow (the balance does not depend on the torque: any model error
    in M, Vm, F or G shows in it whatever tau is). The passivity of the robot equation (Lewis,
    Dawson and Abdallah 2004, Table 3.3.1) is the balance W = H(T) - H(0) + integral qd^T F_m(qd) dt
    with F_m the friction of the forward dynamics, which dissipates (>= 0). The motion is
    integrated by scipy's solve_ivp (DOP853) at relative tolerance ``rtol``; K and P come from
    the arm's exact energies at the states reached.
    """
    from scipy.integrate import solve_ivp

    n = arm.n

    def rate(t: float, state: np.ndarray) -> np.ndarray:
        q, qd = state[:n], state[n : 2 * n]
        tau = arm.inverse_dynamics(q, qd, amplitude * omega**2 * np.cos(omega * t))
        return np.concatenate([qd, arm.forward_dynamics(q, qd, tau), [qd @ tau]])

    speed = amplitude * omega
    typical = 0.5 * speed @ arm.inertia_matrix(q0) @ speed + np.abs(arm.gravity_vector(q0)) @ amplitude
    # one absolute tolerance for all q, one for all qd: a joint with no range to move in (A = 0) asks no more
    scales = [
        np.full(n, max(amplitude.max(), 1e-3)),
        np.full(n, max(speed.max(), 1e-3)),
        np.array([max(typical, 1e-12)]),
    ]
    atol = rtol * np.concatenate(scales)
    samples = np.linspace(0.0, PASSIVITY_DURATION, 101)
    start = np.concatenate([q0, np.zeros(n), [0.0]])
    run = solve_ivp(rate, (0.0, PASSIVITY_DURATION), start, "DOP853", samples, rtol=rtol, atol=atol)
    if not run.success:
        message = f"the motion of '{arm.name}' could not be integrated to rtol = {rtol:g}: {run.message}"
        raise SimulationError(message, run)
    energies = arm.energies(run.y[:n].T, run.y[n : 2 * n].T)
    K, P, W = energies[:, 0], energies[:, 1], run.y[-1]
    flow = float(K.max() + np.abs(P - P[0]).max() + np.abs(W).max()) + _TINY
    return float(W[-1]), float(K[-1] + P[-1] - K[0] - P[0]), flow


def _passivity_rows(robot: Robot, ranges: list[tuple[float, float]], rows: list[Row]) -> None:
    """The energy balance of Table 3.3.1's passivity along the arm's motion, without and with friction.

    integral_0^T qd^T tau dt = H(T) - H(0) + dissipated work (Lewis, Dawson and Abdallah 2004,
    Table 3.3.1), H = K + P: without friction the supplied work equals the change of H; with it,
    it is at least that change. The motion is integrated twice (PASSIVITY_RTOL); the balance is the
    tighter run's, its error estimated by the difference of the two, so integration error is
    never counted as a violation and a violation is one that stays as the tolerance tightens.
    """
    q0, amplitude, omega = _passivity_motion(robot, ranges)
    loose, tight = PASSIVITY_RTOL
    friction = _has_friction(robot)
    for arm, label in ((robot.without_friction(), "lossless"), (robot, "with friction")):
        if label == "with friction" and not friction:
            continue
        work, gained, flow = _energy_balance(arm, q0, amplitude, omega, tight)
        work_loose, gained_loose, _ = _energy_balance(arm, q0, amplitude, omega, loose)
        excess = gained - work  # H(T) - H(0) - integral qd^T tau dt: minus the work dissipated
        estimate = abs((gained_loose - work_loose) - excess)
        tolerance = max(10 * estimate, PASSIVITY_FLOOR * flow)
        how = (f"{PASSIVITY_DURATION:g} s under tau = M a(t) + Vm qd + F + G, DOP853 at rtol {tight:g}; integration "
               f"error {estimate:.2g} J (the rerun at rtol {loose:g}), tolerance {tolerance:.2g} J")  # fmt: skip
        if label == "lossless":
            rows.append(Row("passivity", "integral qd^T tau dt = H(T) - H(0), H = K + P (no friction)",
                            abs(excess) <= tolerance, abs(excess) / flow, None,
                            f"{how}; relative to the energy that flows, {flow:.4g} J", "J", "residual"))  # fmt: skip
        else:
            rows.append(Row("passivity with friction", "H(T) - H(0) <= integral qd^T tau dt (friction dissipates)",
                            excess <= tolerance, excess, None, f"{how}; dissipated {-excess:.4g} J", "J",
                            "margin"))  # fmt: skip


# ----- task coordinates (Section 3.5) ---------------------------------------------------------
_STEP = 5e-3
"""The central difference's step along the motion: ||h qd|| = _STEP / cond J(q), which keeps the
stencil as far inside the regular region, relative to the distance to the singularity, everywhere."""

_TINY = 1e-300


def _task_output(task: object) -> task_space.TaskOutput:
    if not isinstance(task, task_space.TaskOutput):
        raise ArgumentError(
            "task must be a task output of armdyn.task_space (ToolPosition, ToolPose, LinkPoint, PlanarPosition, "
            f"Camera or Output), got {type(task).__name__}"
        )
    return task


def _max_condition(value: object, task: object) -> float:
    """The checked ``max_condition`` (REGION_MAX_CONDITION for None)."""
    if task is None:
        raise ModelError("max_condition applies to task coordinates only: give task=... with it")
    if value is None:
        return REGION_MAX_CONDITION
    limit = inputs.number(value, "max_condition")
    ceiling = task_space.DEFAULT_MAX_CONDITION
    if not 1.0 < limit <= ceiling:
        raise ModelError(
            f"max_condition must be greater than 1 (a condition number is at least 1) and at most {ceiling:g} "
            f"(armdyn.task_space's limit, above which J counts as singular), got {limit:g}"
        )
    return limit


def _task_units(output: task_space.TaskOutput) -> tuple[dict[str, str], str | None]:
    """The units of Mbar, f, vb and v in the output's coordinates, and a note where they need one."""
    if isinstance(output, (task_space.ToolPosition, task_space.LinkPoint, task_space.PlanarPosition)):
        return {"inertia": "kg", "force": "N", "vb": "N/(m/s)^2", "v": "N/(m/s)"}, None
    if isinstance(output, task_space.Camera):
        units = {"inertia": "J s^2/u^2", "force": "J/u", "vb": "J s^2/u^3", "v": "J s/u^2"}
        return units, (
            "u is the camera's image unit (that of its focal length, e.g. pixels): f = J^-T tau is work per "
            "image unit (J/u) and Mbar is in J s^2/u^2"
        )
    generic = dict.fromkeys(("inertia", "force", "vb", "v"), "output units")
    if isinstance(output, task_space.ToolPose):
        return generic, (
            f"{output!r} mixes units: y = [p (m); orientation (rad)] with the rate [v (m/s); w (rad/s)] and "
            "f = [force (N); moment (N m)], so Mbar has blocks in kg, kg m and kg m^2: its values are labelled "
            "'output units'"
        )
    return generic, (
        f"the coordinates of {output!r} have their own units ('output units'); f = J^-T tau is the force dual "
        "to them (f^T ydot is a power in W)"
    )


def _solve(J: np.ndarray, v: np.ndarray) -> np.ndarray:
    """J^-1 v for (k, n, n) J and (k, n) v."""
    return np.linalg.solve(J, v[..., None])[..., 0]


def _units_rows(v: np.ndarray) -> np.ndarray:
    """The rows of v scaled to unit length."""
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), _TINY)


@dataclass
class _Region:
    """The regular samples of the joint ranges (cond J(q) < limit) and the task quantities on them."""

    robot: Robot
    output: task_space.TaskOutput
    limit: float
    box: list[tuple[float, float]]
    q: np.ndarray
    cond: np.ndarray
    J: np.ndarray

    def __post_init__(self) -> None:
        self.n, self.m = self.robot.n, self.J.shape[-2]
        self.square = self.m == self.n
        self.guard = float(max(1e3 * self.limit, task_space.DEFAULT_MAX_CONDITION))
        scale = max(1.0, float(self.cond.max()) / REGION_MAX_CONDITION)
        self.tolerance, self.fd_tolerance = TOLERANCE * scale, FD_TOLERANCE * scale
        self.symbol = "Mbar" if self.square else "Lambda"

    def inertia(self, q: np.ndarray) -> np.ndarray:
        """Mbar (square) or Lambda (redundant) at q, (n,) or (k, n)."""
        if self.square:
            return task_space.task_inertia(self.robot, self.output, q, max_condition=self.guard)
        return task_space.operational_inertia(self.robot, self.output, q, max_condition=self.guard)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        return self.output.jacobian(self.robot, q)

    def margin(self, q: np.ndarray) -> float:
        """limit / cond J(q) - 1: positive inside the region, -1 where J is singular."""
        try:
            return float(self.limit / task_space.condition_number(self.robot, self.output, q) - 1.0)
        except ModelError:
            return -1.0

    def _inside(self, point: np.ndarray, start: np.ndarray) -> np.ndarray:
        """``point`` if it lies in the region, else the farthest point of the segment from ``start`` found inside."""
        n = self.n
        if self.margin(point[:n]) > 0:
            return point
        inside, outside = 0.0, 1.0
        for _ in range(50):
            middle = 0.5 * (inside + outside)
            if self.margin((start + middle * (point - start))[:n]) > 0:
                inside = middle
            else:
                outside = middle
        return start + inside * (point - start)

    def refine(
        self,
        f: Callable[[np.ndarray], float],
        starts: np.ndarray,
        values: np.ndarray,
        largest: bool,
        box: list | None = None,
    ) -> tuple[float, str]:
        """The extreme of f over the region: the sampled one, refined by SLSQP under cond J(q) < limit
        from the best 3 samples; every value kept is f at a point of the region. (value, how).

        A positive f is optimized as log f: near a singularity it grows by orders of magnitude."""
        box = self.box if box is None else box
        sign = -1.0 if largest else 1.0
        best = float(values.max() if largest else values.min())
        lower, upper = np.array(box, dtype=float).T
        failed = (np.linalg.LinAlgError, ModelError)
        positive = bool(np.all(values > 0))
        scale = 1.0 if positive else abs(best) + _TINY
        worse = sign * (np.log(best) if positive else best / scale) + 1.0

        def objective(p: np.ndarray) -> float:
            try:
                value = float(f(p))
            except failed:
                return worse
            if positive:
                value = np.log(value) if value > 0 else -np.inf
            value = sign * value / scale
            return value if np.isfinite(value) else worse

        constraint = {"type": "ineq", "fun": lambda p: self.margin(p[: self.n])}
        for start in starts[np.argsort(sign * values)[:3]]:
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.simplefilter("ignore")
                result = minimize(objective, start, method="SLSQP", bounds=box, constraints=[constraint],
                                  options={"maxiter": 60})  # fmt: skip
            if not np.all(np.isfinite(result.x)):
                continue
            point = self._inside(np.clip(result.x, lower, upper), start)
            try:
                value = float(f(point))
            except failed:
                continue
            if np.isfinite(value):
                best = max(best, value) if largest else min(best, value)
        how = f"{len(values)} regular samples, refined by SLSQP under cond J < {self.limit:g} from the best 3"
        return best, how

    def rate(self, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """d/dt of Mbar (Lambda) along the motion qd, by a 4th-order central difference, (k, m, m), and
        the size below which it is rounding (eps |Mbar| / h, per sample)."""
        speed = np.linalg.norm(qd, axis=-1)
        h = _STEP / (self.cond * np.maximum(speed, _TINY))
        A = [self.inertia(self.q + k * h[:, None] * qd) for k in (-2, -1, 1, 2)]
        rounding = np.finfo(float).eps * np.abs(A[0]).max(axis=(-2, -1)) / h
        return (A[0] - 8 * A[1] + 8 * A[2] - A[3]) / (12 * h[:, None, None]), rounding

    def parts(self, qd: np.ndarray) -> np.ndarray:
        """The sizes of the two terms of Vmbar = J^-T Vm J^-1 - Mbar Jdot J^-1 (of mu_x = Jbar^T Vm Jbar -
        Lambda Jdot Jbar) added, per sample: the scale of the Coriolis residuals, as the terms can cancel
        (for a point mass at a position output, Vmbar = 0)."""
        robot, output, q = self.robot, self.output, self.q
        if self.square:
            inverse, A = np.linalg.solve(self.J, np.broadcast_to(np.eye(self.n), self.J.shape)), self.inertia(q)
        else:
            space = task_space.operational_space(robot, output, q, qd, max_condition=self.guard)
            inverse, A = space.Jbar, space.Lambda
        first = np.swapaxes(inverse, -1, -2) @ robot.coriolis_matrix(q, qd) @ inverse
        second = A @ output.jacobian_dot(robot, q, qd) @ inverse
        return np.abs(first).max(axis=(-2, -1)) + np.abs(second).max(axis=(-2, -1))


def _check_task(
    arm: Robot,
    task: object,
    max_condition: object,
    samples: int,
    seed: int,
    ranges: list[tuple[float, float]],
    groups: set[str],
) -> Report:
    """``check`` in the coordinates of a task output (see ``check``)."""
    limit = _max_condition(max_condition, task)
    output = _task_output(task)
    n = arm.n
    rng = np.random.default_rng(seed)
    low, high = np.array(ranges).T
    candidates = rng.uniform(low, high, (samples, n))
    cond = np.asarray(task_space.condition_number(arm, output, candidates))
    regular = cond < limit
    kept = int(regular.sum())
    if kept < MIN_REGULAR:
        raise ModelError(
            f"only {kept} of {samples} sampled configurations of arm '{arm.name}' have cond J(q) below "
            f"max_condition = {limit:g} for output {output!r}: the joint ranges are singular or nearly so almost "
            f"everywhere, and the task-space bounds need at least {MIN_REGULAR} regular samples; change the "
            "limits, raise max_condition or sample more"
        )
    q = candidates[regular]
    region = _Region(arm, output, limit, [(lo, hi) for lo, hi in ranges], q, cond[regular], output.jacobian(arm, q))
    units, unit_note = _task_units(output)
    rows: list[Row] = []
    bounds: dict[str, float] = {}
    notes = [
        f"in task coordinates of {output!r} (Section 3.5): the bounds hold over the configurations of the "
        f"joint ranges where cond J(q) < max_condition = {limit:g}, and grow without bound near singularities; "
        f"{kept} of {samples} samples kept, {samples - kept} rejected as singular or nearly so"
    ]
    if unit_note:
        notes.append(unit_note)
    prismatic = [i for i, kind in enumerate(arm.kinds) if kind == "prismatic"]
    if prismatic:
        notes.append(
            "the arm has prismatic joints, so its bounds depend on q; they hold over the range "
            + ", ".join(f"q{i + 1} in [{ranges[i][0]:.3g}, {ranges[i][1]:.3g}]" for i in prismatic)
        )
    if not region.square:
        labels = {"coriolis": "Coriolis", "friction": "friction", "linearity": "linearity"}
        skipped = [label for group, label in labels.items() if group in groups]
        named = ", ".join(skipped[:-1]) + (" and " if len(skipped) > 1 else "") + (skipped[-1] if skipped else "")
        notes.append(
            f"{output!r} has m = {region.m} coordinates for n = {n} joints (redundant): the inertia rows are for "
            "Khatib's Lambda = (J M^-1 J^T)^-1, the skew row for Lambda_dot - 2 mu_x (task_space.operational_coriolis) "
            "and the gravity row for p = Jbar^T G"
            + (
                f"; the {named} rows are skipped: Vmbar, Fbar and Wbar are defined for square outputs "
                "(m = n) only, and Jbar^T Vm qd and Jbar^T F(qd) depend on the null-space velocity, not on ydot alone"
                if skipped
                else ""
            )
        )
    if "inertia" in groups:
        _guarded(["inertia"], lambda: _task_inertia_rows(region, rows, bounds, units["inertia"]), rows)
    if region.square and ("coriolis" in groups or "skew" in groups):
        chosen = [group for group in ("coriolis", "skew") if group in groups]
        _guarded(chosen, lambda: _task_coriolis_rows(region, rng, rows, bounds, groups, units), rows)
        if "coriolis" in groups and isinstance(output, task_space.ToolPose):
            notes.append(
                f"the rate of {output!r} is the twist [v; w], and w is not the derivative of any coordinates, so "
                "Vmbar is not a Christoffel form: the Christoffel symmetry row is skipped (the skew row holds)"
            )
    elif "skew" in groups:

        def skew() -> None:
            qd = _units_rows(rng.normal(size=(kept, n)))
            mu_x, _ = task_space.operational_coriolis(arm, output, q, qd, max_condition=region.guard)
            _skew_row(region, qd, mu_x, "mu_x", rows, units["force"])

        _guarded(["skew"], skew, rows)
    if region.square and "friction" in groups:
        if _has_friction(arm):
            _guarded(["friction"], lambda: _task_friction_rows(region, rng, rows, bounds, units), rows)
        else:
            notes.append("the arm has no friction (F = 0, so Fbar = 0): the friction rows are skipped")
    if "gravity" in groups:
        _guarded(["gravity"], lambda: _task_gravity_row(region, rows, bounds, units["force"]), rows)
    if region.square and "linearity" in groups:
        _guarded(["linearity"], lambda: _task_linearity_row(region, rng, rows, units["force"]), rows)
    if "passivity" in groups:
        notes.append(
            "passivity is not checked in task coordinates: the power ydot^T f equals qd^T tau, so it is the "
            "joint-space balance (check without task)"
        )
    kinds = {"mu1": "inertia", "mu2": "inertia", "m1": "inertia", "m2": "inertia", "vb": "vb", "v": "v", "k": "force",
             "gb": "force"}  # fmt: skip
    return Report(arm.name, rows, bounds, ranges, notes, {key: units[kinds[key]] for key in bounds},
                  task=repr(output), max_condition=limit)  # fmt: skip


def _task_inertia_rows(region: _Region, rows: list[Row], bounds: dict[str, float], unit: str) -> None:
    robot, q, J, A = region.robot, region.q, region.J, region.symbol
    M = robot.inertia_matrix(q)
    if region.square:
        inverse = np.linalg.solve(J, np.broadcast_to(np.eye(region.n), J.shape))
        direct, formula = np.swapaxes(inverse, -1, -2) @ M @ inverse, "J^-T M J^-1"
    else:
        direct, formula = np.linalg.inv(J @ np.linalg.solve(M, np.swapaxes(J, -1, -2))), "(J M^-1 J^T)^-1"
    scale = np.abs(direct).max(axis=(-2, -1)) + _TINY
    asymmetry = float((np.abs(direct - np.swapaxes(direct, -1, -2)).max(axis=(-2, -1)) / scale).max())
    rows.append(Row("symmetry", f"{A}(q) = {A}(q)^T, {A} = {formula}", asymmetry < region.tolerance, asymmetry, None,
                    f"{len(q)} regular samples, {formula} by linear solves", unit, "residual"))  # fmt: skip
    inertia = region.inertia(q)
    eig = np.linalg.eigvalsh(inertia)

    def smallest(p: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(region.inertia(p))[0])

    def largest(p: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(region.inertia(p))[-1])

    mu1, how1 = region.refine(smallest, q, eig[:, 0], False)
    mu2, how2 = region.refine(largest, q, eig[:, -1], True)
    bounds["mu1"], bounds["mu2"] = mu1, mu2
    rows.append(Row("positive definite", f"{A}(q) > 0", mu1 > 0, float(eig[:, 0].min()), mu1, how1, unit, "extreme",
                    ("mu1",)))  # fmt: skip
    rows.append(Row("inertia bounds", f"mu1 I <= {A}(q) <= mu2 I, (1/mu2) I <= {A}^-1 <= (1/mu1) I",
                    mu1 > 0 and mu1 <= eig[:, 0].min() * (1 + 1e-12) and eig[:, -1].max() <= mu2 * (1 + 1e-12),
                    float(eig[:, -1].max()), mu2, how2, unit, "extreme", ("mu1", "mu2"),
                    float(eig[:, 0].min())))  # fmt: skip
    ones = np.abs(inertia).sum(axis=-2).max(axis=-1)

    def norm1(p: np.ndarray) -> float:
        return float(np.abs(region.inertia(p)).sum(axis=0).max())

    m1, _ = region.refine(norm1, q, ones, False)
    m2, how = region.refine(norm1, q, ones, True)
    bounds["m1"], bounds["m2"] = m1, m2
    rows.append(Row("norm bounds", f"m1 <= ||{A}(q)||_1 <= m2 (induced 1-norm)", 0 < m1 <= m2, float(ones.max()), m2,
                    how, unit, "extreme", ("m1", "m2"), float(ones.min())))  # fmt: skip


def _skew_row(region: _Region, qd: np.ndarray, C: np.ndarray, name: str, rows: list[Row], unit: str) -> None:
    """Mbar_dot - 2 Vmbar (Lambda_dot - 2 mu_x) skew along the motion qd, relative to the largest of its
    terms, and at least 100 times the rounding of the difference over the tolerance."""
    A = region.symbol
    rate, rounding = region.rate(qd)
    S = rate - 2 * C
    scale = np.maximum(np.abs(rate).max(axis=(-2, -1)), 2 * np.abs(C).max(axis=(-2, -1)))
    scale = np.maximum(np.maximum(scale, 2 * region.parts(qd)), 100 * rounding / region.fd_tolerance) + _TINY
    skew = float((np.abs(S + np.swapaxes(S, -1, -2)).max(axis=(-2, -1)) / scale).max())
    how = (f"{len(rate)} regular samples, {A}_dot by a 4th-order central difference along the motion "
           f"(step ||h qd|| = {_STEP:g} / cond J), tolerance {region.fd_tolerance:.3g}")  # fmt: skip
    rows.append(Row("skew symmetry", f"{A}_dot - 2 {name} is skew: x^T ({A}_dot - 2 {name}) x = 0",
                    skew < region.fd_tolerance, skew, None, how, unit, "residual"))  # fmt: skip


def _task_coriolis_rows(
    region: _Region, rng: np.random.Generator, rows: list[Row], bounds: dict, groups: set, units: dict[str, str]
) -> None:
    robot, output, q, J, n, m = region.robot, region.output, region.q, region.J, region.n, region.m
    k = len(q)
    x = _units_rows(rng.normal(size=(k, m)))
    y = _units_rows(rng.normal(size=(k, m)))

    def coriolis(p: np.ndarray, ydot: np.ndarray) -> np.ndarray:
        return task_space.task_coriolis(robot, output, p, _solve(J, ydot), max_condition=region.guard)

    Vx = coriolis(q, x)
    V = np.einsum("...ij,...j->...i", Vx, x)
    scale = np.maximum(np.abs(Vx).max(axis=(-2, -1)), region.parts(_solve(J, x))) + _TINY
    if "coriolis" in groups:
        stretched = np.einsum("...ij,...j->...i", coriolis(q, 2.5 * x), 2.5 * x)
        quadratic = float((np.abs(stretched - 6.25 * V).max(axis=-1) / (6.25 * scale)).max())
        rows.append(Row("quadratic", "Vbar(q, s ydot) = s^2 Vbar(q, ydot), Vbar = Vmbar ydot",
                        quadratic < region.tolerance, quadratic, None, f"{k} regular samples, s = 2.5", units["force"],
                        "residual"))  # fmt: skip
        norms = np.linalg.norm(Vx, ord=2, axis=(-2, -1))

        def vm_norm(p: np.ndarray) -> float:
            qp = p[:n]
            qd = np.linalg.solve(region.jacobian(qp), _unit(p[n:]))
            return float(np.linalg.norm(task_space.task_coriolis(robot, output, qp, qd, max_condition=region.guard), 2))

        vb, how = region.refine(vm_norm, np.hstack([q, x]), norms, True, region.box + [(-1.0, 1.0)] * m)
        bounds["vb"] = vb
        v_ratio = np.linalg.norm(V, axis=-1)
        holds = bool(np.all(v_ratio <= vb * (1 + 1e-9)) and np.all(norms <= vb * (1 + 1e-9)))
        rows.append(Row("Coriolis bound", "||Vbar|| <= vb ||ydot||^2 and ||Vmbar(q, ydot)||_2 <= vb ||ydot||", holds,
                        float(norms.max()), vb, how + ", ||ydot|| = 1", units["vb"], "extreme", ("vb",)))  # fmt: skip
    if "coriolis" in groups and not isinstance(output, task_space.ToolPose):
        Vy = coriolis(q, y)
        symmetric = np.abs(np.einsum("...ij,...j->...i", Vx, y) - np.einsum("...ij,...j->...i", Vy, x)).max(axis=-1)
        other = np.maximum(np.abs(Vy).max(axis=(-2, -1)), region.parts(_solve(J, y)))
        symmetric = float((symmetric / np.maximum(scale, other)).max())
        rows.append(Row("Christoffel symmetry", "Vmbar(q, x) y = Vmbar(q, y) x", symmetric < region.tolerance,
                        symmetric, None, f"{k} regular samples", units["force"], "residual"))  # fmt: skip
    if "skew" in groups:
        _skew_row(region, _solve(J, x), Vx, "Vmbar", rows, units["force"])


def _task_friction_rows(
    region: _Region, rng: np.random.Generator, rows: list[Row], bounds: dict, units: dict[str, str]
) -> None:
    robot, output, q, J = region.robot, region.output, region.q, region.J
    k = len(q)
    speeds = _units_rows(rng.normal(size=(k, region.m))) * rng.uniform(0.0, 5.0, (k, 1))
    F = task_space.task_friction(robot, output, q, _solve(J, speeds), max_condition=region.guard)
    viscous = robot.viscous_friction
    coulomb = float(np.linalg.norm(_bounded_friction(robot)))

    def inverse(p: np.ndarray) -> np.ndarray:
        J = region.jacobian(p)
        return np.linalg.solve(J, np.broadcast_to(np.eye(J.shape[-1]), J.shape))

    def coupled(p: np.ndarray) -> np.ndarray:
        Jinv = inverse(p)
        return np.linalg.norm(np.swapaxes(Jinv, -1, -2) @ (viscous[:, None] * Jinv), ord=2, axis=(-2, -1))

    def compliance(p: np.ndarray) -> np.ndarray:
        return np.linalg.norm(inverse(p), ord=2, axis=(-2, -1))

    v, how = region.refine(lambda p: float(coupled(p)), q, coupled(q), True)
    largest, _ = region.refine(lambda p: float(compliance(p)), q, compliance(q), True)
    bounds["v"], bounds["k"] = v, coulomb * largest
    lhs = np.linalg.norm(F, axis=-1)
    rhs = v * np.linalg.norm(speeds, axis=-1) + bounds["k"]
    rows.append(Row("friction bound", "||Fbar(q, ydot)|| <= v ||ydot|| + k, Fbar = J^-T F(J^-1 ydot)",
                    bool(np.all(lhs <= rhs * (1 + 1e-9) + 1e-15)), float((lhs - rhs).max()), None,
                    "v = max ||J^-T Fv J^-1||_2, k = ||max |Fd_i||| max ||J^-T||_2; " + how, units["force"], "margin",
                    ("v", "k")))  # fmt: skip
    power = np.einsum("...i,...i->...", speeds, F)
    rows.append(Row("dissipation", "ydot^T Fbar(q, ydot) >= 0 (= qd^T F(qd))", bool(np.all(power >= -1e-12)),
                    float(power.min()), 0.0, f"{k} regular samples", "W"))  # fmt: skip


def _task_gravity_row(region: _Region, rows: list[Row], bounds: dict, unit: str) -> None:
    robot, output, guard = region.robot, region.output, region.guard

    def gravity(p: np.ndarray) -> np.ndarray:
        if region.square:
            return task_space.task_gravity(robot, output, p, max_condition=guard)
        return task_space.operational_space(robot, output, p, np.zeros_like(p), max_condition=guard).p

    norms = np.linalg.norm(gravity(region.q), axis=-1)
    gb, how = region.refine(lambda p: float(np.linalg.norm(gravity(p))), region.q, norms, True)
    bounds["gb"] = gb
    statement = "||Gbar(q)|| <= gb, Gbar = J^-T G" if region.square else "||p(q)|| <= gb, p = Jbar^T G"
    rows.append(Row("gravity bound", statement, bool(np.all(norms <= gb * (1 + 1e-12))), float(norms.max()), gb, how,
                    unit, "extreme", ("gb",)))  # fmt: skip


def _task_linearity_row(region: _Region, rng: np.random.Generator, rows: list[Row], unit: str) -> None:
    robot, output, q, guard = region.robot, region.output, region.q, region.guard
    ydot, yddot = rng.uniform(-2, 2, (2, len(q), region.m))
    qd = _solve(region.J, ydot)
    W = task_space.task_regressor(robot, output, q, qd, yddot, max_condition=guard)
    phi = robot.parameters()
    lhs = np.einsum("...ij,...j->...i", region.inertia(q), yddot)
    lhs = lhs + task_space.task_nonlinear(robot, output, q, qd, max_condition=guard)
    scale = (np.abs(W) @ np.abs(phi)).max(axis=-1) + _TINY
    error = float((np.abs(W @ phi - lhs).max(axis=-1) / scale).max())
    rows.append(Row("linearity", "Mbar yddot + Nbar = Wbar(q, qd, yddot) phi, phi = arm.parameters()",
                    error < region.tolerance, error, None,
                    f"{len(q)} regular samples, Wbar = J^-T W at qdd = J^-1 (yddot - Jdot qd)", unit,
                    "residual"))  # fmt: skip
