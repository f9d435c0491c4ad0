"""WalkToChair: follow the planned SE(2) path with a PID on the tracked pose."""

from __future__ import annotations

import math
from collections.abc import Callable

from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour
from bearchair.behaviours.tracking import locate_torso
from bearchair.skills.results import WalkResult


class WalkToChair(SkillBehaviour):
    """Walks the humanoid to the SE(2) goal, tracked by its ArUco tag.

    Blackboard:
        reads ``/accessibility/result``; writes ``/walk/result``.
    """

    activity = "walking to the chair"

    def __init__(self, name: str = "WalkToChair"):
        super().__init__(name, reads=(keys.ACCESSIBILITY,), writes=(keys.WALK,))

    def prepare(self) -> Callable[[], WalkResult]:
        skills, robot = self.need()
        path = self.blackboard.get(keys.ACCESSIBILITY).path
        if not path:
            raise ValueError("no path to walk: the accessibility check left none")
        return lambda: skills.walk_path(
            robot.humanoid,
            robot.clock,
            lambda: locate_torso(skills, robot),
            path,
            cancel=self.cancel_event,
        )

    def conclude(self, result: WalkResult) -> Status:
        self.blackboard.set(keys.WALK, result, overwrite=True)
        errors = (
            f"{result.position_error_m * 100:.1f} cm, {math.degrees(result.yaw_error_rad):.1f} deg"
        )
        if not result.reached:
            return self.fail(f"goal not reached ({errors}): {result.reason}")
        return self.succeed(f"at the goal ({errors}) after {result.seconds:.1f} s robot time")
