"""Scripted skills for testing behaviours and trees without running any algorithm.

:class:`ScriptedSkills` implements :class:`bearchair.skills.toolbox.MissionSkills`. Each skill
returns a plausible typed result; a test overrides any of them with a value, a list of
values (one per call), an exception to raise, or a delay during which the skill blocks
(and honours its cancel event), and then inspects ``calls``.
"""

from __future__ import annotations

import threading
import time
from collections import defaultdict
from typing import Any

import numpy as np

from bearchair.core.geometry import SittingPose, yaw_transform
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.skills import results as skill_results

SITTING_POSE = SittingPose(np.array([0.6, 0.0, 0.28]), 0.0)
SE2_GOAL = SE2Pose(0.9, 0.0, np.pi)


def default_results() -> dict[str, Any]:
    """One plausible result per skill: a chair at (0.6, 0) facing +x, toward the humanoid."""
    chair_mesh = box_chair_mesh()
    chair_mesh.apply_translation([0.6, 0.0, 0.0])
    joint_names = ("LHipPitch", "RHipPitch")
    return {
        "scan_chair": skill_results.ChairScan(
            chair_mesh, np.asarray(chair_mesh.vertices), 9, {"total": 0.1}
        ),
        "imagine_sitting": skill_results.ImaginationResult(
            True, SITTING_POSE, 3, 24, (), {"total": 0.1}
        ),
        "locate_humanoid": SE2Pose(1.9, 0.0, np.pi),
        "check_seat_reachable": skill_results.SeatReachability(True, "", 0.24, 0.0, 0.3, 0.01),
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
    """Skills that return what the test says.

    Args:
        results: per skill name, a value to return, a list of values (one per call; the
            last repeats), or an exception instance to raise.
        delays_s: per skill name, wall seconds to block before answering.
    """

    def __init__(
        self, results: dict[str, Any] | None = None, delays_s: dict[str, float] | None = None
    ) -> None:
        self.results = {**default_results(), **(results or {})}
        self.delays_s = delays_s or {}
        self.calls: dict[str, list[tuple[tuple, dict]]] = defaultdict(list)
        self.cancelled: list[str] = []

    def _answer(self, name: str, args: tuple, kwargs: dict) -> Any:
        self.calls[name].append((args, kwargs))
        cancel: threading.Event | None = kwargs.get("cancel")
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
        return result

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_") or name not in self.results:
            raise AttributeError(name)
        return lambda *args, **kwargs: self._answer(name, args, kwargs)
