"""Scan views kept clear of large chairs, and registration judged by what the views saw.

Frames come from skills.perception.synthetic (no simulated world); chairs from
skills.chairgen and the box chair.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearchair.core.geometry import transform_points, wrap_angle, yaw_of, yaw_transform
from bearchair.core.meshes import box_chair_mesh
from bearchair.skills.perception import PerceptionError, ReconstructionConfig, reconstruct_chair
from bearchair.skills.perception.clearance import (
    HIDDEN_MARGIN_M,
    ArmClearance,
    ChairExtent,
    chair_extent,
    plan_views,
)
from bearchair.skills.perception.errors import RegistrationError
from bearchair.skills.perception.registration import (
    RegistrationConfig,
    climb_visible_overlap,
    is_visible_peak,
    register_chair,
    visible_fitness,
)
from bearchair.skills.perception.scan import scan_chair
from bearchair.skills.perception.scan_capture import MIN_SCAN_VIEWS, capture_planned
from bearchair.skills.perception.views import (
    CHAIR_VOLUME,
    HOME_CONFIGURATION,
    MAX_CHAIR_HEIGHT_M,
    SCAN_CONFIGURATIONS,
    TRACKING_VIEWS,
    VIEW_CLEARANCE_M,
)
from bearchair.testing.chairgen import generate_chair
from bearchair.testing.synthetic_scenes import SyntheticArm, SyntheticScene
from tests.helpers.scans import frames_of

T_WORLD_CHAIR = yaw_transform(0.6, np.array([0.58, 0.08, 0.0]))


@pytest.fixture(scope="module")
def clearance():
    with ArmClearance() as checker:
        yield checker


def test_the_chair_volume_holds_the_tallest_chair_anywhere_in_the_chair_area():
    upper = CHAIR_VOLUME[1]
    assert upper[2] == MAX_CHAIR_HEIGHT_M
    # A wide generated bench at a corner of the chair area, turned 45 degrees.
    bench = max((generate_chair(seed, "bench") for seed in range(10)), key=lambda c: c.seat_width_m)
    corner = yaw_transform(math.radians(45.0), np.array([0.85, 0.25, 0.0]))
    vertices = transform_points(corner, np.asarray(bench.mesh.vertices))
    assert np.all(vertices[:, 1:] <= upper[1:] + 1e-9)
    assert np.all(vertices[:, 0] <= upper[0] + 1e-9)


def test_the_extent_seen_from_home_holds_the_chair_and_stays_in_the_volume():
    mesh = box_chair_mesh()
    (frame,) = frames_of(mesh, T_WORLD_CHAIR, [HOME_CONFIGURATION])
    extent = chair_extent(frame)
    assert extent.source == "seen"
    vertices = transform_points(T_WORLD_CHAIR, np.asarray(mesh.vertices))
    # What the high view sees, grown by the hidden-parts margin, holds the whole chair.
    assert np.all(vertices.min(axis=0)[:2] >= extent.lower[:2])
    assert np.all(vertices.max(axis=0) <= extent.upper)
    # ... and is far smaller than the volume any chair might fill.
    volume = np.prod(CHAIR_VOLUME[1] - CHAIR_VOLUME[0])
    assert np.prod(extent.upper - extent.lower) < 0.5 * volume


def test_nothing_seen_means_the_whole_volume():
    extent = chair_extent(None)
    assert extent.source == "volume"
    assert np.array_equal(extent.lower, CHAIR_VOLUME[0])


def test_views_too_close_to_a_large_chair_are_routed_replaced_or_skipped(clearance):
    # A chair as tall and wide as the volume allows, filling the whole volume.
    extent = ChairExtent(*CHAIR_VOLUME, "volume")
    planned = plan_views(SCAN_CONFIGURATIONS, extent, clearance)
    assert [view.index for view in planned] == list(range(len(SCAN_CONFIGURATIONS)))
    statuses = {view.status for view in planned}
    assert statuses - {"kept"}, "the full volume blocks some views (the test would not test)"
    current = tuple(HOME_CONFIGURATION)
    for view in planned:
        if view.status == "skipped":
            continue
        start = HOME_CONFIGURATION if view.via_home else current
        # Checked again independently: every motion planned keeps its clearance.
        assert clearance.path_clearance(start, view.joints) >= VIEW_CLEARANCE_M
        if view.status == "replaced":
            assert view.joints != tuple(SCAN_CONFIGURATIONS[view.index])
        current = view.joints


def test_a_small_chair_keeps_every_view(clearance):
    (frame,) = frames_of(box_chair_mesh(), T_WORLD_CHAIR, [HOME_CONFIGURATION])
    planned = plan_views(SCAN_CONFIGURATIONS, chair_extent(frame), clearance)
    assert [view.status for view in planned] == ["kept"] * len(SCAN_CONFIGURATIONS)


class BlockedArm(SyntheticArm):
    """Times out on the configurations in ``blocked`` (a chair in the way)."""

    def __init__(self, scene, blocked):
        super().__init__(scene)
        self.blocked = [np.asarray(b) for b in blocked]
        self.visited = []

    def move_to(self, joint_positions_rad, timeout_s: float = 10.0) -> None:
        target = np.asarray(joint_positions_rad, float)
        if any(np.allclose(target, b) for b in self.blocked):
            raise TimeoutError(
                "Panda did not reach its target in 10.0 s (largest joint error 48 deg)"
            )
        super().move_to(target)
        self.visited.append(target)


@pytest.mark.slow
def test_a_motion_that_stops_short_skips_the_view_and_the_scan_goes_on():
    scene = SyntheticScene(seed=3)
    scene.add_mesh(box_chair_mesh(), T_WORLD_CHAIR)
    arm = BlockedArm(scene, [SCAN_CONFIGURATIONS[2]])
    try:
        planned = plan_views(SCAN_CONFIGURATIONS, ChairExtent(*_tiny_box(), "seen"), _checker())
        frames, notes, seconds = capture_planned(arm, planned, None)
    finally:
        arm.close()
        scene.close()
    assert len(frames) == len(SCAN_CONFIGURATIONS) - 1
    assert len(notes) == 1 and "view 2 skipped" in notes[0] and "48 deg" in notes[0]
    assert np.allclose(arm.visited[-1], HOME_CONFIGURATION)
    assert seconds["capture"] > 0.0


@pytest.mark.slow
def test_a_scan_with_too_few_reachable_views_fails_with_the_reason():
    scene = SyntheticScene(seed=3)
    scene.add_mesh(box_chair_mesh(), T_WORLD_CHAIR)
    blocked = SCAN_CONFIGURATIONS[: len(SCAN_CONFIGURATIONS) - MIN_SCAN_VIEWS + 1]
    arm = BlockedArm(scene, blocked)
    try:
        with pytest.raises(PerceptionError, match=r"only \d of 9 views .*48 deg"):
            scan_chair(arm, seed=0)
    finally:
        arm.close()
        scene.close()


def _tiny_box():
    return np.array([0.55, -0.05, 0.0]), np.array([0.65, 0.05, 0.1])


_shared_checker = None


def _checker() -> ArmClearance:
    global _shared_checker
    if _shared_checker is None:
        _shared_checker = ArmClearance()
    return _shared_checker


@pytest.fixture(scope="module")
def turned_chair():
    """A generated armchair scanned, then turned 150 degrees and seen from the tracking views."""
    mesh = generate_chair(1, "armchair").mesh
    config = ReconstructionConfig(with_mesh=False)
    reference = reconstruct_chair(frames_of(mesh, T_WORLD_CHAIR, SCAN_CONFIGURATIONS), config)
    centre = T_WORLD_CHAIR[:3, 3]
    motion = (
        yaw_transform(0.0, centre + np.array([0.01, -0.005, 0.0]))
        @ yaw_transform(math.radians(150.0))
        @ yaw_transform(0.0, -centre)
    )
    frames = frames_of(
        mesh, motion @ T_WORLD_CHAIR, [SCAN_CONFIGURATIONS[i] for i in TRACKING_VIEWS]
    )
    new = reconstruct_chair(frames, config).chair_points
    return reference.chair_points, new, frames, motion


def test_visible_fitness_tells_a_right_fit_from_a_turned_one(turned_chair):
    reference, _, frames, motion = turned_chair
    centre = T_WORLD_CHAIR[:3, 3]
    right = visible_fitness(transform_points(motion, reference[::2]), frames)
    assert right > 0.9
    for error_deg in (30.0, -30.0, 90.0):
        off = (
            yaw_transform(0.0, centre)
            @ yaw_transform(math.radians(error_deg))
            @ yaw_transform(0.0, -centre)
        )
        assert visible_fitness(transform_points(off @ motion, reference[::2]), frames) < 0.7


def test_a_fit_slipped_3_cm_along_the_chair_is_below_the_bound(turned_chair):
    reference, _, frames, motion = turned_chair
    bound = RegistrationConfig().min_visible_fitness
    assert visible_fitness(transform_points(motion, reference[::2]), frames) >= bound
    for direction in ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)):
        slip = yaw_transform(0.0, np.array([*(0.03 * np.array(direction)), 0.0]))
        slipped = visible_fitness(transform_points(slip @ motion, reference[::2]), frames)
        assert slipped < bound, (direction, slipped)


def test_the_right_fit_is_a_peak_of_the_visible_overlap_and_an_offset_one_is_not(turned_chair):
    reference, _, frames, motion = turned_chair
    centre = T_WORLD_CHAIR[:3, 3]
    assert is_visible_peak(transform_points(motion, reference[::2]), frames)
    offsets = [
        yaw_transform(0.0, np.array([0.03, 0.0, 0.0])),
        yaw_transform(0.0, np.array([0.0, -0.03, 0.0])),
    ]
    offsets.append(
        yaw_transform(0.0, centre) @ yaw_transform(math.radians(10.0)) @ yaw_transform(0.0, -centre)
    )
    for offset in offsets:
        assert not is_visible_peak(transform_points(offset @ motion, reference[::2]), frames)


def _turned_about(centre: np.ndarray, yaw_deg: float) -> np.ndarray:
    return (
        yaw_transform(0.0, centre)
        @ yaw_transform(math.radians(yaw_deg))
        @ yaw_transform(0.0, -centre)
    )


def test_a_slipped_fit_climbs_back_to_the_right_one(turned_chair):
    """ICP on a turned chair is left a few cm along it: the climb on the visible overlap
    brings such fits back to the helper's motion, above the bound."""
    reference, _, frames, motion = turned_chair
    points = reference[::2]
    centroid = np.append(points.mean(axis=0), 1.0)
    slips = [yaw_transform(0.0, np.array([dx, dy, 0.0])) for dx, dy in ((0.02, 0.0), (0.0, -0.03))]
    slips += [
        yaw_transform(0.0, np.array([0.03, 0.03, 0.0])),
        _turned_about(T_WORLD_CHAIR[:3, 3], 5.0),
    ]
    for slip in slips:
        start = slip @ motion
        assert visible_fitness(transform_points(start, points), frames) < 0.9
        climbed, overlap = climb_visible_overlap(start, points, frames)
        assert overlap >= RegistrationConfig().min_visible_fitness
        assert np.linalg.norm((climbed - motion) @ centroid) < 0.01
        assert abs(math.degrees(wrap_angle(yaw_of(climbed) - yaw_of(motion)))) <= 1.5


