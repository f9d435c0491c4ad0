"""Stand-ins for the robot SDKs, shaped like the real ones, for tests and dry runs.

* :class:`NaoqiStandin`: a standalone ``qi`` session (real qi networking, needs the
  ``qi`` extra) serving ALMotion, ALRobotPosture, ALTextToSpeech, ALAutonomousLife,
  ALBasicAwareness and ALBattery with NAOqi's method names and argument types
  (``qi.bind`` signatures): a call with another name or other argument types raises in
  the caller, as the robot would. Motions take time (scaled by ``time_scale``) and are
  cancellable; walking with ``moveTo`` ends by itself; odometry starts away from zero,
  as NAOqi's does after a boot. Every call is recorded in ``calls``.
* :class:`FakePanda`: ``panda_py.Panda``'s methods used here with the SDK's parameter
  names and defaults, forward kinematics of the Panda (Craig's DH parameters), O_T_EE
  with the Franka Hand's F_T_EE, libfranka's column-major state arrays, reflex errors,
  automatic recovery inside ``move_to_joint_position`` (as panda-py does) and
  ``get_robot().stop()`` preempting a move.
* :class:`FakeOpenNI2`: the ``openni.openni2`` calls used here; the driver opens at
  320x240 until told otherwise, and a frame's buffer is overwritten when the frame is
  released.

A cell file whose ``panda_host`` is ``"standin"`` gets :class:`FakePanda` and a
:class:`FakeOpenNI2` camera (``bearchair check-hardware`` dry runs).
"""

from __future__ import annotations

import ctypes
import enum
import itertools
import math
import threading
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from bearchair.core.runtime import RUNTIME
from bearchair.hardware.real import import_sdk

STANDIN_HOST = "standin"
"""The ``panda_host`` that selects :class:`FakePanda` and :class:`FakeOpenNI2`."""

# --- NAOqi ------------------------------------------------------------------------------


class JointKeyframes(NamedTuple):
    """An ``angleInterpolation`` as its body plays it: per joint, its angles (rad) and
    the times (s from now) to reach them."""

    names: list[str]
    angles: list[list[float]]
    times: list[list[float]]


class KinematicNao:
    """The body behind :class:`NaoqiStandin` when no simulation is given: motions take
    their time (divided by ``time_scale``) on the wall clock and change nothing else."""

    def __init__(self, boot_odometry: np.ndarray, time_scale: float) -> None:
        self.time_scale = time_scale
        self.joints: dict[str, float] = {}
        self._odometry = np.asarray(boot_odometry, dtype=float).copy()
        self._walk: tuple[np.ndarray, float, float] | None = None  # velocity, start, end
        self._lock = threading.Lock()

    def _now(self) -> float:
        return time.monotonic() * self.time_scale

    def _settle(self) -> None:
        """Integrates the walk up to now (robot-frame velocity, midpoint heading)."""
        if self._walk is None:
            return
        velocity, start, end = self._walk
        now = self._now()
        dt = max(0.0, min(now, end) - start)
        x, y, theta = self._odometry
        heading = theta + 0.5 * velocity[2] * dt
        c, s = math.cos(heading), math.sin(heading)
        self._odometry = np.array(
            [
                x + (c * velocity[0] - s * velocity[1]) * dt,
                y + (s * velocity[0] + c * velocity[1]) * dt,
                theta + velocity[2] * dt,
            ]
        )
        self._walk = None if now >= end else (velocity, now, end)

    def odometry(self) -> np.ndarray:
        with self._lock:
            self._settle()
            return self._odometry.copy()

    def walk(self, velocity: np.ndarray, duration_s: float) -> None:
        with self._lock:
            self._settle()
            now = self._now()
            self._walk = (np.asarray(velocity, dtype=float), now, now + duration_s)

    def stop_walk(self) -> None:
        with self._lock:
            self._settle()
            self._walk = None

    def walking(self) -> bool:
        with self._lock:
            self._settle()
            return self._walk is not None

    def play(self, keyframes: JointKeyframes, cancelled: threading.Event) -> None:
        names, angles, times = keyframes
        if not cancelled.wait(max(t[-1] for t in times) / self.time_scale):
            self.joints.update({name: a[-1] for name, a in zip(names, angles, strict=True)})

    def hand(self, hand: str, open_hand: bool, cancelled: threading.Event) -> None:
        if not cancelled.wait(0.3 / self.time_scale):
            self.joints[hand] = 1.0 if open_hand else 0.0

    def posture(self, name: str, cancelled: threading.Event) -> None:
        cancelled.wait(0.3 / self.time_scale)

    def cancel_motions(self) -> None:
        """NAOqi killed the joint tasks: the waits end through their events."""

    def say(self, sentence: str) -> None:
        """The kinematic NAO is mute."""


