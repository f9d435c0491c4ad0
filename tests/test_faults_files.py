"""Faults of the places the project writes and reads back, each with what must survive
(issue 32, files and inputs): planted symbolic links, a run folder another run still
writes, a full device behind stdout, no inodes, the umask, a cache that cannot be
written, no display, a damaged stored row, a worker result of the wrong shape, a record
that hides escape sequences, an operator who is not at a terminal.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import sqlite3
import stat
import subprocess
import sys

import numpy as np
import pytest

from bearchair.core.errors import OutputError
from bearchair.evaluation.store import TrialStore, campaign_lock
from bearchair.executive import cli, operator, outputs
from bearchair.executive.records.run_record import RecordWriteError, RunRecorder
from bearchair.executive.records.run_summary import RunSummary
from bearchair.trees.mission import create_tree
from tests.helpers.campaigns import FAKE_WORKER, write_chairs
from tests.helpers.cli_calls import refused
from tests.helpers.missions import FakeMission, one_tick_record
from tests.helpers.process_tree import REPO

# --- the campaign's lock, runs folder and records -----------------------------------------


@pytest.fixture
def campaign(tmp_path, monkeypatch):
    """A one-chair campaign with the fake worker: (argv, out folder)."""
    script = tmp_path / "fake_worker.py"
    script.write_text(FAKE_WORKER)
    monkeypatch.setenv("FAKE_LOG", str(tmp_path / "fake_worker.log"))
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])
    out = tmp_path / "out"
    argv = ["trials", "--chairs", str(folder), "--out", str(out), "--no-record"]
    return [*argv, "--worker-cmd", f"{sys.executable} {script}"], out


def test_a_planted_lock_link_is_refused_and_its_target_kept(campaign, tmp_path, capsys):
    argv, out = campaign
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    out.mkdir()
    (out / "trials.sqlite.lock").symlink_to(victim)
    line = refused(argv, capsys)
    assert "lock file" in line and "symbolic link" in line
    assert victim.read_text() == "precious\n"


def test_two_campaigns_on_one_database_through_a_link_the_second_is_refused(
    campaign, tmp_path, capsys
):
    argv, out = campaign
    out.mkdir()
    real = out / "trials.sqlite"
    link = tmp_path / "alias.sqlite"
    link.symlink_to(real)
    with campaign_lock(real):
        line = refused([*argv, "--db", str(link)], capsys)
    assert "in use by another bearchair trials" in line
    assert not real.exists()  # the second campaign wrote nothing


def test_a_chairs_run_folder_linked_out_of_out_is_refused_and_nothing_outside_deleted(
    campaign, tmp_path, capsys
):
    argv, out = campaign
    outside = tmp_path / "elsewhere"
    (outside / "t0-accessible_obeys-seed1").mkdir(parents=True)
    keep = outside / "t0-accessible_obeys-seed1" / "keep.txt"
    keep.write_text("mine\n")
    (out / "runs").mkdir(parents=True)
    (out / "runs" / "a").symlink_to(outside)
    line = refused(argv, capsys)
    assert "symbolic link" in line and "inside --out" in line
    assert keep.read_text() == "mine\n" and sorted(p.name for p in outside.iterdir()) == [
        "t0-accessible_obeys-seed1"
    ]


def test_a_damaged_stored_row_is_named_and_the_campaign_finishes(campaign, capsys, caplog):
    argv, out = campaign
    assert cli.main(argv) == 0
    capsys.readouterr()
    with sqlite3.connect(out / "trials.sqlite") as db:
        db.execute("UPDATE trials SET stage_seconds = '{not json' WHERE trial_index = 2")
    assert cli.main(argv) == 0  # resumes: everything recorded, the report written again
    damaged = [r.getMessage() for r in caplog.records if "left out" in r.getMessage()]
    assert len(damaged) == 1 and "trials.sqlite: row" in damaged[0] and "a.obj #2" in damaged[0]
    assert (out / "report.md").is_file()
    with TrialStore(out / "trials.sqlite") as store:
        assert len(store.records()) == 6


def test_a_worker_summary_of_the_wrong_shape_fails_that_trial_only(campaign, tmp_path, capsys):
    argv, out = campaign
    script = tmp_path / "fake_worker.py"
    script.write_text(
        FAKE_WORKER.replace(
            '"stages": stages,', '"stages": "all of them" if index == 3 else stages,'
        )
    )
    assert cli.main(argv) == 0
    with TrialStore(out / "trials.sqlite") as store:
        records = {r.trial_index: r for r in store.records()}
    assert len(records) == 6
    assert "the worker's summary is malformed" in records[3].error
    assert all(records[i].error is None for i in (0, 1, 2, 4, 5))


def test_chair_names_in_the_report_are_escaped(campaign, tmp_path, capsys):
    argv, out = campaign
    name = "x|<img src=q onerror=alert(1)>].obj"
    folder = write_chairs(tmp_path / "odd", [name])
    argv = [*argv]
    argv[argv.index("--chairs") + 1] = str(folder)
    assert cli.main(argv) == 0
    report = (out / "report.md").read_text()
    assert "<img" not in report and "&lt;img src=q onerror=alert(1)&gt;" in report
    rows = [line for line in report.splitlines() if "onerror" in line and line.startswith("| ")]
    assert rows and all(row.count(" | ") == 10 for row in rows)  # no cell split by the |


# --- run folders ---------------------------------------------------------------------------


def test_overwrite_of_a_folder_another_run_writes_is_refused(tmp_path, capsys):
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "summary.json").write_text("{}")
    script = (
        "import sys, time; from pathlib import Path\n"
        "from bearchair.executive.outputs import lock_run_dir\n"
        "lock_run_dir(Path(sys.argv[1])); print('locked', flush=True); time.sleep(30)\n"
    )
    other = subprocess.Popen(
        [sys.executable, "-c", script, str(folder)], cwd=REPO, stdout=subprocess.PIPE, text=True
    )
    try:
        assert other.stdout.readline().strip() == "locked"
        line = refused(["run", "--mute", "--out", str(folder), "--overwrite"], capsys)
    finally:
        other.kill()
        other.wait()
    assert "being written by another bearchair run" in line
    assert (folder / "summary.json").read_text() == "{}"


def test_a_finished_run_releases_its_folder_for_the_next_overwrite(tmp_path, monkeypatch, capsys):
    from bearchair.executive import run as executive_run

    monkeypatch.setattr(executive_run, "run_in_simulation", FakeMission())
    out = tmp_path / "run"
    assert cli.main(["run", "--mute", "--out", str(out)]) == 0
    assert outputs._held_locks == {}
    assert cli.main(["run", "--mute", "--out", str(out), "--overwrite"]) == 0
    assert (out / "summary.json").is_file() and "Traceback" not in capsys.readouterr().err


def test_overwrite_accepts_the_projects_own_records_and_removes_links_as_links(tmp_path):
    folder = tmp_path / "run"
    folder.mkdir()
    for name in ("mission.rrd", "cell.json", "summary.json", "worker.stdout"):
        (folder / name).write_text("old")
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "keep.png").write_text("mine")
    (folder / "snapshots").symlink_to(outside, target_is_directory=True)
    assert outputs.prepare_run_dir(folder, overwrite=True) == folder
    assert [p.name for p in folder.iterdir() if not p.name.startswith(".")] == []
    assert (outside / "keep.png").read_text() == "mine"


def test_too_few_inodes_is_refused_before_the_run(tmp_path, capsys, monkeypatch):
    real = os.statvfs

    def few_inodes(path):
        got = real(path)
        fields = list(got)
        fields[7] = 6  # f_favail
        return os.statvfs_result(fields)

    monkeypatch.setattr(os, "statvfs", few_inodes)
    line = refused(["run", "--mute", "--out", str(tmp_path / "run")], capsys)
    assert "only 6 files can still be created" in line


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_records_are_written_with_the_umasks_modes(tmp_path, monkeypatch, umask, mode):
    monkeypatch.setattr(outputs, "current_umask", lambda: umask)
    path = outputs.write_text_atomic(tmp_path / "summary.json", "{}")
    assert stat.S_IMODE(path.stat().st_mode) == mode


def test_a_planted_ticks_link_is_not_followed(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    run = tmp_path / "run"
    run.mkdir()
    (run / "ticks.jsonl").symlink_to(victim)
    with pytest.raises(RecordWriteError):
        RunRecorder(run, create_tree())
    assert victim.read_text() == "precious\n"


def test_gui_without_a_display_is_one_line_before_anything_is_written(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    line = refused(["run", "--gui", "--out", str(tmp_path / "run")], capsys)
    assert "--gui needs a display" in line and not (tmp_path / "run").exists()


# --- the cache -----------------------------------------------------------------------------


@pytest.mark.parametrize("setting", ["", "under-a-file"])
def test_an_unusable_cache_warns_once_and_never_writes_into_the_current_folder(
    tmp_path, monkeypatch, caplog, setting
):
    from bearchair.core import cache

    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    value = "" if setting == "" else str(blocker / "cache")
    monkeypatch.setenv("BEARCHAIR_CACHE", value)
    monkeypatch.setattr(cache, "_cache_dirs", {})
    monkeypatch.chdir(tmp_path)
    first, second = cache.cache_dir(), cache.cache_dir()
    assert first == second and first.is_dir() and tmp_path not in first.parents
    cache.write_cached_arrays(first / "x.npz", {"a": np.zeros(3)})
    assert cache.read_cached_arrays(first / "x.npz")["a"].shape == (3,)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file"]
    assert sum("no cache" in r.message for r in caplog.records) == 1


# --- standard output lost ------------------------------------------------------------------


@contextlib.contextmanager
def stdout_on_a_full_device():
    """sys.stdout on /dev/full for the block (set inside the test: pytest's capture
    replaces sys.stdout again when the test body starts)."""
    saved = sys.stdout
    full = open("/dev/full", "w")  # noqa: SIM115 - closed below
    sys.stdout = full
    try:
        yield
    finally:
        sys.stdout = saved
        with contextlib.suppress(OSError):
            full.close()


def test_tree_on_a_full_device_is_exit_2_with_one_line(capsys):
    with stdout_on_a_full_device():
        status = cli.main(["tree", "--format", "ascii"])
    assert status == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line.startswith("bearchair: cannot write to standard output (no space left")


def test_inspect_on_a_full_device_is_exit_2_with_one_line(tmp_path, capsys):
    one_tick_record(tmp_path / "run")
    with stdout_on_a_full_device():
        status = cli.main(["inspect", str(tmp_path / "run")])
    assert status == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "the output is lost" in line


def test_imagine_json_on_a_full_device_is_exit_2_with_one_line(tmp_path, capsys, monkeypatch):
    import types

    import bearchair.skills.imagination as imagination
    from bearchair.core.meshes import box_chair_mesh

    not_found = types.SimpleNamespace(
        found=False,
        sitting_pose=None,
        n_correct=0,
        n_drops=24,
        seconds={"total": 1.0},
        vote=None,
        backrest=None,
        reason="no drop sat",
    )
    monkeypatch.setattr(imagination, "imagine_sitting", lambda mesh, **kw: not_found)
    path = tmp_path / "chair.obj"
    box_chair_mesh().export(path)
    with stdout_on_a_full_device():
        status = cli.main(["imagine", str(path), "--json", "--workers", "1"])
    assert status == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "cannot write to standard output" in line


@pytest.mark.slow
def test_the_console_to_dev_full_exits_2(tmp_path):
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [sys.executable, "-m", "bearchair.executive.cli", "tree", "--format", "ascii"],
            cwd=REPO,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
        )
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "bearchair: cannot write to standard output (no space left on the device); "
        "the output is lost"
    ]


@pytest.mark.slow
def test_a_reader_that_goes_away_is_not_an_error():
    shell = f"{sys.executable} -m bearchair.executive.cli tree --format ascii | head -c 1"
    done = subprocess.run(["bash", "-c", shell], cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == ""


# --- the operator ----------------------------------------------------------------------------


class _Stdin(io.StringIO):
    def __init__(self, text: str, tty: bool) -> None:
        super().__init__(text)
        self._tty = tty

    def isatty(self) -> bool:
        return self._tty


def test_a_piped_yes_is_not_the_operators_yes(monkeypatch):
    asked = []
    monkeypatch.setattr(sys, "stdin", _Stdin("y\n", tty=False))
    monkeypatch.setattr("builtins.input", lambda prompt: asked.append(prompt) or "y")
    assert operator.ask_operator("Go on? ") is False and asked == []
    assert "pass --yes" in operator.not_asked_because()


def test_run_on_robots_with_a_piped_yes_moves_nothing(tmp_path, capsys, monkeypatch):
    pytest.importorskip("qi")  # the NAO stand-in speaks qi
    from bearchair.hardware.real.standins import NaoqiStandin
    from tests.helpers.cells import standin_cell_file

    monkeypatch.setattr(sys, "stdin", _Stdin("y\n", tty=False))
    monkeypatch.setattr("builtins.input", lambda prompt: "y")
    with NaoqiStandin(time_scale=20.0) as naoqi:
        cell = standin_cell_file(tmp_path, naoqi.url)
        line = refused(["run", "--robots", str(cell), "--out", str(tmp_path / "run")], capsys)
        assert not naoqi.called("wakeUp") and not naoqi.called("moveTo")
    assert "did not confirm: nothing moved" in line and "pass --yes" in line


@pytest.mark.parametrize("stdin", ["closed", "none", "eof"])
def test_a_closed_or_ended_stdin_is_no(monkeypatch, stdin):
    monkeypatch.setattr(operator, "is_terminal", lambda stream: stream is not None)
    if stdin == "closed":
        stream = _Stdin("", tty=True)
        stream.close()
        monkeypatch.setattr(sys, "stdin", stream)
        monkeypatch.setattr(operator, "is_terminal", lambda s: True)
        monkeypatch.setattr("builtins.input", lambda prompt: (_ for _ in ()).throw(ValueError()))
    elif stdin == "none":
        monkeypatch.setattr(sys, "stdin", None)
        monkeypatch.setattr(operator, "is_terminal", lambda s: True)
        monkeypatch.setattr(
            "builtins.input", lambda prompt: (_ for _ in ()).throw(RuntimeError("lost sys.stdin"))
        )
    else:
        monkeypatch.setattr(operator, "is_terminal", lambda s: True)
        monkeypatch.setattr("builtins.input", lambda prompt: (_ for _ in ()).throw(EOFError()))
    assert operator.ask_operator("Go on? ") is False


def test_is_terminal_of_a_closed_stream_is_false():
    stream = io.StringIO()
    stream.close()
    assert operator.is_terminal(stream) is False and operator.is_terminal(None) is False


# --- seeds and replaced chairs ---------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("seed", [2**31, 2**32 - 1])
def test_a_seed_above_open3ds_range_works(seed):
    from bearchair.skills.perception.reconstruction import fit_floor, open3d_seed
    from bearchair.skills.perception.reconstruction_config import ReconstructionConfig

    assert 0 <= open3d_seed(seed) < 2**31 and open3d_seed(seed) == open3d_seed(seed)
    rng = np.random.default_rng(0)
    floor = np.column_stack([rng.uniform(-1, 1, (3000, 2)), rng.normal(0, 0.002, 3000)])
    plane = fit_floor(floor, ReconstructionConfig(seed=seed))
    assert abs(plane[2]) > 0.99


def test_a_chair_replaced_after_the_check_is_a_named_failure_of_the_trial(tmp_path, capsys):
    from bearchair.evaluation import worker

    payload = {
        "chair_path": str(tmp_path / "gone.obj"),
        "placement": "accessible",
        "helper": "obeys",
        "seed": 1,
        "trial_index": 0,
        "out_dir": str(tmp_path / "run"),
        "timeout_s": 60,
    }
    assert worker.main([json.dumps(payload)]) == 3
    result = [line for line in capsys.readouterr().out.splitlines() if "RESULT" in line]
    message = json.loads(result[-1].split(" ", 1)[1])["error"]
    assert "gone.obj: no such file" in message


def test_an_out_that_is_a_dangling_link_is_refused(tmp_path, capsys):
    (tmp_path / "run").symlink_to(tmp_path / "nowhere")
    with pytest.raises(OutputError, match="symbolic link to nothing"):
        outputs.prepare_run_dir(tmp_path / "run")


def test_the_run_summary_prints_a_hostile_chair_name_escaped():
    from bearchair.executive.run import format_summary

    summary = {
        "chair": "\x1b]0;owned\x07chair.obj",
        "placement": "accessible",
        "helper": "obeys",
        "seed": 0,
        "stages": [
            {
                "name": "ScanChair",
                "status": "FAILURE",
                "seconds": 1.0,
                "message": "no chair\n[  ok] forged",
            }
        ],
        "instructions": [],
        "outcome": "failure",
        "failed_stage": "ScanChair",
        "reason": "\x1b[2J",
    }
    text = format_summary(RunSummary.from_json(summary))
    assert "\x1b" not in text and "\x07" not in text
    assert not any(line.startswith("[  ok] forged") for line in text.splitlines())
