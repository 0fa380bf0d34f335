"""Physically consistent estimation of the link parameters: least squares as a semidefinite program.

tau = W(q, qd, qdd) phi (Table 3.3.1, property 9) is linear in each link's ten parameters
phi_i = [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] (the inertia about the link-frame origin,
as in ``armdyn.dynamics.regressor``). Ordinary least squares may return a set no rigid body can
have (a negative mass, principal moments that break the triangle inequality). A density of mass
exists for phi_i if and only if its pseudo-inertia

    J_i = [[Sigma_i, h_i], [h_i^T, m_i]],  Sigma_i = tr(I_i)/2 1 - I_i,  h_i = m_i c_i,

the second moment of the mass distribution, is positive semi-definite (Wensing, Kim and Slotine,
"Linear matrix inequalities for physically consistent inertial parameter identification: a
statistical perspective on the mass distribution", IEEE RA-L 3(1), 2018; the 4x4 J of Lewis,
Dawson and Abdallah 2004, (3.2.27)). Least squares subject to J_i >= 0 for every link is a
semidefinite program. ``consistent_estimate`` first reduces the rows of W to the (p+1) x (p+1)
Gram matrix of [W y], a block of rows at a time, so that the conic problem has p variables and one
second-order cone of size p + 1 whatever the number of samples, and it scales the columns to unit
norm for the solver (cvxpy with Clarabel by default).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from armdyn.errors import ModelError

if TYPE_CHECKING:
    import pandas as pd

LINK_PARAMETERS = 10
"""Parameters per link in phi: [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]."""
CHUNK_ROWS = 8192
"""Rows of W reduced at a time by ``consistent_estimate`` (its extra memory is a few such blocks)."""
CONSISTENCY_TOLERANCE = 1e-9
"""``link_consistency`` calls a link consistent when its smallest pseudo-inertia eigenvalue is at
least -CONSISTENCY_TOLERANCE times its largest (kg, kg m^2)."""
EIGENVALUE_FLOOR = 1e-13
"""``consistent_estimate`` drops the directions of the column-scaled Gram matrix W^T W whose eigenvalue
is below this fraction of the largest (directions W does not see, up to rounding)."""
SOLVER_TOLERANCE = 1e-10
"""Clarabel's gap and feasibility tolerances in ``consistent_estimate`` (its defaults are 1e-8)."""

# J = PSEUDO @ phi10, an exact linear map: Sigma = tr(I)/2 1 - I, h = [mx, my, mz], J44 = m
_PSEUDO = np.zeros((4, 4, LINK_PARAMETERS))
_PSEUDO[0, 0, [4, 6, 9]] = [-0.5, 0.5, 0.5]  # (Iyy + Izz - Ixx) / 2
_PSEUDO[1, 1, [4, 6, 9]] = [0.5, -0.5, 0.5]
_PSEUDO[2, 2, [4, 6, 9]] = [0.5, 0.5, -0.5]
for _row, _col, _k in ((0, 1, 5), (0, 2, 7), (1, 2, 8)):
    _PSEUDO[_row, _col, _k] = _PSEUDO[_col, _row, _k] = -1.0
for _axis in range(3):
    _PSEUDO[_axis, 3, 1 + _axis] = _PSEUDO[3, _axis, 1 + _axis] = 1.0
_PSEUDO[3, 3, 0] = 1.0


def pseudo_inertia(phi10: object) -> np.ndarray:
    """The pseudo-inertia J = [[tr(I)/2 1 - I, h], [h^T, m]] of one link's ten parameters, or a batch.

    J is the second moment of the link's mass distribution, the integral of (r, 1)(r, 1)^T dm (Lewis,
    Dawson and Abdallah 2004, (3.2.27)); a density of mass with these parameters exists if and only
    if J is positive semi-definite (Wensing, Kim and Slotine, IEEE RA-L 3(1), 2018, Theorem 1).

    Parameters
    ----------
    phi10 : array_like
        [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], shape (..., 10): the mass, the first moment
        m c and the inertia about the link-frame origin in link-frame axes.

    Returns
    -------
    numpy.ndarray
        J, shape (..., 4, 4), linear in phi10.

    Raises
    ------
    armdyn.ModelError
        When phi10 is not finite real numbers whose last axis has 10 values.
    """
    phi = _finite(phi10, "phi10")
    if phi.ndim == 0 or phi.shape[-1] != LINK_PARAMETERS:
        raise ModelError(f"phi10 must hold the 10 parameters of a link on its last axis, got shape {phi.shape}")
    return np.einsum("ijk,...k->...ij", _PSEUDO, phi)


