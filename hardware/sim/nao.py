"""The simulated NAO: kinematic walking and joint trajectories with the feet on the floor.

Walking is emulated, not simulated: the feet frame glides over the floor with the
commanded velocity (clipped to NAO-like limits, first-order lag), so the mission's
walking skill can be exercised without a gait controller. Joint motions are kinematic
too: the joints follow the commanded trajectory exactly and the whole body is placed so
that the left sole stays flat at the feet frame (quasi-static whole-body motion, as if
the feet were fixed to the floor). The body's collision shapes still push the chair and
the bear, which are dynamic.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable, Sequence

import numpy as np
import pybullet

from bearchair.core.geometry import make_transform, rot_z, wrap_angle
from bearchair.core.nao_carrying import CARRYING_POSTURE_RAD
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.sim.bullet import (
    LockedBullet,
    T_world_link,
    joint_index_by_name,
    link_index_by_name,
    reset_base_link,
)
from bearchair.hardware.sim.clock import SimClock
from bearchair.hardware.sim.nao_urdf import SOLE_TO_TORSO_M, TAG_LINK

log = logging.getLogger(__name__)

MAX_SPEED_MPS = 0.1
MAX_TURN_RADPS = 0.5
VELOCITY_LAG_S = 0.3
TRANSLATION_SCALE_SIGMA = 0.03
TURN_SCALE_SIGMA = 0.03
YAW_DRIFT_SIGMA_RADPS = 0.01

HOLDING_POSTURE_RAD: dict[str, float] = {**CARRYING_POSTURE_RAD, "LHand": 0.0, "RHand": 0.0}
"""Standing straight, carrying the bear (:mod:`bearchair.core.nao_carrying`), the hands closed."""


class _Trajectory:
    def __init__(
        self, joints: list[str], start_s: float, times_s: np.ndarray, positions: np.ndarray
    ) -> None:
        self.joints = joints
        self.start_s = start_s
        self.times_s = times_s
        self.positions = positions

    def at(self, now_s: float) -> np.ndarray:
        elapsed = now_s - self.start_s
        return np.array(
            [
                np.interp(elapsed, self.times_s, self.positions[:, column])
                for column in range(len(self.joints))
            ]
        )

    def finished(self, now_s: float) -> bool:
        return now_s - self.start_s >= self.times_s[-1]


class SimNao:
    """Implements :class:`bearchair.hardware.interfaces.Humanoid` for the generated NAO model.

    Planar pose: the feet frame, midway between the soles on the floor, x forward.
    Odometry (:meth:`pose`) integrates the lagged, clipped command; the true motion
    (:meth:`true_pose`) differs by a per-command speed-scale error (σ = 3 % for
    translation and turning) and a yaw drift (σ = 0.01 rad/s while walking), drawn from
    the seeded generator at each :meth:`set_velocity`: like the real robot's odometry,
    it drifts with the distance walked.

    Attributes:
        body: pybullet body id.
        joint_indices: revolute joint name (qibullet's names) -> pybullet index.
        joint_limits: name -> (lower, upper) radians.
        motion_count: goes up whenever the body's links may have moved (for caches of
            link poses).
        posture_count: goes up whenever the joint angles may have changed (links fixed
            in the feet frame stay so until then).
    """

    def __init__(
        self,
        bullet: LockedBullet,
        clock: SimClock,
        urdf_path: str,
        start: SE2Pose,
        rng: np.random.Generator,
        texture_id: int | None = None,
    ) -> None:
        self._bullet = bullet
        self._clock = clock
        self._rng = rng
        self._load_body(urdf_path, start, texture_id)

        self._positions = dict.fromkeys(self.joint_indices, 0.0)
        self._positions.update(HOLDING_POSTURE_RAD)
        self._true = np.array([start.x, start.y, start.theta])
        self._odometry = self._true.copy()
        self._command = np.zeros(3)
        self._velocity = np.zeros(3)
        self._scale = np.ones(3)
        self._yaw_drift_radps = 0.0
        self._trajectory: _Trajectory | None = None
        self._stop_trajectory = threading.Event()
        self._emergency_stopped = False
        self._T_feet_base: np.ndarray | None = None
        self.on_hands: Callable[[bool], None] | None = None
        self.motion_count = 0
        self.posture_count = 0
        with bullet.lock:
            for index in self.joint_indices.values():
                bullet.changeDynamics(self.body, index, linearDamping=0.0, angularDamping=0.0)
                bullet.setJointMotorControl2(
                    self.body, index, pybullet.VELOCITY_CONTROL, targetVelocity=0.0, force=0.0
                )
            self._apply_joints()
            self._place_body()
        clock.add_process(self._step)

    def _load_body(self, urdf_path: str, start: SE2Pose, texture_id: int | None) -> None:
        """Loads the URDF standing at ``start`` and indexes its revolute joints (with their
        limits) and links; the tag link gets ``texture_id``'s picture if one is given."""
        bullet = self._bullet
        self.body = bullet.loadURDF(
            urdf_path,
            basePosition=[start.x, start.y, SOLE_TO_TORSO_M],
            baseOrientation=pybullet.getQuaternionFromEuler([0.0, 0.0, start.theta]),
            useFixedBase=True,
            flags=pybullet.URDF_USE_INERTIA_FROM_FILE,
        )
        all_joints = joint_index_by_name(bullet, self.body)
        self.joint_indices = {
            name: index
            for name, index in all_joints.items()
            if bullet.getJointInfo(self.body, index)[2] == pybullet.JOINT_REVOLUTE
        }
        self.joint_limits = {
            name: tuple(bullet.getJointInfo(self.body, index)[8:10])
            for name, index in self.joint_indices.items()
        }
        self._joint_list = list(self.joint_indices.values())
        self.link_indices = link_index_by_name(bullet, self.body)
        self._l_sole = self.link_indices["l_sole"]
        self.tag_link = self.link_indices[TAG_LINK]
        if texture_id is not None:
            bullet.changeVisualShape(
                self.body, self.tag_link, textureUniqueId=texture_id, rgbaColor=[1, 1, 1, 1]
            )

    # --- Humanoid protocol -------------------------------------------------------------
    def pose(self) -> SE2Pose:
        """Odometry: the planar pose the robot believes it has (drifts while walking)."""
        with self._bullet.lock:
            x, y, theta = self._odometry
        return SE2Pose(float(x), float(y), wrap_angle(float(theta)))

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        """Commands a walking velocity in the robot frame, clipped to 0.1 m/s and 0.5 rad/s."""
        self._refuse_if_stopped()
        command = np.array([vx_mps, vy_mps, omega_radps], dtype=float)
        if not np.all(np.isfinite(command)):
            raise ValueError(f"walking velocity must be finite, got {command}")
        speed = math.hypot(command[0], command[1])
        if speed > MAX_SPEED_MPS:
            command[:2] *= MAX_SPEED_MPS / speed
        command[2] = float(np.clip(command[2], -MAX_TURN_RADPS, MAX_TURN_RADPS))
        with self._bullet.lock:
            self._refuse_if_stopped()  # again under the lock: a stop may have come meanwhile
            if not np.allclose(command, self._command):
                self._scale = np.array(
                    [
                        1.0 + self._rng.normal(0.0, TRANSLATION_SCALE_SIGMA),
                        1.0 + self._rng.normal(0.0, TRANSLATION_SCALE_SIGMA),
                        1.0 + self._rng.normal(0.0, TURN_SCALE_SIGMA),
                    ]
                )
                self._yaw_drift_radps = (
                    self._rng.normal(0.0, YAW_DRIFT_SIGMA_RADPS) if np.any(command) else 0.0
                )
            self._command = command

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        """Drives the named joints through the knots (linear interpolation), blocking.

        If the first knot time is after 0, the motion starts from the current posture
        at time 0. Targets beyond a joint's limits by more than 1 mrad are refused;
        smaller excesses are clipped.

        Raises:
            ValueError: unknown joint names, mismatched shapes, non-increasing times or
                positions outside the joint limits.
        """
        self._refuse_if_stopped()
        names = list(joint_names)
        unknown = [name for name in names if name not in self.joint_indices]
        if unknown:
            raise ValueError(f"unknown NAO joints {unknown} (qibullet nao.urdf names expected)")
        times = np.asarray(times_s, dtype=float).reshape(-1)
        positions = np.asarray(positions_rad, dtype=float).reshape(len(times), -1)
        if positions.shape != (len(times), len(names)) or len(times) == 0:
            raise ValueError(
                f"positions must be (K={len(times)}, J={len(names)}), got {np.shape(positions_rad)}"
            )
        if np.any(np.diff(times) <= 0.0) or times[0] < 0.0 or not np.all(np.isfinite(positions)):
            raise ValueError("knot times must start at >= 0 and strictly increase")
        for column, name in enumerate(names):
            lower, upper = self.joint_limits[name]
            if np.any(positions[:, column] < lower - 1e-3) or np.any(
                positions[:, column] > upper + 1e-3
            ):
                raise ValueError(f"{name} outside its limits [{lower:.3f}, {upper:.3f}] rad")
            positions[:, column] = np.clip(positions[:, column], lower, upper)
        with self._bullet.lock:
            if times[0] > 0.0:
                current = np.array([self._positions[name] for name in names])
                times = np.concatenate([[0.0], times])
                positions = np.vstack([current, positions])
            self._refuse_if_stopped()
            self._stop_trajectory.clear()
            trajectory = _Trajectory(names, self._clock.now(), times, positions)
            self._trajectory = trajectory
        while not trajectory.finished(self._clock.now()) and not self._stop_trajectory.is_set():
            self._clock.sleep(min(0.05, max(self._clock.dt_s, trajectory.times_s[-1])))
        self._refuse_if_stopped()
        with self._bullet.lock:
            if self._trajectory is trajectory:
                self._trajectory = None
                for name, value in zip(names, trajectory.positions[-1], strict=True):
                    self._positions[name] = float(value)
                self._apply_joints()
                self._T_feet_base = None
                self._place_body()
                self.motion_count += 1
                self.posture_count += 1

    def set_hands(self, open_hands: bool) -> None:
        """Opens or closes both hands; opening releases the bear if it is held."""
        with self._bullet.lock:
            self._refuse_if_stopped()
            self._positions["LHand"] = self._positions["RHand"] = 1.0 if open_hands else 0.0
            self._apply_joints()
            self._T_feet_base = None
            self.motion_count += 1
            self.posture_count += 1
        if self.on_hands is not None:
            self.on_hands(open_hands)
        self._clock.sleep(0.25)

    def stop(self) -> None:
        """Stops walking at once, ends any trajectory and holds the current posture."""
        with self._bullet.lock:
            self._command = np.zeros(3)
            self._velocity = np.zeros(3)
            self._stop_trajectory.set()
            self._trajectory = None

    def emergency_stop(self) -> None:
        """Stops walking and any trajectory at once and refuses every later motion.

        The simulated NAO is kinematic, so it is still from the next physics step on.
        """
        with self._bullet.lock:
            self._emergency_stopped = True
        self.stop()

    def _refuse_if_stopped(self) -> None:
        if self._emergency_stopped:
            raise RuntimeError("the NAO is emergency-stopped: motion refused")

    # --- ground truth and helpers --------------------------------------------------------
    def place(self, pose: SE2Pose) -> None:
        """Teleports the standing NAO to a planar pose (benchmarks and tests only).

        Stops walking and any trajectory; the true pose and the odometry both become
        ``pose`` (the feet frame: on the floor midway between the soles, x forward). The
        joint angles are kept. A held bear must be moved with it (see
        :meth:`bearchair.hardware.sim.world.SimWorld.place_nao`).
        """
        values = np.array([pose.x, pose.y, pose.theta], dtype=float)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"NAO pose must be finite, got {pose}")
        self.stop()
        with self._bullet.lock:
            self._true = values.copy()
            self._odometry = values.copy()
            self._place_body()
            self.motion_count += 1

    def true_pose(self) -> SE2Pose:
        """Ground-truth planar pose of the feet frame (tests and benchmarks only)."""
        with self._bullet.lock:
            x, y, theta = self._true
        return SE2Pose(float(x), float(y), wrap_angle(float(theta)))

    def joint_positions(self, names: Sequence[str] | None = None) -> dict[str, float]:
        """Current joint angles in radians (all revolute joints when ``names`` is None)."""
        with self._bullet.lock:
            return {name: self._positions[name] for name in (names or self._positions)}

    def T_world_link(self, link_name: str) -> np.ndarray:
        """A link's pose in the world by forward kinematics."""
        return T_world_link(self._bullet, self.body, self.link_indices[link_name])

    def T_world_feet(self) -> np.ndarray:
        """The true feet frame: on the floor, midway between the soles' reference, x forward."""
        x, y, theta = self._true
        return make_transform(rot_z(theta), np.array([x, y, 0.0]))

    def _step(self, now_s: float, dt_s: float) -> None:
        blend = 1.0 - math.exp(-dt_s / VELOCITY_LAG_S)
        self._velocity += (self._command - self._velocity) * blend
        moved = bool(np.any(np.abs(self._velocity) > 1e-6))
        if moved:
            self._odometry = _integrate(self._odometry, self._velocity, dt_s)
            true_velocity = self._velocity * self._scale
            if np.any(self._command):
                true_velocity[2] += self._yaw_drift_radps
            self._true = _integrate(self._true, true_velocity, dt_s)
        trajectory = self._trajectory
        if trajectory is not None:
            for name, value in zip(trajectory.joints, trajectory.at(now_s), strict=True):
                self._positions[name] = float(value)
            self._T_feet_base = None
            self.posture_count += 1
        # The joints are kinematic: re-imposed every step, or gravity would fold the body.
        self._apply_joints()
        if moved or trajectory is not None:
            self._place_body()
            self.motion_count += 1

    def _apply_joints(self) -> None:
        self._bullet.resetJointStatesMultiDof(
            self.body,
            self._joint_list,
            [[self._positions[name]] for name in self.joint_indices],
            [[0.0]] * len(self._joint_list),
        )

    def _place_body(self) -> None:
        """Puts the base so the left sole lies flat at its place beside the feet frame."""
        if self._T_feet_base is None:
            T_world_base = T_world_link(self._bullet, self.body, -1)
            T_base_left = np.linalg.inv(T_world_base) @ T_world_link(
                self._bullet, self.body, self._l_sole
            )
            # The feet frame is half the standing stance (5 cm) to the right of the left
            # sole, in the left sole's own orientation.
            T_left_feet = make_transform(np.eye(3), np.array([0.0, -0.05, 0.0]))
            self._T_feet_base = np.linalg.inv(T_base_left @ T_left_feet)
        reset_base_link(self._bullet, self.body, self.T_world_feet() @ self._T_feet_base)


def _integrate(pose: np.ndarray, velocity: np.ndarray, dt_s: float) -> np.ndarray:
    """Integrates a body-frame velocity (vx, vy, ω) over dt on SE(2) (midpoint heading)."""
    x, y, theta = pose
    heading = theta + 0.5 * velocity[2] * dt_s
    c, s = math.cos(heading), math.sin(heading)
    return np.array(
        [
            x + (c * velocity[0] - s * velocity[1]) * dt_s,
            y + (s * velocity[0] + c * velocity[1]) * dt_s,
            theta + velocity[2] * dt_s,
        ]
    )
