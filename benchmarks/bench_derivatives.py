"""Derivatives of the robot equation: armdyn's analytic RNEA and forward-dynamics derivatives beside Pinocchio's
computeRNEADerivatives and computeABADerivatives, one state and a batch, and statespace.linearize.

Run: .venv/bin/python benchmarks/bench_derivatives.py
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np

import armdyn as ad

ROBOTS = Path(ad.__file__).resolve().parents[2] / ".venv/lib/python3.11/site-packages/cmeel.prefix/share"
URDFS = {"UR5": "ur_description/urdf/ur5_robot.urdf", "Panda": "panda_description/urdf/panda.urdf"}


def per_call(function: object, repeats: int = 2000) -> float:
    """The best of 5 mean times of ``function()``, in microseconds."""
    function()
    best = np.inf
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(repeats):
            function()
        best = min(best, (time.perf_counter() - start) / repeats)
    return best * 1e6


def main() -> None:
    for name, relative in URDFS.items():
        compare(name, ROBOTS / "example-robot-data/robots" / relative)


def compare(name: str, path: Path) -> None:
    """One arm: the derivatives' times beside Pinocchio's."""
    import pinocchio as pin

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(path).without_friction()
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-1, 1, (3, arm.n))
    tau = arm.inverse_dynamics(q, qd, qdd)
    ours = per_call(lambda: arm.inverse_dynamics_derivatives(q, qd, qdd))
    theirs = per_call(lambda: pin.computeRNEADerivatives(model, data, q, qd, qdd))
    ours_fd = per_call(lambda: arm.forward_dynamics_derivatives(q, qd, tau), 500)
    theirs_fd = per_call(lambda: pin.computeABADerivatives(model, data, q, qd, tau))
    count = 10_000
    Q, QD, QDD = rng.uniform(-1, 1, (3, count, arm.n))
    TAU = arm.inverse_dynamics(Q, QD, QDD)
    batch = per_call(lambda: arm.inverse_dynamics_derivatives(Q, QD, QDD), 3) / count
    batch_fd = per_call(lambda: arm.forward_dynamics_derivatives(Q, QD, TAU), 3) / count

    def pin_loop() -> None:
        for k in range(count):
            pin.computeRNEADerivatives(model, data, Q[k], QD[k], QDD[k])

    def pin_loop_fd() -> None:
        for k in range(count):
            pin.computeABADerivatives(model, data, Q[k], QD[k], TAU[k])

    loop = per_call(pin_loop, 1) / count
    loop_fd = per_call(pin_loop_fd, 1) / count
    linearize = per_call(lambda: ad.statespace.linearize(arm, q, qd, tau), 200)
    print(f"{name} (n = {arm.n}), us per state:")
    print(f"  RNEA derivatives, one state: armdyn {ours:.2f}, Pinocchio {theirs:.2f} ({theirs / ours:.2f}x)")
    print(f"  forward dynamics derivatives, one state: armdyn {ours_fd:.2f}, Pinocchio ABA derivatives "
          f"{theirs_fd:.2f} ({theirs_fd / ours_fd:.2f}x)")  # fmt: skip
    print(f"  RNEA derivatives, batch of {count}: armdyn {batch:.2f}, Pinocchio in a Python loop {loop:.2f} "
          f"({loop / batch:.2f}x)")  # fmt: skip
    print(f"  forward dynamics derivatives, batch of {count}: armdyn {batch_fd:.2f}, Pinocchio ABA derivatives in "
          f"a Python loop {loop_fd:.2f} ({loop_fd / batch_fd:.2f}x)")  # fmt: skip
    print(f"  statespace.linearize: {linearize:.1f} us (complex step through the Lagrange-Euler reference, the "
          "former route: 14.6 ms on the Panda)")  # fmt: skip


if __name__ == "__main__":
    main()
