"""Where the NAO stands and where the bear goes, chosen together.

The paper (section "System Pipeline") puts s_goal on the ray from p along the sitting
direction γ, pushes it out of collision, and moves p along the ray toward the robot "due
to the robot workspace constraint". Here the two are searched together: candidate
sitting points p(s) slide from the imagined p toward the NAO over the seat's supported
region, candidate stances stand at t from the imagined p along the same ray, and a pair
is taken when the reach model (:mod:`bearchair.skills.planning.wholebody.reach_model`) places the
bear there, preferring p closest to the imagined one and then the nearest stance. The
whole-body pre-plan (the seating validator) confirms the pair; when it refuses, the next
pair is tried. With u = (cos γ, sin γ) and p₀ the imagined sitting point:

.. math::

    p(s) = p_0 + s\\,u, \\qquad s_{goal}(t) = (p_{0,xy} + t\\,u,\\; γ + π),

    \\text{accept } (s, t) \\iff t - s \\le d_{max}(h(s),\\; t - f_0),

where h(s) is the seat's height under p(s), f₀ how far the chair's front (anything at or
below the seat in the band the NAO's body sweeps) lies ahead of p₀ along u.

Only sitting points where the seat holds the bear are candidates
(:mod:`bearchair.skills.planning.seat`). Stances where the walking NAO's ellipsoid clears the chair
come first; then nearer ones, down to the front of its feet at the chair's front, which
it reaches by stepping straight in from the first clear one (the pre-plan checks its
feet, shins, body and the carried bear against the chair).

When no pair on the imagined ray works, rays turned about p₀ by a few degrees
(``TURNS_RAD``) are searched the same way, with a smaller pre-plan budget each: the
sitting direction is uncertain by that much, and the chosen pair's sitting direction is
the turned one (the NAO faces it, so the bear does).

:func:`check_seat_reachable` runs the search with the chair alone (no walls, no
obstacles): when it finds nothing, no orientation of the chair can help, and the mission
refuses before anyone is asked to turn the chair.
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.arena import Arena, Box2D
from bearchair.core.geometry import SittingPose, wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.chair_along_ray import (
    blocked_above_reason,
    centred_between_rails,
    chair_along_ray,
    closed_above,
    out_of_reach_reason,
    rails_beside,
    surface_samples,
)
from bearchair.skills.planning.collision import NaoCollisionChecker, chair_solid_boxes
from bearchair.skills.planning.preplan import SeatingCheck, SeatingValidator, wholebody_validator
from bearchair.skills.planning.seat import STEP_M, SeatRay, level_surfaces, seat_ray
from bearchair.skills.planning.wholebody.chair_profile import (
    ChairProfileError,
    fit_chair_profile,
)
from bearchair.skills.planning.wholebody.reach_model import ReachModel, reach_model
from bearchair.skills.results import SeatReachability

STANCE_SEARCH_M = 0.08
"""Stances are tried up to this far (metres) beyond the first collision-free one: a
stance a little farther back gives the knees room in front of the seat."""
MAX_STANCE_M = 1.2
"""No stance farther than this (metres) from p₀ is considered."""
MAX_PREPLANS = 6
"""The whole-body pre-plan confirms at most this many candidate pairs on the imagined ray."""
TURNS_RAD = tuple(math.radians(d) for d in (5.0, -5.0, 10.0, -10.0))
"""When no pair on the imagined ray works, the ray is turned about p₀ by these angles
(radians, nearest first) and searched again: the sitting direction imagined from drops
is itself uncertain by a few degrees (the drops' start jitter is 2 deg, and the vote's
weighted mean moves with them), a front bar or a rail may cross the band a few
centimetres nearer on one side, and a wall may leave room for a slanted approach. 10 deg
stays well within the planner's facing tolerance (``wholebody.scene.FACING_TOLERANCE_RAD``, 20
deg) and the seating judge's 45 deg."""
PREPLANS_PER_TURN = 2
"""Pre-plans each turned ray may ask for: the reach model's first pairs are right when
the seat is reachable from there at all."""


