"""One trial of a campaign, in its own process: ``python -m bearchair.evaluation.worker '<json>'``.

The JSON is ``bearchair.evaluation.protocol.TrialSpec.to_payload``: chair_path, placement,
helper, seed, trial_index, out_dir, timeout_s, record (and ``tree``, a ``--tree`` SPEC,
when the campaign runs another tree than the mission's). The worker runs the whole mission in the
simulated world (``bearchair.executive.run.run_in_simulation``), which writes the run record
into out_dir, keeps the robot's reconstructed chair (``chair_reconstructed.ply``) for the
imagined-pose picture, and prints one line ``BEARCHAIR-TRIAL-RESULT {...}`` on stdout
for the harness. Exit status: 0 the mission ended (success or failure), 3 an exception.
"""

from __future__ import annotations

import dataclasses
import faulthandler
import json
import os
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bearchair.evaluation.worker_process import RESULT_MARKER

if TYPE_CHECKING:
    from bearchair.executive.config import RunConfig

MISSION_TIMEOUT_MARGIN_S = 30.0
"""The mission stops itself this long before the harness would kill the worker, so a
slow trial still ends with a full run record."""


class ChairKeeper:
    """Keeps the last reconstructed chair and sitting pose seen on the blackboard.

    Both are in the world frame at the same moment (the mission moves them together
    when the helper turns the chair), so they can be drawn together afterwards.
    """

    def __init__(self) -> None:
        self.chair_mesh: Any = None

    def __call__(self, runner: Any) -> None:
        import py_trees

        from bearchair.behaviours import keys

        storage = py_trees.blackboard.Blackboard.storage
        mesh = storage.get(keys.CHAIR_MESH)
        if mesh is not None:
            self.chair_mesh = mesh

    def save(self, out_dir: Path) -> None:
        if self.chair_mesh is not None:
            self.chair_mesh.export(out_dir / "chair_reconstructed.ply")


def _rerun_installed() -> bool:
    from bearchair.executive.recording.mission_recording import rerun_available

    if rerun_available():
        return True
    print("no recording: rerun-sdk is not installed here", file=sys.stderr)
    return False


def mission_timeout_s(harness_timeout_s: float) -> float:
    """The mission's own timeout: a margin before the harness's kill."""
    return max(harness_timeout_s - MISSION_TIMEOUT_MARGIN_S, 0.8 * harness_timeout_s)


def watch_for_orphaning(poll_s: float = 0.5) -> None:
    """Kills this worker's process group if the harness goes away (a SIGKILLed parent).

    The harness also asks the kernel to kill the worker when it dies; this takes the
    worker's own children (the imagination's processes) along, which that does not.
    """
    parent = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(poll_s)
            if os.getppid() != parent:
                os.killpg(0, signal.SIGKILL)

    threading.Thread(target=watch, name="orphan-watch", daemon=True).start()


def trial_run_config(payload: dict[str, Any]) -> RunConfig:
    """The run of a trial payload: muted, its own timeout a margin inside the harness's
    (the payload's ``timeout_s``), recorded only where Rerun is installed."""
    from bearchair.executive.config import RunConfig

    for key in ("out_dir", "placement", "helper", "seed", "timeout_s"):
        if key not in payload:
            raise KeyError(key)  # a trial names its run: no default stands in
    config = RunConfig.from_payload(payload)
    return dataclasses.replace(
        config,
        gui=False,
        mute=True,
        timeout_s=mission_timeout_s(config.timeout_s),
        record=config.record and _rerun_installed(),
    )


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m bearchair.evaluation.worker '<trial json>'", file=sys.stderr)
        return 2
    try:
        config = trial_run_config(json.loads(argv[0]))
        from bearchair.executive.run import run_in_simulation
        from bearchair.executive.tree_source import load_tree_factory

        out_dir = config.out_dir
        keeper = ChairKeeper()
        summary = run_in_simulation(
            config, on_tick=keeper, tree=load_tree_factory(config.tree_spec)
        )
        try:
            keeper.save(out_dir)
        except Exception as error:  # the picture is optional, the result is not
            print(f"could not save the reconstructed chair: {error}", file=sys.stderr)
    except Exception as error:
        traceback.print_exc()
        message = {"error": f"{type(error).__name__}: {error}".splitlines()[0][:300]}
        print(RESULT_MARKER + json.dumps(message), flush=True)
        return 3
    print(RESULT_MARKER + json.dumps({"summary": summary.to_json()}), flush=True)
    return 0


def run_guarded(entry: Callable[[list[str]], int], argv: list[str]) -> int:
    """``entry(argv)`` as a trial worker runs it, started as a command or as a fork.

    A segfault leaves "Fatal Python error" in worker.log; a worker in a process group of
    its own (started by the harness) dies with the harness; the harness's SIGTERM
    (timeout, Ctrl-C) stops the mission like Ctrl-C, so the robots stop and the run
    folder gets its summary before the SIGKILL that follows. The runtime is shut down at
    the end (``bearchair.core.runtime``: the imagination's worker processes, the planner's
    build thread), as a fork ends without the interpreter's exit hooks.
    """
    from bearchair.core.runtime import RUNTIME
    from bearchair.executive.interrupts import handling_signals

    faulthandler.enable()
    if os.getpgid(0) == os.getpid():
        watch_for_orphaning()
    try:
        with handling_signals():
            return entry(argv)
    finally:
        RUNTIME.shutdown()


if __name__ == "__main__":
    sys.exit(run_guarded(main, sys.argv[1:]))
