"""A quiet, honest console: no C banners, no warning for what the user asked for, wall
and robot seconds each named, chairs left out by ``--max-chairs`` not called skipped."""

from __future__ import annotations

import io
import json
import logging
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import py_trees
import pytest

from bearchair.behaviours.tracking import tracked_humanoid_pose
from bearchair.core.se2 import SE2Pose
from bearchair.evaluation.cmd_trials import left_out_text
from bearchair.evaluation.protocol import SkippedChair, discover_chairs
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.executive.records.run_summary import RunSummary
from bearchair.executive.run import format_summary
from bearchair.executive.runner import StageClock, StageTiming
from bearchair.executive.tick_watchers import StageProgress, stage_seconds_text


def _run_python(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )


@pytest.mark.slow
def test_pybullet_prints_no_banner_at_import_or_connect():
    done = _run_python(
        "from bearchair.core.streams import import_pybullet_quietly\n"
        "import_pybullet_quietly()\n"
        "from bearchair.hardware.sim.bullet import LockedBullet\n"
        "LockedBullet().disconnect_once()\n"
        "print('done')\n"
    )
    # Without the silencing: "pybullet build time: ..." on stderr, "argv[0]=" on stdout.
    assert done.stdout == "done\n"
    assert done.stderr == ""


@pytest.mark.slow
def test_the_console_script_prints_no_pybullet_banner():
    done = subprocess.run(
        [sys.executable, "-m", "bearchair.executive.cli", "tree", "--format", "ascii"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "pybullet build time" not in done.stderr and done.stderr == ""
    assert done.stdout.startswith("{-} Put the bear on the chair")


class _Skills:
    def __init__(self, pose):
        self.pose = pose

    def locate_humanoid(self, arm):
        return self.pose


def test_falling_back_to_odometry_warns_only_after_walking(caplog):
    caplog.set_level(logging.INFO, logger="bearchair.behaviours.tracking")
    odometry = SE2Pose(1.0, 2.0, 0.5)
    robot = SimpleNamespace(arm=None, humanoid=SimpleNamespace(pose=lambda: odometry))
    assert tracked_humanoid_pose(_Skills(None), robot) == odometry  # pyright: ignore[reportArgumentType]
    assert [r.levelno for r in caplog.records] == [logging.INFO]
    caplog.clear()
    tracked_humanoid_pose(_Skills(None), robot, after_walking=True)  # pyright: ignore[reportArgumentType]
    assert [r.levelno for r in caplog.records] == [logging.WARNING]
    caplog.clear()
    seen = SE2Pose(0.0, 0.0, 0.0)
    assert tracked_humanoid_pose(_Skills(seen), robot, after_walking=True) == seen  # pyright: ignore[reportArgumentType]
    assert not caplog.records


def test_stages_are_timed_on_the_wall_and_on_the_robot_s_clock():
    wall, robot = [0.0], [10.0]
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[py_trees.behaviours.Success("A")]
    )
    clock = StageClock(root, lambda: wall[0], lambda: robot[0])
    tree = py_trees.trees.BehaviourTree(root)
    tree.visitors.append(clock)
    # The tick starts at wall 0 / robot 10; the leaf ends when the clocks read 2 / 17.
    original_update = root.children[0].update

    def update():
        wall[0], robot[0] = 2.0, 17.0
        return original_update()

    root.children[0].update = update
    tree.tick()
    (stage,) = clock.stages
    assert stage.seconds == pytest.approx(2.0) and stage.robot_seconds == pytest.approx(7.0)


def test_stage_lines_and_the_table_name_their_clocks():
    stage = StageTiming("WalkToChair", "SUCCESS", 1.0, 4.2, "at the goal", 0.0, 8.9)
    runner = SimpleNamespace(stages=[stage], elapsed=lambda: 4.2)
    out = io.StringIO()
    StageProgress(out)(runner)  # pyright: ignore[reportArgumentType]
    assert "WalkToChair: SUCCESS (3.2 s wall, 8.9 s robot) at the goal" in out.getvalue()
    assert stage_seconds_text(3.25, None) == "3.2 s wall"
    summary = {
        "chair": "c", "placement": "accessible", "helper": "obeys", "seed": 0,
        "stages": [{"name": "WalkToChair", "status": "SUCCESS", "seconds": 3.2,
                    "robot_seconds": 8.9, "message": "at the goal"}],
        "instructions": [], "outcome": "success", "wall_seconds": 30.0,
    }  # fmt: skip
    table = format_summary(RunSummary.from_json(summary))
    assert "wall s robot s" in table and "3.20    8.90" in table
    assert table.endswith("outcome: SUCCESS in 30.0 s wall")


def test_chairs_left_out_by_max_chairs_are_not_called_skipped(tmp_path):
    manifest = {"meshes": [{"file": f"c{i}.obj", "front_yaw_deg": 0.0} for i in range(4)]}
    manifest["meshes"].append({"file": "stool.obj", "front_yaw_deg": None, "kind": "stool"})
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    for name in ["c0.obj", "c1.obj", "c2.obj", "c3.obj", "stool.obj", "extra.obj"]:
        (tmp_path / name).write_text("v 0 0 0\n")
    chosen, skipped = discover_chairs(tmp_path, max_chairs=1)
    assert len(chosen) == 1
    text = left_out_text(skipped)
    assert "3 left out by --max-chairs" in text
    assert "1 without a front" in text and "1 not in manifest.json" in text
    assert "skipped" not in text
    assert left_out_text([]) == "no mesh left out"
    assert left_out_text([SkippedChair("x", "unusable: broken")]) == "1 skipped as unusable"


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_step_bars_draw_on_a_terminal_only():
    from bearchair.core.progress import report, showing
    from bearchair.executive.step_bars import showing_step_bars, step_bars

    assert step_bars(io.StringIO()) is None  # a captured stream: no display at all
    quiet = io.StringIO()
    with showing_step_bars(quiet):
        report("scan: views", 1, 9)
    assert quiet.getvalue() == ""
    terminal = _Terminal()
    with showing_step_bars(terminal):
        for done in range(10):
            report("scan: views", done, 9)
    drawn = terminal.getvalue()
    # tqdm redraws at most every 0.1 s, and takes the bar away when the step is done.
    assert "scan: views" in drawn and "/9 [" in drawn and drawn.endswith("\r")
    seen = []
    with showing(lambda *args: seen.append(args)):
        report("x", 1, 2)
    report("x", 2, 2)  # after the block: nobody is shown it
    assert seen == [("x", 1, 2)]


@pytest.mark.slow
def test_the_scan_and_the_imagination_report_their_steps():
    from bearchair.core.geometry import yaw_transform
    from bearchair.core.meshes import box_chair_mesh
    from bearchair.core.progress import showing
    from bearchair.skills.imagination import imagine_sitting
    from bearchair.skills.perception import scan_chair
    from bearchair.testing.synthetic_scenes import SyntheticArm, SyntheticScene

    scene = SyntheticScene(seed=3)
    scene.add_mesh(box_chair_mesh(), yaw_transform(0.6, np.array([0.58, 0.08, 0.0])))
    arm = SyntheticArm(scene)
    reports: list[tuple[str, int, int]] = []
    try:
        with showing(lambda *args: reports.append(args)):
            scan = scan_chair(arm, seed=0)
            imagination = imagine_sitting(scan.chair_mesh, seed=0, workers=1)
    finally:
        arm.close()
        scene.close()
    views = [(done, total) for what, done, total in reports if what == "scan: views"]
    assert views[0][0] == 0 and views[-1][0] == views[-1][1] >= len(scan.frames)
    assert [done for done, _ in views] == sorted(done for done, _ in views)
    drops = [(done, total) for what, done, total in reports if what == "imagination: drops"]
    assert drops and all(0 <= done <= total for done, total in drops)
    finished = sum(done for done, total in drops if done == total)
    assert finished == imagination.n_drops


def test_trials_progress_is_a_tqdm_bar_on_a_terminal():
    from bearchair.evaluation.campaign_progress import Progress

    terminal = _Terminal()
    progress = Progress(4, already_done=1, stream=terminal)
    progress.start()
    progress.update(
        TrialRecord("a.obj", "accessible", "obeys", 1, 0, "accessible", "success", wall_seconds=30)
    )
    progress.finish()
    drawn = terminal.getvalue()
    assert "trials" in drawn and "2/4" in drawn and "a.obj #1 success" in drawn
