"""The campaign's progress on stderr: a tqdm bar on a terminal, a line per trial elsewhere.

On a terminal the bar (tqdm) counts the finished trials with successes, failures and
the last trial in its postfix, and estimates the time left from this session's pace
(trials found finished in the records at start count as done, not toward the pace).
Elsewhere (a log file, CI, a captured stream) there is no bar to redraw: one line per
finished trial says the same, with the ETA of :meth:`Progress.eta_seconds`.
"""

from __future__ import annotations

import contextlib
import sys
import time
from typing import Any, TextIO

from bearchair.core.userfiles import printable
from bearchair.evaluation.trial_record import TrialRecord


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
    """Counts finished trials and shows them.

    Args:
        total: trials in the campaign.
        already_done: trials found finished in the records (resume).
        stream: where to show them; default stderr.
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
        self._bar: Any = None
        if _is_terminal(self._stream):
            from tqdm import tqdm

            self._bar = tqdm(
                total=total,
                initial=already_done,
                desc="trials",
                unit="trial",
                file=self._stream,
                dynamic_ncols=True,
            )

    def eta_seconds(self) -> float | None:
        """Seconds left at the pace of this session; None before the first trial."""
        if self._session_done == 0:
            return None
        per_trial = (self._clock() - self._start) / self._session_done
        return per_trial * (self.total - self.done)

    def line(self, last: str = "") -> str:
        """The line written per trial where there is no terminal."""
        eta = self.eta_seconds()
        eta_text = "ETA --" if eta is None else f"ETA {format_duration(eta)}"
        text = (
            f"trials {self.done}/{self.total} ok {self.successes} failed {self.failures} "
            f"| {format_duration(self._clock() - self._start)} elapsed, {eta_text}"
        )
        return f"{text} | {last}" if last else text

    def start(self) -> None:
        if self._bar is None:
            self._print(self.line("starting"))

    def update(self, record: TrialRecord) -> None:
        """Counts one finished trial (a record of ``bearchair.evaluation.store``)."""
        self.done += 1
        self._session_done += 1
        if record.succeeded:
            self.successes += 1
        else:
            self.failures += 1
        what = record.failed_stage or ("error" if record.error else "")
        last = (
            f"{printable(record.chair)} #{record.trial_index} {record.outcome}"
            + (f" at {what}" if not record.succeeded and what else "")
            + f" ({record.wall_seconds or 0:.0f} s)"
        )
        if self._bar is None:
            self._print(self.line(last))
            return
        try:
            self._bar.set_postfix_str(
                f"ok {self.successes} failed {self.failures} | {last}", refresh=False
            )
            self._bar.update(1)
        except (OSError, ValueError):  # nobody reads the terminal any more
            self._bar = None

    def finish(self) -> None:
        if self._bar is not None:
            with contextlib.suppress(OSError, ValueError):
                self._bar.close()

    def _print(self, text: str) -> None:
        # A closed stderr (``2>&1 | head``) must not stop the campaign: the records and
        # the report are what matter, and they go to files.
        with contextlib.suppress(OSError, ValueError):
            self._stream.write(text + "\n")
            self._stream.flush()


def _is_terminal(stream: TextIO) -> bool:
    try:
        return bool(getattr(stream, "isatty", lambda: False)())
    except (OSError, ValueError):
        return False
