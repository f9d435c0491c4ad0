"""Ticking a behaviour in a test, and the blackboard around it."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator, Mapping
from typing import Any

import py_trees
from py_trees.common import Access, Status

from bearchair.hardware.interfaces import Robot
from bearchair.skills.mission_skills import MissionSkills


def tick_until_done(
    behaviour: py_trees.behaviour.Behaviour, max_ticks: int = 400, period_s: float = 0.005
) -> list[Status]:
    """Ticks ``behaviour`` until it is no longer RUNNING; returns every status seen.

    Between two ticks it sleeps ``period_s`` (wall seconds), so a leaf's worker thread runs.

    Raises:
        AssertionError: still RUNNING after ``max_ticks`` ticks (the test fails, naming it).
    """
    statuses = []
    for _ in range(max_ticks):
        behaviour.tick_once()
        statuses.append(behaviour.status)
        if behaviour.status != Status.RUNNING:
            return statuses
        time.sleep(period_s)
    raise AssertionError(f"{behaviour.name} still RUNNING after {max_ticks} ticks")


@contextlib.contextmanager
def fresh_blackboard() -> Iterator[None]:
    """py_trees' blackboard is process-global: empty inside, emptied again on the way out."""
    py_trees.blackboard.Blackboard.clear()
    try:
        yield
    finally:
        py_trees.blackboard.Blackboard.clear()


def write_blackboard(values: Mapping[str, Any], client_name: str = "test") -> None:
    """Writes absolute keys (``/chair/mesh``) as earlier stages would have left them."""
    writer = py_trees.blackboard.Client(name=client_name)
    for key, value in values.items():
        writer.register_key(key=key, access=Access.WRITE)
        writer.set(key, value, overwrite=True)


def set_up(
    behaviour: py_trees.behaviour.Behaviour,
    skills: MissionSkills | None = None,
    robot: Robot | None = None,
) -> py_trees.behaviour.Behaviour:
    """Sets every node of ``behaviour`` up as the executive does
    (``setup(skills=..., robot=...)``); returns it, for ``tick_until_done(set_up(leaf))``."""
    for node in behaviour.iterate():
        node.setup(skills=skills, robot=robot)
    return behaviour
