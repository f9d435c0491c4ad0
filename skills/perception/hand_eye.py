"""Hand-eye calibration of the wrist camera: ``T_flange_camera`` from views of a ChArUco board.

Eye-in-hand: the camera rides on the Panda's flange and looks at a board lying still in
the cell. For every view ``i`` the arm gives ``T_base_flange_i`` (libfranka's
``O_T_EE @ inv(F_T_EE)``, as :class:`bearchair.hardware.real.panda.PandaArm` computes it) and the
camera sees the board at ``T_camera_board_i``
(:func:`bearchair.skills.perception.charuco.detect_board`). The board does
not move, so for every view

    T_base_board = T_base_flange_i @ T_flange_camera @ T_camera_board_i,

and for every two views ``i, j`` this is the classic ``A X = X B`` with
``A = inv(T_base_flange_j) @ T_base_flange_i`` (the flange's motion),
``B = T_camera_board_j @ inv(T_camera_board_i)`` (the camera's motion, seen through the
board) and ``X = T_flange_camera``.

Method (:func:`solve_hand_eye`): Park & Martin (1994), OpenCV's ``CALIB_HAND_EYE_PARK``,
over every pair of views. Rotation first: the rotation vectors of the motions satisfy
``alpha_ij = R_X beta_ij``, a least-squares rotation fit with a closed-form answer (here
by SVD, which stays a proper rotation even from only three views, where Park's
``(M^T M)^(-1/2)`` has no inverse); then the translation by linear least squares from
``(R_A - I) t_X = R_X t_B - t_A``. It needs no initial guess and no iteration, weighs all
pairs alike, and in published comparisons (Tsai, Park, Horaud, Andreff, Daniilidis on
noisy data) it is as accurate as the best; Andreff's linear form can return a matrix that
is not a rotation, and Daniilidis' dual quaternions need consistent quaternion signs.
OpenCV 5.0.0.93's wheel did not bind ``cv2.calibrateHandEye`` (opencv/opencv#29565; 5.1
binds it) and the pinned range admits it, so the same method is written here in numpy:
one code path on every OpenCV version. ``tests/test_hand_eye.py`` compares
it with ``cv2.calibrateHandEye(..., method=cv2.CALIB_HAND_EYE_PARK)`` where a wheel has it.

Checks (:class:`~skills.perception.errors.HandEyeError`, one line each): fewer than
:data:`MIN_VIEWS` pairs; flange rotations that turn about fewer than two axes (the
rotation about the one axis, and the translation along it, are then undetermined:
:func:`rotation_diversity_deg` below :data:`MIN_ROTATION_DIVERSITY_DEG`); a board not seen
(:class:`~skills.perception.errors.BoardNotSeenError`). The answer's residuals
(:func:`board_pose_residuals`) are the spread of the board's pose in the base frame over
the views: zero for perfect data, and the honest measure of how far to trust it, except
for the board's scale: a square printed smaller than its nominal size moves every board
pose proportionally closer, which the views, all about as far from the board, absorb
into the camera's offset along its optical axis without a residual.
:func:`bearchair.skills.perception.charuco.board_depth_ratio` checks that scale against
the depth image instead.

Frames: the board's frame is OpenCV's ChArUco frame: origin at the board's outer
top-left chessboard corner as printed, x along its rows (``squares_x``), y down its
columns, z into the board. The camera frame is OpenCV's optical frame (x right, y down,
z forward). Metres and radians throughout; residuals in millimetres and degrees, as
named.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from bearchair.skills.perception.errors import HandEyeError

MIN_VIEWS = 3
"""Fewest (T_base_flange, T_camera_board) pairs solved: two motions about different axes
are the least that fix ``T_flange_camera`` (Tsai & Lenz); three views give three."""

MIN_ROTATION_DIVERSITY_DEG = 5.0
"""Least rotation about a second axis (:func:`rotation_diversity_deg`) accepted. With all
motions about one axis the rotation about it and the translation along it are free; near
that, noise in the board's pose is amplified by about the inverse of this angle. The
stored :data:`CALIBRATION_CONFIGURATIONS` give about 16 degrees."""

MAX_SPREAD_MM = 8.0
"""Acceptance (``bearchair calibrate-hand-eye``): the board's position over the views
must agree within this (largest deviation from the mean): one TSDF voxel of the chair
reconstruction (:class:`bearchair.skills.perception.reconstruction.ReconstructionConfig`, 8 mm)."""

MAX_SPREAD_DEG = 1.0
"""Acceptance: the board's orientation over the views agrees within this (largest
deviation from the mean); 1 degree moves a point 0.5 m away by 9 mm, again one voxel."""

MAX_SCALE_ERROR = 0.02
"""Acceptance: the depth camera's distance to the board and the distance its printed
size gives (:func:`~bearchair.skills.perception.charuco.board_depth_ratio`) agree within 2 %. The residuals cannot see a
wrong square size: with every view about as far from the board, a board printed 3 %
small moves every board pose 3 % closer, which the solve absorbs as a camera 14 mm
farther along its optical axis, with residuals as small as before. 2 % (10 mm at
0.5 m) is above the structured-light depth's own error there and below the 3-6 % a
"fit to page" print loses."""

BOARD_CENTRE_BASE_XY_M = (0.6, 0.0)
"""Where the board lies for :data:`CALIBRATION_CONFIGURATIONS`: flat on the floor, face
up, its centre at this point of the arm's base frame (the chair area's centre), any way
round (the views see all of it for any yaw if the centre is within about 5 cm)."""

CALIBRATION_CONFIGURATIONS: tuple[tuple[float, ...], ...] = (
    # Chosen offline by inverse kinematics on pybullet_data's panda.urdf with the
    # simulated camera mount (hardware.sim.camera.T_HAND_CAMERA on panda_hand): each puts
    # the camera 0.5 m from the board's centre, looking at it, tilted from vertical by
    # `tilt`, from the side `azimuth` (0 = beyond the board, 180 = from the arm), turned
    # about the optical axis by `roll`; joints 0.05 rad inside panda-py's walls, close to
    # HOME. Along the straight joint-space motion from HOME to each, every link from
    # panda_link2 on (the base and panda_link1 stand on the floor) stays 0.26 m above the
    # floor. tests/test_hand_eye.py checks that (> 0.25 m), the walls, and that a board
    # anywhere within 5 cm of its place, at any yaw, is in view from each.
    # tilt 20, azimuth 180, roll 0
    (-0.0554, -0.6978, 0.0527, -2.7020, 0.0519, 2.3463, 0.7464),
    # tilt 30, azimuth 150, roll 30
    (-0.5881, -1.0129, 1.0634, -2.6461, 0.6240, 2.3125, 1.8171),
    # tilt 30, azimuth 210, roll -30
    (0.4767, -0.8769, -0.9702, -2.6653, -0.4175, 2.3895, -0.3963),
    # tilt 25, azimuth 90, roll -40
    (0.4086, 0.2730, 0.1055, -1.6245, -0.4042, 1.6586, 2.2536),
    # tilt 25, azimuth 270, roll 40
    (-0.4291, 0.2723, -0.0820, -1.6252, 0.3987, 1.6606, -0.6795),
    # tilt 25, azimuth 120, roll 0
    (0.1702, -0.0901, 0.3552, -2.1318, -0.4440, 2.0019, 2.5512),
    # tilt 25, azimuth 240, roll 20
    (-0.1818, -0.1605, -0.3315, -2.2045, 0.4248, 2.0163, -0.6126),
    # tilt 10, azimuth 180, roll 45
    (-0.1402, -0.3401, 0.2153, -2.2691, 0.0713, 2.1041, 1.6071),
    # tilt 20, azimuth 200, roll -45
    (0.2601, -0.5403, -0.5118, -2.5014, -0.0964, 2.3104, -0.5185),
)
"""Nine arm configurations (radians) looking at the board from different sides; the
first three already turn about different axes, so ``--views 3`` is solvable."""


class HandEyeResiduals(NamedTuple):
    """How well the views agree on the board's pose in the arm's base frame.

    Attributes:
        T_base_board: the mean board pose over the views (translation mean; rotation the
            chordal mean, the nearest rotation to the sum of the views' rotations).
        translation_mm: per view, its board position's distance from the mean (mm).
        rotation_deg: per view, its board orientation's angle from the mean (degrees).
    """

    T_base_board: np.ndarray
    translation_mm: tuple[float, ...]
    rotation_deg: tuple[float, ...]

    @property
    def max_mm(self) -> float:
        """The largest position deviation (mm)."""
        return max(self.translation_mm)

    @property
    def max_deg(self) -> float:
        """The largest orientation deviation (degrees)."""
        return max(self.rotation_deg)

    @property
    def rms_mm(self) -> float:
        """RMS position deviation (mm)."""
        return float(np.sqrt(np.mean(np.square(self.translation_mm))))

    @property
    def rms_deg(self) -> float:
        """RMS orientation deviation (degrees)."""
        return float(np.sqrt(np.mean(np.square(self.rotation_deg))))

    def acceptable(self) -> bool:
        """Within :data:`MAX_SPREAD_MM` and :data:`MAX_SPREAD_DEG`."""
        return self.max_mm <= MAX_SPREAD_MM and self.max_deg <= MAX_SPREAD_DEG

    def to_json(self) -> dict[str, Any]:
        """JSON-ready numbers (mm, degrees)."""
        return {
            "max_mm": round(self.max_mm, 3),
            "rms_mm": round(self.rms_mm, 3),
            "max_deg": round(self.max_deg, 4),
            "rms_deg": round(self.rms_deg, 4),
            "translation_mm": [round(v, 3) for v in self.translation_mm],
            "rotation_deg": [round(v, 4) for v in self.rotation_deg],
            "T_base_board": np.round(self.T_base_board, 6).tolist(),
        }


class HandEyeCalibration(NamedTuple):
    """The solved hand-eye transform.

    Attributes:
        T_flange_camera: 4x4, the camera's optical frame in the Panda's flange frame.
        residuals: the board pose's spread over the views under this answer.
        views: pairs solved from.
        rotation_diversity_deg: :func:`rotation_diversity_deg` of the flange poses.
    """

    T_flange_camera: np.ndarray
    residuals: HandEyeResiduals
    views: int
    rotation_diversity_deg: float

    def cell_entry(self) -> dict[str, list[list[float]]]:
        """``{"T_flange_camera": [[...], ...]}`` for the cell file (micrometres, 1e-6)."""
        T = np.round(self.T_flange_camera, 6)
        T[3] = (0.0, 0.0, 0.0, 1.0)
        return {"T_flange_camera": (T + 0.0).tolist()}  # + 0.0: no "-0.0" in the file


def _rigid(T: Any, name: str) -> np.ndarray:
    """``T`` as a float 4x4, or HandEyeError naming it when it is not a rigid transform."""
    matrix = np.asarray(T, dtype=float)
    if matrix.shape != (4, 4) or not np.all(np.isfinite(matrix)):
        raise HandEyeError(f"hand-eye: {name} is not a finite 4x4 matrix")
    rotation = matrix[:3, :3]
    if (
        np.max(np.abs(rotation.T @ rotation - np.eye(3))) > 1e-6
        or abs(np.linalg.det(rotation) - 1.0) > 1e-6
        or not np.allclose(matrix[3], (0.0, 0.0, 0.0, 1.0))
    ):
        raise HandEyeError(f"hand-eye: {name} is not a rigid transform (scaled or mirrored)")
    return matrix


def _pairs(count: int) -> list[tuple[int, int]]:
    return [(i, j) for i in range(count) for j in range(i + 1, count)]


def rotation_diversity_deg(T_base_flange: Sequence[np.ndarray]) -> float:
    """How much the flange's relative rotations turn about a second axis (degrees).

    The rotation vectors of the flange's motion between every two views, stacked, have
    as second singular value (per pair, RMS) the rotation that is not about their
    principal axis: 0 when every motion turns about one axis, or none turns at all.
    """
    poses = [np.asarray(T, dtype=float) for T in T_base_flange]
    vectors = [
        Rotation.from_matrix((np.linalg.inv(poses[j]) @ poses[i])[:3, :3]).as_rotvec()
        for i, j in _pairs(len(poses))
    ]
    if len(vectors) < 2:
        return 0.0
    singular = np.linalg.svd(np.asarray(vectors), compute_uv=False)
    return math.degrees(float(singular[1]) / math.sqrt(len(vectors)))


def _nearest_rotation(matrix: np.ndarray) -> np.ndarray:
    """The rotation nearest (Frobenius) to a 3x3 matrix."""
    u, _, vt = np.linalg.svd(matrix)
    return u @ np.diag([1.0, 1.0, float(np.sign(np.linalg.det(u @ vt)))]) @ vt


def board_pose_residuals(
    T_base_flange: Sequence[np.ndarray],
    T_camera_board: Sequence[np.ndarray],
    T_flange_camera: np.ndarray,
) -> HandEyeResiduals:
    """The spread of ``T_base_flange_i @ T_flange_camera @ T_camera_board_i`` over the views.

    With the right ``T_flange_camera`` and exact data every view puts the board at one
    pose in the base frame; each view's distance from their mean is its residual.
    """
    boards = [
        np.asarray(F, dtype=float) @ T_flange_camera @ np.asarray(C, dtype=float)
        for F, C in zip(T_base_flange, T_camera_board, strict=True)
    ]
    mean = np.eye(4)
    mean[:3, 3] = np.mean([T[:3, 3] for T in boards], axis=0)
    mean[:3, :3] = _nearest_rotation(np.sum([T[:3, :3] for T in boards], axis=0))
    translation_mm = tuple(float(np.linalg.norm(T[:3, 3] - mean[:3, 3]) * 1000.0) for T in boards)
    rotation_deg = tuple(
        math.degrees(Rotation.from_matrix(mean[:3, :3].T @ T[:3, :3]).magnitude()) for T in boards
    )
    return HandEyeResiduals(mean, translation_mm, rotation_deg)


def solve_hand_eye(
    T_base_flange: Sequence[np.ndarray], T_camera_board: Sequence[np.ndarray]
) -> HandEyeCalibration:
    """``T_flange_camera`` from views of a still board (Park & Martin, every view pair).

    Args:
        T_base_flange: per view, the flange in the arm's base frame (4x4, metres).
        T_camera_board: per view, the board in the camera frame (4x4, metres), in the
            same order.

    Raises:
        HandEyeError: the lists differ in length or hold a matrix that is not rigid;
            fewer than :data:`MIN_VIEWS` views; the flange's rotations turn about fewer
            than two axes (:func:`rotation_diversity_deg` below
            :data:`MIN_ROTATION_DIVERSITY_DEG`).
    """
    if len(T_base_flange) != len(T_camera_board):
        raise HandEyeError(
            f"hand-eye: {len(T_base_flange)} flange poses but {len(T_camera_board)} board poses"
        )
    if len(T_base_flange) < MIN_VIEWS:
        raise HandEyeError(
            f"hand-eye: {len(T_base_flange)} views, at least {MIN_VIEWS} needed "
            "(two motions about different axes)"
        )
    flange = [_rigid(T, f"T_base_flange[{i}]") for i, T in enumerate(T_base_flange)]
    board = [_rigid(T, f"T_camera_board[{i}]") for i, T in enumerate(T_camera_board)]
    diversity = rotation_diversity_deg(flange)
    if diversity < MIN_ROTATION_DIVERSITY_DEG:
        raise HandEyeError(
            f"hand-eye: the flange rotations are too alike: they turn {diversity:.1f} deg "
            f"about a second axis, at least {MIN_ROTATION_DIVERSITY_DEG:g} needed "
            "(tilt the camera about two different axes between views)"
        )
    motions = [
        (np.linalg.inv(flange[j]) @ flange[i], board[j] @ np.linalg.inv(board[i]))
        for i, j in _pairs(len(flange))
    ]
    # alpha = R_X beta for every motion: the rotation that best maps the betas onto the
    # alphas (orthogonal Procrustes), a proper rotation by the determinant's sign.
    alphas = np.array([Rotation.from_matrix(A[:3, :3]).as_rotvec() for A, _ in motions])
    betas = np.array([Rotation.from_matrix(B[:3, :3]).as_rotvec() for _, B in motions])
    u, _, vt = np.linalg.svd(betas.T @ alphas)
    sign = float(np.sign(np.linalg.det(vt.T @ u.T)))
    R_X = vt.T @ np.diag([1.0, 1.0, sign]) @ u.T
    # (R_A - I) t_X = R_X t_B - t_A, stacked over the motions.
    lhs = np.vstack([A[:3, :3] - np.eye(3) for A, _ in motions])
    rhs = np.concatenate([R_X @ B[:3, 3] - A[:3, 3] for A, B in motions])
    t_X = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
    T_flange_camera = np.eye(4)
    T_flange_camera[:3, :3] = R_X
    T_flange_camera[:3, 3] = t_X
    residuals = board_pose_residuals(flange, board, T_flange_camera)
    return HandEyeCalibration(T_flange_camera, residuals, len(flange), diversity)
