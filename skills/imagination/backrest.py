"""The sitting direction a chair's backrest gives, as a check on the imagined one.

Chairs are mirror-symmetric about their sagittal plane, and the backrest stands at the
rear of the seat. So the horizontal centroid of everything that rises above the seat
(backrest, armrests, which come in symmetric pairs), c_above, lies behind the centroid
of the seat's top surface, c_seat, on the sagittal plane, and a sitter faces

.. math::

    γ_{back} = \\operatorname{atan2}(c_{seat} - c_{above}).

The imagined direction comes from where the virtual child's drops came to rest, and on
round or near-symmetric seats with a wrap-around back the sitters slide and turn, so the
vote may land one rotation (45 deg) off. The backrest cue has no such failure, but needs
a backrest and sees only what the scan saw. Measured: within 5.4 deg of the true front
on all 53 calibration meshes with a front (median 0.6 deg), and within 22 deg on 28
scanned reconstructions of a calibration campaign (median 3.8 deg; the scan sees the
backrest from one side, and the largest errors are on the shallowest backrest offsets),
where the imagined direction was 46-56 deg off on a round seat.

So the imagined pose keeps its direction unless the two disagree by more than
:data:`AGREEMENT_RAD`: then at least one is off by more than half of it, and the chair's
own shape is the better evidence. Seats with nothing above them (stools, benches without
a back) give no cue.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
import trimesh

from skills.geometry import SittingPose, wrap_angle
from skills.planning.seat import seat_support_heights

ABOVE_SEAT_M = 0.06
"""Surface counts as rising above the seat this far over the seat top (metres): above a
dished seat's rim, slat tops and a scan's noise on the seat (a few centimetres), and below
any backrest, which rises 0.2 m or more."""
SEAT_BAND_M = 0.015
"""Upward-facing surface within this of the seat top (metres) is the seat: a scan's
noise (a few millimetres) and a cushion's slope near p."""
NEAR_P_M = 0.35
"""Only surface within this horizontal distance of p counts (metres): the widest child's
seat (0.4 m) and its backrest around p, not something standing beside the chair."""
MIN_BACK_OFFSET_M = 0.03
"""The cue needs c_above at least this far from c_seat (metres). A backrest stands at the
seat's rear, half a seat depth (0.11 m or more on children's seats, 0.22 m deep and up)
behind the seat's centre; armrests along the sides pull the centroid forward, to about
a third of that at worst (0.04 m, the least among the calibration meshes). Nearer, the
shape says nothing about a direction."""
AGREEMENT_RAD = math.radians(30.0)
"""The imagined direction stands when it is within this of the backrest's (radians): the
mission's own tolerance on the sitting direction (the seating judge allows 45 deg)."""
SAMPLES = 40000
"""Surface samples (about one per 0.25 cm² on a child's chair); deterministic by seed."""
UPWARD_NORMAL_Z = 0.9
"""A sample with a normal's z at least this faces up (within 26 deg): the seat's top."""


class BackrestCheck(NamedTuple):
    """The backrest's sitting direction against the imagined one.

    Attributes:
        yaw_rad: γ_back, in the frame of the mesh given (radians).
        offset_m: how far c_above lies from c_seat (metres).
        disagreement_rad: imagined yaw minus γ_back, wrapped (radians).
        used: the sitting pose took γ_back (the two disagreed by more than
            :data:`AGREEMENT_RAD`).
    """

    yaw_rad: float
    offset_m: float
    disagreement_rad: float
    used: bool

    def to_json(self) -> dict[str, Any]:
        return {
            "yaw_deg": round(math.degrees(self.yaw_rad), 2),
            "offset_m": round(self.offset_m, 4),
            "disagreement_deg": round(math.degrees(self.disagreement_rad), 2),
            "used": self.used,
        }


def backrest_yaw(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, *, seed: int = 0
) -> tuple[float, float] | None:
    """γ_back and the centroids' distance (radians, metres), or None without a backrest.

    Args:
        chair_mesh: the chair, z up, metres (any horizontal frame; γ_back comes in it).
        sitting_pose: the imagined g; only p is used (the seat under it).
        seed: the surface sampling's seed.
    """
    p = np.asarray(sitting_pose.position, dtype=float)
    seat_top = float(seat_support_heights(chair_mesh, p[None, :2], float(p[2]))[0])
    if not math.isfinite(seat_top):
        return None
    points, faces = trimesh.sample.sample_surface(chair_mesh, SAMPLES, seed=seed)
    near = np.hypot(points[:, 0] - p[0], points[:, 1] - p[1]) <= NEAR_P_M
    upward = chair_mesh.face_normals[faces][:, 2] >= UPWARD_NORMAL_Z
    seat = near & upward & (np.abs(points[:, 2] - seat_top) <= SEAT_BAND_M)
    above = near & (points[:, 2] > seat_top + ABOVE_SEAT_M)
    if not seat.any() or not above.any():
        return None
    forward = points[seat, :2].mean(axis=0) - points[above, :2].mean(axis=0)
    offset_m = float(np.hypot(*forward))
    if offset_m < MIN_BACK_OFFSET_M:
        return None
    return math.atan2(forward[1], forward[0]), offset_m


def check_direction(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, *, seed: int = 0
) -> tuple[SittingPose, BackrestCheck | None]:
    """The sitting pose with its direction checked against the backrest's.

    Returns:
        (g, the check): g keeps its yaw when the two agree within :data:`AGREEMENT_RAD`,
        or takes γ_back (p unchanged); the check is None when the seat gives no cue.
    """
    cue = backrest_yaw(chair_mesh, sitting_pose, seed=seed)
    if cue is None:
        return sitting_pose, None
    yaw_rad, offset_m = cue
    disagreement = wrap_angle(sitting_pose.yaw - yaw_rad)
    used = abs(disagreement) > AGREEMENT_RAD
    check = BackrestCheck(yaw_rad, offset_m, disagreement, used)
    if not used:
        return sitting_pose, check
    return SittingPose(np.asarray(sitting_pose.position, dtype=float).copy(), yaw_rad), check
