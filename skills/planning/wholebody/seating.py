"""Seating the bear: plan the NAO's whole-body motion, play it, release, stand up.

The plan (the paper, "Motion Planning"):

1. g is expressed in the NAO frame (the NAO faces opposite the sitting direction, so g
   lies ahead of it at a forward distance d and a height h); the chair's cross-section
   becomes two blocks (:mod:`.chair_profile`).
2. q_goal minimises w1·d_COM + w2·torso_pitch² subject to the joint limits, the bear's
   base at g, the bear upright, the centre of mass over the feet and no collision
   (:mod:`.optimisation`).
3. The trajectory from :data:`STANDING_POSTURE` to q_goal minimises
   Σ ½‖q(k) − q_goal‖² under joint velocity limits, with the same stability and
   collision constraints at every knot. Knots after the goal is reached are dropped.
   Over a seat higher than the carried bear, the NAO first raises the bear
   (:func:`plan_raise`, a step back from s_goal) and steps in; the trajectory then
   starts from :data:`RAISED_POSTURE` (:func:`preplan_approach` decides).
4. The retract motion, with the bear released: the legs hold still while the arms
   withdraw the hands back (toward the NAO) and a little up beside the bear,
   then the body stands up, clear of the bear where it was let go, to
   :data:`REST_POSTURE`; both are solved by the same trajectory problem.

Every solution is re-checked numerically against the exact (non-smoothed) constraints
before it is returned.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from typing import NamedTuple

import numpy as np
import trimesh
from scipy.optimize import least_squares

from core.geometry import SittingPose, transform_points, wrap_angle
from core.nao_carrying import BEAR_SEAT_CLEARANCE_M
from core.se2 import SE2Pose
from hardware.interfaces import Humanoid
from skills.planning.seat import slide_on_seat
from skills.planning.wholebody.chair_profile import (
    ChairProfile,
    ChairProfileError,
    fit_chair_profile,
)
from skills.planning.wholebody.nao_model import DRIVEN_JOINTS, to_joint_positions
from skills.planning.wholebody.optimisation import (
    ARM_POINTS,
    BEAR_TILT_GOAL_RAD,
    BEAR_TILT_MOTION_RAD,
    COARSE_KNOTS,
    LEG_TORSO_HEAD_POINTS,
    NO_RELEASED_BEAR,
    PLACEMENT_TOLERANCE_M,
    SeatingProblems,
    released_bear,
    seating_problems,
)
from skills.results import SeatingPlan

STANDING_POSTURE = np.array([0.0, 0.0, 0.0, 0.9208, 1.3629])
"""q = (ankle, knee, hip, shoulder, elbow) that starts the seating motion: standing
straight, the palms where the carrying posture (:data:`core.nao_carrying.CARRYING_POSTURE_RAD`)
has them (within 3 mm and 2 deg, checked by a test), so the bear barely moves when the
arms switch to the planar posture during the lead-in."""
RAISED_POSTURE = np.array([0.0, 0.0, 0.0, 0.0, 0.41])
"""q with the bear raised for stepping up to a high seat: standing straight, the arms
forward, the bear's seat point 0.40 m high and 0.20 m ahead (0.32 m and 0.16 m in
:data:`STANDING_POSTURE`), tilted 0.2 deg. Over a seat higher than the carried bear
(0.32 m) the NAO stops where the carried bear is clear, raises it, and steps in:
standing there with the bear low, it could not reach the seat."""
RAISE_STEP_M = 0.02
"""The raising pose steps back from s_goal in these steps until the raise is clear..."""
MAX_RAISE_BACKOFF_M = 0.2
"""... up to this far (metres)."""
REST_POSTURE = np.array([0.0, 0.0, 0.0, 1.4, 0.4])
"""q after the retract: standing straight, arms down along the body."""
LEAD_IN_S = 1.0
"""Time of the seating motion's first knot: the robot moves from whatever posture it
holds (the carrying posture) to it."""
RETRACT_LEAD_IN_S = 0.3
"""Time of the retract's first knot (q_goal, where the robot already is)."""

