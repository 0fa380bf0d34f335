"""Optimal control with the robot equation as CasADi functions: a point-to-point motion of the PUMA 560 with
torque limits and minimum effort, tracked by computed torque, then an MPC holding a pose under a payload change
(Section 3.4's state equation; Diehl et al. 2006 for multiple shooting).

Part 1, the motion: from START to GOAL, at rest at both ends, in T = 1.2 s, the torque held over each of
50 intervals, every torque within TORQUE_LIMIT (ours: the model has none) and the knots within the joint limits.
The state x = [q; qd] follows xdot = [qd; M^-1 (tau - N)]; one interval is one RK4 step of it, armdyn's
generated ``step`` Function (Coulomb friction smoothed by tanh, as simulate smooths it). Multiple shooting: the
states at the 51 knots and the 50 torques are all variables, the cost is sum |tau_k|^2 h, each interval must end
on the next knot. IPOPT (inside the casadi wheel) solves it from a quintic's states and inverse dynamics. Then
ad.simulate tracks the optimum (a cubic Hermite spline through the knots' q and qd) under computed torque
(kp = 400, kv = 40) on the arm itself.

Part 2, the MPC: the arm holds HOLD while, at t = 0.2 s, it picks up a 2.5 kg payload at the flange. Every
20 ms the controller solves a 15-interval problem (the same multiple shooting; the cost the state's distance
from HOLD and the torque's from the model's G(HOLD); warm-started from the last solution shifted by one interval
and its multipliers) and applies the first torque for the 20 ms. The plant is the RK4 step of the arm with its
friction, and with the payload from the pickup on. The MPC's model is the arm without friction: the nominal
arm throughout (it sags to a steady offset), or refreshed with the payload at the pickup (as when the payload
is known). The solve times (median, max) and the errors are printed.

Run: .venv/bin/python examples/optimal_control.py [--quick]   (writes out/optimal_control.png and
out/optimal_control_mpc.png; --quick solves coarser problems and writes nothing)
"""

from __future__ import annotations

import argparse
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import casadi
import numpy as np
from scipy.interpolate import CubicHermiteSpline

import armdyn as ad
from armdyn import symbolic
from armdyn.simulation import PythonLoopWarning, Result

ARM = ad.models.load("puma560")
START = np.array([0.0, 0.7854, -3.1416, 0.0, 0.7854, 0.0])  # the nominal pose qn
GOAL = np.array([1.2, 0.3, -2.6, 0.5, 0.3, 0.5])
# the PUMA 560 model carries no torque limits: these are ours (N m), tight enough on joints 1-3 to bind
TORQUE_LIMIT = np.array([45.0, 90.0, 40.0, 10.0, 10.0, 10.0])
DURATION, INTERVALS = 1.2, 50
IPOPT = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-8}


def dynamics(arm: ad.Robot) -> casadi.Function:
    """armdyn's generated RK4 step of the arm's state equation, (x, tau, dt) -> x_next, as a CasADi Function."""
    return symbolic.generate_code(arm, ("step",), backend="casadi").step


@dataclass
class Motion:
    """An optimal point-to-point motion: knot times t (K + 1,), states x (K + 1, 2n), torques tau (K, n), the cost
    (N^2 m^2 s), IPOPT's iterations and status, and the seconds to build the problem and to solve it."""

    t: np.ndarray
    x: np.ndarray
    tau: np.ndarray
    cost: float
    iterations: int
    status: str
    build_seconds: float
    solve_seconds: float


def quintic_guess(start: np.ndarray, goal: np.ndarray, duration: float, intervals: int, arm: ad.Robot):
    """The first guess: a quintic rest-to-rest path's states at the knots, the inverse dynamics at mid-interval."""
    path = ad.trajectories.Quintic(start, goal, 0.0, duration)
    h = duration / intervals
    q, qd, _ = path(np.linspace(0.0, duration, intervals + 1))
    tau = arm.inverse_dynamics(*path((np.arange(intervals) + 0.5) * h))
    return np.hstack([q, qd]), tau