class NaoqiStandin:
    """A local NAOqi: ``with NaoqiStandin() as nao: connect(nao.url)``.

    Args:
        time_scale: robot seconds per wall second for the default body.
        boot_odometry: NAOqi's odometry reading when the stand-in starts [x, y, theta].
        body: what the services move (:class:`KinematicNao` by default;
            :class:`bearchair.hardware.real.sim_standins.SimulatedNaoBody` puts the simulated NAO
            behind them).
    """

    def __init__(
        self,
        time_scale: float = 1.0,
        boot_odometry: tuple[float, float, float] = (3.0, -1.0, 0.7),
        body: Any | None = None,
    ) -> None:
        qi = import_sdk("qi", "bearchair[nao]")
        self.calls: list[tuple[str, str, tuple[Any, ...]]] = []
        self.time_scale = time_scale
        self.body = body or KinematicNao(np.asarray(boot_odometry, dtype=float), time_scale)
        self._session = qi.Session()
        self._session.listenStandalone("tcp://127.0.0.1:0")
        self.url = self._session.endpoints()[0]
        self.motion = _make_motion(qi, self)
        services = {
            "ALMotion": self.motion,
            "ALRobotPosture": _make_posture(qi, self),
            "ALTextToSpeech": _make_tts(qi, self),
            "ALAutonomousLife": _make_life(qi, self),
            "ALBasicAwareness": _make_awareness(qi, self),
            "ALBattery": _make_battery(qi, self),
        }
        self.services = services
        for name, service in services.items():
            self._session.registerService(name, service)

    def record(self, service: str, method: str, *args: Any) -> None:
        self.calls.append((service, method, args))

    def called(self, method: str) -> list[tuple[Any, ...]]:
        """The arguments of every call of ``method`` (any service), in order."""
        return [args for _, name, args in self.calls if name == method]

    def close(self) -> None:
        self.motion.halt()
        self._session.close()

    def __enter__(self) -> NaoqiStandin:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _task(
    qi: Any,
    run: Callable[[threading.Event], None],
    value: Any = None,
    on_cancel: Callable[[], None] | None = None,
) -> tuple[Any, threading.Event]:
    """A qi future for ``run(cancelled)`` in a thread; cancelling it sets ``cancelled``."""
    cancelled = threading.Event()

    def cancel(promise: Any) -> None:
        cancelled.set()
        if on_cancel is not None:
            on_cancel()
        promise.setCanceled()

    promise = qi.Promise(cancel)

    def worker() -> None:
        try:
            run(cancelled)
        except Exception as error:
            if not cancelled.is_set():
                promise.setError(str(error))
            return
        if not cancelled.is_set():
            promise.setValue(value)

    RUNTIME.start_thread(worker, name="naoqi-standin task")
    return promise.future(), cancelled


def _make_motion(qi: Any, owner: NaoqiStandin) -> Any:
    """The ALMotion service: its task bookkeeping, walking and joint motions."""

    class ALMotion(
        _motion_joint_methods(qi, owner), _motion_walk_methods(qi, owner), _motion_tasks(qi, owner)
    ):
        pass

    return ALMotion()


