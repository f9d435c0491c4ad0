"""The seat under a sitting point, and where along the sitting ray it holds the bear.

The sitting ray runs from the imagined sitting point p₀ along the sitting direction γ,
toward where the NAO stands. A sitting point p(s) = p₀ + s·u on it is *supported* when
the seat continues under it, at the same height within :data:`SEAT_HEIGHT_TOLERANCE_M`,
for :data:`BEAR_EDGE_MARGIN_M` ahead: the bear's torso rests wholly on the seat and its
centre of mass, ahead of p, stays over it. The heights come from vertical rays over a
disc (:func:`seat_support_heights`), so slats and scan holes narrower than the bear do
not hide the seat.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import trimesh

from skills.geometry import SittingPose
from skills.nao_carrying import BEAR_COM_AHEAD_M, BEAR_TORSO_DEPTH_M

SEAT_HEIGHT_TOLERANCE_M = 0.03
"""How much the seat's height may change under a sliding p and still count as the seat
(a cushion's slope, a scan's noise; a step of more is the seat's edge or an armrest)."""
BEAR_EDGE_MARGIN_M = BEAR_TORSO_DEPTH_M / 2.0 + BEAR_COM_AHEAD_M
"""p stays this far (metres) behind the seat's front edge: the torso's front half and
the centre of mass's offset ahead of p (0.0425 + 0.013 m), so the bear does not tip off."""
SUPPORT_RADIUS_M = 0.04
"""The surface under a point is taken over a disc of this radius (metres), the bear
torso's half width: gaps between slats and holes in a scan are narrower than the bear."""
STEP_M = 0.01
"""Spacing of candidate sitting points and stances along the ray, metres."""
MAX_SLIDE_M = 0.30
"""p slides at most this far toward the NAO (metres): about a child's seat depth."""


_DISC_OFFSETS_M = np.array(
    [
        (dx, dy)
        for dx in np.arange(-SUPPORT_RADIUS_M, SUPPORT_RADIUS_M + 1e-9, 0.01)
        for dy in np.arange(-SUPPORT_RADIUS_M, SUPPORT_RADIUS_M + 1e-9, 0.01)
        if math.hypot(dx, dy) <= SUPPORT_RADIUS_M + 1e-9
    ]
)


def seat_support_heights(chair_mesh: trimesh.Trimesh, xy: np.ndarray, z_from: float) -> np.ndarray:
    """Height of the chair surface below each point, NaN where there is none.

    Vertical rays start at ``z_from`` on a 1 cm grid over a disc of ``SUPPORT_RADIUS_M``
    around each point; each ray finds the first surface below it, and the height is the
    median of the hits. A gap between slats or a hole in a scan does not hide the seat;
    the seat seems to reach ``SUPPORT_RADIUS_M`` past its edge.

    Args:
        chair_mesh: the chair, world frame.
        xy: (N, 2) query points, metres.
        z_from: height the vertical rays start from, metres.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    offsets = _DISC_OFFSETS_M
    hits = _first_surface_below(
        chair_mesh, (xy[:, None, :] + offsets[None, :, :]).reshape(-1, 2), z_from
    ).reshape(len(xy), len(offsets))
    found = ~np.isnan(hits)
    heights = np.full(len(xy), np.nan)
    for i in np.flatnonzero(found.any(axis=1)):
        heights[i] = float(np.median(hits[i, found[i]]))
    return heights


def _first_surface_below(chair_mesh: trimesh.Trimesh, xy: np.ndarray, z_from: float) -> np.ndarray:
    """Height of the first triangle straight below each (x, y) from ``z_from`` (NaN: none)."""
    # A vertical ray hits a triangle where the point lies inside its xy projection; the hit
    # height is the barycentric blend of the corner heights.
    triangles = np.asarray(chair_mesh.triangles, dtype=float)
    # Only triangles under the queried region can be hit.
    low, high = xy.min(axis=0), xy.max(axis=0)
    near = np.all(triangles[:, :, :2].max(axis=1) >= low, axis=1) & np.all(
        triangles[:, :, :2].min(axis=1) <= high, axis=1
    )
    triangles = triangles[near & (triangles[:, :, 2].min(axis=1) <= z_from)]
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    ab, ac = (b - a)[:, :2], (c - a)[:, :2]
    det = ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]
    usable = np.abs(det) > 1e-12
    a, b, c, ab, ac, det = a[usable], b[usable], c[usable], ab[usable], ac[usable], det[usable]
    heights = np.full(len(xy), np.nan)
    for i, point in enumerate(xy):
        ap = point - a[:, :2]
        v = (ap[:, 0] * ac[:, 1] - ap[:, 1] * ac[:, 0]) / det
        w = (ab[:, 0] * ap[:, 1] - ab[:, 1] * ap[:, 0]) / det
        inside = (v >= 0.0) & (w >= 0.0) & (v + w <= 1.0)
        z = (1.0 - v - w) * a[:, 2] + v * b[:, 2] + w * c[:, 2]
        below = z[inside & (z <= z_from)]
        if len(below):
            heights[i] = below.max()
    return heights


class SeatRay(NamedTuple):
    """The seat along the sitting ray from the imagined p (metres).

    Attributes:
        slides_m: (S,) candidate slides s of p toward the NAO, supported ones only.
        seat_heights_m: (S,) the seat's height under each p(s).
    """

    slides_m: np.ndarray
    seat_heights_m: np.ndarray


def seat_ray(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose) -> SeatRay:
    """The supported sitting points along the ray from p toward the NAO (see module doc)."""
    p = np.asarray(sitting_pose.position, dtype=float)
    u = sitting_pose.direction()
    ahead = np.arange(0.0, MAX_SLIDE_M + BEAR_EDGE_MARGIN_M + SUPPORT_RADIUS_M + STEP_M, STEP_M)
    heights = seat_support_heights(chair_mesh, p[:2] + ahead[:, None] * u, float(p[2]) + 0.02)
    if np.isnan(heights[0]):
        return SeatRay(np.zeros(0), np.zeros(0))
    on_seat = np.abs(heights - heights[0]) <= SEAT_HEIGHT_TOLERANCE_M
    # The support disc sees the seat up to its radius past the edge.
    seat_ends_m = (
        ahead[int(np.argmin(on_seat))] - STEP_M - SUPPORT_RADIUS_M
        if not on_seat.all()
        else math.inf
    )
    limit = min(MAX_SLIDE_M, seat_ends_m - BEAR_EDGE_MARGIN_M)
    # p stays where it was imagined when that is already within the margin: the
    # imagination's p is where the child sat, so the seat holds the bear there.
    supported = (ahead <= max(limit, 0.0) + 1e-9) & on_seat
    supported &= np.cumprod(supported).astype(bool)
    return SeatRay(ahead[supported], heights[supported])


def slide_on_seat(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, slide_m: float
) -> tuple[SittingPose, float]:
    """Moves p toward the NAO along the sitting direction by up to ``slide_m`` (metres),
    only over supported seat (see the module doc).

    Returns:
        The moved sitting pose (its height follows the seat) and the distance moved.
    """
    ray = seat_ray(chair_mesh, sitting_pose)
    allowed = np.flatnonzero(ray.slides_m <= slide_m + 1e-9)
    if len(allowed) == 0:
        return sitting_pose, 0.0
    slide = float(ray.slides_m[allowed[-1]])
    moved = np.asarray(sitting_pose.position, dtype=float).copy()
    moved[:2] += slide * sitting_pose.direction()
    moved[2] += float(ray.seat_heights_m[allowed[-1]] - ray.seat_heights_m[0])
    return SittingPose(moved, sitting_pose.yaw), slide
