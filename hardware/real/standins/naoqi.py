"""A local NAOqi over real ``qi`` networking, its methods from NAOqi's documented API.

:class:`NaoqiStandin` serves ALMotion, ALRobotPosture, ALTextToSpeech, ALAutonomousLife,
ALBasicAwareness, ALBattery and ALMemory on a standalone qi session. Every method's qi
signature comes from :file:`hardware/real/naoqi_api.json` (NAOqi 2.8's API reference):
a method the table lacks cannot be served, and a call with another name or other
argument types raises in the caller, as on the robot. What the documentation states
is modelled, each with its line in the table's ``quotes``:

* ``moveTo`` is a blocking call (it returns once the target is reached or the walk is
  stopped); ``move`` latches a velocity until ``stopMove`` or the next ``move``.
* A motion whose joints another running motion holds is postponed until they are free
  ("tasks get postponed"); ``killTasksUsingResources`` kills only the tasks using the
  named joints, and killing the walk's leg joints mid-walk counts as a fall (NAOqi warns
  it can make the robot fall).
* Joint names are the NAO's (or its chains'), angles within its limits (qibullet's
  nao.urdf): degrees or a misspelt joint are refused.
* Every call can be made slow (``call_latency_s``, a slow Wi-Fi link): it is answered
  that much later, from its own thread, so slow calls overlap as NAOqi's do.

The body behind the services is :class:`KinematicNao` (wall-clock motions) unless one is
given (:class:`bearchair.hardware.real.standins.simulated_bodies.SimulatedNaoBody`).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from bearchair.hardware.real import import_sdk
from bearchair.hardware.real.standins.naoqi_model import JointKeyframes, answered_later
from bearchair.hardware.real.standins.naoqi_services import make_services


class KinematicNao:
    """The body behind :class:`NaoqiStandin` when no simulation is given: motions take
    their time (divided by ``time_scale``) on the wall clock and change nothing else.

    Args:
        boot_odometry: NAOqi's odometry at the start [x, y, theta].
        time_scale: robot seconds per wall second.
        stop_runout_s: how long (robot seconds) the walk goes on after ``stopMove``
            before it stands on both feet (``moveIsActive()`` true until then).
    """

    def __init__(self, boot_odometry: np.ndarray, time_scale: float, stop_runout_s: float = 0.0):
        self.time_scale = time_scale
        self.stop_runout_s = stop_runout_s
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
        """Walks at ``velocity`` (robot frame) for ``duration_s`` robot seconds (inf: latched)."""
        with self._lock:
            self._settle()
            now = self._now()
            self._walk = (np.asarray(velocity, dtype=float), now, now + duration_s)

    def stop_walk(self) -> None:
        """``stopMove``: the walk ends on both feet, :attr:`stop_runout_s` later."""
        with self._lock:
            self._settle()
            if self._walk is not None:
                velocity, start, end = self._walk
                self._walk = (velocity, start, min(end, self._now() + self.stop_runout_s))

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
        body: what the services move (:class:`KinematicNao` by default).
        call_latency_s: how long every call takes to be answered (a slow link).
        stop_runout_s: the default body's walk after ``stopMove`` (robot seconds).
        without: services not to serve (a NAO without them).
        move_queue_s: when positive, a ``move`` sent while walking takes effect only this
            much later (wall seconds): NAOqi queueing commands, which the documentation
            does not rule out and ``check-hardware --walk`` must catch.

    Attributes:
        calls: (service, method, args) of every call, in arrival order.
        fell: why the NAO would have fallen (its walk's legs killed mid-walk), or "".
        battery_percent, posture_family, memory: what the monitoring calls read.
    """

    def __init__(
        self,
        time_scale: float = 1.0,
        boot_odometry: tuple[float, float, float] = (3.0, -1.0, 0.7),
        body: Any | None = None,
        call_latency_s: float = 0.0,
        stop_runout_s: float = 0.0,
        without: tuple[str, ...] = (),
        move_queue_s: float = 0.0,
    ) -> None:
        qi = import_sdk("qi", "bearchair[nao]")
        self.qi = qi
        self.calls: list[tuple[str, str, tuple[Any, ...]]] = []
        self.time_scale = time_scale
        self.call_latency_s = call_latency_s
        self.move_queue_s = move_queue_s
        boot = np.asarray(boot_odometry, dtype=float)
        self.body = body or KinematicNao(boot, time_scale, stop_runout_s)
        self.fell = ""
        self.battery_percent = 87
        self.posture_family = "Crouching"
        self.memory: dict[str, Any] = {}
        self._session = qi.Session()
        self._session.listenStandalone("tcp://127.0.0.1:0")
        self.url = self._session.endpoints()[0]
        self.services = make_services(qi, self)
        self.motion = self.services["ALMotion"]
        for name, service in self.services.items():
            if name not in without:
                self._session.registerService(name, service)

    def record(self, service: str, method: str, *args: Any) -> None:
        self.calls.append((service, method, args))

    def called(self, method: str) -> list[tuple[Any, ...]]:
        """The arguments of every call of ``method`` (any service), in order."""
        return [args for _, name, args in self.calls if name == method]

    def answer(self, work: Callable[[], Any], blocking: bool) -> Any:
        """``work()``'s result as the caller gets it: at once, or on a slow link as a
        future answered from a thread. A call NAOqi documents as blocking (``blocking``)
        returns a future its work completes, so it never holds up other calls."""
        if self.call_latency_s <= 0.0:
            return work()
        return answered_later(self.qi, work, self.call_latency_s)

    def close(self) -> None:
        self.motion.halt()
        self._session.close()

    def __enter__(self) -> NaoqiStandin:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
