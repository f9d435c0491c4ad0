"""The seating plan: the NAO's whole-body motion that seats the bear at g, and the retract.

The plan (the paper, "Motion Planning"):

1. g is expressed in the NAO frame (the NAO faces opposite the sitting direction, so g
   lies ahead of it at a forward distance d and a height h); the chair's cross-section
   becomes two blocks (:mod:`.scene`, :mod:`.chair_profile`).
2. q_goal minimises w1·d_COM + w2·torso_pitch² subject to the joint limits, the bear's
   base at g, the bear upright, the centre of mass over the feet and no collision
   (:mod:`.goal`, :mod:`.optimisation`).
3. The trajectory from :data:`.postures.STANDING_POSTURE` to q_goal minimises
   Σ ½‖q(k) − q_goal‖² under joint velocity limits, with the same stability and
   collision constraints at every knot (:mod:`.trajectory`). Knots after the goal is
   reached are dropped. Over a seat higher than the carried bear, the NAO first raises
   the bear (:func:`.raising.plan_raise`, a step back from s_goal) and steps in; the
   trajectory then starts from the raised posture (:func:`.raising.raised_posture`:
   :data:`.postures.RAISED_POSTURE`, or the higher one over a seat its bear does not
   clear; :func:`preplan_approach` decides whether to raise).
4. The retract motion, with the bear released: the legs hold still while the arms
   withdraw the hands back (toward the NAO) and a little up beside the bear,
   then the body stands up, clear of the bear where it was let go, to
   :data:`.postures.REST_POSTURE`; both are solved by the same trajectory problem
   (:mod:`.retract`).

Every solution is re-checked numerically against the exact (non-smoothed) constraints
(:mod:`.posture_check`) before it is returned. :mod:`.execution` plays the plan.
"""

import time

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.seat import slide_on_seat
from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.goal import goal_posture_candidates
from bearchair.skills.planning.wholebody.infeasible import STANCE, InfeasibleSeating
from bearchair.skills.planning.wholebody.nao_model import DRIVEN_JOINTS, to_joint_positions
from bearchair.skills.planning.wholebody.optimisation import (
    BEAR_TILT_MOTION_RAD,
    SeatingProblems,
    seating_problems,
)
from bearchair.skills.planning.wholebody.posture_check import (
    CHECK_TOLERANCE,
    exact_posture_violation,
)
from bearchair.skills.planning.wholebody.postures import STANDING_POSTURE
from bearchair.skills.planning.wholebody.raising import raised_posture, raising_pose
from bearchair.skills.planning.wholebody.retract import RETRACT_LEAD_IN_S, plan_retract
from bearchair.skills.planning.wholebody.scene import SeatingScene, seating_scene
from bearchair.skills.planning.wholebody.trajectory import LEAD_IN_S, solve_trajectory
from bearchair.skills.results import SeatingPlan

TOE_POINT_XZ = np.array([0.10, 0.02])
"""The front of the feet in the NAO frame (metres), checked against the chair."""


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
        raised: the NAO holds the bear in the raised posture
            (:func:`.raising.raised_posture`; it stepped in with it raised, see
            :func:`.raising.plan_raise`), not in :data:`.postures.STANDING_POSTURE`.

    Returns:
        The plan: qibullet joint names (both sides), knot times, joint angles (the last
        row is q_goal), the retract motion and the solve times.

    Raises:
        InfeasibleSeating: naming the violated constraint.
    """
    problems = seating_problems()
    scene = seating_scene(chair_mesh, sitting_pose, humanoid_pose)
    _check_feet_clear(scene.profile)
    start_posture = raised_posture(scene.profile) if raised else STANDING_POSTURE
    too_close = _start_in_chair(problems, scene.profile, start_posture, raised=raised)
    motion, goal_s = _first_feasible_motion(problems, scene, start_posture, too_close)
    times, knots, retract_times, retract_knots, trajectory_s, retract_s = motion
    return SeatingPlan(
        joint_names=DRIVEN_JOINTS,
        times_s=LEAD_IN_S + times,
        positions_rad=to_joint_positions(knots),
        retract_times_s=RETRACT_LEAD_IN_S + retract_times,
        retract_positions_rad=to_joint_positions(retract_knots),
        seconds={"goal": goal_s, "trajectory": trajectory_s, "retract": retract_s},
    )


_Motion = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float]
"""(times, knots, retract times, retract knots, trajectory s, retract s) to a q_goal."""


def _check_feet_clear(profile: ChairProfile) -> None:
    """Raises :class:`InfeasibleSeating` (:data:`STANCE`) when the front of the feet is
    under the chair."""
    toe_clearance = profile.clearance(TOE_POINT_XZ[None, :])[0]
    if toe_clearance < 0.0:
        raise InfeasibleSeating(
            STANCE, f"the NAO's feet are {-toe_clearance:.2f} m under the chair"
        )


def _start_in_chair(
    problems: SeatingProblems, profile: ChairProfile, start_posture: np.ndarray, *, raised: bool
) -> InfeasibleSeating | None:
    """The :data:`STANCE` failure of a start posture (the NAO and the bear it holds, where
    it stands) in the chair, or None when it is clear."""
    # Standing there with the bear held in front must be clear of the chair too: a seat
    # higher than the carried bear reaches it before the NAO's ellipsoid does.
    standing = exact_posture_violation(
        problems,
        start_posture,
        profile,
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
    return too_close


def _first_feasible_motion(
    problems: SeatingProblems,
    scene: SeatingScene,
    start_posture: np.ndarray,
    too_close: InfeasibleSeating | None,
) -> tuple[_Motion, float]:
    """The motion to the first goal candidate from which the trajectory and the retract
    are feasible, and the seconds spent solving for goals.

    Raises:
        InfeasibleSeating: no feasible goal (why); ``too_close`` once a goal is found; or
            the last candidate's motion failure.
    """
    # A goal from which the trajectory or the retract is infeasible may have a sibling
    # (another local optimum) from which both are feasible: try each in turn.
    goal_s = 0.0
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
            return _motion_from_goal(problems, scene.profile, q_goal, start_posture), goal_s
        except InfeasibleSeating as error:
            failure = error


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
    (:func:`bearchair.skills.planning.seat.slide_on_seat`, which keeps it off the seat's edge):
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
) -> _Motion:
    """The seating motion to q_goal and the retract from it (see :data:`_Motion`).

    Raises:
        InfeasibleSeating: the trajectory or the retract is infeasible.
    """
    started = time.perf_counter()
    times, knots = solve_trajectory(problems, profile, q_start, q_goal, bear_held=True)
    trajectory_s = time.perf_counter() - started
    started = time.perf_counter()
    retract_times, retract_knots = plan_retract(problems, profile, q_goal)
    retract_s = time.perf_counter() - started
    return times, knots, retract_times, retract_knots, trajectory_s, retract_s


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
