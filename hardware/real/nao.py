"""The NAO through NAOqi (``qi``): walking, joint trajectories, hands, speech.

NAOqi calls used, with their documented shapes (ALMotion unless named; the signatures
are in :file:`naoqi_api.json`, from the NAOqi 2.8 documentation):

* ``getRobotPosition(useSensors: bool) -> [x, y, theta]``: odometry in NAOqi's world
  frame, which starts wherever the robot was when NAOqi booted. :meth:`NaoHumanoid.pose`
  counts from the first reading, so the cell file's start pose is the origin.
* ``move(x, y, theta)`` (m/s, rad/s, robot frame): NAOqi's tracking command ("the
  robot's instantaneous velocity ... typically used to control the walk from a loop",
  Locomotion control). The velocity is latched until the next ``move`` or ``stopMove``,
  so a client heartbeat (:class:`WalkWatchdog`) calls ``stopMove`` when the walking
  controller misses two of its periods (:data:`HEARTBEAT_PERIOD_S`). ``moveTo`` (a
  target to walk to, a *blocking* call) is not used for tracking.
* ``angleInterpolation(names, angleLists, timeLists, isAbsolute)``, ``openHand(name)``,
  ``closeHand(name)``: called asynchronously; each running motion is kept with the
  joints it uses.
* An emergency stop: ``stopMove()``, then a bounded wait for ``moveIsActive()`` to read
  false (the walk's own stop, which ends on both feet), and only then
  ``killTasksUsingResources`` on the joints of the motions still running. NAOqi warns
  that killing the walk's leg tasks mid-step can make the robot fall.
* Carrying set-up (:meth:`NaoHumanoid.activate`): ``ALAutonomousLife.setState("disabled")``,
  ``ALBasicAwareness.setEnabled(False)`` (it turns the head, which carries the tag, toward
  people), ``wakeUp()``, ``ALRobotPosture.goToPosture("StandInit", speed)``,
  ``setMoveArmsEnabled(False, False)`` (no arm swing while carrying), the carrying posture
  and closed hands, head stiff at (0, 0).

Every call is asynchronous and waited for with a bound (:data:`CALL_TIMEOUT_S`) in
slices, so a half-open Wi-Fi link ends in a :class:`~bearchair.hardware.real.bounded.DeviceTimeout`
naming the call, and Ctrl-C or SIGTERM is honoured while waiting. Connecting reads state
only; nothing moves until :meth:`NaoHumanoid.activate`.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from bearchair.core.errors import BackendError, BackendUnavailable
from bearchair.core.nao_carrying import CARRYING_POSTURE_RAD
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.real import EmergencyStopped, import_sdk
from bearchair.hardware.real.bounded import SLICE_S, DeviceTimeout
from bearchair.hardware.real.nao_watch import WalkWatchdog

log = logging.getLogger(__name__)

# NAO's walking speed limits (NAOqi documentation: about 0.1 m/s forward, 0.5 rad/s).
MAX_FORWARD_MPS = 0.1
MAX_SIDEWAYS_MPS = 0.08
MAX_TURN_RADPS = 0.5
HEARTBEAT_PERIOD_S = 0.2
"""The walking controller's longest expected gap between two commands (seconds): it
commands every 0.1 s (``skills.control.walk``, ``dt_s``) with a tag frame in between;
two missed periods (0.4 s, 4 cm at full speed) and the watchdog stops the walk."""
CONNECT_TIMEOUT_S = 5.0
CALL_TIMEOUT_S = 2.0
"""Bound on one NAOqi call (seconds): on a working link calls answer in tens of ms."""
STOP_CALL_TIMEOUT_S = 0.45
"""Bound on each call of an emergency stop, within the 0.5 s the NAO has to be still."""
WALK_END_TIMEOUT_S = 1.5
"""How long a stop waits for ``moveIsActive()`` to read false: NAOqi ends the walk on
both feet, at most one step (about 0.6 s at the default step period) after ``stopMove``."""
POSTURE_SPEED = 0.3
"""Fraction of the joints' maximum speed for set-up postures (a bear in the arms)."""
MIN_BATTERY_PERCENT = 15
"""Below this charge a run stops (the NAO is set down while it can still stand): at about
an hour of walking per charge (NAO datasheet), 15 % is some 9 minutes, one mission."""
LEG_JOINTS = tuple(
    f"{side}{joint}"
    for side in "LR"
    for joint in ("HipYawPitch", "HipRoll", "HipPitch", "KneePitch", "AnklePitch", "AnkleRoll")
)
TEMPERATURE_STATUS_KEY = "Device/SubDeviceList/{}/Temperature/Sensor/Status"
"""ALMemory's temperature status of a joint: 0 normal; from 1 NAOqi limits its stiffness,
and at 2 on a leg the robot goes to rest (NAOqi 2.8, Diagnosis effect): with a bear in
its arms, the run stops at 1."""
HEAD_JOINTS = ("HeadYaw", "HeadPitch")
HAND_JOINTS = {"LHand": ("LHand",), "RHand": ("RHand",)}


