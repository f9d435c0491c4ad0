"""Trial-worker entries for tests/test_forked_workers.py and tests/test_runtime.py:
module-level, so the trial server can import them by name."""

from __future__ import annotations

import json
import os
import signal
import sys
import time

from bearchair.evaluation.worker_process import RESULT_MARKER

runs_in_this_process = 0
"""How many entries this process has run: a fork starts from the server's 0."""


def report(argv: list[str]) -> int:
    """Prints a summary of the process the trial ran in."""
    global runs_in_this_process
    runs_in_this_process += 1
    payload = json.loads(argv[0])
    summary = {
        "pid": os.getpid(),
        "session_leader": os.getsid(0) == os.getpid(),
        "preloaded": sorted(m for m in ("open3d", "casadi", "pybullet") if m in sys.modules),
        "runs_in_this_process": runs_in_this_process,
        "seed": payload["seed"],
    }
    print("some output of the mission", flush=True)
    print("a warning", file=sys.stderr, flush=True)
    print(RESULT_MARKER + json.dumps({"summary": summary}), flush=True)
    return 0


def sleep_forever(argv: list[str]) -> int:
    with open(os.path.join(json.loads(argv[0])["out_dir"], "pid"), "w") as handle:
        handle.write(str(os.getpid()))
    time.sleep(600)
    return 0


def segfault(argv: list[str]) -> int:
    print("about to crash", file=sys.stderr, flush=True)
    os.kill(os.getpid(), signal.SIGSEGV)
    return 0


def raise_error(argv: list[str]) -> int:
    raise RuntimeError("the entry failed")