def point_to_point(
    step: casadi.Function, start: np.ndarray, goal: np.ndarray, limit: np.ndarray, duration: float, intervals: int,
    guess: tuple[np.ndarray, np.ndarray], options: dict | None = None, joint_limits: np.ndarray | None = None,
) -> Motion:  # fmt: skip
    """Minimum effort from rest at ``start`` to rest at ``goal`` by multiple shooting with IPOPT.

    The variables are the knots' states X (2n, K + 1) and the torques U (n, K); the constraints
    X[:, k+1] = step(X[:, k], U[:, k], h) (the RK4 defects), the boundary states and |U| <= limit (as bounds); the
    cost is sum |U[:, k]|^2 h. ``guess`` gives the first states (K + 1, 2n) and torques (K, n); ``options`` are
    nlpsol's, IPOPT by default; ``joint_limits`` (2, n), lower and upper, bound q at every
    knot. The build (the NLP, its derivatives, the solver) and the solve are timed apart."""
    started = time.perf_counter()
    n, h = start.size, duration / intervals
    X, U = casadi.MX.sym("X", 2 * n, intervals + 1), casadi.MX.sym("U", n, intervals)
    ends = step.map(intervals)(X[:, :-1], U, h)  # every interval's RK4 step, one call
    problem = {"x": casadi.veccat(X, U), "f": h * casadi.sumsqr(U), "g": casadi.vec(ends - X[:, 1:])}
    solver = casadi.nlpsol("point_to_point", "ipopt", problem, IPOPT if options is None else options)
    lower, upper = np.full((intervals + 1, 2 * n), -np.inf), np.full((intervals + 1, 2 * n), np.inf)
    lower[0] = upper[0] = np.concatenate([start, np.zeros(n)])
    lower[-1] = upper[-1] = np.concatenate([goal, np.zeros(n)])
    if joint_limits is not None:
        lower[1:-1, :n], upper[1:-1, :n] = joint_limits[0], joint_limits[1]
    torques = np.tile(limit, intervals)
    first = np.concatenate([guess[0].ravel(), np.clip(guess[1], -limit, limit).ravel()])
    built = time.perf_counter()
    solution = solver(x0=first, lbx=np.concatenate([lower.ravel(), -torques]),
                      ubx=np.concatenate([upper.ravel(), torques]), lbg=0.0, ubg=0.0)  # fmt: skip
    solved = time.perf_counter()
    stats, z = solver.stats(), np.asarray(solution["x"]).ravel()
    states = z[: 2 * n * (intervals + 1)].reshape(intervals + 1, 2 * n)
    return Motion(np.linspace(0.0, duration, intervals + 1), states, z[states.size :].reshape(intervals, n),
                  float(solution["f"]), int(stats["iter_count"]), str(stats["return_status"]), built - started,
                  solved - built)  # fmt: skip


def defects(step: casadi.Function, motion: Motion) -> np.ndarray:
    """The RK4 defects of a motion: step(x_k, tau_k, h) - x_(k+1), (K, 2n)."""
    h = motion.t[1] - motion.t[0]
    ends = step.map(len(motion.tau))(motion.x[:-1].T, motion.tau.T, h)
    return np.asarray(ends).T - motion.x[1:]


