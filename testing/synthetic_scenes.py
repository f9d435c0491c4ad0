"""Rendered RGB-D frames for tests and benchmarks (not a simulated world).

A minimal, physics-free pybullet scene (DIRECT client, TinyRenderer) holding meshes,
a floor, ArUco tags and ChArUco calibration boards, seen by the simulated Carmine of
:mod:`bearchair.hardware.sim.camera` (the same intrinsics, rendering and noise model as the
mission's wrist camera); and :class:`SyntheticArm`, a
:class:`bearchair.hardware.interfaces.ScanningArm` whose camera pose comes from the Panda's forward
kinematics. The mission uses ``bearchair.hardware.sim``; this module exists so the perception
algorithms can be tested on their own. :func:`board_view` draws a calibration board by
its homography alone (no pybullet).
"""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np
import pybullet
import trimesh
from pybullet_utils.bullet_client import BulletClient

from bearchair.core.arena import TagSpec
from bearchair.hardware.interfaces import CameraIntrinsics, RGBDFrame
from bearchair.hardware.sim.camera import (
    CARMINE_INTRINSICS,
    CarmineNoise,
    carmine_images,
    render_view,
)
from bearchair.hardware.wrist_mount import T_HAND_CAMERA
from bearchair.skills.perception.panda_kinematics import PandaKinematics

if TYPE_CHECKING:
    from bearchair.skills.perception.charuco import BoardSpec


class SyntheticScene:
    """Meshes, a floor and tags in a pybullet DIRECT client, rendered by TinyRenderer.

    Args:
        floor: lay a 6 m x 6 m floor at z = 0.
        noise: apply the Carmine's noise model (else only its range limits).
        seed: the noise's seed.
    """

    def __init__(self, *, floor: bool = True, noise: bool = True, seed: int = 0) -> None:
        self.bullet: BulletClient | None = BulletClient(connection_mode=pybullet.DIRECT)
        self._scratch = tempfile.TemporaryDirectory(prefix="bearchair-synthetic-")
        self._rng = np.random.default_rng(seed)
        self._noise = CarmineNoise() if noise else None
        self._count = 0
        if floor:
            shape = self.bullet.createVisualShape(
                pybullet.GEOM_BOX,
                halfExtents=[3.0, 3.0, 0.01],
                rgbaColor=[0.55, 0.5, 0.45, 1.0],
            )
            self.bullet.createMultiBody(0, -1, shape, basePosition=[0, 0, -0.01])

    def close(self) -> None:
        """Disconnects the client and removes the scratch files."""
        if self.bullet is not None:
            self.bullet.disconnect()
            self.bullet = None
        self._scratch.cleanup()

    def _client(self) -> BulletClient:
        """The scene's pybullet client.

        Raises:
            RuntimeError: the scene is closed.
        """
        if self.bullet is None:
            raise RuntimeError("the synthetic scene is closed")
        return self.bullet

    def add_mesh(
        self,
        mesh: trimesh.Trimesh,
        T_world_mesh: np.ndarray | None = None,
        rgba: Sequence[float] = (0.7, 0.45, 0.25, 1.0),
    ) -> int:
        """Adds a mesh (exported to OBJ) and returns its body id."""
        self._count += 1
        path = Path(self._scratch.name) / f"mesh{self._count}.obj"
        mesh.export(path)
        bullet = self._client()
        shape = bullet.createVisualShape(
            pybullet.GEOM_MESH, fileName=str(path), rgbaColor=list(rgba)
        )
        body = bullet.createMultiBody(0, -1, shape)
        self.set_pose(body, np.eye(4) if T_world_mesh is None else T_world_mesh)
        return body

    def add_tag(self, tag: TagSpec, T_world_tag: np.ndarray, border_cells: float = 1.0) -> int:
        """Adds a flat ArUco tag (black square of ``tag.side_m``) with a white margin.

        The tag frame is OpenCV's marker frame: x to the marker image's right, y up in the
        image, z out of the printed face.
        """
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, tag.dictionary))
        cells = dictionary.markerSize + 2
        cell_px = 40
        marker = cv2.aruco.generateImageMarker(dictionary, tag.marker_id, cells * cell_px)
        pad = int(border_cells * cell_px)
        image = cv2.copyMakeBorder(marker, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255)
        half = 0.5 * tag.side_m * image.shape[0] / marker.shape[0]
        obj_text = (
            f"v {-half} {-half} 0\nv {half} {-half} 0\nv {half} {half} 0\nv {-half} {half} 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
            "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n"
        )
        return self._add_textured_quad("tag", image, obj_text, T_world_tag)

    def add_board(self, board: BoardSpec, T_world_board: np.ndarray) -> int:
        """Adds a printed ChArUco board (white margin of half a square) at ``T_world_board``.

        The body's frame is the board's (:mod:`bearchair.skills.perception.hand_eye`): origin at the
        outer top-left chessboard corner, x along its rows, y down its columns, z into the
        board; the printed face looks along -z.
        """
        from bearchair.skills.perception.charuco import board_image

        pixels_per_square = 60
        image = board_image(board, pixels_per_square=pixels_per_square, margin_squares=0.5)
        metres_per_px = board.square_m / pixels_per_square
        margin_m = 0.5 * board.square_m
        x0, y0 = -margin_m, -margin_m
        x1, y1 = x0 + image.shape[1] * metres_per_px, y0 + image.shape[0] * metres_per_px
        # The image's top row is texture v = 1 and lies at board y = y0.
        obj_text = (
            f"v {x0} {y0} 0\nv {x1} {y0} 0\nv {x1} {y1} 0\nv {x0} {y1} 0\n"
            "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nvn 0 0 -1\n"
            "f 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n"
        )
        return self._add_textured_quad("board", image, obj_text, T_world_board)

    def _add_textured_quad(
        self, name: str, image: np.ndarray, obj_text: str, T_world_body: np.ndarray
    ) -> int:
        """A body showing the grey ``image`` on the quad ``obj_text`` (an OBJ with texture
        coordinates) at ``T_world_body``: pybullet reads meshes and textures from files
        only, so both go to the scratch folder first."""
        self._count += 1
        png = Path(self._scratch.name) / f"{name}{self._count}.png"
        cv2.imwrite(str(png), cv2.cvtColor(image, cv2.COLOR_GRAY2RGB))
        obj = Path(self._scratch.name) / f"{name}{self._count}.obj"
        obj.write_text(obj_text)
        bullet = self._client()
        shape = bullet.createVisualShape(pybullet.GEOM_MESH, fileName=str(obj))
        body = bullet.createMultiBody(0, -1, shape)
        texture = bullet.loadTexture(str(png))
        bullet.changeVisualShape(body, -1, textureUniqueId=texture, rgbaColor=[1, 1, 1, 1])
        self.set_pose(body, T_world_body)
        return body

    def set_pose(self, body: int, T_world_body: np.ndarray) -> None:
        """Places a body (its mesh frame) at a world pose."""
        quat = _quaternion_xyzw(T_world_body[:3, :3])
        self._client().resetBasePositionAndOrientation(body, T_world_body[:3, 3].tolist(), quat)

    def remove(self, body: int) -> None:
        """Removes a body from the scene."""
        self._client().removeBody(body)

    def render(
        self,
        T_world_camera: np.ndarray,
        intrinsics: CameraIntrinsics = CARMINE_INTRINSICS,
        stamp_s: float = 0.0,
    ) -> RGBDFrame:
        """What the Carmine sees from an OpenCV camera pose: colour and depth (metres
        along the optical axis, 0 = missing)."""
        view = render_view(self._client(), T_world_camera, intrinsics)
        rgb, depth = carmine_images(view, intrinsics, self._noise, self._rng)
        return RGBDFrame(
            rgb, depth, intrinsics, np.asarray(T_world_camera, dtype=np.float64).copy(), stamp_s
        )


