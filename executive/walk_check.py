"""``check-hardware --move --walk``: what NAOqi's documentation leaves open, measured.

The mission walks the NAO with ``move()`` (a latched velocity) and a client heartbeat
(:class:`bearchair.hardware.real.nao_watch.WalkWatchdog`). The documentation does not
say how far the NAO goes once told to stop, whether a new ``move`` replaces the last at
once or after what is queued, or what NAOqi does when its client disconnects. Each is
measured here on the robot, slowly and without the bear, from NAOqi's odometry:

1. **Run-out**: walk at :data:`PROBE_SPEED_MPS`, then fall silent: the heartbeat stops
   the walk. How long and how far the NAO goes after the last command must stay within
   :data:`MAX_RUNOUT_S` and :data:`MAX_RUNOUT_M`, else FAIL.
2. **Replace or queue**: walk forward, then command a turn on the spot. If the NAO still
   translates :data:`REPLACE_WAIT_S` later (more than :data:`QUEUED_M`), commands queue:
   FAIL (a stop would come after what is queued).
3. **Disconnect**: walk through a second session and close it. Still walking
   :data:`DISCONNECT_WAIT_S` later means a killed process leaves the NAO walking until
   someone stops it: warn (the heartbeat cannot cover a dead process; keep the chest
   button in reach). The walk is then stopped from the first session.

A FAIL means: do not run the mission with the bear on this robot and NAOqi version.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

PROBE_SPEED_MPS = 0.05
"""Half the NAO's walking speed: slow, and within the walking controller's range."""
WALK_S = 1.5
"""How long each probe walks before it measures (seconds): past the first step."""
MAX_RUNOUT_S = 1.5
MAX_RUNOUT_M = 0.06
"""The longest run-out accepted after the last command: two heartbeat periods (0.4 s)
plus one step of NAOqi's stop (about 0.6 s), at full speed 0.1 m/s about 6 cm; beyond
it the chair's 5 cm stop box (``skills.control.walk``) cannot hold."""
REPLACE_WAIT_S = 1.0
QUEUED_M = 0.02
"""Translation (metres) after a turn-on-the-spot command that means the old forward
command is still being walked out (the turn itself moves the torso about 1 cm)."""
DISCONNECT_WAIT_S = 1.5


def check_walk(
    session: Any, cell: Any, timeout_s: float, line: Callable[[str, str, str], None]
) -> None:
    """Activates the NAO (it stands up) and runs the three probes; one line each."""
    from bearchair.hardware.real.nao import NaoHumanoid, call, connect

    nao = NaoHumanoid(session, cell.nao_start, call_timeout_s=timeout_s)
    try:
        nao.activate()
        motion = nao._motion
        _runout(nao, motion, line)
        _replace_or_queue(nao, motion, line)
        second = connect(cell.nao_url, cell.nao_user, cell.nao_password, timeout_s=timeout_s)
        _disconnect(second, motion, line, call)
    except Exception as error:
        line("FAIL", "nao walk", f"{str(error).splitlines()[0]}")
    except BaseException:
        nao.emergency_stop()
        raise
    finally:
        nao.watchdog.close()
        nao.stop()


def _odometry(motion: Any) -> np.ndarray:
    from bearchair.hardware.real.nao import call

    return np.asarray(call(motion, "getRobotPosition", True), dtype=float)


def _still_after(motion: Any, limit_s: float) -> float:
    """Seconds until ``moveIsActive()`` reads false (inf beyond ``limit_s``)."""
    from bearchair.hardware.real.nao import call

    start = time.monotonic()
    while time.monotonic() - start < limit_s:
        if not call(motion, "moveIsActive"):
            return time.monotonic() - start
        time.sleep(0.02)
    return float("inf")


def _runout(nao: Any, motion: Any, line: Callable[[str, str, str], None]) -> None:
    deadline = time.monotonic() + WALK_S
    while True:
        nao.set_velocity(PROBE_SPEED_MPS, 0.0, 0.0)
        last = time.monotonic()
        at_last = _odometry(motion)
        if last >= deadline:
            break
        time.sleep(0.1)
    # No more commands: the heartbeat stops the walk two periods later.
    still_s = (time.monotonic() - last) + _still_after(motion, 3.0 * MAX_RUNOUT_S)
    runout_m = float(np.linalg.norm(_odometry(motion)[:2] - at_last[:2]))
    safe = still_s <= MAX_RUNOUT_S and runout_m <= MAX_RUNOUT_M
    line(
        "ok" if safe else "FAIL",
        "nao walk run-out",
        f"walked {still_s:.2f} s and {runout_m * 100:.1f} cm after the last command "
        f"(at most {MAX_RUNOUT_S} s and {MAX_RUNOUT_M * 100:.0f} cm)",
    )


def _replace_or_queue(nao: Any, motion: Any, line: Callable[[str, str, str], None]) -> None:
    deadline = time.monotonic() + WALK_S
    while time.monotonic() < deadline:
        nao.set_velocity(PROBE_SPEED_MPS, 0.0, 0.0)
        time.sleep(0.1)
    turned = time.monotonic()
    nao.set_velocity(0.0, 0.0, 0.3)
    while time.monotonic() - turned < REPLACE_WAIT_S:
        time.sleep(0.1)
        nao.set_velocity(0.0, 0.0, 0.3)
    before = _odometry(motion)
    for _ in range(5):
        time.sleep(0.1)
        nao.set_velocity(0.0, 0.0, 0.3)
    moved_m = float(np.linalg.norm(_odometry(motion)[:2] - before[:2]))
    nao.stop()
    _still_after(motion, 3.0)
    queued = moved_m > QUEUED_M
    line(
        "FAIL" if queued else "ok",
        "nao walk commands",
        ("queue: " if queued else "replace: ")
        + f"{moved_m * 100:.1f} cm translated {REPLACE_WAIT_S:g} s after a turn-on-the-spot command",
    )


def _disconnect(second: Any, motion: Any, line: Callable[[str, str, str], None], call: Any) -> None:
    from bearchair.hardware.real.nao import service

    call(service(second, "ALMotion"), "move", PROBE_SPEED_MPS, 0.0, 0.0)
    time.sleep(WALK_S)
    second.close()
    time.sleep(DISCONNECT_WAIT_S)
    walking = bool(call(motion, "moveIsActive"))
    call(motion, "stopMove")
    _still_after(motion, 3.0)
    line(
        "warn" if walking else "ok",
        "nao walk disconnect",
        "NAOqi keeps walking after its client disconnects: a killed process leaves the NAO "
        "walking (keep the chest button in reach)"
        if walking
        else f"NAOqi stopped the walk within {DISCONNECT_WAIT_S} s of its client disconnecting",
    )
