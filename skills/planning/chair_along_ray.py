"""The chair along the sitting ray, as the NAO's body meets it, and the refusals it gives.

Distances are metres from the imagined sitting point p₀ along the sitting direction u,
positive toward the NAO; the band is the strip ``BAND_HALF_WIDTH_M`` either side of the
ray that the NAO's body and hands sweep (:mod:`.wholebody.chair_profile`). The stance
search (:mod:`bearchair.skills.planning.stance`) reads the chair through these, and
words its refusals with them.
"""

from __future__ import annotations

import math
from typing import NamedTuple, cast

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.seen_surface import seen_samples
from bearchair.skills.planning.seat import SeatRay
from bearchair.skills.planning.wholebody.chair_profile import (
    BAND_HALF_WIDTH_M,
    BEAR_LANE_HALF_WIDTH_M,
    RAIL_CLEARANCE_M,
    stands_above_seat,
)
from bearchair.skills.planning.wholebody.held_bear import BEAR_DEPTH_M
from bearchair.skills.planning.wholebody.optimisation import BEAR_CHAIR_MARGIN_M
from bearchair.skills.planning.wholebody.reach_model import ReachModel

MAX_CENTRING_M = BEAR_LANE_HALF_WIDTH_M - 0.01
"""How far (metres) p may move across the sitting ray to centre the NAO's band between
armrests: the bear's lane, less a centimetre, still covers the imagined p. A sitter lands
where its drop put it, often a few centimetres off the middle between armrests, and the
NAO's hands need the middle."""


class ChairAlongRay(NamedTuple):
    """The chair in the band the NAO's body sweeps, along the sitting ray (metres, from p₀
    along u, positive toward the NAO).

    Attributes:
        front_m: f₀, the farthest the chair reaches at or below the seat top (plus 1 cm):
            the seat block's front as the whole-body planner sees it.
        above_seat_m: the farthest anything above the seat (a backrest, armrests)
            reaches; -inf when nothing stands on the seat in the band.
    """

    front_m: float
    above_seat_m: float


