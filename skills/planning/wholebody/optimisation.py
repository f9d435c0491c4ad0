"""The goal posture and trajectory optimisations (the paper, eq. 8-16), over casadi SX.

Both problems are built once per process and reused: everything that changes between
solves (the sitting pose g, the chair's profile, start and goal postures, velocity
limits, whether the bear is held) is a parameter or a bound, never a rebuild.

Posture constraints (one vector per posture, see :data:`CONSTRAINT_GROUPS`):

* ``bear placement``: the bear's base b(q) at g within ``PLACEMENT_TOLERANCE_M``;
* ``bear upright``: the held bear within a tilt of vertical;
* ``support polygon``: the centre of mass's x within the feet's support interval
  ``[x_back + margin, x_front - margin]`` (the motion is symmetric, so y is 0);
* ``chair collision``: every sampled body point and the bear's outline clear the
  chair's two blocks (:mod:`.chair_profile`) by the point's radius plus a margin;
* ``bear-body collision``: the NAO's legs, torso and head clear the bear, held or,
  in the retract, where it was let go;
* ``floor``: nothing below the floor.

The block clearance ``max(front_x - x, z - top_z)`` is smoothed for IPOPT by a
log-sum-exp of sharpness κ minus ln(n)/κ, a lower bound within ln(n)/κ (1.7 mm for
n = 2) of the max, so the smoothed constraints are conservative; every result is
re-checked with the exact max.
"""

from __future__ import annotations

import math
import threading
from typing import NamedTuple

import casadi as ca
import numpy as np

from bearchair.core.nao_carrying import (
    PLACEMENT_TOLERANCE_M,
)
from bearchair.core.runtime import RUNTIME
from bearchair.skills.planning.wholebody.held_bear import (
    BEAR_DEPTH_M,
    BEAR_HEIGHT_M,
    BEAR_OUTLINE,
    BEAR_SNOUT_M,
    BEAR_SNOUT_Z_M,
    held_bear,
)
from bearchair.skills.planning.wholebody.nao_model import PlanarNao, planar_nao

BEAR_TILT_GOAL_RAD = math.radians(8.0)
BEAR_TILT_MOTION_RAD = math.radians(30.0)
SUPPORT_MARGIN_M = 0.01
BODY_MARGIN_M = 0.01
BEAR_CHAIR_MARGIN_M = 0.003
SMOOTH_MAX_SHARPNESS = 400.0
NO_RELEASED_BEAR = np.array([10.0, 0.0, -1.0, 0.0, 0.0])
"""The ``released`` parameter when no bear rests anywhere near: 10 m ahead."""

GOAL_COM_WEIGHT = 10.0
GOAL_TORSO_WEIGHT = 1.0
BEAR_LEAN_BACK_RAD = math.radians(5.0)
"""The goal prefers the bear let go leaning back this far (toward the backrest, radians):
it then lands on its rear edge with its centre of mass over it, which rocks it onto its
base. Let go upright or leaning forward onto a seat that falls a few degrees toward the
NAO (a crowned or rounded seat), it landed on its rear edge with its centre of mass ahead
of it, and the impact pitched it forward at about 2 rad/s, over its front. 5 deg is well
inside the 23 deg at which its centre of mass (0.10 m up) would pass the rear edge of its
0.085 m deep base, and inside the goal's tilt bound (``BEAR_TILT_GOAL_RAD``)."""
GOAL_LEAN_WEIGHT = 100.0
"""Weight of the lean's squared error (in sin units): a 5 deg miss costs as much as 0.08 m
of centre of mass off the feet's middle, so the lean wins unless balance needs it."""

N_KNOTS = 30
COARSE_KNOTS = 15
"""Knots of the trajectory tried first (about 2.3 times faster to solve than
:data:`N_KNOTS`); the planner checks it between its knots too and falls back to
:data:`N_KNOTS` when it does not hold (``trajectory.solve_trajectory``)."""

