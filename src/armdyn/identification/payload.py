"""Payload identification: the ten inertial parameters of a tool from a loaded and an unloaded run.

A tool rigidly fixed to link L adds its parameters phi_L (mass, first moment, inertia about the
link-frame origin, in link-frame axes: one link's block of ``armdyn.dynamics.regressor.parameters``)
to that link's, so the arm carrying it follows (Table 3.3.1, property 9)::

    unloaded:  W_b(q, qd, qdd) phi_b                          = tau_u
    loaded:    W_b(q, qd, qdd) phi_b + W_L(q, qd, qdd) phi_L  = tau_l

with W_b the arm's base regressor and W_L the ten columns of link L in the full regressor W. The
two runs stacked are solved together for [phi_b, phi_L] by least squares (Atkeson, An and
Hollerbach, "Estimation of inertial parameters of manipulator loads and links", IJRR 5(3), 1986;
Khalil and Dombre, *Modeling, Identification and Control of Robots*, 2002, 12.6): the arm's own
base parameters, friction included, are estimated alongside and need not be known. Without an
unloaded run, the arm's model stands in for it: tau_l - W phi_arm = W_L phi_L.

From phi_L come the mass m, the centre of mass c = (m c) / m and the inertia about the centre of
mass I_C = I_O - m ((c . c) 1 - c c^T), each with standard errors propagated from the estimate's
covariance by the delta method, and ``PayloadEstimate.apply`` puts the payload on an arm
(``ArmModel.with_payload``).

``stacked_least_squares`` is the estimator shared with ``armdyn.identification.gains``: ordinary
least squares with standard errors from each group's own residual variance (a joint of a run),
and a refusal of equations that do not excite the unknowns.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from armdyn import inputs
from armdyn.dynamics.regressor import BaseParameters, base_parameters, parameters, regressor
from armdyn.errors import ArgumentError, ModelError
from armdyn.identification.least_squares import MAX_CONDITION, POOR_CONDITION, PoorExcitationWarning
from armdyn.kinematics import check_arm, link_index
from armdyn.model import ArmModel
from armdyn.model.inertial import PARAMETER_ENTRIES, Inertial

BODY = 10
"""Inertial parameters of one body: [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]."""
INERTIA_ENTRIES = PARAMETER_ENTRIES
"""The entries of a symmetric 3x3 inertia held in a body's parameters 4 to 9, in that order."""
TORQUE_FIELDS = ("q", "qd", "qdd", "tau")
LEAST_SQUARES = ("ols", "tls")
"""The estimators of ``stacked_least_squares``: ordinary and total least squares."""


class TorqueSamples(Protocol):
    """Samples of one run: anything with attributes q, qd, qdd and tau, each (N, n).

    armdyn.identification.excitation.IdentificationData is one; a tuple (q, qd, qdd, tau) is taken as well.
    """

    q: object
    qd: object
    qdd: object
    tau: object


