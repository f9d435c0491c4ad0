"""The campaign's records: one SQLite row per finished trial, committed at once.

A row is written only when a trial has finished (with a summary, a crash or a
timeout), in one transaction, so an interrupted harness loses no finished trial and
never keeps half a trial. The key (chair, placement, helper, trial index, seed) makes a
rerun skip what is already there.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from bearchair.core.errors import RecordStoreError
from bearchair.core.provenance import software_versions
from bearchair.evaluation.protocol import TrialSpec

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
    "attempts": "INTEGER",  # worker runs: 2 when a crashed or killed worker was retried
    "run_dir": "TEXT",
    "finished_at": "TEXT",
    "software": "TEXT",  # JSON: bearchair's version, git commit, key dependencies' versions
}
KEY_COLUMNS = ("chair", "placement", "helper", "trial_index", "seed")


class TrialStore:
    """The SQLite file of a campaign. Use from one thread (the harness's main thread).

    Opening checks the file before any trial runs: it is a SQLite database, not
    damaged, of this schema (or an older one missing only non-key columns, which are
    added), and writable.

    Args:
        path: the database file; created with its folder if missing.

    Raises:
        RecordStoreError: one line saying what is wrong with the file.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        if self.path.is_dir():
            raise RecordStoreError(f"database {self.path}: is a folder; give a file name")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._db = sqlite3.connect(self.path)
        except (OSError, sqlite3.Error) as error:
            raise RecordStoreError(f"database {self.path}: cannot open it ({error})") from error
        self._db.row_factory = sqlite3.Row
        try:
            self._check_and_create()
        except sqlite3.Error as error:
            self._db.close()
            raise RecordStoreError(f"database {self.path}: {_sqlite_reason(error)}") from error
        except RecordStoreError:
            self._db.close()
            raise

    def _check_and_create(self) -> None:
        db = self._db
        (health,) = db.execute("PRAGMA quick_check").fetchone()
        if health != "ok":
            raise RecordStoreError(
                f"database {self.path}: damaged ({health}); move it away to start afresh, "
                "the run folders keep each trial's summary.json"
            )
        existing = [row[1] for row in db.execute("PRAGMA table_info(trials)")]
        if existing:
            missing_keys = [name for name in KEY_COLUMNS if name not in existing]
            if missing_keys:
                raise RecordStoreError(
                    f"database {self.path}: its trials table is not a bearchair campaign's "
                    f"(no {', '.join(missing_keys)}); give another --db"
                )
        columns = ",\n  ".join(f"{name} {kind}" for name, kind in COLUMNS.items())
        with db:  # also proves the file writable before any trial runs
            db.execute("BEGIN IMMEDIATE")
            db.execute(
                f"CREATE TABLE IF NOT EXISTS trials (\n  {columns},\n"
                f"  PRIMARY KEY ({', '.join(KEY_COLUMNS)}))"
            )
            for name, kind in COLUMNS.items():
                if existing and name not in existing:
                    db.execute(f"ALTER TABLE trials ADD COLUMN {name} {kind.split()[0]}")
            (version,) = db.execute("PRAGMA user_version").fetchone()
            db.execute(f"PRAGMA user_version = {int(version)}")

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
        try:
            with self._db:  # one transaction, committed on exit
                self._db.execute(
                    f"INSERT OR REPLACE INTO trials ({', '.join(names)}) "
                    f"VALUES ({', '.join('?' for _ in names)})",
                    values,
                )
        except sqlite3.Error as error:
            raise RecordStoreError(
                f"database {self.path}: cannot record {record.get('chair')} "
                f"#{record.get('trial_index')} ({_sqlite_reason(error)}); its run folder "
                f"{record.get('run_dir')} keeps the trial's summary.json"
            ) from error

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


def _sqlite_reason(error: sqlite3.Error) -> str:
    text = str(error) or type(error).__name__
    if "not a database" in text or "malformed" in text:
        return f"{text}: not a readable SQLite database; give another --db or move it away"
    if "readonly" in text:
        return f"{text}: the file or its folder is read-only; give a writable --db"
    if "locked" in text:
        return f"{text}: another process holds it"
    return text


@contextlib.contextmanager
def campaign_lock(db_path: Path) -> Iterator[None]:
    """Holds ``<db>.lock`` for a campaign: a second harness on the same records is refused.

    The lock is an ``flock`` on a file beside the database, released by the kernel
    when the process ends however it ends (a SIGKILLed harness leaves no stale lock).

    Raises:
        RecordStoreError: another process holds it.
    """
    lock_path = Path(f"{db_path}.lock")
    try:
        lock_path.parent.mkdir(parents=True, exist_ok=True)
        stream = open(lock_path, "a+")  # noqa: SIM115 - held for the whole block
    except OSError as error:
        raise RecordStoreError(
            f"cannot make the lock file {lock_path}: {error.strerror or error}"
        ) from error
    try:
        try:
            fcntl.flock(stream.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            stream.seek(0)
            holder = stream.read().strip() or "another process"
            raise RecordStoreError(
                f"database {db_path} is in use by another bearchair trials ({holder}); "
                "wait for it to finish or give another --db"
            ) from None
        stream.seek(0)
        stream.truncate()
        stream.write(f"pid {os.getpid()}")
        stream.flush()
        yield
    finally:
        stream.close()  # releases the lock


def _to_sql(value: Any) -> Any:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, dict | list):
        return json.dumps(value, sort_keys=True)
    return value


def _from_row(row: sqlite3.Row) -> dict[str, Any]:
    record = dict(row)
    for name in ("stage_seconds", "sitting_pose", "software"):
        if record.get(name):
            record[name] = json.loads(record[name])
    return record


def record_from_summary(
    spec: TrialSpec,
    summary: dict[str, Any],
    wall_seconds: float,
    run_dir: str | None,
    attempts: int = 1,
) -> dict[str, Any]:
    """A row from a finished mission's ``summary.json`` (see ``bearchair.executive.mission``)."""
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
        "attempts": attempts,
        "run_dir": run_dir,
        "finished_at": _now(),
        "software": summary.get("software") or software_versions(),
    }


def record_from_error(
    spec: TrialSpec, error: str, wall_seconds: float, run_dir: str | None, attempts: int = 1
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
        "attempts": attempts,
        "run_dir": run_dir,
        "finished_at": _now(),
        "software": software_versions(),  # the harness's: the worker left no summary
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
