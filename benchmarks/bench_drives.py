"""The PUMA 560 driven through its DC motors' electrics (Section 3.6): 10 s under motor-side voltage
PD, armdyn's compiled run against scipy's solve_ivp on a plain NumPy right-hand side.

Run: .venv/bin/python benchmarks/bench_drives.py
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from scipy.integrate import solve_ivp

import armdyn as ad
from armdyn import actuators as act
from armdyn import trajectories as tr
from armdyn.control import CurrentComputedTorque, DrivePID

T_FINAL = 10.0


def puma() -> act.ActuatedArm:
    """The PUMA 560's motors as DC drives (representative electrics), without Coulomb friction: its jump at
    rest makes an adaptive solver crawl, which would time the friction law rather than the dynamics."""
    arm = ad.models.puma560()
    arm = arm.replace([dataclasses.replace(link, coulomb=(0.0, 0.0)) for link in arm.links])
    bare, drives = act.motor_drives(arm, torque_constant=0.22, back_emf=0.22, resistance=2.1,
                                    inductance=2e-3, voltage_limit=40.0)  # fmt: skip
    return act.with_actuators(bare, drives)


def numpy_rates(arm: act.ActuatedArm, path: tr.Sinusoid, kp: float, kv: float):
    """The right-hand side a user writes without armdyn's simulation: M, C, G by NumPy solves each call."""
    r = arm._r

    def rates(t: float, x: np.ndarray) -> np.ndarray:
        q_d, qd_d, _ = path(t, 6)
        return arm.state_derivative(x, kp * (q_d - x[:6]) / r + kv * (qd_d - x[6:12]) / r)

    return rates


def main() -> None:
    arm = puma()
    q0 = np.array(ad.models.puma560().configurations["qn"])
    path, law = tr.Sinusoid(0.1, 0.5, 0.0, q0), DrivePID(20.0, 0.5)
    ad.simulate(arm, law, path, t_final=0.01, q0=q0)  # compile (or load the cache)
    walls = []
    for _ in range(3):
        start = time.perf_counter()
        result = ad.simulate(arm, law, path, t_final=T_FINAL, q0=q0)
        walls.append(time.perf_counter() - start)
    wall = min(walls)
    span = 0.2  # solve_ivp is slow: time a fifth of a second and scale
    numpy_rates(arm, path, 20.0, 0.5)(0.0, arm.initial_state(q0))  # load the batched kernels before timing
    start = time.perf_counter()
    solution = solve_ivp(numpy_rates(arm, path, 20.0, 0.5), (0.0, span), arm.initial_state(q0), method="LSODA",
                         rtol=1e-6, atol=1e-9)  # fmt: skip
    scipy_wall = (time.perf_counter() - start) * T_FINAL / span
    difference = np.abs(solution.y[:6, -1] - result.q[int(span / 1e-3)]).max()
    print(f"PUMA 560 with DC motors and electrics, {T_FINAL:g} s under voltage PD ({result.info['substeps']} RK4 "
          "steps per 1 ms sample)")  # fmt: skip
    print(f"  armdyn simulate (compiled RK4): {wall:.3f} s wall, {T_FINAL / wall:.0f}x real time")
    print(f"  scipy solve_ivp (LSODA, rtol 1e-6) on a NumPy right-hand side: {scipy_wall:.1f} s for {T_FINAL:g} s "
          f"(timed over {span:g} s), {scipy_wall / wall:.0f}x slower")  # fmt: skip
    print(f"  q differs by {difference:.1e} rad at {span:g} s")
    print("Other drives and laws, 10 s each (compiled RK4, step from the drives' time constants):")
    others = [
        ("PUMA 560, built-in drives, current computed torque", act.puma560_with_drives(),
         CurrentComputedTorque(100.0, 20.0)),
        ("PUMA 560, flexible shafts, PID", act.representative_drives(ad.models.puma560(), "flexible"),
         DrivePID(20.0, 0.5, 20.0)),
        ("PUMA 560, hydraulic, PID", act.representative_drives(ad.models.puma560(), "hydraulic"),
         DrivePID(0.1, 0.0, 0.1)),
    ]  # fmt: skip
    for label, driven, other in others:
        ad.simulate(driven, other, path, t_final=0.01, q0=q0)
        start = time.perf_counter()
        run = ad.simulate(driven, other, path, t_final=T_FINAL, q0=q0)
        seconds = time.perf_counter() - start
        print(f"  {label}: {seconds:.3f} s wall, {T_FINAL / seconds:.0f}x real time ({run.info['substeps']} steps "
              f"per sample), max |e| after 1 s {np.abs(run.error[1000:]).max():.2g} rad")  # fmt: skip


if __name__ == "__main__":
    main()
