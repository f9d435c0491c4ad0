"""Following an SE(2) path with PID control on x, y and θ in the robot's frame.

At each control step the tracked pose (the ArUco tag seen by the arm camera) gives the
error to the current waypoint w, rotated into the robot's frame:

.. math::

    e_{xy} = R(-θ) (w_{xy} - x_{xy}), \\qquad e_θ = \\mathrm{wrap}(w_θ - θ),

and three PIDs turn it into the walking velocity (vx, vy, ω), saturated to the NAO's
speeds. When the tag is not seen, the pose is the last tracked pose carried forward by
the odometry's motion since then (or the odometry itself before any sighting), and the
step is counted. A tag frame is taken every ``track_period_s`` (0.3 s; every
``lost_track_period_s``, 1 s, while the tag is out of sight), the odometry carrying the
last sighting forward in between. Waypoints advance inside a loose tolerance;
at the last one the robot stops, settles and is measured again, and the walk ends when
that measurement is within the final tolerance (3 cm, 5 degrees).
"""

from __future__ import annotations

import functools
import itertools
import logging
import math
import threading
from collections.abc import Callable
from typing import NamedTuple

from bearchair.core.errors import SkillError
from bearchair.core.geometry import wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Clock, Humanoid
from bearchair.skills.control.pid import PID
from bearchair.skills.results import WalkResult

logger = logging.getLogger(__name__)


class WalkError(SkillError, ValueError):
    """Bad input to the walk (an empty path or a non-positive time step)."""


class WalkGains(NamedTuple):
    """Controller settings. Speeds are the NAO's comfortable walking limits."""

    kp_xy: float = 1.2
    ki_xy: float = 0.15
    kd_xy: float = 0.05
    kp_theta: float = 1.2
    ki_theta: float = 0.1
    kd_theta: float = 0.02
    max_vx_mps: float = 0.10
    max_vy_mps: float = 0.07
    max_omega_radps: float = 0.5
    waypoint_tolerance_m: float = 0.06
    waypoint_tolerance_rad: float = math.radians(25.0)
    final_tolerance_m: float = 0.03
    final_tolerance_rad: float = math.radians(5.0)
    # Stopping happens inside a tighter box so that the settle drift stays within the final
    # one; 5 mm because the seating pre-plan at s_goal may have only ~1 cm of reach to
    # spare (trials stopped 1.3 cm short inside a 1.5 cm box and failed at SeatBear).
    stop_tolerance_m: float = 0.005
    stop_tolerance_rad: float = math.radians(2.5)
    settle_s: float = 0.3
    # A tag frame every 0.3 s, odometry in between: over 0.3 s the NAO walks at most 3 cm,
    # so its odometry's 3 % scale error and 0.01 rad/s drift add at most 1 mm and 3 mrad,
    # well inside the 5 mm stop box; the pose after settling is always a fresh frame.
    track_period_s: float = 0.3
    # While the tag is out of sight (far off or edge-on, where the walk starts), look again
    # once a second: the odometry is all there is meanwhile either way, and 1 s more of it
    # (10 cm at most) adds at most 3 mm before the tag is found.
    lost_track_period_s: float = 1.0


DEFAULT_GAINS = WalkGains()


def path_length(path: tuple[SE2Pose, ...]) -> tuple[float, float]:
    """Total translation (metres) and total absolute rotation (radians) along a path."""
    translation = sum(a.distance_to(b) for a, b in itertools.pairwise(path))
    rotation = sum(abs(wrap_angle(b.theta - a.theta)) for a, b in itertools.pairwise(path))
    return translation, rotation


def walk_timeout_s(
    path: tuple[SE2Pose, ...], gains: WalkGains, start: SE2Pose | None = None
) -> float:
    """A time limit proportional to the path: half the top speeds, plus 20 s to settle."""
    full = (start, *path) if start is not None else path
    translation, rotation = path_length(full)
    return 20.0 + translation / (0.5 * gains.max_vx_mps) + rotation / (0.5 * gains.max_omega_radps)


