"""``bearchair``: run, render and inspect the mission, and its skills on their own.

Subcommands:
    run       the whole mission in the simulated world, with a run record.
    tree      render the mission tree (text, dot, SVG, PNG).
    inspect   replay a recorded run: the tree at any tick, the blackboard, the timeline.
    imagine, scan, ...  skill commands, each registered by its own ``executive.cmd_*``.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from pathlib import Path

from executive.config import RunConfig

# Skill commands live beside their skills' owners: each module has register(subparsers).
SKILL_COMMANDS = (
    "executive.cmd_imagine",
    "executive.cmd_scan",
    "executive.cmd_trials",
    "executive.cmd_view",
)


class CliError(Exception):
    """A user error: printed as one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, not a usage dump
        raise CliError(f"{self.prog}: {message} (see --help)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="bearchair", description=__doc__.split("\n")[0])
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    subparsers = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    run = subparsers.add_parser("run", help="run the mission in the simulated world")
    run.add_argument(
        "--chair", type=Path, help="chair mesh (OBJ/PLY/STL/OFF/GLB); default: a box chair"
    )
    run.add_argument("--placement", choices=("accessible", "inaccessible"), default="accessible")
    run.add_argument("--helper", choices=("obeys", "disobeys", "ignores"), default="obeys")
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--gui", action="store_true", help="watch in the pybullet GUI")
    run.add_argument("--out", type=Path, help="run record directory (default: runs/<time>-seed<N>)")
    run.add_argument("--mute", action="store_true", help="print instructions instead of speaking")
    run.add_argument("--timeout", type=float, default=900.0, help="stop after this many seconds")
    run.add_argument(
        "--snapshots",
        action="store_true",
        help="in simulation, also save a picture whenever a stage ends (OUT/snapshots)",
    )
    add_recording_arguments(run, record_default=False)
    run.add_argument(
        "--robots",
        type=Path,
        metavar="CELL_JSON",
        help="run on the real NAO and Panda described by this file instead of the simulation",
    )
    run.set_defaults(func=_run)

    tree = subparsers.add_parser("tree", help="render the mission tree")
    tree.add_argument(
        "--format", choices=("ascii", "unicode", "dot", "svg", "png"), default="unicode"
    )
    tree.add_argument("--blackboard", action="store_true", help="show blackboard keys and users")
    tree.add_argument(
        "--out", type=Path, help="output file for dot/svg/png (default: mission.<format>)"
    )
    tree.set_defaults(func=_tree)

    inspect = subparsers.add_parser("inspect", help="replay a recorded run")
    inspect.add_argument("run_dir", type=Path)
    inspect.add_argument("--tick", type=int, help="show the tree at this tick (default: the last)")
    inspect.add_argument("--blackboard", action="store_true", help="also show the blackboard")
    inspect.add_argument("--timeline", action="store_true", help="show every status change")
    inspect.set_defaults(func=_inspect)

    for module_name in SKILL_COMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name != module_name:
                raise
            continue  # that skill's command is not part of this installation yet
        module.register(subparsers)
    return parser


def _run(args: argparse.Namespace) -> int:
    from executive.mission import (
        StageProgress,
        default_out_dir,
        format_summary,
        run_in_simulation,
        run_on_robots,
    )

    config = RunConfig(
        chair_path=args.chair,
        placement=args.placement,
        helper=args.helper,
        seed=args.seed,
        gui=args.gui,
        mute=args.mute,
        timeout_s=args.timeout,
        snapshots=args.snapshots,
        record=args.record,
        live=args.live,
    )
    if args.timeout <= 0:
        raise CliError("bearchair run: --timeout must be positive")
    check_recording_arguments("bearchair run", args)
    out_dir = args.out or default_out_dir(config)
    config = RunConfig(**{**config.__dict__, "out_dir": out_dir})
    if args.robots is not None:
        summary = run_on_robots(config, args.robots, on_tick=StageProgress())
    else:
        summary = run_in_simulation(config, on_tick=StageProgress())
    print(format_summary(summary))
    print(f"run record: {out_dir}")
    return 0 if summary["outcome"] == "success" else 1


def add_recording_arguments(parser: argparse.ArgumentParser, *, record_default: bool) -> None:
    """``--record/--no-record`` and ``--live`` (Rerun recordings, ``executive.recording``)."""
    parser.add_argument(
        "--record",
        action=argparse.BooleanOptionalAction,
        default=record_default,
        help="write a Rerun recording of the run, OUT/mission.rrd (open it with "
        f"'bearchair view OUT'; default: {'on' if record_default else 'off'})",
    )
    parser.add_argument(
        "--live",
        nargs="?",
        const="spawn",
        metavar="WHERE",
        help="stream the run to a Rerun viewer as it happens: no value starts the native "
        "viewer, 'web' serves the web viewer, or a viewer's URL (rerun+http://HOST:9876/proxy)",
    )


def check_recording_arguments(command: str, args: argparse.Namespace) -> None:
    """One line before any work when a recording was asked for and cannot be made."""
    from executive.recording import INSTALL_HINT, has_display, rerun_available

    live = getattr(args, "live", None)
    if (args.record or live) and not rerun_available():
        flag = "--record" if args.record else "--live"
        raise CliError(f"{command}: {flag} needs rerun-sdk: {INSTALL_HINT}")
    if live == "spawn" and not has_display():
        raise CliError(
            f"{command}: --live: no display for the native viewer; use --live web "
            "(a web viewer on a port) or --live rerun+http://HOST:9876/proxy"
        )
    if live not in (None, "spawn", "web") and not live.startswith(("rerun://", "rerun+http")):
        raise CliError(
            f"{command}: --live takes no value, 'web', or a viewer URL "
            f"(rerun+http://HOST:9876/proxy), not {live!r}"
        )


def _tree(args: argparse.Namespace) -> int:
    from executive.render import TEXT_FORMATS, render_graph, render_text
    from trees.mission import create_tree

    root = create_tree()
    if args.format in TEXT_FORMATS:
        print(render_text(root, args.format, args.blackboard))
        return 0
    out = args.out or Path(f"mission.{args.format}")
    print(render_graph(root, args.format, out, args.blackboard))
    return 0


def _inspect(args: argparse.Namespace) -> int:
    from executive.inspect_run import RecordedRun

    run = RecordedRun(args.run_dir)
    state = run.at(args.tick)
    print(f"{args.run_dir}: tick {state['tick']} of {run.last_tick}, t = {state['t']:.2f} s")
    print(run.tree_text(args.tick))
    if args.blackboard:
        print("\nblackboard:")
        print(run.blackboard_text(args.tick))
    if args.timeline:
        print("\ntimeline:")
        print(run.timeline_text())
    if run.summary and args.tick is None:
        summary = run.summary
        print(
            f"\noutcome: {summary['outcome']}"
            + (
                f" at {summary['failed_stage']}: {summary['reason']}"
                if summary["failed_stage"]
                else ""
            )
        )
    return 0


def main(argv: list[str] | None = None) -> int:
    """The console script. Exit status: 0 success, 1 mission failure, 2 user error."""
    from executive.inspect_run import RunRecordError
    from executive.render import RenderError
    from hardware.real import BackendUnavailable
    from skills.meshes import MeshLoadError

    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        logging.basicConfig(
            level=logging.DEBUG if args.verbose else logging.WARNING,
            format="%(levelname)s %(name)s: %(message)s",
        )
        return args.func(args)
    except CliError as error:
        print(error, file=sys.stderr)
        return 2
    except (
        MeshLoadError,
        RunRecordError,
        RenderError,
        BackendUnavailable,
        FileNotFoundError,
    ) as error:
        print(f"bearchair: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bearchair: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
