"""PID walking on a kinematic fake humanoid: accuracy, tag dropouts, cancel and timeout."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from bearchair.core.geometry import wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.fakes import FakeClock, FakeHumanoid, FakeTagTracker
from bearchair.skills.control import PID, WalkError, walk_path

START = SE2Pose(1.9, 0.0, math.pi)
PATH = (
    START,
    SE2Pose(1.6, 0.35, 2.6),
    SE2Pose(1.2, 0.4, 3.0),
    SE2Pose(0.95, 0.1, -2.2),
    SE2Pose(0.91, 0.0, 0.05),
)


def _world(miss_probability: float = 0.0, seed: int = 0):
    humanoid = FakeHumanoid(START, velocity_noise=0.1, odometry_scale=1.08, seed=seed)
    clock = FakeClock(humanoid)
    locate = FakeTagTracker(humanoid, miss_probability=miss_probability, seed=seed + 1)
    return humanoid, clock, locate


def test_pid_integrates_and_clamps() -> None:
    pid = PID(kp=1.0, ki=1.0, kd=0.0, integral_limit=0.5)
    assert pid.update(1.0, 0.1) == pytest.approx(1.1)
    for _ in range(20):
        out = pid.update(1.0, 0.1)
    assert out == pytest.approx(1.5)  # the integral is held at its limit


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_walk_reaches_goal_within_3cm_and_5deg(seed: int) -> None:
    humanoid, clock, locate = _world(seed=seed)
    result = walk_path(humanoid, clock, locate, PATH)
    assert result.reached, result.reason
    goal = PATH[-1]
    assert humanoid.true_pose.distance_to(goal) <= 0.03
    assert abs(wrap_angle(humanoid.true_pose.theta - goal.theta)) <= math.radians(5.0)
    assert result.position_error_m <= 0.03 and result.yaw_error_rad <= math.radians(5.0)
    assert humanoid.stopped
    assert result.seconds > 5.0  # it walked at NAO speeds, not teleported


def test_walk_through_tag_dropouts_uses_odometry() -> None:
    humanoid, clock, locate = _world(miss_probability=0.5, seed=4)
    result = walk_path(humanoid, clock, locate, PATH)
    assert locate.misses > 10
    assert result.reached, result.reason
    assert humanoid.true_pose.distance_to(PATH[-1]) <= 0.035


def test_a_tag_frame_every_track_period_and_odometry_between() -> None:
    humanoid, clock, locate = _world(seed=5)
    frames = []

    def counted() -> SE2Pose | None:
        frames.append(clock.now())
        return locate()

    result = walk_path(humanoid, clock, counted, PATH)
    assert result.reached, result.reason
    assert humanoid.true_pose.distance_to(PATH[-1]) <= 0.03
    # 0.1 s control steps, a frame every 0.3 s (and after each settle).
    gaps = np.diff(frames)
    assert np.median(gaps) == pytest.approx(0.3, abs=1e-6)
    assert len(frames) < 0.5 * result.seconds / 0.1


def test_commands_respect_nao_speed_limits() -> None:
    humanoid, clock, locate = _world()
    walk_path(humanoid, clock, locate, PATH)
    assert max(abs(vx) for vx, _, _ in humanoid.commands) <= 0.1 + 1e-9
    assert max(abs(vy) for _, vy, _ in humanoid.commands) <= 0.07 + 1e-9
    assert max(abs(w) for _, _, w in humanoid.commands) <= 0.5 + 1e-9


def test_cancel_stops_the_robot_promptly() -> None:
    humanoid, clock, locate = _world()
    cancel = threading.Event()

    def tracked_then_cancel() -> SE2Pose | None:
        if clock.now() > 2.0:
            cancel.set()
        return locate()

    result = walk_path(humanoid, clock, tracked_then_cancel, PATH, cancel=cancel)
    assert not result.reached and result.reason == "cancelled"
    assert humanoid.stopped
    assert clock.now() < 2.5


def test_timeout_reports_reason() -> None:
    humanoid, clock, locate = _world()
    result = walk_path(humanoid, clock, locate, PATH, timeout_s=3.0)
    assert not result.reached
    assert "timed out" in result.reason
    assert humanoid.stopped


def test_stuck_robot_times_out_in_proportion_to_path() -> None:
    humanoid, clock, _ = _world()
    result = walk_path(humanoid, clock, lambda: START, PATH)  # the tag never moves
    assert not result.reached and "timed out" in result.reason
    assert 30.0 < result.seconds < 200.0


def test_empty_path_is_an_error() -> None:
    humanoid, clock, locate = _world()
    with pytest.raises(WalkError, match="empty path"):
        walk_path(humanoid, clock, locate, ())
