"""The dynamics and kinematics of an arm as free functions: one state or a batch, with ``out=``.

Every function takes the arm first (a Robot: an ArmModel with its packed model), then
states of shape (n,) for one state or (..., n) for a batch, and returns the matching
shape. robot.Robot takes these functions as its methods, so ``arm.inertia_matrix(q)``
and ``api.inertia_matrix(arm, q)`` are the same call.

A one-state call with 1-D C-contiguous float64 arrays goes straight to a compiled kernel
that checks lengths and finiteness itself (an explicit signature, so any other input fails
the type match with a TypeError). Anything else, and any input the kernel refuses, takes
the general path: armdyn.inputs converts, checks (raising a ModelError that names the
argument), broadcasts, and one batch kernel runs over all states.

The functions with that pair of paths are declared below with their signatures and docstrings,
and written out from one row each of TABLE (their one-state and batch kernels, the names of
their states, the shape of their result) by ``_public``, once, at import.
"""

from __future__ import annotations
import __future__

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numba import get_num_threads, set_num_threads
from numba.core.errors import NumbaError

from armdyn import inputs, kinematics
from armdyn.dynamics import frames
from armdyn.dynamics.aba import aba_one
from armdyn.dynamics.aba_blocks import aba_blocks
from armdyn.dynamics.coriolis import coriolis_batch, coriolis_one
from armdyn.dynamics.crba import crba_batch, crba_one
from armdyn.dynamics.derivatives import (
    forward_dynamics_derivatives_batch,
    forward_dynamics_derivatives_one,
    rnea_derivatives_batch,
    rnea_derivatives_one,
)
from armdyn.dynamics.energy import energy_batch, energy_one
from armdyn.dynamics.frames import TOOL, jacobian_dot_one, jacobian_one, pose_one, transforms_one
from armdyn.dynamics.friction import friction_batch, friction_one
from armdyn.dynamics.rnea import (
    CORIOLIS,
    GRAVITY_ONLY,
    INVERSE_DYNAMICS,
    NONLINEAR,
    WITH_WRENCH,
    coriolis_vector_one,
    gravity_one,
    inverse_dynamics_one,
    nonlinear_one,
    rnea_batch,
)
from armdyn.dynamics.rnea_blocks import rnea_blocks
from armdyn.dynamics.status import OK
from armdyn.errors import ArgumentError, ModelError

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from armdyn.robot import Robot

_Declaration = TypeVar("_Declaration", bound=Callable[..., object])

_empty = np.empty
# What the compiled one-state entries raise for arguments they do not take (lists, batches, other
# dtypes: TypeError; an empty list: ValueError; a masked array: a NumbaError): the general path
# then checks them and names what is wrong.
_NOT_ONE_STATE = (TypeError, ValueError, NumbaError)
_NO_MATRIX = np.empty((0, 0))  # a kernel's optional matrix output, not asked for
_EXACT_COULOMB: dict[int, np.ndarray] = {}  # eps = 0 per joint count, read (never written) by the kernels
_NO_WRENCH = np.zeros((1, 6))


SERIAL_WORK = 8192
"""Result values below which a batch runs on the calling thread alone: waking the idle batch
threads costs about 80 us, more than a thousand states take on one (measured crossover between
1,000 and 2,000 states of inverse or forward dynamics on a six-joint arm)."""


def _launch(kernel: Callable, work: int, *args: object) -> None:
    """kernel(*args), on one thread when the result has fewer than SERIAL_WORK values."""
    threads = get_num_threads()
    if work >= SERIAL_WORK or threads == 1:
        kernel(*args)
        return
    set_num_threads(1)
    try:
        kernel(*args)
    finally:
        set_num_threads(threads)


def _where(arm: Robot) -> str:
    return f" for '{arm.name}' (n = {arm.n})"


def _model(arm: Robot) -> np.ndarray:
    if arm.packed is None:
        raise ArgumentError(f"arm '{arm.name}' has symbolic parameters; numeric dynamics and kinematics need numbers")
    return arm.packed


_FRAMES = {"base": frames.WORLD, "tool": frames.LOCAL}
# the fast path's link and frame go unchecked to the kernel: a link that is not an int fails the
# signature (TypeError; OverflowError beyond int64), a frame not in _FRAMES fails the lookup (KeyError)
_NOT_ONE_STATE_OR_OPTION = (*_NOT_ONE_STATE, KeyError, OverflowError)


