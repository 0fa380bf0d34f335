"""Collision detection on an observer's residual: a threshold band per joint, detection with hysteresis, and
the figure of the residual against its band.

A residual r (N, n) estimates the external joint torque (De Luca and Mattone 2003); without contact it is
model error and noise. A joint is in collision while its residual is outside its band, fixed or set from a
collision-free run by a quantile per joint (Haddadin, De Luca and Albu-Schaeffer, "Robot Collisions: A
Survey on Detection, Isolation, and Identification", IEEE T-RO 2017, the thresholds of collision detection).
Hysteresis keeps the state from chattering at the band's edge: a joint is released only once its residual
has stayed within a narrower band for a hold time.

Joints are counted from 0 in arrays and in ``Detection.joint``; messages name them from 1 ("joint 4" is
column 3), as the arm's own messages do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from armdyn.errors import ModelError

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure

__all__ = ["Band", "Detection", "detect", "plot_residuals"]


# ----- checked arrays ------------------------------------------------------------------------------------------
def _floats(value: object, name: str) -> np.ndarray:
    """``value`` as a float array, or a ModelError naming ``name``."""
    if value is None or isinstance(value, (str, bytes, dict, set)):
        raise ModelError(f"{name} must be an array of numbers, got {value!r}")
    try:
        dtype = getattr(value, "dtype", None)
        if np.iscomplexobj(value) or (dtype is not None and dtype.kind not in "biuf"):  # type: ignore[arg-type]
            raise TypeError
        return np.array(value, dtype=float)
    except (TypeError, ValueError, ArithmeticError):
        raise ModelError(f"{name} must be an array of real numbers, got {type(value).__name__}") from None


def _joint_vector(value: object, name: str) -> np.ndarray:
    """A 1-D array of finite numbers, one per joint, or a ModelError naming the argument and the joint."""
    array = _floats(value, name)
    if array.ndim != 1 or array.shape[0] == 0:
        raise ModelError(f"{name} must hold one number per joint, shape (n,) with n >= 1, got shape {array.shape}")
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        j = int(bad[0])
        raise ModelError(f"{name} must be finite: joint {j + 1} (index {j}) is {array[j]}")
    return array


def _samples(
    value: object, name: str, n: int | None = None, t: np.ndarray | None = None, owner: str = "the band"
) -> np.ndarray:
    """An (N, n) array of finite numbers, or a ModelError naming the first sample and joint holding NaN or
    infinity (with its time when ``t`` is given)."""
    array = _floats(value, name)
    if array.ndim != 2 or array.shape[0] == 0 or array.shape[1] == 0:
        raise ModelError(
            f"{name} must have shape (N, n), one row per sample and one column per joint, got {array.shape}"
        )
    if n is not None and array.shape[1] != n:
        raise ModelError(f"{name} has {array.shape[1]} columns (joints); {owner} has {n} joints")
    if t is not None and array.shape[0] != t.shape[0]:
        raise ModelError(f"{name} has {array.shape[0]} samples, the time t has {t.shape[0]}")
    bad = np.argwhere(~np.isfinite(array))
    if bad.size:
        k, j = (int(x) for x in bad[0])
        when = f" (t = {t[k]:.9g} s)" if t is not None else ""
        raise ModelError(
            f"{name} must be finite: sample {k}{when}, joint {j + 1} (column {j}) is {array[k, j]}"
            f"{f' ({len(bad)} such values)' if len(bad) > 1 else ''}"
        )
    return array


def _times(value: object) -> np.ndarray:
    """Sample times (N,), finite and strictly increasing, or a ModelError naming the first sample at fault."""
    t = _floats(value, "t")
    if t.ndim != 1 or t.shape[0] == 0:
        raise ModelError(f"t must be the sample times, shape (N,) with N >= 1, got shape {t.shape}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ModelError(f"t must be finite: sample {int(bad[0])} is {t[bad[0]]}")
    steps = np.diff(t)
    if not np.all(steps > 0):
        k = int(np.argmax(~(steps > 0))) + 1
        raise ModelError(
            f"t must strictly increase: sample {k} is t = {t[k]:.9g} s after t = {t[k - 1]:.9g} s at sample {k - 1}"
        )
    return t


def _number(value: object, name: str) -> float:
    """A finite real number (not a bool), or a ModelError naming it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ModelError(f"{name} must be finite, got {number}")
    return number


