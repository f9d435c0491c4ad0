"""``bearchair inspect``: a recorded run replayed: the tree at any tick, the blackboard,
the timeline, the outcome. Read only: it never writes into the record it reads."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from bearchair.core.userfiles import printable


def register(subparsers: Any) -> None:
    """Adds ``inspect`` to the ``bearchair`` command line."""
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


def _inspect(args: argparse.Namespace) -> int:
    from bearchair.executive.records.replay import RecordedRun

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
