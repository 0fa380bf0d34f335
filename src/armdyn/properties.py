"""The properties of the robot equation (Table 3.3.1, BOOK.md section 3): checks and bounds.

Every bound is computed: the quantity is evaluated on random samples of the joint range
(the arm's limits; the whole circle for revolute joints without limits; a span from the
lower limit for prismatic joints without limits, where bounds depend on q), and the
extremes are then refined by a bounded local optimizer (scipy.optimize, L-BFGS-B) started
from the best samples. The report says for each bound how it was found.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from armdyn import inputs
from armdyn.errors import ModelError
from armdyn.robot import Robot

TOLERANCE = 1e-9
GROUPS = ("inertia", "coriolis", "skew", "friction", "gravity", "linearity", "passivity")
"""The groups of properties ``check`` evaluates; ``only`` picks some of them by name."""


def _check_robot(robot: object) -> None:
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be an armdyn Robot, got {type(robot).__name__}")


def _groups(only: object) -> set[str]:
    """The groups named by ``only``: None for all, one name, or a sequence of names."""
    if only is None:
        return set(GROUPS)
    valid = ", ".join(repr(group) for group in GROUPS)
    if isinstance(only, str):
        names = [only]
    elif isinstance(only, (bytes, Mapping)) or not isinstance(only, Iterable):
        raise TypeError(f"only must be a group name or a sequence of group names ({valid}), got {only!r}")
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


def _quantity(value: float, unit: str, digits: int) -> str:
    """A number with its unit, e.g. "5.828 kg m^2"."""
    text = f"{value:.{digits}g}"
    return f"{text} {unit}" if unit else text


@dataclass
class Report:
    """The properties of Table 3.3.1 for one arm over a joint range (BOOK.md section 3).

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
    """

    arm: str
    rows: list[Row]
    bounds: dict[str, float]
    ranges: list[tuple[float, float]]
    notes: list[str] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)
    references: dict[str, float] = field(default_factory=dict)

    @property
    def all_hold(self) -> bool:
        return all(row.holds for row in self.rows)

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
        the largest excess lhs - rhs of an inequality (<= 0 where it holds).

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
            if row.measure == "extreme":
                extreme = _quantity(row.worst, row.unit, digits)
                if row.lowest is not None:
                    extreme = f"{_quantity(row.lowest, row.unit, digits)} to {extreme}"
            elif row.measure == "residual" or not row.unit:
                residual = f"{row.worst:.3g} (relative)"
            else:
                residual = _quantity(row.worst, row.unit, 3)
            holds = "yes" if row.holds else "NO"
            references = self._named(self.references, row.names, digits)
            rows.append([row.name, row.statement, holds, bound, references, extreme, residual, row.how])
        return list(COLUMNS), rows

    def table(self) -> object:
        """A rich Table of the report (the columns of ``records``).

        Returns
        -------
        rich.table.Table
            One line per property: statement, whether it holds, the computed bounds, the
            book's values, the extreme sampled, the residual or margin, and how.
        """
        from rich.table import Table

        ranges = ", ".join(f"[{lo:.4g}, {hi:.4g}]" for lo, hi in self.ranges)
        table = Table(
            title=f"Table 3.3.1 for {self.arm}, joint ranges {ranges}",
            caption="residual: the largest relative error of an identity (0 is exact); "
            "margin: the largest lhs - rhs of an inequality found (<= 0 where it holds)",
        )
        columns, rows = self.records()
        for column in columns:
            table.add_column(column, overflow="fold")
        for cells in rows:
            cells[2] = "[green]yes[/green]" if cells[2] == "yes" else "[red]NO[/red]"
            table.add_row(*cells)
        return table


def _si(robot: Robot, revolute: str, prismatic: str) -> str:
    """The unit of a quantity of the arm: ``revolute`` for revolute joints, ``prismatic`` for prismatic ones."""
    kinds = set(robot.kinds)
    if kinds == {"revolute"}:
        return revolute
    if kinds == {"prismatic"}:
        return prismatic
    return f"{revolute} or {prismatic}"


def joint_ranges(
    robot: Robot, limits: Sequence[tuple[float, float]] | None = None, prismatic_span: float = 1.0
) -> list[tuple[float, float]]:
    """The range sampled for each joint (see the module docstring).

    The arm's limits where both are finite; otherwise the whole circle for a revolute
    joint, and for a prismatic joint a span of ``prismatic_span`` from its finite limit
    (or centred on 0 when it has none).

    Parameters
    ----------
    robot : Robot
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
    TypeError
        When ``robot`` is not a Robot.
    """
    _check_robot(robot)
    span = inputs.vector(prismatic_span, "prismatic_span")
    if span.shape != (1,) or span[0] <= 0:
        raise ModelError(f"prismatic_span must be one positive finite number, got {prismatic_span!r}")
    prismatic_span = float(span[0])
    if limits is not None:
        pairs = inputs.state(limits, 2, "limits")
        if pairs.shape != (robot.n, 2) or np.any(pairs[:, 0] > pairs[:, 1]):
            raise ModelError(
                f"limits must be {robot.n} finite (lower, upper) pairs with lower <= upper, got {pairs.tolist()}"
            )
        return [(float(lo), float(hi)) for lo, hi in pairs]
    ranges = []
    for (lower, upper), kind in zip(robot.qlim.T, robot.kinds, strict=True):
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


def inertia_bounds(robot: Robot, samples: int = 400, seed: int = 0, limits: Sequence | None = None) -> tuple:
    """(mu1, mu2) with mu1 I <= M(q) <= mu2 I over the joint range (3.3.6).

    The smallest and largest eigenvalues of M(q) over random samples of the joint range,
    refined by L-BFGS-B (see the module docstring); ``check`` restricted to "inertia".

    Parameters
    ----------
    robot : Robot
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
    TypeError
        When ``robot`` is not a Robot, or ``samples`` or ``seed`` is not an integer.
    """
    report = check(robot, samples=samples, seed=seed, limits=limits, only=("inertia",))
    return report.bounds["mu1"], report.bounds["mu2"]


MAX_SAMPLES = 1_000_000
"""The most random configurations ``check`` samples: beyond it a check takes minutes and the
sampled extremes no longer change."""


def check(
    robot: Robot,
    samples: int = 300,
    seed: int = 0,
    limits: Sequence[tuple[float, float]] | None = None,
    only: Sequence[str] | None = None,
) -> Report:
    """Evaluate the properties of Table 3.3.1 on ``robot`` (see the module docstring).

    Every bound is computed on random samples of the joint range, its extremes refined by
    L-BFGS-B; passivity is checked along a simulated trajectory (RK4, 1 ms steps, 1 s).

    Parameters
    ----------
    robot : Robot
        The arm.
    samples : int, optional
        Number of random joint configurations (default 300, from 4 to MAX_SAMPLES = 1,000,000).
    seed : int, optional
        Seed of the random generator (default 0).
    limits : sequence of (float, float), optional
        (lower, upper) per joint to use instead of the arm's own (see ``joint_ranges``).
    only : str or sequence of str, optional
        Restrict to some groups, for speed: one name or several of "inertia", "coriolis",
        "skew", "friction", "gravity", "linearity", "passivity" (GROUPS); default None, all.

    Returns
    -------
    Report
        One Row per property, with the computed bounds and the ranges sampled.

    Raises
    ------
    armdyn.ModelError
        When ``samples`` is below 4 or above MAX_SAMPLES, ``seed`` is negative, ``limits`` is not
        n finite (lower, upper) pairs with lower <= upper, ``only`` is empty or names a group not in
        GROUPS (the message lists them), or when the arm has symbolic parameters.
    TypeError
        When ``robot`` is not a Robot, ``samples`` or ``seed`` is not an integer, or ``only``
        is neither a string nor a sequence of them.
    """
    _check_robot(robot)
    samples = inputs.integer(samples, "samples", 4, MAX_SAMPLES, " (each sample is evaluated and refined)")
    seed = inputs.integer(seed, "seed", 0)
    groups = _groups(only)
    n = robot.n
    ranges = joint_ranges(robot, limits)
    box = [(lo, hi) for lo, hi in ranges]
    rng = np.random.default_rng(seed)
    low, high = np.array(ranges).T
    q = rng.uniform(low, high, (samples, n))
    x = np.array([_unit(v) for v in rng.normal(size=(samples, n))])
    y = np.array([_unit(v) for v in rng.normal(size=(samples, n))])
    rows: list[Row] = []
    bounds: dict[str, float] = {}
    notes = []
    torque = _si(robot, "N m", "N")
    prismatic = [i for i, kind in enumerate(robot.kinds) if kind == "prismatic"]
    if prismatic:
        notes.append(
            "the arm has prismatic joints, so its bounds depend on q; they hold over the range "
            + ", ".join(f"q{i + 1} in [{ranges[i][0]:.3g}, {ranges[i][1]:.3g}]" for i in prismatic)
        )

    if "inertia" in groups:
        _inertia_rows(robot, q, box, rows, bounds)
    if "coriolis" in groups or "skew" in groups:
        _coriolis_rows(robot, q, x, y, box, rows, bounds, groups)
    if "friction" in groups:
        _friction_rows(robot, x, rng, rows, bounds)
    if "gravity" in groups:
        G = robot.gravity_vector(q)
        norms = np.linalg.norm(G, axis=-1)
        gb, how = _extreme(lambda p: float(np.linalg.norm(robot.gravity_vector(p))), q, norms, box, True)
        bounds["gb"] = gb
        rows.append(Row("gravity bound", "||G(q)|| <= gb", bool(np.all(norms <= gb * (1 + 1e-12))), norms.max(), gb,
                        how, torque, "extreme", ("gb",)))  # fmt: skip
    if "linearity" in groups:
        qd, qdd = rng.uniform(-2, 2, (2, samples, n))
        W = robot.regressor(q, qd, qdd)
        tau = robot.inverse_dynamics(q, qd, qdd)
        error = np.abs(W @ robot.parameters() - tau).max() / (np.abs(tau).max() + 1e-300)
        rows.append(Row("linearity", "M qdd + Vm qd + F + G = W(q, qd, qdd) phi", error < 1e-10, error, None,
                        f"{samples} samples, recursive regressor", torque, "residual"))  # fmt: skip
    if "passivity" in groups:
        _passivity_rows(robot, ranges, rows)
    inertia = _si(robot, "kg m^2", "kg")
    units = {"mu1": inertia, "mu2": inertia, "m1": inertia, "m2": inertia,
             "vb": _si(robot, "N m/(rad/s)^2", "N/(m/s)^2"), "v": _si(robot, "N m/(rad/s)", "N/(m/s)"), "k": torque,
             "gb": torque}  # fmt: skip
    return Report(robot.name, rows, bounds, ranges, notes, {key: unit for key, unit in units.items() if key in bounds})


def _inertia_rows(robot: Robot, q: np.ndarray, box: list, rows: list[Row], bounds: dict[str, float]) -> None:
    unit = _si(robot, "kg m^2", "kg")
    M = robot.inertia_matrix(q)
    scale = np.abs(M).max()
    asymmetry = np.abs(M - np.swapaxes(M, -1, -2)).max() / scale
    rows.append(Row("symmetry", "M(q) = M(q)^T", asymmetry < TOLERANCE, asymmetry, None, f"{len(q)} samples", unit,
                    "residual"))  # fmt: skip
    eig = np.linalg.eigvalsh(0.5 * (M + np.swapaxes(M, -1, -2)))

    def smallest(p: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(robot.inertia_matrix(p))[0])

    def largest(p: np.ndarray) -> float:
        return float(np.linalg.eigvalsh(robot.inertia_matrix(p))[-1])

    mu1, how1 = _extreme(smallest, q, eig[:, 0], box, False)
    mu2, how2 = _extreme(largest, q, eig[:, -1], box, True)
    bounds["mu1"], bounds["mu2"] = mu1, mu2
    rows.append(Row("positive definite", "M(q) > 0", mu1 > 0, eig[:, 0].min(), mu1, how1, unit, "extreme", ("mu1",)))
    rows.append(Row("inertia bounds", "mu1 I <= M(q) <= mu2 I, (1/mu2) I <= M^-1 <= (1/mu1) I",
                    mu1 > 0 and mu1 <= eig[:, 0].min() + 1e-12 and eig[:, -1].max() <= mu2 + 1e-12,
                    eig[:, -1].max(), mu2, how2, unit, "extreme", ("mu1", "mu2"), eig[:, 0].min()))  # fmt: skip
    ones = np.abs(M).sum(axis=-2).max(axis=-1)  # induced 1-norm: the largest column sum

    def norm1(p: np.ndarray) -> float:
        return float(np.abs(robot.inertia_matrix(p)).sum(axis=0).max())

    m1, _ = _extreme(norm1, q, ones, box, False)
    m2, how = _extreme(norm1, q, ones, box, True)
    bounds["m1"], bounds["m2"] = m1, m2
    rows.append(Row("norm bounds", "m1 <= ||M(q)||_1 <= m2 (induced 1-norm)", 0 < m1 <= m2, ones.max(), m2, how, unit,
                    "extreme", ("m1", "m2"), ones.min()))  # fmt: skip


def _coriolis_rows(
    robot: Robot, q: np.ndarray, x: np.ndarray, y: np.ndarray, box: list, rows: list[Row], bounds: dict, groups: set
) -> None:
    n = robot.n
    torque = _si(robot, "N m", "N")
    Vm = robot.coriolis_matrix(q, x)
    V = robot.coriolis_vector(q, x)
    scale = np.abs(Vm).max() + 1e-300
    if "coriolis" in groups:
        stretched = robot.coriolis_vector(q, 2.5 * x)
        quadratic = np.abs(stretched - 6.25 * V).max() / (6.25 * np.abs(V).max() + 1e-300)
        rows.append(Row("quadratic", "V(q, s qd) = s^2 V(q, qd)", quadratic < TOLERANCE, quadratic, None,
                        f"{len(q)} samples, s = 2.5", torque, "residual"))  # fmt: skip
        norms = np.linalg.norm(Vm, ord=2, axis=(-2, -1))

        def vm_norm(p: np.ndarray) -> float:
            return float(np.linalg.norm(robot.coriolis_matrix(p[:n], _unit(p[n:])), ord=2))

        starts = np.hstack([q, x])
        vb, how = _extreme(vm_norm, starts, norms, box + [(-1.0, 1.0)] * n, True)
        bounds["vb"] = vb
        v_ratio = np.linalg.norm(V, axis=-1)  # |x| = 1
        holds = bool(np.all(v_ratio <= vb * (1 + 1e-9)) and np.all(norms <= vb * (1 + 1e-9)))
        rows.append(Row("Coriolis bound", "||V|| <= vb ||qd||^2 and ||Vm(q, qd)||_2 <= vb ||qd||", holds,
                        norms.max(), vb, how + ", ||qd|| = 1", _si(robot, "N m/(rad/s)^2", "N/(m/s)^2"), "extreme",
                        ("vb",)))  # fmt: skip
        symmetric = (
            np.abs(
                np.einsum("...ij,...j->...i", robot.coriolis_matrix(q, x), y)
                - np.einsum("...ij,...j->...i", robot.coriolis_matrix(q, y), x)
            ).max()
            / scale
        )
        rows.append(Row("Christoffel symmetry", "Vm(q, x) y = Vm(q, y) x", symmetric < TOLERANCE, symmetric, None,
                        f"{len(q)} samples", torque, "residual"))  # fmt: skip
    if "skew" in groups:
        S = robot.inertia_matrix_dot(q, x) - 2 * Vm
        skew = np.abs(S + np.swapaxes(S, -1, -2)).max() / scale
        rows.append(Row("skew symmetry", "Mdot - 2 Vm is skew: x^T (Mdot - 2 Vm) x = 0", skew < TOLERANCE, skew, None,
                        f"{len(q)} samples", torque, "residual"))  # fmt: skip


def _friction_rows(robot: Robot, x: np.ndarray, rng: np.random.Generator, rows: list[Row], bounds: dict) -> None:
    speeds = x * rng.uniform(0.0, 5.0, (len(x), 1))
    F = robot.friction(speeds)
    v = float(np.max(robot.viscous_friction, initial=0.0))
    k = float(np.linalg.norm(np.abs(robot.coulomb_friction).max(axis=1)))
    bounds["v"], bounds["k"] = v, k
    lhs = np.linalg.norm(F, axis=-1)
    rhs = v * np.linalg.norm(speeds, axis=-1) + k
    rows.append(Row("friction bound", "||Fv qd + Fd|| <= v ||qd|| + k", bool(np.all(lhs <= rhs * (1 + 1e-12) + 1e-15)),
                    float((lhs - rhs).max()), None, "v = max Fv_ii, k = ||max |Fd_i|||, on samples",
                    _si(robot, "N m", "N"), "margin", ("v", "k")))  # fmt: skip
    power = np.einsum("...i,...i->...", speeds, F)
    rows.append(Row("dissipation", "qd^T F(qd) >= 0", bool(np.all(power >= -1e-12)), float(power.min()), 0.0,
                    f"{len(x)} samples", "W"))  # fmt: skip


def _passivity_rows(robot: Robot, ranges: list[tuple[float, float]], rows: list[Row]) -> None:
    """K(t) - K(0) = integral of qd^T (tau - G) dt along a trajectory (fixed-step RK4, 1 ms, 1 s)."""
    n = robot.n
    q0 = np.array([(lo + hi) / 2 for lo, hi in ranges])
    frequencies = 1.0 + np.arange(n) * 0.37
    amplitude = np.maximum(np.abs(robot.gravity_vector(q0)), 1.0)

    def torque(t: float) -> np.ndarray:
        return amplitude * np.sin(2 * np.pi * frequencies * t)

    for arm, label in ((robot.without_friction(), "lossless"), (robot, "with friction")):
        if label == "with friction" and not (np.any(robot.viscous_friction) or np.any(robot.coulomb_friction)):
            continue

        def rate(t: float, state: np.ndarray, arm: Robot = arm) -> np.ndarray:
            q, qd = state[:n], state[n : 2 * n]
            tau = torque(t)
            qdd = arm.forward_dynamics(q, qd, tau)
            return np.concatenate([qd, qdd, [qd @ (tau - arm.gravity_vector(q))]])

        state, dt = np.concatenate([q0, np.zeros(n), [0.0]]), 1e-3
        for step in range(1000):
            t = step * dt
            k1 = rate(t, state)
            k2 = rate(t + dt / 2, state + dt / 2 * k1)
            k3 = rate(t + dt / 2, state + dt / 2 * k2)
            k4 = rate(t + dt, state + dt * k3)
            state = state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        gained = arm.kinetic_energy(state[:n], state[n : 2 * n])
        supplied = state[-1]
        scale = abs(supplied) + abs(gained) + 1e-300
        if label == "lossless":
            error = abs(gained - supplied) / scale
            rows.append(Row("passivity", "K(t) - K(0) = integral qd^T (tau - G) dt", error < 1e-6, error, None,
                            "RK4, 1 ms steps over 1 s, sinusoidal torques, no friction", "J", "residual"))  # fmt: skip
        else:
            rows.append(Row("passivity with friction", "K(t) - K(0) <= integral qd^T (tau - G) dt",
                            gained <= supplied + 1e-9 * scale, (gained - supplied) / scale, None,
                            "the same run with the arm's friction", "", "margin"))  # fmt: skip
