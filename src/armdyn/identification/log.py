"""A robot's log: sample times, joint positions, and the measured joint torques or motor currents.

A ``Log`` holds what a robot recorded while it moved, one row a sample: the times t (N,), the joint
positions q (N, n) and, optionally, the velocities the robot reported, the desired positions and
velocities, and exactly one of the measured joint torques tau or the motor currents (N, n). It is
checked when made, and every error names the file, the column and the sample (counted from 0):
values that are NaN or infinite, a time that does not increase, columns of unequal lengths or
missing, the wrong number of joints, too few samples. ``Log.check_arm`` checks it against an arm
(its number of joints, and angles that look like degrees). Nothing is corrected silently.

The readers make a Log from a file:

- ``read_csv``, ``read_npz`` and ``read_parquet`` read a table whose columns a map names (see
  ``read_csv``: ``{"t": "time", "q": "q{j}", "tau": ["tau_a", "tau_b"]}``, ``{j}`` standing for
  1..n), or the default names (``t`` or ``time``; ``q1``.. or ``q_1``..; ``qd``; ``tau``; ``i`` or
  ``current``; ``q_des``; ``qd_des``);
- ``read_gaz_panda`` reads the text files of the Franka Emika Panda log of Gaz, Cognetti, Oliva,
  Robuffo Giordano and De Luca, "Dynamic identification of the Franka Emika Panda robot with
  retrieval of feasible parameters using penalty-based optimization", IEEE Robotics and Automation
  Letters 4(4), 2019 (one number a line, 7 consecutive lines a sample);
- ``read_log`` picks one of them by the file's suffix (or a folder).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from armdyn.errors import MissingDependencyError, ModelError
from armdyn.model import ArmModel

__all__ = [
    "DEGREE_MARGIN",
    "FIELDS",
    "MIN_LOG_SAMPLES",
    "Log",
    "read_csv",
    "read_gaz_panda",
    "read_log",
    "read_npz",
    "read_parquet",
]

FIELDS = ("t", "q", "qd", "tau", "current", "q_desired", "qd_desired")
"""The fields of a Log a column map may name: t is one column, every other field one column per joint."""
MIN_LOG_SAMPLES = 20
"""The fewest samples a Log holds (a zero-phase filter of order 4 pads each end with 15)."""
DEGREE_MARGIN = 0.2
"""How far (rad) a revolute joint may go beyond a full turn before its angles are taken for degrees."""
DEGREE_EXCESS = 0.5
"""How far (rad, about 30 degrees) a revolute joint's angles must go beyond its limits, all of them fitting the
limits when read as degrees, before they are taken for degrees (a log may pass a limit by a little)."""
_DEFAULT_NAMES = {
    "t": ("t", "time"),
    "q": ("q",),
    "qd": ("qd", "dq"),
    "tau": ("tau",),
    "current": ("i", "current"),
    "q_desired": ("q_desired", "q_des"),
    "qd_desired": ("qd_desired", "qd_des"),
}
_JOINT_FIELDS = FIELDS[1:]
_GAZ_FILES = {
    "t": "exciting_traj_time.txt",
    "q": "exciting_traj_positions.txt",
    "qd": "exciting_traj_velocity.txt",
    "tau": "exciting_traj_torques.txt",
}
_GAZ_JOINTS = 7


@dataclass(frozen=True, eq=False)
class Log:
    """A robot's log: times, joint positions, and measured joint torques or motor currents, checked.

    Parameters
    ----------
    t : array_like
        Sample times (N,), s, strictly increasing (not necessarily uniform).
    q : array_like
        Joint positions (N, n), rad or m ((N,) for one joint).
    qd : array_like, optional
        Joint velocities (N, n) as the robot reported them, rad/s or m/s.
    tau : array_like, optional
        Measured joint torques (N, n), N m or N.
    current : array_like, optional
        Measured motor currents (N, n), A. Exactly one of ``tau`` and ``current`` is given.
    q_desired, qd_desired : array_like, optional
        Desired joint positions and velocities (N, n).
    joint_names : sequence of str, optional
        The joints' names, n of them.
    source : str, optional
        The file (or what else) the log came from, named in every message (default "log").
    columns : mapping of str to sequence of str, optional
        The file's column for each field, one name for t and one per joint for the others, named in
        messages (default ``tau[3]`` and so on).
    first_sample : int, optional
        The index in the source of the first sample (for a part of a log), added to every sample index in
        messages (default 0).

    Raises
    ------
    armdyn.ModelError
        When a field is not an array of numbers, is missing (t, q, or both or neither of tau and current),
        has another number of samples than t or another number of joints than q, when fewer than
        MIN_LOG_SAMPLES samples are given, when a value is NaN or infinite, or when the time does not
        strictly increase; the message names the source, the column and the sample.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray | None = None
    tau: np.ndarray | None = None
    current: np.ndarray | None = None
    q_desired: np.ndarray | None = None
    qd_desired: np.ndarray | None = None
    joint_names: tuple[str, ...] | None = None
    source: str = "log"
    columns: Mapping[str, tuple[str, ...]] | None = None
    first_sample: int = 0

    def __post_init__(self) -> None:
        source = str(self.source)
        object.__setattr__(self, "source", source)
        if self.t is None or self.q is None:
            raise ModelError(f"{source}: a log needs the times t and the joint positions q ({_missing(self)} missing)")
        if (self.tau is None) == (self.current is None):
            which = "both" if self.tau is not None else "neither"
            raise ModelError(
                f"{source}: a log holds exactly one of the measured torques tau and the motor currents; it has {which}"
            )
        t = _array(self.t, "t", source)
        if t.ndim != 1:
            raise ModelError(f"{source}: the time column {self._label('t')} must be one column, got shape {t.shape}")
        object.__setattr__(self, "t", t)
        q = _array(self.q, "q", source)
        q = q[:, None] if q.ndim == 1 else q
        if q.ndim != 2 or q.shape[1] == 0:
            raise ModelError(f"{source}: q must have shape (N, n) with n >= 1 joints, got {q.shape}")
        n = q.shape[1]
        for name in _JOINT_FIELDS:
            value = q if name == "q" else getattr(self, name)
            if value is None:
                continue
            array = _array(value, name, source) if name != "q" else value
            array = array[:, None] if array.ndim == 1 and n == 1 else array
            if array.ndim != 2 or array.shape[1] != n:
                raise ModelError(
                    f"{source}: {name} must have one column per joint, shape (N, {n}) as q has {n} joints, "
                    f"got {array.shape}"
                )
            if array.shape[0] != t.shape[0]:
                raise ModelError(
                    f"{source}: the columns have unequal lengths: {name} has {array.shape[0]} samples, "
                    f"the time {self._label('t')} has {t.shape[0]}"
                )
            array.flags.writeable = False
            object.__setattr__(self, name, array)
        t.flags.writeable = False
        if self.joint_names is not None:
            names = tuple(str(name) for name in self.joint_names)
            if len(names) != n:
                raise ModelError(f"{source}: {len(names)} joint names given for {n} joints (q has {n} columns)")
            object.__setattr__(self, "joint_names", names)
        if self.columns is not None:
            object.__setattr__(self, "columns", {key: tuple(value) for key, value in self.columns.items()})
        if t.shape[0] < MIN_LOG_SAMPLES:
            raise ModelError(f"{source}: {t.shape[0]} samples; a log needs at least {MIN_LOG_SAMPLES}")
        self._check_finite()
        steps = np.diff(t)
        if not np.all(steps > 0):
            k = int(np.argmax(~(steps > 0))) + 1
            raise ModelError(
                f"{source}: the time {self._label('t')} does not strictly increase at sample "
                f"{self.first_sample + k}: t = {t[k]:.9g} s after t = {t[k - 1]:.9g} s at sample "
                f"{self.first_sample + k - 1}"
            )

    # ----- checks and names -------------------------------------------------------------------------------------
    def _label(self, name: str, joint: int | None = None) -> str:
        """The file's name of a field's column (one joint's, from 0), quoted, with the field it holds."""
        columns = (self.columns or {}).get(name)
        if joint is None:
            return f"'{columns[0]}'" if columns else f"'{name}'"
        label = self.joint_names[joint] if self.joint_names else str(joint + 1)
        if columns and joint < len(columns):
            return f"'{columns[joint]}' ({name} of joint {label})"
        return f"'{name}[{joint}]' ({name} of joint {label})"

    def _check_finite(self) -> None:
        """A ModelError naming the earliest sample, and its column, holding NaN or infinity."""
        first: tuple[int, str, int | None, float] | None = None
        count = 0
        for name in FIELDS:
            value = getattr(self, name)
            if value is None:
                continue
            bad = ~np.isfinite(value)
            if not bad.any():
                continue
            count += int(bad.sum())
            rows = bad if bad.ndim == 1 else bad.any(axis=1)
            k = int(np.argmax(rows))
            joint = None if bad.ndim == 1 else int(np.argmax(bad[k]))
            if first is None or k < first[0]:
                first = (k, name, joint, float(value[k] if joint is None else value[k, joint]))
        if first is None:
            return
        k, name, joint, value = first
        when = f" (t = {self.t[k]:.9g} s)" if name != "t" and math.isfinite(self.t[k]) else ""
        more = f"; {count - 1} more NaN or infinite values in the log" if count > 1 else ""
        raise ModelError(
            f"{self.source}: column {self._label(name, joint)} is {value} at sample {self.first_sample + k}"
            f"{when}: every value must be finite{more}"
        )

    def check_arm(self, arm: ArmModel) -> None:
        """Check that the log fits ``arm``: one column per joint, and revolute joint angles in radians.

        A revolute joint's angles are taken for degrees (and refused) when they go beyond a full turn (or
        beyond its limits, when these are wider) by more than DEGREE_MARGIN rad, or when they go beyond
        its limits by more than DEGREE_MARGIN while the same numbers read as degrees fit within them.

        Parameters
        ----------
        arm : armdyn.model.ArmModel
            The arm the log was recorded on.

        Raises
        ------
        armdyn.ModelError
            When the log has another number of joints than the arm, or a revolute joint's angles look like
            degrees; the message names the joint, the column and the sample.
        """
        if not isinstance(arm, ArmModel):
            raise ModelError(f"{self.source}: check_arm needs an armdyn arm, got {type(arm).__name__}")
        if arm.n != self.n:
            raise ModelError(
                f"{self.source}: the log has {self.n} joints (q has {self.n} columns), the arm '{arm.name}' has "
                f"{arm.n} ({', '.join(arm.joint_names)})"
            )
        lower, upper = arm.qlim
        for j, kind in enumerate(arm.kinds):
            if kind != "revolute":
                continue
            angles = self.q[:, j]
            k = int(np.argmax(np.abs(angles)))
            name = arm.joint_names[j]
            where = f"{self.source}: joint '{name}', column {self._label('q', j)}"
            turn = max([2 * math.pi, *(abs(v) for v in (lower[j], upper[j]) if math.isfinite(v))])
            if abs(angles[k]) > turn + DEGREE_MARGIN:
                raise ModelError(
                    f"{where}, reaches {angles[k]:.6g} at sample {self.first_sample + k}, beyond a full turn "
                    f"({turn:.4g} rad): the angles look like degrees; give radians (numpy.radians)"
                )
            below, above = angles < lower[j] - DEGREE_EXCESS, angles > upper[j] + DEGREE_EXCESS
            if below.any() or above.any():
                radians = np.radians(angles)
                fits = np.all((radians >= lower[j] - DEGREE_MARGIN) & (radians <= upper[j] + DEGREE_MARGIN))
                if fits:
                    k = int(np.argmax(below | above))
                    raise ModelError(
                        f"{where}, is {angles[k]:.6g} at sample {self.first_sample + k}, beyond the joint's limits "
                        f"[{lower[j]:.4g}, {upper[j]:.4g}] rad, while all its values read as degrees fit them: "
                        "the angles look like degrees; give radians (numpy.radians)"
                    )

    # ----- sizes ------------------------------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """The number of joints."""
        return int(self.q.shape[1])

    @property
    def samples(self) -> int:
        """The number of samples N."""
        return int(self.t.shape[0])

    @property
    def duration(self) -> float:
        """The time from the first sample to the last, s."""
        return float(self.t[-1] - self.t[0])

    @property
    def sample_rate(self) -> float:
        """The median sample rate, Hz (one over the median time step)."""
        return float(1.0 / np.median(np.diff(self.t)))

    @property
    def effort(self) -> np.ndarray:
        """The measured joint torques, or else the motor currents (N, n)."""
        return self.tau if self.tau is not None else self.current  # type: ignore[return-value]

    @property
    def effort_name(self) -> str:
        """``"tau"`` or ``"current"``: the field the log measures."""
        return "tau" if self.tau is not None else "current"

    # ----- parts ------------------------------------------------------------------------------------------------
    def _part(self, rows: slice) -> Log:
        """The samples ``rows`` (a slice with a step of 1) as a Log, their indices kept for messages."""
        start = rows.indices(self.samples)[0]
        arrays = {name: getattr(self, name) for name in FIELDS}
        parts: dict[str, Any] = {name: (None if value is None else value[rows]) for name, value in arrays.items()}
        return dataclasses.replace(self, **parts, first_sample=self.first_sample + start)

    def split(self, fraction: float) -> tuple[Log, Log]:
        """The log cut in two in time order: the first ``fraction`` of the samples, and the rest.

        Parameters
        ----------
        fraction : float
            The share of the samples in the first part, strictly between 0 and 1 (e.g. 0.7 to identify
            from the first 70% and validate on the last 30%).

        Returns
        -------
        tuple of Log
            (first part, last part); together they hold every sample once.

        Raises
        ------
        armdyn.ModelError
            When ``fraction`` is not strictly between 0 and 1, or a part would have fewer than
            MIN_LOG_SAMPLES samples.
        """
        if not isinstance(fraction, (int, float, np.floating)) or not 0 < fraction < 1:
            raise ModelError(f"{self.source}: split takes a fraction strictly between 0 and 1, got {fraction!r}")
        cut = round(float(fraction) * self.samples)
        if min(cut, self.samples - cut) < MIN_LOG_SAMPLES:
            raise ModelError(
                f"{self.source}: splitting {self.samples} samples at {fraction:g} leaves a part of "
                f"{min(cut, self.samples - cut)} samples; each needs at least {MIN_LOG_SAMPLES}"
            )
        return self._part(slice(0, cut)), self._part(slice(cut, self.samples))

    def window(self, t0: float, t1: float) -> Log:
        """The samples with t0 <= t <= t1.

        Parameters
        ----------
        t0, t1 : float
            The window's first and last time, s, with t0 < t1.

        Returns
        -------
        Log
            The samples in the window (their indices in messages are those of the whole log).

        Raises
        ------
        armdyn.ModelError
            When t0 >= t1 or either is not finite, or the window holds fewer than MIN_LOG_SAMPLES samples.
        """
        start, stop = float(t0), float(t1)
        if not (math.isfinite(start) and math.isfinite(stop) and start < stop):
            raise ModelError(f"{self.source}: a window needs finite times t0 < t1, got [{t0}, {t1}]")
        begin, last = int(np.searchsorted(self.t, start, "left")), int(np.searchsorted(self.t, stop, "right"))
        if last - begin < MIN_LOG_SAMPLES:
            raise ModelError(
                f"{self.source}: the window [{start:g}, {stop:g}] s holds {last - begin} samples (the log spans "
                f"[{self.t[0]:g}, {self.t[-1]:g}] s); a log needs at least {MIN_LOG_SAMPLES}"
            )
        return self._part(slice(begin, last))


