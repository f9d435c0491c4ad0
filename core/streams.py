"""Redirecting a process's file descriptors, for libraries that write from C.

A C library's ``printf`` (pybullet's build banner, for one) goes straight to file
descriptor 1 or 2, past ``sys.stdout`` and ``sys.stderr``: only pointing the descriptors
themselves elsewhere keeps it off the terminal.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
from collections.abc import Iterator


@contextlib.contextmanager
def silenced_fds(*fds: int, target_fd: int | None = None) -> Iterator[None]:
    """Points each of ``fds`` at /dev/null (or at ``target_fd``) for a ``with`` block.

    Python's and C's buffered output is flushed on the way in, so what was written
    before reaches the original destination, and on the way out, so what was written
    inside does not; the descriptors are restored even if the block raises.

    Args:
        fds: the descriptors to redirect, e.g. 1 (stdout) and 2 (stderr).
        target_fd: where they go instead; None for /dev/null.
    """
    _flush_all()
    saved = [os.dup(fd) for fd in fds]
    destination = os.open(os.devnull, os.O_WRONLY) if target_fd is None else target_fd
    try:
        for fd in fds:
            os.dup2(destination, fd)
        yield
    finally:
        _flush_all()
        for fd, original in zip(fds, saved, strict=True):
            os.dup2(original, fd)
            os.close(original)
        if target_fd is None:
            os.close(destination)  # the /dev/null descriptor opened above


def _flush_all() -> None:
    """Flushes ``sys.stdout``, ``sys.stderr`` and every C stdio stream."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(AttributeError, OSError, ValueError):
            stream.flush()
    ctypes.CDLL(None).fflush(None)


def import_pybullet_quietly() -> None:
    """Imports pybullet with its build banner (``pybullet build time: ...``, printed from
    C to descriptor 2 at import) kept off the terminal; later imports print nothing.

    Called by the console script before any command, since the first import may come
    from anywhere (qibullet imports pybullet at its own import).
    """
    if "pybullet" in sys.modules:
        return
    with silenced_fds(2):
        import pybullet  # noqa: F401 - imported for its side effect, once
