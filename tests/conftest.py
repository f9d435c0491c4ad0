"""Shared test fixtures: the calibration chairs (skipped when absent) and a clean blackboard."""

from __future__ import annotations

import json
from pathlib import Path

import py_trees
import pytest

SHARED_CHAIRS = Path(__file__).resolve().parents[2] / "shared" / "chairs"


@pytest.fixture(autouse=True)
def clean_blackboard():
    """py_trees' blackboard is process-global: every test starts with an empty one."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


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
