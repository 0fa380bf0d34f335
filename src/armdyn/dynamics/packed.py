"""An ArmModel packed once into one flat float array that the Numba kernels read (never write),
and the named sizes of the workspace (scratch) each kernel needs.

Every array argument costs Numba dispatch time, so the whole model lives in one array:

    [ header | joint 0 | joint 1 | ... | joint n-1 ]

No kernel writes it (the tests run every call, from two threads at once, and compare it
before and after). Scratch space is a separate workspace: each one-state call allocates
its own inside the compiled code, each parallel chunk of a batch call its own, so calls
from several threads never share one.

Each joint is rewritten so that it moves about or along its own z axis: the placement
absorbs the rotation that carries z onto the joint axis and the parent's frame offset,
and the body's mass properties are expressed in that joint frame ("body frame"). The
kernels then never need a general axis (Featherstone, Rigid Body Dynamics Algorithms,
2008, chapter 4: joint models with a constant motion subspace S = e_z).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from armdyn.errors import ModelError
from armdyn.model import ArmModel, Inertial

# header
N_JOINTS, GRAVITY, TOOL_LINK, TOOL_ROTATION, TOOL_POSITION, PIVOT_FLOOR, HEADER = 0, 1, 4, 5, 14, 17, 20
PIVOT_RELATIVE = 1e-12  # an articulated inertia below this times the arm's inertia scale is zero
# one joint record, relative to its start
PARENT, KIND, ROTATION, POSITION = 0, 1, 2, 11
MASS, FIRST_MOMENT, INERTIA = 14, 15, 18  # INERTIA: Ixx Ixy Ixz Iyy Iyz Izz about the body origin
ARMATURE, VISCOUS, COULOMB_POS, COULOMB_NEG = 24, 25, 26, 27
LINK_ROTATION, LINK_POSITION = 28, 37  # the link frame (DH or URDF) in the body frame, for kinematics
STRIBECK_FORCE, STRIBECK_SPEED = 40, 41  # Fs, vs: Fs exp(-(qd/vs)^2) sgn(qd), joint side
# A, alpha, shift and A / (1 + exp(-alpha shift)) (the law's value at rest, subtracted): Gaz et al. (2019)
SIGMOID_AMPLITUDE, SIGMOID_STEEPNESS, SIGMOID_SHIFT, SIGMOID_REST = 42, 43, 44, 45
STRIDE = 46
REVOLUTE_KIND, PRISMATIC_KIND = 0.0, 1.0


def fields(*sizes: int) -> tuple[int, ...]:
    """The start of each field of a workspace record whose fields have these sizes, then the
    record's size: fields(12, 6, 6) = (0, 12, 18, 24)."""
    starts = [0]
    for size in sizes:
        starts.append(starts[-1] + size)
    return tuple(starts)


# Workspace layouts (each kernel's docstring says what its fields hold). RNEA and G keep one record
# per joint (field f of joint i at RECORD * i + f); the other kernels keep one block per field
# (field f of joint i at f * n + size * i, size the field's size), then a fixed part.
TRANSFORM = 12  # a joint's (R, p): 9 + 3
COMPOSITE = 10  # a composite inertia (m, h, I_O)
SPATIAL = 6  # a spatial vector [angular; linear]
ARTICULATED = 36  # a 6 x 6 articulated-body inertia
COMPOSITE_BIAS = 12  # B^c of Echeandia and Wensing (2021): a 3 x 3 block and a vector
_, RNEA_VELOCITY, RNEA_ACCELERATION, RNEA_FORCE, RNEA_JOINT = fields(TRANSFORM, SPATIAL, SPATIAL, SPATIAL)
RNEA_FIXED = 18  # the tool wrench: its transform (12) and the wrench (6)
_, GRAVITY_ACCELERATION, GRAVITY_MOMENT, GRAVITY_FORCE, GRAVITY_JOINT = fields(TRANSFORM, 3, 3, 3)  # R, p | a | n, f
(CORIOLIS_LOCAL, CORIOLIS_POSE, CORIOLIS_SUBSPACE, CORIOLIS_SUBSPACE_DOT, CORIOLIS_VELOCITY, CORIOLIS_COMPOSITE,
 CORIOLIS_BIAS, CORIOLIS_JOINT) = fields(TRANSFORM, TRANSFORM, *(SPATIAL,) * 3, COMPOSITE, COMPOSITE_BIAS)  # fmt: skip