def connect(
    url: str,
    user: str | None = None,
    password: str | None = None,
    timeout_s: float = CONNECT_TIMEOUT_S,
) -> Any:
    """Opens a qi session to the robot (``tcp://nao.local:9559``, or ``tcps://...:9503``
    with ``user``/``password`` on NAOqi >= 2.9), giving up after ``timeout_s``.

    A peer that accepts the TCP connection and never answers ends the same way; Ctrl-C
    and SIGTERM end the wait within :data:`~bearchair.hardware.real.bounded.SLICE_S`.

    Raises:
        BackendUnavailable: qi is missing or the robot does not answer in time.
    """
    qi = import_sdk("qi", "bearchair[nao]")
    session = qi.Session()
    if user is not None:
        session.setClientAuthenticatorFactory(_CredentialsFactory(user, password or ""))
    future = session.connect(url, _async=True)
    try:
        await_future(future, timeout_s, f"cannot reach the NAO at {url}")
    except BaseException as error:
        future.cancel()
        session.close(_async=True)  # never waited for: the link may be dead
        if isinstance(error, BackendError):
            raise BackendUnavailable(str(error)) from None
        raise
    return session


def await_future(future: Any, timeout_s: float, what: str) -> Any:
    """The value of a qi future within ``timeout_s``, waited for in slices.

    Raises:
        DeviceTimeout: not finished in time (``what: no answer in ... s``).
        BackendError: it finished with an error or was cancelled (one line).
    """
    deadline = time.monotonic() + timeout_s
    while not future.isFinished():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            raise DeviceTimeout(f"{what}: no answer in {timeout_s:g} s")
        # A qi wait blocks in C; a short one lets a stop signal run between slices.
        future.wait(max(1, int(min(SLICE_S, remaining) * 1000)))
    if future.isCanceled():
        raise BackendError(f"{what}: cancelled")
    if future.hasError(0):
        raise BackendError(f"{what}: {_one_line(future.error(0))}")
    return future.value(0)


def _one_line(text: Any) -> str:
    return (str(text).strip().splitlines() or ["(no message)"])[0]


def service(session: Any, name: str, timeout_s: float = CALL_TIMEOUT_S) -> Any:
    """A NAOqi service, within ``timeout_s``.

    Raises:
        BackendUnavailable: the NAO does not offer it or does not answer (one line).
    """
    try:
        return await_future(session.service(name, _async=True), timeout_s, f"NAOqi {name}")
    except BackendError as error:
        raise BackendUnavailable(f"the NAO's {error}") from None


