"""The chair as two blocks in the NAO's sagittal plane, for collision constraints.

The chair mesh is moved into the NAO frame (x forward, y left, z up, origin on the floor
between the feet) and sampled; only the part within a lateral band ``|y - g_y| <= band``
(the width swept by the NAO's body, arms and the bear) matters for a planar, symmetric
motion. The band is centred on the sitting point g, which lies within millimetres of the
NAO's sagittal plane, so that where the NAO stops does not change the profile.
That cross-section is bounded by two axis-aligned blocks, each the region behind a
vertical plane and below a horizontal one:

* the seat block  ``{x >= seat_front_x, z <= seat_top_z}``: the seat top is the
  highest horizontal surface under the sitting pose in the bear's lane, raised where a
  rail beside the lane would be in the palms' way to ``HANDS_ABOVE_SEAT_M`` less
  ``RAIL_CLEARANCE_M`` below the rail's top (the bear is let go over the seat, not over
  an armrest); its front plane is the chair's front-most point at or below the seat;
* the back block  ``{x >= back_front_x, z <= back_top_z}``: everything above the seat
  (backrest, or anything else standing up from it), from its front-most point up to
  its top.

Everything below the seat top and behind its front is treated as solid (no knees under
the seat), which is conservative. The signed clearance of a point to a block is
``max(front_x - x, z - top_z)``: positive outside, and never more than the true
distance.
"""

from __future__ import annotations

from typing import NamedTuple, cast

import numpy as np
import trimesh

from bearchair.core.errors import SkillError
from bearchair.core.geometry import transform_points
from bearchair.core.nao_carrying import BEAR_SEAT_BELOW_HANDS_M, BEAR_SEAT_CLEARANCE_M
from bearchair.core.seen_surface import seen_samples

BAND_HALF_WIDTH_M = 0.11
"""Half-width of the lateral band the planar motion sweeps, metres. Narrower than the
planar arms themselves (their palms' centres at |y| = 0.113 m, the hands 0.0175 m
thick): a band of 0.13 m put many armrests in the way of the bear and refused or raised
the carry on armchairs the NAO now seats, with its wrists in their armrests."""

BEAR_LANE_HALF_WIDTH_M = 0.06
"""Half-width of the lane the bear itself sweeps (its torso is 0.10 m wide), metres."""
HANDS_ABOVE_SEAT_M = BEAR_SEAT_CLEARANCE_M + BEAR_SEAT_BELOW_HANDS_M - 0.015
"""Beside the bear's lane only the hands and arms pass; the lowest of them, the palms
(``BEAR_SEAT_BELOW_HANDS_M`` above the bear's seat point, which is let go
``BEAR_SEAT_CLEARANCE_M`` over the seat; the planner's hand points have a 0.015 m
radius), stays this high over the seat top, metres: lower rails beside the bear are not
in their way."""

RAIL_CLEARANCE_M = 0.01
"""Where a rail beside the bear raises the seat top, the palms pass this much higher over
it (metres): the scan's noise on the rail's top, a few millimetres, must not make the rail
stand in the hands' way."""


def stands_above_seat(
    lateral_m: np.ndarray, z_m: np.ndarray, seat_top_m: float, seen: np.ndarray | None = None
) -> np.ndarray:
    """Which points (lateral offset from the sagittal plane, height; metres) stand above the
    seat in the way of the bear or the hands: above the seat top in the bear's lane, above
    the hands' lowest point beside it. ``seen``: which of them a frame measured
    (:mod:`bearchair.core.seen_surface`); beside the lane only those count, for a scan grows
    an armrest's inner face inward where no view looked (None: all of them)."""
    lateral = np.abs(lateral_m)
    in_lane = lateral <= BEAR_LANE_HALF_WIDTH_M
    beside = z_m > seat_top_m + HANDS_ABOVE_SEAT_M
    if seen is not None:
        beside &= seen
    return (z_m > seat_top_m + 0.015) & (in_lane | beside)


HORIZONTAL_NORMAL_Z = 0.95
"""A surface sample with |n_z| at least this belongs to a horizontal surface."""


class ChairProfileError(SkillError, ValueError):
    """The chair has no usable seat under the sitting pose in the NAO's sagittal plane."""


class ChairProfile(NamedTuple):
    """The chair's cross-section in the NAO frame as two blocks (metres).

    Attributes:
        seat_front_x: the seat block's front plane.
        seat_top_z: the seat's top plane (the largest horizontal surface under g).
        back_front_x: the back block's front plane (large when there is no backrest).
        back_top_z: the back block's top.
    """

    seat_front_x: float
    seat_top_z: float
    back_front_x: float
    back_top_z: float

    def as_vector(self) -> np.ndarray:
        """The four numbers in the order the optimisation's parameters take them."""
        return np.array([self.seat_front_x, self.seat_top_z, self.back_front_x, self.back_top_z])

    def clearance(self, points_xz: np.ndarray) -> np.ndarray:
        """Conservative signed clearance (metres) of (N, 2) points to both blocks."""
        seat = np.maximum(self.seat_front_x - points_xz[:, 0], points_xz[:, 1] - self.seat_top_z)
        back = np.maximum(self.back_front_x - points_xz[:, 0], points_xz[:, 1] - self.back_top_z)
        return np.minimum(seat, back)