def _array(value: object, name: str, source: str) -> np.ndarray:
    """``value`` as a new float array, or a ModelError naming the field."""
    dtype = getattr(value, "dtype", None)
    if dtype is not None and dtype.kind not in "biuf":
        raise ModelError(f"{source}: {name} must hold real numbers, it holds {dtype} values")
    try:
        return np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{source}: {name} must be an array of real numbers") from None


def _missing(log: Log) -> str:
    return " and ".join(name for name in ("t", "q") if getattr(log, name) is None)


# ----- tables: CSV, NPZ, Parquet ---------------------------------------------------------------------------------
ColumnMap = Mapping[str, "str | Sequence[str] | None"]


def _checked_map(columns: ColumnMap | None, source: str) -> dict[str, Any]:
    """The column map as a dict, each value None, one name or a tuple of names, or a ModelError."""
    if columns is None:
        return {}
    if not isinstance(columns, Mapping):
        raise ModelError(f"{source}: the column map must be a mapping of field to column name(s), got {columns!r}")
    checked: dict[str, Any] = {}
    for field, value in columns.items():
        if field not in FIELDS:
            raise ModelError(f"{source}: the column map names '{field}', not a field of a log ({', '.join(FIELDS)})")
        if value is None or isinstance(value, str):
            try:
                _ = value if value is None else value.format(j=1)
            except (KeyError, IndexError, ValueError):
                raise ModelError(
                    f"{source}: the column map's '{field}' is {value!r}; in a pattern {{j}} is the only field"
                ) from None
            checked[field] = value
        elif isinstance(value, Sequence) and value and all(isinstance(v, str) for v in value):
            checked[field] = tuple(value)
        else:
            raise ModelError(
                f"{source}: the column map's '{field}' must be a column name, a pattern with {{j}}, a list of "
                f"names or None, got {value!r}"
            )
    if checked.get("t", "") is None or checked.get("q", "") is None:
        raise ModelError(f"{source}: the column map cannot leave out t or q")
    return checked


