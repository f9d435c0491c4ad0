"""Chooses the Panda's capture configurations for the chair scan, offline, by IK.

Run: ``.venv/bin/python bench/perception_views.py``. For each wanted camera pose (an
eye position looking at a target, image up roughly along world +z) it solves the
Panda's inverse kinematics in pybullet (panda.urdf from pybullet_data, base at the
world origin) from several deterministic starts, then checks the result by forward
kinematics: the optical axis within 3 degrees of the wanted one, the eye within 2 cm,
joint limits, no self-collision, at least 5 cm of clearance to the floor and to the
volume any chair in the chair area can occupy. It prints the joint vectors that
skills/perception/views.py stores as constants.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet
from scipy.optimize import least_squares

from bearchair.skills.perception.look_from_above import view_residual
from bearchair.skills.perception.panda_kinematics import PandaKinematics
from bearchair.skills.perception.views import CHAIR_VOLUME, look_at

# The scan looks at the chair area's centre, 0.2 m up, from 9 directions spread as far
# apart as the arm allows: random joint vectors are sampled, those whose camera looks at
# the target and pass the checks below are kept, 9 are picked by farthest-point
# selection of their viewing directions, and IK then makes each look exactly at it.
SCAN_TARGET = (0.6, 0.0, 0.2)
SAMPLES = 200000
# The overview of the humanoid's walking area: (eye, target).
OVERVIEW = ((0.35, 0.0, 0.85), (1.3, 0.0, 0.35))

LIMITS = [(-2.8973, 2.8973), (-1.7628, 1.7628), (-2.8973, 2.8973), (-3.0718, -0.0698),
          (-2.8973, 2.8973), (-0.0175, 3.7525), (-2.8973, 2.8973)]  # fmt: skip
REST = [-0.0421, -0.5278, -0.0006, -0.8539, 0.0280, 0.8495, 0.7669]  # HOME: eye (0.15, 0, 0.98)
SPREAD_RAD = 1.3


def solve(
    kin: PandaKinematics,
    eye: np.ndarray,
    target: np.ndarray,
    rng: np.random.Generator,
    start_rad: np.ndarray | None = None,
):
    """Least-squares IK on the camera's eye and optical axis (roll is a weak preference)."""
    wanted = look_at(eye, target)
    lower = np.array([lo for lo, _ in LIMITS])
    upper = np.array([hi for _, hi in LIMITS])

    best = None
    for attempt in range(12):
        start = (
            np.asarray(REST if start_rad is None else start_rad)
            if attempt == 0
            else rng.uniform(lower, upper)
        )
        fit = least_squares(
            view_residual,
            np.clip(start, lower + 1e-3, upper - 1e-3),
            bounds=(lower, upper),
            diff_step=1e-4,
            args=(kin, wanted),
        )
        report = check(kin, fit.x, eye, target)
        if report["ok"] and (best is None or report["score"] < best[1]["score"]):
            best = (fit.x, report)
    return best


def check(kin: PandaKinematics, joints: np.ndarray, eye: np.ndarray, target: np.ndarray) -> dict:
    T = kin.camera_pose(joints)
    wanted_axis = (target - eye) / np.linalg.norm(target - eye)
    axis_error = math.degrees(math.acos(np.clip(T[:3, 2] @ wanted_axis, -1, 1)))
    eye_error = float(np.linalg.norm(T[:3, 3] - eye))
    pybullet.performCollisionDetection(physicsClientId=kin.client)
    self_contacts = [
        c for c in pybullet.getContactPoints(kin.robot, kin.robot, physicsClientId=kin.client)
        if abs(c[3] - c[4]) > 1 and {c[3], c[4]} not in ({6, 8}, {9, 10})
    ]  # fmt: skip
    floor_clearance = 10.0
    volume_clearance = 10.0
    lo, hi = CHAIR_VOLUME
    for link in range(2, 11):
        aabb_min, aabb_max = (
            np.asarray(v) for v in pybullet.getAABB(kin.robot, link, physicsClientId=kin.client)
        )
        floor_clearance = min(floor_clearance, aabb_min[2])
        gap = np.maximum(np.maximum(lo - aabb_max, aabb_min - hi), 0.0)
        volume_clearance = min(volume_clearance, float(np.linalg.norm(gap)))
    ok = (
        axis_error < 3.0 and eye_error < 0.02 and not self_contacts
        and floor_clearance > 0.05 and volume_clearance > 0.03
    )  # fmt: skip
    return {
        "ok": ok, "axis_deg": axis_error, "eye_m": eye_error, "self": len(self_contacts),
        "floor_m": floor_clearance, "volume_m": volume_clearance,
        "score": axis_error + 100 * eye_error + 0.1 * float(np.abs(joints - np.asarray(REST)).sum()),
    }  # fmt: skip


def eye_at(target: np.ndarray, azimuth_deg: float, elevation_deg: float, distance_m: float):
    az, el = math.radians(azimuth_deg), math.radians(elevation_deg)
    return target + distance_m * np.array(
        [math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)]
    )