def test_a_fit_turned_30_deg_or_more_off_stays_below_the_bound_after_climbing(turned_chair):
    reference, _, frames, motion = turned_chair
    for error_deg in (30.0, -30.0, 90.0, 180.0):
        start = _turned_about(T_WORLD_CHAIR[:3, 3], error_deg) @ motion
        _, overlap = climb_visible_overlap(start, reference[::2], frames)
        assert overlap < RegistrationConfig().min_visible_fitness, error_deg


@pytest.mark.slow
def test_a_turn_showing_sides_the_reference_never_saw_is_accepted_by_what_the_views_saw(
    turned_chair,
):
    reference, new, frames, motion = turned_chair
    # The reference lacks the half of the chair that faces away from the arm now: the
    # right fit explains few of the new points.
    carried = transform_points(motion, reference)
    half = reference[carried[:, 0] > np.median(carried[:, 0])]
    with pytest.raises(Exception, match="fitness"):
        register_chair(new, half)
    fit = register_chair(new, half, None, frames)
    assert fit.fitness < 0.6
    assert fit.visible_fitness >= RegistrationConfig().min_visible_fitness
    assert abs(math.degrees(wrap_angle(yaw_of(fit.T_world_new_old) - yaw_of(motion)))) < 3.0


@pytest.mark.slow
def test_when_the_best_fitting_yaw_is_wrong_the_views_pick_another():
    """The search past the best-fitting hypothesis (the best other yaws and the global
    registration, judged by the visible overlap): an armchair turned -120 degrees whose
    best-fitting yaw is a quarter turn off. Judged by the fitness alone (no frames) the
    fit is wrong or rejected; with the frames it is the helper's turn."""
    mesh = generate_chair(2, "armchair").mesh
    config = ReconstructionConfig(with_mesh=False)
    reference = reconstruct_chair(frames_of(mesh, T_WORLD_CHAIR, SCAN_CONFIGURATIONS), config)
    centre = T_WORLD_CHAIR[:3, 3]
    turn_rad = math.radians(-120.0)
    motion = yaw_transform(0.0, centre) @ yaw_transform(turn_rad) @ yaw_transform(0.0, -centre)
    frames = frames_of(
        mesh, motion @ T_WORLD_CHAIR, [SCAN_CONFIGURATIONS[i] for i in TRACKING_VIEWS]
    )
    new = reconstruct_chair(frames, config).chair_points
    try:
        by_fitness = register_chair(new, reference.chair_points)
        off_deg = abs(math.degrees(wrap_angle(yaw_of(by_fitness.T_world_new_old) - turn_rad)))
        assert off_deg > 30.0  # the test's premise: the best-fitting yaw is wrong
    except RegistrationError:
        pass
    fit = register_chair(new, reference.chair_points, None, frames)
    assert abs(math.degrees(wrap_angle(yaw_of(fit.T_world_new_old) - turn_rad))) < 3.0
    assert fit.visible_fitness >= RegistrationConfig().min_visible_fitness


