"""Generated code for the robot equation (armdyn.symbolic.generate_code), arm by arm: the time to derive
(trace), generate and compile it, its operation counts, and its speed beside the compiled recursive kernels,
one state through the public call and a batch of 100,000 states. The Robotics Toolbox's symbolic RNE and
SymPy's Kane method, measured on the same arms with the same counter (after common-subexpression
elimination), are given for reference as they were measured (benchmarks/bench_symbolic.py runs the
Toolbox's symbolic rne() for the PUMA 560 side by side).

Run: .venv/bin/python benchmarks/bench_codegen.py
"""

from __future__ import annotations

import time
import timeit
import warnings
from pathlib import Path

import numpy as np

import armdyn as ad
from armdyn.symbolic import generate_code

ROBOTS = Path(ad.__file__).resolve().parents[2] / ".venv/lib/python3.11/site-packages/cmeel.prefix/share"
PANDA = ROBOTS / "example-robot-data/robots/panda_description/urdf/panda.urdf"
PEERS = {  # tau operations after CSE: (Toolbox symbolic RNE, SymPy Kane), measured on the same arms
    "spatial3": (340, 311),
    "puma560": (890, 2518),
    "stanford": (742, 2083),
    "panda7": (2130, 11660),
}


def spatial3() -> ad.Robot:
    """A 3-joint spatial arm whose DH twists are the floats pi/2 and -pi/2."""
    rows = [
        dict(a=0.1, alpha=np.pi / 2, d=0.3, mass=1.0, com=[0.0, 0.05, 0.0], inertia=[0.01, 0.02, 0.015]),
        dict(a=0.4, alpha=0.0, mass=2.0, com=[-0.2, 0.0, 0.0], inertia=[0.01, 0.05, 0.05]),
        dict(a=0.0, alpha=-np.pi / 2, d=0.1, mass=0.5, com=[0.0, 0.0, 0.02], inertia=[0.002, 0.002, 0.001]),
    ]
    return ad.Robot.from_dh(rows, name="spatial3")


def panda7() -> ad.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arm = ad.load_urdf(PANDA, locked={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02})
    return arm.without_friction()


def best(function: object, number: int) -> float:
    """The best of 5 mean times of ``function()``, in microseconds."""
    function()
    return min(timeit.repeat(function, number=number, repeat=5)) / number * 1e6


def main() -> None:
    arms = {"spatial3": spatial3, "puma560": ad.models.puma560, "stanford": ad.models.stanford, "panda7": panda7}
    print(
        "| arm | n | trace + generate s | compile s | tau ops (mul, add, calls) | M ops | Toolbox RNE tau ops | "
        "Kane tau ops | tau one state us (kernel) | M one state us (kernel) | tau batch us/state (kernel) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, make in arms.items():
        print(row(name, make()))


def row(name: str, arm: ad.Robot) -> str:
    """One arm's line of the table."""
    start = time.perf_counter()
    code = generate_code(arm)
    code.python(), code.c()
    generated = time.perf_counter() - start
    start = time.perf_counter()
    compiled = code.compile()
    compiling = time.perf_counter() - start
    counts = code.operation_counts()
    tau = counts["tau"]
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.uniform(-1, 1, (3, arm.n))
    Q, QD, QDD = rng.uniform(-1, 1, (3, 100_000, arm.n))
    assert np.allclose(compiled.tau(q, qd, qdd), arm.inverse_dynamics(q, qd, qdd), rtol=1e-12, atol=1e-12)
    one = best(lambda: compiled.tau(q, qd, qdd), 20000)
    kernel = best(lambda: arm.inverse_dynamics(q, qd, qdd), 20000)
    one_m = best(lambda: compiled.M(q), 20000)
    kernel_m = best(lambda: arm.inertia_matrix(q), 20000)
    batch = best(lambda: compiled.tau(Q, QD, QDD), 3) / 1e5
    kernel_batch = best(lambda: arm.inverse_dynamics(Q, QD, QDD), 3) / 1e5
    toolbox, kane = PEERS[name]
    return (
        f"| {name} | {arm.n} | {generated:.3f} | {compiling:.1f} | {tau['total']} ({tau['multiplications']}, "
        f"{tau['additions']}, {tau['calls']}) | {counts['M']['total']} | {toolbox} | {kane} | "
        f"{one:.2f} ({kernel:.2f}, {one / kernel:.2f}x) | {one_m:.2f} ({kernel_m:.2f}, {one_m / kernel_m:.2f}x) "
        f"| {batch:.3f} ({kernel_batch:.3f}, {batch / kernel_batch:.2f}x) |"
    )


if __name__ == "__main__":
    main()
