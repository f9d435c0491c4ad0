"""The human-assistance loop's leaves: instruct, wait, measure, and give up.

The loop itself (at most :data:`bearchair.behaviours.keys.MAX_ROTATIONS` rotations) is composed in
``trees/mission.py``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import py_trees
from py_trees.common import Access, Status

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour, previous_failure
from bearchair.behaviours.tracking import tracked_humanoid_pose
from bearchair.skills.results import ChairRotation, Instruction, RotationChoice


class InstructHelper(SkillBehaviour):
    """Asks the helper to rotate the chair so that it faces the humanoid, or by the
    smallest rotation the accessibility check plans with (``bearchair.skills.choose_rotation``);
    fails, saying why, when no rotation helps and the chair already faces the humanoid.

    Blackboard:
        reads ``/sitting/pose``, ``/chair/mesh``, ``/mission/arena``, ``/mission/seed``,
        ``/assistance/instructions``, ``/assistance/rotations``; writes the last two and
        ``/assistance/requested`` (the turn asked for).
    """

    activity = "instructing the helper"

    def __init__(self, name: str = "InstructHelper"):
        super().__init__(
            name,
            reads=(
                keys.SITTING_POSE,
                keys.CHAIR_MESH,
                keys.ARENA,
                keys.SEED,
                keys.INSTRUCTIONS,
                keys.ROTATIONS,
            ),
            writes=(keys.INSTRUCTIONS, keys.ROTATIONS, keys.REQUESTED_ROTATION),
        )

    def prepare(self) -> Callable[[], tuple[RotationChoice, Instruction | None]]:
        skills, robot = self.need()
        sitting_pose = self.blackboard.get(keys.SITTING_POSE)
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        arena = self.blackboard.get(keys.ARENA)
        seed = self.blackboard.get(keys.SEED)

        def job() -> tuple[RotationChoice, Instruction | None]:
            humanoid_pose = tracked_humanoid_pose(skills, robot)
            choice = skills.choose_rotation(
                chair_mesh, sitting_pose, humanoid_pose, arena, seed=seed
            )
            if choice.rotation_rad == 0.0:
                return choice, None  # nothing worth asking for
            instruction = skills.compose_instruction(
                sitting_pose, humanoid_pose, rotation_rad=choice.rotation_rad
            )
            robot.speaker.say(instruction.sentence)
            return choice, instruction

        return job

    def conclude(self, outcome: tuple[RotationChoice, Instruction | None]) -> Status:
        choice, instruction = outcome
        if instruction is None:
            return self.fail(choice.reason)
        said = [*self._optional(keys.INSTRUCTIONS, []), instruction.sentence]
        self.blackboard.set(keys.INSTRUCTIONS, said, overwrite=True)
        self.blackboard.set(keys.ROTATIONS, self._optional(keys.ROTATIONS, 0) + 1, overwrite=True)
        self.blackboard.set(keys.REQUESTED_ROTATION, choice.rotation_rad, overwrite=True)
        if not choice.predicted_accessible:
            return self.succeed(f'said "{instruction.sentence}" ({choice.reason})')
        return self.succeed(f'said "{instruction.sentence}"')


class WaitUntilChairStill(SkillBehaviour):
    """Watches the chair with the arm's camera until the helper has stopped turning it."""

    activity = "waiting for the chair to stop moving"

    def __init__(self, name: str = "WaitUntilChairStill"):
        super().__init__(name)

    def prepare(self) -> Callable[[], float]:
        skills, robot = self.need()
        return lambda: skills.wait_until_chair_still(
            robot.arm, robot.clock, cancel=self.cancel_event
        )

    def conclude(self, waited_s: float) -> Status:
        return self.succeed(f"chair still after {waited_s:.1f} s")


class MeasureChairRotation(SkillBehaviour):
    """Measures g_rot by ICP and carries the chair and the sitting pose along with it.

    Blackboard:
        reads ``/chair/points``, ``/chair/mesh``, ``/sitting/pose``, ``/assistance/measured``
        and ``/assistance/requested`` (when set: a weak fit must agree with it); writes the
        first three back moved by g_rot, and appends to ``/assistance/measured``.
    """

    activity = "measuring the chair's rotation"

    def __init__(self, name: str = "MeasureChairRotation"):
        moved = (keys.CHAIR_POINTS, keys.CHAIR_MESH, keys.SITTING_POSE, keys.MEASURED_ROTATIONS)
        super().__init__(name, reads=(*moved, keys.REQUESTED_ROTATION), writes=moved)

    def prepare(self) -> Callable[[], ChairRotation]:
        skills, robot = self.need()
        reference_points = self.blackboard.get(keys.CHAIR_POINTS)
        requested = self._optional(keys.REQUESTED_ROTATION, None)
        return lambda: skills.measure_chair_rotation(
            robot.arm, reference_points, requested_yaw_rad=requested
        )

    def conclude(self, rotation: ChairRotation) -> Status:
        T_world_new_old = rotation.T_world_new_old
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH).copy()
        chair_mesh.apply_transform(T_world_new_old)
        sitting_pose = self.blackboard.get(keys.SITTING_POSE).transformed(T_world_new_old)
        self.blackboard.set(keys.CHAIR_MESH, chair_mesh, overwrite=True)
        self.blackboard.set(keys.CHAIR_POINTS, rotation.chair_points, overwrite=True)
        self.blackboard.set(keys.SITTING_POSE, sitting_pose, overwrite=True)
        measured = [*self._optional(keys.MEASURED_ROTATIONS, []), rotation]
        self.blackboard.set(keys.MEASURED_ROTATIONS, measured, overwrite=True)
        return self.succeed(
            f"chair turned {math.degrees(rotation.yaw_rad):+.1f} deg "
            f"(ICP fitness {rotation.fitness:.2f}, rmse {rotation.inlier_rmse_m * 100:.1f} cm)"
        )


class GiveUp(py_trees.behaviour.Behaviour):
    """Fails with the reason the chair could not be made accessible.

    It sits last in the assistance selector, so it is ticked only when every rotation
    allowed has been asked for and the chair is still not accessible. The last failure
    it names is the tip of the sibling ticked before it (the rotations' loop): the leaf
    whose failure ended the last attempt.

    Blackboard:
        reads ``/assistance/rotations``.
    """

    def __init__(self, name: str = "GiveUp"):
        super().__init__(name=name)
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(key=keys.ROTATIONS, access=Access.READ)

    def update(self) -> Status:
        rotations = (
            self.blackboard.get(keys.ROTATIONS) if self.blackboard.exists(keys.ROTATIONS) else 0
        )
        last = previous_failure(self)
        self.feedback_message = (
            f"chair not accessible after {rotations} rotation(s) "
            f"(at most {keys.MAX_ROTATIONS}); last failure: {last}"
        )
        return Status.FAILURE
