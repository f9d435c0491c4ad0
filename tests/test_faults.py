"""Faults the executive survives, each with what must survive it.

Signals at each stage, a second Ctrl-C, a full disk, a bug, closed pipes, damaged run
records, caches and databases, concurrent and killed campaigns, crashed workers. The
mission runs on fakes (scripted skills, a fake robot) in this process wherever the
point is the record; a subprocess only where the exit status or the process tree is.
"""

from __future__ import annotations

import errno
import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bearchair.core.runtime import RUNTIME
from bearchair.evaluation.store import TrialStore, campaign_lock
from bearchair.executive import cli
from bearchair.executive import run as executive_run
from bearchair.executive.records.replay import RecordedRun
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import RunInfo
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.testing.scripted import ScriptedSkills
from bearchair.trees.mission import create_tree
from tests.helpers.campaigns import FAKE_WORKER, table_without_timing, worker_pids, write_chairs
from tests.helpers.missions import FakeMission
from tests.helpers.process_tree import REPO, process_alive

# --- a mission on fakes behind the real CLI ----------------------------------------------


def signal_later(signum: int, after_s: float) -> threading.Timer:
    timer = threading.Timer(after_s, os.kill, (os.getpid(), signum))
    timer.start()
    return timer


def signal_once_called(signum: int, calls: dict, skill: str) -> list[float]:
    """Sends `signum` to this process once `skill` has been called (the tree is ticking
    and the skill's worker is blocked), however long start-up took on a loaded machine.

    Returns:
        A list that receives the monotonic time the signal was sent.
    """
    sent_at: list[float] = []

    def wait_then_signal() -> None:
        deadline = time.monotonic() + 60.0
        while not calls.get(skill) and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.1)
        sent_at.append(time.monotonic())
        os.kill(os.getpid(), signum)

    threading.Thread(target=wait_then_signal, daemon=True).start()
    return sent_at


def read_summary(run_dir: Path) -> dict:
    return json.loads((run_dir / "summary.json").read_text())


@pytest.mark.parametrize(
    ("signum", "status", "name"),
    [(signal.SIGINT, 130, "SIGINT"), (signal.SIGTERM, 143, "SIGTERM")],
)
def test_a_signal_while_ticking_stops_tree_and_robots_and_keeps_the_summary(
    tmp_path, monkeypatch, capsys, signum, status, name
):
    fake = FakeMission(delays_s={"scan_chair": 30.0})
    monkeypatch.setattr(executive_run, "run_in_simulation", fake)
    out = tmp_path / "run"
    sent_at = signal_once_called(signum, fake.skills.calls, "scan_chair")
    assert cli.main(["run", "--mute", "--out", str(out)]) == status
    assert sent_at and time.monotonic() - sent_at[0] < 5  # the 30 s skill was not waited for
    summary = read_summary(out)
    assert summary["interrupted"] is True and summary["signal"] == name
    assert summary["outcome"] == "failure" and summary["failed_stage"] == "ScanChair"
    # The leaf's terminate() sets the cancel and does not wait for its worker, which sees
    # it at its next poll: possibly after the CLI returned.
    deadline = time.monotonic() + 2.0
    while "scan_chair" not in fake.skills.cancelled and time.monotonic() < deadline:
        time.sleep(0.01)
    assert "scan_chair" in fake.skills.cancelled
    assert fake.robot.humanoid.stopped >= 1
    assert RecordedRun(out).ticks  # the record replays
    assert "Traceback" not in capsys.readouterr().err


class SlowWorld:
    """A simulated world whose construction takes long (or swallows the interrupt)."""

    swallow = False

    build_s = 3.0

    def __init__(self, config) -> None:
        deadline = time.monotonic() + self.build_s
        while time.monotonic() < deadline:
            try:
                time.sleep(0.01)
            except BaseException:  # as trimesh does around its optional imports
                if not self.swallow:
                    raise

    def close(self) -> None:
        pass


