"""Where the NAO should stand to seat the bear, and an SE(2) path to get there.

The paper, section "System Pipeline": the SE(2) goal s_goal faces opposite the sitting
direction γ and lies on the horizontal ray from p along γ, first at ``l_init`` from p,
pushed along the ray until the NAO's ellipsoid is clear of the chair (and further, where
that spot is in a wall or obstacle, until it clears those too); if the NAO is then
beyond its arms' reach of p, p slides along the ray toward the NAO while staying on the
seat. The seat motion is pre-planned at s_goal to check it is valid (p slides closer
while the bear is out of reach; s_goal steps back while the carried bear would be in the
chair); then OMPL's
RRTConnect plans an SE(2) path from the humanoid to s_goal within the arena, checked with
FCL (:mod:`skills.planning.collision`). With u = (cos γ, sin γ) and distance l along
the ray:

.. math::

    s_{goal} = (p_{xy} + l\\,u,\\; γ + π).
"""

from __future__ import annotations

import importlib
import logging
import math
import time
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import trimesh
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from skills.arena import Arena
from skills.geometry import SE2Pose, SittingPose, wrap_angle
from skills.nao_carrying import BEAR_SEAT_CLEARANCE_M
from skills.planning.collision import NaoCollisionChecker, chair_convex_pieces
from skills.planning.reach import check_reach, max_forward_reach
from skills.results import AccessibilityResult

logger = logging.getLogger(__name__)

L_INIT_M = 0.25
"""Initial distance of the NAO from p along the sitting direction, metres."""
PUSH_STEP_M = 0.01
MAX_PUSH_M = 1.0
SEAT_STEP_M = 0.01
REACH_SLACK_M = 0.005
"""p slides to this much inside the arms' reach, so the reach check is not a rounding call."""
SEAT_HEIGHT_TOLERANCE_M = 0.03
"""How much the seat's height may change under p as it slides and still count as the seat."""
SEAT_EDGE_MARGIN_M = 0.07
"""p slides no closer than this to the seat's front edge: the bear's legs stick out
forward (its centre of mass is 2 cm ahead of p), and a bear set down at the edge tips
off it. Trials on chair-chairgen-01 put bears at the rounded front edge and lost them."""
MAX_SLIDE_RETRIES = 6
STANCE_RETRY_STEP_M = 0.02
"""After a pre-plan finds the NAO too close to the chair, s_goal steps back this much."""
SLIDE_RETRY_STEP_M = 0.03
"""After a pre-plan finds the bear out of reach, p slides this much closer and it retries."""
PLANNING_CHECKS = 60_000
"""RRTConnect's budget in state validity checks: about 1 s on the 2-core machine
(68 000 checks/s measured). A count, not a time, so that whether a hard placement gets a
path does not depend on how busy the machine is: the same seed gives the same answer."""
PLANNING_TIME_S = 10.0
"""A wall-clock safety net for the search, far above what the check budget takes."""
CHECK_RESOLUTION_M = 0.01
"""Spacing of validity checks along motions, metres (OMPL's resolution is relative)."""
WAYPOINT_SPACING_M = 0.1


class SeatingCheck(NamedTuple):
    """A seating validator's verdict.

    Attributes:
        reason: why seating from s_goal is infeasible ("" when feasible).
        bear_placement: the failure is about where the bear goes (reach), so sliding p
            closer to the NAO may fix it.
        too_close: the NAO stands too close to the chair (its feet, or the bear it
            carries, in the chair), so standing farther back may fix it.
        raise_at: feasible only with the bear raised, which the NAO does here (back
            along the ray from s_goal) before it steps in; None: walk in as it carries.
    """

    reason: str = ""
    bear_placement: bool = False
    too_close: bool = False
    raise_at: SE2Pose | None = None


SeatingValidator = Callable[[trimesh.Trimesh, SittingPose, SE2Pose], SeatingCheck]
"""Checks seating the bear at g from s_goal (the whole-body pre-plan, or arm reach)."""


class AccessibilityError(ValueError):
    """Bad input to the accessibility check (not an inaccessible chair)."""


