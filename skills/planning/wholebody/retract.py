"""The retract motion, with the bear released: the legs hold still while the arms
withdraw the hands back (toward the NAO) and a little up beside the bear, then the body
stands up to :data:`.postures.REST_POSTURE`, clear of the bear where it was let go."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
from scipy.optimize import least_squares

from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.infeasible import InfeasibleSeating
from bearchair.skills.planning.wholebody.optimisation import SeatingProblems, released_bear
from bearchair.skills.planning.wholebody.posture_check import (
    CHECK_TOLERANCE,
    exact_posture_violation,
)
from bearchair.skills.planning.wholebody.postures import REST_POSTURE
from bearchair.skills.planning.wholebody.trajectory import solve_trajectory

RETRACT_LEAD_IN_S = 0.3
"""Time of the retract's first knot (q_goal, where the robot already is)."""
RETRACT_OFFSETS_M: tuple[tuple[float, float], ...] = ((0.05, 0.03), (0.03, 0.05), (0.0, 0.06))
"""After release the hands first withdraw (back toward the NAO, up) from where they let
go, beside the bear: the first of these whose posture keeps clear of the chair. Pulling
straight back can swing an elbow into a seat's front edge."""


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


def plan_retract(
    problems: SeatingProblems, profile: ChairProfile, q_goal: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(times, knots) of the retract from q_goal, where the bear is let go.

    Raises:
        InfeasibleSeating: no withdrawn-hands posture leads to a feasible retract (the
            first failure).
    """
    released = released_bear(problems.geometry(q_goal))
    # Each withdrawn-hands posture clear of the chair in turn: from one the stand-up may
    # need the centre of mass where the released bear leaves the torso no room.
    first_failure: InfeasibleSeating | None = None
    for q_folded in _clear_withdrawn_postures(problems, profile, q_goal, released):
        try:
            return _retract(problems, profile, q_goal, q_folded, released)
        except InfeasibleSeating as error:
            first_failure = first_failure or error
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