def _consecutive(table: Mapping[str, np.ndarray], pattern: str) -> tuple[str, ...]:
    """The names ``pattern`` gives for j = 1, 2, ... as long as the table has them."""
    names: list[str] = []
    while (name := pattern.format(j=len(names) + 1)) in table:
        names.append(name)
    return tuple(names)


def _absent(table: Mapping[str, np.ndarray], source: str, wanted: str) -> ModelError:
    present = ", ".join(f"'{name}'" for name in table) or "none"
    return ModelError(f"{source}: no column {wanted}; the columns present are {present}")


def _field(
    table: Mapping[str, np.ndarray], field: str, spec: Any, n: int | None, source: str
) -> tuple[np.ndarray | None, tuple[str, ...]]:
    """One field's array and its columns' names: from the map's ``spec`` (a name, a pattern or a tuple of names;
    None: left out), or by the default names when ``spec`` is ``...`` (the map does not name the field)."""
    if spec is None:
        return None, ()
    if isinstance(spec, tuple):
        for name in spec:
            if name not in table:
                raise _absent(table, source, f"'{name}' (the map's {field})")
        return np.stack([_column(table, name, source) for name in spec], axis=1), spec
    if isinstance(spec, str):
        if "{j}" not in spec:
            if spec not in table:
                raise _absent(table, source, f"'{spec}' (the map's {field})")
            return _column(table, spec, source, whole=True), (spec,)
        names = _consecutive(table, spec) if n is None else tuple(spec.format(j=j) for j in range(1, n + 1))
        if not names:
            raise _absent(table, source, f"'{spec.format(j=1)}' (the map's {field}, pattern '{spec}')")
        for name in names:
            if name not in table:
                raise _absent(table, source, f"'{name}' (the map's {field}, pattern '{spec}')")
        return np.stack([_column(table, name, source) for name in names], axis=1), names
    # no map entry: the default names
    for base in _DEFAULT_NAMES[field]:
        if base in table:
            return _column(table, base, source, whole=True), (base,)
    if field == "t":
        raise _absent(table, source, "for the time ('t' or 'time'; or name it in the column map)")
    for base in _DEFAULT_NAMES[field]:
        for pattern in (base + "{j}", base + "_{j}"):
            names = _consecutive(table, pattern)
            if not names:
                continue
            if n is not None and len(names) != n:
                raise ModelError(
                    f"{source}: {len(names)} columns {names[0]}..{names[-1]} for {field}, but q has {n} joints; "
                    "name the columns in the column map"
                )
            return np.stack([_column(table, name, source) for name in names], axis=1), names
    if field == "q":
        raise _absent(table, source, "for q ('q1', 'q2', ... or 'q_1', ...; or name them in the column map)")
    return None, ()


