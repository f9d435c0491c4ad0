"""The trajectory between two postures (eq. 8-11): coarse knots first, checked halfway
between knots too, the fine knots where that does not hold."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.infeasible import InfeasibleSeating
from bearchair.skills.planning.wholebody.optimisation import (
    BEAR_TILT_MOTION_RAD,
    COARSE_KNOTS,
    NO_RELEASED_BEAR,
    SeatingProblems,
)
from bearchair.skills.planning.wholebody.posture_check import (
    CHECK_TOLERANCE,
    exact_posture_violation,
)

LEAD_IN_S = 1.0
"""Time of the seating motion's first knot: the robot moves from whatever posture it
holds (the carrying posture) to it."""

PLANNING_VELOCITY_RADPS = 0.3
"""Joint speed limit of the quasi-static motion (well under the URDF's 6-8 rad/s)."""


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
