"""``inspect`` of a record that hides traps: it stays read-only (its crash log goes
elsewhere), prints escape sequences escaped, skips hostile tick lines and names them,
and does not wait on a FIFO (issue 32, files and inputs)."""

from __future__ import annotations

import json
import os

import pytest

from bearchair.executive import cli
from bearchair.executive.records.run_record import RunRecorder
from bearchair.trees.mission import create_tree
from tests.helpers.cli_calls import refused
from tests.helpers.missions import one_tick_record

# --- inspect: read-only, escaped ------------------------------------------------------------


def test_inspect_writes_its_crash_log_outside_the_record(tmp_path, capsys, monkeypatch):
    from bearchair.executive.records import replay

    run = tmp_path / "run"
    one_tick_record(run)
    before = sorted(p.name for p in run.iterdir())
    monkeypatch.setenv("BEARCHAIR_CACHE", str(tmp_path / "cache"))

    def broken(self, tick):
        raise RuntimeError("a bug")

    monkeypatch.setattr(replay.RecordedRun, "tree_text", broken)
    assert cli.main(["inspect", str(run)]) == 3
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "internal error" in line and str(run) not in line.split("the traceback is in ")[1]
    assert sorted(p.name for p in run.iterdir()) == before


def test_inspect_prints_escape_sequences_of_a_record_escaped(tmp_path, capsys):
    run = tmp_path / "run"
    recorder = RunRecorder(run, create_tree())
    recorder.close()
    shape = json.loads((run / "tree.json").read_text())
    shape[0]["name"] = "\x1b]0;owned\x07Mission\x1b[2J"
    (run / "tree.json").write_text(json.dumps(shape))
    tick = {
        "tick": 1,
        "t": 0.0,
        "nodes": [
            {"path": shape[0]["path"], "status": "RUNNING", "feedback": "line one\n[  ok] forged"}
        ],
        "blackboard": {"\x1bkey": "\x1b[31mred"},
    }
    (run / "ticks.jsonl").write_text(json.dumps(tick) + "\n")
    assert cli.main(["inspect", str(run), "--blackboard", "--timeline"]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\\x1b" in out
    assert not any(line.startswith("[  ok] forged") for line in out.splitlines())


@pytest.mark.parametrize("content", ["[" * 100_000, '{"tick": ' + "9" * 401 + "}"])
def test_a_hostile_tick_line_is_skipped_and_named(tmp_path, capsys, content):
    run = tmp_path / "run"
    one_tick_record(run)
    good = (run / "ticks.jsonl").read_text()
    (run / "ticks.jsonl").write_text(content + "\n" + good)
    assert cli.main(["inspect", str(run)]) == 0
    assert "unreadable line(s) of ticks.jsonl skipped (line 1)" in capsys.readouterr().out


def test_a_summary_that_is_a_fifo_is_noted_not_waited_for(tmp_path, capsys):
    run = tmp_path / "run"
    one_tick_record(run)
    os.mkfifo(run / "summary.json")
    assert cli.main(["inspect", str(run)]) == 0
    assert "summary.json ignored" in capsys.readouterr().out


def test_a_deep_tree_json_is_one_line(tmp_path, capsys):
    run = tmp_path / "run"
    one_tick_record(run)
    (run / "tree.json").write_text("[" * 100_000 + "]" * 100_000)
    line = refused(["inspect", str(run)], capsys)
    assert "tree.json: not valid JSON (nested too deeply)" in line


@pytest.mark.parametrize(
    ("content", "said"),
    [("a = " + "[" * 100_000 + "]" * 100_000, "nested too deeply"), (None, "not a regular file")],
    ids=["deep-toml", "fifo"],
)
def test_a_hostile_mission_configuration_is_one_line(tmp_path, capsys, content, said):
    path = tmp_path / "mission.toml"
    if content is None:
        os.mkfifo(path)
    else:
        path.write_text(content)
    line = refused(["run", "--config", str(path), "--out", str(tmp_path / "run")], capsys)
    assert said in line and not (tmp_path / "run").exists()
