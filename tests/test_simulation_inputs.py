"""Bad inputs of simulate, load_urdf and the command line: a correct result, or an error naming
the argument (one line on stderr and exit code 2 for a command), never a raw exception, a
MemoryError or a read that does not end."""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_array_equal

import armdyn as ad
from armdyn import control, memory, simulation, trajectories
from armdyn.simulation import PythonLoopWarning, simulate
from tests.helpers import assert_one_error_line, invoke

ARM = ad.models.two_link_planar()


def run(**options: object) -> simulation.Result:
    """simulate on the two-link arm for 10 ms, without the Python loop's warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        return simulate(ARM, **{"t_final": 0.01, **options})


def refused(match: str, error: type[Exception] = ad.ModelError, **options: object) -> None:
    with pytest.raises(error, match=match):
        run(**options)


# ----- simulate: methods ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["rk4", "RK4", "rk45", "RK45", "radau", "Radau", "RADAU", "lsoda", "LSODA", "Bdf"])
def test_methods_are_taken_in_any_case(method: str) -> None:
    result = run(controller=control.PID(10.0, 2.0), method=method)
    assert result.info["method"].startswith(method.lower()) and len(result.t) == 11


@pytest.mark.parametrize("method", ["euler", "", "RK4 ", b"rk4", None, 4, np.float64(1.0)])
def test_unknown_methods_are_refused_listing_the_valid_ones(method: object) -> None:
    refused(r"method must be 'rk4' or one of \('rk45', 'rk23', 'dop853', 'radau', 'bdf', 'lsoda'\)", method=method)


# ----- simulate: t_final and dt ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "samples"),
    [
        ({"t_final": 1e9}, "1e+12 samples"),
        ({"dt": 1e-12}, "1e+10 samples"),
        ({"t_final": 1e6, "dt": 1e-3}, "1e+09 samples"),
        ({"dt": 1e-300}, "1e+298 samples"),
        ({"t_final": 1e14, "dt": 1e-300}, "inf samples"),
    ],
)
def test_enormous_runs_are_refused_before_anything_is_allocated(options: dict, samples: str) -> None:
    refused(
        rf"t_final = .* s with dt = .* s is {re.escape(samples)}, whose record needs .*B \(at most 200,000,000",
        **options,
    )


def test_a_run_beyond_the_memory_available_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(memory, "available", lambda: 100_000)
    assert len(run(t_final=1.0).t) == 1001  # 1001 samples of 88 bytes fit
    refused(r"t_final = 5 s with dt = 0.001 s is 5001 samples, .* 97.7 KiB of memory is available", t_final=5.0)


@pytest.mark.parametrize("name", ["t_final", "dt"])
@pytest.mark.parametrize("value", [0.0, -1.0, np.nan, np.inf, 1e16, 1e300, 10**400, None, "0.1", b"1", True, [0.1]])
def test_times_must_be_positive_numbers_below_1e15(name: str, value: object) -> None:
    refused(rf"{name} must be a positive number of seconds, below 1e\+15, got", **{name: value})


@pytest.mark.parametrize("method", ["rk4", "rk45", "radau"])
def test_a_step_longer_than_t_final_is_refused_with_every_method(method: str) -> None:
    """Before, dt = 0.5 over t_final = 0.01 gave the start alone, silently."""
    with pytest.raises(ad.ModelError, match=r"not a whole number of steps .* nearest valid t_final is 0.5 s"):
        run(controller=control.PID(10.0, 2.0), dt=0.5, method=method, q0=[0.1, 0.2])


def test_times_of_other_number_types_give_the_same_run() -> None:
    reference = run(controller=control.PID(10.0, 2.0), t_final=0.02, dt=0.002)
    for t_final, dt in ((np.float64(0.02), np.float64(0.002)), (np.array(0.02), 0.002)):
        result = run(controller=control.PID(10.0, 2.0), t_final=t_final, dt=dt)
        assert_array_equal(result.q, reference.q)
        assert_array_equal(result.tau, reference.tau)


# ----- simulate: controllers, trajectories, progress, disturbance and events of the wrong kind ---------------
@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"controller": control.PID}, r"controller must be callable .* got the class PID itself"),
        ({"controller": control.Digital(control.PID, 0.002)}, "controller .* got the class PID itself"),
        ({"controller": control.Saturated(control.ComputedTorque, 5.0)}, "controller .* class ComputedTorque"),
        ({"controller": "pid"}, "controller must be callable .* got str"),
        ({"controller": 3.0}, "controller must be callable .* got float"),
        ({"controller": object()}, "controller must be callable .* got object"),
        ({"trajectory": trajectories.Sinusoid}, "trajectory must be None or a callable .* class Sinusoid"),
        ({"trajectory": "sine"}, "trajectory must be None or a callable .* got str"),
        ({"trajectory": 1.0}, "trajectory must be None or a callable .* got float"),
        ({"progress": "bar"}, "progress must be None or a callable .* got str"),
        ({"progress": 3}, "progress must be None or a callable .* got int"),
        ({"progress": float}, "progress must be None or a callable .* class float"),
        ({"disturbance": float}, "disturbance must be an array of numbers"),
        ({"disturbance": [[0.5, 0.5], [0.5]]}, "disturbance must be an array of numbers"),
        ({"disturbance": 10**400}, "disturbance must be finite"),
        ({"disturbance": b"abc"}, "disturbance must be an array of numbers"),
    ],
)
def test_arguments_of_the_wrong_kind_are_refused_by_name(options: dict, match: str) -> None:
    refused(match, **options)


@pytest.mark.parametrize(
    ("events", "match"),
    [
        (None, "events must be a sequence of"),
        (5, "events must be a sequence of"),
        ("later", "events must be a sequence of"),
        (b"later", "events must be a sequence of"),
        ({0.5: ARM}, "events must be a sequence of"),
        (list, "events must be a sequence of"),
        ((0.5, ARM), "each event must be a"),
        ([(10**400, ARM)], "an event time must be a finite number"),
        ([(True, ARM)], "an event time must be a finite number"),
        ([(1j, ARM)], "an event time must be a finite number"),
    ],
)
def test_events_that_are_not_time_arm_pairs_are_refused(events: object, match: str) -> None:
    refused(match, events=events)


@pytest.mark.parametrize(
    ("value", "match"),
    [
        (None, "coulomb_smoothing must be a number, got None"),
        (b"abc", "coulomb_smoothing must be a number"),
        ([0.0], "coulomb_smoothing must be a number"),
        (np.array([0.0, 0.0]), "coulomb_smoothing must be a number"),
        (0j, "coulomb_smoothing must be real"),
        (-1.0, "coulomb_smoothing must be at least 0"),
        (np.nan, "coulomb_smoothing must be finite"),
        (10**400, "coulomb_smoothing must be a number"),
        ("AUTO", "coulomb_smoothing must be 'auto' or a number, got 'AUTO'"),
    ],
)
def test_coulomb_smoothing_must_be_auto_or_a_non_negative_number(value: object, match: str) -> None:
    refused(match, coulomb_smoothing=value)


@pytest.mark.parametrize("inner", [control.PID(1.0, 1.0), lambda *a: np.zeros(2)], ids=["compiled", "Python loop"])
def test_a_saturation_limit_per_joint_must_match_the_joints(inner: object) -> None:
    refused(
        r"the torque limit of Saturated must be one number, or 2 \(one per joint\), got limit = \[1.0, 1.0, 1.0\]",
        controller=control.Saturated(inner, [1.0, 1.0, 1.0]),
    )


# ----- simulate: what the user's callables return ---------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"trajectory": lambda t: (np.zeros(3),) * 3}, r"the trajectory's q_d at t = 0.0 must have shape \(2,\)"),
        ({"trajectory": lambda t: (np.zeros(2), np.full(2, np.nan), 0.0)}, "the trajectory's qd_d .* must be finite"),
        ({"trajectory": lambda t: (0.0, 0.0, np.array([0.0, 1j]))}, "the trajectory's qdd_d .* must be real"),
        ({"trajectory": lambda t: (np.zeros(2),) * 2}, r"the trajectory must return \(q_d, qd_d, qdd_d\)"),
        ({"trajectory": lambda t: None}, r"the trajectory must return \(q_d, qd_d, qdd_d\), got None"),
        ({"trajectory": lambda t: ("up", 0.0, 0.0)}, "the trajectory's q_d .* must be an array of numbers"),
        ({"controller": lambda *a: np.zeros(3)}, r"the controller's torque at t = 0.0 must have shape \(2,\)"),
        ({"controller": lambda *a: np.full(2, np.nan)}, "the controller's torque at t = 0.0 must be finite"),
        ({"disturbance": lambda t, q, qd: np.full(2, np.nan)}, "the disturbance at t = 0.0 must be finite"),
    ],
)
def test_what_a_callable_returns_is_checked_naming_the_callable(options: dict, match: str) -> None:
    refused(match, **{"controller": control.PID(10.0, 2.0), **options})


@pytest.mark.parametrize("method", ["rk4", "rk45"])
def test_a_trajectory_of_scalars_stands_for_every_joint(method: str) -> None:
    one = run(controller=control.PID(10.0, 2.0), trajectory=lambda t: (0.1, 0.0, 0.0), method=method)
    every = run(controller=control.PID(10.0, 2.0), trajectory=lambda t: (np.full(2, 0.1), np.zeros(2), np.zeros(2)),
                method=method)  # fmt: skip
    assert_array_equal(one.q, every.q)
    assert_array_equal(one.q_d, np.full((11, 2), 0.1))


# ----- load_urdf ---------------------------------------------------------------------------------------------------
URDF = """<?xml version="1.0"?>
<robot name="small">
  <link name="base"/>
  <link name="l1"><inertial><origin xyz="{com}" rpy="{com_rpy}"/><mass value="1.0"/>
    <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/><dynamics damping="{damping}" friction="{friction}"/>
  </joint>
