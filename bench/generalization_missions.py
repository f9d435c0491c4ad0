"""Whole simulated missions over generated chairs: ``bench/generalization.py --missions N``.

Chair i of ``bearchair.testing.chairgen.generate_chairs(N, seed)`` (the families in
turn) is written as an OBJ beside a manifest (front +x, as generated) and gets the
paper's condition i mod 6 (3 accessible, 2 inaccessible with a helper who obeys, 1 who
disobeys): every stage, the release and the judge, one trial subprocess each, through
the trials harness (``bearchair.evaluation``; records in ``OUT/trials.sqlite``, run
records in ``OUT/runs``, a rerun with the same ``--out`` skips what is done). Prints
seating per family, per condition and per cause, the refused chairs with their reasons
(against the reach model: a chair is inside the NAO's workspace when the reach check
passes on its true mesh and sitting pose), and the release prediction's agreement.
"""

from __future__ import annotations

import json
import sys
from collections import Counter, defaultdict
from pathlib import Path

from bearchair.evaluation.protocol import (
    EXPERIMENT_SETTINGS,
    PROTOCOLS,
    TrialSpec,
    trial_seed,
)
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.testing.chairgen import GeneratedChair, generate_chairs


def mission_specs(chairs: list[GeneratedChair], folder: Path, seed: int) -> list[TrialSpec]:
    """Writes the chairs and their manifest to ``folder``; one trial per chair, the paper's
    conditions in rotation."""
    folder.mkdir(parents=True, exist_ok=True)
    entries, specs = [], []
    conditions = PROTOCOLS["paper"]
    for number, chair in enumerate(chairs):
        path = folder / f"{chair.name}.obj"
        if not path.exists():
            chair.mesh.export(path)
        front = None if chair.front_yaw_rad is None else 0.0
        entries.append({"file": path.name, "kind": "chair", "front_yaw_deg": front})
        index = number % len(conditions)
        placement, helper = EXPERIMENT_SETTINGS[conditions[index]]
        specs.append(
            TrialSpec(
                chair=path.name,
                chair_path=path,
                trial_index=index,
                experiment=conditions[index],
                placement=placement,
                helper=helper,
                seed=trial_seed(seed, path.name, index),
            )
        )
    (folder / "manifest.json").write_text(json.dumps({"meshes": entries}, indent=1))
    return specs


def run_missions(
    count: int,
    seed: int,
    workers: int,
    out: Path,
    timeout_s: float,
    families: list[str] | None = None,
    names: list[str] | None = None,
) -> int:
    """Runs the missions and prints the figures; returns the exit status. With
    ``families``, only their chairs among the ``count`` generated (the same chairs, seeds
    and conditions as the whole bench's); with ``names``, only chairs whose name contains
    one of them (``armchair-0163``)."""
    chairs = [c for c in generate_chairs(count, seed) if c.front_yaw_rad is not None]
    specs = mission_specs(chairs, out / "chairs", seed)
    if families or names:
        kept = {
            c.name + ".obj"
            for c in chairs
            if (not families or c.family in families)
            and (not names or any(n in c.name for n in names))
        }
        chairs = [c for c in chairs if c.name + ".obj" in kept]
        specs = [s for s in specs if s.chair in kept]
    print(
        f"{len(specs)} missions over {len(chairs)} generated chairs with a front "
        f"(of {count}); records in {out}",
        file=sys.stderr,
    )
    return run_specs(specs, chairs, workers, out, timeout_s)


def run_specs(
    specs: list[TrialSpec], chairs: list[GeneratedChair], workers: int, out: Path, timeout_s: float
) -> int:
    """Runs the missions of ``specs`` (:func:`mission_specs`) over ``chairs``, records in
    ``out``, and prints the figures; returns the exit status."""
    from bearchair.evaluation.campaign import run_campaign
    from bearchair.evaluation.campaign_progress import Progress
    from bearchair.evaluation.store import TrialStore, campaign_lock
    from bearchair.evaluation.trial_backends import LocalBackend

    db = out / "trials.sqlite"
    with campaign_lock(db), TrialStore(db) as store:
        done = len(store.finished_keys() & {s.key for s in specs})
        result = run_campaign(
            specs,
            store,
            LocalBackend(workers, timeout_s),
            out / "runs",
            timeout_s,
            progress=Progress(len(specs), done),
        )
        records = store.records(specs)
    if result.interrupted:
        print(f"interrupted: {len(records)} of {len(specs)} recorded; rerun to resume")
        return 130
    by_chair = {c.name + ".obj": c for c in chairs}
    print_missions(records, by_chair, chairs)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from release_agreement import print_agreement, releases

    print()
    print_agreement(releases([out / "runs"]))
    return 0


