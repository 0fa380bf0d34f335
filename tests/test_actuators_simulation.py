"""The arm driven through its motors' electrics: the compiled RK4 run against the NumPy full model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armdyn as ad
from armdyn import actuators as act
from armdyn import trajectories as tr
from armdyn.control import CurrentComputedTorque, DrivePID
from armdyn.errors import ModelError


def _puma() -> act.ActuatedArm:
    """The PUMA 560's motors as DC drives with representative electrics, without Coulomb friction (its
    discontinuity at rest would make the tight reference integration crawl)."""
    puma = ad.models.puma560()
    smooth = puma.replace([dataclasses.replace(link, coulomb=(0.0, 0.0)) for link in puma.links])
    bare, drives = act.motor_drives(smooth, torque_constant=0.22, back_emf=0.22, resistance=2.1,
                                    inductance=2e-3, voltage_limit=40.0, current_limit=8.0)  # fmt: skip
    return act.with_actuators(bare, drives)


@pytest.mark.slow
def test_compiled_run_converges_to_the_numpy_full_model_integrated_tightly() -> None:
    """ad.simulate on an ActuatedArm (RK4, its step at most half of L/R) against solve_ivp (DOP853, 1e-11) on
    ActuatedArm.state_derivative with the same motor-side PD law: q, qd and the currents within 1e-2 of their
    range at the default 1 ms samples (3 RK4 steps each), and fourth order as the step shrinks."""
    arm = _puma()
    q0 = np.array(ad.models.puma560().configurations["qn"])
    path, law = tr.Sinusoid(0.1, 0.5, 0.0, q0), DrivePID(20.0, 0.5)
    r = arm._r

    def rates(t: float, x: np.ndarray) -> np.ndarray:
        q_d, qd_d, _ = path(t, 6)
        return arm.state_derivative(x, 20.0 * (q_d - x[:6]) / r + 0.5 * (qd_d - x[6:12]) / r)

    times = np.linspace(0.0, 0.3, 31)
    reference = solve_ivp(rates, (0, 0.3), arm.initial_state(q0), method="DOP853", rtol=1e-11, atol=1e-12,
                          t_eval=times).y.T  # fmt: skip
    scale = np.abs(reference).max(axis=0)
    errors = {}
    for dt in (1e-3, 2.5e-4, 1e-4):
        result = ad.simulate(arm, law, path, t_final=0.3, dt=dt, q0=q0)
        samples = np.round(times / dt).astype(int)
        errors[dt] = np.max(np.abs(result.drives.x[samples] - reference) / scale)
    print(f"relative errors at dt 1e-3, 2.5e-4, 1e-4: {list(errors.values())}")
    assert errors[1e-3] < 1e-2 and errors[1e-4] < 1e-4
    assert errors[2.5e-4] / errors[1e-4] > 2.5**3.5  # fourth order
    result = ad.simulate(arm, law, path, t_final=0.3, dt=1e-3, q0=q0)
    assert result.info["substeps"] == 3 and result.drives.x.shape == (301, 18)
    assert np.abs(result.drives.i).max() <= 8.0 + 1e-12 and np.abs(result.drives.v).max() <= 40.0
    assert np.allclose(result.tau, arm._K_M * result.drives.i / r)
    assert result.q_d is not None and np.abs(result.error[-1]).max() < 0.02


def test_simulate_with_drives_refuses_what_it_does_not_run() -> None:
    arm = _puma()
    law = DrivePID(20.0, 0.5)
    cases = [
        (
            lambda: ad.simulate(arm, lambda t, q, qd: q, None, t_final=0.01),
            "controller must be an armdyn.control.DrivePID",
        ),
        (lambda: ad.simulate(arm, law, lambda t: t, t_final=0.01), "trajectory must be None"),
        (lambda: ad.simulate(arm, law, None, t_final=0.01, method="rk45"), "method does not apply"),
        (lambda: ad.simulate(arm, law, None, t_final=-1.0), "t_final"),
        (lambda: ad.simulate(arm, DrivePID(-1.0, 0.5), None, t_final=0.01), "kp"),
        (lambda: ad.simulate(arm, law, None, t_final=0.01, q0=np.zeros(5)), "q0"),
    ]
    for call, message in cases:
        with pytest.raises(ModelError, match=message):
            call()


def _drive_pid(arm: act.ActuatedArm, kp: float, kv: float, ki: float, path: object):
    """The DrivePID law written out in NumPy on y = [x, z]: the error on each drive's own coordinate (q / r,
    the flexible rotor's q_M, the hydraulic joint's q), the integral held while the input is clipped in
    the error's direction."""
    names, n, m = arm.state_names, arm.n, arm.n_states
    joints = arm.robot.joint_names

    def coordinate(y: np.ndarray, j: int, q_d: np.ndarray, qd_d: np.ndarray) -> tuple[float, float]:
        drive = arm.drives[j]
        if isinstance(drive, act.Hydraulic):
            return q_d[j] - y[j], qd_d[j] - y[n + j]
        r = drive.gear_ratio
        if drive.flexible:
            angle, speed = names.index(f"qM {joints[j]}"), names.index(f"qdM {joints[j]}")
            return q_d[j] / r - y[angle], qd_d[j] / r - y[speed]
        return (q_d[j] - y[j]) / r, (qd_d[j] - y[n + j]) / r

    limits = np.array([d.voltage_limit if isinstance(d, act.DCMotor) else d.current_limit for d in arm.drives])

    def rates(t: float, y: np.ndarray) -> np.ndarray:
        q_d, qd_d, _ = path(t, n)
        errors = np.array([coordinate(y, j, q_d, qd_d) for j in range(n)])
        u = kp * errors[:, 0] + kv * errors[:, 1] + ki * y[m:]
        wound = (np.abs(u) >= limits) & (u * errors[:, 0] > 0)
        return np.concatenate([arm.state_derivative(y[:m], u), np.where(wound, 0.0, errors[:, 0])])

    return rates


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "kind", "gains"),
    [("two_link_planar", "flexible", (20.0, 0.5, 10.0)), ("polar_rp", "hydraulic", (0.1, 0.002, 0.05))],
)
def test_flexible_and_hydraulic_runs_converge_to_the_numpy_full_model(name: str, kind: str, gains: tuple) -> None:
    """ad.simulate on representative flexible and hydraulic drives (PID with its integral, square-root
    orifices) against solve_ivp (DOP853, 1e-11) on state_derivative with the law in NumPy: within 1e-3 of
    each state's range at the default step, converging as the step shrinks (fourth order where the
    right-hand side is smooth)."""
    arm = act.representative_drives(ad.models.load(name), kind)
    q0 = np.full(arm.n, 0.2)
    path = tr.Sinusoid(0.1, 0.5, 0.0, q0)
    law = DrivePID(*gains)
    times = np.linspace(0.0, 0.5, 11)
    y0 = np.concatenate([arm.initial_state(q0), np.zeros(arm.n)])
    reference = solve_ivp(_drive_pid(arm, *gains, path), (0, 0.5), y0, method="DOP853", rtol=1e-11, atol=1e-13,
                          t_eval=times).y.T[:, : arm.n_states]  # fmt: skip
    scale = np.abs(reference).max(axis=0) + 1e-12
    default = ad.simulate(arm, law, path, t_final=0.5, dt=1e-3, q0=q0)
    errors = []
    for step in (None, default.info["step"] / 2, default.info["step"] / 4):
        result = ad.simulate(arm, law, path, t_final=0.5, dt=1e-3, q0=q0, step=step)
        errors.append(np.max(np.abs(result.drives.x[::50] - reference) / scale))
    print(f"{name} {kind}: substeps {default.info['substeps']}, relative errors {errors}")
    assert errors[0] < 1e-3
    if kind == "flexible":
        assert errors[1] / errors[2] > 2**3.5 or errors[2] < 1e-9  # fourth order, down to rounding
    else:  # the orifice's flow gain jumps where the spool crosses zero: RK4 drops to first order there
        assert errors[0] > errors[1] > 1.8 * errors[2]
    if kind == "hydraulic":
        assert default.drives.pressure.shape == (501, 2) and default.drives.spool.shape == (501, 2)
        assert np.allclose(default.tau, [d.area for d in arm.drives] * default.drives.pressure)
        assert np.abs(default.drives.v).max() <= 0.01
    else:
        assert default.drives.pressure is None and default.drives.i.shape == (501, 2)


