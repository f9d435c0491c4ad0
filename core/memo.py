"""A small bounded, thread-safe memo: the least recently used answer goes first."""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Generic, TypeVar

from bearchair.core.runtime import RUNTIME

Key = TypeVar("Key")
Value = TypeVar("Value")


class BoundedMemo(Generic[Key, Value]):
    """Answers by key, at most ``max_size`` of them, the least recently used dropped first.

    Args:
        max_size: answers kept.
        name: a process-wide memo's name: it registers with the runtime
            (``bearchair.core.runtime.RUNTIME``), whose ``reset`` clears it (between tests).

    Attributes:
        hits: how many ``get`` calls found an answer.
    """

    def __init__(self, max_size: int, name: str | None = None) -> None:
        self._answers: OrderedDict[Key, Value] = OrderedDict()
        self._max_size = max_size
        self._lock = threading.Lock()
        self.hits = 0
        if name is not None:
            RUNTIME.register(name, reset=self.clear)

    def get(self, key: Key) -> Value | None:
        """The answer kept for ``key`` (now the most recently used), or None."""
        with self._lock:
            answer = self._answers.get(key)
            if answer is not None:
                self._answers.move_to_end(key)
                self.hits += 1
            return answer

    def put(self, key: Key, answer: Value) -> None:
        """Keeps ``answer``, dropping the least recently used beyond the memo's size."""
        with self._lock:
            self._answers[key] = answer
            self._answers.move_to_end(key)
            while len(self._answers) > self._max_size:
                self._answers.popitem(last=False)

    def clear(self) -> None:
        """Forgets every answer (and the count of hits)."""
        with self._lock:
            self._answers.clear()
            self.hits = 0

    def __len__(self) -> int:
        return len(self._answers)