def track(motion: Motion, arm: ad.Robot = ARM, dt: float = 1e-3) -> Result:
    """ad.simulate of ``arm`` under computed torque (kp = 400, kv = 40) along the cubic Hermite spline through the
    motion's knots (q and qd at each), from its first state."""
    n = arm.n
    spline = CubicHermiteSpline(motion.t, motion.x[:, :n], motion.x[:, n:])
    duration = float(motion.t[-1])

    def desired(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = min(t, duration)
        return spline(t), spline(t, 1), spline(t, 2)

    law = ad.control.ComputedTorque(400.0, 40.0)
    with warnings.catch_warnings():  # a spline trajectory runs in the Python loop: about a second here
        warnings.simplefilter("ignore", PythonLoopWarning)
        return ad.simulate(arm, law, desired, t_final=duration, dt=dt, q0=motion.x[0, :n], qd0=motion.x[0, n:])


def tracking_error(motion: Motion, run: Result) -> float:
    """The largest |q - q_opt| (rad) at the knots, the simulated run against the optimum."""
    n = motion.x.shape[1] // 2
    rows = np.searchsorted(run.t, motion.t - 1e-9)
    return float(np.abs(run.q[rows] - motion.x[:, :n]).max())


# ----- part 2: MPC ---------------------------------------------------------------------------------------------------
HOLD = np.array([0.0, 0.7854, -3.1416, 0.0, 0.7854, 0.0])
PAYLOAD, PICKUP = 2.5, 0.2  # kg at the flange, picked up at t = 0.2 s
CONTROL_PERIOD, HORIZON = 0.02, 15  # s, intervals
STATE_WEIGHT = np.concatenate([np.full(6, 1e4), np.full(6, 1e2)])  # on (q - HOLD) and qd
TORQUE_WEIGHT = 1e-2
# IPOPT from the last solution and its multipliers, its barrier parameter started small
WARM_START = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6, "ipopt.warm_start_bound_push": 1e-9,
              "ipopt.warm_start_mult_bound_push": 1e-9}  # fmt: skip


class MPC:
    """Model-predictive control of one arm about a pose: each call solves the ``horizon``-interval multiple-shooting
    problem min sum_k (x_k - x_ref)' W (x_k - x_ref) + r |tau_k - tau_ref|^2 over knots and torques (x_ref the pose
    at rest, tau_ref the torque that holds the model there, its G(pose)), the first knot fixed to the measured
    state, from the last call's solution shifted by one interval and its multipliers (warm start), and returns the
    first torque. The NLP and its solver are built once; the measured state enters as bounds on the first knot."""

    def __init__(self, step: casadi.Function, pose: np.ndarray, hold_torque: np.ndarray, limit: np.ndarray,
                 horizon: int, period: float) -> None:  # fmt: skip
        n = self.n = pose.size
        X, U = casadi.MX.sym("X", 2 * n, horizon + 1), casadi.MX.sym("U", n, horizon)
        self.reference = np.concatenate([pose, np.zeros(n)])
        error = X - self.reference
        cost = casadi.sum2(casadi.sum1(STATE_WEIGHT * error**2)) + TORQUE_WEIGHT * casadi.sumsqr(U - hold_torque)
        ends = step.map(horizon)(X[:, :-1], U, period)
        problem = {"x": casadi.veccat(X, U), "f": cost, "g": casadi.vec(ends - X[:, 1:])}
        self.solver = casadi.nlpsol("mpc", "ipopt", problem, {**IPOPT, **WARM_START})
        self.lower = np.concatenate([np.full(2 * n * (horizon + 1), -np.inf), np.tile(-limit, horizon)])
        self.upper = np.concatenate([np.full(2 * n * (horizon + 1), np.inf), np.tile(limit, horizon)])
        self.guess = np.concatenate([np.tile(self.reference, horizon + 1), np.tile(hold_torque, horizon)])
        self.horizon = horizon
        self.multipliers: dict[str, object] = {}
        self.seconds: list[float] = []

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """The first torque of the problem solved from state ``x``; the solve time is appended to ``seconds``."""
        n, horizon = self.n, self.horizon
        lower, upper = self.lower.copy(), self.upper.copy()
        lower[: 2 * n] = upper[: 2 * n] = x
        started = time.perf_counter()
        solution = self.solver(x0=self.guess, lbx=lower, ubx=upper, lbg=0.0, ubg=0.0, **self.multipliers)
        z = np.asarray(solution["x"]).ravel()
        self.multipliers = {"lam_x0": solution["lam_x"], "lam_g0": solution["lam_g"]}
        self.seconds.append(time.perf_counter() - started)
        states, torques = z[: 2 * n * (horizon + 1)], z[2 * n * (horizon + 1) :]
        self.guess = np.concatenate([states[2 * n :], states[-2 * n :], torques[n:], torques[-n:]])  # shifted
        return torques[:n]