# --- objects larger than the chair area: a sofa ------------------------------------------

WIDE_SOFA_M = 1.6
"""As wide as the cell in front of the arm is deep: from the arm's footprint (x 0.15 m) to
the NAO waiting at x 1.9 m less its half depth, about 1.6 m."""


def _wide_sofa():
    """A generated sofa stretched across to :data:`WIDE_SOFA_M`, its front along +x."""
    chair = max((generate_chair(seed, "sofa") for seed in range(6)), key=lambda c: c.seat_width_m)
    mesh = chair.mesh.copy()
    mesh.apply_scale([1.0, WIDE_SOFA_M / float(np.ptp(mesh.vertices[:, 1])), 1.0])
    return mesh, chair.seat_height_m


def test_the_floor_is_the_plane_under_a_seat_larger_than_the_floor_in_view():
    from bearchair.skills.perception.reconstruction import fit_floor

    rng = np.random.default_rng(0)
    # A sofa's seat seen from above, 0.3 m up, with three times the points of the floor.
    seat = np.column_stack([rng.uniform(0.3, 0.9, (6000, 2)), rng.normal(0.3, 0.002, 6000)])
    floor_xy = rng.uniform(-0.2, 1.4, (6000, 2))
    floor_xy = floor_xy[(floor_xy[:, 0] < 0.25) | (floor_xy[:, 0] > 0.95)][:2000]
    floor = np.column_stack([floor_xy, rng.normal(0.0, 0.002, len(floor_xy))])
    plane = fit_floor(np.concatenate([seat, floor]), ReconstructionConfig(seed=0))
    assert plane[2] > 0.99 and abs(plane[3]) < 0.01, plane


