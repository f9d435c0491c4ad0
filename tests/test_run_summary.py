"""The run summary as typed records (executive/records/run_summary.py): written as it is read,
records of the previous version still read, a value of the wrong type refused by name,
and each typed view the same JSON as the result it records."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.core.errors import RunRecordError
from bearchair.core.geometry import SittingPose
from bearchair.executive.records.jsonable import to_jsonable
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import (
    SCHEMA_VERSION,
    JudgementRecord,
    ReleaseRecord,
    RunInfo,
    RunSummary,
    SittingPoseRecord,
)
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.hardware.interfaces import SeatingJudgement
from bearchair.skills.imagination.release import ImaginedRelease, ReleasePrediction
from bearchair.testing.scripted import ScriptedSkills
from bearchair.trees.mission import create_tree

VERSION_1 = {
    # A summary.json as the version before the schema key wrote it (trimmed).
    "chair": "a.obj",
    "placement": "inaccessible",
    "helper": "obeys",
    "seed": 7,
    "backend": "sim",
    "tree": "mission",
    "started_at": "2026-12-01T10:00:00+0000",
    "outcome": "failure",
    "failed_stage": "SeatBear",
    "reason": "SeatBear: bear not seated",
    "interrupted": False,
    "wall_seconds": 88.25,
    "ticks": 1201,
    "stages": [
        {
            "name": "ScanChair",
            "status": "SUCCESS",
            "seconds": 9.5,
            "robot_seconds": 12.0,
            "message": "17 views",
        },
        {"name": "SeatBear", "status": "FAILURE", "seconds": 30.0, "message": "fell"},
    ],
    "sitting_pose": {"position_m": [0.8, 0.1, 0.31], "yaw_deg": -90.0},
    "se2_goal": {"x": 1.25, "y": -0.5, "theta": math.pi / 2},
    "instructions": ["Please turn the chair"],
    "rotations": 1,
    "measured_rotations": [{"yaw_deg": 44.0, "fitness": 0.9}],
    "accessible": True,
    "walk": {"reached": True, "seconds": 20.0},
    "judgement": {
        "seated": False,
        "on_seat": True,
        "torso_tilt_deg": 51.0,
        "facing_error_deg": "nan",
        "reason": "tilted",
        "T_world_bear": None,
    },
    "release_prediction": None,
    "failures": ["SeatBear: fell"],
    "picture": "final_scene.png",
    "ground_truth": {
        "sitting_yaw_deg": -88.0,
        "sitting_yaw_error_deg": 2.0,
        "nao_into_chair_cm": 0.0,
        "nao_into_chair_link": "",
    },
    "software": {"bearchair": "0.9.0"},
}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> tuple[RunSummary, dict]:
    """A mission with scripted skills: its summary in memory and as written."""
    out = tmp_path_factory.mktemp("run")
    root = create_tree()
    recorder = RunRecorder(out, root)
    runner = MissionRunner(
        root,
        ScriptedSkills(),
        fake_robot(judge=FakeJudge()),
        seed=2,
        arena=DEFAULT_ARENA,
        recorder=recorder,
        tick_period_s=0.002,
    )
    summary = summarise(runner.run(), RunInfo(chair="stub", seed=2, backend="sim"))
    recorder.write_summary(summary)
    recorder.close()
    return summary, json.loads((out / "summary.json").read_text())


def test_the_written_summary_reads_back_as_the_summary_that_was_written(recorded):
    summary, written = recorded
    assert written["schema"] == SCHEMA_VERSION and written["software"]["bearchair"]
    read = RunSummary.from_json(written)
    assert dataclasses.replace(read, software=None) == summary
    assert read.to_json() == written
    assert read.succeeded and read.info.chair == "stub" and read.info.seed == 2
    assert read.stage("SeatBear") is not None and read.stage("NoSuchStage") is None
    # The run's info stays the first keys of the file, not an object of its own.
    assert list(written)[:3] == ["schema", "chair", "placement"] and "info" not in written


def test_every_stage_that_ran_is_written_with_its_start_on_the_robot_s_clock(recorded):
    # The ground truth names the stage in which the NAO went into the chair from it.
    summary, written = recorded
    ran = [stage for stage in summary.stages if stage.status != "INVALID"]
    assert ran and all(stage.robot_started_s is not None for stage in ran)
    assert [stage["robot_started_s"] for stage in written["stages"]] == [
        stage.robot_started_s for stage in summary.stages
    ]


def test_a_record_of_the_previous_version_reads_with_its_goal_in_units(recorded):
    summary = RunSummary.from_json(VERSION_1)
    assert summary.se2_goal == {"x_m": 1.25, "y_m": -0.5, "theta_deg": 90.0}
    assert summary.info.placement == "inaccessible" and summary.info.cell_file is None
    assert summary.stages[1].robot_seconds is None and summary.stages[1].message == "fell"
    assert summary.judgement is not None and math.isnan(summary.judgement.facing_error_deg or 0)
    assert summary.sitting_pose == SittingPoseRecord((0.8, 0.1, 0.31), -90.0)
    assert summary.ground_truth is not None and summary.ground_truth.sitting_yaw_error_deg == 2.0
    assert summary.failures == ("SeatBear: fell",) and summary.software == {"bearchair": "0.9.0"}
    rewritten = summary.to_json()
    assert (
        rewritten["schema"] == SCHEMA_VERSION
        and rewritten["judgement"]["facing_error_deg"] == "nan"
    )
    assert RunSummary.from_json(rewritten).se2_goal == summary.se2_goal


def test_a_partial_record_takes_the_defaults_and_ignores_keys_it_does_not_know():
    summary = RunSummary.from_json({"outcome": "success", "someone_elses": 1})
    assert summary == RunSummary(outcome="success")
    assert "signal" not in summary.to_json() and "picture" not in summary.to_json()


@pytest.mark.parametrize(
    ("change", "named"),
    [
        ({"outcome": "fine"}, "RunSummary.outcome"),
        ({"seed": True}, "RunInfo.seed"),
        ({"ticks": 1.5}, "RunSummary.ticks"),
        ({"stages": "all of them"}, "RunSummary.stages"),
        ({"stages": [{"status": "SUCCESS"}]}, "StageRecord: no 'name'"),
        ({"judgement": {"seated": "yes"}}, "JudgementRecord.seated"),
        ({"instructions": ["turn", 3]}, "RunSummary.instructions[1]"),
        ({"se2_goal": {"x": "far", "y": 0, "theta": 0}}, "se2_goal"),
    ],
)
def test_a_value_of_the_wrong_type_is_refused_naming_its_field(change, named):
    with pytest.raises(RunRecordError, match=named.replace("[", r"\[")):
        RunSummary.from_json({**VERSION_1, **change})


def test_a_summary_without_an_outcome_or_not_an_object_is_refused():
    with pytest.raises(RunRecordError, match="no 'outcome'"):
        RunSummary.from_json({"chair": "a.obj"})
    with pytest.raises(RunRecordError, match="not a JSON object"):
        RunSummary.from_json([1, 2])  # pyright: ignore[reportArgumentType]


def _judgement() -> SeatingJudgement:
    T = np.eye(4)
    T[:3, 3] = (0.8, 0.1, 0.33)
    return SeatingJudgement(True, True, 4.5, 12.25, "", T)


def test_each_typed_view_is_the_json_of_the_result_it_records():
    # A key added to one of these results and not to its record fails here, not silently.
    pose = SittingPose(np.array([0.8, 0.1, 0.31]), math.radians(-90.0))
    assert SittingPoseRecord.from_json(pose.to_json()).to_json() == pose.to_json()
    judgement = to_jsonable(_judgement())
    assert JudgementRecord.from_json(judgement).to_json() == judgement
    release = ReleasePrediction(
        stays=True,
        releases=(ImaginedRelease("planned", _judgement()),),
        T_world_bear_release=np.eye(4),
        seconds=1.5,
        seat_patched=False,
        cpu_seconds=1.25,
    )
    view = to_jsonable(release)
    assert ReleaseRecord.from_json(view).to_json() == view


def test_a_view_that_is_not_its_record_is_left_out_of_the_summary_with_a_warning(caplog):
    from bearchair.executive import runner

    assert runner._view_record(JudgementRecord, "a plug-in's verdict") is None
    assert "leaves out str" in caplog.text
