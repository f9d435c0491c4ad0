"""The campaign's records: one SQLite row per finished trial, committed at once.

A row is written only when a trial has finished (with a summary, a crash or a
timeout), in one transaction, so an interrupted harness loses no finished trial and
never keeps half a trial. The key (chair, placement, helper, trial index, seed) makes a
rerun skip what is already there.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import logging
import os
import sqlite3
import stat
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from bearchair.core.errors import RecordStoreError
from bearchair.core.provenance import software_versions
from bearchair.core.userfiles import parse_json, printable
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.executive.records.run_summary import RunSummary

logger = logging.getLogger(__name__)

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
    # Ground truth the simulated world alone knows (GROUND_TRUTH_COLUMNS): how deep the NAO
    # went into the chair, and how far apart its palms held the bear.
    "nao_into_chair_cm": "REAL",
    "nao_into_chair_link": "TEXT",
    "nao_into_chair_stage": "TEXT",
    "palms_apart_handed_over_cm": "REAL",
    "palms_apart_max_cm": "REAL",
    "palms_apart_stage": "TEXT",
}
GROUND_TRUTH_COLUMNS = (
    "nao_into_chair_cm",
    "nao_into_chair_link",
    "nao_into_chair_stage",
    "palms_apart_handed_over_cm",
    "palms_apart_max_cm",
    "palms_apart_stage",
)
"""The columns copied from the run's ``ground_truth`` (its fields of the same names); a
campaign recorded before they existed leaves them empty."""
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

    def add(self, record: TrialRecord) -> None:
        """Writes (or replaces) one trial's row and commits it."""
        row = record.to_row()
        names = list(COLUMNS)
        values = [_to_sql(row[name]) for name in names]
        try:
            with self._db:  # one transaction, committed on exit
                self._db.execute(
                    f"INSERT OR REPLACE INTO trials ({', '.join(names)}) "
                    f"VALUES ({', '.join('?' for _ in names)})",
                    values,
                )
        except sqlite3.Error as error:
            raise RecordStoreError(
                f"database {self.path}: cannot record {record.chair} "
                f"#{record.trial_index} ({_sqlite_reason(error)}); its run folder "
                f"{record.run_dir} keeps the trial's summary.json"
            ) from error

    def records(self, specs: list[TrialSpec] | None = None) -> list[TrialRecord]:
        """Every row as a record, ordered by chair and trial index.

        Args:
            specs: keep only the rows of these trials (the current campaign), if given.
        """
        rows = self._db.execute("SELECT rowid, * FROM trials ORDER BY chair, trial_index, seed")
        records = [_from_row(row, self.path) for row in rows]
        if specs is not None:
            wanted = {spec.key for spec in specs}
            records = [r for r in records if r.key in wanted]
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
    lock_path = Path(f"{Path(db_path).resolve()}.lock")  # one lock per database, however named
    try:
        lock_path.parent.mkdir(parents=True, exist_ok=True)
        descriptor = os.open(
            lock_path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK, 0o666
        )
    except OSError as error:
        reason = (
            "it is a symbolic link (bearchair does not write through one): remove it"
            if error.errno == errno.ELOOP
            else error.strerror or str(error)
        )
        raise RecordStoreError(f"cannot make the lock file {lock_path}: {reason}") from error
    stream = os.fdopen(descriptor, "r+")
    try:
        if not stat.S_ISREG(os.fstat(descriptor).st_mode):
            raise RecordStoreError(
                f"the lock file {lock_path} is not a regular file (a pipe or a device): remove it"
            )
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = printable(stream.read(80).strip() or "another process")
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


def _from_row(row: sqlite3.Row, db_path: Path) -> TrialRecord:
    """A stored row as a record, its JSON columns decoded; a damaged one is left out with
    one warning naming the database and the row (the trial's other columns still count)."""
    record = dict(row)
    record.pop("rowid", None)
    for name in ("stage_seconds", "sitting_pose", "software"):
        if record.get(name):
            try:
                record[name] = parse_json(str(record[name]), name, RecordStoreError)
            except RecordStoreError as error:
                logger.warning(
                    "database %s: row %s (%s #%s): %s; left out",
                    db_path,
                    row["rowid"],
                    printable(record.get("chair"), 80),
                    printable(record.get("trial_index"), 20),
                    printable(error, 120),
                )
                record[name] = None
    return TrialRecord.from_row(record)


def record_from_summary(
    spec: TrialSpec,
    summary: RunSummary,
    wall_seconds: float,
    run_dir: str | None,
    attempts: int = 1,
) -> TrialRecord:
    """A row from a finished mission's ``summary.json``
    (:mod:`bearchair.executive.records.run_summary`)."""
    judgement = summary.judgement
    truth = summary.ground_truth
    ground_truth: dict[str, Any] = {
        name: None if truth is None else getattr(truth, name) for name in GROUND_TRUTH_COLUMNS
    }
    instructions = len(summary.instructions)
    return TrialRecord(
        **_spec_columns(spec),
        outcome="success" if summary.succeeded else "failure",
        failed_stage=summary.failed_stage,
        reason=summary.reason,
        rotations=summary.rotations,
        instructions=instructions,
        accessible_final=summary.accessible,
        accessible_after_assistance=summary.accessible if instructions > 0 else None,
        stage_seconds={
            stage.name: stage.seconds for stage in summary.stages if stage.status != "INVALID"
        },
        seated=None if judgement is None else judgement.seated,
        on_seat=None if judgement is None else judgement.on_seat,
        torso_tilt_deg=None if judgement is None else judgement.torso_tilt_deg,
        facing_error_deg=None if judgement is None else judgement.facing_error_deg,
        judgement_reason=None if judgement is None else judgement.reason,
        sitting_pose=summary.sitting_pose,
        mission_seconds=summary.wall_seconds,
        wall_seconds=round(wall_seconds, 3),
        error="the mission was interrupted inside the worker" if summary.interrupted else None,
        attempts=attempts,
        run_dir=run_dir,
        finished_at=_now(),
        software=summary.software or software_versions(),
        **ground_truth,
    )


def record_from_error(
    spec: TrialSpec, error: str, wall_seconds: float, run_dir: str | None, attempts: int = 1
) -> TrialRecord:
    """A row for a trial that crashed, hung or could not start: a failure with its error."""
    return TrialRecord(
        **_spec_columns(spec),
        outcome="failure",
        reason=error,
        wall_seconds=round(wall_seconds, 3),
        error=error,
        attempts=attempts,
        run_dir=run_dir,
        finished_at=_now(),
        software=software_versions(),  # the harness's: the worker left no summary
    )


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


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")
