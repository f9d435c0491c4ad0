"""The seating problem's numbers in the NAO frame: g and the chair's two blocks seen
from where the NAO stands."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose, transform_points, wrap_angle
from bearchair.core.nao_carrying import LOW_SEAT_RELEASE_GAP_M
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.wholebody.chair_profile import (
    ChairProfile,
    ChairProfileError,
    fit_chair_profile,
)
from bearchair.skills.planning.wholebody.infeasible import InfeasibleSeating
from bearchair.skills.planning.wholebody.reach_model import reach_model

LATERAL_TOLERANCE_M = 0.05
"""How far g may lie beside the NAO's sagittal plane (the planar motion cannot reach it)."""
FACING_TOLERANCE_RAD = math.radians(20.0)
"""How far the NAO's heading may differ from the opposite of the sitting direction."""


class SeatingScene(NamedTuple):
    """The seating problem's numbers in the NAO frame (metres, radians).

    Attributes:
        g_xz: the bear's target base: forward distance d of the sitting pose, height the
            release height over the seat's top under it (``BEAR_SEAT_CLEARANCE_M`` over it,
            or the NAO's deepest crouch over a lower seat: :meth:`.ReachModel.release_height_m`).
        lateral_m: g's offset beside the sagittal plane (ignored by the planar motion).
        facing_error_rad: the NAO's heading minus the opposite of the sitting direction.
        profile: the chair's two-block cross-section.
    """

    g_xz: np.ndarray
    lateral_m: float
    facing_error_rad: float
    profile: ChairProfile


def seating_scene(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, humanoid_pose: SE2Pose
) -> SeatingScene:
    """Expresses g and the chair in the NAO frame at ``humanoid_pose``.

    Raises:
        InfeasibleSeating: g is beside the sagittal plane, the NAO does not face the
            chair, the chair has no seat under g, or the seat under g is too low for the
            NAO to let the bear go on.
    """
    T_nao_world = np.linalg.inv(humanoid_pose.as_transform())
    g_nao = transform_points(T_nao_world, np.asarray(sitting_pose.position, float)[None, :])[0]
    facing_error = wrap_angle(humanoid_pose.theta - (sitting_pose.yaw + math.pi))
    if abs(facing_error) > FACING_TOLERANCE_RAD:
        raise InfeasibleSeating(
            "sitting direction",
            f"the NAO faces {math.degrees(facing_error):+.0f} deg off the opposite of the "
            f"sitting direction (tolerance {math.degrees(FACING_TOLERANCE_RAD):.0f} deg)",
        )
    if abs(g_nao[1]) > LATERAL_TOLERANCE_M:
        raise InfeasibleSeating(
            "bear placement",
            f"the sitting pose is {g_nao[1]:+.2f} m beside the NAO's sagittal plane "
            f"(tolerance {LATERAL_TOLERANCE_M:.2f} m)",
        )
    try:
        profile = fit_chair_profile(chair_mesh, T_nao_world, g_nao)
    except ChairProfileError as error:
        raise InfeasibleSeating("chair", str(error)) from error
    release_z = reach_model().release_height_m(profile.seat_top_z)
    if math.isnan(release_z):
        raise InfeasibleSeating(
            "bear placement",
            f"seat too low to let the bear go on: its top {profile.seat_top_z:.3f} m high, the "
            f"NAO holds the bear no lower than {reach_model().release.lowest_height_m:.3f} m, "
            f"at most {LOW_SEAT_RELEASE_GAP_M:.2f} m over a seat",
        )
    g_xz = np.array([g_nao[0], release_z])
    return SeatingScene(g_xz, float(g_nao[1]), facing_error, profile)
