"""The book's Lagrange-Euler formulation, numerically (Lewis, Dawson and Abdallah 2004, Sections 3.2 and 3.3).

Readable NumPy, batched over leading dimensions: the reference the recursive kernels
are tested against. Link i contributes through its transform T_i(q), its derivatives
dT_i/dq_j = S_j T_i (S_j the world-frame generator of joint j) and its constant
pseudo-inertia matrix J_i. Motors add their reflected inertia G^2 Jm on the diagonal of
M (the rotor's kinetic energy 1/2 Jm (G qd)^2, as the Robotics Toolbox models it).
"""

from __future__ import annotations

import numpy as np

from armdyn.dynamics.friction import sigmoid_vector, stribeck_vector
from armdyn.kinematics import as_state, as_states, check_arm, link_transform_derivatives, twist_generators
from armdyn.model import ArmModel


def pseudo_inertias(arm: ArmModel) -> np.ndarray:
    """The pseudo-inertia matrices J_i of all links, in their link frames, (n, 4, 4) (3.2.27).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.

    Returns
    -------
    numpy.ndarray
        J_i, float, (n, 4, 4), in link order; J_i e4 = [m_i r_i; m_i].

    Raises
    ------
    TypeError
        When ``arm`` is not an armdyn arm, or has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    check_arm(arm)
    return np.stack([link.inertial.pseudo_inertia() for link in arm.links]).astype(float)


def _homogeneous_gravity(arm: ArmModel) -> np.ndarray:
    """g = [gx gy gz 0] (3.2.33): a direction, so the translation of T_i does not act on it."""
    return np.append(arm.gravity.astype(float), 0.0)


def inertia_matrix(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """M(q): m_jk = sum_i trace(dT_i/dq_j J_i (dT_i/dq_k)^T) (3.2.30), plus diag(G^2 Jm).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q : array_like
        Joint positions, (n,) or a batch (..., n); complex values are kept (complex-step
        derivatives).

    Returns
    -------
    numpy.ndarray
        M, (..., n, n), symmetric; complex when ``q`` is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    dT = link_transform_derivatives(arm, q)
    M = np.einsum("...ijab,ibc,...ikac->...jk", dT, pseudo_inertias(arm), dT)
    return M + np.diag(arm.reflected_inertia)


