"""Robot logs and their preprocessing: the Log's checks, the readers, resampling, filtering, differentiation,
parallel filtering and decimation, against logs of known exact motion (sums of sines) and the Panda log of
Gaz et al. (2019) when ../shared is present."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas
import pytest
from numpy.testing import assert_allclose

import armdyn
import armdyn as ad
from armdyn.errors import ModelError
from armdyn.identification.log import (
    MIN_LOG_SAMPLES,
    Log,
    read_csv,
    read_gaz_panda,
    read_log,
    read_npz,
    read_parquet,
)
from armdyn.identification.preprocess import (
    Prepared,
    derivatives,
    excitation_bandwidth,
    lowpass,
    parallel_filter,
    prepare,
    resample,
)
from tests.helpers import URDFS

REPOSITORY = Path(armdyn.__file__).resolve().parents[2]  # src/armdyn/__init__.py
PANDA_LOG = REPOSITORY / ".." / "shared" / "data" / "panda-gaz2019"  # ../shared beside the repository, GPL-3

# ----- logs of a known motion: q_j(t) = sum_k a_jk sin(2 pi f_jk t + p_jk) ---------------------------------------
AMPLITUDES = np.array([[0.6, 0.2], [0.4, 0.3], [0.8, 0.1]])
FREQUENCIES = np.array([[0.3, 1.1], [0.5, 0.9], [0.2, 1.4]])  # Hz
PHASES = np.array([[0.1, 0.7], [1.3, -0.4], [-0.6, 2.0]])
OFFSETS = np.array([0.2, -1.0, 0.5])


def motion(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The exact q, qd, qdd (N, 3) of the sum of sines at times t."""
    w = 2 * np.pi * FREQUENCIES
    angle = w[None] * t[:, None, None] + PHASES[None]
    q = OFFSETS + (AMPLITUDES * np.sin(angle)).sum(axis=2)
    qd = (AMPLITUDES * w * np.cos(angle)).sum(axis=2)
    qdd = -(AMPLITUDES * w**2 * np.sin(angle)).sum(axis=2)
    return q, qd, qdd


