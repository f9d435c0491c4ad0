"""The seat under a sitting point, and where along the sitting ray it holds the bear.

The sitting ray runs from the imagined sitting point p₀ along the sitting direction γ,
toward where the NAO stands. A sitting point p(s) = p₀ + s·u on it is *supported* when
the seat continues under it, at the same height within :data:`SEAT_HEIGHT_TOLERANCE_M`,
for :data:`BEAR_EDGE_MARGIN_M` ahead, and does not fall away by more than
:data:`SEAT_DROP_TOLERANCE_M`: the bear's torso rests wholly on the seat and its
centre of mass, ahead of p, stays over it. The heights come from vertical rays over a
disc (:func:`seat_support_heights`), so slats and scan holes narrower than the bear do
not hide the seat.
"""

from __future__ import annotations

import math
from typing import NamedTuple, cast

import numpy as np
import trimesh
from scipy import ndimage

from bearchair.core.geometry import SittingPose
from bearchair.core.nao_carrying import (
    BEAR_COM_AHEAD_M,
    BEAR_COM_HEIGHT_M,
    BEAR_TORSO_DEPTH_M,
    PLACEMENT_TOLERANCE_M,
)
from bearchair.hardware.bear_model import BEAR_TORSO_FOOTPRINT_M

SEAT_HEIGHT_TOLERANCE_M = 0.03
"""How much the seat's height may change under a sliding p and still count as the seat
(a cushion's slope, a scan's noise; a step of more is the seat's edge or an armrest)."""
SEAT_DROP_TOLERANCE_M = BEAR_TORSO_DEPTH_M * (
    (BEAR_TORSO_DEPTH_M / 2.0 - BEAR_COM_AHEAD_M) / BEAR_COM_HEIGHT_M / 2.0
)
"""How far (metres) the seat may fall away ahead of the highest seat behind it, toward
the NAO, and still count as the seat: a rounded or sloping front edge. A bear whose torso
rests on a seat falling by δ over its depth D leans forward by atan(δ/D); it tips when
its centre of mass passes the torso's front edge, at a lean of
atan((D/2 - c_x)/c_z) = 16 deg (c: the centre of mass ahead of and over the seat point).
Half that slope keeps room for the landing: δ = D·(D/2 - c_x)/(2·c_z) = 1.25 cm. Where
the seat rises ahead (a reclined seat) the bear leans back, which the 3 cm height
tolerance bounds."""
BEAR_EDGE_MARGIN_M = BEAR_TORSO_DEPTH_M / 2.0 + BEAR_COM_AHEAD_M + PLACEMENT_TOLERANCE_M
"""p stays this far (metres) behind the seat's front edge: the torso's front half, the
centre of mass's offset ahead of p and how far short of p the whole-body goal may put the
bear (0.0425 + 0.013 + 0.015 m), so the bear does not tip off. At the reach limit the goal
posture puts the bear that much nearer the NAO, toward the edge: bears set down with p
5.55 cm behind the edge (no tolerance) tipped forward off deep seats in two of 60
calibration trials."""
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
    """Height of the first triangle straight below each (x, y) from ``z_from`` (NaN: none).

    Vertical rays cast down from ``z_from`` with open3d's ray casting (Embree, float32:
    heights to about a micrometre on a chair-sized scene), 30-100 times faster than
    testing every point against every triangle in numpy on meshes of 1-20 k triangles.
    """
    import open3d as o3d  # imported here: the perception stack is slow to import

    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    heights = np.full(len(xy), np.nan)
    if len(xy) == 0 or len(chair_mesh.faces) == 0:
        return heights
    # Tensors' dtype and device as open3d would choose them (its stubs lack their defaults).
    cpu = o3d.core.Device("CPU:0")
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(np.asarray(chair_mesh.vertices, dtype=np.float32), o3d.core.float32, cpu),
        o3d.core.Tensor(np.asarray(chair_mesh.faces, dtype=np.uint32), o3d.core.uint32, cpu),
    )
    rays = np.zeros((len(xy), 6), dtype=np.float32)
    rays[:, :2], rays[:, 2], rays[:, 5] = xy, z_from, -1.0
    hits = scene.cast_rays(o3d.core.Tensor(rays, o3d.core.float32, cpu))
    distance = hits["t_hit"].numpy().astype(float)
    hit = np.isfinite(distance)
    heights[hit] = z_from - distance[hit]
    return heights


