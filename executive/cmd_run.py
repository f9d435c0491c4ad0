"""``bearchair run``: the whole mission, in the simulated world or on the robots, with
its run record (summary, ticks, tree, log, pictures, an optional Rerun recording)."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import logging
from pathlib import Path
from typing import Any

from bearchair.core.errors import InputError
from bearchair.executive.cli_types import positive_seconds, seed_value
from bearchair.executive.cmd_config import (
    add_config_arguments,
    check_run_inputs,
    mission_from_args,
)
from bearchair.executive.exit_codes import EXIT_MISSION_FAILED, EXIT_SUCCESS
from bearchair.executive.interrupts import exit_status
from bearchair.executive.operator import ask_operator
from bearchair.executive.step_bars import showing_step_bars
from bearchair.executive.viewer_links import add_bind_argument

LOG_FILE = "bearchair.log"
"""The run record's log: this process's warnings, and an internal error's traceback."""


def register(subparsers: Any) -> None:
    """Adds ``run`` to the ``bearchair`` command line."""
    run = subparsers.add_parser("run", help="run the mission in the simulated world")
    run.add_argument(
        "--chair", type=Path, help="chair mesh (OBJ/PLY/STL/OFF/GLB); default: a box chair"
    )
    # Flags left off keep the configuration's values (--config; default: accessible, obeys, 0).
    run.add_argument(
        "--placement",
        choices=("accessible", "inaccessible"),
        help="how the simulated chair is placed: its seat reachable by the NAO, or turned so "
        "that the NAO must ask the helper to rotate it (default: accessible, or --config's)",
    )
    run.add_argument(
        "--helper",
        choices=("obeys", "disobeys", "ignores"),
        help="how the simulated helper answers a request to rotate the chair "
        "(default: obeys, or --config's)",
    )
    run.add_argument(
        "--seed",
        type=seed_value,
        help="seeds the world and the skills: the same seed gives the same run "
        "(default: 0, or --config's)",
    )
    run.add_argument("--gui", action="store_true", help="watch in the pybullet GUI")
    run.add_argument("--out", type=Path, help="run record directory (default: runs/<time>-seed<N>)")
    run.add_argument(
        "--mute",
        action="store_true",
        help="print instructions instead of speaking (with --robots: the NAO stays silent)",
    )
    run.add_argument(
        "--timeout",
        type=positive_seconds,
        help="stop the mission as failed after this many wall seconds "
        "(default: 900, or --config's)",
    )
    run.add_argument(
        "--overwrite", action="store_true", help="replace the run record already in --out"
    )
    run.add_argument(
        "--snapshots",
        action="store_true",
        help="in simulation, also save a picture whenever a stage ends (OUT/snapshots)",
    )
    add_recording_arguments(run, record_default=None)
    run.add_argument(
        "--robots",
        type=Path,
        metavar="CELL_JSON",
        help="run on the real NAO and Panda described by this file instead of the simulation",
    )
    run.add_argument("--yes", action="store_true", help="with --robots: start without asking")
    add_config_arguments(run)
    run.add_argument(
        "--groot2",
        nargs="?",
        const=1667,
        type=int,
        metavar="PORT",
        help="publish the running tree to Groot2 on PORT and PORT+1 (default 1667; "
        "docs/btcpp-groot2.md)",
    )
    run.add_argument(
        "--groot2-bind",
        metavar="ADDRESS",
        help="the address Groot2's ports listen on (default 127.0.0.1; '*': every interface, "
        "through BehaviorTree.CPP's own publisher)",
    )
    run.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from bearchair.executive.outputs import default_run_dir, prepare_run_dir
    from bearchair.executive.run import format_summary, run_in_simulation, run_on_robots
    from bearchair.executive.tick_watchers import StageProgress

    if args.robots is not None:
        for option in ("placement", "helper"):
            if getattr(args, option) is not None:
                raise InputError(
                    f"bearchair run: --{option} is for the simulated world; not with --robots"
                )
    check_groot2_arguments("bearchair run", args)
    # Every input and the output place are checked before anything runs.
    mission = mission_from_args(args)
    factory = check_run_inputs(mission)
    outputs = mission.outputs
    check_recording_arguments("bearchair run", argparse.Namespace(**outputs.model_dump()))
    if outputs.out_dir is not None:
        out_dir = prepare_run_dir(outputs.out_dir, overwrite=outputs.overwrite)
    else:
        out_dir = default_run_dir(mission.run.seed)
    args.run_dir = out_dir  # where an internal error's traceback goes
    config = dataclasses.replace(
        mission.run_config(out_dir),
        groot2_port=args.groot2,
        groot2_bind=args.groot2_bind or "127.0.0.1",
    )
    with _log_to(out_dir / LOG_FILE), showing_step_bars():
        if mission.robots.used:
            summary = run_on_robots(
                config,
                mission.robots.cell_file or mission.robots.cell,
                on_tick=StageProgress(),
                confirm=None if args.yes else ask_operator,
                tree=factory,
            )
        else:
            summary = run_in_simulation(config, on_tick=StageProgress(), tree=factory)
    print(format_summary(summary))
    print(f"run record: {out_dir}")
    if summary.interrupted:
        return exit_status()
    return EXIT_SUCCESS if summary.succeeded else EXIT_MISSION_FAILED