def test_integral_action_removes_the_gravity_offset_that_pd_leaves() -> None:
    """The book's independent joint control: under PD on the voltages, gravity (the coupling d_i) leaves
    a steady error r R_a G / (K_M kp) at the motor; the integral removes it. (Without Coulomb friction,
    which would hold an offset of its own.)"""
    arm = _puma()
    q0 = np.array(ad.models.puma560().configurations["qn"])
    pd = ad.simulate(arm, DrivePID(20.0, 0.5), None, t_final=3.0, q0=q0)
    pid = ad.simulate(arm, DrivePID(20.0, 0.5, 40.0), None, t_final=3.0, q0=q0)
    offset = np.abs(pd.q[-1] - q0)
    gravity = np.abs(arm.robot.gravity_vector(pd.q[-1]))
    r, R_a, K_M = (np.array([getattr(d, key) for d in arm.drives]) for key in ("gear_ratio", "resistance",
                                                                               "torque_constant"))  # fmt: skip
    predicted = r**2 * R_a * gravity / (K_M * 20.0)  # at the joint
    assert np.allclose(offset, predicted, rtol=0.05, atol=1e-6)
    assert offset[1] > 1e-3 and np.abs(pid.q[-1] - q0).max() < 1e-2 * offset[1]
    assert "PID" in pid.info["controller"] and "PD" in pd.info["controller"]


