"""Table 1's second part, "chair accessible after human assistance", from records made
of mission summaries where it differs from the seating outcome: a chair made accessible
whose bear then fell, a trial never assisted, a refused instruction."""

from __future__ import annotations

from pathlib import Path

from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.report import compute_table, format_table, markdown_report
from bearchair.evaluation.store import record_from_summary
from bearchair.executive.records.run_summary import RunSummary


def _summary(outcome: str, instructions: int, accessible: bool) -> dict:
    """A mission's summary.json, as much as a record reads of it."""
    return {
        "outcome": outcome,
        "failed_stage": None if outcome == "success" else "SeatBear",
        "reason": "" if outcome == "success" else "SeatBear: bear not seated",
        "instructions": [f"rotate {n}" for n in range(instructions)],
        "rotations": instructions,
        "accessible": accessible,
        "interrupted": False,
        "stages": [],
        "judgement": {"seated": outcome == "success"},
        "wall_seconds": 50.0,
    }


def _record(experiment: str, index: int, outcome: str, instructions: int, accessible: bool):
    helper = "disobeys" if experiment.endswith("disobeys") else "obeys"
    placement = "accessible" if experiment == "accessible" else "inaccessible"
    spec = TrialSpec("c.obj", Path("c.obj"), index, experiment, placement, helper, index)
    summary = RunSummary.from_json(_summary(outcome, instructions, accessible))
    return record_from_summary(spec, summary, 60.0, None)


def test_accessible_after_assistance_is_counted_from_the_records_not_from_seating():
    records = [
        # Obeys: made accessible, then the bear fell; made accessible and seated;
        # assisted but still inaccessible (GiveUp); never assisted (no instruction).
        _record("inaccessible_obeys", 0, "failure", 1, True),
        _record("inaccessible_obeys", 1, "success", 1, True),
        _record("inaccessible_obeys", 2, "failure", 3, False),
        _record("inaccessible_obeys", 3, "failure", 0, False),
        # Disobeys: two instructions and accessible, the bear fell twice over.
        _record("inaccessible_disobeys", 4, "failure", 2, True),
        _record("inaccessible_disobeys", 5, "failure", 2, True),
        # An accessible placement judged accessible at once: not in part (2).
        _record("accessible", 6, "success", 0, True),
    ]
    table = compute_table(records)
    assert [(r.label, r.n, r.count) for r in table.assistance] == [
        ("Obeys", 3, 2),  # the unassisted trial is not counted; seating would say 1
        ("Disobeys", 2, 2),  # seating would say 0
        ("Total", 5, 4),
    ]
    assert [(r.label, r.n, r.count) for r in table.seating][1:3] == [
        ("Inaccessible + Human Obeys", 4, 1),
        ("Inaccessible + Human Disobeys", 2, 0),
    ]
    lines = format_table(table).splitlines()
    part_2 = lines[lines.index("(2) Chair accessible after human assistance") :]
    disobeys = next(line for line in part_2 if line.startswith("Disobeys"))
    assert disobeys.split()[1:] == ["2", "2", "100.0%"]  # not seating's 0.0%


def test_an_accessible_placement_that_was_assisted_is_named_apart():
    records = [
        _record("accessible", 0, "success", 1, True),
        _record("accessible", 1, "success", 0, True),
    ]
    table = compute_table(records)
    assert table.assisted_accessible_trials == 1
    assert [r.n for r in table.assistance] == [0, 0, 0]


def test_each_trial_row_says_accessible_after_assistance_only_where_it_was_assisted():
    """The report's row per trial: "yes"/"no" from the record's own column where an
    instruction was given, blank where none was (not the final accessibility, nor seating)."""
    records = [
        _record("inaccessible_obeys", 0, "failure", 1, True),  # made accessible, bear fell
        _record("inaccessible_obeys", 1, "failure", 3, False),
        _record("inaccessible_obeys", 2, "failure", 0, False),  # never assisted
        _record("accessible", 3, "success", 0, True),  # accessible at once
    ]
    markdown = markdown_report(compute_table(records), records)
    header = next(line for line in markdown.splitlines() if line.startswith("| Chair |"))
    column = [cell.strip() for cell in header.split("|")].index("Accessible after")
    rows = [line for line in markdown.splitlines() if line.startswith("| c.obj |")]
    assert [[cell.strip() for cell in row.split("|")][column] for row in rows] == [
        "yes",
        "no",
        "",
        "",
    ]
