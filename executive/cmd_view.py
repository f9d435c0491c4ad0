"""``bearchair view RUN_DIR``: open a run's Rerun recording (``mission.rrd``).

The native viewer where there is a display; ``--web`` serves Rerun's web viewer on a
port instead (for a robot's computer reached over ssh, or a machine without a
screen: open the printed address in a browser). Both run Rerun's own viewer, shipped
with rerun-sdk (the ``[viewer]`` extra), until it is closed or Ctrl-C.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path
from typing import Any

from executive.recording import (
    DEFAULT_VIEWER_PORT,
    DEFAULT_WEB_PORT,
    INSTALL_HINT,
    RECORDING_FILE,
    has_display,
    rerun_available,
)


def register(subparsers: Any) -> None:
    """Adds the ``view`` subcommand to the ``bearchair`` CLI."""
    parser = subparsers.add_parser(
        "view", help="open a run's Rerun recording (record one with 'bearchair run --record')"
    )
    parser.add_argument(
        "run_dir", type=Path, help=f"a run folder (with {RECORDING_FILE}) or a .rrd"
    )
    parser.add_argument(
        "--web", action="store_true", help="serve the web viewer instead of opening a window"
    )
    parser.add_argument(
        "--port",
        type=int,
        default=DEFAULT_WEB_PORT,
        help=f"the web viewer's HTTP port with --web (default {DEFAULT_WEB_PORT})",
    )
    parser.set_defaults(func=run)


def recording_path(run_dir: Path) -> Path:
    """The ``.rrd`` of a run folder (or the file itself).

    Raises:
        FileNotFoundError: no recording there, with how to make one.
    """
    path = run_dir if run_dir.suffix == ".rrd" else run_dir / RECORDING_FILE
    if not path.is_file():
        if run_dir.is_dir():
            raise FileNotFoundError(
                f"{run_dir} has no {RECORDING_FILE}: record a run with 'bearchair run --record'"
            )
        raise FileNotFoundError(f"no run folder or recording at {run_dir}")
    return path


def viewer_command(path: Path, *, web: bool, port: int) -> list[str]:
    """The command that opens ``path`` in Rerun's viewer (``python -m rerun``)."""
    command = [sys.executable, "-m", "rerun"]
    if web:
        command += [
            "--web-viewer",
            "--web-viewer-port",
            str(port),
            "--port",
            str(DEFAULT_VIEWER_PORT),
        ]
    return [*command, str(path)]


def run(args: argparse.Namespace) -> int:
    from executive.cli import CliError

    if not rerun_available():
        raise CliError(f"bearchair view: needs rerun-sdk: {INSTALL_HINT}")
    if not 0 < args.port < 65536:
        raise CliError(f"bearchair view: --port must be 1..65535, not {args.port}")
    path = recording_path(args.run_dir)
    if not args.web and not has_display():
        raise CliError(
            "bearchair view: no display for the native viewer; use --web and open the "
            "printed address in a browser"
        )
    if args.web:
        print(
            f"web viewer: http://127.0.0.1:{args.port} (Ctrl-C to stop)",
            file=sys.stderr,
            flush=True,
        )
    try:
        return subprocess.run(viewer_command(path, web=args.web, port=args.port)).returncode
    except KeyboardInterrupt:
        return 0
