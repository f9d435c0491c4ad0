"""Thresholds tried at their boundary, and the seat's step-in blocked.

Each boundary test names its threshold and which side of it the boundary itself falls on:

- ``bearchair.skills.imagination.backrest.AGREEMENT_RAD`` (30 deg): an imagined direction
  within it of the backrest's stands (``<=``, the boundary itself included); beyond it,
  the mirror planes decide.
- ``bearchair.skills.perception.registration.RegistrationConfig.min_fitness`` and
  ``max_rmse_m``: a fit exactly at the minimum fitness, or exactly at the maximum RMSE,
  is accepted (``>=`` and ``<=``); the least step past either rejects it. With the new
  views' frames, ``min_visible_fitness``, ``min_peak_visible_fitness`` (for a fit that is a
  peak of the visible overlap) and ``max_rmse_m`` likewise (``>=``, ``>=``, ``<=``).
- ``bearchair.core.arena.ACCESSIBLE_TOLERANCE_RAD`` (30 deg): an accessible placement's
  sitting direction is at most this from the direction toward the humanoid, both
  extremes included.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bearchair.core.arena import (
    ACCESSIBLE_TOLERANCE_RAD,
    DEFAULT_ARENA,
    Box2D,
    accessible_sitting_yaws,
)
from bearchair.core.geometry import SittingPose, wrap_angle
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.skills.imagination.backrest import AGREEMENT_RAD, backrest_yaw, check_direction
from bearchair.skills.perception.errors import RegistrationError
from bearchair.skills.perception.registration import RegistrationConfig, register_chair
from bearchair.skills.planning import accessibility
from bearchair.skills.planning.collision import NaoCollisionChecker, chair_solid_boxes

HAIR_RAD = math.radians(0.1)
"""A step past a boundary: far below any angle the mission resolves, far above rounding."""


@pytest.mark.parametrize("side", [-1.0, 1.0], ids=["left", "right"])
def test_the_backrest_agreement_holds_at_30_degrees_and_not_past_it(side: float) -> None:
    chair_mesh = box_chair_mesh()
    p = np.array([0.0, 0.0, 0.29])
    cue = backrest_yaw(chair_mesh, SittingPose(p, 0.0))
    assert cue is not None
    at = wrap_angle(cue[0] + side * (AGREEMENT_RAD - HAIR_RAD))
    kept, check = check_direction(chair_mesh, SittingPose(p, at))
    assert check is not None and not check.used and kept.yaw == at
    assert math.isnan(check.mirror_back)  # stood by the agreement, no mirror consulted
    past = wrap_angle(cue[0] + side * (AGREEMENT_RAD + HAIR_RAD))
    _, check = check_direction(chair_mesh, SittingPose(p, past))
    assert check is not None and not math.isnan(check.mirror_back)  # judged by the mirrors


@pytest.mark.parametrize("side", [-1.0, 1.0], ids=["left", "right"])
def test_a_direction_exactly_at_the_backrest_agreement_stands(monkeypatch, side: float) -> None:
    """The boundary itself is on the agreeing side (``<=``). No yaw lies exactly 30 deg
    from the backrest's in floating point (``wrap_angle``'s grid), so the bound is set to
    this direction's own disagreement with the backrest, bit for bit."""
    from bearchair.skills.imagination import backrest

    chair_mesh = box_chair_mesh()
    p = np.array([0.0, 0.0, 0.29])
    cue = backrest_yaw(chair_mesh, SittingPose(p, 0.0))
    assert cue is not None
    at = wrap_angle(cue[0] + side * AGREEMENT_RAD)
    disagreement = abs(wrap_angle(at - cue[0]))
    assert disagreement == pytest.approx(AGREEMENT_RAD, abs=1e-12)
    monkeypatch.setattr(backrest, "AGREEMENT_RAD", disagreement)
    kept, check = check_direction(chair_mesh, SittingPose(p, at))
    assert check is not None and not check.used and kept.yaw == at
    assert math.isnan(check.mirror_back)  # stood by the agreement, no mirror consulted


