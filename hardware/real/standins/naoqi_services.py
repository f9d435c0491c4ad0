"""The services of :class:`~bearchair.hardware.real.standins.naoqi.NaoqiStandin`.

Each served method is declared with :func:`exposed`, which takes its qi signature from
NAOqi 2.8's table (:func:`~bearchair.hardware.real.standins.naoqi.documented`), records
the call and answers it as the stand-in's link does.
"""

from __future__ import annotations

import functools
import itertools
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from bearchair.hardware.real.standins.naoqi_model import (
    JointKeyframes,
    check_angles,
    documented,
    naoqi_api,
    qi_type,
    resolve_joints,
    task_future,
)

LEG_JOINTS = frozenset(naoqi_api()["chains"]["LLeg"] + naoqi_api()["chains"]["RLeg"])
WALK_LIMITS = (0.1, 0.08, 0.5)
"""The NAO's walking speed limits (m/s, m/s, rad/s): ``moveTo`` walks at them."""


def exposed(owner: Any, service: str) -> Callable[[Callable[..., Any]], Any]:
    """Serves a method under its NAOqi name with NAOqi 2.8's qi signature.

    Raises:
        KeyError: at class creation, for a method NAOqi 2.8 does not document.
    """
    qi = owner.qi

    def wrap(function: Callable[..., Any]) -> Any:
        name = function.__name__
        entry = documented(service, name)
        blocking = bool(entry.get("blocking", False))

        @functools.wraps(function)
        def method(self: Any, *args: Any) -> Any:
            owner.record(service, name, *args)
            return owner.answer(lambda: function(self, *args), blocking)

        signature = [qi_type(qi, kind) for _, kind in entry["args"]]
        return qi.bind(qi_type(qi, entry["returns"]), signature, methodName=name)(method)

    return wrap


def make_services(qi: Any, owner: Any) -> dict[str, Any]:
    """Every service the stand-in serves, by NAOqi name."""
    return {
        "ALMotion": _motion(qi, owner),
        "ALRobotPosture": _posture(qi, owner),
        "ALTextToSpeech": _tts(owner),
        "ALAutonomousLife": _setting(
            owner, "ALAutonomousLife", ("setState", "getState"), "solitary"
        ),
        "ALBasicAwareness": _setting(owner, "ALBasicAwareness", ("setEnabled", "isEnabled"), True),
        "ALBattery": _battery(owner),
        "ALMemory": _memory(owner),
    }


class _Tasks:
    """ALMotion's motion tasks: each books its joints when called; one needing a joint an
    earlier task holds waits for it ("postponed until the resource is freed")."""

    def __init__(self, qi: Any, owner: Any) -> None:
        self._qi, self._body, self._owner = qi, owner.body, owner
        self._booked: list[tuple[frozenset[str], threading.Event]] = []  # in call order
        self._free = threading.Condition()

    def start(self, joints: list[str], run: Callable[[threading.Event], None]) -> Any:
        """A future for ``run``; postponed while an earlier task holds one of its joints."""
        needed = frozenset(joints)
        booked = threading.Event()  # the task's cancel event, once its thread has it
        entry: list[Any] = [needed, None]
        with self._free:
            self._booked.append(entry)  # type: ignore[arg-type]  # booked at call time

        def task(cancelled: threading.Event) -> None:
            with self._free:
                entry[1] = cancelled
                booked.set()
                while not cancelled.is_set() and any(
                    needed & held
                    for held, _ in self._booked[: self._booked.index(entry)]  # type: ignore[arg-type]
                ):
                    self._free.wait(0.01)
            try:
                if not cancelled.is_set():
                    run(cancelled)
            finally:
                with self._free:
                    self._booked.remove(entry)  # type: ignore[arg-type]
                    self._free.notify_all()

        future, _ = task_future(
            self._qi,
            task,
            on_cancel=self._body.cancel_motions,
            cancel_delay_s=self._owner.call_latency_s,
        )
        booked.wait(1.0)
        return future

    def kill(self, joints: list[str] | None) -> int:
        """Ends the tasks (running or postponed) using any of ``joints`` (None: all)."""
        with self._free:
            killed = [
                cancelled
                for held, cancelled in self._booked
                if cancelled is not None and (joints is None or held & set(joints))
            ]
        for cancelled in killed:
            cancelled.set()
        if killed:
            self._body.cancel_motions()
        return len(killed)