def test_a_chair_inside_the_home_view_needs_no_side_looks():
    from bearchair.skills.perception.clearance import cut_sides

    (frame,) = frames_of(box_chair_mesh(), T_WORLD_CHAIR, [HOME_CONFIGURATION])
    assert cut_sides(frame) == (False, False)


@pytest.mark.slow
def test_a_sofa_wider_than_the_home_view_is_looked_at_sideways_and_scanned_whole(clearance):
    from bearchair.skills.perception.clearance import cut_sides

    mesh, seat_height = _wide_sofa()
    T = yaw_transform(0.0, np.array([0.75, 0.0, 0.0]))
    scene = SyntheticScene(seed=3)
    scene.add_mesh(mesh, T)
    arm = SyntheticArm(scene)
    try:
        arm.move_to(HOME_CONFIGURATION)
        assert cut_sides(arm.capture()) == (True, True), "the test needs a sofa past both edges"
        # The tracking views (the fewest a scan accepts) keep the test short.
        scan = scan_chair(
            arm, seed=0, config=ReconstructionConfig(with_mesh=False), views=TRACKING_VIEWS
        )
    finally:
        arm.close()
        scene.close()
    true = transform_points(T, np.asarray(mesh.vertices))
    points = scan.chair_points
    # The whole width is in the scan (1.63 m; without the side looks, 1.42 m of the 1.6),
    # and the floor under it is the floor, not its seat.
    assert np.ptp(points[:, 1]) >= 0.95 * np.ptp(true[:, 1]), np.ptp(points[:, 1])
    assert points[:, 2].min() < 0.1
    assert any("side look" in note for note in scan.notes)
    # The seat is there near both ends, where the bear might be seated.
    for end in (-1.0, 1.0):
        near_end = points[(end * points[:, 1] > 0.35 * WIDE_SOFA_M)]
        assert np.any(np.abs(near_end[:, 2] - seat_height) < 0.03), end