def _column(table: Mapping[str, np.ndarray], name: str, source: str, whole: bool = False) -> np.ndarray:
    """The table's column ``name`` as floats (a 2-D array only when ``whole``), or a ModelError naming it."""
    value = np.asarray(table[name])
    if value.dtype.kind not in "biuf":
        if value.dtype.kind == "O":
            numbers = np.array([_number(v) for v in value.ravel()], dtype=float)
            bad = np.flatnonzero(np.isnan(numbers) & np.array([not _blank(v) for v in value.ravel()]))
            if bad.size:
                k = int(bad[0])
                raise ModelError(f"{source}: column '{name}' holds {value.ravel()[k]!r} at sample {k}, not a number")
            value = numbers.reshape(value.shape)
        else:
            raise ModelError(f"{source}: column '{name}' holds {value.dtype} values, not numbers")
    if value.ndim != 1 and not (whole and value.ndim == 2):
        raise ModelError(f"{source}: column '{name}' has shape {value.shape}; one value a sample is needed")
    return value.astype(float)


def _number(value: object) -> float:
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return math.nan


def _blank(value: object) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value)) or str(value).strip() == ""


def _from_table(table: Mapping[str, np.ndarray], columns: ColumnMap | None, source: str) -> Log:
    """A Log from a table of named columns (1-D, or 2-D (N, n) for a whole field) and a column map."""
    spec = _checked_map(columns, source)
    t, t_names = _field(table, "t", spec.get("t", ...), None, source)
    q, q_names = _field(table, "q", spec.get("q", ...), None, source)
    assert t is not None and q is not None
    n = 1 if q.ndim == 1 else q.shape[1]
    fields: dict[str, Any] = {"t": t, "q": q}
    names: dict[str, tuple[str, ...]] = {"t": t_names, "q": _per_joint(q_names, n)}
    for field in FIELDS[2:]:
        value, found = _field(table, field, spec.get(field, ...), n, source)
        if value is not None:
            fields[field], names[field] = value, _per_joint(found, n)
    return Log(**fields, source=source, columns=names)


