"""Benchmark of the sitting imagination over the calibration meshes in ../shared/chairs.

For every mesh: found or not, the sitting direction's error against the manifest's
``front_yaw_deg`` (chairs and sofas with a front), the number of drops and correct
sittings, and the wall time. Summary: the share of fronted meshes within 30 degrees,
the tables found as chairs, the median error, the median time per chair (all, and the
24-drop case) and the physics steps per second.

Usage:
    .venv/bin/python bench/imagination.py [--workers 2] [--seed 0] [--only chair-synth]
        [--save raw.pkl] [--json summary.json] [--use-cache]
    .venv/bin/python bench/imagination.py --generated 4 [--families round,armchair]

The preparation of a mesh is cached on disk by its digest; unless ``--use-cache`` is
given, the benchmark uses a fresh cache folder so every mesh is prepared from scratch,
as a newly scanned chair is in a mission. The summary gives the median and the maximum
of the time per mesh (preparation plus drops), tables included.

``--generated N`` runs N chairs per family of ``bearchair.testing.chairgen`` instead (families with a
front only; seeds 0..N-1 shifted by ``--seed``), each turned by a seeded random yaw as the
calibration meshes are, and prints the direction error per family.

``--save`` stores every drop's raw outcome so the SAM thresholds can be re-scored
without simulating again (``--rescore raw.pkl``).
"""

from __future__ import annotations

import argparse
import json
import math
import pickle
import statistics
import sys
import time
from pathlib import Path

CHAIRS_DIR = Path(__file__).resolve().parents[2] / "shared" / "chairs"


def _angle_error_deg(yaw_rad: float, front_deg: float) -> float:
    error = (math.degrees(yaw_rad) - front_deg + 180.0) % 360.0 - 180.0
    return abs(error)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--only",
        default="",
        help="only meshes whose file name contains one of these (comma-separated)",
    )
    parser.add_argument("--save", type=Path, help="pickle the raw drops here")
    parser.add_argument("--rescore", type=Path, help="re-score saved raw drops, no simulation")
    parser.add_argument("--json", type=Path, help="write the summary as JSON here")
    parser.add_argument(
        "--use-cache", action="store_true", help="reuse prepared meshes from the disk cache"
    )
    parser.add_argument(
        "--generated", type=int, default=0, help="N generated chairs per family instead"
    )
    parser.add_argument(
        "--families",
        default="",
        help="generated families (comma-separated; default: every family with a front)",
    )
    args = parser.parse_args(argv)
    if not args.use_cache:
        import os
        import tempfile

        # Before the skills are imported, so the workers inherit it too.
        os.environ["BEARCHAIR_CACHE"] = tempfile.mkdtemp(prefix="bearchair-bench-cache-")
    if args.generated:
        return _generated(args)

    if not CHAIRS_DIR.is_dir():
        print(f"skipped: {CHAIRS_DIR} is absent (calibration meshes not available)")
        return 0
    manifest = json.loads((CHAIRS_DIR / "manifest.json").read_text())
    patterns = args.only.split(",")
    entries = [e for e in manifest["meshes"] if any(p in e["file"] for p in patterns)]

    from bearchair.core.meshes import load_mesh
    from bearchair.skills.imagination import imagine_sitting_details, warm_up
    from bearchair.skills.imagination.sam import score_drop
    from bearchair.skills.imagination.vote import choose_sitting_pose

    rows = []
    saved: dict[str, tuple] = {}
    if args.rescore:
        saved = pickle.loads(args.rescore.read_bytes())
    else:
        started = time.perf_counter()
        warm_up(args.workers)
        print(f"worker start-up: {time.perf_counter() - started:.2f} s ({args.workers} workers)")

    print(
        f"{'mesh':24s} {'kind':6s} {'found':5s} {'err':>6s} {'ncor':>4s} {'drops':>5s} "
        f"{'prep':>5s} {'sim':>5s} {'total':>5s}  reason"
    )
    for entry in entries:
        name = entry["file"]
        if args.rescore:
            if name not in saved:
                continue
            prepared, raw, seconds, steps, physics = saved[name]
            drops = tuple(score_drop(d) for d in raw)
            result = choose_sitting_pose(prepared, drops, seconds, list(raw))
        else:
            mesh = load_mesh(CHAIRS_DIR / name)
            details = imagine_sitting_details(mesh, seed=args.seed, workers=args.workers)
            result, raw = details.result, details.raw_drops
            steps, physics = details.steps, details.physics_seconds
            saved[name] = (details.prepared, raw, result.seconds, steps, physics)
        front = entry.get("front_yaw_deg")
        error = (
            _angle_error_deg(result.sitting_pose.yaw, front)
            if result.found and front is not None
            else None
        )
        rows.append(
            {
                "file": name,
                "kind": entry["kind"],
                "found": result.found,
                "front": front,
                "error_deg": error,
                "n_correct": result.n_correct,
                "n_drops": result.n_drops,
                "seconds": result.seconds,
                "steps": steps,
                "physics_s": physics,
                "reason": result.reason,
                "split": bool(getattr(result, "vote", None) and result.vote.split),
            }
        )
        print(
            f"{name:24s} {entry['kind']:6s} {result.found!s:5s} "
            f"{'' if error is None else f'{error:6.1f}':>6s} {result.n_correct:4d} "
            f"{result.n_drops:5d} {result.seconds['prepare']:5.2f} "
            f"{result.seconds['simulate']:5.2f} {result.seconds['total']:5.2f}  {result.reason}"
            + (f"{result.vote.describe()}" if getattr(result, "vote", None) else "")
        )
        sys.stdout.flush()

    if args.save and not args.rescore:
        args.save.write_bytes(pickle.dumps(saved))
    summary = _summary(rows)
    print()
    for key, value in summary.items():
        print(f"{key:40s} {value}")
    if args.json:
        args.json.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1))
    return 0