def second_derivatives(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """d2T_i/(dq_j dq_l) = S_a S_b T_i, a the joint nearer the root of (j, l), b the other.

    Shape (..., n, n, n, 4, 4) indexed [i, j, l]; zero unless both j and l move link i.
    Parents come before children, so on one path to the root the smaller index is nearer it.

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q : array_like
        Joint positions, (n,) or a batch (..., n); complex values are kept (complex-step
        derivatives).

    Returns
    -------
    numpy.ndarray
        d2T_i/(dq_j dq_l), (..., n, n, n, 4, 4) indexed [..., i, j, l, :, :]; complex when ``q`` is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    S, T = twist_generators(arm, q)
    n = arm.n
    index = np.arange(n)
    first = np.minimum(index[:, None], index[None, :])
    second = np.maximum(index[:, None], index[None, :])
    pairs = S[..., first, :, :] @ S[..., second, :, :]  # (..., j, l, 4, 4)
    both = arm.ancestors[:, :, None] & arm.ancestors[:, None, :]
    return pairs[..., None, :, :, :, :] @ T[..., :, None, None, :, :] * both[..., None, None]


def inertia_matrix_partials(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """dM/dq_l, shape (..., n, n, n) indexed [l, j, k] (differentiating 3.2.30).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q : array_like
        Joint positions, (n,) or a batch (..., n); complex values are kept (complex-step
        derivatives).

    Returns
    -------
    numpy.ndarray
        dm_jk/dq_l, (..., n, n, n) indexed [..., l, j, k], symmetric in j and k; complex when
        ``q`` is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    dT = link_transform_derivatives(arm, q)
    d2T = second_derivatives(arm, q)
    J = pseudo_inertias(arm)
    half = np.einsum("...ijlab,ibc,...ikac->...ljk", d2T, J, dT)
    return half + np.swapaxes(half, -1, -2)


def inertia_matrix_dot(arm: ArmModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Mdot = sum_l dM/dq_l qd_l.

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast
        together. Complex values are kept (complex-step derivatives).

    Returns
    -------
    numpy.ndarray
        Mdot, (..., n, n) for the broadcast batch shape; complex when a state is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``qd`` is not numbers of shape (..., n) or holds NaN or infinity, or when
        their batch shapes do not broadcast together.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    q, qd = as_states(arm, q, qd=qd)
    return np.einsum("...ljk,...l->...jk", inertia_matrix_partials(arm, q), qd)


def christoffel_symbols(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """v_ijk = 1/2 (dm_kj/dq_i + dm_ki/dq_j - dm_ij/dq_k) (3.3.47), shape (..., n, n, n).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q : array_like
        Joint positions, (n,) or a batch (..., n); complex values are kept (complex-step
        derivatives).

    Returns
    -------
    numpy.ndarray
        v_ijk, (..., n, n, n) indexed [..., i, j, k], symmetric in i and j; complex when ``q`` is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    dM = inertia_matrix_partials(arm, q)  # [l, j, k] = dm_jk/dq_l
    return 0.5 * (np.einsum("...ikj->...ijk", dM) + np.einsum("...jki->...ijk", dM) - np.einsum("...kij->...ijk", dM))


def coriolis_matrix(arm: ArmModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """The Christoffel form Vm(q, qd): (Vm)_kj = sum_i v_ijk qd_i (3.3.48).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast
        together. Complex values are kept (complex-step derivatives).

    Returns
    -------
    numpy.ndarray
        Vm, (..., n, n) indexed [..., k, j] for the broadcast batch shape; complex when a state is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``qd`` is not numbers of shape (..., n) or holds NaN or infinity, or when
        their batch shapes do not broadcast together.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    q, qd = as_states(arm, q, qd=qd)
    return np.einsum("...ijk,...i->...kj", christoffel_symbols(arm, q), qd)


def coriolis_vector(arm: ArmModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """V(q, qd) = Vm(q, qd) qd = Mdot qd - 1/2 d/dq (qd^T M qd) (3.2.42).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast
        together. Complex values are kept (complex-step derivatives).

    Returns
    -------
    numpy.ndarray
        V, (..., n) for the broadcast batch shape; complex when a state is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``qd`` is not numbers of shape (..., n) or holds NaN or infinity, or when
        their batch shapes do not broadcast together.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    q, qd = as_states(arm, q, qd=qd)
    return np.einsum("...kj,...j->...k", coriolis_matrix(arm, q, qd), qd)


def potential_energy(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """P(q) = -sum_i g^T T_i J_i e4 = -sum_i m_i g^T T_i r_i (3.2.35, 3.2.36).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q : array_like
        Joint positions, (n,) or a batch (..., n); complex values are kept (complex-step
        derivatives).

    Returns
    -------
    numpy.ndarray
        P, shape (...): a NumPy scalar for one state; complex when ``q`` is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    T = twist_generators(arm, q)[1]
    first_moments = pseudo_inertias(arm)[:, :, 3]  # J_i e4 = [m r; m]
    return -np.einsum("a,...iab,ib->...", _homogeneous_gravity(arm), T, first_moments)


def gravity_vector(arm: ArmModel, q: np.ndarray) -> np.ndarray:
    """G_j(q) = dP/dq_j = -sum_i g^T (dT_i/dq_j) J_i e4 (3.2.43).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q : array_like
        Joint positions, (n,) or a batch (..., n); complex values are kept (complex-step
        derivatives).

    Returns
    -------
    numpy.ndarray
        G, (..., n); complex when ``q`` is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` is not numbers of shape (..., n) or holds NaN or infinity.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    dT = link_transform_derivatives(arm, q)
    first_moments = pseudo_inertias(arm)[:, :, 3]
    return -np.einsum("a,...ijab,ib->...j", _homogeneous_gravity(arm), dT, first_moments)


def kinetic_energy(arm: ArmModel, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """K = 1/2 qd^T M(q) qd (3.2.29).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast
        together. Complex values are kept (complex-step derivatives).

    Returns
    -------
    numpy.ndarray
        K, shape (...) for the broadcast batch shape: a NumPy scalar for one state; complex when
        a state is.

    Raises
    ------
    armdyn.ModelError
        When ``q`` or ``qd`` is not numbers of shape (..., n) or holds NaN or infinity, or when
        their batch shapes do not broadcast together.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    q, qd = as_states(arm, q, qd=qd)
    return 0.5 * np.einsum("...j,...jk,...k->...", qd, inertia_matrix(arm, q), qd)


def friction(arm: ArmModel, qd: np.ndarray) -> np.ndarray:
    """F(qd) = Fv qd + Fd(qd) (3.3.2): viscous G^2 B qd plus Coulomb |G| Tc+ or |G| Tc-, plus the
    Stribeck law Fs exp(-(qd/vs)^2) sgn(qd) and the sigmoid law of Gaz et al. (IEEE RA-L 4(4), 2019)
    A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift)) where the arm has them.

    At qd_i = 0 the Coulomb and Stribeck terms are zero (sgn 0 = 0).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    qd : array_like
        Joint velocities, (n,) or a batch (..., n). Complex values are kept, the Coulomb branch
        then chosen by NumPy's ordering of complex numbers (real part first); the Coulomb term
        is not differentiable at qd_i = 0.

    Returns
    -------
    numpy.ndarray
        F, (..., n); complex when ``qd`` is.

    Raises
    ------
    armdyn.ModelError
        When ``qd`` is not numbers of shape (..., n) or holds NaN or infinity.
    """
    qd = as_state(arm, qd, "qd")
    coulomb = arm.coulomb_friction
    value = arm.viscous_friction * qd + np.where(qd > 0, coulomb[:, 0], np.where(qd < 0, coulomb[:, 1], 0.0))
    stribeck, sigmoid = arm.stribeck_friction, arm.sigmoid_friction
    if np.any(stribeck[:, 0] != 0):
        value = value + stribeck_vector(stribeck, qd)
    if np.any(sigmoid[:, 0] != 0):
        value = value + sigmoid_vector(sigmoid, qd)
    return value


def inverse_dynamics(arm: ArmModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """tau = M(q) qdd + Vm(q, qd) qd + F(qd) + G(q) (3.3.1 without disturbance).

    Parameters
    ----------
    arm : ArmModel
        The arm (an ArmModel or a Robot); only its model data is used, never the compiled kernels.
    q, qd, qdd : array_like
        Joint positions, velocities and accelerations, (n,) or a batch (..., n); the batch
        shapes broadcast together. Complex values are kept: with a complex step i h in q, the
        imaginary part of tau over h is d tau/dq (as statespace.linearize uses it, on the arm
        without friction).

    Returns
    -------
    numpy.ndarray
        tau, (..., n) for the broadcast batch shape; complex when a state is.

    Raises
    ------
    armdyn.ModelError
        When ``q``, ``qd`` or ``qdd`` is not numbers of shape (..., n) or holds NaN or infinity,
        or when their batch shapes do not broadcast together.
    TypeError
        When the arm has symbolic (SymPy) parameters; numeric dynamics need numbers.
    """
    q, qd, qdd = as_states(arm, q, qd=qd, qdd=qdd)
    return (
        np.einsum("...jk,...k->...j", inertia_matrix(arm, q), qdd)
        + coriolis_vector(arm, q, qd)
        + friction(arm, qd)
        + gravity_vector(arm, q)
    )
