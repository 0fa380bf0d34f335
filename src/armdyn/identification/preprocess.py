"""From a robot's log to samples the regressor can use: uniform time, filtered positions, their derivatives.

The steps follow the identification practice of Gautier ("Dynamic identification of robots with power
model", ICRA 1997) and Gautier and Khalil ("Exciting trajectories for the identification of base
inertial parameters of robots", IJRR 11(4), 1992), for logs of trajectories such as the finite Fourier
series of Swevers, Ganseman, Tukel, De Schutter and Van Brussel (IEEE Trans. Robotics and Automation
13(5), 1997):

1. ``resample``: the samples onto a uniform time grid (a robot's clock jitters), by interpolation;
2. ``lowpass``: a zero-phase Butterworth low-pass filter (forward and backward, so no delay) of the
   positions, with a cut-off well above the motion's bandwidth (``excitation_bandwidth``) so that the
   motion passes undistorted and the measurement noise above it does not;
3. ``derivatives``: the velocities and accelerations by central differences of the filtered positions;
4. the measured torques (or currents) filtered by the same filter, the start and end transients
   trimmed, and the samples decimated;
5. ``parallel_filter``: Gautier's parallel filtering and decimation, the same low-pass filter applied to
   the torques and to each column of the regressor W(q, qd, qdd) before keeping every factor-th sample.
   Since the filter is linear, tau = W phi holds for the filtered torques and regressor alike, while the
   high-frequency content of both (the products of signals in W reach beyond the positions' cut-off)
   cannot alias onto the decimated samples.

``prepare`` runs 1 to 4 and returns a ``Prepared``; its ``parallel_filter`` method applies 5 to arrays
computed on its undecimated samples (the regressor, the torques).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import signal
from scipy.interpolate import CubicSpline

from armdyn.errors import ModelError
from armdyn.identification.log import FIELDS, MIN_LOG_SAMPLES, Log

__all__ = [
    "CUTOFF_PER_BANDWIDTH",
    "DECIMATED_RATE_PER_CUTOFF",
    "DECIMATION_SHARE",
    "MAX_CUTOFF_SHARE",
    "PAD_PERIODS",
    "Prepared",
    "derivatives",
    "excitation_bandwidth",
    "lowpass",
    "parallel_filter",
    "prepare",
    "resample",
]

CUTOFF_PER_BANDWIDTH = 10.0
"""The default cut-off of the positions' filter over the motion's bandwidth (``excitation_bandwidth``): a
cut-off well above the motion, so that the filter passes it undistorted (Gautier 1997)."""
MAX_CUTOFF_SHARE = 0.8
"""The default cut-off is at most this share of the Nyquist frequency (rate / 2)."""
DECIMATED_RATE_PER_CUTOFF = 5.0
"""The default decimation keeps a rate of at least this many times the cut-off."""
DECIMATION_SHARE = 0.8
"""The parallel filter's cut-off is this share of the decimated Nyquist frequency, 0.8 rate / (2 factor)
(Gautier 1997, as scipy.signal.decimate)."""
PAD_PERIODS = 10.0
"""The zero-phase filters pad each end with an odd reflection of this many periods of the cut-off (rate /
cutoff samples each; at most the whole signal): their end effects are then far shorter than with
scipy.signal.sosfiltfilt's default padding of a few samples."""
_BAND_WINDOW = "hann"


def _rate(rate: object, name: str = "rate") -> float:
    value = float(rate)  # type: ignore[arg-type]
    if not (math.isfinite(value) and value > 0):
        raise ModelError(f"{name} must be a finite number of samples per second > 0, got {rate!r}")
    return value


