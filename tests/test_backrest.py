"""The backrest's sitting direction: generated chairs of every family, the box chair, and
how it checks an imagined direction (no physics: the cue reads the mesh alone)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from bearchair.core.geometry import SittingPose, make_transform, rot_z, wrap_angle
from bearchair.core.meshes import box_chair_mesh
from bearchair.skills.imagination.backrest import (
    AGREEMENT_RAD,
    MIRROR_MARGIN,
    backrest_yaw,
    check_direction,
)
from bearchair.testing.chairgen import FAMILIES, generate_chair

BACKLESS = ("stool", "bench")


def _turned(mesh, yaw_rad: float, xy=(0.4, -0.2)):
    return mesh.copy().apply_transform(make_transform(rot_z(yaw_rad), np.array([*xy, 0.0])))


def _pose_over_seat(chair, yaw_rad: float, xy=(0.4, -0.2)) -> SittingPose:
    """p over the middle of the generated chair's seat, 5 cm above it, moved like the mesh."""
    p_chair = np.array([chair.seat_front_x_m - chair.seat_depth_m / 2.0, 0.0])
    p = rot_z(yaw_rad)[:2, :2] @ p_chair + np.asarray(xy)
    return SittingPose(np.array([*p, chair.seat_height_m + 0.05]), yaw_rad)


@pytest.mark.parametrize("family", [f for f in FAMILIES if f not in BACKLESS])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_chair_with_a_back_faces_away_from_it(family: str, seed: int) -> None:
    chair = generate_chair(seed, family)
    yaw = math.radians(40.0 * seed - 100.0)
    cue = backrest_yaw(_turned(chair.mesh, yaw), _pose_over_seat(chair, yaw))
    assert cue is not None
    assert abs(math.degrees(wrap_angle(cue[0] - (yaw + chair.front_yaw_rad)))) < 5.0


@pytest.mark.parametrize("family", BACKLESS)
def test_a_seat_with_nothing_above_it_gives_no_direction(family: str) -> None:
    chair = generate_chair(3, family)
    assert backrest_yaw(chair.mesh, _pose_over_seat(chair, 0.0, (0.0, 0.0))) is None


def test_a_direction_within_the_agreement_stands_and_one_beyond_it_is_replaced() -> None:
    chair_mesh = _turned(box_chair_mesh(), math.radians(70.0), (0.0, 0.0))
    p = np.array([0.0, 0.0, 0.29])
    front = math.radians(70.0)  # the box chair faces +x before it is turned
    near = front + AGREEMENT_RAD - math.radians(5.0)
    kept, check = check_direction(chair_mesh, SittingPose(p, near))
    assert check is not None and not check.used and kept.yaw == near
    off = front + math.radians(45.0)  # a vote one rotation off
    replaced, check = check_direction(chair_mesh, SittingPose(p, off))
    assert check.used and abs(math.degrees(wrap_angle(replaced.yaw - front))) < 3.0
    assert np.array_equal(replaced.position, p)
    assert math.degrees(check.disagreement_rad) == pytest.approx(45.0, abs=3.0)


def test_a_cue_pulled_sideways_by_one_armrest_yields_to_the_chairs_mirror_plane() -> None:
    # The scan saw one armrest (a side panel 0.22 m high along +y) and not the other: the
    # centroid of what rises above the seat moves toward it, past the agreement.
    panel = trimesh.creation.box((0.28, 0.03, 0.22))
    panel.apply_translation((0.0, 0.145, 0.35))
    chair_mesh = trimesh.util.concatenate([box_chair_mesh(), panel])
    pose = SittingPose(np.array([0.0, 0.0, 0.29]), 0.0)  # the box chair faces +x
    kept, check = check_direction(chair_mesh, pose)
    assert check is not None and abs(check.disagreement_rad) > AGREEMENT_RAD
    assert not check.used and kept == pose
    assert check.mirror_vote > check.mirror_back + MIRROR_MARGIN


def test_a_cue_beyond_the_agreement_on_a_symmetric_chair_mirrors_it_as_well() -> None:
    chair_mesh = box_chair_mesh()
    _, check = check_direction(chair_mesh, SittingPose(np.array([0.0, 0.0, 0.29]), 0.8))
    assert check.used
    assert check.mirror_back > 0.8 > check.mirror_vote + MIRROR_MARGIN


def test_no_seat_under_p_gives_no_check() -> None:
    pose = SittingPose(np.array([3.0, 3.0, 0.3]), 0.0)
    assert check_direction(box_chair_mesh(), pose) == (pose, None)
