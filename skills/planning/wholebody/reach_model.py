"""Where the NAO can put the bear: a reach model computed from the whole-body model.

For a seat whose top is at height h and whose front plane (everything at or below the
seat, in the band the NAO's body sweeps) is at x_f ahead of the NAO frame's origin, the
model holds d_max(h, x_f): the farthest forward distance at which some goal posture of
:mod:`.optimisation` puts the bear's base at the release height r(h), with
every posture constraint of the planner (joint limits, bear upright, centre of mass over
the feet, body and bear clear of the seat block, floor) and no backrest:

.. math::

    d_{max}(h, x_f) = \\max_q \\; b_x(q) \\quad \\text{s.t.} \\quad
        b_z(q) = r(h),\\; g(q; h, x_f) \\in [g_{lo}, g_{hi}],

where r(h) is the release height (:mod:`.release_height`: ``BEAR_SEAT_CLEARANCE_M`` over
the seat, higher over a low seat, where the bent-hip postures reach much farther than a
crouch); a seat without one has no cell.

It answers, before any pre-plan, whether a sitting point is reachable from a stance
(``d <= d_max(h, d - f)`` where f is how far the seat's front lies ahead of the sitting
point), and whether a seat is reachable from any stance at all
(:meth:`ReachModel.max_seat_height_m`). Each cell is the best of several initial
guesses of IPOPT and re-checked with the exact (non-smoothed) constraints; a cell with
no feasible posture holds NaN.

The grid is computed once (``python -m bearchair.skills.planning.wholebody.reach_model`` writes
``reach_table.json`` beside this module, about a minute on the 2-core machine) and
shipped; a test recomputes cells and compares. Figures of the shipped table (seat
fronts at least 0.20 m ahead): the NAO places the bear on seats 0.11-0.45 m high (the
highest raised carry over the seat's front limits it to 0.429 m), reaching 0.29-0.32 m
ahead on seats 0.1375-0.40 m high (let go 1 cm over the seat, or bent at the hips 0.1975 m
high over seats 0.1375-0.1875 m) and 0.22 m from the crouch over seats 0.11-0.13 m.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import casadi as ca
import numpy as np

from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.optimisation import (
    BEAR_CHAIR_MARGIN_M,
    BEAR_TILT_GOAL_RAD,
    NO_RELEASED_BEAR,
    SeatingProblems,
    _ipopt_options,
    seating_problems,
)
from bearchair.skills.planning.wholebody.posture_check import (
    CHECK_TOLERANCE,
    exact_posture_violation,
)
from bearchair.skills.planning.wholebody.postures import RAISED_POSTURES
from bearchair.skills.planning.wholebody.release_height import (
    NO_LOW_SEATS,
    ReleaseHeights,
    compute_release_heights,
)

TABLE_PATH = Path(__file__).with_name("reach_table.json")
SEAT_HEIGHTS_M = np.round(np.arange(0.10, 0.501, 0.01), 3)
"""Seat-top heights of the grid, metres."""
SEAT_FRONTS_M = np.round(np.arange(0.10, 0.401, 0.02), 3)
"""Seat front planes of the grid (x in the NAO frame), metres. The front of the feet is
0.10 m ahead of the NAO frame's origin: no stance puts a seat's front nearer."""
HEIGHT_TOLERANCE_M = 0.001
"""The bear's base height is held this close to ``h + BEAR_SEAT_CLEARANCE_M``."""
NO_BACKREST = 10.0
"""A back block this far ahead (metres) stands for "no backrest"."""

_GUESSES = (
    np.array([0.0, 0.0, 0.0, 0.0, 0.4]),
    np.array([0.2, 0.0, -0.8, -0.4, 0.4]),
    np.array([-0.3, 0.9, -1.0, 0.3, 0.5]),
    np.array([-0.6, 1.4, -1.2, 0.0, 0.8]),
    np.array([0.1, 0.3, -1.3, -0.6, 0.2]),
)
"""Initial postures q = (ankle, knee, hip, shoulder, elbow): standing with arms ahead,
bending at the hips, crouching and leaning."""


