"""A toy robot backend: a speaker that writes what it says to a file.

A cell file selects it for the speaker role::

    "speaker": {"backend": "example-log-speaker", "path": "said.txt"}
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any


class LogSpeaker:
    """A :class:`bearchair.hardware.interfaces.Speaker` that appends each sentence to a file.

    Attributes:
        path: the file sentences go to, one a line.
        spoken: every sentence said, in order (the name every speaker uses).
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.spoken: list[str] = []

    def say(self, sentence: str) -> None:
        with self.path.open("a", encoding="utf-8") as log:
            log.write(sentence + "\n")
        self.spoken.append(sentence)


def make_log_speaker(settings: Mapping[str, Any]) -> LogSpeaker:
    """The backend's factory: the cell section's settings (``path``) -> the speaker.

    Raises:
        ValueError: no ``path``, or an unknown setting.
    """
    unknown = set(settings) - {"path"}
    if unknown:
        raise ValueError(f"unknown setting {sorted(unknown)[0]!r}; the log speaker takes path")
    if not isinstance(settings.get("path"), str):
        raise ValueError("path: the file the sentences go to is needed")
    return LogSpeaker(Path(settings["path"]))
