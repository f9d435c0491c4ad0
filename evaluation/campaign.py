"""A campaign: run every unfinished trial, record each one as soon as it ends.

The records (SQLite) are the single source of truth: the table and the report are
computed from them, so a campaign interrupted and resumed gives the same table as one
run straight through with the same seed.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from bearchair.core.errors import OutputError, RunRecordError
from bearchair.core.userfiles import printable
from bearchair.evaluation.campaign_progress import Progress
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.store import TrialStore, record_from_error, record_from_summary
from bearchair.evaluation.trial_backends import Backend, Job
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.evaluation.worker_process import WorkerOutcome
from bearchair.executive.records.run_summary import RunSummary
from bearchair.skills.imagination import DEFAULT_WORKERS


class CampaignResult(NamedTuple):
    """How a campaign call went.

    Attributes:
        ran: trials finished (and recorded) by this call.
        already_done: trials skipped because the records already held them.
        interrupted: Ctrl-C stopped it; the unfinished trials run on the next call.
    """

    ran: int
    already_done: int
    interrupted: bool


def run_campaign(
    specs: list[TrialSpec],
    store: TrialStore,
    backend: Backend,
    runs_dir: Path,
    timeout_s: float,
    progress: Progress | None = None,
    on_record: Callable[[TrialRecord], None] | None = None,
    record: bool = False,
    imagination_workers: int = DEFAULT_WORKERS,
    tree: str = "mission",
) -> CampaignResult:
    """Runs the trials the records do not hold yet, recording each as it ends.

    Args:
        specs: the campaign's trials (``expand_protocol``).
        store: the records; each finished trial is committed at once.
        backend: where the trial subprocesses run.
        runs_dir: each trial's run record goes to ``runs_dir / spec.run_dir_name()``.
        timeout_s: per-trial wall time, given to the worker (its mission stops earlier).
        progress: the progress bar (optional).
        on_record: called after each record is committed (tests use it to interrupt).
        record: each trial writes a Rerun recording, ``mission.rrd``, in its run folder.
        imagination_workers: processes each trial's imagination drops in (1: its own).
        tree: the ``--tree`` SPEC every trial's worker runs
            (``bearchair.executive.tree_source``).

    Returns:
        What ran; ``interrupted`` when Ctrl-C stopped it (finished trials are kept).
    """
    check_runs_dir(runs_dir, specs)
    runs_dir = Path(runs_dir).resolve()  # records stay valid from any working directory
    finished = store.finished_keys()
    todo = [spec for spec in specs if spec.key not in finished]
    already_done = len(specs) - len(todo)
    jobs = _jobs(todo, runs_dir, timeout_s, record, imagination_workers, tree)
    ran = 0

    def on_result(spec: TrialSpec, outcome: WorkerOutcome) -> None:
        nonlocal ran
        if outcome.cancelled:
            return
        row = _row(spec, outcome, str(runs_dir / spec.run_dir_name()))
        store.add(row)
        ran += 1
        if progress is not None:
            progress.update(row)
        if on_record is not None:
            on_record(row)

    if progress is not None:
        progress.start()
    try:
        backend.run(jobs, on_result)
    except KeyboardInterrupt:
        return CampaignResult(ran, already_done, interrupted=True)
    finally:
        if progress is not None:
            progress.finish()
    return CampaignResult(ran, already_done, interrupted=False)


def _jobs(
    todo: list[TrialSpec],
    runs_dir: Path,
    timeout_s: float,
    record: bool,
    imagination_workers: int,
    tree: str = "mission",
) -> list[Job]:
    """Each trial with its worker payload, its run folder emptied of an interrupted run's."""
    jobs = []
    for spec in todo:
        run_dir = runs_dir / spec.run_dir_name()
        check_inside(runs_dir, run_dir)
        if run_dir.exists():  # left by an interrupted run: start clean
            shutil.rmtree(run_dir)
        payload = spec.to_payload(
            run_dir, timeout_s, record=record, imagination_workers=imagination_workers
        )
        if tree != "mission":  # the shipped tree's payload is as it always was
            payload["tree"] = tree
        jobs.append((spec, payload))
    return jobs


def check_runs_dir(runs_dir: Path, specs: list[TrialSpec]) -> None:
    """Refuses a runs folder that is a symbolic link, or holds one where a trial's run
    folder goes (see :func:`check_inside`): checked before anything is deleted or run.

    Raises:
        OutputError: one line naming the link.
    """
    if Path(runs_dir).is_symlink():
        raise OutputError(
            f"{printable(runs_dir)} is a symbolic link; bearchair writes trial records only "
            "inside --out: remove the link"
        )
    for spec in specs:
        check_inside(Path(runs_dir), Path(runs_dir) / spec.run_dir_name())


def check_inside(folder: Path, path: Path) -> None:
    """Refuses ``path`` unless every part of it below ``folder`` is a real folder or
    missing: a symbolic link there (``OUT/runs/<chair>`` pointing elsewhere) would make the
    campaign delete and write outside its ``--out``.

    Raises:
        OutputError: one line naming the link and where it points.
    """
    current = folder
    for part in path.relative_to(folder).parts:
        current = current / part
        if current.is_symlink():
            raise OutputError(
                f"{printable(current)} is a symbolic link (to {printable(os.readlink(current))}); "
                "bearchair writes trial records only inside --out: remove the link"
            )
        if current.exists() and not current.is_dir():
            raise OutputError(f"{printable(current)} is a file where a run folder goes: remove it")


def _row(spec: TrialSpec, outcome: WorkerOutcome, run_dir: str) -> TrialRecord:
    """The record of a finished trial: from its summary, else from its error. A summary
    of the wrong shape is this trial's failure, named, not the campaign's."""
    if outcome.summary is not None:
        try:
            summary = RunSummary.from_json(outcome.summary)
        except RunRecordError as error:
            reason = f"the worker's summary is malformed ({type(error).__name__}: {error})"
            return record_from_error(
                spec, printable(reason, 300), outcome.wall_seconds, run_dir, outcome.attempts
            )
        return record_from_summary(spec, summary, outcome.wall_seconds, run_dir, outcome.attempts)
    return record_from_error(
        spec,
        outcome.error or "unknown error",
        outcome.wall_seconds,
        run_dir,
        outcome.attempts,
    )
