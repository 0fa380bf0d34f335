"""A Robot compiled once into one flat float array that the Numba kernels take.

Every array argument costs Numba dispatch time, so the whole model, and the scratch
space of the one-state kernels, lives in a single contiguous buffer:

    [ header | joint 0 | joint 1 | ... | joint n-1 | scratch ]

Each joint is rewritten so that it moves about or along its own z axis: the placement
absorbs the rotation that carries z onto the joint axis and the parent's frame offset,
and the body's mass properties are expressed in that joint frame ("body frame"). The
kernels then never need a general axis (Featherstone, Rigid Body Dynamics Algorithms,
2008, chapter 4: joint models with a constant motion subspace S = e_z).
"""

from __future__ import annotations

import numpy as np

from armdyn.model.inertial import Inertial
from armdyn.model.robot import Robot

# header
N_JOINTS, GRAVITY, TOOL_LINK, TOOL_ROTATION, TOOL_POSITION, HEADER = 0, 1, 4, 5, 14, 20
# one joint record, relative to its start
PARENT, KIND, ROTATION, POSITION = 0, 1, 2, 11
MASS, FIRST_MOMENT, INERTIA = 14, 15, 18  # INERTIA: Ixx Ixy Ixz Iyy Iyz Izz about the body origin
ARMATURE, VISCOUS, COULOMB_POS, COULOMB_NEG = 24, 25, 26, 27
STRIDE = 28
SCRATCH_PER_JOINT = 160  # the largest kernel (the Coriolis matrix) needs 6+6+6+36+36+12 per joint, plus slack
SCRATCH_FIXED = 64
REVOLUTE_KIND, PRISMATIC_KIND = 0.0, 1.0


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


def body_frames(robot: Robot) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(placement of each joint frame in its parent's body frame, pose of each link frame in its body frame)."""
    align = [_homogeneous(_rotation_onto(link.joint.axis)) for link in robot.links]
    placements, link_in_body = [], []
    for i, link in enumerate(robot.links):
        before = robot.base if link.parent < 0 else link_in_body[link.parent]
        placements.append(before @ link.joint.placement @ align[i])
        link_in_body.append(np.linalg.inv(align[i]) @ link.joint.frame_offset)
    return placements, link_in_body


def compile_robot(robot: Robot) -> np.ndarray:
    """The flat buffer of a numeric Robot (the layout constants above describe it)."""
    if robot.is_symbolic:
        from armdyn.errors import ModelError

        raise ModelError(f"robot '{robot.name}' has symbolic parameters; numeric kernels need numbers")
    n = robot.n
    buffer = np.zeros(HEADER + STRIDE * n + SCRATCH_PER_JOINT * n + SCRATCH_FIXED)
    placements, link_in_body = body_frames(robot)
    tool = link_in_body[robot.tool_link] @ robot.tool
    buffer[N_JOINTS] = n
    buffer[GRAVITY : GRAVITY + 3] = robot.gravity
    buffer[TOOL_LINK] = robot.tool_link
    buffer[TOOL_ROTATION : TOOL_ROTATION + 9] = tool[:3, :3].ravel()
    buffer[TOOL_POSITION : TOOL_POSITION + 3] = tool[:3, 3]
    armature, viscous, coulomb = robot.reflected_inertia, robot.viscous_friction, robot.coulomb_friction
    for i, link in enumerate(robot.links):
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
    return buffer