PLANNING_VELOCITY_RADPS = 0.3
"""Joint speed limit of the quasi-static motion (well under the URDF's 6-8 rad/s)."""
RETRACT_OFFSETS_M: tuple[tuple[float, float], ...] = ((0.05, 0.03), (0.03, 0.05), (0.0, 0.06))
"""After release the hands first withdraw (back toward the NAO, up) from where they let
go, beside the bear: the first of these whose posture keeps clear of the chair. Pulling
straight back can swing an elbow into a seat's front edge."""
LATERAL_TOLERANCE_M = 0.05
"""How far g may lie beside the NAO's sagittal plane (the planar motion cannot reach it)."""
FACING_TOLERANCE_RAD = math.radians(20.0)

"""How far the NAO's heading may differ from the opposite of the sitting direction."""
TOE_POINT_XZ = np.array([0.10, 0.02])
"""The front of the feet in the NAO frame (metres), checked against the chair."""
CHECK_TOLERANCE = 1e-4
DIAGNOSIS_TOLERANCE = 0.005

_ACCEPTED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")

_GOAL_GUESSES = (
    np.array([0.2, 0.0, -0.8, -0.4, 0.4]),
    np.array([-0.3, 0.9, -1.0, 0.3, 0.5]),
    np.array([-0.6, 1.4, -1.2, 0.0, 0.8]),
)


STANCE = "stance"
"""The constraint group of an s_goal too close to the chair (feet, or the carried bear,
in it): standing farther back may help."""


class InfeasibleSeating(ValueError):
    """No seating motion satisfies the constraints; the message names the violated one.

    Attributes:
        constraint: the violated constraint group (for example ``"bear placement"``).
        carried_bear: a :data:`STANCE` failure caused by the carried bear (not the feet):
            raising the bear before stepping in may help.
    """

    def __init__(self, constraint: str, detail: str, *, carried_bear: bool = False) -> None:
        super().__init__(f"{constraint}: {detail}" if detail else constraint)
        self.constraint = constraint
        self.carried_bear = carried_bear


class SeatingCancelled(RuntimeError):
    """The seating motion was cancelled before or while it played."""


class SeatingScene(NamedTuple):
    """The seating problem's numbers in the NAO frame (metres, radians).

    Attributes:
        g_xz: the bear's target base: forward distance d of the sitting pose, height h
            ``BEAR_SEAT_CLEARANCE_M`` over the seat's top under it.
        lateral_m: g's offset beside the sagittal plane (ignored by the planar motion).
        facing_error_rad: the NAO's heading minus the opposite of the sitting direction.
        profile: the chair's two-block cross-section.
    """

    g_xz: np.ndarray
    lateral_m: float
    facing_error_rad: float
    profile: ChairProfile


def seating_scene(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, humanoid_pose: SE2Pose
) -> SeatingScene:
    """Expresses g and the chair in the NAO frame at ``humanoid_pose``.

    Raises:
        InfeasibleSeating: g is beside the sagittal plane, the NAO does not face the
            chair, or the chair has no seat under g.
    """
    T_nao_world = np.linalg.inv(humanoid_pose.as_transform())
    g_nao = transform_points(T_nao_world, np.asarray(sitting_pose.position, float)[None, :])[0]
    facing_error = wrap_angle(humanoid_pose.theta - (sitting_pose.yaw + math.pi))
    if abs(facing_error) > FACING_TOLERANCE_RAD:
        raise InfeasibleSeating(
            "sitting direction",
            f"the NAO faces {math.degrees(facing_error):+.0f} deg off the opposite of the "
            f"sitting direction (tolerance {math.degrees(FACING_TOLERANCE_RAD):.0f} deg)",
        )
    if abs(g_nao[1]) > LATERAL_TOLERANCE_M:
        raise InfeasibleSeating(
            "bear placement",
            f"the sitting pose is {g_nao[1]:+.2f} m beside the NAO's sagittal plane "
            f"(tolerance {LATERAL_TOLERANCE_M:.2f} m)",
        )
    try:
        profile = fit_chair_profile(chair_mesh, T_nao_world, g_nao)
    except ChairProfileError as error:
        raise InfeasibleSeating("chair", str(error)) from error
    g_xz = np.array([g_nao[0], profile.seat_top_z + BEAR_SEAT_CLEARANCE_M])
    return SeatingScene(g_xz, float(g_nao[1]), facing_error, profile)