def resample(log: Log, rate: float | None = None, method: str = "linear") -> Log:
    """The log on a uniform time grid t0, t0 + 1/rate, ... up to its last time, by interpolation.

    A robot's clock jitters (samples at 0.7 to 1.6 ms for a nominal 1 ms, say): each field is interpolated
    at the grid's times from the two samples around it (``method="linear"``), or by a cubic spline through
    all the samples (``method="cubic"``, scipy.interpolate.CubicSpline; closer for smooth positions, but it
    may overshoot on noisy torques). Any strictly increasing times are handled, jitter of more than half a
    step and gaps included (a gap is bridged by the interpolation).

    Parameters
    ----------
    log : Log
        The log.
    rate : float, optional
        The grid's rate, Hz (default the log's median rate, ``log.sample_rate``).
    method : {"linear", "cubic"}, optional
        The interpolation, for every field (default "linear").

    Returns
    -------
    Log
        The log on the grid (its sample indices are those of the grid).

    Raises
    ------
    armdyn.ModelError
        When ``rate`` is not a positive number, ``method`` is unknown, or the grid has fewer than
        MIN_LOG_SAMPLES samples.
    """
    if method not in ("linear", "cubic"):
        raise ModelError(f"{log.source}: resample's method must be 'linear' or 'cubic', got {method!r}")
    step = 1.0 / (log.sample_rate if rate is None else _rate(rate))
    t = log.t
    count = math.floor((t[-1] - t[0]) / step * (1 + 1e-12)) + 1
    if count < MIN_LOG_SAMPLES:
        raise ModelError(
            f"{log.source}: resampling {log.duration:g} s at {1 / step:g} Hz gives {count} samples; "
            f"a log needs at least {MIN_LOG_SAMPLES}"
        )
    grid = t[0] + step * np.arange(count)
    grid[-1] = min(grid[-1], t[-1])
    if method == "linear":
        right = np.clip(np.searchsorted(t, grid, side="right"), 1, t.shape[0] - 1)
        weight = ((grid - t[right - 1]) / (t[right] - t[right - 1]))[:, None]

        def interpolate(x: np.ndarray) -> np.ndarray:
            return x[right - 1] + weight * (x[right] - x[right - 1])

    else:

        def interpolate(x: np.ndarray) -> np.ndarray:
            return np.asarray(CubicSpline(t, x, axis=0)(grid))

    fields = {name: getattr(log, name) for name in FIELDS[1:]}
    values: dict[str, Any] = {name: None if x is None else interpolate(x) for name, x in fields.items()}
    return dataclasses.replace(log, t=grid, first_sample=0, **values)


def excitation_bandwidth(q: np.ndarray, rate: float, energy: float = 0.99) -> float:
    """The frequency below which the motion holds ``energy`` of its spectral energy, the largest over the joints.

    For each joint, the power spectrum of q minus its mean (a Hann window against leakage from the
    log's ends), and the lowest frequency at which its cumulative sum reaches ``energy`` of the total; the
    largest over the joints that move.

    Parameters
    ----------
    q : array_like
        Positions on a uniform grid, (N,) or (N, n).
    rate : float
        The sample rate, Hz.
    energy : float, optional
        The share of the energy, strictly between 0 and 1 (default 0.99).

    Returns
    -------
    float
        The bandwidth, Hz (a multiple of the frequency resolution rate / N, at least one).

    Raises
    ------
    armdyn.ModelError
        When ``rate`` is not positive, ``energy`` is not strictly between 0 and 1, q holds fewer than
        MIN_LOG_SAMPLES samples or values that are not finite, or no joint moves.
    """
    fs = _rate(rate)
    if not 0 < energy < 1:
        raise ModelError(f"energy must be a share strictly between 0 and 1, got {energy!r}")
    x = _samples(q, "q")
    x = x.reshape(x.shape[0], -1)
    x = x - x.mean(axis=0)
    power = np.abs(np.fft.rfft(x * signal.get_window(_BAND_WINDOW, x.shape[0])[:, None], axis=0)) ** 2
    total = power.sum(axis=0)
    moving = total > 0
    if not moving.any():
        raise ModelError("excitation_bandwidth: no joint moves (q is constant)")
    share = np.cumsum(power[:, moving], axis=0) / total[moving]
    first = np.maximum(np.argmax(share >= energy, axis=0), 1)  # at least the frequency resolution
    return float(np.fft.rfftfreq(x.shape[0], 1.0 / fs)[first].max())


def _samples(x: object, name: str) -> np.ndarray:
    """``x`` as a float array of N >= MIN_LOG_SAMPLES finite samples along axis 0, or a ModelError."""
    try:
        array = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{name} must be an array of numbers (N, ...)") from None
    if array.ndim == 0 or array.shape[0] < MIN_LOG_SAMPLES:
        raise ModelError(f"{name} must hold at least {MIN_LOG_SAMPLES} samples along axis 0, got shape {array.shape}")
    if not np.isfinite(array).all():
        k = int(np.argmax(~np.isfinite(array).reshape(array.shape[0], -1).all(axis=1)))
        raise ModelError(f"{name} holds NaN or infinity at sample {k}")
    return array


