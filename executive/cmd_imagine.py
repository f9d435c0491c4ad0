"""``bearchair imagine MESH``: the sitting imagination on one mesh file.

Prints the sitting position (metres) and yaw (degrees from +x about +z, the direction
the sitter faces) in the mesh's frame, the number of correct sittings and the time; or
``--json`` one JSON object with the keys found, position, yaw_deg, n_correct, n_drops,
seconds, vote (how the correct sittings spread over the 8 rotations: counts, chosen_deg,
runner_up_deg, share, split, resolved_by, extra_drops; null when none), backrest (the
direction the backrest gives: yaw_deg, offset_m, disagreement_deg, used; null when the
seat has no backrest) and, when not found, reason. A mesh that is not a chair gives ``found: false`` and exit status 0; an
unreadable or empty file, or an ``--image`` that cannot be written (checked before the
simulation), gives one line on stderr and status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

from bearchair.core.userfiles import printable
from bearchair.executive import interrupts
from bearchair.executive.cli_types import positive_int, seed_value

if TYPE_CHECKING:
    import trimesh

    from bearchair.skills.results import ImaginationResult


def register(subparsers: argparse._SubParsersAction) -> None:
    """Adds the ``imagine`` subcommand."""
    parser = subparsers.add_parser(
        "imagine", help="find how to sit on a chair mesh by physical simulation"
    )
    parser.add_argument("mesh", type=Path, help="chair mesh (OBJ/PLY/STL/OFF/GLB), z up, metres")
    parser.add_argument("--seed", type=seed_value, default=0, help="seed of the drops (default 0)")
    parser.add_argument(
        "--workers", type=positive_int, default=2, help="worker processes (default 2)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--image", type=Path, metavar="PNG", help="also draw the result here")
    parser.set_defaults(func=run)


def check_workers(workers: int) -> None:
    """Refuses more drop workers than the machine has processors (one line): the result
    is the same for any number, and 10000 processes would only exhaust the machine."""
    from bearchair.core.errors import InputError

    processors = os.cpu_count() or 1
    if workers > processors:
        raise InputError(
            f"bearchair imagine: --workers {workers}: more than this machine's {processors} "
            f"processors; give at most {processors} (the result is the same for any number)"
        )


def run(args: argparse.Namespace) -> int:
    """Runs the imagination on ``args.mesh``; returns the exit status."""
    from bearchair.core.meshes import load_chair_mesh
    from bearchair.executive.outputs import check_output_file
    from bearchair.skills.imagination import imagine_sitting

    check_workers(args.workers)
    mesh = load_chair_mesh(args.mesh)
    if args.image is not None:  # before the minutes of simulation, not after
        check_output_file(args.image, "--image", (".png",))
    # Ctrl-C cancels the drops (within their polling period) even if a library swallowed
    # the KeyboardInterrupt; the interrupt is then raised here.
    result = imagine_sitting(
        mesh, seed=args.seed, workers=args.workers, cancel=interrupts.stop_requested
    )
    interrupts.raise_if_received()
    if args.image is not None:
        _draw(mesh, result, args.mesh.name, args.image)
    if args.json:
        print(json.dumps(_json_payload(result)))
        return 0
    _print_report(result)
    if args.image is not None:
        print(f"image:            {printable(args.image)}")
    return 0


def _draw(mesh: trimesh.Trimesh, result: ImaginationResult, name: str, image: Path) -> None:
    """The mesh and the sitting pose found (if any) drawn into the PNG ``image``."""
    from bearchair.skills.imagination.sitting_picture import render_sitting

    title = (
        f"{name}: yaw {math.degrees(result.sitting_pose.yaw):.1f} deg, "
        f"{result.n_correct} correct of {result.n_drops}"
        if result.found and result.sitting_pose is not None
        else f"{name}: no sitting pose ({result.reason})"
    )
    render_sitting(mesh, result.sitting_pose, image, title)


def _json_payload(result: ImaginationResult) -> dict:
    """The ``--json`` object (keys in the module's docstring)."""
    seconds = result.seconds.get("total", 0.0)
    payload: dict = {
        "found": result.found,
        "position": [round(float(v), 4) for v in result.sitting_pose.position]
        if result.sitting_pose is not None
        else None,
        "yaw_deg": round(math.degrees(result.sitting_pose.yaw), 2)
        if result.sitting_pose is not None
        else None,
        "n_correct": result.n_correct,
        "n_drops": result.n_drops,
        "seconds": round(seconds, 3),
        "vote": result.vote.to_json() if result.vote is not None else None,
        "backrest": result.backrest.to_json() if result.backrest is not None else None,
    }
    if not result.found:
        payload["reason"] = result.reason
    return payload


def _print_report(result: ImaginationResult) -> None:
    """The human-readable result: pose, correct drops, vote, backrest check and times."""
    if result.found and result.sitting_pose is not None:
        x, y, z = (float(v) for v in result.sitting_pose.position)
        print(f"sitting position: x={x:.3f} y={y:.3f} z={z:.3f} m (mesh frame)")
        print(f"sitting yaw:      {math.degrees(result.sitting_pose.yaw):.1f} deg from +x about +z")
    else:
        print(f"no sitting pose: {printable(result.reason, 400)}")
    print(f"correct sittings: {result.n_correct} of {result.n_drops} drops")
    if result.vote is not None:
        print(f"rotation vote:    {result.vote.describe()}")
    if result.backrest is not None:
        check = result.backrest
        verdict = "taken instead" if check.used else "agrees"
        if not check.used and not math.isnan(check.mirror_vote):
            verdict = (
                f"the vote's plane mirrors the chair better ({check.mirror_vote:.2f} against "
                f"{check.mirror_back:.2f}): the vote stands"
            )
        print(
            f"backrest:         faces {math.degrees(check.yaw_rad):.1f} deg, the vote's "
            f"direction {math.degrees(check.disagreement_rad):+.1f} deg from it: {verdict}"
        )
    seconds = result.seconds.get("total", 0.0)
    print(
        f"time:             {seconds:.2f} s (prepare {result.seconds.get('prepare', 0.0):.2f} s, "
        f"simulate {result.seconds.get('simulate', 0.0):.2f} s)"
    )