def torque(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """A smooth torque of the motion (a linear law: filtering it commutes with filtering its terms)."""
    return 2.0 * qdd + 0.5 * qd + 3.0 * q


def sine_log(rate: float = 1000.0, duration: float = 10.0, jitter: float = 0.0, seed: int = 0, **extra) -> Log:
    """A log of the known motion sampled at k / rate plus a uniform jitter of up to ``jitter`` s."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / rate)
    t = t + rng.uniform(-jitter, jitter, t.shape)
    q, qd, qdd = motion(t)
    return Log(t=t, q=q, qd=qd, tau=torque(q, qd, qdd), source="sines.csv", **extra)


def interior(x: np.ndarray, rate: float, seconds: float = 0.5) -> np.ndarray:
    k = int(seconds * rate)
    return x[k:-k]


# ----- derivatives ------------------------------------------------------------------------------------------------
def test_central_differences_are_close_and_their_error_shrinks_as_the_square_of_the_step() -> None:
    errors = []
    for rate in (100.0, 200.0, 400.0):
        t = np.arange(0.0, 10.0, 1.0 / rate)
        q, qd, qdd = motion(t)
        qd_est, qdd_est = derivatives(q, rate)
        errors.append((np.abs(qd_est - qd).max(), np.abs(interior(qdd_est - qdd, rate, 0.05)).max()))
        assert np.abs(qd_est - qd).max() < 2e-3 * np.abs(qd).max()
    errors = np.array(errors)
    ratios = errors[:-1] / errors[1:]
    assert np.all((ratios > 3.5) & (ratios < 4.5)), ratios  # second order: halving the step quarters the error


def test_prepare_recovers_the_exact_derivatives_of_a_clean_log() -> None:
    log = sine_log(rate=1000.0, duration=12.0)
    prepared = prepare(log, decimate=1, trim=0.5)
    q, qd, qdd = motion(prepared.t)
    assert prepared.factor == 1 and prepared.full is None and prepared.undecimated is prepared
    assert np.abs(prepared.q - q).max() < 1e-7
    assert np.abs(prepared.qd - qd).max() < 1e-4 * np.abs(qd).max()
    assert np.abs(prepared.qdd - qdd).max() < 1e-3 * np.abs(qdd).max()
    assert np.abs(prepared.tau - torque(q, qd, qdd)).max() < 1e-3 * np.abs(prepared.tau).max()


def test_prepare_filters_noise_out_of_the_derivatives() -> None:
    log = sine_log(rate=1000.0, duration=12.0)
    noisy = Log(t=log.t, q=log.q + np.random.default_rng(1).normal(0, 1e-4, log.q.shape), tau=log.tau)
    prepared = prepare(noisy, trim=0.5)
    _, qd, qdd = motion(prepared.t)
    raw_qd, _ = derivatives(noisy.q, 1000.0)
    assert np.sqrt(np.mean((raw_qd - log.qd) ** 2)) > 0.05  # unfiltered differences amplify the noise
    assert np.sqrt(np.mean((prepared.qd - qd) ** 2)) < 2e-3
    assert np.sqrt(np.mean((prepared.qdd - qdd) ** 2)) < 0.03 * np.sqrt(np.mean(qdd**2))


def test_prepare_uses_the_measured_velocity_when_asked() -> None:
    log = sine_log(rate=500.0)
    prepared = prepare(log, use_measured_velocity=True, decimate=1, trim=0.5)
    _, qd, qdd = motion(prepared.t)
    assert np.abs(prepared.qd - qd).max() < 1e-4 * np.abs(qd).max()
    assert np.abs(prepared.qdd - qdd).max() < 1e-2 * np.abs(qdd).max()
    with pytest.raises(ModelError, match=r"sines.csv: use_measured_velocity needs the log's velocities"):
        prepare(Log(t=log.t, q=log.q, tau=log.tau, source="sines.csv"), use_measured_velocity=True)


def test_prepare_of_a_jittered_arm_log_satisfies_the_robot_equation() -> None:
    """Jittered samples of an arm's exact inverse dynamics, 1% torque noise: after preparation the filtered
    torque matches the inverse dynamics of the filtered positions and their derivatives; Gautier's parallel
    filter of the regressor and of the torque keeps tau = W phi."""
    arm = ad.models.puma560().without_friction()
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 8.0, 1e-3) + rng.uniform(-4.5e-4, 4.5e-4, 8000)
    q6, qd6, qdd6 = (np.concatenate([x, x[:, :3]], axis=1) * 0.8 for x in motion(t))
    tau = arm.inverse_dynamics(q6, qd6, qdd6)
    tau += rng.normal(0, 0.01 * np.sqrt(np.mean(tau**2, axis=0)), tau.shape)
    prepared = prepare(Log(t=t, q=q6, tau=tau, source="puma.npz"), trim=0.3)
    model = arm.inverse_dynamics(prepared.q, prepared.qd, prepared.qdd)
    misfit = np.sqrt(np.mean((prepared.tau - model) ** 2, axis=0)) / np.sqrt(np.mean(model**2, axis=0))
    assert np.all(misfit < 0.005), misfit  # the noise left after the filter
    full = prepared.undecimated
    W = arm.regressor(full.q, full.qd, full.qdd)
    filtered_W, filtered_tau = prepared.parallel_filter(W), prepared.parallel_filter(full.tau)
    assert filtered_W.shape == (prepared.t.shape[0], 6, 84)
    exact = prepared.parallel_filter(arm.inverse_dynamics(full.q, full.qd, full.qdd))
    assert_allclose(filtered_W @ arm.parameters(), exact, atol=1e-9 * np.abs(exact).max())
    misfit = np.sqrt(np.mean((filtered_tau - exact) ** 2, axis=0)) / np.sqrt(np.mean(exact**2, axis=0))
    assert np.all(misfit < 0.005), misfit


# ----- resampling -------------------------------------------------------------------------------------------------
def test_jittered_timestamps_are_resampled_onto_a_uniform_grid() -> None:
    log = sine_log(rate=1000.0, jitter=4.9e-4, seed=2)
    assert abs(log.sample_rate - 1000.0) < 10.0
    linear = resample(log)
    steps = np.diff(linear.t)
    assert_allclose(steps, 1.0 / log.sample_rate, rtol=1e-9)
    assert linear.t[0] == log.t[0] and linear.t[-1] <= log.t[-1]
    q, qd, qdd = motion(linear.t)
    step = np.diff(log.t).max()
    bound = step**2 / 8 * np.abs(qdd).max(axis=0)  # the linear interpolation's error bound
    assert np.all(np.abs(linear.q - q).max(axis=0) <= bound)
    assert np.abs(linear.tau - torque(q, qd, qdd)).max() < 1e-4 * np.abs(linear.tau).max()
    cubic = resample(log, method="cubic")
    assert np.abs(cubic.q - q).max() < 1e-3 * bound.min()
    half = resample(log, rate=500.0)
    assert_allclose(np.diff(half.t), 2e-3, rtol=1e-9)
    assert half.samples == pytest.approx(log.samples / 2, abs=2)


def test_resampling_refuses_a_bad_method_or_too_coarse_a_grid() -> None:
    log = sine_log(rate=100.0, duration=1.0)
    with pytest.raises(ModelError, match=r"'linear' or 'cubic'"):
        resample(log, method="quadratic")
    with pytest.raises(ModelError, match=f"gives 10 samples; a log needs at least {MIN_LOG_SAMPLES}"):
        resample(log, rate=10.0)


# ----- bandwidth and filters ---------------------------------------------------------------------------------------
def test_excitation_bandwidth_of_a_known_multi_sine() -> None:
    rate, t = 200.0, np.arange(0.0, 40.0, 1 / 200.0)
    resolution = rate / t.shape[0]
    q = np.stack([np.sin(2 * np.pi * 0.2 * t) + np.sin(2 * np.pi * 1.5 * t), 2.0 * np.sin(2 * np.pi * 0.5 * t)], 1)
    assert abs(excitation_bandwidth(q, rate) - 1.5) <= 2 * resolution
    small = np.sin(2 * np.pi * 0.5 * t) + 0.05 * np.sin(2 * np.pi * 3.0 * t)  # 0.25% of the energy at 3 Hz
    assert abs(excitation_bandwidth(small, rate) - 0.5) <= 2 * resolution
    assert abs(excitation_bandwidth(small, rate, energy=0.999) - 3.0) <= 2 * resolution
    with pytest.raises(ModelError, match=r"no joint moves"):
        excitation_bandwidth(np.ones((100, 2)), rate)
    with pytest.raises(ModelError, match=r"energy must be a share strictly between 0 and 1"):
        excitation_bandwidth(q, rate, energy=1.0)


@pytest.mark.parametrize("ratio", [0.25, 1.0, 2.0])
def test_lowpass_is_zero_phase_with_the_squared_butterworth_gain(ratio: float) -> None:
    rate, cutoff, order = 1000.0, 10.0, 4
    t = np.arange(0.0, 20.0, 1 / rate)
    x = np.sin(2 * np.pi * ratio * cutoff * t)
    y = lowpass(np.stack([x, -x], axis=1)[:, :, None], cutoff, rate, order)
    assert y.shape == (t.shape[0], 2, 1)
    gain = 1.0 / (1.0 + ratio ** (2 * order))  # |H|^2: forward and backward
    assert_allclose(interior(y[:, 0, 0], rate, 2.0), gain * interior(x, rate, 2.0), atol=2e-3)
    assert_allclose(y[:, 1, 0], -y[:, 0, 0])


def test_parallel_filter_is_the_lowpass_decimated_and_keeps_linear_relations() -> None:
    rng = np.random.default_rng(4)
    rate, factor = 1000.0, 10
    cutoff = 0.8 * rate / (2 * factor)
    W = rng.normal(size=(3000, 3, 5)).cumsum(axis=0)
    phi = rng.normal(size=5)
    filtered = parallel_filter(W, rate, cutoff, factor)
    assert filtered.shape == (300, 3, 5)
    assert_allclose(filtered, lowpass(W, cutoff, rate)[::factor], atol=1e-10 * np.abs(W).max())
    assert_allclose(filtered @ phi, parallel_filter(W @ phi, rate, cutoff, factor), atol=1e-9 * np.abs(W).max())
    with pytest.raises(ModelError, match=r"above the decimated Nyquist frequency"):
        parallel_filter(W, rate, 60.0, factor)
    with pytest.raises(ModelError, match=r"decimation factor must be a whole number >= 1"):
        parallel_filter(W, rate, cutoff, 0)


def test_prepare_decimates_by_the_documented_rule_and_keeps_the_undecimated_samples() -> None:
    log = sine_log(rate=1000.0)
    prepared = prepare(log)
    bandwidth = excitation_bandwidth(resample(log).q, 1000.0)
    assert prepared.cutoff == pytest.approx(10 * bandwidth)
    assert prepared.factor == int(1000.0 // (5 * prepared.cutoff)) > 1
    assert prepared.rate == pytest.approx(1000.0 / prepared.factor)
    assert prepared.rate >= 5 * prepared.cutoff
    full = prepared.undecimated
    assert full.factor == 1 and prepared.log is log
    assert_allclose(prepared.q, full.q[:: prepared.factor])
    assert_allclose(prepared.tau, full.tau[:: prepared.factor])
    assert full.t[0] >= log.t[0] + 0.1 - 1e-9 and full.t[-1] <= log.t[-1] - 0.1 + 1e-9
    assert prepared.decimation_cutoff == pytest.approx(0.8 * 1000.0 / (2 * prepared.factor))
    with pytest.raises(ModelError, match=r"one row per undecimated sample"):
        prepared.parallel_filter(prepared.q)


def test_preparing_twenty_thousand_samples_of_seven_joints_is_vectorized() -> None:
    """Not a timing test: a correct preparation of a 20,000 x 7 log (its cost is in the benchmarks)."""
    rng = np.random.default_rng(5)
    t = np.arange(20000) * 1e-3 + rng.uniform(-4e-4, 4e-4, 20000)
    q = np.concatenate([motion(t)[0], motion(t + 1.0)[0], motion(t + 2.0)[0][:, :1]], axis=1)
    log = Log(t=t, q=q, current=rng.normal(size=(20000, 7)))
    prepared = prepare(log)
    assert isinstance(prepared, Prepared) and prepared.q.shape[1] == 7
    assert prepared.tau is None and prepared.current is not None and prepared.effort is prepared.current


# ----- the Log's checks -------------------------------------------------------------------------------------------
def test_log_sizes_split_and_window() -> None:
    log = sine_log(rate=100.0, duration=10.0)
    assert (log.n, log.samples) == (3, 1000)
    assert log.duration == pytest.approx(9.99)
    assert log.sample_rate == pytest.approx(100.0)
    first, last = log.split(0.7)
    assert (first.samples, last.samples) == (700, 300)
    assert_allclose(np.concatenate([first.q, last.q]), log.q)
    assert first.t[-1] < last.t[0] and last.first_sample == 700
    part = log.window(2.0, 3.0)
    assert part.t[0] >= 2.0 and part.t[-1] <= 3.0 and part.samples in (100, 101)
    with pytest.raises(ModelError, match=r"strictly between 0 and 1"):
        log.split(1.0)
    with pytest.raises(ModelError, match=r"leaves a part of 10 samples"):
        log.split(0.01)
    with pytest.raises(ModelError, match=r"the window .* holds 0 samples"):
        log.window(20.0, 30.0)
    with pytest.raises(ValueError, match=r"read-only"):
        log.q[0, 0] = 1.0


def test_nan_names_the_file_the_column_and_the_sample() -> None:
    log = sine_log(rate=100.0)
    tau = log.tau.copy()
    tau[41, 2] = np.nan
    tau[90, 0] = np.inf
    columns = {"tau": ("torque_a", "torque_b", "torque_c")}
    with pytest.raises(ModelError, match=r"sines.csv: column 'torque_c' \(tau of joint 3\) is nan at sample 41 "):
        Log(t=log.t, q=log.q, tau=tau, source="sines.csv", columns=columns)
    with pytest.raises(ModelError, match=r"is nan at sample 41 .*1 more NaN or infinite"):
        Log(t=log.t, q=log.q, tau=tau, source="sines.csv")
    _, last = log.split(0.5)
    q = last.q.copy()
    q[3, 1] = np.inf
    with pytest.raises(ModelError, match=r"column 'q\[1\]' \(q of joint 2\) is inf at sample 503"):
        Log(t=last.t, q=q, tau=last.tau, source="sines.csv", first_sample=last.first_sample)


def test_time_not_increasing_names_the_sample() -> None:
    log = sine_log(rate=100.0)
    t = log.t.copy()
    t[57] = t[56]
    with pytest.raises(ModelError, match=r"sines.csv: the time 't' does not strictly increase at sample 57"):
        Log(t=t, q=log.q, tau=log.tau, source="sines.csv")


def test_unequal_missing_or_too_few_columns_and_samples_are_refused() -> None:
    log = sine_log(rate=100.0)
    with pytest.raises(ModelError, match=r"unequal lengths: q has 999 samples, the time 't' has 1000"):
        Log(t=log.t, q=log.q[:-1], tau=log.tau[:-1])
    with pytest.raises(ModelError, match=r"unequal lengths: tau has 999 samples"):
        Log(t=log.t, q=log.q, tau=log.tau[:-1])
    with pytest.raises(ModelError, match=r"tau must have one column per joint, shape \(N, 3\)"):
        Log(t=log.t, q=log.q, tau=np.ones((1000, 4)))
    with pytest.raises(
        ModelError, match=r"exactly one of the measured torques tau and the motor currents; it has both"
    ):
        Log(t=log.t, q=log.q, tau=log.tau, current=log.tau)
    with pytest.raises(ModelError, match=r"it has neither"):
        Log(t=log.t, q=log.q)
    with pytest.raises(ModelError, match=f"10 samples; a log needs at least {MIN_LOG_SAMPLES}"):
        Log(t=log.t[:10], q=log.q[:10], tau=log.tau[:10])
    with pytest.raises(ModelError, match=r"3 joint names given for 2 joints"):
        Log(t=log.t, q=log.q[:, :2], tau=log.tau[:, :2], joint_names=["a", "b", "c"])


def test_angles_in_degrees_are_refused_by_check_arm() -> None:
    arm = ad.models.puma560()
    t = np.arange(0.0, 5.0, 0.01)
    q = 0.1 * np.sin(np.outer(t, np.arange(1, 7)))
    tau = np.zeros_like(q)
    Log(t=t, q=q, tau=tau).check_arm(arm)
    with pytest.raises(ModelError, match=r"the log has 5 joints .* the arm '.*' has 6"):
        Log(t=t, q=q[:, :5], tau=tau[:, :5]).check_arm(arm)
    large = q.copy()
    large[:, 1] = np.degrees(0.8 + 0.5 * np.sin(t))  # up to 74 "rad": beyond a full turn
    with pytest.raises(
        ModelError, match=r"joint '.*', column 'q\[1\]' \(q of joint 2\), reaches .* beyond a full turn"
    ):
        Log(t=t, q=large, tau=tau).check_arm(arm)
    small = q.copy()
    small[:, 3] = np.degrees(small[:, 3])  # +-5.7 "rad": within a turn, beyond the limits of [-1.92, 2.97] rad
    with pytest.raises(ModelError, match=r"beyond the joint's limits .* the angles look like degrees"):
        Log(t=t, q=small, tau=tau).check_arm(arm)


# ----- readers ----------------------------------------------------------------------------------------------------
def frame_of(log: Log, names: dict[str, list[str]]) -> pandas.DataFrame:
    data = {names["t"][0]: log.t}
    for field in ("q", "qd", "tau"):
        data.update(dict(zip(names[field], getattr(log, field).T, strict=True)))
    return pandas.DataFrame(data)


def assert_same_log(read: Log, log: Log) -> None:
    for field in ("t", "q", "qd", "tau"):
        assert_allclose(getattr(read, field), getattr(log, field), rtol=1e-15, atol=0)
    assert read.current is None and read.q_desired is None


def test_csv_round_trips_with_a_column_map_and_by_the_default_names(tmp_path: Path) -> None:
    log = sine_log(rate=100.0)
    path = tmp_path / "robot.csv"
    names = {"t": ["time"], "q": ["pos1", "pos2", "pos3"], "qd": ["v_a", "v_b", "v_c"], "tau": ["T1", "T2", "T3"]}
    frame_of(log, names).to_csv(path, index=False, float_format="%.17g")
    read = read_csv(path, {"t": "time", "q": "pos{j}", "qd": ["v_a", "v_b", "v_c"], "tau": "T{j}"})
    assert_same_log(read, log)
    assert read.source == str(path) and read.columns["tau"] == ("T1", "T2", "T3")
    default = tmp_path / "default.csv"
    names = {"t": ["time"], "q": ["q_1", "q_2", "q_3"], "qd": ["qd1", "qd2", "qd3"], "tau": ["tau1", "tau2", "tau3"]}
    frame_of(log, names).to_csv(default, index=False, float_format="%.17g")
    assert_same_log(read_log(default), log)


def test_csv_errors_name_the_file_the_column_and_the_sample(tmp_path: Path) -> None:
    log = sine_log(rate=100.0)
    names = {"t": ["t"], "q": ["q1", "q2", "q3"], "qd": ["qd1", "qd2", "qd3"], "tau": ["tau1", "tau2", "tau3"]}
    frame = frame_of(log, names)
    path = tmp_path / "robot.csv"
    frame.drop(columns="tau3").to_csv(path, index=False)
    with pytest.raises(ModelError, match=r"robot.csv: no column 'tau3' .* the columns present are 't', 'q1'"):
        read_csv(path, {"tau": "tau{j}"})
    with pytest.raises(ModelError, match=r"robot.csv: 2 columns tau1..tau2 for tau, but q has 3 joints"):
        read_csv(path)
    with pytest.raises(ModelError, match=r"the column map names 'torque', not a field of a log"):
        read_csv(path, {"torque": "tau{j}"})
    with pytest.raises(ModelError, match=r"the column map's 'tau' is 'tau\{i\}'; in a pattern \{j\} is the only"):
        read_csv(path, {"tau": "tau{i}"})
    holes = frame.copy()
    holes.loc[41, "tau2"] = np.nan
    holes.to_csv(path, index=False)
    with pytest.raises(ModelError, match=r"robot.csv: column 'tau2' \(tau of joint 2\) is nan at sample 41"):
        read_csv(path)
    words = frame.astype(object)
    words.loc[12, "q3"] = "twelve"
    words.to_csv(path, index=False)
    with pytest.raises(ModelError, match=r"robot.csv: column 'q3' holds 'twelve' at sample 12, not a number"):
        read_csv(path)
    frame.drop(columns="t").to_csv(path, index=False)
    with pytest.raises(ModelError, match=r"no column for the time \('t' or 'time'"):
        read_csv(path)
    with pytest.raises(ModelError, match=r"no such file"):
        read_csv(tmp_path / "absent.csv")


def test_npz_round_trips_by_whole_fields_and_by_columns(tmp_path: Path) -> None:
    log = sine_log(rate=100.0)
    path = tmp_path / "robot.npz"
    np.savez(path, t=log.t, q=log.q, qd=log.qd, tau=log.tau)
    assert_same_log(read_npz(path), log)
    mapped = tmp_path / "mapped.npz"
    np.savez(mapped, stamp=log.t, positions=log.q, qd=log.qd, **{f"torque{j + 1}": log.tau[:, j] for j in range(3)})
    read = read_log(mapped, {"t": "stamp", "q": "positions", "tau": "torque{j}"})
    assert_same_log(read, log)
    with pytest.raises(ModelError, match=r"mapped.npz: no column 'velocity' \(the map's qd\)"):
        read_npz(mapped, {"t": "stamp", "q": "positions", "qd": "velocity", "tau": "torque{j}"})


def test_parquet_round_trips(tmp_path: Path) -> None:
    pytest.importorskip("pyarrow", reason="pyarrow reads Parquet")
    log = sine_log(rate=100.0)
    path = tmp_path / "robot.parquet"
    names = {"t": ["t"], "q": ["q1", "q2", "q3"], "qd": ["qd1", "qd2", "qd3"], "tau": ["tau1", "tau2", "tau3"]}
    frame_of(log, names).to_parquet(path, index=False)
    assert_same_log(read_parquet(path), log)
    assert_same_log(read_log(path), log)
    current = frame_of(log, names).rename(columns={f"tau{j}": f"i{j}" for j in (1, 2, 3)})
    current.to_parquet(path, index=False)
    read = read_log(path)
    assert read.tau is None and read.effort_name == "current"
    assert_allclose(read.current, log.tau, rtol=1e-15, atol=0)


def test_read_log_refuses_an_unknown_format(tmp_path: Path) -> None:
    path = tmp_path / "robot.xlsx"
    path.write_text("")
    with pytest.raises(ModelError, match=r"robot.xlsx: unknown log format '.xlsx'; the formats read are .csv"):
        read_log(path)
    with pytest.raises(ModelError, match=r"is a folder without exciting_traj_time.txt"):
        read_log(tmp_path)


def write_gaz_folder(folder: Path, log: Log) -> None:
    """A log in the text format of Gaz et al.: one number a line, a sample's joints on consecutive lines."""
    folder.mkdir()
    np.savetxt(folder / "exciting_traj_time.txt", log.t, fmt="%.17g")
    for name, value in (("positions", log.q), ("velocity", log.qd), ("torques", log.tau)):
        np.savetxt(folder / f"exciting_traj_{name}.txt", value.ravel(), fmt="%.17g")


def test_the_gaz_format_round_trips_and_its_errors_name_the_file(tmp_path: Path) -> None:
    t = np.arange(0.0, 2.0, 1e-3)
    q = np.concatenate([motion(t)[0], motion(t + 1.0)[0], motion(t + 2.0)[0][:, :1]], axis=1)
    log = Log(t=t, q=q, qd=np.gradient(q, t, axis=0), tau=2 * q)
    folder = tmp_path / "gaz"
    write_gaz_folder(folder, log)
    read = read_log(folder)
    assert_same_log(read, log)
    assert read.joint_names == tuple(f"panda_joint{j}" for j in range(1, 8))
    lines = (folder / "exciting_traj_torques.txt").read_text().splitlines()
    (folder / "exciting_traj_torques.txt").write_text("\n".join(lines[:-3]) + "\n")
    with pytest.raises(ModelError, match=r"unequal lengths: exciting_traj_torques.txt holds 13997 numbers"):
        read_gaz_panda(folder)
    lines[7 * 30 + 4] = "nan"
    (folder / "exciting_traj_torques.txt").write_text("\n".join(lines) + "\n")
    with pytest.raises(ModelError, match=r"column 'exciting_traj_torques.txt, joint 5' .* is nan at sample 30"):
        read_gaz_panda(folder)
    lines[7 * 30 + 4] = "1.5e"
    (folder / "exciting_traj_torques.txt").write_text("\n".join(lines) + "\n")
    with pytest.raises(ModelError, match=r"exciting_traj_torques.txt: line 215 is '1.5e', not a number"):
        read_gaz_panda(folder)
    (folder / "exciting_traj_velocity.txt").unlink()
    with pytest.raises(ModelError, match=r"no file exciting_traj_velocity.txt; the folder holds"):
        read_gaz_panda(folder)
    with pytest.raises(ModelError, match=r"takes no column map"):
        read_log(folder, {"q": "q{j}"})


# ----- the Panda log of Gaz et al. (2019) -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def panda_log() -> Log:
    if not PANDA_LOG.is_dir():
        pytest.skip(f"the Panda log of Gaz et al. is not at {PANDA_LOG.resolve()} (../shared beside the repository)")
    return read_gaz_panda(PANDA_LOG)


def test_the_panda_log_reads_and_its_prepared_velocity_matches_the_robots(panda_log: Log) -> None:
    log = panda_log
    assert (log.samples, log.n) == (20544, 7)
    assert np.all(np.diff(log.t) > 0)
    assert log.sample_rate == pytest.approx(1000.0, rel=1e-3)
    prepared = prepare(log, decimate=1)
    reported = np.stack([np.interp(prepared.t, log.t, log.qd[:, j]) for j in range(7)], axis=1)
    rms = np.sqrt(np.mean((prepared.qd - reported) ** 2, axis=0))
    scale = np.sqrt(np.mean(reported**2, axis=0))
    assert np.all(rms < 0.02), rms  # rad/s
    assert np.all(rms < 0.03 * scale), rms / scale


def test_the_panda_log_fits_the_panda_in_radians_and_not_in_degrees(panda_log: Log) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the URDF's mimic finger joint
        arm = ad.load_urdf(URDFS["panda"]).reduced({"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0})
    panda_log.check_arm(arm)
    degrees = Log(t=panda_log.t, q=np.degrees(panda_log.q), tau=panda_log.tau, source=panda_log.source)
    with pytest.raises(ModelError, match=r"panda_joint1.* the angles look like degrees"):
        degrees.check_arm(arm)


def test_bad_cutoffs_are_refused() -> None:
    log = sine_log(rate=1000.0, duration=2.0)
    for cutoff in (0.0, -1.0, 500.0, 800.0, float("nan")):
        with pytest.raises(ModelError, match=r"cut-off frequency must be between 0 and the Nyquist frequency"):
            lowpass(log.q, cutoff, 1000.0)
    with pytest.raises(ModelError, match=r"sines.csv: the cut-off frequency must be between 0 and .* 500 Hz"):
        prepare(log, cutoff=600.0)
    with pytest.raises(ModelError, match=r"trim must be a number of seconds >= 0"):
        prepare(log, trim=-0.1)
    with pytest.raises(ModelError, match=r"trimming 1 s from each end of 1.999 s .* leaves 0 samples"):
        prepare(log, trim=1.0)
