"""Optimal control on armdyn's CasADi functions (examples/optimal_control.py, benchmarks/bench_casadi.py): the
minimum-effort motion meets its constraints and armdyn's own simulation reproduces it, computed torque tracks it,
the MPC holds a pose, and adam's forward dynamics give the benchmark's problem the same optimum."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("casadi", reason="the CasADi backend needs casadi (pip install 'armdyn[casadi]')")

import armdyn as ad
from armdyn.simulation import PythonLoopWarning

ROOT = Path(__file__).resolve().parents[1]
LIMIT = np.array([15.0, 90.0, 18.0, 10.0, 10.0, 10.0])  # N m: tighter than the example's, to bind without friction


def module(path: Path, name: str) -> object:
    """A script as a module (registered under ``name``, as its dataclasses need)."""
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    loaded = importlib.util.module_from_spec(spec)
    sys.modules[name] = loaded
    spec.loader.exec_module(loaded)
    return loaded


@pytest.fixture(scope="module")
def example() -> object:
    return module(ROOT / "examples" / "optimal_control.py", "optimal_control")


@pytest.fixture(scope="module")
def rigid_motion(example: object) -> tuple[object, object, ad.Robot]:
    """The example's problem on the PUMA 560 without friction, LIMIT, 15 intervals: (motion, step, arm)."""
    arm = example.ARM.without_friction()
    step = example.dynamics(arm)
    guess = example.quintic_guess(example.START, example.GOAL, example.DURATION, 15, arm)
    motion = example.point_to_point(
        step, example.START, example.GOAL, LIMIT, example.DURATION, 15, guess, joint_limits=arm.qlim
    )
    return motion, step, arm


def test_the_optimum_meets_its_constraints(example: object, rigid_motion: tuple) -> None:
    motion, step, arm = rigid_motion
    n = arm.n
    assert motion.status == "Solve_Succeeded"
    assert np.all(np.abs(motion.tau) <= LIMIT * (1 + 1e-8))
    assert np.abs(motion.tau / LIMIT).max() > 0.999  # a limit binds: the bounds are in force
    np.testing.assert_allclose(motion.x[0], np.concatenate([example.START, np.zeros(n)]), atol=1e-12)
    np.testing.assert_allclose(motion.x[-1], np.concatenate([example.GOAL, np.zeros(n)]), atol=1e-12)
    assert np.all(motion.x[:, :n] >= arm.qlim[0] - 1e-7) and np.all(motion.x[:, :n] <= arm.qlim[1] + 1e-7)
    assert np.abs(example.defects(step, motion)).max() < 1e-9
    h = example.DURATION / 15
    assert motion.cost == pytest.approx(h * np.sum(motion.tau**2), rel=1e-12)


def test_simulate_reproduces_the_optimum(rigid_motion: tuple) -> None:
    """The oracle: armdyn's simulate (its compiled dynamics, RK4 at the interval) under the optimal torques held
    over each interval passes through the knots."""
    motion, _, arm = rigid_motion
    n, h = arm.n, motion.t[1] - motion.t[0]

    def held(t: float, *_: object) -> np.ndarray:
        return motion.tau[min(round(t / h), len(motion.tau) - 1)]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        run = ad.simulate(
            arm,
            held,
            None,
            t_final=float(motion.t[-1]),
            dt=h,
            q0=motion.x[0, :n],
            qd0=motion.x[0, n:],
            joint_limits="ignore",
        )  # q3 rides its limit (to IPOPT's 4e-8 bound relaxation)
    np.testing.assert_allclose(run.q, motion.x[:, :n], atol=1e-9)
    np.testing.assert_allclose(run.qd, motion.x[:, n:], atol=1e-8)


def test_computed_torque_tracks_the_optimum_with_friction(example: object) -> None:
    """The example's motion with the arm's friction (smoothed in the step), 10 intervals, tracked by simulate."""
    step = example.dynamics(example.ARM)
    guess = example.quintic_guess(example.START, example.GOAL, example.DURATION, 10, example.ARM)
    motion = example.point_to_point(
        step, example.START, example.GOAL, example.TORQUE_LIMIT, example.DURATION, 10, guess
    )
    assert motion.status == "Solve_Succeeded"
    assert np.abs(example.defects(step, motion)).max() < 1e-9
    run = example.track(motion, dt=2e-3)
    assert example.tracking_error(motion, run) < 1e-3


def test_an_impossible_motion_is_reported(example: object) -> None:
    """Torque limits below what holds the arm against gravity at the start: IPOPT does not claim an optimum."""
    arm = example.ARM.without_friction()
    limit = 0.2 * np.abs(arm.gravity_vector(example.START)) + 1e-3
    guess = example.quintic_guess(example.START, example.START, 0.3, 5, arm)
    options = {**example.IPOPT, "ipopt.max_iter": 200}
    motion = example.point_to_point(example.dynamics(arm), example.START, example.START, limit, 0.3, 5, guess, options)
    assert motion.status != "Solve_Succeeded"


def test_the_mpc_holds_the_pose(example: object) -> None:
    """Without a payload the MPC holds the arm at rest with the gravity torque; with it, the refreshed model's
    offset is smaller than the nominal model's."""
    arm = example.ARM.without_friction()
    G = arm.gravity_vector(example.HOLD)
    controller = example.MPC(example.dynamics(arm), example.HOLD, G, example.TORQUE_LIMIT, 5, example.CONTROL_PERIOD)
    tau = controller(np.concatenate([example.HOLD, np.zeros(arm.n)]))
    np.testing.assert_allclose(tau, G, atol=1e-6)  # at rest on the pose with G: the cost's global minimum, 0
    nominal, refreshed = (example.hold(0.3, 5, refresh) for refresh in (False, True))
    before = nominal.t <= example.PICKUP + 1e-9  # the plant is the model until the pickup: it stays on the pose
    np.testing.assert_allclose(nominal.x[before, :6], np.tile(example.HOLD, (before.sum(), 1)), atol=1e-6)
    offset = {key: np.abs(run.x[-1, :6] - example.HOLD).max() for key, run in (("n", nominal), ("r", refreshed))}
    assert offset["r"] < offset["n"]
    assert np.all(nominal.seconds > 0) and len(nominal.seconds) == 15


@pytest.mark.slow
def test_the_example_runs_quick() -> None:
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "optimal_control.py"), "--quick"],
                          capture_output=True, text=True, cwd=ROOT, timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Solve_Succeeded" in done.stdout and "MPC (nominal model)" in done.stdout


# ----- the benchmark's problem: adam beside armdyn ------------------------------------------------------------------
def test_adam_and_armdyn_reach_the_same_optimum(example: object) -> None:
    pytest.importorskip("adam.casadi", reason="the benchmark's peer adam-robotics (with liecasadi) is not installed")
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        bench = module(ROOT / "benchmarks" / "bench_casadi.py", "bench_casadi")
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    entry = bench.Arm("UR5", bench.load(bench.UR5), bench.UR5)
    state = np.random.default_rng(0).uniform(-1, 1, (3, entry.arm.n))
    adam = bench.adam_qdd(entry)
    assert bench.checked(entry.arm, "qdd", adam, state) < 1e-10
    ours, theirs = (bench.solve(build, entry.arm, 6, example) for build in
                    (lambda: bench.armdyn_qdd(entry.arm), lambda: adam))  # fmt: skip
    assert ours.motion.status == theirs.motion.status == "Solve_Succeeded"
    gaps = bench.compare(ours, theirs)
    assert gaps["cost"] < 1e-6 and gaps["states"] < 1e-6 and gaps["torques"] < 1e-6
