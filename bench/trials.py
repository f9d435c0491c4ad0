"""Benchmark: a small real trials campaign (the paper protocol on a few chairs).

Runs ``bearchair trials`` on the first N chairs with a front of ../shared/chairs (or the
built-in box chair when that folder is absent), then prints the median trial wall time
and Table 1. Each chair is 6 trials of the whole mission in the simulated world, so
this takes minutes; timings on the shared 2-core machine are inflated by contention.

    .venv/bin/python bench/trials.py [--max-chairs 2] [--workers 1] [--out DIR] [--seed 0]

The campaign resumes like the CLI: rerun with the same --out to finish or to reprint.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bearchair.evaluation.store import TrialStore
from bearchair.executive import cli

SHARED_CHAIRS = Path(__file__).resolve().parents[2] / "shared" / "chairs"


def box_chair_folder() -> Path:
    """A folder holding the project's box chair and a manifest giving its front (+x)."""
    from bearchair.core.meshes import box_chair_mesh

    folder = Path(tempfile.mkdtemp(prefix="bearchair-box-chair-"))
    box_chair_mesh().export(folder / "box-chair.obj")
    manifest = {"meshes": [{"file": "box-chair.obj", "kind": "chair", "front_yaw_deg": 0.0}]}
    (folder / "manifest.json").write_text(json.dumps(manifest))
    return folder


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--chairs", type=Path, help="default: ../shared/chairs or the box chair")
    parser.add_argument("--max-chairs", type=int, default=2)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--timeout", type=float, default=300.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--out", type=Path, default=Path(tempfile.gettempdir()) / "bearchair-bench-trials"
    )
    args = parser.parse_args()

    chairs = args.chairs
    if chairs is None:
        if (SHARED_CHAIRS / "manifest.json").is_file():
            chairs = SHARED_CHAIRS
        else:
            print(f"{SHARED_CHAIRS} not found: using the built-in box chair", file=sys.stderr)
            chairs = box_chair_folder()
    start = time.monotonic()
    status = cli.main(
        [
            "trials", "--chairs", str(chairs), "--max-chairs", str(args.max_chairs),
            "--workers", str(args.workers), "--timeout", str(args.timeout),
            "--seed", str(args.seed), "--out", str(args.out),
        ]
    )  # fmt: skip
    elapsed = time.monotonic() - start
    if status != 0:
        return status
    with TrialStore(args.out / "trials.sqlite") as store:
        records = store.records()
    walls = [r.wall_seconds for r in records if r.wall_seconds is not None]
    missions = [r.mission_seconds for r in records if r.mission_seconds is not None]
    print()
    print(
        f"trials: {len(records)} in {elapsed:.0f} s of wall time (this call; resumed trials excluded)"
    )
    if walls:
        print(
            f"trial wall time: median {statistics.median(walls):.1f} s, "
            f"min {min(walls):.1f} s, max {max(walls):.1f} s (subprocess, world building included)"
        )
    if missions:
        print(f"mission time (tick loop): median {statistics.median(missions):.1f} s")
    successes = sum(r.succeeded for r in records)
    print(f"seating success: {successes}/{len(records)}")
    print(f"report: {args.out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