class GoalPlacement(NamedTuple):
    """The SE(2) goal on the sitting ray.

    Attributes:
        se2_goal: where the NAO stands (None when no collision-free spot on the ray).
        sitting_pose: g, possibly slid toward the NAO to be within its arms' reach.
        standoff_m: distance from the (slid) p to the NAO along the ray.
        reason: why there is no goal (empty when there is).
        slide_m: how far p was moved toward the NAO.
    """

    se2_goal: SE2Pose | None
    sitting_pose: SittingPose
    standoff_m: float
    reason: str = ""
    slide_m: float = 0.0


def goal_on_ray(sitting_pose: SittingPose, distance_m: float) -> SE2Pose:
    """The NAO pose ``distance_m`` from p along the sitting direction, facing back at p."""
    direction = sitting_pose.direction()
    x, y = np.asarray(sitting_pose.position[:2], dtype=float) + distance_m * direction
    return SE2Pose(float(x), float(y), wrap_angle(sitting_pose.yaw + math.pi))


SUPPORT_RADIUS_M = 0.04
"""The surface under a point is taken over a disc of this radius (metres), not from one
vertical ray: slatted seats (chairgen-10) have gaps 3 cm wide, and scans have holes."""
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


def place_se2_goal(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    checker: NaoCollisionChecker,
    *,
    l_init_m: float = L_INIT_M,
) -> GoalPlacement:
    """Finds s_goal on the sitting ray and slides p within the NAO's reach (see module doc).

    Args:
        chair_mesh: the chair, world frame (for the seat under p).
        sitting_pose: g = (p, γ), world frame.
        checker: the NAO-versus-scene collision checker (its chair is used here).
        l_init_m: first distance tried from p, metres.
    """
    distance = l_init_m
    while checker.collides_with_chair(goal_on_ray(sitting_pose, distance)):
        distance += PUSH_STEP_M
        if distance > l_init_m + MAX_PUSH_M:
            return GoalPlacement(
                None, sitting_pose, distance, "no spot on the sitting ray clear of the chair"
            )
    distance = _clear_of_walls_and_obstacles(checker, sitting_pose, distance, l_init_m + MAX_PUSH_M)
    se2_goal = goal_on_ray(sitting_pose, distance)

    reach_m = max_forward_reach(bear_release_height(chair_mesh, sitting_pose))
    if distance <= reach_m or reach_m == 0.0:
        return GoalPlacement(se2_goal, sitting_pose, distance)
    moved, slide = slide_on_seat(chair_mesh, sitting_pose, distance - (reach_m - REACH_SLACK_M))
    return GoalPlacement(se2_goal, moved, distance - slide, slide_m=slide)


def _clear_of_walls_and_obstacles(
    checker: NaoCollisionChecker, sitting_pose: SittingPose, distance_m: float, max_m: float
) -> float:
    """The first distance from ``distance_m`` on (metres) where the NAO, inside the arena,
    also clears the walls and obstacles; ``distance_m`` itself when there is none.

    A chair near the arena's edge leaves its first chair-free spot with the NAO's front in
    the wall behind the chair; a step further back along the ray (p then slides toward the
    NAO) is a valid goal. When no spot clears everything, the first chair-free one stays so
    that the goal check names what blocks it.
    """
    distance = distance_m
    while distance <= max_m:
        goal = goal_on_ray(sitting_pose, distance)
        if not checker.arena.contains(goal.x, goal.y):
            break
        if not checker.collides_with_walls(goal) and not checker.collides_with_obstacles(goal):
            return distance
        distance += PUSH_STEP_M
    return distance_m


