"""The on-disk cache of what is derived from meshes and of generated simulation assets.

Entries are ``.npz`` files (read without pickle) and generated URDF/OBJ/PNG files, named
by a digest of what they were made from. The cache is optional: when it cannot be
written, a private temporary folder stands in for the process's life.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any, cast

import numpy as np

from bearchair.core.errors import one_line

logger = logging.getLogger(__name__)


def cache_dir() -> Path:
    """The on-disk cache: ``$BEARCHAIR_CACHE`` or ``~/.cache/bearchair``, when it can be
    written; otherwise (a read-only or full home, ``BEARCHAIR_CACHE=""``) a private
    temporary folder for this process, with one warning: a cache is never worth failing
    a run for, and never lands in the current folder."""
    configured = os.environ.get("BEARCHAIR_CACHE")
    if configured not in _cache_dirs:
        _cache_dirs[configured] = _usable_cache_dir(configured)
    root = _cache_dirs[configured]
    with contextlib.suppress(OSError):  # removed since (a test's folder): made again
        root.mkdir(parents=True, exist_ok=True)
    return root


_cache_dirs: dict[str | None, Path] = {}
_CACHE_PROBE_BYTES = 64 * 1024
"""Written once to prove the cache writable (a full disk still creates empty files)."""


def _usable_cache_dir(configured: str | None) -> Path:
    if configured is None:
        root, why = Path.home() / ".cache" / "bearchair", ""
    elif configured.strip():
        root, why = Path(configured), ""
    else:
        root, why = None, "BEARCHAIR_CACHE is set but empty"
    if root is not None:
        try:
            root.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryFile(dir=root, prefix=".probe-") as probe:
                probe.write(b"\0" * _CACHE_PROBE_BYTES)
                probe.flush()
                os.fsync(probe.fileno())
            return root
        except OSError as error:
            why = f"{root} cannot be written ({one_line(error, 120)})"
    private = Path(tempfile.mkdtemp(prefix="bearchair-cache-"))
    atexit.register(shutil.rmtree, private, ignore_errors=True)
    logger.warning("no cache: %s; working without one (in %s, removed at exit)", why, private)
    return private


def read_cached_arrays(path: Path) -> dict[str, np.ndarray] | None:
    """The arrays of a cache entry written by :func:`write_cached_arrays`.

    Cache entries are ``.npz`` files read without pickle: whoever can write the cache
    cannot make this process run code. A missing entry gives None; a damaged one
    (truncated, not npz, holding objects) is deleted and gives None, so the caller
    rebuilds it.
    """
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as stored:
            return {name: stored[name] for name in stored.files}
    except Exception as error:  # zipfile, ValueError (pickled objects), OSError, ...
        logger.info("rebuilding damaged cache entry %s: %s", path, one_line(error))
        with contextlib.suppress(OSError):
            path.unlink()
        return None


def write_cached_arrays(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Writes a cache entry atomically (a temporary file renamed over it).

    Object arrays are refused (they would need pickle). A failed write (full disk,
    read-only cache) is logged and skipped: a cache is never worth failing a run for.
    """
    plain = {name: np.asarray(value) for name, value in arrays.items()}
    if any(value.dtype == object for value in plain.values()):
        raise ValueError("cache arrays must be numbers or strings, not Python objects")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        descriptor, scratch = tempfile.mkstemp(dir=path.parent, suffix=".tmp.npz")
        with os.fdopen(descriptor, "wb") as stream:
            # As Any: numpy's stubs match the keys against savez's allow_pickle flag too.
            np.savez(stream, **cast(dict[str, Any], plain))
        os.replace(scratch, path)
    except OSError as error:
        logger.warning("could not write cache entry %s: %s", path, one_line(error))
        with contextlib.suppress(OSError, UnboundLocalError):
            os.unlink(scratch)
