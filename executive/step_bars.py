"""Progress bars on the console for the steps inside a stage (tqdm), on a terminal only.

``bearchair run`` shows a bar for each long step a skill reports through
:mod:`bearchair.core.progress` (the scan's views, the imagination's drops) while the
stage runs; the bar goes away when the step ends, leaving the stage's own lines
(:class:`bearchair.executive.tick_watchers.StageProgress`). Where stderr is not a terminal (a
log file, CI, a test capturing output) nothing is drawn.
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Iterator
from typing import Any, TextIO

from bearchair.core.progress import showing


class StepBars:
    """A :data:`bearchair.core.progress.ProgressDisplay` drawing one tqdm bar per step.

    Skills report from worker threads: the bars are updated under a lock.

    Args:
        stream: where the bars are drawn (default stderr).
    """

    def __init__(self, stream: TextIO | None = None) -> None:
        self._stream = stream or sys.stderr
        self._bars: dict[str, Any] = {}
        self._lock = threading.Lock()

    def __call__(self, what: str, done: int, total: int) -> None:
        with self._lock:
            bar = self._bars.get(what)
            if bar is None or bar.total != total or done < bar.n:
                if bar is not None:
                    bar.close()
                from tqdm import tqdm  # here: importing it costs 0.15 s, a bar is rare

                bar = tqdm(
                    total=total, desc=what, file=self._stream, leave=False, dynamic_ncols=True
                )
                self._bars[what] = bar
            bar.update(done - bar.n)
            if done >= total:
                bar.close()
                del self._bars[what]

    def close(self) -> None:
        """Takes every unfinished bar off the console (the run ended mid-step)."""
        with self._lock:
            for bar in self._bars.values():
                bar.close()
            self._bars.clear()


def step_bars(stream: TextIO | None = None) -> StepBars | None:
    """Bars for ``stream`` (default stderr) when it is a terminal, else None (no display)."""
    stream = stream or sys.stderr
    isatty = getattr(stream, "isatty", None)
    try:
        on_terminal = bool(isatty and isatty())
    except (OSError, ValueError):
        on_terminal = False
    return StepBars(stream) if on_terminal else None


@contextlib.contextmanager
def showing_step_bars(stream: TextIO | None = None) -> Iterator[None]:
    """For a block: the skills' steps drawn as bars on a terminal (:func:`step_bars`)."""
    bars = step_bars(stream)
    try:
        with showing(bars):
            yield
    finally:
        if bars is not None:
            bars.close()
