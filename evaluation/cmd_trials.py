"""``bearchair trials``: the paper's evaluation protocol over a folder of chairs.

Every trial runs the whole mission in the simulated world, in its own subprocess, and
is recorded in SQLite as soon as it ends; a rerun with the same arguments resumes.
The summary (the paper's Table 1, stage medians, causes of failure) is printed and
written to ``OUT/report.md`` with ``OUT/chairs/*.png`` (imagined pose per chair) and
``OUT/trials/*.png`` (final scene per trial).
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bearchair.core.errors import InputError
from bearchair.executive.cli_types import positive_int, positive_seconds, seed_value
from bearchair.skills.imagination import DEFAULT_WORKERS

if TYPE_CHECKING:
    from bearchair.evaluation.campaign import CampaignResult
    from bearchair.evaluation.protocol import ChairEntry, SkippedChair, TrialSpec
    from bearchair.evaluation.store import TrialStore
    from bearchair.evaluation.trial_backends import Backend
    from bearchair.evaluation.trial_record import TrialRecord

DEFAULT_OUT = Path("trials")
DEFAULT_TIMEOUT_S = 300.0
MIN_TIMEOUT_S = 30.0
"""Below this a trial cannot even build its simulated world and write its record."""


def register(subparsers: Any) -> None:
    """Adds the ``trials`` subcommand to the ``bearchair`` CLI."""
    parser = subparsers.add_parser(
        "trials", help="run the paper's evaluation protocol over a folder of chairs"
    )
    parser.add_argument("--chairs", type=Path, required=True, help="folder of chair meshes")
    parser.add_argument(
        "--protocol", choices=("paper",), default="paper", help="which trials each chair gets"
    )
    parser.add_argument(
        "--workers",
        type=positive_int,
        help="trials at once (default: 1 with --backend local; the cluster's CPUs with --backend ray)",
    )
    parser.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="run trials in processes on this machine, or on a Ray cluster",
    )
    parser.add_argument("--address", help="Ray cluster address (--backend ray); default: local Ray")
    parser.add_argument("--db", type=Path, help="SQLite records (default: OUT/trials.sqlite)")
    parser.add_argument(
        "--out", type=Path, default=DEFAULT_OUT, help="output folder (default: trials)"
    )
    parser.add_argument(
        "--seed", type=seed_value, default=0, help="campaign seed (trial seeds derive from it)"
    )
    parser.add_argument(
        "--timeout",
        type=positive_seconds,
        default=DEFAULT_TIMEOUT_S,
        help=f"per-trial wall time in seconds before the trial is killed (default {DEFAULT_TIMEOUT_S:.0f})",
    )
    parser.add_argument(
        "--max-chairs", type=positive_int, help="only the first N chairs with a front"
    )
    parser.add_argument(
        "--skip-bad",
        action="store_true",
        help="run without the chairs whose mesh or manifest entry is unusable (listed)",
    )
    parser.add_argument(
        "--record",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="write a Rerun recording in each trial's run folder, mission.rrd (default: on "
        "when rerun-sdk is installed; open one with 'bearchair view RUN_DIR')",
    )
    parser.add_argument(
        "--tree",
        metavar="SPEC",
        default="mission",
        help="the tree every trial runs: mission (default), a bearchair.trees entry point, "
        "module:factory, or a BehaviorTree.CPP .xml file",
    )
    parser.add_argument(
        "--worker-cmd",
        help="run each trial with this command instead of 'python -m bearchair.evaluation.worker' "
        "(the trial's JSON is appended)",
    )
    parser.set_defaults(func=run)


def resume_command(args: argparse.Namespace) -> str:
    """The command line that resumes this campaign."""
    words = ["bearchair", "trials", "--chairs", str(args.chairs), "--protocol", args.protocol]
    words += ["--seed", str(args.seed), "--out", str(args.out), "--db", str(_db_path(args))]
    if args.workers is not None:
        words += ["--workers", str(args.workers)]
    words += ["--timeout", f"{args.timeout:g}"]
    words += ["--backend", args.backend]
    if args.address:
        words += ["--address", args.address]
    if args.max_chairs is not None:
        words += ["--max-chairs", str(args.max_chairs)]
    if getattr(args, "skip_bad", False):
        words += ["--skip-bad"]
    if args.worker_cmd:
        words += ["--worker-cmd", args.worker_cmd]
    if not getattr(args, "record", True):
        words += ["--no-record"]
    if getattr(args, "tree", "mission") != "mission":
        words += ["--tree", args.tree]
    return shlex.join(words)


def _recording_available() -> bool:
    """Recordings are on by default; without rerun-sdk the campaign runs without them."""
    from bearchair.executive.recording.mission_recording import INSTALL_HINT, rerun_available

    if rerun_available():
        return True
    print(f"bearchair trials: no recordings (mission.rrd): {INSTALL_HINT}", file=sys.stderr)
    return False


def imagination_workers(args: argparse.Namespace) -> int:
    """Processes each trial's imagination uses: on this machine, the cores left to a trial
    by the others running at once (each pool costs its processes' start-up, and more
    processes than cores only queue); on a Ray cluster, the imagination's default."""
    if args.backend == "ray":
        return DEFAULT_WORKERS
    return max(1, min(DEFAULT_WORKERS, (os.cpu_count() or 1) // (args.workers or 1)))


def _workers_text(args: argparse.Namespace) -> str:
    if args.workers is None and args.backend == "ray":
        return "trials at once: the cluster's CPUs"
    return f"{args.workers or 1} worker(s)"


def _db_path(args: argparse.Namespace) -> Path:
    return args.db or args.out / "trials.sqlite"


def run(args: argparse.Namespace) -> int:
    """Runs (or resumes) the campaign, then prints and writes the summary.

    Everything is checked before the first trial: the arguments, every chair mesh and
    manifest entry (one line per bad one; ``--skip-bad`` goes on without them), the
    output folder and the database (readable, of this schema, writable, not in use).
    """
    from bearchair.evaluation.campaign import check_runs_dir
    from bearchair.evaluation.protocol import expand_protocol
    from bearchair.evaluation.store import TrialStore, campaign_lock
    from bearchair.executive.interrupts import exit_status
    from bearchair.executive.outputs import ensure_writable_dir
    from bearchair.executive.tree_source import build_tree, load_tree_factory

    _check_arguments(args)
    build_tree(load_tree_factory(args.tree), spec=args.tree)  # a bad --tree: before any trial
    chairs, skipped = _chairs(args)
    backend = _backend(args)
    record = args.record and _recording_available()
    specs = expand_protocol(chairs, args.protocol, args.seed)
    db_path = _db_path(args)
    ensure_writable_dir(args.out, "--out")
    ensure_writable_dir(db_path.parent, "folder of --db")
    check_runs_dir(args.out / "runs", specs)  # no link out of --out, before any work
    with campaign_lock(db_path), TrialStore(db_path) as store:
        done_before = len(store.finished_keys() & {spec.key for spec in specs})
        print(
            f"{len(chairs)} chairs x {len(specs) // len(chairs)} trials = {len(specs)} trials "
            f"({done_before} already recorded in {db_path}); "
            f"{left_out_text(skipped)}; backend {args.backend}, {_workers_text(args)}",
            file=sys.stderr,
        )
        result = _run_campaign(args, specs, store, backend, done_before, record)
        records = store.records(specs)
    if result.interrupted:
        print(
            f"bearchair trials: interrupted; {len(records)} of {len(specs)} trials are recorded in "
            f"{db_path} (none lost). Resume with:\n  {resume_command(args)}",
            file=sys.stderr,
        )
        return exit_status()
    # The report goes to its file first: a closed stdout must not lose it.
    table_text = write_report(args, records, skipped, chairs)
    print(f"report: {args.out / 'report.md'}", file=sys.stderr)
    print(table_text)
    return 0


def left_out_text(skipped: list[SkippedChair]) -> str:
    """The meshes not in the campaign, counted by why: those asked to be left out
    (``--max-chairs``), those that cannot take part (no front, not in the manifest) and
    those skipped as unusable (``--skip-bad``); "no mesh left out" when none."""
    counts: dict[str, int] = {}
    for chair in skipped:
        if chair.reason.startswith("beyond --max-chairs"):
            why = "left out by --max-chairs"
        elif chair.reason.startswith("unusable: "):
            why = "skipped as unusable"
        elif chair.reason == "not in manifest.json":
            why = "not in manifest.json"
        else:
            why = "without a front"
        counts[why] = counts.get(why, 0) + 1
    if not counts:
        return "no mesh left out"
    return ", ".join(f"{count} {why}" for why, count in counts.items())


def _check_arguments(args: argparse.Namespace) -> None:
    """What argparse cannot check alone: the timeout's floor, --address without Ray."""
    if args.timeout < MIN_TIMEOUT_S:
        raise InputError(
            f"bearchair trials: --timeout {args.timeout:g} s leaves a trial no time to build "
            f"its world and write its record; give at least {MIN_TIMEOUT_S:.0f} s"
        )
    if args.address and args.backend != "ray":
        raise InputError("bearchair trials: --address only applies to --backend ray")


def _chairs(args: argparse.Namespace) -> tuple[list[ChairEntry], list[SkippedChair]]:
    """The campaign's chairs and the skipped meshes; one stderr line per bad chair."""
    from bearchair.core.errors import ChairSetError
    from bearchair.evaluation.protocol import BadChairsError, discover_chairs

    try:
        chairs, skipped = discover_chairs(
            args.chairs, args.max_chairs, check_meshes=True, skip_bad=args.skip_bad
        )
    except BadChairsError as error:
        for problem in error.problems[:-1]:
            print(f"bearchair trials: {problem}", file=sys.stderr)
        raise InputError(
            f"bearchair trials: {error.problems[-1]} ({len(error.problems)} unusable; fix "
            "them, or pass --skip-bad to run without them)"
        ) from error
    except ChairSetError as error:
        raise InputError(f"bearchair trials: {error}") from error
    for chair in skipped:
        if chair.reason.startswith("unusable: "):
            print(f"bearchair trials: skipped {chair.name}: {chair.reason}", file=sys.stderr)
    return chairs, skipped


def _backend(args: argparse.Namespace) -> Backend:
    """The backend of ``--backend``, with ``--worker-cmd`` if given."""
    from bearchair.core.errors import BackendUnavailable
    from bearchair.evaluation.trial_backends import LocalBackend, RayBackend

    command = shlex.split(args.worker_cmd) if args.worker_cmd else None
    try:
        if args.backend == "ray":
            return RayBackend(args.workers, args.timeout, args.address, command=command)
        return LocalBackend(args.workers or 1, args.timeout, command)
    except BackendUnavailable as error:
        raise InputError(f"bearchair trials: {error}") from error


def _run_campaign(
    args: argparse.Namespace,
    specs: list[TrialSpec],
    store: TrialStore,
    backend: Backend,
    done_before: int,
    record: bool,
) -> CampaignResult:
    """``run_campaign`` with a progress bar; a backend that fails to start is one line."""
    from bearchair.core.errors import BackendUnavailable
    from bearchair.evaluation.campaign import run_campaign
    from bearchair.evaluation.campaign_progress import Progress

    try:
        connect = getattr(backend, "connect", None)
        if connect is not None:  # before the progress bar: Ray's start-up is not a trial
            print(f"bearchair trials: {connect()}", file=sys.stderr)
        progress = Progress(len(specs), done_before)
        return run_campaign(
            specs,
            store,
            backend,
            args.out / "runs",
            args.timeout,
            progress=progress,
            record=record,
            imagination_workers=imagination_workers(args),
            tree=args.tree,
        )
    except BackendUnavailable as error:
        raise InputError(f"bearchair trials: {error}") from error


def write_report(
    args: argparse.Namespace,
    records: list[TrialRecord],
    skipped: list[SkippedChair],
    chairs: list[ChairEntry] | None = None,
) -> str:
    """Writes OUT/report.md and the pictures; returns the table as text."""
    from bearchair.evaluation.pictures import copy_trial_scenes, render_chair_pictures
    from bearchair.evaluation.report import compute_table, format_table, markdown_report
    from bearchair.executive.outputs import write_text_atomic

    table = compute_table(records)
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        copy_trial_scenes(records, args.out / "trials")
    except OSError as error:  # nor must a missing copy
        print(f"bearchair trials: could not copy the trial pictures: {error}", file=sys.stderr)
    try:
        chair_pictures = render_chair_pictures(records, args.out / "chairs")
    except Exception as error:  # a picture must never lose the report
        print(f"bearchair trials: could not draw the imagined poses: {error}", file=sys.stderr)
        chair_pictures = {}
    settings = {
        "chairs": str(args.chairs),
        "protocol": args.protocol,
        "seed": args.seed,
        "trials": len(records),
        "backend": args.backend,
        "per-trial timeout": f"{args.timeout:g} s",
    }
    markdown = markdown_report(
        table,
        records,
        skipped,
        title="bearchair trials",
        settings=settings,
        chair_pictures={c: str(p.relative_to(args.out)) for c, p in chair_pictures.items()},
        seat_heights_m={c.name: c.seat_height_m for c in chairs or [] if c.seat_height_m},
    )
    write_text_atomic(args.out / "report.md", markdown)
    return format_table(table)
