"""In-memory robots for tests and offline runs (dm_control style: shipped beside the
real backends, so tests of skills and behaviours need neither pybullet nor a robot).

:class:`FakeHumanoid` is a kinematic walker: it follows the commanded body velocity with
a first-order lag, its odometry drifts, and it moves only when something calls
:meth:`FakeHumanoid.step` (a :class:`FakeClock` given the humanoid does, while it is slept
through). :class:`FakeTagTracker` sees its true pose with noise, and sometimes not at all.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from bearchair.core.geometry import wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import CameraIntrinsics, RGBDFrame, Robot, SeatingJudgement

HUMANOID_START = SE2Pose(1.9, 0.0, np.pi)
"""Where a :class:`FakeHumanoid` stands unless told otherwise (metres, radians)."""


class FakeHumanoid:
    """A holonomic walker that remembers every command: body velocity → lag → pose.

    Attributes:
        true_pose: where the robot really is (what a tracker sees).
        commands: every (vx m/s, vy m/s, ω rad/s) commanded, in order.
        trajectories: every joint trajectory played, as (joint names, positions in rad).
        hands_open: what :meth:`set_hands` last asked for.
        stopped: how many times :meth:`stop` or :meth:`emergency_stop` was called since
            the last velocity command (0: walking, or never stopped).
    """

    def __init__(
        self,
        start: SE2Pose = HUMANOID_START,
        *,
        lag_s: float = 0.3,
        odometry_scale: float = 1.05,
        velocity_noise: float = 0.0,
        seed: int = 0,
    ) -> None:
        """Args:
        start: initial true pose (odometry starts there too).
        lag_s: velocity time constant, seconds.
        odometry_scale: odometry over-reports travelled distance by this factor (drift).
        velocity_noise: relative standard deviation of the realised velocity.
        seed: noise seed.
        """
        self.true_pose = start
        self._odometry = start
        self._lag_s = lag_s
        self._odometry_scale = odometry_scale
        self._velocity_noise = velocity_noise
        self._rng = np.random.default_rng(seed)
        self._commanded = np.zeros(3)
        self._velocity = np.zeros(3)
        self.commands: list[tuple[float, float, float]] = []
        self.trajectories: list[tuple[tuple[str, ...], np.ndarray]] = []
        self.hands_open = False
        self.stopped = 0

    def pose(self) -> SE2Pose:
        """The odometry's pose estimate."""
        return self._odometry

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        self._commanded = np.array([vx_mps, vy_mps, omega_radps], dtype=float)
        self.commands.append((vx_mps, vy_mps, omega_radps))
        self.stopped = 0

    def stop(self) -> None:
        self._commanded = np.zeros(3)
        self._velocity = np.zeros(3)
        self.stopped += 1

    def emergency_stop(self) -> None:
        self.stop()

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        self.trajectories.append((tuple(joint_names), np.asarray(positions_rad)))

    def set_hands(self, open_hands: bool) -> None:
        self.hands_open = open_hands

    def step(self, dt_s: float) -> None:
        """Advances the body by ``dt_s`` seconds."""
        blend = 1.0 - math.exp(-dt_s / self._lag_s) if self._lag_s > 0 else 1.0
        self._velocity += blend * (self._commanded - self._velocity)
        realised = self._velocity * (1.0 + self._velocity_noise * self._rng.standard_normal(3))
        self.true_pose = _integrate(self.true_pose, realised, dt_s)
        self._odometry = _integrate(self._odometry, realised * self._odometry_scale, dt_s)


def _integrate(pose: SE2Pose, body_velocity: np.ndarray, dt_s: float) -> SE2Pose:
    vx, vy, omega = body_velocity
    return pose.compose(SE2Pose(vx * dt_s, vy * dt_s, omega * dt_s))


class FakeClock:
    """Time that passes only when slept through (no real waiting), from any thread.

    Given a humanoid, sleeping steps it: time then passes in steps of at most ``step_s``
    seconds, each stepping the humanoid; without one, a sleep advances time at once.
    """

    def __init__(self, humanoid: FakeHumanoid | None = None, step_s: float = 0.01) -> None:
        self._now = 0.0
        self._humanoid = humanoid
        self._step_s = step_s
        self._lock = threading.Lock()

    def now(self) -> float:
        return self._now

    def sleep(self, seconds: float) -> None:
        with self._lock:
            if self._humanoid is None:
                self._now += max(0.0, seconds)
                return
            remaining = seconds
            while remaining > 1e-12:
                dt = min(self._step_s, remaining)
                self._humanoid.step(dt)
                self._now += dt
                remaining -= dt


class FakeTagTracker:
    """``locate()`` for the fake: the true pose plus noise, or None when the tag is missed."""

    def __init__(
        self,
        humanoid: FakeHumanoid,
        *,
        position_noise_m: float = 0.003,
        yaw_noise_rad: float = 0.01,
        miss_probability: float = 0.0,
        seed: int = 0,
    ) -> None:
        self._humanoid = humanoid
        self._position_noise_m = position_noise_m
        self._yaw_noise_rad = yaw_noise_rad
        self._miss_probability = miss_probability
        self._rng = np.random.default_rng(seed)
        self.misses = 0

    def __call__(self) -> SE2Pose | None:
        if self._rng.random() < self._miss_probability:
            self.misses += 1
            return None
        pose = self._humanoid.true_pose
        nx, ny = self._rng.normal(0.0, self._position_noise_m, 2)
        return SE2Pose(
            pose.x + nx,
            pose.y + ny,
            wrap_angle(pose.theta + self._rng.normal(0.0, self._yaw_noise_rad)),
        )


class FakeArm:
    """Records the configurations asked for; captures a flat, empty frame."""

    def __init__(self) -> None:
        self.moves: list[np.ndarray] = []
        self.emergency_stops = 0
        self._joints = np.zeros(7)

    def joint_positions(self) -> np.ndarray:
        return self._joints.copy()

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        self._joints = np.asarray(joint_positions_rad, dtype=float)
        self.moves.append(self._joints.copy())

    def emergency_stop(self) -> None:
        self.emergency_stops += 1

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
class FakeSpeaker:
    """Keeps what was said, in ``spoken`` (the name the real speakers use).

    Attributes:
        spoken: every sentence passed to :meth:`say`, in order.
    """

    spoken: list[str] = field(default_factory=list)

    def say(self, sentence: str) -> None:
        self.spoken.append(sentence)


@dataclass
class FakeJudge:
    """Returns a preset judgement."""

    judgement: SeatingJudgement = SeatingJudgement(True, True, 5.0, 3.0)

    def judge(self, sitting_yaw_rad: float, settle_s: float = 2.0) -> SeatingJudgement:
        return self.judgement


def fake_robot(judge: FakeJudge | None = None) -> Robot:
    """A Robot bundle of fakes: nothing moves, time passes only when slept through."""
    return Robot(
        arm=FakeArm(),
        humanoid=FakeHumanoid(),
        speaker=FakeSpeaker(),
        clock=FakeClock(),
        judge=judge,
    )
