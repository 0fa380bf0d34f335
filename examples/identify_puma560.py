"""Identify the PUMA 560's base parameters by the workflow of armdyn.identification.excitation.

1. An excitation trajectory: a finite Fourier series per joint (Swevers, Ganseman, Tukel,
   De Schutter and Van Brussel, IEEE Trans. Robotics and Automation 13(5), 1997) whose
   coefficients minimize the condition number of the stacked base regressor, within the
   joint limits.
2. Data: the arm simulated tracking it under computed torque, with Coulomb friction by the
   exact sign law (the regressor's law), and 0.5 N m of Gaussian noise on the torques.
3. Least squares on the base regressor (armdyn.identify): the estimates, their standard
   errors, and how far each is from the true value in standard errors.

Run: .venv/bin/python examples/identify_puma560.py (about half a minute).
"""

import numpy as np
from rich.console import Console

import armdyn as ad
from armdyn.identification.excitation import (
    FourierTrajectory,
    IdentificationData,
    excitation_trajectory,
    identification_data,
)

ARM = ad.models.puma560()


def excite(iterations: int = 100) -> FourierTrajectory:
    """Step 1: the Fourier series (10 s period, 5 harmonics) after at most ``iterations`` SLSQP iterations
    on the condition number of the base regressor stacked at 100 times over one period."""
    return excitation_trajectory(ARM, period=10.0, harmonics=5, samples=100, seed=0, iterations=iterations)


def measure(trajectory: FourierTrajectory, dt: float = 2e-3) -> IdentificationData:
    """Step 2: one period simulated under computed torque, sampled every ``dt``, 0.5 N m of noise on tau."""
    return identification_data(ARM, trajectory, dt=dt, noise=0.5, seed=1)  # 10 s at 2 ms: 5001 samples


def estimate(data: IdentificationData) -> object:
    """Step 3: least squares on the base regressor (an armdyn Identification)."""
    return ad.identify(ARM, data.q, data.qd, data.qdd, data.tau)


def summary(result: object) -> str:
    """How far the estimates are from the true values, in standard errors."""
    z = result.normalized_errors  # (estimate - true value) / standard error
    return (f"{len(z)} base parameters; {np.mean(np.abs(z) <= 3):.0%} within three standard errors of the true "
            f"values; largest |error| {np.abs(z).max():.2f} standard errors; standardized errors: mean "
            f"{z.mean():.2f}, standard deviation {z.std():.2f}")  # fmt: skip


def main() -> None:
    trajectory = excite()
    print(f"excitation trajectory: cond(W) = {trajectory.condition_number:.3g} over one period")
    result = estimate(measure(trajectory))
    Console(width=140).print(result.table())
    print(summary(result))


if __name__ == "__main__":
    main()