class _PoseEstimate:
    """Tracked pose, falling back to odometry increments when the tag is not seen."""

    def __init__(self, humanoid: Humanoid, locate: Callable[[], SE2Pose | None]) -> None:
        self._humanoid = humanoid
        self._locate = locate
        self._anchor: tuple[SE2Pose, SE2Pose] | None = None  # (tracked, odometry) together
        self.unseen_steps = 0
        self.steps = 0
        self.seen = False  # whether the last tag frame found the tag

    def __call__(self, fresh: bool = True) -> SE2Pose:
        """The pose now: from a tag frame when ``fresh`` (or before any sighting), else
        the last sighting carried forward by the odometry."""
        if not fresh and self._anchor is not None:
            odometry = self._humanoid.pose()
        else:
            self.steps += 1
            tracked = self._locate()
            odometry = self._humanoid.pose()
            self.seen = tracked is not None
            if tracked is not None:
                self._anchor = (tracked, odometry)
                return tracked
            self.unseen_steps += 1
        if self._anchor is None:
            return odometry
        tracked_then, odometry_then = self._anchor
        # T_world_now = T_world_tracked · (T_odom_then⁻¹ · T_odom_now)
        return tracked_then.compose(odometry_then.between(odometry))


def _errors(pose: SE2Pose, target: SE2Pose) -> tuple[float, float, float]:
    """Target minus pose in the robot frame: (forward m, left m, yaw rad)."""
    forward, left, yaw = pose.between(target)
    return forward, left, yaw


def walk_path(
    humanoid: Humanoid,
    clock: Clock,
    locate: Callable[[], SE2Pose | None],
    path: tuple[SE2Pose, ...],
    *,
    cancel: threading.Event | None = None,
    dt_s: float = 0.1,
    gains: WalkGains = DEFAULT_GAINS,
    timeout_s: float | None = None,
) -> WalkResult:
    """Walks the humanoid along ``path`` and stops at its last waypoint.

    Args:
        humanoid: the walking robot (velocity commands in its own frame).
        clock: robot time; ``clock.sleep(dt_s)`` separates control steps.
        locate: the tracked pose now, or None when the tag is not seen.
        path: waypoints in the world frame; the last is the goal (the first may be the start).
        cancel: when set, the robot stops and the walk returns (reason "cancelled").
        dt_s: control period, seconds.
        gains: PID gains, speed limits and tolerances.
        timeout_s: give up after this long on the clock; default :func:`walk_timeout_s`.

    Returns:
        reached True when the final tracked errors are within 3 cm and 5 degrees.

    Raises:
        WalkError: an empty path or a non-positive ``dt_s``.
    """
    _check_walk(path, dt_s)
    estimate = _PoseEstimate(humanoid, locate)
    began = clock.now()
    pose = estimate()
    limit_s = timeout_s if timeout_s is not None else walk_timeout_s(path, gains, pose)
    pids = _controllers(gains)
    goal = path[-1]
    index = 0
    last_frame_s = clock.now()
    finish = functools.partial(_finish, humanoid, clock, estimate, goal, began)
    try:
        while True:
            if cancel is not None and cancel.is_set():
                return finish(False, pose, "cancelled")
            if clock.now() - began > limit_s:
                return finish(False, pose, _timed_out(limit_s, pose, goal, estimate))
            target = path[index]
            ex, ey, etheta = _errors(pose, target)
            distance = math.hypot(ex, ey)
            last = index == len(path) - 1
            if not last and _within(
                distance, etheta, gains.waypoint_tolerance_m, gains.waypoint_tolerance_rad
            ):
                index += 1
                _reset(pids)
                continue
            if last and _within(distance, etheta, gains.stop_tolerance_m, gains.stop_tolerance_rad):
                last_frame_s, pose = _stop_and_settle(humanoid, clock, estimate, gains)
                if _at_goal(pose, goal, gains):
                    return finish(True, pose)
                _reset(pids)
                continue
            _command(humanoid, pids, (ex, ey, etheta), dt_s, gains)
            clock.sleep(dt_s)
            fresh, last_frame_s = _frame_due(clock, estimate, last_frame_s, gains)
            pose = estimate(fresh=fresh)
    except BaseException:
        humanoid.stop()
        raise


def _check_walk(path: tuple[SE2Pose, ...], dt_s: float) -> None:
    """Raises WalkError for an empty path or a non-positive control period."""
    if not path:
        raise WalkError("cannot walk an empty path")
    if dt_s <= 0.0:
        raise WalkError(f"the control period must be positive, got {dt_s}")


