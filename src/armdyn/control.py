"""Controllers of Chapter 4: computed torque (PD or PID), PD plus gravity, classical PID,
digital (zero-order hold) and torque saturation; each class beside its compiled law.

A controller is any callable

    tau = controller(t, q, qd, q_d, qd_d, qdd_d, e_int)            or
    tau = controller(t, q, qd, q_d, qd_d, qdd_d, e_int, plant=arm)

with e = q_d - q and e_int the time integral of e (kept by the simulator); a controller that
takes a ``plant`` keyword is given the arm in force at that time, and one that takes
``coulomb_smoothing`` the eps per joint of the smoothed Coulomb law the simulated plant
follows (so that it can compensate the same law, as the built-in ComputedTorque does). A user's own controller
runs in simulate's Python loop. The built-in ones also describe themselves to the compiled
simulation loop (``spec``), which runs their compiled law (below each class), so that a
whole run is one Numba call. Gains are scalars or per joint.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from armdyn.dynamics.crba import mass_matrix_and_bias
from armdyn.dynamics.friction import coulomb_vector, smooth_coulomb, smooth_coulomb_vector
from armdyn.dynamics.rnea import gravity_core
from armdyn.dynamics.spatial import NUMBA_OPTIONS
from armdyn.errors import ModelError
from armdyn.inputs import gains as _gains
from armdyn.robot import Robot

NO_CONTROL, COMPUTED_TORQUE, PD_GRAVITY, PID_JOINT = 0, 1, 2, 3
KP, KV, KI, LIMIT = 0, 1, 2, 3  # rows of the compiled laws' gain table


def accepts(controller: object, keyword: str) -> bool:
    """True when ``controller`` takes the keyword (by name, or any keyword)."""
    try:
        parameters = inspect.signature(controller).parameters.values()
    except (TypeError, ValueError):  # a builtin or extension callable: no keywords known
        return False
    return any(p.name == keyword or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)


def call(controller: object, args: tuple, plant: Robot | None, coulomb_smoothing: object) -> np.ndarray:
    """controller(*args), with ``plant`` and ``coulomb_smoothing`` for a controller that takes them."""
    extra = {}
    if plant is not None and accepts(controller, "plant"):
        extra["plant"] = plant
    if coulomb_smoothing is not None and accepts(controller, "coulomb_smoothing"):
        extra["coulomb_smoothing"] = coulomb_smoothing
    return controller(*args, **extra)


@dataclass
class Spec:
    """What the compiled loop needs to know of a controller."""

    kind: int
    kp: object
    kv: object
    ki: object
    model: Robot | None = None
    period: float = 0.0
    limit: object = np.inf


@dataclass
class ComputedTorque:
    """tau = M(q) (qdd_d + kv edot + kp e + ki int e) + N(q, qd) (BOOK.md section 5).

    ``model``: the arm the controller believes in (default: the plant itself), for
    robustness studies.
    """

    kp: object
    kv: object
    ki: object = 0.0
    model: Robot | None = None

    def spec(self) -> Spec:
        return Spec(COMPUTED_TORQUE, self.kp, self.kv, self.ki, self.model)

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, q_d: np.ndarray, qd_d: np.ndarray,
                 qdd_d: np.ndarray, e_int: np.ndarray, plant: Robot | None = None,
                 coulomb_smoothing: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        """tau for one state. ``coulomb_smoothing`` (eps per joint, given by simulate) compensates the
        model's Coulomb friction with the smoothed law the simulated plant follows, as the compiled
        law does; without it the exact sign law."""
        arm = self.model or plant
        if arm is None:
            raise ModelError("ComputedTorque needs a model of the arm (model=...) outside simulate()")
        n = arm.n
        u = qdd_d + _gains(self.kv, "kv", n) * (qd_d - qd) + _gains(self.kp, "kp", n) * (q_d - q)
        u = u + _gains(self.ki, "ki", n) * e_int
        N = arm.nonlinear_terms(q, qd)
        if coulomb_smoothing is not None:
            table = arm.coulomb_friction
            N = N - coulomb_vector(table, qd) + smooth_coulomb_vector(table, coulomb_smoothing, qd)
        return arm.inertia_matrix(q) @ u + N


@njit(inline="always", **NUMBA_OPTIONS)
def computed_torque_law(
    model: np.ndarray, model_coulomb: np.ndarray, eps: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray,
    desired: np.ndarray, e_int: np.ndarray, gain: np.ndarray, u: np.ndarray, M: np.ndarray, N: np.ndarray,
    tau: np.ndarray,
) -> None:  # fmt: skip
    """tau = M (qdd_d + kv edot + kp e + ki int e) + N on the model; its Coulomb friction compensated
    with the simulation's smooth law. Leaves M and N of this state in M and N."""
    n = q.shape[0]
    for i in range(n):
        u[i] = (
            desired[2, i] + gain[KV, i] * (desired[1, i] - qd[i]) + gain[KP, i] * (desired[0, i] - q[i])
            + gain[KI, i] * e_int[i]
        )  # fmt: skip
    mass_matrix_and_bias(model, work, q, qd, M, N)
    for i in range(n):
        total = N[i] + smooth_coulomb(model_coulomb, eps, i, qd[i])
        for j in range(n):
            total += M[i, j] * u[j]
        tau[i] = total