# ----- the band ------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Band:
    """The band [lower, upper] per joint in which a collision-free residual stays.

    Made directly, by ``Band.fixed`` (a symmetric threshold) or by ``Band.from_residuals`` (quantiles of a
    collision-free run, Haddadin, De Luca and Albu-Schaeffer 2017). The arrays are read-only.

    Parameters
    ----------
    lower, upper : array_like
        The band's edges per joint, (n,), N m (N for a prismatic joint), finite, lower <= upper.

    Raises
    ------
    armdyn.ModelError
        When lower or upper is not a finite 1-D array, their sizes differ, or lower > upper at a joint
        (the message names the argument and the joint).
    """

    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        lower, upper = _joint_vector(self.lower, "lower"), _joint_vector(self.upper, "upper")
        if lower.shape != upper.shape:
            raise ModelError(f"lower has {lower.shape[0]} joints, upper has {upper.shape[0]}; a band has one of each")
        above = np.flatnonzero(lower > upper)
        if above.size:
            j = int(above[0])
            raise ModelError(f"lower must not exceed upper: joint {j + 1} has lower {lower[j]:g} > upper {upper[j]:g}")
        for name, array in (("lower", lower), ("upper", upper)):
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    @property
    def n(self) -> int:
        """The number of joints."""
        return int(self.lower.shape[0])

    @property
    def centre(self) -> np.ndarray:
        """The band's centre per joint, (lower + upper) / 2, (n,)."""
        return (self.lower + self.upper) / 2

    @property
    def half_width(self) -> np.ndarray:
        """The band's half width per joint, (upper - lower) / 2, (n,)."""
        return (self.upper - self.lower) / 2

    @classmethod
    def fixed(cls, values: object) -> Band:
        """The symmetric band [-values, values] per joint: a fixed threshold on |r|.

        Parameters
        ----------
        values : array_like
            The threshold per joint, (n,), non-negative, N m (N for a prismatic joint).

        Returns
        -------
        Band
            The band.

        Raises
        ------
        armdyn.ModelError
            When values is not a finite 1-D array, or a value is negative (naming the joint).
        """
        threshold = _joint_vector(values, "values")
        negative = np.flatnonzero(threshold < 0)
        if negative.size:
            j = int(negative[0])
            raise ModelError(f"values must be non-negative thresholds: joint {j + 1} has {threshold[j]:g}")
        return cls(-threshold, threshold)

    @classmethod
    def from_residuals(cls, r_free: object, quantile: float = 0.999, margin: float = 1.5) -> Band:
        """The band of a collision-free residual: per joint the empirical quantiles 1 - quantile and quantile
        of r_free, [q_low, q_high], widened about their centre by ``margin``:

            lower = c - margin h,  upper = c + margin h,  c = (q_high + q_low) / 2,  h = (q_high - q_low) / 2

        (the model-error-aware threshold of Haddadin, De Luca and Albu-Schaeffer 2017). r_free is a
        collision-free run of the observer or the residuals of an identification. With fewer than
        1 / (1 - quantile) samples the quantiles are the run's extreme values, and the margin carries the
        whole allowance for what the run did not see.

        Parameters
        ----------
        r_free : array_like
            Collision-free residuals (N, n), N >= 2 samples.
        quantile : float, optional
            The upper quantile, in (0.5, 1) (default 0.999).
        margin : float, optional
            The factor widening the quantile band about its centre, at least 1 (default 1.5).

        Returns
        -------
        Band
            The band.

        Raises
        ------
        armdyn.ModelError
            When r_free is not (N, n) with N >= 2, holds NaN or infinity (naming the sample and joint), when
            quantile is not in (0.5, 1) or margin is below 1.
        """
        q = _number(quantile, "quantile")
        if not 0.5 < q < 1:
            raise ModelError(f"quantile must lie in (0.5, 1) (the upper of the two quantiles), got {q:g}")
        m = _number(margin, "margin")
        if m < 1:
            raise ModelError(f"margin must be at least 1 (it widens the quantile band), got {m:g}")
        r = _samples(r_free, "r_free")
        if r.shape[0] < 2:
            raise ModelError(f"r_free has {r.shape[0]} sample; quantiles need at least 2")
        q_low, q_high = np.quantile(r, [1 - q, q], axis=0)
        centre, half = (q_high + q_low) / 2, (q_high - q_low) / 2
        return cls(centre - m * half, centre + m * half)

    def scaled(self, factor: float) -> Band:
        """This band scaled about its centre: centre +- factor * half_width.

        Parameters
        ----------
        factor : float
            The scale, non-negative.

        Returns
        -------
        Band
            The scaled band.

        Raises
        ------
        armdyn.ModelError
            When factor is not a finite non-negative number.
        """
        f = _number(factor, "factor")
        if f < 0:
            raise ModelError(f"factor must be non-negative, got {f:g}")
        centre, half = self.centre, self.half_width
        return Band(centre - f * half, centre + f * half)

    def contains(self, r: object) -> np.ndarray:
        """Whether each residual lies in the band, lower <= r <= upper, joint by joint.

        Parameters
        ----------
        r : array_like
            Residuals (..., n): one sample (n,) or a batch.

        Returns
        -------
        numpy.ndarray
            Booleans of r's shape.

        Raises
        ------
        armdyn.ModelError
            When r's last axis is not n long, or r holds NaN or infinity (naming the sample and joint).
        """
        array = _floats(r, "r")
        if array.ndim == 0 or array.shape[-1] != self.n:
            raise ModelError(f"r must have shape (..., {self.n}), one value per joint of the band, got {array.shape}")
        bad = np.argwhere(~np.isfinite(array))
        if bad.size:
            index = tuple(int(x) for x in bad[0])
            where = f"sample {index[:-1] if len(index) > 2 else index[0]}, " if len(index) > 1 else ""
            raise ModelError(f"r must be finite: {where}joint {index[-1] + 1} is {array[index]}")
        return (array >= self.lower) & (array <= self.upper)


