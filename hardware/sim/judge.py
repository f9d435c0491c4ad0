"""The physical success judgement: is the bear sitting on the chair, upright, facing out?"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from hardware.interfaces import SeatingJudgement
from hardware.sim.bear import SimBear
from hardware.sim.bullet import LockedBullet
from hardware.sim.clock import SimClock
from skills.geometry import wrap_angle

MAX_TILT_DEG = 30.0
MAX_FACING_ERROR_DEG = 45.0


class SimJudge:
    """Implements :class:`hardware.interfaces.SeatingJudge` from contacts and the bear's pose.

    After ``settle_s`` of simulated time:
        * on_seat: the bear touches the chair and does not touch the floor;
        * torso tilt: angle between the bear's z axis and the world's z axis;
        * facing error: angle between the bear's x axis projected on the floor and the
          sitting direction: the chair's TRUE one when the world knows it (so that a wrong
          imagination cannot pass its own exam), else the one the mission imagined;
    seated = on_seat, tilt <= 30 deg and facing error <= 45 deg.
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
            on_chair = bool(self._bullet.getContactPoints(self._bear.body, self._chair_body))
            on_floor = bool(self._bullet.getContactPoints(self._bear.body, self._floor_body))
            T_world_bear = self._bear.T_world_bear()
        up = T_world_bear[:3, 2]
        tilt_deg = math.degrees(math.acos(float(np.clip(up[2], -1.0, 1.0))))
        forward = T_world_bear[:3, 0]
        if math.hypot(forward[0], forward[1]) < 1e-6:
            facing_deg = 180.0
        else:
            facing_deg = abs(
                math.degrees(wrap_angle(math.atan2(forward[1], forward[0]) - sitting_yaw_rad))
            )
        on_seat = on_chair and not on_floor
        reasons = []
        if not on_chair:
            reasons.append("the bear does not touch the chair")
        if on_floor:
            reasons.append("the bear touches the floor")
        if tilt_deg > MAX_TILT_DEG:
            reasons.append(f"torso tilted {tilt_deg:.0f} deg > {MAX_TILT_DEG:.0f}")
        if facing_deg > MAX_FACING_ERROR_DEG:
            reasons.append(f"facing off by {facing_deg:.0f} deg > {MAX_FACING_ERROR_DEG:.0f}")
        return SeatingJudgement(
            seated=not reasons,
            on_seat=on_seat,
            torso_tilt_deg=tilt_deg,
            facing_error_deg=facing_deg,
            reason="; ".join(reasons),
        )
