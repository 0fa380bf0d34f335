"""Joint limits in simulation (simulate's joint_limits): a warning naming the joint, time and value by
default, a stop that ends the run there, and spring-damper stops that keep the joints inside."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from armdyn.simulation import STOP_TIME_CONSTANT, JointLimitWarning, joint_stops, stop_torques
from tests.helpers import URDFS, invoke


@pytest.fixture(scope="module")
def puma() -> ad.Robot:
    return ad.models.puma560()


def _free_fall(puma: ad.Robot, **options: object) -> ad.simulation.Result:
    options = {"controller": None, **options}
    return ad.simulate(puma, trajectory=None, t_final=1.5, **options)  # the free arm falls: q2 passes -0.785 rad


def test_the_falling_puma_warns_naming_the_joint_the_time_and_the_value(puma: ad.Robot) -> None:
    """Oracle: the first sample of the unconstrained run below q2's lower limit."""
    with pytest.warns(JointLimitWarning) as caught:
        run = _free_fall(puma)
    lower = puma.qlim[0, 1]
    first = int(np.argmax(run.q[:, 1] < lower))
    assert run.q[first, 1] < lower <= run.q[first - 1, 1]
    message = str(caught[0].message)
    assert f"joint 'q2' of 'puma560' left its limits [{lower:.6g}" in message
    assert f"t = {run.t[first]:.6g} s (q = {run.q[first, 1]:.6g} rad)" in message
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointLimitWarning)
        ignored = _free_fall(puma, joint_limits="ignore")  # the same run, without the warning
    np.testing.assert_array_equal(ignored.q, run.q)


def test_stop_ends_the_run_at_the_crossing_with_the_run_up_to_it(puma: ad.Robot) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", JointLimitWarning)
        whole = _free_fall(puma)
    with pytest.raises(ad.SimulationError, match=r"joint 'q2' .* \(joint_limits='stop'\)") as stopped:
        _free_fall(puma, joint_limits="stop")
    kept = stopped.value.result
    rows = len(kept.t)
    np.testing.assert_array_equal(kept.q, whole.q[:rows])
    assert kept.q[-1, 1] < puma.qlim[0, 1] and np.all(kept.q[:-1, 1] >= puma.qlim[0, 1])


