"""Raising the bear before stepping in to a seat higher than the carried bear: where
(back along the NAO's heading from s_goal) and the arms' motion there."""

from __future__ import annotations

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.infeasible import STANCE, InfeasibleSeating
from bearchair.skills.planning.wholebody.nao_model import to_joint_positions
from bearchair.skills.planning.wholebody.optimisation import (
    BEAR_CHAIR_MARGIN_M,
    seating_problems,
)
from bearchair.skills.planning.wholebody.postures import RAISED_POSTURES, STANDING_POSTURE
from bearchair.skills.planning.wholebody.scene import seating_scene
from bearchair.skills.planning.wholebody.trajectory import LEAD_IN_S, solve_trajectory

RAISE_STEP_M = 0.02
"""The raising pose steps back from s_goal in these steps until the raise is clear..."""
MAX_RAISE_BACKOFF_M = 0.2
"""... up to this far (metres)."""


def raised_posture(profile: ChairProfile) -> np.ndarray:
    """The lowest of :data:`.postures.RAISED_POSTURES` whose bear's base clears the seat's
    top by ``BEAR_CHAIR_MARGIN_M`` (the highest when none does: the planner then says
    what is in the way)."""
    problems = seating_problems()
    for posture in RAISED_POSTURES:
        if problems.geometry(posture).bear_base[1] >= profile.seat_top_z + BEAR_CHAIR_MARGIN_M:
            return posture
    return RAISED_POSTURES[-1]


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
    """The arms' motion from :data:`STANDING_POSTURE` to the raised posture
    (:func:`raised_posture`) where the NAO stands, legs still, clear of the chair.

    Returns:
        (knot times from the start of the motion, seconds; (K, J) joint angles of
        :data:`.nao_model.DRIVEN_JOINTS`).

    Raises:
        InfeasibleSeating: the raise touches the chair (or the carried bear is in it).
    """
    problems = seating_problems()
    scene = seating_scene(chair_mesh, sitting_pose, humanoid_pose)
    times, knots = solve_trajectory(
        problems,
        scene.profile,
        STANDING_POSTURE,
        raised_posture(scene.profile),
        bear_held=True,
        freeze_legs=True,
        phase="raise",
    )
    return LEAD_IN_S + times, to_joint_positions(knots)