def test_current_computed_torque_becomes_computed_torque_as_the_current_loop_speeds_up() -> None:
    """Computed torque through current commands against Chapter 4's computed torque on the torque-driven
    mechanics (mechanical_robot): the difference falls as the current loop's bandwidth rises."""
    arm = _puma()
    q0 = np.array(ad.models.puma560().configurations["qn"])
    path = tr.Sinusoid(0.1, 0.5, 0.0, q0)
    ideal = ad.simulate(arm.mechanical_robot(), ad.control.ComputedTorque(100.0, 20.0), path, t_final=1.0,
                        dt=1e-4, q0=q0)  # fmt: skip
    differences = []
    for bandwidth in (1e3, 1e4):
        run = ad.simulate(arm, CurrentComputedTorque(100.0, 20.0, bandwidth=bandwidth), path, t_final=1.0,
                          dt=1e-4, q0=q0)  # fmt: skip
        differences.append(np.abs(run.q - ideal.q).max())
        assert np.abs(run.drives.i).max() < 8.0  # no current limit reached
    print(f"|q - q_ideal| max: {differences} (bandwidth 1e3, 1e4 rad/s)")
    assert differences[1] < 1e-4 and differences[0] / differences[1] > 5  # about 1 / bandwidth
    assert np.abs(ideal.error[-1]).max() < 1e-4  # the start's velocity error decays


def test_the_rk4_step_comes_from_the_drives_time_constants() -> None:
    arm = act.puma560_with_drives()
    q0 = np.zeros(6)
    step = act.stable_step(arm, q0)
    assert step == pytest.approx(0.5 * 1e-3 / 6.7)  # half the wrist armatures' L / R_a
    result = ad.simulate(arm, DrivePID(20.0, 0.5), None, t_final=0.01, q0=q0)
    assert result.info["step"] <= step and result.info["substeps"] == int(np.ceil(1e-3 / step))
    assert act.stable_step(arm, q0, bandwidth=np.full(6, 2e4)) == pytest.approx(0.5 / 2e4)
    flexible = act.representative_drives(ad.models.two_link_planar(), "flexible")
    shafts = act.stable_step(flexible, np.zeros(2))
    assert shafts <= 0.5 * np.min([d.inductance / d.resistance for d in flexible.drives])
    bare = act.with_actuators(ad.models.two_link_planar(), [act.Hydraulic(5e-3, 0.1, 1.0, 1e-12, 1e-4, 1e-12, 1e-4,
                                                                          1e9, 1e7, rotary=True)] * 2)  # fmt: skip
    column = np.sqrt(1e-8 / (1e-4 / 4e9) / np.diag(np.linalg.inv(bare.mechanical_robot().inertia_matrix(np.zeros(2))))
                     ** -1)  # fmt: skip
    assert act.stable_step(bare, np.zeros(2)) == pytest.approx(min(0.5 * 5e-3, 0.15 / column.max()))