@dataclass
class HoldRun:
    """The MPC run: times t (S + 1,), plant states x (S + 1, 2n), torques tau (S, n), solve times (S,) (s)."""

    t: np.ndarray
    x: np.ndarray
    tau: np.ndarray
    seconds: np.ndarray


def hold(duration: float = 1.0, horizon: int = HORIZON, refresh: bool = False, arm: ad.Robot = ARM) -> HoldRun:
    """MPC holding HOLD, the plant (``arm`` with its friction) picking up PAYLOAD kg at PICKUP s. The plant is the
    RK4 step of the arm (with the payload from PICKUP on) at the control period, the torque held over it.

    The MPC's model is the arm without its friction (the smoothed Coulomb law's corner at zero velocity, where a
    held arm sits, stalls IPOPT's Newton steps): the nominal arm throughout, or (``refresh``) the arm with the
    payload from the pickup on, as when the payload's mass is known."""
    n = arm.n
    plants = dynamics(arm), dynamics(arm.with_payload(PAYLOAD))
    model = arm.without_friction()
    models = [model, model.with_payload(PAYLOAD)] if refresh else [model]
    controllers = [
        MPC(dynamics(m), HOLD, m.gravity_vector(HOLD), TORQUE_LIMIT, horizon, CONTROL_PERIOD) for m in models
    ]
    steps = round(duration / CONTROL_PERIOD)
    x, states, torques, seconds = np.concatenate([HOLD, np.zeros(n)]), [], [], []
    states.append(x)
    for k in range(steps):
        loaded = k * CONTROL_PERIOD >= PICKUP - 1e-12
        controller = controllers[-1] if loaded else controllers[0]
        if controller is not controllers[0] and not controller.seconds:
            controller.guess = controllers[0].guess  # the switch keeps the warm start
        tau = controller(x)
        seconds.append(controller.seconds[-1])
        x = np.asarray(plants[loaded](x, tau, CONTROL_PERIOD)).ravel()
        states.append(x)
        torques.append(tau)
    t = np.arange(steps + 1) * CONTROL_PERIOD
    return HoldRun(t, np.array(states), np.array(torques), np.array(seconds))


# ----- figures -------------------------------------------------------------------------------------------------------
def motion_figure(motion: Motion, run: Result) -> object:
    """The joint angles, optimal (the knots) and tracked (the run), and the optimal torques against the limits."""
    import matplotlib.pyplot as plt

    n = motion.tau.shape[1]
    fig, (angles, torques) = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    for i in range(n):
        angles.plot(run.t, run.q[:, i], color=f"C{i}", lw=1.2, label=f"joint {i + 1}")
        angles.plot(motion.t, motion.x[:, i], "o", color=f"C{i}", ms=2.5)
    angles.set(xlabel="time (s)", ylabel="q (rad)", title="joint angles: tracked (lines), optimal knots (dots)")
    angles.legend(fontsize=8, ncols=2)
    edges = np.append(motion.t[:-1], motion.t[-1])
    for i in range(n):
        torques.stairs(motion.tau[:, i] / TORQUE_LIMIT[i], edges, color=f"C{i}", label=f"joint {i + 1}")
        torques.plot(run.t, run.tau[:, i] / TORQUE_LIMIT[i], color=f"C{i}", lw=0.6, alpha=0.6)
    torques.axhline(1.0, color="k", ls="--", lw=0.8)
    torques.axhline(-1.0, color="k", ls="--", lw=0.8)
    torques.set(
        xlabel="time (s)", ylabel="tau / limit", title="torques over their limits: optimal (steps), tracking (thin)"
    )
    fig.suptitle(f"PUMA 560, minimum effort in {motion.t[-1]:g} s by multiple shooting ({len(motion.tau)} intervals)"
                 ", tracked under computed torque", fontsize=10)  # fmt: skip
    return fig