def slide_on_seat(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    slide_m: float,
    edge_margin_m: float = SEAT_EDGE_MARGIN_M,
) -> tuple[SittingPose, float]:
    """Moves p along the sitting direction by up to ``slide_m``, only as far as the seat
    continues under it (its height within ``SEAT_HEIGHT_TOLERANCE_M`` of the seat under p)
    for another ``edge_margin_m`` ahead.

    Returns:
        The moved sitting pose (its height follows the seat) and the distance moved, metres.
    """
    direction = sitting_pose.direction()
    slides = np.minimum(np.arange(0.0, slide_m + SEAT_STEP_M, SEAT_STEP_M), slide_m)
    ahead = np.arange(0.0, slide_m + edge_margin_m + SEAT_STEP_M, SEAT_STEP_M)
    p = np.asarray(sitting_pose.position, dtype=float)
    heights = seat_support_heights(
        chair_mesh, p[:2] + ahead[:, None] * direction, float(p[2]) + 0.02
    )
    if np.isnan(heights[0]):
        logger.warning("no seat found under the sitting position; p is not moved")
        return sitting_pose, 0.0
    on_seat = np.abs(heights - heights[0]) <= SEAT_HEIGHT_TOLERANCE_M
    # The support disc sees the seat up to its radius past the edge.
    seat_ends_m = (
        ahead[int(np.argmin(on_seat))] - SEAT_STEP_M - SUPPORT_RADIUS_M
        if not on_seat.all()
        else math.inf
    )
    # Never slide backwards: when p is already within the margin it stays where it is.
    allowed = slides <= max(seat_ends_m - edge_margin_m, 0.0) + 1e-9
    last = int(np.flatnonzero(allowed)[-1])
    slide = float(slides[last])
    moved = p.copy()
    moved[:2] += slide * direction
    moved[2] += float(np.interp(slide, ahead, heights)) - heights[0]
    return SittingPose(moved, sitting_pose.yaw), slide


def bear_release_height(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose) -> float:
    """Where the bear's seat point is let go: ``BEAR_SEAT_CLEARANCE_M`` over the seat under
    p (metres); p's own height (the imagined pelvis) when no seat is found under it."""
    p = np.asarray(sitting_pose.position, dtype=float)
    seat_z = seat_support_heights(chair_mesh, p[None, :2], float(p[2]) + 0.02)[0]
    return float(p[2]) if np.isnan(seat_z) else float(seat_z) + BEAR_SEAT_CLEARANCE_M


def reach_validator(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SeatingCheck:
    """Fallback validity check: the NAO's arms reach p from s_goal (:mod:`reach`)."""
    offset = np.asarray(sitting_pose.position[:2], dtype=float) - (se2_goal.x, se2_goal.y)
    forward = float(offset @ (math.cos(se2_goal.theta), math.sin(se2_goal.theta)))
    check = check_reach(forward, bear_release_height(chair_mesh, sitting_pose))
    return SeatingCheck(check.reason, forward > check.max_forward_m)


def default_seating_validator() -> SeatingValidator:
    """The whole-body pre-plan when ``skills.planning.wholebody`` provides it, else reach."""
    try:
        module = importlib.import_module("skills.planning.wholebody")
    except ModuleNotFoundError as error:
        if error.name and "skills.planning.wholebody".startswith(error.name):
            return reach_validator
        raise
    preplan = getattr(module, "preplan_approach", None)
    if preplan is None:
        return reach_validator
    infeasible = getattr(module, "InfeasibleSeating", ValueError)
    stance = getattr(module, "STANCE", None)

    def wholebody_validator(
        chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
    ) -> SeatingCheck:
        try:
            raise_at = preplan(chair_mesh, sitting_pose, se2_goal)
        except infeasible as error:
            constraint = getattr(error, "constraint", "")
            return SeatingCheck(
                f"seating pre-plan infeasible: {error}",
                bear_placement=constraint == "bear placement",
                too_close=constraint == stance,
            )
        return SeatingCheck(raise_at=raise_at)

    return wholebody_validator


def stepped_back(se2_goal: SE2Pose, distance_m: float) -> SE2Pose:
    """s_goal moved ``distance_m`` back along the sitting ray (the NAO faces the chair)."""
    return SE2Pose(
        se2_goal.x - distance_m * math.cos(se2_goal.theta),
        se2_goal.y - distance_m * math.sin(se2_goal.theta),
        se2_goal.theta,
    )


class PlannedPath(NamedTuple):
    """An SE(2) path, or why there is none.

    Attributes:
        waypoints: start to goal, every ``WAYPOINT_SPACING_M`` or so (empty when none).
        seconds: OMPL solve plus simplification wall time.
        reason: why no path was found (empty when found).
    """

    waypoints: tuple[SE2Pose, ...]
    seconds: float
    reason: str = ""


def _seed_ompl(seed: int) -> None:
    # OMPL complains (harmlessly) when reseeded after its first RNG was made; the reseed
    # still makes every later planner's sampler sequence a function of ``seed``.
    level = ou.getLogLevel()
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed) % (2**31 - 1) + 1)
    finally:
        ou.setLogLevel(level)


