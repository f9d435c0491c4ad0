"""Trial workers forked from a server that has already paid the imports.

A trial started as a command pays, in a fresh interpreter, about 1.9 s of imports
(open3d, casadi, pybullet, the project) and 1.2 s building the whole-body planner's
casadi problems, in every trial. Here one server process (the standard library's
``multiprocessing`` forkserver, preloading :mod:`bearchair.evaluation.server_preload`)
pays them once, and each trial is a fork of it.

A trial still runs in a process of its own that no other trial has run in, in a session
of its own that dies with the server (which dies with the harness): the server never
runs a mission, and what it holds is the same for every trial, so the same seed gives
the same outcome as in a fresh interpreter. A crash (a native library's segfault) takes
only its fork.
"""

from __future__ import annotations

import contextlib
import json
import multiprocessing
import multiprocessing.forkserver
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from bearchair.core.held_signals import holding_stop_signals
from bearchair.core.runtime import RUNTIME, reap
from bearchair.evaluation.worker import main, run_guarded
from bearchair.evaluation.worker_process import LOG_NAME, die_with_parent

PRELOAD_MODULE = "bearchair.evaluation.server_preload"
STDOUT_NAME = "worker.stdout"
"""A forked worker's stdout, in its run folder until the harness has read it."""

_server_lock = threading.Lock()
_context: Any = None


def _forkserver() -> Any:
    """The process-wide forkserver context, its preload set before its first use; the
    server registers with the runtime, which stops it (``bearchair.core.runtime``)."""
    global _context
    with _server_lock:
        if _context is None:
            _context = multiprocessing.get_context("forkserver")
            _context.set_forkserver_preload([PRELOAD_MODULE])
            RUNTIME.register("trial server", shutdown=stop_trial_server, kill=_kill_trial_server)
        return _context


def stop_trial_server(timeout_s: float) -> bool:
    """Stops the trial server once no trial runs: it ends when its "alive" pipe closes,
    and is reaped within ``timeout_s`` (else SIGKILLed). True when it is gone.

    The server is multiprocessing's private state (``multiprocessing.forkserver``, no
    public API stops it); left alone, it outlives the harness for a moment.
    """
    server: Any = multiprocessing.forkserver._forkserver  # pyright: ignore[reportAttributeAccessIssue]  # private
    if multiprocessing.active_children():
        return False
    with server._lock:
        pid, alive_fd = server._forkserver_pid, server._forkserver_alive_fd
        if pid is None:
            return True
        server._forkserver_pid = server._forkserver_alive_fd = None
        with contextlib.suppress(OSError, TypeError):
            os.close(alive_fd)
    return reap(pid, timeout_s)


def _kill_trial_server() -> None:
    """SIGKILLs the trial server and reaps it (a second stop signal)."""
    server: Any = multiprocessing.forkserver._forkserver  # pyright: ignore[reportAttributeAccessIssue]  # private
    pid = server._forkserver_pid
    if pid is not None:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
        reap(pid, 2.0)


def _run_forked(entry: Callable[[list[str]], int], payload_json: str, out_dir: str) -> None:
    """In the fork: a session of its own, stdout to a file and stderr to the run
    folder's log, then ``entry`` guarded as a worker (``bearchair.evaluation.worker.run_guarded``).
    """
    os.setsid()
    die_with_parent()
    for fd, path, mode in (
        (1, Path(out_dir) / STDOUT_NAME, os.O_WRONLY | os.O_CREAT | os.O_TRUNC),
        (2, Path(out_dir) / LOG_NAME, os.O_WRONLY | os.O_CREAT | os.O_APPEND),
    ):
        target = os.open(path, mode, 0o644)
        os.dup2(target, fd)
        os.close(target)
    try:
        code = run_guarded(entry, [payload_json])
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
    sys.exit(code)


class ForkedWorker:
    """A forked worker, seen through the part of ``subprocess.Popen`` the harness uses."""

    def __init__(self, process: Any, out_dir: Path) -> None:
        self._process = process
        self._stdout_path = out_dir / STDOUT_NAME
        self.pid: int = process.pid

    @property
    def returncode(self) -> int | None:
        return self._process.exitcode

    def wait(self, timeout: float | None = None) -> int:
        self._process.join(timeout)
        if self._process.exitcode is None:
            raise subprocess.TimeoutExpired(f"trial worker {self.pid}", timeout or 0.0)
        return self._process.exitcode

    def communicate(self, timeout: float | None = None) -> tuple[str, None]:
        self.wait(timeout)
        try:
            text = self._stdout_path.read_text(errors="replace")
        except OSError:
            return "", None
        self._stdout_path.unlink(missing_ok=True)
        return text, None


class PreloadedLauncher:
    """Starts each trial worker as a fork of the preloaded trial server.

    The server starts (and preloads, about 3 s) on the first trial; it stops when the
    harness does.

    Args:
        entry: what the fork runs on ``[payload_json]``, returning its exit status; a
            module-level function (it is sent to the server by name). The default is
            the trial worker, ``bearchair.evaluation.worker.main``.
    """

    def __init__(self, entry: Callable[[list[str]], int] = main) -> None:
        self.entry = entry

    def start(self, payload_json: str, log: IO[str]) -> ForkedWorker:
        out_dir = Path(json.loads(payload_json)["out_dir"])
        log.flush()
        process = _forkserver().Process(
            target=_run_forked,
            args=(self.entry, payload_json, str(out_dir)),
            name="trial",
            daemon=False,
        )
        with holding_stop_signals():  # a half-started fork would belong to no one
            process.start()
        return ForkedWorker(process, out_dir)
