"""The momentum observer's cost: one sample through MomentumObserver.step (a control loop's entry) and a whole log
of 100,000 samples through observe, on the 7-joint Panda (armdyn.models.panda_gaz2019, sigmoid friction).

Run: `python benchmarks/bench_observer.py` (--quick: fewer repeats). Prints the machine's load and Numba's threads
(observe computes the samples' momenta in parallel) with the figures. The step's figure is a loop over rows made
beforehand, t a Python float (as a control loop's clock and sensor arrays give them), best and median of 7 runs; the
same loop indexing the rows out of the log's arrays, which costs four NumPy objects per call, is printed beside it.
"""

from __future__ import annotations

import os
import sys
import time

import numba
import numpy as np

import armdyn as ad
from armdyn.observers.momentum import MomentumObserver, observe


def _step_loop(observer: MomentumObserver, t: list, q: list, qd: list, tau: list) -> float:
    """Seconds per step: the samples' rows made beforehand, as a control loop has its sensors' arrays."""
    observer.reset()
    start = time.perf_counter()
    for k in range(len(t)):
        observer.step(t[k], q[k], qd[k], tau[k])
    return (time.perf_counter() - start) / len(t)


def main() -> None:
    quick = "--quick" in sys.argv
    arm = ad.models.panda_gaz2019()
    rng = np.random.default_rng(0)
    samples = 100_000
    t = np.arange(samples) * 1e-3
    q = arm.configurations["qr"] + 0.3 * np.sin(np.outer(t, rng.uniform(0.5, 2.0, 7)))
    qd, tau = np.gradient(q, t, axis=0), rng.normal(size=(samples, 7))
    print(f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}; {numba.get_num_threads()} threads")
    observer = MomentumObserver(arm, gains=50.0)
    for k in range(100):  # warm-up: the compiled kernels loaded
        observer.step(t[k], q[k], qd[k], tau[k])
    calls = 2_000 if quick else 20_000
    rows = (t[:calls].tolist(), list(q[:calls]), list(qd[:calls]), list(tau[:calls]))  # t: Python floats, as a clock's
    steps = [_step_loop(observer, *rows) for _ in range(3 if quick else 7)]
    observer.reset()
    start = time.perf_counter()
    for k in range(calls):  # the rows indexed out of the log in the loop: four NumPy objects made per call
        observer.step(t[k], q[k], qd[k], tau[k])
    indexed = (time.perf_counter() - start) / calls
    observe(arm, t[:1000], q[:1000], qd[:1000], tau[:1000])
    times = []
    for _ in range(2 if quick else 5):
        start = time.perf_counter()
        observe(arm, t, q, qd, tau)
        times.append(time.perf_counter() - start)
    print(f"MomentumObserver.step, one sample of 7 joints: best {min(steps) * 1e6:.2f} us, median "
          f"{np.median(steps) * 1e6:.2f} us ({indexed * 1e6:.2f} us with the rows indexed out of the log arrays "
          "in the loop)")  # fmt: skip
    print(f"observe, a log of {samples:,} samples of 7 joints: best {min(times) * 1e3:.0f} ms, "
          f"median {np.median(times) * 1e3:.0f} ms")  # fmt: skip


if __name__ == "__main__":
    main()
