"""Asking the operator at the terminal (before a real robot moves, for example)."""

from __future__ import annotations


def ask_operator(question: str) -> bool:
    """The operator's yes (no terminal: no)."""
    try:
        return input(question).strip().lower() in ("y", "yes")
    except EOFError:
        return False
