"""Writes a folder of symbolic links to a subset of a chairs folder, with its own manifest.

`bearchair trials --chairs DIR` runs every seat with a front of a folder; to measure on
one part of ``../shared/chairs`` (the sources added later, whose entries carry
``style`` and ``seat_height_m``, or the first sources), write such a folder and point
the trials at it. Nothing is copied: the meshes are linked, the manifest's entries are
the original ones.

    python bench/chair_subset.py --chairs ../shared/chairs --new-sources --out /tmp/new
    python bench/chair_subset.py --chairs ../shared/chairs --first-sources --out /tmp/old
    python bench/chair_subset.py --chairs ../shared/chairs --only chair-gpa,sofa --out /tmp/x
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from bearchair.evaluation.protocol import SEAT_KINDS


def select(entries: list[dict], args: argparse.Namespace) -> list[dict]:
    """The manifest entries the arguments keep, in the manifest's order."""
    chosen = []
    for entry in entries:
        added_later = "style" in entry or "seat_height_m" in entry
        if (args.new_sources and not added_later) or (args.first_sources and added_later):
            continue
        if args.only and not any(p in entry["file"] for p in args.only.split(",")):
            continue
        if args.seats and not (
            entry.get("kind", "chair") in SEAT_KINDS and entry.get("front_yaw_deg") is not None
        ):
            continue
        chosen.append(entry)
    return chosen


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chairs", type=Path, required=True, help="folder with manifest.json")
    parser.add_argument("--out", type=Path, required=True, help="new or empty folder")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--new-sources", action="store_true", help="entries with style/seat height")
    group.add_argument("--first-sources", action="store_true", help="entries without them")
    parser.add_argument("--only", default="", help="comma-separated parts of file names")
    parser.add_argument("--seats", action="store_true", help="only seats with a front")
    args = parser.parse_args(argv)
    manifest_path = args.chairs / "manifest.json"
    if not manifest_path.is_file():
        print(f"chair_subset: {manifest_path}: no such file", file=sys.stderr)
        return 2
    if args.out.exists() and any(args.out.iterdir()):
        print(f"chair_subset: {args.out} is not empty", file=sys.stderr)
        return 2
    document = json.loads(manifest_path.read_text())
    entries = select(document["meshes"], args)
    args.out.mkdir(parents=True, exist_ok=True)
    for entry in entries:
        (args.out / entry["file"]).symlink_to((args.chairs / entry["file"]).resolve())
    (args.out / "manifest.json").write_text(json.dumps({**document, "meshes": entries}, indent=1))
    seats = sum(
        e.get("kind", "chair") in SEAT_KINDS and e.get("front_yaw_deg") is not None for e in entries
    )
    print(f"{args.out}: {len(entries)} meshes, {seats} seats with a front")
    return 0


if __name__ == "__main__":
    sys.exit(main())