CORIOLIS_FIXED = COMPOSITE  # one body inertia
(ABA_LOCAL, ABA_POSE, ABA_SUBSPACE, ABA_VELOCITY, ABA_BIAS, ABA_INERTIA, ABA_MOMENTUM, ABA_U, ABA_ACCELERATION,
 ABA_PIVOT, ABA_JOINT) = fields(TRANSFORM, TRANSFORM, *(SPATIAL,) * 3, ARTICULATED, *(SPATIAL,) * 3, 2)  # fmt: skip
ABA_FIXED = 26  # S qd (6), the body inertia in world axes (10), the body inertia and then its momentum (10)
ENERGY_LOCAL, ENERGY_POSE, ENERGY_VELOCITY, ENERGY_JOINT = fields(TRANSFORM, TRANSFORM, SPATIAL)
ENERGY_FIXED = SPATIAL  # I v
(DERIVATIVE_LOCAL, DERIVATIVE_POSE, DERIVATIVE_SUBSPACE, DERIVATIVE_DV, DERIVATIVE_DA, DERIVATIVE_DAV,
 DERIVATIVE_VELOCITY, DERIVATIVE_ACCELERATION, DERIVATIVE_COMPOSITE, DERIVATIVE_BIAS, DERIVATIVE_FORCE,
 DERIVATIVE_JOINT) = fields(TRANSFORM, TRANSFORM, *(SPATIAL,) * 6, COMPOSITE, COMPOSITE_BIAS, SPATIAL)  # fmt: skip
DERIVATIVE_FIXED = COMPOSITE + 3 * SPATIAL  # one inertia, three 6-vectors
# momentum.momentum_core, one record per joint: R, p | v | I v, then the subtree's momentum H | the subtree's mass and
# first moment (m, m c) | l = R^T l_parent (-g in the joint's axes); the observer's momentum_and_rate keeps G in n
# more values after the records (MOMENTUM_JOINT * n on)
_, MOMENTUM_VELOCITY, MOMENTUM_BODY, MOMENTUM_MASS, MOMENTUM_ACCELERATION, MOMENTUM_JOINT = fields(
    TRANSFORM, SPATIAL, SPATIAL, 4, 3
)
WORK_PER_JOINT = max(RNEA_JOINT + COMPOSITE, TRANSFORM + COMPOSITE, GRAVITY_JOINT, CORIOLIS_JOINT, ABA_JOINT,
                     ENERGY_JOINT, MOMENTUM_JOINT + 1)  # fmt: skip
WORK_FIXED = max(RNEA_FIXED, CORIOLIS_FIXED, ABA_FIXED, ENERGY_FIXED)


@njit(cache=True)
def workspace_size(n: int) -> int:
    """Scratch values any kernel needs for an arm of n joints (one Workspace serves them all)."""
    return WORK_PER_JOINT * n + WORK_FIXED


