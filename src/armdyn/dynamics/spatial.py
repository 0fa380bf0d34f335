"""Small compiled pieces every kernel shares: the Numba options, sin/cos, the state check and the
spatial-algebra steps (Featherstone, Rigid Body Dynamics Algorithms, 2008, chapter 2).

Conventions. Every joint moves about/along the z axis of its body frame (packed.py), so
S = e_3 (revolute) or e_6 (prismatic) in body coordinates. Spatial vectors are [angular; linear].
A body's mass properties are (m, h = m c, I_O about the body origin). Joint i's transform:
R_i (body axes in parent coordinates) and p_i (body origin in the parent). Motion vectors go
parent -> child as w' = R^T w, v' = R^T (v + w x p); forces go child -> parent as f = R f',
n = R n' + p x (R f').

Helpers read the model array ``model`` and read or write the workspace ``work`` at offsets;
all are inlined into their callers.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Final, Literal, TypedDict

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.core.dispatcher import Dispatcher
from numba.extending import intrinsic

from armdyn.dynamics.numba_compat import one_state_dispatcher
from armdyn.dynamics.packed import FIRST_MOMENT, HEADER, INERTIA, KIND, MASS, N_JOINTS, POSITION, ROTATION, STRIDE
from armdyn.dynamics.status import NOT_FINITE, OK, WRONG_LENGTH
from armdyn.inputs import LARGEST_STATE

if TYPE_CHECKING:
    from llvmlite import ir
    from numba.core.base import BaseContext
    from numba.core.typing.context import BaseContext as TypingContext
    from numba.core.typing.templates import Signature


class NumbaOptions(TypedDict):
    """The keyword arguments every kernel passes to ``njit``."""

    cache: bool
    fastmath: set[str]
    error_model: Literal["python", "numpy"]
    boundscheck: bool


NUMBA_OPTIONS: Final[NumbaOptions] = {
    "cache": True,
    "fastmath": {"contract"},
    "error_model": "numpy",
    "boundscheck": False,
}

# The one-state kernels' explicit signatures: C-contiguous float64 arrays. (A read-only model
# array would cost Numba about 60 ns more to type at every call; the tests check instead
# that no call writes it.)
MODEL = types.float64[::1]
VECTOR = types.float64[::1]
MATRIX = types.float64[:, ::1]


def one_state(signature: Signature) -> Callable[[Callable], Dispatcher]:
    """``njit(signature)`` compiled (or loaded from the cache) at the kernel's first call, not at
    import: importing armdyn then costs no compilation, and a program pays only for the kernels
    it calls.

    With the signature compiled, compilation is disabled, so a call with any other argument
    types raises TypeError as with an explicit signature (the api's fast path relies on it);
    numba_compat.one_state_dispatcher says how.
    """

    def decorate(function: Callable) -> Dispatcher:
        return one_state_dispatcher(njit(**NUMBA_OPTIONS)(function), signature)

    return decorate


STACK_SCRATCH = 4096  # values (32 KiB): a one-state kernel's scratch up to this size lives on the stack


@intrinsic
def _stack_empty(
    typingctx: TypingContext, size: types.Integer
) -> tuple[Signature, Callable[[BaseContext, ir.IRBuilder, Signature, tuple[ir.Value, ...]], ir.Value]]:
    """A float64 array of ``size`` values in the calling function's stack frame (uninitialized, no
    reference count): no allocation, but valid only until that function returns, so it must be
    called from code inlined into the kernel that uses it, never returned or stored."""
    array_type = types.Array(types.float64, 1, "C")

    def codegen(
        context: BaseContext, builder: ir.IRBuilder, signature: Signature, args: tuple[ir.Value, ...]
    ) -> ir.Value:
        (count,) = args
        data = builder.alloca(context.get_value_type(types.float64), size=count)
        array = context.make_array(array_type)(context, builder)
        itemsize = context.get_constant(types.intp, 8)
        shape, strides = cgutils.pack_array(builder, [count]), cgutils.pack_array(builder, [itemsize])
        context.populate_array(array, data=data, shape=shape, strides=strides, itemsize=itemsize, meminfo=None)
        return array._getvalue()

    return array_type(types.intp), codegen


@njit(inline="always", **NUMBA_OPTIONS)
def scratch(size: int) -> np.ndarray:
    """Scratch space for one state: on the caller's stack up to STACK_SCRATCH values (an allocation
    costs about 50 ns, a fifth of a small arm's inverse dynamics), on the heap beyond (thread
    stacks are small). For the one-state kernels only; see _stack_empty."""
    if size <= STACK_SCRATCH:
        return _stack_empty(size)  # type: ignore[call-arg, arg-type]  # Numba's stub keeps typingctx, which Numba passes
    return np.empty(size)


# pi/2 split in three parts for an exact range reduction (Cody and Waite), and the
# minimax coefficients of sin and cos on [-pi/4, pi/4] (Moshier, Cephes sin.c).
_PIO2_1, _PIO2_2, _PIO2_3 = 1.57079625129699707031e0, 7.54978941586159635335e-8, 5.39030285815811905290e-15
_S1, _S2, _S3 = -1.66666666666666307295e-1, 8.33333333332211858878e-3, -1.98412698295895385996e-4
_S4, _S5, _S6 = 2.75573136213857245213e-6, -2.50507477628578072866e-8, 1.58962301576546568060e-10
_C1, _C2, _C3 = 4.16666666666665929218e-2, -1.38888888888730564116e-3, 2.48015872888517045348e-5
_C4, _C5, _C6 = -2.75573141792967388112e-7, 2.08757008419747316778e-9, -1.13585365213876817300e-11
_ROUND = 6755399441055744.0  # 1.5 * 2**52: adding and subtracting it rounds to an integer


@njit(inline="always", **NUMBA_OPTIONS)
def sin_cos(x: float) -> tuple[float, float]:
    """(sin x, cos x) to about one unit in the last place for |x| < 1e5, with selects, not branches."""
    k = (x * 0.6366197723675814 + _ROUND) - _ROUND  # nearest integer, in arithmetic
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    z = r * r
    s = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    c = 1.0 - 0.5 * z + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    quadrant = np.int64(k) & 3
    swap = (quadrant & 1) == 1
    sine = c if swap else s
    cosine = s if swap else c
    sine = -sine if quadrant >= 2 else sine
    cosine = -cosine if (quadrant == 1) | (quadrant == 2) else cosine
    return sine, cosine


@njit(inline="always", **NUMBA_OPTIONS)
def vector_status(x: np.ndarray, n: int, index: int) -> int:
    """OK, or WRONG_LENGTH + index when x (state argument ``index``, from 0) has the wrong length, or
    NOT_FINITE + index when it holds NaN, infinity or a value of LARGEST_STATE or more in magnitude
    (the general path then names the rule broken)."""
    if x.shape[0] != n:
        return WRONG_LENGTH + index
    for k in range(n):
        if not abs(x[k]) < LARGEST_STATE:  # NaN fails every comparison
            return NOT_FINITE + index
    return OK


@njit(inline="always", **NUMBA_OPTIONS)
def states_status(model: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, count: int) -> int:
    """The status of the first ``count`` state arguments (a, b, c): OK when each has n finite values,
    else WRONG_LENGTH + k (1, 2, 3) for argument k of the wrong length, NOT_FINITE + k (11, 12, 13)
    for one with NaN or infinity."""
    n = int(model[N_JOINTS])
    status = vector_status(a, n, 0)
    if status == OK and count > 1:
        status = vector_status(b, n, 1)
    if status == OK and count > 2:
        status = vector_status(c, n, 2)
    return status


@njit(inline="always", **NUMBA_OPTIONS)
def force_to_parent(
    rotation: tuple, position: tuple, moment: tuple, force: tuple
) -> tuple[float, float, float, float, float, float]:
    """X^T f: a force [n; f] on a child carried to its parent, [R n + p x (R f); R f]."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation
    px, py, pz = position
    nx, ny, nz = moment
    fx, fy, fz = force
    Fx = r00 * fx + r01 * fy + r02 * fz
    Fy = r10 * fx + r11 * fy + r12 * fz
    Fz = r20 * fx + r21 * fy + r22 * fz
    return (
        r00 * nx + r01 * ny + r02 * nz + py * Fz - pz * Fy,
        r10 * nx + r11 * ny + r12 * nz + pz * Fx - px * Fz,
        r20 * nx + r21 * ny + r22 * nz + px * Fy - py * Fx,
        Fx,
        Fy,
        Fz,
    )


