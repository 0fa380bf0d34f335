"""Random physically valid arms for property tests: trees of revolute and prismatic joints."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

import armdyn as ad


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def random_transform(rng: np.random.Generator, reach: float = 0.5) -> np.ndarray:
    transform = np.eye(4)
    transform[:3, :3] = random_rotation(rng)
    transform[:3, 3] = rng.uniform(-reach, reach, 3)
    return transform


def random_inertial(rng: np.random.Generator, name: str) -> ad.Inertial:
    """A body from a random second-moment matrix diag(s): principal moments s2+s3, s1+s3, s1+s2."""
    mass = rng.uniform(0.1, 5.0)
    second = rng.uniform(0.0, 0.2, 3) * mass
    moments = np.array([second[1] + second[2], second[0] + second[2], second[0] + second[1]])
    rotation = random_rotation(rng)
    return ad.Inertial(mass, rng.uniform(-0.3, 0.3, 3), rotation @ np.diag(moments) @ rotation.T, name)


def random_robot(seed: int, n: int, chain: bool = False, friction: bool = True, motors: bool = True) -> ad.Robot:
    """A random tree (or chain) of n joints with valid inertias, friction and motors."""
    rng = np.random.default_rng(seed)
    links = []
    for i in range(n):
        name = f"j{i}"
        kind = "prismatic" if rng.random() < 0.3 else "revolute"
        axis = rng.normal(size=3)
        joint = ad.Joint(kind, random_transform(rng), axis / np.linalg.norm(axis), random_transform(rng, 0.2), name)
        parent = i - 1 if chain or i == 0 else int(rng.integers(-1, i))
        links.append(
            ad.Link(
                name,
                joint,
                random_inertial(rng, name),
                parent=parent,
                viscous=rng.uniform(0, 0.5) if friction else 0.0,
                coulomb=(rng.uniform(0, 0.3), -rng.uniform(0, 0.3)) if friction else (0.0, 0.0),
                motor_inertia=rng.uniform(0, 1e-3) if motors else 0.0,
                gear_ratio=rng.choice([-1, 1]) * rng.uniform(1, 50) if motors else 1.0,
            )
        )
    gravity = rng.normal(size=3)
    return ad.Robot(links, name=f"random{seed}", gravity=9.81 * gravity / np.linalg.norm(gravity))


def random_state(robot: ad.Robot, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed + 1)
    return tuple(rng.uniform(-2, 2, robot.n) for _ in range(3))


robots = st.builds(random_robot, seed=st.integers(0, 2**31), n=st.integers(1, 7))
