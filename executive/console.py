"""The command line's own standard streams: surviving a reader that goes away, and
saying so when output is lost (a full device)."""

from __future__ import annotations

import contextlib
import os
from typing import Any, TextIO


class TolerantStream:
    """A text stream that survives its reader going away (``| head``, a closed terminal).

    After the first failed write it drops everything: a campaign or a mission must not
    die because nobody reads its progress; its results are in files.
    """

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self.broken = False
        self.lost: OSError | None = None
        """The write error that lost output, when the reader did not just go away."""

    def write(self, text: str) -> int:
        if not self.broken:
            try:
                return self._stream.write(text)
            except (OSError, ValueError) as error:
                self._break(error)
        return len(text)

    def flush(self) -> None:
        if not self.broken:
            try:
                self._stream.flush()
            except (OSError, ValueError) as error:
                self._break(error)

    def _break(self, error: Exception) -> None:
        self.broken = True
        if isinstance(error, OSError) and not isinstance(error, BrokenPipeError):
            self.lost = error  # a full device, an I/O error: the output is lost
        # Python flushes the real stream at exit; point it at /dev/null first.
        with contextlib.suppress(OSError, ValueError, AttributeError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._stream.fileno())
            os.close(devnull)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def lost_output_status(
    out: TolerantStream, err: TolerantStream, status: int, lost_status: int
) -> int:
    """``status``, or ``lost_status`` (with one line on stderr) when standard output could not be written
    (a full device, an I/O error): a command whose answer is lost must not report success.
    A reader that went away (``| head``) is not an error."""
    from bearchair.executive.outputs import describe_os_error

    out.flush()
    if out.lost is None:
        return status
    err.write(
        f"bearchair: cannot write to standard output ({describe_os_error(out.lost)}); "
        "the output is lost\n"
    )
    err.flush()
    return lost_status if status == 0 else status
