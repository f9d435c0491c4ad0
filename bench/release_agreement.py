"""How often the release imagination's prediction agrees with the judge, from run records.

Reads every ``summary.json`` under the folders given (a campaign's ``OUT/runs``, or
``bench/generalization.py --missions``' output) whose mission reached the release (a
``release_prediction`` and a ``judgement``), and prints the agreement, the confusion
table, the error between the predicted and the actual settle position, and the
imagination's share of SeatBear's time. Run the missions with
``BEARCHAIR_RELEASE_CHECK=predict`` to measure it over every release as planned (by
default, ``prefer``, a release predicted to fall moves to a placement predicted to stay
where there is one, so the "falls" predictions it avoided have no verdict)::

    .venv/bin/python bench/release_agreement.py /tmp/trials/runs [more folders]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path
from typing import NamedTuple

from bearchair.core.errors import RunRecordError
from bearchair.executive.records.run_summary import RunSummary


class Release(NamedTuple):
    """One release that happened: what was predicted and what the judge said."""

    run: str
    predicted_stays: bool
    seated: bool
    settle_error_m: float
    imagination_s: float
    imagination_cpu_s: float
    seat_bear_s: float | None
    reason: str

    @property
    def physically_agrees(self) -> bool:
        """The prediction agrees on whether the bear stays on the seat upright: a bear
        the judge fails only for facing off the TRUE front (an imagination miss the
        mission cannot see) counts as staying."""
        facing_only = not self.seated and all(
            part.startswith("facing off") for part in self.reason.split("; ")
        )
        return self.predicted_stays == (self.seated or facing_only)


def releases(folders: list[Path]) -> list[Release]:
    """The releases recorded under ``folders`` (each ``summary.json`` with both)."""
    found = []
    for folder in folders:
        for path in sorted(folder.rglob("summary.json")):
            release = _release(path)
            if release is not None:
                found.append(release)
    return found


def _release(path: Path) -> Release | None:
    try:
        summary = RunSummary.from_json(json.loads(path.read_text()))
    except (OSError, ValueError, RunRecordError):
        return None
    predicted, judgement = summary.release_prediction, summary.judgement
    if predicted is None or judgement is None or judgement.T_world_bear is None:
        return None
    actual = [row[3] for row in judgement.T_world_bear[:3]]
    error = sum((a - b) ** 2 for a, b in zip(actual, predicted.settled_at_m, strict=True))
    seat_bear = summary.stage("SeatBear")
    return Release(
        str(path.parent),
        predicted.stays,
        judgement.seated,
        error**0.5,
        predicted.seconds,
        predicted.seconds if predicted.cpu_seconds is None else predicted.cpu_seconds,
        None if seat_bear is None else seat_bear.seconds,
        judgement.reason,
    )


def print_agreement(found: list[Release]) -> None:
    """The agreement, the confusion table and the settle error, as lines on stdout."""
    if not found:
        print("no releases with a prediction found")
        return
    agree = sum(r.predicted_stays == r.seated for r in found)
    print(
        f"releases: {len(found)}; prediction agrees with the judge: {agree}/{len(found)} "
        f"({100.0 * agree / len(found):.1f} %)"
    )
    physical = sum(r.physically_agrees for r in found)
    print(
        f"  agreeing on staying on the seat upright (facing against the true front left to "
        f"the imagination): {physical}/{len(found)} ({100.0 * physical / len(found):.1f} %)"
    )
    for predicted in (True, False):
        for seated in (True, False):
            n = sum(r.predicted_stays == predicted and r.seated == seated for r in found)
            print(
                f"  predicted {'stays' if predicted else 'falls':5s}, judge "
                f"{'seated' if seated else 'not seated':10s}: {n}"
            )
    errors = sorted(r.settle_error_m for r in found if r.seated)
    if errors:
        print(
            f"settle position error (seated bears): median {1000 * statistics.median(errors):.0f}"
            f" mm, max {1000 * errors[-1]:.0f} mm"
        )
    seconds = [r.imagination_s for r in found]
    print(
        f"release imagination: median {statistics.median(seconds):.2f} s, "
        f"max {max(seconds):.2f} s per SeatBear"
    )
    for r in found:
        if r.predicted_stays != r.seated:
            verdict = "seated" if r.seated else f"not seated ({r.reason})"
            print(
                f"  wrong: {r.run}: predicted {'stays' if r.predicted_stays else 'falls'}, "
                f"judge {verdict}"
            )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", type=Path, nargs="+", help="folders of run records")
    args = parser.parse_args(argv)
    missing = [str(f) for f in args.folders if not f.is_dir()]
    if missing:
        print(f"release_agreement: no such folder: {', '.join(missing)}", file=sys.stderr)
        return 2
    print_agreement(releases(args.folders))
    return 0


if __name__ == "__main__":
    sys.exit(main())
