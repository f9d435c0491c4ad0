"""Human assistance: what to ask the helper so the chair becomes accessible.

See :mod:`skills.assistance.instruction` (the sentence) and
:mod:`skills.assistance.rotation` (which rotation to ask for).
"""

from skills.assistance.instruction import (
    INSTRUCTION_TEMPLATE,
    compose_instruction,
    instructed_rotation,
    rotation_toward,
)
from skills.assistance.rotation import choose_rotation

__all__ = [
    "INSTRUCTION_TEMPLATE",
    "choose_rotation",
    "compose_instruction",
    "instructed_rotation",
    "rotation_toward",
]