def link_consistency(phi_links: object, tolerance: float = CONSISTENCY_TOLERANCE) -> pd.DataFrame:
    """Per link: mass, pseudo-inertia eigenvalues, principal moments about the centre of mass, consistency.

    A link is consistent when its pseudo-inertia J (``pseudo_inertia``) is positive semi-definite,
    its smallest eigenvalue at least -tolerance times its largest (Wensing, Kim and Slotine, IEEE
    RA-L 3(1), 2018). That implies a mass >= 0 and, with a positive mass, principal moments about
    the centre of mass I_c = I - m ((c.c) 1 - c c^T) that are >= 0 and satisfy the triangle
    inequalities I1 + I2 >= I3 (Lewis, Dawson and Abdallah 2004, Section 3.2), reported beside it.

    Parameters
    ----------
    phi_links : array_like
        The link parameters, shape (L, 10) or (10 L,), per link [m, mx, my, mz, Ixx, Ixy, Iyy,
        Ixz, Iyz, Izz] (the first 10 L entries of ``armdyn.dynamics.regressor.parameters``).
    tolerance : float, optional
        Relative tolerance of the eigenvalue test (default CONSISTENCY_TOLERANCE = 1e-9).

    Returns
    -------
    pandas.DataFrame
        One row per link (index "link", from 1): mass; J_eig1 ... J_eig4 (ascending); J_min;
        I1, I2, I3 the principal moments about the centre of mass (NaN without a positive mass);
        triangle (the three triangle inequalities hold, to the same tolerance); consistent.

    Raises
    ------
    armdyn.ModelError
        When phi_links is not finite numbers of shape (L, 10) or (10 L,), or tolerance is not a
        number >= 0.
    """
    import pandas as pd

    phi = _finite(phi_links, "phi_links")
    if phi.ndim == 1 and phi.size % LINK_PARAMETERS == 0 and phi.size > 0:
        phi = phi.reshape(-1, LINK_PARAMETERS)
    if phi.ndim != 2 or phi.shape[1] != LINK_PARAMETERS:
        raise ModelError(f"phi_links must have shape (L, 10) or (10 L,), got shape {phi.shape}")
    tolerance = _nonnegative(tolerance, "tolerance")
    eigenvalues = np.linalg.eigvalsh(pseudo_inertia(phi))
    scale = np.maximum(np.abs(eigenvalues).max(axis=1), np.finfo(float).tiny)
    moments, triangle = _principal_moments(phi, tolerance * scale)
    table = pd.DataFrame({"mass": phi[:, 0]}, index=pd.RangeIndex(1, len(phi) + 1, name="link"))
    for k in range(4):
        table[f"J_eig{k + 1}"] = eigenvalues[:, k]
    table["J_min"] = eigenvalues[:, 0]
    for k in range(3):
        table[f"I{k + 1}"] = moments[:, k]
    table["triangle"] = triangle
    table["consistent"] = eigenvalues[:, 0] >= -tolerance * scale
    return table


