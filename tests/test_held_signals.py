"""A stop signal held while the main thread starts worker processes
(:mod:`bearchair.core.held_signals`): in-process for the holding, in a fresh interpreter
for the pool's start."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from bearchair.core.held_signals import holding_stop_signals
from bearchair.executive import interrupts
from tests.helpers.process_tree import REPO


def test_signals_held_in_nested_sections_are_one_stop_delivered_as_the_outermost_ends():
    reached = []
    with interrupts.handling_signals():
        with pytest.raises(interrupts.Interrupted) as caught:
            with holding_stop_signals():
                with holding_stop_signals():
                    os.kill(os.getpid(), signal.SIGUSR1)
                    time.sleep(0.05)  # the handler runs in here, and holds it
                    os.kill(os.getpid(), signal.SIGUSR2)
                    time.sleep(0.05)
                reached.append("the inner section's end")
                time.sleep(0.05)
            reached.append("after the outer section")  # not reached: delivered at its end
        assert interrupts.received() == signal.SIGUSR1
    assert reached == ["the inner section's end"]
    assert caught.value.signum == signal.SIGUSR1


def test_outside_a_section_the_signal_raises_at_once():
    with interrupts.handling_signals(), pytest.raises(interrupts.Interrupted):
        os.kill(os.getpid(), signal.SIGUSR1)
        time.sleep(1.0)
        pytest.fail("not interrupted")


START_AND_SIGNAL = """
import os, signal, multiprocessing.util as util
from bearchair.core.runtime import RUNTIME
from bearchair.executive.interrupts import Interrupted, handling_signals
from bearchair.skills.imagination import workers
spawn, started = util.spawnv_passfds, []
def spawn_then_signal(*args):
    started.append(spawn(*args))
    os.kill(os.getpid(), signal.SIGUSR1)  # between the child's start and its data
    return started[-1]
util.spawnv_passfds = spawn_then_signal
with handling_signals():
    try:
        workers.warm_up(2, wait=False)
    except Interrupted:
        pass
    in_pool = [p.pid for pool in workers._pools.values() for p in workers._worker_processes(pool)]
    print(len(started), sorted(in_pool) == sorted(started[1:]), flush=True)
    RUNTIME.kill()
"""


def test_a_stop_signal_while_the_pool_starts_leaves_no_worker_half_started():
    """The signal comes in the one place that matters, after each child process starts and
    before it is sent its data: it is held until the pool has its workers, so each started
    worker is one the pool (and the kill path) knows, and none reads an empty pipe."""
    done = subprocess.run(
        [sys.executable, "-c", START_AND_SIGNAL],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    # The resource tracker and the two workers started; the workers are the pool's.
    assert done.stdout.split() == ["3", "True"], done.stdout + done.stderr
    assert "Error" not in done.stderr, done.stderr