class ReachModel(NamedTuple):
    """d_max over a grid of seat heights and seat fronts (see the module doc).

    Attributes:
        seat_heights_m: (H,) seat-top heights, metres.
        seat_fronts_m: (F,) seat front planes in the NAO frame, metres.
        max_forward_m: (H, F) the farthest forward bear placement, metres (NaN: none).
        carry_height_m: the highest the NAO carries the bear's base into a stance (its
            highest raised posture, :data:`.postures.RAISED_POSTURES`), metres: the bear comes over
            the seat's front at this height, so no seat above it less
            ``BEAR_CHAIR_MARGIN_M`` can be reached from any stance.
        release: the free reach and the release height rule r(h).
    """

    seat_heights_m: np.ndarray
    seat_fronts_m: np.ndarray
    max_forward_m: np.ndarray
    carry_height_m: float = math.inf
    release: ReleaseHeights = NO_LOW_SEATS

    def release_height_m(self, seat_height_m: float) -> float:
        """r(h): where the goal lets the bear's seat point go over a seat top (metres; NaN:
        nowhere near enough)."""
        return self.release.release_height_m(seat_height_m)

    def max_forward(self, seat_height_m: float, seat_front_m: float) -> float:
        """d_max (metres) at a seat height and front, NaN when nothing is reachable.

        Bilinear between grid points, NaN when a surrounding cell has no posture; a front
        beyond the grid counts as its last column (the knees have room enough there), a
        front nearer than the grid's first column or a height outside the grid is
        unreachable. Between grid points this may promise up to a few millimetres more
        than a solve would: the pre-plan that follows decides.
        """
        heights, fronts = self.seat_heights_m, self.seat_fronts_m
        if not heights[0] <= seat_height_m <= min(heights[-1], self.carried_over_m()):
            return math.nan
        if seat_front_m < fronts[0] - 1e-9:
            return math.nan
        front = min(seat_front_m, float(fronts[-1]))
        i = int(
            np.clip(np.searchsorted(heights, seat_height_m, side="right") - 1, 0, len(heights) - 2)
        )
        j = int(np.clip(np.searchsorted(fronts, front, side="right") - 1, 0, len(fronts) - 2))
        cells = self.max_forward_m[i : i + 2, j : j + 2]
        t = (seat_height_m - heights[i]) / (heights[i + 1] - heights[i])
        w = (front - fronts[j]) / (fronts[j + 1] - fronts[j])
        weights = np.outer([1.0 - t, t], [1.0 - w, w])
        used = weights > 1e-9
        if np.any(np.isnan(cells[used])):
            return math.nan
        return float(np.sum(weights[used] * cells[used]))

    def reachable(self, seat_height_m: float, seat_front_m: float, forward_m: float) -> bool:
        """Whether a bear placement ``forward_m`` ahead on that seat is within d_max."""
        d_max = self.max_forward(seat_height_m, seat_front_m)
        return not math.isnan(d_max) and forward_m <= d_max

    def carried_over_m(self) -> float:
        """The highest seat top (metres) the carried bear clears on its way in."""
        return self.carry_height_m - BEAR_CHAIR_MARGIN_M

    def max_seat_height_m(self) -> float:
        """The highest seat top (metres) on which the NAO places the bear from any stance:
        where a goal posture exists and the raised bear still clears it."""
        feasible = np.flatnonzero(~np.isnan(self.max_forward_m).all(axis=1))
        if not len(feasible):
            return math.nan
        return min(float(self.seat_heights_m[feasible[-1]]), self.carried_over_m())

    def min_seat_height_m(self) -> float:
        """The lowest seat top (metres) on which the NAO places the bear from any stance."""
        feasible = np.flatnonzero(~np.isnan(self.max_forward_m).all(axis=1))
        return float(self.seat_heights_m[feasible[0]]) if len(feasible) else math.nan

    def to_json(self) -> dict:
        return {
            "carry_height_m": round(self.carry_height_m, 4),
            "release": self.release.to_json(),
            "seat_heights_m": self.seat_heights_m.tolist(),
            "seat_fronts_m": self.seat_fronts_m.tolist(),
            "max_forward_m": [
                [None if math.isnan(v) else round(float(v), 4) for v in row]
                for row in self.max_forward_m
            ],
        }

    @classmethod
    def from_json(cls, data: dict) -> ReachModel:
        table = np.array(
            [[math.nan if v is None else float(v) for v in row] for row in data["max_forward_m"]]
        )
        return cls(
            np.array(data["seat_heights_m"]),
            np.array(data["seat_fronts_m"]),
            table,
            float(data["carry_height_m"]),
            ReleaseHeights.from_json(data["release"]) if "release" in data else NO_LOW_SEATS,
        )


