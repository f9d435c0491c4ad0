"""How a seating plan fails: :class:`InfeasibleSeating`, naming the violated constraint."""

from __future__ import annotations

from bearchair.core.errors import SkillError

STANCE = "stance"
"""The constraint group of an s_goal too close to the chair (feet, or the carried bear,
in it): standing farther back may help."""


class InfeasibleSeating(SkillError, ValueError):
    """No seating motion satisfies the constraints; the message names the violated one.

    Attributes:
        constraint: the violated constraint group (for example ``"bear placement"``).
        carried_bear: a :data:`STANCE` failure caused by the carried bear (not the feet):
            raising the bear before stepping in may help.
    """

    def __init__(self, constraint: str, detail: str, *, carried_bear: bool = False) -> None:
        super().__init__(f"{constraint}: {detail}" if detail else constraint)
        self.constraint = constraint
        self.carried_bear = carried_bear
