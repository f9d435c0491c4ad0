"""The language instruction that asks a helper to turn the chair (the paper, "System Pipeline").

The chair should be turned about the vertical axis so that its sitting direction points at
the NAO: the NAO stands in free space, so the line from the seat to it has nothing in
between, and s_goal, which lies on that line in front of the seat, is then reachable by
walking straight back toward the chair. The rotation is rounded to a multiple of 30 degrees
because people turn chairs by eye. Directions are as seen from above with the world's z
up: counterclockwise is a positive yaw.

If the turned chair is still inaccessible (the helper turned it wrongly, or rounding left
the goal blocked), the mission measures the chair again and asks again with a new
instruction computed from the measured pose; this module keeps no memory between asks.
"""

from __future__ import annotations

import math

from bearchair.core.geometry import SittingPose, wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.skills.results import Instruction

INSTRUCTION_TEMPLATE = (
    "Please rotate the chair about the vertical axis {direction} for {angle} degrees"
)
ANGLE_STEP_DEG = 30
MAX_ANGLE_DEG = 180


def rotation_toward(sitting_pose: SittingPose, target_xy: tuple[float, float]) -> float:
    """The signed yaw (radians, in [-π, π), counterclockwise positive) that turns the sitting
    direction γ to point from p at ``target_xy``."""
    dx = target_xy[0] - float(sitting_pose.position[0])
    dy = target_xy[1] - float(sitting_pose.position[1])
    if math.hypot(dx, dy) < 1e-9:
        raise ValueError("the target is at the sitting position: no direction to turn toward")
    return wrap_angle(math.atan2(dy, dx) - sitting_pose.yaw)


def instructed_rotation(rotation_rad: float) -> tuple[bool, int]:
    """Rounds a rotation to what the helper is told.

    Args:
        rotation_rad: the exact rotation, counterclockwise positive; any real value (wrapped).

    Returns:
        (clockwise, angle_deg): the direction seen from above, and the multiple of 30 in
        0..180 closest to the rotation's magnitude (halves round up). A rotation of exactly
        ±180 degrees, wrapped to -180, is clockwise.
    """
    wrapped = wrap_angle(rotation_rad)
    magnitude_deg = abs(math.degrees(wrapped))
    steps = math.floor(magnitude_deg / ANGLE_STEP_DEG + 0.5)
    angle_deg = min(MAX_ANGLE_DEG, steps * ANGLE_STEP_DEG)
    return wrapped < 0.0, int(angle_deg)


def compose_instruction(
    sitting_pose: SittingPose, humanoid_pose: SE2Pose, rotation_rad: float | None = None
) -> Instruction:
    """The sentence asking the helper to turn the chair's sitting direction toward the NAO.

    Args:
        sitting_pose: g = (p, γ) in the world frame, as measured now.
        humanoid_pose: the NAO's current pose in the world frame.
        rotation_rad: the rotation to ask for instead (counterclockwise positive), as
            :func:`bearchair.skills.assistance.rotation.choose_rotation` chose it.

    Returns:
        The instruction; ``angle_deg`` is 0 when the chair already faces the NAO to within
        15 degrees (then turning cannot help, and the mission's attempt limit ends the loop).
    """
    if rotation_rad is None:
        rotation_rad = rotation_toward(sitting_pose, (humanoid_pose.x, humanoid_pose.y))
    clockwise, angle_deg = instructed_rotation(rotation_rad)
    sentence = INSTRUCTION_TEMPLATE.format(
        direction="clockwise" if clockwise else "counterclockwise", angle=angle_deg
    )
    return Instruction(sentence, clockwise, angle_deg)
