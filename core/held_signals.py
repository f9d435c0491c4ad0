"""Sections of the main thread that a stop signal must not split: the signal is held
until the section ends, then delivered.

Why: Python runs a signal handler between any two bytecodes of the main thread, and
the executive's handler (:mod:`bearchair.executive.interrupts`) raises there. Starting a
worker process is two steps: multiprocessing's spawn starts the child, then writes it
the data it needs to run. An exception between the two leaves a child that reads an
empty pipe, prints ``EOFError: Ran out of input`` on the stderr it shares with the
command, and belongs to no pool, so no one stops it. Code that starts processes runs
inside :func:`holding_stop_signals`; the handler asks :func:`hold` first.

Only the main thread runs signal handlers, so a section entered by another thread
holds nothing (a signal cannot split it).
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator

_depth = 0
"""How many sections the main thread is inside (they nest)."""

_held: list[Callable[[], None]] = []
"""The deliveries of the signals that came inside a section, first first."""


@contextlib.contextmanager
def holding_stop_signals() -> Iterator[None]:
    """Holds the stop signals that come while inside; on leaving the outermost section,
    delivers the first of them (its handler runs, and raises, here). Signals held
    together are one stop: the later ones are dropped, as the first already stops."""
    global _depth
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1
        if _depth == 0 and _held:
            deliver = _held[0]
            _held.clear()
            deliver()


def hold(deliver: Callable[[], None]) -> bool:
    """Called by a signal handler (main thread): inside a section, keeps ``deliver`` to be
    called when the section ends and returns True; outside, returns False (handle it now)."""
    if _depth == 0 or threading.current_thread() is not threading.main_thread():
        return False
    _held.append(deliver)
    return True
