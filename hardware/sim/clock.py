"""Simulated time: sleeping steps the physics and every process that lives in it."""

from __future__ import annotations

import time
from dataclasses import dataclass

from bearchair.hardware.sim.bullet import LockedBullet, StepProcess

PHYSICS_RATE_HZ = 240.0


@dataclass
class WorldTimers:
    """Wall time the simulated world spends on itself, for ``bench/mission.py``.

    Attributes:
        stepping_s: in :meth:`SimClock.step` (the processes and the physics together).
        physics_s: in pybullet's ``stepSimulation`` alone (part of ``stepping_s``).
        steps: physics steps taken.
        render_s: rendering camera frames and pictures (TinyRenderer, depth conversion).
        noise_s: applying the camera noise model to captures.
        frames: frames rendered; pixels: their pixels in total.
    """

    stepping_s: float = 0.0
    physics_s: float = 0.0
    steps: int = 0
    render_s: float = 0.0
    noise_s: float = 0.0
    frames: int = 0
    pixels: int = 0

    def copy(self) -> WorldTimers:
        return WorldTimers(**vars(self))


class SimClock:
    """Implements :class:`bearchair.hardware.interfaces.Clock` on the simulation.

    ``now()`` is simulated seconds since the world was built. ``sleep(s)`` advances the
    physics by ``round(s * 240)`` steps of 1/240 s; before each step, every registered
    process (walking, the helper turning the chair, joint trajectories, the carried bear)
    is advanced. Each step holds the world lock, so other threads interleave between
    steps. In GUI mode the stepping is paced to wall-clock time so it can be watched.
    """

    def __init__(self, bullet: LockedBullet, realtime: bool = False) -> None:
        self._bullet = bullet
        self._dt_s = 1.0 / PHYSICS_RATE_HZ
        self._steps = 0
        self._processes: list[StepProcess] = []
        self._realtime = realtime
        self.timers = WorldTimers()
        bullet.setTimeStep(self._dt_s)

    def pace_to_wall_clock(self, paced: bool = True) -> None:
        """Paces ``sleep`` to wall-clock time (robot time no faster than real time), as
        in GUI mode: a reaction measured in robot time to a command from another thread
        (an emergency stop) then means what it would on the real robot."""
        self._realtime = paced

    @property
    def dt_s(self) -> float:
        """The physics step in seconds."""
        return self._dt_s

    def now(self) -> float:
        """Simulated seconds since the world started."""
        return self._steps * self._dt_s

    def add_process(self, process: StepProcess) -> None:
        """Registers ``process(now_s, dt_s)`` to run before every physics step."""
        with self._bullet.lock:
            self._processes.append(process)

    def sleep(self, seconds: float) -> None:
        """Lets ``seconds`` of simulated time pass (at least zero steps)."""
        steps = max(0, round(seconds / self._dt_s))
        wall_start = time.monotonic()
        for index in range(steps):
            self.step()
            if self._realtime:
                ahead_s = (index + 1) * self._dt_s - (time.monotonic() - wall_start)
                if ahead_s > 0.0:
                    time.sleep(ahead_s)

    def step(self) -> None:
        """Advances every process and the physics by one step."""
        with self._bullet.lock:
            started = time.perf_counter()
            now_s = self.now()
            for process in tuple(self._processes):
                process(now_s, self._dt_s)
            physics_started = time.perf_counter()
            self._bullet.stepSimulation()
            self._steps += 1
            ended = time.perf_counter()
            self.timers.stepping_s += ended - started
            self.timers.physics_s += ended - physics_started
            self.timers.steps += 1