def _chair_cloud(n: int = 3000) -> np.ndarray:
    points = box_chair_mesh().sample(n, seed=0)
    return np.asarray(points) + np.array([0.6, 0.0, 0.0])


@pytest.mark.slow
def test_a_fit_exactly_at_the_minimum_fitness_and_maximum_rmse_is_accepted() -> None:
    cloud = _chair_cloud()
    fit = register_chair(cloud, cloud, RegistrationConfig())
    at_the_boundary = RegistrationConfig(min_fitness=fit.fitness, max_rmse_m=fit.inlier_rmse_m)
    accepted = register_chair(cloud, cloud, at_the_boundary)
    assert accepted.fitness == fit.fitness
    with pytest.raises(RegistrationError):
        register_chair(
            cloud,
            cloud,
            replace(at_the_boundary, min_fitness=float(np.nextafter(fit.fitness, 2.0))),
        )
    with pytest.raises(RegistrationError):
        register_chair(
            cloud,
            cloud,
            replace(at_the_boundary, max_rmse_m=float(np.nextafter(fit.inlier_rmse_m, -1.0))),
        )


def test_accessible_directions_reach_the_tolerance_both_ways_and_no_further() -> None:
    centre = (0.6, 0.0)
    start = DEFAULT_ARENA.humanoid_start
    toward = math.atan2(start.y - centre[1], start.x - centre[0])
    offsets = np.array(
        [wrap_angle(yaw - toward) for yaw in accessible_sitting_yaws(DEFAULT_ARENA, centre)]
    )
    assert offsets.max() == pytest.approx(ACCESSIBLE_TOLERANCE_RAD, abs=1e-9)
    assert offsets.min() == pytest.approx(-ACCESSIBLE_TOLERANCE_RAD, abs=1e-9)


# --- the step in to s_goal --------------------------------------------------------------

STEP_START = SE2Pose(1.6, 0.0, math.pi)
STEP_GOAL = SE2Pose(1.0, 0.0, math.pi)


def _checker(obstacles=(), chair_mesh=None) -> NaoCollisionChecker:
    arena = DEFAULT_ARENA._replace(obstacles=(*DEFAULT_ARENA.obstacles, *obstacles))
    return NaoCollisionChecker(arena, chair_solid_boxes(chair_mesh) if chair_mesh else [])


def test_a_clear_step_in_is_not_blocked() -> None:
    assert accessibility._step_in_blocked_by(_checker(), STEP_START, STEP_GOAL, chair=True) == ""


def test_a_step_in_across_an_obstacle_names_it() -> None:
    """A 2 cm post on the step's line, clear of both of its ends."""
    post = Box2D(1.29, 1.31, -0.01, 0.01)
    checker = _checker((post,))
    assert checker.is_free(STEP_START.x, STEP_START.y, STEP_START.theta)
    assert (
        accessibility._step_in_blocked_by(checker, STEP_START, STEP_GOAL, chair=False) == "obstacle"
    )


def test_a_step_in_through_a_wall_names_the_wall() -> None:
    out = SE2Pose(DEFAULT_ARENA.x_max + 0.2, 0.0, math.pi)
    assert accessibility._step_in_blocked_by(_checker(), out, STEP_GOAL, chair=False) == "wall"


def test_a_step_in_into_the_chair_counts_only_when_asked() -> None:
    """The step ends inside the ellipsoid's clearance of the chair when the whole-body
    pre-plan approved it: the chair counts only for a goal reached without an approach."""
    chair_mesh = box_chair_mesh().apply_translation((0.9, 0.0, 0.0))
    checker = _checker(chair_mesh=chair_mesh)
    assert accessibility._step_in_blocked_by(checker, STEP_START, STEP_GOAL, chair=True) == "chair"
    assert accessibility._step_in_blocked_by(checker, STEP_START, STEP_GOAL, chair=False) == ""