class SeatRay(NamedTuple):
    """The seat along the sitting ray from the imagined p (metres).

    Attributes:
        slides_m: (S,) candidate slides s of p toward the NAO, supported ones only.
        seat_heights_m: (S,) the seat's height under each p(s).
        seat_seen: the scan has the seat's top under p, or under the bear's footprint
            within :data:`UNSEEN_SLIDE_M` ahead of it (the slides then start there); when
            not (a scan that lost it, while the imagined child sat there), p stays and
            nothing is known of the seat ahead of it.
        unseen_m: how far ahead of p the seen seat starts (metres; 0: under p).
    """

    slides_m: np.ndarray
    seat_heights_m: np.ndarray
    seat_seen: bool = True
    unseen_m: float = 0.0


SEAT_MAP_BEHIND_M = 0.15
"""The seat map starts this far (metres) behind p: the bear's footprint and a hole's rim."""
SEAT_MAP_HALF_WIDTH_M = 0.15
"""... and reaches this far (metres) either side of the ray."""
SLAT_GAP_M = min(BEAR_TORSO_FOOTPRINT_M) - 2.0 * PLACEMENT_TOLERANCE_M
"""Gaps in the seat up to this wide (metres) are closed on the seat map: the gaps between
slats, a scan's cracks. The bear's torso, its contact footprint (0.085 m by 0.10 m in
``hardware/bear_model.py``), rests on both sides of such a gap however it is turned and
wherever the whole-body goal sets it down within its placement tolerance (1.5 cm either
way): the footprint's smaller side less twice the tolerance, 0.055 m. The closing's disc
on the map's 1 cm grid is 7 cells across (a radius of 3)."""


class SeatMap(NamedTuple):
    """The seat around the sitting ray (see :func:`seat_map`).

    Attributes:
        along_m: (R,) the rows' distances along u from p, metres.
        seat: (R, C) seat cells, gaps closed and enclosed holes filled.
        heights_m: (R, C) the first surface below p in each cell, metres (NaN: none).
        seat_height_m: h₀, the seat's height under p (NaN: no seat there).
    """

    along_m: np.ndarray
    seat: np.ndarray
    heights_m: np.ndarray
    seat_height_m: float


def seat_map(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose) -> SeatMap:
    """The seat around the sitting ray as a height map (metres).

    A grid of ``STEP_M`` cells in the ray's frame (rows along u from
    ``-SEAT_MAP_BEHIND_M``, columns across from ``-SEAT_MAP_HALF_WIDTH_M``) holds the first
    surface below p (plus 2 cm) in each cell. The seat's height h₀ is the surface under p
    (:func:`_seat_height_under`); a cell is seat when its surface lies within
    ``SEAT_HEIGHT_TOLERANCE_M`` of h₀. Gaps up to
    ``SLAT_GAP_M`` are closed and holes enclosed by seat are filled: a scan's holes are
    not holes in the chair.

    """
    p = np.asarray(sitting_pose.position, dtype=float)
    u = sitting_pose.direction()
    v = np.array([-u[1], u[0]])
    along = np.arange(-SEAT_MAP_BEHIND_M, MAX_SLIDE_M + BEAR_EDGE_MARGIN_M + 2 * STEP_M, STEP_M)
    across = np.arange(-SEAT_MAP_HALF_WIDTH_M, SEAT_MAP_HALF_WIDTH_M + 1e-9, STEP_M)
    a, c = np.meshgrid(along, across, indexing="ij")
    xy = p[:2] + a.reshape(-1, 1) * u + c.reshape(-1, 1) * v
    heights = _first_surface_below(chair_mesh, xy, float(p[2]) + 0.02).reshape(a.shape)
    h0 = _seat_height_under(heights, np.hypot(a, c), float(p[2]))
    if math.isnan(h0):
        return SeatMap(along, np.zeros(a.shape, dtype=bool), heights, math.nan)
    seat = np.abs(np.nan_to_num(heights, nan=-1.0) - h0) <= SEAT_HEIGHT_TOLERANCE_M
    seat &= ~_falls_away_ahead(heights, seat, along)
    radius = round(SLAT_GAP_M / 2.0 / STEP_M)
    disc = np.hypot(*np.mgrid[-radius : radius + 1, -radius : radius + 1]) <= radius + 1e-9
    padded = np.pad(seat, radius + 1, mode="edge")
    closed = cast(np.ndarray, ndimage.binary_closing(padded, structure=disc))[
        radius + 1 : -radius - 1, radius + 1 : -radius - 1
    ]
    return SeatMap(along, cast(np.ndarray, ndimage.binary_fill_holes(closed | seat)), heights, h0)


