"""Human assistance: what to ask the helper so the chair becomes accessible.

See :mod:`bearchair.skills.assistance.instruction` (the sentence) and
:mod:`bearchair.skills.assistance.rotation` (which rotation to ask for).
"""

from bearchair.skills.assistance.instruction import (
    INSTRUCTION_TEMPLATE,
    compose_instruction,
    instructed_rotation,
    rotation_toward,
)
from bearchair.skills.assistance.rotation import choose_rotation

__all__ = [
    "INSTRUCTION_TEMPLATE",
    "choose_rotation",
    "compose_instruction",
    "instructed_rotation",
    "rotation_toward",
]
