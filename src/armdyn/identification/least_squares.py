"""Least squares on the base parameters: tau = W_b(q, qd, qdd) phi_b (Table 3.3.1, property 9)
stacked over samples, with honest standard errors and checks of excitation and friction.

``identify`` refuses samples that do not excite the base parameters: a stacked base regressor of
numerical rank below the number r of base parameters, or with a condition number above
MAX_CONDITION, is a ModelError; a full-rank one whose condition number exceeds POOR_CONDITION gives
a PoorExcitationWarning and the estimates.

Friction in W is the exact Coulomb sign law (the columns of Fc+ and Fc- are qd > 0 and qd < 0).
Torques whose friction near zero velocity follows another law (simulate's smoothed Coulomb
friction, with its default coulomb_smoothing="auto"; stiction on a real arm) are not explained by W
there, and bias every estimate: ``identify`` leaves out joint j's equation at the samples where
|qd_j| < velocity_band, and warns (FrictionMisfitWarning) when the residuals of a joint's slowest
samples are much larger than the rest. ``armdyn.identification.excitation`` generates data that W
explains (simulated with the exact sign law).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from armdyn import inputs
from armdyn.dynamics.regressor import BaseParameters, _check_arm, _flag, base_parameters
from armdyn.errors import ModelError
from armdyn.model import ArmModel

MAX_CONDITION = 1e10
"""``identify`` refuses a stacked base regressor with a larger condition number: the samples
do not excite the base parameters (the estimates would be ruled by rounding and noise)."""
POOR_CONDITION = 1e5
"""``identify`` warns (PoorExcitationWarning) above this condition number; well-excited
trajectories give tens to a few thousand."""


MISFIT_BAND = 0.05
"""``identify``'s friction check compares the residuals of joint j at |qd_j| below this fraction
of its largest speed with those of the other samples."""
MISFIT_RATIO = 4.0
"""``identify`` warns (FrictionMisfitWarning) when the mean square residual of a joint's slow
samples exceeds this multiple of the rest's (at least MISFIT_SAMPLES of each): for Gaussian
noise with as few as 20 slow samples, a chance of about 1e-8 (the F(20, 1000) distribution)."""
MISFIT_SAMPLES = 20


class PoorExcitationWarning(UserWarning):
    """The samples excite the base parameters poorly: the estimates are sensitive to noise."""


class FrictionMisfitWarning(UserWarning):
    """The torques near zero joint velocity do not follow the regressor's Coulomb sign law: the
    estimates are biased (leave those samples out with ``identify``'s velocity_band)."""


@dataclass
class Identification:
    """Least-squares estimate of the base parameters from measured torques.

    Made by ``identify``.

    Parameters
    ----------
    base : BaseParameters
        The base parameters estimated.
    phi : numpy.ndarray
        The estimate of phi_base, (r,).
    standard_errors : numpy.ndarray
        The standard error of each estimate, (r,), from each joint's own residual variance.
    condition_number : float
        The condition number of the stacked base regressor.
    residual_rms : float
        The root-mean-square torque residual over the equations used.
    samples : int
        The number of samples N given.
    left_out : int
        The joint equations left out (|qd_j| < velocity_band), of the N n.
    """

    base: BaseParameters
    phi: np.ndarray
    standard_errors: np.ndarray
    condition_number: float
    residual_rms: float
    samples: int
    left_out: int = 0

    @property
    def names(self) -> list[str]:
        return self.base.names

    @property
    def normalized_errors(self) -> np.ndarray:
        """(estimate - model value) / standard error, per base parameter.

        For data generated from the arm's own model (``armdyn.identification.excitation.identification_data``)
        these are standard normal when the standard errors are honest; for measured data they
        say how far the estimates are from the arm's nominal values.

        Returns
        -------
        numpy.ndarray
            (phi - base.phi) / standard_errors, (r,); infinite where a standard error is 0.
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            return (self.phi - self.base.phi) / self.standard_errors

    def table(self) -> object:
        """A rich Table: each base parameter, its estimate, standard error and model value.

        Returns
        -------
        rich.table.Table
            One line per base parameter.
        """
        from rich.table import Table

        table = Table(
            title=f"Identified base parameters ({self.samples} samples, cond(W) = {self.condition_number:.3g})"
        )
        for column in ("base parameter", "estimate", "std. error", "model value"):
            table.add_column(column, justify="right" if column != "base parameter" else "left")
        for name, value, error, model in zip(self.names, self.phi, self.standard_errors, self.base.phi, strict=True):
            table.add_row(name, f"{value:.6g}", f"{error:.2g}", f"{model:.6g}")
        return table


def identify(
    arm: ArmModel,
    q: object,
    qd: object,
    qdd: object,
    tau: object,
    drives: bool = True,
    velocity_band: float = 0.0,
) -> Identification:
    """Estimate the base parameters from samples (q, qd, qdd, tau), each (N, n), by least squares.

    tau = W_base(q, qd, qdd) phi_base (Table 3.3.1, property 9) stacked over the samples
    and solved for phi_base (by QR of [W_base tau]). The condition number of the stacked
    base regressor says how well the samples excite the parameters: samples that leave
    some base parameter unexcited (numerical rank of W_base below r, NumPy's matrix_rank
    rule, or a condition number above MAX_CONDITION = 1e10) are refused, and a condition
    number above POOR_CONDITION = 1e5 gives a PoorExcitationWarning.

    Standard errors: the square roots of the diagonal of (W^T W)^-1 W^T S W (W^T W)^-1, S
    holding each joint's own residual variance sigma_j^2 on that joint's equations (its
    residual sum of squares over its equations less their leverage), so that joints measured
    with different noise (a base joint's 1 N m, a wrist's 0.01 N m) each count as they are
    (a pooled sigma^2 (W^T W)^-1 makes some standard errors ten times too large and others
    twice too small then); with the same noise on every joint the two agree. They are
    honest, about one standard deviation of the estimate, when the model explains the torques
    up to independent noise: errors in q, qd or qdd are not counted.

    Friction in W is the exact Coulomb sign law. Friction that follows another law near zero
    velocity (simulate's smoothed Coulomb friction, stiction) biases every estimate, with
    standard errors too small to show it. ``velocity_band`` leaves out joint j's equation at
    the samples where |qd_j| < velocity_band; simulate's default smoothing, tanh(qd / eps)
    with eps of a few mrad/s, is the sign law to 2 Tc exp(-2 band / eps) beyond the band,
    about 1e-10 Tc for a band of 12 eps (0.1 rad/s for the PUMA 560 at dt = 1 ms). With
    ``drives`` the residuals of each joint's samples slower than MISFIT_BAND = 5% of its
    largest speed are compared with the rest's, and a mean square more than MISFIT_RATIO = 4
    times larger gives a FrictionMisfitWarning.

    Parameters
    ----------
    arm : ArmModel
        The arm whose base parameters are estimated (its structure; its own values are
        reported alongside for comparison).
    q, qd, qdd : array_like
        Measured joint positions, velocities and accelerations, (N, n).
    tau : array_like
        Measured joint torques, (N, n).
    drives : bool, optional
        True (default) also estimates the friction and motor parameters; False only the
        rigid-body ones.
    velocity_band : float, optional
        Joint speed (rad/s or m/s) below which a joint's equation is left out; default 0,
        every equation used.

    Returns
    -------
    Identification
        The estimate, its standard errors, the condition number and the residual.

    Warns
    -----
    PoorExcitationWarning
        When the condition number of the stacked base regressor is above POOR_CONDITION.
    FrictionMisfitWarning
        When a joint's residuals near zero velocity are much larger than elsewhere: its
        friction there is not the Coulomb sign law, and the estimates are biased.

    Raises
    ------
    armdyn.ModelError
        When a sample array is not real numbers of shape (..., n) or holds NaN or infinity,
        when q, qd, qdd and tau do not all have the same shape, when ``velocity_band`` is not
        a number >= 0, when there are too few samples (the N n equations used must outnumber
        the r base parameters), or when the samples do not excite the base parameters (rank
        of the stacked base regressor below r, or condition number above MAX_CONDITION); the
        message gives the rank and condition number.
    TypeError
        When ``arm`` is not an armdyn arm (an ArmModel) or has symbolic (SymPy) parameters, or
        when ``drives`` is not a bool.
    """
    from scipy.linalg import solve_triangular

    _check_arm(arm)
    where = f" for '{arm.name}'"
    names = ("q", "qd", "qdd", "tau")
    arrays = [inputs.state(value, arm.n, name, where) for name, value in zip(names, (q, qd, qdd, tau), strict=True)]
    if len({a.shape for a in arrays}) > 1:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in zip(names, arrays, strict=True))
        raise ModelError(f"q, qd, qdd and tau must hold the same samples, each (N, {arm.n}); got {shapes}")
    drives = _flag(drives, "drives")
    band = _band(velocity_band)
    base = base_parameters(arm, drives=drives)
    r, n = len(base), arm.n
    samples = int(np.prod(arrays[0].shape[:-1]))
    speed = np.abs(arrays[1]).reshape(-1)
    keep = speed >= band if band > 0 else np.ones(speed.shape, dtype=bool)
    if np.count_nonzero(keep) <= r:
        left = f" ({speed.size - np.count_nonzero(keep)} left out by velocity_band = {band:g})" if band > 0 else ""
        raise ModelError(
            f"identification needs more than {r} joint equations ({r // n + 1} samples of {n} joints), got "
            f"{np.count_nonzero(keep)} from {samples} samples{left}"
        )
    W = base.regressor(*arrays[:3]).reshape(-1, r)[keep]
    y = arrays[3].reshape(-1)[keep]
    joint = np.tile(np.arange(n), samples)[keep]
    # [W y] = Q R: R[:r, :r] has W's singular values (NumPy's stub types mode "r" as returning Q and R; it returns R)
    R: np.ndarray = np.linalg.qr(np.column_stack([W, y]), mode="r")  # type: ignore[assignment]
    singular = np.linalg.svd(R[:r, :r], compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    rank = int(np.sum(singular > singular[0] * max(W.shape) * np.finfo(float).eps)) if singular[0] > 0 else 0
    if rank < r or condition > MAX_CONDITION:
        raise ModelError(
            f"the samples do not excite the {r} base parameters of '{arm.name}': the stacked base regressor "
            f"has rank {rank} of {r} and condition number {condition:.3g} (the limit is {MAX_CONDITION:.0e}); "
            "move every joint over a wide range with varied velocities and accelerations"
        )
    if condition > POOR_CONDITION:
        warnings.warn(
            f"the samples excite the base parameters of '{arm.name}' poorly: the stacked base regressor has "
            f"condition number {condition:.3g} (above {POOR_CONDITION:.0e}); the estimates are sensitive to "
            "noise (see their standard errors)",
            PoorExcitationWarning,
            stacklevel=2,
        )
    phi = solve_triangular(R[:r, :r], R[:r, r])
    residual = y - W @ phi
    inverse = solve_triangular(R[:r, :r], np.eye(r))  # (W^T W)^-1 = R^-1 R^-T
    standard_errors = _standard_errors(W, R[:r, :r], inverse, residual, joint, n)
    if drives:
        _check_friction(arm, speed[keep], residual, joint, y)
    residual_rms = abs(float(R[r, r])) / np.sqrt(W.shape[0])
    return Identification(
        base, phi, standard_errors, condition, residual_rms, samples, int(speed.size - np.count_nonzero(keep))
    )


def _band(value: object) -> float:
    """velocity_band as a float >= 0, or a ModelError naming it."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(f"velocity_band must be a number >= 0 (rad/s or m/s), got {value!r}")
    if not (np.isfinite(value) and value >= 0):
        raise ModelError(f"velocity_band must be a finite number >= 0 (rad/s or m/s), got {value!r}")
    return float(value)


def _standard_errors(
    W: np.ndarray, R: np.ndarray, inverse: np.ndarray, residual: np.ndarray, joint: np.ndarray, n: int
) -> np.ndarray:
    """sqrt(diag(R^-1 A^T S A R^-T)) with A = W R^-1 (orthonormal columns) and S each joint's residual
    variance on its equations: RSS_j over (equations of joint j less their leverage, sum_j = rows - r)."""
    from scipy.linalg import solve_triangular

    rows, r = W.shape
    A = solve_triangular(R, W.T, trans="T").T  # W R^-1, computed without squaring W's condition number
    leverage = np.einsum("ij,ij->i", A, A)  # the diagonal of the hat matrix, summing to r
    pooled = float(residual @ residual) / (rows - r)
    variance = np.full(n, pooled)
    for j in range(n):
        mine = joint == j
        freedom = np.count_nonzero(mine) - leverage[mine].sum()
        if freedom >= 1.0:
            variance[j] = float(residual[mine] @ residual[mine]) / freedom
    weighted = A * np.sqrt(variance[joint])[:, None]
    middle = weighted.T @ weighted  # A^T S A
    return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", inverse, middle, inverse), 0.0))


def _check_friction(arm: ArmModel, speed: np.ndarray, residual: np.ndarray, joint: np.ndarray, y: np.ndarray) -> None:
    """A FrictionMisfitWarning naming the joints whose slow samples fit much worse than the rest."""
    found = []
    for j in range(arm.n):
        mine = joint == j
        if not mine.any():
            continue
        speeds, errors = speed[mine], residual[mine]
        slow = speeds < MISFIT_BAND * speeds.max()
        if min(np.count_nonzero(slow), np.count_nonzero(~slow)) < MISFIT_SAMPLES:
            continue
        inside, outside = np.mean(errors[slow] ** 2), np.mean(errors[~slow] ** 2)
        scale = 1e-9 * (1.0 + np.sqrt(np.mean(y[mine] ** 2)))  # rounding alone never warns
        if inside > MISFIT_RATIO * outside and np.sqrt(inside) > scale:
            found.append(
                f"'{arm.joint_names[j]}' {np.sqrt(inside):.3g} against {np.sqrt(outside):.3g} N m at "
                f"|qd| < {MISFIT_BAND * speeds.max():.3g}"
            )
    if found:
        warnings.warn(
            f"the torques of '{arm.name}' near zero velocity do not follow the Coulomb sign law of the "
            f"regressor (residual rms {'; '.join(found)}): friction there follows another law (simulate's "
            "smoothed Coulomb friction, or stiction) and every estimate is biased; leave those samples out with "
            "velocity_band (0.1 rad/s is 12 times simulate's default smoothing at dt = 1 ms), or simulate "
            "with coulomb_smoothing=0",
            FrictionMisfitWarning,
            stacklevel=3,
        )