def _falls_away_ahead(heights: np.ndarray, seat: np.ndarray, along_m: np.ndarray) -> np.ndarray:
    """(R, C) cells ahead of p lower than the highest seat cell between p and them, in
    their column, by more than :data:`SEAT_DROP_TOLERANCE_M`."""
    ahead = along_m >= -1e-9
    seat_heights = np.where(seat & ahead[:, None], np.nan_to_num(heights, nan=-np.inf), -np.inf)
    highest_behind = np.maximum.accumulate(seat_heights, axis=0)
    falls = np.nan_to_num(heights, nan=np.inf) < highest_behind - SEAT_DROP_TOLERANCE_M
    return falls & ahead[:, None]


def _seat_height_under(heights: np.ndarray, distance_m: np.ndarray, p_z: float) -> float:
    """h₀ (metres): the median of the top surface within ``SUPPORT_RADIUS_M`` of p; where the
    scan lost the seat there, the median of the surfaces within ``SEAT_MAP_BEHIND_M`` that
    lie where a seat under a sitting child's pelvis can (1 to 12 cm below p). NaN: none."""
    disc = (distance_m <= SUPPORT_RADIUS_M) & ~np.isnan(heights)
    if disc.sum() >= 0.2 * (distance_m <= SUPPORT_RADIUS_M).sum():
        # The seat is the top surface: rays through a slatted seat's gaps meet the frame
        # below it, which is not what the bear sits on.
        hits = heights[disc]
        return float(np.median(hits[hits >= hits.max() - SEAT_HEIGHT_TOLERANCE_M]))
    near = (distance_m <= SEAT_MAP_BEHIND_M) & (heights <= p_z - 0.01) & (heights >= p_z - 0.12)
    return float(np.median(heights[near])) if near.any() else math.nan


UNSEEN_SLIDE_M = BEAR_TORSO_DEPTH_M
"""Where the scan lost the seat under p, the bear's seat point may move this far (metres)
ahead along the ray to where the scan shows the seat under its whole torso: one torso
depth. A pelvis sits against the backrest, and the strip of seat in front of a back is
what the views from behind the chair do not see past it (a tub or basket's back wrapping
round its seat hides 5-8 cm of it); the bear, its torso wholly on seen seat, still sits
where the child did to within its own depth."""


