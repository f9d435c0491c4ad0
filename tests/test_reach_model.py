"""The reach model against the whole-body model it is computed from and the planner."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.nao_carrying import BEAR_SEAT_CLEARANCE_M, LOW_SEAT_RELEASE_GAP_M
from bearchair.core.se2 import SE2Pose
from bearchair.skills.imagination.sam import SamThresholds
from bearchair.skills.planning.wholebody import InfeasibleSeating, preplan_approach
from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.postures import HIGH_RAISED_POSTURE, RAISED_POSTURES
from bearchair.skills.planning.wholebody.raising import raised_posture
from bearchair.skills.planning.wholebody.reach_model import (
    ReachModel,
    raised_carry_height_m,
    reach_model,
    release_heights,
    solve_reach_cell,
)
from bearchair.skills.planning.wholebody.release_choice import planned_release_pose
from bearchair.skills.planning.wholebody.release_height import (
    HIP_POSTURE_MARGIN_M,
    NO_LOW_SEATS,
    ReleaseHeights,
)
from bearchair.skills.planning.wholebody.seating import plan_seating

PLANNER_TOLERANCE_M = 0.005
"""The planner seats the bear wherever the model reaches, less this (metres)."""
BEYOND_M = 0.03
"""... and refuses the placement this far (metres) beyond the model's reach."""

# (seat height, seat front ahead of the NAO), metres: low, middle and high seats, the
# feet near the seat and farther back.
CASES = [(0.215, 0.152), (0.239, 0.185), (0.336, 0.208)]


def _chair_in_front_of_the_nao(seat_height_m: float, seat_front_m: float) -> trimesh.Trimesh:
    """A box chair facing the NAO (which stands at the origin facing +x), its seat's
    front ``seat_front_m`` ahead."""
    depth = 0.45
    chair = box_chair_mesh(
        seat_height_m=seat_height_m, seat_depth_m=depth, overall_height_m=seat_height_m + 0.3
    )
    chair.apply_transform(trimesh.transformations.rotation_matrix(math.pi, (0, 0, 1)))
    chair.apply_translation((seat_front_m + depth / 2.0, 0.0, 0.0))
    return chair


def _preplan(seat_height_m: float, seat_front_m: float, forward_m: float) -> None:
    chair = _chair_in_front_of_the_nao(seat_height_m, seat_front_m)
    pose = SittingPose(np.array([forward_m, 0.0, seat_height_m + 0.05]), math.pi)
    preplan_approach(chair, pose, SE2Pose(0.0, 0.0, 0.0))


@pytest.mark.parametrize(("height", "front"), [(0.25, 0.20), (0.33, 0.10), (0.40, 0.16)])
def test_the_shipped_table_is_what_the_whole_body_model_gives(height, front):
    model = reach_model()
    i = int(np.argmin(np.abs(model.seat_heights_m - height)))
    j = int(np.argmin(np.abs(model.seat_fronts_m - front)))
    assert solve_reach_cell(height, front) == pytest.approx(model.max_forward_m[i, j], abs=0.002)


def test_the_release_heights_are_the_whole_body_model_s():
    shipped, solved = reach_model().release, release_heights()
    assert np.allclose(shipped.free_reach_m, solved.free_reach_m, atol=0.002, equal_nan=True)
    # The NAO's knees stop its crouch a little over 0.16 m; bent at the hips it reaches
    # 5 cm or more farther than crouching.
    assert 0.15 <= shipped.lowest_height_m < shipped.hip_height_m <= 0.20
    jump_at = int(np.searchsorted(shipped.heights_m, shipped.hip_height_m - HIP_POSTURE_MARGIN_M))
    assert shipped.free_reach_m[jump_at] - shipped.free_reach_m[jump_at - 1] >= 0.05


