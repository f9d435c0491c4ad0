"""The seating pre-plan: can the NAO seat the bear at g from a prospective s_goal?

The stance search (:mod:`bearchair.skills.planning.stance`) and the accessibility check
(:mod:`bearchair.skills.planning.accessibility`) ask a seating validator about candidate stances. Two are
here: the whole-body pre-plan (:func:`wholebody_validator`, the default, its answers
memoised in :data:`PREPLANS`) and the faster reach model alone (:func:`reach_validator`).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.memo import BoundedMemo
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.wholebody import STANCE, InfeasibleSeating, preplan_approach
from bearchair.skills.planning.wholebody.chair_profile import ChairProfileError, fit_chair_profile
from bearchair.skills.planning.wholebody.reach_model import reach_model


class SeatingCheck(NamedTuple):
    """A seating validator's verdict.

    Attributes:
        reason: why seating from s_goal is infeasible ("" when feasible).
        bear_placement: the failure is about where the bear goes (reach).
        too_close: the NAO stands too close to the chair (its feet, or the bear it
            carries, in it).
        raise_at: feasible only with the bear raised, which the NAO does here (back
            along the ray from s_goal) before it steps in; None: walk in as it carries.
    """

    reason: str = ""
    bear_placement: bool = False
    too_close: bool = False
    raise_at: SE2Pose | None = None


SeatingValidator = Callable[[trimesh.Trimesh, SittingPose, SE2Pose], SeatingCheck]
"""Checks seating the bear at g from s_goal (the whole-body pre-plan, or the reach model)."""


def reach_validator(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SeatingCheck:
    """A fast validity check without the pre-plan: the reach model
    (:mod:`bearchair.skills.planning.wholebody.reach_model`) places the bear at g from s_goal, the
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


class PreplanMemo(BoundedMemo[tuple, SeatingCheck]):
    """The whole-body pre-plan's answers by chair, sitting pose and stance.

    The pre-plan is a pure function of the three (no warm starts), and the mission asks
    it the same questions twice: the chair-alone reachability check and then the
    accessibility check search the same stances on the same scan, each pre-plan taking
    0.3-0.9 s. The chair is keyed by the bytes of its vertices and faces (a SHA-1, under
    a millisecond on a 20 k-face scan), so a chair turned by the helper is a new chair.
    """

    def __init__(self, max_size: int = PREPLAN_MEMO_SIZE, name: str | None = None) -> None:
        super().__init__(max_size, name)

    @staticmethod
    def key(chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose) -> tuple:
        """The memo key of a question: (chair digest, sitting pose, stance)."""
        digest = hashlib.sha1(np.ascontiguousarray(chair_mesh.vertices).tobytes())
        digest.update(np.ascontiguousarray(chair_mesh.faces).tobytes())
        pose = (*np.asarray(sitting_pose.position, dtype=float).tolist(), float(sitting_pose.yaw))
        return digest.hexdigest(), pose, tuple(float(v) for v in se2_goal)


PREPLANS = PreplanMemo(name="pre-plan memo")
"""The memo :func:`wholebody_validator`'s pre-plan answers from."""


def wholebody_validator(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose, se2_goal: SE2Pose
) -> SeatingCheck:
    """The whole-body pre-plan (:func:`bearchair.skills.planning.wholebody.preplan_approach`) as a
    seating validator, answered from :data:`PREPLANS` when it was asked before."""
    key = PREPLANS.key(chair_mesh, sitting_pose, se2_goal)
    answer = PREPLANS.get(key)
    if answer is not None:
        return answer
    try:
        answer = SeatingCheck(raise_at=preplan_approach(chair_mesh, sitting_pose, se2_goal))
    except InfeasibleSeating as error:
        answer = SeatingCheck(
            f"seating pre-plan infeasible: {error}",
            bear_placement=error.constraint == "bear placement",
            too_close=error.constraint == STANCE,
        )
    PREPLANS.put(key, answer)
    return answer