def seat_ray(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose) -> SeatRay:
    """The supported sitting points along the ray from p toward the NAO (see module doc).

    A point p(s) is on the seat when at least half of the seat map's cells within
    ``SUPPORT_RADIUS_M`` across the ray at s are seat; the seat ends at the first s that
    is not, and p(s) is supported up to ``BEAR_EDGE_MARGIN_M`` before that. Where p
    itself is not on the seat, the seat starts at the first p(s), s up to
    :data:`UNSEEN_SLIDE_M`, with seat under the whole torso (half its depth either side).
    """
    along, seat, heights, h0 = seat_map(chair_mesh, sitting_pose)
    if math.isnan(h0):
        return SeatRay(np.zeros(0), np.zeros(0))
    columns = round(SUPPORT_RADIUS_M / STEP_M)
    middle = seat.shape[1] // 2
    band = slice(middle - columns, middle + columns + 1)
    on_seat = seat[:, band].mean(axis=1) >= 0.5
    # The seat's height along the ray: its measured cells' median (h₀ across a filled hole).
    measured = np.where(seat[:, band] & ~np.isnan(heights[:, band]), heights[:, band], np.nan)
    row_heights = np.full(len(along), h0)
    has = ~np.isnan(measured).all(axis=1)
    row_heights[has] = np.nanmedian(measured[has], axis=1)
    ahead = along >= -1e-9
    behind = (along[~ahead], on_seat[~ahead], row_heights[~ahead])
    along, on_seat, row_heights = along[ahead], on_seat[ahead], row_heights[ahead]
    unseen_m = 0.0
    if not on_seat[0]:
        start = _first_seen_torso(on_seat, along)
        if start is None:
            # The scan lost the seat's top here, yet the imagined child sat on it: p stays.
            return SeatRay(np.zeros(1), np.full(1, h0), seat_seen=False)
        along, on_seat, row_heights = along[start:], on_seat[start:], row_heights[start:]
        unseen_m = float(along[0])
    if on_seat.all():
        limit = MAX_SLIDE_M
    else:
        end = int(np.argmin(on_seat))
        lowest_m = float(np.max(row_heights[:end])) - SEAT_DROP_TOLERANCE_M
        edge_m = _seat_edge_between(
            chair_mesh, sitting_pose, along[end - 1], along[end], h0, lowest_m
        )
        limit = min(MAX_SLIDE_M, edge_m - BEAR_EDGE_MARGIN_M)
    if limit < 0.0 and unseen_m == 0.0:
        deeper = _deeper_on_seat(*behind, -limit)
        if deeper is not None:
            return SeatRay(np.array([-deeper[0]]), np.array([deeper[1]]))
    # p stays where it was imagined when it is within the margin and the seat behind it
    # does not reach as far as the margin: the child sat there.
    supported = (along <= max(limit, 0.0) + 1e-9) & on_seat
    supported &= np.cumprod(supported).astype(bool)
    slides, slide_heights = along[supported], row_heights[supported]
    if not len(slides):
        # The seen seat ahead of p is shallower than the bear's margin to its edge.
        return SeatRay(np.zeros(1), np.full(1, h0), seat_seen=False)
    if limit > slides[-1] + EDGE_RESOLUTION_M:
        # The last grid point may lie up to a step short of the margin: add the margin's.
        slides = np.append(slides, limit)
        slide_heights = np.append(slide_heights, slide_heights[-1])
    return SeatRay(slides, slide_heights, unseen_m=unseen_m)


def _deeper_on_seat(
    along_m: np.ndarray, on_seat: np.ndarray, row_heights_m: np.ndarray, deficit_m: float
) -> tuple[float, float] | None:
    """Where p goes when it lies nearer the seat's front edge than ``BEAR_EDGE_MARGIN_M``:
    ``deficit_m`` deeper (away from the NAO), rounded up to the grid, when every row
    between holds seat; (how deep, the seat's height there) or None. The child sat at p;
    the bear is smaller and its centre of mass lies ahead of its seat point."""
    depth_m = math.ceil(deficit_m / STEP_M - 1e-9) * STEP_M
    rows = np.flatnonzero(along_m >= -depth_m - 1e-9)
    if not len(rows) or not on_seat[rows].all():
        return None
    deepest = int(rows[0])
    return float(-along_m[deepest]), float(row_heights_m[deepest])


def _first_seen_torso(on_seat: np.ndarray, along_m: np.ndarray) -> int | None:
    """The first row (index into ``along_m``, rows from p ahead) within
    :data:`UNSEEN_SLIDE_M` of p whose rows within half the torso's depth either side are
    all seat, or None."""
    half = round(BEAR_TORSO_DEPTH_M / 2.0 / STEP_M)
    for row in np.flatnonzero(along_m <= UNSEEN_SLIDE_M + 1e-9):
        if row >= half and on_seat[row - half : row + half + 1].all():
            return int(row)
    return None


EDGE_RESOLUTION_M = 0.001
"""The seat's front edge is located to this (metres) between the grid's last seat row and
its first row past the edge: a centimetre of seat is a centimetre of the NAO's reach."""


