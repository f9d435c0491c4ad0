"""The Franka Panda with its wrist depth camera, as a :class:`bearchair.hardware.interfaces.ScanningArm`."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pybullet
import pybullet_data

from bearchair.core.geometry import make_transform
from bearchair.hardware.interfaces import CameraIntrinsics, RGBDFrame
from bearchair.hardware.sim.bullet import (
    LockedBullet,
    T_world_link,
    cached_asset,
    link_index_by_name,
)
from bearchair.hardware.sim.camera import (
    CARMINE_INTRINSICS,
    CarmineNoise,
    RenderedView,
    carmine_images,
    render_view,
)
from bearchair.hardware.sim.clock import SimClock
from bearchair.hardware.wrist_mount import T_HAND_CAMERA

PANDA_URDF = Path(pybullet_data.getDataPath()) / "franka_panda" / "panda.urdf"
_PANDA_MESHES = PANDA_URDF.parent / "meshes"
ARM_JOINTS = 7
HAND_LINK = "panda_hand"
JOINT_FORCE_LIMITS_NM = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
MAX_JOINT_SPEED_RADPS = 1.5
REACHED_TOLERANCE_RAD = 4e-3
SETTLED_SPEED_RADPS = 0.02

PANDA_READY_RAD = (0.817, -1.007, -0.234, -1.996, -0.575, 1.606, -1.875)
"""The camera 0.75 m above the floor at x = 0.2 m, looking at the chair area's centre (0.6, 0, 0.25)."""


