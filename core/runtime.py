"""The process's state in one home: every memo, pool and background thread the project
keeps registers here with how to forget it (``reset``) and how to stop it (``shutdown``).

Why one home: a thread still building casadi problems, a qi callback or a pool's
management thread running while the interpreter tears itself down ends the process with
SIGABRT, SIGSEGV or SIGBUS after its work is done; and state one test leaves behind (a
memo's answers) changes what the next one sees. So:

- the executive calls :meth:`Runtime.shutdown` on its way out: pools are shut down and
  threads joined, each within a bound, before the interpreter's own exit;
- a stop signal that cannot wait (the second Ctrl-C) calls :meth:`Runtime.kill`, which
  SIGKILLs and reaps the child processes at once;
- tests call :meth:`Runtime.reset` between tests (``tests/conftest.py``), instead of
  replacing private module names.

Modules register at import (``RUNTIME.register(...)``, or a named
:class:`bearchair.core.memo.BoundedMemo`), threads are started through
:meth:`Runtime.start_thread`, so a new pool or thread is one line away from being
stopped properly. Not registered: ``functools.lru_cache`` over functions of fixed inputs
(the parsed NAO model, the reach table, ArUco detectors, the planner's built problems),
which answer the same whatever ran before, so forgetting them would only cost time.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import logging
import multiprocessing
import multiprocessing.resource_tracker
import multiprocessing.util
import os
import signal
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

logger = logging.getLogger(__name__)

SHUTDOWN_TIMEOUT_S = 20.0
"""The bound on :meth:`Runtime.shutdown` as a whole (seconds): well above the longest
uninterruptible work a mission can leave running at its end, the whole-body planner's
problem build (0.7 s alone on the 2-core machine, ``seating_problems``; a few times that
while other processes load the cores), and the imagination's workers finishing the drops
of their current rotation (3-7 drops of 0.2-0.5 s each, NOTES.md)."""


@dataclass(frozen=True)
class Component:
    """One piece of process state.

    Attributes:
        name: what it is, in messages (``imagination pool``).
        reset: forgets what it holds (tests; a memo's answers); None: nothing to forget.
        shutdown: stops it within the seconds given and says whether it did; None:
            nothing to stop.
        kill: stops it at once, without waiting (a second stop signal): SIGKILLs its
            processes; None: nothing to kill.
    """

    name: str
    reset: Callable[[], None] | None = None
    shutdown: Callable[[float], bool] | None = None
    kill: Callable[[], None] | None = None


class Runtime:
    """The registry of the process's memos, pools and threads (one per process:
    :data:`RUNTIME`)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._components: dict[str, Component] = {}
        self._threads: list[threading.Thread] = []

    def register(
        self,
        name: str,
        *,
        reset: Callable[[], None] | None = None,
        shutdown: Callable[[float], bool] | None = None,
        kill: Callable[[], None] | None = None,
    ) -> None:
        """Registers (or replaces, by ``name``) a component; see :class:`Component`."""
        with self._lock:
            self._components[name] = Component(name, reset, shutdown, kill)

    def names(self) -> list[str]:
        """The registered components' names, in registration order."""
        with self._lock:
            return list(self._components)

    def start_thread(self, target: Callable[[], object], name: str) -> threading.Thread:
        """Starts ``target`` in a daemon thread that :meth:`shutdown` joins (within its
        bound) and returns the thread."""
        thread = threading.Thread(target=target, name=name, daemon=True)
        with self._lock:
            self._threads = [t for t in self._threads if t.is_alive()]
            self._threads.append(thread)
        thread.start()
        return thread

    def live_threads(self) -> list[threading.Thread]:
        """The threads started through :meth:`start_thread` still running."""
        with self._lock:
            return [t for t in self._threads if t.is_alive()]

    def reset(self) -> None:
        """Forgets every component's state (the processes and threads stay)."""
        for component in self._snapshot():
            if component.reset is not None:
                component.reset()

    def shutdown(self, timeout_s: float = SHUTDOWN_TIMEOUT_S) -> list[str]:
        """Stops every component (the last registered first) and joins the threads, all
        within ``timeout_s``; returns the names of what is still running (empty: all
        stopped). Never raises: a component that fails to stop is named instead."""
        deadline = time.monotonic() + timeout_s
        left: list[str] = []
        for component in reversed(self._snapshot()):
            if component.shutdown is None:
                continue
            try:
                stopped = component.shutdown(max(deadline - time.monotonic(), 0.0))
            except Exception as error:
                logger.warning("stopping the %s raised: %s", component.name, error)
                stopped = False
            if not stopped:
                left.append(component.name)
        left += self.join_threads(max(deadline - time.monotonic(), 0.0))
        return left

    def join_threads(self, timeout_s: float) -> list[str]:
        """Joins the threads started through :meth:`start_thread`, all within
        ``timeout_s``; returns the names of those still running."""
        deadline = time.monotonic() + timeout_s
        for thread in self.live_threads():
            thread.join(max(deadline - time.monotonic(), 0.0))
        return [f"thread {thread.name!r}" for thread in self.live_threads()]

    def kill(self) -> None:
        """Stops every component at once (SIGKILL to its processes); never raises."""
        for component in reversed(self._snapshot()):
            if component.kill is not None:
                with contextlib.suppress(Exception):
                    component.kill()

    def _snapshot(self) -> list[Component]:
        with self._lock:
            return list(self._components.values())


