"""Skill sets from plug-ins: the ``bearchair.skills`` entry points, checked against the protocol.

An entry point of :data:`SKILLS_GROUP` names either

- a class (or any callable of no argument) whose instances implement
  :class:`bearchair.skills.mission_skills.MissionSkills`: a whole skill set, used instead of the
  defaults; or
- a mapping ``{skill name: function}``: overrides of single skills over the set below it
  (usually the defaults), e.g. ``{"compose_instruction": polite_instruction}``.

:func:`apply_skill_plugins` stacks the named plug-ins in order over a base set. Whatever
does not satisfy the protocol (a missing method, an unknown skill name, a function that
cannot take the skill's arguments) is refused with one line naming it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, cast

from bearchair.core.errors import PluginError, one_line
from bearchair.core.plugins import load_entry_point
from bearchair.core.protocols import binding_error, protocol_gaps, protocol_members
from bearchair.skills.mission_skills import MissionSkills

SKILLS_GROUP = "bearchair.skills"
"""The entry point group of skill plug-ins."""


class OverriddenSkills:
    """A skill set with some skills replaced: every skill of ``base`` but the overridden.

    Args:
        base: the skill set underneath.
        overrides: skill name -> the function to call instead (checked by
            :func:`check_overrides`).

    ``warm_up`` and other attributes that are not skills are the base's.
    """

    def __init__(self, base: MissionSkills, overrides: Mapping[str, Callable[..., Any]]) -> None:
        self.base = base
        self.overrides = dict(overrides)
        for name in protocol_members(MissionSkills):
            setattr(self, name, self.overrides.get(name, getattr(base, name)))

    def __getattr__(self, name: str) -> Any:  # only for what is not a skill (warm_up, ...)
        if name in ("base", "overrides") or name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.base, name)


def check_overrides(overrides: object, origin: str) -> Mapping[str, Callable[..., Any]]:
    """``overrides`` checked: skill names of the protocol, each a function that can take
    that skill's arguments.

    Raises:
        PluginError: one line naming the plug-in (``origin``) and the first wrong entry.
    """
    skills = protocol_members(MissionSkills)
    if not isinstance(overrides, Mapping) or not overrides:
        raise PluginError(
            f"{origin}: skill overrides must be a non-empty mapping of name to function"
        )
    for name, function in overrides.items():
        if name not in skills:
            raise PluginError(f"{origin}: {name!r} is not a skill of MissionSkills")
        if not callable(function):
            raise PluginError(f"{origin}: the override of {name} is not callable")
        problem = binding_error(function, skills[name])
        if problem is not None:
            raise PluginError(f"{origin}: the override of {name} {problem}")
    return cast("Mapping[str, Callable[..., Any]]", overrides)


def check_skill_set(skills: object, origin: str) -> MissionSkills:
    """``skills`` if it satisfies :class:`MissionSkills`.

    Raises:
        PluginError: one line naming the plug-in and every missing or wrong skill.
    """
    gaps = protocol_gaps(skills, MissionSkills)
    if gaps:
        raise PluginError(f"{origin}: not a MissionSkills: {'; '.join(gaps)}")
    return cast("MissionSkills", skills)


def check_skill_plugins(names: Sequence[str]) -> None:
    """Loads the plug-ins ``names`` and checks what can be checked before a run: each is
    installed and loadable, and a mapping of overrides is right (a class is checked when
    :func:`apply_skill_plugins` makes it).

    Raises:
        PluginError: as :func:`apply_skill_plugins`.
    """
    for name in names:
        found = load_entry_point(SKILLS_GROUP, name, "skills plug-in")
        origin = f"skills plug-in {name!r}"
        if isinstance(found, Mapping):
            check_overrides(found, origin)
        elif not callable(found):
            raise PluginError(f"{origin}: neither a MissionSkills class nor a mapping of overrides")


def apply_skill_plugins(base: MissionSkills, names: Sequence[str]) -> MissionSkills:
    """The skill set of the plug-ins ``names``, stacked in order over ``base``.

    Raises:
        PluginError: a plug-in is not installed, cannot be loaded, or does not satisfy
            the protocol.
    """
    skills = base
    for name in names:
        origin = f"skills plug-in {name!r}"
        found = load_entry_point(SKILLS_GROUP, name, "skills plug-in")
        if isinstance(found, Mapping):
            skills = cast("MissionSkills", OverriddenSkills(skills, check_overrides(found, origin)))
            continue
        if not callable(found):
            raise PluginError(f"{origin}: neither a MissionSkills class nor a mapping of overrides")
        try:
            made = found()
        except Exception as error:
            raise PluginError(
                f"{origin}: making the skill set failed: {one_line(error)}"
            ) from error
        skills = check_skill_set(made, origin)
    return skills