def _motion_tasks(qi: Any, owner: NaoqiStandin) -> type:
    """ALMotion's state and its running joint tasks (killed together)."""
    body = owner.body

    class ALMotionTasks:
        def __init__(self) -> None:
            self.awake = False
            self.arm_swing = True
            self._tasks: list[threading.Event] = []
            self._lock = threading.Lock()

        @property
        def joints(self) -> dict[str, float]:
            return body.joints

        @qi.nobind
        def walking(self) -> bool:
            return body.walking()

        @qi.nobind
        def halt(self) -> None:
            body.stop_walk()
            self._kill()

        @qi.nobind
        def _kill(self) -> None:
            with self._lock:
                tasks, self._tasks = self._tasks, []
            for task in tasks:
                task.set()
            body.cancel_motions()

        @qi.nobind
        def _start(self, run: Callable[[threading.Event], None]) -> Any:
            future, cancelled = _task(qi, run, on_cancel=body.cancel_motions)
            with self._lock:
                self._tasks.append(cancelled)
            return future

    return ALMotionTasks


def _motion_walk_methods(qi: Any, owner: NaoqiStandin) -> type:
    """ALMotion's waking, resting, odometry and walking."""
    body = owner.body

    class ALMotionWalking:
        @qi.bind(qi.Void, [])
        def wakeUp(self) -> None:
            owner.record("ALMotion", "wakeUp")
            self.awake = True

        @qi.bind(qi.Void, [])
        def rest(self) -> None:
            owner.record("ALMotion", "rest")
            self.awake = False

        @qi.bind(qi.Bool, [])
        def robotIsWakeUp(self) -> bool:
            owner.record("ALMotion", "robotIsWakeUp")
            return self.awake

        @qi.bind(qi.List(qi.Float), [qi.Bool])
        def getRobotPosition(self, use_sensors: bool) -> list[float]:
            owner.record("ALMotion", "getRobotPosition", use_sensors)
            return [float(v) for v in body.odometry()]

        @qi.bind(qi.Void, [qi.Float, qi.Float, qi.Float])
        def moveTo(self, x: float, y: float, theta: float) -> None:
            # Blocking on the robot; the backend calls it with _async=True. The stand-in
            # walks the displacement in WALK_HORIZON_S, replacing any walk.
            from bearchair.hardware.real.nao import WALK_HORIZON_S

            if not self.awake:
                owner.record("ALMotion", "moveTo", x, y, theta)
                raise RuntimeError("ALMotion.moveTo: the robot is not awake (call wakeUp)")
            body.walk(np.array([x, y, theta]) / WALK_HORIZON_S, WALK_HORIZON_S)
            owner.record("ALMotion", "moveTo", x, y, theta)

        @qi.bind(qi.Void, [])
        def stopMove(self) -> None:
            owner.record("ALMotion", "stopMove")
            body.stop_walk()

        @qi.bind(qi.Void, [qi.Bool, qi.Bool])
        def setMoveArmsEnabled(self, left: bool, right: bool) -> None:
            owner.record("ALMotion", "setMoveArmsEnabled", left, right)
            self.arm_swing = bool(left or right)

        @qi.bind(qi.Bool, [qi.String])
        def getMoveArmsEnabled(self, chain: str) -> bool:
            owner.record("ALMotion", "getMoveArmsEnabled", chain)
            return self.arm_swing

    return ALMotionWalking


