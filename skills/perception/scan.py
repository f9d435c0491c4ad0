"""ScanChair: move the arm through the 9 capture configurations and reconstruct the chair."""

from __future__ import annotations

import threading
import time

from hardware.interfaces import ScanningArm
from skills.perception.errors import PerceptionError
from skills.perception.reconstruction import ReconstructionConfig, reconstruct_chair
from skills.perception.views import HOME_CONFIGURATION, SCAN_CONFIGURATIONS
from skills.results import ChairScan


class ScanCancelled(PerceptionError):
    """The scan was interrupted through its cancel event."""


def scan_chair(
    arm: ScanningArm,
    *,
    seed: int,
    cancel: threading.Event | None = None,
    config: ReconstructionConfig | None = None,
) -> ChairScan:
    """Captures RGB-D at each of :data:`SCAN_CONFIGURATIONS` and reconstructs the chair.

    The arm goes HOME, through the 9 configurations in order, and back HOME.

    Args:
        arm: the scanning arm (camera poses come from its forward kinematics).
        seed: seeds the floor RANSAC.
        cancel: when set, the scan stops before the next motion.
        config: reconstruction parameters (default: :class:`ReconstructionConfig`).

    Returns:
        The chair scan with the frames captured; ``seconds`` has ``motion`` and
        ``capture`` besides the reconstruction's steps.

    Raises:
        ScanCancelled: ``cancel`` was set.
        PerceptionError: bad frames or no chair found.
    """
    config = config or ReconstructionConfig()
    config = ReconstructionConfig(**{**config.__dict__, "seed": seed})
    frames = []
    motion_s = capture_s = 0.0
    # HOME first: every checked motion into the scan sequence starts there.
    tick = time.perf_counter()
    arm.move_to(HOME_CONFIGURATION)
    motion_s += time.perf_counter() - tick
    for joints in SCAN_CONFIGURATIONS:
        if cancel is not None and cancel.is_set():
            raise ScanCancelled("chair scan cancelled")
        tick = time.perf_counter()
        arm.move_to(joints)
        motion_s += time.perf_counter() - tick
        tick = time.perf_counter()
        frames.append(arm.capture())
        capture_s += time.perf_counter() - tick
    tick = time.perf_counter()
    arm.move_to(HOME_CONFIGURATION)
    motion_s += time.perf_counter() - tick
    if cancel is not None and cancel.is_set():
        raise ScanCancelled("chair scan cancelled")
    scan = reconstruct_chair(frames, config)
    seconds = {"motion": motion_s, "capture": capture_s, **scan.seconds}
    return scan._replace(seconds=seconds, frames=tuple(frames))