def _within(distance_m: float, error_rad: float, tolerance_m: float, tolerance_rad: float) -> bool:
    """Whether a distance and a yaw error are both strictly inside their tolerances."""
    return distance_m < tolerance_m and abs(error_rad) < tolerance_rad


def _frame_due(
    clock: Clock, estimate: _PoseEstimate, last_frame_s: float, gains: WalkGains
) -> tuple[bool, float]:
    """Whether a tag frame is due now (one per tracking period: shorter while the tag is
    seen), and the clock time of the last frame (seconds), now if it is due."""
    period_s = gains.track_period_s if estimate.seen else gains.lost_track_period_s
    fresh = clock.now() - last_frame_s >= period_s - 1e-6
    if fresh:
        last_frame_s = clock.now()
    return fresh, last_frame_s


def _controllers(gains: WalkGains) -> tuple[PID, PID, PID]:
    """The PIDs on the forward, left and yaw errors."""
    pid_x = PID(gains.kp_xy, gains.ki_xy, gains.kd_xy, integral_limit=0.05)
    pid_y = PID(gains.kp_xy, gains.ki_xy, gains.kd_xy, integral_limit=0.05)
    pid_theta = PID(gains.kp_theta, gains.ki_theta, gains.kd_theta, integral_limit=0.2)
    return pid_x, pid_y, pid_theta


def _reset(pids: tuple[PID, PID, PID]) -> None:
    for pid in pids:
        pid.reset()


def _command(
    humanoid: Humanoid,
    pids: tuple[PID, PID, PID],
    errors: tuple[float, float, float],
    dt_s: float,
    gains: WalkGains,
) -> None:
    """Sends the PIDs' velocity for the (forward m, left m, yaw rad) errors, saturated."""
    pid_x, pid_y, pid_theta = pids
    ex, ey, etheta = errors
    vx = pid_x.update(ex, dt_s)
    vy = pid_y.update(ey, dt_s)
    omega = pid_theta.update(etheta, dt_s)
    # Scale x and y together so the walking direction is kept under saturation.
    scale = max(1.0, abs(vx) / gains.max_vx_mps, abs(vy) / gains.max_vy_mps)
    omega = max(-gains.max_omega_radps, min(gains.max_omega_radps, omega))
    humanoid.set_velocity(vx / scale, vy / scale, omega)


def _stop_and_settle(
    humanoid: Humanoid, clock: Clock, estimate: _PoseEstimate, gains: WalkGains
) -> tuple[float, SE2Pose]:
    """Stops, lets the robot settle and measures it from a fresh tag frame.

    Returns:
        (the clock's time of that frame in seconds, the pose measured).
    """
    humanoid.stop()
    clock.sleep(gains.settle_s)
    last_frame_s = clock.now()
    return last_frame_s, estimate()


def _at_goal(pose: SE2Pose, goal: SE2Pose, gains: WalkGains) -> bool:
    """Whether ``pose`` is within the final tolerances of ``goal``."""
    return (
        pose.distance_to(goal) <= gains.final_tolerance_m
        and abs(wrap_angle(goal.theta - pose.theta)) <= gains.final_tolerance_rad
    )


def _timed_out(limit_s: float, pose: SE2Pose, goal: SE2Pose, estimate: _PoseEstimate) -> str:
    return (
        f"timed out after {limit_s:.0f} s at {pose.distance_to(goal):.3f} m from the goal"
        f" (tag unseen in {estimate.unseen_steps} of {estimate.steps} steps)"
    )


def _finish(
    humanoid: Humanoid,
    clock: Clock,
    estimate: _PoseEstimate,
    goal: SE2Pose,
    began: float,
    reached: bool,
    final_pose: SE2Pose,
    reason: str = "",
) -> WalkResult:
    """Stops the robot and reports the walk begun at ``began`` (clock seconds)."""
    humanoid.stop()
    error_m = final_pose.distance_to(goal)
    error_rad = abs(wrap_angle(goal.theta - final_pose.theta))
    if estimate.unseen_steps:
        logger.info(
            "walk: tag not seen in %d of %d steps (odometry used)",
            estimate.unseen_steps,
            estimate.steps,
        )
    return WalkResult(reached, error_m, error_rad, clock.now() - began, reason)
