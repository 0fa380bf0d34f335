"""The linear parameterization tau = W(q, qd, qdd) phi (Table 3.3.1, property 9), and the
base (identifiable) parameters.

W is computed recursively, O(n d) for depth d, batched with NumPy over any leading shape
(Atkeson, An and Hollerbach, "Estimation of inertial parameters of manipulator loads and
links", IJRR 5(3), 1986; the spatial form of Featherstone 2008, 9.4): each link's
Newton-Euler force is linear in its ten parameters, f_i = Y(v_i, a_i) phi_i, and joint j
carries the forces of the links it moves, tau_j = S_j^T sum_i f_i.

phi, per link in link order: [m, m cx, m cy, m cz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], the
inertia about the link-frame origin in link-frame axes (Pinocchio's dynamic parameters);
then per joint [Fv, Fc+, Fc-, Ia]: the joint-side viscous and Coulomb friction and the
reflected motor inertia G^2 Jm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armdyn.errors import ModelError
from armdyn.kinematics import as_state, joint_axes, joint_frames
from armdyn.model import ArmModel

BODY_PARAMETERS = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
JOINT_PARAMETERS = ("Fv", "Fc+", "Fc-", "Ia")


def parameter_names(robot: ArmModel) -> list[str]:
    """Names of phi: m1, mx1, ..., Izz1, ..., then Fv1, Fc+1, Fc-1, Ia1, ...

    Parameters
    ----------
    robot : ArmModel
        The arm.

    Returns
    -------
    list of str
        14 n names, in the order of ``parameters``.
    """
    bodies = [f"{name}{i + 1}" for i in range(robot.n) for name in BODY_PARAMETERS]
    return bodies + [f"{name}{i + 1}" for i in range(robot.n) for name in JOINT_PARAMETERS]


def parameters(robot: ArmModel) -> np.ndarray:
    """phi, the parameter vector with W(q, qd, qdd) phi = inverse_dynamics(q, qd, qdd).

    The linear parameterization of Table 3.3.1, property 9. Per link [m, m cx, m cy, m cz,
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz], the inertia about the link-frame origin in link-frame
    axes; then per joint [Fv, Fc+, Fc-, Ia], the joint-side viscous and Coulomb friction
    and the reflected motor inertia G^2 Jm.

    Parameters
    ----------
    robot : ArmModel
        The arm.

    Returns
    -------
    numpy.ndarray
        phi, shape (14 n,).

    Raises
    ------
    TypeError
        When the arm has symbolic (SymPy) parameters; ClosedForm.phi gives them symbolically.
    """
    values = []
    for link in robot.links:
        body = link.inertial
        inertia = body.inertia_about_origin()
        values += [body.mass, *body.first_moment]
        values += [inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2], inertia[1, 2], inertia[2, 2]]
    coulomb = robot.coulomb_friction
    for i in range(robot.n):
        values += [robot.viscous_friction[i], coulomb[i, 0], coulomb[i, 1], robot.reflected_inertia[i]]
    return np.array(values, dtype=float)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.cross(a, b)


def body_regressor(w: np.ndarray, v: np.ndarray, alpha: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Y with f = I a + v x* I v = Y phi_body, shape (..., 6, 10), in the body's own frame.

    v = [w; v] the body velocity, [alpha; a] its spatial acceleration, both at the origin of
    the frame; f = [moment about the origin; force] (Featherstone 2008, 9.4).

    Parameters
    ----------
    w, v : numpy.ndarray
        Angular and linear velocity of the body at the frame origin, (..., 3).
    alpha, a : numpy.ndarray
        Angular and linear parts of its spatial acceleration at the frame origin, (..., 3).

    Returns
    -------
    numpy.ndarray
        Y, shape (..., 6, 10), columns in the order of one link's block of ``parameters``.
    """
    Y = np.zeros((*w.shape[:-1], 6, 10))
    lin = a + _cross(w, v)  # the acceleration of the frame origin
    Y[..., 3:, 0] = lin  # mass: force m lin
    # first moment h: moment h x lin = -[lin]x h; force alpha x h + w x (w x h)
    Y[..., 0, 2], Y[..., 0, 3] = lin[..., 2], -lin[..., 1]
    Y[..., 1, 1], Y[..., 1, 3] = -lin[..., 2], lin[..., 0]
    Y[..., 2, 1], Y[..., 2, 2] = lin[..., 1], -lin[..., 0]
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1.0
        Y[..., 3:, 1 + k] = _cross(alpha, e) + _cross(w, _cross(w, e))
    # inertia about the origin: moment I alpha + w x (I w)
    # I = [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]; columns for xx, xy, yy, xz, yz, zz
    basis = {
        4: ((0, 0),),
        5: ((0, 1), (1, 0)),
        6: ((1, 1),),
        7: ((0, 2), (2, 0)),
        8: ((1, 2), (2, 1)),
        9: ((2, 2),),
    }
    for column, entries in basis.items():
        E = np.zeros((3, 3))
        for r, c in entries:
            E[r, c] = 1.0
        Iw = np.einsum("rc,...c->...r", E, w)
        Y[..., :3, column] = np.einsum("rc,...c->...r", E, alpha) + _cross(w, Iw)
    return Y


