"""The panda_py stand-in (see :mod:`bearchair.hardware.real.standins`)."""

from __future__ import annotations

import enum
import math
import threading
import time
from typing import Any

import numpy as np

# Craig's (modified) DH parameters of the Panda: a, d, alpha per joint, then the flange.
_DH = (
    (0.0, 0.333, 0.0),
    (0.0, 0.0, -math.pi / 2),
    (0.0, 0.316, math.pi / 2),
    (0.0825, 0.0, math.pi / 2),
    (-0.0825, 0.384, -math.pi / 2),
    (0.0, 0.0, math.pi / 2),
    (0.088, 0.0, math.pi / 2),
)
FLANGE_D_M = 0.107
FRANKA_HAND_F_T_EE = np.array(
    [
        [math.cos(-math.pi / 4), -math.sin(-math.pi / 4), 0.0, 0.0],
        [math.sin(-math.pi / 4), math.cos(-math.pi / 4), 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.1034],
        [0.0, 0.0, 0.0, 1.0],
    ]
)
"""Desk's default end effector with the Franka Hand: 10.34 cm along z, -45 deg about z."""


def panda_flange_pose(q: np.ndarray) -> np.ndarray:
    """T_base_flange by forward kinematics (Craig's DH convention)."""
    T = np.eye(4)
    for (a, d, alpha), theta in (*zip(_DH, q, strict=True), ((0.0, FLANGE_D_M, 0.0), 0.0)):
        ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
        T = T @ np.array(
            [
                [ct, -st, 0.0, a],
                [st * ca, ct * ca, -sa, -d * sa],
                [st * sa, ct * sa, ca, d * ca],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
    return T


JOINT_LIMITS = {
    "fer": (
        (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973),
        (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973),
    ),
    "fr3": (
        (-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159),
        (2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159),
    ),
}
"""The FER's and the FR3's (robot system < 5.9) joint limits, as panda-py 1.1.1's
``constants`` give them (rad)."""


class _RobotMode(enum.Enum):
    kOther = 0
    kIdle = 1
    kMove = 2
    kGuiding = 3
    kReflex = 4
    kUserStopped = 5
    kAutomaticErrorRecovery = 6


class _Errors:
    def __init__(self, active: tuple[str, ...] = ()) -> None:
        self.active = active

    def __bool__(self) -> bool:
        return bool(self.active)

    def __str__(self) -> str:
        return "[" + ", ".join(self.active) + "]"


class _State:
    def __init__(self, q: np.ndarray, mode: _RobotMode, errors: _Errors) -> None:
        self.q = q.tolist()
        self.dq = [0.0] * 7
        self.robot_mode = mode
        self.current_errors = errors
        self.last_motion_errors = errors
        O_T_EE = panda_flange_pose(q) @ FRANKA_HAND_F_T_EE
        # libfranka's state arrays are column-major 16-vectors.
        self.O_T_EE = O_T_EE.T.reshape(-1).tolist()
        self.F_T_EE = FRANKA_HAND_F_T_EE.T.reshape(-1).tolist()


class ControlException(RuntimeError):
    """libfranka's ``franka::ControlException`` as panda-py re-raises it."""


class _LibfrankaRobot:
    def __init__(self, panda: PandaStandin) -> None:
        self._panda = panda

    def stop(self) -> None:
        self._panda.stop_times_s.append(time.monotonic())
        self._panda.calls.append(("Robot.stop", ()))
        self._panda.stop_motion()

    def read_once(self) -> _State:
        return self._panda.get_state()

    def automatic_error_recovery(self) -> None:
        self._panda.calls.append(("Robot.automatic_error_recovery", ()))
        self._panda.mode, self._panda.errors = _RobotMode.kIdle, _Errors()

    def server_version(self) -> int:
        return 5

    def set_collision_behavior(self, lower_torque, upper_torque, lower_force, upper_force) -> None:
        self._panda.calls.append(
            ("Robot.set_collision_behavior", (list(lower_torque), list(lower_force)))
        )
        self._panda.collision_thresholds = (
            list(lower_torque),
            list(upper_torque),
            list(lower_force),
            list(upper_force),
        )

    def set_load(self, load_mass, F_x_Cload, load_inertia) -> None:
        self._panda.calls.append(("Robot.set_load", (load_mass, list(F_x_Cload))))
        self._panda.load = (float(load_mass), list(F_x_Cload), list(load_inertia))


class PandaStandin:
    """``panda_py.Panda`` as this project uses it (see the module docstring).

    Attributes:
        q: joint angles (rad); ``mode`` and ``errors``: the robot's state;
        calls: (method, args) of every call; ``time_scale``: robot s per wall s.
    """

    JOINT_SPEED_RADPS = 2.0  # at speed_factor 1 (panda-py scales the limits by it)

    def __init__(self, hostname: str, name: str = "panda", realtime_config: Any = None) -> None:
        self.hostname = hostname
        self.model = "fer"
        """"fer" or "fr3": which joint limits the robot reports."""
        self.collision_thresholds: tuple[list[float], ...] | None = None
        self.load: tuple[float, list[float], list[float]] | None = None
        self.q = np.array([0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4])
        self.mode = _RobotMode.kIdle
        self.errors = _Errors()
        self.time_scale = 10.0
        self.calls: list[tuple[str, tuple[Any, ...]]] = []
        self.stop_times_s: list[float] = []
        """When (``time.monotonic()``) each ``Robot::stop`` arrived."""
        self._abort = threading.Event()
        self._last_error: Exception | None = None
        self._lock = threading.Lock()

    def stop_motion(self) -> None:
        """What libfranka's ``Robot::stop`` does to a running motion: aborts it."""
        self._abort.set()

    def get_state(self) -> _State:
        with self._lock:
            return _State(self.q.copy(), self.mode, self.errors)

    def get_pose(self) -> np.ndarray:
        return panda_flange_pose(self.q) @ FRANKA_HAND_F_T_EE

    def get_joint_limits_lower(self) -> np.ndarray:
        return np.array(JOINT_LIMITS[self.model][0])

    def get_joint_limits_upper(self) -> np.ndarray:
        return np.array(JOINT_LIMITS[self.model][1])

    def get_robot(self) -> _LibfrankaRobot:
        return _LibfrankaRobot(self)

    def recover(self) -> None:
        self.calls.append(("recover", ()))
        self.get_robot().automatic_error_recovery()

    def raise_error(self) -> None:
        error, self._last_error = self._last_error, None
        if error is not None:
            raise error

    def stop_controller(self) -> None:
        self.calls.append(("stop_controller", ()))

    def move_to_joint_position(
        self,
        positions: Any,
        speed_factor: float = 0.2,
        stiffness: Any = None,
        damping: Any = None,
        dq_threshold: float = 0.001,
        success_threshold: float = 0.01,
    ) -> bool:
        self.calls.append(
            ("move_to_joint_position", (np.asarray(positions).tolist(), speed_factor))
        )
        return self._move(
            np.asarray(positions, dtype=float).reshape(7), speed_factor, success_threshold
        )

    def _move(self, target: np.ndarray, speed_factor: float, success_threshold: float) -> bool:
        """Moves to ``target`` (7 joint angles, rad) as panda-py's motion does; False
        (with the error kept for :meth:`raise_error`) when it was aborted."""
        # panda-py recovers from a reflex on its own before every move.
        if self.mode in (_RobotMode.kReflex, _RobotMode.kOther) or self.errors:
            self.recover()
        start = self.q.copy()
        duration = float(np.max(np.abs(target - start))) / (self.JOINT_SPEED_RADPS * speed_factor)
        self._abort.clear()
        begin = time.monotonic()
        self.mode = _RobotMode.kMove
        while True:
            fraction = min(1.0, (time.monotonic() - begin) * self.time_scale / max(duration, 1e-9))
            with self._lock:
                self.q = start + fraction * (target - start)
            if fraction >= 1.0:
                break
            if self._abort.wait(0.005):
                self._last_error = ControlException(
                    "libfranka: Move command aborted: motion aborted by stop"
                )
                self.mode = _RobotMode.kIdle
                return False
        self.mode = _RobotMode.kIdle
        return bool(np.allclose(self.q, target, atol=success_threshold))

    def inject_reflex(self, error: str = "joint_velocity_violation") -> None:
        """Puts the robot in reflex with an error, as a collision would."""
        self.mode, self.errors = _RobotMode.kReflex, _Errors((error,))
