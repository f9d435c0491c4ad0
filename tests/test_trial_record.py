"""A trial's row as a typed record (evaluation/trial_record.py): one field per column,
written and read back through SQLite, and a row of an older database still read."""

from __future__ import annotations

import dataclasses
import sqlite3

from bearchair.evaluation.protocol import ChairEntry, expand_protocol
from bearchair.evaluation.store import COLUMNS, TrialStore, record_from_error, record_from_summary
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.executive.records.run_summary import RunSummary, SittingPoseRecord


def test_the_record_has_a_field_per_column_of_the_table():
    assert {f.name for f in dataclasses.fields(TrialRecord)} == set(COLUMNS)


def test_a_record_reads_back_from_the_database_as_it_was_added(tmp_path):
    first, second = expand_protocol([ChairEntry(tmp_path / "c.obj", "chair", 90.0)])[:2]
    summary = RunSummary.from_json(
        {
            "outcome": "failure",
            "failed_stage": "SeatBear",
            "reason": "SeatBear: fell",
            "instructions": ["turn it"],
            "accessible": True,
            "stages": [{"name": "ScanChair", "status": "SUCCESS", "seconds": 9.5}],
            "sitting_pose": {"position_m": [0.8, 0.1, 0.3], "yaw_deg": 12.5},
            "judgement": {"seated": False, "on_seat": True, "torso_tilt_deg": 40.0},
            "wall_seconds": 50.0,
        }
    )
    made = [
        record_from_summary(first, summary, 61.0, str(tmp_path / "run")),
        record_from_error(second, "worker crashed", 2.0, None),
    ]
    with TrialStore(tmp_path / "t.sqlite") as store:
        for record in made:
            store.add(record)
        read = store.records()
    assert read == made
    assert read[0].accessible_after_assistance is True and read[0].seated is False
    assert read[0].sitting_pose == SittingPoseRecord((0.8, 0.1, 0.3), 12.5)
    assert read[1].seated is None and read[1].stage_seconds == {} and not read[1].succeeded


def test_a_row_of_an_older_database_reads_its_missing_columns_as_none(tmp_path):
    db = tmp_path / "old.sqlite"
    with sqlite3.connect(db) as connection:
        connection.execute(
            "CREATE TABLE trials (chair TEXT, placement TEXT, helper TEXT, trial_index INTEGER,"
            " seed INTEGER, experiment TEXT, outcome TEXT, seated INTEGER, stage_seconds TEXT,"
            " PRIMARY KEY (chair, placement, helper, trial_index, seed))"
        )
        connection.execute(
            "INSERT INTO trials VALUES ('a.obj', 'accessible', 'obeys', 0, 3, 'accessible',"
            " 'success', 1, '{\"ScanChair\": 7.0}')"
        )
    with TrialStore(db) as store:
        (record,) = store.records()
    assert record.key == ("a.obj", "accessible", "obeys", 0, 3) and record.succeeded
    assert record.seated is True and record.stage_seconds == {"ScanChair": 7.0}
    assert record.attempts is None and record.sitting_pose is None and record.software is None


def test_a_damaged_sitting_pose_reads_as_none():
    row = {"chair": "a.obj", "placement": "accessible", "helper": "obeys", "trial_index": 0}
    row |= {"seed": 1, "experiment": "accessible", "outcome": "success"}
    assert TrialRecord.from_row({**row, "sitting_pose": {"yaw": 3}}).sitting_pose is None
    assert TrialRecord.from_row({**row, "unknown_column": 1}) == TrialRecord.from_row(row)