def _worst_violation(
    problems: SeatingProblems, values: np.ndarray, lower: np.ndarray, upper: np.ndarray
) -> tuple[float, str, str]:
    """(violation in metres or radians, group, label) of the most violated row."""
    values = values.reshape(-1, len(problems.rows))
    lower = lower.reshape(-1, len(problems.rows))
    upper = upper.reshape(-1, len(problems.rows))
    violation = np.maximum(lower - values, values - upper)
    knot, row = np.unravel_index(int(np.argmax(violation)), violation.shape)
    entry = problems.rows[row]
    label = entry.label if violation.shape[0] == 1 else f"{entry.label} at knot {knot}"
    return float(violation[knot, row]), entry.group, label


def _posture_values(
    problems: SeatingProblems,
    q: np.ndarray,
    profile: ChairProfile,
    bear_held: bool,
    released: np.ndarray = NO_RELEASED_BEAR,
) -> np.ndarray:
    return np.asarray(
        problems.posture_constraints(q, profile.as_vector(), float(bear_held), released)
    ).ravel()


def exact_posture_violation(
    problems: SeatingProblems,
    q: np.ndarray,
    profile: ChairProfile,
    *,
    g_xz: np.ndarray | None,
    tilt_rad: float,
    bear_held: bool = True,
    released: np.ndarray = NO_RELEASED_BEAR,
) -> tuple[float, str, str]:
    """Worst violation of a posture's constraints with the exact block clearance.

    The optimisation's smoothed max over-estimates the clearance by at most ln(2)/κ;
    here the clearances come from :meth:`ChairProfile.clearance` instead. ``released``:
    where a let-go bear rests (:func:`.optimisation.released_bear`), with ``bear_held``
    False.
    """
    lower, upper = problems.posture_bounds(g_xz=g_xz, tilt_rad=tilt_rad)
    values = _posture_values(problems, q, profile, bear_held, released)
    geometry = problems.geometry(q, bear_held)
    for i, row in enumerate(problems.rows):
        if row.group != "chair collision":
            continue
        if row.label.startswith("NAO "):
            label = row.label[4:]
            point = geometry.body_points[label]
            radius = _radius_of(label)
            values[i] = profile.clearance(point[None, :])[0] - radius
        elif bear_held:
            values[i] = profile.clearance(geometry.bear_points[row.label][None, :])[0]
    return _worst_violation(problems, values, lower, upper)


def _radius_of(label: str) -> float:
    for _, _, radius, name in LEG_TORSO_HEAD_POINTS + ARM_POINTS:
        if name == label:
            return radius
    raise KeyError(label)


def goal_posture_candidates(problems: SeatingProblems, scene: SeatingScene) -> Iterator[np.ndarray]:
    """Feasible goal postures (eq. 12-16), one per initial guess that reaches one.

    The guesses are fixed postures, so a goal depends on the scene alone: the accessibility
    check's pre-plan and SeatBear's plan from where the walk stopped see the same optima
    (a warm start from the last accepted goal made SeatBear's plan depend on which pre-plans
    ran before it: a low carry the pre-plan accepted from one failed from the other).
    Different guesses may end in different local optima, so a caller whose trajectory
    fails from one goal can try the next.

    Raises:
        InfeasibleSeating: when no guess gives a feasible goal (naming the violated
            constraint); raised on the first ``next`` that finds none.
    """
    chair = scene.profile.as_vector()
    lower, upper = problems.posture_bounds(g_xz=scene.g_xz, tilt_rad=BEAR_TILT_GOAL_RAD)
    guesses = list(_GOAL_GUESSES)
    best: tuple[float, str, str] | None = None
    found: list[np.ndarray] = []
    for guess in guesses:
        with problems.lock:
            result = problems.goal_solver(
                x0=guess,
                p=np.r_[scene.g_xz, chair, 0.0],
                lbx=problems.nao.q_lower,
                ubx=problems.nao.q_upper,
                lbg=lower,
                ubg=upper,
            )
        q = np.asarray(result["x"]).ravel()
        violation = exact_posture_violation(
            problems, q, scene.profile, g_xz=scene.g_xz, tilt_rad=BEAR_TILT_GOAL_RAD
        )
        if violation[0] <= CHECK_TOLERANCE:
            if any(np.max(np.abs(q - other)) < 1e-3 for other in found):
                continue  # the same optimum again
            found.append(q)
            yield q
            continue
        if best is None or violation[0] < best[0]:
            best = violation
    if found:
        return
    # Infeasible: is g out of reach? Minimise the placement error under the others.
    free_lower, free_upper = problems.posture_bounds(g_xz=None, tilt_rad=BEAR_TILT_GOAL_RAD)
    with problems.lock:
        result = problems.goal_solver(
            x0=guesses[0],
            p=np.r_[scene.g_xz, chair, 1.0],
            lbx=problems.nao.q_lower,
            ubx=problems.nao.q_upper,
            lbg=free_lower,
            ubg=free_upper,
        )
    q = np.asarray(result["x"]).ravel()
    others = exact_posture_violation(
        problems, q, scene.profile, g_xz=None, tilt_rad=BEAR_TILT_GOAL_RAD
    )
    reached = problems.geometry(q).bear_base
    # The diagnosis needs no precision: a placement error far beyond what the others'
    # residual could explain names the placement.
    if (
        others[0] <= DIAGNOSIS_TOLERANCE
        and np.max(np.abs(reached - scene.g_xz)) > PLACEMENT_TOLERANCE_M
    ):
        raise InfeasibleSeating(
            "bear placement",
            f"out of reach: {scene.g_xz[0]:.2f} m forward, {scene.g_xz[1]:.2f} m high "
            f"(closest reachable {reached[0]:.2f} m forward, {reached[1]:.2f} m high)",
        )
    worst = others if others[0] > CHECK_TOLERANCE else best
    assert worst is not None
    raise InfeasibleSeating(worst[1], f"{worst[2]} violated by {worst[0]:.3f} in the goal posture")