def _motion(qi: Any, owner: Any) -> Any:
    body = owner.body
    tasks = _Tasks(qi, owner)
    api = exposed(owner, "ALMotion")

    class ALMotion(_walking(qi, owner)):
        def __init__(self) -> None:
            self.awake = False
            self.arm_swing = True

        @property
        def joints(self) -> dict[str, float]:
            return body.joints

        @qi.nobind
        def walking(self) -> bool:
            return body.walking()

        @qi.nobind
        def halt(self) -> None:
            body.stop_walk()
            tasks.kill(None)

        @api
        def killTasksUsingResources(self, names: list[str]) -> None:
            joints = resolve_joints(names)
            if body.walking() and LEG_JOINTS & set(joints):
                owner.fell = (
                    f"killTasksUsingResources({sorted(LEG_JOINTS & set(joints))[0]}, ...) mid-walk"
                )
                body.stop_walk()
            tasks.kill(joints)

        @api
        def setStiffnesses(self, names: Any, stiffnesses: Any) -> None:
            resolve_joints(names)

        @api
        def getAngles(self, names: Any, use_sensors: bool) -> list[float]:
            return [float(body.joints.get(name, 0.0)) for name in resolve_joints(names)]

        @api
        def angleInterpolation(
            self, names: Any, angle_lists: Any, time_lists: Any, absolute: bool
        ) -> Any:
            names, angles, times = interpolation_lists(names, angle_lists, time_lists)
            if not absolute:
                raise RuntimeError("the stand-in plays absolute angles only")
            check_angles(names, angles)
            keyframes = JointKeyframes(names, angles, times)
            return tasks.start(names, lambda cancelled: body.play(keyframes, cancelled))

        @api
        def angleInterpolationWithSpeed(self, names: Any, targets: Any, speed: float) -> Any:
            if not 0.0 < speed <= 1.0:
                raise RuntimeError("angleInterpolationWithSpeed: speed fraction in (0, 1]")
            names = resolve_joints(names)
            targets = list(targets) if isinstance(targets, list) else [targets]
            if len(targets) != len(names):
                raise RuntimeError("angleInterpolationWithSpeed: one target per joint")
            check_angles(names, [[float(a)] for a in targets])
            keyframes = JointKeyframes(names, [[float(a)] for a in targets], [[0.5]] * len(names))
            return tasks.start(names, lambda cancelled: body.play(keyframes, cancelled))

        @api
        def openHand(self, hand: str) -> Any:
            return self._hand(hand, True)

        @api
        def closeHand(self, hand: str) -> Any:
            return self._hand(hand, False)

        @qi.nobind
        def _hand(self, hand: str, open_hand: bool) -> Any:
            if hand not in ("LHand", "RHand"):
                raise RuntimeError(f"ALMotion: unknown hand {hand!r}")
            return tasks.start([hand], lambda cancelled: body.hand(hand, open_hand, cancelled))

    return ALMotion()


