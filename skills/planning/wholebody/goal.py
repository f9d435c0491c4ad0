"""The goal posture q_goal (eq. 12-16) and its candidates, one per initial guess."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from bearchair.skills.planning.wholebody.infeasible import InfeasibleSeating
from bearchair.skills.planning.wholebody.optimisation import (
    BEAR_TILT_GOAL_RAD,
    PLACEMENT_TOLERANCE_M,
    SeatingProblems,
)
from bearchair.skills.planning.wholebody.posture_check import (
    CHECK_TOLERANCE,
    exact_posture_violation,
)
from bearchair.skills.planning.wholebody.scene import SeatingScene

DIAGNOSIS_TOLERANCE = 0.005
"""The others' worst violation under which an infeasible goal is blamed on the bear's
placement (metres or radians)."""

_GOAL_GUESSES = (
    np.array([0.2, 0.0, -0.8, -0.4, 0.4]),
    np.array([-0.3, 0.9, -1.0, 0.3, 0.5]),
    np.array([-0.6, 1.4, -1.2, 0.0, 0.8]),
)
"""The goal NLP's initial guesses q (radians), fixed: a goal depends on its scene alone."""


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
    lower, upper = problems.posture_bounds(g_xz=scene.g_xz, tilt_rad=BEAR_TILT_GOAL_RAD)
    best: tuple[float, str, str] | None = None
    found: list[np.ndarray] = []
    for guess in _GOAL_GUESSES:
        q = _solve_goal(problems, scene, guess, lower, upper, diagnose=0.0)
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
    raise _goal_infeasibility(problems, scene, best)


def _solve_goal(
    problems: SeatingProblems,
    scene: SeatingScene,
    guess: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    diagnose: float,
) -> np.ndarray:
    """The goal NLP's solution from ``guess`` within the posture bounds ``lower``,
    ``upper`` (``diagnose`` 1: minimising the placement error instead)."""
    with problems.lock:
        result = problems.goal_solver(
            x0=guess,
            p=np.r_[scene.g_xz, scene.profile.as_vector(), diagnose],
            lbx=problems.nao.q_lower,
            ubx=problems.nao.q_upper,
            lbg=lower,
            ubg=upper,
        )
    return np.asarray(result["x"]).ravel()


def _goal_infeasibility(
    problems: SeatingProblems, scene: SeatingScene, best: tuple[float, str, str] | None
) -> InfeasibleSeating:
    """Why no guess gives a feasible goal: the bear's placement when g is out of reach,
    else the worst violated constraint (``best``: the guesses' least violation)."""
    # Is g out of reach? Minimise the placement error under the others.
    free_lower, free_upper = problems.posture_bounds(g_xz=None, tilt_rad=BEAR_TILT_GOAL_RAD)
    q = _solve_goal(problems, scene, _GOAL_GUESSES[0], free_lower, free_upper, diagnose=1.0)
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
        return InfeasibleSeating(
            "bear placement",
            f"out of reach: {scene.g_xz[0]:.2f} m forward, {scene.g_xz[1]:.2f} m high "
            f"(closest reachable {reached[0]:.2f} m forward, {reached[1]:.2f} m high)",
        )
    worst = others if others[0] > CHECK_TOLERANCE else best
    assert worst is not None
    return InfeasibleSeating(worst[1], f"{worst[2]} violated by {worst[0]:.3f} in the goal posture")
