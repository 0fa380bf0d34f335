"""Bad input gives a clear ModelError or a correct result: never a crash, garbage or a raw traceback.

Each test is named after a reproduction of a defect that was found by trying hostile inputs.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import armdyn as ad
from armdyn.control import PID, ComputedTorque, Digital, PDGravity, Saturated
from armdyn.simulation import PythonLoopWarning, SimulationError, simulate
from armdyn.trajectories import Sinusoid


def run_isolated(code: str) -> subprocess.CompletedProcess:
    """Run a risky case in a fresh interpreter, so that a crash fails the test instead of the run."""
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=300)


@pytest.mark.slow
def test_closed_form_with_a_too_small_out_does_not_crash() -> None:
    done = run_isolated(
        """
        import numpy as np, armdyn as ad
        from armdyn.symbolic import derive
        f = derive(ad.models.two_link_planar()).compile()
        for call in (lambda: f.M(np.zeros((1000000, 2)), out=np.empty((1, 2, 2))),
                     lambda: f.M(np.zeros(2), out=np.empty(1)), lambda: f.G(np.zeros(1)),
                     lambda: f.tau(np.zeros(2), np.zeros(5), np.zeros(2))):
            try:
                call()
            except ad.ModelError as error:
                print("ModelError:", error)
        """
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.count("ModelError:") == 4
    assert "out must be" in done.stdout and "q must have shape (2,)" in done.stdout and "qd must" in done.stdout


@pytest.mark.slow
def test_closed_form_refuses_nan_and_complex_one_states() -> None:
    f = ad.symbolic.derive(ad.models.two_link_planar()).compile()
    with pytest.raises(ad.ModelError, match="q must be finite"):
        f.M(np.array([np.nan, 0.0]))
    with pytest.raises(ad.ModelError, match="q must be real"):
        f.G(np.array([1j, 0.0]))
    np.testing.assert_allclose(f.M(np.zeros(2)), ad.models.two_link_planar().inertia_matrix(np.zeros(2)))


def test_forward_dynamics_of_a_singular_inertia_matrix_names_the_joint() -> None:
    polar = ad.models.polar_rp()  # M = diag(m r^2, m): singular at r = 0
    with pytest.raises(ad.ModelError, match=r"singular.*joint 'theta'"):
        polar.forward_dynamics(np.array([0.3, 0.0]), np.zeros(2), np.zeros(2))
    with pytest.raises(ad.ModelError, match=r"singular at state \(1,\)"):
        polar.forward_dynamics([[0.3, 1.0], [0.3, 0.0]], np.zeros(2), np.zeros(2))
    assert np.all(np.isfinite(polar.forward_dynamics(np.array([0.3, 1.0]), np.zeros(2), np.zeros(2))))


def test_forward_dynamics_of_a_massless_leaf_link_names_the_joint() -> None:
    arm = ad.Robot.from_dh([{"a": 1.0, "mass": 1.0, "com": [-0.5, 0, 0], "inertia": [0.1, 0.1, 0.1]}, {"a": 0.5}])
    with pytest.raises(ad.ModelError, match="joint 'joint2'"):
        arm.forward_dynamics(np.zeros(2), np.zeros(2), np.zeros(2))


def test_simulation_of_a_singular_arm_stops_with_an_error() -> None:
    polar = ad.models.polar_rp()
    with pytest.raises(SimulationError, match=r"M\(q\) is singular.*joint 'theta'") as caught:
        simulate(polar, PDGravity(10, 5), t_final=0.1, q0=[0.0, 0.0])
    assert len(caught.value.result.t) == 0


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({"qd0": [np.nan, 0.0]}, "qd0 must be finite"),
        ({"qd0": [np.inf, 0.0]}, "qd0 must be finite"),
        ({"q0": [0.0, 0.0, 0.0]}, r"q0 must have shape \(2,\)"),
        ({"disturbance": [np.nan, 0.0]}, "disturbance must be finite"),
        ({"events": [(np.nan, ad.models.two_link_planar())]}, "event time must be a finite"),
        ({"events": [(0.5, ad.models.puma560())]}, "must be a numeric Robot with 2 joints"),
        ({"t_final": np.nan}, "t_final must be a positive"),
        ({"dt": -1e-3}, "dt must be a positive"),
        ({"controller": "pd"}, "controller must be callable"),
    ],
)
def test_invalid_simulation_settings_are_model_errors(settings: dict, match: str) -> None:
    arm = ad.models.two_link_planar()
    options = {"controller": PID(10, 2), "t_final": 0.01} | settings
    with pytest.raises(ad.ModelError, match=match):
        simulate(arm, **options)


@pytest.mark.parametrize("limit", [-1.0, np.nan, 0.0, [1.0, np.nan], "big"])
def test_torque_limits_must_be_positive(limit: object) -> None:
    with pytest.raises(ad.ModelError, match="torque limit"):
        Saturated(PID(10, 2), limit)


@pytest.mark.parametrize("period", [-0.01, np.nan, 0.0, np.inf, "fast"])
def test_sample_periods_must_be_positive(period: object) -> None:
    with pytest.raises(ad.ModelError, match="sample period"):
        Digital(PID(10, 2), period)


def test_a_diverging_run_stops_at_the_first_non_finite_state_and_says_when() -> None:
    arm = ad.models.two_link_planar()
    with pytest.raises(SimulationError, match=r"diverged at t = .* s: joint") as caught:
        simulate(arm, ComputedTorque(1e12, 1e7), Sinusoid(0.1, 0.5), t_final=1.0, dt=1e-2)
    result = caught.value.result
    assert 0 < len(result.t) < 101
    assert np.all(np.isfinite(result.q)) and np.all(np.isfinite(result.qd))


def test_a_diverging_python_loop_stops_too() -> None:
    arm = ad.models.two_link_planar()
    law = ComputedTorque(1e12, 1e7, model=arm)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        with pytest.raises(SimulationError, match="diverged"):
            simulate(arm, lambda *a: law(*a), Sinusoid(0.1, 0.5), t_final=1.0, dt=1e-2)


def test_a_controller_returning_garbage_is_named() -> None:
    arm = ad.models.two_link_planar()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PythonLoopWarning)
        with pytest.raises(ad.ModelError, match="controller's torque at t = 0"):
            simulate(arm, lambda *a: [np.nan, 0.0], t_final=0.01)
        with pytest.raises(ad.ModelError, match="controller's torque"):
            simulate(arm, lambda *a: "up", t_final=0.01)


def test_a_scaled_base_is_refused() -> None:
    arm = ad.models.two_link_planar()
    with pytest.raises(ad.ModelError, match="base is not a rigid transform"):
        arm.replace(base=np.diag([2.0, 2.0, 2.0, 1.0]))
    with pytest.raises(ad.ModelError, match="tool is not a rigid transform"):
        arm.replace(tool=np.diag([1.0, -1.0, 1.0, 1.0]))  # a mirror
    with pytest.raises(ad.ModelError, match="last row"):
        arm.replace(tool=np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1.0]]))


@pytest.mark.parametrize("call", ["inverse_dynamics", "inertia_matrix", "gravity_vector", "forward_dynamics"])
def test_complex_states_are_refused_not_cast(call: str) -> None:
    arm = ad.models.puma560()
    args = {"inertia_matrix": 1, "gravity_vector": 1}.get(call, 3)
    states = [arm.qn + 1e-3j] + [np.zeros(6)] * (args - 1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning either
        with pytest.raises(ad.ModelError, match="q must be real"):
            getattr(arm, call)(*states)


@pytest.mark.parametrize("value", [1e16, -1e20, 1e300])
def test_joint_values_beyond_exact_trigonometry_are_refused(value: float) -> None:
    arm = ad.models.puma560()
    q = arm.qn.copy()
    q[0] = value
    with pytest.raises(ad.ModelError, match="reduce them modulo 2 pi"):
        arm.inverse_dynamics(q, np.zeros(6), np.zeros(6))
    with pytest.raises(ad.ModelError, match="reduce them modulo 2 pi"):
        arm.inertia_matrix(np.stack([q, arm.qz]))
    big = arm.qn + 2 * np.pi * 1e6  # large but exact enough: the same dynamics as qn
    np.testing.assert_allclose(arm.gravity_vector(big), arm.gravity_vector(arm.qn), atol=1e-8)


@pytest.mark.parametrize("value", [None, "q", {"q": 1}, [[1, 2], [3]], object()])
def test_wrong_types_name_the_argument(value: object) -> None:
    arm = ad.models.two_link_planar()
    with pytest.raises(ad.ModelError, match=r"^q "):
        arm.inertia_matrix(value)
    with pytest.raises(ad.ModelError, match=r"^qd "):
        arm.coriolis_matrix(np.zeros(2), value)
    with pytest.raises(ad.ModelError, match=r"^tau "):
        arm.forward_dynamics(np.zeros(2), np.zeros(2), value)


READ_ONLY_CALLS = {
    "inverse_dynamics": lambda arm, q: arm.inverse_dynamics(q, q, q),
    "forward_dynamics": lambda arm, q: arm.forward_dynamics(q, q, q),
    "inertia_matrix": lambda arm, q: arm.inertia_matrix(q),
    "coriolis_matrix": lambda arm, q: arm.coriolis_matrix(q, q),
    "gravity_vector": lambda arm, q: arm.gravity_vector(q),
    "jacobian": lambda arm, q: arm.jacobian(q, "tool", 3),
    "inverse_dynamics_derivatives": lambda arm, q: arm.inverse_dynamics_derivatives(q, q, q),
    "task_inertia": lambda arm, q: ad.task_space.task_inertia(arm, ad.task_space.ToolPose(), q),
    "operational_space": lambda arm, q: ad.task_space.operational_space(arm, ad.task_space.ToolPose(), q, q).Lambda,
}


@pytest.mark.parametrize("name", sorted(READ_ONLY_CALLS))
def test_a_read_only_configuration_takes_the_one_state_kernel(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """arm.qn is read-only (Numba types it apart from a writable array): the call copies it and stays on the
    one-state kernel, equal to the writable call, instead of the general path (which is refused here)."""
    arm = ad.models.puma560()
    assert not arm.qn.flags.writeable
    expected = READ_ONLY_CALLS[name](arm, np.array(arm.qn))

    def general_path(*args: object, **kwargs: object) -> None:
        raise AssertionError("the general path was taken")

    monkeypatch.setattr(ad.inputs, "batch_states", general_path)
    got = READ_ONLY_CALLS[name](arm, arm.qn)
    for a, b in zip(got if isinstance(got, tuple) else (got,), expected if isinstance(expected, tuple) else (expected,),
                    strict=True):  # fmt: skip
        assert np.array_equal(a, b)
    frozen = np.zeros(arm.n)
    frozen.flags.writeable = False
    monkeypatch.undo()
    with pytest.raises(ad.ModelError, match="got read-only array of shape"):
        arm.inverse_dynamics(arm.qn, arm.qn, arm.qn, out=frozen)
