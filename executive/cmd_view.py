"""``bearchair view RUN_DIR``: open a run's Rerun recording (``mission.rrd``).

The native viewer where there is a display; ``--web`` serves Rerun's web viewer on a
port instead (for a robot's computer reached over ssh, or a machine without a
screen: open the printed address in a browser). Both run Rerun's own viewer, shipped
with rerun-sdk (the ``[viewer]`` extra), until it is closed or Ctrl-C.
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

from bearchair.executive.recording import (
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
        "record_dir",
        metavar="run_dir",
        type=Path,
        help=f"a run folder (with {RECORDING_FILE}) or a .rrd",
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


def rerun_binary() -> str:
    """The viewer program rerun-sdk ships (what ``python -m rerun`` starts)."""
    if "RERUN_CLI_PATH" in os.environ:
        return os.environ["RERUN_CLI_PATH"]
    import rerun_cli

    folder = Path(rerun_cli.__file__).parent
    bundled = folder / "Rerun.app" / "Contents" / "MacOS" / "Rerun"
    if sys.platform == "darwin" and bundled.exists():
        return str(bundled)
    return str(folder / ("rerun.exe" if sys.platform.startswith("win") else "rerun"))


def viewer_command(path: Path, *, web: bool, port: int) -> list[str]:
    """The command that opens ``path`` in Rerun's viewer.

    The web viewer's page is served on ``port``; the data behind it on a free port, so
    that a viewer already running on Rerun's default port is left alone.
    """
    command = [rerun_binary()]
    if web:
        command += ["--web-viewer", "--web-viewer-port", str(port), "--port", str(_free_port())]
    return [*command, str(path)]


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def run(args: argparse.Namespace) -> int:
    from bearchair.core.errors import InputError

    if not rerun_available():
        raise InputError(f"bearchair view: needs rerun-sdk: {INSTALL_HINT}")
    if not 0 < args.port < 65536:
        raise InputError(f"bearchair view: --port must be 1..65535, not {args.port}")
    path = recording_path(args.record_dir)
    if not args.web and not has_display():
        raise InputError(
            "bearchair view: no display for the native viewer; use --web and open the "
            "printed address in a browser"
        )
    if args.web:
        print(
            f"web viewer: http://127.0.0.1:{args.port} (Ctrl-C to stop)",
            file=sys.stderr,
            flush=True,
        )
    command = viewer_command(path, web=args.web, port=args.port)
    if not Path(command[0]).is_file():
        raise InputError(
            f"bearchair view: rerun-sdk's viewer is missing ({command[0]}): reinstall it"
        )
    if os.name == "posix":
        # This process becomes the viewer: Ctrl-C and SIGTERM reach it, nothing is orphaned.
        sys.stdout.flush()
        sys.stderr.flush()
        os.execv(command[0], command)
    try:
        return subprocess.run(command).returncode
    except KeyboardInterrupt:
        return 0
