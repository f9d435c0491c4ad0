"""The scan's level surfaces, and the refusal of a chair whose level surfaces all lie
beyond the seat heights the NAO places a bear on (where no sitting was imagined)."""

from __future__ import annotations

import math
from typing import cast

import numpy as np
import pytest
import trimesh

from bearchair.skills.planning.seat import SEAT_HEIGHT_TOLERANCE_M, SUPPORT_RADIUS_M, level_surfaces
from bearchair.skills.planning.stance import check_seat_levels
from bearchair.skills.planning.wholebody.reach_model import reach_model
from bearchair.testing.chairgen_families import box

SEAT_M = 0.30
"""The test chairs' seat side, metres."""


def chair(seat_top_m: float, armrest_width_m: float = 0.0, shelf_top_m: float = 0.0):
    """A seat ``SEAT_M`` square on four legs with a backrest; armrests this wide (0: none)
    beside it, 0.18 m over it; a shelf between the legs topped this high (0: none)."""
    half = SEAT_M / 2.0
    parts = [box((SEAT_M, SEAT_M, 0.03), (0.0, 0.0, seat_top_m - 0.015))]
    for x in (-half + 0.015, half - 0.015):
        for y in (-half + 0.015, half - 0.015):
            parts.append(box((0.03, 0.03, seat_top_m - 0.03), (x, y, (seat_top_m - 0.03) / 2)))
    parts.append(box((0.02, SEAT_M, 0.30), (-half - 0.01, 0.0, seat_top_m + 0.15)))
    if armrest_width_m:
        for y in (-half - armrest_width_m / 2, half + armrest_width_m / 2):
            parts.append(box((SEAT_M, armrest_width_m, 0.02), (0.0, y, seat_top_m + 0.18)))
    if shelf_top_m:
        parts.append(box((SEAT_M - 0.06, SEAT_M - 0.06, 0.02), (0.0, 0.0, shelf_top_m - 0.01)))
    return cast(trimesh.Trimesh, trimesh.util.concatenate(parts))


def test_the_seat_is_the_largest_level_surface_and_narrow_tops_are_not_surfaces():
    levels = level_surfaces(chair(0.44, armrest_width_m=2 * SUPPORT_RADIUS_M - 0.02))
    assert levels[0] == pytest.approx(0.44, abs=0.005)
    # The armrests (narrower than the bear's torso) and the backrest's edge hold nothing.
    assert len(levels) == 1


def test_a_torso_wide_armrest_is_a_surface_of_its_own():
    levels = level_surfaces(chair(0.30, armrest_width_m=2 * SUPPORT_RADIUS_M + 0.03))
    assert levels[0] == pytest.approx(0.30, abs=0.005)
    assert sorted(np.round(levels[1:], 2)) == [0.49, 0.49]  # their tops: 0.18 m + 1 cm over


def test_a_seat_above_the_nao_s_heights_is_refused_with_its_height():
    model = reach_model()
    seat_m = model.max_seat_height_m() + 2 * SEAT_HEIGHT_TOLERANCE_M
    verdict = check_seat_levels(chair(seat_m))
    assert not verdict.reachable
    assert verdict.seat_height_m == pytest.approx(seat_m, abs=0.005)
    assert verdict.reason == (
        f"no level surface the bear rests on within the NAO's seat heights "
        f"({model.min_seat_height_m():.3f}-{model.max_seat_height_m():.3f} m): the scan's lie "
        f"at {verdict.seat_height_m:.3f} m"
    )


def test_a_seat_within_the_nao_s_heights_rules_nothing_out():
    verdict = check_seat_levels(chair(0.30))
    assert verdict.reachable and verdict.reason == ""


def test_a_level_surface_within_the_heights_beside_a_high_seat_rules_nothing_out():
    side_table = box((SEAT_M, SEAT_M, 0.02), (SEAT_M + 0.05, 0.0, 0.24))
    verdict = check_seat_levels(
        cast(trimesh.Trimesh, trimesh.util.concatenate([chair(0.46), side_table]))
    )
    assert verdict.reachable


def test_a_shelf_under_a_high_seat_leaves_it_refused():
    # The shelf lies under the seat, where the bear has no room: only top surfaces count.
    verdict = check_seat_levels(chair(0.46, shelf_top_m=0.25))
    assert not verdict.reachable and verdict.reason.startswith("no level surface the bear")


def test_a_scan_with_no_level_surface_rules_nothing_out():
    # A seat tilted 30 deg: nothing level the torso rests on (a scan that lost the seat).
    tilted = box((SEAT_M, SEAT_M, 0.03), (0.0, 0.0, 0.45), rotation_y_rad=math.radians(30))
    assert len(level_surfaces(tilted)) == 0
    verdict = check_seat_levels(tilted)
    assert verdict.reachable and math.isnan(verdict.seat_height_m)


def test_rails_too_high_over_a_seat_within_reach_are_named_not_the_seat():
    from bearchair.core.geometry import SittingPose
    from bearchair.skills.planning.stance import check_seat_reachable

    seat_m, rail_top_m = 0.38, 0.50
    rails = [
        box((SEAT_M, 0.03, rail_top_m - seat_m), (0.0, side * 0.12, (rail_top_m + seat_m) / 2))
        for side in (-1, 1)
    ]
    mesh = cast(trimesh.Trimesh, trimesh.util.concatenate([chair(seat_m), *rails]))
    # Facing +x, away from the backrest, the pelvis 8 cm over the seat.
    verdict = check_seat_reachable(mesh, SittingPose(np.array([-0.05, 0.0, seat_m + 0.08]), 0.0))
    assert not verdict.reachable
    assert verdict.reason.startswith("chair too high in the NAO's way: the bear is carried over")
    assert f"(the seat under the sitting point is {seat_m:.3f} m)" in verdict.reason
    # The rails' inner faces 0.105 m either side of p: 0.030 m short of the hands' 0.240 m.
    assert verdict.reason.endswith(
        "the armrests or rails beside the sitting point stand 0.210 m apart, and the NAO's "
        "hands need 0.240 m between them to lower the bear there (0.030 m short)"
    )


def test_rails_that_leave_the_hands_room_are_not_called_short():
    from bearchair.skills.planning.chair_along_ray import rails_gap_reason

    assert rails_gap_reason(0.25) == ""
    assert rails_gap_reason(math.inf) == ""  # one side, or none, has a rail
    assert rails_gap_reason(0.2395).endswith("(0.001 m short)")