def _butterworth(cutoff: float, rate: float, order: int) -> np.ndarray:
    """The second-order sections of a digital Butterworth low-pass filter, its cut-off checked."""
    fs = _rate(rate)
    if not isinstance(order, (int, np.integer)) or order < 1:
        raise ModelError(f"the filter order must be a whole number >= 1, got {order!r}")
    fc = float(cutoff)
    if not (math.isfinite(fc) and 0 < fc < fs / 2):
        raise ModelError(
            f"the cut-off frequency must be between 0 and the Nyquist frequency rate / 2 = {fs / 2:g} Hz "
            f"(exclusive), got {cutoff!r} Hz"
        )
    return np.asarray(signal.butter(int(order), fc, fs=fs, output="sos"))


def _padding(samples: int, rate: float, cutoff: float) -> int:
    """The samples of odd reflection padding each end: PAD_PERIODS periods of the cut-off, at most samples - 1."""
    return min(samples - 1, math.ceil(PAD_PERIODS * rate / cutoff))


def lowpass(x: np.ndarray, cutoff: float, rate: float, order: int = 4) -> np.ndarray:
    """A zero-phase Butterworth low-pass filter along axis 0: the filter forward, then backward.

    scipy.signal.butter (second-order sections) and scipy.signal.sosfiltfilt, each end padded with an odd
    reflection of the signal (PAD_PERIODS periods of the cut-off). Filtering twice squares the gain,
    |H(f)|^2 = 1 / (1 + (f / cutoff)^(2 order)), so the gain at the cut-off is 1/2, and there is no phase
    shift (no delay).

    Parameters
    ----------
    x : array_like
        Samples on a uniform grid, (N, ...); every trailing column filtered alike.
    cutoff : float
        The cut-off frequency, Hz, 0 < cutoff < rate / 2.
    rate : float
        The sample rate, Hz.
    order : int, optional
        The Butterworth filter's order (default 4; 8 in effect, forward and backward).

    Returns
    -------
    numpy.ndarray
        The filtered samples, the shape of x.

    Raises
    ------
    armdyn.ModelError
        When the cut-off is not strictly between 0 and rate / 2, the order is not a whole number >= 1, or x
        holds fewer than MIN_LOG_SAMPLES samples or values that are not finite.
    """
    sos = _butterworth(cutoff, rate, order)
    array = _samples(x, "x")
    flat = array.reshape(array.shape[0], -1)
    padding = _padding(flat.shape[0], float(rate), float(cutoff))
    return np.asarray(signal.sosfiltfilt(sos, flat, axis=0, padlen=padding)).reshape(array.shape)


