"""Small loggers that turn the skills' typed results into Rerun archetypes.

One function per result type, each ``log_x(stream, value)``: the recording
(:mod:`bearchair.executive.recording.mission_recording`) calls them from the tick loop's
post-tick hook when a blackboard value changes, or when a watched skill call returns.
Nothing here computes anything the mission uses: it only draws what the skills already
said.

Entity paths (the world frame is z up, metres):

==================================== ====================================================
path                                 what
==================================== ====================================================
world/arena/walls, .../obstacles      the planning arena and the fixed obstacles
world/scan/views/<i>                  each view's camera pose (pinhole), depth and colour
world/scan/cloud                      the fused chair cloud after floor removal
world/chair                           the chair mesh now (moves when the helper turns it)
world/imagination/drops/<i>           each drop's final agent links as boxes (green: a
                                      correct sitting by the SAM, red: not)
world/sitting_pose                    g = (p, γ) as an arrow from p along γ
world/accessibility/se2_goal, path    the SE(2) goal and the planned path
world/nao                             the humanoid's tracked pose (the NAO frame, on the floor)
world/<robot>, transforms/<robot>     the Panda and the NAO from their URDFs, and their
                                      joint states (:mod:`.urdf_robots`)
world/walk/path, tag_detections       the humanoid's tracked path and the tag's detections
world/bear                            the bear when judged
assistance/asked, assistance/measured the rotations asked for and measured by ICP
seat/plan/<joint>                     the planned joint trajectory (timeline seat_plan)
seat/judgement                        the judge's verdict
==================================== ====================================================
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import rerun as rr
from scipy.spatial.transform import Rotation

from bearchair.behaviours import keys
from bearchair.core.arena import Arena, Box2D
from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import RGBDFrame, SeatingJudgement
from bearchair.skills.results import (
    AccessibilityResult,
    ChairRotation,
    ChairScan,
    ImaginationResult,
    Instruction,
    SeatingPlan,
    SeatReachability,
    WalkResult,
)

GREEN = (60, 180, 75)
RED = (220, 50, 47)
BLUE = (66, 133, 244)
ORANGE = (245, 130, 48)
GREY = (150, 150, 150)
ARROW_LENGTH_M = 0.3
"""Length of the arrows drawn for headings (metres): about a chair's depth."""
BEAR_HALF_SIZES_M = (0.06, 0.08, 0.12)
"""The teddy bear as a box, in its own frame (x facing, z up the torso)."""


def log_world_frame(stream: rr.RecordingStream) -> None:
    """The world is z up (the robots' models: :mod:`bearchair.executive.recording.urdf_robots`)."""
    stream.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)


def log_arena(stream: rr.RecordingStream, arena: Arena) -> None:
    """The walls, the chair area and the fixed obstacles, as they are for the whole run."""
    walls = [
        (arena.x_min, arena.y_min, 0.0),
        (arena.x_max, arena.y_min, 0.0),
        (arena.x_max, arena.y_max, 0.0),
        (arena.x_min, arena.y_max, 0.0),
        (arena.x_min, arena.y_min, 0.0),
    ]
    stream.log("world/arena/walls", rr.LineStrips3D([walls], colors=[GREY]), static=True)
    stream.log(
        "world/arena/chair_area",
        rr.LineStrips3D([_footprint(arena.chair_area)], colors=[ORANGE]),
        static=True,
    )
    if arena.obstacles:
        stream.log(
            "world/arena/obstacles",
            rr.Boxes3D(
                centers=[
                    ((b.x_min + b.x_max) / 2, (b.y_min + b.y_max) / 2, b.height / 2)
                    for b in arena.obstacles
                ],
                half_sizes=[
                    ((b.x_max - b.x_min) / 2, (b.y_max - b.y_min) / 2, b.height / 2)
                    for b in arena.obstacles
                ],
                colors=[GREY],
            ),
            static=True,
        )


def log_scan(stream: rr.RecordingStream, scan: ChairScan) -> None:
    """Each view (camera pose, depth in millimetres, colour) and the fused chair cloud."""
    for index, frame in enumerate(scan.frames):
        log_view(stream, f"world/scan/views/{index}", frame)
    stream.log(
        "world/scan/cloud",
        rr.Points3D(np.asarray(scan.chair_points, dtype=np.float32), radii=0.002),
    )


