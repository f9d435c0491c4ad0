"""Where the humanoid is, as the mission sees it."""

from __future__ import annotations

import logging

from bearchair.core.geometry import wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Robot
from bearchair.skills.mission_skills import MissionSkills

logger = logging.getLogger(__name__)


def locate_torso(skills: MissionSkills, robot: Robot) -> SE2Pose | None:
    """The humanoid's pose from its ArUco tag, or None when the tag is not seen.

    The tag sits on the head: where the humanoid reads its head's yaw back
    (``head_yaw_rad()``, the real NAO), the tag's heading is turned back by it, so a
    head that drifted does not turn the body's heading with it.
    """
    pose = skills.locate_humanoid(robot.arm)
    head_yaw_rad = getattr(robot.humanoid, "head_yaw_rad", None)
    if pose is None or head_yaw_rad is None:
        return pose
    return SE2Pose(pose.x, pose.y, wrap_angle(pose.theta - float(head_yaw_rad())))


def tracked_humanoid_pose(
    skills: MissionSkills, robot: Robot, *, after_walking: bool = False
) -> SE2Pose:
    """The humanoid's pose from its ArUco tag, or its own odometry when the tag is not seen.

    Odometry drifts while walking, but before walking it is the best estimate there is,
    and the accessibility check only needs the start of the path: so falling back to it
    is said at info level before a walk, and as a warning ``after_walking``.
    """
    pose = locate_torso(skills, robot)
    if pose is None:
        if after_walking:
            logger.warning("humanoid tag not seen after walking: using the humanoid's odometry")
        else:
            logger.info("humanoid tag not seen: using the humanoid's odometry")
        return robot.humanoid.pose()
    return pose
