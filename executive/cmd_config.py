"""``bearchair config``: the mission configuration's JSON Schema, and a resolved configuration.

``bearchair config --schema`` prints the JSON Schema of a mission configuration (for an
editor's completion and checks: Even Better TOML reads it); ``bearchair config --show
[--config FILE] [--tree SPEC] [--set KEY=VALUE ...]`` prints the configuration a run
would use, after the flags, as JSON. This module also holds the flags that
``run`` and ``tree`` share with it (:func:`add_config_arguments`) and turns a command's
flags into a configuration (:func:`mission_from_args`).
"""

from __future__ import annotations

import argparse
import json
import os
import tomllib
from pathlib import Path
from typing import Any

from bearchair.core.errors import InputError

RUN_FLAGS: dict[str, str] = {
    "chair": "run.chair",
    "placement": "run.placement",
    "helper": "run.helper",
    "seed": "run.seed",
    "gui": "run.gui",
    "mute": "run.mute",
    "timeout": "timeouts.mission_s",
    "out": "outputs.out_dir",
    "overwrite": "outputs.overwrite",
    "snapshots": "outputs.snapshots",
    "record": "outputs.record",
    "live": "outputs.live",
    "bind": "outputs.bind",
    "robots": "robots.cell_file",
    "tree": "tree.factory",
}
"""Each flag of ``bearchair run`` and the configuration key it overrides (when given)."""
STORE_TRUE = frozenset({"gui", "mute", "overwrite", "snapshots"})
"""Flags that can only turn a key on: left off, they leave the configuration's value."""


def add_config_arguments(parser: argparse.ArgumentParser) -> None:
    """``--config FILE``, ``--tree SPEC`` and ``--set KEY=VALUE`` (repeatable)."""
    parser.add_argument(
        "--config",
        type=Path,
        metavar="FILE",
        help="a mission configuration (TOML); flags override it",
    )
    parser.add_argument(
        "--tree",
        metavar="SPEC",
        help="the tree: mission (default), a bearchair.trees entry point, module:factory, "
        "or a BehaviorTree.CPP .xml file",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one configuration key, e.g. --set tree.assistance=false "
        "(VALUE is a TOML value; a bare word is a string)",
    )


def register(subparsers: Any) -> None:
    parser = subparsers.add_parser(
        "config", help="the mission configuration: its JSON Schema, or the resolved one"
    )
    shown = parser.add_mutually_exclusive_group(required=True)
    shown.add_argument("--schema", action="store_true", help="print the JSON Schema")
    shown.add_argument("--show", action="store_true", help="print the resolved configuration")
    add_config_arguments(parser)
    parser.set_defaults(func=_config)


def _config(args: argparse.Namespace) -> int:
    from bearchair.executive.mission_config import json_schema

    if args.schema:
        if args.config is not None or args.tree is not None or args.set:
            raise InputError("bearchair config: --schema takes no --config, --tree nor --set")
        print(json.dumps(json_schema(), indent=2))
        return 0
    print(json.dumps(mission_from_args(args).model_dump(mode="json"), indent=2))
    return 0


def mission_from_args(args: argparse.Namespace) -> Any:
    """The configuration of ``--config`` (or the defaults), overridden by the flags that
    were given (:data:`RUN_FLAGS`, then each ``--set``), checked again.

    Raises:
        ConfigError: the file or an override is wrong (one line naming the field).
    """
    from bearchair.executive.mission_config import (
        MissionConfig,
        load_mission_config,
        with_overrides,
    )

    config = load_mission_config(args.config) if args.config is not None else MissionConfig()
    overrides: dict[str, Any] = {}
    for flag, key in RUN_FLAGS.items():
        value = getattr(args, flag, None)
        if value is None or (value is False and flag in STORE_TRUE):  # not given
            continue
        overrides[key] = str(value) if isinstance(value, Path) else value
    for item in getattr(args, "set", None) or []:
        key, value = parse_assignment(item)
        overrides[key] = value
    return with_overrides(config, overrides) if overrides else config


def parse_assignment(text: str) -> tuple[str, Any]:
    """``"tree.max_rotations=2"`` -> ``("tree.max_rotations", 2)``; the value is read as
    TOML (``true``, ``2.5``, ``[0, 1]``, ``"x"``), a bare word as a string.

    Raises:
        InputError: no ``=``, or an empty key.
    """
    key, equals, value = text.partition("=")
    key = key.strip()
    if not equals or not key:
        raise InputError(f"bearchair: --set {text!r}: write KEY=VALUE, e.g. tree.assistance=false")
    try:
        return key, tomllib.loads(f"value = {value.strip()}")["value"]
    except tomllib.TOMLDecodeError:
        return key, value.strip()


def check_run_inputs(config: Any) -> Any:
    """Checks what a run of ``config`` (a ``MissionConfig``) reads before it runs: the
    tree, the skill plug-ins, the chair or the cell file; returns the tree factory.

    Raises:
        PluginError, InputError, MeshError: one line naming what is wrong.
    """
    from bearchair.core.meshes import load_chair_mesh
    from bearchair.core.userfiles import open_regular_file
    from bearchair.executive.tree_source import load_tree_factory
    from bearchair.skills.skill_sets import check_skill_plugins

    factory = load_tree_factory(config.tree.factory)
    check_skill_plugins(config.skills.plugins)
    if config.run.gui:
        from bearchair.executive.recording.mission_recording import has_display

        if not has_display():
            raise InputError(
                "bearchair run: --gui needs a display (neither DISPLAY nor WAYLAND_DISPLAY "
                "is set); run without --gui, or watch with --live web"
            )
    cell_file = config.robots.cell_file
    if config.robots.used:
        if config.run.chair is not None:
            raise InputError("bearchair run: --chair is for the simulation; not with --robots")
        if cell_file is not None:
            try:  # a regular file: a FIFO would block, a folder is no cell file
                os.close(open_regular_file(cell_file, "cell file", InputError))
            except InputError as error:
                raise InputError(f"bearchair run: --robots {error}") from None
    elif config.run.chair is not None:
        load_chair_mesh(config.run.chair)
    return factory
