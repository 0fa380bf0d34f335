"""Simulation of the arm under control (Chapter 4, Appendix B: the book's TRESP program).

``simulate`` integrates M qdd + N(q, qd) + tau_d = tau with fixed-step fourth-order
Runge-Kutta, the controller run once per step (or once per sample period, with the torque
held in between), or with an adaptive solver of scipy.integrate.solve_ivp. When the
controller and the trajectory are armdyn's own and the disturbance is constant, the whole
RK4 run is one compiled Numba call.

Coulomb friction is smoothed: Fd_i = tanh(qd_i / eps_i) Tc+ (qd_i >= 0) or -tanh(qd_i / eps_i) Tc-
(qd_i < 0), continuous through zero velocity, so the integrator does not chatter; the Stribeck
law's sign alike, Fs_i exp(-(qd_i/vs_i)^2) tanh(qd_i / eps_i) (the sigmoid law is smooth as it is).
With ``coulomb_smoothing="auto"`` (the default) eps_i = max(1e-3 rad/s, (Tc_i + Fs_i) dt / M_ii(q0)),
which keeps the stiffness of the smoothed law within fixed-step RK4's stability region; a number
sets every eps_i, and eps -> 0 recovers Fd = Tc sgn(qd). The integral
of the error for PID control is accumulated once per controller evaluation.
"""

from __future__ import annotations

import csv
import math
import reprlib
import time
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike

from armdyn import control, inputs, memory, trajectories
from armdyn.control import COMPUTED_TORQUE, PD_GRAVITY, control_law
from armdyn.control.joint import LIMIT
from armdyn.dynamics import api
from armdyn.dynamics.aba_blocks import ABA_BLOCK_ROWS, LANE_FIELDS, aba_block, base_slot, block_slot, lane_parameters
from armdyn.dynamics.crba import mass_matrix_and_bias
from armdyn.dynamics.drives import KI, KP, KV, closed_loop, hold_limits
from armdyn.dynamics.friction import sign_law_table, smooth_coulomb, smooth_coulomb_vector, stribeck_vector
from armdyn.dynamics.linalg import cholesky, cholesky_solve_vector
from armdyn.dynamics.packed import (
    COULOMB_NEG,
    COULOMB_POS,
    FIRST_MOMENT,
    HEADER,
    INERTIA,
    LINK_POSITION,
    LINK_ROTATION,
    MASS,
    N_JOINTS,
    PIVOT_FLOOR,
    SIGMOID_AMPLITUDE,
    SIGMOID_REST,
    STRIBECK_FORCE,
    STRIDE,
    TOOL_LINK,
    VISCOUS,
    workspace_size,
)
from armdyn.dynamics.rnea import GRAVITY_ONLY, INVERSE_DYNAMICS
from armdyn.dynamics.rnea_blocks import BLOCK, rnea_block
from armdyn.dynamics.spatial import NUMBA_OPTIONS
from armdyn.dynamics.status import OK
from armdyn.errors import ArgumentError, ModelError, SimulationError
from armdyn.files import atomic_write
from armdyn.inputs import LARGEST_STATE, without_read_only
from armdyn.observers.contact import ROW_SIZE, contact_torques, contacts_table
from armdyn.observers.momentum import MomentumObserver, momentum_and_rate, observe
from armdyn.robot import Robot
from armdyn.trajectories import desired

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from armdyn.actuators.packing import DriveRecord
    from armdyn.control.task import Tracking
    from armdyn.viewer import Viewer

SOLVERS = {"rk45": "RK45", "rk23": "RK23", "dop853": "DOP853", "radau": "Radau", "bdf": "BDF", "lsoda": "LSODA"}
"""The adaptive methods: simulate's names for them (taken in any case) and scipy's."""
ADAPTIVE = tuple(SOLVERS)
MAX_SAMPLES = 200_000_000
"""The most samples (t_final / dt + 1) one run records: about 18 GB for the two-link arm (8 (1 + 5 n)
bytes a sample), and minutes of the compiled loop. A run whose record needs more memory than the
system has available is refused too (``_available_memory``), before anything is allocated."""
MAX_SUBSTEPS = 1_000_000
"""The most RK4 steps per sample of dt an arm with drives takes (its step= or stable step)."""


STOPPED_SINGULAR, STOPPED_DIVERGED = 1, 2  # why a compiled run stopped


class PythonLoopWarning(UserWarning):
    """simulate runs a user's controller or trajectory in its Python loop (slower than compiled)."""


class RunSummaries:
    """What one run and many runs answer alike: ``runs``, ``finished``, the per-run ``summaries`` and
    ``summary()``, ``to_xarray()`` with named dimensions (run, time, joint). ``Result`` is one run,
    ``Ensemble`` many; a Result's summary row equals the row many runs compute for the same run."""

    arm: Robot
    t: np.ndarray
    info: dict

    if TYPE_CHECKING:  # what both give: an Ensemble's fields, a Result's properties (computed when first read)

        @property
        def summaries(self) -> np.ndarray:
            """(runs, 5, n): per run and joint the rows named by SUMMARY_NAMES."""

        @property
        def outcome(self) -> np.ndarray:
            """(runs, 3) integers: (-1, 0, -1) for a run that finished, else (row it stopped at, reason, joint)."""

    @property
    def runs(self) -> int:
        """The number of runs (1 for a Result)."""
        return int(self.summaries.shape[0])

    @property
    def finished(self) -> np.ndarray:
        """(runs,) bool: the runs that reached t_final."""
        return np.asarray(self.outcome[:, 0] < 0)

    def summary(self) -> Any:
        """The summaries as a pandas DataFrame: one row per run, a column per quantity and joint
        ("max_error_after q1", ...), the largest over joints ("max_error_after"), and "finished".

        Returns
        -------
        pandas.DataFrame
            One row per run, indexed by "run".

        Raises
        ------
        None
            It only arranges the summaries.
        """
        import pandas  # a dependency, imported when first used (start-up time)

        columns = {}
        for k, name in enumerate(SUMMARY_NAMES):
            values = self.summaries[:, k]
            for j, joint in enumerate(self.arm.joint_names):
                columns[f"{name} {joint}"] = values[:, j]
            if name != "final_q":
                columns[name] = np.abs(values).max(axis=1)
        columns["finished"] = self.finished
        return pandas.DataFrame(columns, index=pandas.RangeIndex(self.runs, name="run"))


def summary_window(after: object, t_final: float) -> float:
    """The start of the summaries' "max error after" window (s): ``after`` from 0 to t_final, or by
    default 1 s (t_final when the run is shorter); an empty window is a ModelError, never a pass."""
    if after is None:
        return min(1.0, t_final)
    start = inputs.number(after, "after", minimum=0.0)
    if start > t_final:
        raise ModelError(f"after = {start:g} s leaves the 'max error after' window empty: it must be at most "
                         f"t_final = {t_final:g} s")  # fmt: skip
    return start


def run_summaries(t: np.ndarray, q: np.ndarray, q_d: np.ndarray, tau: np.ndarray, after: float) -> np.ndarray:
    """(5, n): one run's summary rows (SUMMARY_NAMES) from its samples at every step: the final error
    e = q_d - q, the largest |e| from ``after`` seconds on, the RMS error, the largest |tau|, the final q;
    the rows many runs compute in their compiled loop."""
    if len(t) == 0:
        return np.full((5, q.shape[-1]), np.nan)
    error = q_d - q
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    first = math.ceil(after / dt - 1e-9)
    window = np.abs(error[first:])
    largest_after = window.max(axis=0) if len(window) else np.zeros(q.shape[1])
    rms = np.sqrt(np.sum(error * error, axis=0) / len(t))
    return np.stack((error[-1], largest_after, rms, np.abs(tau).max(axis=0), q[-1]))


@dataclass
class Result(RunSummaries):
    """A simulated run. Arrays have time as their first axis; ``summary()`` and ``to_xarray()`` as
    many runs give them (one run)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    q_d: np.ndarray | None
    arm: Robot
    info: dict = field(default_factory=dict)
    energy_of: Callable[[], np.ndarray] | None = field(default=None, repr=False)
    task: Tracking | None = None
    """The task-space record (armdyn.control.Tracking: y, y_d, error) under a task-space controller."""
    drives: DriveRecord | None = None
    """The drives' record (armdyn.actuators.DriveRecord: state, voltages, currents) of an arm with actuators."""
    residual: np.ndarray | None = None
    """The momentum observer's residual r at every sample, (N, n), of a run with an ``observer``."""
    external_torque: np.ndarray | None = None
    """The contacts' torque tau_ext = J_p^T F at every sample, (N, n), of a run whose disturbance is contacts."""

    @cached_property
    def energy(self) -> np.ndarray:
        """K + P at every sample (computed when first read: one batch call per arm)."""
        return self.energy_of() if self.energy_of is not None else np.full(len(self.t), np.nan)

    @property
    def error(self) -> np.ndarray | None:
        """e = q_d - q (None without a trajectory)."""
        return None if self.q_d is None else self.q_d - self.q

    @cached_property
    def summaries(self) -> np.ndarray:
        """(1, 5, n): the run's summary rows (SUMMARY_NAMES), the error's largest value taken from ``after``
        seconds on (info["after"], by default 1 s or t_final when shorter, as many runs'); without a trajectory
        the error is from the start, held (as the controllers and many runs take it). Computed when first read."""
        q_d = self.q_d if self.q_d is not None else np.broadcast_to(self.q[:1], self.q.shape)  # None: hold q0
        after = float(self.info.get("after", min(1.0, self.t[-1] if len(self.t) else 0.0)))
        return run_summaries(self.t, self.q, q_d, self.tau, after)[None]

    @property
    def outcome(self) -> np.ndarray:
        """(1, 3): (-1, 0, -1), a run that finished (a run that stops raises SimulationError holding it)."""
        return np.array([[-1, 0, -1]])

    def plot(self, path: str | Path | None = None, title: str | None = None) -> Figure:
        """Joint values with their desired values, tracking errors and torques (matplotlib figure)."""
        from armdyn.plotting import plot_result

        return plot_result(self, path, title)

    def animate(self, path: str | Path, **options: Any) -> Path:
        """An animation of the run: the arm moving with its desired and actual tool paths, beside the
        tracking error with a moving time cursor (armdyn.plotting.animate).

        Parameters
        ----------
        path : str or Path
            The file: .gif, or .mp4 when ffmpeg is installed.
        **options
            fps, frames, dpi and title, as armdyn.plotting.animate takes them.

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        ModelError
            When the file's folder does not exist, its suffix is neither .gif nor .mp4, an .mp4 is
            asked for without ffmpeg, or an option is out of range.
        """
        from armdyn.plotting import animate

        return animate(self, path, **options)

    def view(self, **options: Any) -> Viewer:
        """The run played back in 3-D in the browser (armdyn.viewer.Viewer): a time slider and play/pause, the
        desired tool path and the tool's trace, each link coloured by its joint's |tau| relative to the torque
        limits, the drives' inputs for a run with drives, and the viewer's overlays.

        Parameters
        ----------
        **options
            host, port, overlays, urdf and torque_limits, as armdyn.viewer.Viewer takes them.

        Returns
        -------
        armdyn.viewer.Viewer
            The running viewer: open its ``url``, or write the run as an offline page with ``save_html``;
            ``close()`` it (or use it in a ``with`` block).

        Raises
        ------
        armdyn.MissingDependencyError
            When viser or trimesh is not installed (``pip install 'armdyn[view]'``).
        armdyn.ModelError
            As armdyn.viewer.Viewer.
        """
        from armdyn.viewer import Viewer

        return Viewer(self.arm, result=self, **options)

    def _repr_png_(self) -> bytes:
        """The run's figure (Result.plot's) as PNG bytes: Jupyter shows a Result as its figure."""
        from armdyn.plotting import png_bytes

        return png_bytes(self.plot())

    def plot_task(self, path: str | Path | None = None, title: str | None = None) -> Figure:
        """The task-space path over the desired one and the task error (a run under a task-space law)."""
        from armdyn.plotting import plot_task

        if self.task is None:
            raise ModelError("this run has no task-space record: simulate it under a task-space controller "
                             "(armdyn.control.TaskComputedTorque or OperationalSpaceControl)")  # fmt: skip
        return plot_task(self, path, title)

    def to_csv(self, path: str | Path) -> None:
        """One row per time: t, q_i, qd_i, qdd_i, tau_i (and q_d_i, e_i with a trajectory), energy; with
        drives also their inputs v_i and states qM_i, qdM_i, i_i, xv_i, PL_i (joint i's drive)."""
        n = self.q.shape[1]
        columns = {"t": self.t[:, None]}
        for name, values in (("q", self.q), ("qd", self.qd), ("qdd", self.qdd), ("tau", self.tau)):
            columns[name] = values
        if self.q_d is not None:
            columns["q_d"], columns["e"] = self.q_d, self.q_d - self.q  # the error, e = q_d - q
        header = ["t"] + [f"{name}{i + 1}" for name in list(columns)[1:] for i in range(n)] + ["energy"]
        table = np.hstack([*columns.values(), self.energy[:, None]])
        if self.task is not None:
            task = {"y": self.task.y, "y_d": self.task.y_d, "task_e": self.task.error}
            header += [f"{name}{i + 1}" for name, values in task.items() for i in range(values.shape[1])]
            table = np.hstack([table, *task.values()])
        if self.drives is not None:  # the drives' inputs, then their states by name (e.g. "i q1", "PL q2")
            joint = {name: k + 1 for k, name in enumerate(self.arm.joint_names)}  # "i q2" -> "i2", as tau2 and v2
            states = [name.split(" ", 1) for name in self.drives.names[2 * n :]]
            header += [f"v{i + 1}" for i in range(n)] + [f"{key}{joint[name]}" for key, name in states]
            table = np.hstack([table, self.drives.v, self.drives.x[:, 2 * n :]])
        with atomic_write(path, newline="", encoding="utf-8") as handle:  # whole or not at all
            writer = csv.writer(handle)
            writer.writerow(header)
            writer.writerows(table.tolist())

    def to_npz(self, path: str | Path) -> None:
        arrays: dict[str, Any] = {"t": self.t, "q": self.q, "qd": self.qd, "qdd": self.qdd, "tau": self.tau,
                                  "energy": self.energy}  # fmt: skip
        if self.q_d is not None:
            arrays |= {"q_d": self.q_d, "error": self.q_d - self.q}
        if self.task is not None:
            arrays |= {"y": self.task.y, "y_d": self.task.y_d, "task_error": self.task.error}
        target = str(path) if str(path).endswith(".npz") else f"{path}.npz"  # as np.savez names it
        with atomic_write(target, "wb") as handle:  # whole or not at all
            np.savez(handle, **arrays)

    def to_xarray(self) -> Any:
        """The run as an xarray Dataset with dimensions time and joint, as ``Ensemble.to_xarray`` names them
        (run, time, joint) for many runs: ``xarray.concat`` of single runs along "run" holds many runs'
        variables.

        Returns
        -------
        xarray.Dataset
            q, qd, qdd and tau (time, joint), the desired q_d and the error q_d - q with a trajectory, the
            energy K + P (time), the summaries (joint, named by SUMMARY_NAMES), stopped_at and reason;
            ``info`` as attributes; ``.to_dataframe()`` gives pandas.

        Raises
        ------
        None
            It only arranges the arrays.
        """
        import xarray

        variables: dict[str, tuple[tuple[str, ...], np.ndarray]] = {
            name: (("time", "joint"), getattr(self, name)) for name in ("q", "qd", "qdd", "tau")
        }
        if self.q_d is not None:
            variables |= {"q_d": (("time", "joint"), self.q_d), "error": (("time", "joint"), self.q_d - self.q)}
        variables["energy"] = (("time",), self.energy)
        variables |= {name: (("joint",), self.summaries[0, k]) for k, name in enumerate(SUMMARY_NAMES)}
        variables |= {"stopped_at": ((), self.outcome[0, 0]), "reason": ((), self.outcome[0, 1])}
        coordinates = {"time": self.t, "joint": list(self.arm.joint_names)}
        return xarray.Dataset(variables, coords=coordinates, attrs={k: str(v) for k, v in self.info.items()})


