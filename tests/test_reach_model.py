"""The reach model against the whole-body model it is computed from and the planner."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.wholebody import InfeasibleSeating, preplan_approach
from bearchair.skills.planning.wholebody.reach_model import (
    ReachModel,
    raised_carry_height_m,
    reach_model,
    solve_reach_cell,
)

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


def test_no_posture_reaches_a_seat_below_the_crouch():
    assert math.isnan(solve_reach_cell(0.12, 0.25))


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
    # The NAO lifts the bear's base 0.40 m high at most; postures exist above that.
    assert highest == pytest.approx(model.carry_height_m - 0.003, abs=1e-9)
    assert not np.isnan(model.max_forward_m[model.seat_heights_m > highest + 0.02]).all()
    assert math.isnan(model.max_forward(highest + 0.01, 0.3))
    assert 0.14 <= model.min_seat_height_m() <= 0.18
