"""Simulation under control: the book's Chapter 4 examples, energy, solvers, events, output."""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

import armdyn as ad
from armdyn.cli import app
from armdyn.control import PID, ComputedTorque, Digital, PDGravity, Saturated
from armdyn.simulation import PythonLoopWarning, simulate
from armdyn.trajectories import CartesianCircle, Quintic, Sinusoid

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def example(name: str) -> object:
    """One of the book's example scripts in examples/, as a module."""
    if str(EXAMPLES) not in sys.path:
        sys.path.insert(0, str(EXAMPLES))
    return importlib.import_module(name)


# ----- the book's examples ------------------------------------------------------------------------
def test_example_4_4_1_tracks_within_a_millisecond_step() -> None:
    ex = example("example_4_4_1")
    fine, coarse = ex.run(1e-3), ex.run(1e-2)
    assert np.abs(fine.error[fine.t >= 1.0]).max() < 1e-3  # errors die out within about 0.6 s
    assert np.abs(fine.error[fine.t >= 0.6]).max() < 5e-3
    assert abs(fine.error[0, 1] - 0.1) < 1e-12  # the arm starts at rest at q = 0, theta_2d(0) = 0.1
    assert np.abs(fine.tau[:, 0]).max() > np.abs(fine.tau[:, 1]).max()  # joint 1 needs the larger torque
    assert ex.torque_ripple(coarse) > 5 * ex.torque_ripple(fine)  # a 10 ms step leaves ripple


def test_example_4_4_2_integral_action_removes_the_bias() -> None:
    ex = example("example_4_4_2")
    pd, pid = ex.bias(ex.run(0.0)), ex.bias(ex.run(500.0))
    assert 0.025 < pd.max() < 0.04  # the book's peak bias of about 0.033 rad
    assert pid.max() < 0.1 * pd.max()


def test_example_4_4_3_errors_shrink_as_the_gains_grow() -> None:
    ex = example("example_4_4_3")
    runs = [ex.run(wn) for wn in (10, 25, 50)]
    errors = [np.abs(r.error[r.t >= 2.0]).max() for r in runs]
    assert errors[0] > errors[1] > errors[2] > 0  # bounded, not zero, smaller at higher gains
    assert errors[0] < 0.2


def test_example_4_4_4_classical_control_and_windup() -> None:
    ex = example("example_4_4_4")
    weak = ex.run(100, 20)
    assert np.abs(weak.error[weak.t >= 2]).max() > 0.1  # kp = 100, kv = 20 performs badly
    free, limited = ex.run(2500, 100, 1000), ex.run(2500, 100, 1000, limit=35.0)
    assert np.abs(free.error[free.t >= 2]).max() < 0.01
    assert np.abs(limited.tau).max() <= 35.0 + 1e-9
    window = (free.t > 0.05) & (free.t < 0.5)
    assert np.abs(limited.error[window]).max() > 1.5 * np.abs(free.error[window]).max()  # windup


def test_example_4_5_1_limit_cycle_near_a_tenth_of_a_second() -> None:
    ex = example("example_4_5_1")
    fast, slow, limit = ex.run(0.005), ex.run(0.05), ex.run(0.1)
    assert ex.amplitude(fast, 5, 20) < 2e-4
    assert ex.amplitude(slow, 5, 20) < 2e-3
    assert ex.amplitude(limit, 15, 20) >= ex.amplitude(limit, 5, 10)  # sustained, not decaying
    assert ex.amplitude(limit, 5, 20) > 10 * ex.amplitude(slow, 5, 20)


# ----- physics and solvers ---------------------------------------------------------------------------
def test_energy_is_conserved_without_friction_or_torque() -> None:
    arm = ad.models.puma560().without_friction()
    result = simulate(arm, None, None, t_final=10.0, dt=1e-3, q0=arm.qr + 0.1)
    assert np.abs(result.q).max() > 1.0  # it really moved
    drift = np.abs(result.energy - result.energy[0]).max() / np.abs(result.energy).max()
    assert drift < 1e-6


def test_friction_dissipates_energy() -> None:
    arm = ad.models.puma560()
    result = simulate(arm, None, None, t_final=1.0, dt=1e-3, q0=arm.qr + 0.05)
    assert result.energy[-1] < result.energy[0]
    # never gains more than the integrator's error (RK4 through the smoothed Coulomb law)
    assert np.all(np.diff(result.energy) <= 1e-7 * np.abs(result.energy).max())