# ----- detection -----------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Detection:
    """The collisions detected in a residual. Made by ``detect``.

    Parameters
    ----------
    time : float or None
        The time of the first detection (s), None when there is none.
    joint : int or None
        The joint (from 0) that left its band first; when several leave at the same sample, the one
        farthest outside relative to its band's half width. None when there is no detection.
    flags : numpy.ndarray
        Whether the arm is in collision at each sample (any joint is), (N,) bool.
    intervals : list of (float, float or None)
        The collisions as (start, end): the time of detection and the time of release (the first sample
        no longer in collision), end None for a collision still on at the last sample.
    joints_out : numpy.ndarray
        Whether each joint is in collision at each sample, (N, n) bool.
    """

    time: float | None
    joint: int | None
    flags: np.ndarray
    intervals: list[tuple[float, float | None]]
    joints_out: np.ndarray


def detect(t: object, r: object, band: Band, release: float = 0.5, hold: float = 0.0) -> Detection:
    """Collisions in a residual, with hysteresis (Haddadin, De Luca and Albu-Schaeffer 2017).

    A joint enters collision at the first sample its residual leaves ``band`` (r < lower or r > upper). It
    is released at the first sample where its residual has been within ``band.scaled(release)`` (the band
    narrowed about its centre) at every sample for at least ``hold`` seconds; with hold = 0, at the first
    sample within it. The arm is in collision while any joint is.

    Parameters
    ----------
    t : array_like
        Sample times (N,), s, strictly increasing.
    r : array_like
        Residuals (N, n), N m (N for a prismatic joint).
    band : Band
        The collision-free band, n joints.
    release : float, optional
        The fraction of the band, about its centre, a residual must come back within to be released,
        in (0, 1] (default 0.5).
    hold : float, optional
        How long (s) the residual must stay within the release band, non-negative (default 0).

    Returns
    -------
    Detection
        The first detection's time and joint, the collision state per sample and per joint, and the
        collisions' intervals.

    Raises
    ------
    armdyn.ModelError
        When t is not finite and strictly increasing (naming the sample), r is not (N, n) with N = len(t)
        and n = band.n, r holds NaN or infinity (naming the sample and joint), band is not a Band, release
        is not in (0, 1] or hold is negative.
    """
    if not isinstance(band, Band):
        raise ModelError(f"band must be a Band (Band.fixed or Band.from_residuals), got {type(band).__name__}")
    time = _times(t)
    residual = _samples(r, "r", band.n, time)
    fraction, wait = _number(release, "release"), _number(hold, "hold")
    if not 0 < fraction <= 1:
        raise ModelError(f"release must lie in (0, 1] (a fraction of the band), got {fraction:g}")
    if wait < 0:
        raise ModelError(f"hold must be a non-negative time (s), got {wait:g}")
    joints_out = _hysteresis(time, ~band.contains(residual), band.scaled(fraction).contains(residual), wait)
    flags: np.ndarray = np.asarray(joints_out.any(axis=1))
    first, joint = None, None
    if flags.any():
        k = int(np.argmax(flags))
        excursion = np.maximum(band.lower - residual[k], residual[k] - band.upper)
        scale = np.where(band.half_width > 0, band.half_width, 1.0)
        first, joint = float(time[k]), int(np.argmax(np.where(joints_out[k], excursion / scale, -np.inf)))
    joints_out.setflags(write=False)
    flags.setflags(write=False)
    return Detection(first, joint, flags, _intervals(time, flags), joints_out)