class StanceChoice(NamedTuple):
    """The chosen stance and sitting point, or why there is none.

    Attributes:
        se2_goal: where the NAO stands, facing opposite γ (None when nothing works).
        sitting_pose: g with p moved along the ray (the imagined one when nothing works).
        reason: why there is none ("" when there is).
        check: the pre-plan's verdict for the chosen pair (``raise_at`` inside).
        slide_m: how far p moved toward the NAO, metres.
        preplans: how many pairs the pre-plan was asked about.
        depends_on_scene: the failure comes from walls, obstacles or the arena's bounds
            (turning the chair may help), not from the chair and the NAO alone.
        approach: where the walk ends when s_goal is nearer the chair than the walking
            NAO's ellipsoid allows: the NAO steps straight in from there (None: it
            walks to s_goal).
        seat_height_m: the seat's height under the imagined p, metres (NaN: no seat).
        turned_rad: how far the sitting direction was turned from the imagined one
            (``TURNS_RAD``) for the chosen pair, radians.
        centred_m: how far p moved across the ray, between armrests
            (:func:`centred_between_rails`), metres.
    """

    se2_goal: SE2Pose | None
    sitting_pose: SittingPose
    reason: str = ""
    check: SeatingCheck = SeatingCheck()
    slide_m: float = 0.0
    preplans: int = 0
    depends_on_scene: bool = False
    approach: SE2Pose | None = None
    seat_height_m: float = math.nan
    turned_rad: float = 0.0
    centred_m: float = 0.0


def goal_on_ray(sitting_pose: SittingPose, distance_m: float) -> SE2Pose:
    """The NAO pose ``distance_m`` from p along the sitting direction, facing back at p."""
    direction = sitting_pose.direction()
    x, y = np.asarray(sitting_pose.position[:2], dtype=float) + distance_m * direction
    return SE2Pose(float(x), float(y), wrap_angle(sitting_pose.yaw + math.pi))


def planner_seat_top(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, ray: SeatRay) -> float:
    """The seat top (metres) as the whole-body planner's chair profile takes it (the highest
    horizontal surface near p in the NAO's band, side rails included), so that the search
    and the pre-plan see the same two blocks; the seat under p when no profile fits."""
    stance = goal_on_ray(sitting_pose, 0.3)
    T_nao_world = np.linalg.inv(stance.as_transform())
    p = np.asarray(sitting_pose.position, dtype=float)
    p_nao = T_nao_world[:3, :3] @ p + T_nao_world[:3, 3]
    try:
        return fit_chair_profile(chair_mesh, T_nao_world, p_nao).seat_top_z
    except ChairProfileError:
        return float(np.max(ray.seat_heights_m))


def _first_clear(
    checker: NaoCollisionChecker, sitting_pose: SittingPose, start_m: float, *, scene: bool
) -> tuple[float, str]:
    """The first distance (metres) from ``start_m`` on where the NAO clears the chair
    (and, with ``scene``, the walls and obstacles inside the arena), with "" , or NaN
    and what blocks every distance."""
    distance = start_m
    chair_clear = False
    blocker = "the chair"
    while distance <= MAX_STANCE_M:
        goal = goal_on_ray(sitting_pose, distance)
        if not checker.collides_with_chair(goal):
            chair_clear = True
            if not scene:
                return distance, ""
            if not checker.arena.contains(goal.x, goal.y):
                blocker = "the arena's edge"
                break
            if checker.collides_with_walls(goal):
                blocker = "the wall"
            elif checker.collides_with_obstacles(goal):
                blocker = "the obstacle"
            else:
                return distance, ""
        distance += STEP_M
    return math.nan, blocker if chair_clear else "the chair"


def choose_stance(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    checker: NaoCollisionChecker,
    validator: SeatingValidator,
    *,
    scene: bool = True,
    model: ReachModel | None = None,
) -> StanceChoice:
    """Searches stance and sitting point together on the imagined ray, then on rays
    turned about p₀ by ``TURNS_RAD`` (see :func:`_choose_stance_on_ray`).

    Args:
        chair_mesh: the chair, world frame, z up.
        sitting_pose: the imagined g = (p₀, γ), world frame.
        checker: the NAO-versus-scene collision checker.
        validator: the seating pre-plan, asked about the model's best pairs in turn.
        scene: also keep the stance clear of walls and obstacles inside the arena.
        model: the reach model (default: the shipped one).

    Returns:
        The first pair found, or the imagined ray's failure with its reason.
    """
    model = model or reach_model()
    surface = surface_samples(chair_mesh)

    def on_ray(pose: SittingPose, max_preplans: int) -> StanceChoice:
        return _choose_stance_on_ray(
            chair_mesh, pose, checker, validator, scene, model, max_preplans, surface
        )

    first = on_ray(sitting_pose, MAX_PREPLANS)
    if first.se2_goal is not None or not _turning_may_help(first, model):
        return first
    preplans = first.preplans
    p0 = np.asarray(sitting_pose.position, dtype=float)
    for turn in TURNS_RAD:
        choice = on_ray(SittingPose(p0, wrap_angle(sitting_pose.yaw + turn)), PREPLANS_PER_TURN)
        preplans += choice.preplans
        if choice.se2_goal is not None:
            return choice._replace(preplans=preplans, turned_rad=turn)
    return first._replace(preplans=preplans)


