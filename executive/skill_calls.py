"""The mission's skills, passed through, remembering some calls for the recording."""

from __future__ import annotations

import collections
from typing import Any


class SkillCalls:
    """The mission's skills, passed through, remembering what some calls returned.

    The blackboard keeps results, not every call: the walk looks for the humanoid's
    tag many times and keeps only how it ended, and only the sentences of the
    instructions are kept; the NAO's motions are not kept at all. This proxy queues
    ``(skill, result, robot seconds)`` for the watched skills (for a motion, the result
    is ``(plan, robot seconds when it began)``: what it played and from when); the
    recording logs them at the next tick, from the tick's thread.

    Args:
        skills: the :class:`bearchair.skills.mission_skills.MissionSkills` the tree uses.
        clock: the robot's clock (stamps each call).
    """

    WATCHED = ("locate_humanoid", "compose_instruction")
    MOTIONS = ("execute_seating", "release_and_stand")
    """Skills called as ``(humanoid, plan, ...)`` that play the plan's joint motion."""

    def __init__(self, skills: Any, clock: Any) -> None:
        self._skills = skills
        self._clock = clock
        self._events: collections.deque[tuple[str, Any, float]] = collections.deque()

    def __getattr__(self, name: str) -> Any:
        attribute = getattr(self._skills, name)
        if name not in self.WATCHED + self.MOTIONS or not callable(attribute):
            return attribute

        def watched(*args: Any, **kwargs: Any) -> Any:
            started_s = self._clock.now()
            result = attribute(*args, **kwargs)
            event = result
            if name in self.MOTIONS:
                event = (args[1] if len(args) > 1 else kwargs.get("plan"), started_s)
            self._events.append((name, event, self._clock.now()))
            return result

        return watched

    def drain(self) -> list[tuple[str, Any, float]]:
        """The calls returned since the last drain, oldest first (thread-safe)."""
        events = []
        while self._events:
            events.append(self._events.popleft())
        return events
