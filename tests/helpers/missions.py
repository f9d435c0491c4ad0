"""Missions on fakes (a fake robot, scripted skills, no physics): behind the real CLI
(``FakeMission``), straight through the runner (``run_scripted_mission``), and the
smallest run record (``one_tick_record``)."""

from __future__ import annotations

from pathlib import Path

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.executive import run as executive_run
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import RunInfo, RunSummary
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.testing.scripted import ScriptedSkills
from bearchair.trees.mission import create_tree


class FakeMission:
    """Stands in for ``bearchair.executive.run.run_in_simulation``: the real tree, runner and
    record on a fake robot, with scripted skills (no physics)."""

    def __init__(self, delays_s: dict[str, float] | None = None, on_tick=None) -> None:
        self.robot = fake_robot(judge=FakeJudge())
        self.skills = ScriptedSkills(delays_s=delays_s or {})
        self.on_tick = on_tick

    def __call__(self, config, skills=None, on_tick=None, tree=None):
        root = (tree or create_tree)(config.tree_options)
        recorder = RunRecorder(config.out_dir, root)
        run_info = RunInfo(chair="stub", placement="accessible", helper="obeys", seed=0)
        return executive_run._run_tree(
            root, recorder, self.robot, config, run_info, self.skills, self.on_tick, None
        )


def run_scripted_mission(
    skills: ScriptedSkills, out_dir=None, robot=None
) -> tuple[RunSummary, MissionRunner]:
    """The mission tree ticked to its end on ``skills`` and a fake robot (seed 3); the
    summary is written to a run record in ``out_dir`` when one is given."""
    root = create_tree()
    recorder = RunRecorder(out_dir, root) if out_dir else None
    runner = MissionRunner(
        root,
        skills,
        robot or fake_robot(judge=FakeJudge()),
        seed=3,
        arena=DEFAULT_ARENA,
        recorder=recorder,
        tick_period_s=0.002,
        timeout_s=60,
    )
    outcome = runner.run()
    summary = summarise(outcome, RunInfo(chair="stub"))
    if recorder:
        recorder.write_summary(summary)
        recorder.close()
    return summary, runner


def one_tick_record(run: Path) -> Path:
    """A run record of the mission tree with one tick."""
    recorder = RunRecorder(run, create_tree())
    recorder.record_tick(1, 0.0)
    recorder.close()
    return run