def _per_joint(names: tuple[str, ...], n: int) -> tuple[str, ...]:
    """One name per joint: a whole (N, n) column's name becomes 'name[j]' (j from 0)."""
    return names if len(names) == n else tuple(f"{names[0]}[{j}]" for j in range(n))


def _path(path: str | Path) -> Path:
    file = Path(path)
    if not file.exists():
        raise ModelError(f"{path}: no such file")
    if file.is_dir():
        raise ModelError(f"{path} is a folder, not a file")
    return file


def read_csv(path: str | Path, columns: ColumnMap | None = None) -> Log:
    """A Log from a CSV file with a header line: one column for the time, one per joint for each field.

    Parameters
    ----------
    path : str or Path
        The file (comma-separated, a header line of column names, one line a sample).
    columns : mapping, optional
        The column of each field of the log (``t``, ``q``, ``qd``, ``tau``, ``current``, ``q_desired``,
        ``qd_desired``): one column name; a pattern in which ``{j}`` stands for the joint number 1..n
        (``"tau{j}"``); a list of names, one per joint; or None to leave a field out. Fields the map does
        not name are found by the default names when present: ``t`` or ``time``; for a joint field with
        the default name ``f`` (``q``, ``qd`` or ``dq``, ``tau``, ``i`` or ``current``, ``q_desired`` or
        ``q_des``, ``qd_desired`` or ``qd_des``), the columns ``f1, f2, ...`` or ``f_1, f_2, ...``. The
        number of joints n is that of q's columns.

    Returns
    -------
    Log
        The log, its source the file.

    Raises
    ------
    armdyn.ModelError
        When the file does not exist or cannot be read, the map names an unknown field, a column is
        missing (the message lists the columns present), a value is not a number, or the Log's checks
        fail (NaN, time not increasing, both or neither of tau and current, too few samples).
    """
    import pandas

    file = _path(path)
    try:
        frame = pandas.read_csv(file)
    except (ValueError, OSError, pandas.errors.ParserError) as error:
        raise ModelError(f"{path}: cannot be read as CSV: {error}") from None
    table = {str(name).strip(): frame[name].to_numpy() for name in frame.columns}
    return _from_table(table, columns, str(path))


