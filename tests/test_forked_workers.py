"""Trials forked from the preloaded trial server (evaluation.forked_workers)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from bearchair.evaluation.forked_workers import STDOUT_NAME, PreloadedLauncher
from bearchair.evaluation.worker_process import run_worker, run_worker_with_retry
from tests.helpers import forked_fakes


def payload(tmp_path: Path, name: str, seed: int = 0) -> dict:
    return {"out_dir": str(tmp_path / name), "seed": seed}


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # A zombie is dead too: it only waits for its parent (the server) to reap it.
    with open(f"/proc/{pid}/stat") as stat:
        return stat.read().split(")")[-1].split()[0] != "Z"


@pytest.mark.slow
def test_each_trial_is_a_fresh_fork_of_the_preloaded_server(tmp_path):
    launcher = PreloadedLauncher(forked_fakes.report)
    first = run_worker(launcher, payload(tmp_path, "a", seed=1), 120)
    second = run_worker(launcher, payload(tmp_path, "b", seed=2), 120)

    assert first.error is None and second.error is None
    assert (first.summary["seed"], second.summary["seed"]) == (1, 2)
    assert first.summary["pid"] != second.summary["pid"] != os.getpid()
    # The server imported the mission's libraries; it never ran a trial itself, so each
    # fork starts from the same state.
    assert first.summary["preloaded"] == ["casadi", "open3d", "pybullet"]
    assert first.summary["runs_in_this_process"] == second.summary["runs_in_this_process"] == 1
    assert first.summary["session_leader"]  # its group can be killed without the harness
    # stderr goes to the run folder's worker.log; the stdout file is read and removed.
    assert (tmp_path / "a" / "worker.log").read_text().strip().endswith("a warning")
    assert not (tmp_path / "a" / STDOUT_NAME).exists()


@pytest.mark.slow
def test_a_forked_trial_past_its_timeout_is_killed(tmp_path):
    started = time.monotonic()
    outcome = run_worker(PreloadedLauncher(forked_fakes.sleep_forever), payload(tmp_path, "t"), 8)

    assert outcome.summary is None and "timed out after 8 s" in outcome.error
    assert time.monotonic() - started < 8 + 15
    pid = int((tmp_path / "t" / "pid").read_text())
    assert not alive(pid)


def test_a_crashed_fork_is_retried_once_and_named(tmp_path):
    outcome = run_worker_with_retry(
        PreloadedLauncher(forked_fakes.segfault), payload(tmp_path, "c"), 60
    )

    assert outcome.crashed and outcome.attempts == 2
    assert "killed by SIGSEGV" in outcome.error
    assert "Fatal Python error" in outcome.error  # faulthandler's line from worker.log


def test_an_entry_that_raises_is_a_crash_with_its_last_words(tmp_path):
    outcome = run_worker(PreloadedLauncher(forked_fakes.raise_error), payload(tmp_path, "e"), 60)

    assert outcome.summary is None and outcome.crashed
    assert "exited with status 1" in outcome.error and "the entry failed" in outcome.error


def test_stopping_the_harness_stops_a_forked_trial(tmp_path):
    import threading

    from bearchair.evaluation.worker_process import ProcessGroup

    group = ProcessGroup()
    outcomes = []
    thread = threading.Thread(
        target=lambda: outcomes.append(
            run_worker(
                PreloadedLauncher(forked_fakes.sleep_forever), payload(tmp_path, "s"), 300, group
            )
        )
    )
    thread.start()
    pid_file = tmp_path / "s" / "pid"
    deadline = time.monotonic() + 60
    while not pid_file.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert group.stop_all() == 1
    thread.join(30)

    assert outcomes and outcomes[0].cancelled
    assert not alive(int(pid_file.read_text()))