def solve_trajectory(
    problems: SeatingProblems,
    profile: ChairProfile,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    *,
    bear_held: bool,
    released: np.ndarray = NO_RELEASED_BEAR,
    freeze_legs: bool = False,
    velocity_radps: float = PLANNING_VELOCITY_RADPS,
    phase: str = "trajectory",
) -> tuple[np.ndarray, np.ndarray]:
    """The knots from ``q_start`` to ``q_goal`` (eq. 8-11) and their times.

    First with :data:`.optimisation.COARSE_KNOTS` knots, accepted when the exact
    constraints hold at every knot and halfway between; else with the problems' full
    knot count, checked at its knots. With ``bear_held`` False the body keeps clear of
    the bear at ``released`` (:func:`.optimisation.released_bear`).

    Returns:
        (times_s (K,), postures (K, 5)), trailing knots at q_goal dropped.

    Raises:
        InfeasibleSeating: naming the violated constraint and knot.
    """
    tilt_rad = BEAR_TILT_MOTION_RAD if bear_held else math.pi
    start_violation = exact_posture_violation(
        problems,
        q_start,
        profile,
        g_xz=None,
        tilt_rad=BEAR_TILT_MOTION_RAD,
        bear_held=bear_held,
        released=released,
    )
    if start_violation[0] > CHECK_TOLERANCE:
        raise InfeasibleSeating(
            start_violation[1],
            f"{start_violation[2]} violated by {start_violation[0]:.3f} in the start posture "
            f"of the {phase} (the NAO stands too close to the chair?)",
        )
    problem = _TrajectoryProblem(
        problems, profile, q_start, q_goal, bear_held, released, freeze_legs, tilt_rad
    )
    try:
        # Coarse knots first, checked halfway between knots too (what the robot passes
        # through); the fine problem where that does not hold.
        times, knots, worst = problem.solve(COARSE_KNOTS, velocity_radps, between=True)
        if worst[0] <= CHECK_TOLERANCE:
            return times, knots
    except _NoTrajectory:
        pass
    try:
        times, knots, worst = problem.solve(problems.n_knots, velocity_radps, between=False)
    except _NoTrajectory:
        raise InfeasibleSeating("trajectory", f"no finite solution of the {phase}") from None
    if worst[0] > CHECK_TOLERANCE:
        raise InfeasibleSeating(worst[1], f"{worst[2]} violated by {worst[0]:.3f} in the {phase}")
    return times, knots


class _NoTrajectory(Exception):
    """The solver's result is unusable (kept apart from a constraint violation)."""


