"""Where the NAO should stand to seat the bear, and an SE(2) path to get there.

The paper, section "System Pipeline": the SE(2) goal s_goal faces opposite the sitting
direction γ on the horizontal ray from p along γ, clear of the chair; p moves along the
ray toward the NAO as far as its workspace needs; the seat motion is pre-planned at
s_goal to check it is valid; then OMPL's RRTConnect plans an SE(2) path from the
humanoid to s_goal within the arena, checked with FCL (:mod:`skills.planning.collision`).

Stance and sitting point are chosen together by :mod:`skills.planning.stance` (reach
model, then the pre-plan). The walking NAO is an ellipsoid that covers the carried
bear; a stance nearer the chair than the ellipsoid allows (a footrest or a base that
sticks out under the seat) is reached by walking to the first pose on the ray where the
ellipsoid is clear and stepping straight in, as the whole-body pre-plan checked (feet,
shins, body and carried bear against the chair). With u = (cos γ, sin γ) and distance
l along the ray:

.. math::

    s_{goal} = (p_{xy} + l\\,u,\\; γ + π).
"""

from __future__ import annotations

import hashlib
import importlib
import logging
import math
import threading
import time
from collections import OrderedDict
from typing import NamedTuple

import numpy as np
import trimesh
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from core.arena import Arena
from core.geometry import SittingPose, wrap_angle
from core.se2 import SE2Pose
from skills.planning.collision import NaoCollisionChecker, chair_solid_boxes
from skills.planning.seat import seat_support_heights
from skills.planning.stance import (
    SeatingCheck,
    SeatingValidator,
    choose_stance,
    goal_on_ray,
)
from skills.planning.wholebody.chair_profile import ChairProfileError, fit_chair_profile
from skills.planning.wholebody.reach_model import reach_model
from skills.results import AccessibilityResult

logger = logging.getLogger(__name__)

__all__ = [
    "AccessibilityError",
    "SeatingCheck",
    "SeatingValidator",
    "check_accessibility",
    "default_seating_validator",
    "goal_on_ray",
    "plan_se2_path",
    "reach_validator",
    "seat_support_heights",
    "stepped_back",
]

PLANNING_CHECKS = 60_000
"""RRTConnect's budget in state validity checks: about 1 s on the 2-core machine
(68 000 checks/s measured). A count, not a time, so that whether a hard placement gets a
path does not depend on how busy the machine is: the same seed gives the same answer."""
PLANNING_TIME_S = 10.0
"""A wall-clock safety net for the search, far above what the check budget takes."""
CHECK_RESOLUTION_M = 0.01
"""Spacing of validity checks along motions, metres (OMPL's resolution is relative)."""
WAYPOINT_SPACING_M = 0.1


class AccessibilityError(ValueError):
    """Bad input to the accessibility check (not an inaccessible chair)."""


