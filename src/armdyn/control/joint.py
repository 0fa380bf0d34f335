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
import math
import reprlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TypeGuard, cast

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from armdyn import inputs
from armdyn.dynamics.crba import mass_matrix_and_bias
from armdyn.dynamics.drives import KI, KP, KV
from armdyn.dynamics.friction import coulomb_vector, smooth_coulomb, smooth_coulomb_vector, stribeck_vector
from armdyn.dynamics.rnea import gravity_core
from armdyn.dynamics.spatial import NUMBA_OPTIONS
from armdyn.errors import ArgumentError, ModelError
from armdyn.inputs import LARGEST_STATE
from armdyn.robot import Robot

NO_CONTROL, COMPUTED_TORQUE, PD_GRAVITY, PID_JOINT = 0, 1, 2, 3
LIMIT = 3  # the torque limit's row of the compiled laws' gain table, after KP, KV, KI (armdyn.dynamics.drives)


def accepts(controller: Callable[..., object], keyword: str) -> bool:
    """True when ``controller`` takes the keyword (by name, or any keyword)."""
    try:
        parameters = inspect.signature(controller).parameters.values()
    except (TypeError, ValueError):  # a builtin or extension callable: no keywords known
        return False
    return any(p.name == keyword or p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters)


def call(
    controller: Callable[..., np.ndarray], args: tuple, plant: Robot | None, coulomb_smoothing: object
) -> np.ndarray:
    """controller(*args), with ``plant`` and ``coulomb_smoothing`` for a controller that takes them."""
    extra: dict[str, object] = {}
    if plant is not None and accepts(controller, "plant"):
        extra["plant"] = plant
    if coulomb_smoothing is not None and accepts(controller, "coulomb_smoothing"):
        extra["coulomb_smoothing"] = coulomb_smoothing
    return controller(*args, **extra)


def _states(names: Sequence[str], values: Sequence[object], n: int, where: str) -> list[np.ndarray]:
    """The states a law uses, checked by inputs.batch_states and broadcast to their common shape
    (..., n); an error names the argument. One state of float64 arrays, as simulate's Python loop
    passes them, is taken as it is after one vectorized test (NaN fails it), since the full check
    costs more than the law itself."""
    if all(_plain(v, n) for v in values):
        plain = cast("list[np.ndarray]", list(values))
        if np.abs(np.concatenate(plain)).max() < LARGEST_STATE:
            return plain
    batch, flat = inputs.batch_states(names, values, n, where)
    return [a.reshape(*batch, n) for a in flat]


def _plain(value: object, n: int) -> TypeGuard[np.ndarray]:
    """Whether ``value`` is a plain float64 array of shape (n,) (not a subclass, native order)."""
    return type(value) is np.ndarray and value.shape == (n,) and value.dtype == np.float64


def _joints(names: Sequence[str], values: Sequence[ArrayLike]) -> int:
    """n for a law without an arm (PID): the last axis its states share, or a ModelError naming
    their shapes (an argument that is no array at all is named by ``_states``)."""
    shapes = {}
    for name, value in zip(names, values, strict=True):
        try:
            shape = np.shape(value)
        except (TypeError, ValueError):  # a ragged list: named by _states
            continue
        if shape:
            shapes[name] = shape
    widths = {shape[-1] for shape in shapes.values()}
    if len(widths) == 1 and min(widths) > 0:
        return widths.pop()
    listed = ", ".join(f"{name} {shape}" for name, shape in shapes.items()) or "no arrays"
    raise ModelError(f"the states given to PID must all have shape (n,) or (..., n) for one n >= 1, got {listed}")


def _gain(value: object, name: str, n: int) -> float | np.ndarray:
    """A gain checked by inputs.gains; a plain non-negative float or int (the usual gain) is returned
    as it is, skipping that costlier check: it multiplies exactly as the array of n copies would (an
    int up to 2**53 converts to float64 exactly)."""
    if (type(value) is float and 0.0 <= value < math.inf) or (type(value) is int and 0 <= value <= 2**53):
        return value
    return inputs.gains(value, name, n)


def _arm_of(controller: ComputedTorque | PDGravity, plant: object) -> Robot:
    """The arm a model-based law computes with: its own model, else the plant simulate gives."""
    name, arm = ("model", controller.model) if controller.model is not None else ("plant", plant)
    kind = type(controller).__name__
    if arm is None:
        raise ModelError(f"{kind} needs a model of the arm (model=...) outside simulate()")
    inputs.arm_argument(arm, Robot, name=f"{kind}'s {name}")
    return cast(Robot, arm)