def test_a_blocked_step_in_makes_the_chair_inaccessible_with_no_path(monkeypatch) -> None:
    """check_accessibility refuses the goal when the step in to it from the approach is
    blocked, before planning a path there (the walk would end where the NAO cannot step
    in). The stance chooser is made to end the walk 0.3 m back along the ray, as it does
    when s_goal lies inside the walking NAO's clearance of the chair."""
    from bearchair.skills.planning.preplan import reach_validator

    chair_mesh = box_chair_mesh().apply_translation((0.6, 0.0, 0.0))
    sitting_pose = SittingPose(np.array([0.6, 0.0, 0.29]), 0.0)
    choose = accessibility.choose_stance

    def with_an_approach(*args, **kwargs):
        choice = choose(*args, **kwargs)
        goal = choice.se2_goal
        return choice._replace(approach=SE2Pose(goal.x + 0.3, goal.y, goal.theta))

    monkeypatch.setattr(accessibility, "choose_stance", with_an_approach)

    def check(arena):
        return accessibility.check_accessibility(
            chair_mesh,
            sitting_pose,
            DEFAULT_ARENA.humanoid_start,
            arena,
            seed=0,
            seating_validator=reach_validator,
        )

    clear = check(DEFAULT_ARENA)
    assert clear.accessible and clear.step_in_from is not None, clear.reason
    assert clear.path[-1] == clear.step_in_from  # the walk ends where the step begins
    # A 1 cm post halfway along this very step in.
    mid_x = (clear.step_in_from.x + clear.se2_goal.x) / 2
    post = Box2D(mid_x - 0.005, mid_x + 0.005, -0.005, 0.005)
    blocked = check(DEFAULT_ARENA._replace(obstacles=(*DEFAULT_ARENA.obstacles, post)))
    assert not blocked.accessible and blocked.path == ()
    assert blocked.reason == "the step in to s_goal touches the obstacle"


def test_a_step_in_from_where_the_bear_is_raised_counts_the_chair(monkeypatch) -> None:
    """Without an approach, s_goal is clear of the walking NAO's clearance of the chair,
    so the step in from where the bear is raised (``raise_at``) must not touch the chair
    either: a raise point whose straight step to s_goal crosses the chair is refused,
    naming the chair, before a path is planned there."""
    from bearchair.skills.planning.preplan import reach_validator

    # Mid-arena, so that the far side of the chair is clear of the walls and the arm.
    chair_mesh = box_chair_mesh().apply_translation((1.2, 0.0, 0.0))
    sitting_pose = SittingPose(np.array([1.2, 0.0, 0.29]), 0.0)
    choose = accessibility.choose_stance

    def raised_beyond_the_chair(*args, **kwargs):
        choice = choose(*args, **kwargs)
        goal = choice.se2_goal
        assert goal is not None
        beyond = SE2Pose(goal.x - 0.7, goal.y, goal.theta)  # the chair lies between
        assert _checker(chair_mesh=chair_mesh).is_free(beyond.x, beyond.y, beyond.theta)
        return choice._replace(approach=None, check=choice.check._replace(raise_at=beyond))

    monkeypatch.setattr(accessibility, "choose_stance", raised_beyond_the_chair)
    result = accessibility.check_accessibility(
        chair_mesh,
        sitting_pose,
        DEFAULT_ARENA.humanoid_start,
        DEFAULT_ARENA,
        seed=0,
        seating_validator=reach_validator,
    )
    assert not result.accessible and result.path == ()
    assert result.reason == "the step in to s_goal touches the chair"


# --- registration judged by the new views: the visible overlap and RMSE bounds ----------