def _rotation_onto(axis: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector ``axis`` (identity for z itself)."""
    z = np.asarray(axis, dtype=float)
    if np.allclose(z, [0.0, 0.0, 1.0], atol=0.0, rtol=0.0):
        return np.eye(3)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def _homogeneous(rotation: np.ndarray) -> np.ndarray:
    transform = np.eye(4)
    transform[:3, :3] = rotation
    return transform


def body_frames(arm: ArmModel) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(placement of each joint frame in its parent's body frame, pose of each link frame in its body frame)."""
    align = [_homogeneous(_rotation_onto(link.joint.axis)) for link in arm.links]
    placements: list[np.ndarray] = []
    link_in_body: list[np.ndarray] = []
    for i, link in enumerate(arm.links):
        before = arm.base if link.parent < 0 else link_in_body[link.parent]
        placements.append(before @ link.joint.placement @ align[i])
        link_in_body.append(np.linalg.inv(align[i]) @ link.joint.frame_offset)
    return placements, link_in_body


def pack(arm: ArmModel) -> np.ndarray:
    """The model array of a numeric arm (the layout constants above describe it)."""
    if arm.is_symbolic:
        raise ModelError(f"arm '{arm.name}' has symbolic parameters; numeric kernels need numbers")
    n = arm.n
    buffer = np.zeros(HEADER + STRIDE * n)
    placements, link_in_body = body_frames(arm)
    tool = link_in_body[arm.tool_link] @ arm.tool
    buffer[N_JOINTS] = n
    buffer[GRAVITY : GRAVITY + 3] = arm.gravity
    buffer[TOOL_LINK] = arm.tool_link
    buffer[TOOL_ROTATION : TOOL_ROTATION + 9] = tool[:3, :3].ravel()
    buffer[TOOL_POSITION : TOOL_POSITION + 3] = tool[:3, 3]
    armature, viscous, coulomb = arm.reflected_inertia, arm.viscous_friction, arm.coulomb_friction
    stribeck, sigmoid = arm.stribeck_friction, arm.sigmoid_friction
    for i, link in enumerate(arm.links):
        record = buffer[HEADER + STRIDE * i : HEADER + STRIDE * (i + 1)]
        record[PARENT] = link.parent
        record[KIND] = REVOLUTE_KIND if link.joint.is_revolute else PRISMATIC_KIND
        record[ROTATION : ROTATION + 9] = placements[i][:3, :3].ravel()
        record[POSITION : POSITION + 3] = placements[i][:3, 3]
        body: Inertial = link.inertial.transformed(link_in_body[i])
        inertia = body.inertia_about_origin()
        record[MASS] = body.mass
        record[FIRST_MOMENT : FIRST_MOMENT + 3] = body.first_moment
        record[INERTIA : INERTIA + 6] = inertia[np.triu_indices(3)]
        record[ARMATURE] = armature[i]
        record[VISCOUS] = viscous[i]
        record[COULOMB_POS], record[COULOMB_NEG] = coulomb[i]
        record[STRIBECK_FORCE], record[STRIBECK_SPEED] = stribeck[i]
        record[SIGMOID_AMPLITUDE], record[SIGMOID_STEEPNESS], record[SIGMOID_SHIFT] = sigmoid[i]
        record[SIGMOID_REST] = sigmoid_rest(*sigmoid[i])
        record[LINK_ROTATION : LINK_ROTATION + 9] = link_in_body[i][:3, :3].ravel()
        record[LINK_POSITION : LINK_POSITION + 3] = link_in_body[i][:3, 3]
    buffer[PIVOT_FLOOR] = PIVOT_RELATIVE * inertia_scale(arm)
    return buffer


def sigmoid_rest(amplitude: float, steepness: float, shift: float) -> float:
    """A / (1 + exp(-alpha shift)): the sigmoid law's first term at rest, which the law subtracts (0 for A = 0;
    written as friction.logistic, without overflow)."""
    x = steepness * shift
    value = 1.0 / (1.0 + math.exp(-x)) if x >= 0.0 else math.exp(x) / (1.0 + math.exp(x))
    return amplitude * value if amplitude != 0.0 else 0.0


def inertia_scale(arm: ArmModel) -> float:
    """A size of the arm's inertia, kg m^2: each link's inertia about its centre of mass, its
    mass at the arm's reach, and the reflected motor inertias, summed (1 for a massless arm).
    Forward dynamics calls an articulated inertia below PIVOT_RELATIVE times this zero."""
    reach = sum(np.linalg.norm(link.joint.placement[:3, 3]) + np.linalg.norm(link.joint.frame_offset[:3, 3])
                for link in arm.links)  # fmt: skip
    total = float(np.sum(arm.reflected_inertia))
    for link in arm.links:
        body = link.inertial
        total += float(np.trace(body.inertia)) + float(body.mass * (reach + np.linalg.norm(body.com)) ** 2)
    return total if total > 0 else 1.0
