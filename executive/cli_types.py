"""argparse types for numbers the commands take: seeds, seconds, counts.

Each refuses what would break a run later (a negative seed numpy cannot take, a NaN
timeout that never fires, an infinite one) with a message argparse turns into the
command's one error line.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import TypeVar

MAX_SEED = 2**32 - 1
"""numpy's seed range."""

Number = TypeVar("Number", int, float)


def _converted(text: str, convert: Callable[[str], Number], message: str) -> Number:
    """``convert(text)``, or argparse's error with ``message`` when it is not a number."""
    try:
        return convert(text)
    except ValueError:
        raise argparse.ArgumentTypeError(message) from None


def seed_value(text: str) -> int:
    """An argparse type: a seed, an integer in [0, 2**32 - 1]."""
    value = _converted(text, int, f"invalid int value {text!r} for a seed")
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"seed {value} is outside 0..{MAX_SEED}")
    return value


def positive_seconds(text: str) -> float:
    """An argparse type: a finite number of seconds above zero."""
    value = _converted(text, float, f"invalid number of seconds {text!r}")
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} seconds: must be finite and positive")
    return value


def positive_int(text: str) -> int:
    """An argparse type: an integer of at least 1."""
    value = _converted(text, int, f"invalid integer {text!r}")
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value}: must be at least 1")
    return value
