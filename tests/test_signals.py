"""Every signal that ends ``bearchair run`` and ``bearchair imagine``, sent to the real
console script in a subprocess: the exit status is 128 + the signal's number
(docs/exit-status.md), the run's summary says which signal, and no process the command
started survives it (the imagination's pool workers, its resource tracker).

The process tree is the point here, so these are subprocesses; what the tree and the
robots do on a signal is checked in-process in tests/test_faults.py.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bearchair.core.meshes import box_chair_mesh
from bearchair.executive import cli
from tests.helpers.process_tree import REPO, bearchair, descendants, reap_all, survivors, wait_for

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


@pytest.mark.slow
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
    last_line = err.read_text().strip().splitlines()[-1]
    assert last_line == f"bearchair: interrupted by {name}", err.read_text()


@pytest.mark.slow
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


@pytest.mark.slow
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
    """A simulated world whose construction is interrupted by a Ctrl-C: it sends the
    signal itself, so it always arrives while the world is built (a timer started before
    the run may fire before the run folder exists on a loaded machine)."""

    def __init__(self, config) -> None:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(3.0)

    def close(self) -> None:
        pass


@pytest.mark.slow
def test_ctrl_c_while_the_world_is_built_leaves_a_record_inspect_replays(
    tmp_path, monkeypatch, capsys
):
    import bearchair.hardware.sim.world

    monkeypatch.setattr(bearchair.hardware.sim.world, "SimWorld", _SlowWorld)
    out = tmp_path / "run"
    assert cli.main(["run", "--mute", "--out", str(out)]) == 130
    capsys.readouterr()
    assert cli.main(["inspect", str(out)]) == 0
    shown = capsys.readouterr().out
    assert "tick 0 of 0" in shown and "interrupted by SIGINT" in shown


# --- the second signal, while the first one's clean-up is held up -----------------------
# Two signals sent a moment apart may both arrive after the first one's clean-up ended
# (it takes milliseconds): these scripts hold that clean-up (a slow robot stop, a slow
# pool shutdown) so the second signal is sure to come in the middle of it.

SECOND_SIGNAL_ON_A_POOL = """
import sys, time
from bearchair.executive import interrupts
from bearchair.skills.imagination.workers import warm_up
warm_up(2)
with interrupts.handling_signals():
    try:
        print("ready", flush=True)
        time.sleep(120)
    except KeyboardInterrupt:
        print("stopping slowly", flush=True)
        time.sleep(120)
"""


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_second_signal_kills_and_reaps_the_pool_before_it_exits(tmp_path):
    err = tmp_path / "stderr.txt"
    process = subprocess.Popen(
        [sys.executable, "-c", SECOND_SIGNAL_ON_A_POOL],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=err.open("w"),
        text=True,
        start_new_session=True,
    )
    assert process.stdout.readline().strip() == "ready", err.read_text()
    assert len(descendants(process.pid)) >= 3  # two workers and the resource tracker
    process.send_signal(signal.SIGTERM)
    assert process.stdout.readline().strip() == "stopping slowly"
    process.send_signal(signal.SIGTERM)
    assert process.wait(30) == 143
    assert survivors(process.pid) == []


SECOND_SIGNAL_ON_A_RUN = """
import sys, threading, time
from pathlib import Path
from bearchair.executive import cli
from bearchair.executive import run as executive_run
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import RunInfo
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.testing.scripted import ScriptedSkills
from bearchair.trees.mission import create_tree

robot = fake_robot(judge=FakeJudge())
skills = ScriptedSkills(delays_s={"scan_chair": 60.0})
stop = robot.emergency_stop
stops = []

def slow_stop():  # the first stop hangs, as a robot that does not answer would
    stops.append(1)
    stop()
    if len(stops) == 1 and skills.calls.get("scan_chair"):
        print("stopping slowly", flush=True)
        time.sleep(60)

robot.emergency_stop = slow_stop

def fake_run(config, skills_=None, on_tick=None, tree=None):
    root = create_tree()
    recorder = RunRecorder(config.out_dir, root)
    info = RunInfo(chair="stub", placement="accessible", helper="obeys", seed=0)
    return executive_run._run_tree(root, recorder, robot, config, info, skills, None, None)

executive_run.run_in_simulation = fake_run

def ready():
    while not skills.calls.get("scan_chair"):
        time.sleep(0.01)
    print("ready", flush=True)

threading.Thread(target=ready, daemon=True).start()
sys.exit(cli.main(["run", "--mute", "--out", sys.argv[1]]))
"""


@pytest.mark.slow
@pytest.mark.timeout(180)
def test_a_second_signal_during_a_slow_stop_still_writes_the_summary(tmp_path):
    out = tmp_path / "run"
    err = tmp_path / "stderr.txt"
    process = subprocess.Popen(
        [sys.executable, "-c", SECOND_SIGNAL_ON_A_RUN, str(out)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=err.open("w"),
        text=True,
        start_new_session=True,
    )
    assert process.stdout.readline().strip() == "ready", err.read_text()
    process.send_signal(signal.SIGHUP)
    assert process.stdout.readline().strip() == "stopping slowly", err.read_text()
    process.send_signal(signal.SIGINT)
    assert process.wait(30) == 130, err.read_text()  # the status of the signal that ended it
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["signal"] == "SIGHUP"
    assert summary["failed_stage"] == "ScanChair"
    assert "bearchair: second SIGINT: exiting now" in err.read_text()
