"""The ChArUco calibration board: its description, its printed image, its detection in
a colour image (the board's pose in the camera frame) and a check of its printed scale
against the depth image.

Frames: the board's frame is OpenCV's ChArUco frame: origin at the board's outer
top-left chessboard corner as printed, x along its rows (``squares_x``), y down its
columns, z into the board. The camera frame is OpenCV's optical frame (x right, y down,
z forward). Metres, pixels as named. The calibration that uses it:
:mod:`bearchair.skills.perception.hand_eye`.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from typing import NamedTuple, cast

import cv2
import numpy as np

from bearchair.hardware.interfaces import CameraIntrinsics
from bearchair.skills.perception.errors import BoardNotSeenError

MIN_BOARD_CORNERS = 6
"""Fewest ChArUco corners from which a board pose is computed (PnP needs 4 on a plane;
6, not on one line, leave some redundancy against one bad corner)."""

MAX_REPROJECTION_PX = 2.0
"""A board pose whose corners reproject worse than this (RMS, pixels) is refused: the
intrinsics are wrong, the board is bent, or a corner was misdetected."""

MIN_DEPTH_PIXELS = 200
"""Fewest valid depth pixels on the board for :func:`board_depth_ratio`."""


class BoardSpec(NamedTuple):
    """A printed ChArUco board.

    Attributes:
        squares_x: squares along the board's x axis (its long side).
        squares_y: squares along its y axis.
        square_m: side of one chessboard square as printed, metres (measure the print).
        marker_m: side of one ArUco marker inside a white square, metres.
        dictionary: the ``cv2.aruco`` predefined dictionary of the markers.
    """

    squares_x: int = 7
    squares_y: int = 5
    square_m: float = 0.030
    marker_m: float = 0.022
    dictionary: str = "DICT_5X5_50"

    def printed_at(self, square_m: float) -> BoardSpec:
        """The same board printed at another scale (a printer that shrinks the page)."""
        return self._replace(square_m=square_m, marker_m=self.marker_m * square_m / self.square_m)

    @property
    def corners(self) -> int:
        """Inner chessboard corners: the points a detection can find."""
        return (self.squares_x - 1) * (self.squares_y - 1)


CALIBRATION_BOARD = BoardSpec()
"""7 x 5 squares of 30 mm (21 x 15 cm: on A4 with its margins), 22 mm markers from
DICT_5X5_50: another dictionary than the NAO's head tag (DICT_4X4_50), so neither
detector mistakes a marker of the other for its own."""


class BoardDetection(NamedTuple):
    """The board's pose in one camera frame.

    Attributes:
        T_camera_board: 4x4, the board's frame in the camera's optical frame (metres).
        corners: ChArUco corners found (of :attr:`BoardSpec.corners`).
        reprojection_rms_px: RMS distance between the found corners and the pose's
            projection of the board's corners, pixels.
    """

    T_camera_board: np.ndarray
    corners: int
    reprojection_rms_px: float


@lru_cache(maxsize=8)
def charuco_board(board: BoardSpec) -> cv2.aruco.CharucoBoard:
    """The OpenCV board object of a :class:`BoardSpec` (OpenCV >= 4.7's ChArUco API)."""
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, board.dictionary))
    return cv2.aruco.CharucoBoard(
        (board.squares_x, board.squares_y), board.square_m, board.marker_m, dictionary
    )


@lru_cache(maxsize=8)
def _detector(board: BoardSpec) -> cv2.aruco.CharucoDetector:
    return cv2.aruco.CharucoDetector(charuco_board(board))


def board_image(
    board: BoardSpec = CALIBRATION_BOARD, pixels_per_square: int = 354, margin_squares: float = 0.5
) -> np.ndarray:
    """The printable board (grey uint8), with a white margin of ``margin_squares``.

    At the default 354 pixels per 30 mm square the picture is 300 dpi: print it at 100 %
    and measure a square (``bearchair calibrate-hand-eye --square-mm``). Board point
    (X, Y) lies at pixel ``margin + (X, Y) * pixels_per_square / square_m`` (pixel
    centres at integers minus one half: OpenCV's convention).
    """
    margin = round(margin_squares * pixels_per_square)
    size = (
        board.squares_x * pixels_per_square + 2 * margin,
        board.squares_y * pixels_per_square + 2 * margin,
    )
    return charuco_board(board).generateImage(size, marginSize=margin, borderBits=1)