# (link, offset in link frame (m), radius (m), label): sampled points of the NAO's body.
LEG_TORSO_HEAD_POINTS = (
    ("LTibia", (0.0, 0.0, 0.0), 0.035, "knee"),
    ("LTibia", (0.0, 0.0, -0.05), 0.03, "shin"),
    ("LThigh", (0.0, 0.0, -0.05), 0.035, "thigh"),
    ("LThigh", (0.0, 0.0, 0.0), 0.04, "hip"),
    ("torso", (0.045, 0.0, -0.05), 0.02, "belly"),
    ("torso", (0.045, 0.0, 0.02), 0.02, "chest"),
    ("torso", (0.045, 0.0, 0.09), 0.02, "upper chest"),
    ("Head", (0.0, 0.0, 0.05), 0.055, "head"),
)
ARM_POINTS = (
    ("LBicep", (0.0, 0.0, 0.0), 0.03, "shoulder"),
    ("LBicep", (0.05, 0.0, 0.0), 0.025, "upper arm"),
    ("LElbow", (0.0, 0.0, 0.0), 0.025, "elbow"),
    ("l_wrist", (0.0, 0.0, 0.0), 0.025, "wrist"),
    ("l_gripper", (0.0, 0.0, 0.0), 0.015, "hand"),
)


class ConstraintRow(NamedTuple):
    """One scalar posture constraint: ``lower <= value <= upper`` (before bounds)."""

    group: str
    label: str


class PostureGeometry(NamedTuple):
    """Named numeric quantities of one posture (NAO frame, metres)."""

    com_x: float
    bear_base: np.ndarray
    bear_up: np.ndarray
    torso_pitch_rad: float
    body_points: dict[str, np.ndarray]
    bear_points: dict[str, np.ndarray]


def _smooth_max(a: ca.SX, b: ca.SX, sharpness: float = SMOOTH_MAX_SHARPNESS) -> ca.SX:
    """A smooth lower bound of max(a, b) (see :func:`_smooth_max_n`)."""
    return _smooth_max_n([a, b], sharpness)


def _smooth_max_n(values: list[ca.SX], sharpness: float = SMOOTH_MAX_SHARPNESS) -> ca.SX:
    """A smooth lower bound of max(values): log-sum-exp minus ln(n)/κ.

    max - ln(n)/κ <= result <= max, so a constraint on it is conservative. The exact max
    shifts the exponents into range; its kinks cancel out of the value.
    """
    m = values[0]
    for v in values[1:]:
        m = ca.fmax(m, v)
    total = sum(ca.exp(sharpness * (v - m)) for v in values)
    return m + (ca.log(total) - math.log(len(values))) / sharpness