def _hysteresis(t: np.ndarray, outside: np.ndarray, inner: np.ndarray, hold: float) -> np.ndarray:
    """The collision state (N, n): set at a sample outside the band, reset at a sample that ends ``hold``
    seconds of unbroken samples within the inner band; on from the latest set to the next reset."""
    samples = np.arange(t.shape[0])[:, None]
    run_began = np.maximum.accumulate(np.where(inner & ~_previous(inner), samples, -1), axis=0)
    elapsed = t[:, None] - t[np.maximum(run_began, 0)]
    tolerance = 1e-12 * max(abs(t[0]), abs(t[-1]), 1.0)  # a hold of k steps is met at the k-th step
    reset = inner & (elapsed + tolerance >= hold)
    last_set = np.maximum.accumulate(np.where(outside, samples, -1), axis=0)
    last_reset = np.maximum.accumulate(np.where(reset, samples, -1), axis=0)
    return last_set > last_reset


def _previous(flags: np.ndarray) -> np.ndarray:
    """flags shifted one sample later, False at the first sample."""
    shifted = np.zeros_like(flags)
    shifted[1:] = flags[:-1]
    return shifted


def _intervals(t: np.ndarray, flags: np.ndarray) -> list[tuple[float, float | None]]:
    """The runs of ``flags`` as (time of the first sample on, time of the first sample off or None)."""
    starts = np.flatnonzero(flags & ~_previous(flags))
    ends = np.flatnonzero(~flags & _previous(flags))
    return [(float(t[s]), float(t[ends[i]]) if i < ends.shape[0] else None) for i, s in enumerate(starts.tolist())]


