"""Friction laws for identification: each a set of regressor columns per joint, linear in some
parameters and (for the Stribeck and sigmoid laws) nonlinear in others.

F_j(qd_j), joint side, added to the rigid-body torque (eq. (3.3.2), F(qd) = Fv qd + Fd(qd)):

- ``viscous``: Fv qd;
- ``coulomb``: Fv qd + Fc+ [qd > 0] + Fc- [qd < 0] (asymmetric Coulomb; Tc- <= 0 <= Tc+);
- ``stribeck``: the Coulomb law plus Fs exp(-(qd / vs)^2) sign(qd), nonlinear in vs;
- ``sigmoid``: Fv qd + A (s(alpha (qd + shift)) - s(alpha shift)) with s the logistic function, the
  law of Gaz, Cognetti, Oliva, Robuffo Giordano and De Luca, "Dynamic identification of the Franka
  Emika Panda robot with retrieval of feasible parameters using penalty-based optimization", IEEE
  RA-L 4(4), 2019; nonlinear in alpha and shift.

The nonlinear parameters are fitted by variable projection (Golub and Pereyra, "The
differentiation of pseudo-inverses and nonlinear least squares problems whose variables
separate", SIAM J. Numer. Anal. 10(2), 1973): for given nonlinear parameters every other
parameter, rigid body included, is the linear least-squares solution, so only the nonlinear ones
are searched (``fit_nonlinear``). The laws are the ones Link carries (``viscous``, ``coulomb``,
``stribeck``, ``sigmoid``), so an identified arm simulates with the friction it was fitted with.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armdyn.dynamics.friction import logistic_vector
from armdyn.errors import ModelError

LAWS = ("viscous", "coulomb", "stribeck", "sigmoid")


@dataclass(frozen=True)
class FrictionLaw:
    """One friction law for every joint of an arm.

    Parameters
    ----------
    name : str
        One of LAWS.
    nonlinear : numpy.ndarray
        The nonlinear parameters, (n, k): none for viscous and Coulomb (k = 0), vs for Stribeck
        (k = 1), alpha and shift for the sigmoid (k = 2).
    """

    name: str
    nonlinear: np.ndarray

    @property
    def linear_names(self) -> tuple[str, ...]:
        """The linear parameters of one joint, in the order of ``columns``."""
        return {
            "viscous": ("Fv",),
            "coulomb": ("Fv", "Fc+", "Fc-"),
            "stribeck": ("Fv", "Fc+", "Fc-", "Fs"),
            "sigmoid": ("Fv", "A"),
        }[self.name]

    @property
    def nonlinear_names(self) -> tuple[str, ...]:
        return {"viscous": (), "coulomb": (), "stribeck": ("vs",), "sigmoid": ("alpha", "shift")}[self.name]

    def columns(self, qd: np.ndarray) -> np.ndarray:
        """The law's columns at joint velocities qd: F_j = columns[..., j, :] @ p_j.

        Parameters
        ----------
        qd : array_like
            Joint velocities, (..., n).

        Returns
        -------
        numpy.ndarray
            (..., n, k): each joint's columns, in the order of ``linear_names``.
        """
        return law_columns(self.name, np.asarray(qd, dtype=float), self.nonlinear)

    def lower_bounds(self) -> np.ndarray:
        """Lower bounds of one joint's linear parameters (the sign rules Fv, Fc+, Fs, A >= 0).

        Returns
        -------
        numpy.ndarray
            (k,), -inf where there is none.
        """
        rule = {"Fv": 0.0, "Fc+": 0.0, "Fc-": -np.inf, "Fs": 0.0, "A": 0.0}
        return np.array([rule[name] for name in self.linear_names])

    def upper_bounds(self) -> np.ndarray:
        """Upper bounds of one joint's linear parameters (the sign rule Fc- <= 0).

        Returns
        -------
        numpy.ndarray
            (k,), inf where there is none.
        """
        rule = {"Fv": np.inf, "Fc+": np.inf, "Fc-": 0.0, "Fs": np.inf, "A": np.inf}
        return np.array([rule[name] for name in self.linear_names])

    def link_fields(self, linear: np.ndarray) -> list[dict[str, object]]:
        """Link keywords (joint side, gear 1) of each joint: viscous, coulomb, stribeck, sigmoid.

        Parameters
        ----------
        linear : array_like
            (n, k): each joint's linear parameters, in the order of ``linear_names``.

        Returns
        -------
        list of dict
            One mapping of Link keywords per joint.
        """
        fields: list[dict[str, object]] = []
        for j, p in enumerate(np.asarray(linear, dtype=float)):
            values = dict(zip(self.linear_names, p, strict=True))
            joint: dict[str, object] = {"viscous": float(values["Fv"])}
            if "Fc+" in values:
                joint["coulomb"] = (float(values["Fc+"]), float(values["Fc-"]))
            if self.name == "stribeck":
                joint["stribeck"] = (float(values["Fs"]), float(self.nonlinear[j, 0]))
            if self.name == "sigmoid":
                joint["sigmoid"] = (float(values["A"]), float(self.nonlinear[j, 0]), float(self.nonlinear[j, 1]))
            fields.append(joint)
        return fields


def sigmoid_friction(qd: np.ndarray, alpha: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """s(alpha (qd + shift)) - s(alpha shift): Gaz et al.'s law (2019) per unit amplitude A; 0 at rest.

    Parameters
    ----------
    qd : numpy.ndarray
        Joint velocities.
    alpha, shift : numpy.ndarray
        The law's slope and shift, broadcasting with qd.

    Returns
    -------
    numpy.ndarray
        The law per unit amplitude.
    """
    return logistic_vector(alpha * (qd + shift)) - logistic_vector(alpha * shift)


def stribeck_friction(qd: np.ndarray, vs: np.ndarray) -> np.ndarray:
    """exp(-(qd / vs)^2) sign(qd): the Stribeck excess per unit breakaway torque Fs.

    Parameters
    ----------
    qd : numpy.ndarray
        Joint velocities.
    vs : numpy.ndarray
        The Stribeck velocities, broadcasting with qd.

    Returns
    -------
    numpy.ndarray
        The excess per unit Fs.
    """
    return np.exp(-((qd / vs) ** 2)) * np.sign(qd)


def nonlinear_column(name: str, qd: np.ndarray, parameters: np.ndarray) -> np.ndarray:
    """The law's nonlinear term per unit amplitude.

    Parameters
    ----------
    name : str
        "stribeck" or "sigmoid".
    qd : numpy.ndarray
        Joint velocities (...).
    parameters : numpy.ndarray
        (..., k'): the nonlinear parameters, broadcasting with qd.

    Returns
    -------
    numpy.ndarray
        The term, shape of qd.
    """
    if name == "stribeck":
        return stribeck_friction(qd, parameters[..., 0])
    return sigmoid_friction(qd, parameters[..., 0], parameters[..., 1])


def nonlinear_derivatives(name: str, qd: np.ndarray, parameters: np.ndarray) -> np.ndarray:
    """d(nonlinear term)/d(each nonlinear parameter) at qd (...), parameters (..., k'): (..., k').

    Sigmoid, g = s(alpha (qd + shift)) - s(alpha shift) with s' = s (1 - s): dg/dalpha =
    s'(alpha (qd + shift)) (qd + shift) - s'(alpha shift) shift, dg/dshift = alpha (s'(alpha (qd + shift))
    - s'(alpha shift)). Stribeck, h = exp(-(qd/vs)^2) sign(qd): dh/dvs = 2 qd^2 / vs^3 h.

    Parameters
    ----------
    name : str
        "stribeck" or "sigmoid".
    qd : numpy.ndarray
        Joint velocities (...).
    parameters : numpy.ndarray
        (..., k'): the nonlinear parameters, broadcasting with qd.

    Returns
    -------
    numpy.ndarray
        (..., k'): the derivatives.
    """
    if name == "stribeck":
        vs = parameters[..., 0]
        return (2 * qd**2 / vs**3 * stribeck_friction(qd, vs))[..., None]
    alpha, shift = parameters[..., 0], parameters[..., 1]
    moving, rest = logistic_vector(alpha * (qd + shift)), logistic_vector(alpha * shift)
    slope_moving, slope_rest = moving * (1 - moving), rest * (1 - rest)
    d_alpha = slope_moving * (qd + shift) - slope_rest * shift
    d_shift = alpha * (slope_moving - slope_rest)
    return np.stack([d_alpha, d_shift], axis=-1)


def law_columns(name: str, qd: np.ndarray, nonlinear: np.ndarray) -> np.ndarray:
    """The columns of the named law.

    Parameters
    ----------
    name : str
        One of LAWS.
    qd : numpy.ndarray
        Joint velocities, (..., n).
    nonlinear : numpy.ndarray
        (n, k'): the nonlinear parameters (k' = 0 for the viscous and Coulomb laws).

    Returns
    -------
    numpy.ndarray
        (..., n, k): Fv's column, then Fc+ and Fc- (Coulomb, Stribeck), then the nonlinear term.

    Raises
    ------
    armdyn.ModelError
        When ``name`` is not one of LAWS.
    """
    if name not in LAWS:
        raise ModelError(f"friction law must be one of {', '.join(LAWS)}, got {name!r}")
    parts = [qd]
    if name in ("coulomb", "stribeck"):
        parts += [(qd > 0).astype(float), (qd < 0).astype(float)]
    if name in ("stribeck", "sigmoid"):
        parts.append(nonlinear_column(name, qd, nonlinear))
    return np.stack(parts, axis=-1)


def initial_nonlinear(name: str, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start and bounds of the nonlinear parameters from the joints' speeds qd (N, n).

    The transition of the sigmoid (width about 4 / alpha) and the Stribeck velocity vs start at a
    twentieth of each joint's largest speed and are searched between 1/2000 and the whole range;
    the sigmoid's shift within a tenth of the range either side of zero.

    Parameters
    ----------
    name : str
        One of LAWS.
    qd : numpy.ndarray
        (N, n) joint velocities.

    Returns
    -------
    tuple of numpy.ndarray
        The start, lower and upper bounds, each (n, k').
    """
    top = np.maximum(np.max(np.abs(qd), axis=0), 1e-9)
    n = qd.shape[-1]
    if name == "stribeck":
        return (top / 20)[:, None], (top / 2000)[:, None], top[:, None]
    if name == "sigmoid":
        start = np.column_stack([80 / top, np.zeros(n)])
        lower = np.column_stack([4 / top, -top / 10])
        upper = np.column_stack([8000 / top, top / 10])
        return start, lower, upper
    return np.zeros((n, 0)), np.zeros((n, 0)), np.zeros((n, 0))


def fit_nonlinear(
    name: str,
    fixed: np.ndarray,
    y: np.ndarray,
    qd: np.ndarray,
    through: Callable[[np.ndarray], np.ndarray] | None = None,
) -> FrictionLaw:
    """The law's nonlinear parameters by variable projection (Golub and Pereyra 1973).

    For given nonlinear parameters theta the linear ones (every column of ``fixed`` and the law's
    amplitudes) are the least-squares solution; the residual projected off ``fixed``'s columns is
    minimized over theta alone, with Kaufman's approximation of its Jacobian ("A variable projection
    method for solving separable nonlinear least squares problems", BIT 15, 1975).

    Parameters
    ----------
    name : str
        One of LAWS.
    fixed : numpy.ndarray
        (N n, p): every column that does not depend on the nonlinear parameters (rigid body, motor
        inertia, offsets, the law's own linear columns), rows sample by sample, joints within.
    y : numpy.ndarray
        (N n,): the measured torques of those rows.
    qd : numpy.ndarray
        (M, n): the joint velocities the law is evaluated at (M = N without ``through``).
    through : callable, optional
        Maps values (M, n, ...) at those velocities to (N, n, ...) at the rows' samples: the filter the
        torques went through, and decimation (``Prepared.filtered_as_torques``); default none.

    Returns
    -------
    FrictionLaw
        The law with its fitted nonlinear parameters (a law without any is returned as it is).
    """
    from scipy.optimize import least_squares

    qd = np.asarray(qd, dtype=float)
    n = qd.shape[1]
    start, lower, upper = initial_nonlinear(name, qd)
    if start.shape[1] == 0:
        return FrictionLaw(name, start)
    apply = through if through is not None else (lambda values: values)
    Q, _ = np.linalg.qr(fixed)
    projected_y = y - Q @ (Q.T @ y)
    k = start.shape[1]
    diagonal = np.eye(n)

    def spread(per_joint: np.ndarray) -> np.ndarray:
        """(N, n, m) values of each joint -> (N n, n m) columns, each joint's on its own rows only."""
        samples, _, m = per_joint.shape
        return (per_joint[:, :, None, :] * diagonal[None, :, :, None]).reshape(samples * n, n * m)

    def solve(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        columns = spread(apply(nonlinear_column(name, qd, theta.reshape(n, k)))[..., None])
        columns -= Q @ (Q.T @ columns)
        amplitude, *_ = np.linalg.lstsq(columns, projected_y, rcond=None)
        return projected_y - columns @ amplitude, amplitude

    def residual(theta: np.ndarray) -> np.ndarray:
        return solve(theta)[0]

    def jacobian(theta: np.ndarray) -> np.ndarray:
        """-P (dF/dtheta) a, Kaufman's approximation of the projected residual's Jacobian."""
        _, amplitude = solve(theta)
        slopes = apply(nonlinear_derivatives(name, qd, theta.reshape(n, k)))  # (N, n, k)
        J = -spread(slopes * amplitude[None, :, None])
        return J - Q @ (Q.T @ J)

    solution = least_squares(
        residual, start.ravel(), jac=jacobian, bounds=(lower.ravel(), upper.ravel()), x_scale="jac"
    )
    return FrictionLaw(name, solution.x.reshape(n, -1))
