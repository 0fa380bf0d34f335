"""Example 4.2-1: the RR arm (a1 = a2 = 2 m) drawing a circle under computed torque in task
coordinates, tau = J^T (Mbar (yddot_d + kv edot + kp e) + Nbar) (Section 3.5).

The tool starts 2 cm off the circle (centre (2, 1) m, radius 0.5 m, one turn in 2 s); with
kp = 400, kv = 40 (wn = 20, critically damped) the path error falls below 1e-4 m within
half a second. The figure draws the path over the desired circle, and the path error.
Run: .venv/bin/python examples/example_4_2_1.py
"""

from pathlib import Path

import numpy as np

import armdyn as ad
from armdyn import task_space, trajectories
from armdyn.simulation import Result, simulate

ARM = ad.models.two_link_planar(1.0, 1.0, 2.0, 2.0, g=9.8)
CENTRE, RADIUS, PERIOD = (2.0, 1.0), 0.5, 2.0
CIRCLE = ad.trajectories.Circle(CENTRE, RADIUS, PERIOD)
OUTPUT = task_space.PlanarPosition()


def run(t_final: float = 2.0, dt: float = 1e-3, offset: float = 0.02) -> Result:
    """The closed loop from a start ``offset`` (rad) off the circle in each joint."""
    joint_path = trajectories.CartesianCircle(2.0, 2.0, CENTRE, RADIUS, PERIOD)  # the same circle, in joints
    q0, qd0, _ = joint_path(0.0)
    law = ad.control.TaskComputedTorque(OUTPUT, CIRCLE, 400.0, 40.0)
    return simulate(ARM, law, joint_path, t_final=t_final, dt=dt, q0=q0 + offset * np.array([1.0, -1.0]), qd0=qd0)


def path_error(result: Result) -> np.ndarray:
    """|y(t) - y_d(t)| (m) at every sample, from the run's task record."""
    return np.linalg.norm(result.task.error, axis=1)


def figure(result: Result) -> object:
    """The tool path drawn over the desired circle, and the path error on a log scale (a matplotlib Figure)."""
    import matplotlib.pyplot as plt

    error = path_error(result)
    drawn = result.task.y
    turn = np.linspace(0.0, 2 * np.pi, 200)
    fig, (path, err) = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained")
    path.plot(CENTRE[0] + RADIUS * np.cos(turn), CENTRE[1] + RADIUS * np.sin(turn), "k--", lw=1, label="desired circle")
    path.plot(drawn[:, 0], drawn[:, 1], color="C0", label="tool path")
    path.plot(*drawn[0], "o", color="C1", label="start")
    path.set(xlabel="x (m)", ylabel="y (m)", aspect="equal", title="tool path")
    path.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False, fontsize=8)
    err.semilogy(result.t, np.maximum(error, 1e-12), color="C0")
    err.set(xlabel="time (s)", ylabel="path error |y - y_d| (m)", title="path error")
    err.grid(True, alpha=0.3)
    fig.suptitle("Example 4.2-1: computed torque in task coordinates (kp = 400, kv = 40), a1 = a2 = 2 m", fontsize=10)
    return fig


if __name__ == "__main__":
    import matplotlib

    matplotlib.use("Agg")

    Path("out").mkdir(exist_ok=True)
    result = run()
    error = path_error(result)
    print(f"path error: {error[0]:.2e} m at the start, largest after 0.5 s {error[result.t >= 0.5].max():.2e} m")
    figure(result).savefig("out/example_4_2_1.png", dpi=150)
    print("wrote out/example_4_2_1.png")