def _smoothing(value: object, n: int) -> np.ndarray:
    """coulomb_smoothing: eps >= 0 per joint (or one for all), as (n,) or a scalar array."""
    if _plain(value, n) and value.min() >= 0.0 and value.max() < math.inf:  # NaN fails
        return value
    eps = inputs.vector(value, "coulomb_smoothing")
    if eps.shape[0] not in (1, n) or np.any(eps < 0):
        raise ModelError(f"coulomb_smoothing must be eps >= 0 (rad/s) for every joint or one per joint ({n}), "
                         f"got {reprlib.repr(value)}")  # fmt: skip
    return eps


def _where(controller: object, arm: Robot | None = None) -> str:
    """Where a state error happened, for its message."""
    return f" for {type(controller).__name__}" + (f" on '{arm.name}'" if arm is not None else "")


def _times_matrix(M: np.ndarray, u: np.ndarray) -> np.ndarray:
    """M u for one state (as before, for bitwise equal torques) or per state of a batch."""
    return M @ u if u.ndim == 1 else (M @ u[..., None])[..., 0]


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
    """tau = M(q) (qdd_d + kv edot + kp e + ki int e) + N(q, qd) (Section 3.4).

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
        """tau for one state (n,) or a batch (..., n) of the states' common batch shape.

        ``coulomb_smoothing`` (eps per joint, given by simulate) compensates the model's Coulomb
        and Stribeck friction with the smoothed law the simulated plant follows, as the compiled law does;
        without it the exact sign law. ``t`` is not used. A state that is not numbers of shape
        (..., n), holds NaN or infinity, or does not broadcast with the others is a ModelError
        naming it."""
        arm = _arm_of(self, plant)
        n = arm.n
        names = ("q", "qd", "q_d", "qd_d", "qdd_d", "e_int")
        q, qd, q_d, qd_d, qdd_d, e_int = _states(names, (q, qd, q_d, qd_d, qdd_d, e_int), n, _where(self, arm))
        u = qdd_d + _gain(self.kv, "kv", n) * (qd_d - qd) + _gain(self.kp, "kp", n) * (q_d - q)
        u = u + _gain(self.ki, "ki", n) * e_int
        N = arm.nonlinear_terms(q, qd)
        if coulomb_smoothing is not None:
            eps, table = _smoothing(coulomb_smoothing, n), arm.coulomb_friction
            with np.errstate(over="ignore"):  # qd / a tiny eps overflows to inf, where tanh is exactly +-1
                N = N - coulomb_vector(table, qd) + smooth_coulomb_vector(table, eps, qd)
                stribeck = arm.stribeck_friction
                if np.any(stribeck[:, 0] != 0):  # the Stribeck law's sign smoothed alike
                    N = N - stribeck_vector(stribeck, qd) + stribeck_vector(stribeck, qd, eps)
        return _times_matrix(arm.inertia_matrix(q), u) + N


@njit(inline="always", **NUMBA_OPTIONS)
def computed_torque_law(
    model: np.ndarray, model_coulomb: np.ndarray, eps: np.ndarray, work: np.ndarray, q: np.ndarray, qd: np.ndarray,
    desired: np.ndarray, e_int: np.ndarray, gain: np.ndarray, u: np.ndarray, M: np.ndarray, N: np.ndarray,
    tau: np.ndarray,
) -> None:  # fmt: skip
    """tau = M (qdd_d + kv edot + kp e + ki int e) + N on the model; its Coulomb and Stribeck friction
    (``model_coulomb``, (n, 4), taken out of ``model`` by simulation.packed_plants) compensated with the
    simulation's smooth law. Leaves M and N of this state in M and N."""
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
        """tau for one state (n,) or a batch (..., n); ``t``, ``qdd_d`` and ``e_int`` are not used.
        A state that is not numbers of shape (..., n), holds NaN or infinity, or does not
        broadcast with the others is a ModelError naming it."""
        arm = _arm_of(self, plant)
        n = arm.n
        q, qd, q_d, qd_d = _states(("q", "qd", "q_d", "qd_d"), (q, qd, q_d, qd_d), n, _where(self, arm))
        return _gain(self.kp, "kp", n) * (q_d - q) + _gain(self.kv, "kv", n) * (qd_d - qd) + arm.gravity_vector(q)


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
        """tau for one state (n,) or a batch (..., n), n taken from the states (they must agree);
        ``t`` and ``qdd_d`` are not used. A state that is not numbers of shape (..., n), holds NaN
        or infinity, or does not broadcast with the others is a ModelError naming it."""
        names, values = ("q", "qd", "q_d", "qd_d", "e_int"), (q, qd, q_d, qd_d, e_int)
        n = _joints(names, values)
        q, qd, q_d, qd_d, e_int = _states(names, values, n, _where(self))
        e, edot = q_d - q, qd_d - qd
        return _gain(self.kp, "kp", n) * e + _gain(self.kv, "kv", n) * edot + _gain(self.ki, "ki", n) * e_int


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

    controller: Callable[..., np.ndarray]
    period: float

    def __post_init__(self) -> None:
        period = inputs.number(self.period, "period", " (the sample period of a Digital controller)")
        if not period > 0:
            raise ModelError(f"a Digital controller needs a positive sample period, got period = {period!r}")
        self.period = period  # a float, whatever number was given (simulate divides it by dt)
        if not callable(self.controller):
            raise ArgumentError(f"Digital needs a controller (a callable), got {type(self.controller).__name__}")

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

    controller: Callable[..., np.ndarray]
    limit: ArrayLike = field(default=np.inf)

    def __post_init__(self) -> None:
        _torque_limit(self.limit)
        if not callable(self.controller):
            raise ArgumentError(f"Saturated needs a controller (a callable), got {type(self.controller).__name__}")

    def spec(self) -> Spec | None:
        inner = getattr(self.controller, "spec", None)
        spec = inner() if inner is not None else None
        if spec is None:
            return None
        spec.limit = self.limit
        return spec

    def __call__(self, *args: object, plant: Robot | None = None, coulomb_smoothing: object = None) -> np.ndarray:
        """The controller's torques clipped to +-limit; a limit per joint must match their number."""
        tau = call(self.controller, args, plant, coulomb_smoothing)
        limit = _torque_limit(self.limit)
        if limit.ndim and limit.shape[0] != 1 and np.shape(tau)[-1:] != limit.shape:
            raise ModelError(f"the torque limit has {limit.shape[0]} values, one per joint, but the controller "
                             f"gives torques of shape {np.shape(tau)}")  # fmt: skip
        return np.clip(tau, -limit, limit)