def _motion_joint_methods(qi: Any, owner: NaoqiStandin) -> type:
    """ALMotion's stiffness, joint interpolations and hands, each a cancellable task."""
    body = owner.body

    class ALMotionJoints:
        # From ALMotionTasks, ALMotion's other base: kill the running tasks, start one.
        _kill: Callable[[], None]
        _start: Callable[[Callable[[threading.Event], None]], Any]

        @qi.bind(qi.Void, [qi.List(qi.String)])
        def killTasksUsingResources(self, names: list[str]) -> None:
            owner.record("ALMotion", "killTasksUsingResources", list(names))
            self._kill()

        @qi.bind(qi.Void, [qi.Dynamic, qi.Dynamic])
        def setStiffnesses(self, names: Any, stiffnesses: Any) -> None:
            owner.record("ALMotion", "setStiffnesses", names, stiffnesses)

        @qi.bind(qi.Void, [qi.Dynamic, qi.Dynamic, qi.Dynamic, qi.Bool])
        def angleInterpolation(
            self, names: Any, angle_lists: Any, time_lists: Any, absolute: bool
        ) -> Any:
            owner.record("ALMotion", "angleInterpolation", names, angle_lists, time_lists, absolute)
            names, angles, times = _interpolation_lists(names, angle_lists, time_lists)
            if not absolute:
                raise RuntimeError("the stand-in plays absolute angles only")
            keyframes = JointKeyframes(names, angles, times)
            return self._start(lambda cancelled: body.play(keyframes, cancelled))

        @qi.bind(qi.Void, [qi.Dynamic, qi.Dynamic, qi.Float])
        def angleInterpolationWithSpeed(
            self, names: Any, targets: Any, max_speed_fraction: float
        ) -> Any:
            owner.record(
                "ALMotion", "angleInterpolationWithSpeed", names, targets, max_speed_fraction
            )
            if not 0.0 < max_speed_fraction <= 1.0:
                raise RuntimeError("angleInterpolationWithSpeed: speed fraction in (0, 1]")
            names = [names] if isinstance(names, str) else list(names)
            targets = list(targets) if isinstance(targets, list) else [targets]
            if len(targets) != len(names):
                raise RuntimeError("angleInterpolationWithSpeed: one target per joint")
            keyframes = JointKeyframes(names, [[float(a)] for a in targets], [[0.5]] * len(names))
            return self._start(lambda cancelled: body.play(keyframes, cancelled))

        @qi.bind(qi.Void, [qi.String])
        def openHand(self, hand: str) -> Any:
            owner.record("ALMotion", "openHand", hand)
            if hand not in ("LHand", "RHand"):
                raise RuntimeError(f"openHand: unknown hand {hand!r}")
            return self._start(lambda cancelled: body.hand(hand, True, cancelled))

        @qi.bind(qi.Void, [qi.String])
        def closeHand(self, hand: str) -> Any:
            owner.record("ALMotion", "closeHand", hand)
            if hand not in ("LHand", "RHand"):
                raise RuntimeError(f"closeHand: unknown hand {hand!r}")
            return self._start(lambda cancelled: body.hand(hand, False, cancelled))

    return ALMotionJoints


def _interpolation_lists(
    names: Any, angle_lists: Any, time_lists: Any
) -> tuple[list[str], list[list[float]], list[list[float]]]:
    """``angleInterpolation``'s arguments as NAOqi accepts them (a name or names; an angle
    or a list per joint; likewise times), as lists, checked as NAOqi checks them.

    Raises:
        RuntimeError: not one angle list and one time list per joint, or times that are
            not positive and increasing.
    """
    names = [names] if isinstance(names, str) else list(names)
    angles = [a if isinstance(a, list) else [a] for a in angle_lists]
    times = [t if isinstance(t, list) else [t] for t in time_lists]
    if len(angles) != len(names) or len(times) != len(names):
        raise RuntimeError("angleInterpolation: one angle list and one time list per joint")
    for joint_angles, joint_times in zip(angles, times, strict=True):
        if (
            len(joint_angles) != len(joint_times)
            or any(b <= a for a, b in itertools.pairwise(joint_times))
            or joint_times[0] <= 0.0
        ):
            raise RuntimeError("angleInterpolation: times must be positive and increasing")
    return names, angles, times


def _make_posture(qi: Any, owner: NaoqiStandin) -> Any:
    class ALRobotPosture:
        @qi.bind(qi.Bool, [qi.String, qi.Float])
        def goToPosture(self, name: str, speed: float) -> Any:
            owner.record("ALRobotPosture", "goToPosture", name, speed)
            if name not in ("Stand", "StandInit", "StandZero", "Crouch", "Sit", "LyingBack"):
                raise RuntimeError(f"goToPosture: unknown posture {name!r}")

            def run(cancelled: threading.Event) -> None:
                owner.body.posture(name, cancelled)

            future, _ = _task(qi, run, value=True)
            return future

    return ALRobotPosture()


