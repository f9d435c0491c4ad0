"""``bearchair tree``: the mission tree rendered as text, a picture (dot, SVG, PNG) or
BehaviorTree.CPP v4 XML for Groot2."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from bearchair.core.errors import InputError
from bearchair.executive.cmd_config import add_config_arguments, mission_from_args


def register(subparsers: Any) -> None:
    """Adds ``tree`` to the ``bearchair`` command line."""
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


def _tree(args: argparse.Namespace) -> int:
    from bearchair.executive.outputs import check_output_file
    from bearchair.executive.tree_render import TEXT_FORMATS, render_graph, render_text
    from bearchair.executive.tree_source import build_tree, load_tree_factory

    mission = mission_from_args(args)
    factory = load_tree_factory(mission.tree.factory)
    if args.format == "btcpp":
        from bearchair.executive.tree_render import write_btcpp

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
