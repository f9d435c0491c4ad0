"""The humanoid's planar pose from the ArUco tag on top of its head.

The tag lies flat (its z axis up), its x axis along the humanoid's forward direction,
its centre on the humanoid's vertical axis. ``cv2.aruco`` finds its four corners;
``solvePnP`` (IPPE_SQUARE, the solver for a planar square) gives T_camera_tag, and
T_world_tag = T_world_camera T_camera_tag. The humanoid's SE(2) pose is the tag
centre's (x, y); its heading is that of the tag's x axis, measured from the corners cut
with the horizontal plane at the tag's height (:func:`planar_yaw`), which is steadier
than PnP's rotation when the tag is seen at a grazing angle. Where the depth
image covers the tag, the tag centre's position along the viewing ray is taken from the
measured depth (median over the tag's pixels) rather than from the apparent size of a
tag only a few tens of pixels wide.
"""

from __future__ import annotations

import math
import weakref
from functools import lru_cache
from typing import NamedTuple

import cv2
import numpy as np

from bearchair.core.arena import HUMANOID_TAG, TagSpec
from bearchair.core.geometry import yaw_of
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import RGBDFrame, ScanningArm
from bearchair.skills.perception.views import HOME_CONFIGURATION, OVERVIEW_CONFIGURATION

MAX_TILT_DEG = 35.0
"""A fitted tag tilted more than this from horizontal is a bad fit, not the head tag."""

AT_CONFIGURATION_RAD = 0.01
"""The arm counts as already at the overview when every joint is within this."""


@lru_cache(maxsize=4)
def _detector(dictionary: str) -> cv2.aruco.ArucoDetector:
    parameters = cv2.aruco.DetectorParameters()
    # Line fits along the tag's contour: the head tag is a few pixels tall at the far end
    # of the arena, too small for corner windows. Over 60 rendered poses the heading was
    # within 1.4 degrees (sub-pixel corners: 3.5 degrees at worst, 7 % beyond 3).
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_CONTOUR
    return cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary)), parameters
    )


def detect_tag_corners(rgb: np.ndarray, tag: TagSpec) -> np.ndarray | None:
    """The tag's four corners (4, 2) in pixels (OpenCV order), or None when not seen."""
    gray = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY)
    corners, ids, _ = _detector(tag.dictionary).detectMarkers(gray)
    if ids is None:
        return None
    for marker_corners, marker_id in zip(corners, ids.reshape(-1), strict=True):
        if int(marker_id) == tag.marker_id:
            return marker_corners.reshape(4, 2).astype(np.float64)
    return None


def tag_pose_in_camera(
    corners_px: np.ndarray, frame: RGBDFrame, side_m: float
) -> np.ndarray | None:
    """T_camera_tag from the corners by IPPE_SQUARE, or None when solvePnP fails.

    A small square seen at a grazing angle has two nearly equally good poses (the planar
    ambiguity); IPPE returns both, and the one whose face points most nearly up in the
    world is kept, since the tag lies flat on the head.
    """
    half = side_m / 2.0
    object_points = np.array(
        [[-half, half, 0.0], [half, half, 0.0], [half, -half, 0.0], [-half, -half, 0.0]]
    )
    count, rvecs, tvecs, _ = cv2.solvePnPGeneric(
        object_points,
        corners_px,
        frame.intrinsics.matrix(),
        None,
        flags=cv2.SOLVEPNP_IPPE_SQUARE,
    )
    if not count:
        return None
    world_up_in_camera = np.asarray(frame.T_world_camera)[:3, :3].T @ np.array([0.0, 0.0, 1.0])
    best, best_alignment = None, -2.0
    for rvec, tvec in zip(rvecs, tvecs, strict=True):
        transform = np.eye(4)
        transform[:3, :3] = cv2.Rodrigues(rvec)[0]
        transform[:3, 3] = np.asarray(tvec).reshape(3)
        alignment = float(transform[:3, 2] @ world_up_in_camera)
        if alignment > best_alignment:
            best, best_alignment = transform, alignment
    return best