def goal_blocked_reason(checker: NaoCollisionChecker, goal: SE2Pose) -> str:
    """Why the NAO cannot stand at ``goal`` (outside the arena, or touching something), or ""."""
    if not checker.arena.contains(goal.x, goal.y):
        return "s_goal is outside the planning arena"
    blocker = checker.blocked_by(goal)
    return f"s_goal is blocked by the {blocker}" if blocker else ""


def plan_se2_path(
    checker: NaoCollisionChecker,
    start: SE2Pose,
    goal: SE2Pose,
    *,
    seed: int,
    check_budget: int = PLANNING_CHECKS,
    time_budget_s: float = PLANNING_TIME_S,
) -> PlannedPath:
    """RRTConnect in SE(2) over the arena, then shortcut simplification.

    Args:
        checker: validity of a NAO pose (arena bounds, walls, obstacles, chair).
        start: the humanoid's pose now.
        goal: s_goal.
        seed: OMPL's random seed (same seed, same path).
        check_budget: the search gives up after this many state validity checks.
        time_budget_s: ... or after this many seconds, whichever comes first.
    """
    arena = checker.arena
    reason = goal_blocked_reason(checker, goal)
    if reason:
        return PlannedPath((), 0.0, reason)
    if not arena.contains(start.x, start.y):
        return PlannedPath((), 0.0, "the humanoid is outside the planning arena")
    blocker = checker.blocked_by(start)
    if blocker:
        return PlannedPath((), 0.0, f"the humanoid's own pose touches the {blocker}")

    log_level = ou.getLogLevel()
    ou.setLogLevel(ou.LogLevel.LOG_ERROR)  # this build defaults to DEBUG chatter on stderr
    try:
        return _run_rrt_connect(
            checker, start, goal, seed=seed, check_budget=check_budget, time_budget_s=time_budget_s
        )
    finally:
        ou.setLogLevel(log_level)


def _run_rrt_connect(
    checker: NaoCollisionChecker,
    start: SE2Pose,
    goal: SE2Pose,
    *,
    seed: int,
    check_budget: int,
    time_budget_s: float,
) -> PlannedPath:
    arena = checker.arena
    _seed_ompl(seed)
    space = ob.SE2StateSpace()
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, arena.x_min)
    bounds.setHigh(0, arena.x_max)
    bounds.setLow(1, arena.y_min)
    bounds.setHigh(1, arena.y_max)
    space.setBounds(bounds)
    setup = og.SimpleSetup(space)
    checks_made = 0

    def is_valid(state: ob.State) -> bool:
        nonlocal checks_made
        checks_made += 1
        return checker.is_free(state.getX(), state.getY(), state.getYaw())

    setup.setStateValidityChecker(is_valid)
    information = setup.getSpaceInformation()
    information.setStateValidityCheckingResolution(CHECK_RESOLUTION_M / space.getMaximumExtent())
    start_state, goal_state = space.allocState(), space.allocState()
    for state, pose in ((start_state, start), (goal_state, goal)):
        state.setX(pose.x)
        state.setY(pose.y)
        state.setYaw(wrap_angle(pose.theta))  # SO(2) bounds are [-π, π)
    setup.setStartAndGoalStates(start_state, goal_state)
    setup.setPlanner(og.RRTConnect(information))

    began = time.perf_counter()
    setup.solve(
        ob.PlannerTerminationCondition(
            lambda: checks_made >= check_budget or time.perf_counter() - began > time_budget_s
        )
    )
    if not setup.haveExactSolutionPath():
        return PlannedPath((), time.perf_counter() - began, "no collision-free path to s_goal")
    setup.simplifySolution()
    path = setup.getSolutionPath()
    path.interpolate(max(2, math.ceil(path.length() / WAYPOINT_SPACING_M) + 1))
    seconds = time.perf_counter() - began
    waypoints = tuple(
        SE2Pose(float(s.getX()), float(s.getY()), wrap_angle(float(s.getYaw())))
        for s in (path.getState(i) for i in range(path.getStateCount()))
    )
    # The ends are exactly the requested poses (OMPL may copy them with rounding).
    return PlannedPath((start, *waypoints[1:-1], goal), seconds)


