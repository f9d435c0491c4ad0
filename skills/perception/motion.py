"""Waiting for the helper to finish turning the chair, by watching depth frames."""

from __future__ import annotations

import threading

import numpy as np

from bearchair.hardware.interfaces import Clock, RGBDFrame, ScanningArm
from bearchair.skills.perception.pinhole import clean_depth, depth_to_world, validate_frame
from bearchair.skills.perception.views import CHAIR_VOLUME, STILL_CHECK_CONFIGURATION


def chair_volume_mask(frame: RGBDFrame, margin_m: float = 0.02) -> np.ndarray:
    """Pixels whose depth lands in the chair volume, above the floor by ``margin_m``."""
    points = depth_to_world(frame, clean_depth(frame))
    lower, upper = CHAIR_VOLUME
    lower = lower + np.array([0.0, 0.0, margin_m])
    return np.all((points >= lower) & (points <= upper), axis=-1)


def depth_change(previous: RGBDFrame, current: RGBDFrame, threshold_m: float = 0.03) -> float:
    """Fraction of chair-volume pixels (in either frame) whose depth changed by more than
    ``threshold_m`` (or appeared/disappeared). Both frames come from the same view."""
    region = chair_volume_mask(previous) | chair_volume_mask(current)
    if not np.any(region):
        return 0.0
    a = clean_depth(previous)[region]
    b = clean_depth(current)[region]
    both = (a > 0) & (b > 0)
    changed = np.count_nonzero(both & (np.abs(a - b) > threshold_m))
    # Sensor dropouts make single pixels come and go: only count them where both exist.
    return changed / max(1, np.count_nonzero(both))


def wait_until_chair_still(
    arm: ScanningArm,
    clock: Clock,
    *,
    cancel: threading.Event | None = None,
    period_s: float = 0.4,
    still_for_s: float = 1.2,
    start_grace_s: float = 3.0,
    timeout_s: float = 20.0,
    moving_fraction: float = 0.02,
) -> float:
    """Watches the chair area from a fixed view until the chair has stopped moving.

    Captures every ``period_s`` (``clock.sleep`` in between, so the simulator runs).
    Two consecutive frames "agree" when at most ``moving_fraction`` of the chair-volume
    pixels changed depth by more than 3 cm. The chair is still once frames have agreed
    for ``still_for_s`` after it was seen moving; if it has not moved within
    ``start_grace_s`` (the helper ignored the request) it is still too. Gives up after
    ``timeout_s``.

    Returns:
        Seconds waited on ``clock``.
    """
    started = clock.now()
    current = [float(v) for v in arm.joint_positions()]
    if np.max(np.abs(np.asarray(current) - np.asarray(STILL_CHECK_CONFIGURATION))) > 0.01:
        arm.move_to(STILL_CHECK_CONFIGURATION)
    previous = arm.capture()
    validate_frame(previous)
    seen_moving = False
    agreed_since: float | None = None
    while clock.now() - started < timeout_s:
        if cancel is not None and cancel.is_set():
            break
        clock.sleep(period_s)
        frame = arm.capture()
        moving = depth_change(previous, frame) > moving_fraction
        previous = frame
        now = clock.now()
        if moving:
            seen_moving = True
            agreed_since = None
            continue
        if agreed_since is None:
            agreed_since = now - period_s
        if seen_moving and now - agreed_since >= still_for_s:
            break
        if not seen_moving and now - started >= start_grace_s:
            break
    return clock.now() - started