def _torque_limit(value: ArrayLike) -> np.ndarray:
    """A Saturated limit as a float array: a positive number or one per joint (inf for none)."""
    try:
        if np.iscomplexobj(value):
            raise TypeError("complex")
        limit = np.asarray(value, dtype=float)
    except (TypeError, ValueError, ArithmeticError):  # OverflowError: an int beyond float
        raise ModelError(
            f"a torque limit must be a positive number or one per joint, got {reprlib.repr(value)}"
        ) from None
    if limit.ndim > 1 or not limit.size or np.any(np.isnan(limit)) or np.any(limit <= 0):
        raise ModelError(
            f"a torque limit must be positive (inf for none), one or one per joint, got {reprlib.repr(value)}"
        )
    return limit


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


def describe_controller(controller: object) -> str:
    """A short description of a controller for titles and reports: its kind and gains."""
    if controller is None:
        return "no control (zero torque)"
    if isinstance(controller, Digital):
        return f"{describe_controller(controller.controller)}, sampled every {controller.period * 1e3:g} ms"
    if isinstance(controller, Saturated):
        return f"{describe_controller(controller.controller)}, torques within +-{_short(controller.limit)}"
    if isinstance(controller, ComputedTorque | PDGravity | PID):
        gains = [f"kp = {_short(controller.kp)}", f"kv = {_short(controller.kv)}"]
        ki = getattr(controller, "ki", 0.0)
        if _nonzero(ki):
            gains.append(f"ki = {_short(ki)}")
        model = getattr(controller, "model", None)
        belief = f", model '{model.name}'" if model is not None else ""
        label = {"ComputedTorque": "computed torque", "PDGravity": "PD plus gravity", "PID": "joint PID"}
        return f"{label[type(controller).__name__]} ({', '.join(gains)}{belief})"
    own = getattr(type(controller), "describe", None)  # a law that describes itself (armdyn.control.task's)
    if callable(own):
        return str(own(controller))
    return getattr(controller, "__name__", type(controller).__name__)


def _nonzero(value: object) -> bool:
    """Whether a gain is worth naming: not zero (or not numbers, which the controller refuses when run)."""
    try:
        return bool(np.any(np.asarray(value, dtype=float) != 0))
    except (TypeError, ValueError, ArithmeticError):
        return True


def _short(value: object) -> str:
    """A gain or limit for a title: one number when all joints share it."""
    try:
        array = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError, ArithmeticError):  # not numbers: the controller refuses it when run
        return reprlib.repr(value)
    if array.ndim != 1 or not array.size:
        return reprlib.repr(value)
    if np.all(array == array[0]):
        return f"{array[0]:g}"
    return "[" + ", ".join(f"{v:g}" for v in array) + "]"
