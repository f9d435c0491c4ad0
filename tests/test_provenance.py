"""Every record names the software that made it: bearchair's version, commit, dependencies."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import casadi
import numpy
import py_trees

from bearchair.core import provenance
from bearchair.evaluation.protocol import ChairEntry, expand_protocol
from bearchair.evaluation.store import TrialStore, record_from_error, record_from_summary
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import RunSummary

REPO = Path(__file__).resolve().parents[1]


def test_version_prints_the_installed_version_and_the_checkout_commit():
    done = subprocess.run(
        [sys.executable, "-m", "bearchair.executive.cli", "--version"],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=REPO,
    )
    assert done.returncode == 0, done.stderr
    line = done.stdout.strip()
    assert line.startswith(f"bearchair {provenance.bearchair_version()}")
    head = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    if head:  # a checkout: the commit is named
        assert f"commit {head[:12]}" in line


def test_software_versions_name_the_key_dependencies_as_installed():
    software = provenance.software_versions()
    assert software["dependencies"]["numpy"] == numpy.__version__
    assert software["dependencies"]["casadi"] == casadi.__version__
    assert set(software["dependencies"]) == set(provenance.KEY_DISTRIBUTIONS)
    assert provenance.distribution_version("no-such-distribution-xyz") is None


def test_every_summary_carries_the_software(tmp_path):
    recorder = RunRecorder(tmp_path, py_trees.behaviours.Success(name="leaf"))
    try:
        path = recorder.write_summary(RunSummary(outcome="success"))
    finally:
        recorder.close()
    summary = json.loads(path.read_text())
    assert summary["outcome"] == "success"
    assert summary["software"] == json.loads(json.dumps(provenance.software_versions()))


def test_every_trial_row_carries_the_software(tmp_path):
    chair = ChairEntry(path=tmp_path / "c.obj", kind="chair", front_yaw_deg=0.0)
    first, second = expand_protocol([chair])[:2]
    made_by = {"bearchair": "9.9.9", "git_commit": "abc", "dependencies": {"numpy": "1"}}
    store = TrialStore(tmp_path / "trials.sqlite")
    try:
        store.add(
            record_from_summary(
                first,
                RunSummary.from_json({"outcome": "success", "software": made_by}),
                1.0,
                None,
            )
        )
        store.add(record_from_error(second, "worker crashed", 1.0, None))
        rows = {row.trial_index: row for row in store.records()}
    finally:
        store.close()
    assert rows[first.trial_index].software == made_by  # the worker's own summary
    assert (rows[second.trial_index].software or {})["bearchair"] == provenance.bearchair_version()
