"""The procedural chair generator: every family, its frame and its ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearchair.core.geometry import transform_points, yaw_transform
from bearchair.skills.planning.seat import seat_support_heights
from bearchair.testing.chairgen import (
    FAMILIES,
    SEAT_HEIGHT_RANGE_M,
    generate_chair,
    generate_chairs,
)


@pytest.mark.parametrize("family", FAMILIES)
def test_each_family_stands_in_the_calibration_frame_with_its_seat_where_it_says(family):
    for seed in range(3):
        chair = generate_chair(seed, family)
        bounds = chair.mesh.bounds
        assert bounds[0, 2] == pytest.approx(0.0, abs=1e-9)
        assert np.allclose((bounds[0, :2] + bounds[1, :2]) / 2.0, 0.0, atol=1e-9)
        low, high = SEAT_HEIGHT_RANGE_M
        assert low - 1e-9 <= chair.seat_height_m <= high + 1e-9
        # The seat's top is the first surface below, just behind its front edge.
        x = chair.seat_front_x_m - 0.03
        top = seat_support_heights(chair.mesh, np.array([[x, 0.0]]), chair.seat_height_m + 0.02)
        assert top[0] == pytest.approx(chair.seat_height_m, abs=1e-6)
        assert chair.name == f"gen-{family}-{seed:04d}"


def test_the_same_seed_gives_the_same_chair_and_another_seed_another():
    first, again, other = (
        generate_chair(7, "armchair"),
        generate_chair(7, "armchair"),
        generate_chair(8, "armchair"),
    )
    assert np.array_equal(first.mesh.vertices, again.mesh.vertices)
    assert first.seat_height_m != other.seat_height_m


def test_stools_and_benches_have_no_front_and_chairs_face_plus_x():
    assert generate_chair(1, "stool").front_yaw_rad is None
    assert generate_chair(1, "bench").front_yaw_rad is None
    chair = generate_chair(1, "four_legs")
    assert chair.front_yaw_rad == 0.0
    # The backrest stands behind the seat (at -x), above it.
    above = chair.mesh.vertices[chair.mesh.vertices[:, 2] > chair.seat_height_m + 0.05]
    assert above[:, 0].max() < chair.seat_front_x_m - chair.seat_depth_m / 2.0


def test_the_true_sitting_pose_is_over_the_seat_s_middle_facing_the_front_in_the_world():
    chair = generate_chair(2, "armchair")
    T_world_chair = yaw_transform(math.pi / 2.0, np.array([1.0, -0.5, 0.0]))
    pose = chair.true_sitting_pose(T_world_chair)
    assert pose.yaw == pytest.approx(math.pi / 2.0)
    # Back in the chair frame, the point lies on the seat's top, halfway along its depth.
    p_chair = transform_points(np.linalg.inv(T_world_chair), pose.position[None, :])[0]
    assert p_chair[0] == pytest.approx(chair.seat_front_x_m - chair.seat_depth_m / 2.0)
    top = seat_support_heights(chair.mesh, p_chair[None, :2], chair.seat_height_m + 0.02)
    assert top[0] == pytest.approx(p_chair[2], abs=1e-6)


def test_a_footrest_sticks_out_in_front_of_the_seat():
    chair = generate_chair(4, "footrest")
    assert chair.front_protrusion_m > 0.04
    low = chair.mesh.vertices[chair.mesh.vertices[:, 2] < chair.seat_height_m - 0.05]
    assert low[:, 0].max() == pytest.approx(
        chair.seat_front_x_m + chair.front_protrusion_m, abs=0.011
    )


def test_a_campaign_of_chairs_cycles_through_every_family():
    chairs = generate_chairs(len(FAMILIES) * 2, seed=100)
    assert [c.family for c in chairs] == list(FAMILIES) * 2
    assert len({c.seed for c in chairs}) == len(chairs)


def test_an_unknown_family_is_refused_by_name():
    with pytest.raises(ValueError, match="unknown chair family 'throne'"):
        generate_chair(0, "throne")