class SeatingProblems:
    """The two NLPs and the posture model, built once.

    Parameters of the goal NLP: ``[g_x, g_z, chair(4), diagnose]``; with ``diagnose``
    = 1 the cost becomes the bear placement error (used to explain infeasibility).
    Parameters of the trajectory NLP: ``[q_goal(5), chair(4), bear_held, released(5),
    weights(5)]``; ``released`` is where a let-go bear rests (see
    :func:`released_bear`), which the NAO's legs, torso and head keep clear of.
    """

    def __init__(self, nao: PlanarNao | None = None, n_knots: int = N_KNOTS) -> None:
        self.nao = nao or planar_nao()
        self.n_knots = n_knots
        q = ca.SX.sym("q", 5)
        chair = ca.SX.sym("chair", 4)
        bear_held = ca.SX.sym("bear_held")
        released = ca.SX.sym("released", 5)
        values, self.rows, self.row_lower, self.row_upper, geometry = self._posture(
            q, chair, bear_held, released
        )
        self.posture_constraints = ca.Function(
            "posture_g", [q, chair, bear_held, released], [values]
        )
        self.posture_geometry = ca.Function("posture_geometry", [q, bear_held], geometry)
        self.support_centre_x = 0.5 * sum(self.nao.support_x)
        self._build_goal(q, chair)
        # The fine trajectory NLP (1.4 s to build) is built when a coarse plan is first
        # refused: 2 of 39 solves on six chairs, but once in most missions, so the
        # mission's warm-up (start_building_problems) builds it ahead.
        self._trajectory_solvers = {COARSE_KNOTS: self._build_trajectory(COARSE_KNOTS)}
        self._building = threading.Lock()
        self.lock = threading.Lock()

    def trajectory_solver(self, n: int) -> ca.Function:
        """The trajectory NLP on ``n`` knots (:data:`COARSE_KNOTS` or ``n_knots``), built
        on first use."""
        with self._building:
            if n not in self._trajectory_solvers:
                self._trajectory_solvers[n] = self._build_trajectory(n)
            return self._trajectory_solvers[n]

    # ---- the posture model -------------------------------------------------------
    def _posture(self, q: ca.SX, chair: ca.SX, bear_held: ca.SX, released: ca.SX):
        """The posture vector's expressions, rows and bounds (before the solve-time ones),
        and the :class:`PostureGeometry` outputs, of a symbolic posture ``q``."""
        nao = self.nao
        frames = nao.frames(q)
        bear_base, forward, up, com, torso_pitch = held_bear(nao, frames, bear_held)
        rows = _ConstraintRows()
        # Placement and uprightness get their bounds at solve time (goal vs motion).
        rows.add("bear placement", "forward", bear_base[0], -math.inf, math.inf)
        rows.add("bear placement", "height", bear_base[1], -math.inf, math.inf)
        rows.add("bear upright", "bear tilt", forward[1] * bear_held, -math.inf, math.inf)
        rows.add(
            "support polygon",
            "centre of mass",
            com[0],
            nao.support_x[0] + SUPPORT_MARGIN_M,
            nao.support_x[1] - SUPPORT_MARGIN_M,
        )
        body_points = _add_body_rows(rows, nao, frames, chair)
        bear_points = _add_bear_rows(rows, bear_base, forward, up, chair, bear_held)
        _add_body_bear_rows(rows, body_points, bear_base, forward, bear_held, released)
        geometry = [
            com[0],
            bear_base,
            up,
            torso_pitch,
            ca.horzcat(*body_points.values()),
            ca.horzcat(*bear_points.values()),
        ]
        self.body_labels = list(body_points)
        self.bear_labels = list(bear_points)
        return (
            ca.vertcat(*rows.exprs),
            rows.rows,
            np.array(rows.lower),
            np.array(rows.upper),
            geometry,
        )

    def geometry(self, q: np.ndarray, bear_held: bool = True) -> PostureGeometry:
        """Numeric quantities of a posture (for checks and reports)."""
        com_x, base, up, torso, body, bear = self.posture_geometry(q, float(bear_held))
        body = np.asarray(body)
        bear = np.asarray(bear)
        return PostureGeometry(
            com_x=float(com_x),
            bear_base=np.asarray(base).ravel(),
            bear_up=np.asarray(up).ravel(),
            torso_pitch_rad=float(torso),
            body_points={label: body[:, i] for i, label in enumerate(self.body_labels)},
            bear_points={label: bear[:, i] for i, label in enumerate(self.bear_labels)},
        )

    def posture_bounds(
        self, *, g_xz: np.ndarray | None, tilt_rad: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the posture vector: placement at g (or free), tilt."""
        lower, upper = self.row_lower.copy(), self.row_upper.copy()
        if g_xz is not None:
            lower[0:2] = np.asarray(g_xz) - PLACEMENT_TOLERANCE_M
            upper[0:2] = np.asarray(g_xz) + PLACEMENT_TOLERANCE_M
            # Never higher than g: the bear is let go there and drops the difference.
            upper[1] = float(g_xz[1])
        lower[2], upper[2] = -math.sin(tilt_rad), math.sin(tilt_rad)
        return lower, upper

    # ---- the goal posture (eq. 12-16) -------------------------------------------
    def _build_goal(self, q: ca.SX, chair: ca.SX) -> None:
        g_xz = ca.SX.sym("g", 2)
        diagnose = ca.SX.sym("diagnose")
        values = self.posture_constraints(q, chair, 1.0, NO_RELEASED_BEAR)
        com_x, base, up, torso_pitch, _, _ = self.posture_geometry(q, 1.0)
        d_com = ca.sqrt((com_x - self.support_centre_x) ** 2 + 1e-8)
        cost = GOAL_COM_WEIGHT * d_com + GOAL_TORSO_WEIGHT * torso_pitch**2
        # up[0] > 0: the bear's top leans away from the NAO, toward the backrest.
        cost += GOAL_LEAN_WEIGHT * (up[0] - math.sin(BEAR_LEAN_BACK_RAD)) ** 2
        placement_error = ca.sumsqr(base - g_xz)
        objective = (1 - diagnose) * cost + diagnose * 100.0 * placement_error
        nlp = {"x": q, "p": ca.vertcat(g_xz, chair, diagnose), "f": objective, "g": values}
        self.goal_solver = ca.nlpsol("seating_goal", "ipopt", nlp, _ipopt_options(200))

    # ---- the trajectory (eq. 8-11) ----------------------------------------------
    def _build_trajectory(self, n: int) -> ca.Function:
        Q = ca.SX.sym("Q", 5, n)
        q_goal = ca.SX.sym("q_goal", 5)
        chair = ca.SX.sym("chair", 4)
        bear_held = ca.SX.sym("bear_held")
        released = ca.SX.sym("released", 5)
        weights = ca.SX.sym("weights", 5)
        cost = 0
        for k in range(n):
            diff = Q[:, k] - q_goal
            cost += 0.5 * ca.sum1(weights * diff**2)
        velocity = [Q[:, k + 1] - Q[:, k] for k in range(n - 1)]
        interior = self.posture_constraints.map(n - 2)(Q[:, 1:-1], chair, bear_held, released)
        g = ca.vertcat(*velocity, ca.vec(interior))
        nlp = {
            "x": ca.vec(Q),
            "p": ca.vertcat(q_goal, chair, bear_held, released, weights),
            "f": cost,
            "g": g,
        }
        return ca.nlpsol(f"seating_trajectory_{n}", "ipopt", nlp, _ipopt_options(300))


class _ConstraintRows:
    """The posture constraints as they are added: rows, expressions and bounds."""

    def __init__(self) -> None:
        self.rows: list[ConstraintRow] = []
        self.exprs: list[ca.SX] = []
        self.lower: list[float] = []
        self.upper: list[float] = []

    def add(self, group: str, label: str, expr: ca.SX, lo: float, hi: float = math.inf) -> None:
        """Adds ``lo <= expr <= hi``."""
        self.rows.append(ConstraintRow(group, label))
        self.exprs.append(expr)
        self.lower.append(lo)
        self.upper.append(hi)


def _chair_clearance(chair: ca.SX, p: ca.SX) -> ca.SX:
    """The smoothed clearance (metres) of a point (x, z) to the chair's two blocks."""
    seat_front, seat_top, back_front, back_top = (chair[i] for i in range(4))
    seat = _smooth_max(seat_front - p[0], p[1] - seat_top)
    back = _smooth_max(back_front - p[0], p[1] - back_top)
    return ca.fmin(seat, back)


def _add_body_rows(
    rows: _ConstraintRows, nao: PlanarNao, frames: dict[str, ca.SX], chair: ca.SX
) -> dict[str, ca.SX]:
    """Adds the chair and floor rows of the NAO's sampled body points; returns the points
    by label."""
    body_points: dict[str, ca.SX] = {}
    for link, offset, radius, label in LEG_TORSO_HEAD_POINTS + ARM_POINTS:
        point = nao.point(frames, link, offset)
        body_points[label] = point
        rows.add(
            "chair collision",
            f"NAO {label}",
            _chair_clearance(chair, point) - radius,
            BODY_MARGIN_M,
        )
        rows.add("floor", f"NAO {label}", point[1] - radius, 0.0)
    return body_points


def _add_bear_rows(
    rows: _ConstraintRows,
    bear_base: ca.SX,
    forward: ca.SX,
    up: ca.SX,
    chair: ca.SX,
    bear_held: ca.SX,
) -> dict[str, ca.SX]:
    """Adds the chair and floor rows of the held bear's outline; returns its points by
    label."""
    # A released bear (bear_held = 0) no longer moves with the hands: its chair and
    # floor rows are lifted by a metre.
    lift = 1.0 - bear_held
    bear_points: dict[str, ca.SX] = {}
    for bx, bz, label in BEAR_OUTLINE:
        point = bear_base + bx * forward + bz * up
        bear_points[label] = point
        rows.add(
            "chair collision", label, _chair_clearance(chair, point) + lift, BEAR_CHAIR_MARGIN_M
        )
        rows.add("floor", label, point[1] + lift, 0.0)
    return bear_points


def _add_body_bear_rows(
    rows: _ConstraintRows,
    body_points: dict[str, ca.SX],
    bear_base: ca.SX,
    forward: ca.SX,
    bear_held: ca.SX,
    released: ca.SX,
) -> None:
    """Adds the rows that keep the NAO's legs, torso and head clear of the bear."""
    # The body keeps clear of the bear held, and of the bear let go where it rests:
    # standing up, the head must not sweep through it.
    body_bear_base = bear_held * bear_base + (1.0 - bear_held) * released[0:2]
    body_bear_forward = bear_held * forward + (1.0 - bear_held) * released[2:4]
    body_bear_up = ca.vertcat(-body_bear_forward[1], body_bear_forward[0])
    for _link, _offset, radius, label in LEG_TORSO_HEAD_POINTS:
        rel = body_points[label] - body_bear_base
        lx = ca.dot(rel, body_bear_forward)
        lz = ca.dot(rel, body_bear_up)
        outline = _smooth_max_n(
            [-BEAR_DEPTH_M / 2 - lx, lx - BEAR_DEPTH_M / 2, -lz, lz - BEAR_HEIGHT_M]
        )
        # The let-go bear's snout (lx < 0 is its face) too: standing up with only the
        # outline clear, the head swept 3 cm into it and pushed the bear over. It may
        # be touched, and entered as deep as where it was let go (released[4]); the
        # held bear's is left to the outline's margin.
        snout = _smooth_max_n(
            [
                -BEAR_DEPTH_M / 2 - BEAR_SNOUT_M - lx,
                lx + BEAR_DEPTH_M / 2,
                BEAR_SNOUT_Z_M[0] - lz,
                lz - BEAR_SNOUT_Z_M[1],
            ]
        )
        outside = ca.fmin(outline, snout + BODY_MARGIN_M + released[4] + bear_held)
        rows.add("bear-body collision", f"NAO {label}", outside - radius, BODY_MARGIN_M)


def released_bear(geometry: PostureGeometry) -> np.ndarray:
    """The ``released`` parameter of a bear let go from a posture: its base (x, z) and its
    forward axis (x, z) in the NAO frame, where the hands held it, and how deep (metres)
    the body already is in its snout there (the retract may go no deeper), with the
    smoothing's ln(4)/κ so that the posture itself meets the smoothed row."""
    up = geometry.bear_up
    forward = np.array([up[1], -up[0]])
    base = geometry.bear_base
    deepest = -math.inf
    for _link, _offset, radius, label in LEG_TORSO_HEAD_POINTS:
        rel = geometry.body_points[label] - base
        lx, lz = float(rel @ forward), float(rel @ up)
        snout = max(
            -BEAR_DEPTH_M / 2 - BEAR_SNOUT_M - lx,
            lx + BEAR_DEPTH_M / 2,
            BEAR_SNOUT_Z_M[0] - lz,
            lz - BEAR_SNOUT_Z_M[1],
        )
        deepest = max(deepest, radius - snout)
    allowance = max(deepest + math.log(4.0) / SMOOTH_MAX_SHARPNESS, 0.0)
    return np.array([base[0], base[1], forward[0], forward[1], allowance])


def _ipopt_options(max_iter: int) -> dict:
    return {
        "print_time": False,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        "ipopt.max_iter": max_iter,
        "ipopt.tol": 1e-6,
        "ipopt.constr_viol_tol": 1e-5,
        "ipopt.mu_strategy": "adaptive",
    }


_problems: SeatingProblems | None = None
_problems_lock = threading.Lock()


def seating_problems() -> SeatingProblems:
    """The process-wide problems (built on first use: 0.7 s on the 2-core machine)."""
    global _problems
    with _problems_lock:
        if _problems is None:
            _problems = SeatingProblems()
        return _problems


def start_building_problems() -> threading.Thread:
    """Builds :func:`seating_problems`, then its fine trajectory NLP, in a background
    thread and returns it.

    The mission's first pre-plan comes after the scan and the imagination; built while
    they run (casadi releases the GIL while it builds), it does not wait for the build.
    A pre-plan that comes first waits on the same locks. One coarse plan refused in a
    mission needs the fine NLP (in 6 of 7 missions of bench/mission.py), so it is built
    too.
    """

    def build() -> None:
        problems = seating_problems()
        problems.trajectory_solver(problems.n_knots)

    # Through the runtime: the exit joins it, as casadi crashes an interpreter that
    # finalises while it builds.
    return RUNTIME.start_thread(build, name="build seating problems")