@dataclass
class PDGravity:
    """tau = kp e + kv edot + G(q) (Example 4.4-3)."""

    kp: object
    kv: object
    model: Robot | None = None

    def spec(self) -> Spec:
        return Spec(PD_GRAVITY, self.kp, self.kv, 0.0, self.model)

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, q_d: np.ndarray, qd_d: np.ndarray,
                 qdd_d: np.ndarray, e_int: np.ndarray, plant: Robot | None = None,
                 coulomb_smoothing: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        arm = self.model or plant
        if arm is None:
            raise ModelError("PDGravity needs a model of the arm (model=...) outside simulate()")
        n = arm.n
        return _gains(self.kp, "kp", n) * (q_d - q) + _gains(self.kv, "kv", n) * (qd_d - qd) + arm.gravity_vector(q)


@njit(inline="always", **NUMBA_OPTIONS)
def pd_gravity_law(
    model: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray, desired: np.ndarray, gain: np.ndarray,
    G: np.ndarray, tau: np.ndarray,
) -> None:  # fmt: skip
    """tau = kp e + kv edot + G(q) on the model."""
    gravity_core(model, work, q, G)
    for i in range(q.shape[0]):
        tau[i] = gain[KP, i] * (desired[0, i] - q[i]) + gain[KV, i] * (desired[1, i] - qd[i]) + G[i]


@dataclass
class PID:
    """Classical independent-joint control, tau = kp e + kv edot + ki int e (Example 4.4-4)."""

    kp: object
    kv: object
    ki: object = 0.0

    def spec(self) -> Spec:
        return Spec(PID_JOINT, self.kp, self.kv, self.ki)

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, q_d: np.ndarray, qd_d: np.ndarray,
                 qdd_d: np.ndarray, e_int: np.ndarray, plant: Robot | None = None,
                 coulomb_smoothing: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
        n = q.shape[-1]
        e, edot = q_d - q, qd_d - qd
        return _gains(self.kp, "kp", n) * e + _gains(self.kv, "kv", n) * edot + _gains(self.ki, "ki", n) * e_int


@njit(inline="always", **NUMBA_OPTIONS)
def pid_law(
    q: np.ndarray, qd: np.ndarray, desired: np.ndarray, e_int: np.ndarray, gain: np.ndarray, tau: np.ndarray
) -> None:
    """tau = kp e + kv edot + ki int e."""
    for i in range(q.shape[0]):
        tau[i] = gain[KP, i] * (desired[0, i] - q[i]) + gain[KV, i] * (desired[1, i] - qd[i]) + gain[KI, i] * e_int[i]


@dataclass
class Digital:
    """A controller run once per sample ``period`` with its torque held in between (Section 4.5)."""

    controller: object
    period: float

    def __post_init__(self) -> None:
        if not (isinstance(self.period, (int, float, np.number)) and np.isfinite(self.period) and self.period > 0):
            raise ModelError(f"a Digital controller needs a positive, finite sample period, got {self.period!r}")
        if not callable(self.controller):
            raise ModelError(f"Digital needs a controller (a callable), got {type(self.controller).__name__}")

    def spec(self) -> Spec | None:
        inner = getattr(self.controller, "spec", None)
        if inner is None:
            return None
        spec = inner()
        if spec is None:
            return None
        spec.period = self.period
        return spec

    def __call__(self, *args: object, plant: Robot | None = None, coulomb_smoothing: object = None) -> np.ndarray:
        return call(self.controller, args, plant, coulomb_smoothing)


