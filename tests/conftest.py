"""Shared test fixtures: the calibration chairs (skipped when absent), a clean blackboard
and a fresh runtime.

The testing kit's fixtures (``bearchair.testing``: ``mission_blackboard``,
``tick_until_done``, ``fake_robot``, ``scripted_skills``) come from its pytest plugin.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bearchair.testing import fresh_blackboard

SHARED_CHAIRS = Path(__file__).resolve().parents[2] / "shared" / "chairs"
RUNTIME_JOIN_S = 30.0
"""How long a test's background threads (the planner's build: 0.7 s alone, a few times
that on the loaded 2-core machine) are waited for after it."""


@pytest.fixture(autouse=True)
def clean_blackboard():
    """py_trees' blackboard is process-global: every test starts with an empty one (the
    kit's fixture of the same name, made automatic here)."""
    with fresh_blackboard():
        yield


@pytest.fixture(autouse=True)
def fresh_runtime():
    """The process's memos (``bearchair.core.runtime``) start empty in every test, so no
    answer depends on which tests ran before; the threads a test started are joined
    after it, so none runs on into the next test or the interpreter's exit."""
    from bearchair.core.runtime import RUNTIME

    RUNTIME.reset()
    yield
    RUNTIME.join_threads(RUNTIME_JOIN_S)


@pytest.fixture(scope="session")
def shared_chairs() -> Path:
    """The calibration meshes folder; the test is skipped when it is absent."""
    if not (SHARED_CHAIRS / "manifest.json").is_file():
        pytest.skip(f"calibration chairs not found at {SHARED_CHAIRS}")
    return SHARED_CHAIRS


@pytest.fixture(scope="session")
def shared_manifest(shared_chairs: Path) -> list[dict]:
    """The calibration manifest's entries."""
    return json.loads((shared_chairs / "manifest.json").read_text())["meshes"]
