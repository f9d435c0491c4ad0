"""A campaign: run every unfinished trial, record each one as soon as it ends.

The records (SQLite) are the single source of truth: the table and the report are
computed from them, so a campaign interrupted and resumed gives the same table as one
run straight through with the same seed.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

from bearchair.evaluation.backends import Backend, Job
from bearchair.evaluation.progress import Progress
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.store import TrialStore, record_from_error, record_from_summary
from bearchair.evaluation.worker_process import WorkerOutcome
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
    on_record: Callable[[dict[str, Any]], None] | None = None,
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
        if run_dir.exists():  # left by an interrupted run: start clean
            shutil.rmtree(run_dir)
        payload = spec.to_payload(
            run_dir, timeout_s, record=record, imagination_workers=imagination_workers
        )
        if tree != "mission":  # the shipped tree's payload is as it always was
            payload["tree"] = tree
        jobs.append((spec, payload))
    return jobs


def _row(spec: TrialSpec, outcome: WorkerOutcome, run_dir: str) -> dict[str, Any]:
    """The record of a finished trial: from its summary, else from its error."""
    if outcome.summary is not None:
        return record_from_summary(
            spec, outcome.summary, outcome.wall_seconds, run_dir, outcome.attempts
        )
    return record_from_error(
        spec,
        outcome.error or "unknown error",
        outcome.wall_seconds,
        run_dir,
        outcome.attempts,
    )
