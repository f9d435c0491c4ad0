"""SeatBear and ReleaseAndStand: the whole-body motion, the release, and the verdict."""

from __future__ import annotations

from collections.abc import Callable

from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour
from bearchair.behaviours.tracking import locate_torso, tracked_humanoid_pose
from bearchair.hardware.interfaces import SeatingJudgement
from bearchair.skills.results import SeatingPlan


class SeatBear(SkillBehaviour):
    """Plans the seating motion from where the humanoid stands now, then plays it.

    When the accessibility check says so, the humanoid first steps straight in to s_goal
    from where the walk stopped: s_goal nearer the chair than the walking ellipsoid
    allows, or a seat higher than the carried bear (it then raises the bear first).

    Blackboard:
        reads ``/chair/mesh``, ``/sitting/pose``, ``/accessibility/result``; writes
        ``/seat/plan``.
    """

    activity = "seating the bear"

    def __init__(self, name: str = "SeatBear"):
        super().__init__(
            name,
            reads=(keys.CHAIR_MESH, keys.SITTING_POSE, keys.ACCESSIBILITY),
            writes=(keys.SEATING_PLAN,),
        )

    def prepare(self) -> Callable[[], SeatingPlan]:
        skills, robot = self.need()
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        sitting_pose = self.blackboard.get(keys.SITTING_POSE)
        accessibility = self.blackboard.get(keys.ACCESSIBILITY)
        raised = accessibility.raise_at is not None
        steps_in = raised or accessibility.step_in_from is not None

        def job() -> SeatingPlan:
            if steps_in:
                here = tracked_humanoid_pose(skills, robot, after_walking=True)
                if raised:
                    skills.raise_bear(
                        robot.humanoid, chair_mesh, sitting_pose, here, cancel=self.cancel_event
                    )
                step_in = skills.walk_path(
                    robot.humanoid,
                    robot.clock,
                    lambda: locate_torso(skills, robot),
                    (here, accessibility.se2_goal),
                    cancel=self.cancel_event,
                )
                if not step_in.reached:
                    held = "raised" if raised else "carried"
                    raise RuntimeError(f"stepping in with the bear {held}: {step_in.reason}")
            humanoid_pose = tracked_humanoid_pose(skills, robot, after_walking=True)
            plan = skills.plan_seating(chair_mesh, sitting_pose, humanoid_pose, raised=raised)
            skills.execute_seating(robot.humanoid, plan, cancel=self.cancel_event)
            return plan

        return job

    def conclude(self, plan: SeatingPlan) -> Status:
        self.blackboard.set(keys.SEATING_PLAN, plan, overwrite=True)
        solve_s = sum(plan.seconds.values())
        release = getattr(plan, "release", None)
        predicted = (
            ""
            if release is None
            else f"; release imagined: stays in {release.staying}/{len(release.releases)}"
        )
        return self.succeed(
            f"bear placed: {len(plan.times_s)} knots over {float(plan.times_s[-1]):.1f} s "
            f"(planned in {solve_s:.2f} s{predicted})"
        )


class ReleaseAndStand(SkillBehaviour):
    """Opens the hands, retracts them, stands up; in simulation, judges the seating.

    Blackboard:
        reads ``/seat/plan``, ``/sitting/pose``; writes ``/seat/judgement``.
    """

    activity = "releasing the bear and standing up"

    def __init__(self, name: str = "ReleaseAndStand"):
        super().__init__(
            name, reads=(keys.SEATING_PLAN, keys.SITTING_POSE), writes=(keys.JUDGEMENT,)
        )

    def prepare(self) -> Callable[[], SeatingJudgement | None]:
        skills, robot = self.need()
        plan = self.blackboard.get(keys.SEATING_PLAN)
        sitting_yaw = self.blackboard.get(keys.SITTING_POSE).yaw

        def job() -> SeatingJudgement | None:
            skills.release_and_stand(robot.humanoid, plan, cancel=self.cancel_event)
            return None if robot.judge is None else robot.judge.judge(sitting_yaw)

        return job

    def conclude(self, judgement: SeatingJudgement | None) -> Status:
        if judgement is None:
            return self.succeed("released and standing (no physical judge on real robots)")
        self.blackboard.set(keys.JUDGEMENT, judgement, overwrite=True)
        numbers = f"tilt {judgement.torso_tilt_deg:.0f} deg, facing error {judgement.facing_error_deg:.0f} deg"
        if not judgement.seated:
            return self.fail(f"bear not seated: {judgement.reason} ({numbers})")
        return self.succeed(f"bear seated ({numbers})")