@pytest.mark.slow
@pytest.mark.parametrize("swallow", [False, True], ids=["raised", "swallowed-by-a-library"])
def test_ctrl_c_while_the_world_is_built_leaves_a_summary(tmp_path, monkeypatch, swallow):
    import bearchair.hardware.sim.world

    world = type("World", (SlowWorld,), {"swallow": swallow})
    monkeypatch.setattr(bearchair.hardware.sim.world, "SimWorld", world)
    out = tmp_path / "run"
    timer = signal_later(signal.SIGINT, 0.5)
    start = time.monotonic()
    status = cli.main(["run", "--mute", "--out", str(out)])
    timer.cancel()
    assert status == 130
    summary = read_summary(out)
    assert summary["interrupted"] and "while building the simulated world" in summary["reason"]
    # A swallowed interrupt is honoured as soon as the build returns.
    assert (time.monotonic() - start < SlowWorld.build_s) != swallow


SECOND_SIGNAL = textwrap.dedent(
    """
    import sys, time
    from pathlib import Path
    from bearchair.executive import interrupts
    marker = Path(sys.argv[1])
    with interrupts.handling_signals():
        with interrupts.emergency_stop_on_second_signal(lambda: marker.write_text("stopped")):
            try:
                print("ready", flush=True)
                time.sleep(60)
            except KeyboardInterrupt:
                print("stopping slowly", flush=True)
                time.sleep(60)  # a slow clean-up: the second Ctrl-C must not wait for it
    """
)


