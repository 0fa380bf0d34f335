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
reflected motor inertia G^2 Jm. Stribeck and sigmoid friction (Link.stribeck, Link.sigmoid)
are not linear in their parameters and are not columns of W: tau = W phi holds for an arm
without them (armdyn.identification fits them).

A batch is computed a block of states at a time (about CHUNK_BYTES of W per block), so the
peak memory of a large batch is the result's own size plus a few times CHUNK_BYTES; a
result larger than MEMORY_LIMIT is refused beforehand with a ModelError saying how much it
needs (pass ``out=``, for example a numpy.memmap, to write it elsewhere).

Identification from these columns (least squares, physically consistent estimates, logs of real
arms) is armdyn.identification's.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from armdyn import inputs
from armdyn.errors import ModelError
from armdyn.kinematics import check_arm, joint_axes, joint_frames
from armdyn.model import ArmModel

BODY_PARAMETERS = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
JOINT_PARAMETERS = ("Fv", "Fc+", "Fc-", "Ia")

CHUNK_BYTES = 4 * 2**20
"""Bytes of W computed at a time: the temporaries of one block are a few times this."""
MEMORY_LIMIT: int | None = None
"""The largest result ``regressor`` allocates, in bytes; None (default) is half the machine's
physical memory (16 GiB where that cannot be read)."""
MAX_BASE_SAMPLES = 100_000
"""The most random states ``base_parameters`` stacks (for a 7-joint arm, 0.7 GB of regressor)."""


def _check_arm(arm: object, numeric: bool = True) -> None:
    check_arm(arm, numeric, " (ClosedForm.W and ClosedForm.phi give the parameterization symbolically)")


