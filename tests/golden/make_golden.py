"""Reference results of armdyn, written to golden.npz and checked bit for bit by tests/test_golden.py.

Every call into armdyn is in ``scenarios()``: each scenario is a zero-argument callable returning a dict
of arrays (a run's records, a batch's quantities). ``compact`` reduces each array to what is stored:
small arrays whole, larger ones by their last row, about eleven evenly spaced rows and their column sums.

Run from the repository root to (re)write the file:

    python tests/golden/make_golden.py
"""

from __future__ import annotations

import sys
import sysconfig
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

GOLDEN = Path(__file__).with_name("golden.npz")
UR5 = (
    Path(sysconfig.get_paths()["purelib"])
    / "cmeel.prefix/share/example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
)
WHOLE = 400  # arrays of at most this many numbers are stored whole
SAMPLES = 11  # rows sampled from a larger array


def compact(arrays: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """What is stored of a scenario's arrays: small ones whole; a larger one, seen as rows (first axes
    flattened, last axis kept), by its last row, SAMPLES evenly spaced rows and its column sums."""
    stored = {}
    for key, value in arrays.items():
        x = np.asarray(value)
        if x.size <= WHOLE:
            stored[key] = x.copy()
            continue
        rows = x.reshape(-1, x.shape[-1]) if x.ndim >= 2 else x.reshape(-1, 1)
        step = max(1, (len(rows) - 1) // (SAMPLES - 1))
        stored[f"{key}.last"] = rows[-1].copy()
        stored[f"{key}.rows"] = rows[::step].copy()
        stored[f"{key}.sum"] = rows.sum(axis=0)
        stored[f"{key}.shape"] = np.array(x.shape)
    return stored


def scenarios() -> dict[str, Callable[[], dict[str, np.ndarray]]]:
    """Scenario name -> zero-argument callable returning its arrays. The only place that uses armdyn."""
    import armdyn as ad
    from armdyn import actuators as act
    from armdyn import control
    from armdyn import task_space as ts
    from armdyn import trajectories as tr
    from armdyn.simulation import PythonLoopWarning, plant_variants
    from armdyn.study import Normal, Study, Uniform

    def simulate(*args: object, **kwargs: object) -> dict[str, np.ndarray]:
        """ad.simulate, its Python-loop warning silenced, and the run's records."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PythonLoopWarning)
            result = ad.simulate(*args, **kwargs)
        out = {"t": result.t, "q": result.q, "qd": result.qd, "qdd": result.qdd, "tau": result.tau}
        if result.q_d is not None:
            out["q_d"] = result.q_d
        if result.drives is None:
            out["energy"] = result.energy
        else:
            out |= {"drives.x": result.drives.x, "drives.v": result.drives.v, "drives.i": result.drives.i}
            for name in ("spool", "pressure"):
                if getattr(result.drives, name) is not None:
                    out[f"drives.{name}"] = getattr(result.drives, name)
        if result.task is not None:
            out |= {"task.y": result.task.y, "task.y_d": result.task.y_d, "task.error": result.task.error}
        return out

    def ur5() -> ad.Robot:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return ad.load_urdf(UR5)

    def two_link() -> ad.Robot:
        return ad.models.two_link_planar()

    def puma() -> ad.Robot:
        return ad.models.puma560()

    def states(arm: ad.Robot, seed: int, count: int = 16) -> tuple[np.ndarray, ...]:
        rng = np.random.default_rng(seed)
        return tuple(rng.uniform(-1.5, 1.5, (count, arm.n)) for _ in range(3))

    cases: dict[str, Callable[[], dict[str, np.ndarray]]] = {}

    # ----- joint-space runs of ad.simulate -------------------------------------------------------------------------
    q2 = np.array([0.3, 0.6])
    sin2 = tr.Sinusoid(0.1, 1.0, 0.0, q2)
    quintic2 = tr.Quintic(q2, q2 + [0.4, -0.3], 0.0, 0.4)
    qn = np.array(puma().configurations["qn"])
    sin6 = tr.Sinusoid(0.1, 0.5, 0.0, qn)
    quintic6 = tr.Quintic(qn, qn + 0.2, 0.05, 0.35)

    def pd_lambda(t, q, qd, q_d, qd_d, qdd_d, e_int):
        return 400.0 * (q_d - q) + 40.0 * (qd_d - qd)

    def gravity_lambda(t, q, qd, q_d, qd_d, qdd_d, e_int, plant=None):
        return plant.gravity_vector(q) + 300.0 * (q_d - q) + 30.0 * (qd_d - qd)

    two = {
        "ct_sinusoid": lambda: simulate(two_link(), control.ComputedTorque(100.0, 20.0), sin2, 0.5, q0=q2),
        "ct_ki_quintic": lambda: simulate(
            two_link(), control.ComputedTorque(100.0, 20.0, 5.0), quintic2, 0.5, q0=q2 + 0.01
        ),
        "ct_model_payload": lambda: simulate(
            two_link().with_payload(1.0), control.ComputedTorque(100.0, 20.0, model=two_link()), sin2, 0.5, q0=q2
        ),
        "pdg_quintic": lambda: simulate(two_link(), control.PDGravity(200.0, 30.0), quintic2, 0.5, q0=q2),
        "pid_none": lambda: simulate(two_link(), control.PID(300.0, 40.0, 50.0), None, 0.5, q0=q2, qd0=[0.2, -0.1]),
        "pid_sinusoid": lambda: simulate(two_link(), control.PID([300.0, 200.0], [40.0, 30.0]), sin2, 0.5, q0=q2),
        "digital_ct": lambda: simulate(
            two_link(), control.Digital(control.ComputedTorque(100.0, 20.0), 5e-3), sin2, 0.5, q0=q2
        ),
        "digital_pid": lambda: simulate(
            two_link(), control.Digital(control.PID(300.0, 40.0, 10.0), 2e-3), quintic2, 0.5, q0=q2
        ),
        "saturated_pdg": lambda: simulate(
            two_link(), control.Saturated(control.PDGravity(400.0, 40.0), 20.0), quintic2, 0.5, q0=q2
        ),
        "saturated_digital_ct": lambda: simulate(
            two_link(),
            control.Saturated(control.Digital(control.ComputedTorque(200.0, 30.0), 4e-3), [30.0, 10.0]),
            sin2,
            0.5,
            q0=q2 - 0.05,
        ),
        "free_fall": lambda: simulate(two_link(), None, None, 0.3, q0=q2),
        "free_fall_short_whole": lambda: simulate(two_link(), None, None, 0.02, q0=q2, qd0=[1.0, -1.0]),
        "disturbance": lambda: simulate(
            two_link(), control.PDGravity(200.0, 30.0), sin2, 0.5, q0=q2, disturbance=[2.0, -1.0]
        ),
        "events_payload": lambda: simulate(
            two_link(),
            control.ComputedTorque(100.0, 20.0),
            sin2,
            0.5,
            q0=q2,
            events=[(0.2, two_link().with_payload(2.0))],
        ),
        "coulomb_exact": lambda: simulate(
            two_link(), control.PID(100.0, 10.0), None, 0.3, q0=q2, coulomb_smoothing=0.0
        ),
        "coulomb_eps": lambda: simulate(two_link(), control.PID(100.0, 10.0), None, 0.3, q0=q2, coulomb_smoothing=1e-2),
        "python_lambda": lambda: simulate(two_link(), pd_lambda, sin2, 0.3, q0=q2),
        "python_plant_keyword": lambda: simulate(two_link(), gravity_lambda, quintic2, 0.3, q0=q2),
        "python_digital_lambda": lambda: simulate(two_link(), control.Digital(pd_lambda, 5e-3), sin2, 0.3, q0=q2),
        "python_saturated_lambda": lambda: simulate(
            two_link(), control.Saturated(pd_lambda, 15.0), quintic2, 0.3, q0=q2
        ),
        "python_trajectory": lambda: simulate(
            two_link(), control.ComputedTorque(100.0, 20.0), lambda t: sin2(t, 2), 0.3, q0=q2
        ),
        "python_disturbance_law": lambda: simulate(
            two_link(), control.PDGravity(200.0, 30.0), sin2, 0.3, q0=q2, disturbance=lambda t, q, qd: -0.5 * qd
        ),
        "rk45_ct": lambda: simulate(two_link(), control.ComputedTorque(100.0, 20.0), sin2, 0.3, q0=q2, method="rk45"),
        "rk23_pid": lambda: simulate(two_link(), control.PID(300.0, 40.0, 20.0), quintic2, 0.3, q0=q2, method="rk23"),
        "rk45_python_lambda": lambda: simulate(two_link(), pd_lambda, sin2, 0.2, q0=q2, method="rk45"),
        "cartesian_circle": lambda: simulate(
            two_link(),
            control.ComputedTorque(400.0, 40.0),
            tr.CartesianCircle(1.0, 1.0, (1.0, 0.8), 0.3, 1.0),
            0.3,
            q0=tr.CartesianCircle(1.0, 1.0, (1.0, 0.8), 0.3, 1.0)(0.0)[0],
        ),
    }
    cases |= {f"sim.two_link.{k}": v for k, v in two.items()}

    six = {
        "ct_sinusoid": lambda: simulate(puma(), control.ComputedTorque(100.0, 20.0), sin6, 0.3, q0=qn),
        "ct_ki_model": lambda: simulate(
            puma().with_payload(1.5, (0.0, 0.0, 0.05)),
            control.ComputedTorque(100.0, 20.0, 5.0, model=puma()),
            sin6,
            0.3,
            q0=qn,
        ),
        "pdg_quintic": lambda: simulate(puma(), control.PDGravity(200.0, 30.0), quintic6, 0.4, q0=qn),
        "pid_sinusoid": lambda: simulate(puma(), control.PID(400.0, 40.0, 100.0), sin6, 0.3, q0=qn),
        "digital_pdg": lambda: simulate(
            puma(), control.Digital(control.PDGravity(200.0, 30.0), 3e-3), sin6, 0.3, q0=qn
        ),
        "saturated_ct": lambda: simulate(
            puma(), control.Saturated(control.ComputedTorque(400.0, 40.0), 30.0), quintic6, 0.4, q0=qn
        ),
        "none_free": lambda: simulate(puma(), None, None, 0.2, q0=qn),
        "disturbance": lambda: simulate(
            puma(), control.ComputedTorque(100.0, 20.0), sin6, 0.3, q0=qn, disturbance=np.linspace(-1.0, 1.0, 6)
        ),
        "events_payload": lambda: simulate(
            puma(),
            control.PDGravity(200.0, 30.0),
            sin6,
            0.3,
            q0=qn,
            events=[(0.1, puma().with_payload(2.0)), (0.2, puma())],
        ),
        "coulomb_exact": lambda: simulate(
            puma(), control.PDGravity(100.0, 10.0), None, 0.2, q0=qn, coulomb_smoothing=0.0
        ),
        "coulomb_eps": lambda: simulate(
            puma(), control.PDGravity(100.0, 10.0), None, 0.2, q0=qn, coulomb_smoothing=0.05
        ),
        "python_plant_keyword": lambda: simulate(puma(), gravity_lambda, sin6, 0.2, q0=qn),
        "rk45_pdg": lambda: simulate(puma(), control.PDGravity(200.0, 30.0), sin6, 0.2, q0=qn, method="rk45"),
    }
    cases |= {f"sim.puma560.{k}": v for k, v in six.items()}

    def built_in(name: str, law: object, path: str, t_final: float = 0.3) -> Callable[[], dict[str, np.ndarray]]:
        def run() -> dict[str, np.ndarray]:
            arm = ad.models.load(name)
            q0 = np.full(arm.n, 0.2)
            trajectory = {
                "sinusoid": tr.Sinusoid(0.05, 1.0, 0.0, q0),
                "quintic": tr.Quintic(q0, q0 + 0.1, 0.0, 0.2),
                "none": None,
            }[path]
            return simulate(arm, law, trajectory, t_final, q0=q0)

        return run

    others = {
        "scara.ct_sinusoid": built_in("scara", control.ComputedTorque(100.0, 20.0), "sinusoid"),
        "scara.pid_quintic": built_in(
            "scara",
            control.PID([300.0, 300.0, 300.0, 0.1], [30.0, 30.0, 30.0, 0.01], [10.0, 10.0, 10.0, 0.0]),
            "quintic",
        ),
        "stanford.ct_sinusoid": built_in("stanford", control.ComputedTorque(100.0, 20.0), "sinusoid"),
        "stanford.pdg_none": built_in("stanford", control.PDGravity(200.0, 30.0), "none"),
        "polar_rp.ct_quintic": built_in("polar_rp", control.ComputedTorque(100.0, 20.0), "quintic"),
        "cylindrical.pdg_sinusoid": built_in("cylindrical", control.PDGravity(200.0, 30.0), "sinusoid"),
        "ur5.ct_sinusoid": lambda: simulate(
            ur5(),
            control.ComputedTorque(100.0, 20.0),
            tr.Sinusoid(0.1, 1.0, 0.0, [0.3, -1.2, 1.4, -1.6, -1.5, 0.4]),
            0.3,
            q0=[0.3, -1.2, 1.4, -1.6, -1.5, 0.4],
        ),
        "ur5.pdg_quintic": lambda: simulate(
            ur5(),
            control.PDGravity(300.0, 30.0),
            tr.Quintic([0.3, -1.2, 1.4, -1.6, -1.5, 0.4], [0.5, -1.0, 1.2, -1.4, -1.3, 0.6], 0.0, 0.25),
            0.3,
            q0=[0.3, -1.2, 1.4, -1.6, -1.5, 0.4],
        ),
    }
    cases |= {f"sim.{k}": v for k, v in others.items()}

    # ----- task-space control (armdyn.control.task, armdyn.trajectories.task) -----------------------------------
    arm22 = ad.models.two_link_planar(1.0, 1.0, 2.0, 2.0)
    circle_joints = tr.CartesianCircle(2.0, 2.0, (2.0, 1.0), 0.5, 2.0)
    y0 = ts.PlanarPosition().value(arm22, np.array([0.3, 1.2]))
    q_ur5, q_ur5_end = np.array([0.3, -1.2, 1.4, -1.6, -1.5, 0.4]), np.array([0.8, -1.0, 1.1, -1.3, -1.2, 0.9])
    tip = ts.ToolPosition().value(puma(), qn)

    task = {
        "two_link.ct_circle": lambda: simulate(
            arm22,
            ad.control.TaskComputedTorque(
                ts.PlanarPosition(), ad.trajectories.Circle((2.0, 1.0), 0.5, 2.0), 400.0, 40.0
            ),
            circle_joints,
            0.3,
            q0=circle_joints(0.0)[0] + [0.02, -0.02],
            qd0=circle_joints(0.0)[1],
        ),
        "two_link.ct_line": lambda: simulate(
            arm22,
            ad.control.TaskComputedTorque(
                ts.PlanarPosition(), ad.trajectories.Line(y0, y0 + [0.3, -0.2], 0.2), 400.0, 40.0
            ),
            None,
            0.3,
            q0=[0.3, 1.2],
        ),
        "two_link.ct_line_model": lambda: simulate(
            arm22.with_payload(0.5),
            ad.control.TaskComputedTorque(
                ts.PlanarPosition(),
                ad.trajectories.Line(y0, y0 + [0.2, 0.1], 0.2, start_time=0.05),
                300.0,
                30.0,
                model=arm22,
            ),
            None,
            0.3,
            q0=[0.3, 1.2],
        ),
        "ur5.ct_poseline": lambda: simulate(
            ur5().without_friction(),
            ad.control.TaskComputedTorque(
                ts.ToolPose(),
                ad.trajectories.PoseLine(ur5().tool_pose(q_ur5), ur5().tool_pose(q_ur5_end), 0.2, start_time=0.05),
                400.0,
                40.0,
            ),
            None,
            0.3,
            q0=q_ur5 + 0.05,
        ),
        "puma560.osc_line": lambda: simulate(
            puma(),
            ad.control.OperationalSpaceControl(
                ts.ToolPosition(),
                ad.trajectories.Line(tip, tip + [0.05, -0.03, 0.02], 0.2),
                400.0,
                40.0,
                qn,
                100.0,
                20.0,
            ),
            None,
            0.3,
            q0=qn,
        ),
        "puma560.osc_line_rk45": lambda: simulate(
            puma(),
            ad.control.OperationalSpaceControl(
                ts.ToolPosition(),
                ad.trajectories.Line(tip, tip + [0.0, 0.05, 0.0], 0.15),
                400.0,
                40.0,
                lambda t: qn + 0.1 * np.sin(2 * t),
                100.0,
                20.0,
            ),
            None,
            0.2,
            q0=qn,
            method="rk45",
        ),
    }
    cases |= {f"task.{k}": v for k, v in task.items()}

    # ----- arms with drives (armdyn.actuators) -------------------------------------------------------------------
    def custom_puma() -> act.ActuatedArm:
        bare, drives = act.motor_drives(
            puma(),
            torque_constant=0.22,
            back_emf=0.22,
            resistance=2.1,
            inductance=2e-3,
            voltage_limit=40.0,
            current_limit=8.0,
        )
        return act.with_actuators(bare, drives)

    def representative(name: str, kind: str) -> act.ActuatedArm:
        return act.representative_drives(ad.models.load(name), kind)

    q02 = np.full(2, 0.2)
    drives = {
        "puma560_dc.drivepid": lambda: simulate(
            act.puma560_with_drives(), ad.control.DrivePID(20.0, 0.5), sin6, 0.1, q0=qn
        ),
        "puma560_dc.drivepid_ki_none": lambda: simulate(
            act.puma560_with_drives(), ad.control.DrivePID(20.0, 0.5, 20.0), None, 0.1, q0=qn
        ),
        "puma560_motor_drives.drivepid": lambda: simulate(
            custom_puma(), ad.control.DrivePID(20.0, 0.5), sin6, 0.1, q0=qn
        ),
        "puma560_motor_drives.current_ct": lambda: simulate(
            custom_puma(), ad.control.CurrentComputedTorque(100.0, 20.0, bandwidth=1e3), sin6, 0.1, q0=qn
        ),
        "two_link_dc.drivepid": lambda: simulate(
            representative("two_link_planar", "dc"), ad.control.DrivePID(20.0, 0.5, 20.0), sin2, 0.3, q0=q2
        ),
        "two_link_dc.current_ct": lambda: simulate(
            representative("two_link_planar", "dc"),
            ad.control.CurrentComputedTorque(100.0, 20.0, 2.0),
            quintic2,
            0.3,
            q0=q2,
        ),
        "two_link_flexible.drivepid": lambda: simulate(
            representative("two_link_planar", "flexible"),
            ad.control.DrivePID(20.0, 0.5, 10.0),
            tr.Sinusoid(0.1, 0.5, 0.0, q02),
            0.3,
            q0=q02,
        ),
        "polar_rp_hydraulic.drivepid": lambda: simulate(
            representative("polar_rp", "hydraulic"),
            ad.control.DrivePID(0.1, 0.002, 0.05),
            tr.Sinusoid(0.1, 0.5, 0.0, q02),
            0.3,
            q0=q02,
        ),
        "scara_hydraulic.drivepid_none": lambda: simulate(
            representative("scara", "hydraulic"), ad.control.DrivePID(0.1, 0.0, 0.1), None, 0.1, q0=np.full(4, 0.2)
        ),
        "two_link_flexible.act_simulate_step": lambda: simulate_drives(
            representative("two_link_planar", "flexible"), ad.control.DrivePID(20.0, 0.5), sin2, 0.2, q0=q2, step=1e-4
        ),
    }

    def simulate_drives(*args: object, **kwargs: object) -> dict[str, np.ndarray]:
        result = ad.simulate(*args, **kwargs)
        return {
            "t": result.t,
            "q": result.q,
            "qd": result.qd,
            "tau": result.tau,
            "drives.x": result.drives.x,
            "drives.v": result.drives.v,
        }

    cases |= {f"drives.{k}": v for k, v in drives.items()}

    # ----- batches of runs (simulate with runs=) ------------------------------------------------------------------
    def ensemble(*args: object, **kwargs: object) -> dict[str, np.ndarray]:
        many = ad.simulate(*args, **{"keep": "summary", **kwargs})  # keep= takes the many-runs path
        return {"t": many.t, "summaries": many.summaries, "outcome": many.outcome} | {
            f"samples.{k}": v for k, v in many.samples.items()
        }

    def puma_variants() -> dict[str, np.ndarray]:
        rng = np.random.default_rng(3)
        runs = 5
        masses, centres = rng.uniform(0, 2, runs), rng.uniform(-0.05, 0.05, (runs, 3))
        starts = qn + rng.uniform(-0.05, 0.05, (runs, 6))
        gains = np.stack([np.stack([np.full(6, 100.0 + 10 * k), np.full(6, 20.0), np.zeros(6)]) for k in range(runs)])
        return ensemble(
            puma(),
            control.ComputedTorque(1.0, 1.0),
            [tr.Sinusoid(0.1, 0.5 + 0.1 * k, 0.0, starts[k]) for k in range(runs)],
            t_final=0.3,
            q0=starts,
            plants=plant_variants(puma(), runs, payload_mass=masses, payload_com=centres),
            models=plant_variants(puma(), runs, payload_mass=0.5 * masses),
            gains=gains,
            disturbance=rng.uniform(-1, 1, (runs, 6)),
            keep=10,
        )

    many = {
        "puma560.ct_variants": puma_variants,
        "puma560.pdg_summary": lambda: ensemble(
            puma(),
            control.PDGravity(200.0, 30.0),
            sin6,
            t_final=0.3,
            q0=qn + np.linspace(0, 0.1, 4)[:, None],
            after=0.1,
        ),
        "puma560.saturated_digital_pid": lambda: ensemble(
            puma(),
            control.Saturated(control.Digital(control.PID(300.0, 30.0, 20.0), 2e-3), 40.0),
            quintic6,
            t_final=0.3,
            q0=qn,
            plants=plant_variants(
                puma(),
                3,
                mass_scale=np.outer([0.9, 1.0, 1.1], np.ones(6)),
                friction_scale=np.outer([0.5, 1.0, 2.0], np.ones(6)),
            ),
            keep=25,
        ),
        "two_link.pid_quintic_full": lambda: ensemble(
            two_link(),
            control.PID(300.0, 40.0),
            [tr.Quintic(q2, q2 + 0.1 * k, 0.0, 0.05) for k in range(3)],
            t_final=0.05,
            q0=q2,
            keep="full",
        ),
        "two_link.ct_starts_gains": lambda: ensemble(
            two_link(),
            control.ComputedTorque(100.0, 20.0),
            sin2,
            t_final=0.5,
            q0=[[0.0, 0.0], [0.5, 0.5], [0.3, 0.6]],
            gains=np.array([[[100.0, 100.0], [20.0, 20.0], [0.0, 0.0]]] * 3) * [[[1.0]], [[2.0]], [[0.5]]],
            disturbance=[1.0, -1.0],
            after=0.2,
        ),
        "two_link.none_payloads": lambda: ensemble(
            two_link(),
            None,
            None,
            t_final=0.1,
            q0=q2,
            plants=plant_variants(two_link(), 4, payload_mass=[0, 1, 2, 3]),
            keep=5,
        ),
    }
    cases |= {f"many.{k}": v for k, v in many.items()}

    # ----- Monte Carlo studies (armdyn.study) ---------------------------------------------------------------------
    def study(runs: int, seed: int, *args: object, **kwargs: object) -> dict[str, np.ndarray]:
        with tempfile.TemporaryDirectory() as folder:
            result = Study(*args, **kwargs).run(runs, seed=seed, out=Path(folder) / "study")
        table = result.table
        out = {f"table.{c}": table[c].to_numpy() for c in table.columns if np.issubdtype(table[c].dtype, np.number)}
        out["table.holds"] = table["holds"].to_numpy().astype(np.int64)
        out["table.finished"] = table["finished"].to_numpy().astype(np.int64)
        out["estimate"] = np.array([result.estimate.low, result.estimate.high])
        return out

    studies = {
        "two_link.ct_payload_mass": lambda: study(
            40,
            7,
            two_link(),
            control.ComputedTorque(100.0, 20.0),
            tr.Sinusoid(0.1, 1.0, 0.0, q2),
            spec="max_error_after < 2e-3",
            t_final=0.3,
            after=0.2,
            q0=q2,
            payload=Uniform(0.0, 2.0),
            mass_error=Uniform(-0.2, 0.2),
            block=15,
        ),
        "puma560.pdg_friction_start": lambda: study(
            20,
            3,
            puma(),
            control.PDGravity(200.0, 30.0),
            sin6,
            t_final=0.2,
            after=0.1,
            q0=qn,
            payload=Normal(1.0, 0.3),
            friction_error=Uniform(-0.5, 0.5),
            start_error=Normal(0.0, 0.01),
            block=8,
        ),
    }
    cases |= {f"study.{k}": v for k, v in studies.items()}

    # ----- batch dynamics -----------------------------------------------------------------------------------------
    def dynamics(make: Callable[[], ad.Robot], seed: int) -> dict[str, Callable[[], dict[str, np.ndarray]]]:
        def of(compute: Callable[[ad.Robot, tuple], dict]) -> Callable[[], dict[str, np.ndarray]]:
            return lambda: compute(make(), states(make(), seed))

        return {
            "rnea": of(lambda a, s: {"tau": a.inverse_dynamics(*s)}),
            "aba": of(lambda a, s: {"qdd": a.forward_dynamics(*s)}),
            "mass": of(lambda a, s: {"M": a.inertia_matrix(s[0]), "Mdot": a.inertia_matrix_dot(s[0], s[1])}),
            "coriolis": of(
                lambda a, s: {
                    "Vm": a.coriolis_matrix(s[0], s[1]),
                    "Vmqd": a.coriolis_vector(s[0], s[1]),
                    "N": a.nonlinear_terms(s[0], s[1]),
                }
            ),
            "gravity_friction": of(lambda a, s: {"G": a.gravity_vector(s[0]), "F": a.friction(s[1])}),
            "energies": of(lambda a, s: {"E": a.energies(s[0], s[1])}),
            "regressor": of(lambda a, s: {"W": a.regressor(*s), "phi": a.parameters()}),
            "id_derivatives": of(
                lambda a, s: dict(zip(("dq", "dqd"), a.inverse_dynamics_derivatives(*s), strict=True))
            ),
            "fd_derivatives": of(
                lambda a, s: dict(zip(("dq", "dqd", "dtau"), a.forward_dynamics_derivatives(*s), strict=True))
            ),
            "kinematics": of(
                lambda a, s: {
                    "T": a.tool_pose(s[0]),
                    "J": a.jacobian(s[0]),
                    "Jdot": a.jacobian_dot(s[0], s[1]),
                    "links": a.link_transforms(s[0]),
                }
            ),
        }

    for name, make, seed in (("two_link", two_link, 1), ("puma560", puma, 2), ("ur5", ur5, 3)):
        cases |= {f"dyn.{name}.{k}": v for k, v in dynamics(make, seed).items()}

    def task_quantities(make: Callable[[], ad.Robot], output: ts.TaskOutput, seed: int) -> dict[str, np.ndarray]:
        arm = make()
        rng = np.random.default_rng(seed)
        q = (
            np.array([0.3, 1.2]) + rng.uniform(-0.3, 0.3, (8, arm.n))
            if arm.n == 2
            else (qn + rng.uniform(-0.3, 0.3, (8, arm.n)))
        )
        qd = rng.uniform(-1, 1, (8, arm.n))
        ydd = rng.uniform(-1, 1, (8, output.value(arm, q[0]).shape[-1]))
        return {
            "Mbar": ts.task_inertia(arm, output, q),
            "Vmbar": ts.task_coriolis(arm, output, q, qd),
            "Gbar": ts.task_gravity(arm, output, q),
            "Nbar": ts.task_nonlinear(arm, output, q, qd),
            "Fbar": ts.task_friction(arm, output, q, qd),
            "Wbar": ts.task_regressor(arm, output, q, qd, ydd),
            "f": ts.task_inverse_dynamics(arm, output, q, qd, ydd),
            "yddot": ts.task_forward_dynamics(arm, output, q, qd, ydd),
            "cond": ts.condition_number(arm, output, q),
        }

    def operational(seed: int) -> dict[str, np.ndarray]:
        arm, output = puma(), ts.ToolPosition()
        rng = np.random.default_rng(seed)
        q, qd = qn + rng.uniform(-0.3, 0.3, (8, 6)), rng.uniform(-1, 1, (8, 6))
        space = ts.operational_space(arm, output, q, qd)
        mu, p = ts.operational_coriolis(arm, output, q, qd)
        return {
            "Lambda": ts.operational_inertia(arm, output, q),
            "space.Lambda": space.Lambda,
            "space.Jbar": space.Jbar,
            "space.mu": space.mu,
            "space.p": space.p,
            "space.friction": space.friction,
            "space.Nproj": space.Nproj,
            "mu": mu,
            "p": p,
        }

    cases |= {
        "taskdyn.two_link.planar_position": lambda: task_quantities(two_link, ts.PlanarPosition(), 4),
        "taskdyn.puma560.tool_pose": lambda: task_quantities(puma, ts.ToolPose(), 5),
        "taskdyn.puma560.operational_space": lambda: operational(6),
    }
    return cases


def main(only: list[str]) -> None:
    """Record every scenario, or only the named ones (the others kept as recorded): a deliberate change of
    a result is recorded by name, never by recording everything again."""
    stored = dict(np.load(GOLDEN)) if only else {}
    known = scenarios()
    unknown = set(only) - set(known)
    if unknown:
        raise SystemExit(f"no such scenario: {', '.join(sorted(unknown))}")
    for name, compute in known.items():
        if only and name not in only:
            continue
        stored = {key: value for key, value in stored.items() if not key.startswith(f"{name}/")}
        for key, value in compact(compute()).items():
            stored[f"{name}/{key}"] = value
    np.savez_compressed(GOLDEN, **stored)
    print(f"{len(scenarios())} scenarios, {len(stored)} arrays, {GOLDEN.stat().st_size / 1e3:.0f} kB -> {GOLDEN}")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))
    main(sys.argv[1:])
