"""The tree's node labels in a recording: a node's name over its feedback, cut short."""

from __future__ import annotations

FEEDBACK_LABEL_CHARS = 48
"""Feedback shown in a node's label is cut here; the full text is in ``tree/log``."""


def node_label(name: str, feedback: str) -> str:
    """``name``, and under it ``feedback`` cut at :data:`FEEDBACK_LABEL_CHARS` (the full
    text is in ``tree/log``)."""
    if not feedback:
        return name
    cut = (
        feedback
        if len(feedback) <= FEEDBACK_LABEL_CHARS
        else feedback[: FEEDBACK_LABEL_CHARS - 1] + "…"
    )
    return f"{name}\n{cut}"