def _flag(value: object, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {value!r} ({type(value).__name__})")
    return bool(value)


def _memory_limit() -> int:
    if MEMORY_LIMIT is not None:
        return int(MEMORY_LIMIT)
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2
    except (AttributeError, ValueError, OSError):
        return 16 * 2**30


def _size(size: float) -> str:
    return f"{size / 2**30:.3g} GiB" if size >= 2**30 else f"{size / 2**20:.3g} MiB"


def parameter_names(arm: ArmModel) -> list[str]:
    """Names of phi: m1, mx1, ..., Izz1, ..., then Fv1, Fc+1, Fc-1, Ia1, ...

    Parameters
    ----------
    arm : ArmModel
        The arm.

    Returns
    -------
    list of str
        14 n names, in the order of ``parameters``.

    Raises
    ------
    TypeError
        When ``arm`` is not an armdyn arm (an ArmModel).
    """
    _check_arm(arm, numeric=False)
    bodies = [f"{name}{i + 1}" for i in range(arm.n) for name in BODY_PARAMETERS]
    return bodies + [f"{name}{i + 1}" for i in range(arm.n) for name in JOINT_PARAMETERS]


def parameters(arm: ArmModel) -> np.ndarray:
    """phi, the parameter vector with W(q, qd, qdd) phi = inverse_dynamics(q, qd, qdd).

    The linear parameterization of Table 3.3.1, property 9. Per link [m, m cx, m cy, m cz,
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz], the inertia about the link-frame origin in link-frame
    axes; then per joint [Fv, Fc+, Fc-, Ia], the joint-side viscous and Coulomb friction
    and the reflected motor inertia G^2 Jm. An arm's Stribeck and sigmoid friction are not
    in phi (they are not columns of W): for such an arm W phi is inverse dynamics less them.

    Parameters
    ----------
    arm : ArmModel
        The arm.

    Returns
    -------
    numpy.ndarray
        phi, shape (14 n,).

    Raises
    ------
    TypeError
        When ``arm`` is not an armdyn arm (an ArmModel), or when it has symbolic (SymPy)
        parameters; ClosedForm.phi gives them symbolically.
    """
    _check_arm(arm)
    values = []
    for link in arm.links:
        values += list(link.inertial.parameters())
    coulomb = arm.coulomb_friction
    for i in range(arm.n):
        values += [arm.viscous_friction[i], coulomb[i, 0], coulomb[i, 1], arm.reflected_inertia[i]]
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

    Raises
    ------
    armdyn.ModelError
        When an argument is not real numbers of shape (..., 3), holds NaN or infinity, or
        when their batch shapes do not broadcast together.
    """
    names = ("w", "v", "alpha", "a")
    batch, flat = inputs.batch_states(names, (w, v, alpha, a), 3)
    return _body_regressor(*flat).reshape(*batch, 6, 10)


def _body_regressor(w: np.ndarray, v: np.ndarray, alpha: np.ndarray, a: np.ndarray) -> np.ndarray:
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


def regressor(arm: ArmModel, q: object, qd: object, qdd: object, out: np.ndarray | None = None) -> np.ndarray:
    """W(q, qd, qdd), shape (..., n, 14 n), with W phi = tau (Table 3.3.1, property 9).

    Viscous and Coulomb friction and motors included: W ``parameters(arm)`` equals the inverse
    dynamics (less the Stribeck and sigmoid friction, which are not columns of W; they are
    fitted by armdyn.identification).
    Computed recursively, O(n d) for depth d (Atkeson, An and Hollerbach 1986), batched
    over any leading shape, a block of states at a time (see the module docstring): the
    peak memory is W's own size plus a few times CHUNK_BYTES.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    q, qd, qdd : array_like
        Joint positions, velocities and accelerations, (n,) or a batch (..., n); the batch
        shapes broadcast together.
    out : numpy.ndarray, optional
        A writable C-contiguous float64 array of W's shape to fill (a numpy.memmap for a W
        larger than memory); default None, a new array.

    Returns
    -------
    numpy.ndarray
        W, shape (..., n, 14 n).

    Raises
    ------
    armdyn.ModelError
        When a state is not real numbers of shape (..., n) or holds NaN or infinity, when the
        batch shapes do not broadcast together, when ``out`` is not a writable C-contiguous
        float64 array of W's shape, or when ``out`` is None and W would need more than
        MEMORY_LIMIT bytes (the message says how much).
    TypeError
        When ``arm`` is not an armdyn arm (an ArmModel), or when it has symbolic (SymPy)
        parameters; ClosedForm.W gives W symbolically.
    """
    return _stacked(arm, q, qd, qdd, None, out)


def _stacked(arm: ArmModel, q: object, qd: object, qdd: object, columns: np.ndarray | None, out: object) -> np.ndarray:
    """W[..., columns] (all columns for None), a block of states at a time into one result."""
    _check_arm(arm)
    n = arm.n
    batch, flat = inputs.batch_states(("q", "qd", "qdd"), (q, qd, qdd), n, f" for '{arm.name}'")
    width = 14 * n if columns is None else len(columns)
    shape = (*batch, n, width)
    if out is None:
        needed = 8 * int(np.prod(shape, dtype=float))
        if needed > _memory_limit():
            raise ModelError(
                f"the regressor of {int(np.prod(batch))} states of '{arm.name}' needs {_size(needed)} for its "
                f"result of shape {shape} (float64), more than the limit of {_size(_memory_limit())} "
                "(armdyn.dynamics.regressor.MEMORY_LIMIT, default half the machine's memory): compute it over "
                "fewer states at a time, or pass out= (a numpy.memmap, for instance)"
            )
    result = inputs.result(out, shape)
    if not batch:  # one state: the block without a batch axis (faster for NumPy's small arrays)
        W = _regressor_block(arm, flat[0][0], flat[1][0], flat[2][0])
        result[...] = W if columns is None else W[..., columns]
        return result
    target = result.reshape(-1, n, width)
    step = max(1, CHUNK_BYTES // (8 * n * 14 * n))
    for start in range(0, target.shape[0], step):
        block = slice(start, start + step)
        W = _regressor_block(arm, flat[0][block], flat[1][block], flat[2][block])
        target[block] = W if columns is None else W[..., columns]
    return result


def _regressor_block(arm: ArmModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """W of a block of states, each (B, n) (or one state (n,)) float64, as (B, n, 14 n) (or (n, 14 n))."""
    batch = q.shape[:-1]
    n = arm.n
    links, joints = joint_frames(arm, q)
    z, o = joint_axes(arm, joints)
    revolute = np.array([kind == "revolute" for kind in arm.kinds])
    S = np.concatenate([np.where(revolute[:, None], z, 0.0), np.where(revolute[:, None], _cross(o, z), z)], -1)
    ancestors = arm.ancestors.astype(float)  # [i, j]: joint j moves link i
    # world spatial velocity of each link (at the world origin): v_i = sum_j S_j qd_j
    v = np.einsum("ij,...jk,...j->...ik", ancestors, S, qd)
    # each joint's Sdot = v_j x S_j (v_j the velocity of the link the joint moves)
    w_, u_ = v[..., :3], v[..., 3:]
    Sdot = np.concatenate([_cross(w_, S[..., :3]), _cross(w_, S[..., 3:]) + _cross(u_, S[..., :3])], -1)
    gravity = np.concatenate([np.zeros(3), -arm.gravity.astype(float)])
    a = gravity + np.einsum("ij,...jk->...ik", ancestors, S * qdd[..., None] + Sdot * qd[..., None])
    # into each link's frame: w_L = R^T w, v_L = R^T (v + w x p), likewise for the acceleration
    R, p = links[..., :3, :3], links[..., :3, 3]
    Rt = np.swapaxes(R, -1, -2)
    w_L = np.einsum("...ab,...b->...a", Rt, v[..., :3])
    v_L = np.einsum("...ab,...b->...a", Rt, v[..., 3:] + _cross(v[..., :3], p))
    alpha_L = np.einsum("...ab,...b->...a", Rt, a[..., :3])
    a_L = np.einsum("...ab,...b->...a", Rt, a[..., 3:] + _cross(a[..., :3], p))
    Y = _body_regressor(w_L, v_L, alpha_L, a_L)  # (..., n, 6, 10), link frames
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
    arm : ArmModel
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

    arm: ArmModel
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
            When a state is not real numbers of shape (..., n) or holds NaN or infinity, when
            the batch shapes do not broadcast together, or when W_base would need more than
            MEMORY_LIMIT bytes.
        """
        return _stacked(self.arm, q, qd, qdd, self.columns, None)

    def __len__(self) -> int:
        return len(self.columns)