def reach_validator(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SeatingCheck:
    """A fast validity check without the pre-plan: the reach model
    (:mod:`skills.planning.wholebody.reach_model`) places the bear at g from s_goal, the
    chair's profile seen from there (seat front, seat top) as the whole-body planner
    sees it, and the front of the feet clear of the chair."""
    T_nao_world = np.linalg.inv(se2_goal.as_transform())
    p = np.asarray(sitting_pose.position, dtype=float)
    p_nao = T_nao_world[:3, :3] @ p + T_nao_world[:3, 3]
    try:
        profile = fit_chair_profile(chair_mesh, T_nao_world, p_nao)
    except ChairProfileError as error:
        return SeatingCheck(str(error), bear_placement=True)
    forward = float(p_nao[0])
    d_max = reach_model().max_forward(profile.seat_top_z, profile.seat_front_x)
    if math.isnan(d_max):
        return SeatingCheck(
            f"no posture places the bear on a {profile.seat_top_z:.2f} m seat whose front is "
            f"{profile.seat_front_x:.2f} m ahead",
            too_close=profile.seat_front_x < reach_model().seat_fronts_m[0],
            bear_placement=True,
        )
    if forward > d_max:
        return SeatingCheck(
            f"out of reach: {forward:.2f} m forward, the NAO reaches {d_max:.2f} m on a "
            f"{profile.seat_top_z:.2f} m seat",
            bear_placement=True,
        )
    return SeatingCheck()


PREPLAN_MEMO_SIZE = 64
"""Pre-plan answers kept, the least recently used dropped first (a stance search asks a
few to a few dozen questions)."""


class PreplanMemo:
    """The whole-body pre-plan's answers by chair, sitting pose and stance.

    The pre-plan is a pure function of the three (no warm starts), and the mission asks
    it the same questions twice: the chair-alone reachability check and then the
    accessibility check search the same stances on the same scan, each pre-plan taking
    0.3-0.9 s. The chair is keyed by the bytes of its vertices and faces (a SHA-1, under
    a millisecond on a 20 k-face scan), so a chair turned by the helper is a new chair.
    """

    def __init__(self, max_size: int = PREPLAN_MEMO_SIZE) -> None:
        self._answers: OrderedDict[tuple, SeatingCheck] = OrderedDict()
        self._max_size = max_size
        self._lock = threading.Lock()
        self.hits = 0

    @staticmethod
    def key(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose) -> tuple:
        digest = hashlib.sha1(np.ascontiguousarray(chair_mesh.vertices).tobytes())
        digest.update(np.ascontiguousarray(chair_mesh.faces).tobytes())
        pose = (*np.asarray(sitting_pose.position, dtype=float).tolist(), float(sitting_pose.yaw))
        return digest.hexdigest(), pose, tuple(float(v) for v in se2_goal)

    def get(self, key: tuple) -> SeatingCheck | None:
        with self._lock:
            answer = self._answers.get(key)
            if answer is not None:
                self._answers.move_to_end(key)
                self.hits += 1
            return answer

    def put(self, key: tuple, answer: SeatingCheck) -> None:
        with self._lock:
            self._answers[key] = answer
            self._answers.move_to_end(key)
            while len(self._answers) > self._max_size:
                self._answers.popitem(last=False)


PREPLANS = PreplanMemo()
"""The memo :func:`default_seating_validator`'s pre-plan answers from."""


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
        key = PREPLANS.key(chair_mesh, sitting_pose, se2_goal)
        answer = PREPLANS.get(key)
        if answer is not None:
            return answer
        try:
            answer = SeatingCheck(raise_at=preplan(chair_mesh, sitting_pose, se2_goal))
        except infeasible as error:
            constraint = getattr(error, "constraint", "")
            answer = SeatingCheck(
                f"seating pre-plan infeasible: {error}",
                bear_placement=constraint == "bear placement",
                too_close=constraint == stance,
            )
        PREPLANS.put(key, answer)
        return answer

    return wholebody_validator


def stepped_back(se2_goal: SE2Pose, distance_m: float) -> SE2Pose:
    """s_goal moved ``distance_m`` back along the sitting ray (the NAO faces the chair)."""
    return se2_goal.stepped_back(distance_m)


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
            when available, else the reach model.
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

    checker = NaoCollisionChecker(arena, chair_solid_boxes(chair_mesh))
    validator = seating_validator or default_seating_validator()
    choice = choose_stance(chair_mesh, sitting_pose, checker, validator, scene=True)
    if choice.se2_goal is None:
        reason = choice.reason
        if choice.check.reason and not reason.startswith("seating pre-plan"):
            reason = f"seating pre-plan infeasible: {reason}"
        return AccessibilityResult(False, None, choice.sitting_pose, (), reason)
    se2_goal, sitting_pose = choice.se2_goal, choice.sitting_pose

    # The walk ends where the walking NAO's ellipsoid is clear; from there it steps
    # straight in (raising the bear first when the pre-plan says so).
    approach = choice.approach
    raise_at = choice.check.raise_at
    if raise_at is not None and approach is not None:
        raise_at = _farther(se2_goal, raise_at, approach)
    path_goal = raise_at or approach or se2_goal
    if path_goal != se2_goal:
        blocked = _step_in_blocked_by(checker, path_goal, se2_goal, chair=approach is None)
        if blocked:
            reason = f"the step in to s_goal touches the {blocked}"
            return AccessibilityResult(False, se2_goal, sitting_pose, (), reason)

    planned = plan_se2_path(checker, humanoid_pose, path_goal, seed=seed, check_budget=check_budget)
    return AccessibilityResult(
        not planned.reason,
        se2_goal,
        sitting_pose,
        planned.waypoints,
        planned.reason,
        planned.seconds,
        raise_at=raise_at,
        step_in_from=approach if raise_at is None else None,
    )


def _farther(se2_goal: SE2Pose, a: SE2Pose, b: SE2Pose) -> SE2Pose:
    """Of two poses back along the ray from s_goal, the one farther from it."""
    return a if se2_goal.distance_to(a) >= se2_goal.distance_to(b) else b


def _step_in_blocked_by(
    checker: NaoCollisionChecker, start: SE2Pose, goal: SE2Pose, *, chair: bool
) -> str:
    """What the walking NAO touches on the straight step from ``start`` to ``goal`` ("" if
    nothing); with ``chair`` False only walls and obstacles count (the step ends inside
    the ellipsoid's clearance of the chair, which the whole-body pre-plan checked)."""
    steps = max(2, math.ceil(start.distance_to(goal) / CHECK_RESOLUTION_M) + 1)
    for t in np.linspace(0.0, 1.0, steps):
        pose = SE2Pose(
            start.x + t * (goal.x - start.x), start.y + t * (goal.y - start.y), goal.theta
        )
        if checker.collides_with_walls(pose):
            return "wall"
        if checker.collides_with_obstacles(pose):
            return "obstacle"
        if chair and checker.collides_with_chair(pose):
            return "chair"
    return ""
