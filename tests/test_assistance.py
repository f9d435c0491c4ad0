"""The helper instruction: rounding, directions, wrap-around, and an obeying helper."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skills.assistance import compose_instruction, instructed_rotation, rotation_toward
from skills.geometry import SE2Pose, SittingPose


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
