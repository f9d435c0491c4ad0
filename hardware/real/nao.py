"""The NAO through NAOqi (``qi``): walking, joint trajectories, hands, speech.

NAOqi calls used, with their documented shapes (ALMotion unless named):

* ``getRobotPosition(useSensors: bool) -> [x, y, theta]``: odometry in NAOqi's world
  frame, which starts wherever the robot was when NAOqi booted. :meth:`NaoHumanoid.pose`
  counts from the first reading, so the cell file's start pose is the origin.
* ``moveTo(x, y, theta)`` (metres, radians, relative to the robot): walking. Each
  :meth:`NaoHumanoid.set_velocity` sends the displacement of :data:`WALK_HORIZON_S` at
  the commanded velocity; NAOqi replaces the previous target with the new one, and the
  robot stops by itself when no new command comes. So a dead process leaves the NAO
  walking for at most 0.5 s (5 cm, 0.25 rad), where ``move(vx, vy, wz)`` would latch the
  velocity until someone calls ``stopMove``.
* ``angleInterpolation(names, angleLists, timeLists, isAbsolute)``, ``openHand(name)``,
  ``closeHand(name)``: called asynchronously (``_async=True``): the qi future is kept,
  and :meth:`NaoHumanoid.emergency_stop` cancels it, then ``stopMove()`` and
  ``killTasksUsingResources(joints)`` end whatever NAOqi still runs.
* Carrying set-up (:meth:`NaoHumanoid.activate`): ``ALAutonomousLife.setState("disabled")``,
  ``ALBasicAwareness.setEnabled(False)`` (it turns the head, which carries the tag, toward
  people), ``wakeUp()``, ``ALRobotPosture.goToPosture("StandInit", speed)``,
  ``setMoveArmsEnabled(False, False)`` (no arm swing while carrying), the carrying posture
  and closed hands, head stiff at (0, 0).

Connecting reads state only; nothing moves until :meth:`NaoHumanoid.activate`.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from bearchair.core.errors import BackendUnavailable
from bearchair.core.nao_carrying import CARRYING_POSTURE_RAD
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.real import EmergencyStopped, import_sdk

log = logging.getLogger(__name__)

# NAO's walking speed limits (NAOqi documentation: about 0.1 m/s forward, 0.5 rad/s).
MAX_FORWARD_MPS = 0.1
MAX_SIDEWAYS_MPS = 0.08
MAX_TURN_RADPS = 0.5
WALK_HORIZON_S = 0.5
"""How long one walking command lasts on the robot if no other follows (seconds)."""
CONNECT_TIMEOUT_S = 5.0
POSTURE_SPEED = 0.3
"""Fraction of the joints' maximum speed for set-up postures (a bear in the arms)."""
HEAD_JOINTS = ("HeadYaw", "HeadPitch")
BODY_JOINTS = (
    *HEAD_JOINTS,
    *(
        f"{side}{joint}"
        for side in "LR"
        for joint in ("ShoulderPitch", "ShoulderRoll", "ElbowYaw", "ElbowRoll", "WristYaw", "Hand")
    ),
    *(
        f"{side}{joint}"
        for side in "LR"
        for joint in ("HipYawPitch", "HipRoll", "HipPitch", "KneePitch", "AnklePitch", "AnkleRoll")
    ),
)
"""Every NAO joint: the resources ``killTasksUsingResources`` frees on an emergency stop."""


def connect(
    url: str,
    user: str | None = None,
    password: str | None = None,
    timeout_s: float = CONNECT_TIMEOUT_S,
) -> Any:
    """Opens a qi session to the robot (``tcp://nao.local:9559``, or ``tcps://...:9503``
    with ``user``/``password`` on NAOqi >= 2.9), giving up after ``timeout_s``.

    Raises:
        BackendUnavailable: qi is missing or the robot does not answer in time.
    """
    qi = import_sdk("qi", "bearchair[nao]")
    session = qi.Session()
    if user is not None:
        session.setClientAuthenticatorFactory(_CredentialsFactory(user, password or ""))
    future = session.connect(url, _async=True)
    if future.wait(int(timeout_s * 1000)) != qi.FutureState.FinishedWithValue:
        future.cancel()
        reason = future.error() if future.hasError() else f"no answer in {timeout_s:g} s"
        raise BackendUnavailable(f"cannot reach the NAO at {url}: {reason}")
    return session