def test_the_bear_is_let_go_higher_only_over_seats_below_the_bent_hip_postures():
    model = reach_model()
    z_hip, z_low = model.release.hip_height_m, model.release.lowest_height_m
    for seat in (0.19, 0.25, 0.40):
        assert model.release_height_m(seat) == pytest.approx(seat + BEAR_SEAT_CLEARANCE_M)
    # Below, at z_hip while the drop stays within the gap; then from the crouch; then none.
    assert model.release_height_m(z_hip - BEAR_SEAT_CLEARANCE_M - 0.001) == z_hip
    assert model.release_height_m(z_hip - LOW_SEAT_RELEASE_GAP_M) == z_hip
    assert model.release_height_m(z_hip - LOW_SEAT_RELEASE_GAP_M - 0.001) == z_low
    assert math.isnan(model.release_height_m(z_low - LOW_SEAT_RELEASE_GAP_M - 0.001))
    assert math.isnan(solve_reach_cell(z_low - LOW_SEAT_RELEASE_GAP_M - 0.001, 0.25))
    assert model.min_seat_height_m() >= z_low - LOW_SEAT_RELEASE_GAP_M


@pytest.mark.parametrize("height", [0.145, 0.165])
def test_the_planner_lets_the_bear_go_bent_at_the_hips_over_a_low_seat(height):
    front = 0.185
    d_max = reach_model().max_forward(height, front)
    assert d_max > 0.28  # the bent-hip postures' reach, not the crouch's 0.22-0.24 m
    chair = _chair_in_front_of_the_nao(height, front)
    pose = SittingPose(np.array([d_max - PLANNER_TOLERANCE_M, 0.0, height + 0.05]), math.pi)
    plan = plan_seating(chair, pose, SE2Pose(0.0, 0.0, 0.0))
    release = planned_release_pose(plan, SE2Pose(0.0, 0.0, 0.0))
    z_hip = reach_model().release.hip_height_m
    assert z_hip - 0.016 <= release[2, 3] <= z_hip + 0.001
    assert release[2, 3] - height <= LOW_SEAT_RELEASE_GAP_M


@pytest.mark.parametrize(("height", "front"), CASES)
def test_the_planner_seats_the_bear_where_the_model_reaches(height, front):
    d_max = reach_model().max_forward(height, front)
    _preplan(height, front, d_max - PLANNER_TOLERANCE_M)


@pytest.mark.parametrize(("height", "front"), CASES)
def test_the_planner_refuses_the_bear_beyond_the_model_reach(height, front):
    d_max = reach_model().max_forward(height, front)
    with pytest.raises(InfeasibleSeating) as refused:
        _preplan(height, front, d_max + BEYOND_M)
    assert refused.value.constraint == "bear placement"


def test_lookup_interpolates_and_stops_where_a_neighbour_has_no_posture():
    heights = np.array([0.2, 0.3])
    fronts = np.array([0.1, 0.2])
    model = ReachModel(heights, fronts, np.array([[0.30, 0.32], [0.28, 0.30]]), 0.4)
    assert model.max_forward(0.2, 0.1) == pytest.approx(0.30)
    assert model.max_forward(0.25, 0.15) == pytest.approx(0.30)  # bilinear
    assert model.max_forward(0.2, 0.5) == pytest.approx(0.32)  # beyond the grid: last column
    assert math.isnan(model.max_forward(0.2, 0.05))  # feet in the seat
    assert not model.reachable(0.2, 0.1, 0.31) and model.reachable(0.2, 0.1, 0.29)
    holed = model._replace(max_forward_m=np.array([[0.30, 0.32], [0.28, np.nan]]))
    assert math.isnan(holed.max_forward(0.25, 0.15))  # a neighbour without a posture
    assert holed.max_forward(0.2, 0.15) == pytest.approx(0.31)  # on the row that has both