@pytest.mark.slow
def test_representative_drives_hold_every_built_in_arm() -> None:
    """Each kind of representative drive on each built-in arm holds its start under gravity (PID), and the
    reduced model exists for the rigid drives."""
    for name in ad.models.names():
        robot = ad.models.load(name)
        q0 = np.asarray(robot.configurations.get("qn", robot.configurations.get("qz", np.zeros(robot.n))), float)
        for kind, law in (("dc", DrivePID(20.0, 0.5, 20.0)), ("flexible", DrivePID(20.0, 0.5, 20.0)),
                          ("hydraulic", DrivePID(0.1, 0.0, 0.1))):  # fmt: skip
            arm = act.representative_drives(robot, kind)
            kinds = {"hydraulic" if isinstance(d, act.Hydraulic) else "flexible" if d.flexible else "dc"
                     for d in arm.drives}  # fmt: skip
            assert arm.n == robot.n and kinds == {kind}
            if kind != "flexible":
                assert arm.reduced_robot().n == robot.n
            result = ad.simulate(arm, law, None, t_final=2.0, q0=q0)
            assert np.abs(result.q[-1] - q0).max() < 2e-2, (name, kind)


def test_bad_laws_and_steps_are_refused() -> None:
    arm = _puma()
    flexible = act.representative_drives(ad.models.two_link_planar(), "flexible")
    cases = [
        (lambda: ad.simulate(flexible, CurrentComputedTorque(100.0, 20.0), None, t_final=0.01), "rigid DC"),
        (
            lambda: ad.simulate(arm, CurrentComputedTorque(100.0, 20.0, bandwidth=0.0), None, t_final=0.01),
            "bandwidth",
        ),
        (lambda: ad.simulate(arm, DrivePID(1.0, 0.1), None, t_final=0.01, step=-1e-4), "step"),
        (lambda: ad.simulate(arm, DrivePID(1.0, 0.1), None, t_final=0.01, step=float("nan")), "step"),
        (lambda: ad.simulate(arm, DrivePID(1.0, 0.1), None, t_final=0.01, runs=2), "runs does not apply"),
        (lambda: ad.simulate(arm, DrivePID(1.0, 0.1), None, t_final=0.01, method="rk45"), "method does not apply"),
        (lambda: ad.simulate(ad.models.puma560(), DrivePID(1.0, 0.1), None, t_final=0.01, step=1e-4), "step applies"),
        (lambda: act.representative_drives(ad.models.two_link_planar(), "pneumatic"), "kind must be one of"),
        (lambda: act.stable_step(arm, np.zeros((2, 6))), "one configuration"),
        (
            lambda: ad.simulate(
                act.representative_drives(ad.models.polar_rp(), "hydraulic"),
                DrivePID(0.1, 0.0),
                None,
                t_final=0.1,
            ),
            "M\\(q\\) is singular at q = \\[0. 0.\\]",
        ),
    ]
    for call, message in cases:
        with pytest.raises(ModelError, match=message):
            call()
    with pytest.raises(TypeError):
        act.representative_drives("puma560")


def test_the_built_in_puma_drives() -> None:
    arm = act.puma560_with_drives()
    assert arm.n == 6 and arm.drives[0].name == "motor q1"
    assert np.allclose(arm.reduced_robot().inertia_matrix(np.zeros(6)), ad.models.puma560().inertia_matrix(np.zeros(6)))
    assert [d.torque_constant for d in arm.drives] == list(act.PUMA560_ELECTRICS["torque_constant"])


def test_a_run_with_drives_that_diverges_is_a_simulation_error_holding_the_run() -> None:
    """An RK4 step seven times the wrist armatures' L / R_a blows the run up; the drives have no limits
    (held currents and clipped voltages would keep it bounded)."""
    arm = act.with_actuators(*act.motor_drives(ad.models.puma560(), **{**act.PUMA560_ELECTRICS,
                                                                       "voltage_limit": np.inf,
                                                                       "current_limit": np.inf}))  # fmt: skip
    with pytest.raises(ad.SimulationError, match="stopped at t = ") as stopped:
        ad.simulate(arm, DrivePID(1e6, 1e4), None, t_final=0.05, step=1e-3, q0=np.full(6, 0.2))
    run = stopped.value.result
    assert 0 < run.t.shape[0] < 51 and run.drives.x.shape == (run.t.shape[0], arm.n_states)
    assert np.all(np.isfinite(run.q))


