"""Identification's speed and memory on a log of 20,000 samples of a 7-joint arm: preprocessing (resampling,
zero-phase filtering, differentiation, decimation), the friction law's fit, least squares and the physically
consistent estimate, each timed; the peak memory traced (tracemalloc, which sees NumPy's arrays) against the
log's own size.

The log is the real Panda's of Gaz et al. (2019) where ../shared holds it (20,544 samples), else a simulated
Panda's of the same length. Run: `python benchmarks/bench_identification_speed.py` (--quick: fewer repeats).
"""

from __future__ import annotations

import os
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np

import armdyn as ad
from armdyn.identification.log import Log, read_gaz_panda
from armdyn.identification.workflow import identify_log

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "panda-gaz2019"
FINGERS = {"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02}


def panda() -> ad.Robot:
    import sysconfig

    path = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ad.load_urdf(path / "panda_description/urdf/panda.urdf", locked=FINGERS)


def the_log(arm: ad.Robot) -> tuple[Log, str]:
    if SHARED.is_dir():
        return read_gaz_panda(SHARED), "the real Panda log of Gaz et al. (2019)"
    rng = np.random.default_rng(0)
    t = (np.arange(20_544) + rng.uniform(-0.49, 0.49, 20_544)) / 1000.0
    phase = rng.uniform(0, 2 * np.pi, (3, 7))
    q = sum(0.3 * np.sin((k + 1) * 0.6 * t[:, None] + phase[k]) for k in range(3)) + np.array(
        [0, 0, 0, -1.5, 0, 1.5, 0]
    )
    qd = np.gradient(q, t, axis=0)
    tau = arm.inverse_dynamics(q, qd, np.gradient(qd, t, axis=0))
    return Log(t=t, q=q, tau=tau * (1 + 0.01 * rng.standard_normal(tau.shape))), "a simulated Panda log"


def main() -> None:
    quick = "--quick" in sys.argv
    arm = panda()
    log, what = the_log(arm)
    size = sum(a.nbytes for a in (log.t, log.q, log.qd, log.tau) if a is not None)
    print(f"{what}: {log.samples} samples of {log.n} joints, {size / 2**20:.2f} MiB; load average "
          f"{', '.join(f'{x:.2f}' for x in os.getloadavg())}")  # fmt: skip
    identify_log(arm, log, friction="sigmoid")  # warm-up: imports, the solver's first problem
    for friction in ("coulomb", "sigmoid"):
        best: dict[str, float] = {}
        totals = []
        for _ in range(2 if quick else 5):
            start = time.perf_counter()
            model = identify_log(arm, log, friction=friction)
            totals.append(time.perf_counter() - start)
            for key, value in model.timings.items():
                best[key] = min(best.get(key, np.inf), value)
        tracemalloc.start()
        identify_log(arm, log, friction=friction)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        steps = ", ".join(f"{key} {value:.3f}" for key, value in best.items())
        print(f"{friction:8s} whole: best {min(totals):.3f} s, median {np.median(totals):.3f} s ({steps}); "
              f"peak memory {peak / 2**20:.1f} MiB = {peak / size:.1f} x the log")  # fmt: skip


if __name__ == "__main__":
    main()
