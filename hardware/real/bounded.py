"""Waiting on a robot without hanging: every wait has a bound and names the device.

An SDK call that blocks in C (libfranka's connect, an OpenNI read, a qi future) cannot
be interrupted from Python, and a signal handler runs only between bytecodes of the
main thread. So the call runs in a daemon worker, and the caller waits for it in slices
of :data:`SLICE_S`: Ctrl-C and SIGTERM (``executive.interrupts`` raises in the main
thread) then end the wait within a slice, and the deadline ends it at the latest.
A worker that outlives its deadline is abandoned: it is a daemon and blocks nothing.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, TypeVar

from bearchair.core.errors import BackendUnavailable

SLICE_S = 0.05
"""Longest uninterruptible wait (seconds): a stop signal is honoured within it."""

T = TypeVar("T")


class DeviceTimeout(BackendUnavailable, TimeoutError):
    """A device did not answer within its bound (the message names it and the call)."""


def wait_until(done: Callable[[], bool], timeout_s: float) -> bool:
    """Polls ``done`` every :data:`SLICE_S` until it is true or ``timeout_s`` passed."""
    deadline = time.monotonic() + timeout_s
    while not done():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            return False
        time.sleep(min(SLICE_S, remaining))
    return True


def call_within(timeout_s: float, job: Callable[[], T], what: str) -> T:
    """Runs ``job`` in a daemon worker and returns its result within ``timeout_s``.

    Args:
        timeout_s: the bound (seconds).
        job: the blocking SDK call.
        what: the device and the call, for the message (``"the Panda at 172.16.0.2"``).

    Raises:
        DeviceTimeout: no answer in time (the worker is abandoned).
        KeyboardInterrupt: a stop signal arrived while waiting (within :data:`SLICE_S`).
        Exception: whatever ``job`` raised.
    """
    result: dict[str, Any] = {}
    finished = threading.Event()

    def run() -> None:
        try:
            result["value"] = job()
        except BaseException as error:  # handed to the caller
            result["error"] = error
        finally:
            finished.set()

    threading.Thread(target=run, name=f"bounded: {what}", daemon=True).start()
    if not wait_until(finished.is_set, timeout_s):
        raise DeviceTimeout(f"{what}: no answer in {timeout_s:g} s")
    if "error" in result:
        raise result["error"]
    return result["value"]
