"""Where the humanoid is, as the mission sees it."""

from __future__ import annotations

import logging

from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Robot
from bearchair.skills.toolbox import MissionSkills

logger = logging.getLogger(__name__)


def tracked_humanoid_pose(skills: MissionSkills, robot: Robot) -> SE2Pose:
    """The humanoid's pose from its ArUco tag, or its own odometry when the tag is not seen.

    Odometry drifts while walking, but before walking it is the best estimate there is,
    and the accessibility check only needs the start of the path.
    """
    pose = skills.locate_humanoid(robot.arm)
    if pose is None:
        logger.warning("humanoid tag not seen: using the humanoid's odometry")
        return robot.humanoid.pose()
    return pose