@njit(inline="always", **NUMBA_OPTIONS)
def inertia_apply(body: tuple, motion: tuple) -> tuple[float, float, float, float, float, float]:
    """I v for a rigid-body inertia body = (m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz) (I_O about
    the origin, h = m c) and a motion v = [w; u]: [I_O w + h x u; m u - h x w]."""
    mass, hx, hy, hz, i0, i1, i2, i3, i4, i5 = body
    wx, wy, wz, ux, uy, uz = motion
    return (
        i0 * wx + i1 * wy + i2 * wz + hy * uz - hz * uy,
        i1 * wx + i3 * wy + i4 * wz + hz * ux - hx * uz,
        i2 * wx + i4 * wy + i5 * wz + hx * uy - hy * ux,
        mass * ux - (hy * wz - hz * wy),
        mass * uy - (hz * wx - hx * wz),
        mass * uz - (hx * wy - hy * wx),
    )


@njit(inline="always", **NUMBA_OPTIONS)
def newton_euler_step(
    rotation: tuple,
    position: tuple,
    parent_velocity: tuple,
    parent_acceleration: tuple,
    rate: float,
    acc: float,
    prism: float,
    body: tuple,
) -> tuple:
    """One joint of RNEA's forward pass (Featherstone 2008, 5.3), for a joint along z.

    From the parent's spatial velocity v_p and acceleration a_p (in the parent's axes), the
    joint transform (R, p), the joint rate and acceleration and the joint kind (prism 0 for
    revolute, 1 for prismatic): v = X v_p + S qd, a = X a_p + S qdd + (X v_p) x S qd and the
    body's force f = I a + v x* I v, with body = (m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz).
    Returns v, a and f, each [angular; linear], as one flat tuple of 18 values.
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation
    px, py, pz = position
    wx, wy, wz, vx, vy, vz = parent_velocity
    ax, ay, az, lx, ly, lz = parent_acceleration
    mass, hx, hy, hz, i0, i1, i2, i3, i4, i5 = body
    # l + a x p, v + w x p
    tx = vx + wy * pz - wz * py
    ty = vy + wz * px - wx * pz
    tz = vz + wx * py - wy * px
    ux = lx + ay * pz - az * py
    uy = ly + az * px - ax * pz
    uz = lz + ax * py - ay * px
    Wx = r00 * wx + r10 * wy + r20 * wz
    Wy = r01 * wx + r11 * wy + r21 * wz
    Wz = r02 * wx + r12 * wy + r22 * wz
    Vx = r00 * tx + r10 * ty + r20 * tz
    Vy = r01 * tx + r11 * ty + r21 * tz
    Vz = r02 * tx + r12 * ty + r22 * tz
    Ax = r00 * ax + r10 * ay + r20 * az
    Ay = r01 * ax + r11 * ay + r21 * az
    Az = r02 * ax + r12 * ay + r22 * az
    Lx = r00 * ux + r10 * uy + r20 * uz
    Ly = r01 * ux + r11 * uy + r21 * uz
    Lz = r02 * ux + r12 * uy + r22 * uz
    rev = 1.0 - prism
    # (X v_p) x S qd: revolute [W x e3; V x e3] qd, prismatic [0; W x e3] qd
    Ax += rev * Wy * rate
    Ay -= rev * Wx * rate
    Az += rev * acc
    Lx += (rev * Vy + prism * Wy) * rate
    Ly -= (rev * Vx + prism * Wx) * rate
    Lz += prism * acc
    Wz += rev * rate
    Vz += prism * rate
    kx, ky, kz, llx, lly, llz = inertia_apply(body, (Wx, Wy, Wz, Vx, Vy, Vz))  # the body's momentum
    # f = I a + v x* momentum
    return (
        Wx, Wy, Wz, Vx, Vy, Vz, Ax, Ay, Az, Lx, Ly, Lz,
        i0 * Ax + i1 * Ay + i2 * Az + hy * Lz - hz * Ly + Wy * kz - Wz * ky + Vy * llz - Vz * lly,
        i1 * Ax + i3 * Ay + i4 * Az + hz * Lx - hx * Lz + Wz * kx - Wx * kz + Vz * llx - Vx * llz,
        i2 * Ax + i4 * Ay + i5 * Az + hx * Ly - hy * Lx + Wx * ky - Wy * kx + Vx * lly - Vy * llx,
        mass * Lx - (hy * Az - hz * Ay) + Wy * llz - Wz * lly,
        mass * Ly - (hz * Ax - hx * Az) + Wz * llx - Wx * llz,
        mass * Lz - (hx * Ay - hy * Ax) + Wx * lly - Wy * llx,
    )  # fmt: skip


@njit(inline="always", **NUMBA_OPTIONS)
def add_force_to_parent(work: np.ndarray, t: int, src: np.ndarray, s: int, dst: np.ndarray, d: int) -> None:
    """dst += X^T src for a force at src[s:s+6], transform (R, p) at work[t:t+12]."""
    rotation = (work[t], work[t + 1], work[t + 2], work[t + 3], work[t + 4], work[t + 5], work[t + 6], work[t + 7],
                work[t + 8])  # fmt: skip
    moved = force_to_parent(
        rotation, (work[t + 9], work[t + 10], work[t + 11]), (src[s], src[s + 1], src[s + 2]),
        (src[s + 3], src[s + 4], src[s + 5]),
    )  # fmt: skip
    for k in range(6):
        dst[d + k] += moved[k]


@njit(inline="always", **NUMBA_OPTIONS)
def joint_transform(model: np.ndarray, j: int, qj: float, work: np.ndarray, o: int) -> None:
    """R_j = P_R Rz(q) (revolute) or P_R (prismatic), p_j = P_p (+ q P_R e_z): work[o:o+9], work[o+9:o+12]."""
    b = HEADER + STRIDE * j
    r = b + ROTATION
    if model[b + KIND] == 0.0:
        s, c = sin_cos(qj)
        for row in range(3):
            x, y = model[r + 3 * row], model[r + 3 * row + 1]
            work[o + 3 * row] = x * c + y * s
            work[o + 3 * row + 1] = y * c - x * s
            work[o + 3 * row + 2] = model[r + 3 * row + 2]
        for k in range(3):
            work[o + 9 + k] = model[b + POSITION + k]
    else:
        for k in range(9):
            work[o + k] = model[r + k]
        for k in range(3):
            work[o + 9 + k] = model[b + POSITION + k] + qj * model[r + 3 * k + 2]


@njit(inline="always", **NUMBA_OPTIONS)
def motion_to_child(work: np.ndarray, t: int, src: np.ndarray, s: int, dst: np.ndarray, d: int) -> None:
    """dst = X src for a motion vector: [R^T a; R^T (l + a x p)], transform at work[t:t+12]."""
    ax, ay, az = src[s], src[s + 1], src[s + 2]
    px, py, pz = work[t + 9], work[t + 10], work[t + 11]
    lx = src[s + 3] + ay * pz - az * py
    ly = src[s + 4] + az * px - ax * pz
    lz = src[s + 5] + ax * py - ay * px
    for k in range(3):
        dst[d + k] = work[t + k] * ax + work[t + 3 + k] * ay + work[t + 6 + k] * az
        dst[d + 3 + k] = work[t + k] * lx + work[t + 3 + k] * ly + work[t + 6 + k] * lz


@njit(inline="always", **NUMBA_OPTIONS)
def inertia_times(model: np.ndarray, j: int, v: np.ndarray, s: int, out: np.ndarray, o: int) -> None:
    """out = I_j v = [I_O a + h x l; m l - h x a] for v = [a; l]."""
    b = HEADER + STRIDE * j
    mass = model[b + MASS]
    hx, hy, hz = model[b + FIRST_MOMENT], model[b + FIRST_MOMENT + 1], model[b + FIRST_MOMENT + 2]
    i = b + INERTIA
    ax, ay, az, lx, ly, lz = v[s], v[s + 1], v[s + 2], v[s + 3], v[s + 4], v[s + 5]
    out[o] = model[i] * ax + model[i + 1] * ay + model[i + 2] * az + hy * lz - hz * ly
    out[o + 1] = model[i + 1] * ax + model[i + 3] * ay + model[i + 4] * az + hz * lx - hx * lz
    out[o + 2] = model[i + 2] * ax + model[i + 4] * ay + model[i + 5] * az + hx * ly - hy * lx
    out[o + 3] = mass * lx - (hy * az - hz * ay)
    out[o + 4] = mass * ly - (hz * ax - hx * az)
    out[o + 5] = mass * lz - (hx * ay - hy * ax)


@njit(inline="always", **NUMBA_OPTIONS)
def add_inertia_to_parent(work: np.ndarray, t: int, src: int, dst: int) -> None:
    """Composite inertia: (model, h, I_O) of a child, moved into its parent's frame and added there.

    h' = R h + m p;  I_O' = R I_O R^T - [Rh]x [p]x - [p]x [Rh]x - m [p]x [p]x.
    """
    mass = work[src]
    rh0 = work[t] * work[src + 1] + work[t + 1] * work[src + 2] + work[t + 2] * work[src + 3]
    rh1 = work[t + 3] * work[src + 1] + work[t + 4] * work[src + 2] + work[t + 5] * work[src + 3]
    rh2 = work[t + 6] * work[src + 1] + work[t + 7] * work[src + 2] + work[t + 8] * work[src + 3]
    px, py, pz = work[t + 9], work[t + 10], work[t + 11]
    # R I R^T: I stored as Ixx Ixy Ixz Iyy Iyz Izz at src + 4
    i0, i1, i2, i3, i4, i5 = work[src + 4], work[src + 5], work[src + 6], work[src + 7], work[src + 8], work[src + 9]
    # A = R I (3x3), then (A R^T) upper triangle
    r00, r01, r02 = work[t], work[t + 1], work[t + 2]
    r10, r11, r12 = work[t + 3], work[t + 4], work[t + 5]
    r20, r21, r22 = work[t + 6], work[t + 7], work[t + 8]
    a00 = r00 * i0 + r01 * i1 + r02 * i2
    a01 = r00 * i1 + r01 * i3 + r02 * i4
    a02 = r00 * i2 + r01 * i4 + r02 * i5
    a10 = r10 * i0 + r11 * i1 + r12 * i2
    a11 = r10 * i1 + r11 * i3 + r12 * i4
    a12 = r10 * i2 + r11 * i4 + r12 * i5
    a20 = r20 * i0 + r21 * i1 + r22 * i2
    a21 = r20 * i1 + r21 * i3 + r22 * i4
    a22 = r20 * i2 + r21 * i4 + r22 * i5
    j00 = a00 * r00 + a01 * r01 + a02 * r02
    j01 = a00 * r10 + a01 * r11 + a02 * r12
    j02 = a00 * r20 + a01 * r21 + a02 * r22
    j11 = a10 * r10 + a11 * r11 + a12 * r12
    j12 = a10 * r20 + a11 * r21 + a12 * r22
    j22 = a20 * r20 + a21 * r21 + a22 * r22
    # - (hx px + px hx) - m px px, with [a]x[b]x = b a^T - (a.b) I
    hp = rh0 * px + rh1 * py + rh2 * pz
    pp = px * px + py * py + pz * pz
    work[dst] += mass
    work[dst + 1] += rh0 + mass * px
    work[dst + 2] += rh1 + mass * py
    work[dst + 3] += rh2 + mass * pz
    work[dst + 4] += j00 - (2.0 * px * rh0 - 2.0 * hp) - mass * (px * px - pp)
    work[dst + 5] += j01 - (px * rh1 + py * rh0) - mass * (px * py)
    work[dst + 6] += j02 - (px * rh2 + pz * rh0) - mass * (px * pz)
    work[dst + 7] += j11 - (2.0 * py * rh1 - 2.0 * hp) - mass * (py * py - pp)
    work[dst + 8] += j12 - (py * rh2 + pz * rh1) - mass * (py * pz)
    work[dst + 9] += j22 - (2.0 * pz * rh2 - 2.0 * hp) - mass * (pz * pz - pp)


@njit(inline="always", **NUMBA_OPTIONS)
def pose_product(a: np.ndarray, ia: int, b: np.ndarray, ib: int, out: np.ndarray, o: int) -> None:
    """out[o:o+12] = A B for poses (R, p) stored as 12 values (R row-major, then p):
    R = R_a R_b, p = p_a + R_a p_b."""
    for r in range(3):
        for c in range(3):
            out[o + 3 * r + c] = (
                a[ia + 3 * r] * b[ib + c] + a[ia + 3 * r + 1] * b[ib + 3 + c] + a[ia + 3 * r + 2] * b[ib + 6 + c]
            )
        out[o + 9 + r] = (
            a[ia + 9 + r] + a[ia + 3 * r] * b[ib + 9] + a[ia + 3 * r + 1] * b[ib + 10] + a[ia + 3 * r + 2] * b[ib + 11]
        )


@njit(inline="always", **NUMBA_OPTIONS)
def world_pose(model: np.ndarray, work: np.ndarray, local: int, parent_pose: int, pose: int, has_parent: bool) -> None:
    """Pose of a body in the world: R_w = R_wp R, p_w = p_wp + R_wp p (12 values at work[pose:])."""
    if not has_parent:
        for k in range(12):
            work[pose + k] = work[local + k]
        return
    pose_product(work, parent_pose, work, local, work, pose)


@njit(inline="always", **NUMBA_OPTIONS)
def motion_cross(work: np.ndarray, v: int, s: int, out: int) -> None:
    """out = v x s for motion vectors [w; u] x [a; l] = [w x a; w x l + u x a]."""
    wx, wy, wz, ux, uy, uz = work[v], work[v + 1], work[v + 2], work[v + 3], work[v + 4], work[v + 5]
    ax, ay, az, lx, ly, lz = work[s], work[s + 1], work[s + 2], work[s + 3], work[s + 4], work[s + 5]
    work[out] = wy * az - wz * ay
    work[out + 1] = wz * ax - wx * az
    work[out + 2] = wx * ay - wy * ax
    work[out + 3] = wy * lz - wz * ly + uy * az - uz * ay
    work[out + 4] = wz * lx - wx * lz + uz * ax - ux * az
    work[out + 5] = wx * ly - wy * lx + ux * ay - uy * ax


@njit(inline="always", **NUMBA_OPTIONS)
def world_motion_subspace(model: np.ndarray, j: int, work: np.ndarray, pose: int, out: int) -> None:
    """S_j in world coordinates: [z; p x z] (revolute) or [0; z] (prismatic)."""
    zx, zy, zz = work[pose + 2], work[pose + 5], work[pose + 8]
    if model[HEADER + STRIDE * j + KIND] != 0.0:
        work[out], work[out + 1], work[out + 2], work[out + 3], work[out + 4], work[out + 5] = 0.0, 0.0, 0.0, zx, zy, zz
    else:
        px, py, pz = work[pose + 9], work[pose + 10], work[pose + 11]
        work[out], work[out + 1], work[out + 2] = zx, zy, zz
        work[out + 3] = py * zz - pz * zy
        work[out + 4] = pz * zx - px * zz
        work[out + 5] = px * zy - py * zx


@njit(inline="always", **NUMBA_OPTIONS)
def dot6(work: np.ndarray, a: int, b: int) -> float:
    return (
        work[a] * work[b]
        + work[a + 1] * work[b + 1]
        + work[a + 2] * work[b + 2]
        + work[a + 3] * work[b + 3]
        + work[a + 4] * work[b + 4]
        + (work[a + 5] * work[b + 5])
    )


@njit(inline="always", **NUMBA_OPTIONS)
def dot_with(work: np.ndarray, a: int, values: tuple) -> float:
    """work[a:a+6] . values, summed left to right."""
    return (
        work[a] * values[0]
        + work[a + 1] * values[1]
        + work[a + 2] * values[2]
        + work[a + 3] * values[3]
        + work[a + 4] * values[4]
        + work[a + 5] * values[5]
    )


@njit(inline="always", **NUMBA_OPTIONS)
def rigid_times(work: np.ndarray, i: int, v: int, out: int) -> None:
    """out = I v for a rigid-body inertia (m, h, I_O) stored at work[i:i+10]: [I_O a + h x l; m l - h x a]."""
    mass, hx, hy, hz = work[i], work[i + 1], work[i + 2], work[i + 3]
    ax, ay, az, lx, ly, lz = work[v], work[v + 1], work[v + 2], work[v + 3], work[v + 4], work[v + 5]
    work[out] = work[i + 4] * ax + work[i + 5] * ay + work[i + 6] * az + hy * lz - hz * ly
    work[out + 1] = work[i + 5] * ax + work[i + 7] * ay + work[i + 8] * az + hz * lx - hx * lz
    work[out + 2] = work[i + 6] * ax + work[i + 8] * ay + work[i + 9] * az + hx * ly - hy * lx
    work[out + 3] = mass * lx - (hy * az - hz * ay)
    work[out + 4] = mass * ly - (hz * ax - hx * az)
    work[out + 5] = mass * lz - (hx * ay - hy * ax)