def call(proxy: Any, method: str, *args: Any, timeout_s: float = CALL_TIMEOUT_S) -> Any:
    """``proxy.method(*args)`` asynchronously, its result within ``timeout_s``.

    Raises:
        DeviceTimeout, BackendError: no answer, or NAOqi's error (one line naming the call).
    """
    future = getattr(proxy, method)(*args, _async=True)
    return await_future(future, timeout_s, f"NAOqi {method}")


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
        call_timeout_s: the bound on one NAOqi call.
        clock: the walking controller's clock, for the heartbeat (default: wall time).

    Raises:
        BackendUnavailable: a service is missing or the NAO does not answer.
    """

    def __init__(
        self,
        session: Any,
        odom_origin: SE2Pose = SE2Pose(0.0, 0.0, 0.0),
        call_timeout_s: float = CALL_TIMEOUT_S,
        clock: Any | None = None,
    ) -> None:
        self._session = session
        self._timeout_s = call_timeout_s
        self._motion = service(session, "ALMotion", call_timeout_s)
        self._posture = service(session, "ALRobotPosture", call_timeout_s)
        self._odom_origin = odom_origin
        self._lock = threading.Lock()
        self._running: dict[Any, tuple[str, ...]] = {}  # future -> the joints it moves
        self._walking = False
        self._stopped = False
        self._active = False
        now = clock.now if clock is not None else time.monotonic
        self.watchdog = WalkWatchdog(self._watchdog_stop, HEARTBEAT_PERIOD_S, now)
        # Odometry is counted from here: NAOqi's own origin is where it booted.
        self._odom_first = np.asarray(self._call("getRobotPosition", True), dtype=float)

    # --- lifecycle -------------------------------------------------------------------
    def state(self) -> dict[str, Any]:
        """What check-hardware prints: awake, Autonomous Life, battery, arm swing (reads only)."""
        life = service(self._session, "ALAutonomousLife", self._timeout_s)
        awareness = service(self._session, "ALBasicAwareness", self._timeout_s)
        battery = service(self._session, "ALBattery", self._timeout_s)
        return {
            "awake": bool(self._call("robotIsWakeUp")),
            "arm_swing": bool(self._call("getMoveArmsEnabled", "Arms")),
            "autonomous_life": str(call(life, "getState", timeout_s=self._timeout_s)),
            "basic_awareness": bool(call(awareness, "isEnabled", timeout_s=self._timeout_s)),
            "battery_percent": int(call(battery, "getBatteryCharge", timeout_s=self._timeout_s)),
        }

    def activate(self) -> None:
        """Sets the NAO up for carrying the bear (this moves it: after the operator agrees)."""
        self._refuse_if_stopped()
        life = service(self._session, "ALAutonomousLife", self._timeout_s)
        call(life, "setState", "disabled", timeout_s=self._timeout_s)
        awareness = service(self._session, "ALBasicAwareness", self._timeout_s)
        call(awareness, "setEnabled", False, timeout_s=self._timeout_s)
        self._call("wakeUp", timeout_s=30.0)
        self._motion_task(
            self._posture.goToPosture("StandInit", POSTURE_SPEED, _async=True),
            "StandInit",
            _all_joints(),
            30.0,
        )
        self._call("setMoveArmsEnabled", False, False)
        self._call("setStiffnesses", "Head", 1.0)
        names = [*HEAD_JOINTS, *CARRYING_POSTURE_RAD]
        angles = [0.0, 0.0, *CARRYING_POSTURE_RAD.values()]
        future = self._motion.angleInterpolationWithSpeed(names, angles, POSTURE_SPEED, _async=True)
        self._motion_task(future, "carrying posture", tuple(names), 30.0)
        self.set_hands(False)
        # The first odometry reading is where the cell file says the NAO starts.
        self._odom_first = np.asarray(self._call("getRobotPosition", True), dtype=float)
        self._active = True

    def health(self) -> str | None:
        """Why the NAO cannot go on carrying (battery, a fall, a hot leg), or None."""
        battery = service(self._session, "ALBattery", self._timeout_s)
        charge = int(call(battery, "getBatteryCharge", timeout_s=self._timeout_s))
        if charge < MIN_BATTERY_PERCENT:
            return f"the NAO's battery is at {charge} % (below {MIN_BATTERY_PERCENT} %)"
        if self._active:
            family = str(call(self._posture, "getPostureFamily", timeout_s=self._timeout_s))
            if family != "Standing":
                return f"the NAO is no longer standing (posture family {family}): it fell?"
        memory = service(self._session, "ALMemory", self._timeout_s)
        keys = [TEMPERATURE_STATUS_KEY.format(joint) for joint in LEG_JOINTS]
        statuses = call(memory, "getListData", keys, timeout_s=self._timeout_s)
        hot = [(j, int(v)) for j, v in zip(LEG_JOINTS, statuses, strict=True) if int(v or 0) >= 1]
        if hot:
            joint, status = max(hot, key=lambda item: item[1])
            return f"the NAO's {joint} is hot (temperature status {status}): NAOqi limits its stiffness"
        return None

    # --- Humanoid protocol -----------------------------------------------------------
    def pose(self) -> SE2Pose:
        now = SE2Pose(*map(float, self._call("getRobotPosition", True)))
        first = SE2Pose(*map(float, self._odom_first))
        # The odometry since the first reading, carried from where that reading was.
        return self._odom_origin.compose(first.between(now))

    def head_yaw_rad(self) -> float:
        """The head's measured yaw (rad): the tag on the head turns with it."""
        return float(self._call("getAngles", "HeadYaw", True)[0])

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        """Walks at this robot-frame velocity (clipped to the NAO's limits) until the next
        command, :meth:`stop`, or two missed heartbeat periods."""
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
            future = self._motion.move(vx, vy, omega, _async=True)
            self._walking = True
        self.watchdog.beat()
        # move() returns at once on the robot: its result is checked, within the bound.
        await_future(future, self._timeout_s, "NAOqi move")

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
        duration = float(times[-1]) + self._timeout_s
        self._motion_task(future, "joint trajectory", tuple(joint_names), duration)

    def set_hands(self, open_hands: bool) -> None:
        self._refuse_if_stopped()
        method = "openHand" if open_hands else "closeHand"
        futures = [(hand, getattr(self._motion, method)(hand, _async=True)) for hand in HAND_JOINTS]
        for hand, future in futures:
            self._motion_task(future, "hands", HAND_JOINTS[hand], 5.0 + self._timeout_s)

    def stop(self) -> None:
        """Stops walking (the posture is held)."""
        self.watchdog.idle()
        with self._lock:
            self._walking = False
        self._call("stopMove")

    def emergency_stop(self) -> None:
        """Ends the walk with ``stopMove`` and waits (bounded) for it to end; then cancels the
        running motions and frees only their joints; latching. Never raises.

        Each call is asynchronous with :data:`STOP_CALL_TIMEOUT_S`; nothing waits for a
        walk command's result. Without a walk, the stop and the kill go out together.
        """
        with self._lock:
            self._stopped = True
            walking, self._walking = self._walking, False
            running = dict(self._running)
        self.watchdog.idle()
        stop_move = _send(self._motion, "stopMove")
        if walking:
            # The walk ends on both feet first: its leg tasks are never killed mid-step.
            _settle(stop_move, "stopMove")
            self._wait_walk_end(STOP_CALL_TIMEOUT_S)
        for future in running:
            _quietly(future.cancel)
        joints = sorted({joint for used in running.values() for joint in used})
        kill = _send(self._motion, "killTasksUsingResources", joints) if joints else None
        for future, what in ((stop_move, "stopMove"), (kill, "killTasksUsingResources")):
            _settle(future, what)

    def close(self) -> None:
        """Stops the NAO and closes the qi session (its threads must not outlive the
        interpreter: a qi callback running while it finalises aborts the process)."""
        self.emergency_stop()
        with contextlib.suppress(Exception):
            self._session.close()

    def stand(self, speed: float = 0.5) -> None:
        """Goes to NAOqi's StandInit posture."""
        self._refuse_if_stopped()
        future = self._posture.goToPosture("StandInit", speed, _async=True)
        self._motion_task(future, "StandInit", _all_joints(), 30.0)

    # --- helpers -----------------------------------------------------------------------
    def _call(self, method: str, *args: Any, timeout_s: float | None = None) -> Any:
        return call(self._motion, method, *args, timeout_s=timeout_s or self._timeout_s)

    def _stop_call(self, method: str, *args: Any) -> None:
        _settle(_send(self._motion, method, *args), method)

    def _wait_walk_end(self, timeout_s: float) -> bool:
        """Polls ``moveIsActive()`` until it reads false, within ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while (remaining := deadline - time.monotonic()) > 0.0:
            try:
                if not self._call("moveIsActive", timeout_s=remaining):
                    return True
            except Exception as error:
                log.error("NAO emergency stop: %s", error)
                return False
        return False

    def _watchdog_stop(self) -> None:
        """The heartbeat was missed twice: the walk is stopped (the mission is told)."""
        with self._lock:
            walking, self._walking = self._walking, False
        if walking:
            log.error("NAO walk: no command for %.1f s: stopMove", 2 * HEARTBEAT_PERIOD_S)
            self._stop_call("stopMove")

    def _motion_task(
        self, future: Any, what: str, joints: tuple[str, ...], timeout_s: float
    ) -> Any:
        """Waits for a NAOqi motion (bounded); raises EmergencyStopped if a stop ended it."""
        with self._lock:
            if self._stopped:
                _quietly(future.cancel)
                raise EmergencyStopped(f"the NAO is emergency-stopped: {what} refused")
            self._running[future] = joints
        try:
            value = await_future(future, timeout_s, f"NAOqi {what}")
        except BackendError:
            if self._stopped:
                raise EmergencyStopped(f"the NAO is emergency-stopped: {what} cancelled") from None
            raise
        finally:
            with self._lock:
                self._running.pop(future, None)
        if self._stopped:
            raise EmergencyStopped(f"the NAO is emergency-stopped: {what} cancelled")
        return value

    def _refuse_if_stopped(self) -> None:
        if self._stopped:
            raise EmergencyStopped("the NAO is emergency-stopped: motion refused")


def _all_joints() -> tuple[str, ...]:
    """Every joint a posture change may move: the body's chains."""
    return ("Body",)


