"""Asking the operator at the terminal (before a real robot moves, for example)."""

from __future__ import annotations

import sys
from typing import TextIO


def is_terminal(stream: TextIO | None) -> bool:
    """Whether ``stream`` is open and a terminal (a closed or missing stream is not)."""
    try:
        return stream is not None and not stream.closed and stream.isatty()
    except (OSError, ValueError, AttributeError):
        return False


def not_asked_because() -> str | None:
    """Why :func:`ask_operator` cannot ask (for the refusal's message), or None."""
    if is_terminal(sys.stdin) and is_terminal(sys.stdout):
        return None
    return "not asked: stdin or stdout is not a terminal; pass --yes to agree from a script"


def ask_operator(question: str) -> bool:
    """The operator's yes, typed at a terminal.

    Only a person at a terminal can agree: when stdin or stdout is not a terminal (a
    pipe, a file, a closed stream), the answer is no without asking (``--yes`` is the way
    to agree from a script); an end of input, a closed stdin or a Ctrl-D is no.
    """
    if not_asked_because() is not None:
        return False
    try:
        return input(question).strip().lower() in ("y", "yes")
    except (EOFError, OSError, ValueError, RuntimeError):  # RuntimeError: lost sys.stdin
        return False