# ----- the compiled loop ------------------------------------------------------------------------------
@njit(**NUMBA_OPTIONS)
def _accelerations(
    plant: np.ndarray, coulomb: np.ndarray, eps: np.ndarray, stops: np.ndarray, work: np.ndarray, q: np.ndarray,
    qd: np.ndarray, tau: np.ndarray, M: np.ndarray, N: np.ndarray, qdd: np.ndarray,
) -> int:  # fmt: skip
    """qdd = M^-1 (tau - N - Fd_smooth + tau_stop) by CRBA, RNEA and a Cholesky solve; -1, or the joint
    where M is singular (see _solve).

    For the arms of this library (n up to about ten) this is faster than the O(n)
    articulated-body algorithm and equal to it to rounding; ``tau`` carries the disturbance.
    """
    mass_matrix_and_bias(plant, work, q, qd, M, N)
    return _solve(M, N, tau, coulomb, eps, stops, q, qd, qdd, plant[PIVOT_FLOOR])


@njit(inline="always", **NUMBA_OPTIONS)
def _solve(
    M: np.ndarray, N: np.ndarray, tau: np.ndarray, coulomb: np.ndarray, eps: np.ndarray, stops: np.ndarray,
    q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, floor: float,
) -> int:  # fmt: skip
    """qdd = M^-1 (tau - N - Fd_smooth + tau_stop) by Cholesky factorization (M is overwritten).

    Returns -1, or the first joint whose pivot is not above ``floor`` (M singular; qdd not
    computed)."""
    singular = cholesky(M, floor)
    if singular >= 0:
        return singular
    for i in range(qd.shape[0]):
        qdd[i] = tau[i] - N[i] - smooth_coulomb(coulomb, eps, i, qd[i]) + stop_torque(stops, i, q[i], qd[i])
    cholesky_solve_vector(M, qdd)
    return -1


@njit(inline="always", **NUMBA_OPTIONS)
def stop_torque(stops: np.ndarray, i: int, q: float, qd: float) -> float:
    """The torque of joint i's limit stop, a spring-damper beyond [lower, upper] (stops[i] = lower, upper,
    K, B): -K (q - upper) - B qd past the upper limit, K (lower - q) - B qd below the lower one, never
    pulling the joint outward; zero inside (MuJoCo's soft joint limit, as a spring-damper)."""
    if q > stops[i, 1]:
        return min(0.0, -stops[i, 2] * (q - stops[i, 1]) - stops[i, 3] * qd)
    if q < stops[i, 0]:
        return max(0.0, stops[i, 2] * (stops[i, 0] - q) - stops[i, 3] * qd)
    return 0.0


STOP_TIME_CONSTANT = 0.02
"""The time constant (s) of a joint-limit stop (joint_limits="spring"): MuJoCo's default soft-limit time
constant, critically damped."""

JOINT_LIMIT_CHOICES = ("warn", "stop", "spring", "ignore")


def joint_stops(arm: Robot, q0: np.ndarray, spring: bool) -> np.ndarray:
    """(n, 4) rows (lower, upper, K, B) of stop_torque: the arm's limits as critically damped
    spring-dampers of time constant STOP_TIME_CONSTANT on each joint's own inertia M_ii(q0),
    K = M_ii / tc^2, B = 2 M_ii / tc; limits at infinity (no stop) unless ``spring``."""
    stops = np.zeros((arm.n, 4))
    stops[:, 0], stops[:, 1] = -np.inf, np.inf
    if spring:
        inertia = np.diag(np.asarray(arm.inertia_matrix(q0)))
        stops[:, :2] = arm.qlim.T
        stops[:, 2], stops[:, 3] = inertia / STOP_TIME_CONSTANT**2, 2.0 * inertia / STOP_TIME_CONSTANT
    return stops


def stop_torques(stops: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """stop_torque for every joint at once (NumPy, for the Python loop and solve_ivp's Python route)."""
    above, below = q > stops[:, 1], q < stops[:, 0]  # gaps taken only there: an infinite limit has none
    beyond_upper = np.minimum(0.0, -stops[:, 2] * np.where(above, q - stops[:, 1], 0.0) - stops[:, 3] * qd)
    below_lower = np.maximum(0.0, stops[:, 2] * np.where(below, stops[:, 0] - q, 0.0) - stops[:, 3] * qd)
    return np.where(above, beyond_upper, np.where(below, below_lower, 0.0))


@njit(inline="always", **NUMBA_OPTIONS)
def rk4_stage_state(y: np.ndarray, rate: np.ndarray, c: float, h: float, out: np.ndarray) -> None:
    """The state at which RK4 evaluates its next stage: out = y + c h k (c = 1/2, 1/2, 1)."""
    for j in range(y.shape[0]):
        out[j] = y[j] + c * h * rate[j]


@njit(inline="always", **NUMBA_OPTIONS)
def rk4_advance(y: np.ndarray, k1: np.ndarray, k2: np.ndarray, k3: np.ndarray, k4: np.ndarray, h: float) -> None:
    """The classical fourth-order Runge-Kutta step y += h/6 (k1 + 2 k2 + 2 k3 + k4) from the four stage
    rates: the one compiled RK4 of the fixed-step runs, with or without drives."""
    for j in range(y.shape[0]):
        y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@njit(**NUMBA_OPTIONS)
def run_rk4(
    plant: tuple, controller: tuple, trajectory: tuple, steps: tuple, state: tuple, record: tuple, watch: tuple
) -> None:
    """Steps first..last-1 of fixed-step RK4 (the book's TRESP), recording each step's start.

    plant = (models (P, L), Coulomb and Stribeck tables (P, n, 4), switch times (P - 1,), disturbance (n,),
    Coulomb smoothing eps (n,), joint stops (n, 4): lower, upper, K, B, see stop_torque): the plant in
    force is models[p] from switch time p - 1 on.
    controller = (kind, model, model Coulomb and Stribeck (n, 4), gain table (4, n), hold, shares plant):
    control.control_law every ``hold`` steps on ``model``; "shares plant" when the model is
    the plant's own, so that the plant reuses the controller's M and N.
    trajectory = (kind, params (4, n), q0 (n,)): trajectories.desired.
    steps = (t0, dt, first, last). state = ([q; qd], held torque, integral of e, outcome),
    advanced in place. record = (t, q, qd, qdd, tau, q_d), each indexed by step.
    The run stops where M becomes singular or the state non-finite: outcome = (rows recorded,
    STOPPED_SINGULAR or STOPPED_DIVERGED, joint); it stays (-1, 0, -1) while all is well.
    watch = (contacts (C, ROW_SIZE) of observers.contact, held over each step as the disturbance is; the
    momentum observer (on, model, Coulomb and Stribeck (n, 4), eps (n,), gains (n,), memory (4, n)): its
    known terms integrated with the plant's own RK4 stages (observer_sample); record (residual, external
    torque), each indexed by step, written when the observer is on / there are contacts).
    """
    models, coulombs, switches, disturbance, eps, stops = plant
    contacts, observer, watched = watch
    observing, observer_gains, observer_memory = observer[0], observer[4], observer[5]
    residuals, external_torques = watched
    kind, model, model_coulomb, gain, hold, shares_plant = controller
    trajectory_kind, params, q0 = trajectory
    t0, dt, first, last = steps
    x, tau_held, e_int, outcome = state
    T_, Q, QD, QDD, TAU, QDES = record
    n = q0.shape[0]
    work = np.empty(workspace_size(n))
    control_work = np.empty(workspace_size(n))
    goal = np.empty((3, n))
    q, qd = x[:n].copy(), x[n:].copy()
    stages = np.empty((8, n))  # the RK4 slopes of q and qd
    k1q, k1v, k2q, k2v, k3q, k3v, k4q, k4v = stages[0], stages[1], stages[2], stages[3], stages[4], stages[5], \
        stages[6], stages[7]  # fmt: skip
    scratch = np.empty((6, n))
    qs, vs, net, applied, u, Nv = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4], scratch[5]
    M_, Mp = np.empty((n, n)), np.empty((n, n))
    external, momentum, known = np.zeros(n), np.empty(n), np.empty(n)
    observer_work = np.empty(workspace_size(n))
    for k in range(first, last):
        t = t0 + k * dt
        p = 0
        while p < switches.shape[0] and t >= switches[p]:
            p += 1
        plant_model, coulomb = models[p], coulombs[p]
        desired(trajectory_kind, params, t, q0, goal)
        fresh = kind == COMPUTED_TORQUE and shares_plant and p == 0 and k % hold == 0
        if kind > 0 and k % hold == 0:
            for i in range(n):
                e_int[i] += (goal[0, i] - q[i]) * dt * hold
            control_law(kind, model, model_coulomb, eps, control_work, q, qd, goal, e_int, gain, u, M_, Nv, tau_held)
        if contacts.shape[0] > 0:
            contact_torques(plant_model, contacts, work, t, q, qd, external)
            external_torques[k] = external
        for i in range(n):
            applied[i] = tau_held[i] - disturbance[i] + external[i]
        if observing:
            observer_terms(observer, observer_work, q, qd, tau_held, momentum, known)
            observer_sample(observer_memory, observer_gains, dt, momentum, known)
            residuals[k] = observer_memory[0]
        if fresh:  # the controller has just computed this state's M and N on the plant itself
            Mp[:, :] = M_
            singular = _solve(Mp, Nv, applied, coulomb, eps, stops, q, qd, k1v, plant_model[PIVOT_FLOOR])
        else:
            singular = _accelerations(plant_model, coulomb, eps, stops, work, q, qd, applied, Mp, net, k1v)
        if singular >= 0:
            outcome[0], outcome[1], outcome[2] = k, STOPPED_SINGULAR, singular
            break
        T_[k] = t
        for i in range(n):
            Q[k, i], QD[k, i], QDD[k, i], TAU[k, i], QDES[k, i] = q[i], qd[i], k1v[i], tau_held[i], goal[0, i]
        for i in range(n):
            k1q[i] = qd[i]
        rk4_stage_state(q, k1q, 0.5, dt, qs)
        rk4_stage_state(qd, k1v, 0.5, dt, vs)
        singular = max(singular, _accelerations(plant_model, coulomb, eps, stops, work, qs, vs, applied, Mp, net, k2v))
        if observing:
            observer_terms(observer, observer_work, qs, vs, tau_held, momentum, known)
            observer_stage(observer_memory, 2.0, dt, known)
        for i in range(n):
            k2q[i] = vs[i]
        rk4_stage_state(q, k2q, 0.5, dt, qs)
        rk4_stage_state(qd, k2v, 0.5, dt, vs)
        singular = max(singular, _accelerations(plant_model, coulomb, eps, stops, work, qs, vs, applied, Mp, net, k3v))
        if observing:
            observer_terms(observer, observer_work, qs, vs, tau_held, momentum, known)
            observer_stage(observer_memory, 2.0, dt, known)
        for i in range(n):
            k3q[i] = vs[i]
        rk4_stage_state(q, k3q, 1.0, dt, qs)
        rk4_stage_state(qd, k3v, 1.0, dt, vs)
        singular = max(singular, _accelerations(plant_model, coulomb, eps, stops, work, qs, vs, applied, Mp, net, k4v))
        if observing:
            observer_terms(observer, observer_work, qs, vs, tau_held, momentum, known)
            observer_stage(observer_memory, 1.0, dt, known)
        for i in range(n):
            k4q[i] = vs[i]
        rk4_advance(q, k1q, k2q, k3q, k4q, dt)
        rk4_advance(qd, k1v, k2v, k3v, k4v, dt)
        for i in range(n):  # a state that blew up explains a singular stage too
            if not (abs(q[i]) < LARGEST_STATE and abs(qd[i]) < np.inf):  # NaN fails both
                outcome[0], outcome[1], outcome[2] = k + 1, STOPPED_DIVERGED, i
                break
        if outcome[0] < 0 and singular >= 0:
            outcome[0], outcome[1], outcome[2] = k + 1, STOPPED_SINGULAR, singular
        if outcome[0] >= 0:
            break
    x[:n] = q
    x[n:] = qd


@njit(**NUMBA_OPTIONS)
def observer_terms(
    observer: tuple, work: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, p: np.ndarray,
    known: np.ndarray,
) -> None:  # fmt: skip
    """p and the known terms tau - beta of the observer's model at one state (observers.momentum.momentum_and_rate):
    one compiled function that the loop's four stages call, not four inlined copies (a shorter compile)."""
    _, model, coulomb, eps, _, _ = observer
    momentum_and_rate(model, coulomb, eps, work, q, qd, tau, p, known)


@njit(inline="always", **NUMBA_OPTIONS)
def observer_sample(memory: np.ndarray, gains: np.ndarray, h: float, momentum: np.ndarray, known: np.ndarray) -> None:
    """The momentum observer at a sample, in the loop: r = a r + (1 - a) (p - p_prev - integral) / h with
    a = exp(-K h) (the sampled observer's exact first-order filter, observers.momentum), the integral of the
    known terms tau - beta over the step just taken being the plant's RK4 quadrature h/6 (k1 + 2 k2 + 2 k3 + k4)
    of them (observer_stage), so that it is as exact as the plant's integration where a sampled log's
    trapezoid rule is not (the friction's reversals). Then the next step's integral starts with its first
    stage. memory = (r, p_prev, integral, [started, ...])."""
    r, previous, integral, started = memory[0], memory[1], memory[2], memory[3]
    for j in range(r.shape[0]):
        if started[0] > 0.0:
            a = np.exp(-gains[j] * h)
            r[j] = a * r[j] + (1.0 - a) * (momentum[j] - previous[j] - integral[j]) / h
        previous[j] = momentum[j]
        integral[j] = h / 6.0 * known[j]
    started[0] = 1.0


@njit(inline="always", **NUMBA_OPTIONS)
def observer_stage(memory: np.ndarray, weight: float, h: float, known: np.ndarray) -> None:
    """Adds an RK4 stage's known terms, weighted 2, 2 or 1, to the observer's integral over the step."""
    for j in range(known.shape[0]):
        memory[2, j] += weight * h / 6.0 * known[j]


