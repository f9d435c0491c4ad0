"""Progress inside a long step (scan views visited, imagination drops simulated).

A skill says how far it is with :func:`report`; it shows nothing by itself. The
program that runs the skills decides whether and how to show it by installing a
display for a block (:func:`showing`): ``bearchair run`` installs progress bars on a
terminal only (:mod:`bearchair.executive.console`). Like logging, the display is one
for the process, so skills running in worker threads reach it too; reports from
several threads must be cheap and safe, which a display takes care of.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

ProgressDisplay = Callable[[str, int, int], None]
"""``display(what, done, total)``: ``what`` names the step (``"scan: views"``)."""

_display: ProgressDisplay | None = None


def report(what: str, done: int, total: int) -> None:
    """Says that ``done`` of ``total`` units of ``what`` are finished (no display: nothing).

    A display must never stop the skill: what it raises is dropped.
    """
    display = _display
    if display is None:
        return
    with contextlib.suppress(Exception):
        display(what, done, total)


@contextlib.contextmanager
def showing(display: ProgressDisplay | None) -> Iterator[None]:
    """Installs ``display`` for the block (None: no progress shown), then the previous one."""
    global _display
    previous, _display = _display, display
    try:
        yield
    finally:
        _display = previous
