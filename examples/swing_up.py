"""What derivatives are for: the RR arm swung up from hanging to upright in 2 s with minimum torque,
then held there by LQR (Section 3.4; Carpentier and Mansard 2018 for the derivatives).

Trajectory optimization by multiple shooting: the torque is held over 40 intervals of 50 ms, each
integrated by 5 RK4 steps of 10 ms, and the states at the 39 inner knots are variables too; the
cost is the integral of |tau|^2, the constraints each interval ending on the next knot (the last
on the upright state at 2 s) and every torque within +-60 N m. The constraints' Jacobian comes
from statespace.rk4_step's exact step derivatives (A_d, B_d), chained over each interval.
Starting from the inverse dynamics of a quintic swing, scipy's SLSQP solves the problem with it,
and again with finite-difference gradients for comparison. Then
statespace.linearize about the upright arm gives A and B, python-control's LQR a gain K, and
ad.simulate holds the arm upright from a 0.2 rad push.
Run: .venv/bin/python examples/swing_up.py
"""

from __future__ import annotations

import time
import warnings

import numpy as np
from scipy.optimize import minimize

import armdyn as ad
from armdyn import statespace
from armdyn.simulation import PythonLoopWarning, Result

ARM = ad.models.two_link_planar(1.0, 1.0, 1.0, 1.0, g=9.8)
HANGING, UPRIGHT = np.array([-np.pi / 2, 0.0, 0.0, 0.0]), np.array([np.pi / 2, 0.0, 0.0, 0.0])
INTERVALS, SUBSTEPS, STEP = 40, 5, 0.01  # 40 x 5 x 10 ms = 2 s
LIMIT = 60.0  # N m: the torque bound of every interval


