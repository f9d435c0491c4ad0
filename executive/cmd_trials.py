"""``bearchair trials``: the paper's evaluation protocol over a folder of chairs.

Every trial runs the whole mission in the simulated world, in its own subprocess, and
is recorded in SQLite as soon as it ends; a rerun with the same arguments resumes.
The summary (the paper's Table 1, stage medians, causes of failure) is printed and
written to ``OUT/report.md`` with ``OUT/chairs/*.png`` (imagined pose per chair) and
``OUT/trials/*.png`` (final scene per trial).
"""

from __future__ import annotations

import argparse
import contextlib
import shlex
import signal
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

DEFAULT_OUT = Path("trials")
DEFAULT_TIMEOUT_S = 300.0


def register(subparsers: Any) -> None:
    """Adds the ``trials`` subcommand to the ``bearchair`` CLI."""
    parser = subparsers.add_parser(
        "trials", help="run the paper's evaluation protocol over a folder of chairs"
    )
    parser.add_argument("--chairs", type=Path, required=True, help="folder of chair meshes")
    parser.add_argument("--protocol", choices=("paper",), default="paper")
    parser.add_argument("--workers", type=int, default=1, help="trials at once (default 1)")
    parser.add_argument("--backend", choices=("local", "ray"), default="local")
    parser.add_argument("--address", help="Ray cluster address (--backend ray); default: local Ray")
    parser.add_argument("--db", type=Path, help="SQLite records (default: OUT/trials.sqlite)")
    parser.add_argument(
        "--out", type=Path, default=DEFAULT_OUT, help="output folder (default: trials)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="campaign seed (trial seeds derive from it)"
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=DEFAULT_TIMEOUT_S,
        help=f"per-trial wall time in seconds before the trial is killed (default {DEFAULT_TIMEOUT_S:.0f})",
    )
    parser.add_argument("--max-chairs", type=int, help="only the first N chairs with a front")
    parser.add_argument(
        "--record",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="write a Rerun recording in each trial's run folder, mission.rrd (default: on "
        "when rerun-sdk is installed; open one with 'bearchair view RUN_DIR')",
    )
    parser.add_argument(
        "--worker-cmd",
        help="run each trial with this command instead of 'python -m executive.trial_worker' "
        "(the trial's JSON is appended)",
    )
    parser.set_defaults(func=run)


def resume_command(args: argparse.Namespace) -> str:
    """The command line that resumes this campaign."""
    words = ["bearchair", "trials", "--chairs", str(args.chairs), "--protocol", args.protocol]
    words += ["--seed", str(args.seed), "--out", str(args.out), "--db", str(_db_path(args))]
    words += ["--workers", str(args.workers), "--timeout", f"{args.timeout:g}"]
    words += ["--backend", args.backend]
    if args.address:
        words += ["--address", args.address]
    if args.max_chairs is not None:
        words += ["--max-chairs", str(args.max_chairs)]
    if args.worker_cmd:
        words += ["--worker-cmd", args.worker_cmd]
    if not args.record:
        words += ["--no-record"]
    return shlex.join(words)


@contextlib.contextmanager
def _sigterm_as_interrupt() -> Iterator[None]:
    """SIGTERM stops the campaign like Ctrl-C: the trial workers run in their own
    sessions, so the harness must stop them itself rather than die and orphan them."""

    def interrupt(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _recording_available() -> bool:
    """Recordings are on by default; without rerun-sdk the campaign runs without them."""
    from executive.recording import INSTALL_HINT, rerun_available

    if rerun_available():
        return True
    print(f"bearchair trials: no recordings (mission.rrd): {INSTALL_HINT}", file=sys.stderr)
    return False


def _db_path(args: argparse.Namespace) -> Path:
    return args.db or args.out / "trials.sqlite"


def run(args: argparse.Namespace) -> int:
    """Runs (or resumes) the campaign, then prints and writes the summary."""
    from executive.cli import CliError
    from executive.trials.backends import BackendUnavailableError, LocalBackend, RayBackend
    from executive.trials.campaign import run_campaign
    from executive.trials.progress import Progress
    from executive.trials.protocol import ChairSetError, discover_chairs, expand_protocol
    from executive.trials.store import TrialStore

    if args.workers < 1:
        raise CliError("bearchair trials: --workers must be at least 1")
    if args.timeout <= 0:
        raise CliError("bearchair trials: --timeout must be positive")
    if args.max_chairs is not None and args.max_chairs < 1:
        raise CliError("bearchair trials: --max-chairs must be at least 1")
    if args.address and args.backend != "ray":
        raise CliError("bearchair trials: --address only applies to --backend ray")
    try:
        chairs, skipped = discover_chairs(args.chairs, args.max_chairs)
    except ChairSetError as error:
        raise CliError(f"bearchair trials: {error}") from error
    command = shlex.split(args.worker_cmd) if args.worker_cmd else None
    try:
        if args.backend == "ray":
            backend: Any = RayBackend(args.workers, args.timeout, args.address, command=command)
        else:
            backend = LocalBackend(args.workers, args.timeout, command)
    except BackendUnavailableError as error:
        raise CliError(f"bearchair trials: {error}") from error

    record = args.record and _recording_available()
    specs = expand_protocol(chairs, args.protocol, args.seed)
    db_path = _db_path(args)
    try:
        store = TrialStore(db_path)
    except Exception as error:  # sqlite3.Error, OSError: a bad --db path
        raise CliError(f"bearchair trials: cannot open records {db_path}: {error}") from error
    with store:
        done_before = len(store.finished_keys() & {spec.key for spec in specs})
        print(
            f"{len(chairs)} chairs x {len(specs) // len(chairs)} trials = {len(specs)} trials "
            f"({done_before} already recorded in {db_path}); "
            f"{len(skipped)} mesh(es) skipped; backend {args.backend}, {args.workers} worker(s)",
            file=sys.stderr,
        )
        progress = Progress(len(specs), done_before)
        try:
            with _sigterm_as_interrupt():
                result = run_campaign(
                    specs,
                    store,
                    backend,
                    args.out / "runs",
                    args.timeout,
                    progress=progress,
                    record=record,
                )
        except BackendUnavailableError as error:
            raise CliError(f"bearchair trials: {error}") from error
        records = store.records(specs)
    if result.interrupted:
        print(
            f"bearchair trials: interrupted; {len(records)} of {len(specs)} trials are recorded in "
            f"{db_path} (none lost). Resume with:\n  {resume_command(args)}",
            file=sys.stderr,
        )
        return 130
    print(write_report(args, records, skipped))
    print(f"report: {args.out / 'report.md'}", file=sys.stderr)
    return 0


def write_report(args: argparse.Namespace, records: list[dict], skipped: list) -> str:
    """Writes OUT/report.md and the pictures; returns the table as text."""
    from executive.trials.pictures import copy_trial_scenes, render_chair_pictures
    from executive.trials.report import compute_table, format_table, markdown_report

    table = compute_table(records)
    args.out.mkdir(parents=True, exist_ok=True)
    copy_trial_scenes(records, args.out / "trials")
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
    )
    (args.out / "report.md").write_text(markdown)
    return format_table(table)