def _depth_range_correction(
    corners_px: np.ndarray, frame: RGBDFrame, centre_camera: np.ndarray
) -> np.ndarray:
    """The tag centre moved along its viewing ray to the depth measured on the tag."""
    depth = np.asarray(frame.depth_m, dtype=np.float64)
    mask = np.zeros(depth.shape, dtype=np.uint8)
    centre_px = corners_px.mean(axis=0)
    # Shrink the quadrilateral so that pixels at the tag's border (mixed depths) are out.
    inner = centre_px + 0.7 * (corners_px - centre_px)
    cv2.fillConvexPoly(mask, np.round(inner).astype(np.int32), 1)
    values = depth[(mask > 0) & np.isfinite(depth) & (depth > 0)]
    if len(values) < 8:
        return centre_camera
    # The tag is a plane: its mean depth over a symmetric patch is the centre's depth.
    measured_z = float(np.median(values))
    if abs(measured_z - centre_camera[2]) > 0.15 * centre_camera[2]:
        return centre_camera  # the depth belongs to something else
    return centre_camera * (measured_z / centre_camera[2])


def planar_yaw(corners_px: np.ndarray, frame: RGBDFrame, height_m: float) -> float:
    """The tag's heading from its corners' viewing rays cut with the plane z = height_m.

    With the tag known to lie flat, only its heading is unknown, and the four edges'
    directions on the plane give it without PnP's tilt ambiguity at grazing views:
    the x axis runs from corner 0 to 1 and from 3 to 2, the y axis from 3 to 0 and from
    2 to 1 (OpenCV's corner order); the heading is the circular mean of the four.
    """
    K_inv = np.linalg.inv(frame.intrinsics.matrix())
    pose = np.asarray(frame.T_world_camera, dtype=np.float64)
    rays = (pose[:3, :3] @ (K_inv @ np.column_stack((corners_px, np.ones(4))).T)).T
    scale = (height_m - pose[2, 3]) / rays[:, 2]
    on_plane = pose[:3, 3] + scale[:, None] * rays
    x_edges = [on_plane[1] - on_plane[0], on_plane[2] - on_plane[3]]
    y_edges = [on_plane[0] - on_plane[3], on_plane[1] - on_plane[2]]
    angles = [math.atan2(e[1], e[0]) for e in x_edges]
    angles += [math.atan2(e[1], e[0]) - math.pi / 2 for e in y_edges]
    return math.atan2(sum(math.sin(a) for a in angles), sum(math.cos(a) for a in angles))


def estimate_tag_pose(
    frame: RGBDFrame, tag: TagSpec = HUMANOID_TAG, *, planar_heading: bool = True
) -> SE2Pose | None:
    """The humanoid's SE(2) pose (world frame) from one frame, or None when no tag is seen.

    Args:
        frame: one capture.
        tag: the tag's dictionary, id and size.
        planar_heading: heading from :func:`planar_yaw` (default) or from PnP's x axis.

    Returns None, never a guess, when the tag is not detected, PnP fails or the fit is
    tilted more than :data:`MAX_TILT_DEG` from horizontal.
    """
    return _tag_pose_and_corners(frame, tag, planar_heading)[0]


def _tag_pose_and_corners(
    frame: RGBDFrame, tag: TagSpec, planar_heading: bool = True
) -> tuple[SE2Pose, np.ndarray] | tuple[None, None]:
    """:func:`estimate_tag_pose` and the corners (pixels of ``frame``) it used (both None
    when no pose)."""
    corners = detect_tag_corners(frame.rgb, tag)
    if corners is None:
        return None, None
    T_camera_tag = tag_pose_in_camera(corners, frame, tag.side_m)
    if T_camera_tag is None:
        return None, None
    T_camera_tag[:3, 3] = _depth_range_correction(corners, frame, T_camera_tag[:3, 3])
    T_world_tag = np.asarray(frame.T_world_camera) @ T_camera_tag
    if T_world_tag[2, 2] < math.cos(math.radians(MAX_TILT_DEG)):
        return None, None
    if planar_heading:
        heading = planar_yaw(corners, frame, float(T_world_tag[2, 3]))
    else:
        heading = yaw_of(T_world_tag)
    return SE2Pose(float(T_world_tag[0, 3]), float(T_world_tag[1, 3]), heading), corners