def read_npz(path: str | Path, columns: ColumnMap | None = None) -> Log:
    """A Log from a NumPy ``.npz`` archive: one array a column, or a whole field as one (N, n) array.

    Parameters
    ----------
    path : str or Path
        The archive (``numpy.savez``); its arrays are the columns, by their names.
    columns : mapping, optional
        The column map of ``read_csv``; a name without ``{j}`` may name a 2-D array (N, n) holding a whole
        field. By default a field is also found as one array of its own name (``q``, ``tau``, ...).

    Returns
    -------
    Log
        The log, its source the file.

    Raises
    ------
    armdyn.ModelError
        When the file does not exist or is not an archive of numeric arrays, a column is missing (the message
        lists those present), or the Log's checks fail.
    """
    file = _path(path)
    try:
        with np.load(file, allow_pickle=False) as archive:
            table = {name: archive[name] for name in archive.files}
    except (ValueError, OSError, EOFError) as error:
        raise ModelError(f"{path}: cannot be read as a NumPy archive (.npz): {error}") from None
    return _from_table(table, columns, str(path))


def read_parquet(path: str | Path, columns: ColumnMap | None = None) -> Log:
    """A Log from a Parquet file (through pandas and pyarrow): one column for the time, one per joint.

    Parameters
    ----------
    path : str or Path
        The file.
    columns : mapping, optional
        The column map of ``read_csv``.

    Returns
    -------
    Log
        The log, its source the file.

    Raises
    ------
    armdyn.ModelError
        When the file does not exist or cannot be read as Parquet, a column is missing (the message lists
        those present), a value is not a number, or the Log's checks fail.
    armdyn.MissingDependencyError
        When pyarrow is not installed.
    """
    import pandas

    file = _path(path)
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MissingDependencyError("pyarrow", "cluster", needed_by="armdyn.identification.log.read_parquet") from None
    try:
        frame = pandas.read_parquet(file)
    except (ValueError, OSError) as error:
        raise ModelError(f"{path}: cannot be read as Parquet: {error}") from None
    table = {str(name): frame[name].to_numpy() for name in frame.columns}
    return _from_table(table, columns, str(path))


