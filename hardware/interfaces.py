"""The hardware interfaces every backend implements, simulated or real.

Skills talk to robots only through these protocols; ``hardware/sim`` implements them
in pybullet and ``hardware/real`` through the robots' SDKs. All quantities are SI:
metres, radians, seconds. Camera frames follow OpenCV: x right, y down, z forward.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np

from bearchair.core.se2 import SE2Pose


class CameraIntrinsics(NamedTuple):
    """Pinhole intrinsics in pixels."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    def matrix(self) -> np.ndarray:
        """The 3x3 camera matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


class RGBDFrame(NamedTuple):
    """One registered colour and depth capture.

    Attributes:
        rgb: (H, W, 3) uint8.
        depth_m: (H, W) float32 depth along the optical axis in metres; 0 where missing.
        intrinsics: the camera's pinhole model (shared by rgb and depth).
        T_world_camera: 4x4 camera pose (OpenCV optical frame) from forward kinematics.
        stamp_s: capture time in seconds on the robot's clock.
    """

    rgb: np.ndarray
    depth_m: np.ndarray
    intrinsics: CameraIntrinsics
    T_world_camera: np.ndarray
    stamp_s: float


@runtime_checkable
class Clock(Protocol):
    """Time as the robots see it: real time, or simulated time that advances the physics."""

    def now(self) -> float:
        """Seconds since the backend started."""
        ...

    def sleep(self, seconds: float) -> None:
        """Lets ``seconds`` pass (the simulator steps its physics meanwhile)."""
        ...


@runtime_checkable
class ScanningArm(Protocol):
    """The arm carrying the wrist depth camera (a Franka Panda in the paper)."""

    def joint_positions(self) -> np.ndarray:
        """Current arm joint angles in radians."""
        ...

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        """Moves to a joint configuration and blocks until it is reached.

        Raises:
            TimeoutError: the configuration was not reached in time.
        """
        ...

    def capture(self) -> RGBDFrame:
        """Captures one RGB-D frame with the camera pose from forward kinematics."""
        ...

    def emergency_stop(self) -> None:
        """Stops the arm now from any thread: a running ``move_to`` ends with an error.

        Latching: later motions are refused. Must not raise.
        """
        ...


@runtime_checkable
class Humanoid(Protocol):
    """The humanoid that carries the bear (a NAO in the paper)."""

    def pose(self) -> SE2Pose:
        """The robot's own estimate of its planar pose in the world frame (odometry)."""
        ...

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        """Commands a walking velocity in the robot's own frame."""
        ...

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        """Plays a joint trajectory and blocks until it ends.

        Args:
            joint_names: the J joints driven.
            times_s: K increasing knot times from the start of the motion.
            positions_rad: (K, J) joint angles.
        """
        ...

    def set_hands(self, open_hands: bool) -> None:
        """Opens (True) or closes (False) both hands."""
        ...

    def stop(self) -> None:
        """Stops walking and holds the current posture."""
        ...

    def emergency_stop(self) -> None:
        """Stops every motion now from any thread (walk, trajectory, hands).

        A blocking ``play_joint_trajectory`` returns or raises; latching: later motions
        are refused. Must not raise.
        """
        ...


@runtime_checkable
class Speaker(Protocol):
    """Says sentences aloud (or prints them when there is no audio)."""

    def say(self, sentence: str) -> None:
        """Speaks one sentence and returns when it has been said."""
        ...


@runtime_checkable
class Helper(Protocol):
    """The person who turns the chair when asked (simulation only: a real person listens)."""

    def hear(self, sentence: str) -> None:
        """Receives a spoken instruction; the helper acts on it as time passes."""
        ...


class SeatingJudgement(NamedTuple):
    """A physical verdict on the seated bear (simulation only).

    Attributes:
        seated: every criterion below holds.
        on_seat: the bear touches the chair and not the floor.
        torso_tilt_deg: angle between the bear's torso axis and vertical.
        facing_error_deg: angle between the bear's facing and the sitting direction.
        reason: empty on success, else which criterion failed.
        T_world_bear: 4x4 pose of the bear when judged (None when not known).
    """

    seated: bool
    on_seat: bool
    torso_tilt_deg: float
    facing_error_deg: float
    reason: str = ""
    T_world_bear: np.ndarray | None = None


@runtime_checkable
class SeatingJudge(Protocol):
    """Judges whether the bear ended up seated (only a simulator can know this)."""

    def judge(self, sitting_yaw_rad: float, settle_s: float = 2.0) -> SeatingJudgement:
        """Lets the scene settle, then judges the bear against the sitting direction."""
        ...


EMERGENCY_STOP_WAIT_S = 5.0
"""How long :meth:`Robot.emergency_stop` waits for its devices' stops to return (seconds:
the NAO's take at most about 1.4 s, each NAOqi call bounded);
a device that has not by then goes on stopping in its own thread."""


def _stop_quietly(device: Any) -> None:
    with contextlib.suppress(Exception):
        device.emergency_stop()


@dataclass
class Robot:
    """Everything the mission needs from the outside world, injected at ``tree.setup``.

    Attributes:
        arm: the scanning arm with its wrist camera.
        humanoid: the humanoid carrying the bear.
        speaker: the voice that instructs the helper.
        clock: robot time (simulated or real).
        helper: in simulation, the person who turns the chair; None on real robots.
        judge: in simulation, the physical success judgement; None on real robots.
    """

    arm: ScanningArm
    humanoid: Humanoid
    speaker: Speaker
    clock: Clock
    helper: Helper | None = None
    judge: SeatingJudge | None = None

    def emergency_stop(self) -> None:
        """Stops every actuator now (Ctrl-C, SIGTERM, a timeout, an error); never raises.

        Safe from any thread and more than once; motions are refused afterwards.
        """
        # Every device at once, each in its own thread: the wired arm never waits on the
        # humanoid's Wi-Fi, and one device's error or hang never keeps another moving.
        stoppers = [
            threading.Thread(target=_stop_quietly, args=(device,), daemon=True, name="estop")
            for device in (self.arm, self.humanoid)
        ]
        for stopper in stoppers:
            stopper.start()
        deadline = time.monotonic() + EMERGENCY_STOP_WAIT_S
        for stopper in stoppers:
            stopper.join(max(0.0, deadline - time.monotonic()))

    def close(self) -> None:
        """Stops every actuator, then closes the devices that hold a connection (a
        ``close()`` of their own: the NAO's qi session); safe to call more than once."""
        self.emergency_stop()
        for device in (self.humanoid, self.arm):
            close = getattr(device, "close", None)
            if callable(close):
                with contextlib.suppress(Exception):
                    close()
