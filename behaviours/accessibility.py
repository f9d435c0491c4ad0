"""CheckSeatReachable and CheckAccessibility: can the NAO seat the bear on this chair at
all, and from here: an SE(2) goal, a seat pre-plan and a path to the goal."""

from __future__ import annotations

import math
from collections.abc import Callable

from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour
from bearchair.behaviours.tracking import tracked_humanoid_pose
from bearchair.core.se2 import SE2Pose
from bearchair.skills.results import AccessibilityResult, SeatReachability

REFUSED = "refused: "
"""How CheckSeatReachable's message starts when it refuses the mission: the seat is out
of the NAO's reach from every stance (the trials count these apart)."""


class CheckSeatReachable(SkillBehaviour):
    """FAILURE, refusing the mission with the reason, when no stance lets the NAO seat the
    bear on this seat whatever the chair's orientation (too high, too deep for its
    reach); SUCCESS otherwise. Runs before anyone is asked to turn the chair. Where the
    scan lost the seat under the sitting point, an unreachable seat is not refused (the
    chair may be within reach): the leaf fails saying the scan cannot tell.

    Blackboard:
        reads ``/chair/mesh``, ``/sitting/pose``; writes ``/accessibility/reachable``.
    """

    activity = "checking the seat is within the NAO's reach"

    def __init__(self, name: str = "CheckSeatReachable"):
        super().__init__(
            name, reads=(keys.CHAIR_MESH, keys.SITTING_POSE), writes=(keys.REACHABILITY,)
        )

    def prepare(self) -> Callable[[], SeatReachability]:
        skills, _ = self.need()
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        sitting_pose = self.blackboard.get(keys.SITTING_POSE)
        return lambda: skills.check_seat_reachable(chair_mesh, sitting_pose)

    def conclude(self, verdict: SeatReachability) -> Status:
        self.blackboard.set(keys.REACHABILITY, verdict, overwrite=True)
        if not verdict.reachable and not verdict.seat_seen:
            return self.fail(
                "cannot tell whether the seat is within reach: the scan shows no seat under "
                f"the sitting point ({verdict.reason})"
            )
        if not verdict.reachable:
            return self.fail(f"{REFUSED}{verdict.reason}")
        across = f" and {verdict.centred_m:.2f} m across" if verdict.centred_m else ""
        return self.succeed(
            f"seat {verdict.seat_height_m:.2f} m high within reach (p moved "
            f"{verdict.slide_m:.2f} m{across}, stance {verdict.stance_m:.2f} m from it)"
        )


class CheckAccessibility(SkillBehaviour):
    """SUCCESS when the humanoid can reach a valid pose to seat the bear, else FAILURE.

    Blackboard:
        reads ``/mission/seed``, ``/mission/arena``, ``/chair/mesh``, ``/sitting/pose``;
        writes ``/accessibility/result``, ``/accessibility/se2_goal``, ``/sitting/pose``,
        ``/humanoid/pose``.
    """

    activity = "checking accessibility"

    def __init__(self, name: str = "CheckAccessibility"):
        super().__init__(
            name,
            reads=(keys.SEED, keys.ARENA, keys.CHAIR_MESH, keys.SITTING_POSE),
            writes=(keys.ACCESSIBILITY, keys.SE2_GOAL, keys.SITTING_POSE, keys.HUMANOID_POSE),
        )

    def prepare(self) -> Callable[[], tuple[SE2Pose, AccessibilityResult]]:
        skills, robot = self.need()
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        sitting_pose = self.blackboard.get(keys.SITTING_POSE)
        arena = self.blackboard.get(keys.ARENA)
        seed = self.blackboard.get(keys.SEED)

        def job() -> tuple[SE2Pose, AccessibilityResult]:
            humanoid_pose = tracked_humanoid_pose(skills, robot)
            result = skills.check_accessibility(
                chair_mesh, sitting_pose, humanoid_pose, arena, seed=seed
            )
            return humanoid_pose, result

        return job

    def conclude(self, outcome: tuple[SE2Pose, AccessibilityResult]) -> Status:
        humanoid_pose, result = outcome
        self.blackboard.set(keys.HUMANOID_POSE, humanoid_pose, overwrite=True)
        self.blackboard.set(keys.ACCESSIBILITY, result, overwrite=True)
        if not result.accessible or result.se2_goal is None:
            return self.fail(f"not accessible: {result.reason}")
        self.blackboard.set(keys.SE2_GOAL, result.se2_goal, overwrite=True)
        self.blackboard.set(keys.SITTING_POSE, result.sitting_pose, overwrite=True)
        goal = result.se2_goal
        return self.succeed(
            f"path of {len(result.path)} waypoints to ({goal.x:.2f}, {goal.y:.2f}) m, "
            f"{math.degrees(goal.theta):.0f} deg in {result.seconds:.2f} s"
        )
