"""The campaign's records: one SQLite row per finished trial, committed at once.

A row is written only when a trial has finished (with a summary, a crash or a
timeout), in one transaction, so an interrupted harness loses no finished trial and
never keeps half a trial. The key (chair, placement, helper, trial index, seed) makes a
rerun skip what is already there.
"""

from __future__ import annotations

import json
import sqlite3
import time
from pathlib import Path
from typing import Any

from executive.trials.protocol import TrialSpec

COLUMNS: dict[str, str] = {
    "chair": "TEXT NOT NULL",
    "placement": "TEXT NOT NULL",
    "helper": "TEXT NOT NULL",
    "trial_index": "INTEGER NOT NULL",
    "seed": "INTEGER NOT NULL",
    "experiment": "TEXT NOT NULL",
    "chair_path": "TEXT",
    "outcome": "TEXT NOT NULL",  # success | failure
    "failed_stage": "TEXT",
    "reason": "TEXT",
    "rotations": "INTEGER",  # rotations asked of the helper
    "instructions": "INTEGER",  # sentences said
    "accessible_final": "INTEGER",  # the last accessibility check said accessible (0/1)
    "accessible_after_assistance": "INTEGER",  # as above, only when an instruction was given
    "stage_seconds": "TEXT",  # JSON {stage name: seconds} of the stages that ran
    "seated": "INTEGER",
    "on_seat": "INTEGER",
    "torso_tilt_deg": "REAL",
    "facing_error_deg": "REAL",
    "judgement_reason": "TEXT",
    "sitting_pose": "TEXT",  # JSON {position_m, yaw_deg}, world frame at the end of the trial
    "mission_seconds": "REAL",  # the mission's own wall time (summary wall_seconds)
    "wall_seconds": "REAL",  # the whole trial subprocess, world building included
    "error": "TEXT",  # crash / timeout / worker error; NULL when the mission ran to its end
    "run_dir": "TEXT",
    "finished_at": "TEXT",
}
KEY_COLUMNS = ("chair", "placement", "helper", "trial_index", "seed")


class TrialStore:
    """The SQLite file of a campaign. Use from one thread (the harness's main thread).

    Args:
        path: the database file; created with its folder if missing.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._db = sqlite3.connect(self.path)
        self._db.row_factory = sqlite3.Row
        columns = ",\n  ".join(f"{name} {kind}" for name, kind in COLUMNS.items())
        with self._db:
            self._db.execute(
                f"CREATE TABLE IF NOT EXISTS trials (\n  {columns},\n"
                f"  PRIMARY KEY ({', '.join(KEY_COLUMNS)}))"
            )

    def close(self) -> None:
        self._db.close()

    def __enter__(self) -> TrialStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def finished_keys(self) -> set[tuple[str, str, str, int, int]]:
        """The keys of every recorded trial."""
        rows = self._db.execute(f"SELECT {', '.join(KEY_COLUMNS)} FROM trials")
        return {tuple(row) for row in rows}  # type: ignore[misc]

    def add(self, record: dict[str, Any]) -> None:
        """Writes (or replaces) one trial's row and commits it."""
        unknown = set(record) - set(COLUMNS)
        if unknown:
            raise ValueError(f"unknown record fields: {sorted(unknown)}")
        names = list(COLUMNS)
        values = [_to_sql(record.get(name)) for name in names]
        with self._db:  # one transaction, committed on exit
            self._db.execute(
                f"INSERT OR REPLACE INTO trials ({', '.join(names)}) "
                f"VALUES ({', '.join('?' for _ in names)})",
                values,
            )

    def records(self, specs: list[TrialSpec] | None = None) -> list[dict[str, Any]]:
        """Every row as a dict (JSON columns decoded), ordered by chair and trial index.

        Args:
            specs: keep only the rows of these trials (the current campaign), if given.
        """
        rows = self._db.execute("SELECT * FROM trials ORDER BY chair, trial_index, seed")
        records = [_from_row(row) for row in rows]
        if specs is not None:
            wanted = {spec.key for spec in specs}
            records = [r for r in records if tuple(r[k] for k in KEY_COLUMNS) in wanted]
        return records


def _to_sql(value: Any) -> Any:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, dict | list):
        return json.dumps(value, sort_keys=True)
    return value


def _from_row(row: sqlite3.Row) -> dict[str, Any]:
    record = dict(row)
    for name in ("stage_seconds", "sitting_pose"):
        if record.get(name):
            record[name] = json.loads(record[name])
    return record


def record_from_summary(
    spec: TrialSpec, summary: dict[str, Any], wall_seconds: float, run_dir: str | None
) -> dict[str, Any]:
    """A row from a finished mission's ``summary.json`` (see ``executive.mission``)."""
    judgement = summary.get("judgement") or {}
    instructions = len(summary.get("instructions") or [])
    accessible = bool(summary.get("accessible", False))
    interrupted = bool(summary.get("interrupted", False))
    return {
        **_spec_columns(spec),
        "outcome": "success" if summary.get("outcome") == "success" else "failure",
        "failed_stage": summary.get("failed_stage"),
        "reason": summary.get("reason") or "",
        "rotations": int(summary.get("rotations") or 0),
        "instructions": instructions,
        "accessible_final": accessible,
        "accessible_after_assistance": accessible if instructions > 0 else None,
        "stage_seconds": {
            stage["name"]: float(stage["seconds"])
            for stage in summary.get("stages", [])
            if stage.get("status") not in (None, "INVALID")
        },
        "seated": _optional_bool(judgement.get("seated")),
        "on_seat": _optional_bool(judgement.get("on_seat")),
        "torso_tilt_deg": _optional_float(judgement.get("torso_tilt_deg")),
        "facing_error_deg": _optional_float(judgement.get("facing_error_deg")),
        "judgement_reason": judgement.get("reason"),
        "sitting_pose": summary.get("sitting_pose"),
        "mission_seconds": _optional_float(summary.get("wall_seconds")),
        "wall_seconds": round(wall_seconds, 3),
        "error": "the mission was interrupted inside the worker" if interrupted else None,
        "run_dir": run_dir,
        "finished_at": _now(),
    }


def record_from_error(
    spec: TrialSpec, error: str, wall_seconds: float, run_dir: str | None
) -> dict[str, Any]:
    """A row for a trial that crashed, hung or could not start: a failure with its error."""
    return {
        **_spec_columns(spec),
        "outcome": "failure",
        "failed_stage": None,
        "reason": error,
        "rotations": None,
        "instructions": None,
        "accessible_final": None,
        "accessible_after_assistance": None,
        "stage_seconds": {},
        "wall_seconds": round(wall_seconds, 3),
        "error": error,
        "run_dir": run_dir,
        "finished_at": _now(),
    }


def _spec_columns(spec: TrialSpec) -> dict[str, Any]:
    return {
        "chair": spec.chair,
        "placement": spec.placement,
        "helper": spec.helper,
        "trial_index": spec.trial_index,
        "seed": spec.seed,
        "experiment": spec.experiment,
        "chair_path": str(spec.chair_path),
    }


def _optional_bool(value: Any) -> bool | None:
    return None if value is None else bool(value)


def _optional_float(value: Any) -> float | None:
    try:
        return None if value is None else float(value)
    except (TypeError, ValueError):
        return None


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")
