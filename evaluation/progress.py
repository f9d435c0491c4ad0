"""A plain-text progress bar with an ETA, on stderr.

On a terminal the line is redrawn in place (``\\r``); otherwise (a log file, CI) one
line per finished trial. The ETA is the session's elapsed time per trial finished in
this session, times the trials left (so trials running side by side are accounted for).
"""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

from bearchair.core.userfiles import printable

BAR_WIDTH = 24


def format_duration(seconds: float) -> str:
    """``1h02m``, ``3m05s`` or ``42s``."""
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    if hours:
        return f"{hours}h{minutes:02d}m"
    if minutes:
        return f"{minutes}m{secs:02d}s"
    return f"{secs}s"


class Progress:
    """Counts finished trials and prints the bar.

    Args:
        total: trials in the campaign.
        already_done: trials found finished in the records (resume).
        stream: where to print; default stderr.
        clock: monotonic time source (tests).
    """

    def __init__(
        self,
        total: int,
        already_done: int = 0,
        stream: TextIO | None = None,
        clock: Any = time.monotonic,
    ) -> None:
        self.total = total
        self.done = already_done
        self.successes = 0
        self.failures = 0
        self._stream = stream or sys.stderr
        self._clock = clock
        self._start = clock()
        self._session_done = 0
        self._tty = bool(getattr(self._stream, "isatty", lambda: False)())

    def eta_seconds(self) -> float | None:
        """Seconds left at the pace of this session; None before the first trial."""
        if self._session_done == 0:
            return None
        per_trial = (self._clock() - self._start) / self._session_done
        return per_trial * (self.total - self.done)

    def line(self, last: str = "") -> str:
        filled = round(BAR_WIDTH * self.done / self.total) if self.total else BAR_WIDTH
        bar = "#" * filled + "-" * (BAR_WIDTH - filled)
        eta = self.eta_seconds()
        eta_text = "ETA --" if eta is None else f"ETA {format_duration(eta)}"
        text = (
            f"[{bar}] {self.done}/{self.total} ok {self.successes} failed {self.failures} "
            f"| {format_duration(self._clock() - self._start)} elapsed, {eta_text}"
        )
        return f"{text} | {last}" if last else text

    def start(self) -> None:
        self._print(self.line("starting"))

    def update(self, record: dict[str, Any]) -> None:
        """Counts one finished trial (a record of ``bearchair.evaluation.store``)."""
        self.done += 1
        self._session_done += 1
        if record.get("outcome") == "success":
            self.successes += 1
        else:
            self.failures += 1
        what = record.get("failed_stage") or ("error" if record.get("error") else "")
        last = (
            f"{printable(record['chair'])} #{record['trial_index']} {record['outcome']}"
            + (f" at {what}" if record.get("outcome") != "success" and what else "")
            + f" ({record.get('wall_seconds') or 0:.0f} s)"
        )
        self._print(self.line(last))

    def finish(self) -> None:
        if self._tty:
            try:
                self._stream.write("\n")
                self._stream.flush()
            except (OSError, ValueError):
                self._tty = False

    def _print(self, text: str) -> None:
        # A closed stderr (``2>&1 | head``) must not stop the campaign: the records and
        # the report are what matter, and they go to files.
        try:
            if self._tty:
                self._stream.write("\r\033[K" + text)
            else:
                self._stream.write(text + "\n")
            self._stream.flush()
        except (OSError, ValueError):
            self._tty = False
