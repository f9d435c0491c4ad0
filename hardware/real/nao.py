"""The NAO through NAOqi: ALMotion for walking and joints, ALTextToSpeech for speech.

NAOqi's ``ALMotion.move(x, y, theta)`` takes velocities in m/s and rad/s in the robot
frame, ``angleInterpolation`` plays absolute joint angles at given times, and
``getRobotPosition(True)`` returns the odometry [x, y, theta] in NAOqi's world frame,
which :class:`NaoHumanoid` maps into ours through ``T_world_odom``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from hardware.real import BackendUnavailable, import_sdk
from skills.geometry import SE2Pose, wrap_angle

# NAO's walking speed limits (NAOqi documentation: about 0.1 m/s forward, 0.5 rad/s).
MAX_FORWARD_MPS = 0.1
MAX_SIDEWAYS_MPS = 0.08
MAX_TURN_RADPS = 0.5


def connect(url: str) -> Any:
    """Opens a qi session to the robot, e.g. ``tcp://nao.local:9559``."""
    qi = import_sdk("qi", "qi")
    session = qi.Session()
    try:
        session.connect(url)
    except RuntimeError as error:
        raise BackendUnavailable(f"cannot reach the NAO at {url}: {error}") from error
    return session


class NaoHumanoid:
    """:class:`hardware.interfaces.Humanoid` on a real NAO.

    Args:
        session: a connected qi session (or any object whose ``service(name)`` returns
            ALMotion-like objects: tests pass a fake).
        odom_origin: the world pose of NAOqi's odometry origin (from the ArUco tag at
            the start), so that ``pose()`` is in the world frame.
    """

    def __init__(self, session: Any, odom_origin: SE2Pose = SE2Pose(0.0, 0.0, 0.0)) -> None:
        self._motion = session.service("ALMotion")
        self._posture = session.service("ALRobotPosture")
        self._odom_origin = odom_origin
        self._motion.wakeUp()
        self._motion.moveInit()

    def pose(self) -> SE2Pose:
        x, y, theta = self._motion.getRobotPosition(True)
        c, s = math.cos(self._odom_origin.theta), math.sin(self._odom_origin.theta)
        return SE2Pose(
            self._odom_origin.x + c * x - s * y,
            self._odom_origin.y + s * x + c * y,
            wrap_angle(self._odom_origin.theta + theta),
        )

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        self._motion.move(
            float(np.clip(vx_mps, -MAX_FORWARD_MPS, MAX_FORWARD_MPS)),
            float(np.clip(vy_mps, -MAX_SIDEWAYS_MPS, MAX_SIDEWAYS_MPS)),
            float(np.clip(omega_radps, -MAX_TURN_RADPS, MAX_TURN_RADPS)),
        )

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        positions = np.asarray(positions_rad, dtype=float)
        times = np.asarray(times_s, dtype=float)
        if positions.shape != (len(times), len(joint_names)):
            raise ValueError(
                f"trajectory shape {positions.shape} does not match "
                f"{len(times)} knots x {len(joint_names)} joints"
            )
        # NAOqi wants strictly positive, increasing times: drop a knot at t = 0.
        keep = times > 0.0
        angle_lists = [positions[keep, j].tolist() for j in range(len(joint_names))]
        time_lists = [times[keep].tolist()] * len(joint_names)
        self._motion.angleInterpolation(list(joint_names), angle_lists, time_lists, True)

    def set_hands(self, open_hands: bool) -> None:
        for hand in ("LHand", "RHand"):
            (self._motion.openHand if open_hands else self._motion.closeHand)(hand)

    def stop(self) -> None:
        self._motion.stopMove()

    def stand(self, speed: float = 0.5) -> None:
        """Goes to NAOqi's StandInit posture."""
        self._posture.goToPosture("StandInit", speed)


class NaoSpeaker:
    """:class:`hardware.interfaces.Speaker` through the NAO's own voice."""

    def __init__(self, session: Any) -> None:
        self._tts = session.service("ALTextToSpeech")

    def say(self, sentence: str) -> None:
        self._tts.say(sentence)


class WallClock:
    """:class:`hardware.interfaces.Clock` on real robots: real time."""

    def __init__(self) -> None:
        self._start = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._start

    def sleep(self, seconds: float) -> None:
        time.sleep(max(0.0, seconds))
