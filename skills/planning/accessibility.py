"""Where the NAO should stand to seat the bear, and an SE(2) path to get there.

The paper, section "System Pipeline": the SE(2) goal s_goal faces opposite the sitting
direction γ on the horizontal ray from p along γ, clear of the chair; p moves along the
ray toward the NAO as far as its workspace needs; the seat motion is pre-planned at
s_goal to check it is valid; then OMPL's RRTConnect plans an SE(2) path from the
humanoid to s_goal within the arena, checked with FCL (:mod:`bearchair.skills.planning.collision`).

Stance and sitting point are chosen together by :mod:`bearchair.skills.planning.stance` (reach
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

import math
import time
from typing import NamedTuple, cast

import numpy as np
import trimesh
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from bearchair.core.arena import Arena
from bearchair.core.errors import SkillError
from bearchair.core.geometry import SittingPose, wrap_angle
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.collision import NaoCollisionChecker, chair_solid_boxes
from bearchair.skills.planning.preplan import SeatingValidator, wholebody_validator
from bearchair.skills.planning.stance import StanceChoice, choose_stance
from bearchair.skills.results import AccessibilityResult

__all__ = [
    "AccessibilityError",
    "check_accessibility",
    "plan_se2_path",
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
OMPL_LOG_LEVEL = ou.LogLevel.LOG_NONE
"""OMPL's (process-wide) log level, set once when this module is imported: this build
defaults to DEBUG chatter on stderr, and reports every reseed after its first RNG as an
error (:func:`_seed_ompl` reseeds on every plan). A failed search comes back as
:class:`PlannedPath`'s reason."""

ou.setLogLevel(OMPL_LOG_LEVEL)


class AccessibilityError(SkillError, ValueError):
    """Bad input to the accessibility check (not an inaccessible chair)."""


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
    # OMPL complains (harmlessly, see OMPL_LOG_LEVEL) when reseeded after its first RNG was
    # made; the reseed still makes every later planner's sampler sequence a function of
    # ``seed``.
    ou.RNG.setSeed(int(seed) % (2**31 - 1) + 1)


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

    return _run_rrt_connect(
        checker, start, goal, seed=seed, check_budget=check_budget, time_budget_s=time_budget_s
    )


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
        se2 = cast(ob.SE2StateType, state)  # the states of an SE2StateSpace
        return checker.is_free(se2.getX(), se2.getY(), se2.getYaw())

    setup.setStateValidityChecker(is_valid)
    information = setup.getSpaceInformation()
    information.setStateValidityCheckingResolution(CHECK_RESOLUTION_M / space.getMaximumExtent())
    start_state = cast(ob.SE2StateType, space.allocState())
    goal_state = cast(ob.SE2StateType, space.allocState())
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
        for s in (cast(ob.SE2StateType, path.getState(i)) for i in range(path.getStateCount()))
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
            (:func:`bearchair.skills.planning.preplan.wholebody_validator`).
        check_budget: RRTConnect gives up after this many state validity checks.

    Returns:
        accessible with the path, or not with the reason; ``seconds`` is the OMPL time.

    Raises:
        AccessibilityError: an empty chair mesh or a non-finite pose.
    """
    _check_inputs(chair_mesh, sitting_pose, humanoid_pose)
    checker = NaoCollisionChecker(arena, chair_solid_boxes(chair_mesh))
    validator = seating_validator or wholebody_validator
    choice = choose_stance(chair_mesh, sitting_pose, checker, validator, scene=True)
    if choice.se2_goal is None:
        return AccessibilityResult(False, None, choice.sitting_pose, (), _refusal(choice))
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


def _check_inputs(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, humanoid_pose: SE2Pose
) -> None:
    """Raises :class:`AccessibilityError` on an empty chair mesh or a non-finite pose."""
    if chair_mesh is None or len(chair_mesh.faces) == 0:
        raise AccessibilityError("the chair mesh has no triangles")
    if not (np.all(np.isfinite(sitting_pose.position)) and math.isfinite(sitting_pose.yaw)):
        raise AccessibilityError("the sitting pose is not finite")
    if not all(math.isfinite(v) for v in humanoid_pose):
        raise AccessibilityError("the humanoid's pose is not finite")


def _refusal(choice: StanceChoice) -> str:
    """Why no stance works, naming the pre-plan when it refused."""
    reason = choice.reason
    if choice.check.reason and not reason.startswith("seating pre-plan"):
        reason = f"seating pre-plan infeasible: {reason}"
    return reason


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
