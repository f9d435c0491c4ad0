"""The testing kit: what a test of a leaf, a tree or a skill set needs, installed with bearchair.

Import it (``from bearchair.testing import ScriptedSkills, tick_until_done``) or use its
pytest fixtures, which pytest loads by itself wherever bearchair is installed (the
``pytest11`` entry point names :mod:`bearchair.testing.plugin`):

================== =====================================================================
fixture            gives
================== =====================================================================
clean_blackboard   an empty py_trees blackboard (emptied again afterwards)
mission_blackboard a clean blackboard holding the executive's inputs (seed 0, the arena)
tick_until_done    :func:`tick_until_done`
fake_robot         a :class:`bearchair.hardware.interfaces.Robot` of in-memory fakes
scripted_skills    a :class:`ScriptedSkills` with every default answer
================== =====================================================================

Its modules besides the fixtures: :mod:`bearchair.testing.scripted` (skills answering
from a script, each stub checked against the real skill's signature),
:mod:`bearchair.testing.chairgen` (generated chairs of known geometry, with
``chairgen_families``) and :mod:`bearchair.testing.synthetic_scenes` (rendered RGB-D
frames of meshes, tags and calibration boards, without a simulated world).

Layering: this room may import everything below the executive (core, hardware, skills,
behaviours, trees): a kit for testing leaves and trees must not pull in the executive's
run loop, CLI and recordings, and nothing in bearchair imports the kit (only tests do).
"""

from __future__ import annotations

from bearchair.hardware.fakes import (
    FakeArm,
    FakeClock,
    FakeHumanoid,
    FakeJudge,
    FakeSpeaker,
    FakeTagTracker,
    fake_robot,
)
from bearchair.testing.scripted import ScriptedSkills, default_results
from bearchair.testing.ticking import (
    fresh_blackboard,
    set_up,
    tick_until_done,
    write_blackboard,
)

__all__ = [
    "FakeArm",
    "FakeClock",
    "FakeHumanoid",
    "FakeJudge",
    "FakeSpeaker",
    "FakeTagTracker",
    "ScriptedSkills",
    "default_results",
    "fake_robot",
    "fresh_blackboard",
    "set_up",
    "tick_until_done",
    "write_blackboard",
]