class _TrajectoryProblem(NamedTuple):
    problems: SeatingProblems
    profile: ChairProfile
    q_start: np.ndarray
    q_goal: np.ndarray
    bear_held: bool
    released: np.ndarray
    freeze_legs: bool
    tilt_rad: float

    def solve(
        self, n: int, velocity_radps: float, *, between: bool
    ) -> tuple[np.ndarray, np.ndarray, tuple[float, str, str]]:
        """(times, knots, worst exact violation) of the n-knot problem; ``between`` also
        checks the postures halfway between consecutive knots."""
        problems, q_start, q_goal = self.problems, self.q_start, self.q_goal
        # The knot spacing that lets the slowest joint arrive with a third of the knots
        # to spare; the cost then spends them at the goal and they are dropped.
        travel = float(np.max(np.abs(q_goal - q_start)))
        dt = max(travel / velocity_radps / (n * 2 / 3), 0.05)
        dq = velocity_radps * dt
        lower_row, upper_row = problems.posture_bounds(g_xz=None, tilt_rad=self.tilt_rad)
        lbx = np.tile(problems.nao.q_lower, n)
        ubx = np.tile(problems.nao.q_upper, n)
        if self.freeze_legs:
            for k in range(n):
                lbx[5 * k : 5 * k + 3] = ubx[5 * k : 5 * k + 3] = q_start[:3]
        lbx[:5] = ubx[:5] = q_start
        lbx[-5:] = ubx[-5:] = q_goal
        lbg = np.r_[np.full(5 * (n - 1), -dq), np.tile(lower_row, n - 2)]
        ubg = np.r_[np.full(5 * (n - 1), dq), np.tile(upper_row, n - 2)]
        x0 = np.linspace(q_start, q_goal, n).ravel()
        parameters = np.r_[
            q_goal, self.profile.as_vector(), float(self.bear_held), self.released, np.ones(5)
        ]
        solver = problems.trajectory_solver(n)
        with problems.lock:
            result = solver(x0=x0, p=parameters, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        knots = np.asarray(result["x"]).reshape(n, 5)
        if not np.all(np.isfinite(knots)):
            raise _NoTrajectory
        checked = [(f"knot {k}", knots[k]) for k in range(1, n - 1)]
        if between:
            checked += [
                (f"between knots {k} and {k + 1}", (knots[k] + knots[k + 1]) / 2.0)
                for k in range(n - 1)
            ]
        worst = (0.0, "", "")
        for where, q in checked:
            violation = exact_posture_violation(
                problems,
                q,
                self.profile,
                g_xz=None,
                tilt_rad=self.tilt_rad,
                bear_held=self.bear_held,
                released=self.released,
            )
            if violation[0] > worst[0]:
                worst = (violation[0], violation[1], f"{violation[2]} at {where}")
        steps = np.max(np.abs(np.diff(knots, axis=0)))
        if steps > dq + CHECK_TOLERANCE:
            worst = max(worst, (steps - dq, "joint velocity", "a knot step"))
        arrived = np.flatnonzero(np.max(np.abs(knots - q_goal), axis=1) <= 1e-3)
        last = int(arrived[0]) if len(arrived) else n - 1
        knots = knots[: last + 1]
        knots[-1] = q_goal
        return np.arange(len(knots)) * dt, knots, worst


def withdrawn_hands_posture(
    problems: SeatingProblems,
    q_goal: np.ndarray,
    back_m: float = RETRACT_OFFSETS_M[0][0],
    up_m: float = RETRACT_OFFSETS_M[0][1],
) -> np.ndarray:
    """q_goal with the arms moved so the hands withdraw back and up from the bear.

    The legs keep their goal angles; shoulder and elbow are found by least squares on
    the hands' (x, z) target, within their joint limits.
    """
    nao = problems.nao

    def hand(q: np.ndarray) -> np.ndarray:
        return nao.numeric_frames(q)["l_gripper"][[0, 2], 3]

    target = hand(q_goal) + np.array([-back_m, up_m])

    def residual(arms: np.ndarray) -> np.ndarray:
        return hand(np.r_[q_goal[:3], arms]) - target

    lower, upper = nao.q_lower[3:], nao.q_upper[3:]
    start = np.clip(q_goal[3:], lower + 1e-6, upper - 1e-6)
    fit = least_squares(residual, start, bounds=(lower, upper))
    return np.r_[q_goal[:3], fit.x]


def plan_seating(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    *,
    raised: bool = False,
) -> SeatingPlan:
    """The whole-body motion that seats the bear at g from the NAO's current pose.

    Args:
        chair_mesh: the chair in the world frame (z up, metres).
        sitting_pose: the imagined sitting pose g (world frame).
        humanoid_pose: the NAO's planar pose (the point on the floor between its feet).
        raised: the NAO holds the bear in :data:`RAISED_POSTURE` (it stepped in with it
            raised, see :func:`plan_raise`), not in :data:`STANDING_POSTURE`.

    Returns:
        The plan: qibullet joint names (both sides), knot times, joint angles (the last
        row is q_goal), the retract motion and the solve times.

    Raises:
        InfeasibleSeating: naming the violated constraint.
    """
    problems = seating_problems()
    scene = seating_scene(chair_mesh, sitting_pose, humanoid_pose)
    toe_clearance = scene.profile.clearance(TOE_POINT_XZ[None, :])[0]
    if toe_clearance < 0.0:
        raise InfeasibleSeating(
            STANCE, f"the NAO's feet are {-toe_clearance:.2f} m under the chair"
        )
    # Standing there with the bear held in front must be clear of the chair too: a seat
    # higher than the carried bear reaches it before the NAO's ellipsoid does.
    start_posture = RAISED_POSTURE if raised else STANDING_POSTURE
    standing = exact_posture_violation(
        problems,
        start_posture,
        scene.profile,
        g_xz=None,
        tilt_rad=BEAR_TILT_MOTION_RAD,
        bear_held=True,
    )
    too_close = None
    if standing[0] > CHECK_TOLERANCE and standing[1] == "chair collision":
        too_close = InfeasibleSeating(
            STANCE,
            f"{standing[2]} {standing[0]:.3f} m inside the chair in the "
            f"{'raised' if raised else 'standing'} posture (the NAO stands too close)",
            carried_bear=standing[2].startswith("bear"),
        )
    # A goal from which the trajectory or the retract is infeasible may have a sibling
    # (another local optimum) from which both are feasible: try each in turn.
    goal_s = trajectory_s = retract_s = 0.0
    failure: InfeasibleSeating | None = None
    candidates = goal_posture_candidates(problems, scene)
    while True:
        started = time.perf_counter()
        try:
            q_goal = next(candidates)
        except StopIteration:
            assert failure is not None
            raise failure from None
        goal_s += time.perf_counter() - started
        if too_close is not None:
            # Only now: an unreachable g is the first thing to report (no stance helps).
            raise too_close
        try:
            motion = _motion_from_goal(problems, scene.profile, q_goal, start_posture)
        except InfeasibleSeating as error:
            failure = error
            continue
        break
    times, knots, retract_times, retract_knots, trajectory_s, retract_s = motion
    return SeatingPlan(
        joint_names=DRIVEN_JOINTS,
        times_s=LEAD_IN_S + times,
        positions_rad=to_joint_positions(knots),
        retract_times_s=RETRACT_LEAD_IN_S + retract_times,
        retract_positions_rad=to_joint_positions(retract_knots),
        seconds={"goal": goal_s, "trajectory": trajectory_s, "retract": retract_s},
    )


REACHED_POSE_SLIDES_M = (0.01, 0.02, 0.03)
"""How far p may slide toward the NAO when the bear is a little too far (``_TOO_FAR``) from
where it stopped."""


_TOO_FAR = ("bear placement", "support polygon")
"""Constraints a bear placed nearer the NAO may meet."""


def plan_seating_where_standing(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    *,
    raised: bool = False,
) -> SeatingPlan:
    """:func:`plan_seating` from where the NAO stopped, sliding p closer when needed.

    The walk stops within 5 mm of s_goal, and the stance search accepts a pre-plan at
    s_goal with less reach to spare than that (it goes to the reach model's limit). Then
    p slides toward the NAO along the seat, up to 3 cm, over supported seat only
    (:func:`skills.planning.seat.slide_on_seat`, which keeps it off the seat's edge):
    when the bear is out of reach, or the NAO would lean its centre of mass off its feet
    to put it there (both say the bear is a little too far).

    Raises:
        InfeasibleSeating: the first failure, when no slide helps.
    """
    try:
        return plan_seating(chair_mesh, sitting_pose, humanoid_pose, raised=raised)
    except InfeasibleSeating as error:
        if error.constraint not in _TOO_FAR:
            raise
        first_failure = error
    for slide_m in REACHED_POSE_SLIDES_M:
        moved, moved_m = slide_on_seat(chair_mesh, sitting_pose, slide_m)
        if moved_m < slide_m - 1e-6:
            break  # the seat ends here
        try:
            return plan_seating(chair_mesh, moved, humanoid_pose, raised=raised)
        except InfeasibleSeating as error:
            if error.constraint not in _TOO_FAR:
                raise
    raise first_failure


def _motion_from_goal(
    problems: SeatingProblems, profile: ChairProfile, q_goal: np.ndarray, q_start: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]:
    """(times, knots, retract times, retract knots, trajectory s, retract s) to q_goal.

    Raises:
        InfeasibleSeating: the trajectory or the retract is infeasible.
    """
    started = time.perf_counter()
    times, knots = solve_trajectory(problems, profile, q_start, q_goal, bear_held=True)
    trajectory_s = time.perf_counter() - started
    started = time.perf_counter()
    released = released_bear(problems.geometry(q_goal))
    # Each withdrawn-hands posture clear of the chair in turn: from one the stand-up may
    # need the centre of mass where the released bear leaves the torso no room.
    first_failure: InfeasibleSeating | None = None
    for q_folded in _clear_withdrawn_postures(problems, profile, q_goal, released):
        try:
            retract_times, retract_knots = _retract(problems, profile, q_goal, q_folded, released)
        except InfeasibleSeating as error:
            first_failure = first_failure or error
            continue
        retract_s = time.perf_counter() - started
        return times, knots, retract_times, retract_knots, trajectory_s, retract_s
    assert first_failure is not None
    raise first_failure


def _retract(
    problems: SeatingProblems,
    profile: ChairProfile,
    q_goal: np.ndarray,
    q_folded: np.ndarray,
    released: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """(times, knots) of the retract: the hands back to ``q_folded``, then standing up.

    Raises:
        InfeasibleSeating: either part is infeasible.
    """
    fold_times, fold = solve_trajectory(
        problems,
        profile,
        q_goal,
        q_folded,
        bear_held=False,
        released=released,
        freeze_legs=True,
        phase="retract (hands back)",
    )
    stand_times, stand = solve_trajectory(
        problems,
        profile,
        q_folded,
        REST_POSTURE,
        bear_held=False,
        released=released,
        phase="retract (standing up)",
    )
    return np.r_[fold_times, fold_times[-1] + stand_times[1:]], np.vstack([fold, stand[1:]])


def _clear_withdrawn_postures(
    problems: SeatingProblems, profile: ChairProfile, q_goal: np.ndarray, released: np.ndarray
) -> Iterator[np.ndarray]:
    """The withdrawn-hands postures of ``RETRACT_OFFSETS_M`` clear of the chair, in order
    (only the last one when none is: the retract then reports the violation)."""
    clear = 0
    for back_m, up_m in RETRACT_OFFSETS_M:
        q_folded = withdrawn_hands_posture(problems, q_goal, back_m, up_m)
        violation = exact_posture_violation(
            problems,
            q_folded,
            profile,
            g_xz=None,
            tilt_rad=math.pi,
            bear_held=False,
            released=released,
        )
        if violation[0] <= CHECK_TOLERANCE:
            clear += 1
            yield q_folded
    if not clear:
        yield q_folded


def preplan_seating(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SeatingPlan:
    """The seating plan from a prospective SE(2) goal (the accessibility check's pre-plan).

    Raises:
        InfeasibleSeating: naming the violated constraint.
    """
    return plan_seating(chair_mesh, sitting_pose, se2_goal)


def preplan_approach(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SE2Pose | None:
    """The accessibility check's pre-plan: can the NAO seat the bear from s_goal?

    First as it walks, with the bear carried low; when only the carried bear is in the
    chair there (a seat higher than the bear), with the bear raised instead, which the
    NAO does before it steps in from the raising pose this returns.

    Returns:
        None when the NAO can walk to s_goal with the bear carried low; else the pose,
        on the way back from s_goal, where it raises the bear before stepping in.

    Raises:
        InfeasibleSeating: naming the violated constraint (of the low carry when the
            raised one does not help).
    """
    try:
        plan_seating(chair_mesh, sitting_pose, se2_goal)
        return None
    except InfeasibleSeating as error:
        if not error.carried_bear:
            raise
        low_failure = error
    try:
        plan_seating(chair_mesh, sitting_pose, se2_goal, raised=True)
        return raising_pose(chair_mesh, sitting_pose, se2_goal)
    except InfeasibleSeating:
        raise low_failure from None


def raising_pose(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SE2Pose:
    """Where to raise the bear before stepping in to s_goal: the first pose back along
    the NAO's heading, in :data:`RAISE_STEP_M` steps, from which the raise is clear.

    Raises:
        InfeasibleSeating: none within :data:`MAX_RAISE_BACKOFF_M`.
    """
    failure: InfeasibleSeating | None = None
    for back_m in np.arange(RAISE_STEP_M, MAX_RAISE_BACKOFF_M + 1e-9, RAISE_STEP_M):
        pose = se2_goal.stepped_back(float(back_m))
        try:
            plan_raise(chair_mesh, sitting_pose, pose)
            return pose
        except InfeasibleSeating as error:
            failure = error
    assert failure is not None
    raise InfeasibleSeating(
        STANCE, f"no pose within {MAX_RAISE_BACKOFF_M:.2f} m to raise the bear ({failure})"
    )


def plan_raise(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, humanoid_pose: SE2Pose
) -> tuple[np.ndarray, np.ndarray]:
    """The arms' motion from :data:`STANDING_POSTURE` to :data:`RAISED_POSTURE` where the
    NAO stands, legs still, clear of the chair.

    Returns:
        (knot times from the start of the motion, seconds; (K, J) joint angles of
        :data:`DRIVEN_JOINTS`).

    Raises:
        InfeasibleSeating: the raise touches the chair (or the carried bear is in it).
    """
    problems = seating_problems()
    scene = seating_scene(chair_mesh, sitting_pose, humanoid_pose)
    times, knots = solve_trajectory(
        problems,
        scene.profile,
        STANDING_POSTURE,
        RAISED_POSTURE,
        bear_held=True,
        freeze_legs=True,
        phase="raise",
    )
    return LEAD_IN_S + times, to_joint_positions(knots)


def raise_bear(
    humanoid: Humanoid,
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    *,
    cancel: threading.Event | None = None,
) -> None:
    """Plans (:func:`plan_raise`) and plays the raise where the NAO stands; blocks.

    Raises:
        InfeasibleSeating: the raise is not clear of the chair from here.
        SeatingCancelled: ``cancel`` was set before or during the motion.
    """
    times_s, positions_rad = plan_raise(chair_mesh, sitting_pose, humanoid_pose)
    _play(humanoid, DRIVEN_JOINTS, times_s, positions_rad, cancel, "raising the bear")


def _play(
    humanoid: Humanoid,
    joint_names: tuple[str, ...],
    times_s: np.ndarray,
    positions_rad: np.ndarray,
    cancel: threading.Event | None,
    what: str,
) -> None:
    if cancel is not None and cancel.is_set():
        raise SeatingCancelled(f"{what} cancelled before it started")
    humanoid.play_joint_trajectory(joint_names, list(map(float, times_s)), positions_rad)
    if cancel is not None and cancel.is_set():
        raise SeatingCancelled(f"{what} cancelled while playing")


def execute_seating(
    humanoid: Humanoid, plan: SeatingPlan, *, cancel: threading.Event | None = None
) -> None:
    """Plays the seating motion; blocks until it ends.

    Raises:
        SeatingCancelled: ``cancel`` was set before or during the motion.
    """
    _play(humanoid, plan.joint_names, plan.times_s, plan.positions_rad, cancel, "seating motion")


def release_and_stand(
    humanoid: Humanoid, plan: SeatingPlan, *, cancel: threading.Event | None = None
) -> None:
    """Opens the hands (releasing the bear), folds them back and stands upright.

    Raises:
        SeatingCancelled: ``cancel`` was set before or during the motion.
    """
    if cancel is not None and cancel.is_set():
        raise SeatingCancelled("release cancelled before it started")
    humanoid.set_hands(True)
    _play(
        humanoid,
        plan.joint_names,
        plan.retract_times_s,
        plan.retract_positions_rad,
        cancel,
        "retract motion",
    )
