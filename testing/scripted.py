"""Scripted skills for testing behaviours and trees without running any algorithm.

:class:`ScriptedSkills` implements :class:`bearchair.skills.mission_skills.MissionSkills`, one
method per skill with the protocol's own signature. Each skill returns a plausible typed
result; a test overrides any of them with a value, a list of values (one per call), an
exception to raise, a function of the skill's arguments, or a delay during which the
skill blocks (and honours its cancel event), and then inspects ``calls``.

A script is checked against the protocol: an unknown skill name (``"scan_chiar"``) is a
``ValueError`` at construction, a scripted function that cannot take the skill's
arguments is a ``TypeError`` at construction, and every call is bound against the
protocol's signature (a wrong keyword is a ``TypeError`` at the call, as with the real
skills). The testing kit (``bearchair.testing``) exports it.
"""

from __future__ import annotations

import difflib
import threading
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from bearchair.core.arena import Arena
from bearchair.core.geometry import SittingPose, yaw_transform
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.protocols import binding_error, protocol_members
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Clock, Humanoid, ScanningArm
from bearchair.skills import results as skill_results
from bearchair.skills.mission_skills import Locate, MissionSkills

SKILLS = protocol_members(MissionSkills)
"""Every skill of the protocol and its signature (without ``self``)."""

SITTING_POSE = SittingPose(np.array([0.6, 0.0, 0.28]), 0.0)
SE2_GOAL = SE2Pose(0.9, 0.0, np.pi)


def _seat_seen_already(
    arm: ScanningArm, scan: skill_results.ChairScan, sitting_pose: SittingPose, **_: Any
) -> skill_results.ChairScan:
    """``look_at_seat``'s default: the scan shows the seat under p, so it comes back as it
    went in."""
    return scan


def default_results() -> dict[str, Any]:
    """One plausible result per skill: a chair at (0.6, 0) facing +x, toward the humanoid."""
    chair_mesh = box_chair_mesh()
    chair_mesh.apply_translation([0.6, 0.0, 0.0])
    joint_names = ("LHipPitch", "RHipPitch")
    return {
        "scan_chair": skill_results.ChairScan(
            chair_mesh, np.asarray(chair_mesh.vertices), 9, {"total": 0.1}
        ),
        "look_from_above": skill_results.ChairScan(
            chair_mesh,
            np.asarray(chair_mesh.vertices),
            10,
            {"total": 0.1},
            notes=("one more view",),
        ),
        "look_at_seat": _seat_seen_already,
        "imagine_sitting": skill_results.ImaginationResult(
            True, SITTING_POSE, 3, 24, (), {"total": 0.1}
        ),
        "locate_humanoid": SE2Pose(1.9, 0.0, np.pi),
        "check_seat_reachable": skill_results.SeatReachability(True, "", 0.24, 0.0, 0.3, 0.01),
        "check_seat_levels": skill_results.SeatReachability(True, "", float("nan")),
        "check_accessibility": skill_results.AccessibilityResult(
            True, SE2_GOAL, SITTING_POSE, (SE2Pose(1.9, 0.0, np.pi), SE2_GOAL), "", 0.01
        ),
        "choose_rotation": skill_results.RotationChoice(-np.pi / 2, True, "", 1),
        "compose_instruction": skill_results.Instruction(
            "Please rotate the chair about the vertical axis clockwise for 90 degrees", True, 90
        ),
        "wait_until_chair_still": 3.0,
        "measure_chair_rotation": skill_results.ChairRotation(
            yaw_transform(-np.pi / 2), -np.pi / 2, 0.9, 0.004, np.zeros((10, 3))
        ),
        "walk_path": skill_results.WalkResult(True, 0.01, 0.02, 12.0),
        "raise_bear": None,
        "plan_seating": skill_results.SeatingPlan(
            joint_names,
            np.linspace(0.0, 3.0, 4),
            np.zeros((4, 2)),
            np.linspace(0.0, 2.0, 3),
            np.zeros((3, 2)),
            {"goal": 0.1, "trajectory": 0.2},
        ),
        "execute_seating": None,
        "release_and_stand": None,
    }