class _MaxForwardProblem:
    """The NLP of one cell: maximise the bear's forward placement at a fixed height."""

    def __init__(self, problems: SeatingProblems) -> None:
        q = ca.SX.sym("q", 5)
        chair = ca.SX.sym("chair", 4)
        values = problems.posture_constraints(q, chair, 1.0, NO_RELEASED_BEAR)
        _, base, _, torso_pitch, _, _ = problems.posture_geometry(q, 1.0)
        # A little weight on the torso pitch picks the most upright of equally far postures.
        cost = -base[0] + 1e-3 * torso_pitch**2
        nlp = {"x": q, "p": chair, "f": cost, "g": values}
        self.solver = ca.nlpsol("reach_cell", "ipopt", nlp, _ipopt_options(300))
        self.problems = problems

    def solve(self, seat_height_m: float, seat_front_m: float, bear_z: float) -> float:
        """d_max of one cell (metres) with the bear's base at ``bear_z``, NaN when no guess
        reaches a feasible posture."""
        problems = self.problems
        profile = ChairProfile(seat_front_m, seat_height_m, NO_BACKREST, seat_height_m)
        lower, upper = problems.posture_bounds(g_xz=None, tilt_rad=BEAR_TILT_GOAL_RAD)
        lower[1], upper[1] = bear_z - HEIGHT_TOLERANCE_M, bear_z + HEIGHT_TOLERANCE_M
        best = math.nan
        for guess in _GUESSES:
            with problems.lock:
                result = self.solver(
                    x0=guess,
                    p=profile.as_vector(),
                    lbx=problems.nao.q_lower,
                    ubx=problems.nao.q_upper,
                    lbg=lower,
                    ubg=upper,
                )
            q = np.asarray(result["x"]).ravel()
            violation, _, _ = exact_posture_violation(
                problems, q, profile, g_xz=None, tilt_rad=BEAR_TILT_GOAL_RAD
            )
            base = problems.geometry(q).bear_base
            if violation > CHECK_TOLERANCE or abs(base[1] - bear_z) > 2 * HEIGHT_TOLERANCE_M:
                continue
            if math.isnan(best) or base[0] > best:
                best = float(base[0])
        return best


def _solve_cell(
    problem: _MaxForwardProblem, seat_height_m: float, seat_front_m: float, release: ReleaseHeights
) -> float:
    bear_z = release.release_height_m(seat_height_m)
    return math.nan if math.isnan(bear_z) else problem.solve(seat_height_m, seat_front_m, bear_z)


def compute_reach_model(
    seat_heights_m: np.ndarray = SEAT_HEIGHTS_M, seat_fronts_m: np.ndarray = SEAT_FRONTS_M
) -> ReachModel:
    """Solves every cell of the grid (see the module doc); about a minute."""
    problem = _MaxForwardProblem(seating_problems())
    release = _release_heights(problem)
    table = np.array(
        [
            [_solve_cell(problem, float(h), float(f), release) for f in seat_fronts_m]
            for h in seat_heights_m
        ]
    )
    return ReachModel(
        np.asarray(seat_heights_m),
        np.asarray(seat_fronts_m),
        table,
        raised_carry_height_m(),
        release,
    )


def _release_heights(problem: _MaxForwardProblem) -> ReleaseHeights:
    """The free reach d(r): the bear's base at r over a seat far below and far ahead."""
    seat_height_m, seat_front_m = float(SEAT_HEIGHTS_M[0]) - 0.05, float(SEAT_FRONTS_M[-1])
    return compute_release_heights(lambda r: problem.solve(seat_height_m, seat_front_m, r))


@lru_cache(maxsize=1)
def release_heights() -> ReleaseHeights:
    """The free reach and release heights, solved now (not the shipped table's)."""
    return _release_heights(_max_forward_problem())


def raised_carry_height_m() -> float:
    """Height (metres) of the bear's base in the highest raised carrying posture."""
    return float(seating_problems().geometry(RAISED_POSTURES[-1]).bear_base[1])


def solve_reach_cell(seat_height_m: float, seat_front_m: float) -> float:
    """d_max of one (seat height, seat front) pair, solved now (metres, NaN: none)."""
    return _solve_cell(_max_forward_problem(), seat_height_m, seat_front_m, release_heights())


@lru_cache(maxsize=1)
def _max_forward_problem() -> _MaxForwardProblem:
    return _MaxForwardProblem(seating_problems())


@lru_cache(maxsize=1)
def reach_model() -> ReachModel:
    """The shipped reach model (``reach_table.json``)."""
    return ReachModel.from_json(json.loads(TABLE_PATH.read_text()))


def main() -> None:
    import time

    started = time.perf_counter()
    model = compute_reach_model()
    TABLE_PATH.write_text(json.dumps(model.to_json(), indent=None) + "\n")
    print(
        f"wrote {TABLE_PATH} in {time.perf_counter() - started:.1f} s: seats "
        f"{model.min_seat_height_m():.2f}-{model.max_seat_height_m():.2f} m reachable"
    )


if __name__ == "__main__":
    main()