def regressor(robot: ArmModel, q: object, qd: object, qdd: object) -> np.ndarray:
    """W(q, qd, qdd), shape (..., n, 14 n), with W phi = tau (Table 3.3.1, property 9).

    Friction and motors included: W ``parameters(robot)`` equals the inverse dynamics.
    Computed recursively, O(n d) for depth d (Atkeson, An and Hollerbach 1986), batched
    over any leading shape.

    Parameters
    ----------
    robot : ArmModel
        The arm.
    q, qd, qdd : array_like
        Joint positions, velocities and accelerations, (n,) or a batch (..., n); the batch
        shapes broadcast together.

    Returns
    -------
    numpy.ndarray
        W, shape (..., n, 14 n).

    Raises
    ------
    armdyn.ModelError
        When a state is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; ClosedForm.W gives W symbolically.
    """
    q, qd, qdd = (as_state(robot, x, name) for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")))
    batch = np.broadcast_shapes(q.shape[:-1], qd.shape[:-1], qdd.shape[:-1])
    q, qd, qdd = (np.broadcast_to(x, (*batch, robot.n)) for x in (q, qd, qdd))
    n = robot.n
    links, joints = joint_frames(robot, q)
    z, o = joint_axes(robot, joints)
    revolute = np.array([kind == "revolute" for kind in robot.kinds])
    S = np.concatenate([np.where(revolute[:, None], z, 0.0), np.where(revolute[:, None], _cross(o, z), z)], -1)
    ancestors = robot.ancestors.astype(float)  # [i, j]: joint j moves link i
    # world spatial velocity of each link (at the world origin): v_i = sum_j S_j qd_j
    v = np.einsum("ij,...jk,...j->...ik", ancestors, S, qd)
    # each joint's Sdot = v_j x S_j (v_j the velocity of the link the joint moves)
    w_, u_ = v[..., :3], v[..., 3:]
    Sdot = np.concatenate([_cross(w_, S[..., :3]), _cross(w_, S[..., 3:]) + _cross(u_, S[..., :3])], -1)
    gravity = np.concatenate([np.zeros(3), -robot.gravity.astype(float)])
    a = gravity + np.einsum("ij,...jk->...ik", ancestors, S * qdd[..., None] + Sdot * qd[..., None])
    # into each link's frame: w_L = R^T w, v_L = R^T (v + w x p), likewise for the acceleration
    R, p = links[..., :3, :3], links[..., :3, 3]
    Rt = np.swapaxes(R, -1, -2)
    w_L = np.einsum("...ab,...b->...a", Rt, v[..., :3])
    v_L = np.einsum("...ab,...b->...a", Rt, v[..., 3:] + _cross(v[..., :3], p))
    alpha_L = np.einsum("...ab,...b->...a", Rt, a[..., :3])
    a_L = np.einsum("...ab,...b->...a", Rt, a[..., 3:] + _cross(a[..., :3], p))
    Y = body_regressor(w_L, v_L, alpha_L, a_L)  # (..., n, 6, 10), link frames
    # back to the world (force at the world origin): f_w = R f, n_w = R n + p x (R f)
    force = np.einsum("...ab,...bk->...ak", R, Y[..., 3:, :])
    moment = np.einsum("...ab,...bk->...ak", R, Y[..., :3, :]) + np.cross(p[..., :, None], force, axis=-2)
    Yw = np.concatenate([moment, force], -2)
    # tau_j = S_j . sum over links i moved by j of Yw_i: W[j, block i] = S_j . Yw_i when j moves i
    bodies = np.einsum("ij,...jk,...ikc->...jic", ancestors, S, Yw).reshape(*batch, n, 10 * n)
    drives = np.zeros((*batch, n, 4 * n))
    index = np.arange(n)
    drives[..., index, 4 * index] = qd
    drives[..., index, 4 * index + 1] = qd > 0
    drives[..., index, 4 * index + 2] = qd < 0
    drives[..., index, 4 * index + 3] = qdd
    return np.concatenate([bodies, drives], -1)


@dataclass
class BaseParameters:
    """The identifiable combinations of phi: tau = W_base(q, qd, qdd) phi_base.

    Made by ``base_parameters``.

    Parameters
    ----------
    robot : ArmModel
        The arm.
    columns : numpy.ndarray
        The indices of the r columns of W kept, in increasing order.
    regrouping : numpy.ndarray
        (r, p) matrix with phi_base = regrouping @ phi (p = 14 n, or 10 n without drives).
    names : list of str
        Readable combinations, e.g. "Izz2 + 0.1865*m3".
    phi : numpy.ndarray
        phi_base of the arm's own parameters, (r,).
    """

    robot: ArmModel
    columns: np.ndarray
    regrouping: np.ndarray
    names: list[str]
    phi: np.ndarray

    def regressor(self, q: object, qd: object, qdd: object) -> np.ndarray:
        """W_base = W[..., columns], shape (..., n, r).

        Parameters
        ----------
        q, qd, qdd : array_like
            Joint positions, velocities and accelerations, (n,) or a batch (..., n).

        Returns
        -------
        numpy.ndarray
            W_base, shape (..., n, r), with W_base phi_base = tau.

        Raises
        ------
        armdyn.ModelError
            When a state is not numbers of shape (..., n) or holds NaN or infinity.
        """
        return regressor(self.robot, q, qd, qdd)[..., self.columns]

    def __len__(self) -> int:
        return len(self.columns)


def _term(coefficient: float, name: str) -> str:
    if abs(coefficient - 1.0) < 1e-9:
        return name
    if abs(coefficient + 1.0) < 1e-9:
        return f"-{name}"
    return f"{coefficient:.6g}*{name}"


def base_parameters(
    robot: ArmModel, samples: int = 200, seed: int = 0, tolerance: float = 1e-9, drives: bool = True
) -> BaseParameters:
    """The base parameters by QR with column pivoting of regressors stacked at random states.

    Columns whose pivot falls below ``tolerance`` times the largest are dependent: they are
    regrouped into the independent ones they are combinations of (Gautier, "Numerical
    calculation of the base inertial parameters of robots", J. Robot. Syst. 8(4), 1991).
    The random states are uniform within the joint limits (within [-pi, pi] where a limit
    is infinite), with velocities and accelerations uniform in [-2, 2].

    Parameters
    ----------
    robot : ArmModel
        The arm.
    samples : int, optional
        Number of random states stacked (default 200, at least 1).
    seed : int, optional
        Seed of the random generator (default 0).
    tolerance : float, optional
        Relative pivot size below which a column counts as dependent (default 1e-9).
    drives : bool, optional
        True (default) includes the friction and motor columns; False leaves them out
        (the rigid-body parameters only).

    Returns
    -------
    BaseParameters
        The kept columns, the regrouping matrix, readable names and the arm's phi_base.

    Raises
    ------
    armdyn.ModelError
        When ``samples`` is below 1.
    TypeError
        When the arm has symbolic (SymPy) parameters.
    """
    from scipy.linalg import qr

    if samples < 1:
        raise ModelError(f"samples must be at least 1, got {samples}")
    rng = np.random.default_rng(seed)
    lower, upper = robot.qlim
    low = np.where(np.isfinite(lower), lower, -np.pi)
    high = np.where(np.isfinite(upper), upper, np.pi)
    q = rng.uniform(low, high, (samples, robot.n))
    qd, qdd = rng.uniform(-2, 2, (2, samples, robot.n))
    width = 14 * robot.n if drives else 10 * robot.n
    stacked = regressor(robot, q, qd, qdd)[..., :width].reshape(-1, width)
    _, R, pivots = qr(stacked, mode="economic", pivoting=True)
    diagonal = np.abs(np.diag(R))
    rank = int(np.sum(diagonal > tolerance * diagonal[0]))
    independent, dependent = pivots[:rank], pivots[rank:]
    beta = np.linalg.solve(R[:rank, :rank], R[:rank, rank:])
    beta[np.abs(beta) < 1e-10] = 0.0
    regrouping = np.zeros((rank, stacked.shape[1]))
    regrouping[np.arange(rank), independent] = 1.0
    regrouping[:, dependent] = beta
    order = np.argsort(independent)
    independent, regrouping = independent[order], regrouping[order]
    names_all = parameter_names(robot)
    names = []
    for row in regrouping:
        terms = [_term(row[k], names_all[k]) for k in np.flatnonzero(row)]
        names.append(" + ".join(terms).replace("+ -", "- "))
    return BaseParameters(robot, independent, regrouping, names, regrouping @ parameters(robot)[:width])


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
        The standard error of each estimate, (r,).
    condition_number : float
        The condition number of the stacked base regressor.
    residual_rms : float
        The root-mean-square torque residual.
    samples : int
        The number of samples N used.
    """

    base: BaseParameters
    phi: np.ndarray
    standard_errors: np.ndarray
    condition_number: float
    residual_rms: float
    samples: int

    @property
    def names(self) -> list[str]:
        return self.base.names

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


def identify(robot: ArmModel, q: object, qd: object, qdd: object, tau: object, drives: bool = True) -> Identification:
    """Estimate the base parameters from samples (q, qd, qdd, tau), each (N, n), by least squares.

    tau = W_base(q, qd, qdd) phi_base (Table 3.3.1, property 9) stacked over the samples
    and solved for phi_base. Standard errors: sigma sqrt(diag((W^T W)^-1)) with sigma^2
    the residual variance (N n - r degrees of freedom); the condition number of the stacked
    base regressor says how well the trajectory excites the parameters.

    Parameters
    ----------
    robot : ArmModel
        The arm whose base parameters are estimated (its structure; its own values are
        reported alongside for comparison).
    q, qd, qdd : array_like
        Measured joint positions, velocities and accelerations, (N, n).
    tau : array_like
        Measured joint torques, (N, n).
    drives : bool, optional
        True (default) also estimates the friction and motor parameters; False only the
        rigid-body ones.

    Returns
    -------
    Identification
        The estimate, its standard errors, the condition number and the residual.

    Raises
    ------
    armdyn.ModelError
        When a sample array is not numbers of shape (..., n) or holds NaN or infinity, when
        q, qd, qdd and tau hold different numbers of samples, or when there are too few
        samples (N n must exceed the number r of base parameters).
    """
    tau = as_state(robot, tau, "tau").reshape(-1, robot.n)
    base = base_parameters(robot, drives=drives)
    W = base.regressor(q, qd, qdd).reshape(-1, len(base))
    y = tau.reshape(-1)
    if W.shape[0] != y.shape[0]:
        raise ModelError(f"q, qd, qdd give {W.shape[0] // robot.n} samples but tau has {tau.shape[0]}")
    if W.shape[0] <= len(base):
        raise ModelError(f"identification needs more than {len(base) // robot.n + 1} samples, got {tau.shape[0]}")
    phi, *_ = np.linalg.lstsq(W, y, rcond=None)
    residual = y - W @ phi
    dof = W.shape[0] - len(base)
    variance = float(residual @ residual) / dof
    covariance = variance * np.linalg.pinv(W.T @ W)
    return Identification(
        base, phi, np.sqrt(np.abs(np.diag(covariance))), float(np.linalg.cond(W)),
        float(np.sqrt(np.mean(residual**2))), tau.shape[0],
    )  # fmt: skip
