"""The one home for process state (bearchair.core.runtime): memos reset, pools and threads
stopped within bounds, child processes killed and reaped; and ``run --robots`` over the
SDK stand-ins, which used to crash at interpreter exit, ending cleanly ten times in ten."""

from __future__ import annotations

import json
import multiprocessing
import subprocess
import sys
import threading
import time

import pytest

from bearchair.core.memo import BoundedMemo
from bearchair.core.runtime import RUNTIME, Runtime, reap
from tests.helpers.cells import standin_cell_file
from tests.helpers.process_tree import REPO, descendants


def test_reset_forgets_and_shutdown_stops_in_reverse_order_and_names_what_did_not():
    runtime = Runtime()
    order: list[str] = []
    memo: BoundedMemo[str, int] = BoundedMemo(4)
    memo.put("a", 1)
    runtime.register("memo", reset=memo.clear)
    runtime.register("first", shutdown=lambda t: order.append("first") or True)
    runtime.register("stuck", shutdown=lambda t: order.append("stuck") or False)

    def raises(timeout_s: float) -> bool:
        raise RuntimeError("boom")

    runtime.register("broken", shutdown=raises)
    runtime.reset()
    assert memo.get("a") is None
    assert runtime.shutdown(1.0) == ["broken", "stuck"]  # the last registered first
    assert order == ["stuck", "first"]


def test_shutdown_joins_threads_within_its_bound_and_names_one_that_outlives_it():
    runtime = Runtime()
    release = threading.Event()
    quick = runtime.start_thread(lambda: time.sleep(0.2), name="quick")
    runtime.start_thread(release.wait, name="stuck")
    start = time.monotonic()
    left = runtime.shutdown(1.0)
    assert left == ["thread 'stuck'"] and not quick.is_alive()
    assert time.monotonic() - start < 2.0  # bounded, although one thread never ends
    release.set()
    assert runtime.join_threads(5.0) == []


def test_a_named_memo_is_reset_by_the_runtime_and_an_unnamed_one_is_not():
    named: BoundedMemo[str, int] = BoundedMemo(4, name="test memo")
    unnamed: BoundedMemo[str, int] = BoundedMemo(4)
    named.put("a", 1)
    unnamed.put("a", 1)
    assert named.get("a") == 1 and named.hits == 1
    RUNTIME.reset()
    assert named.get("a") is None and named.hits == 0
    assert unnamed.get("a") == 1


def test_the_process_wide_memos_and_pool_are_registered():
    import bearchair.skills.imagination.chair_solid
    import bearchair.skills.imagination.workers
    import bearchair.skills.planning.preplan  # noqa: F401 - registers the pre-plan memo

    assert {
        "multiprocessing resource tracker",
        "imagination pool",
        "prepared-chair memory",
        "pre-plan memo",
    } <= set(RUNTIME.names())


def test_reap_kills_a_child_that_does_not_end_in_time():
    child = subprocess.Popen(["sleep", "60"])
    start = time.monotonic()
    assert reap(child.pid, 0.2) is False
    assert time.monotonic() - start < 5.0
    quick = subprocess.Popen(["true"])
    assert reap(quick.pid, 5.0) is True


EXIT_BOUND_S = 5.0
"""How long a signalled child may take to exit and be reaped."""


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_the_imagination_pool_stops_with_its_workers_and_resource_tracker():
    """In a fresh interpreter: start the pool, stop the runtime; nothing is left."""
    script = (
        "import os, multiprocessing, time\n"
        "from bearchair.core.runtime import RUNTIME\n"
        "from bearchair.skills.imagination.workers import warm_up\n"
        "warm_up(2)\n"
        "print(len(multiprocessing.active_children()), flush=True)\n"
        "print(RUNTIME.shutdown(30.0), flush=True)\n"
        "print(len(multiprocessing.active_children()), flush=True)\n"
        "input()\n"  # holds the process while the test looks at its children
    )
    process = subprocess.Popen(
        [sys.executable, "-c", script],
        cwd=REPO,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline().strip() == "2"
        assert process.stdout.readline().strip() == "[]"
        assert process.stdout.readline().strip() == "0"
        # The resource tracker too: it was signalled; on a loaded machine it may take a
        # moment to exit and be reaped (EXIT_BOUND_S).
        deadline = time.monotonic() + EXIT_BOUND_S
        while descendants(process.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert descendants(process.pid) == []
    finally:
        process.communicate("\n", timeout=30)
    assert process.returncode == 0


def test_the_kill_path_reaps_multiprocessing_children_at_once():
    context = multiprocessing.get_context("spawn")
    child = context.Process(target=time.sleep, args=(60,), daemon=True)
    child.start()
    start = time.monotonic()
    RUNTIME.kill()
    assert not child.is_alive() and time.monotonic() - start < 5.0


# --- run --robots over the stand-ins, ten times ----------------------------------------

RUNS = 10


@pytest.mark.slow
@pytest.mark.timeout(1200)
def test_run_on_robots_over_the_standins_exits_cleanly_ten_times_in_ten(tmp_path):
    """Each run connects qi to the NAOqi stand-in, moves the stand-in Panda through the
    scan, fails (the stand-in camera sees a flat wall: "no floor plane"), writes its
    record and exits: status 1, never a signal (it used to end in SIGABRT or SIGSEGV at
    interpreter exit in about half the runs, a qi session and the planner's build thread
    still live)."""
    pytest.importorskip("qi")
    from bearchair.hardware.real.standins import NaoqiStandin

    statuses = []
    with NaoqiStandin(time_scale=20.0) as naoqi:
        cell = standin_cell_file(tmp_path, naoqi.url)
        for run in range(RUNS):
            out = tmp_path / f"run{run}"
            done = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "bearchair.executive.cli",
                    "run",
                    "--robots",
                    str(cell),
                    "--yes",
                    "--mute",
                    "--timeout",
                    "120",
                    "--out",
                    str(out),
                ],
                cwd=REPO,
                stdin=subprocess.DEVNULL,
                capture_output=True,
                text=True,
                timeout=300,
            )
            statuses.append(done.returncode)
            assert done.returncode in (0, 1), done.stderr[-2000:]
            assert json.loads((out / "summary.json").read_text())["backend"] == "real"
            assert "still running at exit" not in done.stderr
    assert len(statuses) == RUNS


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_the_trial_server_and_its_forks_stop_with_the_runtime():
    """In a fresh interpreter: one forked trial, then the runtime stopped; the trial
    server (multiprocessing's forkserver) is not left behind."""
    script = (
        "import io, json, sys, tempfile\n"
        "from bearchair.core.runtime import RUNTIME\n"
        "from bearchair.evaluation.forked_workers import PreloadedLauncher\n"
        "from bearchair.evaluation.worker_process import run_worker\n"
        "from tests.helpers import forked_fakes\n"
        "out = tempfile.mkdtemp()\n"
        "outcome = run_worker(PreloadedLauncher(forked_fakes.report), "
        "{'out_dir': out, 'seed': 3}, 120)\n"
        "print(outcome.summary['seed'], flush=True)\n"
        "print(RUNTIME.shutdown(30.0), flush=True)\n"
        "input()\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", script],
        cwd=REPO,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert process.stdout.readline().strip() == "3"
        assert process.stdout.readline().strip() == "[]"
        assert descendants(process.pid) == []
    finally:
        process.communicate("\n", timeout=30)
    assert process.returncode == 0
