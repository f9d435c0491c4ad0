"""Which processes a command left behind: its descendants while it runs, and what
still lives in its session after it ended (descendants are re-parented to init when
their parent dies, but keep its session). psutil when installed, else /proc."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time
from pathlib import Path

try:
    import psutil
except ImportError:  # pragma: no cover - psutil comes with ray, in the trials extra
    psutil = None

REPO = Path(__file__).resolve().parents[2]
"""The repository's root (tests/helpers/ is two folders below it)."""


def bearchair(args: list[str], stderr_path: Path, **kwargs) -> subprocess.Popen:
    """Starts ``bearchair ARGS`` as the console script, in a session of its own (so
    the processes it starts can be found after it ended), stderr into ``stderr_path``."""
    return subprocess.Popen(
        [sys.executable, "-m", "bearchair.executive.cli", *args],
        cwd=REPO,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=stderr_path.open("w"),
        text=True,
        start_new_session=True,
        **kwargs,
    )


def process_alive(pid: int) -> bool:
    """Running (a zombie waiting for its reaper counts as gone)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    return "State:\tZ" not in status


def descendants(pid: int) -> list[int]:
    """The live descendants of ``pid``."""
    if psutil is not None:
        try:
            return [
                p.pid for p in psutil.Process(pid).children(recursive=True) if process_alive(p.pid)
            ]
        except psutil.NoSuchProcess:
            return []
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return [p for p in found if process_alive(p)]


def session_members(sid: int) -> list[int]:
    """The live processes of the session ``sid`` (other than zombies)."""
    members = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            members.append(int(entry.name))
    return members


def survivors(sid: int, settle_s: float = 3.0) -> list[str]:
    """What still runs in the session ``sid`` after ``settle_s`` (a child SIGKILLed a
    moment ago may still be dying), as ``pid: command line``."""
    deadline = time.monotonic() + settle_s
    while session_members(sid) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = []
    for pid in session_members(sid):
        try:
            command = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        left.append(f"{pid}: {command[:160]}")
    return left


def wait_for(predicate, timeout_s: float, poll_s: float = 0.1) -> bool:
    """Polls ``predicate`` until it is true or ``timeout_s`` passed; its last value."""
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            return False
        time.sleep(poll_s)
    return True


def reap_all(pids: list[int]) -> None:
    """SIGKILLs what a failed test left behind (its own cleanup, never the assertion)."""
    for pid in pids:
        with contextlib.suppress(OSError):
            os.kill(pid, 9)