def print_missions(
    records: list[TrialRecord],
    by_chair: dict[str, GeneratedChair],
    chairs: list[GeneratedChair],
) -> None:
    """Seating per family, per condition and per cause; the refusals with the reach check."""
    from bearchair.evaluation.ground_truth_report import (
        TOUCH_DEPTHS_CM,
        nao_into_chair,
        palms_apart,
        palms_lines,
        touch_lines,
    )
    from bearchair.evaluation.report import failure_cause, failure_kind, refusal

    outside_reason = _inside_workspace(chairs)
    inside = {name: not reason for name, reason in outside_reason.items()}
    rows: dict[str, list[bool]] = defaultdict(list)
    conditions: dict[str, list[bool]] = defaultdict(list)
    causes: Counter[str] = Counter()
    refused = []
    for record in records:
        chair = by_chair[record.chair]
        seated = record.succeeded
        if inside[chair.name]:
            rows[chair.family].append(seated)
            conditions[record.experiment].append(seated)
        if not seated:
            cause = failure_cause(record)
            causes[failure_kind(cause)] += 1
            if record.failed_stage == "CheckSeatReachable" or refusal(record):
                refused.append((chair, cause, inside[chair.name]))
    total = [s for values in rows.values() for s in values]
    print(
        f"\nseated, chairs inside the NAO's workspace: {sum(total)}/{len(total)} "
        f"({_percent(sum(total), len(total))})"
    )
    print(f"{'family':14s} {'seated':>8s}")
    for family, values in sorted(rows.items()):
        print(
            f"{family:14s} {sum(values):>3d}/{len(values):<4d} {_percent(sum(values), len(values))}"
        )
    for condition, values in sorted(conditions.items()):
        print(f"  {condition:22s} {sum(values)}/{len(values)}")
    print("\nfailures by cause (numbers replaced by #):")
    for cause, n in causes.most_common():
        print(f"  {n:3d} x {cause}")
    touches = nao_into_chair(records)
    if touches is not None:
        print()
        print("\n".join(touch_lines(touches)))
        shallowest = TOUCH_DEPTHS_CM[0]
        families = Counter(
            by_chair[r.chair].family for r in records if (r.nao_into_chair_cm or 0.0) > shallowest
        )
        if families:
            print(
                f"  deeper than {shallowest:g} cm, by family: "
                + ", ".join(f"{family} {n}" for family, n in families.most_common())
            )
    palms = palms_apart(records)
    if palms is not None:
        print("\n".join(palms_lines(palms)))
    outside = [c for c in chairs if not inside[c.name]]
    verdicts: Counter[str] = Counter()
    lines = []
    for chair in outside:
        mission = next(r for r in records if r.chair == chair.name + ".obj")
        verdict = _outside_verdict(mission)
        verdicts[verdict.split(" at ")[0]] += 1
        lines.append((chair, verdict))
    counts = ", ".join(f"{kind} {n}" for kind, n in sorted(verdicts.items()))
    print(
        f"\nchairs outside the workspace (reach check on the true chair): {len(outside)}"
        + (f" ({counts})" if counts else "")
    )
    for chair, verdict in lines:
        print(
            f"  {chair.name} (seat {chair.seat_height_m:.3f} m): {outside_reason[chair.name]};"
            f" the mission: {verdict}"
        )
    print("refused by the mission:")
    for chair, cause, was_inside in refused:
        note = "" if not was_inside else " (the true chair passes the reach check)"
        print(f"  refused {chair.name} (seat {chair.seat_height_m:.3f} m){note}: {cause}")


def _outside_verdict(mission: TrialRecord) -> str:
    """What a mission did on a chair outside the workspace: refused (right), seated (the
    check on the true chair, with p over the seat's middle, is stricter than the mission,
    which may seat the bear elsewhere on the seat), or failed at another stage, unrefused.
    ``CheckSeatReachable`` failing counts as refused (a scan that cannot tell gives its
    reason too), as does a refusal where no sitting was imagined."""
    from bearchair.evaluation.report import refusal

    if mission.succeeded:
        return "seated"
    if mission.failed_stage == "CheckSeatReachable" or refusal(mission):
        return "refused"
    return f"NOT refused: failed at {mission.failed_stage}"


def _inside_workspace(chairs: list[GeneratedChair]) -> dict[str, str]:
    """Chair name -> "" when the reach check passes on its true mesh and sitting pose,
    else its reason."""
    from generalization import ground_truth_pose

    from bearchair.skills.planning.stance import check_seat_reachable

    out = {}
    for chair in chairs:
        reach = check_seat_reachable(chair.mesh, ground_truth_pose(chair))
        out[chair.name] = "" if reach.reachable else reach.reason or "unreachable"
    return out


def _percent(part: int, whole: int) -> str:
    return f"{100.0 * part / whole:.1f} %" if whole else "-"
