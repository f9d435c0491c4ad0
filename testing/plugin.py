"""bearchair's pytest plugin (the ``pytest11`` entry point): the testing kit's fixtures.

See :mod:`bearchair.testing` for what each gives. Every fixture is function-scoped; a
project's own fixture of the same name wins over these. bearchair is imported only when
a test asks for a fixture: pytest loads this module in every session of the environment.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from bearchair.hardware.interfaces import Robot
    from bearchair.testing.scripted import ScriptedSkills


@pytest.fixture
def clean_blackboard() -> Iterator[None]:
    """An empty blackboard for the test, emptied again afterwards."""
    from bearchair.testing.ticking import fresh_blackboard

    with fresh_blackboard():
        yield


@pytest.fixture
def mission_blackboard(clean_blackboard: None) -> None:
    """A clean blackboard holding the executive's inputs: seed 0 and the default arena
    (``bearchair.behaviours.mission_inputs.set_mission_inputs``)."""
    from bearchair.behaviours.mission_inputs import set_mission_inputs

    set_mission_inputs(seed=0)


@pytest.fixture
def tick_until_done() -> Callable[..., list[Any]]:
    """:func:`bearchair.testing.tick_until_done`."""
    from bearchair.testing.ticking import tick_until_done as tick

    return tick


@pytest.fixture
def fake_robot() -> Robot:
    """A Robot of in-memory fakes whose judge says "seated" (``hardware.fakes``)."""
    from bearchair.hardware.fakes import FakeJudge
    from bearchair.hardware.fakes import fake_robot as make_fake_robot

    return make_fake_robot(judge=FakeJudge())


@pytest.fixture
def scripted_skills() -> ScriptedSkills:
    """Skills answering their defaults (script more with ``ScriptedSkills({...})``)."""
    from bearchair.testing.scripted import ScriptedSkills

    return ScriptedSkills()