def _quietly(action: Any) -> None:
    try:
        action()
    except Exception as error:  # a stop must go on
        log.error("NAO emergency stop: %s", error)


def _send(proxy: Any, method: str, *args: Any) -> Any:
    """Sends a stopping call without waiting; None if it could not even be sent."""
    try:
        return getattr(proxy, method)(*args, _async=True)
    except Exception as error:  # a stop must go on
        log.error("NAO emergency stop: %s: %s", method, error)
        return None


def _settle(future: Any, what: str) -> None:
    """Waits (bounded by :data:`STOP_CALL_TIMEOUT_S`) for a stopping call; logs a failure."""
    if future is None:
        return
    try:
        await_future(future, STOP_CALL_TIMEOUT_S, f"NAOqi {what}")
    except Exception as error:  # a stop must go on
        log.error("NAO emergency stop: %s", error)


class NaoSpeaker:
    """:class:`bearchair.hardware.interfaces.Speaker` through the NAO's own voice (ALTextToSpeech.say).

    Attributes:
        spoken: every sentence said, in order (the name every speaker uses).
    """

    def __init__(self, session: Any, timeout_s: float = 30.0) -> None:
        self._tts = service(session, "ALTextToSpeech")
        self._timeout_s = timeout_s
        self.spoken: list[str] = []

    def say(self, sentence: str) -> None:
        # say() returns once spoken: a sentence takes seconds, not minutes.
        call(self._tts, "say", sentence, timeout_s=self._timeout_s)
        self.spoken.append(sentence)


class WallClock:
    """:class:`bearchair.hardware.interfaces.Clock` on real robots: real time."""

    def __init__(self) -> None:
        self._start = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._start

    def sleep(self, seconds: float) -> None:
        time.sleep(max(0.0, seconds))