class _CredentialsAuthenticator:
    def __init__(self, user: str, password: str) -> None:
        self._user, self._password = user, password

    def initialAuthData(self) -> dict[str, str]:
        return {"user": self._user, "token": self._password}

    def _processAuth(self, data: Any) -> dict[str, str]:
        return {}


class _CredentialsFactory:
    def __init__(self, user: str, password: str) -> None:
        self._user, self._password = user, password

    def newAuthenticator(self) -> _CredentialsAuthenticator:
        return _CredentialsAuthenticator(self._user, self._password)


class NaoHumanoid:
    """:class:`bearchair.hardware.interfaces.Humanoid` on a real NAO.

    Args:
        session: a connected qi session (tests pass one connected to
            :mod:`bearchair.hardware.real.standins`).
        odom_origin: the world pose where the NAO stands now (the cell file's start
            pose): :meth:`pose` is this composed with the odometry since the first reading.
    """

    def __init__(self, session: Any, odom_origin: SE2Pose = SE2Pose(0.0, 0.0, 0.0)) -> None:
        self._session = session
        self._motion = session.service("ALMotion")
        self._posture = session.service("ALRobotPosture")
        self._odom_origin = odom_origin
        self._lock = threading.Lock()
        self._futures: set[Any] = set()
        self._walk_future: Any = None
        self._stopped = False
        # Odometry is counted from here: NAOqi's own origin is where it booted.
        self._odom_first = np.asarray(self._motion.getRobotPosition(True), dtype=float)

    # --- lifecycle -------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """What check-hardware prints: awake, Autonomous Life, battery, arm swing (reads only)."""
        report: dict[str, Any] = {
            "awake": bool(self._motion.robotIsWakeUp()),
            "arm_swing": bool(self._motion.getMoveArmsEnabled("Arms")),
        }
        report["autonomous_life"] = str(self._session.service("ALAutonomousLife").getState())
        report["basic_awareness"] = bool(self._session.service("ALBasicAwareness").isEnabled())
        report["battery_percent"] = int(self._session.service("ALBattery").getBatteryCharge())
        return report

    def activate(self) -> None:
        """Sets the NAO up for carrying the bear (this moves it: after the operator agrees)."""
        self._refuse_if_stopped()
        self._session.service("ALAutonomousLife").setState("disabled")
        self._session.service("ALBasicAwareness").setEnabled(False)
        self._motion.wakeUp()
        self._wait(self._posture.goToPosture("StandInit", POSTURE_SPEED, _async=True), "StandInit")
        self._motion.setMoveArmsEnabled(False, False)
        self._motion.setStiffnesses("Head", 1.0)
        names = [*HEAD_JOINTS, *CARRYING_POSTURE_RAD]
        angles = [0.0, 0.0, *CARRYING_POSTURE_RAD.values()]
        self._wait(
            self._motion.angleInterpolationWithSpeed(names, angles, POSTURE_SPEED, _async=True),
            "carrying posture",
        )
        self.set_hands(False)
        # The first odometry reading is where the cell file says the NAO starts.
        self._odom_first = np.asarray(self._motion.getRobotPosition(True), dtype=float)

    # --- Humanoid protocol -----------------------------------------------------------
    def pose(self) -> SE2Pose:
        now = SE2Pose(*map(float, self._motion.getRobotPosition(True)))
        first = SE2Pose(*map(float, self._odom_first))
        # The odometry since the first reading, carried from where that reading was.
        return self._odom_origin.compose(first.between(now))

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        self._refuse_if_stopped()
        command = np.array([vx_mps, vy_mps, omega_radps], dtype=float)
        if not np.all(np.isfinite(command)):
            raise ValueError(f"walking velocity must be finite, got {command}")
        vx = float(np.clip(vx_mps, -MAX_FORWARD_MPS, MAX_FORWARD_MPS))
        vy = float(np.clip(vy_mps, -MAX_SIDEWAYS_MPS, MAX_SIDEWAYS_MPS))
        omega = float(np.clip(omega_radps, -MAX_TURN_RADPS, MAX_TURN_RADPS))
        # Sent under the lock, so that an emergency stop comes after it and sees it.
        with self._lock:
            if self._stopped:
                raise EmergencyStopped("the NAO is emergency-stopped: motion refused")
            self._walk_future = self._motion.moveTo(
                vx * WALK_HORIZON_S, vy * WALK_HORIZON_S, omega * WALK_HORIZON_S, _async=True
            )

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        self._refuse_if_stopped()
        positions = np.asarray(positions_rad, dtype=float)
        times = np.asarray(times_s, dtype=float)
        if positions.shape != (len(times), len(joint_names)):
            raise ValueError(
                f"trajectory shape {positions.shape} does not match "
                f"{len(times)} knots x {len(joint_names)} joints"
            )
        if not np.all(np.isfinite(positions)) or np.any(np.diff(times) <= 0.0):
            raise ValueError("knot times must strictly increase and angles be finite")
        # NAOqi wants strictly positive, increasing times: drop a knot at t = 0.
        keep = times > 0.0
        angle_lists = [positions[keep, j].tolist() for j in range(len(joint_names))]
        time_lists = [times[keep].tolist()] * len(joint_names)
        future = self._motion.angleInterpolation(
            list(joint_names), angle_lists, time_lists, True, _async=True
        )
        self._wait(future, "joint trajectory")

    def set_hands(self, open_hands: bool) -> None:
        self._refuse_if_stopped()
        call = self._motion.openHand if open_hands else self._motion.closeHand
        futures = [call(hand, _async=True) for hand in ("LHand", "RHand")]
        for future in futures:
            self._wait(future, "hands")

    def stop(self) -> None:
        """Stops walking (the posture is held)."""
        with self._lock:
            walk, self._walk_future = self._walk_future, None
        if walk is not None:
            walk.cancel()
        self._motion.stopMove()

    def emergency_stop(self) -> None:
        """Cancels every running NAOqi call, stops the walk, frees every joint task; latching."""
        with self._lock:
            self._stopped = True
            pending = [*self._futures, self._walk_future]
            self._walk_future = None
        for future in pending:
            if future is not None:
                with contextlib.suppress(Exception):
                    future.cancel()
        for call in (
            lambda: self._motion.stopMove(),
            lambda: self._motion.killTasksUsingResources(list(BODY_JOINTS)),
            # A walk command still in flight may land after the first stopMove.
            lambda: pending[-1] is not None and pending[-1].wait(int(WALK_HORIZON_S * 1000)),
            lambda: self._motion.stopMove(),
        ):
            try:
                call()
            except Exception as error:  # keep stopping whatever fails
                log.error("NAO emergency stop: %s", error)

    def stand(self, speed: float = 0.5) -> None:
        """Goes to NAOqi's StandInit posture."""
        self._refuse_if_stopped()
        self._wait(self._posture.goToPosture("StandInit", speed, _async=True), "StandInit")

    # --- helpers -----------------------------------------------------------------------
    def _wait(self, future: Any, what: str) -> Any:
        """Waits for a NAOqi call; raises EmergencyStopped if it was cancelled by a stop."""
        with self._lock:
            if self._stopped:
                future.cancel()
                raise EmergencyStopped(f"the NAO is emergency-stopped: {what} refused")
            self._futures.add(future)
        try:
            future.wait()
        finally:
            with self._lock:
                self._futures.discard(future)
        if future.isCanceled() or self._stopped:
            raise EmergencyStopped(f"the NAO is emergency-stopped: {what} cancelled")
        if future.hasError():
            raise RuntimeError(f"NAOqi {what} failed: {future.error()}")
        return future.value()

    def _refuse_if_stopped(self) -> None:
        if self._stopped:
            raise EmergencyStopped("the NAO is emergency-stopped: motion refused")


class NaoSpeaker:
    """:class:`bearchair.hardware.interfaces.Speaker` through the NAO's own voice (ALTextToSpeech.say).

    Attributes:
        spoken: every sentence said, in order (the name every speaker uses).
    """

    def __init__(self, session: Any) -> None:
        self._tts = session.service("ALTextToSpeech")
        self.spoken: list[str] = []

    def say(self, sentence: str) -> None:
        self._tts.say(sentence)
        self.spoken.append(sentence)


class WallClock:
    """:class:`bearchair.hardware.interfaces.Clock` on real robots: real time."""

    def __init__(self) -> None:
        self._start = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._start

    def sleep(self, seconds: float) -> None:
        time.sleep(max(0.0, seconds))
