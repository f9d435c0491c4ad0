"""The seat under the sitting point, from the scan: dished, sling, slatted and thin seats,
and seats deep between armrests (issue 27).

Each chair is generated (``bearchair.testing.chairgen``), rendered from the 9 scan views
in a synthetic scene with the Carmine's noise and reconstructed; the sitting point is put
from the generator's truth (the test's oracle, not the mission's), 8 cm over the seat and
60 % of its depth back from its front edge, where a child's pelvis is.
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np
import pytest
import trimesh

from bearchair.core.geometry import SittingPose, transform_points, yaw_transform
from bearchair.core.nao_carrying import BEAR_TORSO_DEPTH_M, PLACEMENT_TOLERANCE_M
from bearchair.hardware.bear_model import BEAR_PARTS, BEAR_TORSO_FOOTPRINT_M
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.skills.perception import ReconstructionConfig, reconstruct_chair
from bearchair.skills.perception.reconstruction import SUPPORT_TILT_RAD
from bearchair.skills.perception.views import SCAN_CONFIGURATIONS
from bearchair.skills.planning.seat import (
    SLAT_GAP_M,
    STEP_M,
    UNSEEN_SLIDE_M,
    seat_map,
    seat_ray,
)
from bearchair.testing.chairgen import GeneratedChair, generate_chair
from bearchair.testing.chairgen_families import box
from tests.helpers.scans import frames_of

T_WORLD_CHAIR = yaw_transform(0.6, np.array([0.58, 0.08, 0.0]))
"""Where the chair stands in the chair area: turned so that the arm sees it from behind
and from its side, as the perception tests place the box chair."""


def sitting_pose(chair: GeneratedChair) -> SittingPose:
    """The test's sitting point on a generated chair (its truth), world frame."""
    p = np.array([chair.seat_front_x_m - 0.6 * chair.seat_depth_m, 0.0, chair.seat_height_m + 0.08])
    return SittingPose(transform_points(T_WORLD_CHAIR, p[None])[0], 0.6)


_FRAMES: dict[tuple[str, int], list[RGBDFrame]] = {}
_SCANS: dict[tuple[str, int], trimesh.Trimesh] = {}


def frames(family: str, seed: int) -> list[RGBDFrame]:
    """The 9 scan views of a generated chair (rendered once per module)."""
    if (family, seed) not in _FRAMES:
        mesh = generate_chair(seed, family).mesh
        _FRAMES[family, seed] = frames_of(mesh, T_WORLD_CHAIR, SCAN_CONFIGURATIONS, seed=3)
    return _FRAMES[family, seed]


def scanned(family: str, seed: int) -> tuple[GeneratedChair, trimesh.Trimesh]:
    """A generated chair and its reconstructed mesh (fused once per module)."""
    if (family, seed) not in _SCANS:
        scan = reconstruct_chair(frames(family, seed), ReconstructionConfig())
        _SCANS[family, seed] = scan.chair_mesh
    return generate_chair(seed, family), _SCANS[family, seed]


@pytest.mark.parametrize(
    ("family", "seed"),
    [
        # Only the view from straight above sees the dish's floor behind p past the rim
        # and the back: the surfaces two views agree on lost 84 % of the seat within 8 cm
        # of p, and the mission failed in CheckSeatReachable.
        ("basket", 1),
        ("basket", 4),
        # The seat deep between the armrests and the back, seen whole by one view.
        ("armchair", 0),
        ("armchair", 1),
        # A sling, 6 mm of cloth sagging between its rails.
        ("x_frame", 0),
        # Slats 2-4 cm thick with 1-2.5 cm gaps.
        ("slatted", 0),
    ],
)
@pytest.mark.slow
def test_the_scan_has_the_seat_under_the_sitting_point(family, seed):
    chair, mesh = scanned(family, seed)
    pose = sitting_pose(chair)
    truth = chair.mesh.copy()
    truth.apply_transform(T_WORLD_CHAIR)
    true_map = seat_map(truth, pose)
    ray = seat_ray(mesh, pose)
    assert ray.seat_seen, f"{chair.name}: the scan shows no seat under the sitting point"
    assert len(ray.slides_m) >= 2
    # The seat's height under p within a centimetre of the true seat's there.
    assert seat_map(mesh, pose).seat_height_m == pytest.approx(true_map.seat_height_m, abs=0.01)


@pytest.mark.slow
def test_a_thin_seat_survives_the_scan():
    # A 6 mm slab (a plywood or sling seat) on four legs, with a back: seen from above and
    # below by the views, thinner than the TSDF's voxel and truncation.
    top, depth, width, slab = 0.30, 0.30, 0.32, 0.006
    parts = [box((depth, width, slab), (0.0, 0.0, top - slab / 2.0))]
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            leg = top - slab
            parts.append(
                box(
                    (0.025, 0.025, leg), (sx * (depth / 2 - 0.02), sy * (width / 2 - 0.02), leg / 2)
                )
            )
    parts.append(box((0.02, width, 0.25), (-depth / 2.0 + 0.01, 0.0, top + 0.125)))
    mesh = trimesh.util.concatenate(parts)
    views = frames_of(mesh, T_WORLD_CHAIR, SCAN_CONFIGURATIONS, seed=3)
    scan = reconstruct_chair(views, ReconstructionConfig()).chair_mesh
    pose = SittingPose(
        transform_points(T_WORLD_CHAIR, np.array([[-0.03, 0.0, top + 0.08]]))[0], 0.6
    )
    ray = seat_ray(scan, pose)
    assert ray.seat_seen and len(ray.slides_m) >= 2
    assert seat_map(scan, pose).seat_height_m == pytest.approx(top, abs=0.01)