@contextlib.contextmanager
def _log_to(path: Path):
    """Also sends this process's warnings (and an internal error) to ``path``."""
    try:
        handler: logging.Handler | None = logging.FileHandler(path, encoding="utf-8")
    except OSError:
        handler = None  # the record itself will say what is wrong with the folder
    if handler is not None:
        handler.setLevel(logging.INFO)
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
        logging.getLogger().addHandler(handler)
    try:
        yield
    finally:
        if handler is not None:
            logging.getLogger().removeHandler(handler)
            handler.close()


def add_recording_arguments(
    parser: argparse.ArgumentParser, *, record_default: bool | None
) -> None:
    """``--record/--no-record`` and ``--live`` (Rerun recordings,
    :mod:`bearchair.executive.recording.mission_recording`);
    ``record_default`` None: left off, the flag is None (the configuration decides, off)."""
    default = {True: "on", False: "off", None: "the configuration's, off"}[record_default]
    parser.add_argument(
        "--record",
        action=argparse.BooleanOptionalAction,
        default=record_default,
        help="write a Rerun recording of the run, OUT/mission.rrd (open it with "
        f"'bearchair view OUT'; default: {default})",
    )
    parser.add_argument(
        "--live",
        nargs="?",
        const="spawn",
        metavar="WHERE",
        help="stream the run to a Rerun viewer as it happens: no value starts the native "
        "viewer, 'web' serves the web viewer, or a viewer's URL (rerun+http://HOST:9876/proxy)",
    )
    add_bind_argument(parser, configured=True)


def check_recording_arguments(command: str, args: argparse.Namespace) -> None:
    """One line before any work when a recording was asked for and cannot be made."""
    from bearchair.executive.recording.mission_recording import (
        INSTALL_HINT,
        has_display,
        rerun_available,
    )

    live = getattr(args, "live", None)
    if (args.record or live) and not rerun_available():
        flag = "--record" if args.record else "--live"
        raise InputError(f"{command}: {flag} needs rerun-sdk: {INSTALL_HINT}")
    if live == "spawn" and not has_display():
        raise InputError(
            f"{command}: --live: no display for the native viewer; use --live web "
            "(a web viewer on a port) or --live rerun+http://HOST:9876/proxy"
        )
    if live not in (None, "spawn", "web") and not live.startswith(("rerun://", "rerun+http")):
        raise InputError(
            f"{command}: --live takes no value, 'web', or a viewer URL "
            f"(rerun+http://HOST:9876/proxy), not {live!r}"
        )


def check_groot2_arguments(command: str, args: argparse.Namespace) -> None:
    """One line before any work when ``--groot2`` cannot be served."""
    from bearchair.executive.groot2 import (
        INSTALL_HINT,
        check_groot2_address,
        check_groot2_port,
        missing_modules,
    )

    if args.groot2 is None:
        if args.groot2_bind is not None:
            raise InputError(f"{command}: --groot2-bind is for --groot2 [PORT]")
        return
    check_groot2_port(args.groot2)
    missing = missing_modules()
    if missing:
        raise InputError(f"{command}: --groot2 needs {', '.join(missing)}: {INSTALL_HINT}")
    check_groot2_address(args.groot2, args.groot2_bind or "127.0.0.1")