def _principal_moments(phi: np.ndarray, slack: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments about the centre of mass (NaN where m <= 0) and the triangle test, per link."""
    mass = phi[:, 0]
    positive = mass > 0
    com = np.divide(phi[:, 1:4], mass[:, None], out=np.zeros((len(phi), 3)), where=positive[:, None])
    origin = phi[:, [4, 5, 7, 5, 6, 8, 7, 8, 9]].reshape(-1, 3, 3)  # I about the link-frame origin
    shift = np.einsum("l,lk->l", mass, com * com)[:, None, None] * np.eye(3) - np.einsum("l,li,lj->lij", mass, com, com)
    moments = np.linalg.eigvalsh(origin - shift)
    moments[~positive] = np.nan
    triangle = positive & (moments[:, 0] + moments[:, 1] >= moments[:, 2] - slack)
    return moments, triangle


def bounds_from_prior(prior: object, links: int, mass_tolerance: float = 0.1) -> np.ndarray:
    """Mass bounds (1 -+ mass_tolerance) m_i from a prior model's parameters, for ``consistent_estimate``.

    Parameters
    ----------
    prior : array_like
        The prior's parameters, at least 10 L values, per link [m, mx, ..., Izz] first (as
        ``armdyn.dynamics.regressor.parameters`` orders them).
    links : int
        L, the number of links.
    mass_tolerance : float, optional
        The relative tolerance of each mass, in [0, 1) (default 0.1: known within 10%).

    Returns
    -------
    numpy.ndarray
        (L, 2), per link the lower and upper bound of its mass (kg).

    Raises
    ------
    armdyn.ModelError
        When prior is not finite numbers with at least 10 L values, a prior mass is negative,
        links is not an integer >= 1, or mass_tolerance is not a number in [0, 1).
    """
    links = _links(links)
    phi = _finite(prior, "prior").reshape(-1)
    if phi.size < LINK_PARAMETERS * links:
        raise ModelError(f"prior must hold at least {LINK_PARAMETERS * links} values for {links} links, got {phi.size}")
    tolerance = _nonnegative(mass_tolerance, "mass_tolerance")
    if tolerance >= 1:
        raise ModelError(f"mass_tolerance must be below 1 (a relative tolerance), got {tolerance:g}")
    mass = phi[: LINK_PARAMETERS * links : LINK_PARAMETERS]
    if np.any(mass < 0):
        link = int(np.flatnonzero(mass < 0)[0])
        raise ModelError(f"prior mass of link {link + 1} is negative ({mass[link]:g} kg): no bound can be made from it")
    return np.column_stack([(1 - tolerance) * mass, (1 + tolerance) * mass])


@dataclass
class ConsistentEstimate:
    """A physically consistent estimate of the link parameters (and the extra columns).

    Made by ``consistent_estimate``.

    Parameters
    ----------
    phi : numpy.ndarray
        The estimate, (10 L + e,): per link [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz], then the
        e extra parameters in W's column order.
    links : int
        L, the number of links.
    residual_rms : float
        sqrt(sum w (W phi - y)^2 / sum w), the (weighted) root-mean-square residual of the estimate.
    ls_rms : float
        The same for ordinary (weighted) least squares without constraints, bounds or
        regularization: the smallest residual any phi gives, for comparison.
    unconstrained_phi : numpy.ndarray
        The minimizer of the same objective (regularization included) without the pseudo-inertia
        constraints and the bounds (the minimum-norm one in the scaled variables when W is rank
        deficient and there is no regularization).
    status : str
        The solver's status (cvxpy's name, "optimal").
    solver : str
        The solver used.
    reduce_time : float
        Seconds spent reducing W and y to their Gram matrix and its square root.
    solve_time : float
        Seconds spent building and solving the conic problem.
    consistency : pandas.DataFrame
        ``link_consistency`` of the estimate.
    """

    phi: np.ndarray
    links: int
    residual_rms: float
    ls_rms: float
    unconstrained_phi: np.ndarray
    status: str
    solver: str
    reduce_time: float
    solve_time: float
    consistency: pd.DataFrame

    @property
    def link_parameters(self) -> np.ndarray:
        """The link parameters, (L, 10)."""
        return self.phi[: LINK_PARAMETERS * self.links].reshape(self.links, LINK_PARAMETERS)

    @property
    def extra(self) -> np.ndarray:
        """The e extra parameters (friction, motor inertia, offsets...), (e,)."""
        return self.phi[LINK_PARAMETERS * self.links :]

    def base(self, regrouping: object) -> np.ndarray:
        """The base parameters of the estimate, phi_base = regrouping @ phi[:p].

        With ``armdyn.dynamics.regressor.base_parameters(arm, drives=False)`` the regrouping has the
        10 n rigid-body columns; with drives=True 14 n, the rigid ones then [Fv, Fc+, Fc-, Ia] per
        joint: phi's extra columns must then be those four per joint, in that order (the columns of
        ``regressor``) for the mapping to mean anything.

        Parameters
        ----------
        regrouping : array_like or BaseParameters
            The (r, p) regrouping matrix, p at most len(phi), or a BaseParameters holding it.

        Returns
        -------
        numpy.ndarray
            phi_base, (r,).

        Raises
        ------
        armdyn.ModelError
            When the regrouping is not a finite 2-D array with at most len(phi) columns.
        """
        matrix = _finite(getattr(regrouping, "regrouping", regrouping), "regrouping")
        if matrix.ndim != 2 or matrix.shape[1] > self.phi.size:
            raise ModelError(
                f"regrouping must be a 2-D array with at most {self.phi.size} columns (the length of phi), "
                f"got shape {matrix.shape}"
            )
        return matrix @ self.phi[: matrix.shape[1]]


def consistent_estimate(
    W: object,
    y: object,
    links: int,
    prior: object = None,
    regularization: float = 0.0,
    mass_bounds: object = None,
    extra_bounds: object = None,
    weights: object = None,
    margin: float = 0.0,
    solver: str = "CLARABEL",
) -> ConsistentEstimate:
    """Least squares of tau = W phi with every link's pseudo-inertia positive semi-definite.

    Solves the semidefinite program of Wensing, Kim and Slotine (IEEE RA-L 3(1), 2018):

        minimize    ||sqrt(w) (W phi - y)||^2 + regularization * sum_j (n_j (phi_j - prior_j))^2
        subject to  J_i(phi_i) - margin 1 >= 0 (positive semi-definite), i = 1 ... L,
                    mass and extra-column bounds,

    J_i the pseudo-inertia of link i (``pseudo_inertia``). n_j = ||sqrt(w) W[:, j]|| is the norm of
    column j (for a column of zeros, a parameter the data do not see, the geometric mean of the
    others): a parameter moved by delta from the prior costs regularization * (n_j delta)^2, what
    the data would charge if its column were orthogonal to the others, so that one regularization
    weighs parameters of every unit alike (ridge regression on the standardized columns).

    The rows are first reduced to the Gram matrix [W y]^T diag(w) [W y], accumulated CHUNK_ROWS rows
    at a time (matrix products, the fastest way through many rows: the normal equations' summary of
    the data), with the columns scaled to unit norm (phi_j = x_j / n_j) for the solver's sake. Its
    square root by a symmetric eigendecomposition, G = V L V^T, R = L^(1/2) V^T, r = L^(-1/2) V^T g,
    gives ||sqrt(w)(W phi - y)||^2 = ||R x - r||^2 + rho^2: the conic problem has p variables and one
    second-order cone of size at most p + 1 whatever the number of rows. Directions with an
    eigenvalue below EIGENVALUE_FLOOR = 1e-13 of the largest are those W does not see (the columns
    regrouped in the base parameters, up to rounding) and are dropped; forming G squares the
    condition number of the scaled W, harmless below about 1e5 (``identify`` warns above that).
    The objective is divided by ||sqrt(w) y||. The solution is checked against the constraints in
    the original units: nothing is ever replaced by the unconstrained answer.

    Parameters
    ----------
    W : array_like
        The regressor, (rows, 10 L + e): the link columns first (per link [m, mx, my, mz, Ixx,
        Ixy, Iyy, Ixz, Iyz, Izz], as ``armdyn.dynamics.regressor.regressor``), then e extra
        columns (friction, motor inertia, offsets...). Stacked samples, e.g. W.reshape(-1, p).
    y : array_like
        The measured torques, (rows,), in W's row order.
    links : int
        L, the number of links.
    prior : array_like, optional
        A prior phi, (10 L + e,) (a URDF's values, ``parameters(arm)``); needed when
        regularization > 0.
    regularization : float, optional
        Weight of the quadratic pull toward the prior (default 0, none); 1e6 or more returns the
        prior, where it is feasible.
    mass_bounds : array_like, optional
        Per link a lower and an upper mass (kg): an (L, 2) array (NaN or infinity for no bound) or a
        sequence of L pairs or None (``bounds_from_prior`` makes one from a prior).
    extra_bounds : array_like, optional
        Per extra column a lower and an upper bound, (e, 2) or a sequence of e pairs or None (e.g.
        (0, inf) for a viscous friction or a motor inertia).
    weights : array_like, optional
        w, one weight >= 0 per row (e.g. 1 / sigma_j^2 of the row's joint); default all 1.
    margin : float, optional
        J_i >= margin 1 (default 0): a margin > 0 keeps every mass >= margin kg and the second
        moments >= margin kg m^2.
    solver : str, optional
        The cvxpy solver (default "CLARABEL"; "SCS" also handles the problem, less precisely).

    Returns
    -------
    ConsistentEstimate
        phi, the residual RMS beside the unconstrained least-squares RMS, the solver's status and
        time, the per-link consistency table and the mapping to base parameters.

    Raises
    ------
    armdyn.ModelError
        When W is not a finite 2-D array with at least 10 L columns (naming the first bad row and
        column), y or weights do not match its rows or hold NaN, infinity or (weights) negative
        values, links is not an integer >= 1, the prior does not match W's columns or is missing
        with regularization > 0, a bound is malformed or infeasible (lower above upper, or a mass
        upper bound below the margin: the bound is named), or the solver fails, declares the
        problem infeasible or returns a solution that breaks a constraint (its status is named).
    """
    start = time.perf_counter()
    links = _links(links)
    gram, total = _gram(W, y, weights, links)
    p = gram.shape[0] - 1
    extras = p - LINK_PARAMETERS * links
    regularization = _nonnegative(regularization, "regularization")
    margin = _nonnegative(margin, "margin")
    prior_phi = _prior(prior, p, regularization)
    lower, upper = _all_bounds(mass_bounds, extra_bounds, links, extras, margin)
    norms = np.sqrt(np.diag(gram)[:p])
    seen = norms > 1e-12 * max(norms.max(), np.finfo(float).tiny)
    typical = float(np.exp(np.mean(np.log(norms[seen])))) if np.any(seen) else 1.0
    scale = 1 / np.where(seen, norms, typical)  # phi = scale * x, the columns of sqrt(w) W scale to unit norm
    R, r, rho2 = _square_root(gram[:p, :p] * np.outer(scale, scale), gram[:p, p] * scale, gram[p, p])
    A, b = _regularized(R, r, regularization, prior_phi / scale)
    unconstrained = scale * np.linalg.lstsq(A, b, rcond=None)[0]
    reduce_time = time.perf_counter() - start
    start = time.perf_counter()
    size = max(float(np.sqrt(gram[p, p])), np.finfo(float).tiny)
    phi, status = _solve(A / size, b / size, scale, links, lower, upper, margin, solver)
    solve_time = time.perf_counter() - start
    _check_solution(phi, links, lower, upper, margin, status)
    residual = float(np.sqrt((np.sum((R @ (phi / scale) - r) ** 2) + rho2) / total))
    table = link_consistency(phi[: LINK_PARAMETERS * links])
    return ConsistentEstimate(
        phi,
        links,
        residual,
        float(np.sqrt(rho2 / total)),
        unconstrained,
        status,
        solver,
        reduce_time,
        solve_time,
        table,
    )


def _gram(W: object, y: object, weights: object, links: int) -> tuple[np.ndarray, float]:
    """[W y]^T diag(w) [W y], (p+1, p+1), accumulated CHUNK_ROWS rows at a time; and sum w."""
    matrix: Any = W if hasattr(W, "shape") and hasattr(W, "dtype") else _finite(W, "W")  # a memmap stays one
    shape = matrix.shape
    if len(shape) != 2 or shape[0] < 1 or shape[1] < LINK_PARAMETERS * links:
        raise ModelError(
            f"W must be a 2-D array (rows, 10 L + e) with at least {LINK_PARAMETERS * links} columns for {links} "
            f"links and at least one row, got shape {shape}"
        )
    rows, p = shape
    target = _finite(y, "y")
    if target.shape != (rows,):
        raise ModelError(f"y must hold one torque per row of W, shape ({rows},), got shape {target.shape}")
    w = np.ones(rows) if weights is None else _finite(weights, "weights")
    if w.shape != (rows,):
        raise ModelError(f"weights must hold one weight per row of W, shape ({rows},), got shape {w.shape}")
    if np.any(w < 0):
        raise ModelError(f"weights must be >= 0: row {int(np.flatnonzero(w < 0)[0])} has {w[w < 0][0]:g}")
    total = float(w.sum())
    if total <= 0:
        raise ModelError("weights must not all be 0")
    gram, root = np.zeros((p + 1, p + 1)), np.sqrt(w)
    for first in range(0, rows, CHUNK_ROWS):
        block = np.asarray(matrix[first : first + CHUNK_ROWS], dtype=float)
        bad = ~np.isfinite(block)
        if bad.any():
            row, column = np.argwhere(bad)[0]
            raise ModelError(f"W holds NaN or infinity at row {first + row}, column {column}")
        stacked = np.column_stack([block, target[first : first + CHUNK_ROWS]]) * root[first : first + CHUNK_ROWS, None]
        gram += stacked.T @ stacked  # one symmetric rank-k update (BLAS syrk)
    return gram, total


def _square_root(G: np.ndarray, g: np.ndarray, yy: float) -> tuple[np.ndarray, np.ndarray, float]:
    """R, r, rho^2 with ||R x - r||^2 + rho^2 = x^T G x - 2 g^T x + yy, R = L^(1/2) V^T from G = V L V^T.

    Eigenvalues below EIGENVALUE_FLOOR of the largest are directions W does not see (columns that
    only act in combinations, regrouped in the base parameters): their rows are dropped.
    """
    eigenvalues, V = np.linalg.eigh(G)
    keep = eigenvalues > EIGENVALUE_FLOOR * max(float(eigenvalues[-1]), np.finfo(float).tiny)
    root = np.sqrt(eigenvalues[keep])
    r = (V[:, keep].T @ g) / root
    return root[:, None] * V[:, keep].T, r, max(yy - float(r @ r), 0.0)


def _regularized(A: np.ndarray, b: np.ndarray, weight: float, x_prior: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[A; sqrt(weight) 1] x ~ [b; sqrt(weight) x_prior], reduced again to a p x p triangle by QR."""
    if weight == 0:
        return A, b
    p = A.shape[1]
    root = np.sqrt(weight)
    stacked = np.vstack([np.column_stack([A, b]), np.column_stack([root * np.eye(p), root * x_prior])])
    triangle: Any = np.linalg.qr(stacked, mode="r")  # NumPy's stub says (Q, R) for mode "r"; it returns R
    return triangle[:p, :p], triangle[:p, p]


def _solve(
    A: np.ndarray,
    b: np.ndarray,
    scale: np.ndarray,
    links: int,
    lower: np.ndarray,
    upper: np.ndarray,
    margin: float,
    solver: str,
) -> tuple[np.ndarray, str]:
    """minimize ||A x - b|| subject to J_i(scale x) >= margin 1 and the bounds; phi = scale x."""
    import cvxpy as cp

    p = A.shape[1]
    x = cp.Variable(p)
    pseudo = _PSEUDO.reshape(16, LINK_PARAMETERS)
    constraints = []
    for i in range(links):
        part = slice(LINK_PARAMETERS * i, LINK_PARAMETERS * (i + 1))
        J = cp.reshape((pseudo * scale[part]) @ x[part], (4, 4), order="C")
        constraints.append(J - margin * np.eye(4) >> 0)
    for bound, sign in ((lower, 1.0), (upper, -1.0)):
        index = np.flatnonzero(np.isfinite(bound))
        if index.size:
            constraints.append(sign * x[index] >= sign * bound[index] / scale[index])
    problem = cp.Problem(cp.Minimize(cp.norm(A @ x - b, 2)), constraints)
    options: dict[str, Any] = {}
    if solver.upper() == "CLARABEL":
        options = {"tol_gap_abs": SOLVER_TOLERANCE, "tol_gap_rel": SOLVER_TOLERANCE, "tol_feas": SOLVER_TOLERANCE}
    try:
        problem.solve(solver=solver, **options)
    except (cp.error.SolverError, ValueError) as error:
        raise ModelError(
            f"the consistent estimate's semidefinite program failed with solver {solver}: {error}"
        ) from None
    if problem.status != cp.OPTIMAL or x.value is None:
        raise ModelError(
            f"the consistent estimate's semidefinite program was not solved: solver {solver} returned status "
            f"'{problem.status}'" + (": check the mass and extra bounds" if "infeasible" in problem.status else "")
        )
    return scale * np.asarray(x.value), str(problem.status)


def _check_solution(
    phi: np.ndarray, links: int, lower: np.ndarray, upper: np.ndarray, margin: float, status: str
) -> None:
    """Refuse a solution that breaks a constraint by more than the solver's tolerance allows."""
    J = pseudo_inertia(phi[: LINK_PARAMETERS * links].reshape(links, LINK_PARAMETERS))
    eigenvalues = np.linalg.eigvalsh(J)
    slack = 1e-6 * np.maximum(np.abs(eigenvalues).max(axis=1), 1e-12)
    broken = np.flatnonzero(eigenvalues[:, 0] - margin < -slack)
    if broken.size:
        link = int(broken[0])
        raise ModelError(
            f"the solver returned status '{status}' but link {link + 1}'s pseudo-inertia has eigenvalue "
            f"{eigenvalues[link, 0]:.3g}, below the margin {margin:g}: the solution is not consistent"
        )
    room = 1e-6 * np.maximum(np.abs(phi), 1e-9)
    outside = np.flatnonzero((phi < lower - room) | (phi > upper + room))
    if outside.size:
        k = int(outside[0])
        raise ModelError(
            f"the solver returned status '{status}' but phi[{k}] = {phi[k]:.6g} is outside its bounds "
            f"[{lower[k]:g}, {upper[k]:g}]"
        )


def _all_bounds(
    mass_bounds: object, extra_bounds: object, links: int, extras: int, margin: float
) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of every parameter (-inf, inf where none), with infeasible ones refused."""
    p = LINK_PARAMETERS * links + extras
    lower, upper = np.full(p, -np.inf), np.full(p, np.inf)
    masses = _pairs(mass_bounds, links, "mass_bounds", "link")
    rigid = slice(0, LINK_PARAMETERS * links, LINK_PARAMETERS)
    lower[rigid], upper[rigid] = masses[:, 0], masses[:, 1]
    for link in range(links):
        if masses[link, 1] < margin:
            raise ModelError(
                f"mass_bounds of link {link + 1}: the upper bound {masses[link, 1]:g} kg is below the margin "
                f"{margin:g} (a positive semi-definite pseudo-inertia needs a mass >= margin): infeasible"
            )
    pairs = _pairs(extra_bounds, extras, "extra_bounds", "extra column")
    lower[LINK_PARAMETERS * links :], upper[LINK_PARAMETERS * links :] = pairs[:, 0], pairs[:, 1]
    return lower, upper


def _pairs(value: object, count: int, name: str, item: str) -> np.ndarray:
    """(count, 2) lower and upper bounds from an array (NaN: none) or a sequence of pairs or None."""
    bounds = np.column_stack([np.full(count, -np.inf), np.full(count, np.inf)])
    if value is None:
        return bounds
    if isinstance(value, np.ndarray):
        entries: list[object] = list(value)
    elif isinstance(value, (list, tuple)):
        entries = list(value)
    else:
        raise ModelError(f"{name} must be an ({count}, 2) array or a sequence of {count} pairs or None, got {value!r}")
    if len(entries) != count:
        raise ModelError(f"{name} must hold one pair (lower, upper) per {item}, {count} of them, got {len(entries)}")
    for k, entry in enumerate(entries):
        if entry is None:
            continue
        pair = [np.nan if v is None else v for v in entry] if isinstance(entry, (list, tuple)) else entry
        try:
            numbers = np.asarray(pair, dtype=float)
        except (TypeError, ValueError):
            raise ModelError(f"{name} of {item} {k + 1} must be a pair (lower, upper), got {entry!r}") from None
        if numbers.shape != (2,):
            raise ModelError(f"{name} of {item} {k + 1} must be a pair (lower, upper), got {entry!r}")
        low = -np.inf if np.isnan(numbers[0]) else numbers[0]
        high = np.inf if np.isnan(numbers[1]) else numbers[1]
        if low > high or low == np.inf or high == -np.inf:
            raise ModelError(f"{name} of {item} {k + 1}: lower bound {low:g} is above upper bound {high:g}: infeasible")
        bounds[k] = low, high
    return bounds


def _prior(prior: object, p: int, regularization: float) -> np.ndarray:
    if prior is None:
        if regularization > 0:
            raise ModelError("regularization > 0 pulls toward a prior: give prior (10 L + e values)")
        return np.zeros(p)
    phi = _finite(prior, "prior")
    if phi.shape != (p,):
        raise ModelError(f"prior must hold one value per column of W, shape ({p},), got shape {phi.shape}")
    return phi


def _links(value: object) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ModelError(f"links must be an integer >= 1, got {value!r}")
    return int(value)


def _nonnegative(value: object, name: str) -> float:
    if isinstance(value, (bool, np.bool_)):
        raise ModelError(f"{name} must be a number >= 0, got {value!r}")
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ModelError(f"{name} must be a number >= 0, got {value!r}") from None
    if not np.isfinite(number) or number < 0:
        raise ModelError(f"{name} must be a finite number >= 0, got {value!r}")
    return number


def _finite(value: object, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{name} must be real numbers, got {type(value).__name__}") from None
    bad = ~np.isfinite(array)
    if bad.any():
        raise ModelError(f"{name} holds NaN or infinity at index {tuple(int(i) for i in np.argwhere(bad)[0])}")
    return array
