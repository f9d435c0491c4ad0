"""Human assistance: what to ask the helper so the chair becomes accessible.

See :mod:`skills.assistance.instruction`.
"""

from skills.assistance.instruction import (
    INSTRUCTION_TEMPLATE,
    compose_instruction,
    instructed_rotation,
    rotation_toward,
)

__all__ = ["INSTRUCTION_TEMPLATE", "compose_instruction", "instructed_rotation", "rotation_toward"]