def fit_chair_profile(
    chair_mesh: trimesh.Trimesh,
    T_nao_world: np.ndarray,
    sitting_point_nao: np.ndarray,
    *,
    band_half_width_m: float = BAND_HALF_WIDTH_M,
    samples: int = 30000,
    seed: int = 0,
) -> ChairProfile:
    """Fits the two-block profile of a chair seen from the NAO.

    Args:
        chair_mesh: the chair in the world frame (z up, metres).
        T_nao_world: maps world points into the NAO frame.
        sitting_point_nao: (3,) the sitting pose's position in the NAO frame.
        band_half_width_m: lateral half-width of the swept band.
        samples: surface samples (deterministic for a given ``seed``).
        seed: sampling seed.

    Raises:
        ChairProfileError: no chair surface lies under the sitting pose in the band.
    """
    # Without sample_color, trimesh returns exactly (points, face indices).
    points, face_index = cast(
        tuple[np.ndarray, np.ndarray],
        trimesh.sample.sample_surface(chair_mesh, samples, seed=seed),
    )
    seen = seen_samples(chair_mesh, face_index)
    points = np.vstack([points, chair_mesh.vertices])
    normals = np.vstack(
        [chair_mesh.face_normals[face_index], np.zeros((len(chair_mesh.vertices), 3))]
    )
    points = transform_points(T_nao_world, points)
    normals = normals @ T_nao_world[:3, :3].T
    # The band is centred on g, not on the NAO: the NAO stops within millimetres of its
    # goal, and a rail at the band's edge must not be in the pre-plan's profile and out of
    # the one planned where the NAO stopped.
    g_x, g_y, g_z = (float(v) for v in sitting_point_nao)
    points[:, 1] -= g_y
    in_band = np.abs(points[:, 1]) <= band_half_width_m
    points, normals, seen = points[in_band], normals[in_band], seen[in_band]
    if len(points) == 0:
        raise ChairProfileError("no part of the chair lies in front of the NAO")

    seat_top_z = _seat_top_z(points, normals, seen, g_x, g_z)
    below = points[:, 2] <= seat_top_z + 0.01
    seat_front_x = float(np.min(points[below, 0]))
    above = stands_above_seat(points[:, 1], points[:, 2], seat_top_z, seen)
    if np.any(above):
        back_front_x = float(np.min(points[above, 0]))
        back_top_z = float(np.max(points[above, 2]))
    else:
        back_front_x, back_top_z = seat_front_x + 10.0, seat_top_z
    return ChairProfile(seat_front_x, seat_top_z, back_front_x, back_top_z)


def _seat_top_z(
    points: np.ndarray, normals: np.ndarray, seen: np.ndarray, g_x: float, g_z: float
) -> float:
    """The seat top (metres) under g = (``g_x``, ``g_z``) from the band's (N, 3) surface
    points, their normals (NAO frame, y from g) and which of them a frame measured (the
    rails beside the lane are judged on those: :func:`stands_above_seat`).

    Raises:
        ChairProfileError: no chair surface lies under g.
    """
    # The seat top: the highest horizontal surface under g not far above it (a pelvis
    # sits a few centimetres above the seat; higher horizontal surfaces are armrests or
    # the backrest's top), in the bear's lane; beside it, a rail the hands must pass over
    # raises it to where the palms clear the rail.
    under = (np.abs(points[:, 0] - g_x) <= 0.06) & (points[:, 2] <= g_z + 0.05)
    horizontal = under & (np.abs(normals[:, 2]) >= HORIZONTAL_NORMAL_Z)
    in_lane = np.abs(points[:, 1]) <= BEAR_LANE_HALF_WIDTH_M
    candidates = next(
        (points[m] for m in (horizontal & in_lane, under & in_lane, horizontal, under) if m.any()),
        points[:0],
    )
    if len(candidates) == 0:
        raise ChairProfileError(
            f"no seat under the sitting pose ({g_x:.2f} m forward, {g_z:.2f} m high)"
        )
    seat_top_z = float(np.max(candidates[:, 2]))
    # A rail's top from all its samples, not only its horizontal top: a rail at the band's
    # edge would otherwise be a rail (its top in the band) or, a millimetre further out,
    # something standing above the seat (only its inner side in the band).
    rails = under & ~in_lane & seen
    if rails.any():
        rail_top = float(np.max(points[rails, 2]))
        seat_top_z = max(seat_top_z, rail_top - HANDS_ABOVE_SEAT_M + RAIL_CLEARANCE_M)
    return seat_top_z


def largest_horizontal_surface_height(chair_mesh: trimesh.Trimesh, *, bin_m: float = 0.01) -> float:
    """Height (metres) of the chair's largest horizontal upward-facing surface: its seat.

    Sums the area of upward faces (normal z >= 0.95) in height bins and returns the
    area-weighted height of the largest bin.
    """
    normals = chair_mesh.face_normals
    up = normals[:, 2] >= HORIZONTAL_NORMAL_Z
    heights = chair_mesh.triangles_center[up, 2]
    areas = chair_mesh.area_faces[up]
    if len(heights) == 0:
        raise ChairProfileError("the chair has no horizontal surface")
    bins = np.floor(heights / bin_m).astype(int)
    totals: dict[int, float] = {}
    for b, a in zip(bins, areas, strict=True):
        totals[b] = totals.get(b, 0.0) + float(a)
    best = max(totals, key=totals.__getitem__)
    mask = bins == best
    return float(np.average(heights[mask], weights=areas[mask]))