@dataclass
class Saturated:
    """A controller whose torques are clipped to +-limit (scalar or per joint, > 0; inf for none)."""

    controller: object
    limit: object = field(default=np.inf)

    def __post_init__(self) -> None:
        try:
            limit = np.atleast_1d(np.asarray(self.limit, dtype=float))
        except (TypeError, ValueError):
            raise ModelError(f"a torque limit must be a positive number or one per joint, got {self.limit!r}") from None
        if limit.ndim != 1 or np.any(np.isnan(limit)) or np.any(limit <= 0):
            raise ModelError(f"a torque limit must be positive (inf for none), got {self.limit!r}")
        if not callable(self.controller):
            raise ModelError(f"Saturated needs a controller (a callable), got {type(self.controller).__name__}")

    def spec(self) -> Spec | None:
        inner = getattr(self.controller, "spec", None)
        spec = inner() if inner is not None else None
        if spec is None:
            return None
        spec.limit = self.limit
        return spec

    def __call__(self, *args: object, plant: Robot | None = None, coulomb_smoothing: object = None) -> np.ndarray:
        tau = call(self.controller, args, plant, coulomb_smoothing)
        limit = np.asarray(self.limit, dtype=float)
        return np.clip(tau, -limit, limit)


@njit(**NUMBA_OPTIONS)
def control_law(
    kind: int, model: np.ndarray, model_coulomb: np.ndarray, eps: np.ndarray, work: np.ndarray, q: np.ndarray,
    qd: np.ndarray, desired: np.ndarray, e_int: np.ndarray, gain: np.ndarray, u: np.ndarray, M: np.ndarray,
    N: np.ndarray, tau: np.ndarray,
) -> None:  # fmt: skip
    """The compiled law of a built-in controller (``kind``), then saturation at gain[LIMIT].

    gain rows: KP, KV, KI, LIMIT, per joint; desired rows: q_d, qd_d, qdd_d.
    """
    if kind == COMPUTED_TORQUE:
        computed_torque_law(model, model_coulomb, eps, work, q, qd, desired, e_int, gain, u, M, N, tau)
    elif kind == PD_GRAVITY:
        pd_gravity_law(model, work, q, qd, desired, gain, N, tau)
    else:
        pid_law(q, qd, desired, e_int, gain, tau)
    for i in range(q.shape[0]):
        tau[i] = min(max(tau[i], -gain[LIMIT, i]), gain[LIMIT, i])


def describe(controller: object) -> str:
    """A short description of a controller for titles and reports: its kind and gains."""
    if controller is None:
        return "no control (zero torque)"
    if isinstance(controller, Digital):
        return f"{describe(controller.controller)}, sampled every {controller.period * 1e3:g} ms"
    if isinstance(controller, Saturated):
        return f"{describe(controller.controller)}, torques within +-{_short(controller.limit)}"
    if isinstance(controller, ComputedTorque | PDGravity | PID):
        gains = [f"kp = {_short(controller.kp)}", f"kv = {_short(controller.kv)}"]
        ki = getattr(controller, "ki", 0.0)
        if np.any(np.asarray(ki, dtype=float) != 0):
            gains.append(f"ki = {_short(ki)}")
        model = getattr(controller, "model", None)
        belief = f", model '{model.name}'" if model is not None else ""
        label = {"ComputedTorque": "computed torque", "PDGravity": "PD plus gravity", "PID": "joint PID"}
        return f"{label[type(controller).__name__]} ({', '.join(gains)}{belief})"
    return getattr(controller, "__name__", type(controller).__name__)


def _short(value: object) -> str:
    array = np.atleast_1d(np.asarray(value, dtype=float))
    if np.all(array == array[0]):
        return f"{array[0]:g}"
    return "[" + ", ".join(f"{v:g}" for v in array) + "]"
