"""The real skills' binding (skills.default_skills) against the protocol the tree uses."""

from __future__ import annotations

import inspect

from bearchair.skills.default_skills import DefaultSkills
from bearchair.skills.mission_skills import MissionSkills


def protocol_methods() -> set[str]:
    return {
        name
        for name, member in vars(MissionSkills).items()
        if inspect.isfunction(member) and not name.startswith("_")
    }


def test_every_skill_the_tree_asks_for_is_bound_to_a_function():
    skills = DefaultSkills(imagination_workers=1)
    missing = {name for name in protocol_methods() if not callable(getattr(skills, name, None))}
    assert not missing


def test_each_bound_skill_takes_the_protocols_keywords():
    skills = DefaultSkills(imagination_workers=1)
    for name in protocol_methods() - {"imagine_sitting"}:
        wanted = inspect.signature(getattr(MissionSkills, name)).parameters
        bound = inspect.signature(getattr(skills, name)).parameters
        keywords = {p for p, v in wanted.items() if v.kind is v.KEYWORD_ONLY}
        assert keywords <= set(bound), f"{name}: {keywords - set(bound)}"
        positional = [p for p, v in wanted.items() if v.kind is v.POSITIONAL_OR_KEYWORD][1:]
        assert len(positional) <= len(bound), name