def test_single_run_options_are_refused_with_many_runs() -> None:
    arm = ad.models.two_link_planar()
    single_run_only = [
        ({"method": "rk45"}, "method"),
        ({"events": [(0.1, arm)]}, "events"),
        ({"progress": print}, "progress"),
        ({"coulomb_smoothing": 0.0}, "coulomb_smoothing"),
    ]
    for options, name in single_run_only:
        with pytest.raises(ad.ArgumentError, match=f"{name} does not apply to many runs at once"):
            ad.simulate(arm, ad.control.PDGravity(1.0, 1.0), None, t_final=0.01, runs=2, **options)


def _limited_puma(current_limit: float, voltage_limit: float = 40.0) -> act.ActuatedArm:
    """The PUMA 560 with the large motors' electrics on every joint and the given limits."""
    electrics = {"torque_constant": 0.22, "back_emf": 0.22, "resistance": 2.1, "inductance": 2e-3}
    bare, drives = act.motor_drives(ad.models.puma560(), **electrics, voltage_limit=voltage_limit,
                                    current_limit=current_limit)  # fmt: skip
    return act.with_actuators(bare, drives)


@pytest.mark.parametrize("step", [None, 1e-3])
def test_the_current_and_voltage_limits_hold_at_every_sample_and_decide_the_run(step: float | None) -> None:
    """A saturated current loop: under a PID that asks for far more than the amplifier gives, each current
    reaches its limit and never leaves it (to rounding), at the default step and at one RK4 step per 1 ms
    sample; the voltage stays within its limit; and runs at 0.5, 5 and 20 A differ (the limit decides the
    motion). Where a current is held, the voltage recorded is the one that holds it, R_a i + K_b qd / r."""
    q0 = np.array(ad.models.puma560().configurations["qn"])
    path, law = tr.Sinusoid(0.5, 2.0, 0.0, q0), DrivePID(20.0, 0.5)
    runs = {}
    for limit in (0.5, 5.0, 20.0):
        arm = _limited_puma(limit)
        run = ad.simulate(arm, law, path, t_final=0.3, q0=q0, step=step)
        current, voltage = run.drives.i, run.drives.v
        assert np.abs(current).max() <= limit * (1 + 1e-15), (limit, np.abs(current).max())
        assert np.abs(current).max() == pytest.approx(limit, rel=1e-12)  # the limit is met
        assert np.abs(voltage).max() <= 40.0
        held = np.abs(current) >= limit * (1 - 1e-15)
        holding = arm._R_a * current + arm._K_b * run.qd / arm._r
        assert held.sum() > 10 and np.allclose(voltage[held], holding[held], rtol=1e-12, atol=1e-12)
        runs[limit] = run
    for low, high in ((0.5, 5.0), (5.0, 20.0)):
        assert np.abs(runs[low].q - runs[high].q).max() > 1e-3, (low, high)


def test_the_spool_stays_within_its_stroke() -> None:
    """A valve whose current limit would take the spool to five times its stroke: the spool meets its hard
    stop and never passes it, while the rest of the run goes on."""
    base = act.representative_drives(ad.models.polar_rp(), "hydraulic")
    arm = act.with_actuators(base.robot, [dataclasses.replace(d, current_limit=0.05) for d in base.drives])
    q0 = np.full(2, 0.2)
    for path, law in ((tr.Sinusoid(0.3, 2.0, 0.0, q0), DrivePID(0.1, 0.0, 0.1)), (None, DrivePID(1.0, 0.01))):
        run = ad.simulate(arm, law, path, t_final=0.5, q0=q0 + (0.1 if path is None else 0.0))
        stroke = np.array([d.stroke for d in arm.drives])
        assert np.all(np.abs(run.drives.spool) <= stroke), np.abs(run.drives.spool).max(axis=0) / stroke
        assert np.abs(run.drives.spool).max() == stroke.max()  # the stop is met
        assert np.abs(run.drives.v).max() <= 0.05


