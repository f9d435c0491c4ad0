"""The mission's skills behind one injectable object.

Behaviours never import skill modules: they call methods of a :class:`MissionSkills`
object passed to ``tree.setup(skills=...)``. :class:`DefaultSkills` binds each method
to its skill module on first use, so a module that is not ready fails at the leaf that
needs it, with a :class:`SkillNotReady` error naming it, and never earlier. Tests pass
their own stubs with the same methods.
"""

from __future__ import annotations

import functools
import importlib
import threading
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
import trimesh

from core.arena import Arena
from core.geometry import SittingPose
from core.se2 import SE2Pose
from hardware.interfaces import Clock, Humanoid, ScanningArm
from skills.imagination import DEFAULT_WORKERS
from skills.results import (
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


class SkillNotReady(RuntimeError):
    """A skill the mission needs is not implemented (yet) in this installation."""


class MissionSkills(Protocol):
    """What the mission tree asks of its skills, one method per capability.

    ``cancel`` is set when the behaviour is interrupted; long skills poll it and
    return (or raise) promptly.
    """

    def scan_chair(
        self, arm: ScanningArm, *, seed: int, cancel: threading.Event | None = None
    ) -> ChairScan: ...

    def imagine_sitting(
        self, chair_mesh: trimesh.Trimesh, *, seed: int, cancel: threading.Event | None = None
    ) -> ImaginationResult: ...

    def locate_humanoid(self, arm: ScanningArm) -> SE2Pose | None: ...

    def check_seat_reachable(
        self, chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose
    ) -> SeatReachability: ...

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
        self, arm: ScanningArm, reference_points: np.ndarray
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


# Which module implements which skill: "module:function".
SKILL_SOURCES: dict[str, str] = {
    "scan_chair": "skills.perception:scan_chair",
    "imagine_sitting": "skills.imagination:imagine_sitting",
    "locate_humanoid": "skills.perception:locate_humanoid",
    "check_seat_reachable": "skills.planning.stance:check_seat_reachable",
    "check_accessibility": "skills.planning.se2:check_accessibility",
    "choose_rotation": "skills.assistance:choose_rotation",
    "compose_instruction": "skills.assistance:compose_instruction",
    "wait_until_chair_still": "skills.perception:wait_until_chair_still",
    "measure_chair_rotation": "skills.perception:measure_chair_rotation",
    "walk_path": "skills.control:walk_path",
    "raise_bear": "skills.planning.wholebody:raise_bear",
    "plan_seating": "skills.planning.wholebody:plan_seating_where_standing",
    "execute_seating": "skills.planning.wholebody:execute_seating",
    "release_and_stand": "skills.planning.wholebody:release_and_stand",
}


def resolve_skill(name: str) -> Callable[..., Any]:
    """Imports the function implementing skill ``name``.

    Raises:
        SkillNotReady: its module or function does not exist.
    """
    module_name, function_name = SKILL_SOURCES[name].split(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name and module_name.startswith(error.name):
            raise SkillNotReady(
                f"skill '{name}' is not implemented: no module {module_name}"
            ) from error
        raise
    function = getattr(module, function_name, None)
    if function is None:
        raise SkillNotReady(f"skill '{name}' is not implemented: no {module_name}.{function_name}")
    return function


class DefaultSkills:
    """The real skills, each bound lazily from :data:`SKILL_SOURCES`.

    Args:
        imagination_workers: processes ``imagine_sitting`` drops in (1: this one).
    """

    def __init__(self, imagination_workers: int = DEFAULT_WORKERS) -> None:
        self.imagination_workers = imagination_workers

    def warm_up(self) -> threading.Thread:
        """Starts building, in the background, what a skill would otherwise build on its
        first call: the whole-body planner's problems (2 s), needed after the scan and the
        imagination. (Modules are not imported there: some import each other, and two
        threads importing such a pair can deadlock.)"""
        from skills.planning.wholebody.optimisation import start_building_problems

        return start_building_problems()

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name not in SKILL_SOURCES:
            raise AttributeError(name)
        function = resolve_skill(name)
        if name == "imagine_sitting":
            function = functools.partial(function, workers=self.imagination_workers)
        setattr(self, name, function)
        return function