def interval(x: np.ndarray, tau: np.ndarray, derivatives: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One interval: SUBSTEPS RK4 steps from x under tau held, and (with derivatives) d x_end/d x, d x_end/d tau,
    the steps' (A_d, B_d) chained: A = A_5 ... A_1, B = sum of A_5 ... A_(s+1) B_s."""
    A, B = np.eye(4), np.zeros((4, 2))
    for _ in range(SUBSTEPS):
        if derivatives:
            x, A_d, B_d = statespace.rk4_step(ARM, x[:2], x[2:], tau, STEP)
            A, B = A_d @ A, A_d @ B + B_d
        else:
            x = _rk4(x, tau)
    return x, A, B


def _rk4(x: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """One RK4 step on the compiled forward dynamics (the same step rk4_step takes, without derivatives)."""

    def rate(state: np.ndarray) -> np.ndarray:
        return np.concatenate([state[2:], ARM.forward_dynamics(state[:2], state[2:], tau)])

    k1 = rate(x)
    k2 = rate(x + 0.5 * STEP * k1)
    k3 = rate(x + 0.5 * STEP * k2)
    k4 = rate(x + STEP * k3)
    return x + STEP / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def unpack(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Multiple shooting's variables: the torques (INTERVALS, 2), then the states at the inner knots; the
    first knot is HANGING and the last UPRIGHT."""
    torques = z[: 2 * INTERVALS].reshape(INTERVALS, 2)
    knots = np.vstack([HANGING, z[2 * INTERVALS :].reshape(INTERVALS - 1, 4), UPRIGHT])
    return torques, knots


def defects(z: np.ndarray) -> np.ndarray:
    """Continuity: each interval's end minus the next knot, (INTERVALS * 4,)."""
    torques, knots = unpack(z)
    return np.concatenate([interval(knots[k], torques[k], False)[0] - knots[k + 1] for k in range(INTERVALS)])


def defects_jacobian(z: np.ndarray) -> np.ndarray:
    """d defects / d z from each interval's chained step derivatives (block-sparse, stored dense)."""
    torques, knots = unpack(z)
    jacobian = np.zeros((4 * INTERVALS, z.size))
    for k in range(INTERVALS):
        _, A, B = interval(knots[k], torques[k], True)
        rows = slice(4 * k, 4 * k + 4)
        jacobian[rows, 2 * k : 2 * k + 2] = B
        if k > 0:  # the knot this interval starts from
            start = 2 * INTERVALS + 4 * (k - 1)
            jacobian[rows, start : start + 4] = A
        if k < INTERVALS - 1:  # the knot it must reach
            end = 2 * INTERVALS + 4 * k
            jacobian[rows, end : end + 4] = -np.eye(4)
    return jacobian


def first_guess() -> np.ndarray:
    """The inverse dynamics' torques along a quintic from hanging to upright, and the quintic's states at the knots."""
    from armdyn.trajectories import Quintic

    span = SUBSTEPS * STEP
    path = Quintic(HANGING[:2], UPRIGHT[:2], 0.0, INTERVALS * span)
    torques = [ARM.inverse_dynamics(*path((k + 0.5) * span, 2)) for k in range(INTERVALS)]
    knots = [np.concatenate(path(k * span, 2)[:2]) for k in range(1, INTERVALS)]
    return np.concatenate([np.ravel(torques), np.ravel(knots)])


def optimize(analytic: bool) -> tuple[object, float]:
    """SLSQP on min sum |tau|^2 dt subject to the defects vanishing, with analytic or finite-difference gradients."""
    hold = SUBSTEPS * STEP

    def cost(z: np.ndarray) -> float:
        return float(hold * np.sum(z[: 2 * INTERVALS] ** 2))

    def cost_gradient(z: np.ndarray) -> np.ndarray:
        gradient = np.zeros_like(z)
        gradient[: 2 * INTERVALS] = 2 * hold * z[: 2 * INTERVALS]
        return gradient

    constraint = {"type": "eq", "fun": defects} | ({"jac": defects_jacobian} if analytic else {})
    guess = first_guess()
    bounds = [(-LIMIT, LIMIT)] * (2 * INTERVALS) + [(None, None)] * (guess.size - 2 * INTERVALS)
    start = time.perf_counter()
    result = minimize(cost, guess, jac=cost_gradient if analytic else None, bounds=bounds, constraints=[constraint],
                      method="SLSQP", options={"maxiter": 1000, "ftol": 1e-6})  # fmt: skip
    return result, time.perf_counter() - start


def upright_run(push: float = 0.2, t_final: float = 3.0) -> Result:
    """LQR about the upright arm (tau0 = G), from statespace.linearize: the run from ``push`` rad off upright
    (joint 1 pushed by +push, joint 2 by -push)."""
    import control

    tau0 = ARM.gravity_vector(UPRIGHT[:2])
    model = statespace.linearize(ARM, UPRIGHT[:2], UPRIGHT[2:], tau0)
    gain, _, _ = control.lqr(model.A, model.B, np.diag([100.0, 100.0, 1.0, 1.0]), np.eye(2))

    def lqr(t: float, q: np.ndarray, qd: np.ndarray, *_: object) -> np.ndarray:
        return tau0 - gain @ (np.concatenate([q, qd]) - UPRIGHT)

    with warnings.catch_warnings():  # a 3 s run of a NumPy law: the Python loop costs nothing worth compiling
        warnings.simplefilter("ignore", PythonLoopWarning)
        return ad.simulate(ARM, lqr, None, t_final=t_final, q0=UPRIGHT[:2] + [push, -push])


def hold_upright() -> float:
    """The largest |q - q_up| after 3 s from a 0.2 rad push, under LQR about the upright arm (``upright_run``)."""
    run = upright_run()
    return float(np.abs(run.q[-1] - UPRIGHT[:2]).max())


def main() -> None:
    interval(HANGING, np.zeros(2), True)  # load the compiled kernels
    for analytic in (True, False):
        result, seconds = optimize(analytic)
        miss = np.abs(defects(result.x)).max()
        label = "analytic gradients" if analytic else "finite differences"
        print(f"{label}: {result.message.strip()} after {result.nit} iterations, {seconds:.1f} s; "
              f"cost {result.fun:.4f} N^2 m^2 s, largest defect {miss:.1e}")  # fmt: skip
    print(f"LQR about the upright arm: |q - q_up| after 3 s from a 0.2 rad push = {hold_upright():.1e} rad")


if __name__ == "__main__":
    main()
