"""The ``bearchair`` command line: rendering, inspecting, and clear one-line errors."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.executive.cli import main
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import RunInfo
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.testing.scripted import ScriptedSkills
from bearchair.trees.mission import STAGES, create_tree


def test_tree_unicode_shows_every_stage(capsys):
    assert main(["tree", "--format", "unicode"]) == 0
    out = capsys.readouterr().out
    for stage in STAGES:
        assert stage in out


def test_tree_blackboard_lists_keys_and_users(capsys):
    assert main(["tree", "--format", "ascii", "--blackboard"]) == 0
    out = capsys.readouterr().out
    assert "/sitting/pose" in out and "ImagineOnScan (W)" in out


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz not installed")
def test_tree_svg_is_written(tmp_path, capsys):
    out = tmp_path / "mission.svg"
    assert main(["tree", "--format", "svg", "--out", str(out)]) == 0
    svg = out.read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    for stage in STAGES:
        assert stage in svg


@pytest.mark.slow
def test_py_trees_render_can_build_the_tree_offline(tmp_path):
    # The design card: the tree renders through py-trees-render with no hardware.
    render = shutil.which(
        "py-trees-render", path=str(__import__("pathlib").Path(sys.executable).parent)
    )
    if render is None:
        pytest.skip("py-trees-render not installed")
    done = subprocess.run(
        [render, "bearchair.trees.mission.create_tree"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert list(tmp_path.glob("*.dot"))


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["run", "--placement", "sideways"], "invalid choice"),
        (["run", "--seed", "abc"], "invalid int"),
        (["tree", "--format", "gif"], "invalid choice"),
        (["fly"], "invalid choice"),
        (["run", "--chair", "/no/such/chair.obj"], "no such file"),
        (["inspect", "/no/such/run"], "not a run record"),
    ],
)
def test_bad_arguments_give_one_clear_line(argv, expected, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert expected in err
    assert len(err.splitlines()) == 1
    assert "Traceback" not in err


def test_run_rejects_an_empty_mesh_file(tmp_path, capsys):
    empty = tmp_path / "chair.obj"
    empty.write_text("")
    assert main(["run", "--chair", str(empty), "--mute"]) == 2
    assert "empty file" in capsys.readouterr().err


def test_inspect_replays_a_recorded_run(tmp_path, capsys):
    root = create_tree()
    recorder = RunRecorder(tmp_path, root)
    runner = MissionRunner(
        root,
        ScriptedSkills(delays_s={"scan_chair": 0.05}),
        fake_robot(judge=FakeJudge()),
        seed=1,
        arena=DEFAULT_ARENA,
        recorder=recorder,
        tick_period_s=0.002,
    )
    recorder.write_summary(summarise(runner.run(), RunInfo(chair="stub")))
    recorder.close()

    assert main(["inspect", str(tmp_path), "--timeline", "--blackboard"]) == 0
    out = capsys.readouterr().out
    assert "ReleaseAndStand [✓]" in out
    assert "outcome: success" in out
    assert "/sitting/pose" in out
    assert "ScanChair" in out and "RUNNING -> SUCCESS" in out

    assert main(["inspect", str(tmp_path), "--tick", "1"]) == 0
    first = capsys.readouterr().out
    assert "ScanChair [*]" in first and "ReleaseAndStand [-]" in first

    assert main(["inspect", str(tmp_path), "--tick", "99999"]) == 2
    assert "outside the run" in capsys.readouterr().err


def test_stage_snapshots_picture_each_stage_end_once(tmp_path) -> None:
    from collections import namedtuple
    from types import SimpleNamespace

    from bearchair.executive.tick_watchers import StageSnapshots

    Stage = namedtuple("Stage", "name status")
    calls: list[tuple[str, str]] = []

    def render(path, view: str, stage: str, status: str, reason: str) -> None:
        assert path.name.startswith(f"{stage}-{status.lower()}", 3) and isinstance(reason, str)
        calls.append((path.name, view))
        path.write_bytes(b"png")

    snapshots = StageSnapshots(render, tmp_path / "snapshots")
    runner = SimpleNamespace(
        stages=[Stage("ScanChair", "RUNNING"), Stage("ImagineSitting", "INVALID")]
    )
    snapshots(runner)
    assert calls == []
    runner.stages = [Stage("ScanChair", "SUCCESS"), Stage("ImagineSitting", "RUNNING")]
    snapshots(runner)
    snapshots(runner)
    assert calls == [
        ("01-ScanChair-success.png", "perspective"),
        ("01-ScanChair-success-top.png", "top"),
    ]
    runner.stages = [Stage("ScanChair", "SUCCESS"), Stage("ImagineSitting", "FAILURE")]
    snapshots(runner)
    assert calls[-1] == ("02-ImagineSitting-failure-top.png", "top")
    assert [p.name for p in snapshots.written] == [name for name, _ in calls]
    assert all(p.exists() for p in snapshots.written)

    def broken(path, view: str, **caption) -> None:
        raise RuntimeError("no renderer")

    quiet = StageSnapshots(broken, tmp_path / "broken")
    quiet(runner)  # logged, never raised: a missing picture must not stop the mission
    assert quiet.written == []


def register_hello(subparsers) -> None:
    """A command of a package above executive, as an entry point names one."""
    hello = subparsers.add_parser("hello", help="say hello")
    hello.set_defaults(func=lambda args: print("hello") or 0)


def _registered(monkeypatch, **commands: str) -> None:
    """Makes the installed metadata hold these commands (name = "module:function")."""
    from importlib import metadata

    from bearchair.executive.cli import COMMANDS_GROUP

    found = metadata.EntryPoints(
        metadata.EntryPoint(name, value, COMMANDS_GROUP) for name, value in commands.items()
    )

    def entry_points(**selection):
        assert selection == {"group": COMMANDS_GROUP}
        return found

    monkeypatch.setattr(metadata, "entry_points", entry_points)


def test_commands_of_other_packages_come_from_their_entry_points(monkeypatch, capsys):
    _registered(monkeypatch, hello="tests.test_cli:register_hello")
    assert main(["hello"]) == 0
    assert capsys.readouterr().out == "hello\n"
    _registered(monkeypatch)
    assert main(["hello"]) == 2
    assert "invalid choice: 'hello'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("value", "why"),
    [
        ("no_such_package.cli:register", "No module named 'no_such_package'"),
        ("tests.test_cli:no_such_function", "no_such_function"),
    ],
)
def test_a_registered_command_that_cannot_be_loaded_is_one_line(monkeypatch, capsys, value, why):
    _registered(monkeypatch, hello="tests.test_cli:register_hello", broken=value)
    assert main(["hello"]) == 2  # not a silently missing command
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert f"the 'broken' command ({value}) cannot be loaded" in err and why in err
    assert "reinstall bearchair" in err


def test_pyproject_registers_the_trials_command_of_evaluation():
    import argparse
    import tomllib
    from importlib import metadata
    from pathlib import Path

    from bearchair.executive.cli import COMMANDS_GROUP

    pyproject = Path(__file__).resolve().parents[1] / "pyproject.toml"
    declared = tomllib.loads(pyproject.read_text())["project"]["entry-points"][COMMANDS_GROUP]
    assert declared == {"trials": "bearchair.evaluation.cmd_trials:register"}
    subparsers = argparse.ArgumentParser().add_subparsers()
    metadata.EntryPoint("trials", declared["trials"], COMMANDS_GROUP).load()(subparsers)
    assert list(subparsers.choices) == ["trials"]
