"""Benchmark: SE(2) accessibility, planning time and the human-assistance loop.

Prints, for the box chair and (when ../shared/chairs exists) the calibration chairs:

* accessible placements (sitting direction within ±30 degrees of the NAO, leaving room
  to stand in front inside the arena: ``bearchair.core.arena.accessible_sitting_yaws``): how often a
  path is found and the planning times (median over the runs, max);
* inaccessible placements (sitting direction toward the arm, or toward a side edge):
  how many the arena really makes inaccessible, and with a simulated helper who turns the
  chair by the instructed angle (plus N(0, 5 deg) of human error) about its centre, how
  often it is accessible after the first rotation; and with a helper who disobeys the first
  instruction (no turn, or the wrong way), how often within three rotations. A chair that
  stays inaccessible is tried at the same spot facing the NAO straight: when that fails
  too (its seating pre-plan is infeasible there), no rotation could help, and it is listed.

The sitting pose stands in for the imagination's: the manifest's ``front_yaw_deg`` gives
γ, and p is 5 cm above the first surface straight below the chair's centre. The chair's
rotation is known exactly here (no ICP). Usage::

    .venv/bin/python bench/planning.py [--runs 20] [--trials 40] [--seed 0]
        [--x-min 0.15] [--y-half 0.75]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from collections import Counter
from pathlib import Path
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.arena import DEFAULT_ARENA, Arena, accessible_sitting_yaws
from bearchair.core.geometry import SittingPose, yaw_transform
from bearchair.core.meshes import box_chair_mesh, load_mesh
from bearchair.evaluation.protocol import SEAT_KINDS
from bearchair.skills.assistance import compose_instruction
from bearchair.skills.planning.accessibility import check_accessibility
from bearchair.skills.planning.preplan import reach_validator
from bearchair.skills.planning.seat import seat_support_heights
from bearchair.skills.results import AccessibilityResult

SHARED_CHAIRS = Path(__file__).resolve().parents[2] / "shared" / "chairs"
PELVIS_ABOVE_SEAT_M = 0.05
HELPER_ERROR_DEG = 5.0
MAX_ROTATIONS = 3


class Chair(NamedTuple):
    name: str
    mesh: trimesh.Trimesh  # chair frame: centred in x, y; lowest point z = 0
    sitting_pose: SittingPose  # chair frame


def chair_from_mesh(name: str, mesh: trimesh.Trimesh, front_yaw_deg: float) -> Chair | None:
    """The chair with a stand-in sitting pose, or None when no seat is under its centre."""
    centre = mesh.bounds.mean(axis=0)[:2]
    top = float(mesh.bounds[1, 2]) + 0.01
    # The first surface below the top at the centre, or a little toward the front.
    front = np.array([math.cos(math.radians(front_yaw_deg)), math.sin(math.radians(front_yaw_deg))])
    for shift in (0.0, 0.03, 0.06):
        xy = centre + shift * front
        seat = seat_support_heights(mesh, xy[None, :], top)[0]
        if np.isfinite(seat) and seat < 0.45:
            position = np.array([xy[0], xy[1], seat + PELVIS_ABOVE_SEAT_M])
            return Chair(name, mesh, SittingPose(position, math.radians(front_yaw_deg)))
    return None


def load_chairs() -> list[Chair]:
    """The calibration chairs that have a front, or [] when the folder is absent."""
    manifest = SHARED_CHAIRS / "manifest.json"
    if not manifest.is_file():
        return []
    chairs = []
    for entry in json.loads(manifest.read_text())["meshes"]:
        if entry.get("kind", "chair") not in SEAT_KINDS or entry["front_yaw_deg"] is None:
            continue
        chair = chair_from_mesh(
            entry["file"], load_mesh(SHARED_CHAIRS / entry["file"]), entry["front_yaw_deg"]
        )
        if chair is None:
            print(f"  skipped {entry['file']}: no seat under its centre")
        else:
            chairs.append(chair)
    return chairs


def place(
    chair: Chair, centre_xy: np.ndarray, sitting_yaw: float
) -> tuple[trimesh.Trimesh, SittingPose]:
    """The chair turned so that its sitting direction is ``sitting_yaw`` and moved to ``centre_xy``."""
    T_world_chair = yaw_transform(sitting_yaw - chair.sitting_pose.yaw, np.array([*centre_xy, 0.0]))
    return chair.mesh.copy().apply_transform(T_world_chair), chair.sitting_pose.transformed(
        T_world_chair
    )


def random_centre(rng: np.random.Generator, arena: Arena) -> np.ndarray:
    area = arena.chair_area
    return np.array([rng.uniform(area.x_min, area.x_max), rng.uniform(area.y_min, area.y_max)])


def bench_accessible(chairs: list[Chair], arena: Arena, runs: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    found, plan_s, total_s, reasons = 0, [], [], []
    for run in range(runs):
        chair = chairs[run % len(chairs)]
        centre = random_centre(rng, arena)
        yaw = float(rng.choice(accessible_sitting_yaws(arena, tuple(centre))))
        mesh, sitting = place(chair, centre, yaw)
        began = time.perf_counter()
        result = _check(mesh, sitting, arena, seed + run)
        total_s.append(time.perf_counter() - began)
        plan_s.append(result.seconds)
        found += result.accessible
        if not result.accessible:
            reasons.append(f"{chair.name}: {result.reason}")
    timed = [s for s in plan_s if s > 0.0]
    print(f"  path found: {found}/{runs}")
    if timed:
        print(
            f"  OMPL solve+simplify: median {statistics.median(timed) * 1000:.1f} ms, "
            f"max {max(timed) * 1000:.1f} ms"
        )
    print(
        f"  whole check (stance search, pre-plans, path): "
        f"median {statistics.median(total_s) * 1000:.1f} ms, max {max(total_s) * 1000:.1f} ms"
    )
    for reason in reasons[:5]:
        print(f"    not found: {reason}")


VALIDATOR: list = [None]  # None: the default (whole-body pre-plan when available)


def _check(
    mesh: trimesh.Trimesh, sitting: SittingPose, arena: Arena, seed: int
) -> AccessibilityResult:
    """check_accessibility, with an error in another module counted instead of fatal."""
    try:
        return check_accessibility(
            mesh, sitting, arena.humanoid_start, arena, seed=seed, seating_validator=VALIDATOR[0]
        )
    except Exception as error:
        return AccessibilityResult(
            False, None, sitting, (), f"error: {type(error).__name__}: {error}"
        )


def _turn_about_centre(mesh: trimesh.Trimesh, sitting: SittingPose, angle_rad: float):
    centre = mesh.bounds.mean(axis=0)
    T = yaw_transform(angle_rad, np.array([centre[0], centre[1], 0.0])) @ yaw_transform(
        0.0, -np.array([centre[0], centre[1], 0.0])
    )
    return mesh.copy().apply_transform(T), sitting.transformed(T)


def assistance_trial(
    mesh: trimesh.Trimesh,
    sitting: SittingPose,
    arena: Arena,
    rng: np.random.Generator,
    *,
    seed: int,
    disobey_first: str | None,
) -> tuple[int | None, str]:
    """Rotations until accessible (0 = already), or None after :data:`MAX_ROTATIONS`, and
    the last reason it was not accessible."""
    reason = ""
    for rotation in range(MAX_ROTATIONS + 1):
        result = _check(mesh, sitting, arena, seed)
        if result.accessible:
            return rotation, reason
        reason = result.reason
        if rotation == MAX_ROTATIONS:
            return None, reason
        instruction = compose_instruction(sitting, arena.humanoid_start)
        turn = math.radians(instruction.angle_deg) * (-1.0 if instruction.clockwise else 1.0)
        if rotation == 0 and disobey_first == "still":
            turn = 0.0
        elif rotation == 0 and disobey_first == "wrong-way":
            turn = -turn
        turn += math.radians(rng.normal(0.0, HELPER_ERROR_DEG))
        mesh, sitting = _turn_about_centre(mesh, sitting, turn)
    return None, reason


def _short(reason: str) -> str:
    return reason.split(" (")[0].split(" violated")[0][:90]


def bench_inaccessible(chairs: list[Chair], arena: Arena, trials: int, seed: int) -> None:
    rng = np.random.default_rng(seed + 1000)
    already = {"arm": 0, "edge": 0}
    needing_help, obeyed_first, disobeyed_within = 0, 0, 0
    leaks: list[str] = []
    unseatable: list[str] = []
    initial_reasons: Counter[str] = Counter()
    failure_reasons: Counter[str] = Counter()
    for trial in range(trials):
        chair = chairs[trial % len(chairs)]
        centre = random_centre(rng, arena)
        # Toward the arm (-x) in even trials, toward the nearer side edge (±y) in odd ones.
        kind = "arm" if trial % 2 == 0 else "edge"
        base = math.pi if kind == "arm" else math.copysign(math.pi / 2, centre[1])
        yaw = base + math.radians(rng.uniform(-30.0, 30.0))
        mesh, sitting = place(chair, centre, yaw)
        trial_rng = np.random.default_rng(seed + trial)
        obeyed, reason = assistance_trial(
            mesh, sitting, arena, trial_rng, seed=seed + trial, disobey_first=None
        )
        if obeyed == 0:
            already[kind] += 1
            leaks.append(
                f"{chair.name} at ({centre[0]:.2f}, {centre[1]:.2f}) facing {math.degrees(yaw):.0f} deg"
            )
            continue
        needing_help += 1
        initial = _check(mesh, sitting, arena, seed)
        initial_reasons[_short(initial.reason)] += 1
        obeyed_first += obeyed == 1
        if obeyed != 1:
            failure_reasons[f"{chair.name}: {_short(reason)}"] += 1
        mode = "still" if trial % 4 < 2 else "wrong-way"
        disobeyed, last_reason = assistance_trial(
            mesh, sitting, arena, trial_rng, seed=seed + trial, disobey_first=mode
        )
        disobeyed_within += disobeyed is not None
        if disobeyed is None:
            failure_reasons[f"{chair.name} ({mode} first): {_short(last_reason)}"] += 1
        if obeyed != 1 or disobeyed is None:
            # Would any orientation do? Facing the NAO straight from the same spot.
            toward = math.atan2(
                arena.humanoid_start.y - centre[1], arena.humanoid_start.x - centre[0]
            )
            facing = _check(*place(chair, centre, toward), arena, seed)
            if not facing.accessible:
                unseatable.append(
                    f"{chair.name} at ({centre[0]:.2f}, {centre[1]:.2f}): {_short(facing.reason)}"
                )
    arm_trials = (trials + 1) // 2
    print(
        f"  accessible without help although facing the arm: {already['arm']}/{arm_trials}, "
        f"facing the nearer side edge: {already['edge']}/{trials - arm_trials}"
    )
    for leak in leaks[:6]:
        print(f"    {leak}")
    if needing_help:
        print(
            f"  obeying helper, accessible after the first rotation: {obeyed_first}/{needing_help}"
            f" ({100.0 * obeyed_first / needing_help:.0f}%)"
        )
        print(
            f"  helper disobeys once, accessible within {MAX_ROTATIONS} rotations: "
            f"{disobeyed_within}/{needing_help} ({100.0 * disobeyed_within / needing_help:.0f}%)"
        )
        for line in unseatable:
            print(f"    not accessible facing the NAO either (no rotation can help): {line}")
        print(f"  why they were inaccessible at first: {dict(initial_reasons)}")
        if failure_reasons:
            print(
                f"  why not accessible (after the first rotation; within 3): {dict(failure_reasons)}"
            )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="accessible placements per set")
    parser.add_argument("--trials", type=int, default=40, help="inaccessible placements per set")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--x-min", type=float, default=DEFAULT_ARENA.x_min, help="arena back wall, m"
    )
    parser.add_argument(
        "--y-half", type=float, default=DEFAULT_ARENA.y_max, help="arena half width, m"
    )
    parser.add_argument(
        "--validator",
        choices=("default", "reach"),
        default="default",
        help="seat pre-plan: the whole-body planner when available, or the arm-reach model",
    )
    args = parser.parse_args(argv)
    VALIDATOR[0] = reach_validator if args.validator == "reach" else None
    print(f"validator: {args.validator}")
    arena = DEFAULT_ARENA._replace(x_min=args.x_min, y_min=-args.y_half, y_max=args.y_half)
    print(
        f"arena x [{arena.x_min}, {arena.x_max}] y [{arena.y_min}, {arena.y_max}]; timings on a shared machine"
    )

    box = chair_from_mesh("box-chair", box_chair_mesh(), 0.0)
    print("box chair, accessible placements:")
    bench_accessible([box], arena, args.runs, args.seed)
    print("box chair, inaccessible placements:")
    bench_inaccessible([box], arena, args.trials, args.seed)

    chairs = load_chairs()
    if not chairs:
        print(f"calibration chairs not found at {SHARED_CHAIRS}: skipped")
        return 0
    print(f"calibration chairs ({len(chairs)}), accessible placements:")
    bench_accessible(chairs, arena, args.runs, args.seed)
    print(f"calibration chairs ({len(chairs)}), inaccessible placements:")
    bench_inaccessible(chairs, arena, args.trials, args.seed)
    return 0


if __name__ == "__main__":
    sys.exit(main())
