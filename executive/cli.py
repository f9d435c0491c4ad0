"""``bearchair``: run, render and inspect the mission, and its skills on their own.

Subcommands:
    run       the whole mission in the simulated world, with a run record.
    tree      render the mission tree (text, dot, SVG, PNG).
    inspect   replay a recorded run: the tree at any tick, the blackboard, the timeline.
    imagine, scan, ...  skill commands, each registered by its own ``bearchair.executive.cmd_*``.
    trials    the evaluation harness: a command of a package above this one
              (``evaluation``), found through the entry points of :data:`COMMANDS_GROUP`.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import importlib.metadata
import json
import logging
import os
import sqlite3
import sys
import tempfile
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bearchair.core.errors import BackendUnavailable, BearchairError, InputError, one_line
from bearchair.core.provenance import version_line
from bearchair.core.streams import import_pybullet_quietly
from bearchair.core.userfiles import printable
from bearchair.executive import (
    cmd_calibrate_hand_eye,
    cmd_check_hardware,
    cmd_config,
    cmd_imagine,
    cmd_scan,
    cmd_view,
)
from bearchair.executive.cli_types import positive_seconds, seed_value
from bearchair.executive.cmd_config import (
    add_config_arguments,
    check_run_inputs,
    mission_from_args,
)
from bearchair.executive.console import TolerantStream, lost_output_status
from bearchair.executive.interrupts import exit_status, handling_signals, received, signal_name
from bearchair.executive.operator import ask_operator
from bearchair.executive.step_bars import showing_step_bars
from bearchair.executive.viewer_links import add_bind_argument

OWN_COMMANDS = (
    cmd_imagine,
    cmd_scan,
    cmd_check_hardware,
    cmd_calibrate_hand_eye,
    cmd_view,
    cmd_config,
)
"""executive's own commands: each module has ``register(subparsers)``."""
COMMANDS_GROUP = "bearchair.commands"
"""The entry-point group of commands from packages above executive (pyproject.toml):
each names a ``register(subparsers)``, loaded from the installed metadata."""

EXIT_SUCCESS = 0
EXIT_MISSION_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_INTERNAL_ERROR = 3
LOG_FILE = "bearchair.log"
"""The run folder's log: warnings of the run, and the traceback of an internal error."""


class CommandUnavailableError(BackendUnavailable):
    """A command registered in the installed metadata cannot be loaded (a stale install)."""


class DefaultsHelpFormatter(argparse.HelpFormatter):
    """``--help`` says each option's default, unless its text already does or it has
    none worth saying (None, False: a flag that is off)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            "default" in text
            or default is None
            or default is False
            or default == argparse.SUPPRESS
            or not action.option_strings
        ):
            return text
        return f"{text} (default: %(default)s)"


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", DefaultsHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # one line, not a usage dump
        raise InputError(f"{self.prog}: {message} (see --help)")


LOG_LEVELS = ("debug", "info", "warning", "error")


def add_logging_arguments(parser: argparse.ArgumentParser, *, top: bool) -> None:
    """``-v`` and ``--log-level``, accepted before or after the subcommand: each
    subcommand has them too, with no default of its own (the top level's stands)."""
    parser.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        default=False if top else argparse.SUPPRESS,
        help="log debug messages (the same as --log-level debug)",
    )
    parser.add_argument(
        "--log-level",
        choices=LOG_LEVELS,
        default="warning" if top else argparse.SUPPRESS,
        help="the least severe log messages shown on the console",
    )


def build_parser() -> argparse.ArgumentParser:
    assert __doc__ is not None  # only python -OO strips it, and that strips asserts too
    parser = _Parser(prog="bearchair", description=__doc__.split("\n")[0])
    add_logging_arguments(parser, top=True)
    parser.add_argument(
        "--version", action="version", version=version_line(), help="print the version and exit"
    )
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

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

    tree = subparsers.add_parser("tree", help="render the mission tree")
    tree.add_argument(
        "--format",
        choices=("ascii", "unicode", "dot", "svg", "png", "btcpp"),
        default="unicode",
        help="text on the console (ascii, unicode) or a file (dot, svg, png; btcpp: "
        "BehaviorTree.CPP v4 XML for Groot2, docs/btcpp-groot2.md)",
    )
    tree.add_argument("--blackboard", action="store_true", help="show blackboard keys and users")
    tree.add_argument(
        "--out",
        type=Path,
        help="output file for dot/svg/png (default: mission.<format>) or btcpp (default: stdout)",
    )
    add_config_arguments(tree)
    tree.set_defaults(func=_tree)

    inspect = subparsers.add_parser("inspect", help="replay a recorded run")
    # Not named run_dir: that is where an internal error's traceback would go, and
    # inspect reads a record, it never writes one.
    inspect.add_argument(
        "record_dir", metavar="run_dir", type=Path, help="a run folder written by 'bearchair run'"
    )
    inspect.add_argument("--tick", type=int, help="show the tree at this tick (default: the last)")
    inspect.add_argument("--blackboard", action="store_true", help="also show the blackboard")
    inspect.add_argument("--timeline", action="store_true", help="show every status change")
    inspect.add_argument(
        "--tree", metavar="SPEC", help="also say whether the record's tree is the one SPEC builds"
    )
    inspect.set_defaults(func=_inspect)

    for module in OWN_COMMANDS:
        module.register(subparsers)
    for register in registered_commands():
        register(subparsers)
    for subparser in subparsers.choices.values():
        add_logging_arguments(subparser, top=False)
    return parser