def test_python_loop_and_adaptive_solver_agree_with_the_compiled_loop() -> None:
    arm = ad.models.two_link_planar()
    desired = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0, np.pi / 2])
    compiled = simulate(arm, ComputedTorque(100, 20), desired, t_final=1.0, dt=1e-3)
    law = ComputedTorque(100, 20, model=arm)

    def mine(t: float, q: np.ndarray, qd: np.ndarray, q_d: np.ndarray, qd_d: np.ndarray, qdd_d: np.ndarray,
             e_int: np.ndarray) -> np.ndarray:  # fmt: skip
        return law(t, q, qd, q_d, qd_d, qdd_d, e_int)

    with pytest.warns(PythonLoopWarning, match="of your own in Python"):
        python = simulate(arm, mine, desired, t_final=1.0, dt=1e-3)
    assert python.info["method"] == "rk4 (Python)" and compiled.info["method"] == "rk4 (compiled)"
    assert_allclose(python.q, compiled.q, atol=1e-12)
    adaptive = simulate(arm, ComputedTorque(100, 20), desired, t_final=1.0, dt=1e-3, method="rk45")
    assert_allclose(adaptive.q, compiled.q, atol=5e-4)  # the held torque of RK4 against a continuous law


def test_quintic_and_circle_trajectories() -> None:
    move = Quintic([0.0, 0.0], [1.0, -0.5], 0.0, 2.0)
    q, qd, _ = move(np.array([0.0, 1.0, 2.0]))
    assert_allclose(q[[0, 2]], [[0.0, 0.0], [1.0, -0.5]])
    assert_allclose(qd[[0, 2]], 0.0, atol=1e-15)
    assert_allclose(q[1], [0.5, -0.25])
    arm = ad.models.two_link_planar(a1=2.0, a2=2.0)
    circle = CartesianCircle(2.0, 2.0, (2.0, 1.0), 0.5, period=2.0)  # Example 4.2-1
    t = np.linspace(0, 2, 9)
    qc, qdc, qddc = circle(t)
    tip = arm.tool_pose(qc)[:, :2, 3]
    assert_allclose(np.linalg.norm(tip - [2.0, 1.0], axis=1), 0.5, atol=1e-12)
    h = 1e-6
    assert_allclose((circle(t + h)[0] - circle(t - h)[0]) / (2 * h), qdc, atol=1e-6)
    assert_allclose((circle(t + h)[1] - circle(t - h)[1]) / (2 * h), qddc, atol=1e-5)
    result = simulate(arm, ComputedTorque(400, 40), circle, t_final=2.0, dt=1e-3, q0=qc[0], qd0=qdc[0])
    assert np.abs(result.error).max() < 1e-4


def test_a_payload_change_during_a_run() -> None:
    """The book's problem: m2 from 1 to 2 kg at t = 5 s, the controller keeping its old model."""
    arm = ad.models.two_link_planar()
    heavier = ad.models.two_link_planar(m2=2.0)
    desired = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0, np.pi / 2])
    result = simulate(arm, ComputedTorque(100, 20, model=arm), desired, t_final=8.0, dt=1e-3, events=[(5.0, heavier)])
    before = np.abs(result.error[(result.t > 3) & (result.t < 5)]).max()
    after = np.abs(result.error[result.t > 6]).max()
    assert after > 10 * before  # the model error shows once the payload is there


def test_pd_gravity_digital_and_saturation_compose() -> None:
    arm = ad.models.two_link_planar()
    desired = Sinusoid([0.1, 0.1], [0.5, 0.5])
    law = Digital(Saturated(PDGravity(400, 40), 50.0), 0.01)
    result = simulate(arm, law, desired, t_final=2.0, dt=1e-3)
    held = result.tau[1:10]
    assert_allclose(held, np.repeat(result.tau[:1], 9, axis=0))  # zero-order hold over 10 steps
    assert np.abs(result.tau).max() <= 50.0 + 1e-12


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "euler"}, "method must be"),
        ({"dt": 0.0}, "dt must be a positive number"),
        ({"q0": [0.0]}, r"q0 must have shape \(2,\)"),
        ({"controller": Digital(PID(1, 1), 0.0015)}, "whole number of steps"),
        ({"controller": Digital(PID(1, 1), 0.01), "method": "rk45"}, "needs method='rk4'"),
        ({"controller": PID([1, 2, 3], 1)}, "gain kp"),
    ],
)
def test_bad_simulations_are_refused(kwargs: dict, match: str) -> None:
    with pytest.raises(ad.ModelError, match=match):
        simulate(ad.models.two_link_planar(), **{"t_final": 0.1, **kwargs})


