"""The mission's skills behind one injectable object: the :class:`MissionSkills` protocol.

Behaviours never import skill modules: they call methods of a :class:`MissionSkills`
object passed to ``tree.setup(skills=...)``: the real ones
(``bearchair.skills.default_skills.DefaultSkills``) or a test's stubs
(``bearchair.testing.scripted.ScriptedSkills``). A stub for a skill that is not ready raises
:class:`SkillNotReady`, and the tree fails at the leaf that needs it, naming it.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Protocol

import numpy as np
import trimesh

from bearchair.core.arena import Arena
from bearchair.core.errors import SkillError
from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Clock, Humanoid, ScanningArm
from bearchair.skills.results import (
    AccessibilityResult,
    ChairRotation,
    ChairScan,
    ImaginationResult,
    Instruction,
    RotationChoice,
    SeatingPlan,
    SeatReachability,
    WalkResult,
)

Locate = Callable[[], SE2Pose | None]
"""Returns the humanoid's tracked pose now, or None when it is not seen."""


class SkillNotReady(SkillError, RuntimeError):
    """A skill the mission needs is not implemented (yet) in this installation."""


class MissionSkills(Protocol):
    """What the mission tree asks of its skills, one method per capability.

    ``cancel`` is set when the behaviour is interrupted; long skills poll it and
    return (or raise) promptly.
    """

    def scan_chair(
        self, arm: ScanningArm, *, seed: int, cancel: threading.Event | None = None
    ) -> ChairScan: ...

    def look_from_above(
        self,
        arm: ScanningArm,
        scan: ChairScan,
        *,
        seed: int,
        target: np.ndarray | None = None,
        cancel: threading.Event | None = None,
    ) -> ChairScan: ...

    def imagine_sitting(
        self, chair_mesh: trimesh.Trimesh, *, seed: int, cancel: threading.Event | None = None
    ) -> ImaginationResult: ...

    def look_at_seat(
        self,
        arm: ScanningArm,
        scan: ChairScan,
        sitting_pose: SittingPose,
        *,
        seed: int,
        cancel: threading.Event | None = None,
    ) -> ChairScan: ...

    def locate_humanoid(self, arm: ScanningArm) -> SE2Pose | None: ...

    def check_seat_reachable(
        self, chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose
    ) -> SeatReachability: ...

    def check_seat_levels(self, chair_mesh: trimesh.Trimesh) -> SeatReachability: ...

    def check_accessibility(
        self,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        arena: Arena,
        *,
        seed: int,
    ) -> AccessibilityResult: ...

    def choose_rotation(
        self,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        arena: Arena,
        *,
        seed: int,
    ) -> RotationChoice: ...

    def compose_instruction(
        self,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        rotation_rad: float | None = None,
    ) -> Instruction: ...

    def wait_until_chair_still(
        self, arm: ScanningArm, clock: Clock, *, cancel: threading.Event | None = None
    ) -> float: ...

    def measure_chair_rotation(
        self,
        arm: ScanningArm,
        reference_points: np.ndarray,
        *,
        requested_yaw_rad: float | None = None,
    ) -> ChairRotation: ...

    def walk_path(
        self,
        humanoid: Humanoid,
        clock: Clock,
        locate: Locate,
        path: tuple[SE2Pose, ...],
        *,
        cancel: threading.Event | None = None,
    ) -> WalkResult: ...

    def raise_bear(
        self,
        humanoid: Humanoid,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        *,
        cancel: threading.Event | None = None,
    ) -> None: ...

    def plan_seating(
        self,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        *,
        raised: bool = False,
    ) -> SeatingPlan: ...

    def execute_seating(
        self, humanoid: Humanoid, plan: SeatingPlan, *, cancel: threading.Event | None = None
    ) -> None: ...

    def release_and_stand(
        self, humanoid: Humanoid, plan: SeatingPlan, *, cancel: threading.Event | None = None
    ) -> None: ...
