"""The signals that end the process: the first stops the work in order, a second one
exits at once.

Handled: SIGINT (Ctrl-C), SIGTERM (``kill``, a scheduler), SIGHUP (the terminal or the
ssh session closing), SIGQUIT (Ctrl-\\), SIGUSR1 and SIGUSR2 (their default would kill
the process with no record). The first signal raises :class:`Interrupted` (a ``KeyboardInterrupt``, so every
``except KeyboardInterrupt`` that already stops a tree, cancels a skill or stops a
campaign's workers handles SIGTERM the same way). The mission runner then stops the
tree and the robots and writes the summary with ``interrupted: true``; the CLI exits
with 128 + the signal's number (129 SIGHUP, 130 SIGINT, 131 SIGQUIT, 138 SIGUSR1,
140 SIGUSR2, 143 SIGTERM; ``docs/exit-status.md``).

A second signal while that is going on does not wait: it calls the registered
emergency stops (the robots'), SIGKILLs and reaps the child processes (the runtime's
``kill``: the imagination's workers and the resource tracker), writes one line and
leaves with ``os._exit``.

A signal that comes while the main thread starts a worker process is held until it has
started (:mod:`bearchair.core.held_signals`), so no child is left half-started.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Callable, Iterator
from typing import Any

from bearchair.core.held_signals import hold
from bearchair.core.runtime import RUNTIME

HANDLED_SIGNALS = (
    signal.SIGINT,
    signal.SIGTERM,
    signal.SIGHUP,
    signal.SIGQUIT,
    signal.SIGUSR1,
    signal.SIGUSR2,
)
"""The signals that stop a command with its record written (exit status 128 + number)."""

_first_signal: int | None = None
_emergency_stops: list[Callable[[], None]] = []
_owner_pid: int | None = None

stop_requested = threading.Event()
"""Set by the first stop signal: long computations take it as their ``cancel`` event,
so they end within their polling period even when a library swallowed the exception."""


class Interrupted(KeyboardInterrupt):
    """The operator (Ctrl-C) or the system (SIGTERM, SIGHUP, ...) asked the process to stop."""

    def __init__(self, signum: int = signal.SIGINT) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)

    @property
    def exit_status(self) -> int:
        return 128 + self.signum


def exit_status(error: BaseException | None = None) -> int:
    """128 + the first signal received (or of ``error``); 130 when nothing says otherwise."""
    if isinstance(error, Interrupted):
        return error.exit_status
    return 128 + (_first_signal or signal.SIGINT)


def received() -> int | None:
    """The first stop signal received since :func:`handling_signals` began, if any."""
    return _first_signal


def raise_if_received() -> None:
    """Raises :class:`Interrupted` if a stop signal came and its exception was swallowed.

    Some libraries catch ``BaseException`` (trimesh around its optional imports, for
    one), so the handler's exception can vanish; loops and stage boundaries call this
    so the signal is honoured all the same.
    """
    if _first_signal is not None:
        raise Interrupted(_first_signal)


def signal_name(signum: int | None = None) -> str:
    """``SIGINT``, ``SIGHUP``, ... of ``signum`` (default: the first received)."""
    signum = signum if signum is not None else (_first_signal or signal.SIGINT)
    return signal.Signals(signum).name


def _handle(signum: int, frame: Any) -> None:
    global _first_signal
    if os.getpid() != _owner_pid:
        return  # a forked child inherited the handler: its parent decides
    if _first_signal is None:
        if hold(lambda: _handle(signum, None)):
            return  # a worker process is starting: the signal comes once it has
        _first_signal = signum
        stop_requested.set()
        raise Interrupted(signum)
    for stop in list(_emergency_stops):
        with contextlib.suppress(BaseException):
            stop()
    with contextlib.suppress(BaseException):
        RUNTIME.kill()
    with contextlib.suppress(OSError):
        os.write(2, f"bearchair: second {signal_name(signum)}: exiting now\n".encode())
    os._exit(128 + signum)


@contextlib.contextmanager
def handling_signals() -> Iterator[None]:
    """Installs the handlers for the duration of a command (main thread only)."""
    global _first_signal, _owner_pid
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {sig: signal.getsignal(sig) for sig in HANDLED_SIGNALS}
    _first_signal, _owner_pid = None, os.getpid()
    stop_requested.clear()
    for sig in HANDLED_SIGNALS:
        signal.signal(sig, _handle)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        _first_signal = None
        stop_requested.clear()
        _emergency_stops.clear()


@contextlib.contextmanager
def emergency_stop_on_second_signal(stop: Callable[[], None]) -> Iterator[None]:
    """While inside, a second signal calls ``stop`` before the process exits."""
    _emergency_stops.append(stop)
    try:
        yield
    finally:
        with contextlib.suppress(ValueError):
            _emergency_stops.remove(stop)
