"""One more view of the chair, chosen while the mission runs: from above, where the scan
has not looked from.

The nine scan views (:data:`bearchair.skills.perception.views.SCAN_CONFIGURATIONS`) look
at the chair area from the arm's side. A seat deep between a tall back and armrests, or
the front of a back that faces away from the arm, can be hidden from every one of them;
the imagination then finds no sitting on the scan, although the chair has one. So when
the scan lacks what the mission needs, the arm looks once more, from above: over the
chair's middle when the imagination found no sitting (:func:`look_from_above`), over the
sitting point when the scan shows no seat under it (:func:`look_at_seat`).

The view: eye candidates around the target at :data:`AZIMUTHS_DEG`, :data:`ELEVATIONS_DEG`
over its horizontal and :data:`DISTANCES_M` from it, each looking at the target, tried in
order of how far their viewing direction lies from every view the scan already has (the
largest angle first: the farthest-point rule the scan's own views were chosen by,
``bench/perception_views.py``), so each look adds what the others could not see. A
candidate is solved by least-squares IK on the eye and the optical axis from HOME and
accepted on the offline views' tolerances (the eye within :data:`EYE_TOLERANCE_M`, the axis
within :data:`AXIS_TOLERANCE_DEG`) when its motion from HOME keeps
:data:`bearchair.skills.perception.views.VIEW_CLEARANCE_M` from the scanned chair's box
grown by :data:`SCAN_BOX_MARGIN_M`. The first accepted is visited; the frame is fused with
the scan's and the chair reconstructed again.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares

from bearchair.core.errors import Cancelled
from bearchair.core.geometry import SittingPose
from bearchair.hardware.interfaces import ScanningArm
from bearchair.hardware.real.panda import wall_limits
from bearchair.skills.perception.clearance import ArmClearance, PlannedView
from bearchair.skills.perception.errors import PerceptionError
from bearchair.skills.perception.panda_kinematics import PandaKinematics
from bearchair.skills.perception.reconstruction import reconstruct_chair
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.perception.scan_capture import capture_planned
from bearchair.skills.perception.views import HOME_CONFIGURATION, VIEW_CLEARANCE_M, look_at
from bearchair.skills.planning.seat import seat_ray
from bearchair.skills.results import ChairScan

AZIMUTHS_DEG = (0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0)
"""Azimuths of the eye about the target (degrees, from the direction toward the arm's base,
counter-clockwise): all round; the arm's reach and the clearance decide which are kept."""

ELEVATIONS_DEG = (80.0, 65.0, 50.0)
"""Elevations of the eye over the target's horizontal (degrees): steeper than most scan
views, which look from 20-45 deg over the chair area's centre."""

DISTANCES_M = (0.45, 0.6)
"""Eye-to-target distances tried (metres): beyond the 0.35 m a structured-light depth
camera needs, near enough for the arm to reach over a chair's middle."""

EYE_TOLERANCE_M = 0.02
AXIS_TOLERANCE_DEG = 3.0

SCAN_BOX_MARGIN_M = 0.05
"""The scanned chair's box is grown by this (metres) before the clearance check: the
scan may have missed the thinnest parts (a rail, a back's top edge)."""


class LookCancelled(Cancelled, PerceptionError):
    """The look was interrupted through its cancel event."""


class NoViewFromAbove(PerceptionError):
    """No candidate view is reachable clear of the scanned chair."""


def chair_middle(scan: ChairScan) -> np.ndarray:
    """The middle (metres, world) of the scanned chair's box: where a look over it aims."""
    lower, upper = scan.chair_mesh.bounds
    return (np.asarray(lower, float) + np.asarray(upper, float)) / 2.0