class ScriptedSkills:
    """Skills that return what the test says (a :class:`MissionSkills`).

    Args:
        results: per skill name, a value to return, a list of values (one per call; the
            last repeats), an exception instance to raise, or a function called with the
            skill's arguments (its return value is the answer).
        delays_s: per skill name, wall seconds to block before answering.

    Attributes:
        calls: per skill name, every call's (positional args, keyword args).
        cancelled: the skills whose delay was cut short by their cancel event.

    Raises:
        ValueError: a name in ``results`` or ``delays_s`` is not a skill of the protocol.
        TypeError: a scripted function cannot take the skill's arguments.
    """

    def __init__(
        self, results: dict[str, Any] | None = None, delays_s: dict[str, float] | None = None
    ) -> None:
        results, delays_s = dict(results or {}), dict(delays_s or {})
        for what, script in (("results", results), ("delays_s", delays_s)):
            for name in script:
                _check_skill_name(name, what)
        for name, answer in results.items():
            if callable(answer) and not isinstance(answer, BaseException):
                problem = binding_error(answer, SKILLS[name])
                if problem is not None:
                    raise TypeError(f"ScriptedSkills: the function scripted for {name} {problem}")
        self.results = {**default_results(), **results}
        self.delays_s = delays_s
        self.calls: dict[str, list[tuple[tuple, dict]]] = defaultdict(list)
        self.cancelled: list[str] = []

    def _answer(self, name: str, *args: Any, **kwargs: Any) -> Any:
        bound = SKILLS[name].bind(*args, **kwargs)  # TypeError on a wrong argument
        self.calls[name].append((args, kwargs))
        cancel: threading.Event | None = bound.arguments.get("cancel")
        deadline = time.monotonic() + self.delays_s.get(name, 0.0)
        while time.monotonic() < deadline:
            if cancel is not None and cancel.is_set():
                self.cancelled.append(name)
                raise InterruptedError(f"{name} cancelled")
            time.sleep(0.005)
        result = self.results[name]
        if isinstance(result, list):
            result = result[min(len(self.calls[name]), len(result)) - 1]
        if isinstance(result, BaseException):
            raise result
        if callable(result):
            return result(*args, **kwargs)
        return result

    # One method per skill, each with the protocol's signature (a test compares them).

    def scan_chair(
        self, arm: ScanningArm, *, seed: int, cancel: threading.Event | None = None
    ) -> skill_results.ChairScan:
        return self._answer("scan_chair", arm, seed=seed, cancel=cancel)

    def look_from_above(
        self,
        arm: ScanningArm,
        scan: skill_results.ChairScan,
        *,
        seed: int,
        target: np.ndarray | None = None,
        cancel: threading.Event | None = None,
    ) -> skill_results.ChairScan:
        return self._answer("look_from_above", arm, scan, seed=seed, target=target, cancel=cancel)

    def imagine_sitting(
        self, chair_mesh: trimesh.Trimesh, *, seed: int, cancel: threading.Event | None = None
    ) -> skill_results.ImaginationResult:
        return self._answer("imagine_sitting", chair_mesh, seed=seed, cancel=cancel)

    def look_at_seat(
        self,
        arm: ScanningArm,
        scan: skill_results.ChairScan,
        sitting_pose: SittingPose,
        *,
        seed: int,
        cancel: threading.Event | None = None,
    ) -> skill_results.ChairScan:
        return self._answer("look_at_seat", arm, scan, sitting_pose, seed=seed, cancel=cancel)

    def locate_humanoid(self, arm: ScanningArm) -> SE2Pose | None:
        return self._answer("locate_humanoid", arm)

    def check_seat_reachable(
        self, chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose
    ) -> skill_results.SeatReachability:
        return self._answer("check_seat_reachable", chair_mesh, sitting_pose)

    def check_seat_levels(self, chair_mesh: trimesh.Trimesh) -> skill_results.SeatReachability:
        return self._answer("check_seat_levels", chair_mesh)

    def check_accessibility(
        self,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        arena: Arena,
        *,
        seed: int,
    ) -> skill_results.AccessibilityResult:
        return self._answer(
            "check_accessibility", chair_mesh, sitting_pose, humanoid_pose, arena, seed=seed
        )

    def choose_rotation(
        self,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        arena: Arena,
        *,
        seed: int,
    ) -> skill_results.RotationChoice:
        return self._answer(
            "choose_rotation", chair_mesh, sitting_pose, humanoid_pose, arena, seed=seed
        )

    def compose_instruction(
        self,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        rotation_rad: float | None = None,
    ) -> skill_results.Instruction:
        return self._answer("compose_instruction", sitting_pose, humanoid_pose, rotation_rad)

    def wait_until_chair_still(
        self, arm: ScanningArm, clock: Clock, *, cancel: threading.Event | None = None
    ) -> float:
        return self._answer("wait_until_chair_still", arm, clock, cancel=cancel)

    def measure_chair_rotation(
        self,
        arm: ScanningArm,
        reference_points: np.ndarray,
        *,
        requested_yaw_rad: float | None = None,
    ) -> skill_results.ChairRotation:
        return self._answer(
            "measure_chair_rotation", arm, reference_points, requested_yaw_rad=requested_yaw_rad
        )

    def walk_path(
        self,
        humanoid: Humanoid,
        clock: Clock,
        locate: Locate,
        path: tuple[SE2Pose, ...],
        *,
        cancel: threading.Event | None = None,
    ) -> skill_results.WalkResult:
        return self._answer("walk_path", humanoid, clock, locate, path, cancel=cancel)

    def raise_bear(
        self,
        humanoid: Humanoid,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        *,
        cancel: threading.Event | None = None,
    ) -> None:
        return self._answer(
            "raise_bear", humanoid, chair_mesh, sitting_pose, humanoid_pose, cancel=cancel
        )

    def plan_seating(
        self,
        chair_mesh: trimesh.Trimesh,
        sitting_pose: SittingPose,
        humanoid_pose: SE2Pose,
        *,
        raised: bool = False,
    ) -> skill_results.SeatingPlan:
        return self._answer("plan_seating", chair_mesh, sitting_pose, humanoid_pose, raised=raised)

    def execute_seating(
        self,
        humanoid: Humanoid,
        plan: skill_results.SeatingPlan,
        *,
        cancel: threading.Event | None = None,
    ) -> None:
        return self._answer("execute_seating", humanoid, plan, cancel=cancel)

    def release_and_stand(
        self,
        humanoid: Humanoid,
        plan: skill_results.SeatingPlan,
        *,
        cancel: threading.Event | None = None,
    ) -> None:
        return self._answer("release_and_stand", humanoid, plan, cancel=cancel)


def _check_skill_name(name: str, what: str) -> None:
    """Raises ValueError naming an unknown skill (and the nearest known one)."""
    if name in SKILLS:
        return
    near = difflib.get_close_matches(name, SKILLS, n=1, cutoff=0.6)
    hint = f" (did you mean {near[0]}?)" if near else ""
    raise ValueError(
        f"ScriptedSkills {what}: {name!r} is not a skill of MissionSkills{hint}; "
        f"skills: {', '.join(SKILLS)}"
    )


_: Callable[[], MissionSkills] = ScriptedSkills  # pyright checks it satisfies the protocol
