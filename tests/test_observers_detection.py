"""Collision detection on residuals: bands from quantiles, detection with hysteresis, the residual figure.

Residuals are synthetic: Gaussian noise of known spread, plus a step of known time, size and joint.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from scipy.stats import norm

from armdyn.errors import ModelError
from armdyn.observers.detection import Band, Detection, detect, plot_residuals

matplotlib.use("Agg")

DT = 1e-3  # s, a 1 kHz control loop
N_JOINTS = 7
STEP_JOINT = 3  # joint 4, counted from 1
SIGMA = 0.2  # N m, the noise's standard deviation


def noise(seed: int, seconds: float, n: int = N_JOINTS) -> tuple[np.ndarray, np.ndarray]:
    """Times and white Gaussian residuals of SIGMA over ``seconds`` at 1 kHz."""
    rng = np.random.default_rng(seed)
    samples = round(seconds / DT)
    return np.arange(samples) * DT, SIGMA * rng.standard_normal((samples, n))


def step_run(seed: int = 7, start: float = 2.0, end: float = 4.0, size: float = 5.0):
    """A residual of noise plus a step of ``size`` N m on joint 4 from ``start`` to ``end`` s, and its truth."""
    t, r = noise(seed, 6.0)
    truth = np.zeros_like(r)
    truth[(t >= start - DT / 2) & (t < end - DT / 2), STEP_JOINT] = size
    return t, r + truth, truth


# ----- the band ------------------------------------------------------------------------------------------------
def test_band_from_residuals_matches_the_quantiles_widened_about_their_centre() -> None:
    rng = np.random.default_rng(1)
    r = np.column_stack([rng.normal(0.3, 0.1, 20_000), rng.uniform(-2.0, 1.0, 20_000)])
    band = Band.from_residuals(r, quantile=0.99, margin=2.0)
    # uniform on [-2, 1]: quantiles -1.97 and 0.97, centre -0.5, half width 1.47, widened to 2.94
    assert band.lower[1] == pytest.approx(-0.5 - 2 * 1.47, abs=0.02)
    assert band.upper[1] == pytest.approx(-0.5 + 2 * 1.47, abs=0.02)
    # Gaussian: the 0.99 quantile is 2.326 sigma from the mean
    assert band.centre[0] == pytest.approx(0.3, abs=0.01)
    assert band.half_width[0] == pytest.approx(2 * 2.326 * 0.1, rel=0.03)
    assert band.contains(np.array([0.3, -0.5])).tolist() == [True, True]
    assert band.contains(np.array([[0.3 + 0.48, -0.5], [0.3, 2.5]])).tolist() == [[False, True], [True, False]]


def test_band_fixed_is_symmetric_and_scaled_about_its_centre() -> None:
    band = Band.fixed([1.0, 2.0, 0.5])
    np.testing.assert_array_equal(band.lower, [-1.0, -2.0, -0.5])
    np.testing.assert_array_equal(band.upper, [1.0, 2.0, 0.5])
    shifted = Band(np.array([1.0, -3.0]), np.array([3.0, 1.0]))
    half = shifted.scaled(0.5)
    np.testing.assert_allclose(half.lower, [1.5, -2.0])
    np.testing.assert_allclose(half.upper, [2.5, 0.0])
    assert band.contains(np.array([1.0, -2.0, 0.0])).all()  # the edges belong to the band
    with pytest.raises(ValueError):
        band.lower[0] = 0.0  # read-only


# ----- detection ---------------------------------------------------------------------------------------------
def test_a_step_on_joint_4_is_detected_within_one_sample() -> None:
    t, r, _ = step_run(start=2.0, end=6.5)
    band = Band.from_residuals(r[t < 2.0 - DT / 2])  # the collision-free part
    found = detect(t, r, band)
    assert found.time is not None and abs(found.time - 2.0) <= DT + 1e-12
    assert found.joint == STEP_JOINT
    assert not found.flags[t < 2.0 - DT / 2].any()
    assert found.flags[t >= 2.0].all()  # the step stays, and so does the collision
    assert found.intervals == [(found.time, None)]
    assert found.joints_out[:, STEP_JOINT].sum() == found.flags.sum()
    assert found.joints_out.shape == r.shape and found.flags.shape == t.shape


def test_the_step_is_detected_at_its_first_sample_on_several_seeds() -> None:
    for seed in range(5):
        t, r, _ = step_run(seed=seed, start=2.0, end=6.5, size=5.0)
        found = detect(t, r, Band.from_residuals(r[t < 1.999]))
        assert found.time is not None and abs(found.time - 2.0) <= DT + 1e-12, seed
        assert found.joint == STEP_JOINT, seed


def _gaussian_false_alarm_probability(band: Band, sigma: float) -> np.ndarray:
    """The probability per sample that N(0, sigma) noise leaves the band, per joint."""
    return norm.cdf(band.lower / sigma) + norm.sf(band.upper / sigma)


def test_false_alarms_on_noise_alone_follow_the_gaussian_tail_of_the_band() -> None:
    """Band from 10 s, then 60 s at 1 kHz of fresh noise on 7 joints, several seeds: the samples outside the
    band number what the Gaussian tail beyond the band's edges predicts (about 3.6e-6 per sample and joint
    for quantile 0.999 and margin 1.5, the band's edge at 1.5 x 3.09 sigma), and every such sample is
    flagged."""
    counted, expected = 0, 0.0
    for seed in range(8):
        _, calibration = noise(1000 + seed, 10.0)
        band = Band.from_residuals(calibration, quantile=0.999, margin=1.5)
        assert band.half_width == pytest.approx(1.5 * norm.ppf(0.999) * SIGMA, rel=0.15)
        t, r = noise(2000 + seed, 60.0)
        found = detect(t, r, band, release=1.0)
        outside = ~band.contains(r)
        np.testing.assert_array_equal(found.flags, outside.any(axis=1))  # release 1, hold 0: no memory
        counted += int(outside.sum())
        expected += float(_gaussian_false_alarm_probability(band, SIGMA).sum() * r.shape[0])
    # a Poisson count: within 4 standard deviations of its mean (expected is about 16 here)
    assert abs(counted - expected) <= 4 * math.sqrt(expected) + 1


def test_no_false_alarm_on_noise_alone_over_60_s() -> None:
    """60 s at 1 kHz of Gaussian noise on 7 joints, band from a separate 10 s at quantile 0.999: with margin
    1.5 an alarm is expected about once a run (the test above), so the zero count is checked with margin
    2.0, where the Gaussian tail predicts under 0.01 alarms a run; on several seeds, the count is 0."""
    for seed in (11, 12, 13, 14, 15):
        _, calibration = noise(seed, 10.0)
        band = Band.from_residuals(calibration, quantile=0.999, margin=2.0)
        t, r = noise(100 + seed, 60.0)
        assert _gaussian_false_alarm_probability(band, SIGMA).sum() * t.shape[0] < 0.01
        found = detect(t, r, band)
        assert found.time is None and found.joint is None, seed
        assert found.intervals == [] and not found.flags.any() and not found.joints_out.any()


def test_hysteresis_releases_after_the_step_ends() -> None:
    t, r, _ = step_run(seed=3, start=2.0, end=3.0, size=5.0)
    band = Band.from_residuals(r[t < 1.999])
    inner = band.scaled(0.5).contains(r)
    found = detect(t, r, band, release=0.5, hold=0.05)
    assert len(found.intervals) == 1
    start, end = found.intervals[0]
    assert start == pytest.approx(2.0, abs=DT)
    # the oracle: the first sample after the step's end that closes 50 ms within the half band
    after = np.flatnonzero(t >= 3.0 - DT / 2)
    run = 0
    for k in after:
        run = run + 1 if inner[k, STEP_JOINT] else 0
        if run > 50:  # 51 samples span 50 ms
            break
    assert end == pytest.approx(t[k], abs=1e-12)
    assert end >= 3.05 - 1e-9
    assert not found.flags[t >= end].any()
    assert found.flags[(t >= 2.0) & (t < end - DT / 2)].all()


def test_hysteresis_holds_a_joint_back_in_its_band_until_within_the_release_band() -> None:
    """Piecewise-constant residual on one joint, band [-1, 1]: out at 0.1 s, back to 0.8 (in the band,
    outside half of it) still in collision, to 0.2 at 0.3 s, released after a hold of 20 ms."""
    t = np.arange(500) * DT
    r = np.zeros((500, 1))
    r[(t >= 0.1 - DT / 2) & (t < 0.2 - DT / 2)] = 3.0
    r[(t >= 0.2 - DT / 2) & (t < 0.3 - DT / 2)] = 0.8
    r[t >= 0.3 - DT / 2] = 0.2
    found = detect(t, r, Band.fixed([1.0]), release=0.5, hold=0.02)
    assert found.time == pytest.approx(0.1)
    assert found.intervals == [(pytest.approx(0.1), pytest.approx(0.32))]
    without_hysteresis = detect(t, r, Band.fixed([1.0]), release=1.0)
    assert without_hysteresis.intervals == [(pytest.approx(0.1), pytest.approx(0.2))]
    held = detect(t, r, Band.fixed([1.0]), release=0.1)  # 0.2 never comes within 0.1: never released
    assert held.intervals == [(pytest.approx(0.1), None)]


def test_hysteresis_agrees_with_a_sample_by_sample_state_machine() -> None:
    """detect against the plain loop of its definition, on noise crossing a narrow band often, with uneven
    time steps."""
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.uniform(0.5e-3, 1.5e-3, 3000))
    r = np.cumsum(rng.normal(0.0, 0.05, (3000, 3)), axis=0) * 0.3 + rng.normal(0.0, 0.05, (3000, 3))
    band = Band(np.array([-0.3, -0.5, -0.1]), np.array([0.3, 0.2, 0.6]))
    for release, hold in ((0.5, 0.0), (0.5, 0.004), (0.8, 0.01), (1.0, 0.002)):
        found = detect(t, r, band, release, hold)
        inner = band.scaled(release)
        state = np.zeros(3, dtype=bool)
        since = np.full(3, np.nan)
        for k in range(t.shape[0]):
            for j in range(3):
                if not band.lower[j] <= r[k, j] <= band.upper[j]:
                    state[j], since[j] = True, np.nan
                elif inner.lower[j] <= r[k, j] <= inner.upper[j]:
                    since[j] = t[k] if np.isnan(since[j]) else since[j]
                    if state[j] and t[k] - since[j] >= hold - 1e-12:
                        state[j] = False
                else:
                    since[j] = np.nan
            np.testing.assert_array_equal(found.joints_out[k], state, err_msg=f"sample {k}, {release}, {hold}")
        assert found.joints_out.any(axis=0).all()  # every joint went out at least once


def test_simultaneous_exits_name_the_joint_farthest_outside() -> None:
    t = np.arange(10) * DT
    r = np.zeros((10, 3))
    r[5:] = [2.0, -30.0, 5.0]  # joint 2 is 29 half widths out, joint 3 only 4
    found = detect(t, r, Band.fixed([1.0, 1.0, 1.0]))
    assert found.time == pytest.approx(5 * DT) and found.joint == 1
    assert found.joints_out[5].all()


# ----- the figure -------------------------------------------------------------------------------------------------
def test_the_figure_has_one_axis_per_joint_and_saves(tmp_path: Path) -> None:
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Polygon, Rectangle

    t, r, truth = step_run(start=2.0, end=3.0)
    band = Band.from_residuals(r[t < 1.999])
    found = detect(t, r, band, hold=0.02)
    path = tmp_path / "residuals.png"
    fig = plot_residuals(t, r, band, found, truth, path=path)
    assert len(fig.axes) == N_JOINTS
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    joint4 = fig.axes[STEP_JOINT]
    lines = joint4.get_lines()
    dashed = [line for line in lines if line.get_linestyle() == "--"]
    assert len(dashed) == 1 and np.array_equal(dashed[0].get_ydata(), truth[:, STEP_JOINT])
    vertical = [line for line in lines if np.ptp(np.asarray(line.get_xdata(), dtype=float)) == 0]
    assert len(vertical) == 1 and vertical[0].get_xdata()[0] == pytest.approx(found.time)
    shaded = [p for p in joint4.patches if isinstance(p, (Polygon, Rectangle, PolyCollection))]
    assert len(shaded) == 1 + len(found.intervals)  # the band and each collision
    plt.close(fig)
    bare = plot_residuals(t, r)
    assert len(bare.axes) == N_JOINTS and all(len(axis.patches) == 0 for axis in bare.axes)
    plt.close(bare)


# ----- errors ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("lower", "upper", "message"),
    [
        ([0.0, 1.0], [1.0], "lower has 2 joints, upper has 1"),
        ([0.0, 2.0], [1.0, 1.0], "joint 2 has lower 2 > upper 1"),
        ([0.0, np.nan], [1.0, 1.0], "lower must be finite: joint 2"),
        ([0.0, 0.0], [1.0, np.inf], "upper must be finite: joint 2"),
        ([[0.0]], [[1.0]], r"lower must hold one number per joint"),
        ([], [], r"lower must hold one number per joint"),
        ("abc", [1.0], "lower must be an array of numbers"),
    ],
)
def test_band_errors(lower: object, upper: object, message: str) -> None:
    with pytest.raises(ModelError, match=message):
        Band(lower, upper)  # type: ignore[arg-type]


def test_band_constructor_errors() -> None:
    with pytest.raises(ModelError, match="values must be non-negative thresholds: joint 3 has -1"):
        Band.fixed([1.0, 1.0, -1.0])
    with pytest.raises(ModelError, match="values must be finite: joint 1"):
        Band.fixed([np.nan])
    r = np.random.default_rng(0).normal(size=(100, 3))
    for quantile in (0.5, 1.0, 0.3, 1.2):
        with pytest.raises(ModelError, match=r"quantile must lie in \(0.5, 1\)"):
            Band.from_residuals(r, quantile=quantile)
    with pytest.raises(ModelError, match="quantile must be a number"):
        Band.from_residuals(r, quantile="high")  # type: ignore[arg-type]
    with pytest.raises(ModelError, match="quantile must be finite"):
        Band.from_residuals(r, quantile=float("nan"))
    with pytest.raises(ModelError, match="margin must be at least 1"):
        Band.from_residuals(r, margin=0.9)
    bad = r.copy()
    bad[42, 2] = np.nan
    with pytest.raises(ModelError, match=r"r_free must be finite: sample 42, joint 3 \(column 2\) is nan"):
        Band.from_residuals(bad)
    with pytest.raises(ModelError, match=r"r_free must have shape \(N, n\)"):
        Band.from_residuals(r[:, 0])
    with pytest.raises(ModelError, match="quantiles need at least 2"):
        Band.from_residuals(r[:1])
    band = Band.fixed([1.0, 1.0, 1.0])
    with pytest.raises(ModelError, match=r"r must have shape \(\.\.\., 3\)"):
        band.contains(np.zeros(2))
    with pytest.raises(ModelError, match="r must be finite: sample 1, joint 2 is nan"):
        band.contains(np.array([[0.0, 0.0, 0.0], [0.0, np.nan, 0.0]]))
    with pytest.raises(ModelError, match="factor must be non-negative"):
        band.scaled(-0.5)


def test_detect_errors() -> None:
    t = np.arange(10) * DT
    r = np.zeros((10, 3))
    band = Band.fixed([1.0, 1.0, 1.0])
    backwards = t.copy()
    backwards[4] = backwards[3]
    with pytest.raises(ModelError, match=r"t must strictly increase: sample 4 is t = 0\.003 s after t = 0\.003 s"):
        detect(backwards, r, band)
    with pytest.raises(ModelError, match="t must be finite: sample 2"):
        detect(np.where(t == t[2], np.nan, t), r, band)
    with pytest.raises(ModelError, match=r"t must be the sample times, shape \(N,\)"):
        detect(t[:, None], r, band)
    with pytest.raises(ModelError, match="r has 9 samples, the time t has 10"):
        detect(t, r[:9], band)
    with pytest.raises(ModelError, match=r"r has 2 columns \(joints\); the band has 3 joints"):
        detect(t, r[:, :2], band)
    with pytest.raises(ModelError, match=r"r must have shape \(N, n\)"):
        detect(t, r[:, 0], band)
    bad = r.copy()
    bad[7, 1] = np.nan
    with pytest.raises(ModelError, match=r"r must be finite: sample 7 \(t = 0.007 s\), joint 2 \(column 1\) is nan"):
        detect(t, bad, band)
    with pytest.raises(ModelError, match="band must be a Band"):
        detect(t, r, [1.0, 1.0, 1.0])  # type: ignore[arg-type]
    for release in (0.0, 1.5, -0.5):
        with pytest.raises(ModelError, match=r"release must lie in \(0, 1\]"):
            detect(t, r, band, release=release)
    with pytest.raises(ModelError, match="hold must be a non-negative time"):
        detect(t, r, band, hold=-0.01)
    with pytest.raises(ModelError, match="hold must be finite"):
        detect(t, r, band, hold=float("inf"))


def test_plot_errors(tmp_path: Path) -> None:
    t = np.arange(10) * DT
    r = np.zeros((10, 3))
    with pytest.raises(ModelError, match="band must be a Band of 3 joints as r has, got a Band of 2 joints"):
        plot_residuals(t, r, band=Band.fixed([1.0, 1.0]))
    other = detect(t[:5], r[:5], Band.fixed([1.0, 1.0, 1.0]))
    with pytest.raises(ModelError, match="detection must be detect's result on this t and r"):
        plot_residuals(t, r, detection=other)
    with pytest.raises(ModelError, match=r"truth has 2 columns \(joints\); r has 3 joints"):
        plot_residuals(t, r, truth=np.zeros((10, 2)))
    with pytest.raises(ModelError, match="r must be finite: sample 3"):
        plot_residuals(t, np.where(np.arange(10)[:, None] == 3, np.nan, r))
    with pytest.raises(ModelError, match="t must strictly increase"):
        plot_residuals(t[::-1], r)
    with pytest.raises(ModelError):
        plot_residuals(t, r, path=tmp_path / "missing" / "figure.png")
    assert isinstance(other, Detection)