@njit(**NUMBA_OPTIONS)
def run_drives(
    model: np.ndarray,
    drives: np.ndarray,
    gains: np.ndarray,
    law: int,
    kind: int,
    params: np.ndarray,
    q0: np.ndarray,
    y: np.ndarray,
    h: float,
    substeps: int,
    times: np.ndarray,
    states: np.ndarray,
    applied: np.ndarray,
    torques: np.ndarray,
    accelerations: np.ndarray,
    references: np.ndarray,
    first: int,
    stop: int,
) -> int:
    """Samples first..stop-1 of RK4 on y = [x, z] (the arm with its drives and the law's integrators),
    ``substeps`` steps of h between samples, the drive-level law evaluated at every stage
    (armdyn.dynamics.drives.closed_loop), the currents and spools put back within their limits at every
    stage and step (hold_limits); records each sample (the inputs as applied). Returns -1, or the sample
    where M(q) was singular or the state stopped being finite. The four stages share one evaluation site,
    so the inlined model is compiled once."""
    n, size, last = int(model[N_JOINTS]), y.shape[0], states.shape[0] - 1
    rates, stage_y = np.empty((4, size)), np.empty(size)
    u, tau, reference, work = np.empty(n), np.empty(n), np.empty((3, n)), np.empty(2 * n)
    recorded = states.shape[1]
    for sample in range(first, stop):
        t = sample * substeps * h
        for step in range(substeps):
            for stage in range(4):
                c = 0.0 if stage == 0 else (0.5 if stage < 3 else 1.0)
                if stage > 0:
                    rk4_stage_state(y, rates[stage - 1], c, h, stage_y)
                    hold_limits(drives, stage_y)
                at = y if stage == 0 else stage_y
                status = closed_loop(model, drives, gains, law, kind, params, q0, t + (step + c) * h, at, u, tau,
                                     reference, work, rates[stage], stage != 2)  # fmt: skip
                if status != OK:
                    return sample
                if step == 0 and stage == 0:
                    times[sample] = t
                    states[sample] = y[:recorded]
                    applied[sample] = u
                    torques[sample] = tau
                    accelerations[sample] = rates[0, n : 2 * n]
                    references[sample] = reference[0]
                    for j in range(size):
                        if not np.isfinite(y[j]):
                            return sample
                    if sample == last:
                        return -1
            rk4_advance(y, rates[0], rates[1], rates[2], rates[3], h)
            hold_limits(drives, y)
    return -1


# ----- the Python side ---------------------------------------------------------------------------------
def packed_plants(arms: list[Robot]) -> tuple[np.ndarray, np.ndarray]:
    """Compiled plants with their Coulomb and Stribeck friction taken out (the loop adds the smoothed
    laws), and those laws per arm, (A, n, 4): Tc+, Tc-, Fs, vs (friction.sign_law_table)."""
    plants, coulombs = [], []
    for arm in arms:
        assert arm.packed is not None, "the callers refuse symbolic arms"
        buffer = arm.packed.copy()  # packed once per Robot
        for i in range(arm.n):
            base = HEADER + STRIDE * i
            buffer[base + COULOMB_POS] = buffer[base + COULOMB_NEG] = buffer[base + STRIBECK_FORCE] = 0.0
        plants.append(buffer)
        coulombs.append(sign_law_table(arm))
    if len({b.shape for b in plants}) != 1:
        raise ModelError("every arm of a run (events included) must have the same joints")
    return np.stack(plants), np.stack(coulombs)


def unwrapped_law(controller: object, n: int) -> tuple[control.Spec | None, float, object]:
    """(spec for the compiled loop or None, sample period (0 continuous), the controller), each
    controller of a Digital or Saturated chain checked first (a class, a torque limit per joint)."""
    if controller is None:
        return control.Spec(control.NO_CONTROL, 0.0, 0.0, 0.0), 0.0, None
    period = 0.0
    inner = controller
    while True:
        _callable_argument(inner, "controller", "callable (see armdyn.control)", "armdyn.control.PID(kp, kv)")
        if isinstance(inner, control.Digital):
            period = inner.period
        elif isinstance(inner, control.Saturated):
            _check_limit(inner.limit, n)
        else:
            break
        inner = inner.controller
    spec_of = getattr(controller, "spec", None)
    spec = spec_of() if spec_of is not None else None
    return spec, period, controller


def _callable_argument(value: object, name: str, what: str, example: str) -> None:
    """Refuse ``value`` unless None or a callable object; a class is refused by name, being the
    usual slip (control.PID where control.PID(kp, kv) was meant), since calling it builds an object."""
    if value is None:
        return
    if isinstance(value, type):
        raise ArgumentError(
            f"{name} must be {what}, got the class {value.__name__} itself, not an object (e.g. {example})"
        )
    if not callable(value):
        raise ArgumentError(f"{name} must be {what}, got {type(value).__name__}")


def _check_limit(limit: object, n: int) -> None:
    """A Saturated torque limit must be one number or one per joint (Saturated checked its values)."""
    try:
        shape = np.atleast_1d(np.asarray(limit, dtype=float)).shape
    except (TypeError, ValueError):
        shape = None
    if shape not in ((1,), (n,)):
        shown = reprlib.repr(limit)
        raise ModelError(
            f"the torque limit of Saturated must be one number, or {n} (one per joint), got limit = {shown}"
        )


def _one_state(value: object, n: int, name: str, allow_scalar: bool = False) -> np.ndarray:
    """One finite state vector (n,) (or a real scalar for every joint), checked by armdyn.inputs."""
    if allow_scalar and isinstance(value, (int, float, np.integer, np.floating)):  # not np.ndim: a ragged list
        try:
            value = np.full(n, value, dtype=float)
        except OverflowError:  # a Python int beyond float
            raise ModelError(f"{name} must be finite, got {reprlib.repr(value)}") from None
    array = inputs.state(value, n, name, bounded=name in ("q0", "qd0"))  # torques may be large
    if array.shape != (n,):
        raise ModelError(f"{name} must be one state of {n} values, got shape {array.shape}")
    return array


def _events(arm: Robot, events: object) -> list[tuple[float, Robot]]:
    """(time, arm) pairs sorted by time; each time finite and >= 0, each arm a Robot with the plant's joints."""
    if isinstance(events, (str, bytes, Mapping)) or not isinstance(events, Iterable):
        raise ModelError(f"events must be a sequence of (time, arm) pairs, got {reprlib.repr(events)}")
    checked = []
    for event in events:
        try:
            time, plant = event
        except (TypeError, ValueError):
            raise ModelError(f"each event must be a (time, arm) pair, got {event!r}") from None
        if not _is_time(time):
            raise ModelError(f"an event time must be a finite number of seconds >= 0, got {reprlib.repr(time)}")
        if not isinstance(plant, Robot) or plant.n != arm.n or plant.is_symbolic:
            raise ModelError(f"the arm of the event at t = {time} must be a numeric Robot with {arm.n} joints")
        checked.append((float(time), plant))
    return sorted(checked, key=lambda e: e[0])


def _is_time(value: object) -> bool:
    """Whether ``value`` is a real number (not a bool) that is finite and >= 0 as a float."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    try:
        seconds = float(value)
    except OverflowError:  # a Python int beyond float
        return False
    return math.isfinite(seconds) and seconds >= 0


def _users_own(item: object) -> bool:
    return item is not None and type(item).__module__ not in (
        "armdyn.control.joint",
        "armdyn.control.task",
        "armdyn.trajectories.joint",
        "armdyn.trajectories.task",
    )


def checked_times(t_final: object, dt: object) -> tuple[float, float]:
    """t_final and dt as positive floats (below 1e15), t_final a whole number of steps dt (to 1e-9
    relative), or a ModelError naming them (and the nearest valid t_final): nothing is rounded silently."""
    checked = []
    for name, value in (("t_final", t_final), ("dt", dt)):
        try:
            seconds = inputs.number(value, name)
        except ModelError:  # one message for every way of not being a time
            seconds = math.nan
        if not seconds > 0:
            raise ModelError(
                f"{name} must be a positive number of seconds, below {LARGEST_STATE:.0e}, got {reprlib.repr(value)}"
            )
        checked.append(seconds)
    t_final, dt = checked
    ratio = t_final / dt
    steps = round(ratio) if ratio <= MAX_SAMPLES else 0  # a record too long is step_count's to refuse
    if ratio <= MAX_SAMPLES and (steps < 1 or abs(ratio - steps) > 1e-9 * ratio):
        nearest = sorted({max(1, math.floor(ratio)), max(1, math.ceil(ratio))})
        raise ModelError(
            f"t_final = {t_final:g} s is not a whole number of steps of dt = {dt:g} s ({ratio:.6g} steps): the "
            f"nearest valid t_final is {' or '.join(f'{k * dt:.12g} s' for k in nearest)}"
        )
    return t_final, dt


def _method_name(method: object) -> str:
    """The method's name in lower case ("rk4" or one of ADAPTIVE), or a ModelError listing them."""
    if not isinstance(method, str) or method.lower() not in ("rk4", *ADAPTIVE):
        raise ModelError(f"method must be 'rk4' or one of {ADAPTIVE} (in any case), got {reprlib.repr(method)}")
    return method.lower()


def _smoothing_choice(eps: object) -> str | float:
    """coulomb_smoothing as "auto" or a float >= 0, or a ModelError naming it."""
    if isinstance(eps, str):
        if eps != "auto":
            raise ModelError(f"coulomb_smoothing must be 'auto' or a number, got {reprlib.repr(eps)}")
        return eps
    return inputs.number(eps, "coulomb_smoothing", minimum=0.0)


def step_count(t_final: float, dt: float, n: int, adaptive: bool) -> int:
    """The number of steps, round(t_final / dt), refused before anything is allocated when the
    record would hold more than MAX_SAMPLES samples or more bytes than the memory available."""
    samples = t_final / dt + 1  # a float: it may be far beyond any array (1e14 s / 1e-300 s)
    per_sample = 8 * (1 + (9 if adaptive else 5) * n)  # t and 5 (n,) arrays; solve_ivp's 3n states held twice
    available = memory.available()
    if samples > MAX_SAMPLES or (available is not None and samples * per_sample > available):
        room = "" if available is None else f"; {memory.size(available)} of memory is available"
        raise ModelError(
            f"t_final = {t_final:g} s with dt = {dt:g} s is {samples:.4g} samples, whose record needs "
            f"{memory.size(samples * per_sample)} (at most {MAX_SAMPLES:,} samples{room}): "
            "shorten t_final or lengthen dt"
        )
    return round(t_final / dt)


