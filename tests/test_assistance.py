"""The helper instruction: rounding, directions, wrap-around, and an obeying helper."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.core.geometry import SittingPose
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.skills.assistance import (
    choose_rotation,
    compose_instruction,
    instructed_rotation,
    rotation_toward,
)
from bearchair.skills.assistance.rotation import turned_about_centre
from bearchair.skills.results import AccessibilityResult

HUMANOID = SE2Pose(1.9, 0.0, math.pi)


@pytest.mark.parametrize(
    ("rotation_deg", "clockwise", "angle_deg"),
    [
        (0.0, False, 0),
        (14.9, False, 0),
        (-14.9, True, 0),
        (15.0, False, 30),  # halves round up
        (29.0, False, 30),
        (-44.0, True, 30),
        (46.0, False, 60),
        (90.0, False, 90),
        (-90.0, True, 90),
        (-105.0, True, 120),
        (164.0, False, 150),
        (166.0, False, 180),
        (179.0, False, 180),
        (-179.0, True, 180),
        (180.0, True, 180),  # wraps to -180: clockwise
        (-180.0, True, 180),
        (350.0, True, 0),  # wrap-around: +350 is -10
        (340.0, True, 30),  # +340 is -20
        (-340.0, False, 30),  # -340 is +20
        (720.0 + 95.0, False, 90),
    ],
)
def test_instructed_rotation_table(rotation_deg: float, clockwise: bool, angle_deg: int) -> None:
    assert instructed_rotation(math.radians(rotation_deg)) == (clockwise, angle_deg)


def test_angles_are_multiples_of_30_within_0_to_180() -> None:
    for rotation_deg in np.linspace(-400.0, 400.0, 801):
        _, angle_deg = instructed_rotation(math.radians(rotation_deg))
        assert angle_deg % 30 == 0 and 0 <= angle_deg <= 180


def _sitting(x: float, y: float, yaw_deg: float) -> SittingPose:
    return SittingPose(np.array([x, y, 0.3]), math.radians(yaw_deg))


def test_rotation_toward_wraps_across_plus_minus_180() -> None:
    # Facing -170 deg, the NAO straight ahead at +170 deg: turn clockwise by 20 deg.
    target = (math.cos(math.radians(170.0)), math.sin(math.radians(170.0)))
    rotation = rotation_toward(_sitting(0.0, 0.0, -170.0), target)
    assert math.degrees(rotation) == pytest.approx(-20.0)


@pytest.mark.parametrize(
    ("yaw_deg", "sentence"),
    [
        # The NAO is at +x from the chair: a chair facing +y must turn clockwise 90.
        (90.0, "Please rotate the chair about the vertical axis clockwise for 90 degrees"),
        (-90.0, "Please rotate the chair about the vertical axis counterclockwise for 90 degrees"),
        (180.0, "Please rotate the chair about the vertical axis clockwise for 180 degrees"),
        (
            -135.0,
            "Please rotate the chair about the vertical axis counterclockwise for 150 degrees",
        ),
        (3.0, "Please rotate the chair about the vertical axis clockwise for 0 degrees"),
    ],
)
def test_compose_instruction_sentence(yaw_deg: float, sentence: str) -> None:
    instruction = compose_instruction(_sitting(0.6, 0.0, yaw_deg), SE2Pose(1.9, 0.0, math.pi))
    assert instruction.sentence == sentence
    assert instruction.clockwise == ("counterclockwise" not in sentence)


def test_obeyed_instruction_points_the_chair_at_the_nao_within_15_degrees() -> None:
    humanoid = SE2Pose(1.9, 0.3, math.pi)
    for yaw_deg in range(-180, 180, 7):
        sitting = _sitting(0.5, -0.2, yaw_deg)
        instruction = compose_instruction(sitting, humanoid)
        turn = math.radians(instruction.angle_deg) * (-1.0 if instruction.clockwise else 1.0)
        residual = rotation_toward(SittingPose(sitting.position, sitting.yaw + turn), humanoid[:2])
        assert abs(math.degrees(residual)) <= 15.0 + 1e-9


def test_target_at_the_sitting_position_is_an_error() -> None:
    with pytest.raises(ValueError, match="no direction"):
        rotation_toward(_sitting(1.0, 1.0, 0.0), (1.0, 1.0))


class _AccessibleWhenFacing:
    """An accessibility check that plans only when the sitting direction is one yaw."""

    def __init__(self, accessible_yaw_deg: float | None) -> None:
        self.accessible_yaw_deg = accessible_yaw_deg
        self.yaws_deg: list[float] = []

    def __call__(self, chair_mesh, sitting_pose, humanoid_pose, arena, *, seed):
        yaw_deg = math.degrees(sitting_pose.yaw)
        self.yaws_deg.append(round(yaw_deg))
        wanted = self.accessible_yaw_deg
        ok = wanted is not None and abs((yaw_deg - wanted + 180.0) % 360.0 - 180.0) < 1.0
        return AccessibilityResult(ok, None, sitting_pose, (), "" if ok else "touches the wall")


def test_rotation_toward_the_nao_is_asked_for_when_it_plans() -> None:
    check = _AccessibleWhenFacing(0.0)
    sitting = _sitting(0.6, 0.0, -90.0)
    choice = choose_rotation(
        box_chair_mesh(), sitting, HUMANOID, DEFAULT_ARENA, seed=0, check=check
    )
    assert choice.predicted_accessible and math.degrees(choice.rotation_rad) == pytest.approx(90)
    assert check.yaws_deg == [0]  # the paper's rotation, checked once


def test_a_chair_facing_the_nao_but_walled_in_is_turned_by_the_smallest_rotation_that_plans():
    check = _AccessibleWhenFacing(-60.0)
    sitting = _sitting(0.6, 0.0, 0.0)  # already faces the NAO at +x: the paper asks for 0
    assert compose_instruction(sitting, HUMANOID).angle_deg == 0
    choice = choose_rotation(
        box_chair_mesh(), sitting, HUMANOID, DEFAULT_ARENA, seed=0, check=check
    )
    assert math.degrees(choice.rotation_rad) == pytest.approx(-60) and choice.checked == 3
    assert check.yaws_deg == [-30, 30, -60]  # by size: 30 first, then 60
    instruction = compose_instruction(sitting, HUMANOID, rotation_rad=choice.rotation_rad)
    assert instruction.sentence.endswith("clockwise for 60 degrees") and instruction.clockwise


def test_when_no_rotation_plans_nothing_useless_is_asked_for() -> None:
    facing = choose_rotation(
        box_chair_mesh(),
        _sitting(0.6, 0.0, 0.0),
        HUMANOID,
        DEFAULT_ARENA,
        seed=0,
        check=_AccessibleWhenFacing(None),
    )
    assert facing.rotation_rad == 0.0 and not facing.predicted_accessible
    assert "no rotation" in facing.reason and "touches the wall" in facing.reason
    away = choose_rotation(
        box_chair_mesh(),
        _sitting(0.6, 0.0, 180.0),
        HUMANOID,
        DEFAULT_ARENA,
        seed=0,
        check=_AccessibleWhenFacing(None),
    )
    assert abs(math.degrees(away.rotation_rad)) == pytest.approx(180)  # the paper's still
    assert away.checked == 11


def test_rotations_are_tried_about_the_chair_centre() -> None:
    chair = box_chair_mesh()
    chair.apply_translation([0.6, 0.2, 0.0])
    sitting = _sitting(0.65, 0.2, 0.0)
    turned_chair, turned_pose = turned_about_centre(chair, sitting, math.pi / 2)
    np.testing.assert_allclose(turned_chair.bounds.mean(axis=0)[:2], [0.6, 0.2], atol=1e-9)
    np.testing.assert_allclose(turned_pose.position[:2], [0.6, 0.25], atol=1e-9)
    assert turned_pose.yaw == pytest.approx(math.pi / 2)