def eye_candidates(target_m: np.ndarray, seen_from: Sequence[np.ndarray] = ()) -> list[np.ndarray]:
    """The eyes (metres, world) tried, in order: the largest angle between the viewing
    direction and those of ``seen_from`` (the eyes of the views the scan has) first; ties
    (no view yet) steeper, then nearer first."""
    target = np.asarray(target_m, float)
    toward_arm = np.arctan2(-target[1], -target[0])
    seen = [_unit(target - np.asarray(eye, float)) for eye in seen_from]
    scored = []
    for order, (elevation, distance, azimuth) in enumerate(
        (e, d, a) for e in ELEVATIONS_DEG for d in DISTANCES_M for a in AZIMUTHS_DEG
    ):
        e, a = math.radians(elevation), toward_arm + math.radians(azimuth)
        eye = target + distance * np.array(
            [math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)]
        )
        direction = _unit(target - eye)
        nearest = min(
            (float(np.arccos(np.clip(direction @ s, -1.0, 1.0))) for s in seen), default=0.0
        )
        scored.append((-round(nearest, 6), order, eye))
    return [eye for _, _, eye in sorted(scored, key=lambda row: row[:2])]


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / max(float(np.linalg.norm(vector)), 1e-12)


def view_residual(
    joints_rad: np.ndarray, kinematics: PandaKinematics, T_world_camera: np.ndarray
) -> np.ndarray:
    """The IK's residual of a camera pose: the eye's error (metres, x10: a centimetre
    weighs as 0.1 of the optical axis's error) and the axis's, with a weak pull on the
    image's roll (x0.1)."""
    T = kinematics.camera_pose(joints_rad)
    wanted = T_world_camera
    return np.concatenate(
        (
            10.0 * (T[:3, 3] - wanted[:3, 3]),
            T[:3, 2] - wanted[:3, 2],
            0.1 * (T[:3, 0] - wanted[:3, 0]),
        )
    )


def solve_view(
    kinematics: PandaKinematics,
    eye_m: np.ndarray,
    target_m: np.ndarray,
    start_rad: Sequence[float] = HOME_CONFIGURATION,
) -> np.ndarray | None:
    """Joints (radians) whose wrist camera sits at ``eye_m`` looking at ``target_m``, within
    :data:`EYE_TOLERANCE_M` and :data:`AXIS_TOLERANCE_DEG`, inside the joint range the
    Panda's controller accepts (``hardware.real.panda.wall_limits``); None when the IK
    misses."""
    wanted = look_at(eye_m, target_m)
    # Within panda-py's joint walls, not merely the joint limits: the real arm moves a
    # target inside the walls to their edge (another view) or refuses it.
    lower, upper = wall_limits()
    start = np.clip(np.asarray(start_rad, float), lower + 1e-3, upper - 1e-3)
    fit = least_squares(
        view_residual, start, bounds=(lower, upper), diff_step=1e-4, args=(kinematics, wanted)
    )
    T = kinematics.camera_pose(fit.x)
    axis = (np.asarray(target_m, float) - T[:3, 3]) / np.linalg.norm(target_m - T[:3, 3])
    axis_error = math.degrees(math.acos(float(np.clip(T[:3, 2] @ axis, -1.0, 1.0))))
    if np.linalg.norm(T[:3, 3] - eye_m) > EYE_TOLERANCE_M or axis_error > AXIS_TOLERANCE_DEG:
        return None
    return fit.x


def plan_look(target_m: np.ndarray, scan: ChairScan) -> tuple[PlannedView, np.ndarray]:
    """The first candidate view (see the module doc) clear of the scanned chair, the
    scan's frames' eyes taken as seen.

    Returns:
        The view to visit (from HOME) and its eye (metres, world).

    Raises:
        NoViewFromAbove: no candidate is reachable clear of the chair.
    """
    lower, upper = (np.asarray(b, float) for b in scan.chair_mesh.bounds)
    with ArmClearance() as clearance:
        clearance.set_box(lower - SCAN_BOX_MARGIN_M, upper + SCAN_BOX_MARGIN_M)
        kinematics = clearance.kinematics
        seen_from = [np.asarray(frame.T_world_camera, float)[:3, 3] for frame in scan.frames]
        candidates = eye_candidates(target_m, seen_from)
        for eye in candidates:
            joints = solve_view(kinematics, eye, target_m)
            if joints is None:
                continue
            path_m = clearance.path_clearance(HOME_CONFIGURATION, tuple(joints))
            if path_m >= VIEW_CLEARANCE_M:
                view = PlannedView(0, tuple(float(j) for j in joints), False, "kept", path_m)
                return view, eye
    raise NoViewFromAbove(
        f"no view from above the chair reachable clear of it: {len(candidates)} "
        f"eyes {DISTANCES_M[0]:.2f}-{DISTANCES_M[-1]:.2f} m from "
        f"({target_m[0]:.2f}, {target_m[1]:.2f}, {target_m[2]:.2f}) m tried"
    )


