"""The physical success judgement: is the bear sitting on the chair, upright, facing out?"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bearchair.hardware.interfaces import SeatingJudgement
from bearchair.hardware.seating_criteria import judge_bear_pose
from bearchair.hardware.sim.bear import SimBear
from bearchair.hardware.sim.bullet import LockedBullet
from bearchair.hardware.sim.clock import SimClock


class SimJudge:
    """Implements :class:`bearchair.hardware.interfaces.SeatingJudge` from contacts and the bear's pose.

    After ``settle_s`` of simulated time, the criteria of
    :mod:`bearchair.hardware.seating_criteria`, the facing error against the chair's TRUE
    sitting direction when the world knows it (so that a wrong imagination cannot pass
    its own exam), else the one the mission imagined.
    """

    def __init__(
        self,
        bullet: LockedBullet,
        clock: SimClock,
        bear: SimBear,
        chair_body: int,
        floor_body: int,
        true_sitting_yaw: Callable[[], float | None] = lambda: None,
    ) -> None:
        self._bullet = bullet
        self._clock = clock
        self._bear = bear
        self._chair_body = chair_body
        self._floor_body = floor_body
        self._true_sitting_yaw = true_sitting_yaw

    def judge(self, sitting_yaw_rad: float, settle_s: float = 2.0) -> SeatingJudgement:
        """Lets the scene settle for ``settle_s`` seconds, then judges the bear."""
        self._clock.sleep(settle_s)
        true_yaw = self._true_sitting_yaw()
        if true_yaw is not None:
            sitting_yaw_rad = true_yaw
        with self._bullet.lock:
            chair_contacts = self._bullet.getContactPoints(self._bear.body, self._chair_body)
            on_floor = bool(self._bullet.getContactPoints(self._bear.body, self._floor_body))
            T_world_bear = self._bear.T_world_bear()
        return judge_bear_pose(
            T_world_bear, [np.asarray(c[5]) for c in chair_contacts], on_floor, sitting_yaw_rad
        )
