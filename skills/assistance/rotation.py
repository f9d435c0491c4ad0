"""Which rotation to ask the helper for: toward the NAO, or the smallest that plans.

The paper asks for the rotation that points the chair's sitting direction at the NAO
(:func:`bearchair.skills.assistance.instruction.rotation_toward`). Where the chair stands, walls
or obstacles can leave that orientation inaccessible too (the chair already faces the
NAO, and the room in front of it is too narrow for the NAO to stand in): asking for it
then is asking for nothing. So the rotations the helper can be told (multiples of 30
degrees) are tried on the scanned chair, turned about its centre as a helper turns it,
with the accessibility check the mission runs next: the one toward the NAO first, then
the others by size. The first that plans is asked for.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import trimesh

from bearchair.core.arena import Arena
from bearchair.core.geometry import SittingPose, wrap_angle, yaw_transform
from bearchair.core.se2 import SE2Pose
from bearchair.skills.assistance.instruction import (
    ANGLE_STEP_DEG,
    instructed_rotation,
    rotation_toward,
)
from bearchair.skills.results import AccessibilityResult, RotationChoice

AccessibilityCheck = Callable[..., AccessibilityResult]


def rotations_to_try(toward_rad: float) -> list[float]:
    """The instructable rotations (radians): the one nearest ``toward_rad`` first, then
    the others by size (the nearer to it first among equal sizes); no zero rotation."""
    clockwise, angle_deg = instructed_rotation(toward_rad)
    first = math.radians(-angle_deg if clockwise else angle_deg)
    steps = range(-180 + ANGLE_STEP_DEG, 180 + 1, ANGLE_STEP_DEG)
    others = [
        math.radians(d) for d in steps if d != 0 and abs(wrap_angle(math.radians(d) - first)) > 1e-9
    ]
    others.sort(key=lambda r: (abs(r), abs(r - first)))
    return ([first] if angle_deg else []) + others


def turned_about_centre(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, rotation_rad: float
) -> tuple[trimesh.Trimesh, SittingPose]:
    """The chair and its sitting pose turned about the vertical through the chair's
    bounding-box centre (as the helper turns it)."""
    centre = np.r_[chair_mesh.bounds.mean(axis=0)[:2], 0.0]
    T = yaw_transform(0.0, centre) @ yaw_transform(rotation_rad) @ yaw_transform(0.0, -centre)
    return chair_mesh.copy().apply_transform(T), sitting_pose.transformed(T)


def choose_rotation(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    arena: Arena,
    *,
    seed: int,
    check: AccessibilityCheck | None = None,
) -> RotationChoice:
    """The rotation to ask for (see the module doc).

    Args:
        chair_mesh: the chair as scanned (and measured after earlier turns), world frame.
        sitting_pose: g in the world frame.
        humanoid_pose: where the NAO stands.
        arena: the workspace.
        seed: the accessibility check's seed.
        check: the accessibility check (default ``bearchair.skills.planning.accessibility.check_accessibility``).
    """
    if check is None:
        from bearchair.skills.planning.accessibility import check_accessibility

        check = check_accessibility
    toward = rotation_toward(sitting_pose, (humanoid_pose.x, humanoid_pose.y))
    candidates = rotations_to_try(toward)
    reason = ""
    for count, rotation in enumerate(candidates, start=1):
        turned_mesh, turned_pose = turned_about_centre(chair_mesh, sitting_pose, rotation)
        result = check(turned_mesh, turned_pose, humanoid_pose, arena, seed=seed)
        if result.accessible:
            return RotationChoice(rotation, True, "", count)
        reason = reason or result.reason
    fallback = candidates[0] if instructed_rotation(toward)[1] else 0.0
    why = f"no rotation about the vertical axis makes the chair accessible ({reason})"
    return RotationChoice(fallback, False, why, len(candidates))
