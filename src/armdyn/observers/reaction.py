"""Reaction to a detected collision: a controller that runs the momentum observer beside the task controller
in the same simulation and, once the residual leaves its band, stops, floats or retracts.

The strategies of Haddadin, De Luca and Albu-Schaeffer ("Robot collisions: a survey on detection,
isolation, and identification", IEEE T-RO 33(6), 2017, Section VII):

- ``"stop"``: hold the position of the moment of detection, tau = G(q) + Kp (q_stop - q) - Kv qd;
- ``"gravity"``: gravity compensation alone, tau = G(q) + F(qd) (the arm yields to the contact);
- ``"reflex"``: the reflex torque reaction, tau = G(q) + F(qd) + K_R r, which moves the arm along the
  external torque the observer estimates (away from the contact).

The controller is called once per sample and its torque held over the step (simulate's RK4), so the
observer takes that held torque exactly (``MomentumObserver(held_torque=True)``); its residual is recorded
at every sample (``times``, ``residuals``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import numpy as np

from armdyn.control.joint import call
from armdyn.dynamics.friction import friction_vector
from armdyn.errors import ModelError
from armdyn.model import ArmModel
from armdyn.observers.detection import Band
from armdyn.observers.momentum import MomentumObserver

STRATEGIES = ("stop", "gravity", "reflex")


class ReactiveController:
    """A task controller watched by the momentum observer, with a reaction once a collision is detected.

    Parameters
    ----------
    controller : callable
        The task controller, ``controller(t, q, qd, q_d, qd_d, qdd_d, e_int) -> tau`` (one of
        armdyn.control's, or the user's).
    arm : ArmModel
        The observer's model (a Robot).
    band : Band
        The residual's band per joint: leaving it is a collision.
    strategy : str, optional
        "stop" (default), "gravity" or "reflex".
    gains : float or array_like, optional
        The observer's K per joint (1/s), default 100.
    reaction_gains : tuple of float, optional
        (Kp, Kv) of "stop" (default (400, 40)) or (K_R,) of "reflex" (default (1.0,)).
    coulomb_smoothing : float or array_like, optional
        As the observer's (the smoothing simulate's plant uses; default the exact sign law).

    Raises
    ------
    armdyn.ModelError
        When the strategy is unknown, the band is not an observers.detection.Band of the arm's joints,
        or the gains are not positive.
    """

    def __init__(
        self,
        controller: Callable[..., Any],
        arm: ArmModel,
        band: Band,
        strategy: str = "stop",
        gains: object = 100.0,
        reaction_gains: tuple[float, ...] | None = None,
        coulomb_smoothing: object = None,
    ) -> None:
        if strategy not in STRATEGIES:
            raise ModelError(f"strategy must be one of {', '.join(STRATEGIES)}, got {strategy!r}")
        if not isinstance(band, Band) or band.n != arm.n:
            raise ModelError(f"band must be an armdyn.observers.detection.Band of {arm.n} joints, got {band!r}")
        defaults = {"stop": (400.0, 40.0), "gravity": (), "reflex": (1.0,)}[strategy]
        values = tuple(float(x) for x in (reaction_gains if reaction_gains is not None else defaults))
        if len(values) != len(defaults) or any(not (np.isfinite(x) and x > 0) for x in values):
            raise ModelError(f"reaction_gains of '{strategy}' must be {len(defaults)} positive numbers, got {values}")
        self.controller, self.arm, self.band, self.strategy = controller, arm, band, strategy
        self.reaction_gains = values
        self.observer = MomentumObserver(arm, gains, held_torque=True, coulomb_smoothing=coulomb_smoothing)
        self._eps, self._given_smoothing = self.observer._eps, coulomb_smoothing
        self.reset()

    def reset(self) -> None:
        """Forget a run: the observer restarts and no collision is detected."""
        self.observer.reset()
        self.times: list[float] = []
        self.residuals: list[np.ndarray] = []
        self.detected_at: float | None = None
        self._stop: np.ndarray | None = None

    def __call__(
        self,
        t: float,
        q: np.ndarray,
        qd: np.ndarray,
        q_d: object,
        qd_d: object,
        qdd_d: object,
        e_int: object,
        plant: ArmModel | None = None,
        coulomb_smoothing: object = None,
    ) -> np.ndarray:
        """The torque at sample t: the task controller's until a collision, then the reaction's.

        Parameters
        ----------
        t : float
            The time (s).
        q, qd : numpy.ndarray
            The state, (n,).
        q_d, qd_d, qdd_d, e_int : object
            The desired path and the error's integral, passed to the task controller.
        plant : ArmModel, optional
            The arm in force (simulate gives it), passed to a task controller that takes it.
        coulomb_smoothing : object, optional
            simulate's smoothing of the Coulomb law: the observer's too, unless one was given.

        Returns
        -------
        numpy.ndarray
            tau, (n,).
        """
        if self.times and t <= self.times[-1]:
            self.reset()  # a new run
        if self._given_smoothing is None and coulomb_smoothing is not None:
            self.observer = MomentumObserver(self.arm, self.observer.gains, True, coulomb_smoothing)
            self._eps, self._given_smoothing = self.observer._eps, coulomb_smoothing
        r = self.observer.step(t, q, qd, np.zeros(self.arm.n)).copy()  # r_k needs only the torque held before
        self.times.append(float(t))
        self.residuals.append(r)
        if self.detected_at is None and not np.all(self.band.contains(r)):
            self.detected_at = float(t)
            self._stop = np.array(q, dtype=float)
        if self.detected_at is None:
            args = (t, q, qd, q_d, qd_d, qdd_d, e_int)
            tau = np.asarray(call(self.controller, args, cast(Any, plant), coulomb_smoothing))
        else:
            tau = self.reaction(q, qd, r)
        self.observer.hold(tau)
        return tau

    def reaction(self, q: np.ndarray, qd: np.ndarray, r: np.ndarray) -> np.ndarray:
        """The reaction's torque after a detection (see the module docstring).

        Parameters
        ----------
        q, qd : numpy.ndarray
            The state, (n,).
        r : numpy.ndarray
            The observer's residual, (n,).

        Returns
        -------
        numpy.ndarray
            tau, (n,).
        """
        gravity = self.arm.gravity_vector(q)  # type: ignore[attr-defined]
        if self.strategy == "stop":
            kp, kv = self.reaction_gains
            assert self._stop is not None
            return gravity + kp * (self._stop - q) - kv * qd
        compensation = gravity + friction_vector(self.arm, qd, self._eps)
        if self.strategy == "gravity":
            return compensation
        return compensation + self.reaction_gains[0] * r

    @property
    def record(self) -> tuple[np.ndarray, np.ndarray]:
        """(t (N,), r (N, n)): the residual at every sample of the run so far."""
        return np.array(self.times), np.array(self.residuals).reshape(-1, self.arm.n)