# ----- the figure ----------------------------------------------------------------------------------------------
def plot_residuals(
    t: object,
    r: object,
    band: Band | None = None,
    detection: Detection | None = None,
    truth: object = None,
    path: str | Path | None = None,
) -> Figure:
    """The residual per joint, one plot each, with its band shaded, the collisions shaded, the time of
    detection as a vertical line and the true external torque dashed.

    Parameters
    ----------
    t : array_like
        Sample times (N,), s, strictly increasing.
    r : array_like
        Residuals (N, n), N m (N for a prismatic joint).
    band : Band, optional
        The band, shaded per joint.
    detection : Detection, optional
        ``detect``'s result on t and r: its time drawn as a vertical line, its collisions shaded.
    truth : array_like, optional
        The true external joint torque (N, n), dashed.
    path : str or pathlib.Path, optional
        Where to write the figure (PNG for a .png path); the figure is closed after writing.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, n axes.

    Raises
    ------
    armdyn.ModelError
        When t, r or truth are not as ``detect`` takes them (shapes, order, NaN), the band or the detection
        has another number of joints or samples, or the path's folder does not exist.
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from armdyn.plotting import save_figure, wrap

    time = _times(t)
    residual = _samples(r, "r", None, time)
    n = residual.shape[1]
    if band is not None and (not isinstance(band, Band) or band.n != n):
        raise ModelError(f"band must be a Band of {n} joints as r has, got {_described(band)}")
    if detection is not None and (not isinstance(detection, Detection) or detection.joints_out.shape != residual.shape):
        raise ModelError(f"detection must be detect's result on this t and r, shape {residual.shape}")
    true = None if truth is None else _samples(truth, "truth", n, time, owner="r")
    fig, grid = plt.subplots(n, 1, figsize=(9, 1.5 * n + 1.2), sharex=True, squeeze=False, layout="constrained")
    axes = list(grid[:, 0])
    handles: list[Artist] = [Line2D([], [], color="C0", label="residual r")]
    for i, axis in enumerate(axes):
        if band is not None:
            axis.axhspan(band.lower[i], band.upper[i], color="C2", alpha=0.2, linewidth=0)
        if detection is not None:
            for start, end in detection.intervals:
                axis.axvspan(start, time[-1] if end is None else end, color="C3", alpha=0.12, linewidth=0)
            if detection.time is not None:
                axis.axvline(detection.time, color="C3", linewidth=1.0)
        axis.plot(time, residual[:, i], color="C0", linewidth=0.9)
        if true is not None:
            axis.plot(time, true[:, i], color="k", linestyle="--", linewidth=1.0)
        axis.set_ylabel(f"joint {i + 1}")
        axis.grid(True, alpha=0.3)
    if band is not None:
        handles.append(Patch(color="C2", alpha=0.2, label="band"))
    if true is not None:
        handles.append(Line2D([], [], color="k", linestyle="--", label="true external torque"))
    if detection is not None:
        handles += [Patch(color="C3", alpha=0.12, label="in collision"), Line2D([], [], color="C3", label="detection")]
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(time[0], time[-1])
    fig.supylabel("residual (N m, or N for a prismatic joint)", fontsize=9)
    axes[0].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    fig.suptitle(wrap(_title(detection, n)), fontsize=10)
    if path is not None:
        save_figure(fig, path)
        plt.close(fig)
    return fig


def _title(detection: Detection | None, n: int) -> str:
    """The figure's title: what it shows and the first detection."""
    title = f"Observer residual per joint ({n} joints)"
    if detection is None:
        return title
    if detection.time is None or detection.joint is None:
        return f"{title}: no collision detected"
    count = len(detection.intervals)
    return (
        f"{title}: collision detected at t = {detection.time:.4g} s on joint {detection.joint + 1}; "
        f"{count} collision{'s' if count != 1 else ''}"
    )


def _described(value: object) -> str:
    """A short description of a band argument for a message."""
    return f"a Band of {value.n} joints" if isinstance(value, Band) else type(value).__name__