def derivatives(q: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations by central differences: qd = dq/dt and qdd = dqd/dt (numpy.gradient,
    second-order accurate, one-sided second-order differences at the ends).

    Differentiation amplifies noise (by 2 pi f at frequency f): differentiate positions already low-passed
    (``lowpass``), as ``prepare`` does (Gautier 1997). The error of a central difference is h^2 / 6 times
    the third derivative (h = 1 / rate), so for a motion of bandwidth f it shrinks as (f / rate)^2.

    Parameters
    ----------
    q : array_like
        Positions on a uniform grid, (N, ...), N >= MIN_LOG_SAMPLES.
    rate : float
        The sample rate, Hz.

    Returns
    -------
    tuple of numpy.ndarray
        (qd, qdd), each the shape of q.

    Raises
    ------
    armdyn.ModelError
        When ``rate`` is not positive, or q holds fewer than MIN_LOG_SAMPLES samples or values that are not
        finite.
    """
    step = 1.0 / _rate(rate)
    positions = _samples(q, "q")
    qd = np.gradient(positions, step, axis=0, edge_order=2)
    return qd, np.gradient(qd, step, axis=0, edge_order=2)


def parallel_filter(x: np.ndarray, rate: float, cutoff: float, factor: int) -> np.ndarray:
    """Gautier's parallel filtering and decimation (1997): a zero-phase low-pass filter along axis 0, then
    every ``factor``-th sample.

    Apply it alike to the torques tau (N, n) and to the regressor W (N, n, p) computed from the filtered
    positions: tau = W phi holds for the filtered pair (the filter is linear), while the content of both
    above ``cutoff`` (W's products of signals reach beyond the positions' cut-off, and the torques' noise)
    is removed before the decimation, so it cannot alias. The cut-off must be below the decimated Nyquist
    frequency, rate / (2 factor); Gautier takes 0.8 of it (DECIMATION_SHARE). The columns are filtered in
    blocks, so that a large regressor needs little memory beyond its decimated copy.

    Parameters
    ----------
    x : array_like
        Samples on a uniform grid, (N, ...).
    rate : float
        The sample rate of x, Hz.
    cutoff : float
        The low-pass filter's cut-off, Hz, 0 < cutoff <= rate / (2 factor).
    factor : int
        Keep every factor-th sample (1: filter only).

    Returns
    -------
    numpy.ndarray
        The filtered samples 0, factor, 2 factor, ... : shape (ceil(N / factor), ...).

    Raises
    ------
    armdyn.ModelError
        When ``factor`` is not a whole number >= 1, the cut-off is not strictly between 0 and rate / 2 or is
        above the decimated Nyquist frequency rate / (2 factor), or x holds fewer than MIN_LOG_SAMPLES
        samples or values that are not finite.
    """
    if not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ModelError(f"the decimation factor must be a whole number >= 1, got {factor!r}")
    fs = _rate(rate)
    if factor > 1 and float(cutoff) > fs / (2 * factor):
        raise ModelError(
            f"the parallel filter's cut-off {cutoff:g} Hz is above the decimated Nyquist frequency "
            f"rate / (2 factor) = {fs / (2 * factor):g} Hz: what lies between would alias; take at most "
            f"{DECIMATION_SHARE * fs / (2 * factor):g} Hz"
        )
    sos = _butterworth(cutoff, fs, 4)
    array = _samples(x, "x")
    flat = array.reshape(array.shape[0], -1)
    padding = _padding(flat.shape[0], fs, float(cutoff))
    out = np.empty((len(range(0, flat.shape[0], factor)), flat.shape[1]))
    block = max(1, 2**20 // flat.shape[0])
    for start in range(0, flat.shape[1], block):
        columns = flat[:, start : start + block]
        out[:, start : start + block] = signal.sosfiltfilt(sos, columns, axis=0, padlen=padding)[::factor]
    return out.reshape(out.shape[:1] + array.shape[1:])


@dataclass(frozen=True, eq=False)
class Prepared:
    """A log prepared for identification: uniform time, filtered positions and their derivatives, filtered
    torques (or currents), trimmed and decimated (see ``prepare``, which makes it).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times (M,), s, uniform at ``rate``.
    q, qd, qdd : numpy.ndarray
        Filtered positions, and their velocities and accelerations (M, n).
    tau, current : numpy.ndarray or None
        The measured torques or the motor currents (M, n), filtered with the positions' filter (one of them).
    rate : float
        The sample rate of t, Hz (the log's rate over ``factor``).
    cutoff : float
        The cut-off of the positions' (and torques') filter, Hz.
    factor : int
        The decimation factor: these samples are every factor-th of the undecimated ones.
    log : Log
        The log it came from.
    trim : float
        The seconds cut from each end.
    untrimmed : tuple of numpy.ndarray, optional
        The filtered (q, qd, qdd) before trimming and decimation, at the undecimated rate.
    window : slice, optional
        The undecimated samples kept by the trim, as a slice of ``untrimmed``.
    full : Prepared or None
        The same before decimation (factor 1), its arrays those of which these are every factor-th sample
        (views: no copy); None when factor is 1 (the samples are the undecimated ones: ``undecimated``).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray | None
    current: np.ndarray | None
    rate: float
    cutoff: float
    factor: int
    log: Log
    full: Prepared | None = None
    trim: float = 0.0
    untrimmed: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    window: slice | None = None

    def __post_init__(self) -> None:
        for name in ("t", "q", "qd", "qdd", "tau", "current"):
            value = getattr(self, name)
            if value is not None:
                value.flags.writeable = False

    @property
    def undecimated(self) -> Prepared:
        """The samples before decimation (this Prepared itself when the factor is 1)."""
        return self if self.full is None else self.full

    @property
    def effort(self) -> np.ndarray:
        """The filtered torques, or else the filtered motor currents (M, n)."""
        return self.tau if self.tau is not None else self.current  # type: ignore[return-value]

    @property
    def decimation_cutoff(self) -> float:
        """The cut-off of Gautier's parallel decimation filter, Hz: 0.8 of the decimated Nyquist frequency
        (the undecimated rate over 2 factor), or that of the positions' filter when there is no decimation."""
        if self.factor == 1:
            return self.cutoff
        return DECIMATION_SHARE * self.undecimated.rate / (2 * self.factor)

    def filtered_as_torques(self, values: np.ndarray) -> np.ndarray:
        """Values computed at the untrimmed filtered states, through the torques' filter, then trimmed and
        decimated as these samples are: the regressor's columns that are not smooth in the states (a friction
        law's) see the filter the torques saw, so that filter(W) phi = filter(tau) holds for them too
        (Gautier 1997's parallel filtering).

        Parameters
        ----------
        values : numpy.ndarray
            (M, ...) at ``untrimmed``'s M samples.

        Returns
        -------
        numpy.ndarray
            (N, ...) at these samples.

        Raises
        ------
        armdyn.ModelError
            When the Prepared has no untrimmed states, or ``values`` has another number of rows.
        """
        if self.untrimmed is None or self.window is None:
            raise ModelError(f"{self.log.source}: these samples keep no untrimmed states to filter values at")
        rows = self.untrimmed[0].shape[0]
        if np.shape(values)[0] != rows:
            raise ModelError(
                f"{self.log.source}: filtered_as_torques takes ({rows}, ...) values, got {np.shape(values)}"
            )
        filtered = lowpass(np.asarray(values, dtype=float), self.cutoff, self.rate * self.factor)
        return filtered[self.window][:: self.factor]

    def parallel_filter(self, x: np.ndarray) -> np.ndarray:
        """Gautier's parallel filtering and decimation (``parallel_filter``) of an array computed on the
        undecimated samples, with this preparation's rate, decimation cut-off and factor: its rows then
        match this Prepared's samples.

        Apply it to the regressor W(q, qd, qdd) of ``undecimated`` and to ``undecimated.tau`` alike.

        Parameters
        ----------
        x : array_like
            An array (N, ...) with one row per undecimated sample.

        Returns
        -------
        numpy.ndarray
            The filtered array at this Prepared's samples, (M, ...).

        Raises
        ------
        armdyn.ModelError
            When x does not have one row per undecimated sample, or holds values that are not finite.
        """
        rows = self.undecimated.t.shape[0]
        shape = np.shape(x)
        if not shape or shape[0] != rows:
            raise ModelError(
                f"{self.log.source}: parallel_filter takes an array with one row per undecimated sample ({rows}, "
                f"...), got shape {shape}; compute it on prepared.undecimated"
            )
        return parallel_filter(x, self.undecimated.rate, self.decimation_cutoff, self.factor)


def prepare(
    log: Log,
    cutoff: float | None = None,
    decimate: int | None = None,
    trim: float | None = None,
    use_measured_velocity: bool = False,
) -> Prepared:
    """A log prepared for identification (Gautier 1997): resampled, filtered, differentiated, trimmed, decimated.

    1. ``resample`` onto a uniform grid at the log's median rate (linear interpolation);
    2. ``lowpass`` the positions: a zero-phase Butterworth filter of order 4 whose cut-off is by default
       CUTOFF_PER_BANDWIDTH (10) times the motion's bandwidth (``excitation_bandwidth``, 99% of the energy),
       at most MAX_CUTOFF_SHARE (0.8) of the Nyquist frequency rate / 2;
    3. ``derivatives``: qd and qdd by central differences of the filtered positions (with
       ``use_measured_velocity``, qd is the robot's reported velocity through the same filter, and qdd its
       central difference);
    4. the torques (or currents) through the same filter, so that they and the positions share its
       small distortion of the motion;
    5. ``trim`` seconds cut from each end (a robot's start and stop, and the filter's end effects, which
       last about 2 / cutoff seconds: by default the larger of 0.1 s and 2 / cutoff);
    6. every factor-th sample kept: by default the largest factor whose decimated rate is still at least
       DECIMATED_RATE_PER_CUTOFF (5) times the cut-off. The samples are band-limited by the filter of step
       2 already, so they do not alias; for the regressor, whose products of signals reach beyond the
       cut-off, compute it on ``undecimated`` and decimate it and the torques with ``parallel_filter``.

    Parameters
    ----------
    log : Log
        The log.
    cutoff : float, optional
        The filter's cut-off, Hz, 0 < cutoff < rate / 2 (default from the bandwidth, above).
    decimate : int, optional
        The decimation factor, a whole number >= 1 (default above; 1 keeps every sample).
    trim : float, optional
        Seconds cut from each end, >= 0 (default the larger of 0.1 s and 2 / cutoff).
    use_measured_velocity : bool, optional
        Take the velocities the robot reported (the log's qd) instead of differentiating the positions.
    Returns
    -------
    Prepared
        The samples; its ``full`` the undecimated ones.

    Raises
    ------
    armdyn.ModelError
        When the cut-off is not strictly between 0 and rate / 2, ``decimate`` is not a whole number >= 1,
        ``trim`` is negative, fewer than MIN_LOG_SAMPLES samples remain after trimming and decimating, no
        joint moves, or ``use_measured_velocity`` is asked of a log without velocities.
    """
    if use_measured_velocity and log.qd is None:
        raise ModelError(f"{log.source}: use_measured_velocity needs the log's velocities qd, and it has none")
    if decimate is not None and (not isinstance(decimate, (int, np.integer)) or decimate < 1):
        raise ModelError(f"{log.source}: the decimation factor must be a whole number >= 1, got {decimate!r}")
    if trim is not None and not (isinstance(trim, (int, float, np.floating)) and math.isfinite(trim) and trim >= 0):
        raise ModelError(f"{log.source}: trim must be a number of seconds >= 0, got {trim!r}")
    uniform = resample(log)
    rate = uniform.sample_rate
    try:
        if cutoff is None:
            bandwidth = excitation_bandwidth(uniform.q, rate)
            fc = min(CUTOFF_PER_BANDWIDTH * bandwidth, MAX_CUTOFF_SHARE * rate / 2)
        else:
            fc = float(cutoff)
        q = lowpass(uniform.q, fc, rate)
        effort = lowpass(uniform.effort, fc, rate)
        if use_measured_velocity:
            qd = lowpass(uniform.qd, fc, rate)  # type: ignore[arg-type]
            qdd = np.gradient(qd, 1.0 / rate, axis=0, edge_order=2)
        else:
            qd, qdd = derivatives(q, rate)
    except ModelError as error:
        raise ModelError(f"{log.source}: {error}") from None
    trim = max(0.1, 2.0 / fc) if trim is None else float(trim)
    factor = int(decimate) if decimate is not None else max(1, int(rate // (DECIMATED_RATE_PER_CUTOFF * fc)))
    t = uniform.t
    keep = slice(int(np.searchsorted(t, t[0] + trim, "left")), int(np.searchsorted(t, t[-1] - trim, "right")))
    kept = len(range(*keep.indices(t.shape[0]))[::factor])
    if kept < MIN_LOG_SAMPLES:
        raise ModelError(
            f"{log.source}: trimming {trim:g} s from each end of {uniform.duration:g} s and keeping every "
            f"{factor}-th sample leaves {kept} samples; at least {MIN_LOG_SAMPLES} are needed"
        )
    efforts: dict[str, Any] = {"tau": None, "current": None, log.effort_name: effort[keep]}
    full = Prepared(
        t[keep], q[keep], qd[keep], qdd[keep], **efforts, rate=rate, cutoff=fc, factor=1, log=log, trim=trim,
        untrimmed=(q, qd, qdd), window=keep,
    )  # fmt: skip
    if factor == 1:
        return full
    every = slice(None, None, factor)
    return Prepared(
        full.t[every],
        full.q[every],
        full.qd[every],
        full.qdd[every],
        tau=None if full.tau is None else full.tau[every],
        current=None if full.current is None else full.current[every],
        rate=rate / factor,
        cutoff=fc,
        factor=factor,
        log=log,
        full=full,
        trim=trim,
        untrimmed=(q, qd, qdd),
        window=keep,
    )