WINDOW_MARGIN_PX = 40
"""How far around the tag's last sighting the next tag frame reaches, at least (pixels).

Between two tag frames of the walk (0.3 s, :class:`bearchair.skills.control.walk.WalkGains`) the
NAO moves at most 3 cm and turns at most 0.15 rad: 29 px at the near end of the arena
(0.6 m from the camera, fx = 577 px), less farther away. The margin is also at least the
tag's own size in the image. A tag not found in its window is looked for in a full frame.
"""


class _Sighting(NamedTuple):
    """The window around the tag's last sighting by an arm's camera, in full-image pixels."""

    x0: int
    y0: int
    width: int
    height: int
    image_width: int
    image_height: int


class TagSightings:
    """Where the tag was last seen by each arm's camera, for :func:`locate_humanoid`: the
    next frame is read out around it (arms that can). Owned by whoever tracks the
    humanoid (the mission's skills object, one per mission), not by the process.

    Weak keys: an arm's entry goes with the arm.
    """

    def __init__(self) -> None:
        self._last: weakref.WeakKeyDictionary[object, _Sighting] = weakref.WeakKeyDictionary()

    def get(self, arm: object) -> _Sighting | None:
        """The last sighting by this arm, or None."""
        return self._last.get(arm)

    def remember(self, arm: object, sighting: _Sighting) -> None:
        """This arm saw the tag in ``sighting``'s window."""
        self._last[arm] = sighting

    def forget(self, arm: object) -> None:
        """This arm moved or lost the tag: the next frame is a full one."""
        self._last.pop(arm, None)


def _window_around(corners_px: np.ndarray, image_width: int, image_height: int) -> _Sighting:
    """The window around corners given in full-image pixels."""
    size = float(np.max(corners_px.max(axis=0) - corners_px.min(axis=0)))
    margin = max(WINDOW_MARGIN_PX, size)
    x0, y0 = np.maximum(np.floor(corners_px.min(axis=0) - margin).astype(int), 0)
    x1, y1 = np.minimum(
        np.ceil(corners_px.max(axis=0) + margin).astype(int), [image_width, image_height]
    )
    return _Sighting(int(x0), int(y0), int(x1 - x0), int(y1 - y0), image_width, image_height)


def locate_humanoid(
    arm: ScanningArm,
    *,
    tag: TagSpec = HUMANOID_TAG,
    configuration: tuple[float, ...] = OVERVIEW_CONFIGURATION,
    sightings: TagSightings | None = None,
) -> SE2Pose | None:
    """Moves the arm to the overview through HOME (unless already there), captures and
    finds the tag.

    An arm whose camera can read out a window of its image (``capture_region(x0, y0,
    width, height)``, as the simulated one can) is asked only for the window around the
    tag's last sighting in ``sightings`` (:data:`WINDOW_MARGIN_PX`) while the arm has not
    moved since; if the tag is not in it, a full frame is taken. Only where the mission
    last saw the tag chooses the window; without ``sightings`` every frame is full.

    Returns:
        The humanoid's SE(2) pose in the world frame from this capture, or None when the
        tag is not in it.
    """
    sightings = sightings or TagSightings()
    current = np.asarray(arm.joint_positions(), dtype=np.float64)
    wanted = np.asarray(configuration, dtype=np.float64)
    if current.shape != wanted.shape or np.max(np.abs(current - wanted)) > AT_CONFIGURATION_RAD:
        sightings.forget(arm)
        arm.move_to(HOME_CONFIGURATION)
        arm.move_to(configuration)
    capture_region = getattr(arm, "capture_region", None)
    sighting = sightings.get(arm)
    if sighting is not None and capture_region is not None:
        frame = capture_region(sighting.x0, sighting.y0, sighting.width, sighting.height)
        pose, corners = _tag_pose_and_corners(frame, tag)
        if pose is not None:
            assert corners is not None  # found with the pose
            offset = np.array([sighting.x0, sighting.y0], dtype=np.float64)
            sightings.remember(
                arm, _window_around(corners + offset, sighting.image_width, sighting.image_height)
            )
            return pose
    frame = arm.capture()
    pose, corners = _tag_pose_and_corners(frame, tag)
    if pose is None:
        sightings.forget(arm)
    elif capture_region is not None:
        assert corners is not None  # found with the pose
        sightings.remember(
            arm, _window_around(corners, frame.intrinsics.width, frame.intrinsics.height)
        )
    return pose