def look_from_above(
    arm: ScanningArm,
    scan: ChairScan,
    *,
    seed: int,
    target: np.ndarray | None = None,
    cancel: threading.Event | None = None,
) -> ChairScan:
    """Looks once more, from above ``target``, and reconstructs the chair from every view.

    Args:
        arm: the scanning arm (the frame's pose from its forward kinematics).
        scan: the scan so far (its frames are fused again with the new one).
        seed: seeds the floor RANSAC, as the scan's.
        target: the point to look at (metres, world); None: the scanned chair's middle.
        cancel: when set, the look stops before its motion.

    Returns:
        The chair scan from the scan's frames and the new one; ``notes`` says where the
        look came from.

    Raises:
        LookCancelled: ``cancel`` was set.
        PerceptionError: no view reachable clear of the chair, the motion stopped short,
            or the reconstruction failed.
    """
    aim = chair_middle(scan) if target is None else np.asarray(target, float)
    view, eye = plan_look(aim, scan)
    frames, notes, seconds = capture_planned(arm, [view], cancel, LookCancelled)
    if cancel is not None and cancel.is_set():
        raise LookCancelled("the look from above was cancelled")
    if not frames:
        raise PerceptionError("the look from above was not reached: " + "; ".join(notes))
    config = replace(scan.config or ReconstructionConfig(), seed=seed)
    again = reconstruct_chair([*scan.frames, *frames], config)
    note = (
        f"one more view from ({eye[0]:.2f}, {eye[1]:.2f}, {eye[2]:.2f}) m looking at "
        f"({aim[0]:.2f}, {aim[1]:.2f}, {aim[2]:.2f}) m"
    )
    return again._replace(
        seconds={**again.seconds, **{f"look {k}": v for k, v in seconds.items()}},
        notes=(*scan.notes, *notes, note),
        frames=(*scan.frames, *frames),
        config=config,
    )


def seat_seen_under(scan: ChairScan, sitting_pose: SittingPose) -> bool:
    """Whether the scan has the seat's top under the sitting point (or under the bear's
    footprint just ahead of it: :func:`bearchair.skills.planning.seat.seat_ray`)."""
    ray = seat_ray(scan.chair_mesh, sitting_pose)
    return len(ray.slides_m) > 0 and ray.seat_seen


def look_at_seat(
    arm: ScanningArm,
    scan: ChairScan,
    sitting_pose: SittingPose,
    *,
    seed: int,
    cancel: threading.Event | None = None,
) -> ChairScan:
    """The scan, with one look from above the sitting point when it shows no seat there.

    Args:
        arm: the scanning arm.
        scan: the scan so far.
        sitting_pose: the imagined g (world frame).
        seed: seeds the floor RANSAC, as the scan's.
        cancel: when set, the look stops before its motion.

    Returns:
        ``scan`` itself when it shows the seat under p; else the scan with the look (its
        last note says so), or ``scan`` with a note when no view reaches (the seat check
        then says what the scan lacks).

    Raises:
        LookCancelled: ``cancel`` was set.
        PerceptionError: the motion stopped short or the reconstruction failed.
    """
    if seat_seen_under(scan, sitting_pose):
        return scan
    try:
        return look_from_above(
            arm, scan, seed=seed, target=np.asarray(sitting_pose.position, float), cancel=cancel
        )
    except NoViewFromAbove as error:
        return scan._replace(notes=(*scan.notes, str(error)))
