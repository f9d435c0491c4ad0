"""Shared test fixtures: the calibration chairs (skipped when absent) and a clean blackboard.

The testing kit's fixtures (``bearchair.testing``: ``mission_blackboard``,
``tick_until_done``, ``fake_robot``, ``scripted_skills``) come from its pytest plugin.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bearchair.testing import fresh_blackboard

SHARED_CHAIRS = Path(__file__).resolve().parents[2] / "shared" / "chairs"


@pytest.fixture(autouse=True)
def clean_blackboard():
    """py_trees' blackboard is process-global: every test starts with an empty one (the
    kit's fixture of the same name, made automatic here)."""
    with fresh_blackboard():
        yield


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