def _turning_may_help(choice: StanceChoice, model: ReachModel) -> bool:
    """False when the seat under p is outside every posture's heights (or absent)."""
    height = choice.seat_height_m
    return model.min_seat_height_m() <= height <= model.max_seat_height_m()


def _choose_stance_on_ray(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    checker: NaoCollisionChecker,
    validator: SeatingValidator,
    scene: bool,
    model: ReachModel,
    max_preplans: int,
    surface: tuple[np.ndarray, np.ndarray],
) -> StanceChoice:
    """Searches stance and sitting point together on one ray (see the module doc).

    Stances where the walking NAO's ellipsoid is clear come first (it walks there);
    then stances nearer the chair, down to the front of the feet at the chair's front,
    which it reaches by stepping straight in from the first clear one. The arguments
    are :func:`choose_stance`'s; ``max_preplans`` is how many pairs the pre-plan may be
    asked about, ``surface`` the chair's :func:`surface_samples`.
    """
    ray = seat_ray(chair_mesh, sitting_pose)
    if len(ray.slides_m) == 0:
        return StanceChoice(None, sitting_pose, "no seat under the sitting position")
    seat_top = planner_seat_top(chair_mesh, sitting_pose, ray)
    sitting_pose, ray, seat_top, centred_m = _centred_ray(
        chair_mesh, sitting_pose, ray, seat_top, surface
    )
    chair = chair_along_ray(chair_mesh, sitting_pose, seat_top, *surface)
    seat_under_p0 = float(ray.seat_heights_m[0])
    front = chair.front_m
    none = StanceChoice(None, sitting_pose, "", seat_height_m=seat_under_p0, centred_m=centred_m)
    # The planner lets the bear go over its own seat top (a dished seat's rim, rails):
    # the reach model is asked about that height.
    planner_ray = SeatRay(ray.slides_m, np.maximum(ray.seat_heights_m, seat_top))
    true_height = dict(zip(map(float, ray.slides_m), map(float, ray.seat_heights_m), strict=True))
    chair_clear, _ = _first_clear(checker, sitting_pose, 0.0, scene=False)
    if math.isnan(chair_clear):
        return none._replace(reason="no spot on the sitting ray clear of the chair")
    walk_in, blocker = _first_clear(checker, sitting_pose, chair_clear, scene=scene)
    if math.isnan(walk_in):
        return none._replace(
            reason=f"no spot on the sitting ray clear of the chair and {blocker}",
            depends_on_scene=True,
        )
    pairs, stances = _stance_pairs(planner_ray, front, walk_in, model)
    if not pairs:
        left, right = rails_beside(chair_mesh, sitting_pose, seat_under_p0, *surface)
        return none._replace(
            reason=out_of_reach_reason(
                planner_ray, front, stances, model, seat_under_p0, left - right
            ),
            depends_on_scene=scene and walk_in > chair_clear + 1e-9,
        )
    search = _RaySearch(
        chair_mesh, sitting_pose, checker, validator, scene, true_height, walk_in, none
    )
    last = _confirm_pairs(search, pairs, max_preplans)
    if last.se2_goal is None and closed_above(chair, ray) and not last.depends_on_scene:
        # The planar planner may still find its way past what stands on the seat (its
        # seat top is the highest horizontal surface near p), so that only names the
        # refusal when the pre-plan finds none.
        return last._replace(reason=f"{blocked_above_reason(chair, ray)} ({last.reason})")
    return last


def _stance_pairs(
    planner_ray: SeatRay, front_m: float, walk_in_m: float, model: ReachModel
) -> tuple[list[tuple[float, float, float]], np.ndarray]:
    """The reach model's (slide, seat height, stance) pairs (:func:`_model_pairs`) over the
    stances walked to (from ``walk_in_m`` back by ``STANCE_SEARCH_M``), then those stepped
    in to (nearer, down to the front of the feet at the chair's front), and all those
    stances (metres from p₀)."""
    walk_stances = np.arange(walk_in_m, walk_in_m + STANCE_SEARCH_M + 1e-9, STEP_M)
    nearest = max(front_m + float(model.seat_fronts_m[0]), 0.0)
    step_stances = np.arange(walk_in_m - STEP_M, nearest - 1e-9, -STEP_M)
    pairs = _model_pairs(planner_ray, front_m, walk_stances, model)
    pairs += _model_pairs(planner_ray, front_m, step_stances, model)
    return pairs, np.concatenate([walk_stances, step_stances])


