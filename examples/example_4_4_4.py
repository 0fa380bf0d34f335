"""Example 4.4-4: classical joint PD/PID control, tau = kp e + kv edot + ki int e (no model).

kp = 100, kv = 20 performs badly (errors of a third of a radian); wn = 50 (kp = 2500,
kv = 100) with ki = 1000 tracks well, but asks for 250 N m at the start; with torque
limits of +-35 N m the integrator winds up while the torque is saturated, and the error
overshoots about twice as far. Run: .venv/bin/python examples/example_4_4_4.py
"""

from pathlib import Path

import numpy as np
from example_4_4_1 import ARM, DESIRED

from armdyn.control import PID, Saturated
from armdyn.simulation import Result, simulate


def run(kp: float, kv: float, ki: float = 0.0, limit: float = np.inf, t_final: float = 5.0) -> Result:
    return simulate(ARM, Saturated(PID(kp, kv, ki), limit), DESIRED, t_final=t_final, dt=1e-3)


if __name__ == "__main__":
    Path("out").mkdir(exist_ok=True)
    weak = run(100, 20)
    print(f"PD kp = 100, kv = 20: largest error after 2 s {np.abs(weak.error[weak.t >= 2]).max():.3f} rad")
    free, limited = run(2500, 100, 1000), run(2500, 100, 1000, limit=35.0)
    for label, result in (("no limit", free), ("+-35 N m", limited)):
        early = np.abs(result.error[(result.t > 0.05) & (result.t < 0.5)]).max()
        print(f"PID wn = 50, ki = 1000, {label}: peak error 0.05-0.5 s {early:.4f} rad, "
              f"largest torque {np.abs(result.tau).max():.1f} N m")  # fmt: skip
    limited.plot("out/example_4_4_4.png", title="Example 4.4-4: PID with +-35 N m torque limits (windup)")