</robot>
"""
SLOTS = {"com": "0.1 0 0", "com_rpy": "0 0 0", "xyz": "0 0 0.1", "rpy": "0 0 0", "axis": "0 0 1", "damping": "0.1",
         "friction": "0.05"}  # fmt: skip


def urdf(tmp_path: Path, **changes: str) -> Path:
    path = tmp_path / "small.urdf"
    path.write_text(URDF.format(**(SLOTS | changes)), encoding="utf-8")
    return path


@pytest.mark.parametrize("path", [3, None, object(), 1.5, ["small.urdf"]])
def test_a_path_that_is_no_path_is_a_type_error_naming_it(path: object) -> None:
    with pytest.raises(TypeError, match=r"path must be a str, bytes or os\.PathLike naming the URDF file, got"):
        ad.load_urdf(path)


def test_a_bytes_path_loads_the_file_it_names(tmp_path: Path) -> None:
    path = urdf(tmp_path)
    assert_array_equal(ad.load_urdf(os.fsencode(path)).packed, ad.load_urdf(path).packed)
    with pytest.raises(ad.ModelError, match=r"nosuch\.urdf: no such URDF file; check the path"):
        ad.load_urdf(b"nosuch.urdf")


def test_a_file_not_in_its_encoding_is_a_model_error(tmp_path: Path) -> None:
    path = tmp_path / "latin.urdf"
    path.write_bytes(URDF.format(**SLOTS).replace("small", "sm\u00e4ll").encode("latin-1"))
    with pytest.raises(ad.ModelError, match=r"latin\.urdf: cannot be read as XML .*UTF-8 unless"):
        ad.load_urdf(path)


@pytest.mark.parametrize("attribute", ["damping", "friction"])
@pytest.mark.parametrize("text", ["abc", "1 2", "0x10"])
def test_damping_and_friction_that_are_not_numbers_are_refused(tmp_path: Path, attribute: str, text: str) -> None:
    with pytest.raises(ad.ModelError, match=rf"small\.urdf: joint 'j1': <dynamics> {attribute} is '{text}', not a"):
        ad.load_urdf(urdf(tmp_path, **{attribute: text}))


VECTORS = {
    "xyz": "joint 'j1': <origin> xyz",
    "rpy": "joint 'j1': <origin> rpy",
    "axis": "joint 'j1': <axis> xyz",
    "com": "link 'l1': <inertial><origin> xyz",
    "com_rpy": "link 'l1': <inertial><origin> rpy",
}


@pytest.mark.parametrize("slot", list(VECTORS))
def test_vectors_of_four_numbers_are_refused_naming_the_element(tmp_path: Path, slot: str) -> None:
    with pytest.raises(ad.ModelError, match=rf"small\.urdf: {VECTORS[slot]} '1 2 3 4' holds 4 numbers"):
        ad.load_urdf(urdf(tmp_path, **{slot: "1 2 3 4"}))


@pytest.mark.parametrize("slot", list(VECTORS))
@pytest.mark.parametrize("value", ["1e300", "-1e16", "1e15"])
def test_vectors_of_1e15_or_more_are_refused_naming_the_element(tmp_path: Path, slot: str, value: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow on the way
        with pytest.raises(ad.ModelError, match=rf"{VECTORS[slot]} '{value} 0 1' holds a value of 1e\+15 or more"):
            ad.load_urdf(urdf(tmp_path, **{slot: f"{value} 0 1"}))


def test_vectors_below_1e15_still_load(tmp_path: Path) -> None:
    arm = ad.load_urdf(urdf(tmp_path, xyz="1e14 0 0.1"))
    assert arm.links[0].joint.placement[0, 3] == 1e14


@pytest.mark.parametrize(
    ("gravity", "match"),
    [
        (np.array([0.0, 0.0, -9.81 + 1e-20j]), "gravity must be real"),
        (np.array(0.5), r"gravity must be an array of numbers of shape \(3,\)"),
        (0.5, r"gravity must be an array of numbers of shape \(3,\)"),
        (["x", 0.0, -9.81], "gravity must be an array of numbers"),
        ([10**400, 0.0, 0.0], "gravity must be an array of numbers"),
        (np.full(3, "2020-01-01", dtype="datetime64[D]"), "gravity must be an array of numbers"),
        ([0.0, np.nan, -9.81], "gravity must be finite"),
    ],
)
def test_gravity_that_is_not_three_finite_numbers_is_refused(tmp_path: Path, gravity: object, match: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning
        with pytest.raises(ad.ModelError, match=match):
            ad.load_urdf(urdf(tmp_path), gravity=gravity)


# ----- the command line ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "options",
    [["--t-final", "1e9"], ["--dt", "1e-12"], ["--t-final", "1e6", "--dt", "1e-3"], ["--dt", "1e-300"]],
)
def test_cli_enormous_simulations_are_one_error_line(options: list[str]) -> None:
    assert_one_error_line(invoke("simulate", "two_link_planar", *options), "samples, whose record needs", "t_final")


def test_cli_simulate_takes_scipy_method_names() -> None:
    result = invoke("simulate", "two_link_planar", "--t-final", "0.05", "--method", "Radau")
    assert result.exit_code == 0, result.output
    assert "radau (compiled right-hand side)" in result.output


def test_cli_check_refuses_samples_beyond_its_cap() -> None:
    assert_one_error_line(invoke("check", "two_link_planar", "--samples", "1000000000000"), "--samples", "1000000")


@pytest.mark.parametrize("kind", ["device", "fifo", "folder"])
def test_cli_identify_reads_only_regular_files(tmp_path: Path, kind: str) -> None:
    path = Path("/dev/zero") if kind == "device" else tmp_path / kind
    if kind == "fifo":
        os.mkfifo(path)  # opening it would wait for a writer
    elif kind == "folder":
        path.mkdir()
    assert_one_error_line(invoke("identify", "two_link_planar", path), f"{path} is not a regular file")


def test_cli_identify_refuses_a_file_beyond_its_cap(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from armdyn import cli

    monkeypatch.setattr(cli, "CSV_BYTES", 64)
    path = tmp_path / "big.csv"
    path.write_text("q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2\n" + "0,0,0,0,0,0,0,0\n" * 10)
    assert_one_error_line(invoke("identify", "two_link_planar", path), "big.csv is larger than 64 bytes")


# ----- time and the summaries' window: nothing rounded or passed silently ---------------------------------
@pytest.mark.parametrize(("t_final", "dt", "nearest"), [(0.1, 1.0, "1 s"), (0.25, 0.1, "0.2 s or 0.3 s")])
def test_t_final_not_a_whole_number_of_steps_is_refused_with_the_nearest_valid_value(
    t_final: float, dt: float, nearest: str
) -> None:
    """Before, t_final = 0.1 with dt = 1 gave one sample at t = 0; now the error names the valid values, and
    a run at the value named ends there (the oracle: its last time)."""
    with pytest.raises(ad.ModelError, match=f"not a whole number of steps.*nearest valid t_final is {nearest}"):
        run(t_final=t_final, dt=dt)
    valid = float(nearest.split(" ")[0])
    assert run(t_final=valid, dt=dt).t[-1] == pytest.approx(valid, rel=1e-12)


def test_t_final_that_is_a_whole_number_of_steps_to_rounding_runs() -> None:
    """1.0 / 0.001 is 1000.0000000000001 in floating point: a whole number of steps, 1001 samples."""
    assert len(run(t_final=1.0, dt=0.001).t) == 1001


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"keep": 0}, "keep must be 'summary', 'full' or a whole number of steps >= 1, got 0"),
        ({"after": -0.5}, "after must be at least 0"),
        ({"after": float("nan")}, "after must be finite"),
        ({"after": "1 s"}, "after must be a number"),
        ({"after": 0.02}, r"window empty: it must be at most t_final = 0.01 s"),
        ({"runs": 10**12}, "1,000,000,000,000 runs .* needs"),
    ],
)
def test_many_run_arguments_out_of_range_are_refused_by_name(options: dict, message: str) -> None:
    with pytest.raises(ad.ModelError, match=message):
        run(controller=control.PDGravity(10.0, 1.0), **options)


def test_the_summaries_default_window_is_the_final_sample_on_a_run_shorter_than_one_second() -> None:
    """Before, runs shorter than the 1 s default had an empty window and a largest error of 0 (a pass); the
    oracle is the largest |q_d - q| of the samples kept, from t_final on, for one run and for many."""
    path = trajectories.Sinusoid(0.2, 2.0, 0.0, np.zeros(2))
    many = run(controller=control.PDGravity(10.0, 1.0), trajectory=path, t_final=0.5, dt=0.001, keep="full")
    error = np.abs(many.samples["q_d"][0] - many.samples["q"][0])
    assert np.all(error[-1] > 0)
    np.testing.assert_array_equal(many.summaries[0, 1], error[-1])
    one = run(controller=control.PDGravity(10.0, 1.0), trajectory=path, t_final=0.5, dt=0.001)
    np.testing.assert_allclose(one.summaries[0, 1], np.abs(one.q_d - one.q)[-1], rtol=0, atol=0)