# ----- output ------------------------------------------------------------------------------------------
def test_result_files_and_plot(tmp_path: Path) -> None:
    result = example("example_4_4_1").run(1e-3, t_final=1.0)
    result.to_csv(tmp_path / "run.csv")
    table = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True)
    assert len(table) == 1001 and {"t", "q1", "e2", "tau1", "energy"} <= set(table.dtype.names)
    result.to_npz(tmp_path / "run.npz")
    assert set(np.load(tmp_path / "run.npz").files) >= {"t", "q", "error"}
    result.plot(tmp_path / "run.png")
    assert (tmp_path / "run.png").stat().st_size > 20_000


def test_simulate_command(tmp_path: Path) -> None:
    png, csv = tmp_path / "out.png", tmp_path / "out.csv"
    result = CliRunner().invoke(
        app,
        ["simulate", "two_link_planar", "--controller", "computed-torque", "--kp", "100", "--kv", "20",
         "--trajectory", "sine", "--t-final", "2", "--plot", str(png), "--csv", str(csv)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert png.exists() and csv.exists() and "final error" in result.output
    assert CliRunner().invoke(app, ["simulate", "puma560", "--controller", "magic"]).exit_code == 2


@pytest.mark.slow
def test_demo_is_the_main_job(demo_run: tuple) -> None:
    result, folder = demo_run
    assert result.exit_code == 0, result.output
    assert (folder / "demo.png").exists() and (folder / "demo.csv").exists() and (folder / "demo.gif").exists()
    assert "final tracking errors" in result.output and "Table 3.3.1" in result.output
    assert "Section 3.5" in result.output and "Mbar" in result.output
    assert "poles -8.702, -2.298" in result.output and (folder / "demo-drives.png").exists()


def test_the_top_level_names() -> None:
    assert ad.simulate is simulate
    assert ad.control.ComputedTorque is ComputedTorque and ad.trajectories.Sinusoid is Sinusoid
    assert ad.statespace.linearize is not None and ad.symbolic.derive is not None
    with pytest.raises(AttributeError):
        _ = ad.no_such_name


def test_users_controller_is_given_the_plant_and_its_errors_are_not_swallowed() -> None:
    arm = ad.models.two_link_planar()
    heavier = arm.with_payload(1.0)
    seen = []

    def with_plant(t, q, qd, q_d, qd_d, qdd_d, e_int, plant=None):
        seen.append(plant)
        return plant.gravity_vector(q)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        simulate(arm, with_plant, t_final=0.01, dt=1e-3, events=[(0.005, heavier)])
    assert seen[0] is arm and seen[-1] is heavier

    def broken(t, q, qd, q_d, qd_d, qdd_d, e_int):
        raise TypeError("a bug inside the controller")

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        with pytest.raises(TypeError, match="a bug inside the controller"):
            simulate(arm, broken, t_final=0.01)


def test_built_in_controllers_run_compiled_without_a_warning() -> None:
    arm = ad.models.two_link_planar()
    with warnings.catch_warnings():
        warnings.simplefilter("error", PythonLoopWarning)
        for controller in (ComputedTorque(100, 20), PDGravity(100, 20), PID(100, 20, 5), None):
            result = simulate(arm, controller, Sinusoid(0.1, 0.5), t_final=0.01)
            assert result.info["method"] == "rk4 (compiled)"
    with pytest.raises(ad.ModelError, match="controller must be callable"):
        simulate(arm, "computed-torque", t_final=0.01)


def test_figures_name_the_controller_keep_legends_off_the_data_and_carry_units() -> None:
    """Issue: the 12-entry legend covered the data, titles omitted the controller and gains, and
    revolute-only arms got "rad or m" axes."""
    import matplotlib

    matplotlib.use("Agg")
    arm = ad.models.puma560()
    result = simulate(arm, ComputedTorque(100, 20), Sinusoid(0.1, 0.5, offset=arm.qn), t_final=0.1, q0=arm.qn)
    figure = result.plot()
    assert "computed torque (kp = 100, kv = 20)" in figure._suptitle.get_text()
    legends = [axis.get_legend() for axis in figure.axes if axis.get_legend() is not None]
    assert len(legends) == 1 and not figure.legends  # one legend, beside the top plot
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    box, data = legends[0].get_window_extent(renderer), figure.axes[0].get_window_extent(renderer)
    assert box.x0 >= data.x1  # right of the plotting area, never over the data
    title = figure._suptitle.get_window_extent(renderer)
    assert title.x0 >= 0 and title.x1 <= figure.bbox.x1  # the title fits the figure (wrapped)
    labels = [axis.get_ylabel() for axis in figure.axes]
    assert labels == ["joint position (rad)", "error q_d - q (rad)", "torque (N m)"]
    polar = simulate(ad.models.polar_rp(), PDGravity([100, 100], [20, 20]), t_final=0.05, q0=[0.0, 1.0])
    assert polar.plot().axes[-1].get_ylabel() == "torque (N m or N)"
    assert result.info["controller"] == "computed torque (kp = 100, kv = 20)"


def test_one_scenario_through_every_route_gives_one_answer() -> None:
    """Issue: ComputedTorque on the PUMA 560 (with Coulomb friction) tracked 100x worse on the Python
    loop and rk45 than on the compiled loop: the Python controller compensated the exact sign law
    while the plant followed the smoothed one."""
    arm = ad.models.puma560()
    path = Sinusoid(0.3, 0.5, offset=arm.qn)
    start = {"q0": path(0.0, 6)[0], "qd0": path(0.0, 6)[1], "t_final": 0.3, "dt": 1e-3}
    own_path = lambda t: path(t, 6)  # noqa: E731 - a trajectory of the user's own: the Python routes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        compiled = simulate(arm, ComputedTorque(100, 20), path, **start)
        python = simulate(arm, ComputedTorque(100, 20), own_path, **start)
        rk45 = simulate(arm, ComputedTorque(100, 20), path, method="rk45", **start)
        rk45_python = simulate(arm, ComputedTorque(100, 20), own_path, method="rk45", **start)
    assert compiled.info["method"] == "rk4 (compiled)" and python.info["method"] == "rk4 (Python)"
    assert "compiled right-hand side" in rk45.info["method"] and "Python" in rk45_python.info["method"]
    assert_allclose(python.q, compiled.q, atol=1e-10)
    assert_allclose(rk45_python.q, rk45.q, atol=1e-7)
    # held torque over each 1 ms step (RK4) against continuous control (rk45): close, not equal
    assert_allclose(rk45.q, compiled.q, atol=2e-4)
    assert np.abs(compiled.error[-100:]).max() < 2e-3 and np.abs(python.error[-100:]).max() < 2e-3


def test_one_run_many_runs_and_read_only_inputs_share_one_compiled_loop() -> None:
    """Each variant of the loop's argument types is another compile of tens of seconds in a fresh process: a single
    run, many runs, read-only starts and the observer with contacts must all take the one compiled run_rk4."""
    from armdyn import simulation
    from armdyn.control import ComputedTorque
    from armdyn.observers.contact import Push
    from armdyn.observers.momentum import MomentumObserver

    arm = ad.models.two_link_planar()
    frozen = np.array([0.1, -0.2])
    frozen.flags.writeable = False
    law, path = ComputedTorque(100, 20), Sinusoid([0.1, 0.1], 0.5)
    ad.simulate(arm, law, path, t_final=0.01)
    push = Push(arm, 1, [0.1, 0.0, 0.0], [0.0, 1.0, 0.0], 0.0)
    ad.simulate(arm, law, path, t_final=0.01, q0=frozen, disturbance=push, observer=MomentumObserver(arm, 50.0))
    ad.simulate(arm, law, path, t_final=0.01, runs=2, q0=np.broadcast_to(frozen, (2, 2)))
    assert len(simulation.run_rk4.signatures) == 1
    assert len(simulation.run_many.signatures) == 1
