"""Running one trial in its own subprocess, whatever happens to it.

The trial worker (``bearchair.evaluation.worker.main``) prints one line
``BEARCHAIR-TRIAL-RESULT {"summary": ...}`` (or ``{"error": ...}``) on stdout. Its
stderr goes to ``worker.log`` in the trial's run directory. A :class:`WorkerLauncher`
starts it: :class:`CommandLauncher` as a command (``python -m bearchair.evaluation.worker
'<json>'``, a fresh interpreter), ``bearchair.evaluation.forked_workers.PreloadedLauncher``
as a fork of a server that has already imported the mission's modules. A worker that dies (for
example a segfault in a native library) or outlives its timeout is reported with an
error instead; a timed-out worker is killed with its whole process group (the
imagination's pool processes included).
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import IO, Any, NamedTuple, Protocol

from bearchair.core.errors import RecordStoreError
from bearchair.core.userfiles import parse_json

RESULT_MARKER = "BEARCHAIR-TRIAL-RESULT "
LOG_NAME = "worker.log"
"""The worker's stderr, in its run folder."""
KILL_GRACE_S = 3.0
"""Time a worker gets between SIGTERM and SIGKILL."""
EOF_GRACE_S = 2.0
"""Time a worker's stdout gets to end after the worker exited (seconds): what the worker
wrote is in the pipe by then; only a process it left behind keeps the pipe open longer."""
STDOUT_POLL_S = 0.5
"""How often the wait for a worker's output checks whether the worker has exited."""


class WorkerOutcome(NamedTuple):
    """What came back from one trial subprocess.

    Attributes:
        summary: the JSON the worker printed: a run summary (``RunSummary.to_json``, read
            with ``RunSummary.from_json``), or a bench's own result; None when it did not end.
        error: why there is no summary (crash, timeout, exception), None otherwise.
        wall_seconds: the subprocess's wall time, world building included.
        cancelled: the harness stopped it (Ctrl-C): not a result, never recorded.
        crashed: the worker died without a result (a signal, an exit without the result
            line): worth one retry, unlike a timeout or an error the mission reported.
        attempts: how many times the worker ran (2 after a retry).
    """

    summary: dict[str, Any] | None
    error: str | None
    wall_seconds: float
    cancelled: bool = False
    crashed: bool = False
    attempts: int = 1


def default_worker_command() -> list[str]:
    """The real trial worker, with this interpreter (the trial JSON is appended)."""
    return [sys.executable, "-m", "bearchair.evaluation.worker"]


class WorkerHandle(Protocol):
    """A started worker, as much of ``subprocess.Popen`` as the harness uses.

    The worker runs in a process group of its own whose id is ``pid``.
    """

    pid: int

    @property
    def returncode(self) -> int | None: ...

    def wait(self, timeout: float | None = None) -> int:
        """Its exit status (negative: the signal that killed it); raises
        ``subprocess.TimeoutExpired`` if it is still running after ``timeout`` s."""
        ...

    def communicate(self, *, timeout: float | None = None) -> tuple[str, Any]:
        """Waits as :meth:`wait` does and returns what it printed on stdout (and None)."""
        ...


class WorkerLauncher(Protocol):
    """Starts trial workers."""

    def start(self, payload_json: str, log: IO[str]) -> WorkerHandle:
        """Starts one worker on a trial, its stderr into ``log``, in a new session that
        dies with the harness."""
        ...


class CommandLauncher:
    """Workers started as a command (a fresh interpreter each), the trial's JSON appended.

    Args:
        command: the worker command (tests inject a fake one).
        env: the worker's environment; None: this process's.
    """

    def __init__(self, command: list[str] | None = None, env: dict[str, str] | None = None) -> None:
        self.command = command or default_worker_command()
        self.env = env

    def start(self, payload_json: str, log: IO[str]) -> subprocess.Popen[str]:
        return subprocess.Popen(
            [*self.command, payload_json],
            stdout=subprocess.PIPE,
            stderr=log,
            stdin=subprocess.DEVNULL,
            text=True,
            env=self.env,
            start_new_session=True,
            preexec_fn=die_with_parent,
        )


def as_launcher(how: WorkerLauncher | list[str] | None) -> WorkerLauncher:
    """A launcher; a command (a list) is started with :class:`CommandLauncher`."""
    if how is None or isinstance(how, list):
        return CommandLauncher(how)
    return how


class ProcessGroup:
    """The live trial subprocesses, so Ctrl-C can stop every one of them.

    Each worker starts in its own session (so the terminal's Ctrl-C does not reach it
    and make it write an "interrupted" summary that would look like a result); stopping
    signals its whole process group.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._live: set[WorkerHandle] = set()
        self.stopping = False

    def start(
        self, launcher: WorkerLauncher, payload_json: str, log: IO[str]
    ) -> WorkerHandle | None:
        """Starts a worker unless the group is stopping (then returns None)."""
        with self._lock:
            if self.stopping:
                return None
            process = launcher.start(payload_json, log)
            self._live.add(process)
            return process

    def kill_all_now(self) -> None:
        """SIGKILLs every live worker's group without waiting (a second Ctrl-C)."""
        self.stopping = True
        for process in list(self._live):
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)

    def finished(self, process: WorkerHandle) -> None:
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


