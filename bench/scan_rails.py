"""How far the scan moves the armrests and rails beside the sitting point.

Run: ``.venv/bin/python bench/scan_rails.py [--per-family 8] [--truncations 4,3,2]
[--families armchair,swivel_tub,basket,x_frame,sofa]``.

The NAO's hands lower the bear between armrests only where the scan leaves them room
(:func:`bearchair.skills.planning.chair_along_ray.rails_beside`, the band
``BAND_HALF_WIDTH_M``), so a scan that puts an armrest's inner face a few millimetres
inward can refuse a chair the NAO could seat. For generated chairs of the families with
armrests or side walls (seeds 0 .. per-family - 1), placed as a mission places them
(seeded, camera noise on), each chair is scanned once per TSDF truncation given (in
voxels, :class:`~bearchair.skills.perception.reconstruction_config.ReconstructionConfig`)
and the nearest rails left and right of the true sitting point (the seat's middle,
facing the chair's front) are found on the true mesh, on the scan, and on the scan's
surface a frame measured (the reconstruction's mark, :mod:`bearchair.core.seen_surface`:
what the TSDF grew behind an armrest's top is left out), as the planners judge them. Prints per chair
the true and scanned rails (metres across the sitting ray, left positive); per
truncation how far the scanned rails stand inward of the true ones (a negative value:
outward, the scan thinned the rail), how much narrower the gap between them came out,
and the scan's time. Chairs with no rail within reach of the band on both sides are
listed as such and left out of the figures.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.skills.perception import PerceptionError, scan_chair
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.planning.chair_along_ray import rails_beside, surface_samples
from bearchair.testing.chairgen import FAMILIES, generate_chair

RAIL_FAMILIES = ("armchair", "swivel_tub", "basket", "x_frame", "sofa")


def _percentiles(values: list[float]) -> str:
    v = 1000.0 * np.asarray(values)
    return (
        f"median {np.median(v):+.1f}, p90 {np.percentile(v, 90):+.1f}, "
        f"max {v.max():+.1f}, min {v.min():+.1f} mm"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--per-family", type=int, default=8)
    parser.add_argument("--families", default=",".join(RAIL_FAMILIES))
    parser.add_argument("--truncations", default="4,3,2", help="TSDF truncations, voxels")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    families = [f for f in args.families.split(",") if f in FAMILIES]
    truncations = [float(t) for t in args.truncations.split(",") if t]
    inward: dict[float, list[float]] = {t: [] for t in truncations}
    narrower: dict[float, list[float]] = {t: [] for t in truncations}
    seconds: dict[float, list[float]] = {t: [] for t in truncations}
    no_rails: list[str] = []
    folder = Path(tempfile.mkdtemp(prefix="bench-scan-rails-"))
    for family in families:
        for number in range(args.per_family):
            chair = generate_chair(args.seed + number, family)
            path = folder / f"{chair.name}.obj"
            chair.mesh.export(path)
            config = SimConfig(chair_path=path, seed=args.seed + number, front_yaw_deg=0.0)
            line = [chair.name]
            true_rails: tuple[float, float] | None = None
            for truncation in truncations:
                with SimWorld(config) as world:
                    pose = chair.true_sitting_pose(world.T_world_chair_true())
                    true_a, true_b = rails_beside(world.chair_mesh_true, pose, chair.seat_height_m)
                    if not (math.isfinite(true_a) and math.isfinite(true_b)):
                        break
                    true_rails = (true_a, true_b)
                    tick = time.perf_counter()
                    try:
                        scan = scan_chair(
                            world.robot.arm,
                            seed=args.seed,
                            config=ReconstructionConfig(sdf_trunc_voxels=truncation),
                        )
                    except (PerceptionError, TimeoutError) as error:
                        line.append(f"trunc {truncation:g}: scan failed: {error}")
                        continue
                    seconds[truncation].append(time.perf_counter() - tick)
                points, seen = surface_samples(scan.chair_mesh)
                everywhere = np.ones(len(points), bool)
                for key, kept in ((truncation, everywhere), (-truncation, seen)):
                    a, b = rails_beside(scan.chair_mesh, pose, chair.seat_height_m, points, kept)
                    label = "seen" if key < 0 else f"trunc {truncation:g}"
                    line.append(f"{label}: {a:+.4f} {b:+.4f}")
                    if math.isfinite(a):
                        inward.setdefault(key, []).append(true_a - a)
                    if math.isfinite(b):
                        inward.setdefault(key, []).append(b - true_b)
                    if math.isfinite(a - b):
                        narrower.setdefault(key, []).append((true_a - true_b) - (a - b))
            if true_rails is None:
                no_rails.append(chair.name)
                continue
            print(
                f"{line[0]}: true {true_rails[0]:+.4f} {true_rails[1]:+.4f}; " + "; ".join(line[1:])
            )
            sys.stdout.flush()
    print()
    print(f"chairs without rails within reach of the band on both sides: {len(no_rails)}")
    for truncation in truncations:
        for key, what in ((truncation, "the surface"), (-truncation, "what a view saw")):
            if not inward.get(key):
                continue
            print(
                f"truncation {truncation:g} voxels, {what}: {len(inward[key])} rails, inward "
                f"{_percentiles(inward[key])}; gaps narrower {_percentiles(narrower[key])}"
            )
        if seconds[truncation]:
            print(f"  scan {np.median(seconds[truncation]):.1f} s median")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
