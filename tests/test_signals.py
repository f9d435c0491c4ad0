"""Every signal that ends ``bearchair run`` and ``bearchair imagine``, sent to the real
console script in a subprocess: the exit status is 128 + the signal's number
(docs/exit-status.md), the run's summary says which signal, and no process the command
started survives it (the imagination's pool workers, its resource tracker).

The process tree is the point here, so these are subprocesses; what the tree and the
robots do on a signal is checked in-process in tests/test_faults.py.
"""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest

from bearchair.core.meshes import box_chair_mesh
from bearchair.executive import cli
from tests.process_tree import bearchair, descendants, reap_all, survivors, wait_for

STOP_SIGNALS = [
    signal.SIGINT,
    signal.SIGTERM,
    signal.SIGHUP,
    signal.SIGQUIT,
    signal.SIGUSR1,
    signal.SIGUSR2,
]
START_S = 180.0
"""How long a command may take to get going on the loaded 2-core machine (imports, the
simulated world: 5-30 s measured)."""


def _ticking(out: Path) -> bool:
    ticks = out / "ticks.jsonl"
    return ticks.is_file() and ticks.stat().st_size > 0


def _stop(process, signum: int, timeout_s: float = 60.0) -> int:
    """Sends ``signum`` and waits for the exit; a process that does not exit is killed
    (and the test fails on its status)."""
    process.send_signal(signum)
    try:
        return process.wait(timeout_s)
    except Exception:
        reap_all([process.pid, *descendants(process.pid)])
        process.wait(10)
        raise


@pytest.mark.slow
@pytest.mark.timeout(400)
@pytest.mark.parametrize("signum", STOP_SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_each_stop_signal_ends_run_with_its_status_a_summary_and_no_child(tmp_path, signum):
    out = tmp_path / "run"
    err = tmp_path / "stderr.txt"
    process = bearchair(["run", "--mute", "--seed", "0", "--out", str(out)], err)
    assert wait_for(lambda: _ticking(out) or process.poll() is not None, START_S)
    assert process.poll() is None, err.read_text()
    time.sleep(3.0)  # a few seconds into the mission
    status = _stop(process, signum)
    name = signal.Signals(signum).name
    assert status == 128 + signum, err.read_text()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["signal"] == name
    assert summary["outcome"] == "failure"
    assert cli.main(["inspect", str(out)]) == 0  # the record replays
    assert survivors(process.pid) == []
    assert "Traceback" not in err.read_text()


def _chair_file(tmp_path: Path) -> Path:
    path = tmp_path / "chair.obj"
    box_chair_mesh().export(path)
    return path


@pytest.mark.timeout(300)
@pytest.mark.parametrize("signum", STOP_SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_each_stop_signal_ends_imagine_and_takes_its_pool_along(tmp_path, signum):
    err = tmp_path / "stderr.txt"
    process = bearchair(["imagine", str(_chair_file(tmp_path)), "--workers", "2"], err)
    # Two pool workers and the resource tracker: the children the issue found orphaned.
    assert wait_for(lambda: len(descendants(process.pid)) >= 3, START_S), err.read_text()
    started = descendants(process.pid)
    status = _stop(process, signum)
    name = signal.Signals(signum).name
    assert status == 128 + signum, err.read_text()
    assert survivors(process.pid) == [], f"started {started}"
    assert err.read_text().strip().splitlines()[-1] == f"bearchair: interrupted by {name}"


@pytest.mark.timeout(300)
def test_a_second_ctrl_c_on_imagine_leaves_no_pool_worker_behind(tmp_path):
    err = tmp_path / "stderr.txt"
    process = bearchair(["imagine", str(_chair_file(tmp_path)), "--workers", "2"], err)
    assert wait_for(lambda: len(descendants(process.pid)) >= 3, START_S), err.read_text()
    process.send_signal(signal.SIGINT)
    time.sleep(0.2)  # while the first one's clean-up runs (two at once are one to Python)
    process.send_signal(signal.SIGINT)
    assert process.wait(60) == 130
    assert survivors(process.pid) == []


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_sighup_while_the_imagination_runs_stops_the_mission_and_its_pool(tmp_path):
    """The ssh session closing while the imagination's workers drop: the summary is
    written and the pool workers and the resource tracker go with the run."""
    out = tmp_path / "run"
    err = tmp_path / "stderr.txt"
    process = bearchair(["run", "--mute", "--seed", "0", "--out", str(out)], err)
    assert wait_for(
        lambda: len(descendants(process.pid)) >= 3 or process.poll() is not None, 2 * START_S
    ), err.read_text()
    assert process.poll() is None, err.read_text()
    status = _stop(process, signal.SIGHUP)
    assert status == 129, err.read_text()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] and summary["signal"] == "SIGHUP"
    assert survivors(process.pid) == []


@pytest.mark.timeout(300)
def test_a_second_ctrl_c_during_a_run_still_writes_the_summary(tmp_path):
    out = tmp_path / "run"
    err = tmp_path / "stderr.txt"
    process = bearchair(["run", "--mute", "--seed", "0", "--out", str(out)], err)
    assert wait_for(lambda: _ticking(out) or process.poll() is not None, START_S)
    assert process.poll() is None, err.read_text()
    process.send_signal(signal.SIGINT)
    time.sleep(0.2)  # while the first one's orderly stop runs
    process.send_signal(signal.SIGINT)
    assert process.wait(60) == 130
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["signal"] == "SIGINT"
    assert survivors(process.pid) == []


class _SlowWorld:
    """A simulated world whose construction takes 3 s: long enough for a Ctrl-C."""

    def __init__(self, config) -> None:
        time.sleep(3.0)

    def close(self) -> None:
        pass


def test_ctrl_c_while_the_world_is_built_leaves_a_record_inspect_replays(
    tmp_path, monkeypatch, capsys
):
    import os
    import threading

    import bearchair.hardware.sim.world

    monkeypatch.setattr(bearchair.hardware.sim.world, "SimWorld", _SlowWorld)
    out = tmp_path / "run"
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        assert cli.main(["run", "--mute", "--out", str(out)]) == 130
    finally:
        timer.cancel()
    capsys.readouterr()
    assert cli.main(["inspect", str(out)]) == 0
    shown = capsys.readouterr().out
    assert "tick 0 of 0" in shown and "interrupted by SIGINT" in shown