def _centred_ray(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    ray: SeatRay,
    seat_top_m: float,
    surface: tuple[np.ndarray, np.ndarray],
) -> tuple[SittingPose, SeatRay, float, float]:
    """(sitting pose, its seat ray, the planner's seat top in metres, how far p moved in
    metres) with p centred between armrests (:func:`centred_between_rails`) when there is
    a seat under the centred p; else the given ones and 0."""
    centred = centred_between_rails(chair_mesh, sitting_pose, seat_top_m, *surface)
    if centred is sitting_pose:
        return sitting_pose, ray, seat_top_m, 0.0
    centred_ray = seat_ray(chair_mesh, centred)
    if not len(centred_ray.slides_m):
        return sitting_pose, ray, seat_top_m, 0.0
    centred_m = float(
        np.linalg.norm(np.asarray(centred.position) - np.asarray(sitting_pose.position))
    )
    return centred, centred_ray, planner_seat_top(chair_mesh, centred, centred_ray), centred_m


class _RaySearch(NamedTuple):
    """One ray's search, as the pre-plan confirms the reach model's pairs on it.

    Attributes:
        chair_mesh: the chair, world frame, z up.
        sitting_pose: g = (p₀, γ) the ray starts from (centred between armrests).
        checker: the NAO-versus-scene collision checker.
        validator: the seating pre-plan.
        scene: also keep the stance clear of walls and obstacles inside the arena.
        true_height: slide (metres) -> the seat's height (metres) under p there.
        walk_in: the first stance (metres from p₀) the walking NAO's ellipsoid clears.
        none: the ray's choice before any pair is found.
    """

    chair_mesh: trimesh.Trimesh
    sitting_pose: SittingPose
    checker: NaoCollisionChecker
    validator: SeatingValidator
    scene: bool
    true_height: dict[float, float]
    walk_in: float
    none: StanceChoice


def _confirm_pairs(
    search: _RaySearch, pairs: list[tuple[float, float, float]], max_preplans: int
) -> StanceChoice:
    """The first of the (slide, seat height, stance) ``pairs`` the pre-plan confirms, or
    the last failure; asking it at most ``max_preplans`` times (``preplans`` says how
    many)."""
    sitting_pose, checker, none = search.sitting_pose, search.checker, search.none
    seat_under_p0 = none.seat_height_m
    p0 = np.asarray(sitting_pose.position, dtype=float)
    u = sitting_pose.direction()
    approach_from = goal_on_ray(sitting_pose, search.walk_in)
    last = none
    preplans = 0
    too_close_within = -math.inf  # stances at or nearer than this put the NAO in the chair
    out_of_reach: dict[float, float] = {}  # slide -> its stances from here on fall short
    for slide, _, stance in pairs:
        if preplans == max_preplans:
            break
        if stance <= too_close_within + 1e-9 or stance >= out_of_reach.get(slide, math.inf) - 1e-9:
            continue
        moved = p0.copy()
        moved[:2] += slide * u
        moved[2] += search.true_height[slide] - seat_under_p0
        pose = SittingPose(moved, sitting_pose.yaw)
        goal = goal_on_ray(sitting_pose, stance)
        if search.scene and (
            checker.collides_with_walls(goal) or checker.collides_with_obstacles(goal)
        ):
            blocked = "the wall" if checker.collides_with_walls(goal) else "the obstacle"
            if not last.reason:
                last = none._replace(
                    reason=f"every stance that reaches the seat touches {blocked}",
                    depends_on_scene=True,
                )
            continue
        check = search.validator(search.chair_mesh, pose, goal)
        preplans += 1
        if not check.reason:
            approach = approach_from if stance < search.walk_in - 1e-9 else None
            return none._replace(
                se2_goal=goal,
                sitting_pose=pose,
                check=check,
                slide_m=slide,
                preplans=preplans,
                approach=approach,
            )
        # The pre-plan knows the NAO better than the model: a stance it finds too close
        # rules out every nearer one, a bear it cannot reach every farther stance for
        # that p; anything else (a collision on the way) rules out that p.
        if check.too_close:
            too_close_within = max(too_close_within, stance)
        elif check.bear_placement:
            out_of_reach[slide] = min(out_of_reach.get(slide, math.inf), stance)
        else:
            out_of_reach[slide] = -math.inf
        last = none._replace(sitting_pose=pose, reason=check.reason, check=check, slide_m=slide)
    return last._replace(preplans=preplans)


