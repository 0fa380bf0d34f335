"""Many closed-loop runs at once (armdyn.simulate with runs=) beside a Python loop over ad.simulate and MuJoCo's
rollout, on one machine.

1. 10,000 PUMA 560 computed-torque runs of 2 s at 1 kHz with random payloads, summaries only: runs per
   second on 1 and 2 threads (parallel efficiency), beside a Python loop over ad.simulate.
2. 1,000 UR5 runs of 1 s at 1 ms, RK4, zero torque, from random initial states: simulate(runs=) beside
   MuJoCo's rollout on the same arm (its URDF, contacts and joint limits off) at the same thread count,
   with the final states compared.

Run: .venv/bin/python benchmarks/bench_ensemble.py [--runs 10000]
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

import numpy as np

import armdyn as ad
from armdyn import control
from armdyn import trajectories as tr
from armdyn.simulation import plant_variants, simulate

ROBOTS = Path(ad.__file__).resolve().parents[2] / ".venv/lib/python3.11/site-packages/cmeel.prefix/share"
UR5 = "example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"


def puma_study(runs: int) -> None:
    arm = ad.models.puma560()
    q0 = arm.configuration("qn")
    law, path = control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 0.5, 0.0, q0)
    payloads = np.random.default_rng(0).uniform(0.0, 2.0, runs)
    plants = plant_variants(arm, runs, payload_mass=payloads)
    simulate(arm, law, path, t_final=0.01, q0=q0, plants=plant_variants(arm, 2))  # compile or load
    rates = {}
    for threads in (1, 2):
        start = time.perf_counter()
        result = simulate(arm, law, path, t_final=2.0, q0=q0, plants=plants, threads=threads)
        rates[threads] = runs / (time.perf_counter() - start)
    loop_runs = 200
    start = time.perf_counter()
    for mass in payloads[:loop_runs]:
        ad.simulate(arm.with_payload(float(mass)), law, path, t_final=2.0, q0=q0)
    loop_rate = loop_runs / (time.perf_counter() - start)
    start = time.perf_counter()
    for _ in range(loop_runs):  # the same arm every run: the loop's floor, without building a variant
        ad.simulate(arm, law, path, t_final=2.0, q0=q0)
    bare_rate = loop_runs / (time.perf_counter() - start)
    per_run = result.summaries[0].nbytes + result.outcome[0].nbytes
    print(f"PUMA 560, {runs} computed-torque runs of 2 s at 1 kHz, random payloads 0-2 kg, summaries only")
    print(f"  simulate(runs=), 1 thread: {rates[1]:.0f} runs/s; 2 threads: {rates[2]:.0f} runs/s "
          f"(parallel efficiency {rates[2] / (2 * rates[1]):.0%})")  # fmt: skip
    print(f"  Python loop over ad.simulate (with_payload each run, {loop_runs} runs timed): {loop_rate:.0f} runs/s")
    print(f"  the same loop without building a variant (one arm): {bare_rate:.0f} runs/s")
    print(f"  simulate(runs=) per core: {rates[1] / loop_rate:.2f}x the loop ({rates[1] / bare_rate:.2f}x the loop's "
          f"floor); on 2 threads {rates[2] / loop_rate:.2f}x")  # fmt: skip
    print(f"  memory kept per run: {per_run} bytes; max |error| after 1 s over the runs: "
          f"{np.abs(result.summaries[:, 1]).max():.2e} rad")  # fmt: skip


def mujoco_ur5(path: Path) -> object:
    """The UR5 of the URDF in MuJoCo: meshes dropped, RK4 at 1 ms, no contacts, no joint limits."""
    import mujoco

    text = re.sub(r"<(visual|collision)>.*?</\1>", "", path.read_text(), flags=re.S)
    model = mujoco.MjModel.from_xml_string(text)
    model.opt.timestep, model.opt.integrator = 1e-3, mujoco.mjtIntegrator.mjINT_RK4
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_LIMIT
    return model


def ur5_rollouts(runs: int, threads: int = 2) -> None:
    import mujoco
    from mujoco import rollout

    arm = ad.load_urdf(ROBOTS / UR5)
    model = mujoco_ur5(ROBOTS / UR5)
    rng = np.random.default_rng(1)
    q0, qd0 = rng.uniform(-np.pi, np.pi, (runs, 6)), rng.uniform(-1, 1, (runs, 6))
    simulate(arm, None, None, t_final=0.01, q0=q0[:2], qd0=qd0[:2], runs=2)
    start = time.perf_counter()
    ours = simulate(arm, None, None, t_final=1.0, q0=q0, qd0=qd0, threads=threads)
    armdyn_rate = runs / (time.perf_counter() - start)
    size = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    states = np.zeros((runs, size))
    states[:, 1 : 1 + model.nq], states[:, 1 + model.nq : 1 + model.nq + model.nv] = q0, qd0
    datas = [mujoco.MjData(model) for _ in range(threads)]
    rollout.rollout(model, datas, states[:2], nstep=10)
    start = time.perf_counter()
    finals, _ = rollout.rollout(model, datas, states, nstep=1000)
    mujoco_rate = runs / (time.perf_counter() - start)
    difference = np.abs(finals[:, -1, 1 : 1 + model.nq] - ours.summaries[:, 4]).max()
    print(f"UR5, {runs} runs of 1 s at 1 ms, RK4, zero torque, random starts, {threads} threads")
    print(f"  simulate(runs=): {armdyn_rate:.0f} runs/s; MuJoCo rollout: {mujoco_rate:.0f} runs/s "
          f"({armdyn_rate / mujoco_rate:.1f}x); final q differ by {difference:.1e} rad at most")  # fmt: skip


def dask_scaling(runs: int) -> None:
    """A study of PUMA computed-torque runs on a Dask LocalCluster of 1 and then 2 worker processes (one task
    thread and one Numba thread each), against the same study in this process."""
    from armdyn.study import Study, Uniform

    arm = ad.models.puma560()
    q0 = arm.configuration("qn")
    study = Study(arm, control.ComputedTorque(100.0, 20.0), tr.Sinusoid(0.1, 0.5, 0.0, q0), t_final=2.0,
                  payload=Uniform(0.0, 2.0), mass_error=Uniform(-0.1, 0.1), block=250)  # fmt: skip
    start = time.perf_counter()
    local = study.run(runs, seed=0)
    rates = {"local": runs / (time.perf_counter() - start)}
    for workers in (1, 2):
        start = time.perf_counter()
        remote = study.run(runs, seed=0, scheduler="local-cluster", workers=workers)
        rates[workers] = runs / (time.perf_counter() - start)
        assert remote.table.equals(local.table)
    print(f"Study of {runs} PUMA runs of 2 s (payload and 10 % mass errors), blocks of 250, cluster start-up included")
    print(f"  this process (2 threads): {rates['local']:.0f} runs/s; Dask LocalCluster 1 worker: {rates[1]:.0f} "
          f"runs/s, 2 workers: {rates[2]:.0f} runs/s (efficiency {rates[2] / (2 * rates[1]):.0%}); "
          f"tables equal bit for bit; {local.estimate}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10_000)
    args = parser.parse_args()
    puma_study(args.runs)
    ur5_rollouts(1000)
    dask_scaling(4000)


if __name__ == "__main__":
    main()
