"""Whole-body seating figures: solve times, and seating success in the simulated world.

    python bench/wholebody.py                  # solve times over chairs and stances
    python bench/wholebody.py --sim --runs 10  # plan, execute, release, judge (box chair)
    python bench/wholebody.py --sim --calibration --runs 20
    python bench/wholebody.py --walk-error     # plans where the walk may stop, per chair

Solve times: the box chair and the calibration chairs (../shared/chairs, skipped when
absent) with the sitting pose at their true seat (above the area centroid of the mesh's
largest horizontal surface, 2 cm over the chair's top there: a cushion counts), the NAO
facing it on the sitting ray at stances 0.22 to 0.36 m. Prints the median and spread of
the goal posture, trajectory and retract solve times and the feasible stances.

Walk error: for each calibration chair (true mesh, sitting pose at its true seat) the
stance the mission's search chooses, then the plan from the 8 corners of the walk's stop
box around it (``WalkGains.stop_tolerance_m`` forward and sideways, ``stop_tolerance_rad``
in heading): the search accepts s_goal for a plan made where the NAO really stops, and
every corner should plan. Prints the chairs where some corner fails, with the failures.

Simulation: the chair is placed 0.5 m in front of the NAO's start pose (sitting
direction toward the NAO) and settles; the NAO is placed (``SimWorld.place_nao``) at the
stance the mission's stance search chooses (reach model, then the pre-plan, p sliding
along the seat); the plan is played through
``SimNao.play_joint_trajectory``, the bear released and the judge asked (the simulator
hands the bear over facing the NAO, as in the paper).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose, make_transform, rot_z, wrap_angle
from bearchair.core.meshes import box_chair_mesh, load_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.evaluation.protocol import SEAT_KINDS
from bearchair.skills.planning.collision import NaoCollisionChecker, chair_solid_boxes
from bearchair.skills.planning.preplan import wholebody_validator
from bearchair.skills.planning.seat import seat_support_heights
from bearchair.skills.planning.stance import choose_stance, open_floor_arena
from bearchair.skills.planning.wholebody import InfeasibleSeating, plan_seating, preplan_seating
from bearchair.skills.planning.wholebody.chair_profile import (
    HORIZONTAL_NORMAL_Z,
    largest_horizontal_surface_height,
)

CHAIRS_DIR = Path(__file__).resolve().parents[2] / "shared" / "chairs"
STANCES_M = (0.22, 0.24, 0.26, 0.28, 0.30, 0.32, 0.34, 0.36)


def true_seat_point(chair_mesh: trimesh.Trimesh) -> np.ndarray:
    """Where a sitter rests: above the seat's area centroid, 2 cm over the seat's top.

    The seat is the largest horizontal surface; its area centroid gives (x, y). The height
    is the highest chair surface straight below that point (a cushion or a dished seat
    rises above the seat's largest flat part), found within 8 cm above that part so that
    nothing overhanging (a backrest's top) counts.
    """
    seat_z = largest_horizontal_surface_height(chair_mesh)
    up = chair_mesh.face_normals[:, 2] >= HORIZONTAL_NORMAL_Z
    centres = chair_mesh.triangles_center
    on_seat = up & (np.abs(centres[:, 2] - seat_z) <= 0.01)
    xy = np.average(centres[on_seat, :2], axis=0, weights=chair_mesh.area_faces[on_seat])
    top = seat_support_heights(chair_mesh, xy[None, :], seat_z + 0.08)[0]
    return np.array([xy[0], xy[1], (seat_z if np.isnan(top) else max(top, seat_z)) + 0.02])


def calibration_chairs() -> list[tuple[str, Path, float]]:
    """(name, path, front yaw in degrees) of the calibration chairs with a known front."""
    manifest = CHAIRS_DIR / "manifest.json"
    if not manifest.exists():
        return []
    entries = json.loads(manifest.read_text())["meshes"]
    return [
        (entry["file"], CHAIRS_DIR / entry["file"], float(entry["front_yaw_deg"]))
        for entry in entries
        if entry.get("kind", "chair") in SEAT_KINDS and entry["front_yaw_deg"] is not None
    ]


def stance_pose(sitting_pose: SittingPose, distance_m: float) -> SE2Pose:
    """The NAO on the sitting ray, ``distance_m`` from p, facing the chair."""
    x, y = sitting_pose.position[:2] + distance_m * sitting_pose.direction()
    return SE2Pose(float(x), float(y), wrap_angle(sitting_pose.yaw + math.pi))


def solve_times(chairs: list[tuple[str, trimesh.Trimesh, float]]) -> None:
    """Prints solve-time statistics and feasible stances per chair."""
    goal_s: list[float] = []
    trajectory_s: list[float] = []
    retract_s: list[float] = []
    together: list[float] = []
    failures: dict[str, int] = {}
    for name, mesh, front_yaw_deg in chairs:
        sitting_pose = SittingPose(true_seat_point(mesh), math.radians(front_yaw_deg))
        feasible = []
        for distance in STANCES_M:
            try:
                plan = preplan_seating(mesh, sitting_pose, stance_pose(sitting_pose, distance))
            except InfeasibleSeating as error:
                failures[error.constraint] = failures.get(error.constraint, 0) + 1
                continue
            feasible.append(distance)
            goal_s.append(plan.seconds["goal"])
            trajectory_s.append(plan.seconds["trajectory"])
            retract_s.append(plan.seconds["retract"])
            together.append(plan.seconds["goal"] + plan.seconds["trajectory"])
        stances = ", ".join(f"{d:.2f}" for d in feasible) or "none"
        print(
            f"  {name:24s} seat {sitting_pose.position[2] - 0.02:.3f} m  feasible stances: {stances}"
        )
    if not together:
        print("no feasible plan")
        return

    def stats(values: list[float]) -> str:
        q = np.percentile(values, [10, 50, 90])
        return f"median {q[1]:.3f} s (p10 {q[0]:.3f}, p90 {q[2]:.3f}, max {max(values):.3f})"

    print(f"plans: {len(together)} feasible, {sum(failures.values())} infeasible {failures}")
    print(f"goal posture: {stats(goal_s)}")
    print(f"trajectory:   {stats(trajectory_s)}")
    print(f"retract:      {stats(retract_s)}")
    print(f"goal + trajectory: {stats(together)} (target: median <= 1 s)")


def feasible_stance(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose
) -> tuple[SE2Pose, SittingPose, SE2Pose | None] | None:
    """The stance, sitting point and raising pose (None: no raise) the mission's search
    chooses with the chair alone (:func:`bearchair.skills.planning.stance.choose_stance`: reach
    model, then the pre-plan)."""
    checker = NaoCollisionChecker(open_floor_arena(chair_mesh), chair_solid_boxes(chair_mesh))
    choice = choose_stance(chair_mesh, sitting_pose, checker, wholebody_validator, scene=False)
    if choice.se2_goal is None:
        return None
    return choice.se2_goal, choice.sitting_pose, choice.check.raise_at


def sim_run(chair_path: Path | None, front_yaw_deg: float, seed: int) -> tuple[bool, str]:
    """One simulated seating: returns (seated, description).

    The chair stands 0.5 m in front of the NAO's start, its sitting direction toward the
    NAO, and settles; the NAO is then placed at the stance the mission's search chooses
    (with a lateral error of up to 2 cm; first where it raises the bear, when the search
    says so), plans from its own pose, plays the motion, releases the bear, stands up and
    the judge decides.
    """
    from bearchair.hardware.sim.world import SimConfig, SimWorld
    from bearchair.skills.planning.wholebody import execute_seating, raise_bear, release_and_stand

    config = SimConfig(
        chair_path=chair_path,
        seed=seed,
        camera_noise=False,
        front_yaw_deg=None if chair_path is None else front_yaw_deg,
    )
    with SimWorld(config) as world:
        nao_pose = world.nao.true_pose()
        sitting_yaw = wrap_angle(nao_pose.theta + math.pi)
        chair_yaw = wrap_angle(sitting_yaw - math.radians(front_yaw_deg))
        T = make_transform(rot_z(chair_yaw), np.array([nao_pose.x - 0.5, nao_pose.y, 0.0]))
        T[2, 3] = world.chair.T_world_chair()[2, 3]
        world.chair.set_T_world_chair(T)
        world.clock.sleep(0.3)
        chair_mesh = world.chair_mesh_true
        rng = np.random.default_rng(seed)
        lateral = rng.uniform(-0.02, 0.02)
        found = feasible_stance(chair_mesh, SittingPose(true_seat_point(chair_mesh), sitting_yaw))
        if found is None:
            return False, "no feasible stance"
        stance, sitting_pose, raise_at = found
        distance = stance.distance_to(stance_pose(sitting_pose, 0.0))
        side = np.array([-math.sin(stance.theta), math.cos(stance.theta)])

        def place(pose: SE2Pose) -> None:
            world.place_nao(SE2Pose(*(np.array([pose.x, pose.y]) + lateral * side), pose.theta))
            world.clock.sleep(0.2)

        if raise_at is not None:
            place(raise_at)
            raise_bear(world.nao, chair_mesh, sitting_pose, world.nao.pose())
        place(stance)
        plan = plan_seating(chair_mesh, sitting_pose, world.nao.pose(), raised=raise_at is not None)
        execute_seating(world.nao, plan)
        release_and_stand(world.nao, plan)
        verdict = world.judge.judge(sitting_yaw)
        bear = world.bear.T_world_bear()[:3, 3]
        slid = np.linalg.norm(sitting_pose.position[:2] - true_seat_point(chair_mesh)[:2])
        return verdict.seated, (
            f"stance {distance:.2f} m, p slid {slid:.2f} m, tilt {verdict.torso_tilt_deg:.0f} "
            f"deg, facing {verdict.facing_error_deg:.0f} deg, bear at height {bear[2]:.3f} m"
            + (f" ({verdict.reason})" if verdict.reason else "")
        )


def walk_error(chairs: list[tuple[str, trimesh.Trimesh, float]]) -> None:
    """Prints, per chair, the stop-box corners from which the seating does not plan."""
    from bearchair.skills.control.walk import WalkGains
    from bearchair.skills.planning.wholebody import plan_seating_where_standing

    gains = WalkGains()
    step_m, step_rad = gains.stop_tolerance_m, gains.stop_tolerance_rad
    corners = [
        (forward, side, turn)
        for forward in (-step_m, step_m)
        for side in (-step_m, step_m)
        for turn in (-step_rad, step_rad)
    ]
    searched = planned = tried = 0
    for name, mesh, front_yaw_deg in chairs:
        found = feasible_stance(
            mesh, SittingPose(true_seat_point(mesh), math.radians(front_yaw_deg))
        )
        if found is None:
            print(f"  {name:24s} no stance")
            continue
        searched += 1
        stance, sitting_pose, raise_at = found
        heading = np.array([math.cos(stance.theta), math.sin(stance.theta)])
        side_axis = np.array([-heading[1], heading[0]])
        failures = []
        for forward, side, turn in corners:
            x, y = np.array([stance.x, stance.y]) + forward * heading + side * side_axis
            pose = SE2Pose(float(x), float(y), wrap_angle(stance.theta + turn))
            tried += 1
            try:
                plan_seating_where_standing(mesh, sitting_pose, pose, raised=raise_at is not None)
                planned += 1
            except InfeasibleSeating as error:
                failures.append(
                    f"({forward * 1e3:+.0f} mm, {side * 1e3:+.0f} mm, "
                    f"{math.degrees(turn):+.1f} deg) {error}"
                )
        if failures:
            print(f"  {name:24s} {len(failures)}/{len(corners)} corners fail")
            for failure in failures:
                print(f"      {failure}")
    print(
        f"stop-box corners that plan: {planned}/{tried} "
        f"({100.0 * planned / max(tried, 1):.1f} %) on {searched} chairs with a stance"
    )


def main() -> None:
    """Parses the options and prints the figures."""
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawTextHelpFormatter
    )
    parser.add_argument("--sim", action="store_true", help="run seatings in the simulated world")
    parser.add_argument("--calibration", action="store_true", help="use the calibration chairs")
    parser.add_argument("--runs", type=int, default=10, help="simulated runs")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--walk-error", action="store_true", help="plan from the corners of the walk's stop box"
    )
    args = parser.parse_args()

    started = time.perf_counter()
    from bearchair.skills.planning.wholebody.optimisation import seating_problems

    seating_problems()
    print(f"problems built in {time.perf_counter() - started:.2f} s (once per process)")
    # The machine is shared: these timings include contention from other processes.
    if not args.sim:
        chairs = [("box chair", box_chair_mesh(), 0.0)]
        for name, path, front in calibration_chairs():
            chairs.append((name, load_mesh(path), front))
        if len(chairs) == 1:
            print(f"(no calibration chairs at {CHAIRS_DIR}: box chair only)")
        (walk_error if args.walk_error else solve_times)(chairs)
        return

    runs: list[tuple[Path | None, float, str]]
    if args.calibration:
        listed = calibration_chairs()
        if not listed:
            sys.exit(f"no calibration chairs at {CHAIRS_DIR}")
        runs = [(path, front, name) for name, path, front in listed]
    else:
        runs = [(None, 0.0, "box chair")]
    seated = 0
    for i in range(args.runs):
        path, front, name = runs[i % len(runs)]
        seed = args.seed + i
        began = time.perf_counter()
        try:
            ok, description = sim_run(path, front, seed)
        except InfeasibleSeating as error:
            ok, description = False, f"infeasible: {error}"
        seated += ok
        print(
            f"  run {i:2d} {name:24s} seed {seed:3d}: {'SEATED' if ok else 'not seated'}  "
            f"{description}  [{time.perf_counter() - began:.1f} s]",
            flush=True,
        )
    print(f"seated {seated}/{args.runs} ({100.0 * seated / args.runs:.0f} %)")


if __name__ == "__main__":
    main()