_PR_SET_PDEATHSIG = 1
try:
    _libc: Any = ctypes.CDLL(None, use_errno=True)  # loaded before any fork
except OSError:  # not Linux, or no libc symbols: the orphan watch in the worker remains
    _libc = None


def die_with_parent() -> None:
    """In a forked child: SIGKILL it when its parent dies (even by SIGKILL).

    The workers run in their own sessions (the terminal's Ctrl-C must not reach them),
    so without this a killed harness would orphan them and they would go on writing
    into run folders that a resumed campaign is reusing.
    """
    if _libc is not None:
        _libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)


def kill_process_group(process: WorkerHandle, grace_s: float = KILL_GRACE_S) -> None:
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
    launcher: WorkerLauncher | list[str],
    payload: dict[str, Any],
    timeout_s: float,
    group: ProcessGroup | None = None,
) -> WorkerOutcome:
    """Runs one trial worker to its end, its crash or its timeout.

    Args:
        launcher: starts the worker; a list is a worker command, the payload's JSON
            appended as its last argument.
        payload: the trial (``TrialSpec.to_payload``); ``out_dir`` is created.
        timeout_s: wall time after which the worker is killed and the trial failed.
        group: registers the process so the harness can stop it on Ctrl-C.
    """
    group = group or ProcessGroup()
    out_dir = Path(payload["out_dir"])
    out_dir.mkdir(parents=True, exist_ok=True)
    log_path = out_dir / LOG_NAME
    start = time.monotonic()
    with open(log_path, "w") as log:
        process = group.start(as_launcher(launcher), json.dumps(payload), log)
        if process is None:
            return WorkerOutcome(None, "not started: the harness is stopping", 0.0, cancelled=True)
        try:
            stdout = _stdout_of(process, timeout_s)
        except subprocess.TimeoutExpired:
            kill_process_group(process)
            with contextlib.suppress(subprocess.TimeoutExpired):
                _stdout_of(process, EOF_GRACE_S)  # a pipe held by what escaped is given up
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
    returncode = process.returncode
    assert returncode is not None  # communicate() returned: the worker has exited
    return WorkerOutcome(None, _crash_description(returncode, log_path), elapsed, crashed=True)


def _stdout_of(process: WorkerHandle, timeout_s: float) -> str:
    """What the worker printed, once it has exited and its stdout ended.

    The worker's exit is waited for, not its stdout's end alone: a grandchild that keeps
    the pipe open (one daemonised into a session of its own escapes the group's kill)
    would otherwise hold the campaign forever. Once the worker has exited, its group is
    killed and the pipe given :data:`EOF_GRACE_S` to end; then what was read is taken.

    Raises:
        subprocess.TimeoutExpired: the worker itself still runs after ``timeout_s``.
    """
    deadline = time.monotonic() + timeout_s
    exited_at: float | None = None
    while True:
        now = time.monotonic()
        step = min(STDOUT_POLL_S, max(deadline - now, 0.0))
        try:
            stdout, _ = process.communicate(timeout=step)
            return stdout or ""
        except subprocess.TimeoutExpired as expired:
            partial = expired.output
        if exited_at is None and process.returncode is None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(timeout=0)
        if process.returncode is not None:
            exited_at = exited_at or now
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(process.pid, signal.SIGKILL)  # what it left in its group
            if now - exited_at >= EOF_GRACE_S:
                with contextlib.suppress(OSError, AttributeError):
                    process.stdout.close()  # pyright: ignore[reportAttributeAccessIssue]  # Popen's
                if isinstance(partial, bytes):
                    return partial.decode(errors="replace")
                return partial or ""
        elif now >= deadline:
            raise subprocess.TimeoutExpired(f"trial worker {process.pid}", timeout_s)


def run_worker_with_retry(
    launcher: WorkerLauncher | list[str],
    payload: dict[str, Any],
    timeout_s: float,
    group: ProcessGroup | None = None,
) -> WorkerOutcome:
    """:func:`run_worker`, run once more (from a clean run folder) if the worker crashed.

    A killed or crashed worker (out of memory, a native library's segfault) says
    nothing about the trial; a second crash is recorded, with ``attempts`` 2.
    """
    group = group or ProcessGroup()
    first = run_worker(launcher, payload, timeout_s, group)
    if not first.crashed or group.stopping:
        return first
    out_dir = Path(payload["out_dir"])
    with contextlib.suppress(OSError):
        shutil.rmtree(out_dir)
    second = run_worker(launcher, payload, timeout_s, group)
    error = second.error
    if error is not None and not second.cancelled:
        error = f"{error} (retried once; first: {first.error})"
    return second._replace(error=error, attempts=2)


def _last_result(stdout: str) -> dict[str, Any] | None:
    for line in reversed(stdout.splitlines()):
        if line.startswith(RESULT_MARKER):
            try:  # bounded: a worker's output is data like any other
                message = parse_json(line[len(RESULT_MARKER) :], "result", RecordStoreError)
            except RecordStoreError:
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