def sample_views(kin: PandaKinematics, rng: np.random.Generator, target: np.ndarray, samples: int):
    """Random reachable configurations whose camera looks within 8 degrees of ``target``
    from 0.45..1.1 m and that pass the clearance checks: (joints, eye) pairs."""
    lower = np.array([lo for lo, _ in LIMITS])
    upper = np.array([hi for _, hi in LIMITS])
    found = []
    for _ in range(samples):
        # Stay in the ready pose's (elbow up) family so that straight joint-space motions
        # between views, and from the ready pose, keep clear of the chair.
        joints = np.clip(np.asarray(REST) + rng.uniform(-SPREAD_RAD, SPREAD_RAD, 7), lower, upper)
        T = kin.camera_pose(joints)
        offset = target - T[:3, 3]
        distance = np.linalg.norm(offset)
        if not 0.5 < distance < 1.1 or T[:3, 2] @ offset / distance < math.cos(math.radians(8)):
            continue
        if T[2, 3] < 0.3:
            continue
        if (
            check(kin, joints, T[:3, 3], T[:3, 3] + T[:3, 2])["ok"]
            and unoccluded(kin, T[:3, 3])
            and path_clearance(kin, np.asarray(REST), joints) > 0.03
        ):
            found.append((joints, T[:3, 3].copy()))
    return found


def path_clearance(
    kin: PandaKinematics, start: np.ndarray, end: np.ndarray, steps: int = 40
) -> float:
    """Smallest clearance (floor, chair volume; -1 on self-collision) along the straight
    joint-space motion from ``start`` to ``end``."""
    worst = 10.0
    for fraction in np.linspace(0.0, 1.0, steps):
        joints = (1.0 - fraction) * start + fraction * end
        report = check(kin, joints, np.zeros(3), np.ones(3))
        worst = min(worst, report["floor_m"], report["volume_m"], -1.0 if report["self"] else 10.0)
    return worst


def unoccluded(kin: PandaKinematics, eye: np.ndarray, at_least: float = 0.97) -> bool:
    """True when the arm's own links block few rays from the eye to the chair volume."""
    lo, hi = CHAIR_VOLUME
    grid = np.stack(np.meshgrid(*(np.linspace(lo[i], hi[i], 5) for i in range(3))), -1).reshape(
        -1, 3
    )
    # Start the rays 6 cm out so that the hand carrying the camera does not count.
    starts = eye + 0.06 * (grid - eye) / np.linalg.norm(grid - eye, axis=1, keepdims=True)
    hits = pybullet.rayTestBatch(starts.tolist(), grid.tolist(), physicsClientId=kin.client)
    blocked = sum(1 for hit in hits if hit[0] == kin.robot)
    return blocked <= (1.0 - at_least) * len(grid)


def spread(candidates, target: np.ndarray, count: int) -> list:
    """Farthest-point selection on the viewing directions (the first is the highest view)."""
    directions = np.array([(eye - target) / np.linalg.norm(eye - target) for _, eye in candidates])
    chosen = [int(np.argmax(directions[:, 2]))]
    for _ in range(count - 1):
        gaps = np.min(
            np.linalg.norm(directions[:, None] - directions[chosen][None], axis=2), axis=1
        )
        chosen.append(int(np.argmax(gaps)))
    return [candidates[i] for i in chosen]


def print_view(
    name: str, joints: np.ndarray, report: dict, eye: np.ndarray, aim: np.ndarray
) -> None:
    values = ", ".join(f"{v:.4f}" for v in joints)
    print(
        f"    # {name}: eye {np.round(eye, 3).tolist()} -> {np.round(aim, 3).tolist()}, axis "
        f"{report['axis_deg']:.1f} deg off, clearance floor {report['floor_m']:.2f} m, "
        f"chair volume {report['volume_m']:.2f} m"
    )
    print(f"    ({values}),")


def main() -> None:
    kin = PandaKinematics()
    rng = np.random.default_rng(0)
    target = np.array(SCAN_TARGET)
    candidates = sample_views(kin, rng, target, SAMPLES)
    print(f"# {len(candidates)} valid sampled views out of {SAMPLES}")
    # The sampled joint vectors are used as they are (each already looks within 8 degrees
    # of the target); only the overview, a single wanted pose, is solved by IK.
    chosen = spread(candidates, target, 9)
    # Visit them in nearest-neighbour order (joint space) from the ready pose.
    order, position = [], np.asarray(REST)
    remaining = list(range(len(chosen)))
    while remaining:
        nearest = min(remaining, key=lambda i: float(np.abs(chosen[i][0] - position).sum()))
        order.append(nearest)
        remaining.remove(nearest)
        position = chosen[nearest][0]
    previous = np.asarray(REST)
    for rank, index in enumerate(order):
        joints, eye = chosen[index]
        clearance = path_clearance(kin, previous, joints)
        print(f"    # path from the previous configuration: clearance {clearance:.2f} m")
        print_view(f"scan{rank}", joints, check(kin, joints, eye, target), eye, target)
        previous = joints
    eye, aim = np.asarray(OVERVIEW[0]), np.asarray(OVERVIEW[1])
    best = solve(kin, eye, aim, rng)
    if best is None:
        print("overview: NO valid IK solution")
    else:
        print_view("overview", best[0], best[1], eye, aim)
    kin.close()


if __name__ == "__main__":
    main()