def test_seats_higher_than_the_raised_bear_are_out_of_reach():
    model = reach_model()
    assert model.carry_height_m == pytest.approx(raised_carry_height_m(), abs=1e-4)
    highest = model.max_seat_height_m()
    # The NAO lifts the bear's base 0.43 m high at most; postures exist above that.
    assert highest == pytest.approx(model.carry_height_m - 0.003, abs=1e-9)
    # ... which reaches every seat the imagination sits a child on (the pelvis at most
    # H_max, 0.075 m over the seat).
    assert highest >= SamThresholds().height_max_m - 0.075
    assert not np.isnan(model.max_forward_m[model.seat_heights_m > highest + 0.02]).all()
    assert math.isnan(model.max_forward(highest + 0.01, 0.3))


@pytest.mark.parametrize(("seat_top", "expected"), [(0.30, 0), (0.39, 0), (0.41, 1), (0.425, 1)])
def test_the_nao_raises_the_bear_to_the_lowest_posture_that_clears_the_seat(seat_top, expected):
    profile = ChairProfile(0.25, seat_top, 10.0, seat_top)
    assert raised_posture(profile) is RAISED_POSTURES[expected]


def test_a_seat_above_the_first_raised_bear_is_seated_from_the_higher_one():
    height, front = 0.415, 0.16  # the carried bear (0.16-0.20 m ahead) would be in it
    chair = _chair_in_front_of_the_nao(height, front)
    d_max = reach_model().max_forward(height, front)
    pose = SittingPose(np.array([d_max - PLANNER_TOLERANCE_M, 0.0, height + 0.05]), math.pi)
    assert preplan_approach(chair, pose, SE2Pose(0.0, 0.0, 0.0)) is not None  # raised
    plan = plan_seating(chair, pose, SE2Pose(0.0, 0.0, 0.0), raised=True)
    first = np.asarray(plan.positions_rad)[0]
    shoulder = first[list(plan.joint_names).index("LShoulderPitch")]
    assert shoulder == pytest.approx(HIGH_RAISED_POSTURE[3], abs=0.02)


def test_a_seat_too_low_to_let_the_bear_go_on_is_infeasible_not_an_error():
    # A seat top 3 cm over the floor (a base plate under p, a toy chair): no release height.
    height = 0.03
    chair = _chair_in_front_of_the_nao(height, 0.2)
    pose = SittingPose(np.array([0.3, 0.0, height + 0.05]), math.pi)
    assert math.isnan(reach_model().release_height_m(height))
    with pytest.raises(InfeasibleSeating) as refused:
        plan_seating(chair, pose, SE2Pose(0.0, 0.0, 0.0))
    assert refused.value.constraint == "bear placement"
    assert "seat too low to let the bear go on: its top 0.030 m" in str(refused.value)


def test_the_release_height_rule_on_a_free_reach_curve():
    # No posture below 0.17 m, a crouch reaching 0.22 m up to 0.1825 m, then bent at the hips.
    heights = np.round(np.arange(0.15, 0.3001, 0.0025), 4)
    reach = np.where(heights < 0.17, np.nan, np.where(heights < 0.185, 0.22, 0.29 + heights / 10))
    release = ReleaseHeights(heights, reach)
    z_hip = 0.185 + HIP_POSTURE_MARGIN_M
    assert release.lowest_height_m == pytest.approx(0.17)
    assert release.hip_height_m == pytest.approx(z_hip)
    c, gap = BEAR_SEAT_CLEARANCE_M, LOW_SEAT_RELEASE_GAP_M
    assert release.release_height_m(0.25) == pytest.approx(0.25 + c)  # the usual 1 cm
    assert release.release_height_m(z_hip - c) == pytest.approx(z_hip)  # 1 cm over: usual
    assert release.release_height_m(z_hip - c - 0.001) == pytest.approx(z_hip)  # bent
    assert release.release_height_m(z_hip - gap) == pytest.approx(z_hip)
    assert release.release_height_m(z_hip - gap - 0.001) == pytest.approx(0.17)  # crouch
    assert release.release_height_m(0.17 - gap) == pytest.approx(0.17)
    assert math.isnan(release.release_height_m(0.17 - gap - 0.001))  # none
    assert NO_LOW_SEATS.release_height_m(0.05) == pytest.approx(0.05 + c)
