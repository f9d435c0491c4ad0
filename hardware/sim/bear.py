"""The simulated world's teddy bear: the body of :mod:`bearchair.hardware.bear_model`
(its one description), held by the NAO's hands or let go."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pybullet

from bearchair.core.bullet_poses import matrix_to_pose
from bearchair.hardware.bear_model import T_bear_base, create_bear_body
from bearchair.hardware.sim.bullet import (
    LockedBullet,
    T_world_base_link,
    reset_base_link,
)
from bearchair.hardware.sim.clock import SimClock

HOLD_FORCE_N = 60.0
"""The grip of the simulated hands: the constraint's force limit (N)."""


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