def test_spring_stops_keep_the_falling_puma_near_its_limit_and_agree_across_routes(puma: ad.Robot) -> None:
    """A critically damped stop entered at speed v goes in at most v tc / e (e = 2.718...), plus the static
    deflection tau_gravity / K under load (K = M_ii / tc^2); the compiled loop, the Python loop and an adaptive
    solver integrate the same stop law."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointLimitWarning)  # a spring run does not warn
        compiled = _free_fall(puma, joint_limits="spring")
    lower = puma.qlim[0]
    stiffness = np.diag(puma.inertia_matrix(np.zeros(6))) / STOP_TIME_CONSTANT**2
    deflection = np.abs(puma.gravity_vector(compiled.q[-1])) / stiffness
    impact = abs(compiled.qd[int(np.argmax(compiled.q[:, 1] < lower[1])), 1])
    assert compiled.q[:, 1].min() >= lower[1] - impact * STOP_TIME_CONSTANT / np.e - 2 * deflection[1]
    assert compiled.q[:, 1].min() < lower[1]  # the stop is reached, and holds
    assert abs(compiled.qd[-1, 1]) < 1e-2

    def own_law(t: float, q: np.ndarray, qd: np.ndarray, *_: object) -> np.ndarray:
        return np.zeros(6)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ad.simulation.PythonLoopWarning)
        python = _free_fall(puma, controller=own_law, joint_limits="spring")
    np.testing.assert_allclose(python.q, compiled.q, rtol=0, atol=1e-9)
    adaptive = _free_fall(puma, method="rk45", joint_limits="spring")
    np.testing.assert_allclose(adaptive.q[-1], compiled.q[-1], atol=2e-3)


def test_the_stop_law_pushes_back_and_never_pulls() -> None:
    arm = ad.models.two_link_planar()
    arm = arm.replace([dataclasses.replace(link, limits=(-1.0, 1.0)) for link in arm.links])
    stops = joint_stops(arm, np.zeros(2), spring=True)
    K, B = stops[:, 2], stops[:, 3]
    q, qd = np.array([1.1, -1.2]), np.array([0.5, 0.0])
    np.testing.assert_allclose(stop_torques(stops, q, qd), [-K[0] * 0.1 - B[0] * 0.5, K[1] * 0.2])
    leaving_fast = stop_torques(stops, np.array([1.001, 0.0]), np.array([-100.0, 0.0]))  # moving back in fast
    assert leaving_fast[0] == 0.0 and leaving_fast[1] == 0.0
    assert np.all(stop_torques(stops, np.array([0.5, -0.5]), np.array([9.0, -9.0])) == 0.0)
    assert np.all(np.isinf(joint_stops(arm, np.zeros(2), spring=False)[:, :2]))


@pytest.mark.parametrize("bad", ["warning", "", None, 1, "SPRING"])
def test_joint_limits_must_be_a_known_choice(puma: ad.Robot, bad: object) -> None:
    with pytest.raises(ad.ModelError, match="joint_limits must be one of warn, stop, spring, ignore"):
        ad.simulate(puma, None, None, t_final=0.01, joint_limits=bad)


def test_many_runs_refuse_joint_limits_by_name(puma: ad.Robot) -> None:
    with pytest.raises(ad.ArgumentError, match="joint_limits"):
        ad.simulate(puma, control.PDGravity(10.0, 1.0), None, t_final=0.01, runs=2, joint_limits="spring")


def test_the_cli_default_path_keeps_the_panda_inside_its_limits_and_the_option_reaches_simulate() -> None:
    """Before, the default sine drove the Panda's finger to 0.120 m against its 0.04 m limit."""
    panda = URDFS["panda"]
    quiet = invoke("simulate", panda, "--t-final", "2")
    assert quiet.exit_code == 0, quiet.output
    assert "left its limits" not in quiet.output
    falling = invoke("simulate", "puma560", "--controller", "none", "--trajectory", "none", "--t-final", "1.5")
    assert falling.exit_code == 0 and "joint 'q2' of 'puma560' left its limits" in falling.output
    held = invoke("simulate", "puma560", "--controller", "none", "--trajectory", "none", "--t-final", "1.5",
                  "--joint-limits", "stop")  # fmt: skip
    assert held.exit_code != 0 and "joint_limits='stop'" in held.output


def test_the_default_sine_stays_inside_the_limits_of_a_narrow_joint() -> None:
    """The CLI's path about a start outside a narrow range: its samples lie within the limits (oracle)."""
    from armdyn.cli import _trajectory

    arm = ad.models.two_link_planar()
    arm = arm.replace([dataclasses.replace(link, limits=(0.0, 0.04)) for link in arm.links])
    path = _trajectory("sine", arm, 0.1, 0.5)
    assert isinstance(path, tr.Sinusoid)
    samples = np.array([path(t, 2)[0] for t in np.linspace(0, 2, 201)])
    assert np.all(samples >= 0.0) and np.all(samples <= 0.04)


@pytest.mark.slow
def test_the_panda_finger_warns_when_driven_past_its_limit_and_stops_hold_it() -> None:
    """A sine of 0.1 m on the finger (range 0 to 0.04 m), as the CLI's default path was: a warning naming the
    finger; with spring stops the finger stays within a few millimetres of its range (the stop's deflection
    under the controller's push, about tau / K)."""
    panda = ad.load_urdf(URDFS["panda"])
    lower, upper = panda.qlim
    margin = 0.1 * (upper - lower)  # every joint of the Panda has finite limits
    start = np.clip(np.zeros(panda.n), lower + margin, upper - margin)
    finger = panda.joint_names.index("panda_finger_joint1")
    amplitude = np.zeros(panda.n)
    amplitude[finger] = 0.1
    path = tr.Sinusoid(amplitude, 0.5, 0.0, start)
    law = control.ComputedTorque(100.0, 20.0)
    with pytest.warns(JointLimitWarning, match="joint 'panda_finger_joint1' of 'panda' left its limits"):
        free = ad.simulate(panda, law, path, t_final=2.0, q0=start)
    assert free.q[:, finger].max() > upper[finger] + 0.03
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointLimitWarning)
        held = ad.simulate(panda, law, path, t_final=2.0, q0=start, joint_limits="spring")
    assert held.q[:, finger].max() < upper[finger] + 0.01 and held.q[:, finger].min() > lower[finger] - 0.01
