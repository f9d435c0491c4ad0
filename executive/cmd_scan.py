"""``bearchair scan --chair MESH``: scan a chair in the simulated world as ScanChair does.

Places the chair in the simulated world, moves the Panda through the 9 capture
configurations, reconstructs the chair and writes ``chair.ply`` (mesh) and
``chair_points.ply`` (point cloud) to ``--out``. Prints the timings, or with ``--json``
one object with the keys mesh, points, seconds (per step) and views. An unreadable mesh
or a failed scan gives one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from bearchair.core.streams import silenced_fds
from bearchair.executive.cli_types import seed_value


def register(subparsers: argparse._SubParsersAction) -> None:
    """Adds the ``scan`` subcommand."""
    parser = subparsers.add_parser("scan", help="scan and reconstruct a chair in simulation")
    parser.add_argument(
        "--chair", type=Path, required=True, metavar="MESH", help="chair mesh, z up, metres"
    )
    parser.add_argument("--seed", type=seed_value, default=0, help="seeds placement and noise")
    parser.add_argument(
        "--out", type=Path, default=Path("scan-out"), help="output folder (default scan-out)"
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Scans the chair; returns the exit status."""
    import time

    import numpy as np
    import trimesh

    from bearchair.core.meshes import load_chair_mesh
    from bearchair.executive.outputs import atomic_path, ensure_writable_dir
    from bearchair.hardware.sim.world import SimConfig, SimWorld
    from bearchair.skills.perception import PerceptionError, scan_chair

    load_chair_mesh(args.chair)
    ensure_writable_dir(args.out, "--out")  # before the scan, not after
    started = time.perf_counter()
    try:
        # pybullet's C code prints to stdout when it connects: keep stdout for our output.
        with silenced_fds(1, target_fd=2):
            world = SimWorld(SimConfig(chair_path=args.chair, seed=args.seed))
        with world:
            world_s = time.perf_counter() - started
            scan = scan_chair(world.robot.arm, seed=args.seed)
    except PerceptionError as error:
        print(f"bearchair scan: {error}", file=sys.stderr)
        return 2
    mesh_path = args.out / "chair.ply"
    points_path = args.out / "chair_points.ply"
    with atomic_path(mesh_path) as scratch:
        scan.chair_mesh.export(scratch)
    with atomic_path(points_path) as scratch:
        trimesh.PointCloud(np.asarray(scan.chair_points)).export(scratch)
    seconds = {"world": world_s, **scan.seconds}
    if args.json:
        print(
            json.dumps(
                {
                    "mesh": str(mesh_path),
                    "points": str(points_path),
                    "seconds": {k: round(v, 3) for k, v in seconds.items()},
                    "views": scan.views,
                }
            )
        )
        return 0
    print(
        f"chair: {len(scan.chair_mesh.faces)} faces -> {mesh_path}; "
        f"{len(scan.chair_points)} points -> {points_path}"
    )
    for step, value in seconds.items():
        print(f"  {step:<8} {value:7.3f} s (wall)")
    print(f"views: {scan.views}")
    return 0
