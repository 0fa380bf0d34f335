"""Example 4.4-2: PID computed-torque control against a constant disturbance.

tau_d = 1 N m on each joint. PD computed torque (kp = 100, kv = 20) leaves a steady bias,
about 0.03 rad on joint 2 (e = M^-1 tau_d / kp); the integral gain ki = 500 removes it.
Run: .venv/bin/python examples/example_4_4_2.py
"""

from pathlib import Path

import numpy as np
from example_4_4_1 import ARM, DESIRED

from armdyn.control import ComputedTorque
from armdyn.simulation import Result, simulate


def run(ki: float, t_final: float = 5.0) -> Result:
    return simulate(ARM, ComputedTorque(100.0, 20.0, ki=ki), DESIRED, t_final=t_final, dt=1e-3, disturbance=[1.0, 1.0])


def bias(result: Result) -> np.ndarray:
    """The largest error per joint once the transient is over (t >= 3 s)."""
    return np.abs(result.error[result.t >= 3.0]).max(axis=0)


if __name__ == "__main__":
    Path("out").mkdir(exist_ok=True)
    pd, pid = run(0.0), run(500.0)
    print(f"PD: bias {bias(pd).round(4)} rad; PID (ki = 500): {bias(pid).round(5)} rad")
    pd.plot("out/example_4_4_2_pd.png", title="Example 4.4-2: PD computed torque, tau_d = 1 N m")
    pid.plot("out/example_4_4_2_pid.png", title="Example 4.4-2: PID computed torque, ki = 500")
