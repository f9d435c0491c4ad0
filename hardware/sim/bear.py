"""The teddy bear: a rigid body in a sitting shape, built from primitives.

The bear frame has its origin at the bottom centre of the torso (where it sits), x the
way it faces (its legs stick out forward), z up along its torso. Height to the top of
the ears: 0.25 m; mass 0.2 kg.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
import pybullet

from bearchair.hardware.sim.bullet import (
    LockedBullet,
    T_world_base_link,
    matrix_to_pose,
    reset_base_link,
)
from bearchair.hardware.sim.clock import SimClock

BEAR_MASS_KG = 0.2
BEAR_LATERAL_FRICTION = 0.9
"""Plush on wood or plastic."""
BEAR_ROLLING_FRICTION = 0.001
HOLD_FORCE_N = 60.0
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
    release imagination (:mod:`bearchair.skills.imagination.release`) its model of the
    bear. The body's base frame is :func:`T_bear_base` in the bear frame.

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


class SimBear:
    """The bear body, optionally held by a moving anchor (the NAO's hands).

    While held, a fixed constraint between the world and the bear is moved every physics
    step to ``anchor() @ T_anchor_bear`` and the bear does not collide with the holder's
    links; :meth:`release` removes the constraint and lets physics take over.
    """

    def __init__(self, bullet: LockedBullet, clock: SimClock, T_world_bear: np.ndarray) -> None:
        self._bullet = bullet
        with bullet.lock:
            self.body = create_bear_body(bullet)
        self._T_bear_base = T_bear_base()
        self._constraint: int | None = None
        self._anchor: Callable[[], np.ndarray] | None = None
        self._T_anchor_bear = np.eye(4)
        self._ignored: list[tuple[int, int]] = []
        self._last_anchor: np.ndarray | None = None
        self.set_T_world_bear(T_world_bear)
        clock.add_process(self._step)

    @property
    def held(self) -> bool:
        """True while a holder carries the bear."""
        return self._constraint is not None

    def T_world_bear(self) -> np.ndarray:
        """The bear frame in the world (ground truth)."""
        return T_world_base_link(self._bullet, self.body) @ np.linalg.inv(self._T_bear_base)

    def set_T_world_bear(self, T_world_bear: np.ndarray) -> None:
        """Teleports the bear (at rest)."""
        reset_base_link(self._bullet, self.body, T_world_bear @ self._T_bear_base)

    def hold(self, anchor: Callable[[], np.ndarray], holder_body: int) -> None:
        """Attaches the bear rigidly to a moving frame at their current relative pose.

        Args:
            anchor: returns the holder's anchor frame ``T_world_anchor`` (e.g. between the hands).
            holder_body: the holder's body, whose links stop colliding with the bear.
        """
        with self._bullet.lock:
            self.release()
            self._anchor = anchor
            self._last_anchor = None
            self._T_anchor_bear = np.linalg.inv(anchor()) @ self.T_world_bear()
            position, orientation = matrix_to_pose(self.T_world_bear() @ self._T_bear_base)
            self._constraint = self._bullet.createConstraint(
                self.body,
                -1,
                -1,
                -1,
                pybullet.JOINT_FIXED,
                [0, 0, 0],
                [0, 0, 0],
                position,
                [0, 0, 0, 1],
                orientation,
            )
            self._bullet.changeConstraint(self._constraint, maxForce=HOLD_FORCE_N)
            self._ignored = []
            for holder_link in range(-1, self._bullet.getNumJoints(holder_body)):
                for bear_link in range(-1, self._bullet.getNumJoints(self.body)):
                    self._bullet.setCollisionFilterPair(
                        holder_body, self.body, holder_link, bear_link, 0
                    )
                    self._ignored.append((holder_body, holder_link))

    def follow_anchor(self) -> None:
        """Teleports a held bear to its place on the anchor (after the holder teleported).

        Does nothing when the bear is not held.
        """
        with self._bullet.lock:
            if self._constraint is None or self._anchor is None:
                return
            T_world_bear = self._anchor() @ self._T_anchor_bear
            self.set_T_world_bear(T_world_bear)
            self._bullet.resetBaseVelocity(self.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
            position, orientation = matrix_to_pose(T_world_bear @ self._T_bear_base)
            self._bullet.changeConstraint(
                self._constraint,
                jointChildPivot=position,
                jointChildFrameOrientation=orientation,
                maxForce=HOLD_FORCE_N,
            )

    def release(self) -> None:
        """Removes the holding constraint; the bear then falls or settles under physics.

        Collisions with the holder come back, except with the holder's links the bear
        overlaps at this moment (they stay off so the bear is not shot out of the hands).
        """
        with self._bullet.lock:
            if self._constraint is None:
                return
            self._bullet.removeConstraint(self._constraint)
            self._constraint = None
            self._anchor = None
            self._last_anchor = None
            for holder_body, holder_link in set(self._ignored):
                overlapping = self._bullet.getClosestPoints(
                    holder_body, self.body, 0.0, linkIndexA=holder_link
                )
                if overlapping:
                    continue
                for bear_link in range(-1, self._bullet.getNumJoints(self.body)):
                    self._bullet.setCollisionFilterPair(
                        holder_body, self.body, holder_link, bear_link, 1
                    )
            self._ignored = []

    def _step(self, now_s: float, dt_s: float) -> None:
        if self._constraint is None or self._anchor is None:
            return
        T_world_anchor = self._anchor()
        if T_world_anchor is self._last_anchor:
            return  # the holder has not moved: the constraint already holds the bear there
        self._last_anchor = T_world_anchor
        position, orientation = matrix_to_pose(
            T_world_anchor @ self._T_anchor_bear @ self._T_bear_base
        )
        self._bullet.changeConstraint(
            self._constraint,
            jointChildPivot=position,
            jointChildFrameOrientation=orientation,
            maxForce=HOLD_FORCE_N,
        )


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
