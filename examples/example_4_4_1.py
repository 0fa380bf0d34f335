"""Example 4.4-1: PD computed-torque control of the two-link arm (m1 = m2 = a1 = a2 = 1, g = 9.8).

theta_1d = 0.1 sin(pi t), theta_2d = 0.1 cos(pi t); kp = 100, kv = 20 (wn = 10, critically
damped). The errors die out within about 0.6 s; a 10 ms integration step leaves ripple in
the torques, a 1 ms step none. Run: .venv/bin/python examples/example_4_4_1.py
"""

from pathlib import Path

import numpy as np

import armdyn as ad
from armdyn.control import ComputedTorque
from armdyn.simulation import Result, simulate
from armdyn.trajectories import Sinusoid

ARM = ad.models.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
DESIRED = Sinusoid([0.1, 0.1], [0.5, 0.5], phase=[0.0, np.pi / 2])


def run(dt: float = 1e-3, t_final: float = 5.0) -> Result:
    return simulate(ARM, ComputedTorque(100.0, 20.0), DESIRED, t_final=t_final, dt=dt)


def torque_ripple(result: Result) -> float:
    """The largest step-to-step change of the torque after the transient (N m)."""
    late = result.t >= 1.0
    return float(np.abs(np.diff(result.tau[late], axis=0)).max())


if __name__ == "__main__":
    Path("out").mkdir(exist_ok=True)
    fine, coarse = run(1e-3), run(1e-2)
    for label, result in (("1 ms", fine), ("10 ms", coarse)):
        late = np.abs(result.error[result.t >= 1.0]).max()
        print(f"{label} step: largest error after 1 s {late:.2e} rad, torque ripple {torque_ripple(result):.3f} N m")
    fine.plot("out/example_4_4_1.png", title="Example 4.4-1: PD computed torque, 1 ms step")
    coarse.plot("out/example_4_4_1_coarse.png", title="Example 4.4-1: PD computed torque, 10 ms step")
