"""Control in task coordinates (Section 3.5; Khatib 1987): computed torque on a square output
and operational-space control of a redundant arm, with the task-space record of a run."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armdyn import inputs
from armdyn.errors import ArgumentError, ModelError
from armdyn.robot import Robot
from armdyn.task_space.operational import OperationalSpace, operational_space
from armdyn.task_space.outputs import TaskOutput, _check_arm, _check_output


def _desired(path: Callable, t: float, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """path(t), checked: three arrays of m finite values."""
    try:
        parts = tuple(path(t))
    except TypeError as error:
        raise ModelError(f"path(t) must return (y_d, yd_d, ydd_d): {error}") from None
    if len(parts) != 3:
        raise ModelError(f"path(t) must return three arrays (y_d, yd_d, ydd_d), got {len(parts)} items at t = {t:g}")
    y_d, yd_d, ydd_d = (inputs.numbers(part, name, (m,), f" from path(t) at t = {t:g}")
                        for part, name in zip(parts, ("y_d", "yd_d", "ydd_d"), strict=True))  # fmt: skip
    return y_d, yd_d, ydd_d


@dataclass(frozen=True)
class Tracking:
    """The task-space record of a run under a task-space controller (``Result.task``).

    Parameters
    ----------
    output : str
        The output's description, e.g. "ToolPose()".
    y : numpy.ndarray
        The output at every sample, (T, k) as ``TaskOutput.value`` gives it.
    y_d : numpy.ndarray
        The desired output, (T, k).
    error : numpy.ndarray
        The task error e = y_d - y (ToolPose: its orientation part as in ``TaskOutput.error``), (T, m).
    """

    output: str
    y: np.ndarray
    y_d: np.ndarray
    error: np.ndarray


class TaskComputedTorque:
    """Computed-torque control in task coordinates (Section 3.5):
    tau = J^T (Mbar (yddot_d + Kv edot + Kp e) + Nbar), e = y_d - y, edot = yd_d - J qd.

    It decouples the task coordinates into double integrators with PD feedback, for a square,
    nonsingular J (a singular J is a ModelError, see ``task_inertia``). Computed as
    J^T (Lambda a + mu + p + friction) from ``operational_space`` (one compiled call for the
    built-in outputs), which is the same for m = n. For ToolPose the orientation error is the
    rotation vector of R_d R^T (``TaskOutput.error``) and the rates are [v; w]. A controller for
    ``armdyn.simulate``: ``path(t)`` gives (y_d, yd_d, ydd_d) (a Circle, Line or PoseLine); the
    model is ``model`` or, inside simulate, the plant; simulate's Result then carries the task
    error (``Result.task``).

    Parameters
    ----------
    output : TaskOutput
        The task coordinates y = h(q), with m = n.
    path : callable
        t -> (y_d, yd_d, ydd_d), e.g. a Circle, Line or PoseLine.
    kp, kv : float
        The proportional and derivative gains (1/s^2, 1/s).
    model : Robot, optional
        The arm the law computes with; default the plant ``simulate`` passes.
    """

    square = True

    def __init__(self, output: TaskOutput, path: Callable, kp: float, kv: float, model: Robot | None = None) -> None:
        self.output = _check_output(output)
        if not callable(path) or isinstance(path, type):
            raise ArgumentError(f"path must be a callable t -> (y_d, yd_d, ydd_d), got {path!r}")
        self.path = path
        self.kp = inputs.number(kp, "kp", minimum=0.0)
        self.kv = inputs.number(kv, "kv", minimum=0.0)
        self.model = None if model is None else _check_arm(model)

    def _arm(self, plant: Robot | None) -> Robot:
        arm = self.model if self.model is not None else plant
        if arm is None:
            raise ModelError(f"{type(self).__name__} needs a model of the arm (model=...) outside simulate()")
        return arm

    def _task_force(self, arm: Robot, t: float, q: np.ndarray, qd: np.ndarray) -> tuple[OperationalSpace, np.ndarray]:
        """The operational space at (q, qd) and f = Lambda (yddot_d + kv edot + kp e) + mu + p + friction."""
        space = operational_space(arm, self.output, q, qd)
        m = space.J.shape[-2]
        if self.square and m != arm.n:
            raise ModelError(f"{type(self).__name__} needs a square output (m = n = {arm.n}); {self.output!r} has "
                             f"{m} rows: use OperationalSpaceControl for a redundant arm")  # fmt: skip
        y_d, yd_d, ydd_d = _desired(self.path, t, len(self.output.value(arm, q)))
        e, edot = self.output.error(arm, q, y_d), yd_d[:m] - space.J @ qd if len(yd_d) == m else None
        if edot is None:
            raise ModelError(f"path(t) must give a velocity and an acceleration of {m} values for {self.output!r}")
        force = space.Lambda @ (ydd_d + self.kv * edot + self.kp * e) + space.mu + space.p + space.friction
        return space, force

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray, *joint_reference: object, plant: Robot | None = None
    ) -> np.ndarray:
        """The torque at time t for the state (q, qd); the joint-space reference simulate passes
        is not used.

        Parameters
        ----------
        t : float
            The time (s).
        q, qd : numpy.ndarray
            The joint positions and velocities, (n,).
        *joint_reference : object
            simulate's joint-space reference (q_d, qd_d, qdd_d, e_int), ignored.
        plant : Robot, optional
            The arm simulated, used when the law has no model of its own.

        Returns
        -------
        numpy.ndarray
            tau, (n,).

        Raises
        ------
        armdyn.ModelError
            When there is no arm to compute with, J is singular, the output is not square, or
            the path gives values of the wrong length.
        """
        space, force = self._task_force(self._arm(plant), t, q, qd)
        return space.J.T @ force

    def tracking(self, arm: Robot, t: np.ndarray, q: np.ndarray) -> Tracking:
        """The task-space record of a run: y, y_d and e at the times t.

        Parameters
        ----------
        arm : Robot
            The plant (used when the law has no model of its own).
        t : numpy.ndarray
            The times, (T,).
        q : numpy.ndarray
            The joint positions, (T, n).

        Returns
        -------
        Tracking
            The output, its desired value and the task error at every sample.

        Raises
        ------
        armdyn.ModelError
            When there is no arm, or the path gives values of the wrong length.
        """
        arm = self._arm(arm)
        y = self.output.value(arm, q)
        k = y.shape[-1]
        y_d = np.array([_desired(self.path, float(time), k)[0] for time in t]).reshape(len(t), k)
        return Tracking(repr(self.output), y, y_d, self.output.error(arm, q, y_d))

    def describe(self) -> str:
        """The law and its gains, for titles and reports.

        Returns
        -------
        str
            A short description.

        Raises
        ------
        None
            It only formats the gains.
        """
        return f"task-space computed torque on {self.output!r} (kp = {self.kp:g}, kv = {self.kv:g})"


class OperationalSpaceControl(TaskComputedTorque):
    """Operational-space control of a redundant arm (Khatib 1987): the task by computed torque
    in task coordinates, a joint posture in the null space,
    tau = J^T (Lambda (yddot_d + kv edot + kp e) + mu + p + friction) + Nproj^T tau_0,
    tau_0 = M (kp0 (q_0 - q) - kv0 qd), e = y_d - y, edot = yd_d - J qd.

    The null-space torque leaves the task acceleration unchanged (J M^-1 Nproj^T = 0: the
    generalized inverse is dynamically consistent), so the task error obeys
    edd + kv ed + kp e = 0 whatever the posture does. A controller for ``armdyn.simulate``,
    whose Result then carries the task error (``Result.task``).

    Parameters
    ----------
    output : TaskOutput
        The task coordinates (m <= n): ToolPosition, ToolPose (orientation error as in
        ``TaskOutput.error``), LinkPoint, PlanarPosition or an Output.
    path : callable
        t -> (y_d, yd_d, ydd_d), e.g. a Line or PoseLine.
    kp, kv : float
        The task gains (1/s^2, 1/s).
    posture : callable or array_like
        The joint posture q_0: a fixed (n,) configuration or a callable t -> q_0(t).
    kp0, kv0 : float
        The posture gains (1/s^2, 1/s).
    model : Robot, optional
        The arm the law computes with; default the plant ``simulate`` passes.
    """

    square = False

    def __init__(
        self,
        output: TaskOutput,
        path: Callable,
        kp: float,
        kv: float,
        posture: object,
        kp0: float,
        kv0: float,
        model: Robot | None = None,
    ) -> None:
        super().__init__(output, path, kp, kv, model)
        self.posture = posture if callable(posture) else inputs.numbers(posture, "posture")
        self.kp0 = inputs.number(kp0, "kp0", minimum=0.0)
        self.kv0 = inputs.number(kv0, "kv0", minimum=0.0)

    def __call__(
        self, t: float, q: np.ndarray, qd: np.ndarray, *joint_reference: object, plant: Robot | None = None
    ) -> np.ndarray:
        """The torque at time t for the state (q, qd); simulate's joint reference is not used.

        Parameters
        ----------
        t : float
            The time (s).
        q, qd : numpy.ndarray
            The joint positions and velocities, (n,).
        *joint_reference : object
            simulate's joint-space reference, ignored.
        plant : Robot, optional
            The arm simulated, used when the law has no model of its own.

        Returns
        -------
        numpy.ndarray
            tau, (n,).

        Raises
        ------
        armdyn.ModelError
            When there is no arm to compute with, J is singular, the path gives values of the
            wrong length, or the posture has the wrong length.
        """
        arm = self._arm(plant)
        space, force = self._task_force(arm, t, q, qd)
        target = np.asarray(self.posture(t) if callable(self.posture) else self.posture, dtype=float)
        if target.shape != q.shape:
            raise ModelError(f"posture must have {q.shape[0]} values, got shape {target.shape}")
        tau_0 = arm.inertia_matrix(q) @ (self.kp0 * (target - q) - self.kv0 * qd)
        return space.J.T @ force + space.Nproj.T @ tau_0

    def describe(self) -> str:
        """The law and its gains, for titles and reports.

        Returns
        -------
        str
            A short description.

        Raises
        ------
        None
            It only formats the gains.
        """
        return (
            f"operational-space control on {self.output!r} (kp = {self.kp:g}, kv = {self.kv:g}; "
            f"posture kp0 = {self.kp0:g}, kv0 = {self.kv0:g})"
        )