def simulate(
    arm: Robot | DrivenPlant,
    controller: object = None,
    trajectory: object = None,
    t_final: float = 5.0,
    dt: float = 1e-3,
    method: str = "rk4",
    q0: ArrayLike | None = None,
    qd0: ArrayLike | None = None,
    disturbance: object = None,
    events: Sequence[tuple[float, Robot]] = (),
    coulomb_smoothing: float | str = "auto",
    progress: Callable[[float], None] | None = None,
    step: float | None = None,
    runs: int | None = None,
    plants: Plants | Robot | None = None,
    models: Plants | Robot | None = None,
    gains: object = None,
    keep: str | int | None = None,
    after: float | None = None,
    threads: int | None = None,
    joint_limits: str = "warn",
    observer: MomentumObserver | None = None,
) -> Result | Ensemble:
    """Simulate a plant under control from (q0, qd0) for t_final seconds (Lewis, Dawson and Abdallah 2004, Chapter 4).

    The one way to simulate: one run of an arm (a Robot), one run of an arm with its drives (an
    ActuatedArm, Section 3.6: the drives' electrics and hydraulics integrated with the links), or many
    runs at once (``runs=``, or any of the per-run arguments below).

    Integrates M qdd + N(q, qd) + tau_d = tau. With ``method="rk4"`` (the book's TRESP) the
    controller runs once per step, or once per sample period of a Digital controller with
    its torque held in between. When the controller is one of armdyn.control's, the
    trajectory None, Sinusoid or Quintic and the disturbance constant, the whole run is
    one compiled call; a controller or trajectory of the user's own runs in a Python loop
    of the same scheme, 80 to 300 times slower (more for smaller arms), and simulate says so with a
    PythonLoopWarning (silence it with the warnings module once the cost is known).
    Coulomb friction is smoothed through zero velocity (see the module docstring).

    Parameters
    ----------
    arm : Robot or ActuatedArm
        The plant: a numeric arm, or an arm with its drives (any DrivenPlant).
    controller : callable, optional
        None (zero torque), one of armdyn.control's, or any callable
        ``controller(t, q, qd, q_d, qd_d, qdd_d, e_int) -> tau``; one that takes a ``plant``
        keyword is given the arm in force at time t.
    trajectory : callable, optional
        None (hold q0), a Sinusoid, Quintic or CartesianCircle of armdyn.trajectories, or any
        callable ``t -> (q_d, qd_d, qdd_d)``.
    t_final : float
        Seconds to simulate (below 1e15).
    dt : float
        The RK4 step, and the sampling of the result for adaptive methods. t_final must be a whole
        number of steps (to 1e-9 relative; else the error names the nearest valid t_final). It records about
        t_final / dt + 1 samples, at most MAX_SAMPLES (200,000,000), of 8 (1 + 5 n) bytes
        each (8 (1 + 9 n) with an adaptive method), which must fit in the memory available
        (the system's, less where a cgroup or RLIMIT_AS limit leaves less): a longer run is
        refused before anything is allocated.
    method : str
        "rk4" (fixed step dt) or an adaptive solve_ivp method: "rk45", "rk23", "dop853",
        "radau", "bdf", "lsoda" (in any case: "RK45" and "Radau" as scipy spells them).
    q0, qd0 : array_like, optional
        Initial joint positions and velocities (zeros by default).
    disturbance : array_like or callable, optional
        tau_d: a constant (n,) vector, a callable ``(t, q, qd) -> tau_d``, or contacts on link points
        (armdyn.observers.contact's Push, Impulse or Clamp, or a list of them: tau_d = -J_p^T F, run in the
        compiled loop, their torque recorded as ``Result.external_torque``).
    events : sequence of (float, Robot)
        (time, arm) pairs: from that time on the plant is that arm (a payload change).
    coulomb_smoothing : float or "auto"
        eps of the smoothed Coulomb law, one number for every joint, or "auto" (sized to
        the step, see the module docstring); 0 is the exact sign law.
    progress : callable, optional
        Called with the fraction done (0 to 1) as the compiled run (or an adaptive one) proceeds.
    step : float, optional
        An arm with drives only: the largest RK4 step (s), the run recording every ``dt``; by default
        the step the drives' time constants allow (armdyn.actuators.stable_step at the start).
    runs : int, optional
        Many runs in one compiled call, parallel over runs (each equal to the single run with its
        arguments to rounding), taken when ``runs`` or any of the many-run arguments below is given:
        N, or None for the length of the per-run arguments. q0, qd0 and the disturbance may then hold
        one row per run, the trajectory may be a sequence (one per run, of one kind), and the
        controller must be one of armdyn.control's joint laws; method="rk4" only.
    plants, models : Plants or Robot, optional
        Many runs: the plants, and the controller's models (its belief), one variant per run or one
        for all (``plant_variants``).
    gains : array_like, optional
        Many runs: (N, 3, n) or (3, n), kp, kv and ki per run, replacing the controller's.
    keep : "summary", "full" or int, optional
        Many runs: what is kept of each, the summaries only (default), every step, or every k-th step.
    after : float, optional
        Many runs: the start of the "max error after" window of the summaries (s), from 0 to t_final;
        default 1 s, or t_final when the run is shorter.
    threads : int, optional
        Many runs: Numba's thread count for the call (default: as set; all cores).
    joint_limits : str
        One run: what the arm's joint limits (``arm.qlim``) do. "warn" (default): the run ignores them
        and a JointLimitWarning names the first joint that left its limits, when and where; "stop":
        a SimulationError at that sample (its ``result`` holds the run up to it); "spring": each limit
        is a critically damped spring-damper stop of time constant STOP_TIME_CONSTANT (0.02 s, MuJoCo's
        soft limit) on the joint's own inertia, which a joint enters only slightly; "ignore": nothing.
        Many runs ignore the limits. An arm with drives takes "warn", "stop" and "ignore".
    observer : MomentumObserver, optional
        One run of a Robot: a generalized-momentum observer (armdyn.observers.momentum) that watches the run on
        its own model and gains, its residual recorded as ``Result.residual``. In the compiled loop it
        integrates its known terms with the plant's own RK4 stages; after a Python loop (or an adaptive
        method) it runs on the recorded samples. Its Coulomb smoothing is the plant's unless it has its own.

    Returns
    -------
    Result or Ensemble
        One run: times, joint positions, velocities, accelerations and torques (time first), the
        desired positions with a trajectory, energies, ``info`` (the route taken), with an observer its
        residual, with contacts their torque and, for an arm with drives, ``drives`` (a DriveRecord).
        Many runs: an Ensemble (per-run summaries, and the samples kept, with dimensions run, time and
        joint).

    Raises
    ------
    ModelError
        When t_final or dt is not a positive number (or is 1e15 or more), or the run would
        record more samples than MAX_SAMPLES or than the memory available holds (the message
        says how much it needs); when q0 or qd0 has the wrong shape; when the controller's model
        does not match the arm, a Saturated limit is not one number or one per joint, or a
        Digital period is not a whole number of steps (or meets an adaptive method); when events
        is not a sequence of (time >= 0, numeric Robot) pairs, coulomb_smoothing is not "auto" or
        a number >= 0, the method is unknown (the message lists the methods), or a disturbance is
        neither a callable nor one or n finite numbers; and during the
        run when a controller, trajectory or disturbance of the user's returns other than n
        finite values (the message names which).
    armdyn.ArgumentError
        When the plant is neither a numeric Robot nor an arm with drives, an option does not apply to
        the plant or to many runs (the message names it), or the controller, the trajectory or the
        progress callback is neither None nor a callable object (a class, such as control.PID for
        control.PID(kp, kv), included), or plants or models is not a Robot or Plants.
    SimulationError
        When M(q) becomes singular or the state non-finite during the run (its ``result``
        holds the run up to then), or an adaptive solver fails.
    """
    given_events = tuple(events) if isinstance(events, list) else events  # a generator is read once, by _events
    if not isinstance(joint_limits, str) or joint_limits not in JOINT_LIMIT_CHOICES:
        raise ModelError(
            f"joint_limits must be one of {', '.join(JOINT_LIMIT_CHOICES)}, got {reprlib.repr(joint_limits)}"
        )
    limits = joint_limits
    single_run_options = {"method": (method, "rk4"), "events": (given_events, ()), "progress": (progress, None),
                          "coulomb_smoothing": (coulomb_smoothing, "auto"),
                          "joint_limits": (joint_limits, "warn"), "observer": (observer, None)}  # fmt: skip
    per_run = {"runs": runs, "plants": plants, "models": models, "gains": gains, "keep": keep, "after": after,
               "threads": threads}  # fmt: skip
    if isinstance(arm, DrivenPlant):
        if limits == "spring":
            raise ArgumentError("joint_limits='spring' applies to a Robot (an arm with drives takes 'warn', 'stop' "
                                "or 'ignore')")  # fmt: skip
        driven_options = {name: value for name, value in single_run_options.items() if name != "joint_limits"}
        _refuse_options(arm, {**driven_options, "disturbance": (disturbance, None),
                              **{name: (value, None) for name, value in per_run.items()}})  # fmt: skip
        return within_limits(_simulate_driven(arm, controller, trajectory, t_final, dt, q0, qd0, step), limits)
    inputs.arm_argument(
        arm, Robot, "arm", numeric=True, why=" (simulate takes a numeric Robot or an armdyn.actuators.ActuatedArm)"
    )
    if step is not None:
        raise ArgumentError("step applies to an arm with drives (a Robot's RK4 step is dt)")
    if any(value is not None for value in per_run.values()):  # many runs are asked for by name, never guessed
        _refuse_options(arm, single_run_options)
        if contacts_table(arm, disturbance) is not None:
            raise ArgumentError("contacts (Push, Impulse, Clamp) apply to one run; many runs take a constant "
                                "disturbance, one (n,) row per run or one for all")  # fmt: skip
        return _simulate_runs(arm, controller, trajectory, t_final, dt, runs, q0, qd0, plants, models, gains,
                              disturbance, keep, after, threads)  # fmt: skip
    n = arm.n
    t_final, dt = checked_times(t_final, dt)
    method = _method_name(method)
    adaptive = method in ADAPTIVE
    coulomb_smoothing = _smoothing_choice(coulomb_smoothing)
    _callable_argument(
        trajectory, "trajectory", "None or a callable t -> (q_d, qd_d, qdd_d)", "armdyn.trajectories.Sinusoid(a, f)"
    )
    _callable_argument(progress, "progress", "None or a callable taking the fraction done", "print")
    start, velocity = (np.zeros(n) if x is None else _one_state(x, n, name) for x, name in ((q0, "q0"), (qd0, "qd0")))
    if observer is not None and not isinstance(observer, MomentumObserver):
        raise ArgumentError(f"observer must be an armdyn.observers.momentum.MomentumObserver, got {observer!r:.60}")
    if observer is not None and observer.arm.n != n:
        raise ModelError(f"the observer's arm has {observer.arm.n} joints, the simulated arm {n}")
    contacts = contacts_table(arm, disturbance)
    contact_sum = None
    if contacts is not None:
        contact_sum = _ContactSum(list(disturbance) if isinstance(disturbance, (list, tuple)) else [disturbance])
        disturbance = contact_sum
    if disturbance is not None and (isinstance(disturbance, type) or not callable(disturbance)):  # a class: no law
        disturbance = np.broadcast_to(_one_state(disturbance, n, "disturbance", allow_scalar=True), (n,)).copy()
    plant_events = _events(arm, events)
    arms = [arm] + [e[1] for e in plant_events]
    steps = step_count(t_final, dt, n, adaptive)
    law = controller
    spec, period, controller = unwrapped_law(controller, n)
    if adaptive and period:
        raise ModelError("a Digital controller needs method='rk4' (the book's fixed-step TRESP)")
    compiled = (
        spec is not None
        and trajectories.packed(trajectory, n) is not None
        and (disturbance is None or not callable(disturbance) or (contacts is not None and not adaptive))
        and (spec.model is None or not spec.model.is_symbolic)
    )
    stops = joint_stops(arm, start, limits == "spring")
    setup = _compiled_setup(arm, arms, plant_events, spec, period, trajectory, start,
                            None if contacts is not None else disturbance, dt, coulomb_smoothing, stops) \
        if compiled else None  # fmt: skip
    users_disturbance = callable(disturbance) and contacts is None
    if not compiled and (_users_own(controller) or _users_own(trajectory) or users_disturbance):
        warnings.warn(
            "simulate runs this controller, trajectory or disturbance of your own in Python, 80 to 300 times "
            "slower than the compiled code that armdyn.control's controllers with a Sinusoid or Quintic trajectory "
            "and a constant disturbance run in",
            PythonLoopWarning,
            stacklevel=2,
        )
    described = {
        "controller": control.describe_controller(controller),
        "trajectory": trajectories.describe_trajectory(trajectory),
    }
    if adaptive:
        result = _adaptive(arms, plant_events, controller, trajectory, start, velocity, disturbance, steps, dt,
                           method, coulomb_smoothing, progress, setup, stops)  # fmt: skip
    elif compiled:
        assert setup is not None
        watch = _watch(arm, contacts, observer, setup[0][4], steps)
        result = _compiled_rk4(arm, arms, plant_events, trajectory, start, velocity, steps, dt, progress, setup, watch)
        if contact_sum is not None:
            contact_sum.took(watch[0])
        if observer is not None:
            result.info["observer"] = "in the loop, its known terms integrated with the plant's RK4 stages"
    else:
        result = _python_rk4(arms, plant_events, controller, period, trajectory, start, velocity, disturbance,
                             steps, dt, coulomb_smoothing, stops)  # fmt: skip
    result.info.update(described)
    if not compiled or adaptive:  # the compiled loop records them itself
        _watched_after(result, contact_sum, observer, not adaptive)
    tracking = getattr(law, "tracking", None)
    if callable(tracking):  # a task-space law records its task error
        result.task = tracking(arm, result.t, result.q)
    return within_limits(result, "ignore" if limits == "spring" else limits)


class JointLimitWarning(UserWarning):
    """A simulated joint left its limits (simulate's joint_limits="warn")."""


def within_limits(result: Result, mode: str) -> Result:
    """The run checked against its arm's joint limits (simulate's ``joint_limits``): unchanged, with a
    JointLimitWarning naming the first joint that left its limits ("warn"), or a SimulationError holding
    the run up to that sample ("stop")."""
    if mode == "ignore" or len(result.t) == 0:
        return result
    lower, upper = result.arm.qlim
    slack = 1e-9 * np.maximum(1.0, np.abs(np.where(np.isfinite(lower), lower, 0.0)))
    outside = (result.q < lower - slack) | (result.q > upper + slack)
    if not outside.any():
        return result
    row = int(np.argmax(outside.any(axis=1)))
    joint = int(np.argmax(outside[row]))
    value, name = result.q[row, joint], result.arm.joint_names[joint]
    unit = "m" if result.arm.kinds[joint] == "prismatic" else "rad"
    what = (f"joint '{name}' of '{result.arm.name}' left its limits [{lower[joint]:.6g}, {upper[joint]:.6g}] {unit} at "
            f"t = {result.t[row]:.6g} s (q = {value:.6g} {unit})")  # fmt: skip
    if mode == "stop":
        kept = Result(result.t[: row + 1], result.q[: row + 1], result.qd[: row + 1], result.qdd[: row + 1],
                      result.tau[: row + 1], None if result.q_d is None else result.q_d[: row + 1], result.arm,
                      {**result.info, "stopped": "joint limit"}, result.energy_of)  # fmt: skip
        kept.drives = result.drives
        raise SimulationError(f"the run stopped: {what} (joint_limits='stop')", kept)
    warnings.warn(f"{what}; simulation does not enforce joint limits: give joint_limits='spring' to model them as "
                  "stops, 'stop' to end the run there, or 'ignore'", JointLimitWarning, stacklevel=3)  # fmt: skip
    return result


@runtime_checkable
class DrivenPlant(Protocol):
    """What the stepper needs of an arm with drives (armdyn.actuators.ActuatedArm implements it): its
    joints and full state, the mechanics the drives act on, the drives packed for the compiled model,
    the RK4 step their time constants allow, its start, and the record of what the drives did."""

    name: str
    n: int
    n_states: int

    def mechanical_robot(self) -> Robot: ...

    def packed_drives(self) -> np.ndarray: ...

    def stable_step(self, q: ArrayLike, bandwidth: ArrayLike | None = None) -> float: ...

    def initial_state(self, q: ArrayLike, qd: ArrayLike | None = None) -> np.ndarray: ...

    def drive_record(self, states: np.ndarray, applied: np.ndarray) -> DriveRecord: ...


def _refuse_options(arm: object, options: Mapping[str, tuple[object, object]]) -> None:
    """An ArgumentError naming the options given that do not apply to this plant or route."""
    given = [name for name, (value, default) in options.items() if not _is_default(value, default)]
    if given:
        what = "an arm with drives" if isinstance(arm, DrivenPlant) else "many runs at once"
        raise ArgumentError(f"{', '.join(given)} do{'es' if len(given) == 1 else ''} not apply to {what}")


def _is_default(value: object, default: object) -> bool:
    """Whether an option was left at its default (an empty sequence of events included)."""
    if value is default:
        return True
    if isinstance(default, tuple):
        return isinstance(value, (tuple, list)) and len(value) == 0
    return isinstance(value, str) and value == default


def _simulate_driven(
    arm: DrivenPlant, controller: object, trajectory: object, t_final: float, dt: float, q0: object, qd0: object,
    step: float | None,
) -> Result:  # fmt: skip
    """One run of an arm with its drives (Lewis, Dawson and Abdallah 2004, Section 3.6): the full model
    x = [q, qd, q_M, qd_M, i, x_v, P_L] and the law's integrators by compiled RK4, the drive-level law
    evaluated at every stage, the inputs clipped to their limits and the currents and spools held within
    theirs at every stage (armdyn.dynamics.drives: a saturated current loop, a spool's hard stop). The drives
    are stiff (L/R is about a millisecond, an oil column rings at hundreds of hertz): the run records every
    ``dt`` and integrates with the step their time constants allow (``info["substeps"]`` steps per sample)."""
    from armdyn.control.drives import drive_law

    n = arm.n
    drives = arm.packed_drives()
    law, gains, bandwidth = drive_law(controller, arm)
    t_final, dt = checked_times(t_final, dt)
    path = trajectories.packed(trajectory, n)
    if path is None:
        raise ArgumentError("trajectory must be None, an armdyn.trajectories.Sinusoid or a Quintic (an arm with "
                            "drives runs compiled)")  # fmt: skip
    start, rates = (np.zeros(n) if x is None else _one_state(x, n, name) for x, name in ((q0, "q0"), (qd0, "qd0")))
    longest = arm.stable_step(start, bandwidth)
    if step is not None:
        longest = inputs.number(step, "step")
        if not (0 < longest < math.inf):
            raise ModelError(f"step must be a positive number of seconds, got {step}")
    samples = step_count(t_final, dt, arm.n_states, False) + 1
    if not dt / longest <= MAX_SUBSTEPS or (samples - 1) * (dt / longest) > MAX_SAMPLES:
        what = "step" if step is not None else "the drives' stable step (give a larger step=)"
        shortest = max(dt / MAX_SUBSTEPS, t_final / MAX_SAMPLES)
        raise ModelError(
            f"{what} = {longest:g} s needs {dt / longest:.4g} RK4 steps per sample of dt = {dt:g} s: at most "
            f"{MAX_SUBSTEPS:,} per sample and {MAX_SAMPLES:,} in all (step >= {shortest:g} s)"
        )
    substeps = max(1, math.ceil(dt / longest - 1e-9))
    y = np.concatenate([arm.initial_state(start, rates), np.zeros(n)])
    times, states = np.empty(samples), np.empty((samples, arm.n_states))
    applied, torques = np.empty((samples, n)), np.empty((samples, n))
    accelerations, references = np.empty((samples, n)), np.empty((samples, n))
    mechanical = arm.mechanical_robot()
    assert mechanical.packed is not None, "an ActuatedArm refuses symbolic arms"
    stopped, packed = [-1], mechanical.packed

    def advance(first: int, last: int) -> bool:
        stopped[0] = run_drives(packed, drives, gains, law, path[0], path[1], start, y, dt / substeps, substeps,
                                times, states, applied, torques, accelerations, references, first, last)  # fmt: skip
        return stopped[0] < 0

    info = {"method": "rk4 (compiled, with the drives' dynamics)", "dt": dt, "substeps": substeps,
            "step": dt / substeps, "controller": control.describe_controller(controller),
            "trajectory": trajectories.describe_trajectory(trajectory)}  # fmt: skip

    def recorded(rows: int, extra: dict) -> Result:
        q, qd = states[:rows, :n], states[:rows, n : 2 * n]
        run = Result(times[:rows], q, qd, accelerations[:rows], torques[:rows],
                     references[:rows] if trajectory is not None else None, mechanical, {**info, **extra},
                     lambda: np.asarray(mechanical.kinetic_energy(q, qd) + mechanical.potential_energy(q)))  # fmt: skip
        run.drives = arm.drive_record(states[:rows], applied[:rows])
        return run

    in_chunks(advance, samples, None, lambda rows: recorded(rows, {"stopped": "interrupted"}))
    result = recorded(samples if stopped[0] < 0 else stopped[0], {})
    if stopped[0] >= 0:
        raise SimulationError(
            f"the run of '{arm.name}' with its drives stopped at t = {stopped[0] * dt:.6g} s: M(q) became singular or "
            "the state not finite (lower the gains, give a smaller step=, or check the drives' limits); the run "
            "up to then is in this error's .result",
            result,
        )
    return result