def _term(coefficient: float, name: str) -> str:
    if abs(coefficient - 1.0) < 1e-9:
        return name
    if abs(coefficient + 1.0) < 1e-9:
        return f"-{name}"
    return f"{coefficient:.6g}*{name}"


def base_parameters(
    arm: ArmModel,
    samples: int = 200,
    seed: int = 0,
    tolerance: float = 1e-9,
    drives: bool = True,
    at_rest: bool = False,
) -> BaseParameters:
    """The base parameters by QR with column pivoting of regressors stacked at random states.

    Columns whose pivot falls below ``tolerance`` times the largest are dependent: they are
    regrouped into the independent ones they are combinations of (Gautier, "Numerical
    calculation of the base inertial parameters of robots", J. Robot. Syst. 8(4), 1991).
    The random states are uniform within the joint limits (within [-pi, pi] where a limit
    is infinite), with velocities and accelerations uniform in [-2, 2]. With every joint
    moving, [qd > 0] + [qd < 0] is 1, so the Coulomb columns of a joint whose gravity torque is
    constant (a vertical prismatic joint) take that constant in: such a set explains every
    moving state, which is what ``identify`` estimates from; ``at_rest=True`` also samples joints
    at rest (a quarter of the velocities 0) and gives the set that explains tau at rest too.

    Parameters
    ----------
    arm : ArmModel
        The arm.
    samples : int, optional
        Number of random states stacked (default 200, from 1 to MAX_BASE_SAMPLES = 100,000:
        the stacked regressor holds samples x n rows).
    seed : int, optional
        Seed of the random generator (default 0).
    tolerance : float, optional
        Relative pivot size below which a column counts as dependent (default 1e-9).
    drives : bool, optional
        True (default) includes the friction and motor columns; False leaves them out
        (the rigid-body parameters only).
    at_rest : bool, optional
        False (default): sample moving joints only (the set ``identify`` estimates from moving
        data); True: a quarter of the joint velocities 0, for a W_base phi_base equal to tau at
        rest as well (``generate_code(arm, ["Wb"])`` uses this).

    Returns
    -------
    BaseParameters
        The kept columns, the regrouping matrix, readable names and the arm's phi_base.

    Raises
    ------
    armdyn.ModelError
        When ``samples`` is below 1 or above MAX_BASE_SAMPLES, ``seed`` is negative, or ``tolerance`` is not a number
        in (0, 1).
    TypeError
        When ``arm`` is not an armdyn arm (an ArmModel) or has symbolic (SymPy) parameters, when
        ``samples`` or ``seed`` is not an integer, or when ``drives`` or ``at_rest`` is not a bool.
    """
    from scipy.linalg import qr

    _check_arm(arm)
    samples = inputs.integer(
        samples, "samples", 1, MAX_BASE_SAMPLES, " (the stacked regressor grows with it; a few hundred suffice)"
    )
    seed = inputs.integer(seed, "seed", 0)
    drives = _flag(drives, "drives")
    at_rest = _flag(at_rest, "at_rest")
    given = inputs.vector(tolerance, "tolerance")
    if given.shape != (1,) or not 0 < given[0] < 1:
        raise ModelError(f"tolerance must be one number in (0, 1), got {given.tolist()}")
    tolerance = float(given[0])
    rng = np.random.default_rng(seed)
    lower, upper = arm.qlim
    low = np.where(np.isfinite(lower), lower, -np.pi)
    high = np.where(np.isfinite(upper), upper, np.pi)
    q = rng.uniform(low, high, (samples, arm.n))
    qd, qdd = rng.uniform(-2, 2, (2, samples, arm.n))
    if at_rest:
        qd[rng.random(qd.shape) < 0.25] = 0.0
    width = 14 * arm.n if drives else 10 * arm.n
    stacked = regressor(arm, q, qd, qdd)[..., :width].reshape(-1, width)
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
    names_all = parameter_names(arm)
    names = []
    for row in regrouping:
        terms = [_term(row[k], names_all[k]) for k in np.flatnonzero(row)]
        names.append(" + ".join(terms).replace("+ -", "- "))
    return BaseParameters(arm, independent, regrouping, names, regrouping @ parameters(arm)[:width])
