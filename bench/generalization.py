"""Benchmark: does the mission's planning generalise to chairs it has never seen?

Generates chairs (``bearchair.testing.chairgen``: every family, seeded) and, for each, runs the
stages that decide whether the bear can be seated, without a whole mission:

1. imagination (``--imagine``): the sitting pose from drops of the virtual child; its
   direction must be within 30 deg of the chair's true front (chairs without a front
   pass on any direction). Without ``--imagine`` the sitting pose is the ground truth's:
   p over the seat's middle, 5 cm above it, facing the front;
2. the reach check right after imagination: a refused chair is counted as refused,
   with its reason, and compared with the reach model (a refusal is right when the
   model has no stance for the seat);
3. accessibility in an accessible placement of the arena (chair centre and sitting
   direction drawn as the simulated world draws them), which includes the whole-body
   seating pre-plan at s_goal;
4. with ``--seat``, seating in the simulated world (``bench/wholebody.py``'s run: the
   NAO placed where the stance search puts it with the chair alone, the motion planned
   and played, the bear released and judged).

Prints the success rate per stage and per family, the refusals with their reasons, and
the worst families. Usage::

    .venv/bin/python bench/generalization.py [--chairs 200] [--seed 0] [--imagine]
        [--seat] [--family sled] [--workers 2] [--verbose]
    .venv/bin/python bench/generalization.py --calibration 24
    .venv/bin/python bench/generalization.py --missions 200 [--workers 2] [--out DIR]
        [--family basket --family x_frame]

``--missions N`` runs whole simulated missions instead (``bench/generalization_missions.py``).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import multiprocessing
import statistics
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path
from typing import NamedTuple

import numpy as np

from bearchair.core.arena import DEFAULT_ARENA, accessible_sitting_yaws
from bearchair.core.geometry import SittingPose, wrap_angle, yaw_transform
from bearchair.skills.planning.accessibility import check_accessibility
from bearchair.skills.planning.stance import check_seat_reachable
from bearchair.testing.chairgen import FAMILIES, GeneratedChair, generate_chair

PELVIS_ABOVE_SEAT_M = 0.05
DIRECTION_TOLERANCE_DEG = 30.0


class Outcome(NamedTuple):
    chair: GeneratedChair
    imagined: bool  # direction within tolerance (True without --imagine)
    refused: str  # the reach check's reason ("" when not refused)
    accessible: bool
    reason: str
    seconds: float  # the accessibility check's wall time
    seated: bool | None = None  # with --seat: the judge's verdict in the simulated world
    in_workspace: bool = True  # the reach check passes on the true mesh and sitting pose


def ground_truth_pose(chair: GeneratedChair) -> SittingPose:
    """p over the middle of the seat, 5 cm above it, facing the front (+x)."""
    x = chair.seat_front_x_m - chair.seat_depth_m / 2.0
    return SittingPose(np.array([x, 0.0, chair.seat_height_m + PELVIS_ABOVE_SEAT_M]), 0.0)


def imagined_pose(
    chair: GeneratedChair, seed: int, workers: int = 2
) -> tuple[SittingPose | None, bool]:
    """The imagined sitting pose, and whether its direction is within the tolerance
    (``workers``: the imagination's processes; a seed gives the same pose for any)."""
    from bearchair.skills.imagination import imagine_sitting

    result = imagine_sitting(chair.mesh, seed=seed, workers=workers)
    pose = result.sitting_pose
    if pose is None:
        return None, False
    if chair.front_yaw_rad is None:
        return pose, True
    error = abs(math.degrees(wrap_angle(pose.yaw - chair.front_yaw_rad)))
    return pose, error <= DIRECTION_TOLERANCE_DEG


def seat_in_simulation(chair: GeneratedChair, seed: int) -> tuple[bool, str]:
    """bench/wholebody.py's simulated seating on the chair (exported to a scratch OBJ)."""
    import tempfile

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from wholebody import sim_run

    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / f"{chair.name}.obj"
        chair.mesh.export(path)
        return sim_run(path, 0.0, seed)


def run_chair(
    chair: GeneratedChair, seed: int, imagine: bool, seat: bool = False, workers: int = 2
) -> Outcome:
    outcome = _run_stages(chair, seed, imagine, seat, workers)
    truth = check_seat_reachable(chair.mesh, ground_truth_pose(chair))
    return outcome._replace(in_workspace=truth.reachable)


def _run_stages(
    chair: GeneratedChair, seed: int, imagine: bool, seat: bool, workers: int
) -> Outcome:
    rng = np.random.default_rng(seed)
    if imagine:
        sitting, direction_ok = imagined_pose(chair, seed, workers)
        if sitting is None:
            return Outcome(chair, False, "", False, "imagination found no sitting pose", 0.0)
    else:
        sitting, direction_ok = ground_truth_pose(chair), True
    verdict = check_seat_reachable(chair.mesh, sitting)
    if not verdict.reachable:
        return Outcome(chair, direction_ok, verdict.reason, False, verdict.reason, 0.0)
    arena = DEFAULT_ARENA
    area = arena.chair_area
    centre = (rng.uniform(area.x_min, area.x_max), rng.uniform(area.y_min, area.y_max))
    yaw = float(rng.choice(accessible_sitting_yaws(arena, centre)))
    T_world_chair = yaw_transform(yaw - sitting.yaw, np.array([*centre, 0.0]))
    mesh = chair.mesh.copy().apply_transform(T_world_chair)
    placed = sitting.transformed(T_world_chair)
    began = time.perf_counter()
    result = check_accessibility(mesh, placed, arena.humanoid_start, arena, seed=seed)
    seconds = time.perf_counter() - began
    outcome = Outcome(chair, direction_ok, "", result.accessible, result.reason, seconds)
    if seat and result.accessible:
        seated, description = seat_in_simulation(chair, seed)
        outcome = outcome._replace(seated=seated, reason="" if seated else description)
    return outcome


def _percent(part: int, whole: int) -> str:
    return f"{part}/{whole} ({100.0 * part / whole:.0f}%)" if whole else "0/0"


def workspace_split(outcomes: list[Outcome]) -> None:
    """Chairs within the NAO's workspace must pass; the others must be stopped with a
    reason (refused, or no sitting imagined on them). Within the workspace: the reach
    check (the reach model and the stance search, chair alone) passes on the true mesh
    with the true sitting pose, so the seat's height, depth and what stands in front
    of it (footrests, bases) all count."""
    inside = [o for o in outcomes if o.in_workspace]
    beyond = [o for o in outcomes if not o.in_workspace]
    passed = [o for o in inside if o.imagined and o.accessible]
    print(
        f"within the workspace (true seat reachable): {len(inside)} chairs, pass "
        f"{_percent(len(passed), len(inside))}, refused {sum(bool(o.refused) for o in inside)}"
    )
    for family in FAMILIES:
        group = [o for o in inside if o.chair.family == family]
        if group:
            ok = sum(o.imagined and o.accessible for o in group)
            print(f"  {family:<11} {_percent(ok, len(group))}")
    for o in inside:
        if not (o.imagined and o.accessible):
            why = o.reason or "direction more than 30 deg off the front"
            print(
                f"    failed {o.chair.name} (seat {o.chair.seat_height_m:.2f} m high, "
                f"{o.chair.seat_depth_m:.2f} m deep): {why[:150]}"
            )
    stopped = [o for o in beyond if not o.accessible and o.reason]
    print(
        f"beyond the workspace: {len(beyond)} chairs, stopped with a reason "
        f"{_percent(len(stopped), len(beyond))} (refused {sum(bool(o.refused) for o in beyond)})"
    )


def report(outcomes: list[Outcome]) -> None:
    workspace_split(outcomes)
    by_family: dict[str, list[Outcome]] = defaultdict(list)
    for outcome in outcomes:
        by_family[outcome.chair.family].append(outcome)
    print(
        f"{'family':<11} {'chairs':>6} {'direction':>10} {'refused':>8} {'accessible':>11} {'pass (not refused)':>19}"
    )
    worst: list[tuple[float, str]] = []
    for family in FAMILIES:
        group = by_family.get(family, [])
        if not group:
            continue
        kept = [o for o in group if not o.refused]
        passed = [o for o in kept if o.imagined and o.accessible]
        rate = len(passed) / len(kept) if kept else 1.0
        worst.append((rate, family))
        print(
            f"{family:<11} {len(group):>6} {sum(o.imagined for o in group):>10} "
            f"{sum(bool(o.refused) for o in group):>8} {sum(o.accessible for o in group):>11} "
            f"{_percent(len(passed), len(kept)):>19}"
        )
    kept = [o for o in outcomes if not o.refused]
    passed = [o for o in kept if o.imagined and o.accessible]
    print(
        f"all: {len(outcomes)} chairs, refused {sum(bool(o.refused) for o in outcomes)}, "
        f"pass among the rest {_percent(len(passed), len(kept))}"
    )
    print("worst families: " + ", ".join(f"{f} {100 * r:.0f}%" for r, f in sorted(worst)[:3]))
    timed = [o.seconds for o in outcomes if o.seconds > 0]
    if timed:
        print(
            f"accessibility check: median {statistics.median(timed):.2f} s, max {max(timed):.2f} s"
        )
    refusals = Counter(o.refused.split(":")[0] for o in outcomes if o.refused)
    print(f"refusals: {dict(refusals)}")
    judged = [o for o in outcomes if o.seated is not None]
    if judged:
        seated = Counter(o.chair.family for o in judged if o.seated)
        print(
            f"seated in simulation: {_percent(sum(o.seated for o in judged), len(judged))} of "
            "the accessible chairs; by family: "
            + ", ".join(
                f"{f} {seated[f]}/{sum(o.chair.family == f for o in judged)}" for f in FAMILIES
            )
        )
        for o in judged:
            if not o.seated:
                print(f"  not seated {o.chair.name}: {o.reason[:160]}")
    for o in outcomes:
        if o.refused:
            print(
                f"  refused {o.chair.name}: seat {o.chair.seat_height_m:.2f} m high, "
                f"{o.chair.seat_depth_m:.2f} m deep: {o.refused}"
            )
    failures = Counter(
        f"{o.chair.family}: {o.reason.split(' (')[0][:100]}" for o in kept if not o.accessible
    )
    for reason, count in failures.most_common(12):
        print(f"  not accessible x{count}: {reason}")
    wrong = [o.chair.name for o in outcomes if not o.imagined]
    if wrong:
        print(f"  direction wrong: {', '.join(wrong)}")


def calibration_reach(limit: int | None) -> None:
    """The reach check on the calibration chairs with a front (``../shared/chairs``), with
    bench/planning.py's stand-in sitting pose: which would be refused, and why."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from planning import load_chairs

    from bearchair.skills.planning.seat import seat_ray

    chairs = load_chairs()[:limit]
    if not chairs:
        print("calibration chairs not found (../shared/chairs): skipped")
        return
    refused = 0
    for chair in chairs:
        verdict = check_seat_reachable(chair.mesh, chair.sitting_pose)
        ray = seat_ray(chair.mesh, chair.sitting_pose)
        room = float(ray.slides_m[-1]) if len(ray.slides_m) else float("nan")
        refused += not verdict.reachable
        print(
            f"  {chair.name:<24} seat {verdict.seat_height_m:.2f} m, p may slide {room:.2f} m: "
            + ("reachable" if verdict.reachable else f"REFUSED: {verdict.reason}"),
            flush=True,
        )
    print(f"calibration chairs refused: {refused}/{len(chairs)}")


def _run_job(job: tuple[int, str, argparse.Namespace]) -> Outcome:
    seed, family, args = job
    # The bench's own processes take the cores: each imagination runs in its process.
    workers = 1 if args.workers > 1 else 2
    return run_chair(generate_chair(seed, family), seed, args.imagine, args.seat, workers)


def _status_line(outcome: Outcome) -> str:
    chair = outcome.chair
    status = "refused" if outcome.refused else ("ok" if outcome.accessible else "FAIL")
    status += "" if outcome.in_workspace else " (beyond the workspace)"
    if outcome.seated is not None:
        status += ", seated" if outcome.seated else ", NOT SEATED"
    return (
        f"{chair.name}: seat {chair.seat_height_m:.2f} h {chair.seat_depth_m:.2f} d "
        f"{status} {outcome.reason[:140]}"
    )


@contextlib.contextmanager
def _pool(workers: int):
    """``map`` over the jobs in order: in this process, or in ``workers`` processes."""
    if workers <= 1:
        yield map
        return
    with multiprocessing.get_context("spawn").Pool(workers) as pool:
        yield lambda function, jobs: pool.imap(function, jobs)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chairs", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--imagine", action="store_true", help="imagine the sitting pose")
    parser.add_argument("--seat", action="store_true", help="seat the bear in simulation")
    parser.add_argument(
        "--family",
        choices=FAMILIES,
        action="append",
        help="only this family (repeat for several); with --missions, that family's chairs "
        "among the N generated, the same chairs as the whole bench's",
    )
    parser.add_argument(
        "--only",
        default="",
        help="--missions: only chairs whose name contains one of these (comma-separated, "
        "e.g. armchair-0163,x_frame-0045), the same seeds and conditions as the whole bench's",
    )
    parser.add_argument("--verbose", action="store_true", help="a line per chair")
    parser.add_argument("--workers", type=int, default=1, help="processes (chairs are independent)")
    parser.add_argument(
        "--calibration",
        type=int,
        metavar="N",
        help="instead: the reach check on the first N calibration chairs with a front",
    )
    parser.add_argument(
        "--missions",
        type=int,
        metavar="N",
        help="instead: whole simulated missions over N generated chairs (the paper's six "
        "conditions in rotation)",
    )
    parser.add_argument(
        "--out", type=Path, default=Path("generalization-missions"), help="--missions' records"
    )
    parser.add_argument("--timeout", type=float, default=300.0, help="--missions: s per mission")
    args = parser.parse_args(argv)
    if args.missions:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from generalization_missions import run_missions

        names = [n for n in args.only.split(",") if n]
        return run_missions(
            args.missions, args.seed, args.workers, args.out, args.timeout, args.family, names
        )
    if args.calibration:
        calibration_reach(args.calibration)
        return 0
    families = tuple(args.family) if args.family else FAMILIES
    jobs = [(args.seed + i, families[i % len(families)], args) for i in range(args.chairs)]
    outcomes = []
    began = time.perf_counter()
    with _pool(args.workers) as pool:
        for outcome in pool(_run_job, jobs):
            outcomes.append(outcome)
            if args.verbose:
                print(_status_line(outcome), flush=True)
            elif len(outcomes) % 20 == 0:
                print(
                    f"  {len(outcomes)}/{args.chairs} chairs, {time.perf_counter() - began:.0f} s",
                    file=sys.stderr,
                )
    report(outcomes)
    return 0


if __name__ == "__main__":
    sys.exit(main())