def surface_samples(chair_mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """(points, seen): (N, 3) points of the chair's surface the search looks at (20000
    samples, seed 0, and the vertices; world frame, metres) and (N,) whether a frame
    measured each (:mod:`bearchair.core.seen_surface`; all of a mesh without the mark)."""
    # Without sample_color, trimesh returns exactly (points, face indices).
    points, face_index = cast(
        tuple[np.ndarray, np.ndarray], trimesh.sample.sample_surface(chair_mesh, 20000, seed=0)
    )
    return np.vstack([points, chair_mesh.vertices]), seen_samples(chair_mesh, face_index)


def chair_along_ray(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    seat_top_m: float,
    points: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> ChairAlongRay:
    """Where the chair lies along the sitting ray within ``BAND_HALF_WIDTH_M`` of it,
    below and above the seat top (:mod:`.wholebody.chair_profile`'s two blocks);
    ``points``, ``seen``: :func:`surface_samples` when the caller has them."""
    p = np.asarray(sitting_pose.position, dtype=float)
    u = sitting_pose.direction()
    if points is None:
        points, seen = surface_samples(chair_mesh)
    rel = points[:, :2] - p[:2]
    along = rel @ u
    across = rel @ np.array([-u[1], u[0]])
    in_band = np.abs(across) <= BAND_HALF_WIDTH_M
    below = in_band & (points[:, 2] <= seat_top_m + 0.01)
    above = in_band & stands_above_seat(across, points[:, 2], seat_top_m, seen)
    return ChairAlongRay(
        float(along[below].max()) if below.any() else 0.0,
        float(along[above].max()) if above.any() else -math.inf,
    )


def centred_between_rails(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    seat_top_m: float,
    points: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> SittingPose:
    """p moved across the ray so that what stands on the seat beside it (armrests) leaves
    the NAO's band, ``RAIL_CLEARANCE_M`` outside it on each side it stands (to the gap's
    middle where the gap holds the band but not both clearances); p unchanged when
    nothing stands within that of the band ahead of the bear's back, the gap is
    narrower than the band, or the move would be longer than ``MAX_CENTRING_M``.

    With a and b the nearest such points left and right of the ray (across it, metres;
    a missing side counts as far away), band w and clearance c, the move is

    .. math::

        δ = \\operatorname{clip}\\Big(\\tfrac{a + b}{2},\\; b + w + c,\\; a - w - c\\Big),

    the middle of the gap, kept within the moves that clear both sides (δ = (a + b) / 2
    when 2w ≤ a − b < 2(w + c)). ``points``, ``seen``: :func:`surface_samples` when
    the caller has them.
    """
    a, b = rails_beside(chair_mesh, sitting_pose, seat_top_m, points, seen)
    reach = BAND_HALF_WIDTH_M + RAIL_CLEARANCE_M
    if a > reach and b < -reach:
        return sitting_pose
    lowest, highest = b + reach, a - reach
    if lowest <= highest:
        middle = (
            (a + b) / 2.0 if math.isfinite(a + b) else (lowest if math.isfinite(b) else highest)
        )
        move = float(np.clip(middle, lowest, highest))
    elif a - b >= 2.0 * BAND_HALF_WIDTH_M:
        move = (a + b) / 2.0  # room for the band, not its clearance: the most either side
    else:
        return sitting_pose  # the gap is narrower than the band: no move helps
    if abs(move) > MAX_CENTRING_M:
        return sitting_pose
    u = sitting_pose.direction()
    moved = np.asarray(sitting_pose.position, dtype=float).copy()
    moved[:2] += move * np.array([-u[1], u[0]])
    return SittingPose(moved, sitting_pose.yaw)


def rails_beside(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    seat_top_m: float,
    points: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> tuple[float, float]:
    """(a, b): across the sitting ray (metres, left of it positive), the nearest points
    left and right of p that stand on a ``seat_top_m`` high seat in the way of the bear or
    the hands (:func:`.wholebody.chair_profile.stands_above_seat`), ahead of the bear's
    back and within ``BAND_HALF_WIDTH_M + RAIL_CLEARANCE_M + MAX_CENTRING_M`` of the ray;
    +inf (left) or -inf (right) where a side has none; beside the bear's lane only
    what a frame measured counts (``seen``). ``points``, ``seen``: :func:`surface_samples`
    when the caller has them."""
    p = np.asarray(sitting_pose.position, dtype=float)
    u = sitting_pose.direction()
    if points is None:
        points, seen = surface_samples(chair_mesh)
    rel = points[:, :2] - p[:2]
    along, across = rel @ u, rel @ np.array([-u[1], u[0]])
    ahead = along >= -(BEAR_DEPTH_M / 2.0 + BEAR_CHAIR_MARGIN_M)
    standing = ahead & (np.abs(across) <= BAND_HALF_WIDTH_M + RAIL_CLEARANCE_M + MAX_CENTRING_M)
    standing &= stands_above_seat(across, points[:, 2], seat_top_m, seen)
    left = across[standing & (across > 0.0)]
    right = across[standing & (across <= 0.0)]
    return (
        float(left.min()) if len(left) else math.inf,
        float(right.max()) if len(right) else -math.inf,
    )


def rails_gap_reason(gap_m: float) -> str:
    """How far armrests or rails ``gap_m`` apart (metres, :func:`rails_beside`'s a - b)
    fall short of the room the NAO's hands need to lower the bear between them; empty
    when they leave it (or there are not two)."""
    needed = 2.0 * (BAND_HALF_WIDTH_M + RAIL_CLEARANCE_M)
    if not math.isfinite(gap_m) or gap_m >= needed:
        return ""
    return (
        f"the armrests or rails beside the sitting point stand {gap_m:.3f} m apart, and the "
        f"NAO's hands need {needed:.3f} m between them to lower the bear there "
        f"({needed - gap_m:.3f} m short)"
    )


def closed_above(chair: ChairAlongRay, ray: SeatRay) -> bool:
    """Whether something standing on the seat in the band (armrests, a backrest) leaves
    no sitting point on the ray room for the bear's back in front of it."""
    return not np.any(ray.slides_m >= chair.above_seat_m + BEAR_DEPTH_M / 2.0 + BEAR_CHAIR_MARGIN_M)


def blocked_above_reason(chair: ChairAlongRay, ray: SeatRay) -> str:
    overhang = chair.above_seat_m + BEAR_DEPTH_M / 2.0 - float(ray.slides_m[-1])
    return (
        f"the seat is closed in the NAO's way: something on it within "
        f"{BAND_HALF_WIDTH_M:.3f} m of the sitting ray (armrests, a backrest) leaves no room "
        f"for the bear ({BEAR_DEPTH_M:.3f} m deep) on the seat's front "
        f"({overhang:.3f} m short); the NAO's hands hold the bear "
        f"{BAND_HALF_WIDTH_M:.3f} m either side of it"
    )


def seat_height_reason(height_m: float, model: ReachModel) -> str:
    """Why a seat ``height_m`` high (metres) is beyond the heights the NAO places a bear
    on from any stance; empty when it is within them."""
    highest, lowest = model.max_seat_height_m(), model.min_seat_height_m()
    if height_m > highest:
        return (
            f"seat too high for the NAO: seat {height_m:.3f} m, the NAO places a bear at most "
            f"{highest:.3f} m high"
        )
    if height_m < lowest:
        return (
            f"seat too low for the NAO: seat {height_m:.3f} m, the NAO places a bear on seats "
            f"at least {lowest:.3f} m high"
        )
    return ""


def out_of_reach_reason(
    ray: SeatRay,
    front_m: float,
    stances_m: np.ndarray,
    model: ReachModel,
    seat_under_p_m: float = math.nan,
    rails_gap_m: float = math.nan,
) -> str:
    """Why the reach model places the bear nowhere on this seat from any stance.

    ``ray`` holds the heights the bear is carried over (the seat, or the chair's top in
    the NAO's way where higher); ``seat_under_p_m``, the seat itself under p (metres),
    names which of the two is too high; ``rails_gap_m``, how far apart the armrests or
    rails beside p stand (metres, :func:`rails_beside`), says by how much they leave the
    hands too little room to lower the bear between them instead.
    """
    height = float(ray.seat_heights_m[0])
    beyond = seat_height_reason(height, model)
    if beyond and height > seat_under_p_m and not seat_height_reason(seat_under_p_m, model):
        between = rails_gap_reason(rails_gap_m)
        return (
            f"chair too high in the NAO's way: the bear is carried over armrests or rails as "
            f"onto a {height:.3f} m seat (the seat under the sitting point is "
            f"{seat_under_p_m:.3f} m), and the NAO places a bear at most "
            f"{model.max_seat_height_m():.3f} m high" + (f"; {between}" if between else "")
        )
    if beyond:
        return beyond
    # The stance that comes closest: the nearest sitting point against the reach there.
    best = (math.inf, math.nan, math.nan)
    for stance in stances_m:
        d_max = model.max_forward(height, float(stance - front_m))
        needed = float(stance - ray.slides_m[-1])
        if not math.isnan(d_max) and needed - d_max < best[0]:
            best = (needed - d_max, needed, d_max)
    if math.isnan(best[1]):
        return f"seat out of the NAO's reach: no posture places a bear on a {height:.3f} m seat"
    return (
        f"seat out of the NAO's reach: the nearest supported sitting point is {best[1]:.3f} m "
        f"ahead of the NAO at best, which reaches {best[2]:.3f} m there on a {height:.3f} m "
        f"seat"
    )
