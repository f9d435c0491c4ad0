"""Output places: checked before any work, written atomically.

Every command that writes something checks where it goes before it computes anything
(a scan or a campaign must not spend minutes and then fail on ``--out``): the place is
a folder (or can be made one), it is writable, and its file system has room. A run
folder is new: an existing non-empty one is refused unless the caller overwrites it,
so an old ``summary.json`` never sits beside new ticks. Records are written to a
temporary file in the same folder and renamed over the target, so a crash or a full
disk never leaves half a file.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import functools
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TextIO

from bearchair.core.errors import OutputError

MIN_FREE_BYTES = 20 * 1024 * 1024
"""Room a run needs on its file system: a mission's ticks.jsonl is a few MB, its
pictures a few hundred kB; below this the run would fail part-way."""

MIN_FREE_INODES = 64
"""Files a run may create on its file system (a record is about ten, its snapshots a few
dozen): with fewer left, it would run to the end and lose its record."""

RUN_RECORD_NAMES = (
    "summary.json",
    "ticks.jsonl",
    "tree.json",
    "final_scene.png",
    "bearchair.log",
    "chair_reconstructed.ply",
    "worker.log",
    "worker.stdout",
    "snapshots",
    "mission.rrd",
    "cell.json",
)
"""What a run writes into its folder: what ``--overwrite`` removes (nothing else)."""
RUN_LOCK_NAME = ".bearchair-run.lock"
"""The lock a run holds on its folder while it writes there (``flock``): ``--overwrite``
of a folder another run is still writing is refused."""


def describe_os_error(error: OSError) -> str:
    """``<path>: <reason>`` for an OSError, with the reason in words."""
    reason = error.strerror or str(error) or type(error).__name__
    if error.errno == errno.ENOSPC:
        reason = "no space left on the device"
    where = error.filename if error.filename is not None else ""
    return f"{where}: {reason}" if where else reason


def _first_file_on_the_way(path: Path) -> Path | None:
    """The first existing ancestor of ``path`` (or itself) that is not a directory."""
    for candidate in [*reversed(path.parents), path]:
        if candidate.exists() and not candidate.is_dir():
            return candidate
    return None


def check_free_space(folder: Path, what: str, min_free_bytes: int | None = None) -> None:
    """Refuses a folder whose file system has less than ``min_free_bytes`` free, or fewer
    than :data:`MIN_FREE_INODES` files left to create (``f_favail``)."""
    needed = MIN_FREE_BYTES if min_free_bytes is None else min_free_bytes
    try:
        free = shutil.disk_usage(folder).free
        files = os.statvfs(folder)
    except OSError:
        return  # not measurable here (some network file systems): the writes will tell
    if free < needed:
        raise OutputError(
            f"{what} {folder}: only {free / 1e6:.1f} MB free on its file system "
            f"(needs {needed / 1e6:.0f} MB); free some space or choose another place"
        )
    # A file system that does not count its inodes (btrfs, some FUSE) reports 0 of 0.
    if files.f_files > 0 and files.f_favail < MIN_FREE_INODES:
        raise OutputError(
            f"{what} {folder}: only {files.f_favail} files can still be created on its file "
            f"system (needs {MIN_FREE_INODES}); delete some files or choose another place"
        )


def ensure_writable_dir(folder: Path, what: str = "output folder") -> Path:
    """Makes ``folder`` (and its parents) if needed and proves it writable.

    Raises:
        OutputError: it is (or lies under) a file, cannot be made, is not writable, or
            its file system is (nearly) full.
    """
    folder = Path(folder)
    blocker = _first_file_on_the_way(folder)
    if blocker is not None:
        raise OutputError(
            f"{what} {folder}: {blocker} is a file, not a folder; choose another place"
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".bearchair-probe-"):
            pass
    except OSError as error:
        raise OutputError(
            f"{what} {folder}: cannot write there ({describe_os_error(error)})"
        ) from error
    check_free_space(folder, what)
    return folder


def prepare_run_dir(folder: Path, overwrite: bool = False) -> Path:
    """A run folder ready for a new record: new or empty, or emptied of an old record.

    The folder is locked for this process (:data:`RUN_LOCK_NAME`) until it ends, so a
    second run with ``--overwrite`` cannot empty it while this one writes. Old entries
    are removed without following symbolic links.

    Raises:
        OutputError: the folder holds files and ``overwrite`` is False (or it holds
            files that are not a run record's), another run is writing it, or it
            cannot be written.
    """
    folder = Path(folder)
    if folder.is_symlink() and not folder.is_dir():
        raise OutputError(f"run folder {folder}: a symbolic link to nothing; choose another --out")
    if not folder.is_dir():
        ensure_writable_dir(folder, "run folder")
        lock_run_dir(folder)
        return folder
    present = sorted(p.name for p in folder.iterdir() if not p.name.startswith(".bearchair"))
    if present and not overwrite:
        raise OutputError(
            f"run folder {folder} is not empty (holds {', '.join(present[:3])}"
            f"{', ...' if len(present) > 3 else ''}); pass --overwrite to replace its "
            "record, or choose a new --out"
        )
    foreign = [name for name in present if name not in RUN_RECORD_NAMES]
    if foreign:
        raise OutputError(
            f"run folder {folder} holds files that are not a run record "
            f"({', '.join(foreign[:3])}); --overwrite only replaces run records: "
            "choose a new --out"
        )
    ensure_writable_dir(folder, "run folder")
    lock_run_dir(folder)
    for name in present:
        _remove(folder, name)
    return folder


_held_locks: dict[str, int] = {}
"""The run-folder locks this process holds, by resolved folder: descriptors."""


def lock_run_dir(folder: Path) -> None:
    """Holds an ``flock`` on ``folder/RUN_LOCK_NAME`` until :func:`release_run_dir_locks`
    (the command's end) or this process's end, however it ends.

    Raises:
        OutputError: another process holds it (a run still writing the folder).
    """
    key = str(Path(folder).resolve())
    if key in _held_locks:
        return
    path = Path(folder) / RUN_LOCK_NAME
    try:
        descriptor = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666)
    except OSError as error:
        raise OutputError(
            f"run folder {folder}: cannot lock it ({describe_os_error(error)})"
        ) from error
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(descriptor)
        raise OutputError(
            f"run folder {folder} is being written by another bearchair run; wait for it "
            "to finish or choose another --out"
        ) from None
    _held_locks[key] = descriptor


def release_run_dir_locks() -> None:
    """Releases every run-folder lock of this process (the command has finished)."""
    while _held_locks:
        _, descriptor = _held_locks.popitem()
        with contextlib.suppress(OSError):
            os.close(descriptor)


def _remove(folder: Path, name: str) -> None:
    """Removes ``folder/name``: a link as a link, a folder with its contents (rmtree does
    not follow links inside it)."""
    target = folder / name
    try:
        if target.is_dir() and not target.is_symlink():
            shutil.rmtree(target)
        else:
            target.unlink()
    except OSError as error:
        raise OutputError(
            f"run folder {folder}: cannot remove the old {name} ({describe_os_error(error)})"
        ) from error


def open_new_file(path: Path) -> TextIO:
    """``path`` opened for writing text, created with the umask's modes, never through a
    symbolic link (a link planted there is refused, not followed).

    Raises:
        OSError: as ``open`` would (ELOOP for a link).
    """
    descriptor = os.open(
        path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW | os.O_CLOEXEC, 0o666
    )
    return os.fdopen(descriptor, "w", encoding="utf-8")


def claim_new_run_dir(parent: Path, stem: str) -> Path:
    """A folder ``parent/stem`` that no other process has, made now (``-2``, ``-3`` ...).

    Two runs started in the same second get different folders: ``mkdir`` either
    creates the folder or fails, atomically.
    """
    ensure_writable_dir(parent, "runs folder")
    for attempt in range(1, 1000):
        candidate = parent / (stem if attempt == 1 else f"{stem}-{attempt}")
        try:
            candidate.mkdir()
            lock_run_dir(candidate)
        except FileExistsError:
            continue
        except OSError as error:
            raise OutputError(
                f"cannot make run folder {candidate}: {describe_os_error(error)}"
            ) from error
        return candidate
    raise OutputError(f"{parent}: 999 run folders named {stem}-*; clean some up")


def default_run_dir(seed: int, parent: Path = Path("runs")) -> Path:
    """``runs/<date>-<time>-seed<N>``, unique (see :func:`claim_new_run_dir`)."""
    return claim_new_run_dir(parent, f"{time.strftime('%Y%m%d-%H%M%S')}-seed{seed}")


def check_output_file(path: Path, what: str, suffixes: tuple[str, ...] = ()) -> Path:
    """Checks that ``path`` can be written as a file (its folder is made if needed).

    Raises:
        OutputError: it is a folder, its folder cannot be made or written, or its
            suffix is not one of ``suffixes``.
    """
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        raise OutputError(
            f"{what} {path}: expected a {' or '.join(suffixes)} file name, not '{path.suffix}'"
        )
    if path.is_dir():
        raise OutputError(f"{what} {path}: is a folder; give a file name")
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputError(f"{what} {path}: exists and is not writable")
    ensure_writable_dir(path.parent if str(path.parent) else Path("."), f"folder of {what}")
    return path


@contextlib.contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """A temporary path beside ``path``, renamed over it when the block succeeds.

    Raises:
        OutputError: the temporary file could not be written or renamed (full disk,
            permissions); the target is left as it was.
    """
    path = Path(path)
    # The suffix stays last: writers that pick the format from the name still work.
    descriptor, temporary = tempfile.mkstemp(
        dir=path.parent, prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}"
    )
    try:
        os.fchmod(descriptor, 0o666 & ~current_umask())  # mkstemp makes 0600
    finally:
        os.close(descriptor)
    scratch = Path(temporary)
    try:
        yield scratch
        os.replace(scratch, path)
    except OSError as error:
        raise OutputError(f"cannot write {path}: {describe_os_error(error)}") from error
    finally:
        with contextlib.suppress(OSError):
            scratch.unlink()


@functools.cache
def current_umask() -> int:
    """This process's umask, read once (by setting it and back: there is no getter)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_text_atomic(path: Path, text: str) -> Path:
    """Writes ``text`` to ``path`` all at once or not at all (see :func:`atomic_path`)."""
    try:
        with atomic_path(path) as scratch, open(scratch, "w", encoding="utf-8") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
    except OSError as error:  # mkstemp itself
        raise OutputError(f"cannot write {path}: {describe_os_error(error)}") from error
    return Path(path)