def run_regressor(arm: ArmModel, run: object, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The full regressor W (N, n, 14 n) of a run's samples (``armdyn.dynamics.regressor.regressor``).

    For a run that went through a filter (a ``Prepared`` log: it has ``filtered_as_torques``), the
    friction columns (Fv, Fc+, Fc-), which are not smooth in the states, are computed at the untrimmed
    filtered states and passed through the filter the torques or currents went through (Gautier 1997's
    parallel filtering); for plain arrays, W as it is.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    run : object
        The run (a Prepared log, or anything else).
    q, qd, qdd : numpy.ndarray
        The run's samples, (N, n).

    Returns
    -------
    numpy.ndarray
        (N, n, 14 n).
    """
    W = regressor(arm, q, qd, qdd)
    through = getattr(run, "filtered_as_torques", None)
    untrimmed = getattr(run, "untrimmed", None)
    if through is None or untrimmed is None:
        return W
    velocity = untrimmed[1]
    friction = through(np.stack([velocity, (velocity > 0).astype(float), (velocity < 0).astype(float)], axis=-1))
    n = arm.n
    for j in range(n):
        W[:, j, BODY * n + 4 * j : BODY * n + 4 * j + 3] = friction[:, j, :]
    return W


def run_arrays(
    run: object, arm: ArmModel, label: str, fields: tuple[str, ...] = TORQUE_FIELDS
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The four arrays of a run, checked: each (N, n) finite numbers, all of one N.

    Parameters
    ----------
    run : TorqueSamples or tuple
        An object with attributes named ``fields`` (default q, qd, qdd, tau), or a tuple of the
        four arrays in that order.
    arm : ArmModel
        The arm (for n and its name).
    label : str
        Names the run in error messages ("the loaded run").
    fields : tuple of str, optional
        The four names, default ("q", "qd", "qdd", "tau"); ("q", "qd", "qdd", "current") for
        currents.

    Returns
    -------
    tuple of numpy.ndarray
        The four arrays, each (N, n) float64.

    Raises
    ------
    armdyn.ModelError
        When an array is not finite real numbers of shape (N, n), or the four do not hold the
        same samples; the message names the run and the array.
    armdyn.ArgumentError
        When ``run`` is neither a tuple of four arrays nor an object with the four attributes.
    """
    if isinstance(run, tuple):
        if len(run) != len(fields):
            raise ArgumentError(f"{label} must be a tuple ({', '.join(fields)}), got a tuple of {len(run)} items")
        values = list(run)
    else:
        missing = [name for name in fields if not hasattr(run, name)]
        if missing:
            raise ArgumentError(
                f"{label} must be a tuple ({', '.join(fields)}) or have attributes {', '.join(fields)}; "
                f"{type(run).__name__} has no {', '.join(missing)}"
            )
        values = [getattr(run, name) for name in fields]
    where = f" in {label} for '{arm.name}'"
    arrays = [inputs.state(value, arm.n, name, where) for name, value in zip(fields, values, strict=True)]
    for name, array in zip(fields, arrays, strict=True):
        if array.ndim != 2:
            raise ModelError(f"{name}{where} must be samples of shape (N, {arm.n}), got {array.shape}")
    if len({array.shape for array in arrays}) > 1:
        shapes = ", ".join(f"{name} {array.shape}" for name, array in zip(fields, arrays, strict=True))
        raise ModelError(f"{', '.join(fields)}{where} must hold the same samples, each (N, {arm.n}); got {shapes}")
    q, qd, qdd, y = arrays
    return q, qd, qdd, y


def body_parameters(mass: object, com: object = (0.0, 0.0, 0.0), inertia: object = None) -> np.ndarray:
    """The ten parameters [m, m c, I_O] of a rigid body given by its mass, centre of mass and inertia.

    The inverse of ``PayloadEstimate``'s mass, com and inertia: I_O = I_C + m ((c . c) 1 - c c^T),
    the inertia about the frame origin (parallel-axis theorem; Lewis, Dawson and Abdallah 2004,
    Section 3.2), in the order of one link's block of ``armdyn.dynamics.regressor.parameters``.

    Parameters
    ----------
    mass : float
        The mass (kg), >= 0.
    com : array_like, optional
        The centre of mass in the frame (m), default the origin.
    inertia : array_like, optional
        The inertia about the centre of mass, in the frame's axes: 3 moments, 6 values
        [Ixx Iyy Izz Ixy Iyz Ixz] or 3x3; default None, a point mass.

    Returns
    -------
    numpy.ndarray
        [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], (10,).

    Raises
    ------
    armdyn.ModelError
        When the mass properties are not those of a rigid body (see armdyn.model.Inertial).
    """
    body = Inertial(mass, com, np.zeros((3, 3)) if inertia is None else inertia, "payload")  # type: ignore[arg-type]
    return body.parameters()


@dataclass(frozen=True, eq=False)
class LinearEstimate:
    """x with A x = y in the least-squares sense, and its covariance.

    Made by ``stacked_least_squares``.

    Parameters
    ----------
    x : numpy.ndarray
        The estimate, (p,).
    covariance : numpy.ndarray
        Its covariance, (p, p), from each group's own residual variance.
    condition_number : float
        The condition number of A.
    residual : numpy.ndarray
        y - A x, (rows,).
    """

    x: np.ndarray
    covariance: np.ndarray
    condition_number: float
    residual: np.ndarray

    @property
    def standard_errors(self) -> np.ndarray:
        """The square roots of the covariance's diagonal, (p,)."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def residual_rms(self) -> float:
        """The root-mean-square residual."""
        return float(np.sqrt(np.mean(self.residual**2)))


def stacked_least_squares(
    A: np.ndarray, y: np.ndarray, groups: np.ndarray, what: str, method: str = "ols"
) -> LinearEstimate:
    """x with A x = y by ordinary or total least squares, with standard errors from each group's residual variance.

    "ols": x = argmin |A x - y|, through A = Q R. "tls": total least squares on the columns of
    [A, y] scaled to unit norm, [A, y] D v = 0 for the right singular vector v of its smallest
    singular value, D the scaling, x = -(D v)[:p] / (D v)[p] (Golub and Van Loan, *Matrix
    Computations*, 4th ed., 2013, 6.3): it lets the columns of A be noisy too, which biases
    ordinary least squares toward zero. The covariance is R^-1 Q^T S Q R^-T at x (for "tls"
    the ordinary one, valid when the errors in A are small), S holding on each equation the
    residual variance of its group g (a joint of one run): sigma_g^2 = RSS_g / (N_g - h_g), h_g
    the group's share of the leverage diag(Q Q^T), as ``armdyn.identify`` does per joint. A of
    numerical rank below its p columns, or of condition number above MAX_CONDITION, is refused;
    above POOR_CONDITION a PoorExcitationWarning is given.

    Parameters
    ----------
    A : numpy.ndarray
        The stacked regressor, (rows, p), rows > p.
    y : numpy.ndarray
        The stacked measurements, (rows,).
    groups : numpy.ndarray
        The group of each equation, integers from 0, (rows,).
    what : str
        Names the unknowns in error messages ("the 10 parameters of a payload on link 'wrist_3'").
    method : str, optional
        "ols" (default) or "tls".

    Returns
    -------
    LinearEstimate
        The estimate, its covariance, the condition number of A and the residual.

    Warns
    -----
    armdyn.dynamics.regressor.PoorExcitationWarning
        When the condition number of A is above POOR_CONDITION.

    Raises
    ------
    armdyn.ModelError
        When there are no more equations than unknowns, the equations do not excite the
        unknowns (rank below p, or condition number above MAX_CONDITION; the message names
        ``what``, the rank and the condition number), ``method`` is unknown, or the total
        least-squares solution does not exist (the smallest singular vector has no y part).
    """
    from scipy.linalg import solve_triangular

    if method not in LEAST_SQUARES:
        raise ModelError(f"method must be 'ols' or 'tls', got {method!r}")
    rows, p = A.shape
    if rows <= p:
        raise ModelError(f"{what} need more than {p} equations, got {rows}: give more samples")
    Q, R = np.linalg.qr(A)
    singular = np.linalg.svd(R, compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    rank = int(np.sum(singular > singular[0] * rows * np.finfo(float).eps)) if singular[0] > 0 else 0
    if rank < p or condition > MAX_CONDITION:
        raise ModelError(
            f"the samples do not excite {what}: the stacked regressor has rank {rank} of {p} and condition number "
            f"{condition:.3g} (the limit is {MAX_CONDITION:.0e}); move every joint over a wide range with varied "
            "velocities and accelerations"
        )
    if condition > POOR_CONDITION:
        warnings.warn(
            f"the samples excite {what} poorly: the stacked regressor has condition number {condition:.3g} (above "
            f"{POOR_CONDITION:.0e}); the estimates are sensitive to noise (see their standard errors)",
            PoorExcitationWarning,
            stacklevel=3,
        )
    x = solve_triangular(R, Q.T @ y) if method == "ols" else _total_least_squares(A, y, what)
    residual = y - A @ x
    leverage = np.einsum("ij,ij->i", Q, Q)
    variance = np.full(int(groups.max()) + 1, float(residual @ residual) / (rows - p))
    for group in range(variance.size):
        mine = groups == group
        freedom = np.count_nonzero(mine) - leverage[mine].sum()
        if freedom >= 1.0:
            variance[group] = float(residual[mine] @ residual[mine]) / freedom
    weighted = Q * np.sqrt(variance[groups])[:, None]
    inverse = solve_triangular(R, np.eye(p))
    covariance = inverse @ (weighted.T @ weighted) @ inverse.T
    return LinearEstimate(x, (covariance + covariance.T) / 2, condition, residual)


def _total_least_squares(A: np.ndarray, y: np.ndarray, what: str) -> np.ndarray:
    """-(D v)[:p] / (D v)[p] for v the smallest right singular vector of [A, y] D, D scaling columns to unit norm."""
    augmented = np.column_stack([A, y])
    scale = np.linalg.norm(augmented, axis=0)
    scale[scale == 0] = 1.0
    v = np.linalg.svd(augmented / scale, full_matrices=False)[2][-1] / scale
    if abs(v[-1]) <= np.finfo(float).eps * np.abs(v).max():
        raise ModelError(f"the total least-squares solution for {what} does not exist (its y part is 0)")
    return -v[:-1] / v[-1]


def _normal_quantile(confidence: float) -> float:
    from scipy.stats import norm

    return float(norm.ppf(0.5 + confidence / 2))


def _confidence(value: object) -> float:
    level = inputs.number(value, "confidence")
    if not 0 < level < 1:
        raise ModelError(f"confidence must be a probability in (0, 1), e.g. 0.95, got {level:g}")
    return level


@dataclass(frozen=True, eq=False)
class PayloadEstimate:
    """The ten inertial parameters of a payload, with their covariance, and what follows from them.

    Made by ``identify_payload``. The parameters are those of one link's block of
    ``armdyn.dynamics.regressor.parameters``, in the frame of the link the payload is fixed to.

    Parameters
    ----------
    link : int
        The index of the link the payload is fixed to.
    link_name : str
        Its name.
    phi : numpy.ndarray
        [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], the inertia about the link-frame
        origin, (10,).
    covariance : numpy.ndarray
        The covariance of phi, (10, 10).
    condition_number : float
        The condition number of the stacked regressor.
    residual_rms : float
        The root-mean-square torque residual (N m or N).
    samples : int
        The samples used, of both runs.
    base : BaseParameters or None
        The arm's base parameters estimated alongside; None when the arm's model stood in for
        the unloaded run.
    base_phi : numpy.ndarray or None
        Their estimate, (r,), or None.
    confidence : float, optional
        The level of the confidence intervals, default 0.95.
    """

    link: int
    link_name: str
    phi: np.ndarray
    covariance: np.ndarray
    condition_number: float
    residual_rms: float
    samples: int
    base: BaseParameters | None
    base_phi: np.ndarray | None
    confidence: float = 0.95

    @property
    def standard_errors(self) -> np.ndarray:
        """The standard errors of phi, (10,)."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def mass(self) -> float:
        """m (kg)."""
        return float(self.phi[0])

    @property
    def mass_standard_error(self) -> float:
        """The standard error of m (kg)."""
        return float(self.standard_errors[0])

    @property
    def mass_interval(self) -> np.ndarray:
        """[low, high], the confidence interval of m (kg), (2,)."""
        half = _normal_quantile(self.confidence) * self.mass_standard_error
        return np.array([self.mass - half, self.mass + half])

    def _positive_mass(self) -> float:
        if not self.mass > 0:
            raise ModelError(
                f"the payload's estimated mass is {self.mass:.3g} +- {self.mass_standard_error:.2g} kg on link "
                f"'{self.link_name}': not positive, so it has no centre of mass (does the loaded run carry a payload?)"
            )
        return self.mass

    @property
    def com(self) -> np.ndarray:
        """c = (m c) / m, the centre of mass in the link frame (m), (3,).

        Raises
        ------
        armdyn.ModelError
            When the estimated mass is not positive.
        """
        return self.phi[1:4] / self._positive_mass()

    @property
    def com_covariance(self) -> np.ndarray:
        """The covariance of c by the delta method, J Sigma J^T with J = dc/dphi, (3, 3).

        Raises
        ------
        armdyn.ModelError
            When the estimated mass is not positive.
        """
        jacobian = com_jacobian(self.phi[0], self.phi[1:4])
        return jacobian @ self.covariance @ jacobian.T

    @property
    def com_standard_errors(self) -> np.ndarray:
        """The standard errors of c (m), (3,)."""
        return np.sqrt(np.diag(self.com_covariance))

    @property
    def com_interval(self) -> np.ndarray:
        """The confidence interval of each coordinate of c, [[low, high], ...] (m), (3, 2)."""
        half = _normal_quantile(self.confidence) * self.com_standard_errors
        return np.stack([self.com - half, self.com + half], -1)

    @property
    def inertia(self) -> np.ndarray:
        """I_C = I_O - m ((c . c) 1 - c c^T), the inertia about the centre of mass, link axes (kg m^2), (3, 3).

        Raises
        ------
        armdyn.ModelError
            When the estimated mass is not positive.
        """
        m, h = self._positive_mass(), self.phi[1:4]
        about_origin = np.empty((3, 3))
        for k, (r, c) in enumerate(INERTIA_ENTRIES):
            about_origin[r, c] = about_origin[c, r] = self.phi[4 + k]
        return about_origin - ((h @ h) * np.eye(3) - np.outer(h, h)) / m

    @property
    def inertia_standard_errors(self) -> np.ndarray:
        """The standard errors of I_C's entries by the delta method (kg m^2), (3, 3).

        Raises
        ------
        armdyn.ModelError
            When the estimated mass is not positive.
        """
        jacobian = inertia_jacobian(self._positive_mass(), self.phi[1:4])
        errors = np.sqrt(np.diag(jacobian @ self.covariance @ jacobian.T))
        table = np.empty((3, 3))
        for k, (r, c) in enumerate(INERTIA_ENTRIES):
            table[r, c] = table[c, r] = errors[k]
        return table

    @property
    def inertia_interval(self) -> np.ndarray:
        """The confidence interval of each entry of I_C, [..., [low, high]] (kg m^2), (3, 3, 2)."""
        half = _normal_quantile(self.confidence) * self.inertia_standard_errors
        return np.stack([self.inertia - half, self.inertia + half], -1)

    def apply(self, arm: ArmModel, inertia: bool = True) -> ArmModel:
        """The arm carrying the estimated payload: ``arm.with_payload(mass, com, inertia)``.

        Parameters
        ----------
        arm : ArmModel
            The arm (without the payload); its link ``link`` must be its tool link, where
            ``with_payload`` puts a payload.
        inertia : bool, optional
            True (default) gives the payload its estimated inertia about the centre of mass;
            False makes it a point mass (when the inertia is too small to be estimated well).

        Returns
        -------
        ArmModel
            The arm with the payload, of the arm's class.

        Raises
        ------
        armdyn.ModelError
            When the estimated mass is not positive, the estimated inertia is not that of a
            rigid body (not positive semi-definite, or its moments break the triangle inequality:
            pass inertia=False), or the payload's link is not the arm's tool link.
        armdyn.ArgumentError
            When ``arm`` is not an armdyn arm or ``inertia`` is not a bool.
        """
        inputs.arm_argument(arm, ArmModel, numeric=True)
        if not isinstance(inertia, (bool, np.bool_)):
            raise ArgumentError(f"inertia must be True or False, got {inertia!r}")
        if arm.n <= self.link or arm.tool_link != self.link:
            raise ModelError(
                f"the payload was identified on link {self.link} ('{self.link_name}'), but the tool link of "
                f"'{arm.name}' is link {arm.tool_link}: with_payload puts a payload on the tool link"
            )
        if not inertia:
            return arm.with_payload(self.mass, self.com)
        try:
            return arm.with_payload(self.mass, self.com, self.inertia)
        except ModelError as error:
            raise ModelError(
                f"the payload's estimated inertia about its centre of mass (standard errors "
                f"{np.diag(self.inertia_standard_errors)} kg m^2 on the moments) is not a rigid body's: {error}; "
                "excite the tool link's rotations more, or pass inertia=False for a point mass"
            ) from None


def com_jacobian(mass: float, first_moment: np.ndarray) -> np.ndarray:
    """dc/dphi for c = h / m: the delta method's Jacobian of the centre of mass, (3, 10).

    dc/dm = -h / m^2, dc/dh = 1 / m (Casella and Berger, *Statistical Inference*, 2002, 5.5.4).

    Parameters
    ----------
    mass : float
        m (kg), non-zero.
    first_moment : numpy.ndarray
        h = m c (kg m), (3,).

    Returns
    -------
    numpy.ndarray
        The Jacobian with respect to the ten body parameters, (3, 10).
    """
    jacobian = np.zeros((3, BODY))
    jacobian[:, 0] = -first_moment / mass**2
    jacobian[:, 1:4] = np.eye(3) / mass
    return jacobian


def inertia_jacobian(mass: float, first_moment: np.ndarray) -> np.ndarray:
    """d I_C / dphi for I_C = I_O - ((h . h) 1 - h h^T) / m, over I_C's six entries, (6, 10).

    The six entries in the order of INERTIA_ENTRIES (xx, xy, yy, xz, yz, zz): dI_C/dI_O = 1,
    dI_C/dm = ((h . h) 1 - h h^T) / m^2, dI_C/dh_k = -(2 h_k 1 - e_k h^T - h e_k^T) / m.

    Parameters
    ----------
    mass : float
        m (kg), non-zero.
    first_moment : numpy.ndarray
        h = m c (kg m), (3,).

    Returns
    -------
    numpy.ndarray
        The Jacobian with respect to the ten body parameters, (6, 10).
    """
    h = first_moment
    shift = (h @ h) * np.eye(3) - np.outer(h, h)
    jacobian = np.zeros((6, BODY))
    for k, (r, c) in enumerate(INERTIA_ENTRIES):
        jacobian[k, 0] = shift[r, c] / mass**2
        for axis in range(3):
            e = np.eye(3)[axis]
            derivative = 2 * h[axis] * np.eye(3) - np.outer(e, h) - np.outer(h, e)
            jacobian[k, 1 + axis] = -derivative[r, c] / mass
        jacobian[k, 4 + k] = 1.0
    return jacobian


def identify_payload(
    arm: ArmModel,
    unloaded: TorqueSamples | tuple | None,
    loaded: TorqueSamples | tuple,
    link: int | str | None = None,
    drives: bool = True,
    confidence: float = 0.95,
) -> PayloadEstimate:
    """The ten inertial parameters of a payload fixed to a link, from a loaded and an unloaded run.

    The two runs stacked (Atkeson, An and Hollerbach, IJRR 5(3), 1986; Khalil and Dombre 2002,
    12.6; Table 3.3.1, property 9 of Lewis, Dawson and Abdallah 2004)::

        [ W_b(u)    0    ] [ phi_b ]   [ tau_u ]
        [ W_b(l)  W_L(l) ] [ phi_L ] = [ tau_l ]

    solved by ordinary least squares for the arm's base parameters phi_b (friction and motor
    inertia included with ``drives``) and the payload's phi_L, W_L being the ten columns of link
    L in the regressor. With ``unloaded`` None the arm's model stands in for the unloaded run:
    tau_l - tau_arm(q, qd, qdd) = W_L phi_L, tau_arm the arm's inverse dynamics (a Robot's, with its
    whole friction law; for a bare ArmModel W phi_arm, phi_arm = ``parameters(arm)``); the estimate is
    then only as good as that model. Standard errors
    come from each joint's own residual variance in each run (as ``armdyn.identify``); errors in
    q, qd or qdd are not counted.

    All ten parameters are identifiable when the arm's joints determine the tool's wrench (six
    joints or more, away from singularities) and the samples excite them; otherwise the stacked
    regressor is rank-deficient and refused.

    Parameters
    ----------
    arm : ArmModel
        The arm without the payload (its structure; with ``unloaded`` None, its values too).
    unloaded : TorqueSamples, tuple or None
        The run without the payload: q, qd, qdd, tau, each (N_u, n); None to use the arm's model.
    loaded : TorqueSamples or tuple
        The run with the payload, likewise (N_l, n).
    link : int, str or None, optional
        The link the payload is fixed to, by index or name; default None, the arm's tool link.
    drives : bool, optional
        True (default) also estimates the arm's friction and motor parameters from the runs;
        False only its rigid-body ones.
    confidence : float, optional
        The level of the confidence intervals, default 0.95.

    Returns
    -------
    PayloadEstimate
        phi_L with its covariance, the mass, centre of mass and inertia about it with
        confidence intervals, and ``apply(arm)``.

    Warns
    -----
    armdyn.dynamics.regressor.PoorExcitationWarning
        When the condition number of the stacked regressor is above POOR_CONDITION.

    Raises
    ------
    armdyn.ModelError
        When a run's arrays are not finite (N, n) numbers holding the same samples, when there
        are too few samples, when the samples do not excite the unknowns (the rank and the
        condition number are named; above MAX_CONDITION = 1e10), when ``link`` names no link,
        or when ``confidence`` is not in (0, 1).
    armdyn.ArgumentError
        When ``arm`` is not a numeric armdyn arm, a run is neither a tuple of four arrays nor has
        the four attributes, or ``drives`` is not a bool.
    """
    check_arm(arm, True)
    index = link_index(arm, link)
    level = _confidence(confidence)
    if not isinstance(drives, (bool, np.bool_)):
        raise ArgumentError(f"drives must be True or False, got {drives!r}")
    n, columns = arm.n, slice(BODY * index, BODY * (index + 1))
    q, qd, qdd, tau = run_arrays(loaded, arm, "the loaded run")
    W_loaded = run_regressor(arm, loaded, q, qd, qdd)
    joints = np.tile(np.arange(n), len(q))
    name = arm.links[index].name
    if unloaded is None:
        dynamics = getattr(arm, "inverse_dynamics", None)  # a Robot: its whole friction law, sigmoid included
        model = dynamics(q, qd, qdd) if dynamics is not None else W_loaded @ parameters(arm)
        y = (tau - model).reshape(-1)
        what = f"the 10 parameters of a payload on link '{name}' of '{arm.name}'"
        fit = stacked_least_squares(W_loaded[..., columns].reshape(-1, BODY), y, joints, what)
        return PayloadEstimate(
            index, name, fit.x, fit.covariance, fit.condition_number, fit.residual_rms, len(q), None, None, level
        )
    base = base_parameters(arm, drives=bool(drives))
    r = len(base)
    q_u, qd_u, qdd_u, tau_u = run_arrays(unloaded, arm, "the unloaded run")
    W_unloaded = run_regressor(arm, unloaded, q_u, qd_u, qdd_u)
    A = np.zeros((len(q_u) * n + len(q) * n, r + BODY))
    A[: len(q_u) * n, :r] = W_unloaded[..., base.columns].reshape(-1, r)
    A[len(q_u) * n :, :r] = W_loaded[..., base.columns].reshape(-1, r)
    A[len(q_u) * n :, r:] = W_loaded[..., columns].reshape(-1, BODY)
    y = np.concatenate([tau_u.reshape(-1), tau.reshape(-1)])
    groups = np.concatenate([np.tile(np.arange(n), len(q_u)), n + joints])
    what = f"the 10 parameters of a payload on link '{name}' and the {r} base parameters of '{arm.name}'"
    fit = stacked_least_squares(A, y, groups, what)
    return PayloadEstimate(
        index,
        name,
        fit.x[r:],
        fit.covariance[r:, r:],
        fit.condition_number,
        fit.residual_rms,
        len(q_u) + len(q),
        base,
        fit.x[:r],
        level,
    )