def _target(arm: Robot, link: object) -> int:
    """frames.TOOL for None, else the checked link index."""
    return frames.TOOL if link is None else kinematics.link_index(arm, link)


def _frame(frame: object) -> int:
    """frames.WORLD or frames.LOCAL for "base" or "tool", else the ModelError of check_frame."""
    if type(frame) is str and frame in _FRAMES:
        return _FRAMES[frame]
    kinematics.check_frame(frame)
    assert isinstance(frame, str)  # check_frame lets only the strings "base" and "tool" through
    return _FRAMES[frame]


def _with_target(kernel: Callable, *options: int) -> Callable:
    """A batch kernel with its trailing integer options (target, frame) bound."""

    def call(model: np.ndarray, *arrays: np.ndarray) -> None:
        kernel(model, *arrays[:-1], *options, arrays[-1])

    return call


def _rnea(
    arm: Robot, flags: int, names: tuple[str, ...], states: tuple, out: object, trailing: tuple, f_ext: object = None
) -> np.ndarray:
    """The general path of the RNEA family: checked, broadcast, vectorized across states."""
    model = _model(arm)
    batch, flat = inputs.batch_states(names, states, arm.n, _where(arm))
    flat += [flat[-1]] * (3 - len(flat))
    result = inputs.result(out, (*batch, *trailing))
    target = result.reshape(-1, arm.n)
    if not target.shape[0]:
        return result
    if f_ext is None:
        _launch(rnea_blocks, target.size, model, flat[0], flat[1], flat[2], flags, target)
    else:
        wrench = inputs.wrenches(f_ext, batch)
        _launch(rnea_batch, target.size, model, flat[0], flat[1], flat[2], wrench, flags | WITH_WRENCH, target)
    return result


def _batch(
    arm: Robot, kernel: Callable, names: tuple[str, ...], states: tuple, out: object, trailing: tuple
) -> np.ndarray:
    """The general path of the other kernels: checked, broadcast, one parallel batch call."""
    model = _model(arm)
    batch, flat = inputs.batch_states(names, states, arm.n, _where(arm))
    result = inputs.result(out, (*batch, *trailing))
    target = result.reshape(-1, *trailing)
    if target.shape[0]:
        _launch(kernel, target.size, model, *flat, target)
    return result


def _forward(
    arm: Robot, kernel: Callable, names: tuple[str, ...], states: tuple, out: object, trailing: tuple
) -> np.ndarray:
    """The general path of a kernel that may find M(q) singular: checked, broadcast, one parallel
    batch call that marks each singular state's joint, and the error naming the first."""
    model = _model(arm)
    batch, flat = inputs.batch_states(names, states, arm.n, _where(arm))
    result = inputs.result(out, (*batch, *trailing))
    singular = np.full(flat[0].shape[0], -1)
    if singular.size:
        _launch(kernel, result.size, model, *flat, result.reshape(-1, *trailing), singular)
    if singular.max(initial=-1) >= 0:
        raise _singular(arm, flat[0], singular, batch)
    return result


@dataclass(frozen=True)
class Entry:
    """How one public function computes: its compiled kernel pair and the shape of its result.

    The one-state kernel takes (model, *states, *options, result) and returns a status; the
    general path ``general(arm, batch, names, states, out, trailing)`` checks and broadcasts the
    states and runs ``batch`` over all of them (for the RNEA family ``batch`` is the flags of
    rnea.rnea_core and ``general`` is _rnea).
    """

    one: Callable
    batch: Callable | int
    shape: str  # the result's shape for one state, in n: "n", "n, n", "2", "n, 4, 4"...
    general: Callable = _batch
    options: str = ""  # the one-state kernel's arguments between the states and the result
    wrench: bool = False  # takes f_ext (the one-state kernel only when it is None)
    target: bool = False  # takes frame and link, as jacobian