@pytest.fixture(scope="module")
def seen_chair():
    """The box chair scanned from every scan view (the reference) and seen again, unmoved,
    from the tracking views (the new points and their frames): rendered, not simulated."""
    from bearchair.core.geometry import yaw_transform
    from bearchair.skills.perception import ReconstructionConfig, reconstruct_chair
    from bearchair.skills.perception.views import SCAN_CONFIGURATIONS, TRACKING_VIEWS
    from bearchair.testing.synthetic_scenes import SyntheticArm, SyntheticScene

    scene = SyntheticScene(seed=3)
    scene.add_mesh(box_chair_mesh(), yaw_transform(0.6, np.array([0.58, 0.08, 0.0])))
    arm = SyntheticArm(scene)
    try:
        frames = []
        for joints in SCAN_CONFIGURATIONS:
            arm.move_to(joints)
            frames.append(arm.capture())
    finally:
        arm.close()
        scene.close()
    config = ReconstructionConfig(with_mesh=False)
    tracking = [frames[i] for i in TRACKING_VIEWS]
    reference = reconstruct_chair(frames, config).chair_points
    return reference, reconstruct_chair(tracking, config).chair_points, tracking


def _judged(monkeypatch, reference, new, frames, config) -> tuple[float, float]:
    """Registers with frames and returns the first fit's visible overlap and RMSE, the two
    numbers ``register_chair`` compares with its bounds (recorded on their way, unchanged)."""
    from bearchair.skills.perception import registration

    seen, refined = [], []
    original_seen, original_refine = registration._seen, registration._refine

    def recording_seen(*args):
        seen.append(original_seen(*args))
        return seen[-1]

    def recording_refine(*args):
        refined.append(original_refine(*args))
        return refined[-1]

    monkeypatch.setattr(registration, "_seen", recording_seen)
    monkeypatch.setattr(registration, "_refine", recording_refine)
    register_chair(new, reference, config, frames)
    monkeypatch.undo()
    return seen[0], refined[0][2]


@pytest.mark.slow
def test_with_frames_a_fit_exactly_at_the_visible_overlap_and_rmse_bounds_is_accepted(
    monkeypatch, seen_chair
) -> None:
    """With frames, ``min_visible_fitness``, ``min_peak_visible_fitness`` (for a peak)
    and ``max_rmse_m`` hold at the boundary (``>=``, ``>=``, ``<=``); the least step past
    them rejects the fit (with the peak's floor just above the overlap, only the fixed
    bound can accept it)."""
    reference, new, frames = seen_chair
    visible, rmse = _judged(monkeypatch, reference, new, frames, RegistrationConfig())
    above = float(np.nextafter(visible, 2.0))
    at_the_boundary = RegistrationConfig(
        min_visible_fitness=visible, min_peak_visible_fitness=above, max_rmse_m=rmse
    )
    assert _judged(monkeypatch, reference, new, frames, at_the_boundary) == (visible, rmse)
    register_chair(new, reference, at_the_boundary, frames)  # accepted
    # The peak's floor at the boundary: the fixed bound just above, the unmoved chair's
    # fit a peak of the visible overlap, accepted.
    at_the_peak_floor = replace(
        at_the_boundary, min_visible_fitness=above, min_peak_visible_fitness=visible
    )
    register_chair(new, reference, at_the_peak_floor, frames)
    # Past the bound, without the climb (which moves the fit to a higher overlap).
    past = replace(at_the_boundary, min_visible_fitness=above)
    no_climb = replace(past, climb_steps_m=(), climb_steps_deg=())
    with pytest.raises(RegistrationError, match="visible overlap"):
        register_chair(new, reference, no_climb, frames)
    # With it, the fit climbs past the bound and is accepted, unless it then turns the
    # chair away from the turn asked for (the chair did not move: 90 deg is off).
    climbed = register_chair(new, reference, replace(past, max_rmse_m=0.01), frames)
    assert climbed.visible_fitness > visible
    with pytest.raises(RegistrationError, match="found by climbing it"):
        register_chair(new, reference, replace(past, max_rmse_m=0.01), frames, math.pi / 2)
    with pytest.raises(RegistrationError, match="RMSE"):
        register_chair(
            new,
            reference,
            replace(at_the_boundary, max_rmse_m=float(np.nextafter(rmse, -1.0))),
            frames,
        )
