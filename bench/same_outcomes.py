"""Two campaigns, trial by trial: do they give the same outcome? (a refactor's check)

    python bench/same_outcomes.py BEFORE/trials.sqlite AFTER/trials.sqlite

Pairs the trials by their key (chair, placement, helper, trial index, seed) and compares
what the mission did and how the judge saw it: the outcome, the failed stage and its
reason, rotations and instructions, accessibility, the judge's verdict and numbers, the
sitting pose, the error and the attempts. Wall times, run folders, the chairs' paths and
software versions are left out: they differ between any two runs. Prints
each differing trial with its fields, then the count; exits 1 when any trial differs or
is in one campaign only.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from bearchair.evaluation.store import GROUND_TRUTH_COLUMNS, KEY_COLUMNS, TrialStore
from bearchair.evaluation.trial_record import TrialRecord

NOT_COMPARED = {
    "stage_seconds",
    "wall_seconds",
    "mission_seconds",
    "run_dir",
    "chair_path",
    "finished_at",
    "software",
}
"""Fields of a trial's row that differ between any two runs of the same trial: wall
times (``mission_seconds`` is the mission's own wall seconds), places (the run's folder,
and the chair's copy in it: the chair's name is in the key) and versions."""


def compared(record: TrialRecord) -> dict[str, object]:
    """The row's fields that the same trial must repeat."""
    return {
        name: value
        for name, value in dataclasses.asdict(record).items()
        if name not in NOT_COMPARED and name not in KEY_COLUMNS
    }


def key(record: TrialRecord) -> tuple[object, ...]:
    return tuple(getattr(record, name) for name in KEY_COLUMNS)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("before", type=Path, help="the first campaign's trials.sqlite")
    parser.add_argument("after", type=Path, help="the second campaign's trials.sqlite")
    args = parser.parse_args(argv)
    for path in (args.before, args.after):
        if not path.is_file():
            print(f"error: {path}: no such campaign database", file=sys.stderr)
            return 2
    with TrialStore(args.before) as store:
        before = {key(r): r for r in store.records()}
    with TrialStore(args.after) as store:
        after = {key(r): r for r in store.records()}
    differing = 0
    for trial in sorted(set(before) | set(after), key=str):
        if trial not in before or trial not in after:
            differing += 1
            print(f"{trial}: only in {'after' if trial in after else 'before'}")
            continue
        old, new = compared(before[trial]), compared(after[trial])
        changes = {
            name: (old[name], new[name])
            for name in old
            if old[name] != new[name]
            and not (name in GROUND_TRUTH_COLUMNS and (old[name] is None or new[name] is None))
        }
        if changes:
            differing += 1
            print(f"{trial}:")
            for name, (was, now) in changes.items():
                print(f"  {name}: {was!r} -> {now!r}")
    same = len(set(before) | set(after)) - differing
    seated = [sum(bool(r.seated) for r in runs.values()) for runs in (before, after)]
    print(
        f"{same}/{same + differing} trials the same; seated {seated[0]}/{len(before)} "
        f"before, {seated[1]}/{len(after)} after"
    )
    return 0 if differing == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
