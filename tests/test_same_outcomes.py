"""bench/same_outcomes.py: two campaigns compared trial by trial, the ground truth a
campaign recorded before its columns existed left out of the comparison."""

from __future__ import annotations

import dataclasses
import importlib.util
from pathlib import Path

from bearchair.evaluation.protocol import ChairEntry, expand_protocol
from bearchair.evaluation.store import GROUND_TRUTH_COLUMNS, TrialStore, record_from_summary
from bearchair.executive.records.run_summary import RunSummary

_SPEC = importlib.util.spec_from_file_location(
    "same_outcomes", Path(__file__).resolve().parents[1] / "bench" / "same_outcomes.py"
)
assert _SPEC is not None and _SPEC.loader is not None
same_outcomes = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(same_outcomes)


def _campaign(path: Path, outcome: str, touch_cm: float | None) -> Path:
    (spec,) = expand_protocol([ChairEntry(path.parent / "c.obj", "chair", 90.0)])[:1]
    truth = None if touch_cm is None else {"nao_into_chair_cm": touch_cm}
    summary = RunSummary.from_json({"outcome": outcome, "stages": [], "ground_truth": truth})
    record = record_from_summary(spec, summary, 30.0, None)
    if touch_cm is None:  # a campaign recorded before the ground-truth columns
        record = dataclasses.replace(record, **dict.fromkeys(GROUND_TRUTH_COLUMNS, None))
    with TrialStore(path) as store:
        store.add(record)
    return path


def test_a_column_one_campaign_never_had_is_not_a_difference(tmp_path, capsys):
    old = _campaign(tmp_path / "old.sqlite", "success", None)
    new = _campaign(tmp_path / "new.sqlite", "success", 2.5)
    assert same_outcomes.main([str(old), str(new)]) == 0
    assert "1/1 trials the same" in capsys.readouterr().out


def test_a_different_outcome_or_measurement_is(tmp_path, capsys):
    first = _campaign(tmp_path / "a.sqlite", "success", 2.5)
    assert (
        same_outcomes.main([str(first), str(_campaign(tmp_path / "b.sqlite", "failure", 2.5))]) == 1
    )
    assert (
        same_outcomes.main([str(first), str(_campaign(tmp_path / "c.sqlite", "success", 4.0))]) == 1
    )
    assert "nao_into_chair_cm: 2.5 -> 4.0" in capsys.readouterr().out
