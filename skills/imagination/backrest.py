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

The centroid has one failure of its own: a scan that saw one armrest and not the other
pulls c_above sideways (46 deg on a narrow armchair). The chair's shape settles which of
the two is its sagittal plane, because a chair is its own mirror image across it: the
share of the chair's surface points whose mirror image across the vertical plane along a
direction, through the seat (the best of offsets within :data:`MIRROR_OFFSETS_M` of p),
lands within :data:`MIRROR_TOLERANCE_M` of the surface,

.. math::

    m(γ) = \\max_{o} \\; \\frac{1}{N} \\left|\\{x_i : d(R_{γ,o}\\, x_i, X) \\le τ\\}\\right|.

The cue is taken only when the vote's plane does not mirror the chair better by more
than :data:`MIRROR_MARGIN`: a vote whose plane mirrors the chair clearly better is the
chair's real symmetry (the measurements behind the margin: docs/decisions.md, "the
backrest cue's mirror check"). The two are mirrored only when they disagree (0.15-0.2 s
on a scan)."""

from __future__ import annotations

import math
from typing import Any, NamedTuple, cast

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose, wrap_angle
from bearchair.skills.planning.seat import seat_support_heights

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
MIRROR_TOLERANCE_M = 0.015
"""A mirrored point lands on the chair when it is this close to a surface point (metres):
one and a half of the scan's 1 cm voxels."""
MIRROR_OFFSETS_M = np.arange(-0.06, 0.0601, 0.01)
"""Mirror planes are tried at these lateral offsets from p (metres): the imagined sitter's
mean position lies within a few centimetres of the seat's middle."""
MIRROR_SAMPLES = 10000
"""Points mirrored (of the ``SAMPLES``), enough to tell a tenth of the surface apart."""
MIRROR_MARGIN = 0.1
"""The vote's direction stands against the cue when its plane mirrors this much more of
the chair's surface (a share of the points): a plane that is the chair's sagittal plane
against one that is not, not two near-symmetric planes of a round seat."""


class BackrestCheck(NamedTuple):
    """The backrest's sitting direction against the imagined one.

    Attributes:
        yaw_rad: γ_back, in the frame of the mesh given (radians).
        offset_m: how far c_above lies from c_seat (metres).
        disagreement_rad: imagined yaw minus γ_back, wrapped (radians).
        used: the sitting pose took γ_back (the two disagreed by more than
            :data:`AGREEMENT_RAD` and the vote's plane did not mirror the chair better).
        mirror_back: m(γ_back), the share of the chair mirrored by the cue's plane (NaN
            where the two agreed and it was not needed).
        mirror_vote: m(γ) of the imagined direction (NaN likewise).
    """

    yaw_rad: float
    offset_m: float
    disagreement_rad: float
    used: bool
    mirror_back: float = math.nan
    mirror_vote: float = math.nan

    def to_json(self) -> dict[str, Any]:
        return {
            "yaw_deg": round(math.degrees(self.yaw_rad), 2),
            "offset_m": round(self.offset_m, 4),
            "disagreement_deg": round(math.degrees(self.disagreement_rad), 2),
            "used": self.used,
            "mirror_back": None if math.isnan(self.mirror_back) else round(self.mirror_back, 3),
            "mirror_vote": None if math.isnan(self.mirror_vote) else round(self.mirror_vote, 3),
        }


def backrest_yaw(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    *,
    seed: int = 0,
    surface: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[float, float] | None:
    """γ_back and the centroids' distance (radians, metres), or None without a backrest.

    Args:
        chair_mesh: the chair, z up, metres (any horizontal frame; γ_back comes in it).
        sitting_pose: the imagined g; only p is used (the seat under it).
        seed: the surface sampling's seed.
        surface: the chair's surface samples and their faces when the caller has them.
    """
    p = np.asarray(sitting_pose.position, dtype=float)
    seat_top = float(seat_support_heights(chair_mesh, p[None, :2], float(p[2]))[0])
    if not math.isfinite(seat_top):
        return None
    points, faces = _surface(chair_mesh, seed) if surface is None else surface
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


def _surface(chair_mesh: trimesh.Trimesh, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``SAMPLES`` surface points (metres) and the faces they lie on."""
    # Without sample_color, trimesh returns exactly (points, face indices).
    return cast(
        tuple[np.ndarray, np.ndarray],
        trimesh.sample.sample_surface(chair_mesh, SAMPLES, seed=seed),
    )


def mirror_share(points: np.ndarray, p: np.ndarray, yaw_rad: float, tree: Any = None) -> float:
    """m(γ) (see the module doc): the largest share of ``points`` (N, 3) whose mirror image
    across a vertical plane along ``yaw_rad``, within ``MIRROR_OFFSETS_M`` of p, lies within
    ``MIRROR_TOLERANCE_M`` of a point; ``tree``: a ``cKDTree`` of ``points`` if built."""
    from scipy.spatial import cKDTree  # pyright: ignore[reportAttributeAccessIssue]  # no stub for scipy's compiled _ckdtree

    u = np.array([math.cos(yaw_rad), math.sin(yaw_rad)])
    v = np.array([-u[1], u[0]])
    tree = cKDTree(points) if tree is None else tree
    lateral = (points[:, :2] - np.asarray(p, dtype=float)[:2]) @ v
    best = 0.0
    for offset in MIRROR_OFFSETS_M:
        mirrored = points.copy()
        mirrored[:, :2] -= 2.0 * (lateral - offset)[:, None] * v
        distance, _ = tree.query(mirrored, distance_upper_bound=MIRROR_TOLERANCE_M)
        best = max(best, float(np.mean(np.isfinite(distance))))
    return best


def check_direction(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, *, seed: int = 0
) -> tuple[SittingPose, BackrestCheck | None]:
    """The sitting pose with its direction checked against the backrest's.

    Returns:
        (g, the check): g keeps its yaw when the two agree within :data:`AGREEMENT_RAD`,
        or takes γ_back (p unchanged); the check is None when the seat gives no cue.
    """
    surface = _surface(chair_mesh, seed)
    cue = backrest_yaw(chair_mesh, sitting_pose, seed=seed, surface=surface)
    if cue is None:
        return sitting_pose, None
    yaw_rad, offset_m = cue
    disagreement = wrap_angle(sitting_pose.yaw - yaw_rad)
    if abs(disagreement) <= AGREEMENT_RAD:
        return sitting_pose, BackrestCheck(yaw_rad, offset_m, disagreement, False)
    from scipy.spatial import cKDTree  # pyright: ignore[reportAttributeAccessIssue]  # no stub for scipy's compiled _ckdtree

    points = surface[0][:MIRROR_SAMPLES]
    tree = cKDTree(points)
    p = np.asarray(sitting_pose.position, dtype=float)
    mirror_back = mirror_share(points, p, yaw_rad, tree)
    mirror_vote = mirror_share(points, p, sitting_pose.yaw, tree)
    used = mirror_vote <= mirror_back + MIRROR_MARGIN
    check = BackrestCheck(yaw_rad, offset_m, disagreement, used, mirror_back, mirror_vote)
    if not used:
        return sitting_pose, check
    return SittingPose(np.asarray(sitting_pose.position, dtype=float).copy(), yaw_rad), check
