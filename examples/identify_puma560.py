"""Identify the PUMA 560's base parameters by the workflow of armdyn.excitation.

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
from armdyn.excitation import excitation_trajectory, identification_data

arm = ad.models.puma560()
trajectory = excitation_trajectory(arm, period=10.0, harmonics=5, samples=100, seed=0)
print(f"excitation trajectory: cond(W) = {trajectory.condition_number:.3g} over one period")

data = identification_data(arm, trajectory, dt=2e-3, noise=0.5, seed=1)  # 10 s simulated, 5001 samples
result = ad.identify(arm, data.q, data.qd, data.qdd, data.tau)
Console(width=140).print(result.table())

z = result.normalized_errors  # (estimate - true value) / standard error
print(f"{len(z)} base parameters; {np.mean(np.abs(z) <= 3):.0%} within three standard errors of the true values; "
      f"largest |error| {np.abs(z).max():.2f} standard errors; standardized errors: mean {z.mean():.2f}, "
      f"standard deviation {z.std():.2f}")  # fmt: skip