def hold_figure(runs: dict[str, HoldRun]) -> object:
    """MPC runs by label: the largest |q - HOLD| over the joints, and the torques of joints 2 and 3, the pickup
    marked."""
    import matplotlib.pyplot as plt

    fig, (error, torques) = plt.subplots(1, 2, figsize=(12, 4.2), layout="constrained")
    for index, (label, run) in enumerate(runs.items()):
        n = run.tau.shape[1]
        error.plot(run.t, 1e3 * np.abs(run.x[:, :n] - HOLD).max(axis=1), color=f"C{index}", label=label)
        for joint, style in ((1, "-"), (2, "--")):
            torques.step(run.t[:-1], run.tau[:, joint], where="post", color=f"C{index}", ls=style,
                         label=f"{label}, joint {joint + 1}")  # fmt: skip
    for axis in (error, torques):
        axis.axvline(PICKUP, color="k", ls=":", lw=0.8)
        axis.set(xlabel="time (s)")
    error.set(ylabel="max |q - q_hold| (mrad)", title=f"the pose held: {PAYLOAD} kg picked up at {PICKUP} s")
    torques.set(ylabel="tau (N m)", title="MPC torque, joints 2 (solid) and 3 (dashed)")
    error.legend(fontsize=8)
    torques.legend(fontsize=7, ncols=2)
    fig.suptitle(f"MPC of the PUMA 560 ({HORIZON} intervals of {1e3 * CONTROL_PERIOD:g} ms, IPOPT, warm-started)",
                 fontsize=10)  # fmt: skip
    return fig


def main(quick: bool = False) -> None:
    intervals = 20 if quick else INTERVALS
    step = dynamics(ARM)
    motion = point_to_point(step, START, GOAL, TORQUE_LIMIT, DURATION, intervals,
                            quintic_guess(START, GOAL, DURATION, intervals, ARM), joint_limits=ARM.qlim)  # fmt: skip
    print(
        f"minimum effort, {intervals} intervals: {motion.status} after {motion.iterations} IPOPT iterations; "
        f"build {motion.build_seconds:.2f} s, solve {motion.solve_seconds:.2f} s; cost {motion.cost:.3f} N^2 m^2 s"
    )
    print(f"largest RK4 defect {np.abs(defects(step, motion)).max():.1e}, largest |tau| / limit "
          f"{np.abs(motion.tau / TORQUE_LIMIT).max():.4f}")  # fmt: skip
    run = track(motion)
    print(f"computed torque along the optimum: largest |q - q_opt| at the knots {tracking_error(motion, run):.1e} rad")
    runs = {}
    for label, refresh in (("nominal model", False), ("model refreshed at the pickup", True)):
        mpc = runs[label] = hold(0.4 if quick else 1.0, 10 if quick else HORIZON, refresh)
        offset = np.abs(mpc.x[:, : ARM.n] - HOLD).max(axis=1)
        print(f"MPC ({label}), {len(mpc.seconds)} solves: median {1e3 * np.median(mpc.seconds):.0f} ms, "
              f"max {1e3 * mpc.seconds.max():.0f} ms; largest |q - q_hold| {offset.max():.1e} rad, "
              f"at the end {offset[-1]:.1e} rad")  # fmt: skip
    if not quick:
        import matplotlib

        matplotlib.use("Agg")
        Path("out").mkdir(exist_ok=True)
        motion_figure(motion, run).savefig("out/optimal_control.png", dpi=150)
        hold_figure(runs).savefig("out/optimal_control_mpc.png", dpi=150)
        print("wrote out/optimal_control.png and out/optimal_control_mpc.png")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarser problems, no figures (for the tests)")
    main(parser.parse_args().quick)
