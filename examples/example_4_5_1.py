"""Example 4.5-1: digital computed-torque control, sample periods from 5 ms up.

The controller runs once per sample period T with its torque held (zero-order hold);
RK4 with a 5 ms step. Small periods track as well as continuous control; near T = 0.1 s
the loop sits on its stability boundary and a sustained oscillation (a limit cycle)
appears. Run: .venv/bin/python examples/example_4_5_1.py
"""

from pathlib import Path

import numpy as np
from example_4_4_1 import ARM, DESIRED

from armdyn.control import ComputedTorque, Digital
from armdyn.simulation import Result, simulate


def run(period: float, t_final: float = 20.0) -> Result:
    return simulate(ARM, Digital(ComputedTorque(100.0, 20.0), period), DESIRED, t_final=t_final, dt=0.005)


def amplitude(result: Result, start: float, end: float) -> float:
    window = (result.t >= start) & (result.t < end)
    return float(np.abs(result.error[window]).max())


if __name__ == "__main__":
    Path("out").mkdir(exist_ok=True)
    for period in (0.005, 0.02, 0.05, 0.08, 0.1):
        result = run(period)
        print(f"T = {period * 1000:.0f} ms: error amplitude 5-10 s {amplitude(result, 5, 10):.2e} rad, "
              f"15-20 s {amplitude(result, 15, 20):.2e} rad")  # fmt: skip
    run(0.1).plot("out/example_4_5_1.png", title="Example 4.5-1: digital computed torque, T = 0.1 s")
