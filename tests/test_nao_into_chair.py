"""How deep the NAO went into the chair, from the simulated world's contact to the
campaign's report: the stage it happened in, the record's columns, the report's counts."""

from __future__ import annotations

from pathlib import Path

from bearchair.evaluation.ground_truth_report import TOUCH_DEPTHS_CM, nao_into_chair
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.report import compute_table, format_table, markdown_report
from bearchair.evaluation.store import TrialStore, record_from_summary
from bearchair.executive.records.run_summary import RunSummary

STAGES = [
    {"name": "ScanChair", "status": "SUCCESS", "robot_seconds": 13.0, "robot_started_s": 0.2},
    {"name": "ImagineSitting", "status": "SUCCESS", "robot_seconds": 0.0, "robot_started_s": 13.2},
    {"name": "WalkToChair", "status": "SUCCESS", "robot_seconds": 9.0, "robot_started_s": 13.2},
    {"name": "SeatBear", "status": "SUCCESS", "robot_seconds": 4.7, "robot_started_s": 22.2},
    {"name": "ReleaseAndStand", "status": "FAILURE", "robot_seconds": 9.7, "robot_started_s": 26.9},
]


def _summary(cm: float, link: str, stage: str, stages: list | None = None) -> RunSummary:
    return RunSummary.from_json(
        {
            "outcome": "success",
            "stages": STAGES if stages is None else stages,
            "judgement": {"seated": True},
            "ground_truth": {
                "nao_into_chair_cm": cm,
                "nao_into_chair_link": link,
                "nao_into_chair_stage": stage,
            },
        }
    )


def _record(index: int, cm: float, link: str = "r_wrist", stage: str = "SeatBear"):
    spec = TrialSpec("c.obj", Path("c.obj"), index, "accessible", "accessible", "obeys", index)
    return record_from_summary(spec, _summary(cm, link, stage), 30.0, None)


def test_the_stage_at_a_time_is_the_last_to_start_at_or_before_it():
    summary = _summary(0.0, "", "")
    assert summary.stage_at(0.1) == ""  # before the first stage
    assert summary.stage_at(5.0) == "ScanChair"
    # A stage of no robot time (imagination) shares its start with the next one: the
    # later stage in the tree holds the time.
    assert summary.stage_at(13.2) == "WalkToChair"
    assert summary.stage_at(26.0) == "SeatBear"
    assert summary.stage_at(40.0) == "ReleaseAndStand"
    # A record written before the stages' start times were kept cannot say.
    old = _summary(0.0, "", "", [{"name": "ScanChair", "robot_seconds": 13.0}])
    assert old.stage_at(5.0) == ""


def test_the_record_keeps_the_ground_truth_touch_through_the_store(tmp_path):
    made = [_record(0, 7.8, "r_wrist", "SeatBear"), _record(1, 0.0, "", "")]
    with TrialStore(tmp_path / "t.sqlite") as store:
        for record in made:
            store.add(record)
        read = store.records()
    assert read == made
    assert (read[0].nao_into_chair_cm, read[0].nao_into_chair_link) == (7.8, "r_wrist")
    assert read[0].nao_into_chair_stage == "SeatBear"


def test_the_report_counts_the_touches_by_depth_and_stage_and_names_the_deepest():
    records = [
        _record(0, 0.0, "", ""),
        _record(1, 0.6, "l_wrist", "SeatBear"),
        _record(2, 2.5, "r_wrist", "SeatBear"),
        _record(3, 11.5, "l_wrist", "ReleaseAndStand"),
        _record(4, 1.5, "RForeArm", "SeatBear"),
    ]
    touches = nao_into_chair(records)
    assert touches is not None
    assert (touches.trials, touches.touched) == (5, 4)
    assert dict(touches.deeper_than) == dict(zip(TOUCH_DEPTHS_CM, (3, 2, 1), strict=True))
    assert touches.by_stage == (("SeatBear", 2), ("ReleaseAndStand", 1))
    assert [(index, cm) for _, index, cm, _, _ in touches.deepest] == [
        (3, 11.5),
        (2, 2.5),
        (4, 1.5),
        (1, 0.6),
    ]
    table = compute_table(records)
    text = format_table(table)
    assert "4 of 5 trials touched it" in text
    assert "c.obj #3 11.5 cm (l_wrist, ReleaseAndStand)" in text
    report = markdown_report(table, records)
    assert "## The NAO in the chair (ground truth)" in report
    assert "- c.obj #3: 11.5 cm, l_wrist during ReleaseAndStand" in report


def test_records_without_the_measurement_leave_the_report_without_the_section():
    spec = TrialSpec("c.obj", Path("c.obj"), 0, "accessible", "accessible", "obeys", 0)
    summary = RunSummary.from_json({"outcome": "success", "stages": []})
    records = [record_from_summary(spec, summary, 30.0, None)]
    assert nao_into_chair(records) is None
    assert "NAO in the chair" not in format_table(compute_table(records))