def stop_resource_tracker(timeout_s: float) -> bool:
    """Stops multiprocessing's resource tracker, if this process started it and no
    multiprocessing child still uses it: it ends when its pipe closes, and is reaped
    within ``timeout_s``. True when it is gone (or was never started).

    The tracker is multiprocessing's private state (no public API stops it); left alone,
    it outlives the process that started it for a moment, a child nobody reaps.
    """
    tracker: Any = multiprocessing.resource_tracker._resource_tracker  # pyright: ignore[reportAttributeAccessIssue]  # private
    if multiprocessing.active_children():
        return False
    # Semaphores of stopped pools that are garbage but not yet collected would unregister
    # after the tracker has gone, and that starts a new tracker nobody stops.
    gc.collect()
    with tracker._lock:
        fd, pid = tracker._fd, tracker._pid
        if fd is None or pid is None:
            return True
        tracker._fd = tracker._pid = None
        with contextlib.suppress(OSError):
            os.close(fd)
    return reap(pid, timeout_s)


def kill_child_processes() -> None:
    """SIGKILLs and reaps every multiprocessing child of this process, releases their
    named semaphores (multiprocessing's exit finalizers, so the resource tracker has no
    leak to warn about) and stops the tracker."""
    children = multiprocessing.active_children()
    for child in children:
        with contextlib.suppress(Exception):
            child.kill()
    for child in children:
        with contextlib.suppress(Exception):
            child.join(2.0)
    with contextlib.suppress(Exception):
        multiprocessing.util._run_finalizers(0)  # pyright: ignore[reportAttributeAccessIssue]  # private
    stop_resource_tracker(2.0)


RUNTIME = Runtime()
"""This process's runtime."""

# Registered first, so stopped last: after every pool has stopped its workers.
RUNTIME.register(
    "multiprocessing resource tracker", shutdown=stop_resource_tracker, kill=kill_child_processes
)


@atexit.register
def _shutdown_at_exit() -> None:
    """The last chance, for a process that never called :meth:`Runtime.shutdown` (a
    library user, the test runner): atexit handlers run before the interpreter frees its
    modules, while a thread still running could crash it."""
    left = RUNTIME.shutdown()
    if left:
        logger.warning("still running at exit: %s", ", ".join(left))


def reap(pid: int, timeout_s: float, poll_s: float = 0.01) -> bool:
    """Waits up to ``timeout_s`` for the child ``pid`` to end, SIGKILLs it if it has
    not, and reaps it; True when it ended by itself (or was already gone)."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            done, _ = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:
            return True  # not ours, or already reaped
        if done:
            return True
        if time.monotonic() >= deadline:
            break
        time.sleep(poll_s)
    with contextlib.suppress(ProcessLookupError):
        os.kill(pid, signal.SIGKILL)
    with contextlib.suppress(ChildProcessError):
        os.waitpid(pid, 0)
    return False