def test_a_second_ctrl_c_exits_at_once_after_the_emergency_stop(tmp_path):
    marker = tmp_path / "stop-called"
    process = subprocess.Popen(
        [sys.executable, "-c", SECOND_SIGNAL, str(marker)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stdout.readline().strip() == "ready"
    process.send_signal(signal.SIGINT)
    assert process.stdout.readline().strip() == "stopping slowly"
    start = time.monotonic()
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=10)
    assert process.returncode == 130 and time.monotonic() - start < 2
    assert marker.read_text() == "stopped"
    assert err.strip() == "bearchair: second SIGINT: exiting now"


# --- full disk, a bug, closed pipes -------------------------------------------------------


class FullDisk:
    """A ticks.jsonl stream that fills the disk after ``lines`` lines."""

    def __init__(self, stream, lines: int) -> None:
        self._stream, self._left = stream, lines
        self.closed = False

    def write(self, text: str) -> int:
        if self._left <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        self._left -= 1
        return self._stream.write(text)

    def flush(self) -> None:
        self._stream.flush()

    def close(self) -> None:
        self.closed = True
        self._stream.close()


def test_a_full_disk_while_ticking_is_one_line_and_the_robots_stop(tmp_path, monkeypatch, capsys):
    real_init = RunRecorder.__init__

    def init(self, out_dir, root):
        real_init(self, out_dir, root)
        self._ticks = FullDisk(self._ticks, lines=1)

    monkeypatch.setattr(RunRecorder, "__init__", init)
    # The scan's end changes the record: that second line finds the disk full.
    fake = FakeMission(delays_s={"scan_chair": 0.2, "imagine_sitting": 30.0})
    monkeypatch.setattr(executive_run, "run_in_simulation", fake)
    out = tmp_path / "run"
    assert cli.main(["run", "--mute", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no space left on the device" in err[0], err
    assert "robots stopped" in err[0]
    # The imagination (running, or queued in its worker on the tick the scan ended) never
    # ran to its end: either its worker saw the cancel, or the stop cancelled the queued
    # job before the skill was called.
    assert fake.robot.humanoid.stopped >= 1
    imagined = fake.skills.calls.get("imagine_sitting", [])
    assert not imagined or "imagine_sitting" in fake.skills.cancelled, fake.skills.cancelled
    assert set(fake.skills.calls) <= {"scan_chair", "imagine_sitting"}, set(fake.skills.calls)
    # What reached the disk is still a readable record (its first tick), with its summary.
    assert len(RecordedRun(out).ticks) == 1
    assert "no space" in read_summary(out)["record_error"]


def test_a_failed_summary_write_leaves_no_half_file(tmp_path, monkeypatch, capsys):
    import bearchair.executive.outputs

    real_replace = os.replace

    def full(source, target):
        if Path(target).name == "summary.json":
            raise OSError(errno.ENOSPC, "No space left on device")
        real_replace(source, target)

    monkeypatch.setattr(executive_run, "run_in_simulation", FakeMission())
    monkeypatch.setattr(bearchair.executive.outputs.os, "replace", full)
    out = tmp_path / "run"
    assert cli.main(["run", "--mute", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "summary.json" in err and "no space left" in err and len(err.splitlines()) == 1
    assert not (out / "summary.json").exists()
    assert not [p for p in out.iterdir() if ".tmp" in p.name]  # no temporary left behind


def test_a_bug_exits_3_with_one_line_and_the_traceback_in_the_run_folder(
    tmp_path, monkeypatch, capsys
):
    def broken(summary):
        raise TypeError("unsupported format string passed to NoneType.__format__")

    monkeypatch.setattr(executive_run, "run_in_simulation", FakeMission())
    monkeypatch.setattr(executive_run, "format_summary", broken)
    out = tmp_path / "run"
    assert cli.main(["run", "--mute", "--out", str(out)]) == 3
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert "internal error (TypeError" in err and str(out / "bearchair.log") in err
    log = (out / "bearchair.log").read_text()
    assert "Traceback (most recent call last)" in log and "broken" in log
    assert read_summary(out)["outcome"] == "success"  # the record was complete before the bug


def test_a_bug_outside_a_run_logs_to_the_cache(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BEARCHAIR_CACHE", str(tmp_path / "cache"))
    from bearchair.executive import cmd_tree

    monkeypatch.setattr(cmd_tree, "_tree", lambda args: 1 / 0)
    assert cli.main(["tree"]) == 3
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "ZeroDivisionError" in err
    logs = list((tmp_path / "cache" / "logs").glob("crash-*.log"))
    assert len(logs) == 1 and "ZeroDivisionError" in logs[0].read_text()


@pytest.mark.slow
def test_a_closed_stdout_is_not_a_traceback():
    # `bearchair tree | head -1`: the reader goes away after the first line.
    command = f"{sys.executable} -m bearchair.executive.cli tree --format ascii | head -1"
    done = subprocess.run(
        ["bash", "-o", "pipefail", "-c", command], cwd=REPO, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr


# --- run records ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def recorded_run(tmp_path_factory) -> Path:
    from bearchair.core.arena import DEFAULT_ARENA
    from bearchair.executive.runner import MissionRunner, summarise

    out = tmp_path_factory.mktemp("recorded")
    root = create_tree()
    recorder = RunRecorder(out, root)
    runner = MissionRunner(
        root,
        ScriptedSkills(delays_s={"scan_chair": 0.02}),
        fake_robot(judge=FakeJudge()),
        seed=1,
        arena=DEFAULT_ARENA,
        recorder=recorder,
        tick_period_s=0.002,
    )
    recorder.write_summary(summarise(runner.run(), RunInfo(chair="stub")))
    recorder.close()
    return out


def copy_run(source: Path, target: Path) -> Path:
    target.mkdir()
    for name in ("tree.json", "ticks.jsonl", "summary.json"):
        (target / name).write_bytes((source / name).read_bytes())
    return target


def test_a_damaged_line_in_the_middle_is_skipped_not_the_rest(recorded_run, tmp_path, capsys):
    run = copy_run(recorded_run, tmp_path / "run")
    first, *_, last = (run / "ticks.jsonl").read_text().splitlines()
    torn_in_the_middle = first[: len(first) // 2]
    torn_at_the_end = '{"tick": 99999, "t": 1'
    lines = [first, torn_in_the_middle, last, torn_at_the_end]
    (run / "ticks.jsonl").write_text("\n".join(lines) + "\n")
    assert cli.main(["inspect", str(run), "--timeline"]) == 0
    out = capsys.readouterr().out
    assert "2 unreadable line(s) of ticks.jsonl skipped (line 2, 4)" in out
    assert "ReleaseAndStand [✓]" in out  # the ticks after the damage are all there
    assert "outcome: success" in out


@pytest.mark.parametrize(
    ("content", "note"),
    [(b"{not json", "unreadable"), (b"\xff\xfe\x00binary", "not UTF-8"), (b"[1, 2]", "object")],
)
def test_a_damaged_summary_is_ignored_with_a_note(recorded_run, tmp_path, capsys, content, note):
    run = copy_run(recorded_run, tmp_path / "run")
    (run / "summary.json").write_bytes(content)
    assert cli.main(["inspect", str(run)]) == 0
    out = capsys.readouterr().out
    assert "summary.json ignored" in out and note in out
    assert "outcome: unknown" in out and "ReleaseAndStand [✓]" in out


def test_a_new_run_never_sits_beside_an_old_record(recorded_run, tmp_path, monkeypatch, capsys):
    run = copy_run(recorded_run, tmp_path / "run")
    (run / "final_scene.png").write_bytes(b"old picture")
    monkeypatch.setattr(executive_run, "run_in_simulation", FakeMission())
    assert cli.main(["run", "--mute", "--out", str(run)]) == 2
    assert "--overwrite" in capsys.readouterr().err
    assert cli.main(["run", "--mute", "--out", str(run), "--overwrite"]) == 0
    assert not (run / "final_scene.png").exists()  # the old picture went with the old record
    assert read_summary(run)["chair"] == "stub"


def test_runs_started_in_the_same_second_get_their_own_folders(tmp_path):
    from bearchair.executive.outputs import claim_new_run_dir

    folders: list[Path] = []
    barrier = threading.Barrier(8)

    def claim() -> None:
        barrier.wait()
        folders.append(claim_new_run_dir(tmp_path / "runs", "20261201-120000-seed0"))

    threads = [threading.Thread(target=claim) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(set(folders)) == 8 and all(folder.is_dir() for folder in folders)


# --- caches -----------------------------------------------------------------------------


def test_a_damaged_or_pickled_cache_entry_is_rebuilt_never_executed(tmp_path):
    from bearchair.core.meshes import read_cached_arrays, write_cached_arrays

    entry = tmp_path / "entry.npz"
    write_cached_arrays(entry, {"a": np.arange(3.0), "name": np.asarray("box")})
    stored = read_cached_arrays(entry)
    assert stored is not None and stored["a"].tolist() == [0.0, 1.0, 2.0]
    assert str(stored["name"]) == "box"

    entry.write_bytes(entry.read_bytes()[:40])  # truncated
    assert read_cached_arrays(entry) is None and not entry.exists()

    marker = tmp_path / "code-ran"

    class Payload:
        def __reduce__(self):
            return (Path.write_text, (marker, "pwned"))

    np.savez(entry, evil=np.array([Payload()], dtype=object), allow_pickle=True)
    assert read_cached_arrays(entry) is None
    assert not marker.exists() and not entry.exists()
    with pytest.raises(ValueError, match="not Python objects"):
        write_cached_arrays(entry, {"evil": np.array([Payload()], dtype=object)})


def test_the_imagination_cache_survives_a_damaged_entry(tmp_path, monkeypatch):
    from bearchair.core.meshes import box_chair_mesh
    from bearchair.skills.imagination import chair_solid as imagination_chair

    monkeypatch.setenv("BEARCHAIR_CACHE", str(tmp_path))
    # The memory starts empty: the runtime is reset before every test (conftest.py).
    mesh = box_chair_mesh()
    first = imagination_chair.prepare_chair(mesh)
    entries = list((tmp_path / "imagination").glob("*.npz"))
    assert len(entries) == 1 and not list((tmp_path / "imagination").glob("*.pkl"))
    entries[0].write_bytes(b"garbage")
    RUNTIME.reset()  # forget the prepared chair: read it from the cache
    again = imagination_chair.prepare_chair(mesh)
    assert again.mass_kg == pytest.approx(first.mass_kg)
    assert np.allclose(again.T_obb_mesh, first.T_obb_mesh) and len(again.pieces) == len(
        first.pieces
    )
    RUNTIME.reset()  # forget the prepared chair: read it from the cache
    cached = imagination_chair.prepare_chair(mesh)  # read back from the rebuilt entry
    assert np.allclose(np.stack(cached.pieces), np.stack(first.pieces))


# --- campaign databases and processes -----------------------------------------------------


def fake_worker_command(tmp_path: Path, monkeypatch, script: str = FAKE_WORKER) -> str:
    path = tmp_path / "fake_worker.py"
    path.write_text(script)
    monkeypatch.setenv("FAKE_LOG", str(tmp_path / "fake_worker.log"))
    return f"{sys.executable} {path}"


def test_a_second_campaign_on_the_same_database_is_refused(tmp_path, capsys):
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])
    db = tmp_path / "out" / "trials.sqlite"
    with campaign_lock(db):
        status = cli.main(["trials", "--chairs", str(folder), "--out", str(tmp_path / "out")])
        err = capsys.readouterr().err.strip()
    assert status == 2 and "in use by another bearchair trials" in err
    assert len(err.splitlines()) == 1 and f"pid {os.getpid()}" in err
    with campaign_lock(db):  # released: the next one gets it
        pass


def test_a_damaged_database_is_refused_before_any_trial(tmp_path, monkeypatch, capsys):
    command = fake_worker_command(tmp_path, monkeypatch)
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])
    db = tmp_path / "t.sqlite"
    with TrialStore(db) as store:
        store._db.execute("CREATE TABLE padding (x TEXT)")
        with store._db:
            store._db.executemany(
                "INSERT INTO padding VALUES (?)", [("x" * 500,) for _ in range(200)]
            )
    data = bytearray(db.read_bytes())
    for page in (1, 2, 3, 4):  # damaged pages (their b-tree headers)
        data[4096 * page : 4096 * page + 64] = os.urandom(64)
    db.write_bytes(bytes(data))
    status = cli.main(
        ["trials", "--chairs", str(folder), "--db", str(db), "--out", str(tmp_path / "o"),
         "--worker-cmd", command]
    )  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert status == 2 and str(db) in err and len(err.splitlines()) == 1
    assert not (tmp_path / "fake_worker.log").exists()  # no trial ran


def test_a_database_that_fails_mid_campaign_keeps_the_finished_trials(
    tmp_path, monkeypatch, capsys
):
    command = fake_worker_command(tmp_path, monkeypatch)
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])
    real_add = TrialStore.add
    added: list = []

    def add(self, record):
        if len(added) == 2:  # the disk fills up at the third trial
            self._db.execute("PRAGMA query_only = ON")
        real_add(self, record)
        added.append(record)

    monkeypatch.setattr(TrialStore, "add", add)
    out = tmp_path / "out"
    status = cli.main(
        ["trials", "--chairs", str(folder), "--out", str(out), "--worker-cmd", command]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and "cannot record a.obj" in err[-1] and "summary.json" in err[-1]
    assert "Traceback" not in "\n".join(err)
    with TrialStore(out / "trials.sqlite") as store:
        assert len(store.records()) == 2  # what was committed stays


CRASH_ONCE = FAKE_WORKER.replace(
    'if chair.startswith("crash") and index == 1:',
    'first = out.parent / f"{chair}-{index}-ran"\n'
    'if chair.startswith("flaky") and not first.exists():\n'
    '    first.write_text("1"); os.kill(os.getpid(), signal.SIGKILL)\n'
    'if chair.startswith("crash") and index == 1:',
)


@pytest.mark.slow
def test_a_killed_worker_is_retried_once_and_marked(tmp_path, monkeypatch):
    from bearchair.evaluation.campaign import run_campaign
    from bearchair.evaluation.protocol import ChairEntry, expand_protocol
    from bearchair.evaluation.trial_backends import LocalBackend

    command = fake_worker_command(tmp_path, monkeypatch, CRASH_ONCE).split()
    chairs = [ChairEntry(tmp_path / name, "chair", 90.0) for name in ("flaky.obj", "crash.obj")]
    specs = expand_protocol(chairs, "paper", 0)
    with TrialStore(tmp_path / "t.sqlite") as store:
        run_campaign(specs, store, LocalBackend(2, 30, command), tmp_path / "runs", 30)
        records = {(r.chair, r.trial_index): r for r in store.records()}
    flaky = [r for (chair, _), r in records.items() if chair == "flaky.obj"]
    assert all(r.attempts == 2 and r.error is None for r in flaky)  # retried, then fine
    crashed = records[("crash.obj", 1)]
    assert crashed.attempts == 2 and "retried once" in crashed.error
    assert "SIGSEGV" in crashed.error
    assert records[("crash.obj", 0)].attempts == 1


@pytest.mark.slow
def test_a_sigkilled_campaign_resumes_to_the_same_table_with_no_orphan(tmp_path, monkeypatch):
    command = fake_worker_command(tmp_path, monkeypatch)
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])

    def campaign(out: Path) -> list[str]:
        return [
            sys.executable, "-m", "bearchair.executive.cli", "trials", "--chairs", str(folder),
            "--out", str(out), "--seed", "4", "--workers", "2", "--worker-cmd", command,
        ]  # fmt: skip

    env = {**os.environ, "FAKE_SLEEP_S": "0"}
    straight = subprocess.run(
        campaign(tmp_path / "straight"), cwd=REPO, env=env, capture_output=True
    )
    assert straight.returncode == 0, straight.stderr

    (tmp_path / "fake_worker.log").unlink()
    out = tmp_path / "killed"
    env["FAKE_SLEEP_S"] = "0.6"
    harness = subprocess.Popen(campaign(out), cwd=REPO, env=env, stderr=subprocess.PIPE)
    db = out / "trials.sqlite"
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            rows = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
        except sqlite3.Error:
            rows = 0
        if rows >= 2:
            break
        time.sleep(0.05)
    harness.kill()
    harness.wait(timeout=10)
    time.sleep(0.5)
    assert not [pid for pid in worker_pids(tmp_path) if process_alive(pid)]  # none orphaned
    kept = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
    assert 2 <= kept < 6

    env["FAKE_SLEEP_S"] = "0"
    resumed = subprocess.run(campaign(out), cwd=REPO, env=env, capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    with TrialStore(db) as store, TrialStore(tmp_path / "straight" / "trials.sqlite") as other:
        assert len(store.records()) == 6
        assert table_without_timing(store.records()) == table_without_timing(other.records())
        run_dirs = {Path(r.run_dir) for r in store.records()}
    # Every run folder on disk belongs to a recorded trial: the killed ones were redone.
    on_disk = {p for p in (out / "runs").glob("*/*") if p.is_dir()}
    assert on_disk == run_dirs
    assert all((run_dir / "summary.json").is_file() for run_dir in run_dirs)


@pytest.mark.slow
def test_a_closed_stderr_does_not_stop_a_campaign(tmp_path, monkeypatch):
    command = fake_worker_command(tmp_path, monkeypatch)
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])
    out = tmp_path / "out"
    shell = (
        f"{sys.executable} -m bearchair.executive.cli trials --chairs {folder} --out {out} "
        f"--worker-cmd '{command}' 2>&1 >/dev/null | head -c 1 >/dev/null"
    )
    done = subprocess.run(["bash", "-c", shell], cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0
    assert (out / "report.md").is_file()
    with TrialStore(out / "trials.sqlite") as store:
        assert len(store.records()) == 6


# --- meshes: the up-axis check over the calibration chairs ----------------------------


@pytest.mark.slow
def test_up_axis_warnings_over_the_calibration_meshes(shared_chairs, shared_manifest):
    from bearchair.core.meshes import check_chair_mesh, load_mesh

    turned_up = trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0])
    upright_warned, turned_warned, on_its_side, turned = [], 0, 0, 0
    for entry in shared_manifest:
        mesh = load_mesh(shared_chairs / entry["file"])
        if check_chair_mesh(mesh, entry["file"]):  # whatever its kind
            upright_warned.append(entry["file"])
        if entry["kind"] == "table":
            continue
        mesh.apply_transform(turned_up)  # as a y-up file read as z-up
        turned += 1
        warnings = check_chair_mesh(mesh)
        turned_warned += bool(warnings)
        on_its_side += any("on its side" in w for w in warnings)
    assert upright_warned == []
    assert turned_warned >= 0.9 * turned
    assert on_its_side >= 0.75 * turned
