"""Running one trial in its own subprocess, whatever happens to it.

The trial worker (``python -m executive.trial_worker '<json>'``) prints one line
``BEARCHAIR-TRIAL-RESULT {"summary": ...}`` (or ``{"error": ...}``) on stdout. Its
stderr goes to ``worker.log`` in the trial's run directory. A worker that dies (for
example a segfault in a native library) or outlives its timeout is reported with an
error instead; a timed-out worker is killed with its whole process group (the
imagination's pool processes included).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, NamedTuple

RESULT_MARKER = "BEARCHAIR-TRIAL-RESULT "
KILL_GRACE_S = 3.0
"""Time a worker gets between SIGTERM and SIGKILL."""


class WorkerOutcome(NamedTuple):
    """What came back from one trial subprocess.

    Attributes:
        summary: the mission's summary (``executive.mission``), None when it did not end.
        error: why there is no summary (crash, timeout, exception), None otherwise.
        wall_seconds: the subprocess's wall time, world building included.
        cancelled: the harness stopped it (Ctrl-C): not a result, never recorded.
    """

    summary: dict[str, Any] | None
    error: str | None
    wall_seconds: float
    cancelled: bool = False


def default_worker_command() -> list[str]:
    """The real trial worker, with this interpreter (the trial JSON is appended)."""
    return [sys.executable, "-m", "executive.trial_worker"]


class ProcessGroup:
    """The live trial subprocesses, so Ctrl-C can stop every one of them.

    Each worker starts in its own session (so the terminal's Ctrl-C does not reach it
    and make it write an "interrupted" summary that would look like a result); stopping
    signals its whole process group.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._live: set[subprocess.Popen] = set()
        self.stopping = False

    def start(self, command: list[str], **popen_kwargs: Any) -> subprocess.Popen | None:
        """Starts a worker unless the group is stopping (then returns None)."""
        with self._lock:
            if self.stopping:
                return None
            process = subprocess.Popen(command, start_new_session=True, **popen_kwargs)
            self._live.add(process)
            return process

    def finished(self, process: subprocess.Popen) -> None:
        with self._lock:
            self._live.discard(process)

    def stop_all(self) -> int:
        """Stops every live worker (SIGTERM, then SIGKILL); returns how many there were."""
        with self._lock:
            self.stopping = True
            live = list(self._live)
        for process in live:
            kill_process_group(process)
        return len(live)


def kill_process_group(process: subprocess.Popen, grace_s: float = KILL_GRACE_S) -> None:
    """SIGTERM to the worker's process group, SIGKILL if still alive after ``grace_s``."""
    for sig, wait_s in ((signal.SIGTERM, grace_s), (signal.SIGKILL, 5.0)):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, sig)
        try:
            process.wait(timeout=wait_s)
            break
        except subprocess.TimeoutExpired:
            continue
    # Leftover grandchildren of the group (pool processes) go with SIGKILL too.
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signal.SIGKILL)


def run_worker(
    command: list[str],
    payload: dict[str, Any],
    timeout_s: float,
    group: ProcessGroup | None = None,
) -> WorkerOutcome:
    """Runs one trial worker to its end, its crash or its timeout.

    Args:
        command: the worker command; the payload's JSON is appended as the last argument.
        payload: the trial (``TrialSpec.to_payload``); ``out_dir`` is created.
        timeout_s: wall time after which the worker is killed and the trial failed.
        group: registers the process so the harness can stop it on Ctrl-C.
    """
    group = group or ProcessGroup()
    out_dir = Path(payload["out_dir"])
    out_dir.mkdir(parents=True, exist_ok=True)
    log_path = out_dir / "worker.log"
    start = time.monotonic()
    with open(log_path, "w") as log:
        process = group.start(
            [*command, json.dumps(payload)],
            stdout=subprocess.PIPE,
            stderr=log,
            stdin=subprocess.DEVNULL,
            text=True,
        )
        if process is None:
            return WorkerOutcome(None, "not started: the harness is stopping", 0.0, cancelled=True)
        try:
            stdout, _ = process.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            kill_process_group(process)
            process.communicate()
            group.finished(process)
            elapsed = time.monotonic() - start
            if group.stopping:
                return WorkerOutcome(None, "stopped by the harness", elapsed, cancelled=True)
            return WorkerOutcome(None, f"timed out after {timeout_s:.0f} s: worker killed", elapsed)
        except BaseException:  # KeyboardInterrupt (a Ray task cancelled): take the worker along
            kill_process_group(process)
            group.finished(process)
            raise
        group.finished(process)
    elapsed = time.monotonic() - start
    if group.stopping:
        return WorkerOutcome(None, "stopped by the harness", elapsed, cancelled=True)
    message = _last_result(stdout)
    if message is not None and "summary" in message:
        return WorkerOutcome(message["summary"], None, elapsed)
    if message is not None and "error" in message:
        return WorkerOutcome(None, f"worker error: {message['error']}", elapsed)
    return WorkerOutcome(None, _crash_description(process.returncode, log_path), elapsed)


def _last_result(stdout: str) -> dict[str, Any] | None:
    for line in reversed(stdout.splitlines()):
        if line.startswith(RESULT_MARKER):
            try:
                message = json.loads(line[len(RESULT_MARKER) :])
            except json.JSONDecodeError:
                return None
            return message if isinstance(message, dict) else None
    return None


def _crash_description(returncode: int, log_path: Path) -> str:
    if returncode < 0:
        try:
            how = f"killed by {signal.Signals(-returncode).name}"
        except ValueError:
            how = f"killed by signal {-returncode}"
    else:
        how = f"exited with status {returncode} without a result"
    tail = _last_log_line(log_path)
    return f"worker crashed: {how}" + (f" ({tail})" if tail else "")


def _last_log_line(log_path: Path, max_chars: int = 200) -> str:
    """The most telling line of the worker's stderr: a fatal error, else the last line."""
    try:
        lines = [line.strip() for line in log_path.read_text(errors="replace").splitlines()]
    except OSError:
        return ""
    lines = [line for line in lines if line]
    for line in lines:
        if line.startswith("Fatal Python error"):
            return line[:max_chars]
    return lines[-1][:max_chars] if lines else ""