def test_the_hard_stops_put_a_state_back_and_hold_its_rate() -> None:
    """The compiled pieces of the saturated current loop and the spool stop: hold_limits projects a state
    past a limit back onto it (NaN stays NaN), and at the limit full_rates zeroes the rate that points out,
    applying the voltage that holds the current (R_a i + K_b qd_M), while a rate pointing in is left."""
    from armdyn.dynamics import drives as compiled

    arm = act.with_actuators(*act.motor_drives(ad.models.two_link_planar(), torque_constant=0.2, back_emf=0.2,
                                               resistance=2.0, inductance=2e-3, voltage_limit=24.0,
                                               current_limit=3.0))  # fmt: skip
    table = arm.packed_drives()
    x = arm.initial_state(np.array([0.3, -0.2]), np.array([0.5, -1.0]))
    c = arm._slices["i"]
    x[c] = [7.0, np.nan]
    compiled.hold_limits(table, x)
    assert x[c][0] == 3.0 and np.isnan(x[c][1])
    x[c] = [3.0, -3.0]
    model = arm.mechanical_robot().packed
    for u, held in (([24.0, -24.0], True), ([-24.0, 24.0], False)):
        applied, out = np.array(u), np.empty(arm.n_states)
        compiled.full_rates(model, table, x, applied, np.empty(2), out)
        unheld = (np.array(u) - arm._R_a * x[c] - arm._K_b * x[2:4] / arm._r) / arm._L
        if held:
            assert np.all(out[c] == 0.0) and np.all(unheld * x[c] > 0)
            assert np.allclose(applied, arm._R_a * x[c] + arm._K_b * x[2:4] / arm._r, rtol=1e-15)
        else:
            assert np.allclose(out[c], unheld, rtol=1e-15) and np.array_equal(applied, u)


def test_limits_far_away_leave_the_run_unchanged_bit_for_bit() -> None:
    """Limits that are never met (1e6 A, 1e6 V, a 1 m stroke) give the run without limits, bit for bit."""
    q0 = np.array(ad.models.puma560().configurations["qn"])
    path = tr.Sinusoid(0.1, 0.5, 0.0, q0)
    free, far = _limited_puma(np.inf, np.inf), _limited_puma(1e6, 1e6)
    runs = [ad.simulate(arm, DrivePID(20.0, 0.5, 20.0), path, t_final=0.1, q0=q0) for arm in (free, far)]
    assert np.array_equal(runs[0].drives.x, runs[1].drives.x) and np.array_equal(runs[0].drives.v, runs[1].drives.v)
    base = act.representative_drives(ad.models.polar_rp(), "hydraulic")
    free = act.with_actuators(base.robot, [dataclasses.replace(d, current_limit=np.inf, stroke=np.inf)
                                           for d in base.drives])  # fmt: skip
    far = act.with_actuators(base.robot, [dataclasses.replace(d, current_limit=1e6, stroke=1.0) for d in base.drives])
    q0 = np.full(2, 0.2)
    runs = [ad.simulate(arm, DrivePID(0.1, 0.002, 0.05), tr.Sinusoid(0.1, 0.5, 0.0, q0), t_final=0.1, q0=q0)
            for arm in (free, far)]  # fmt: skip
    assert np.array_equal(runs[0].drives.x, runs[1].drives.x) and np.array_equal(runs[0].drives.v, runs[1].drives.v)


def test_a_step_needing_more_than_a_million_steps_a_sample_is_refused_naming_step() -> None:
    motor = act.DCMotor(2e-4, 1e-3, 0.2, 0.2, 2.0, 2e-3, 0.02, voltage_limit=40.0, current_limit=8.0)
    arm = act.with_actuators(ad.models.two_link_planar(), [motor, motor])
    law = DrivePID(20.0, 0.5)
    run = ad.simulate(arm, law, t_final=1e-3, step=2e-9)  # 5 10**5 steps a sample: taken
    assert run.info["substeps"] == 500_000 and np.all(np.isfinite(run.q))
    for step in (1e-12, 1e-300):  # 1e-300 once overflowed the step count; 1e-12 ran for hours
        with pytest.raises(ModelError, match=r"^step = .* RK4 steps per sample .* at most 1,000,000 per sample"):
            ad.simulate(arm, law, t_final=0.01, step=step)
