"""The client heartbeat that ends a latched NAO walk when its controller falls silent.

NAOqi's ``move(x, y, theta)`` keeps walking at the last velocity until told otherwise.
:class:`WalkWatchdog` is beaten by every walking command; when two periods pass
without a beat while armed, it calls its ``stop`` (``stopMove``) once and disarms. It
covers a mission thread that hangs or dies inside this process; a process killed
outright takes its watchdog with it, which is why ``check-hardware --move --walk``
measures what NAOqi does when the client disconnects (docs/real-robots.md).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

log = logging.getLogger(__name__)


class WalkWatchdog:
    """Calls ``stop`` when armed and not beaten for two ``period_s``.

    Args:
        stop: what ends the walk (must not raise; errors are logged).
        period_s: the controller's expected longest gap between two commands (seconds).
        now: the controller's clock (seconds; robot time in a simulation).
    """

    def __init__(
        self, stop: Callable[[], None], period_s: float, now: Callable[[], float] = time.monotonic
    ) -> None:
        self._stop = stop
        self.period_s = period_s
        self._now = now
        self._last_beat_s: float | None = None  # None: disarmed
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._closed = threading.Event()
        self.fired = 0
        """How many times the watchdog stopped a walk."""

    def beat(self) -> None:
        """A walking command went out: armed, the deadline two periods from now."""
        with self._lock:
            self._last_beat_s = self._now()
            if self._thread is None:
                self._thread = threading.Thread(
                    target=self._watch, name="nao-walk-watchdog", daemon=True
                )
                self._thread.start()

    def idle(self) -> None:
        """The walk was stopped on purpose: disarmed until the next beat."""
        with self._lock:
            self._last_beat_s = None

    def close(self) -> None:
        self.idle()
        self._closed.set()

    def _watch(self) -> None:
        # Checked four times per period: the stop goes out at most 2.25 periods after the beat.
        while not self._closed.wait(self.period_s / 4.0):
            with self._lock:
                last = self._last_beat_s
                late = last is not None and self._now() - last > 2.0 * self.period_s
                if late:
                    self._last_beat_s = None
            if late:
                self.fired += 1
                try:
                    self._stop()
                except Exception as error:  # the watchdog must outlive one failed stop
                    log.error("NAO walk watchdog: %s", error)
