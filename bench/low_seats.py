"""Benchmark: whole missions on low seats, where the bear is let go higher than 1 cm.

Over a seat lower than the NAO's bent-hip postures reach 1 cm over (about 0.175 m), the
goal lets the bear go at those postures' lowest height, up to ``LOW_SEAT_RELEASE_GAP_M``
over the seat (``bearchair.skills.planning.wholebody.release_height``). This bench checks
that drop: chairs of every family with a front (``bearchair.testing.chairgen``), scaled
vertically so that their seats stand ``--low``-``--high`` m high (a toddler's chair of
each shape), one whole simulated mission each with the paper's conditions in rotation
(``bench/generalization.py --missions``' harness). Prints seating per family and per
band of seat heights, the release's drop over the true seat, and the refusals.

Usage::

    .venv/bin/python bench/low_seats.py [--chairs 36] [--low 0.12] [--high 0.19]
        [--seed 0] [--workers 2] [--out DIR] [--timeout 900]
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from generalization_missions import mission_specs, run_specs

from bearchair.testing.chairgen import FAMILIES, GeneratedChair, generate_chair

BANDS_M = (0.12, 0.135, 0.16, 0.175, 0.20)
"""Seat-height bands (metres): the crouch's drop, the bent-hip drop, the 1 cm release."""


def low_chairs(count: int, low_m: float, high_m: float, seed: int) -> list[GeneratedChair]:
    """``count`` generated chairs with a front, the families in turn, each scaled along z
    so that its seat top stands at a seeded height in [``low_m``, ``high_m``]."""
    rng = np.random.default_rng(seed)
    families = [f for f in FAMILIES if generate_chair(0, f).front_yaw_rad is not None]
    chairs = []
    for number in range(count):
        chair = generate_chair(seed + number, families[number % len(families)])
        target = float(rng.uniform(low_m, high_m))
        mesh = chair.mesh.copy()
        mesh.apply_scale([1.0, 1.0, target / chair.seat_height_m])
        chairs.append(chair._replace(mesh=mesh, seat_height_m=target))
    return chairs


def print_drops(out: Path, chairs: list[GeneratedChair]) -> None:
    """Seating per band of seat heights, with the release's height over the true seat."""
    by_name = {c.name + ".obj": c for c in chairs}
    bands: dict[str, list[tuple[bool, float]]] = defaultdict(list)
    for summary_path in sorted((out / "runs").glob("*/*/summary.json")):
        summary = json.loads(summary_path.read_text())
        chair = by_name.get(summary["chair"])
        prediction = summary.get("release_prediction")
        if chair is None or prediction is None:
            continue
        drop = float(prediction["released_at_m"][2]) - chair.seat_height_m
        index = int(np.searchsorted(BANDS_M, chair.seat_height_m, side="right")) - 1
        band = f"{BANDS_M[max(index, 0)]:.3f}-{BANDS_M[min(index + 1, len(BANDS_M) - 1)]:.3f} m"
        bands[band].append((summary["outcome"] == "success", drop))
    print("\nreleases by seat height (the bear's seat point over the true seat when let go):")
    for band, rows in sorted(bands.items()):
        seated = sum(s for s, _ in rows)
        drops = [d for _, d in rows]
        print(
            f"  seats {band}: seated {seated}/{len(rows)} of the released, drop "
            f"{100 * min(drops):.1f}-{100 * max(drops):.1f} cm"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--chairs", type=int, default=36)
    parser.add_argument("--low", type=float, default=0.12, help="lowest seat top, metres")
    parser.add_argument("--high", type=float, default=0.19, help="highest seat top, metres")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=900.0, help="s per mission")
    parser.add_argument("--out", type=Path, default=Path("low-seats"))
    args = parser.parse_args(argv)
    if not 0.0 < args.low <= args.high:
        parser.error(f"--low {args.low} and --high {args.high}: need 0 < low <= high")
    chairs = low_chairs(args.chairs, args.low, args.high, args.seed)
    specs = mission_specs(chairs, args.out / "chairs", args.seed)
    print(f"{len(specs)} missions on low seats; records in {args.out}", file=sys.stderr)
    status = run_specs(specs, chairs, args.workers, args.out, args.timeout)
    print_drops(args.out, chairs)
    return status


if __name__ == "__main__":
    sys.exit(main())