def _model_pairs(
    ray: SeatRay, front_m: float, stances_m: np.ndarray, model: ReachModel
) -> list[tuple[float, float, float]]:
    """(slide, seat height, stance) triples the reach model accepts, ordered by slide
    (the smallest first: p stays nearest the imagined one), then as ``stances_m`` is."""
    pairs = []
    for slide, height in zip(ray.slides_m, ray.seat_heights_m, strict=True):
        for stance in stances_m:
            d_max = model.max_forward(float(height), float(stance - front_m))
            if not math.isnan(d_max) and stance - slide <= d_max:
                pairs.append((float(slide), float(height), float(stance)))
    return pairs


def open_floor_arena(chair_mesh: trimesh.Trimesh) -> Arena:
    """An arena with no walls near and no obstacles around the chair (the chair alone)."""
    centre = chair_mesh.bounds.mean(axis=0)
    half = 3.0
    return Arena(
        x_min=float(centre[0]) - half,
        x_max=float(centre[0]) + half,
        y_min=float(centre[1]) - half,
        y_max=float(centre[1]) + half,
        chair_area=Box2D(float(centre[0]), float(centre[0]), float(centre[1]), float(centre[1])),
        arm_base_xy=(float(centre[0]) - half, float(centre[1])),
        obstacles=(),
        humanoid_start=SE2Pose(float(centre[0]) + half - 0.5, float(centre[1]), math.pi),
    )


def check_seat_reachable(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    *,
    seating_validator: SeatingValidator | None = None,
) -> SeatReachability:
    """Whether the NAO can seat the bear on this chair from any collision-free stance,
    whatever the walls and obstacles around it (so turning the chair cannot help).

    Args:
        chair_mesh: the chair, world frame, z up.
        sitting_pose: the imagined g, world frame.
        seating_validator: the pre-plan (default: the whole-body one).
    """
    began = time.perf_counter()
    ray = seat_ray(chair_mesh, sitting_pose)
    if len(ray.slides_m) == 0:
        p_z = float(sitting_pose.position[2])
        return SeatReachability(False, "no seat under the sitting position", p_z)
    checker = NaoCollisionChecker(open_floor_arena(chair_mesh), chair_solid_boxes(chair_mesh))
    validator = seating_validator or wholebody_validator
    choice = choose_stance(chair_mesh, sitting_pose, checker, validator, scene=False)
    p0 = np.asarray(sitting_pose.position, dtype=float)
    height = choice.seat_height_m
    seconds = time.perf_counter() - began
    if choice.se2_goal is None:
        reason = choice.reason
        if choice.check.reason:
            reason = f"no stance passes the seating pre-plan: {reason}"
        return SeatReachability(False, reason, height, seconds=seconds, seat_seen=ray.seat_seen)
    stance = float(np.hypot(choice.se2_goal.x - p0[0], choice.se2_goal.y - p0[1]))
    return SeatReachability(True, "", height, choice.slide_m, stance, seconds, choice.centred_m)


def check_seat_levels(chair_mesh: trimesh.Trimesh) -> SeatReachability:
    """Where no sitting was imagined: whether the scan shows nothing the NAO can place the
    bear on, whatever the sitting point: no level surface the bear's torso rests on
    (:func:`bearchair.skills.planning.seat.level_surfaces`) within the seat heights the
    NAO places a bear on.

    Not reachable only when the scan has such surfaces and every one is too high or too
    low (the reason lists them, largest first; ``seat_height_m`` is the largest's).
    Reachable (nothing rules the chair out) when one lies within the heights, or when the
    scan shows none (it may have lost the seat).

    Args:
        chair_mesh: the chair, world frame, z up (the floor at z = 0).
    """
    began = time.perf_counter()
    model = reach_model()
    lowest, highest = model.min_seat_height_m(), model.max_seat_height_m()
    levels = level_surfaces(chair_mesh)
    seconds = time.perf_counter() - began
    if not len(levels) or bool(np.any((levels >= lowest) & (levels <= highest))):
        return SeatReachability(True, "", math.nan, seconds=seconds)
    shown = ", ".join(f"{height:.3f}" for height in levels[:3])
    more = f" and {len(levels) - 3} more" if len(levels) > 3 else ""
    return SeatReachability(
        False,
        f"no level surface the bear rests on within the NAO's seat heights "
        f"({lowest:.3f}-{highest:.3f} m): the scan's lie at {shown} m{more}",
        float(levels[0]),
        seconds=seconds,
    )