class SyntheticArm:
    """A :class:`bearchair.hardware.interfaces.ScanningArm` that teleports and renders a scene.

    Motions are instantaneous; a clock, if given, advances by ``seconds_per_move``.
    """

    def __init__(
        self,
        scene: SyntheticScene,
        initial_joints_rad: Sequence[float] = (0.0, -0.5, 0.0, -2.3, 0.0, 1.9, 0.785),
        T_hand_camera: np.ndarray = T_HAND_CAMERA,
    ) -> None:
        self.scene = scene
        self.kinematics = PandaKinematics()
        self.T_hand_camera = T_hand_camera
        self._joints = np.asarray(initial_joints_rad, dtype=np.float64)
        self.moves = 0
        self.captures = 0
        self.stamp_s = 0.0

    def joint_positions(self) -> np.ndarray:
        return self._joints.copy()

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        self._joints = np.asarray(joint_positions_rad, dtype=np.float64).copy()
        self.moves += 1

    def capture(self) -> RGBDFrame:
        self.captures += 1
        T_world_camera = self.kinematics.camera_pose(self._joints, self.T_hand_camera)
        return self.scene.render(T_world_camera, stamp_s=self.stamp_s)

    def close(self) -> None:
        self.kinematics.close()


def board_view(
    board: BoardSpec,
    T_camera_board: np.ndarray,
    intrinsics: CameraIntrinsics,
    background: int = 110,
    noise_grey: float = 2.0,
    seed: int = 0,
) -> np.ndarray:
    """A camera's (H, W, 3) uint8 picture of a printed board at ``T_camera_board``.

    The printed board (:func:`bearchair.skills.perception.charuco.board_image`) is mapped by the
    plane's homography ``K [r1 r2 t]`` at twice the resolution and averaged down 2 x 2
    (so edges are anti-aliased as a lens and sensor would), on a grey background, with
    Gaussian grey noise. Exact pinhole geometry, no distortion, no lighting.
    """
    from bearchair.skills.perception.charuco import board_image

    pixels_per_square = 120
    margin_px = pixels_per_square // 2
    image = board_image(board, pixels_per_square=pixels_per_square, margin_squares=0.5)
    scale = board.square_m / pixels_per_square
    # Board-image pixel centre (i, j) is board point ((i + 0.5 - margin) * scale, ...).
    pixel_to_board = np.array(
        [
            [scale, 0.0, (0.5 - margin_px) * scale],
            [0.0, scale, (0.5 - margin_px) * scale],
            [0.0, 0.0, 1.0],
        ]
    )
    # The double-resolution camera: pixel centres at 2 u + 0.5.
    K2 = intrinsics.matrix() * np.array([[2.0], [2.0], [1.0]])
    K2[0, 2] += 0.5
    K2[1, 2] += 0.5
    T = np.asarray(T_camera_board, dtype=float)
    homography = K2 @ np.column_stack((T[:3, 0], T[:3, 1], T[:3, 3])) @ pixel_to_board
    big = cv2.warpPerspective(
        image,
        homography,
        (2 * intrinsics.width, 2 * intrinsics.height),
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=background,
    )
    grey = cv2.resize(big, (intrinsics.width, intrinsics.height), interpolation=cv2.INTER_AREA)
    rng = np.random.default_rng(seed)
    noisy = np.clip(grey + rng.normal(0.0, noise_grey, grey.shape), 0, 255).astype(np.uint8)
    return cv2.cvtColor(noisy, cv2.COLOR_GRAY2RGB)


def _quaternion_xyzw(rotation: np.ndarray) -> list[float]:
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(rotation).as_quat().tolist()
