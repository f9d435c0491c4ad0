"""A skill override: instructions that thank the helper (the ``example-polite`` skills plug-in).

Selected with ``[skills] plugins = ["example-polite"]`` in a mission configuration; every
other skill stays the default one.
"""

from __future__ import annotations

from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.skills.assistance import compose_instruction
from bearchair.skills.results import Instruction

THANKS = " Thank you!"


def polite_instruction(
    sitting_pose: SittingPose, humanoid_pose: SE2Pose, rotation_rad: float | None = None
) -> Instruction:
    """The default instruction, with thanks: the same turn, asked for politely."""
    instruction = compose_instruction(sitting_pose, humanoid_pose, rotation_rad)
    return instruction._replace(sentence=instruction.sentence + THANKS)


POLITE_INSTRUCTIONS = {"compose_instruction": polite_instruction}
"""The plug-in: skill name -> the function used instead of the default."""