def check_accessibility(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    arena: Arena,
    *,
    seed: int,
    seating_validator: SeatingValidator | None = None,
    check_budget: int = PLANNING_CHECKS,
) -> AccessibilityResult:
    """Finds s_goal for a sitting pose, checks it and plans the humanoid's path there.

    Args:
        chair_mesh: the chair, world frame, z up.
        sitting_pose: g = (p, γ), world frame.
        humanoid_pose: where the humanoid is now.
        arena: walls and fixed obstacles.
        seed: OMPL's random seed.
        seating_validator: checks seating from s_goal; default: the whole-body pre-plan
            when available, else the arm-reach check.
        check_budget: RRTConnect gives up after this many state validity checks.

    Returns:
        accessible with the path, or not with the reason; ``seconds`` is the OMPL time.

    Raises:
        AccessibilityError: an empty chair mesh or a non-finite pose.
    """
    if chair_mesh is None or len(chair_mesh.faces) == 0:
        raise AccessibilityError("the chair mesh has no triangles")
    if not (np.all(np.isfinite(sitting_pose.position)) and math.isfinite(sitting_pose.yaw)):
        raise AccessibilityError("the sitting pose is not finite")
    if not all(math.isfinite(v) for v in humanoid_pose):
        raise AccessibilityError("the humanoid's pose is not finite")

    original_pose = sitting_pose
    checker = NaoCollisionChecker(arena, chair_convex_pieces(chair_mesh))
    placement = place_se2_goal(chair_mesh, sitting_pose, checker)
    if placement.se2_goal is None:
        return AccessibilityResult(False, None, placement.sitting_pose, (), placement.reason)
    se2_goal, sitting_pose = placement.se2_goal, placement.sitting_pose

    reason = goal_blocked_reason(checker, se2_goal)
    if reason:
        return AccessibilityResult(False, se2_goal, sitting_pose, (), reason)
    validator = seating_validator or default_seating_validator()
    check = validator(chair_mesh, sitting_pose, se2_goal)
    # The pre-plan knows the NAO better than the ellipsoid and the reach model that placed
    # s_goal: while the bear is out of reach, slide p closer along the seat; while the NAO
    # stands too close (the carried bear in the chair), step s_goal back along the ray.
    slide = placement.slide_m
    for _ in range(MAX_SLIDE_RETRIES):
        if check.reason and check.too_close:
            backed = stepped_back(se2_goal, STANCE_RETRY_STEP_M)
            if goal_blocked_reason(checker, backed):
                break
            se2_goal = backed
        elif check.reason and check.bear_placement:
            moved, moved_m = slide_on_seat(chair_mesh, original_pose, slide + SLIDE_RETRY_STEP_M)
            if moved_m <= slide + 1e-6:
                break  # the seat ends here
            slide, sitting_pose = moved_m, moved
        else:
            break
        check = validator(chair_mesh, sitting_pose, se2_goal)
    if check.reason:
        return AccessibilityResult(False, se2_goal, sitting_pose, (), check.reason)
    if check.raise_at is not None:
        # The path ends where the bear is raised; the NAO then steps straight in.
        blocked = _step_in_blocked_by(checker, check.raise_at, se2_goal)
        if blocked:
            reason = f"the step in from raising the bear to s_goal touches the {blocked}"
            return AccessibilityResult(False, se2_goal, sitting_pose, (), reason)

    path_goal = check.raise_at or se2_goal
    planned = plan_se2_path(checker, humanoid_pose, path_goal, seed=seed, check_budget=check_budget)
    return AccessibilityResult(
        not planned.reason,
        se2_goal,
        sitting_pose,
        planned.waypoints,
        planned.reason,
        planned.seconds,
        raise_at=check.raise_at,
    )


def _step_in_blocked_by(checker: NaoCollisionChecker, start: SE2Pose, goal: SE2Pose) -> str:
    """What the NAO touches on the straight step from ``start`` to ``goal`` ("" if none)."""
    steps = max(2, math.ceil(start.distance_to(goal) / CHECK_RESOLUTION_M) + 1)
    for t in np.linspace(0.0, 1.0, steps):
        pose = SE2Pose(
            start.x + t * (goal.x - start.x), start.y + t * (goal.y - start.y), goal.theta
        )
        blocker = checker.blocked_by(pose)
        if blocker:
            return blocker
    return ""