def _make_tts(qi: Any, owner: NaoqiStandin) -> Any:
    class ALTextToSpeech:
        @qi.bind(qi.Void, [qi.String])
        def say(self, sentence: str) -> None:
            owner.record("ALTextToSpeech", "say", sentence)
            owner.body.say(sentence)

    return ALTextToSpeech()


LIFE_STATES = ("disabled", "solitary", "interactive", "safeguard")


def _life_state(state: str) -> str:
    if state not in LIFE_STATES:
        raise RuntimeError(f"ALAutonomousLife.setState: unknown state {state!r}")
    return state


def _make_life(qi: Any, owner: NaoqiStandin) -> Any:
    return _make_setting(
        qi, owner, "ALAutonomousLife", ("setState", "getState"), qi.String, "solitary", _life_state
    )


def _make_awareness(qi: Any, owner: NaoqiStandin) -> Any:
    return _make_setting(
        qi, owner, "ALBasicAwareness", ("setEnabled", "isEnabled"), qi.Bool, True, bool
    )


def _make_setting(
    qi: Any,
    owner: NaoqiStandin,
    service: str,
    methods: tuple[str, str],
    qi_type: Any,
    initial: Any,
    accept: Callable[[Any], Any],
) -> Any:
    """A NAOqi service holding one setting, with its setter and getter (``methods``),
    each call recorded; ``accept`` checks and converts what the setter is given."""
    setter, getter = methods

    @qi.bind(qi.Void, [qi_type])
    def set_value(self: Any, value: Any) -> None:
        owner.record(service, setter, value)
        self.value = accept(value)

    @qi.bind(qi_type, [])
    def get_value(self: Any) -> Any:
        owner.record(service, getter)
        return self.value

    return type(service, (), {"value": initial, setter: set_value, getter: get_value})()


def _make_battery(qi: Any, owner: NaoqiStandin) -> Any:
    class ALBattery:
        @qi.bind(qi.Int32, [])
        def getBatteryCharge(self) -> int:
            owner.record("ALBattery", "getBatteryCharge")
            return 87

    return ALBattery()


# --- panda_py ---------------------------------------------------------------------------

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
    def __init__(self, panda: FakePanda) -> None:
        self._panda = panda

    def stop(self) -> None:
        self._panda.calls.append(("Robot.stop", ()))
        self._panda.stop_motion()

    def read_once(self) -> _State:
        return self._panda.get_state()

    def automatic_error_recovery(self) -> None:
        self._panda.calls.append(("Robot.automatic_error_recovery", ()))
        self._panda.mode, self._panda.errors = _RobotMode.kIdle, _Errors()

    def server_version(self) -> int:
        return 5


class FakePanda:
    """``panda_py.Panda`` as this project uses it (see the module docstring).

    Attributes:
        q: joint angles (rad); ``mode`` and ``errors``: the robot's state;
        calls: (method, args) of every call; ``time_scale``: robot s per wall s.
    """

    JOINT_SPEED_RADPS = 2.0  # at speed_factor 1 (panda-py scales the limits by it)

    def __init__(self, hostname: str, name: str = "panda", realtime_config: Any = None) -> None:
        self.hostname = hostname
        self.q = np.array([0.0, -math.pi / 4, 0.0, -3 * math.pi / 4, 0.0, math.pi / 2, math.pi / 4])
        self.mode = _RobotMode.kIdle
        self.errors = _Errors()
        self.time_scale = 10.0
        self.calls: list[tuple[str, tuple[Any, ...]]] = []
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


# --- openni -----------------------------------------------------------------------------


class _VideoMode:
    def __init__(self, resolutionX: int, resolutionY: int, fps: int, pixelFormat: int) -> None:
        self.resolutionX, self.resolutionY, self.fps, self.pixelFormat = (
            resolutionX,
            resolutionY,
            fps,
            pixelFormat,
        )