def _generated_chairs(count: int, seed: int, families: list[str]):
    """(name, mesh, front_yaw_deg, family, seat height) of generated chairs, each turned by a
    seeded yaw (the calibration meshes come turned too, so the OBB is not axis-aligned)."""
    import numpy as np
    import trimesh

    from bearchair.testing.chairgen import generate_chair

    for family in families:
        for index in range(count):
            chair = generate_chair(seed + index, family)
            if chair.front_yaw_rad is None:
                continue
            yaw = float(np.random.default_rng([seed + index, 7]).uniform(-math.pi, math.pi))
            mesh = chair.mesh.copy()
            mesh.apply_transform(trimesh.transformations.rotation_matrix(yaw, (0, 0, 1)))
            front = math.degrees(chair.front_yaw_rad + yaw)
            yield chair.name, mesh, front, family, chair.seat_height_m


def _generated(args: argparse.Namespace) -> int:
    from bearchair.skills.imagination import imagine_sitting_details, warm_up
    from bearchair.skills.imagination.sam import score_drop
    from bearchair.skills.imagination.vote import choose_sitting_pose
    from bearchair.testing.chairgen import FAMILIES

    families = [f for f in (args.families.split(",") if args.families else FAMILIES) if f]
    saved: dict[str, tuple] = {}
    if args.rescore:
        saved = pickle.loads(args.rescore.read_bytes())
    else:
        warm_up(args.workers)
    rows = []
    print(f"{'chair':24s} {'seat':>5s} {'found':5s} {'err':>6s} {'ncor':>4s} {'drops':>5s}  vote")
    for name, mesh, front, family, seat in _generated_chairs(args.generated, args.seed, families):
        if args.rescore:
            if name not in saved:
                continue
            prepared, raw, seconds = saved[name][:3]
            drops = tuple(score_drop(d) for d in raw)
            result = choose_sitting_pose(prepared, drops, seconds, list(raw))
        else:
            details = imagine_sitting_details(mesh, seed=args.seed, workers=args.workers)
            result, raw = details.result, details.raw_drops
            saved[name] = (details.prepared, raw, result.seconds)
        error = _angle_error_deg(result.sitting_pose.yaw, front) if result.found else None
        vote = getattr(result, "vote", None)
        rows.append({"file": name, "family": family, "seat_m": seat, "error_deg": error})
        print(
            f"{name:24s} {seat:5.2f} {result.found!s:5s} "
            f"{'' if error is None else f'{error:6.1f}':>6s} {result.n_correct:4d} "
            f"{result.n_drops:5d}  {'' if vote is None else vote.describe()} {result.reason}"
        )
        sys.stdout.flush()
    if args.save and not args.rescore:
        args.save.write_bytes(pickle.dumps(saved))
    print()
    print(f"{'family':12s} {'chairs':>6s} {'found':>5s} {'<=30deg':>7s} {'median':>6s} {'max':>6s}")
    for family in families:
        mine = [r for r in rows if r["family"] == family]
        if not mine:
            continue
        errors = [r["error_deg"] for r in mine if r["error_deg"] is not None]
        within = sum(e <= 30.0 for e in errors)
        print(
            f"{family:12s} {len(mine):6d} {len(errors):5d} {within:7d} "
            f"{statistics.median(errors) if errors else float('nan'):6.1f} "
            f"{max(errors) if errors else float('nan'):6.1f}"
        )
    if args.json:
        args.json.write_text(json.dumps({"rows": rows}, indent=1))
    return 0


def _summary(rows: list[dict]) -> dict:
    fronted = [r for r in rows if r["front"] is not None]
    within = [r for r in fronted if r["error_deg"] is not None and r["error_deg"] <= 30.0]
    errors = [r["error_deg"] for r in fronted if r["error_deg"] is not None]
    tables = [r for r in rows if r["kind"] == "table"]
    totals = [r["seconds"]["total"] for r in rows]
    simulate = [r["seconds"]["simulate"] for r in rows]
    prepare = [r["seconds"]["prepare"] for r in rows]
    totals_24 = [r["seconds"]["total"] for r in rows if r["n_drops"] == 24]
    steps = sum(r["steps"] for r in rows)
    physics = sum(r["physics_s"] for r in rows)
    return {
        "fronted meshes within 30 deg": f"{len(within)}/{len(fronted)} "
        f"({100.0 * len(within) / max(len(fronted), 1):.1f}%)",
        "fronted meshes found": f"{len(errors)}/{len(fronted)}",
        "split votes (fronted)": sum(r.get("split", False) for r in fronted),
        "tables found as chairs": f"{sum(r['found'] for r in tables)}/{len(tables)}",
        "median error (deg, found fronted)": round(statistics.median(errors), 1)
        if errors
        else None,
        "median total s per mesh": round(statistics.median(totals), 3) if totals else None,
        "max total s per mesh": f"{max(totals):.3f} ({max(rows, key=lambda r: r['seconds']['total'])['file']})"
        if totals
        else None,
        "median / max prepare s per mesh": f"{statistics.median(prepare):.3f} / {max(prepare):.3f}"
        if prepare
        else None,
        "median simulate s per mesh": round(statistics.median(simulate), 3) if simulate else None,
        "median total s, 24-drop meshes": round(statistics.median(totals_24), 3)
        if totals_24
        else None,
        "24-drop meshes": f"{len(totals_24)}/{len(rows)}",
        "physics steps per second (per drop, summed over workers)": round(steps / physics)
        if physics
        else None,
    }


if __name__ == "__main__":
    sys.exit(main())