def _seat_edge_between(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    last_seat_m: float,
    past_edge_m: float,
    h0: float,
    lowest_m: float,
) -> float:
    """Where along the ray (metres from p) the seat's top ends, between a grid row that
    is seat and the next that is not: the farthest row at ``EDGE_RESOLUTION_M`` spacing
    where at least half of the band across the ray (``SUPPORT_RADIUS_M`` either side)
    meets the seat's height h₀ within ``SEAT_HEIGHT_TOLERANCE_M`` and lies no lower than
    ``lowest_m`` (where the seat falls away, :data:`SEAT_DROP_TOLERANCE_M`)."""
    p = np.asarray(sitting_pose.position, dtype=float)
    u = sitting_pose.direction()
    v = np.array([-u[1], u[0]])
    rows = np.arange(last_seat_m, past_edge_m, EDGE_RESOLUTION_M)
    across = np.arange(-SUPPORT_RADIUS_M, SUPPORT_RADIUS_M + 1e-9, STEP_M)
    a, c = np.meshgrid(rows, across, indexing="ij")
    xy = p[:2] + a.reshape(-1, 1) * u + c.reshape(-1, 1) * v
    heights = _first_surface_below(chair_mesh, xy, float(p[2]) + 0.02).reshape(a.shape)
    seat = np.abs(np.nan_to_num(heights, nan=-1.0) - h0) <= SEAT_HEIGHT_TOLERANCE_M
    seat &= np.nan_to_num(heights, nan=-1.0) >= lowest_m
    on_seat = np.flatnonzero(seat.mean(axis=1) >= 0.5)
    return float(rows[on_seat[-1]]) if len(on_seat) else float(last_seat_m)


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


def level_surfaces(chair_mesh: trimesh.Trimesh) -> np.ndarray:
    """Heights (metres) of the chair's level surfaces the bear's torso rests on, one per
    surface, largest first.

    The top surface over the chair's footprint is sampled on a ``STEP_M`` grid by vertical
    rays (:func:`_first_surface_below`). A cell holds the torso where every cell within
    ``SUPPORT_RADIUS_M`` of it (the torso's half width) has a surface, all within
    ``SEAT_HEIGHT_TOLERANCE_M`` of one another: a seat, not an armrest's narrow top nor a
    backrest's edge. Each connected group of such cells is a surface; its height is its
    cells' median, and the largest (most cells) comes first.
    """
    if len(chair_mesh.faces) == 0:
        return np.zeros(0)
    (x0, y0, _), (x1, y1, z1) = chair_mesh.bounds
    xs = np.arange(x0, x1 + STEP_M, STEP_M)
    ys = np.arange(y0, y1 + STEP_M, STEP_M)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    heights = _first_surface_below(
        chair_mesh, np.column_stack([gx.ravel(), gy.ravel()]), float(z1) + 0.01
    ).reshape(gx.shape)
    radius = round(SUPPORT_RADIUS_M / STEP_M)
    disc = np.hypot(*np.mgrid[-radius : radius + 1, -radius : radius + 1]) <= radius + 1e-9
    missing = np.isnan(heights)
    near_missing = cast(
        np.ndarray, ndimage.maximum_filter(missing, footprint=disc, mode="constant", cval=True)
    )
    highest = ndimage.maximum_filter(
        np.where(missing, -np.inf, heights), footprint=disc, mode="constant", cval=-np.inf
    )
    lowest = ndimage.minimum_filter(
        np.where(missing, np.inf, heights), footprint=disc, mode="constant", cval=np.inf
    )
    holds = ~near_missing & (highest - lowest <= SEAT_HEIGHT_TOLERANCE_M)
    # Two surfaces at heights further apart than the tolerance never touch: the cells at
    # the step between them hold nothing.
    labels, n = cast(tuple[np.ndarray, int], ndimage.label(holds))
    if n == 0:
        return np.zeros(0)
    sizes = np.bincount(labels.ravel())[1:]
    order = np.argsort(-sizes, kind="stable") + 1
    return np.array([float(np.median(heights[labels == label])) for label in order])