@pytest.mark.slow
def test_the_one_view_support_surfaces_are_deterministic():
    _, first = scanned("basket", 1)
    second = reconstruct_chair(frames("basket", 1), ReconstructionConfig()).chair_mesh
    assert np.array_equal(first.vertices, second.vertices)
    assert np.array_equal(first.faces, second.faces)


def _slats(gap_m: float) -> trimesh.Trimesh:
    """A seat of 3 cm slats with ``gap_m`` between them, 0.30 m high (its true geometry)."""
    slat, top, width = 0.03, 0.30, 0.32
    parts = [
        box((slat, width, 0.02), (0.20 - slat / 2.0 - k * (slat + gap_m), 0.0, top - 0.01))
        for k in range(int(0.40 // (slat + gap_m)) + 1)
    ]
    return cast(trimesh.Trimesh, trimesh.util.concatenate(parts))


def test_gaps_narrower_than_the_bears_footprint_allows_are_closed():
    # p right over a gap's middle: the bear rests on the slats both sides of it.
    narrow = SLAT_GAP_M - STEP_M
    mesh = _slats(narrow)
    gap_middle = 0.20 - 0.03 - narrow / 2.0
    pose = SittingPose(np.array([gap_middle, 0.0, 0.38]), 0.0)
    ray = seat_ray(mesh, pose)
    assert ray.seat_seen
    assert float(ray.seat_heights_m[0]) == pytest.approx(0.30, abs=1e-3)


def test_a_gap_wider_than_the_bear_can_bridge_is_not_seat():
    wide = BEAR_TORSO_FOOTPRINT_M[0]
    mesh = _slats(wide)
    gap_middle = 0.20 - 0.03 - wide / 2.0
    ray = seat_ray(mesh, SittingPose(np.array([gap_middle, 0.0, 0.38]), 0.0))
    assert not ray.seat_seen


def test_the_seat_maps_numbers_come_from_the_bear():
    torso = BEAR_PARTS[0]
    assert torso.kind == "box"
    assert (torso.size[0], torso.size[1]) == BEAR_TORSO_FOOTPRINT_M
    # core's torso depth (the planner's) is the bear model's.
    assert BEAR_TORSO_FOOTPRINT_M[0] == BEAR_TORSO_DEPTH_M
    assert pytest.approx(min(BEAR_TORSO_FOOTPRINT_M) - 2 * PLACEMENT_TOLERANCE_M) == SLAT_GAP_M
    assert math.degrees(SUPPORT_TILT_RAD) == pytest.approx(16.4, abs=0.1)


@pytest.mark.slow
def test_a_seat_hidden_in_front_of_a_tub_back_is_taken_where_the_scan_sees_it():
    # The tub's back, wrapping round the seat, hides the 5 cm of seat in front of it from
    # the views behind the chair, and p sits there: the bear moves to where the scan sees
    # the seat under its whole torso, no farther than its depth.
    chair, mesh = scanned("swivel_tub", 0)
    ray = seat_ray(mesh, sitting_pose(chair))
    assert ray.seat_seen
    assert 0.0 < ray.unseen_m <= UNSEEN_SLIDE_M
    assert float(ray.slides_m[0]) == pytest.approx(ray.unseen_m)
    assert float(ray.seat_heights_m[0]) == pytest.approx(chair.seat_height_m, abs=0.01)


def _seat_from(start_m: float) -> trimesh.Trimesh:
    """A flat seat 0.30 m high whose top the scan shows only from ``start_m`` ahead of p
    (at the origin, facing +x) to 0.30 m ahead, and a strip behind p (the seat's back)."""
    parts = [
        box((0.30 - start_m, 0.32, 0.02), ((0.30 + start_m) / 2.0, 0.0, 0.29)),
        box((0.03, 0.32, 0.02), (-0.10, 0.0, 0.29)),
    ]
    return cast(trimesh.Trimesh, trimesh.util.concatenate(parts))


def test_the_seat_starts_where_the_bears_torso_is_wholly_on_seen_seat():
    pose = SittingPose(np.array([0.0, 0.0, 0.38]), 0.0)
    assert seat_ray(_seat_from(0.0), pose).unseen_m == 0.0
    ray = seat_ray(_seat_from(0.03), pose)
    assert ray.seat_seen
    # The torso's rear half (4 rows of 1 cm) on the seen seat from 3 cm on.
    half = round(BEAR_TORSO_DEPTH_M / 2.0 / STEP_M) * STEP_M
    assert ray.unseen_m == pytest.approx(0.03 + half, abs=0.011)
    assert float(ray.seat_heights_m[0]) == pytest.approx(0.30, abs=1e-3)
    # Seen seat that starts farther than a torso's depth ahead is not where the child sat.
    far = seat_ray(_seat_from(UNSEEN_SLIDE_M), pose)
    assert not far.seat_seen and far.unseen_m == 0.0
