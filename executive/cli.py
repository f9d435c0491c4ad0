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
    cmd_inspect,
    cmd_run,
    cmd_scan,
    cmd_tree,
    cmd_view,
)
from bearchair.executive.cmd_run import LOG_FILE
from bearchair.executive.console import TolerantStream, lost_output_status
from bearchair.executive.exit_codes import EXIT_BAD_INPUT, EXIT_INTERNAL_ERROR
from bearchair.executive.interrupts import exit_status, handling_signals, received, signal_name

OWN_COMMANDS = (
    cmd_run,
    cmd_tree,
    cmd_inspect,
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
