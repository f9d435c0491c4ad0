"""Same input, same output: open3d's CPU kernels run on one thread inside perception.

open3d's parallel kernels add up in whichever order the threads finish: two runs of the
tensor TSDF's marching cubes on the same frames gave vertices 1-3 µm apart (sometimes a
different face count), and a scan 1 µm off is enough to change where the imagination
seats the agent and so the whole mission. One thread makes every scan and registration
repeat exactly, at a cost of about 0.05 s per scan (9 views at 1 cm, measured).
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

import open3d as o3d

_lock = threading.RLock()


@contextmanager
def one_open3d_thread() -> Iterator[None]:
    """Runs the body (or, as a decorator, the function) with open3d on one thread."""
    # The limit is process-wide: the lock keeps two perception calls from undoing each other.
    with _lock:
        previous = o3d.utility.get_max_threads()
        o3d.utility.set_max_threads(1)
        try:
            yield
        finally:
            o3d.utility.set_max_threads(previous)
