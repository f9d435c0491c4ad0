"""A trial worker that leaves a process behind holding its stdout must not hold the
campaign: the worker's exit is waited for, not the pipe's end (evaluation.worker_process)."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import textwrap
import time
from pathlib import Path

import pytest

from bearchair.evaluation.worker_process import EOF_GRACE_S, run_worker
from tests.helpers.process_tree import wait_for

# The worker prints its result, then starts a grandchild that inherits its stdout and
# outlives it: in the worker's own process group, or daemonised into a session of its
# own (beyond the group's kill). GRANDCHILD_PID names the file the grandchild's pid goes
# to; HANG makes the worker itself sleep past its timeout afterwards.
LEAVES_A_GRANDCHILD = textwrap.dedent(
    """
    import json, os, subprocess, sys, time
    payload = json.loads(sys.argv[-1])
    print("BEARCHAIR-TRIAL-RESULT " + json.dumps({"summary": {"seed": payload["seed"]}}),
          flush=True)
    own_session = os.environ["OWN_SESSION"] == "1"
    child = subprocess.Popen(["sleep", "600"], start_new_session=own_session)
    with open(os.environ["GRANDCHILD_PID"], "w") as f:
        f.write(str(child.pid))
    if os.environ.get("HANG") == "1":
        time.sleep(600)
    """
)


def _alive(pid: int) -> bool:
    try:
        return "State:\tZ" not in Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False


def _run(tmp_path: Path, monkeypatch, *, own_session: bool, hang: bool, timeout_s: float):
    script = tmp_path / "worker.py"
    script.write_text(LEAVES_A_GRANDCHILD)
    pid_file = tmp_path / "grandchild.pid"
    monkeypatch.setenv("OWN_SESSION", "1" if own_session else "0")
    monkeypatch.setenv("HANG", "1" if hang else "0")
    monkeypatch.setenv("GRANDCHILD_PID", str(pid_file))
    payload = {"out_dir": str(tmp_path / "trial"), "seed": 7}
    start = time.monotonic()
    try:
        outcome = run_worker([sys.executable, str(script)], payload, timeout_s)
        elapsed = time.monotonic() - start
        assert wait_for(pid_file.exists, 5.0)
        grandchild = int(pid_file.read_text())
        return outcome, elapsed, grandchild
    finally:
        if pid_file.exists() and pid_file.read_text():
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(pid_file.read_text()), signal.SIGKILL)


@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.parametrize("own_session", [False, True], ids=["in-its-group", "own-session"])
def test_a_grandchild_holding_stdout_does_not_hold_the_result(tmp_path, monkeypatch, own_session):
    outcome, elapsed, grandchild = _run(
        tmp_path, monkeypatch, own_session=own_session, hang=False, timeout_s=60.0
    )
    assert outcome.summary == {"seed": 7} and outcome.error is None
    # The worker exited at once: its result comes after the pipe's grace, not the timeout.
    assert elapsed < EOF_GRACE_S + 10.0
    if not own_session:  # what the worker left in its group is killed with the group
        assert wait_for(lambda: not _alive(grandchild), 5.0)


@pytest.mark.slow
@pytest.mark.timeout(120)
@pytest.mark.parametrize("own_session", [False, True], ids=["in-its-group", "own-session"])
def test_a_hung_worker_with_a_grandchild_on_its_stdout_ends_at_its_timeout(
    tmp_path, monkeypatch, own_session
):
    timeout_s = 4.0
    outcome, elapsed, _ = _run(
        tmp_path, monkeypatch, own_session=own_session, hang=True, timeout_s=timeout_s
    )
    assert outcome.summary is None and outcome.error is not None
    assert outcome.error.startswith("timed out after 4 s")
    # The timeout, the SIGTERM's grace (3 s) and the pipe's grace: not forever.
    assert elapsed < timeout_s + 3.0 + EOF_GRACE_S + 10.0
