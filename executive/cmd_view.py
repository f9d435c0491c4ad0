"""``bearchair view RUN_DIR``: open a run's Rerun recording (``mission.rrd``).

The native viewer where there is a display; ``--web`` serves Rerun's web viewer on a
port instead (for a robot's computer reached over ssh, or a machine without a
screen: open the printed link in a browser). The web viewer listens on 127.0.0.1
unless ``--bind`` says otherwise (:mod:`bearchair.executive.viewer_links`). Both run Rerun's own viewer, shipped
with rerun-sdk (the ``[viewer]`` extra), until it is closed or Ctrl-C.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from bearchair.executive.recording.mission_recording import (
    DEFAULT_WEB_PORT,
    INSTALL_HINT,
    RECORDING_FILE,
    has_display,
    rerun_available,
)
from bearchair.executive.viewer_links import (
    LOOPBACK,
    add_bind_argument,
    free_port,
    quiet_rerun_environment,
    rerun_binary,
    ssh_tunnel_hint,
    web_viewer_link,
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
        help="the web viewer's HTTP port with --web (default: %(default)s)",
    )
    add_bind_argument(parser)
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


def viewer_command(path: Path, *, web: bool, port: int, bind: str = LOOPBACK) -> list[str]:
    """The command that opens ``path`` in Rerun's viewer.

    The web viewer's page is served on ``port``; the data behind it on a free port, so
    that a viewer already running on Rerun's default port is left alone; both on
    ``bind`` (the native viewer's own server too). The path goes absolute, so that a file named like an option
    (``--version.rrd``) is read as a file.
    """
    # The native viewer hosts a gRPC server too: it gets the same bind.
    command = [rerun_binary(), "--bind", bind]
    if web:
        command += ["--web-viewer", "--web-viewer-port", str(port)]
        command += ["--port", str(free_port(bind))]
    return [*command, str(path.absolute())]


def grpc_port_of(command: list[str]) -> int | None:
    """The ``--port`` (the data's gRPC port) of a viewer command, if it has one."""
    return int(command[command.index("--port") + 1]) if "--port" in command else None


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
    command = viewer_command(path, web=args.web, port=args.port, bind=args.bind)
    if args.web:
        grpc_port = grpc_port_of(command)
        assert grpc_port is not None  # a web command always names its data port
        print(
            f"web viewer: {web_viewer_link(args.bind, args.port, grpc_port)} (Ctrl-C to stop)",
            file=sys.stderr,
        )
        hint = ssh_tunnel_hint(args.bind, args.port, grpc_port)
        if hint:
            print(hint, file=sys.stderr, flush=True)
    if not Path(command[0]).is_file():
        raise InputError(
            f"bearchair view: rerun-sdk's viewer is missing ({command[0]}): reinstall it"
        )
    if os.name == "posix":
        # This process becomes the viewer: Ctrl-C and SIGTERM reach it, nothing is orphaned.
        sys.stdout.flush()
        sys.stderr.flush()
        os.execve(command[0], command, quiet_rerun_environment())
    try:
        return subprocess.run(command, env=quiet_rerun_environment()).returncode
    except KeyboardInterrupt:
        return 0
