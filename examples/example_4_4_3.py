"""Example 4.4-3: PD plus gravity, tau = kp e + kv edot + G(q), for wn = 10, 25, 50.

kp = wn^2, kv = 2 wn. Without the rest of the dynamics the errors stay bounded but not
zero, and shrink as the gains grow. Run: .venv/bin/python examples/example_4_4_3.py
"""

from pathlib import Path

import numpy as np
from example_4_4_1 import ARM, DESIRED

from armdyn.control import PDGravity
from armdyn.simulation import Result, simulate


def run(wn: float, t_final: float = 10.0) -> Result:
    return simulate(ARM, PDGravity(wn**2, 2 * wn), DESIRED, t_final=t_final, dt=1e-3)


if __name__ == "__main__":
    Path("out").mkdir(exist_ok=True)
    for wn in (10, 25, 50):
        result = run(wn)
        error = np.abs(result.error[result.t >= 2.0]).max(axis=0)
        print(f"wn = {wn}: largest error after 2 s {error.round(5)} rad")
        result.plot(f"out/example_4_4_3_wn{wn}.png", title=f"Example 4.4-3: PD plus gravity, wn = {wn}")