@pytest.mark.slow
def test_the_side_looks_bound_the_whole_sofa_so_the_views_are_checked_against_it(clearance):
    from bearchair.skills.perception.scan_capture import side_looks

    mesh, _ = _wide_sofa()
    T = yaw_transform(0.0, np.array([0.75, 0.0, 0.0]))
    scene = SyntheticScene(seed=3)
    scene.add_mesh(mesh, T)
    arm = SyntheticArm(scene)
    try:
        arm.move_to(HOME_CONFIGURATION)
        home = arm.capture()
        looks, notes = side_looks(arm, home, clearance)
        assert np.allclose(arm.joint_positions(), HOME_CONFIGURATION), "back at HOME"
    finally:
        arm.close()
        scene.close()
    true = transform_points(T, np.asarray(mesh.vertices))
    seen_home = chair_extent(home)
    extent = chair_extent([home, *looks])
    assert len(looks) >= 2 and len(notes) == 2, notes
    # From HOME alone the sofa's ends are outside the box the views are checked against;
    # with the side looks the box holds the whole sofa (to the 2 cm voxels).
    assert seen_home.lower[1] > true[:, 1].min() + 0.1
    assert seen_home.upper[1] < true[:, 1].max() - 0.1
    assert np.all(extent.lower[:2] <= true.min(axis=0)[:2] + 0.02)
    assert np.all(extent.upper <= true.max(axis=0) + HIDDEN_MARGIN_M + 0.03)
    assert np.all(extent.upper[:2] >= true.max(axis=0)[:2] - 0.02)
    # Every view still planned keeps its clearance from that box.
    planned = plan_views(SCAN_CONFIGURATIONS, extent, clearance)
    kept = [view for view in planned if view.status != "skipped"]
    assert len(kept) >= MIN_SCAN_VIEWS
    assert all(view.clearance_m >= VIEW_CLEARANCE_M for view in kept)


@pytest.mark.slow
def test_a_fit_accepted_only_as_a_peak_must_agree_with_the_turn_asked_for(
    turned_chair, monkeypatch
):
    """With no fit reaching the visible-overlap bound and every fit a peak, acceptance
    rests on the peak alone: the fit stands when it agrees with the turn asked for (or
    its reverse, the helper who turned the wrong way) and is rejected, naming both
    turns, when it is more than one instruction step from either."""
    from bearchair.skills.perception import registration

    reference, new, frames, motion = turned_chair
    carried = transform_points(motion, reference)
    half = reference[carried[:, 0] > np.median(carried[:, 0])]
    monkeypatch.setattr(registration, "is_visible_peak", lambda *_args: True)
    peak_only = RegistrationConfig(min_visible_fitness=1.01)
    for asked_deg in (150.0, 170.0, -150.0):
        fit = register_chair(new, half, peak_only, frames, math.radians(asked_deg))
        assert abs(math.degrees(wrap_angle(yaw_of(fit.T_world_new_old) - yaw_of(motion)))) < 3.0
    with pytest.raises(RegistrationError, match=r"turns the chair \+15\d deg.*\+60 deg asked for"):
        register_chair(new, half, peak_only, frames, math.radians(60.0))