TABLE = {
    "inverse_dynamics": Entry(inverse_dynamics_one, INVERSE_DYNAMICS, "n", _rnea, wrench=True),
    "nonlinear_terms": Entry(nonlinear_one, NONLINEAR, "n", _rnea),
    "coriolis_vector": Entry(coriolis_vector_one, CORIOLIS, "n", _rnea),
    "gravity_vector": Entry(gravity_one, GRAVITY_ONLY, "n", _rnea),
    "friction": Entry(friction_one, friction_batch, "n"),
    "inertia_matrix": Entry(crba_one, crba_batch, "n, n"),
    "coriolis_matrix": Entry(coriolis_one, coriolis_batch, "n, n"),
    "forward_dynamics": Entry(aba_one, aba_blocks, "n", _forward),
    "energies": Entry(energy_one, energy_batch, "2"),
    "link_transforms": Entry(transforms_one, frames.transforms_batch, "n, 4, 4"),
    "tool_pose": Entry(pose_one, _with_target(frames.pose_batch, TOOL), "4, 4", options="TOOL"),
    "jacobian": Entry(jacobian_one, frames.jacobian_batch, "6, n", target=True),
    "jacobian_dot": Entry(jacobian_dot_one, frames.jacobian_dot_batch, "6, n", target=True),
}
"""The public functions with a one-state fast path and a general path, by name (see _public)."""

# the link unchecked when a plain non-negative int (the kernel refuses it out of range); anything else made out
# of range, for the general path's checks (Numba would convert a bool or a float to the kernel's int)
SOURCES: dict[str, str] = {}
"""The source written out for each public function of TABLE (for reading; tracebacks name it)."""
_TARGET = "target = TOOL if link is None else link if type(link) is int and link >= 0 else arm.n\n        "
_TEMPLATE = """
def {name}({parameters}):
    {guard}{shape_prelude}result = _empty({shape}) if out is None else out
    {indent}try:
        {indent}{target}if {one}(arm.packed, {states}, {options}result) == {ok}:
            {indent}return result
    {indent}except {refused}:
        {indent}if (thawed := inputs.thawed({states})) is not None:
            {indent}return {name}(arm, *thawed, {passed}out=out)
    return {general}(arm, {batch}, {names}, ({states},), out, {trailing}{wrench})
"""


def _public(declaration: _Declaration) -> _Declaration:
    """The public function of TABLE's row for ``declaration`` (its name, signature and docstring):

        result = new (n-shaped) array, or out
        if one-state kernel(model, *states, result) == OK: return result   (the fast path)
        a read-only vector among the states: again with writable copies
        return the general path (checked, broadcast, one batch call)

    The body is written out for each row once, at import, so that the fast path runs no more
    Python than a hand-written one (about 1 us a call on a six-joint arm)."""
    name = declaration.__name__
    row = TABLE[name]
    signature = inspect.signature(declaration)
    extra = {"f_ext"} if row.wrench else {"frame", "link"} if row.target else set()
    states = [p for p in signature.parameters if p not in {"arm", "out", *extra}]
    if list(signature.parameters) != ["arm", *states, *(["f_ext"] if row.wrench else []),
                                      *(["frame", "link"] if row.target else []), "out"]:  # fmt: skip
        raise TypeError(f"{name}: its parameters do not match its row of TABLE")
    dims = [d.strip() for d in row.shape.split(",")]
    shared = dims.count("n") > 1
    n = "n" if shared else "arm.n"
    shape = ", ".join(n if d == "n" else d for d in dims)
    passed = "frame=frame, link=link, " if row.target else ""
    batch = f"_{name}_batch"
    if row.target:  # the general path checks the link and the frame first, then binds them
        batch = f"_with_target({batch}, _target(arm, link), _frame(frame))"
    source = _TEMPLATE.format(
        name=name,
        parameters=", ".join(signature.parameters),
        guard="if f_ext is None:\n        " if row.wrench else "",
        indent="    " if row.wrench else "",
        shape_prelude=f"n = arm.n\n    {'    ' if row.wrench else ''}" if shared else "",
        shape=f"({shape})" if len(dims) > 1 else shape,
        target=_TARGET if row.target else "",
        one=f"_{name}_one",
        states=", ".join(states),
        options=f"{row.options}, " if row.options else "target, _FRAMES[frame], " if row.target else "",
        ok=OK,
        refused="_NOT_ONE_STATE_OR_OPTION" if row.target else "_NOT_ONE_STATE",
        passed=passed,
        general=f"_{name}_general",
        batch=batch,
        names=repr(tuple(states)),
        trailing=f"({shape})" if len(dims) > 1 else f"({shape},)",
        wrench=", f_ext" if row.wrench else "",
    )
    namespace = globals()
    namespace[f"_{name}_one"], namespace[f"_{name}_batch"], namespace[f"_{name}_general"] = (
        row.one, row.batch, row.general
    )  # fmt: skip
    exec(
        compile(source, f"<armdyn.dynamics.api {name}>", "exec", flags=__future__.annotations.compiler_flag), namespace
    )
    SOURCES[name] = source
    function = namespace[name]
    function.__defaults__ = declaration.__defaults__
    function.__doc__ = declaration.__doc__
    function.__annotations__ = declaration.__annotations__
    function.__qualname__ = declaration.__qualname__
    return function


