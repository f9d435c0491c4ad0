"""The skill override: polite, still understood, accepted by bearchair's plug-in check."""

import math

import numpy as np

from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.sim.helper import parse_instruction
from bearchair.skills.skill_sets import apply_skill_plugins
from bearchair.testing import ScriptedSkills
from bearchair_example.skills import THANKS, polite_instruction

SEAT_FACING_AWAY = SittingPose(position=np.array([0.6, 0.0, 0.3]), yaw=math.pi)
HUMANOID = SE2Pose(1.9, 0.0, math.pi)


def test_the_polite_instruction_thanks_and_the_simulated_helper_still_understands_it():
    instruction = polite_instruction(SEAT_FACING_AWAY, HUMANOID)
    assert instruction.sentence.endswith(THANKS)
    heard = parse_instruction(instruction.sentence)
    assert heard is not None and round(abs(math.degrees(heard.signed_angle_rad))) == 180


def test_the_plugin_overrides_only_compose_instruction():
    base = ScriptedSkills()
    skills = apply_skill_plugins(base, ["example-polite"])
    sentence = skills.compose_instruction(SEAT_FACING_AWAY, HUMANOID).sentence
    assert sentence.endswith(THANKS) and not base.calls["compose_instruction"]
    assert skills.scan_chair == base.scan_chair
