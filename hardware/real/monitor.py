"""The devices' health during a run: a fault stops the robots and the mission, with why.

:class:`RobotMonitor` asks each device's ``health()`` every :data:`POLL_PERIOD_S` in
its own thread (the NAO: battery, fall, leg temperature; the Panda: reflex, user stop,
errors) and keeps the first fault's reason; :meth:`RobotMonitor.check`, called by the
mission after every tick, raises it as :class:`~bearchair.hardware.real.RobotFault`,
and the runner stops every device at once and then the tree, so the run ends with that
message rather than with the first motion refused. None of these faults needs a stop
faster than a tick: the Panda's reflex has stopped it already and NAOqi's fall manager
acts on its own.
"""

from __future__ import annotations

import logging
import threading
from typing import Any

from bearchair.hardware.real import RobotFault

log = logging.getLogger(__name__)

POLL_PERIOD_S = 0.5
"""How often the devices are asked (seconds): a fall or a reflex is seen within it."""


class RobotMonitor:
    """Watches ``robot``'s devices that have ``health() -> str | None``.

    Args:
        robot: a :class:`bearchair.hardware.interfaces.Robot`.
        period_s: the polling period.
    """

    def __init__(self, robot: Any, period_s: float = POLL_PERIOD_S) -> None:
        self._robot = robot
        self._period_s = period_s
        self._devices = [d for d in (robot.arm, robot.humanoid) if hasattr(d, "health")]
        self.reason: str | None = None
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="robot-monitor", daemon=True)

    def start(self) -> RobotMonitor:
        self._thread.start()
        return self

    def close(self) -> None:
        self._closed.set()

    def check(self, *_: Any) -> None:
        """Raises RobotFault once a device has reported a fault (a post-tick hook)."""
        if self.reason is not None:
            raise RobotFault(self.reason)

    def _watch(self) -> None:
        while not self._closed.wait(self._period_s) and self.reason is None:
            for device in self._devices:
                try:
                    reason = device.health()
                except Exception as error:  # an unreachable device is a fault too
                    reason = f"{type(device).__name__} health check failed: {error}"
                if reason is not None:
                    self.reason = reason
                    log.error("stopping the run: %s", reason)
                    return