@_public
def inverse_dynamics(
    arm: Robot,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    f_ext: ArrayLike | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Joint torques tau = M(q) qdd + Vm(q, qd) qd + F(qd) + G(q) (3.3.1).

    The recursive Newton-Euler algorithm, O(n) (Featherstone 2008, 5.3); friction and the
    reflected motor inertia G^2 Jm included. With a wrench the tool exerts on its
    surroundings, tau gains J^T f_ext.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd, qdd : array_like
        Joint positions, velocities and accelerations, (n,) or a batch (..., n); the batch
        shapes broadcast together.
    f_ext : array_like, optional
        Wrench [force; moment] the tool exerts, in the tool frame about the tool point, (6,)
        or one per state (..., 6).
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        tau, shape (..., n).

    Raises
    ------
    ModelError
        When a state has the wrong shape or holds NaN or infinity, when ``out`` does not fit,
        or when the arm has symbolic parameters.
    """


@_public
def nonlinear_terms(arm: Robot, q: ArrayLike, qd: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """N(q, qd) = Vm(q, qd) qd + F(qd) + G(q), so that M qdd + N = tau (3.3.1).

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        N, shape (..., n).

    Raises
    ------
    ModelError
        When a state or ``out`` is invalid (see inverse_dynamics).
    """


@_public
def coriolis_vector(arm: Robot, q: ArrayLike, qd: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """V(q, qd) = Vm(q, qd) qd, the Coriolis and centripetal torques (3.3.1).

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        V, shape (..., n).

    Raises
    ------
    ModelError
        When a state or ``out`` is invalid (see inverse_dynamics).
    """


@_public
def gravity_vector(arm: Robot, q: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """G(q), the gravity torques, dP/dq (3.2.43).

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        G, shape (..., n).

    Raises
    ------
    ModelError
        When q or ``out`` is invalid (see inverse_dynamics).
    """


@_public
def friction(arm: Robot, qd: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """F(qd) = Fv qd + Fd(qd), joint side: G^2 B qd plus |G| Tc+ (qd > 0) or |G| Tc- (qd < 0)
    (Table 3.3.1, property 6), plus the Stribeck law Fs exp(-(qd/vs)^2) sgn(qd) and the sigmoid law
    A / (1 + exp(-alpha (qd + shift))) - A / (1 + exp(-alpha shift)) of Gaz et al. (IEEE RA-L 4(4),
    2019) where the links have them (Link.stribeck, Link.sigmoid).

    Parameters
    ----------
    arm : Robot
        The arm.
    qd : array_like
        Joint velocities, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        F, shape (..., n).

    Raises
    ------
    ModelError
        When qd or ``out`` is invalid (see inverse_dynamics).
    """


@_public
def inertia_matrix(arm: Robot, q: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """M(q), symmetric positive definite, with G^2 Jm on the diagonal (3.2.31).

    The composite-rigid-body algorithm (Featherstone 2008, 6.2).

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        M, shape (..., n, n).

    Raises
    ------
    ModelError
        When q or ``out`` is invalid (see inverse_dynamics).
    """


@_public
def coriolis_matrix(arm: Robot, q: ArrayLike, qd: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """The Christoffel form Vm(q, qd) (3.3.48): Mdot - 2 Vm is skew symmetric.

    Echeandia and Wensing (2021), Algorithm 2, O(n d) for depth d.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        Vm, shape (..., n, n).

    Raises
    ------
    ModelError
        When a state or ``out`` is invalid (see inverse_dynamics).
    """


@_public
def forward_dynamics(
    arm: Robot, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, out: np.ndarray | None = None
) -> np.ndarray:
    """Joint accelerations qdd = M(q)^-1 (tau - N(q, qd)) (Section 3.4).

    The articulated-body algorithm, O(n) (Featherstone 2008, 7.3).

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd, tau : array_like
        Joint positions, velocities and torques, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        qdd, shape (..., n).

    Raises
    ------
    ModelError
        When a state or ``out`` is invalid (see inverse_dynamics), or when M(q) is singular at a
        state (a joint about which nothing with mass or inertia moves): the message names the
        state and the joint.
    """


def _singular(arm: Robot, q: np.ndarray, singular: np.ndarray, batch: tuple[int, ...]) -> ModelError:
    """The error for a state whose inertia matrix is singular, naming the state and the joint."""
    index = int(np.flatnonzero(singular >= 0)[0])
    joint = arm.joint_names[singular[index]]
    where = f"at state {tuple(int(k) for k in np.unravel_index(index, batch))} " if batch else ""
    return ModelError(
        f"M(q) of '{arm.name}' is singular {where}(q = {np.array2string(q[index], precision=4)}): nothing with "
        f"mass or inertia moves about joint '{joint}' there (its articulated inertia vanishes). Give the links "
        "beyond it mass and inertia, or lock the joint"
    )


@_public
def energies(arm: Robot, q: ArrayLike, qd: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """Kinetic and potential energy together, [K, P] (3.2.29 and 3.2.35).

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or (..., n).
    out : numpy.ndarray, optional
        Where to write the result.

    Returns
    -------
    numpy.ndarray
        Shape (..., 2): K, then P.

    Raises
    ------
    ModelError
        When a state or ``out`` is invalid (see inverse_dynamics).
    """


def kinetic_energy(arm: Robot, q: ArrayLike, qd: ArrayLike) -> float | np.ndarray:
    """K = 1/2 qd^T M(q) qd (3.2.29), with the motor rotors' 1/2 G^2 Jm qd^2.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or (..., n).

    Returns
    -------
    float or numpy.ndarray
        K: a float for one state, shape (...) for a batch.

    Raises
    ------
    ModelError
        When a state is invalid (see inverse_dynamics).
    """
    values = energies(arm, q, qd)
    return float(values[0]) if values.ndim == 1 else values[..., 0]


def potential_energy(arm: Robot, q: ArrayLike) -> float | np.ndarray:
    """P(q) = -sum_i m_i g^T p_ci (3.2.35).

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, (n,) or (..., n).

    Returns
    -------
    float or numpy.ndarray
        P: a float for one state, shape (...) for a batch.

    Raises
    ------
    ModelError
        When q is invalid (see inverse_dynamics).
    """
    values = energies(arm, q, q)
    return float(values[1]) if values.ndim == 1 else values[..., 1]


def inertia_matrix_dot(arm: Robot, q: ArrayLike, qd: ArrayLike) -> np.ndarray:
    """dM/dt = Vm + Vm^T, exact for the Christoffel Vm (Table 3.3.1, property 4).

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or (..., n).

    Returns
    -------
    numpy.ndarray
        Mdot, shape (..., n, n).

    Raises
    ------
    ModelError
        When a state is invalid (see inverse_dynamics).
    """
    Vm = coriolis_matrix(arm, q, qd)
    return Vm + np.swapaxes(Vm, -1, -2)


@_public
def link_transforms(arm: Robot, q: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """T_i(q), the world pose of every link frame (Appendix A), compiled.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        T_i, (..., n, 4, 4): base @ the chain of placements, joint motions and frame offsets.

    Raises
    ------
    ModelError
        When q is invalid (see inverse_dynamics) or ``out`` does not fit.
    """


@_public
def tool_pose(arm: Robot, q: ArrayLike, out: np.ndarray | None = None) -> np.ndarray:
    """The tool's world pose T_k(q) @ tool (k the tool link), compiled.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        The pose, (..., 4, 4).

    Raises
    ------
    ModelError
        When q is invalid (see inverse_dynamics) or ``out`` does not fit.
    """


@_public
def jacobian(
    arm: Robot, q: ArrayLike, frame: str = "base", link: int | None = None, out: np.ndarray | None = None
) -> np.ndarray:
    """The geometric Jacobian J(q), [v; w] = J qd with the linear rows first, compiled.

    Column j is [z_j x (p - o_j); z_j] for a revolute joint and [z_j; 0] for a prismatic one
    (Appendix A), zero for joints that do not move the point p.

    Parameters
    ----------
    arm : Robot
        The arm.
    q : array_like
        Joint positions, (n,) or a batch (..., n).
    frame : str, optional
        "base" (default): rows in world axes; "tool": rows in the axes of the target frame.
    link : int, optional
        The link whose frame origin is the point (and whose axes "tool" means); default
        (None) the tool.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        J, (..., 6, n).

    Raises
    ------
    ModelError
        When q is invalid (see inverse_dynamics), ``out`` does not fit, ``frame`` is not
        "base" or "tool", or ``link`` is not None or an integer index of a link.
    """


@_public
def jacobian_dot(
    arm: Robot,
    q: ArrayLike,
    qd: ArrayLike,
    frame: str = "base",
    link: int | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """dJ/dt, the time derivative of ``jacobian`` (same point and axes), compiled.

    For a revolute column, d/dt [z x (p - o); z] = [zdot x (p - o) + z x (pdot - odot); zdot],
    for a prismatic one [zdot; 0], with zdot = w_parent x z; in the target's axes,
    d/dt (R^T J) = R^T (dJ/dt - [w]x J). Jdot qd is the acceleration of the point (and of the
    frame's rotation) at qdd = 0, the term task-space dynamics need.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd : array_like
        Joint positions and velocities, (n,) or a batch (..., n); the batch shapes broadcast.
    frame : str, optional
        "base" (default) or "tool", as for ``jacobian``.
    link : int, optional
        The link whose frame origin is the point; default (None) the tool.
    out : numpy.ndarray, optional
        Where to write the result: C-contiguous float64 of the result's shape.

    Returns
    -------
    numpy.ndarray
        dJ/dt, (..., 6, n).

    Raises
    ------
    ModelError
        As for ``jacobian``, and when qd is invalid.
    """


def smoothing_per_joint(arm: Robot, value: object) -> np.ndarray:
    """coulomb_smoothing as eps >= 0 per joint (n,): None is 0 (the exact sign law). A bool is
    refused: True is no smoothing width (rad/s or m/s)."""
    if value is None:
        exact = _EXACT_COULOMB.get(arm.n)
        if exact is None:
            exact = _EXACT_COULOMB[arm.n] = np.zeros(arm.n)
        return exact
    if isinstance(value, (bool, np.bool_)) or getattr(value, "dtype", None) == np.bool_:
        raise ModelError(f"coulomb_smoothing must be eps >= 0 (rad/s or m/s), one for all joints or one per joint"
                         f"{_where(arm)}, got {value!r} (a bool, not a width)")  # fmt: skip
    eps = inputs.numbers(value, "coulomb_smoothing", where=_where(arm))
    if eps.shape not in ((), (arm.n,)) or np.any(eps < 0):
        raise ModelError(f"coulomb_smoothing must be eps >= 0 (rad/s or m/s), one for all joints or one per joint"
                         f"{_where(arm)}, got {np.array2string(eps, precision=4)}")  # fmt: skip
    return np.ascontiguousarray(np.broadcast_to(eps, (arm.n,)), dtype=float).copy()


def inverse_dynamics_derivatives(
    arm: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, out: tuple | None = None, coulomb_smoothing: object = None
) -> tuple[np.ndarray, np.ndarray]:
    """d tau/dq and d tau/dqd of tau = M qdd + Vm qd + F + G, analytic (Section 3.4).

    The recursive Newton-Euler algorithm differentiated along with itself in the world frame
    (Carpentier and Mansard, RSS 2018; armdyn.dynamics.derivatives), compiled, one state or a
    batch in one parallel call. The reflected motor inertia and the viscous friction are included;
    the exact Coulomb law is constant away from zero velocity and adds nothing, its smoothed form
    tanh(qd / eps) Tc (``coulomb_smoothing``, as ``simulate`` uses it) adds its slope; the Stribeck
    law (its sign smoothed alike) and the sigmoid law add theirs.
    d tau/dqdd is M (``inertia_matrix``).

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd, qdd : array_like
        Joint positions, velocities and accelerations, (n,) or a batch (..., n).
    out : tuple of two numpy.ndarray, optional
        Where to write d tau/dq and d tau/dqd, each C-contiguous float64 (..., n, n).
    coulomb_smoothing : float or array_like, optional
        eps >= 0 of the smoothed Coulomb law, one for all joints or one per joint; None or 0 is
        the exact sign law.

    Returns
    -------
    tuple of numpy.ndarray
        (d tau/dq, d tau/dqd), each (..., n, n), row i the derivatives of tau_i.

    Raises
    ------
    ModelError
        When a state, ``out`` or ``coulomb_smoothing`` is invalid (see inverse_dynamics), or the
        arm is symbolic.
    """
    model = _model(arm)
    n = arm.n
    eps = smoothing_per_joint(arm, coulomb_smoothing)
    if out is None or (type(out) in (tuple, list) and len(out) == 2):  # one plain state: straight to the kernel
        d_q, d_qd = (np.empty((n, n)), np.empty((n, n))) if out is None else out
        try:
            if rnea_derivatives_one(model, q, qd, qdd, eps, d_q, d_qd, _NO_MATRIX) == 0:
                return d_q, d_qd
        except _NOT_ONE_STATE:
            if (thawed := inputs.thawed(q, qd, qdd)) is not None:
                q, qd, qdd = thawed
                return inverse_dynamics_derivatives(arm, q, qd, qdd, out=out, coulomb_smoothing=coulomb_smoothing)
    batch, flat = inputs.batch_states(("q", "qd", "qdd"), (q, qd, qdd), n, _where(arm))
    results = inputs.results(out, [(*batch, n, n)] * 2, ("d tau/dq", "d tau/dqd"), flat)
    if flat[0].shape[0]:
        views = [r.reshape(-1, n, n) for r in results]
        _launch(rnea_derivatives_batch, results[0].size, model, *flat, eps, *views)
    return results[0], results[1]


def forward_dynamics_derivatives(
    arm: Robot, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, out: tuple | None = None, coulomb_smoothing: object = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """d qdd/dq, d qdd/dqd and d qdd/dtau of qdd = M^-1 (tau - N), analytic (Section 3.4).

    qdd = FD(q, qd, tau) by the articulated-body algorithm, the inverse dynamics' derivatives
    there, and one Cholesky factorization of M (Carpentier and Mansard 2018): d qdd/dq =
    -M^-1 d tau/dq and d qdd/dqd = -M^-1 d tau/dqd by triangular solves, d qdd/dtau = M^-1;
    compiled, one state or a batch in one parallel call.

    Parameters
    ----------
    arm : Robot
        The arm.
    q, qd, tau : array_like
        Joint positions, velocities and torques, (n,) or a batch (..., n).
    out : tuple of three numpy.ndarray, optional
        Where to write the three results, each C-contiguous float64 (..., n, n).
    coulomb_smoothing : float or array_like, optional
        eps >= 0 of the smoothed Coulomb law the plant follows (qdd and its slope), one for all
        joints or one per joint; None or 0 is the exact sign law.

    Returns
    -------
    tuple of numpy.ndarray
        (d qdd/dq, d qdd/dqd, d qdd/dtau), each (..., n, n).

    Raises
    ------
    ModelError
        When a state, ``out`` or ``coulomb_smoothing`` is invalid, or M(q) is singular at a state.
    """
    model = _model(arm)
    n = arm.n
    eps = smoothing_per_joint(arm, coulomb_smoothing)
    if out is None or (type(out) in (tuple, list) and len(out) == 3):  # one plain state: straight to the kernel
        d_q, d_qd, d_tau = (np.empty((n, n)), np.empty((n, n)), np.empty((n, n))) if out is None else out
        try:
            if forward_dynamics_derivatives_one(model, q, qd, tau, eps, d_q, d_qd, d_tau) == 0:
                return d_q, d_qd, d_tau
        except _NOT_ONE_STATE:
            if (thawed := inputs.thawed(q, qd, tau)) is not None:
                q, qd, tau = thawed
                return forward_dynamics_derivatives(arm, q, qd, tau, out=out, coulomb_smoothing=coulomb_smoothing)
    batch, flat = inputs.batch_states(("q", "qd", "tau"), (q, qd, tau), n, _where(arm))
    results = inputs.results(out, [(*batch, n, n)] * 3, ("d qdd/dq", "d qdd/dqd", "d qdd/dtau"), flat)
    singular = np.full(flat[0].shape[0], -1)
    if singular.size:
        views = [r.reshape(-1, n, n) for r in results]
        _launch(forward_dynamics_derivatives_batch, results[0].size, model, *flat, eps, *views, singular)
    if singular.max(initial=-1) >= 0:
        raise _singular(arm, flat[0], singular, batch)
    return results[0], results[1], results[2]
