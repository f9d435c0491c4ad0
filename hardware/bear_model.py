"""The teddy bear's description: the one the robot plans with and the simulated world
builds its bear from (shape, mass, friction), and its pybullet body.

The bear frame has its origin at the bottom centre of the torso (where it sits), x the
way it faces (its legs stick out forward), z up along its torso. Height to the top of
the ears: 0.25 m; mass 0.2 kg. A description of the object the robots handle, not of a
simulator: the release imagination (:mod:`bearchair.skills.imagination.release`) builds
its model of the bear from it as :mod:`bearchair.hardware.sim.bear` builds the world's.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
import pybullet

BEAR_MASS_KG = 0.2
BEAR_LATERAL_FRICTION = 0.9
"""Plush on wood or plastic."""
BEAR_ROLLING_FRICTION = 0.001
_BROWN = (0.55, 0.35, 0.17, 1.0)
_LIGHT = (0.8, 0.65, 0.45, 1.0)
_DARK = (0.15, 0.08, 0.04, 1.0)


class BearPart(NamedTuple):
    """A primitive of the bear: kind box/sphere/capsule, size (m), centre and rpy in the bear frame."""

    kind: str
    size: tuple[float, ...]
    centre: tuple[float, float, float]
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    colour: tuple[float, float, float, float] = _BROWN


_ALONG_X = (0.0, math.pi / 2.0, 0.0)
BEAR_PARTS: tuple[BearPart, ...] = (
    BearPart("box", (0.085, 0.1, 0.12), (0.0, 0.0, 0.06)),
    BearPart("sphere", (0.06,), (0.0, 0.0, 0.175)),
    BearPart("sphere", (0.02,), (0.05, 0.0, 0.165), colour=_LIGHT),
    BearPart("sphere", (0.02,), (0.0, 0.04, 0.23)),
    BearPart("sphere", (0.02,), (0.0, -0.04, 0.23)),
    BearPart("capsule", (0.025, 0.07), (0.07, 0.03, 0.025), _ALONG_X),
    BearPart("capsule", (0.025, 0.07), (0.07, -0.03, 0.025), _ALONG_X),
    BearPart("capsule", (0.018, 0.05), (0.02, 0.062, 0.07), (0.6, 0.0, 0.0)),
    BearPart("capsule", (0.018, 0.05), (0.02, -0.062, 0.07), (-0.6, 0.0, 0.0)),
    BearPart("sphere", (0.008,), (0.068, 0.0, 0.172), colour=_DARK),
)

BEAR_TORSO_FOOTPRINT_M: tuple[float, float] = (BEAR_PARTS[0].size[0], BEAR_PARTS[0].size[1])
"""The bear's contact footprint when it sits (metres): the bottom of its torso, the box it
sits on (its first part), as (depth along x, width along y). Its legs rest on the seat
ahead of it too, but the torso carries it."""


def _volume(part: BearPart) -> float:
    if part.kind == "box":
        return float(np.prod(part.size))
    radius = part.size[0]
    sphere = 4.0 / 3.0 * math.pi * radius**3
    return sphere if part.kind == "sphere" else sphere + math.pi * radius**2 * part.size[1]


def bear_centre_of_mass() -> np.ndarray:
    """Centre of mass in the bear frame, for a uniformly dense bear."""
    volumes = np.array([_volume(part) for part in BEAR_PARTS])
    centres = np.array([part.centre for part in BEAR_PARTS])
    return (volumes[:, None] * centres).sum(axis=0) / volumes.sum()


def T_bear_base() -> np.ndarray:
    """The bear body's base frame (its centre of mass, axes of the bear frame) in the bear
    frame."""
    transform = np.eye(4)
    transform[:3, 3] = bear_centre_of_mass()
    return transform


def create_bear_body(bullet: Any) -> int:
    """Adds the bear (shape, mass, friction) to a pybullet client and returns its body id.

    The one description of the bear: the simulated world builds its bear with it, and the
    release imagination its model of the bear. The body's base frame is :func:`T_bear_base` in the bear frame.

    Args:
        bullet: a pybullet client (``LockedBullet`` or ``BulletClient``); hold its lock.
    """
    com = bear_centre_of_mass()
    shapes = [_part_shapes(bullet, part, com) for part in BEAR_PARTS]
    body = _compound_body(
        bullet, [collision for collision, _ in shapes], [visual for _, visual in shapes]
    )
    for link in range(-1, len(BEAR_PARTS) - 1):
        bullet.changeDynamics(
            body,
            link,
            lateralFriction=BEAR_LATERAL_FRICTION,
            rollingFriction=BEAR_ROLLING_FRICTION,
        )
    return body


def _part_shapes(bullet: Any, part: BearPart, com: np.ndarray) -> tuple[int, int]:
    """(collision shape id, visual shape id) of one part, placed relative to the bear's
    centre of mass ``com`` (the multibody's base frame)."""
    position = list(np.asarray(part.centre) - com)
    orientation = pybullet.getQuaternionFromEuler(part.rpy)
    if part.kind == "capsule":
        geometry = {"radius": part.size[0], "height": part.size[1]}
        kind = pybullet.GEOM_CAPSULE
        visual_geometry = {"radius": part.size[0], "length": part.size[1]}
    elif part.kind == "box":
        geometry = {"halfExtents": [v / 2.0 for v in part.size]}
        kind = pybullet.GEOM_BOX
        visual_geometry = geometry
    else:
        geometry = {"radius": part.size[0]}
        kind = pybullet.GEOM_SPHERE
        visual_geometry = geometry
    collision = bullet.createCollisionShape(
        kind, collisionFramePosition=position, collisionFrameOrientation=orientation, **geometry
    )
    visual = bullet.createVisualShape(
        kind,
        rgbaColor=list(part.colour),
        visualFramePosition=position,
        visualFrameOrientation=orientation,
        **visual_geometry,
    )
    return collision, visual


def _compound_body(bullet: Any, collision_ids: list[int], visual_ids: list[int]) -> int:
    """A compound of primitives: one multibody with one fixed link per extra part, half
    the bear's mass in the base and half shared by the links."""
    links = len(BEAR_PARTS) - 1
    return bullet.createMultiBody(
        baseMass=BEAR_MASS_KG * 0.5,
        baseCollisionShapeIndex=collision_ids[0],
        baseVisualShapeIndex=visual_ids[0],
        basePosition=[0, 0, 0],
        linkMasses=[BEAR_MASS_KG * 0.5 / links] * links,
        linkCollisionShapeIndices=collision_ids[1:],
        linkVisualShapeIndices=visual_ids[1:],
        linkPositions=[[0, 0, 0]] * links,
        linkOrientations=[[0, 0, 0, 1]] * links,
        linkInertialFramePositions=[[0, 0, 0]] * links,
        linkInertialFrameOrientations=[[0, 0, 0, 1]] * links,
        linkParentIndices=[0] * links,
        linkJointTypes=[pybullet.JOINT_FIXED] * links,
        linkJointAxis=[[0, 0, 1]] * links,
    )
