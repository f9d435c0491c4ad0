"""Minimal in-memory robots for tests and offline runs (dm_control style: shipped beside
the real backends so tests of behaviours need neither pybullet nor a robot)."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from core.se2 import SE2Pose
from hardware.interfaces import CameraIntrinsics, RGBDFrame, Robot, SeatingJudgement


class FakeClock:
    """Time that passes only when slept through (no real waiting)."""

    def __init__(self) -> None:
        self._now = 0.0
        self._lock = threading.Lock()

    def now(self) -> float:
        return self._now

    def sleep(self, seconds: float) -> None:
        with self._lock:
            self._now += max(0.0, seconds)


class FakeArm:
    """Records the configurations asked for; captures a flat, empty frame."""

    def __init__(self) -> None:
        self.moves: list[np.ndarray] = []
        self._joints = np.zeros(7)

    def joint_positions(self) -> np.ndarray:
        return self._joints.copy()

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        self._joints = np.asarray(joint_positions_rad, dtype=float)
        self.moves.append(self._joints.copy())

    def emergency_stop(self) -> None:
        self.emergency_stops = getattr(self, "emergency_stops", 0) + 1

    def capture(self) -> RGBDFrame:
        intrinsics = CameraIntrinsics(64, 48, 57.0, 57.0, 31.5, 23.5)
        return RGBDFrame(
            rgb=np.zeros((48, 64, 3), np.uint8),
            depth_m=np.zeros((48, 64), np.float32),
            intrinsics=intrinsics,
            T_world_camera=np.eye(4),
            stamp_s=0.0,
        )


@dataclass
class FakeHumanoid:
    """Remembers every command; its pose is wherever it was put."""

    current_pose: SE2Pose = SE2Pose(1.9, 0.0, np.pi)
    velocities: list[tuple[float, float, float]] = field(default_factory=list)
    trajectories: list[tuple[tuple[str, ...], np.ndarray]] = field(default_factory=list)
    hands_open: bool = False
    stopped: int = 0

    def pose(self) -> SE2Pose:
        return self.current_pose

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        self.velocities.append((vx_mps, vy_mps, omega_radps))

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        self.trajectories.append((tuple(joint_names), np.asarray(positions_rad)))

    def set_hands(self, open_hands: bool) -> None:
        self.hands_open = open_hands

    def stop(self) -> None:
        self.stopped += 1

    def emergency_stop(self) -> None:
        self.stopped += 1


@dataclass
class FakeSpeaker:
    """Keeps what was said."""

    said: list[str] = field(default_factory=list)

    def say(self, sentence: str) -> None:
        self.said.append(sentence)


@dataclass
class FakeJudge:
    """Returns a preset judgement."""

    judgement: SeatingJudgement = SeatingJudgement(True, True, 5.0, 3.0)

    def judge(self, sitting_yaw_rad: float, settle_s: float = 2.0) -> SeatingJudgement:
        return self.judgement


def fake_robot(judge: FakeJudge | None = None) -> Robot:
    """A Robot bundle of fakes."""
    return Robot(
        arm=FakeArm(),
        humanoid=FakeHumanoid(),
        speaker=FakeSpeaker(),
        clock=FakeClock(),
        judge=judge,
    )