def read_gaz_panda(folder: str | Path) -> Log:
    """The log of a Franka Emika Panda in the format of Gaz et al. (2019): four text files in a folder.

    The files (one number a line; a sample is 7 consecutive lines, joints 1..7, except the time):
    ``exciting_traj_time.txt`` (s), ``exciting_traj_positions.txt`` (rad), ``exciting_traj_velocity.txt``
    (rad/s, as the robot reports them) and ``exciting_traj_torques.txt`` (N m, measured, gravity
    included). The joints are named ``panda_joint1`` .. ``panda_joint7``, as in the Panda's URDF.

    Parameters
    ----------
    folder : str or Path
        The folder holding the four files.

    Returns
    -------
    Log
        The log, with t, q, qd and tau; its source the folder.

    Raises
    ------
    armdyn.ModelError
        When the folder or a file is missing, a line is not a number, a file does not hold 7 numbers per
        sample time, or the Log's checks fail (the message names the file and the sample).
    """
    import pandas

    where = Path(folder)
    if not where.is_dir():
        raise ModelError(f"{folder}: no such folder (the Panda log of Gaz et al. is a folder of four files)")
    data: dict[str, Any] = {}
    for field, name in _GAZ_FILES.items():
        file = where / name
        if not file.is_file():
            present = ", ".join(sorted(p.name for p in where.iterdir())) or "nothing"
            raise ModelError(f"{folder}: no file {name}; the folder holds {present}")
        try:
            frame = pandas.read_csv(file, header=None, dtype=str, skip_blank_lines=False, keep_default_na=False)
        except (ValueError, OSError, pandas.errors.ParserError) as error:
            raise ModelError(f"{file}: cannot be read as one number a line: {error}") from None
        if frame.shape[1] != 1:
            raise ModelError(f"{file}: one number a line is expected, a line holds {frame.shape[1]} fields")
        data[field] = _numbers_by_line(frame[0].to_numpy(), file)
    samples = data["t"].shape[0]
    for field in ("q", "qd", "tau"):
        if data[field].shape[0] != _GAZ_JOINTS * samples:
            raise ModelError(
                f"{folder}: the columns have unequal lengths: {_GAZ_FILES[field]} holds {data[field].shape[0]} "
                f"numbers, not {_GAZ_JOINTS} per each of the {samples} times of {_GAZ_FILES['t']}"
            )
        data[field] = data[field].reshape(samples, _GAZ_JOINTS)
    names = {field: tuple(f"{_GAZ_FILES[field]}, joint {j}" for j in range(1, _GAZ_JOINTS + 1)) for field in data}
    names["t"] = (_GAZ_FILES["t"],)
    joints = tuple(f"panda_joint{j}" for j in range(1, _GAZ_JOINTS + 1))
    return Log(**data, joint_names=joints, source=str(folder), columns=names)