def registered_commands() -> list[Callable[[Any], None]]:
    """The ``register`` function of every command in :data:`COMMANDS_GROUP`, by name.

    Raises:
        CommandUnavailableError: a registered command's module or function is missing.
    """
    found = []
    entry_points = importlib.metadata.entry_points(group=COMMANDS_GROUP)
    for entry_point in sorted(entry_points, key=lambda e: e.name):
        try:
            found.append(entry_point.load())
        except (ImportError, AttributeError) as error:
            raise CommandUnavailableError(
                f"bearchair: the {entry_point.name!r} command ({entry_point.value}) cannot be "
                f"loaded: {one_line(error)}; reinstall bearchair (pip install -e .)"
            ) from error
    return found


def _run(args: argparse.Namespace) -> int:
    from bearchair.executive.mission import (
        StageProgress,
        format_summary,
        run_in_simulation,
        run_on_robots,
    )
    from bearchair.executive.outputs import default_run_dir, prepare_run_dir

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
    """``--record/--no-record`` and ``--live`` (Rerun recordings, ``bearchair.executive.recording``);
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
    from bearchair.executive.recording import INSTALL_HINT, has_display, rerun_available

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


def _tree(args: argparse.Namespace) -> int:
    from bearchair.executive.outputs import check_output_file
    from bearchair.executive.render import TEXT_FORMATS, render_graph, render_text
    from bearchair.executive.tree_source import build_tree, load_tree_factory

    mission = mission_from_args(args)
    factory = load_tree_factory(mission.tree.factory)
    if args.format == "btcpp":
        from bearchair.executive.render import write_btcpp

        return write_btcpp(
            build_tree(factory, mission.tree.options(), mission.tree.factory), args.out
        )
    if args.format in TEXT_FORMATS:
        if args.out is not None:
            raise InputError(
                f"bearchair tree: --out is for dot/svg/png, not --format {args.format}"
            )
    else:
        args.out = check_output_file(
            args.out or Path(f"mission.{args.format}"), "--out", (f".{args.format}",)
        )
    root = build_tree(factory, mission.tree.options(), mission.tree.factory)
    if args.out is None:
        print(render_text(root, args.format, args.blackboard))
    else:
        print(render_graph(root, args.format, args.out, args.blackboard))
    return 0


def _inspect(args: argparse.Namespace) -> int:
    from bearchair.executive.inspect_run import RecordedRun

    run = RecordedRun(args.record_dir)
    state = run.at(args.tick)
    print(
        f"{printable(args.record_dir)}: tick {state['tick']} of {run.last_tick}, t = {state['t']:.2f} s"
    )
    for note in run.notes:
        print(f"note: {printable(note, 1000)}")
    if args.tree is not None:
        print(f"tree: {run.compare_tree(args.tree)}")
    print(run.tree_text(args.tick))
    if args.blackboard:
        print("\nblackboard:")
        print(run.blackboard_text(args.tick))
    if args.timeline:
        print("\ntimeline:")
        print(run.timeline_text())
    if args.tick is None:
        outcome = run.outcome_text()
        if outcome:
            print(f"\n{outcome}")
    return 0


def _error_line(error: BaseException) -> str:
    """One line for a user-facing error, prefixed ``bearchair:`` unless it names itself."""
    from bearchair.executive.outputs import describe_os_error

    if isinstance(error, OSError):
        text = describe_os_error(error)
    elif isinstance(error, json.JSONDecodeError):
        text = f"not valid JSON ({error.msg} at line {error.lineno} column {error.colno})"
    elif isinstance(error, UnicodeError):
        text = f"not text (UTF-8): {one_line(error)}"
    elif isinstance(error, sqlite3.Error):
        text = f"database error: {one_line(error)}"
    else:
        text = printable(str(error).strip() or type(error).__name__, 600)
    return text if text.startswith("bearchair") else f"bearchair: {text}"


USER_ERRORS: tuple[type[BaseException], ...] = (
    BearchairError,
    OSError,
    json.JSONDecodeError,
    UnicodeError,
    sqlite3.Error,
)
"""Exceptions that mean bad input or an unusable place: exit 2, one line."""


def _crash_log(args: argparse.Namespace | None) -> Path:
    """Where an internal error's traceback goes: the run folder's log, else a new file."""
    run_dir = getattr(args, "run_dir", None) if args is not None else None
    if run_dir is not None and Path(run_dir).is_dir():
        return Path(run_dir) / LOG_FILE
    from bearchair.core.meshes import cache_dir

    stamp = f"crash-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}.log"
    try:
        folder = cache_dir() / "logs"
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        folder = Path(tempfile.gettempdir())
    return folder / stamp


def _report_internal_error(error: BaseException, args: argparse.Namespace | None) -> None:
    path = _crash_log(args)
    try:
        with open(path, "a", encoding="utf-8") as log:
            log.write(f"{time.strftime('%Y-%m-%dT%H:%M:%S%z')} internal error\n")
            traceback.print_exception(error, file=log)
        where = f"the traceback is in {path}"
    except OSError:
        where = "the traceback could not be written"
    print(
        f"bearchair: internal error ({type(error).__name__}: {printable(one_line(error), 200)}); "
        f"this is a bug, please report it; {where}",
        file=sys.stderr,
    )


def main(argv: list[str] | None = None) -> int:
    """The console script.

    Exit status (``docs/exit-status.md``): 0 success, 1 mission failure, 2 bad input or
    an unusable place (one line on stderr), 3 internal error (one line; the traceback in
    the run folder's ``bearchair.log``), 128 + the signal's number when a stop signal
    ended it (129 SIGHUP, 130 SIGINT, 131 SIGQUIT, 138 SIGUSR1, 140 SIGUSR2, 143 SIGTERM;
    the record is kept).
    """
    console = argv is None  # the console script (tests pass their argv)
    saved = sys.stdout, sys.stderr
    out, err = TolerantStream(sys.stdout), TolerantStream(sys.stderr)
    sys.stdout, sys.stderr = out, err
    try:
        with handling_signals():
            status = _main(argv)
            status = lost_output_status(out, err, status, EXIT_BAD_INPUT)
            if console and received() is not None:
                _exit_now(status)
            if console:
                _stop_the_runtime(status)
            return status
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        sys.stdout, sys.stderr = saved
        outputs = sys.modules.get("bearchair.executive.outputs")
        if outputs is not None:  # the run folder is written: another run may replace it
            outputs.release_run_dir_locks()


def _stop_the_runtime(status: int) -> None:
    """Stops the pools and joins the threads the command started, before the interpreter
    tears itself down (a thread still in casadi or qi then crashes it: SIGABRT, SIGSEGV).

    What does not stop within its bound is named on stderr, and the process leaves with
    ``os._exit(status)``, its records already written, rather than crash at exit.
    """
    from bearchair.core.runtime import RUNTIME

    left = RUNTIME.shutdown()
    if left:
        print(f"bearchair: still running at exit: {', '.join(left)}", file=sys.stderr)
        _exit_now(status)


def _exit_now(status: int) -> None:
    """Leaves the process at once after a stop signal, its records already written.

    The imagination's worker processes ignore SIGINT and would finish their batch of
    drops before the interpreter's exit could join them (12 s measured on
    ``imagine``); terminating them under a live ``ProcessPoolExecutor`` makes its
    management thread print a traceback. So: flush, silence stderr, SIGKILL and reap the
    children (the runtime's ``kill``: pool workers and the resource tracker), and
    ``os._exit``.
    """
    from bearchair.core.runtime import RUNTIME

    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    with contextlib.suppress(OSError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 2)
    RUNTIME.kill()
    os._exit(status)


def _main(argv: list[str] | None) -> int:
    args: argparse.Namespace | None = None
    try:
        import_pybullet_quietly()
        parser = build_parser()
        args = parser.parse_args(argv)
        logging.basicConfig(
            level=logging.DEBUG if args.verbose else getattr(logging, args.log_level.upper()),
            format="%(levelname)s %(name)s: %(message)s",
        )
        return args.func(args)
    except KeyboardInterrupt as error:
        print(
            f"bearchair: interrupted by {signal_name(getattr(error, 'signum', None))}",
            file=sys.stderr,
        )
        return exit_status(error)
    except SystemExit as error:  # argparse's --help, or a library that exits
        return error.code if isinstance(error.code, int) else EXIT_BAD_INPUT
    except Exception as error:
        if isinstance(error, USER_ERRORS):
            print(_error_line(error), file=sys.stderr)
            return EXIT_BAD_INPUT
        _report_internal_error(error, args)
        return EXIT_INTERNAL_ERROR


if __name__ == "__main__":
    sys.exit(main())