def log_view(stream: rr.RecordingStream, path: str, frame: RGBDFrame) -> None:
    """One RGB-D capture under its camera pose (OpenCV optical frame: x right, y down)."""
    T = np.asarray(frame.T_world_camera, dtype=float)
    intrinsics = frame.intrinsics
    stream.log(path, rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
    stream.log(
        path,
        rr.Pinhole(
            image_from_camera=intrinsics.matrix(),
            resolution=(intrinsics.width, intrinsics.height),
            camera_xyz=rr.ViewCoordinates.RDF,
            image_plane_distance=0.1,
        ),
    )
    stream.log(
        f"{path}/depth",
        rr.EncodedDepthImage(depth_png(frame.depth_m), media_type="image/png", meter=1000.0),
    )
    stream.log(f"{path}/rgb", rr.Image(frame.rgb).compress(jpeg_quality=80))


def depth_png(depth_m: np.ndarray) -> bytes:
    """Depth as a 16-bit PNG in millimetres (0: no depth), what depth cameras send;
    about a quarter of the raw float32 image for a rendered or sensed scene."""
    import cv2

    depth_mm = np.clip(np.nan_to_num(depth_m) * 1000.0, 0, 65535).astype(np.uint16)
    ok, png = cv2.imencode(".png", depth_mm)
    if not ok:
        raise ValueError("could not encode a depth image as PNG")
    return png.tobytes()


def log_chair(stream: rr.RecordingStream, chair_mesh: Any) -> None:
    """The chair mesh as the mission now believes it is (world frame)."""
    stream.log(
        "world/chair",
        rr.Mesh3D(
            vertex_positions=np.asarray(chair_mesh.vertices, dtype=np.float32),
            triangle_indices=np.asarray(chair_mesh.faces, dtype=np.uint32),
            vertex_normals=np.asarray(chair_mesh.vertex_normals, dtype=np.float32),
            albedo_factor=(200, 170, 120, 255),
        ),
    )


def log_imagination(stream: rr.RecordingStream, result: ImaginationResult) -> None:
    """Every drop's final agent (links as boxes, coloured by the SAM's verdict) and a
    table of the verdicts."""
    from bearchair.skills.imagination.agent import LINKS

    half_sizes, centres = _link_boxes(LINKS)
    T_world_chair = result.T_mesh_chair if result.T_mesh_chair is not None else np.eye(4)
    rows = ["| drop | rotation | offset (m) | J | L | H (m) | contacts up/low | correct |"]
    rows.append("|---|---|---|---|---|---|---|---|")
    for index, drop in enumerate(result.drops):
        verdict = "correct" if drop.correct else "not correct"
        rows.append(
            f"| {index} | {drop.rotation_index} | {drop.offset_m:.3f} | {drop.joint_score:.2f} "
            f"| {drop.link_score:.2f} | {drop.sitting_height_m:.3f} "
            f"| {drop.upper_contacts}/{drop.lower_contacts} | {verdict} |"
        )
        archetypes: list[Any] = [
            rr.AnyValues(
                correct=drop.correct,
                rotation_index=drop.rotation_index,
                joint_score=float(drop.joint_score),
                link_score=float(drop.link_score),
                sitting_height_m=float(drop.sitting_height_m),
            )
        ]
        if drop.link_poses is not None:
            T_world_links = T_world_chair @ np.asarray(drop.link_poses)
            rotations = T_world_links[:, :3, :3]
            archetypes.append(
                rr.Boxes3D(
                    centers=np.einsum("lij,lj->li", rotations, centres) + T_world_links[:, :3, 3],
                    half_sizes=half_sizes,
                    quaternions=Rotation.from_matrix(rotations).as_quat(),
                    colors=[GREEN if drop.correct else RED],
                    labels=[f"drop {index}: {verdict}"] + [""] * (len(LINKS) - 1),
                )
            )
        stream.log(f"world/imagination/drops/{index}", *archetypes)
    summary = (
        f"{result.n_correct} correct sittings of the chosen rotation, {result.n_drops} drops"
        if result.found
        else f"no sitting pose: {result.reason}"
    )
    stream.log(
        "imagination/verdicts",
        rr.TextDocument(summary + "\n\n" + "\n".join(rows), media_type=rr.MediaType.MARKDOWN),
    )


def log_sitting_pose(stream: rr.RecordingStream, pose: SittingPose) -> None:
    """g = (p, γ): an arrow from the pelvis position p along the sitting direction γ."""
    direction = np.array([math.cos(pose.yaw), math.sin(pose.yaw), 0.0]) * ARROW_LENGTH_M
    stream.log(
        "world/sitting_pose",
        rr.Arrows3D(
            origins=[np.asarray(pose.position, dtype=float)],
            vectors=[direction],
            colors=[GREEN],
            labels=[f"g: {math.degrees(pose.yaw):.0f} deg"],
        ),
        rr.AnyValues(yaw_rad=float(pose.yaw)),
    )


def log_accessibility(stream: rr.RecordingStream, result: AccessibilityResult) -> None:
    """The SE(2) goal, where the bear is raised (if it is) and the planned path."""
    if result.se2_goal is not None:
        stream.log("world/accessibility/se2_goal", _se2_arrow(result.se2_goal, BLUE, "s_goal"))
    else:
        stream.log("world/accessibility/se2_goal", rr.Clear(recursive=False))
    if result.raise_at is not None:
        stream.log("world/accessibility/raise_at", _se2_arrow(result.raise_at, ORANGE, "raise"))
    path = [(p.x, p.y, 0.01) for p in result.path]
    if len(path) >= 2:
        stream.log("world/accessibility/path", rr.LineStrips3D([path], colors=[BLUE], radii=0.005))
    else:
        stream.log("world/accessibility/path", rr.Clear(recursive=False))
    verdict = "accessible" if result.accessible else f"not accessible: {result.reason}"
    stream.log(
        "accessibility/log",
        rr.TextLog(f"{verdict} ({len(result.path)} waypoints, {result.seconds:.2f} s)"),
    )


def log_reachability(stream: rr.RecordingStream, result: SeatReachability) -> None:
    """Whether some stance reaches the seat with the chair alone (before any rotation)."""
    if result.reachable:
        text = (
            f"seat reachable: seat {result.seat_height_m:.3f} m high, stance "
            f"{result.stance_m:.3f} m from p, p slid {result.slide_m * 100:.1f} cm"
        )
    else:
        text = f"seat not reachable: {result.reason}"
    stream.log("accessibility/log", rr.TextLog(text))


def log_instruction(stream: rr.RecordingStream, instruction: Instruction) -> None:
    """A rotation asked of the helper (signed: counter-clockwise positive, degrees)."""
    signed_deg = -instruction.angle_deg if instruction.clockwise else instruction.angle_deg
    stream.log("assistance/asked_deg", rr.Scalars(float(signed_deg)))
    stream.log("assistance/log", rr.TextLog(f'asked: "{instruction.sentence}"'))


def log_rotation(stream: rr.RecordingStream, rotation: ChairRotation) -> None:
    """The rotation ICP measured after the helper acted."""
    yaw_deg = math.degrees(rotation.yaw_rad)
    stream.log("assistance/measured_deg", rr.Scalars(yaw_deg))
    stream.log(
        "assistance/log",
        rr.TextLog(
            f"measured: {yaw_deg:+.1f} deg (ICP fitness {rotation.fitness:.2f}, "
            f"rmse {rotation.inlier_rmse_m * 100:.1f} cm)"
        ),
    )


def log_humanoid_pose(stream: rr.RecordingStream, pose: SE2Pose) -> None:
    """Where the mission tracks the humanoid (its tag, else odometry): moves its body."""
    stream.log(
        "world/nao",
        rr.Transform3D(
            translation=(pose.x, pose.y, 0.0),
            rotation=rr.RotationAxisAngle(axis=(0.0, 0.0, 1.0), radians=pose.theta),
        ),
    )


def log_walked_path(stream: rr.RecordingStream, poses: list[SE2Pose]) -> None:
    """The humanoid's tracked poses so far as one line."""
    stream.log(
        "world/walk/path",
        rr.LineStrips3D([[(p.x, p.y, 0.005) for p in poses]], colors=[GREY], radii=0.003),
    )


def log_tag_detection(stream: rr.RecordingStream, pose: SE2Pose | None) -> None:
    """One look for the humanoid's tag: its pose, or nothing when the tag was not seen."""
    if pose is None:
        stream.log("walk/tag_seen", rr.Scalars(0.0))
        return
    stream.log("walk/tag_seen", rr.Scalars(1.0))
    stream.log("world/walk/tag_detections", _se2_arrow(pose, ORANGE, None, length_m=0.1))


def log_walk(stream: rr.RecordingStream, result: WalkResult) -> None:
    """How the walk ended."""
    stream.log(
        "walk/log",
        rr.TextLog(
            f"{'reached' if result.reached else 'not reached'}: "
            f"{result.position_error_m * 100:.1f} cm, "
            f"{math.degrees(result.yaw_error_rad):.1f} deg after {result.seconds:.1f} s"
            + (f" ({result.reason})" if result.reason else "")
        ),
    )


def log_seating_plan(stream: rr.RecordingStream, plan: SeatingPlan) -> None:
    """The planned joint trajectory, one series per joint, on the ``seat_plan`` timeline
    (seconds from the start of the seating motion; the retract motion follows it)."""
    times = np.asarray(plan.times_s, dtype=float)
    positions = np.asarray(plan.positions_rad, dtype=float)
    retract_times = np.asarray(plan.retract_times_s, dtype=float)
    retract = np.asarray(plan.retract_positions_rad, dtype=float)
    if len(retract_times):
        times = np.concatenate([times, times[-1] + retract_times])
        positions = np.concatenate([positions, retract.reshape(len(retract_times), -1)])
    for column, name in enumerate(plan.joint_names):
        stream.send_columns(
            f"seat/plan/{name}",
            indexes=[rr.TimeColumn("seat_plan", duration=times)],
            columns=rr.Scalars.columns(scalars=positions[:, column]),
        )


def log_judgement(stream: rr.RecordingStream, judgement: SeatingJudgement) -> None:
    """The judge's verdict, and the bear where it was judged."""
    verdict = "seated" if judgement.seated else f"not seated: {judgement.reason}"
    stream.log(
        "seat/judgement",
        rr.TextLog(
            f"{verdict} (tilt {judgement.torso_tilt_deg:.0f} deg, "
            f"facing error {judgement.facing_error_deg:.0f} deg)",
            level=rr.TextLogLevel.INFO if judgement.seated else rr.TextLogLevel.WARN,
        ),
        rr.AnyValues(
            seated=judgement.seated,
            torso_tilt_deg=float(judgement.torso_tilt_deg),
            facing_error_deg=float(judgement.facing_error_deg),
        ),
    )
    if judgement.T_world_bear is not None:
        T = np.asarray(judgement.T_world_bear, dtype=float)
        stream.log("world/bear", rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
        stream.log(
            "world/bear/body",
            rr.Boxes3D(
                half_sizes=[BEAR_HALF_SIZES_M],
                centers=[(0.0, 0.0, BEAR_HALF_SIZES_M[2])],
                colors=[GREEN if judgement.seated else RED],
                labels=["bear"],
            ),
        )


def _se2_arrow(
    pose: SE2Pose, colour: tuple[int, int, int], label: str | None, length_m: float = ARROW_LENGTH_M
) -> rr.Arrows3D:
    vector = (length_m * math.cos(pose.theta), length_m * math.sin(pose.theta), 0.0)
    return rr.Arrows3D(
        origins=[(pose.x, pose.y, 0.01)],
        vectors=[vector],
        colors=[colour],
        labels=None if label is None else [label],
    )


def _footprint(box: Box2D) -> list[tuple[float, float, float]]:
    return [
        (box.x_min, box.y_min, 0.0),
        (box.x_max, box.y_min, 0.0),
        (box.x_max, box.y_max, 0.0),
        (box.x_min, box.y_max, 0.0),
        (box.x_min, box.y_min, 0.0),
    ]


def _link_boxes(links: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each agent link's primitive as a box: half sizes and centre, in the link frame."""
    half_sizes, centres = [], []
    for link in links:
        if link.shape == "box":
            half = np.asarray(link.size, dtype=float) / 2.0
        elif link.shape == "sphere":
            half = np.full(3, link.size[0])
        else:  # capsule: radius, cylinder length, along x or z
            radius, length = link.size
            long_half = length / 2.0 + radius
            half = (
                np.array([long_half, radius, radius])
                if link.along == "x"
                else np.array([radius, radius, long_half])
            )
        half_sizes.append(half)
        centres.append(np.asarray(link.centre_m, dtype=float))
    return np.array(half_sizes), np.array(centres)


SCENE_LOGGERS: dict[str, Callable[[rr.RecordingStream, Any], None]] = {
    keys.ARENA: log_arena,
    keys.CHAIR_SCAN: log_scan,
    keys.CHAIR_MESH: log_chair,
    keys.IMAGINATION: log_imagination,
    keys.SITTING_POSE: log_sitting_pose,
    keys.REACHABILITY: log_reachability,
    keys.ACCESSIBILITY: log_accessibility,
    keys.WALK: log_walk,
    keys.SEATING_PLAN: log_seating_plan,
    keys.JUDGEMENT: log_judgement,
}
"""The blackboard keys drawn in the scene, each with the function that draws its value."""