def detect_board(
    rgb: np.ndarray,
    intrinsics: CameraIntrinsics,
    board: BoardSpec = CALIBRATION_BOARD,
    distortion: np.ndarray | None = None,
) -> BoardDetection:
    """The board's pose in the camera frame from one colour image.

    Finds the ArUco markers, interpolates the ChArUco corners between them (sub-pixel),
    and fits the pose by PnP for a plane (IPPE: both solutions of the planar ambiguity,
    the better kept), refined by Levenberg-Marquardt on the reprojection error.

    Args:
        rgb: (H, W, 3) uint8 colour image (or (H, W) grey).
        intrinsics: the camera's pinhole model in pixels.
        board: the printed board.
        distortion: OpenCV distortion coefficients; None for an undistorted image (the
            Carmine's and RealSense's registered images, with their factory models).

    Raises:
        BoardNotSeenError: fewer than :data:`MIN_BOARD_CORNERS` corners, corners on one
            line, no pose, or a pose that reprojects worse than :data:`MAX_REPROJECTION_PX`.
    """
    object_points, image_points, found = _board_corners(rgb, board)
    K = intrinsics.matrix()
    dist = np.zeros(5) if distortion is None else np.asarray(distortion, dtype=float)
    rvec, tvec = _planar_pose(object_points, image_points, K, dist, found)
    projected, _ = cv2.projectPoints(object_points, rvec, tvec, K, dist)
    offsets = projected.reshape(-1, 2) - np.asarray(image_points).reshape(-1, 2)
    rms = float(np.sqrt(np.mean(np.sum(offsets**2, axis=1))))
    if rms > MAX_REPROJECTION_PX:
        raise BoardNotSeenError(
            f"calibration board: its {found} corners reproject {rms:.2f} px RMS from the best "
            f"pose (at most {MAX_REPROJECTION_PX} px): wrong intrinsics or a bent board"
        )
    T_camera_board = np.eye(4)
    T_camera_board[:3, :3] = cv2.Rodrigues(rvec)[0]
    T_camera_board[:3, 3] = np.asarray(tvec).reshape(3)
    return BoardDetection(T_camera_board, found, rms)


def _board_corners(rgb: np.ndarray, board: BoardSpec) -> tuple[np.ndarray, np.ndarray, int]:
    """The ChArUco corners found in the image: (board points, image points, how many).

    Raises:
        BoardNotSeenError: fewer than :data:`MIN_BOARD_CORNERS` corners, or on one line.
    """
    image = np.ascontiguousarray(rgb)
    gray = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image
    corners_px, ids, _, marker_ids = _detector(board).detectBoard(gray)
    found = 0 if ids is None else len(ids)
    markers = 0 if marker_ids is None else len(marker_ids)
    if found < MIN_BOARD_CORNERS:
        raise BoardNotSeenError(
            f"calibration board not seen: {found} of its {board.corners} corners found "
            f"({markers} markers), at least {MIN_BOARD_CORNERS} needed"
        )
    cv_board = charuco_board(board)
    if cv_board.checkCharucoCornersCollinear(ids):
        raise BoardNotSeenError(
            f"calibration board seen edge-on: its {found} corners found lie on one line"
        )
    # cv2's stubs type an InputArrayOfArrays as a sequence; the (N, 1, 2) array is one.
    object_points, image_points = cv_board.matchImagePoints(
        cast(Sequence[np.ndarray], corners_px), ids
    )
    return object_points, image_points, found


def _planar_pose(
    object_points: np.ndarray,
    image_points: np.ndarray,
    K: np.ndarray,
    dist: np.ndarray,
    found: int,
) -> tuple[np.ndarray, np.ndarray]:
    """(rvec, tvec) of the board from its ``found`` corners: the better IPPE solution,
    refined by Levenberg-Marquardt.

    Raises:
        BoardNotSeenError: no pose fits the corners.
    """
    count, rvecs, tvecs, errors = cv2.solvePnPGeneric(
        object_points, image_points, K, dist, flags=cv2.SOLVEPNP_IPPE
    )
    if not count:
        raise BoardNotSeenError(f"calibration board: no pose fits its {found} corners")
    best = int(np.argmin(np.asarray(errors).reshape(-1)))
    return cv2.solvePnPRefineLM(object_points, image_points, K, dist, rvecs[best], tvecs[best])


def board_depth_ratio(
    detection: BoardDetection,
    depth_m: np.ndarray,
    intrinsics: CameraIntrinsics,
    board: BoardSpec = CALIBRATION_BOARD,
) -> float | None:
    """The depth image's distance to the board over the distance its pose gives.

    Over the pixels of the chessboard's inner 80 % (away from its edges' mixed depths),
    the median of measured depth over the depth of the board's plane at that pixel. 1
    when the printed size, the colour intrinsics and the depth agree; a board printed
    ``s`` times its nominal size (with the nominal size given) reads ``s``.

    Returns:
        The ratio, or None with fewer than :data:`MIN_DEPTH_PIXELS` valid depth pixels.
    """
    T = detection.T_camera_board
    width, height = board.squares_x * board.square_m, board.squares_y * board.square_m
    centre = np.array([width / 2.0, height / 2.0, 0.0])
    outline = np.array(
        [[0.0, 0.0, 0.0], [width, 0.0, 0.0], [width, height, 0.0], [0.0, height, 0.0]]
    )
    inner = centre + 0.8 * (outline - centre)
    in_camera = (T[:3, :3] @ inner.T).T + T[:3, 3]
    if np.any(in_camera[:, 2] <= 0.0):
        return None
    K = intrinsics.matrix()
    pixels = (K @ in_camera.T).T
    pixels = pixels[:, :2] / pixels[:, 2:]
    depth = np.asarray(depth_m, dtype=np.float64)
    mask = np.zeros(depth.shape, dtype=np.uint8)
    cv2.fillConvexPoly(mask, np.round(pixels).astype(np.int32), 1)
    rows, cols = np.nonzero((mask > 0) & np.isfinite(depth) & (depth > 0.0))
    if len(rows) < MIN_DEPTH_PIXELS:
        return None
    rays = np.linalg.inv(K) @ np.vstack((cols, rows, np.ones(len(rows))))
    normal = T[:3, 2]
    plane_depth = float(normal @ T[:3, 3]) / (normal @ rays)
    return float(np.median(depth[rows, cols] / plane_depth))