def _walking(qi: Any, owner: Any) -> type:
    """ALMotion's waking, odometry and walking."""
    body = owner.body
    api = exposed(owner, "ALMotion")

    class ALMotionWalking:
        awake: bool
        arm_swing: bool

        @api
        def wakeUp(self) -> None:
            self.awake = True

        @api
        def rest(self) -> None:
            self.awake = False

        @api
        def robotIsWakeUp(self) -> bool:
            return self.awake

        @api
        def getRobotPosition(self, use_sensors: bool) -> list[float]:
            return [float(v) for v in body.odometry()]

        @api
        def move(self, x: float, y: float, theta: float) -> None:
            # "Makes the robot move at the given velocity ... a non-blocking call": latched.
            self._refuse_asleep("move")
            velocity = np.clip([x, y, theta], -np.array(WALK_LIMITS), WALK_LIMITS)
            if not np.any(velocity):
                body.stop_walk()
                return
            if owner.move_queue_s > 0.0 and body.walking():
                later = threading.Timer(owner.move_queue_s, body.walk, (velocity, float("inf")))
                later.daemon = True
                later.start()
                return
            body.walk(velocity, float("inf"))

        @api
        def moveTo(self, x: float, y: float, theta: float) -> Any:
            # "Makes the robot move to the given pose ... This is a blocking call."
            self._refuse_asleep("moveTo")
            duration = float(np.max(np.abs([x, y, theta]) / np.array(WALK_LIMITS)))
            if duration <= 0.0:
                return
            body.walk(np.array([x, y, theta]) / duration, duration)

            def walked(cancelled: threading.Event) -> None:
                while body.walking() and not cancelled.is_set():
                    time.sleep(0.01)

            return task_future(qi, walked)[0]  # answered once the walk has ended

        @api
        def stopMove(self) -> None:
            body.stop_walk()

        @api
        def moveIsActive(self) -> bool:
            return body.walking()

        @api
        def setMoveArmsEnabled(self, left: bool, right: bool) -> None:
            self.arm_swing = bool(left or right)

        @api
        def getMoveArmsEnabled(self, chain: str) -> bool:
            return self.arm_swing

        @qi.nobind
        def _refuse_asleep(self, method: str) -> None:
            if not self.awake:
                raise RuntimeError(f"ALMotion.{method}: the robot is not awake (call wakeUp)")

    return ALMotionWalking


def interpolation_lists(
    names: Any, angle_lists: Any, time_lists: Any
) -> tuple[list[str], list[list[float]], list[list[float]]]:
    """``angleInterpolation``'s arguments as NAOqi accepts them (a name or names; an angle
    or a list per joint; likewise times), as lists, checked as NAOqi checks them.

    Raises:
        RuntimeError: an unknown joint, not one angle list and one time list per joint,
            or times that are not positive and increasing.
    """
    names = resolve_joints(names)
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


def _posture(qi: Any, owner: Any) -> Any:
    api = exposed(owner, "ALRobotPosture")
    families = naoqi_api()["posture_families"]

    class ALRobotPosture:
        @api
        def goToPosture(self, name: str, speed: float) -> Any:
            if name not in families:
                raise RuntimeError(f"goToPosture: unknown posture {name!r}")

            def run(cancelled: threading.Event) -> None:
                owner.body.posture(name, cancelled)
                if not cancelled.is_set():
                    owner.posture_family = families[name]

            return task_future(qi, run, value=True)[0]

        @api
        def getPostureFamily(self) -> str:
            return owner.posture_family

        @api
        def stopMove(self) -> None:
            """Nothing to stop: postures are cancelled through their futures."""

    return ALRobotPosture()


def _tts(owner: Any) -> Any:
    api = exposed(owner, "ALTextToSpeech")

    class ALTextToSpeech:
        @api
        def say(self, sentence: str) -> None:
            owner.body.say(sentence)

    return ALTextToSpeech()


def _setting(owner: Any, service: str, methods: tuple[str, str], initial: Any) -> Any:
    """A NAOqi service holding one setting, with its setter and getter (``methods``)."""
    api = exposed(owner, service)
    setter, getter = methods
    states = naoqi_api()["autonomous_life_states"]

    def set_value(self: Any, value: Any) -> None:
        if service == "ALAutonomousLife" and value not in states:
            raise RuntimeError(f"{service}.{setter}: unknown state {value!r}")
        self.value = value

    def get_value(self: Any) -> Any:
        return self.value

    set_value.__name__, get_value.__name__ = setter, getter
    return type(service, (), {"value": initial, setter: api(set_value), getter: api(get_value)})()


def _battery(owner: Any) -> Any:
    api = exposed(owner, "ALBattery")

    class ALBattery:
        @api
        def getBatteryCharge(self) -> int:
            return int(owner.battery_percent)

    return ALBattery()


def _memory(owner: Any) -> Any:
    api = exposed(owner, "ALMemory")

    class ALMemory:
        @api
        def getData(self, key: str) -> Any:
            return owner.memory.get(key, 0)

        @api
        def getListData(self, keys: Any) -> Any:
            return [owner.memory.get(key, 0) for key in keys]

    return ALMemory()
