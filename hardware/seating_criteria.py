"""What counts as seated: the judge's criteria on a bear at rest.

The one definition of "seated": the simulated world's judge
(:class:`bearchair.hardware.sim.judge.SimJudge`) applies it to the world's bear, the
release imagination (:mod:`bearchair.skills.imagination.release`) to its model's. The
paper counts a trial by asking annotators whether the robot seated the bear; these are
that question's answer in numbers:

* on_seat: the bear touches the chair and does not touch the floor;
* torso tilt: angle between the bear's z axis and the world's z axis, at most
  ``MAX_TILT_DEG``, or ``MAX_RECLINE_DEG`` when the bear leans back (within 45 deg of
  straight back) against the chair (touching it at its head or upper torso);
* facing error: angle between the bear's x axis projected on the floor and the sitting
  direction, at most ``MAX_FACING_ERROR_DEG``.
"""

from __future__ import annotations

import math

import numpy as np

from bearchair.core.geometry import wrap_angle
from bearchair.hardware.interfaces import SeatingJudgement

MAX_TILT_DEG = 30.0
MAX_RECLINE_DEG = 45.0
"""How far a bear leaning back against the chair may recline. The paper counts a trial by
asking annotators whether the robot seated the bear; a bear whose head rests on a
reclined backrest (garden and lounge chairs recline 30-40 deg) is seated, as a child on it
would be. Leaning forward or sideways, or back into nothing, the limit stays 30 deg."""
BACK_SUPPORT_HEIGHT_M = 0.12
"""A contact with the chair this high up the bear (from its seat point along its torso;
the torso is 0.12 m tall, the head above it) supports its back."""
MAX_FACING_ERROR_DEG = 45.0


def judge_bear_pose(
    T_world_bear: np.ndarray,
    chair_contact_points: list[np.ndarray],
    on_floor: bool,
    sitting_yaw_rad: float,
) -> SeatingJudgement:
    """The criteria of this module on a bear at rest.

    Args:
        T_world_bear: the bear frame in the world.
        chair_contact_points: world points where the bear touches the chair.
        on_floor: the bear touches the floor.
        sitting_yaw_rad: the sitting direction the bear must face.
    """
    up = T_world_bear[:3, 2]
    tilt_deg = math.degrees(math.acos(float(np.clip(up[2], -1.0, 1.0))))
    forward = T_world_bear[:3, 0]
    heights_up_bear = [
        float(np.dot(np.asarray(point) - T_world_bear[:3, 3], up)) for point in chair_contact_points
    ]
    back_supported = any(h >= BACK_SUPPORT_HEIGHT_M for h in heights_up_bear)
    max_tilt_deg = MAX_RECLINE_DEG if back_supported and _leans_back(up, forward) else MAX_TILT_DEG
    if math.hypot(forward[0], forward[1]) < 1e-6:
        facing_deg = 180.0
    else:
        facing_deg = abs(
            math.degrees(wrap_angle(math.atan2(forward[1], forward[0]) - sitting_yaw_rad))
        )
    on_chair = bool(chair_contact_points)
    reasons = []
    if not on_chair:
        reasons.append("the bear does not touch the chair")
    if on_floor:
        reasons.append("the bear touches the floor")
    if tilt_deg > max_tilt_deg:
        reasons.append(f"torso tilted {tilt_deg:.0f} deg > {max_tilt_deg:.0f}")
    if facing_deg > MAX_FACING_ERROR_DEG:
        reasons.append(f"facing off by {facing_deg:.0f} deg > {MAX_FACING_ERROR_DEG:.0f}")
    return SeatingJudgement(
        seated=not reasons,
        on_seat=on_chair and not on_floor,
        torso_tilt_deg=tilt_deg,
        facing_error_deg=facing_deg,
        reason="; ".join(reasons),
        T_world_bear=T_world_bear,
    )


def _leans_back(up: np.ndarray, forward: np.ndarray) -> bool:
    """The torso axis leans within 45 deg of straight back from the bear's facing."""
    lean, facing = np.asarray(up[:2], float), np.asarray(forward[:2], float)
    if np.linalg.norm(lean) < 1e-6 or np.linalg.norm(facing) < 1e-6:
        return False
    cosine = -float(np.dot(lean, facing)) / (np.linalg.norm(lean) * np.linalg.norm(facing))
    return bool(cosine >= math.cos(math.radians(45.0)))