def law_table(spec: control.Spec, period: float, dt: float, n: int) -> tuple[np.ndarray, int]:
    """The compiled law's gain table (4, n): kp, kv, ki and the torque limit; and its hold, the steps per
    sample period (1 when continuous), refused unless the period is a whole number of steps."""
    gain = np.stack([
        *(inputs.gains(g, name, n) for g, name in ((spec.kp, "kp"), (spec.kv, "kv"), (spec.ki, "ki"))),
        np.broadcast_to(np.asarray(spec.limit, dtype=float), (n,)),
    ])  # fmt: skip
    hold = max(1, round(period / dt)) if period else 1
    if period and abs(hold * dt - period) > 1e-9 * period:
        raise ModelError(f"the sample period {period} must be a whole number of steps dt = {dt}")
    return gain, hold


def _compiled_setup(arm, arms, events, spec, period, trajectory, q0, disturbance, dt, eps, stops):
    """The plant, controller and trajectory tuples of run_rk4 and continuous_rate."""
    n = arm.n
    plants, coulombs = packed_plants(arms)
    switches = np.array([e[0] for e in events], dtype=float)
    if spec.model is not None and spec.model.n != n:
        raise ModelError("the controller's model must have the plant's joints")
    models, model_coulombs = packed_plants([spec.model if spec.model is not None else arm])
    model, model_coulomb = models[0], model_coulombs[0]
    gain, hold = law_table(spec, period, dt, n)
    trajectory_kind, params = trajectories.packed(trajectory, n)
    tau_d = np.zeros(n) if disturbance is None else np.broadcast_to(np.asarray(disturbance, float), (n,)).copy()
    smoothing = _smoothing(arm, eps, dt, q0)
    return (
        (plants, coulombs, switches, tau_d, smoothing, stops),
        (spec.kind, model, model_coulomb, gain, hold, spec.model is None),
        (trajectory_kind, params, q0),
    )


def _compiled_rk4(arm, arms, events, trajectory, q0, qd0, steps, dt, progress, setup, watch):
    n = arm.n
    plant, controller, desired_path, watch = without_read_only((*setup, watch))
    arrays = {name: np.empty((steps + 1, n)) for name in ("q", "qd", "qdd", "tau", "q_d")}
    times = np.empty(steps + 1)
    state, tau_held, e_int, outcome = np.concatenate([q0, qd0]), np.zeros(n), np.zeros(n), np.array([-1, 0, -1])
    record = (times, arrays["q"], arrays["qd"], arrays["qdd"], arrays["tau"], arrays["q_d"])

    def advance(first: int, last: int) -> bool:
        run_rk4(plant, controller, desired_path, (0.0, dt, first, last), (state, tau_held, e_int, outcome), record,
                watch)  # fmt: skip
        return outcome[0] < 0

    def recorded(rows: int, extra: dict) -> Result:
        q, qd = arrays["q"][:rows], arrays["qd"][:rows]
        return Result(times[:rows], q, qd, arrays["qdd"][:rows], arrays["tau"][:rows],
                      arrays["q_d"][:rows] if trajectory is not None else None, arm,
                      {"method": "rk4 (compiled)", "dt": dt, "integral": e_int, "coulomb_smoothing": plant[4], **extra},
                      lambda: _energies(arms, events, times[:rows], q, qd),
                      residual=watch[2][0][:rows] if watch[1][0] else None,
                      external_torque=watch[2][1][:rows] if watch[0].shape[0] else None)  # fmt: skip

    in_chunks(advance, steps + 1, progress, lambda rows: recorded(rows, {"stopped": "interrupted"}))
    rows = steps + 1 if outcome[0] < 0 else int(outcome[0])
    result = recorded(rows, {})
    if outcome[0] >= 0:
        raise _stopped(arm, int(outcome[1]), int(outcome[2]), rows * dt, state[:n], result)
    return result


def _watch(arm: Robot, contacts: np.ndarray | None, observer: MomentumObserver | None, eps: np.ndarray,
           steps: int) -> tuple:  # fmt: skip
    """run_rk4's ``watch``: the contacts, the observer (its model, friction, smoothing, gains and memory) and
    their record, empty where there is none."""
    n = arm.n
    table = np.zeros((0, ROW_SIZE)) if contacts is None else contacts
    if observer is None:
        watcher = (False, arm.packed, np.zeros((n, 4)), np.zeros(n), np.ones(n), np.zeros((4, n)))
    else:
        own = observer.smoothing
        smoothing = own if observer.coulomb_smoothing is not None else eps
        watcher = (True, observer.arm.packed, sign_law_table(observer.arm), smoothing, observer.rates,  # type: ignore[attr-defined]
                   np.zeros((4, n)))  # fmt: skip
    rows = steps + 1
    record = (np.empty((rows if observer is not None else 0, n)), np.zeros((rows if contacts is not None else 0, n)))
    return table, watcher, record


