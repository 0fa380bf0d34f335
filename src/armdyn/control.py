"""Controllers of Chapter 4: computed torque (PD or PID), PD plus gravity, classical PID,
digital (zero-order hold) and torque saturation.

A controller is a small object with one method:

    tau = controller(t, q, qd, q_d, qd_d, qdd_d, e_int)

with e = q_d - q and e_int the time integral of e (kept by the simulator). Users can
write their own; the built-in ones also describe themselves to the compiled simulation
loop (``spec``), so that a whole run is one Numba call. Gains are scalars or per joint.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from armdyn.errors import ModelError
from armdyn.model.robot import Robot

COMPUTED_TORQUE, PD_GRAVITY, PID_JOINT = 1, 2, 3


def _gains(value: object, name: str, n: int) -> np.ndarray:
    array = np.atleast_1d(np.asarray(value, dtype=float))
    if array.ndim != 1 or array.shape[0] not in (1, n) or not np.all(np.isfinite(array)) or np.any(array < 0):
        raise ModelError(f"gain {name} must be a non-negative scalar or {n} values, got {value!r}")
    return np.broadcast_to(array, (n,)).copy()


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
                 qdd_d: np.ndarray, e_int: np.ndarray, plant: Robot | None = None) -> np.ndarray:  # fmt: skip
        arm = self.model or plant
        if arm is None:
            raise ModelError("ComputedTorque needs a model of the arm (model=...) outside simulate()")
        n = arm.n
        u = qdd_d + _gains(self.kv, "kv", n) * (qd_d - qd) + _gains(self.kp, "kp", n) * (q_d - q)
        u = u + _gains(self.ki, "ki", n) * e_int
        return arm.inertia_matrix(q) @ u + arm.nonlinear_terms(q, qd)


@dataclass
class PDGravity:
    """tau = kp e + kv edot + G(q) (Example 4.4-3)."""

    kp: object
    kv: object
    model: Robot | None = None

    def spec(self) -> Spec:
        return Spec(PD_GRAVITY, self.kp, self.kv, 0.0, self.model)

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, q_d: np.ndarray, qd_d: np.ndarray,
                 qdd_d: np.ndarray, e_int: np.ndarray, plant: Robot | None = None) -> np.ndarray:  # fmt: skip
        arm = self.model or plant
        if arm is None:
            raise ModelError("PDGravity needs a model of the arm (model=...) outside simulate()")
        n = arm.n
        return _gains(self.kp, "kp", n) * (q_d - q) + _gains(self.kv, "kv", n) * (qd_d - qd) + arm.gravity_vector(q)


@dataclass
class PID:
    """Classical independent-joint control, tau = kp e + kv edot + ki int e (Example 4.4-4)."""

    kp: object
    kv: object
    ki: object = 0.0

    def spec(self) -> Spec:
        return Spec(PID_JOINT, self.kp, self.kv, self.ki)

    def __call__(self, t: float, q: np.ndarray, qd: np.ndarray, q_d: np.ndarray, qd_d: np.ndarray,
                 qdd_d: np.ndarray, e_int: np.ndarray, plant: Robot | None = None) -> np.ndarray:  # fmt: skip
        n = q.shape[-1]
        e, edot = q_d - q, qd_d - qd
        return _gains(self.kp, "kp", n) * e + _gains(self.kv, "kv", n) * edot + _gains(self.ki, "ki", n) * e_int


@dataclass
class Digital:
    """A controller run once per sample ``period`` with its torque held in between (Section 4.5)."""

    controller: object
    period: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.period) and self.period > 0):
            raise ModelError(f"a Digital controller needs a positive sample period, got {self.period}")

    def spec(self) -> Spec | None:
        inner = getattr(self.controller, "spec", None)
        if inner is None:
            return None
        spec = inner()
        if spec is None:
            return None
        spec.period = self.period
        return spec

    def __call__(self, *args: object, **kwargs: object) -> np.ndarray:
        return self.controller(*args, **kwargs)


@dataclass
class Saturated:
    """A controller whose torques are clipped to +-limit (scalar or per joint)."""

    controller: object
    limit: object = field(default=np.inf)

    def spec(self) -> Spec | None:
        inner = getattr(self.controller, "spec", None)
        spec = inner() if inner is not None else None
        if spec is None:
            return None
        spec.limit = self.limit
        return spec

    def __call__(self, *args: object, **kwargs: object) -> np.ndarray:
        tau = self.controller(*args, **kwargs)
        limit = np.asarray(self.limit, dtype=float)
        return np.clip(tau, -limit, limit)
