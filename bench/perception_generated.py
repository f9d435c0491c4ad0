"""Scan and tracking of generated chairs in the simulated world (camera noise on).

Run: ``.venv/bin/python bench/perception_generated.py [--per-family 2] [--families bench,armchair]
[--place 0.35,-0.25,45]``.

For each family of ``bearchair.testing.chairgen``, the largest of ``--pool`` seeded chairs (by
footprint diagonal times height) are placed in the simulated world as the mission places
them (seeded), scanned, then turned by the helper's rotations (±90 and 180 degrees about
their centre, a few millimetres of slip) and tracked with ``measure_chair_rotation``.
Prints per chair: scan completed or its error, views captured / skipped / replaced,
the reconstruction's Chamfer distance to the true mesh; per rotation: the yaw error,
centre error (yaw modulo a half turn for chairs without a front, which look the same
turned 180 degrees), fitness and the visible-overlap fitness, or the rejection. Ends
with the counts. Runs with whatever ``skills`` is first on the path, so the same script measures
a branch and main (``PYTHONPATH=/path/to/main``).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from bearchair.core.geometry import wrap_angle, yaw_of, yaw_transform
from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.skills.perception import PerceptionError, measure_chair_rotation, scan_chair
from bearchair.testing.chairgen import FAMILIES, generate_chair

ROTATIONS_DEG = (90, -90, 180)


def chamfer_m(a: trimesh.Trimesh, b: trimesh.Trimesh, samples: int = 20000) -> float:
    pa, pb = a.sample(samples, seed=0), b.sample(samples, seed=1)
    return 0.5 * float(cKDTree(pb).query(pa)[0].mean() + cKDTree(pa).query(pb)[0].mean())


def largest_chairs(family: str, count: int, pool: int):
    chairs = [generate_chair(seed, family) for seed in range(pool)]
    size = [
        float(np.linalg.norm(np.ptp(c.mesh.bounds[:, :2], axis=0)) * c.mesh.bounds[1, 2])
        for c in chairs
    ]
    order = np.argsort(size)[::-1][:count]
    return [chairs[i] for i in order]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-family", type=int, default=2)
    parser.add_argument("--pool", type=int, default=20, help="seeds per family to pick from")
    parser.add_argument("--families", default="bench,armchair,four_legs,round,box_base,sled")
    parser.add_argument("--rotations", default=",".join(str(r) for r in ROTATIONS_DEG))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--place",
        default="",
        help="x,y,yaw_deg: stand every chair there before the scan (e.g. at the chair "
        "area's edge nearest the arm, where a large chair meets the scan views)",
    )
    args = parser.parse_args()
    families = [f for f in args.families.split(",") if f in FAMILIES]
    rotations = [int(r) for r in args.rotations.split(",") if r]
    scans_ok = scans = 0
    fits: list[tuple[str, int, float, float, float]] = []
    failures: list[str] = []
    folder = Path(tempfile.mkdtemp(prefix="bench-perception-generated-"))
    for family in families:
        for number, chair in enumerate(largest_chairs(family, args.per_family, args.pool)):
            path = folder / f"{chair.name}.obj"
            chair.mesh.export(path)
            extents = np.ptp(chair.mesh.bounds, axis=0)
            label = f"{chair.name} ({extents[0]:.2f} x {extents[1]:.2f} x {extents[2]:.2f} m)"
            config = SimConfig(chair_path=path, seed=args.seed + number, front_yaw_deg=0.0)
            scans += 1
            with SimWorld(config) as world:
                arm = world.robot.arm
                if args.place:
                    x, y, yaw_deg = (float(v) for v in args.place.split(","))
                    world.chair.set_T_world_chair(
                        yaw_transform(math.radians(yaw_deg), np.array([x, y, 0.0]))
                    )
                    world.clock.sleep(0.3)
                tick = time.perf_counter()
                try:
                    scan = scan_chair(arm, seed=args.seed)
                except (PerceptionError, TimeoutError) as error:
                    print(f"{label}: scan FAILED: {error}")
                    failures.append(f"{chair.name} scan: {error}")
                    continue
                scans_ok += 1
                notes = getattr(scan, "notes", ())
                print(
                    f"{label}: scan ok, {scan.views} views, chamfer "
                    f"{100 * chamfer_m(world.chair_mesh_true, scan.chair_mesh):.2f} cm, "
                    f"{time.perf_counter() - tick:.1f} s"
                    + (f"; {'; '.join(notes)}" if notes else "")
                )
                sys.stdout.flush()
                reference = scan.chair_points
                T_old = world.T_world_chair_true()
                for rotation_deg in rotations:
                    shift = np.array([0.008, -0.006, 0.0])
                    T_new = (
                        yaw_transform(0.0, T_old[:3, 3] + shift)
                        @ yaw_transform(math.radians(rotation_deg))
                        @ yaw_transform(0.0, -T_old[:3, 3])
                        @ T_old
                    )
                    world.chair.set_T_world_chair(T_new)
                    world.clock.sleep(0.3)
                    truth = world.T_world_chair_true() @ np.linalg.inv(T_old)
                    try:
                        rotation = measure_chair_rotation(arm, reference)
                    except (PerceptionError, TimeoutError) as error:
                        print(f"  turn {rotation_deg:+4d} deg: REJECTED {error}")
                        failures.append(f"{chair.name} turn {rotation_deg}: {error}")
                        fits.append((chair.name, rotation_deg, math.inf, math.inf, math.nan))
                    else:
                        centre = T_old[:3, 3]
                        moved = (
                            rotation.T_world_new_old[:3, :3] @ centre
                            + rotation.T_world_new_old[:3, 3]
                        )
                        centre_error = float(
                            np.linalg.norm(moved - (truth[:3, :3] @ centre + truth[:3, 3]))
                        )
                        yaw_error = abs(math.degrees(wrap_angle(rotation.yaw_rad - yaw_of(truth))))
                        if chair.front_yaw_rad is None:
                            # No front (a bench, a stool): a half turn looks the same.
                            yaw_error = min(yaw_error, 180.0 - yaw_error)
                        fits.append(
                            (chair.name, rotation_deg, yaw_error, centre_error, rotation.fitness)
                        )
                        print(
                            f"  turn {rotation_deg:+4d} deg: yaw error {yaw_error:.2f} deg, centre "
                            f"error {100 * centre_error:.2f} cm, fitness {rotation.fitness:.2f}"
                            + (
                                f", visible overlap {rotation.visible_fitness:.2f}"
                                if hasattr(rotation, "visible_fitness")
                                else ""
                            )
                        )
                    sys.stdout.flush()
                    world.chair.set_T_world_chair(T_old)
                    world.clock.sleep(0.3)
    print("\n== summary ==")
    print(f"scans completed: {scans_ok} of {scans}")
    good = [f for f in fits if f[2] <= 3.0 and f[3] <= 0.015]
    accepted = [f for f in fits if math.isfinite(f[2])]
    wrong = [f for f in accepted if f[2] > 3.0 or f[3] > 0.015]
    print(
        f"rotations tracked: {len(accepted)} of {len(fits)} accepted, {len(good)} within 3 deg "
        f"and 1.5 cm, {len(wrong)} accepted but wrong"
    )
    if accepted:
        fitness = np.array([f[4] for f in accepted])
        print(f"fitness of accepted fits: min {fitness.min():.2f}, median {np.median(fitness):.2f}")
    for failure in failures:
        print(f"  {failure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
