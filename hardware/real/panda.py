"""The Franka Panda through ``panda_py`` with a PrimeSense Carmine 1.09 on its wrist
through OpenNI2 (``openni``).

The camera pose of each frame comes from forward kinematics: ``T_world_camera =
T_world_base @ T_base_hand(q) @ T_hand_camera``, with ``T_base_hand`` measured by the
arm (libfranka's O_T_EE with the end effector frame set to the flange) and
``T_hand_camera`` the hand-eye calibration.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from hardware.interfaces import CameraIntrinsics, RGBDFrame
from hardware.real import BackendUnavailable, import_sdk

# The Carmine 1.09's factory depth intrinsics at 640x480 (replace with a calibration).
CARMINE_INTRINSICS = CameraIntrinsics(640, 480, 570.3, 570.3, 319.5, 239.5)


class CarmineCamera:
    """RGB-D frames from a PrimeSense Carmine through OpenNI2, depth registered to colour."""

    def __init__(self, intrinsics: CameraIntrinsics = CARMINE_INTRINSICS) -> None:
        openni2 = import_sdk("openni.openni2", "openni")
        try:
            openni2.initialize()
            self._device = openni2.Device.open_any()
        except Exception as error:
            raise BackendUnavailable(f"no OpenNI2 camera found: {error}") from error
        self._device.set_image_registration_mode(openni2.IMAGE_REGISTRATION_DEPTH_TO_COLOR)
        self._depth = self._device.create_depth_stream()
        self._colour = self._device.create_color_stream()
        self._depth.start()
        self._colour.start()
        self.intrinsics = intrinsics

    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """One (rgb uint8 HxWx3, depth metres float32 HxW, 0 = missing) pair."""
        h, w = self.intrinsics.height, self.intrinsics.width
        depth_mm = np.frombuffer(self._depth.read_frame().get_buffer_as_uint16(), np.uint16)
        rgb = np.frombuffer(self._colour.read_frame().get_buffer_as_uint8(), np.uint8)
        return rgb.reshape(h, w, 3).copy(), depth_mm.reshape(h, w).astype(np.float32) / 1000.0


class PandaArm:
    """:class:`hardware.interfaces.ScanningArm` on a real Panda.

    Args:
        robot: a ``panda_py.Panda`` (or a test double with ``move_to_joint_position``,
            ``get_state().q`` and ``get_pose()``).
        camera: the wrist camera.
        T_world_base: the arm base in the world frame.
        T_hand_camera: the hand-eye calibration (camera optical frame in the flange frame).
        speed_factor: fraction of the arm's velocity limits for scanning moves.
    """

    def __init__(
        self,
        robot: Any,
        camera: Any,
        T_world_base: np.ndarray,
        T_hand_camera: np.ndarray,
        speed_factor: float = 0.2,
    ) -> None:
        self._robot = robot
        self._camera = camera
        self._T_world_base = np.asarray(T_world_base, dtype=float)
        self._T_hand_camera = np.asarray(T_hand_camera, dtype=float)
        self._speed_factor = speed_factor
        self._start = time.monotonic()

    @classmethod
    def connect(cls, host: str, T_world_base: np.ndarray, T_hand_camera: np.ndarray) -> PandaArm:
        """Connects to the arm's controller at ``host`` and opens the wrist camera."""
        panda_py = import_sdk("panda_py", "panda-python")
        try:
            robot = panda_py.Panda(host)
        except Exception as error:
            raise BackendUnavailable(f"cannot reach the Panda at {host}: {error}") from error
        return cls(robot, CarmineCamera(), T_world_base, T_hand_camera)

    def joint_positions(self) -> np.ndarray:
        return np.asarray(self._robot.get_state().q, dtype=float)

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        target = np.asarray(joint_positions_rad, dtype=float)
        if target.shape != (7,):
            raise ValueError(f"the Panda has 7 joints, got {target.shape}")
        if not self._robot.move_to_joint_position(target, speed_factor=self._speed_factor):
            raise TimeoutError(f"the Panda did not reach {np.round(target, 3).tolist()}")

    def capture(self) -> RGBDFrame:
        # Read the pose before and after the frame: a moving arm would smear the fusion.
        T_base_hand = np.asarray(self._robot.get_pose(), dtype=float)
        rgb, depth_m = self._camera.read()
        return RGBDFrame(
            rgb=rgb,
            depth_m=depth_m,
            intrinsics=self._camera.intrinsics,
            T_world_camera=self._T_world_base @ T_base_hand @ self._T_hand_camera,
            stamp_s=time.monotonic() - self._start,
        )