class _ContactSum:
    """Contacts as one disturbance of the Python loop: tau_d = -sum of J_p^T F."""

    def __init__(self, contacts: list) -> None:
        self.contacts = contacts

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return sum((contact(t, q, qd) for contact in self.contacts), np.zeros(q.shape[-1]))

    def external_torque(self, t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        return -self(t, q, qd)

    def took(self, table: np.ndarray) -> None:
        """Clamps keep the anchors the compiled run took."""
        for contact, row in zip(self.contacts, table, strict=True):
            taker = getattr(contact, "take_anchor", None)
            if taker is not None:
                taker(row)


def _watched_after(result: Result, contacts: _ContactSum | None, observer: MomentumObserver | None,
                   held: bool) -> None:  # fmt: skip
    """The contacts' torque and the observer's residual of a run not in the compiled loop, from its samples."""
    if contacts is not None:
        samples = zip(result.t, result.q, result.qd, strict=True)
        result.external_torque = np.array([contacts.external_torque(t, q, qd) for t, q, qd in samples])
    if observer is not None and len(result.t) >= 2:
        given = observer.coulomb_smoothing
        eps = given if given is not None else result.info.get("coulomb_smoothing")
        result.residual = observe(observer.arm, result.t, result.q, result.qd, result.tau, observer.rates, held, eps)
        result.info["observer"] = "on the samples after the run"


CHUNK_SECONDS = 0.1
"""The wall time of one compiled call of a long run: between calls Ctrl-C (KeyboardInterrupt) is seen and the
progress reported."""


class RunInterrupted(KeyboardInterrupt):
    """Ctrl-C during a run: a KeyboardInterrupt whose ``result`` holds the run computed until then."""

    def __init__(self, message: str, result: object) -> None:
        super().__init__(message)
        self.result = result


def in_chunks(
    advance: Callable[[int, int], bool], rows: int, progress: Callable[[float], None] | None,
    interrupted: Callable[[int], object],
) -> None:  # fmt: skip
    """Rows 0..rows-1 of a compiled loop in calls of about CHUNK_SECONDS each (``advance(first, last)``,
    False when the run stopped), so that Ctrl-C stops a long run within a fraction of a second: it raises
    RunInterrupted holding ``interrupted(rows done)``. The loop's results do not depend on the chunks."""
    done, size, reported = 0, min(rows, 256), 0.0
    try:
        while done < rows:
            last = min(rows, done + size)
            started = time.perf_counter()
            going = advance(done, last)
            spent = time.perf_counter() - started
            done = last
            if not going:
                return
            if progress is not None and (done == rows or done / rows >= reported + 0.05):
                reported = done / rows
                progress(reported)
            size = int(min(max(size * 2, 1), max(1.0, size * CHUNK_SECONDS / max(spent, 1e-6))))
    except KeyboardInterrupt:
        raise RunInterrupted(f"interrupted after {done} of {rows} samples", interrupted(done)) from None


def _stopped(arm: Robot, reason: int, joint: int, t: float, q: np.ndarray, result: Result) -> SimulationError:
    """The error of a run that cannot go on, naming the time and the joint."""
    name = arm.joint_names[joint]
    if reason == STOPPED_SINGULAR:
        message = (
            f"the simulation of '{arm.name}' stopped at t = {t:.6g} s: M(q) is singular at q = "
            f"{np.array2string(q, precision=4)}, nothing with mass or inertia moves about joint '{name}'"
        )
    else:
        message = (
            f"the simulation of '{arm.name}' diverged at t = {t:.6g} s: joint '{name}' reached a non-finite "
            "state (lower the gains, or the step dt); the run up to then is in this error's .result"
        )
    return SimulationError(message, result)


def _energies(arms: list[Robot], events: list, times: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """K + P at every sample, each by the arm in force at that time (one batch call per arm)."""
    phase = np.searchsorted(np.array([e[0] for e in events], dtype=float), times, side="right")
    energy = np.empty(len(times))
    for index, arm in enumerate(arms):
        mask = phase == index
        if np.any(mask):
            kinetic_and_potential = api.energies(arm, q[mask], qd[mask])
            energy[mask] = kinetic_and_potential[:, 0] + kinetic_and_potential[:, 1]
    return energy


def _smoothing(arm: Robot, eps: str | float, dt: float, q0: np.ndarray) -> np.ndarray:
    """eps_i per joint (``eps`` checked by _smoothing_choice). "auto": the friction's stiffness
    Tc_i / (eps_i M_ii) times dt stays at 1, inside RK4's stability limit (2.79), and eps_i is
    never below 1e-3 rad/s."""
    if isinstance(eps, str):
        largest = np.abs(arm.coulomb_friction).max(axis=1) + arm.stribeck_friction[:, 0]
        diagonal = np.diag(arm.inertia_matrix(q0))  # zero where M(q0) is singular: the run then stops there
        stiffness = np.divide(largest * dt, diagonal, out=np.zeros(arm.n), where=diagonal > 0)
        return np.maximum(1e-3, stiffness)
    return np.full(arm.n, float(eps))


def _plant_at(arms: list[Robot], events: list, t: float) -> Robot:
    index = sum(1 for e in events if t >= e[0])
    return arms[index]


def _dynamics(arms, events, eps, stops):
    bare = [a.replace([_no_coulomb(link) for link in a.links]) for a in arms]
    stribeck = [a.stribeck_friction if np.any(a.stribeck_friction[:, 0] != 0) else None for a in arms]

    def qdd(t: float, q: np.ndarray, qd: np.ndarray, tau: np.ndarray) -> np.ndarray:
        _check_bounded(q, qd, tau)
        index = sum(1 for e in events if t >= e[0])
        friction = smooth_coulomb_vector(arms[index].coulomb_friction, eps, qd)
        if stribeck[index] is not None:
            friction = friction + stribeck_vector(stribeck[index], qd, eps)
        return bare[index].forward_dynamics(q, qd, tau - friction + stop_torques(stops, q, qd))

    return qdd


def _no_coulomb(link):
    import dataclasses

    return dataclasses.replace(link, coulomb=(0.0, 0.0), stribeck=(0.0, 0.0))


def _desired_of(
    trajectory: Callable[[float], tuple[ArrayLike, ArrayLike, ArrayLike]] | None, t: float, q0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q_d, qd_d, qdd_d) at t, each checked to be n finite values (a scalar or one value for every joint)."""
    if trajectory is None:
        return q0, np.zeros_like(q0), np.zeros_like(q0)
    values = trajectory(t)
    try:
        q_d, qd_d, qdd_d = values
    except (TypeError, ValueError):
        raise ModelError(
            f"the trajectory must return (q_d, qd_d, qdd_d), got {reprlib.repr(values)} at t = {t}"
        ) from None
    n = q0.shape[0]
    return (
        _returned(q_d, n, f"the trajectory's q_d at t = {t}"),
        _returned(qd_d, n, f"the trajectory's qd_d at t = {t}"),
        _returned(qdd_d, n, f"the trajectory's qdd_d at t = {t}"),
    )


def _returned(value: ArrayLike, n: int, what: str) -> np.ndarray:
    """What a callable of the user's returned, as n finite floats, a scalar or a single value
    standing for every joint (as armdyn's trajectories of scalar parameters give); or a
    ModelError naming ``what``."""
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and value.shape == (n,) and np.isfinite(value).all():
        return value  # the usual case, once per step: no further checks
    try:
        shape = np.shape(value)
    except (TypeError, ValueError):  # a ragged sequence: inputs.state names it
        shape = None
    if shape in ((), (1,)) and not isinstance(value, (str, bytes)):
        value = np.broadcast_to(value, (n,))
    return _one_state(value, n, what)


def _torque(controller, plant, t, q, qd, desired, e_int, eps):
    if controller is None:
        return np.zeros_like(q)
    tau = control.call(controller, (t, q, qd, *desired, e_int), plant, eps)
    return _one_state(tau, q.shape[0], f"the controller's torque at t = {t}", allow_scalar=True)


def _tau_d(
    disturbance: np.ndarray | Callable[[float, np.ndarray, np.ndarray], ArrayLike] | None,
    t: float,
    q: np.ndarray,
    qd: np.ndarray,
) -> np.ndarray:
    """tau_d at (t, q, qd): the run's constant (n,) disturbance, or its law's value checked."""
    if disturbance is None:
        return np.zeros_like(q)
    if callable(disturbance):
        return _one_state(disturbance(t, q, qd), q.shape[0], f"the disturbance at t = {t}")
    return disturbance


def _python_rk4(arms, events, controller, period, trajectory, q0, qd0, disturbance, steps, dt, eps, stops):
    """The same TRESP scheme in Python, for controllers and trajectories of the user's own."""
    n = arms[0].n
    smoothing = _smoothing(arms[0], eps, dt, q0)
    qdd_of = _dynamics(arms, events, smoothing, stops)
    hold = max(1, round(period / dt)) if period else 1
    out = {name: np.empty((steps + 1, n)) for name in ("q", "qd", "qdd", "tau", "q_d")}
    times = np.empty(steps + 1)
    q, qd, tau, e_int = q0.copy(), qd0.copy(), np.zeros(n), np.zeros(n)
    k = 0
    try:
        for k in range(steps + 1):
            t = k * dt
            plant = _plant_at(arms, events, t)
            desired = _desired_of(trajectory, t, q0)
            if k % hold == 0:
                e_int = e_int + (desired[0] - q) * dt * hold
                tau = _torque(controller, plant, t, q, qd, desired, e_int, smoothing)
            applied = tau - _tau_d(disturbance, t, q, qd)
            try:
                k1v = qdd_of(t, q, qd, applied)
            except _DivergedError as diverged:  # the torque itself blew up
                rows, joint = k, diverged.joint
                break
            times[k] = t
            out["q"][k], out["qd"][k], out["qdd"][k], out["tau"][k], out["q_d"][k] = q, qd, k1v, tau, desired[0]
            try:
                k2v = qdd_of(t + dt / 2, q + dt / 2 * qd, qd + dt / 2 * k1v, applied)
                k3v = qdd_of(t + dt / 2, q + dt / 2 * (qd + dt / 2 * k1v), qd + dt / 2 * k2v, applied)
                k4v = qdd_of(t + dt, q + dt * (qd + dt / 2 * k2v), qd + dt * k3v, applied)
                k2q, k3q, k4q = qd + dt / 2 * k1v, qd + dt / 2 * k2v, qd + dt * k3v
                q = q + dt / 6 * (qd + 2 * k2q + 2 * k3q + k4q)
                qd = qd + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
                _check_bounded(q, qd)
            except _DivergedError as diverged:
                rows, joint = k + 1, diverged.joint
                break
        else:
            rows = steps + 1
    except KeyboardInterrupt:
        partial = Result(times[:k], out["q"][:k], out["qd"][:k], out["qdd"][:k], out["tau"][:k],
                         out["q_d"][:k] if trajectory is not None else None, arms[0],
                         {"method": "rk4 (Python)", "dt": dt, "stopped": "interrupted"})  # fmt: skip
        raise RunInterrupted(f"interrupted after {k} of {steps + 1} samples", partial) from None
    q_d = out["q_d"][:rows] if trajectory is not None else None
    result = Result(times[:rows], out["q"][:rows], out["qd"][:rows], out["qdd"][:rows], out["tau"][:rows], q_d,
                    arms[0], {"method": "rk4 (Python)", "dt": dt, "integral": e_int, "coulomb_smoothing": smoothing},
                    lambda: _energies(arms, events, times[:rows], out["q"][:rows], out["qd"][:rows]))  # fmt: skip
    if rows <= steps:
        raise _stopped(arms[0], STOPPED_DIVERGED, joint, rows * dt, q, result)
    return result


class _DivergedError(Exception):
    """A state of the Python loop that blew up (joint ``joint``)."""

    def __init__(self, joint: int) -> None:
        super().__init__(joint)
        self.joint = joint


def _check_bounded(q: np.ndarray, qd: np.ndarray, tau: np.ndarray | None = None) -> None:
    bad = ~((np.abs(q) < LARGEST_STATE) & (np.abs(qd) < LARGEST_STATE))
    if tau is not None:
        bad |= ~(np.abs(tau) < LARGEST_STATE)
    if bad.any():
        raise _DivergedError(int(np.flatnonzero(bad)[0]))


def _adaptive(arms, events, controller, trajectory, q0, qd0, disturbance, steps, dt, method, eps, progress, setup,
              stops):  # fmt: skip
    """solve_ivp on x = [q; qd; e_int]; the controller runs at every function evaluation, compiled
    (``continuous_rate``) when the compiled RK4 loop could run it, else in Python."""
    n = arms[0].n
    smoothing = _smoothing(arms[0], eps, dt, q0)
    qdd_of = _dynamics(arms, events, smoothing, stops)
    times = np.arange(steps + 1) * dt
    buffers = np.empty(3 * n), np.empty(n)  # the rate, the torque

    def python_rate(t: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q, qd, e_int = x[:n], x[n : 2 * n], x[2 * n :]
        desired = _desired_of(trajectory, t, q0)
        tau = _torque(controller, _plant_at(arms, events, t), t, q, qd, desired, e_int, smoothing)
        return np.concatenate([qd, qdd_of(t, q, qd, tau - _tau_d(disturbance, t, q, qd)), desired[0] - q]), tau

    def compiled_rate(t: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = np.ascontiguousarray(x)  # one layout, one compiled continuous_rate (solve_ivp and x[k] give others)
        singular = continuous_rate(t, x, setup[0], setup[1], setup[2], buffers[0], buffers[1])
        if singular >= 0:
            empty = np.empty((0, n))
            raise _stopped(arms[0], STOPPED_SINGULAR, singular, t, x[:n],
                           Result(times[:0], empty, empty, empty, empty, None, arms[0]))  # fmt: skip
        return buffers[0].copy(), buffers[1].copy()

    rate_and_torque = compiled_rate if setup is not None else python_rate
    reported = [0.0]

    def rate(t: float, x: np.ndarray) -> np.ndarray:
        if progress is not None and t >= reported[0] + 0.05 * times[-1]:
            reported[0] = t
            progress(t / times[-1])
        return rate_and_torque(t, x)[0]

    x, evaluations = _solved(rate, times, np.concatenate([q0, qd0, np.zeros(n)]), method)
    q, qd = x[:, :n], x[:, n : 2 * n]
    qdd, tau, q_d = np.empty_like(q), np.empty_like(q), np.empty_like(q)
    for k, t in enumerate(times):
        slope, tau[k] = rate_and_torque(t, x[k])
        qdd[k] = slope[n : 2 * n]
        q_d[k] = _desired_of(trajectory, t, q0)[0]
    if progress is not None:
        progress(1.0)
    route = f"{method} ({'compiled' if setup is not None else 'Python'} right-hand side)"
    return Result(times, q, qd, qdd, tau, q_d if trajectory is not None else None, arms[0],
                  {"method": route, "dt": dt, "evaluations": evaluations},
                  lambda: _energies(arms, events, times, q, qd))  # fmt: skip


def _solved(rate: Callable, times: np.ndarray, x0: np.ndarray, method: str) -> tuple[np.ndarray, int]:
    """The states at ``times`` by solve_ivp's ``method`` (one row each) and its number of rate
    evaluations; the start alone when ``times`` is [0] (dt beyond 2 t_final: no step to take)."""
    from scipy.integrate import solve_ivp

    if len(times) == 1:  # solve_ivp has no empty span
        return x0[None], 0
    solution = solve_ivp(rate, (0.0, times[-1]), x0, method=SOLVERS[method], t_eval=times, rtol=1e-8, atol=1e-10)
    if not solution.success or not np.all(np.isfinite(solution.y)):
        raise ModelError(
            f"the {method} solver failed at t = {solution.t[-1]:.6g} s: {solution.message} (the closed loop may "
            "diverge: lower the gains)"
        )
    return solution.y.T, solution.nfev


@njit(**NUMBA_OPTIONS)
def continuous_rate(
    t: float, x: np.ndarray, plant: tuple, controller: tuple, trajectory: tuple, rate: np.ndarray, tau: np.ndarray
) -> int:
    """d/dt [q; qd; e_int] under continuous control, for the adaptive solvers: the built-in
    controller's compiled law at every evaluation (the same tuples as run_rk4; hold unused).
    Writes the rate and the torque; returns -1, or the joint where M is singular."""
    models, coulombs, switches, disturbance, eps, stops = plant
    kind, model, model_coulomb, gain = controller[0], controller[1], controller[2], controller[3]
    trajectory_kind, params, q0 = trajectory
    n = q0.shape[0]
    p = 0
    while p < switches.shape[0] and t >= switches[p]:
        p += 1
    q, qd, e_int = x[:n], x[n : 2 * n], x[2 * n :]
    goal = np.empty((3, n))
    desired(trajectory_kind, params, t, q0, goal)
    work = np.empty(workspace_size(n))
    u, N, applied, qdd = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    M = np.empty((n, n))
    for i in range(n):
        tau[i] = 0.0
    if kind > 0:
        control_law(kind, model, model_coulomb, eps, work, q, qd, goal, e_int, gain, u, M, N, tau)
    for i in range(n):
        applied[i] = tau[i] - disturbance[i]
    singular = _accelerations(models[p], coulombs[p], eps, stops, work, q, qd, applied, M, N, qdd)
    for i in range(n):
        rate[i] = qd[i]
        rate[n + i] = qdd[i]
        rate[2 * n + i] = goal[0, i] - q[i]
    return singular


# ----- many runs at once ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Plants:
    """Variants of one arm, packed for the compiled loop: one model row per variant (``plant_variants``).

    Attributes
    ----------
    arm : Robot
        The nominal arm they vary.
    packed : numpy.ndarray
        (V, L): each variant's packed model, its Coulomb and Stribeck friction taken out.
    coulomb : numpy.ndarray
        (V, n, 4): each variant's Coulomb friction (Tc+, Tc-) at the joints and Stribeck friction (Fs, vs).
    """

    arm: Robot
    packed: np.ndarray
    coulomb: np.ndarray

    def __len__(self) -> int:
        return self.packed.shape[0]


def _per_variant(value: object, name: str, count: int, tail: tuple[int, ...]) -> np.ndarray:
    """``value`` as (count, *tail): one value for every variant or one per variant."""
    array = inputs.numbers(value, name)
    try:
        return np.broadcast_to(array if array.ndim > len(tail) else array[None], (count, *tail)).astype(float)
    except ValueError:
        raise ModelError(f"{name} must have the shape {tail or '()'} or ({count}, {', '.join(map(str, tail))}), "
                         f"got {array.shape}") from None  # fmt: skip


def plant_variants(
    arm: Robot,
    count: int,
    payload_mass: object = 0.0,
    payload_com: object = (0.0, 0.0, 0.0),
    payload_inertia: object = (0.0, 0.0, 0.0),
    mass_scale: object = 1.0,
    friction_scale: object = 1.0,
) -> Plants:
    """``count`` variants of the arm, each with its own payload, link masses and friction, packed at once.

    Each argument is one value for every variant or one per variant. The mass properties enter the
    packed model linearly (mass, first moment m c, inertia about the body origin), so a variant is
    the nominal row with its links scaled and the payload added by the parallel-axis theorem, in
    one array operation: no Robot is built per variant. Variant k equals
    ``arm.with_payload(...)`` with the links' masses, first moments and inertias times
    ``mass_scale[k]`` and the friction forces (viscous B, Coulomb Tc, Stribeck Fs, the sigmoid's A)
    times ``friction_scale[k]``.

    Parameters
    ----------
    arm : Robot
        The nominal arm, numeric.
    count : int
        The number of variants, >= 1.
    payload_mass : float or array_like, optional
        kg, >= 0: (count,) or one value.
    payload_com : array_like, optional
        The payload's centre of mass in the tool link's frame, m: (3,) or (count, 3).
    payload_inertia : array_like, optional
        Its principal moments about its centre of mass in the tool link's axes, kg m^2:
        (3,) or (count, 3), each >= 0 and obeying the triangle inequality.
    mass_scale : float or array_like, optional
        Factors > 0 on the links' mass properties: one, (n,) per joint, (count, 1) per variant, or
        (count, n).
    friction_scale : float or array_like, optional
        Factors >= 0 on the joints' friction forces (B, Tc, Fs, A), shaped as ``mass_scale``.

    Returns
    -------
    Plants
        The packed variants.

    Raises
    ------
    armdyn.ModelError
        When count is not a positive integer, or a value has the wrong shape or breaks its rule
        (negative mass, a scale <= 0, moments breaking the triangle inequality).
    armdyn.ArgumentError
        When the arm is not a numeric Robot.
    """
    inputs.arm_argument(arm, Robot, "arm", numeric=True, why=" (variants are packed models)")
    count = inputs.integer(count, "count", 1)
    n = arm.n
    assert arm.packed is not None, "arm_argument refuses symbolic arms"
    per_variant = 8.0 * (3 * arm.packed.size + 7 + 4 * n)  # the packed rows, their Coulomb tables, the arguments
    memory.affordable(min(count, 2**63) * per_variant, f"count = {_count(count)} variants")
    mass = _per_variant(payload_mass, "payload_mass", count, ())
    com = _per_variant(payload_com, "payload_com", count, (3,))
    moments = _per_variant(payload_inertia, "payload_inertia", count, (3,))
    scale = _per_variant(mass_scale, "mass_scale", count, (n,))
    friction = _per_variant(friction_scale, "friction_scale", count, (n,))
    if np.any(mass < 0) or np.any(moments < 0):
        raise ModelError("payload_mass and payload_inertia must be >= 0")
    ordered = np.sort(moments, axis=1)
    if np.any(ordered[:, 0] + ordered[:, 1] < ordered[:, 2] * (1 - 1e-12)):
        raise ModelError("payload_inertia's moments must obey the triangle inequality (I_a + I_b >= I_c)")
    if np.any(scale <= 0) or np.any(friction < 0):
        raise ModelError("mass_scale must be > 0 and friction_scale >= 0 (per variant and joint)")
    packed, coulomb = vary_packed(nominal(arm), mass, com, moments, scale, friction)
    return Plants(arm, packed, coulomb)


@dataclass(frozen=True)
class Nominal:
    """What varying an arm needs of it, as arrays only (what a study sends to its workers).

    Attributes
    ----------
    packed : numpy.ndarray
        (L,): the packed model, its Coulomb and Stribeck friction taken out.
    coulomb : numpy.ndarray
        (n, 4): Coulomb friction at the joints (Tc+, Tc-) and Stribeck friction (Fs, vs).
    tool : int
        The tool link's index.
    rotation, offset : numpy.ndarray
        The tool link's frame in its body frame: (3, 3) and (3,).
    """

    packed: np.ndarray
    coulomb: np.ndarray
    tool: int
    rotation: np.ndarray
    offset: np.ndarray


def nominal(arm: Robot) -> Nominal:
    """The arrays of ``arm`` that ``vary_packed`` and a study's workers use (no Robot object).

    Parameters
    ----------
    arm : Robot
        A numeric arm.

    Returns
    -------
    Nominal
        Its packed model and tool frame.

    Raises
    ------
    armdyn.ArgumentError
        When the arm is not a numeric Robot.
    """
    inputs.arm_argument(arm, Robot, "arm", numeric=True, why=" (a packed model)")
    assert arm.packed is not None, "arm_argument refused a symbolic arm"
    base, coulomb = packed_plants([arm])
    tool = int(arm.packed[TOOL_LINK])
    start = HEADER + STRIDE * tool
    rotation = arm.packed[start + LINK_ROTATION : start + LINK_ROTATION + 9].reshape(3, 3).copy()
    offset = arm.packed[start + LINK_POSITION : start + LINK_POSITION + 3].copy()
    return Nominal(base[0], coulomb[0], tool, rotation, offset)


def vary_packed(
    arm: Nominal, mass: np.ndarray, com: np.ndarray, moments: np.ndarray, scale: np.ndarray, friction: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(packed (V, L), Coulomb and Stribeck (V, n, 4)) of V variants: links' mass properties times ``scale``
    (V, n), friction forces (B, Tc, Fs, the sigmoid's A) times ``friction`` (V, n), the payload (mass (V,),
    centre (V, 3) and principal moments (V, 3) in the tool link's frame) added by the parallel-axis theorem.
    The arguments are checked by ``plant_variants``."""
    count, n = scale.shape
    packed = np.repeat(arm.packed[None], count, axis=0)
    for j in range(n):
        start = HEADER + STRIDE * j
        packed[:, start + MASS : start + INERTIA + 6] *= scale[:, j, None]
        packed[:, start + VISCOUS] *= friction[:, j]
        if packed[0, start + SIGMOID_AMPLITUDE] != 0.0:
            packed[:, start + SIGMOID_AMPLITUDE] *= friction[:, j]
            packed[:, start + SIGMOID_REST] *= friction[:, j]
    start = HEADER + STRIDE * arm.tool
    centre = com @ arm.rotation.T + arm.offset  # the payload's centre in the body frame
    inertia = np.einsum("ij,kj,jl->kil", arm.rotation, moments, arm.rotation.T)  # R diag(I) R^T per variant
    inertia += mass[:, None, None] * (np.sum(centre**2, axis=1)[:, None, None] * np.eye(3)
                                      - centre[:, :, None] * centre[:, None, :])  # fmt: skip
    packed[:, start + MASS] += mass
    packed[:, start + FIRST_MOMENT : start + FIRST_MOMENT + 3] += mass[:, None] * centre
    upper = inertia[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]  # Ixx Ixy Ixz Iyy Iyz Izz
    packed[:, start + INERTIA : start + INERTIA + 6] += upper
    table = np.repeat(arm.coulomb[None], count, axis=0)
    table[:, :, :3] *= friction[:, :, None]  # Tc+, Tc-, Fs; not the Stribeck velocity vs
    return packed, table


SUMMARY_NAMES = ("final_error", "max_error_after", "rms_error", "max_tau", "final_q")
"""The per-run, per-joint summaries many runs keep (simulate with runs=) (rows of its summary array)."""
FINAL_ERROR, MAX_ERROR_AFTER, RMS_ERROR, MAX_TAU, FINAL_Q = range(5)


@njit(**NUMBA_OPTIONS)
def _auto_smoothing(plant: np.ndarray, coulomb: np.ndarray, q: np.ndarray, qd: np.ndarray, dt: float) -> np.ndarray:
    """simulate's coulomb_smoothing="auto" (see _smoothing) for one packed plant at its start."""
    n = q.shape[0]
    M, N = np.empty((n, n)), np.empty(n)
    mass_matrix_and_bias(plant, np.empty(workspace_size(n)), q, qd, M, N)
    eps = np.empty(n)
    for i in range(n):
        largest = max(abs(coulomb[i, 0]), abs(coulomb[i, 1])) + coulomb[i, 2]
        eps[i] = max(1e-3, largest * dt / M[i, i] if M[i, i] > 0 else 0.0)
    return eps


@njit(parallel=True, **NUMBA_OPTIONS)
def run_many(
    plants: tuple, models: tuple, control: tuple, path: tuple, starts: tuple, timing: tuple, outputs: tuple
) -> None:
    """Runs r = 0..N-1 of run_rk4 in parallel (prange over runs), each in chunks of rows.

    plants = (packed (P, L), Coulomb and Stribeck (P, n, 4), plant of each run (N,), disturbance (N, n)); each run's
    Coulomb smoothing is simulate's "auto" on its own plant and start (_auto_smoothing).
    models = (packed (Q, L), Coulomb and Stribeck (Q, n, 4), model of each run (N,), shares plant (N,)).
    control = (kind, gains (N, 4, n), hold). path = (kind, params (N, 4, n)). starts = (q0 (N, n),
    qd0 (N, n)). timing = (dt, rows, chunk, keep every, first row of the summaries' "after").
    outputs = (summaries (N, 5, n), outcome (N, 3), kept q, qd, tau, q_d (N, K, n)): each run writes
    only its own rows, so the result does not depend on the thread count.
    """
    plant_rows, plant_coulombs, plant_of, disturbances = plants
    model_rows, model_coulombs, model_of, shares = models
    kind, gains, hold = control
    path_kind, params = path
    q0s, qd0s = starts
    dt, rows, chunk, every, after = timing
    summaries, outcomes, kept_q, kept_qd, kept_tau, kept_qd_d = outputs
    n = q0s.shape[1]
    free = np.zeros((n, 4))  # many runs have no joint stops: limits at infinity
    free[:, 0], free[:, 1] = -np.inf, np.inf
    for r in prange(q0s.shape[0]):
        p, m = plant_of[r], model_of[r]
        eps = _auto_smoothing(plant_rows[p], plant_coulombs[p], q0s[r], qd0s[r], dt)
        plant = (plant_rows[p : p + 1], plant_coulombs[p : p + 1], np.empty(0), disturbances[r], eps, free)
        # no literal constants in run_rk4's arguments: the types are then simulate's, and one compiled run_rk4
        # serves both (a literal 0 or False would compile it a second time)
        no_observer, first_step = n < 0, np.int64(0)
        watch = (np.zeros((0, ROW_SIZE)), (no_observer, plant_rows[p], plant_coulombs[p], eps, eps, np.zeros((4, n))),
                 (np.empty((0, n)), np.empty((0, n))))  # fmt: skip
        law = (kind, model_rows[m], model_coulombs[m], gains[r], hold, shares[r])
        state = (np.concatenate((q0s[r], qd0s[r])), np.zeros(n), np.zeros(n), outcomes[r])
        record = (np.empty(chunk), np.empty((chunk, n)), np.empty((chunk, n)), np.empty((chunk, n)),
                  np.empty((chunk, n)), np.empty((chunk, n)))  # fmt: skip
        summary = summaries[r]
        summary[:, :] = 0.0
        for first in range(0, rows, chunk):
            count = min(chunk, rows - first)
            run_rk4(
                plant, law, (path_kind, params[r], q0s[r]), (first * dt, dt, first_step, count), state, record, watch
            )
            done = count if outcomes[r, 0] < 0 else int(outcomes[r, 0])
            for k in range(done):
                row = first + k
                _keep_row(summary, record[5][k], record[1][k], record[4][k], row, after)
                if every > 0 and row % every == 0:
                    slot = row // every
                    kept_q[r, slot], kept_qd[r, slot] = record[1][k], record[2][k]
                    kept_tau[r, slot], kept_qd_d[r, slot] = record[4][k], record[5][k]
            if outcomes[r, 0] >= 0:
                outcomes[r, 0] += first
                break
        for i in range(n):
            summary[RMS_ERROR, i] = math.sqrt(summary[RMS_ERROR, i] / rows)


BLOCKED_RUNS = 2 * BLOCK
"""Runs from which simulate(runs=N) advances them together, BLOCK at a time (run_blocks), when their plants are
one arm but for its masses, inertias and friction (a payload, plant_variants)."""


def blocks_apply(packed: np.ndarray, plant_of: np.ndarray) -> bool:
    """Whether run_blocks takes the runs: BLOCKED_RUNS or more, their plants (rows of ``packed``) equal but in
    the per-state fields of the block pass (aba_blocks.LANE_FIELDS: masses, first moments, inertias, viscous
    friction; the Coulomb and Stribeck laws are the loop's, per run)."""
    if plant_of.shape[0] < BLOCKED_RUNS:
        return False
    used = packed[np.unique(plant_of)]
    shared = np.ones(packed.shape[1], dtype=bool)
    for j in range(int(packed[0, N_JOINTS])):
        shared[HEADER + STRIDE * j + np.array(LANE_FIELDS)] = False
    return bool(np.all(used[:, shared] == used[:1, shared]))


@njit(parallel=True, **NUMBA_OPTIONS)
def run_blocks(
    plants: tuple, models: tuple, control: tuple, path: tuple, starts: tuple, timing: tuple, outputs: tuple
) -> None:
    """run_many's runs advanced together BLOCK runs at a time: each RK4 stage is one articulated-body pass over
    the block's states (aba_blocks.aba_block, the state index innermost so that the arithmetic runs in SIMD
    lanes), blocks in parallel. The runs' plants are one arm but for the per-state fields of the pass
    (blocks_apply); each run's plant, law, trajectory, start, disturbance and Coulomb law are its own, as in
    run_many; the same arguments and outputs.

    The plant's accelerations are the articulated-body algorithm's (Featherstone 2008, 7.3) with a polynomial
    sine and cosine, where run_many solves M qdd = tau - N by Cholesky: the two agree to rounding, and the runs
    to about 1e-12 of their values (a run's rounding grows as its dynamics does)."""
    runs = starts[0].shape[0]
    blocks = (runs + BLOCK - 1) // BLOCK
    for block in prange(blocks):
        first = block * BLOCK
        _run_block(plants, models, control, path, starts, timing, outputs, first, min(BLOCK, runs - first))


@njit(**NUMBA_OPTIONS)
def _run_block(
    plants: tuple, models: tuple, control: tuple, path: tuple, starts: tuple, timing: tuple, outputs: tuple,
    first: int, size: int,
) -> None:  # fmt: skip
    """Runs first .. first + size - 1 of run_blocks, every step: the laws run by run (once per sample), then
    the four RK4 stages each one block pass; records as run_many keeps them."""
    plant_rows, plant_coulombs, plant_of, disturbances = plants
    model_rows, model_coulombs, model_of, _ = models
    kind, gains, hold = control
    path_kind, params = path
    q0s, qd0s = starts
    dt, rows, chunk, every, after = timing
    summaries, outcomes, kept_q, kept_qd, kept_tau, kept_qd_d = outputs
    n = q0s.shape[1]
    plant = plant_rows[plant_of[first]]  # the kinematics, shared; each run's masses and friction: lane_parameters
    x = np.empty((n + 1) * ABA_BLOCK_ROWS * BLOCK)
    base_slot(plant, block_slot(x, n))
    coulombs = np.empty((BLOCK, n, 4))
    for s in range(BLOCK):  # a last block's absent runs repeat its first (aba_block reads its states for them)
        p = plant_of[first + (s if s < size else 0)]
        lane_parameters(plant_rows[p], x, s)
        coulombs[s] = plant_coulombs[p]
    lanes = np.zeros((11, BLOCK, n))  # rows of absent runs (a last, partial block) stay zero, never read
    q, qd, qs, vs, acc, sum_q, sum_v = lanes[0], lanes[1], lanes[2], lanes[3], lanes[4], lanes[5], lanes[6]
    tau_held, applied, stage_tau, e_int = lanes[7], lanes[8], lanes[9], lanes[10]
    eps, goals = np.empty((BLOCK, n)), np.empty((BLOCK, 3, n))
    singular = np.full(BLOCK, -1)
    work, u, M_, Nv = np.empty(workspace_size(n)), np.empty(n), np.empty((n, n)), np.empty(n)
    shared_model = model_of[first]
    for s in range(size):
        if model_of[first + s] != shared_model:
            shared_model = -1
    blocked_law = shared_model >= 0 and kind in (COMPUTED_TORQUE, PD_GRAVITY)
    law_lanes, law_store, law_x = np.zeros((2, BLOCK, n)), np.empty((n, 30, BLOCK)), np.zeros(45 * BLOCK)
    for s in range(size):
        r = first + s
        q[s], qd[s] = q0s[r], qd0s[r]
        eps[s] = _auto_smoothing(plant_rows[plant_of[r]], coulombs[s], q0s[r], qd0s[r], dt)
        summaries[r, :, :] = 0.0
    for k in range(rows):
        t = (k // chunk * chunk) * dt + (k % chunk) * dt  # run_many's time: its chunk's start, then the step
        running = 0
        for s in range(size):
            r = first + s
            if outcomes[r, 0] >= 0:
                continue
            running += 1
            desired(path_kind, params[r], t, q0s[r], goals[s])
            if kind > 0 and k % hold == 0:
                for i in range(n):
                    e_int[s, i] += (goals[s, 0, i] - q[s, i]) * dt * hold
                if not blocked_law:
                    m = model_of[r]
                    control_law(kind, model_rows[m], model_coulombs[m], eps[s], work, q[s], qd[s], goals[s],
                                e_int[s], gains[r], u, M_, Nv, tau_held[s])  # fmt: skip
        if running == 0:
            break
        if blocked_law and k % hold == 0:
            _block_law(kind, model_rows[shared_model], model_coulombs[shared_model], eps, gains[first : first + size],
                       q, qd, goals, e_int, law_lanes, law_store, law_x, tau_held, size)  # fmt: skip
        for s in range(size):
            for i in range(n):
                applied[s, i] = tau_held[s, i] - disturbances[first + s, i]
        _block_rates(plant, coulombs, eps, x, q, qd, applied, stage_tau, acc, singular, size)
        for s in range(size):
            r = first + s
            if outcomes[r, 0] >= 0:
                continue
            if singular[s] >= 0:
                outcomes[r, 0], outcomes[r, 1], outcomes[r, 2] = k, STOPPED_SINGULAR, singular[s]
                continue
            _keep_row(summaries[r], goals[s, 0], q[s], tau_held[s], k, after)
            if every > 0 and k % every == 0:
                slot = k // every
                kept_q[r, slot], kept_qd[r, slot], kept_tau[r, slot], kept_qd_d[r, slot] = q[s], qd[s], \
                    tau_held[s], goals[s, 0]  # fmt: skip
        stopped = singular.copy()
        for c in range(3):  # stages 2 to 4: at q + c h qd_stage, qd + c h qdd_stage
            scale = 1.0 if c == 2 else 0.5
            for s in range(size):
                for i in range(n):
                    sum_q[s, i] = qd[s, i] if c == 0 else sum_q[s, i] + 2.0 * vs[s, i]
                    sum_v[s, i] = acc[s, i] if c == 0 else sum_v[s, i] + 2.0 * acc[s, i]
                    step_q = qd[s, i] if c == 0 else vs[s, i]
                    qs[s, i] = q[s, i] + scale * dt * step_q
                    vs[s, i] = qd[s, i] + scale * dt * acc[s, i]
            _block_rates(plant, coulombs, eps, x, qs, vs, applied, stage_tau, acc, singular, size)
            for s in range(size):
                stopped[s] = max(stopped[s], singular[s])
        for s in range(size):
            r = first + s
            if outcomes[r, 0] >= 0:
                continue
            for i in range(n):
                q[s, i] += dt / 6.0 * (sum_q[s, i] + vs[s, i])
                qd[s, i] += dt / 6.0 * (sum_v[s, i] + acc[s, i])
            for i in range(n):  # a state that blew up explains a singular stage too
                if not (abs(q[s, i]) < LARGEST_STATE and abs(qd[s, i]) < np.inf):  # NaN fails both
                    outcomes[r, 0], outcomes[r, 1], outcomes[r, 2] = k + 1, STOPPED_DIVERGED, i
                    break
            if outcomes[r, 0] < 0 and stopped[s] >= 0:
                outcomes[r, 0], outcomes[r, 1], outcomes[r, 2] = k + 1, STOPPED_SINGULAR, stopped[s]
    for s in range(size):
        for i in range(n):
            summaries[first + s, RMS_ERROR, i] = math.sqrt(summaries[first + s, RMS_ERROR, i] / rows)


@njit(**NUMBA_OPTIONS)
def _block_law(
    kind: int, model: np.ndarray, model_coulomb: np.ndarray, eps: np.ndarray, gains: np.ndarray, q: np.ndarray,
    qd: np.ndarray, goals: np.ndarray, e_int: np.ndarray, lanes: np.ndarray, store: np.ndarray, x: np.ndarray,
    tau: np.ndarray, size: int,
) -> None:  # fmt: skip
    """The computed-torque or PD-plus-gravity law (control.joint) of a block's runs on one model, by one RNEA
    pass over their states (rnea_blocks.rnea_block): M u + N = RNEA(q, qd, u), the model's Coulomb law
    compensated with each run's smoothing, or G(q) = RNEA(q, 0, 0) without friction; then each run's
    saturation. ``lanes`` (2, BLOCK, n) holds u and the RNEA result."""
    u, law = lanes[0], lanes[1]
    n = q.shape[1]
    if kind == COMPUTED_TORQUE:
        for s in range(size):
            for i in range(n):
                u[s, i] = (
                    goals[s, 2, i] + gains[s, KV, i] * (goals[s, 1, i] - qd[s, i])
                    + gains[s, KP, i] * (goals[s, 0, i] - q[s, i]) + gains[s, KI, i] * e_int[s, i]
                )  # fmt: skip
        rnea_block(model, q, qd, u, INVERSE_DYNAMICS, 0, size, store, x, law)
        for s in range(size):
            for i in range(n):
                law[s, i] += smooth_coulomb(model_coulomb, eps[s], i, qd[s, i])
    else:
        rnea_block(model, q, qd, qd, GRAVITY_ONLY, 0, size, store, x, law)
        for s in range(size):
            for i in range(n):
                law[s, i] += gains[s, KP, i] * (goals[s, 0, i] - q[s, i]) + gains[s, KV, i] * (
                    goals[s, 1, i] - qd[s, i]
                )
    for s in range(size):
        for i in range(n):
            tau[s, i] = min(max(law[s, i], -gains[s, LIMIT, i]), gains[s, LIMIT, i])


@njit(**NUMBA_OPTIONS)  # called, not inlined: the loop's two call sites share one compiled pass
def _block_rates(
    plant: np.ndarray, coulombs: np.ndarray, eps: np.ndarray, x: np.ndarray, q: np.ndarray, qd: np.ndarray,
    applied: np.ndarray, stage_tau: np.ndarray, qdd: np.ndarray, singular: np.ndarray, size: int,
) -> None:  # fmt: skip
    """qdd = FD(q, qd, tau - Fd_smooth(qd)) for the block's runs: each run's smoothed Coulomb law (``coulombs``
    (BLOCK, n, 4)) in the torque, the plants' own Coulomb and Stribeck terms being taken out (packed_plants); no
    joint stops (run_many has none)."""
    for s in range(size):
        for i in range(q.shape[1]):
            stage_tau[s, i] = applied[s, i] - smooth_coulomb(coulombs[s], eps[s], i, qd[s, i])
    aba_block(plant, x, q, qd, stage_tau, 0, size, qdd, singular)


@njit(inline="always", **NUMBA_OPTIONS)
def _keep_row(summary: np.ndarray, q_d: np.ndarray, q: np.ndarray, tau: np.ndarray, row: int, after: int) -> None:
    """A recorded row's share of run_many's summaries (RMS error summed here, its root taken at the end)."""
    for i in range(q.shape[0]):
        error = q_d[i] - q[i]
        summary[RMS_ERROR, i] += error * error
        summary[MAX_TAU, i] = max(summary[MAX_TAU, i], abs(tau[i]))
        if row >= after:
            summary[MAX_ERROR_AFTER, i] = max(summary[MAX_ERROR_AFTER, i], abs(error))
        summary[FINAL_ERROR, i] = error
        summary[FINAL_Q, i] = q[i]


@dataclass
class Ensemble(RunSummaries):
    """What ``simulate(..., runs=N)`` kept of N runs: per-run summaries, and samples when asked.

    Attributes
    ----------
    arm : Robot
        The nominal arm.
    t : numpy.ndarray
        The times of the kept samples, (K,) (empty with keep="summary").
    summaries : numpy.ndarray
        (N, 5, n): per run and joint the final error, the largest |error| from ``after`` on, the
        RMS error, the largest |tau| and the final q (rows named by SUMMARY_NAMES).
    outcome : numpy.ndarray
        (N, 3) integers: (-1, 0, -1) for a run that finished, else (row it stopped at, 1 singular
        M or 2 diverged, joint).
    samples : dict
        "q", "qd", "tau", "q_d": (N, K, n) each, when kept.
    info : dict
        dt, t_final, after, the controller and the trajectory.
    """

    arm: Robot
    t: np.ndarray
    summaries: np.ndarray
    outcome: np.ndarray
    samples: dict
    info: dict

    def to_xarray(self) -> object:
        """An xarray Dataset with dimensions run, joint and (when samples were kept) time.

        Returns
        -------
        xarray.Dataset
            The summaries as variables (run, joint), the samples as (run, time, joint), the
            outcome as (run,) variables; ``.to_dataframe()`` gives pandas.

        Raises
        ------
        None
            It only arranges the arrays.
        """
        import xarray

        variables: dict[str, tuple[tuple[str, ...], np.ndarray]] = {
            name: (("run", "joint"), self.summaries[:, k]) for k, name in enumerate(SUMMARY_NAMES)
        }
        variables |= {name: (("run", "time", "joint"), values) for name, values in self.samples.items()}
        variables |= {"stopped_at": (("run",), self.outcome[:, 0]), "reason": (("run",), self.outcome[:, 1])}
        coordinates = {"run": np.arange(self.runs), "joint": self.arm.joint_names}
        if self.samples:
            coordinates["time"] = self.t
        return xarray.Dataset(variables, coords=coordinates, attrs={k: str(v) for k, v in self.info.items()})

    def plot(self, path: str | Path | None = None, quantity: str = "max_error_after") -> object:
        """The error envelope over time (median and 5-95 % and 25-75 % bands of |q_d - q| per joint,
        when samples were kept) and histograms of a summary quantity per joint.

        Parameters
        ----------
        path : str or Path, optional
            Write the figure there (PNG); default: return it only.
        quantity : str, optional
            The summary for the histograms (one of SUMMARY_NAMES), default "max_error_after".

        Returns
        -------
        matplotlib.figure.Figure
            The figure.

        Raises
        ------
        armdyn.ModelError
            When ``quantity`` is not a summary's name.
        """
        from armdyn.plotting import plot_ensemble

        if quantity not in SUMMARY_NAMES:
            raise ModelError(f"quantity must be one of {', '.join(SUMMARY_NAMES)}, got {quantity!r}")
        return plot_ensemble(self, path, quantity, SUMMARY_NAMES.index(quantity))


def launch_many(
    plants: tuple, models: tuple, law: tuple, path: tuple, starts: tuple, timing: tuple, threads: int | None = None
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """run_many on arrays only (its tuples; timing = (dt, rows, keep every, first row of "after")), on
    ``threads`` Numba threads: (summaries (N, 5, n), outcome (N, 3), kept q, qd, tau, q_d)."""
    import numba

    dt, rows, every, after = timing
    runs, n = starts[0].shape
    kept = 0 if every == 0 else (rows - 1) // every + 1
    summaries, outcome = np.empty((runs, 5, n)), np.tile(np.array([-1, 0, -1]), (runs, 1))
    samples = [np.zeros((runs, kept, n)) for _ in range(4)]
    chunk = law[2] * max(1, 256 // law[2])  # whole sample periods of a Digital law
    previous = numba.get_num_threads()
    if threads is not None:
        # numba.config sets its options when imported, unseen by a type checker
        largest = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
        numba.set_num_threads(inputs.integer(threads, "threads", 1, largest))
    try:
        plants, models, law, path, starts = without_read_only((plants, models, law, path, starts))
        runner = run_blocks if blocks_apply(plants[0], plants[2]) else run_many
        runner(plants, models, law, path, starts, (dt, rows, chunk, every, after), (summaries, outcome, *samples))
    finally:
        numba.set_num_threads(previous)
    return summaries, outcome, samples


def _runs_of(value: object, name: str, runs: int, n: int, default: float = 0.0) -> np.ndarray:
    """A per-run (runs, n) array from None (``default``), one state (n,) or (runs, n)."""
    if value is None:
        return np.full((runs, n), default)
    array = inputs.numbers(value, name)
    if array.shape in ((n,), ()) or array.shape == (runs, n):
        return np.ascontiguousarray(np.broadcast_to(array, (runs, n)), dtype=float)
    raise ModelError(f"{name} must be one value, {n} values or ({runs}, {n}) (one row per run), got {array.shape}")


def _variants(value: object, arm: Robot, runs: int, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(packed (V, L), Coulomb and Stribeck (V, n, 4), variant of each run) from None (the arm), a Robot or Plants."""
    if value is None:
        value = arm
    if isinstance(value, Robot):
        if value.n != arm.n or value.is_symbolic:
            raise ModelError(f"{name} must be a numeric arm with the plant's {arm.n} joints")
        packed, coulomb = packed_plants([value])
        return packed, coulomb, np.zeros(runs, dtype=np.int64)
    if isinstance(value, Plants):
        assert arm.packed is not None, "many runs refuse a symbolic arm"
        if value.arm.n != arm.n or value.packed.shape[1] != arm.packed.shape[0]:
            raise ModelError(f"{name} must vary an arm with the plant's {arm.n} joints")
        if len(value) not in (1, runs):
            raise ModelError(f"{name} holds {len(value)} variants: give 1 or one per run ({runs})")
        return value.packed, value.coulomb, np.arange(runs, dtype=np.int64) % len(value)
    raise ArgumentError(f"{name} must be None, a Robot or armdyn.simulation.Plants (plant_variants), got "
                        f"{type(value).__name__}")  # fmt: skip


def _paths(trajectory: object, runs: int, n: int) -> tuple[int, np.ndarray]:
    """The compiled kind and (runs, 4, n) parameters of one trajectory or one per run (of one kind)."""
    paths = list(trajectory) if isinstance(trajectory, (list, tuple)) else [trajectory]
    if isinstance(trajectory, (list, tuple)) and len(paths) != runs:
        raise ModelError(f"give one trajectory or one per run ({runs}), got {len(paths)}")
    packed = [trajectories.packed(path, n) for path in paths]
    specs = [spec for spec in packed if spec is not None]
    if len(specs) != len(packed):
        raise ArgumentError("many runs run None, armdyn.trajectories.Sinusoid or Quintic trajectories")
    if len({spec[0] for spec in specs}) != 1:
        raise ModelError("the runs' trajectories must be of one kind (all Sinusoid, or all Quintic)")
    params = np.stack([spec[1] for spec in specs])
    return specs[0][0], np.ascontiguousarray(np.broadcast_to(params, (runs, *params.shape[1:])))


def _count(count: int) -> str:
    """A count for a message: 1,000 or, past 10^15, its order of magnitude (about 10^400)."""
    return f"{count:,}" if count <= 10**15 else f"about 10^{len(str(count)) - 1}"


def _rows(value: object, ndim: int = 2) -> int | None:
    """The length of a per-run argument's first axis (one row per run) when it has ``ndim`` axes, else None."""
    try:
        shape = np.asarray(value).shape  # as np.shape(value)
    except (TypeError, ValueError):  # a ragged sequence: the argument's own check names it
        return None
    return shape[0] if len(shape) == ndim else None


def _simulate_runs(
    arm: Robot,
    controller: object,
    trajectory: object,
    t_final: float,
    dt: float,
    runs: int | None,
    q0: object,
    qd0: object,
    plants: Plants | Robot | None,
    models: Plants | Robot | None,
    gains: object,
    disturbance: object,
    keep: str | int | None,
    after: float | None,
    threads: int | None,
) -> Ensemble:
    """N closed-loop runs in one compiled call, parallel over runs (Chapter 4's TRESP, as one run).

    Each run integrates the robot equation under the controller by the same fixed-step RK4 as one run
    (run k equals that single run to rounding), with its own start, plant, controller model, gains,
    trajectory and constant disturbance. Plant and model variants are packed arrays (``plant_variants``),
    never Robot objects per run. What is kept is chosen: ``keep="summary"`` keeps per run and joint only
    the final error, the largest |error| from ``after`` seconds on, the RMS error, the largest |tau| and
    the final q (40 n bytes a run: a million runs of a six-joint arm in 240 MB); an integer k also keeps
    q, qd, tau and q_d every k-th step; ``"full"`` every step. The arguments are ``simulate``'s.
    """
    keep = "summary" if keep is None else keep
    inputs.arm_argument(arm, Robot, "arm", numeric=True, why=" (many runs run compiled code)")
    n = arm.n
    t_final, dt = checked_times(t_final, dt)
    after = summary_window(after, t_final)
    steps = step_count(t_final, dt, n, False)
    rows = steps + 1
    every = 0 if keep == "summary" else 1 if keep == "full" else keep
    if isinstance(every, str) or not isinstance(every, (int, np.integer)) or isinstance(every, bool) or every < 0:
        raise ModelError(f"keep must be 'summary', 'full' or a whole number of steps >= 1, got {keep!r}")
    if keep == 0:
        raise ModelError("keep must be 'summary', 'full' or a whole number of steps >= 1, got 0 (to keep only the "
                         "summaries, give keep='summary')")  # fmt: skip
    if every > steps:
        raise ModelError(f"keep must be 'summary', 'full' or a whole number of steps from 1 to the run's {steps} "
                         f"steps, got {keep!r}")  # fmt: skip
    kept = 0 if every == 0 else (rows - 1) // every + 1
    spec, period, law = unwrapped_law(controller, n)
    if spec is None:
        raise ArgumentError("many runs run armdyn.control's laws (ComputedTorque, PDGravity, PID, in Digital or "
                         f"Saturated) or None (no torque), got {type(controller).__name__}")  # fmt: skip
    counts = {name: len(v) for name, v in (("plants", plants), ("models", models)) if isinstance(v, Plants)}
    named = (("q0", q0), ("qd0", qd0), ("disturbance", disturbance))
    counts |= {name: count for name, v in named if (count := _rows(v)) is not None}
    counts |= {"trajectory": len(trajectory)} if isinstance(trajectory, (list, tuple)) else {}
    counts |= {"gains": count} if (count := _rows(gains, 3)) is not None else {}
    counts = {name: count for name, count in counts.items() if count != 1}
    rows_given = ", ".join(f"{name} has {count}" for name, count in counts.items())
    if runs is None:
        if len(set(counts.values())) > 1:
            raise ModelError(f"the per-run arguments disagree on the number of runs: {rows_given} rows")
        runs = next(iter(counts.values()), 1)
    runs = inputs.integer(runs, "runs", 1)
    if set(counts.values()) - {runs}:
        raise ModelError(f"runs = {runs}, but {rows_given} rows (give one row or one per run)")
    per_run = 8 * ((17 + 4 * kept) * n + 6)  # starts, disturbance, gains, paths, summaries, outcome, kept samples
    memory.affordable(min(runs, 2**63) * per_run,
                      f"{_count(runs)} runs (their starts, gains, summaries and samples kept)")  # fmt: skip
    plant_rows, plant_coulombs, plant_of = _variants(plants, arm, runs, "plants")
    shares = np.full(runs, spec.model is None and models is None)
    model_rows, model_coulombs, model_of = _variants(models if models is not None else spec.model, arm, runs,
                                                     "models")  # fmt: skip
    if spec.model is None and models is None:
        model_rows, model_coulombs, model_of = plant_rows, plant_coulombs, plant_of
    table, hold = law_table(spec, period, dt, n)
    table = np.ascontiguousarray(np.broadcast_to(table, (runs, 4, n)))
    if gains is not None:
        given = inputs.numbers(gains, "gains")
        if given.shape not in ((3, n), (runs, 3, n)) or np.any(given < 0):
            raise ModelError(f"gains must be (3, {n}) or ({runs}, 3, {n}) values >= 0 (kp, kv, ki), got {given.shape}")
        table[:, :3] = given
    path_kind, params = _paths(trajectory, runs, n)
    starts = (_runs_of(q0, "q0", runs, n), _runs_of(qd0, "qd0", runs, n))
    tau_d = _runs_of(disturbance, "disturbance", runs, n)
    summaries, outcome, samples = launch_many(
        (plant_rows, plant_coulombs, plant_of, tau_d), (model_rows, model_coulombs, model_of, shares),
        (spec.kind, table, hold), (path_kind, params), starts, (dt, rows, every, math.ceil(after / dt - 1e-9)),
        threads)  # fmt: skip
    times = np.arange(kept) * every * dt
    return Ensemble(arm, times, summaries, outcome, dict(zip(("q", "qd", "tau", "q_d"), samples, strict=True)) if kept
                    else {}, {"dt": dt, "t_final": t_final, "after": after,
                              "controller": control.describe_controller(law),
                              "trajectory": trajectories.describe_trajectory(
                                  trajectory if not isinstance(trajectory, (list, tuple)) else trajectory[0]),
                              })  # fmt: skip