def _numbers_by_line(lines: np.ndarray, file: Path) -> np.ndarray:
    """The lines of a text file as numbers ('nan' and 'inf' kept, for the Log to name), or a ModelError naming
    the first line that is not a number."""
    try:
        return lines.astype(float)
    except ValueError:
        k = next(k for k, line in enumerate(lines) if math.isnan(_number(line)) and line.strip().lower() != "nan")
        raise ModelError(f"{file}: line {k + 1} is {lines[k]!r}, not a number") from None


_READERS = {".csv": read_csv, ".npz": read_npz, ".parquet": read_parquet, ".pq": read_parquet}


def read_log(path: str | Path, columns: ColumnMap | None = None) -> Log:
    """A Log from a file, read by its suffix (``.csv``, ``.npz``, ``.parquet`` or ``.pq``), or from a folder
    in the format of Gaz et al. (``read_gaz_panda``).

    Parameters
    ----------
    path : str or Path
        The file or folder.
    columns : mapping, optional
        The column map (see ``read_csv``); not for a folder.

    Returns
    -------
    Log
        The log.

    Raises
    ------
    armdyn.ModelError
        When the path does not exist, its suffix is none of those read, a column map is given for a folder,
        or the reader refuses the file.
    """
    where = Path(path)
    if where.is_dir():
        if not (where / _GAZ_FILES["t"]).is_file():
            raise ModelError(
                f"{path} is a folder without {_GAZ_FILES['t']}; a folder is read as a Panda log of Gaz et al. "
                f"(files {', '.join(_GAZ_FILES.values())}), any other log is one file"
            )
        if columns is not None:
            raise ModelError(f"{path}: a Panda log folder of Gaz et al. has fixed files; it takes no column map")
        return read_gaz_panda(where)
    if not where.exists():
        raise ModelError(f"{path}: no such file or folder")
    reader = _READERS.get(where.suffix.lower())
    if reader is None:
        raise ModelError(
            f"{path}: unknown log format '{where.suffix}'; the formats read are {', '.join(_READERS)}, and a folder "
            "in the format of Gaz et al."
        )
    return reader(where, columns)
