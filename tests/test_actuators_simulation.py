"""The arm driven through its motors' electrics: the compiled RK4 run against the NumPy full model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import armdyn as ad
from armdyn import actuators as act
from armdyn import trajectories as tr
from armdyn.errors import ModelError


def _puma() -> act.ActuatedArm:
    """The PUMA 560's motors as DC drives with representative electrics, without Coulomb friction (its
    discontinuity at rest would make the tight reference integration crawl)."""
    puma = ad.models.puma560()
    smooth = puma.replace([dataclasses.replace(link, coulomb=(0.0, 0.0)) for link in puma.links])
    bare, drives = act.motor_drives(smooth, torque_constant=0.22, back_emf=0.22, resistance=2.1,
                                    inductance=2e-3, voltage_limit=40.0, current_limit=8.0)  # fmt: skip
    return act.with_actuators(bare, drives)


def test_compiled_run_converges_to_the_numpy_full_model_integrated_tightly() -> None:
    """ad.simulate on an ActuatedArm (RK4, its step at most half of L/R) against solve_ivp (DOP853, 1e-11) on
    ActuatedArm.state_derivative with the same motor-side PD law: q, qd and the currents within 1e-2 of their
    range at the default 1 ms samples (3 RK4 steps each), and fourth order as the step shrinks."""
    arm = _puma()
    q0 = np.array(ad.models.puma560().configurations["qn"])
    path, law = tr.Sinusoid(0.1, 0.5, 0.0, q0), act.VoltagePD(20.0, 0.5)
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
    assert errors[1e-3] < 1e-2 and errors[1e-4] < 1e-4
    assert errors[2.5e-4] / errors[1e-4] > 2.5**3.5  # fourth order
    result = ad.simulate(arm, law, path, t_final=0.3, dt=1e-3, q0=q0)
    assert result.info["substeps"] == 3 and result.drives.x.shape == (301, 18)
    assert np.abs(result.drives.i).max() <= 8.0 + 1e-12 and np.abs(result.drives.v).max() <= 40.0
    assert np.allclose(result.tau, arm._K_M * result.drives.i / r)
    assert result.q_d is not None and np.abs(result.error[-1]).max() < 0.02


def test_simulate_with_drives_refuses_what_it_does_not_run() -> None:
    arm = _puma()
    law = act.VoltagePD(20.0, 0.5)
    cases = [
        (lambda: ad.simulate(arm, lambda t, q, qd: q, None, t_final=0.01), "controller must be an armdyn.actuators"),
        (lambda: ad.simulate(arm, law, lambda t: t, t_final=0.01), "trajectory must be None"),
        (lambda: ad.simulate(arm, law, None, t_final=0.01, method="rk45"), "does not take method"),
        (lambda: ad.simulate(arm, law, None, t_final=-1.0), "t_final"),
        (lambda: ad.simulate(arm, act.VoltagePD(-1.0, 0.5), None, t_final=0.01), "kp"),
        (lambda: ad.simulate(arm, law, None, t_final=0.01, q0=np.zeros(5)), "q0"),
    ]
    for call, message in cases:
        with pytest.raises(ModelError, match=message):
            call()
    bare = ad.models.two_link_planar()
    flexible = act.with_actuators(bare, [act.DCMotor(1e-3, 1e-4, 0.1, 0.1, 1.0, 1e-3, 0.1, stiffness=100.0)] * 2)
    with pytest.raises(ModelError, match="flexible or hydraulic"):
        ad.simulate(flexible, law, None, t_final=0.01)