def look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """OpenCV camera pose at ``eye`` looking at ``target`` with the image upright (world z up)."""
    forward = target - eye
    forward = forward / np.linalg.norm(forward)
    up = np.array([0.0, 0.0, 1.0]) if abs(forward[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    return make_transform(np.column_stack([right, down, forward]), eye)


def coarse_panda_urdf() -> Path:
    """``panda.urdf`` drawn with its collision meshes instead of its visual ones.

    TinyRenderer transforms every triangle of every visual shape for every frame, even
    a 160x120 one, and the visual meshes (about 10 MB of OBJ) cost about 130 ms a frame
    on this machine, against under 1 ms for everything else in the scene. The wrist
    camera never sees the arm (the fingers stay above the image's top edge), so only the
    scene pictures show the coarser arm. Kinematics, inertias and collision shapes are
    the file's own.
    """
    text = PANDA_URDF.read_text()
    text = text.replace("package://meshes/visual/", "package://meshes/collision/")
    text = text.replace("package://meshes/", f"{_PANDA_MESHES.as_posix()}/")
    return cached_asset("panda-coarse", text, ".urdf")


class SimPanda:
    """A fixed-base Panda whose wrist camera renders the scene.

    ``move_to`` runs joint position control (at most 1.5 rad/s per joint) and steps the
    simulation through the clock until every joint is within 4 mrad of its target and
    nearly still. ``capture`` renders through TinyRenderer at the pose given by forward
    kinematics of the hand link composed with :data:`T_HAND_CAMERA`.

    Attributes:
        body: the pybullet body id.
        intrinsics: the camera's pinhole model.
        last_view: the noiseless rendering behind the last capture (tests and benchmarks
            only: ground-truth depth and segmentation).
    """

    def __init__(
        self,
        bullet: LockedBullet,
        clock: SimClock,
        base_xy: tuple[float, float],
        rng: np.random.Generator,
        camera_noise: bool = True,
        initial_joints: Sequence[float] = PANDA_READY_RAD,
    ) -> None:
        self._bullet = bullet
        self._clock = clock
        self._rng = rng
        self._noise = CarmineNoise() if camera_noise else None
        self.intrinsics: CameraIntrinsics = CARMINE_INTRINSICS
        self.body = bullet.loadURDF(
            str(coarse_panda_urdf()),
            basePosition=[base_xy[0], base_xy[1], 0.0],
            useFixedBase=True,
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
        )
        self._hand = link_index_by_name(bullet, self.body)[HAND_LINK]
        info = [bullet.getJointInfo(self.body, j) for j in range(ARM_JOINTS)]
        self.lower_limits = np.array([item[8] for item in info])
        self.upper_limits = np.array([item[9] for item in info])
        self.last_view: RenderedView | None = None
        self._emergency_stopped = False
        with bullet.lock:
            for joint, angle in enumerate(initial_joints):
                bullet.resetJointState(self.body, joint, angle)
            for finger in (9, 10):
                bullet.resetJointState(self.body, finger, 0.0)
                bullet.setJointMotorControl2(
                    self.body, finger, pybullet.POSITION_CONTROL, targetPosition=0.0, force=20.0
                )
            self._command(np.asarray(initial_joints, dtype=float))

    def joint_positions(self) -> np.ndarray:
        """The seven arm joint angles in radians."""
        with self._bullet.lock:
            states = self._bullet.getJointStates(self.body, list(range(ARM_JOINTS)))
        return np.array([state[0] for state in states])

    def joint_velocities(self) -> np.ndarray:
        """The seven arm joint speeds in rad/s."""
        with self._bullet.lock:
            states = self._bullet.getJointStates(self.body, list(range(ARM_JOINTS)))
        return np.array([state[1] for state in states])

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        """Moves to a joint configuration, stepping the simulation until it is reached.

        Raises:
            ValueError: not 7 finite angles, or outside the joint limits.
            TimeoutError: not reached within ``timeout_s`` simulated seconds.
        """
        self._refuse_if_stopped()
        target = np.asarray(joint_positions_rad, dtype=float).reshape(-1)
        if target.shape != (ARM_JOINTS,) or not np.all(np.isfinite(target)):
            raise ValueError(f"the Panda needs {ARM_JOINTS} finite joint angles, got {target}")
        outside = (target < self.lower_limits - 1e-6) | (target > self.upper_limits + 1e-6)
        if np.any(outside):
            joints = ", ".join(f"joint {index + 1}" for index in np.flatnonzero(outside))
            raise ValueError(f"target outside the Panda's joint limits at {joints}")
        with self._bullet.lock:
            self._refuse_if_stopped()  # again under the lock: a stop may have come meanwhile
            self._command(target)
        start_s = self._clock.now()
        while True:
            self._refuse_if_stopped()
            error = np.max(np.abs(self.joint_positions() - target))
            speed = np.max(np.abs(self.joint_velocities()))
            if error < REACHED_TOLERANCE_RAD and speed < SETTLED_SPEED_RADPS:
                return
            if self._clock.now() - start_s > timeout_s:
                raise TimeoutError(
                    f"Panda did not reach its target in {timeout_s:.1f} s "
                    f"(largest joint error {math.degrees(error):.1f} deg)"
                )
            self._clock.sleep(1.0 / 60.0)

    def emergency_stop(self) -> None:
        """Brakes every joint (zero velocity at full torque, as the Panda's stop does) and
        refuses later moves; a ``move_to`` running in another thread raises at its next check.
        """
        with self._bullet.lock:
            self._emergency_stopped = True
            for joint in range(ARM_JOINTS):
                self._bullet.setJointMotorControl2(
                    self.body,
                    joint,
                    pybullet.VELOCITY_CONTROL,
                    targetVelocity=0.0,
                    force=JOINT_FORCE_LIMITS_NM[joint],
                )

    def _refuse_if_stopped(self) -> None:
        if self._emergency_stopped:
            raise RuntimeError("the Panda is emergency-stopped: motion refused")

    def T_world_camera(self) -> np.ndarray:
        """Camera pose: forward kinematics of the hand link composed with the hand-eye extrinsic."""
        with self._bullet.lock:
            return T_world_link(self._bullet, self.body, self._hand) @ T_HAND_CAMERA

    def capture(self) -> RGBDFrame:
        """Renders one RGB-D frame (640x480) at the current arm configuration."""
        return self._render(self.intrinsics)

    def capture_region(self, x0: int, y0: int, width: int, height: int) -> RGBDFrame:
        """Reads out only a window of the image, as a camera's region of interest does.

        The frame holds the pixels [y0, y0 + height) x [x0, x0 + width) of the full
        image, with the same noise model; its intrinsics are the full camera's with the
        principal point moved to the window's origin (cx - x0, cy - y0), so every
        pinhole computation on it holds unchanged. Rendering costs in proportion to the
        pixels: a 100x100 window of the head tag costs 1/30 of a full frame.

        Raises:
            ValueError: an empty window or one not inside the image.
        """
        full = self.intrinsics
        if width < 1 or height < 1 or x0 < 0 or y0 < 0:
            raise ValueError(f"bad image window x0={x0} y0={y0} {width}x{height}")
        if x0 + width > full.width or y0 + height > full.height:
            raise ValueError(
                f"image window x0={x0} y0={y0} {width}x{height} leaves the "
                f"{full.width}x{full.height} image"
            )
        window = CameraIntrinsics(width, height, full.fx, full.fy, full.cx - x0, full.cy - y0)
        return self._render(window)

    def _render(self, intrinsics: CameraIntrinsics) -> RGBDFrame:
        timers = self._clock.timers
        with self._bullet.lock:
            started = time.perf_counter()
            T_world_camera = self.T_world_camera()
            view = render_view(self._bullet, T_world_camera, intrinsics)
            stamp_s = self._clock.now()
            timers.render_s += time.perf_counter() - started
            timers.frames += 1
            timers.pixels += intrinsics.width * intrinsics.height
        self.last_view = view
        started = time.perf_counter()
        rgb, depth = carmine_images(view, intrinsics, self._noise, self._rng)
        timers.noise_s += time.perf_counter() - started
        return RGBDFrame(rgb, depth, intrinsics, T_world_camera, stamp_s)

    def _command(self, target: np.ndarray) -> None:
        with self._bullet.lock:
            for joint in range(ARM_JOINTS):
                self._bullet.setJointMotorControl2(
                    self.body,
                    joint,
                    pybullet.POSITION_CONTROL,
                    targetPosition=float(target[joint]),
                    force=JOINT_FORCE_LIMITS_NM[joint],
                    maxVelocity=MAX_JOINT_SPEED_RADPS,
                )