class _Frame:
    def __init__(self, data: np.ndarray, width: int, height: int, timestamp_us: int) -> None:
        self._buffer = (ctypes.c_uint8 * data.nbytes).from_buffer_copy(data.tobytes())
        self.width, self.height, self.timestamp = width, height, timestamp_us
        self.dataSize = data.nbytes

    def get_buffer_as_uint8(self) -> Any:
        return (ctypes.c_uint8 * self.dataSize).from_buffer(self._buffer)

    def get_buffer_as_uint16(self) -> Any:
        return (ctypes.c_uint16 * (self.dataSize // 2)).from_buffer(self._buffer)

    def __del__(self) -> None:
        # OpenNI hands the buffer back to the driver on release: it is reused.
        ctypes.memset(self._buffer, 0xAB, self.dataSize)


class _Stream:
    def __init__(self, source: FakeOpenNI2, kind: str) -> None:
        self._source, self._kind = source, kind
        pixel = source.PIXEL_FORMAT_DEPTH_1_MM if kind == "depth" else source.PIXEL_FORMAT_RGB888
        self._mode = _VideoMode(320, 240, 30, pixel)  # the PS1080 driver's default
        self.started = False

    def configure_mode(self, width: int, height: int, fps: int, pixel_format: int) -> None:
        self._mode = _VideoMode(width, height, fps, pixel_format)

    def get_video_mode(self) -> _VideoMode:
        return self._mode

    def start(self) -> None:
        self.started = True

    def stop(self) -> None:
        self.started = False

    def read_frame(self) -> _Frame:
        if not self.started:
            raise RuntimeError("OpenNI: stream not started")
        w, h = self._mode.resolutionX, self._mode.resolutionY
        rgb, depth_mm = self._source.render(w, h)
        stamp_us = self._source.stamp_us()
        data = depth_mm.astype(np.uint16) if self._kind == "depth" else rgb.astype(np.uint8)
        return _Frame(np.ascontiguousarray(data), w, h, stamp_us)


class FakeOpenNI2:
    """The ``openni.openni2`` module as :class:`bearchair.hardware.real.camera.CarmineCamera` uses it.

    Args:
        render: ``(width, height) -> (rgb uint8 HxWx3, depth uint16 mm HxW)``; default a
            grey wall 1 m away.
        library_dir: the only folder from which ``initialize`` loads the library.
        devices: how many cameras are plugged in.
        stamp_us: the frames' timestamps in microseconds (default: the wall clock).
    """

    PIXEL_FORMAT_DEPTH_1_MM = 100
    PIXEL_FORMAT_RGB888 = 200
    IMAGE_REGISTRATION_DEPTH_TO_COLOR = 1

    def __init__(
        self,
        render: Callable[[int, int], tuple[np.ndarray, np.ndarray]] | None = None,
        library_dir: str | None = None,
        devices: int = 1,
        stamp_us: Callable[[], int] | None = None,
    ) -> None:
        self.render = render or _wall
        self.stamp_us = stamp_us or (lambda: int(time.monotonic() * 1e6))
        self._library_dir = library_dir
        self._devices = devices
        self.registration: int | None = None
        self.sync = False
        fake = self

        class Device:
            @classmethod
            def open_any(cls) -> Device:
                if fake._devices == 0:
                    raise RuntimeError("OniError: DeviceOpen using default: no devices found")
                return cls()

            def create_depth_stream(self) -> _Stream:
                return _Stream(fake, "depth")

            def create_color_stream(self) -> _Stream:
                return _Stream(fake, "colour")

            def is_image_registration_mode_supported(self, mode: int) -> bool:
                return mode == fake.IMAGE_REGISTRATION_DEPTH_TO_COLOR

            def set_image_registration_mode(self, mode: int) -> None:
                fake.registration = mode

            def set_depth_color_sync_enabled(self, enable: bool) -> None:
                fake.sync = bool(enable)

        self.Device = Device

    def initialize(self, dll_directories: Any = None) -> None:
        if self._library_dir is not None and dll_directories != self._library_dir:
            raise RuntimeError(f"OpenNI2 library not found in {dll_directories!r}")


def _wall(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    return np.full((height, width, 3), 128, np.uint8), np.full((height, width), 1000, np.uint16)


# --- pyrealsense2 -----------------------------------------------------------------------


_RealSenseStream = enum.Enum("stream", {"depth": 1, "color": 2})
_RealSenseFormat = enum.Enum("format", {"z16": 1, "rgb8": 5})


class _RealSenseFrame:
    def __init__(self, data: np.ndarray) -> None:
        self._data = data

    def get_data(self) -> np.ndarray:
        return self._data

    def __bool__(self) -> bool:
        return True


class _RealSenseFrameset:
    def __init__(self, depth: np.ndarray, colour: np.ndarray) -> None:
        self._depth, self._colour = depth, colour

    def get_depth_frame(self) -> _RealSenseFrame:
        return _RealSenseFrame(self._depth)

    def get_color_frame(self) -> _RealSenseFrame:
        return _RealSenseFrame(self._colour)


class _RealSenseIntrinsics:
    width, height, fx, fy, ppx, ppy = 640, 480, 615.0, 615.0, 320.0, 240.0


class _RealSenseProfile:
    """What ``pipeline.start`` returns: the device (its depth scale) and stream profiles."""

    def __init__(self, fake: FakeRealSense) -> None:
        self._fake = fake

    def get_device(self) -> Any:
        fake = self._fake
        sensor = type("depth_sensor", (), {"get_depth_scale": lambda s: fake.depth_scale_m})
        return type("device", (), {"first_depth_sensor": lambda s: sensor()})()

    def get_stream(self, stream_type: Any) -> Any:
        video = type(
            "video_stream_profile", (), {"get_intrinsics": lambda s: _RealSenseIntrinsics()}
        )
        return type("stream_profile", (), {"as_video_stream_profile": lambda s: video()})()


class FakeRealSense:
    """The ``pyrealsense2`` calls :class:`bearchair.hardware.real.camera.RealSenseCamera` makes.

    A D435-like camera: depth in units of :attr:`depth_scale_m`, colour intrinsics as
    given; frames from ``render`` (default a grey wall 1 m away); ``devices=0`` makes
    ``pipeline.start`` fail as the SDK does ("No device connected").
    """

    def __init__(
        self,
        render: Callable[[int, int], tuple[np.ndarray, np.ndarray]] | None = None,
        devices: int = 1,
        depth_scale_m: float = 0.001,
    ) -> None:
        self.render = render or _wall
        self.depth_scale_m = depth_scale_m
        self.enabled: list[tuple[Any, ...]] = []
        self.aligned_to: Any = None
        self.serial: str  # set by config.enable_device
        fake = self

        class config:
            def enable_device(self, serial: str) -> None:
                fake.serial = serial

            def enable_stream(self, stream_type, width, height, fmt, framerate) -> None:
                fake.enabled.append((stream_type, width, height, fmt, framerate))

        class pipeline:
            def start(self, cfg: Any) -> _RealSenseProfile:
                if fake._devices == 0:
                    raise RuntimeError("No device connected")
                return _RealSenseProfile(fake)

            def wait_for_frames(self, timeout_ms: int = 5000) -> _RealSenseFrameset:
                w, h = fake.enabled[0][1], fake.enabled[0][2]
                rgb, depth_mm = fake.render(w, h)
                units = np.round(depth_mm.astype(np.float64) / 1000.0 / fake.depth_scale_m)
                return _RealSenseFrameset(units.astype(np.uint16), rgb)

            def stop(self) -> None:
                pass

        class align:
            def __init__(self, align_to: Any) -> None:
                fake.aligned_to = align_to

            def process(self, frames: Any) -> Any:
                return frames

        self._devices = devices
        self.stream, self.format, self.config = _RealSenseStream, _RealSenseFormat, config
        self.pipeline, self.align = pipeline, align
