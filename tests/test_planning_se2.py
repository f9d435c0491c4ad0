"""SE(2) goal placement, arm reach and OMPL planning around a box chair in the default arena."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from bearchair.core.arena import DEFAULT_ARENA, Arena, Box2D
from bearchair.core.geometry import SittingPose, yaw_transform
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning import collision, preplan
from bearchair.skills.planning.accessibility import (
    AccessibilityError,
    check_accessibility,
    stepped_back,
)
from bearchair.skills.planning.collision import NaoCollisionChecker, chair_solid_boxes
from bearchair.skills.planning.preplan import SeatingCheck, reach_validator
from bearchair.skills.planning.seat import (
    BEAR_EDGE_MARGIN_M,
    SEAT_DROP_TOLERANCE_M,
    STEP_M,
    seat_ray,
    seat_support_heights,
    slide_on_seat,
)
from bearchair.skills.planning.stance import check_seat_reachable, choose_stance, goal_on_ray
from bearchair.skills.planning.wholebody import InfeasibleSeating
from bearchair.skills.planning.wholebody.reach_model import reach_model

PELVIS_ABOVE_SEAT_M = 0.05
START = DEFAULT_ARENA.humanoid_start


def _placed_chair(x: float, y: float, yaw_deg: float, **chair_kwargs):
    """A box chair (sitting direction +x, seat centre at the origin) moved into the world."""
    T_world_chair = yaw_transform(math.radians(yaw_deg), np.array([x, y, 0.0]))
    seat_height = chair_kwargs.get("seat_height_m", 0.24)
    chair_mesh = box_chair_mesh(**chair_kwargs).apply_transform(T_world_chair)
    sitting_pose = SittingPose(np.array([0.0, 0.0, seat_height + PELVIS_ABOVE_SEAT_M]), 0.0)
    return chair_mesh, sitting_pose.transformed(T_world_chair)


def _check(chair_mesh, sitting_pose, arena: Arena = DEFAULT_ARENA, seed: int = 0):
    return check_accessibility(
        chair_mesh, sitting_pose, START, arena, seed=seed, seating_validator=reach_validator
    )


@pytest.mark.parametrize("yaw_deg", [0.0, 25.0, -30.0])
def test_chair_facing_the_humanoid_is_accessible(yaw_deg: float) -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.1, yaw_deg)
    result = _check(chair_mesh, sitting_pose)
    assert result.accessible, result.reason
    assert result.path[0] == START and result.path[-1] == result.se2_goal
    checker = NaoCollisionChecker(DEFAULT_ARENA, chair_solid_boxes(chair_mesh))
    for a, b in zip(result.path, result.path[1:], strict=False):
        for t in np.linspace(0.0, 1.0, 6):
            x, y = a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)
            assert checker.is_free(x, y, a.theta), (x, y)
    assert math.cos(result.se2_goal.theta - (sitting_pose.yaw + math.pi)) > 0.9999


def test_chair_facing_the_back_wall_next_to_it_is_not_accessible() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.4, 0.0, 180.0)
    result = _check(chair_mesh, sitting_pose)
    assert not result.accessible
    assert result.path == ()
    assert "sitting ray" in result.reason
    assert "wall" in result.reason or "arena" in result.reason


def test_goal_blocked_everywhere_means_no_path_after_the_check_budget(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A fence across the arena between the humanoid and the chair.
    fenced = DEFAULT_ARENA._replace(
        obstacles=(
            *DEFAULT_ARENA.obstacles,
            Box2D(1.3, 1.4, DEFAULT_ARENA.y_min, DEFAULT_ARENA.y_max),
        )
    )
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0)
    checks = []
    is_free = NaoCollisionChecker.is_free
    monkeypatch.setattr(
        NaoCollisionChecker,
        "is_free",
        lambda self, *pose: checks.append(pose) or is_free(self, *pose),
    )
    result = check_accessibility(
        chair_mesh,
        sitting_pose,
        START,
        fenced,
        seed=0,
        seating_validator=reach_validator,
        check_budget=4000,
    )
    assert not result.accessible
    assert result.reason == "no collision-free path to s_goal"
    # The search stopped at its budget (plus the goal placement's own checks), not earlier.
    assert 4000 <= len(checks) < 4000 + 2000


def test_same_seed_same_path() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.7, -0.2, 90.0)
    first, second = (
        _check(chair_mesh, sitting_pose, seed=5),
        _check(chair_mesh, sitting_pose, seed=5),
    )
    assert first.accessible and first.path == second.path


def _anywhere(chair_mesh, pose, se2_goal) -> SeatingCheck:
    return SeatingCheck()


def test_goal_is_the_first_spot_on_the_ray_clear_of_the_chair() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.1, 40.0)
    checker = NaoCollisionChecker(DEFAULT_ARENA, chair_solid_boxes(chair_mesh))
    choice = choose_stance(chair_mesh, sitting_pose, checker, _anywhere, scene=False)
    goal = choice.se2_goal
    assert not checker.collides_with_chair(goal) and choice.approach is None
    direction = sitting_pose.direction()
    offset = np.array([goal.x, goal.y]) - sitting_pose.position[:2]
    along = float(offset @ direction)
    assert abs(offset @ [-direction[1], direction[0]]) < 1e-9  # on the ray from the first p
    # One step closer collides: the walk ends at the first free spot.
    assert checker.collides_with_chair(goal_on_ray(sitting_pose, along - STEP_M))
    # The seat's front edge is 0.14 m ahead of p; the ellipsoid reaches ~0.20 m forward;
    # the chair's solid stands up to a cell's diagonal outside its surface.
    assert 0.32 <= along <= 0.36 + collision.CHAIR_CELL_M
    # p slid just far enough for the reach model (the seat is 0.24 m high, the seat front
    # 0.19 m ahead of the NAO: d_max about 0.32 m).
    model = reach_model()
    front = choice.se2_goal.distance_to(goal_on_ray(sitting_pose, 0.14))
    assert along - choice.slide_m <= model.max_forward(0.24, front)
    assert along - (choice.slide_m - STEP_M) > model.max_forward(0.24, front)
    assert choice.preplans == 1


def test_goal_in_the_wall_behind_a_chair_at_the_arena_edge_is_pushed_clear() -> None:
    # At the arm-side edge, turned 34 degrees: the first spot clear of the chair puts the
    # NAO's front in the wall; the goal moves on along the ray and p slides to reach.
    chair_mesh, sitting_pose = _placed_chair(0.36, 0.16, -34.0, seat_depth_m=0.36)
    checker = NaoCollisionChecker(DEFAULT_ARENA, chair_solid_boxes(chair_mesh))
    chair_clear_along = 0.0
    while checker.collides_with_chair(goal_on_ray(sitting_pose, chair_clear_along)):
        chair_clear_along += STEP_M
    assert checker.collides_with_walls(goal_on_ray(sitting_pose, chair_clear_along))
    result = _check(chair_mesh, sitting_pose)
    assert result.accessible, result.reason
    assert checker.blocked_by(result.se2_goal) == ""
    assert result.sitting_pose.position[0] > sitting_pose.position[0]  # slid toward the NAO


def test_far_sitting_position_slides_toward_the_nao_on_the_seat() -> None:
    chair_mesh, _ = _placed_chair(0.6, 0.0, 0.0, seat_depth_m=0.5)
    p_back = SittingPose(np.array([0.45, 0.0, 0.29]), 0.0)  # 0.15 m behind the seat centre
    result = _check(chair_mesh, p_back)
    assert result.accessible, result.reason
    moved = result.sitting_pose.position
    assert moved[0] > 0.45 + 0.05 and moved[1] == pytest.approx(0.0)
    assert seat_support_heights(chair_mesh, moved[None, :2], 0.31)[0] == pytest.approx(0.24)
    # The reach validator (the reach model) accepts it: the bear is within d_max.
    assert not reach_validator(chair_mesh, result.sitting_pose, result.se2_goal).reason


def test_seat_behind_a_long_footrest_is_refused_as_out_of_reach() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0)
    # A footrest block 0.25 m deep in front of the seat: the NAO's feet stop at its front.
    footrest = trimesh.creation.box(
        extents=(0.25, 0.3, 0.1),
        transform=trimesh.transformations.translation_matrix((0.6 + 0.14 + 0.125, 0.0, 0.15)),
    )
    chair_mesh = trimesh.util.concatenate([chair_mesh, footrest])
    result = _check(chair_mesh, sitting_pose)
    assert not result.accessible
    assert "out of the NAO's reach" in result.reason
    verdict = check_seat_reachable(chair_mesh, sitting_pose, seating_validator=reach_validator)
    assert not verdict.reachable and "out of the NAO's reach" in verdict.reason
    assert verdict.seat_height_m == pytest.approx(0.24, abs=0.005)


def test_a_short_footrest_is_stepped_over_from_the_walking_stance() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0)
    # A footrest bar 8 cm in front of the seat, 12 cm high: the walking ellipsoid stops
    # too far back; the feet may come up to the bar.
    footrest = trimesh.creation.box(
        extents=(0.02, 0.3, 0.02),
        transform=trimesh.transformations.translation_matrix((0.6 + 0.14 + 0.08, 0.0, 0.12)),
    )
    chair_mesh = trimesh.util.concatenate([chair_mesh, footrest])
    checker = NaoCollisionChecker(DEFAULT_ARENA, chair_solid_boxes(chair_mesh))
    result = _check(chair_mesh, sitting_pose)
    assert result.accessible, result.reason
    assert result.step_in_from is not None and result.raise_at is None
    assert result.path[-1] == result.step_in_from
    assert not checker.collides_with_chair(result.step_in_from)
    assert checker.collides_with_chair(result.se2_goal)  # inside the walking clearance
    # The feet (0.10 m ahead of the NAO frame) stay behind the bar's front.
    bar_front_x = 0.6 + 0.14 + 0.09
    assert result.se2_goal.x - 0.10 >= bar_front_x - 1e-6


def test_chair_solid_holds_the_surface_and_closes_the_space_under_the_seat() -> None:
    chair_mesh, _ = _placed_chair(0.6, 0.1, 35.0)
    boxes = np.array(chair_solid_boxes(chair_mesh))
    lower, upper = boxes[:, 0], boxes[:, 1]

    # The solid is built from surface samples half a cell apart: a sliver of the surface
    # between them may stand out by a millimetre.
    def inside(points: np.ndarray, tolerance_m: float = 0.002) -> np.ndarray:
        within = (points[:, None] >= lower - tolerance_m) & (points[:, None] <= upper + tolerance_m)
        return np.any(np.all(within, axis=2), axis=1)

    surface = trimesh.sample.sample_surface(chair_mesh, 2000, seed=0)[0]
    assert inside(surface).all()
    # Under the seat (between the legs) is solid; beside the chair, a cell away, is not.
    under_seat = np.array([[0.6, 0.1, 0.05]])
    beside = chair_mesh.bounds[1] + np.array([collision.CHAIR_CELL_M + 0.005, 0.0, 0.0])
    beside[2] = 0.1
    assert inside(under_seat).all() and not inside(beside[None]).any()
    checker = NaoCollisionChecker(DEFAULT_ARENA, list(boxes))
    assert checker.collides_with_chair(SE2Pose(0.6, 0.1, 0.0))


def test_bad_inputs_raise_one_line_errors() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0)
    with pytest.raises(AccessibilityError, match="not finite"):
        _check(chair_mesh, SittingPose(np.array([np.nan, 0.0, 0.3]), 0.0))
    with pytest.raises(AccessibilityError, match="no triangles"):
        _check(trimesh.Trimesh(), sitting_pose)


def test_humanoid_pose_is_unchanged_type() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0)
    result = _check(chair_mesh, sitting_pose)
    assert all(isinstance(w, SE2Pose) for w in result.path)


def test_out_of_reach_preplan_slides_p_closer_and_retries(monkeypatch: pytest.MonkeyPatch) -> None:
    """A whole-body pre-plan stand-in that reaches only 0.29 m: the search tries the
    next sitting point closer to the NAO until it fits."""
    calls: list[float] = []
    reach_m = [0.29]

    def preplan_approach(chair_mesh, sitting_pose, se2_goal):
        forward = math.hypot(
            sitting_pose.position[0] - se2_goal.x, sitting_pose.position[1] - se2_goal.y
        )
        calls.append(forward)
        if forward > reach_m[0]:
            raise InfeasibleSeating("bear placement", f"out of reach: {forward:.2f} m forward")
        return None

    monkeypatch.setattr(preplan, "preplan_approach", preplan_approach)
    monkeypatch.setattr(preplan, "PREPLANS", preplan.PreplanMemo())  # no real answers kept

    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0, seat_depth_m=0.4)
    result = check_accessibility(chair_mesh, sitting_pose, START, DEFAULT_ARENA, seed=0)
    assert result.accessible, result.reason
    assert len(calls) >= 2 and calls[-1] <= 0.29 < calls[0]
    assert result.sitting_pose.position[0] > sitting_pose.position[0]

    # A seat too short to slide far enough: rejected with the pre-plan's reason.
    reach_m[0] = 0.12
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0, seat_depth_m=0.2)
    result = check_accessibility(chair_mesh, sitting_pose, START, DEFAULT_ARENA, seed=0)
    assert not result.accessible and "out of reach" in result.reason


def test_seat_of_slats_is_found_under_a_gap_and_ends_at_its_front_edge() -> None:
    # Slats 3 cm wide with 3 cm gaps, running across the sitting direction (+x), seat
    # top at 0.24 m from x = -0.15 to 0.12.
    slats = [
        trimesh.creation.box(
            extents=(0.03, 0.3, 0.02),
            transform=trimesh.transformations.translation_matrix((x, 0.0, 0.23)),
        )
        for x in np.arange(-0.135, 0.136, 0.06)
    ]
    seat = trimesh.util.concatenate(slats)
    in_a_gap = np.array([[-0.105, 0.0]])
    assert seat_support_heights(seat, in_a_gap, 0.3)[0] == pytest.approx(0.24)
    assert np.isnan(seat_support_heights(seat, np.array([[0.25, 0.0]]), 0.3)[0])
    p = SittingPose(np.array([-0.105, 0.0, 0.29]), 0.0)
    moved, slide_m = slide_on_seat(seat, p, 1.0)
    # Slides to BEAR_EDGE_MARGIN_M behind the front edge (to its 1 mm), not past it.
    assert 0.12 - BEAR_EDGE_MARGIN_M - 0.002 <= moved.position[0] <= 0.12 - BEAR_EDGE_MARGIN_M
    assert moved.position[2] == pytest.approx(0.29)
    assert slide_m == pytest.approx(moved.position[0] - p.position[0])


def _flat_seat(front_m: float, back_m: float = -0.15) -> trimesh.Trimesh:
    """A flat seat slab, its top 0.24 m high, from x = ``back_m`` to ``front_m``."""
    return trimesh.creation.box(
        extents=(front_m - back_m, 0.3, 0.02),
        transform=trimesh.transformations.translation_matrix(((front_m + back_m) / 2, 0, 0.23)),
    )


def test_p_nearer_the_front_edge_than_the_margin_goes_deeper_by_the_shortfall() -> None:
    # p 3 cm behind the front edge: the bear, smaller than the imagined child and heavier
    # ahead of its seat point, goes back until its margin to the edge holds.
    p = SittingPose(np.array([0.09, 0.0, 0.29]), 0.0)
    ray = seat_ray(_flat_seat(0.12), p)
    shortfall = BEAR_EDGE_MARGIN_M - 0.03
    assert len(ray.slides_m) == 1 and ray.seat_seen
    assert -shortfall - 0.01 - 1e-9 <= ray.slides_m[0] <= -shortfall
    moved, slide_m = slide_on_seat(_flat_seat(0.12), p, 0.03)
    assert slide_m == pytest.approx(ray.slides_m[0]) and moved.position[0] < p.position[0]
    assert 0.12 - moved.position[0] >= BEAR_EDGE_MARGIN_M


def test_p_near_the_edge_of_a_seat_too_shallow_to_go_deeper_stays() -> None:
    # The seat behind p ends 2 cm behind it: no room to go back, the child sat at p.
    p = SittingPose(np.array([0.09, 0.0, 0.29]), 0.0)
    ray = seat_ray(_flat_seat(0.12, back_m=0.07), p)
    assert len(ray.slides_m) == 1 and ray.slides_m[0] == pytest.approx(0.0, abs=1e-9)


def _seat_with_a_lower_front(step_down_m: float) -> trimesh.Trimesh:
    """A seat 0.24 m high from x = -0.15 to 0.05 and, from 0.05 to 0.15, a strip lower by
    ``step_down_m`` (a rounded or waterfall front)."""
    back = trimesh.creation.box(
        extents=(0.2, 0.3, 0.02),
        transform=trimesh.transformations.translation_matrix((-0.05, 0, 0.23)),
    )
    front_top = 0.24 - step_down_m
    front = trimesh.creation.box(
        extents=(0.1, 0.3, 0.02),
        transform=trimesh.transformations.translation_matrix((0.1, 0, front_top - 0.01)),
    )
    return trimesh.util.concatenate([back, front])


@pytest.mark.parametrize("step_down_m", [0.005, 0.02])
def test_a_seat_that_falls_away_at_its_front_ends_where_it_falls(step_down_m: float) -> None:
    p = SittingPose(np.array([-0.1, 0.0, 0.29]), 0.0)
    moved, _ = slide_on_seat(_seat_with_a_lower_front(step_down_m), p, 1.0)
    # A step the bear's torso rests across is still the seat; off a deeper one the bear
    # would lean forward, so the seat ends at the step.
    edge_m = 0.15 if step_down_m <= SEAT_DROP_TOLERANCE_M else 0.05
    assert edge_m - BEAR_EDGE_MARGIN_M - 0.002 <= moved.position[0] <= edge_m - BEAR_EDGE_MARGIN_M


def test_nao_too_close_for_the_carried_bear_steps_back_along_the_ray() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.0, 0.0)
    nominal = check_accessibility(
        chair_mesh, sitting_pose, START, DEFAULT_ARENA, seed=0, seating_validator=_anywhere
    )
    needed_x = nominal.se2_goal.x + 0.03
    asked: list[float] = []

    def bear_in_the_chair_when_close(chair_mesh, pose, se2_goal) -> SeatingCheck:
        asked.append(se2_goal.x)
        if se2_goal.x < needed_x - 1e-9:
            return SeatingCheck("stance: the bear is in the chair", too_close=True)
        return SeatingCheck()

    result = check_accessibility(
        chair_mesh,
        sitting_pose,
        START,
        DEFAULT_ARENA,
        seed=0,
        seating_validator=bear_in_the_chair_when_close,
    )
    assert result.accessible, result.reason
    assert needed_x <= result.se2_goal.x < needed_x + STEP_M + 1e-9
    assert result.se2_goal.y == pytest.approx(nominal.se2_goal.y)
    assert result.se2_goal.theta == pytest.approx(nominal.se2_goal.theta)
    assert result.path[-1] == result.se2_goal
    # Each refused stance was asked about once: nearer ones are not asked again.
    assert len(asked) == len(set(np.round(asked, 6)))


def test_accessible_sitting_yaws_leave_room_to_stand_inside_the_arena() -> None:
    from bearchair.core.arena import (
        ACCESSIBLE_TOLERANCE_RAD,
        STANDING_MARGIN_M,
        STANDING_ROOM_M,
        accessible_sitting_yaws,
    )

    start = DEFAULT_ARENA.humanoid_start
    for centre in ((0.6, 0.0), (0.85, 0.25), (0.35, -0.25)):
        yaws = accessible_sitting_yaws(DEFAULT_ARENA, centre)
        assert len(yaws) > 0
        toward = math.atan2(start.y - centre[1], start.x - centre[0])
        assert np.all(np.abs(yaws - toward) <= ACCESSIBLE_TOLERANCE_RAD + 1e-9)
        for distance in np.linspace(*STANDING_ROOM_M, 4):
            front = np.array(centre) + distance * np.c_[np.cos(yaws), np.sin(yaws)]
            assert all(DEFAULT_ARENA.contains(x, y, STANDING_MARGIN_M) for x, y in front)
    # Beside the arena's side edge, turning toward that edge is excluded.
    yaws = accessible_sitting_yaws(DEFAULT_ARENA, (0.85, 0.25))
    assert yaws.max() < math.radians(10.0)


def test_a_raised_approach_ends_the_path_where_the_bear_is_raised() -> None:
    chair_mesh, sitting_pose = _placed_chair(0.6, 0.1, 20.0)

    def raise_first(chair_mesh, sitting_pose, se2_goal) -> SeatingCheck:
        return SeatingCheck(raise_at=stepped_back(se2_goal, 0.06))

    result = check_accessibility(
        chair_mesh, sitting_pose, START, DEFAULT_ARENA, seed=0, seating_validator=raise_first
    )
    assert result.accessible, result.reason
    assert result.raise_at == stepped_back(result.se2_goal, 0.06)
    assert result.path[-1] == result.raise_at
    assert result.to_json()["raise_at"]["x_m"] == pytest.approx(result.raise_at.x, abs=1e-3)


def _seat_with_hole(hole_half_m: float, open_to_front: bool) -> trimesh.Trimesh:
    """A 0.3 x 0.3 m seat top at 0.24 m (centred at the origin, front at +x) with a square
    hole in the middle, as a scan that lost part of the seat leaves it."""
    pieces = []
    edges = [-0.15, -hole_half_m, hole_half_m, 0.15]
    for i in range(3):
        for j in range(3):
            if i == j == 1 or (open_to_front and j == 1 and i == 2):
                continue
            x0, x1, y0, y1 = edges[i], edges[i + 1], edges[j], edges[j + 1]
            pieces.append(
                trimesh.creation.box(
                    extents=(x1 - x0, y1 - y0, 0.02),
                    transform=trimesh.transformations.translation_matrix(
                        ((x0 + x1) / 2, (y0 + y1) / 2, 0.23)
                    ),
                )
            )
    return trimesh.util.concatenate(pieces)


def test_a_hole_in_the_scanned_seat_is_seat_when_the_seat_encloses_it() -> None:
    p = SittingPose(np.array([-0.02, 0.0, 0.29]), 0.0)
    moved, _ = slide_on_seat(_seat_with_hole(0.07, open_to_front=False), p, 1.0)
    # The hole (14 cm wide) is filled: p slides to the bear's margin behind the front edge.
    assert 0.15 - BEAR_EDGE_MARGIN_M - 0.002 <= moved.position[0] <= 0.15 - BEAR_EDGE_MARGIN_M
    assert moved.position[2] == pytest.approx(0.29)


def test_a_sitting_point_over_a_lost_seat_top_stays_where_it_was_imagined() -> None:
    p = SittingPose(np.array([-0.02, 0.0, 0.29]), 0.0)
    seat = _seat_with_hole(0.07, open_to_front=True)
    moved, slide_m = slide_on_seat(seat, p, 1.0)
    assert slide_m == 0.0 and np.array_equal(moved.position, p.position)
    ray = seat_ray(seat, p)
    assert ray.seat_heights_m == pytest.approx([0.24]) and not ray.seat_seen
    assert seat_ray(_seat_with_hole(0.07, open_to_front=False), p).seat_seen
    nothing = check_seat_reachable(seat, SittingPose(np.array([1.0, 1.0, 0.29]), 0.0))
    assert not nothing.reachable and nothing.reason == "no seat under the sitting position"


def test_a_ray_turned_about_p_is_searched_when_the_imagined_one_fails() -> None:
    from bearchair.core.geometry import wrap_angle
    from bearchair.skills.planning.stance import MAX_PREPLANS, PREPLANS_PER_TURN, TURNS_RAD

    chair_mesh, sitting_pose = _placed_chair(0.6, 0.1, 30.0)
    checker = NaoCollisionChecker(DEFAULT_ARENA, chair_solid_boxes(chair_mesh))
    asked: list[float] = []

    def off_the_imagined_ray_only(chair, pose, se2_goal) -> SeatingCheck:
        turned = wrap_angle(pose.yaw - sitting_pose.yaw)
        asked.append(turned)
        if abs(turned) < math.radians(4.0):
            return SeatingCheck("bear placement: out of reach", bear_placement=True)
        return SeatingCheck()

    choice = choose_stance(chair_mesh, sitting_pose, checker, off_the_imagined_ray_only)
    assert choice.se2_goal is not None, choice.reason
    assert choice.turned_rad == pytest.approx(TURNS_RAD[0])
    assert choice.sitting_pose.yaw == pytest.approx(wrap_angle(sitting_pose.yaw + TURNS_RAD[0]))
    assert math.cos(choice.se2_goal.theta - (choice.sitting_pose.yaw + math.pi)) > 0.9999
    assert asked[0] == pytest.approx(0.0) and choice.preplans == len(asked)

    asked.clear()
    nowhere = choose_stance(
        chair_mesh, sitting_pose, checker, lambda *_: SeatingCheck("chair collision: knee")
    )
    assert nowhere.se2_goal is None and nowhere.turned_rad == 0.0
    assert nowhere.reason == "chair collision: knee"  # the imagined ray's reason
    assert nowhere.preplans <= MAX_PREPLANS + PREPLANS_PER_TURN * len(TURNS_RAD)


def test_p_off_the_middle_between_armrests_is_centred_for_the_hands() -> None:
    from bearchair.skills.planning.chair_along_ray import centred_between_rails
    from bearchair.skills.planning.stance import planner_seat_top

    # Armrest panels 0.15 m over the seat (above the hands), inner faces 0.13 m either
    # side of the middle: the band of the hands (0.11 m, plus 1 cm) fits between them.
    armchair, middle = _placed_chair(0.6, 0.1, 30.0, armrest_height_m=0.39)
    left = np.array([-math.sin(middle.yaw), math.cos(middle.yaw), 0.0])
    off_middle = SittingPose(middle.position + 0.025 * left, middle.yaw)
    seat_top = planner_seat_top(armchair, off_middle, seat_ray(armchair, off_middle))
    centred = centred_between_rails(armchair, off_middle, seat_top)
    assert np.dot(centred.position - middle.position, left) == pytest.approx(0.0, abs=0.005)
    assert centred.yaw == off_middle.yaw
    assert centred.position[2] == off_middle.position[2]

    reachable = check_seat_reachable(armchair, off_middle)
    assert reachable.reachable, reachable.reason
    assert reachable.centred_m == pytest.approx(0.025, abs=0.005)

    # Armrests 0.23 m apart hold the band (0.22 m) but not its clearance on both sides:
    # p goes to their middle, the most room either side. Armrests 0.21 m apart leave the
    # band no room wherever p is; no armrests, nothing to move for.
    snug, snug_middle = _placed_chair(0.6, 0.1, 30.0, seat_width_m=0.29, armrest_height_m=0.39)
    snug_off = SittingPose(snug_middle.position + 0.01 * left, middle.yaw)
    top = planner_seat_top(snug, snug_off, seat_ray(snug, snug_off))
    snug_centred = centred_between_rails(snug, snug_off, top)
    assert np.dot(snug_centred.position - snug_middle.position, left) == pytest.approx(
        0.0, abs=0.002
    )
    narrow, narrow_middle = _placed_chair(0.6, 0.1, 30.0, seat_width_m=0.27, armrest_height_m=0.39)
    narrow_off = SittingPose(narrow_middle.position + 0.025 * left, middle.yaw)
    top = planner_seat_top(narrow, narrow_off, seat_ray(narrow, narrow_off))
    assert centred_between_rails(narrow, narrow_off, top) is narrow_off
    plain, plain_middle = _placed_chair(0.6, 0.1, 30.0)
    plain_off = SittingPose(plain_middle.position + 0.025 * left, middle.yaw)
    top = planner_seat_top(plain, plain_off, seat_ray(plain, plain_off))
    assert centred_between_rails(plain, plain_off, top) is plain_off
