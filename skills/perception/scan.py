"""ScanChair: move the arm through the 9 capture configurations and reconstruct the chair."""

from __future__ import annotations

import threading

import numpy as np

from bearchair.core.errors import Cancelled
from bearchair.hardware.interfaces import ScanningArm
from bearchair.skills.perception.errors import PerceptionError
from bearchair.skills.perception.reconstruction import reconstruct_chair
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.perception.scan_capture import MIN_SCAN_VIEWS, capture_scan
from bearchair.skills.perception.views import CHAIR_VOLUME, SCAN_CONFIGURATIONS
from bearchair.skills.results import ChairScan


class ScanCancelled(Cancelled, PerceptionError):
    """The scan was interrupted through its cancel event."""


def scan_chair(
    arm: ScanningArm,
    *,
    seed: int,
    cancel: threading.Event | None = None,
    config: ReconstructionConfig | None = None,
    views: tuple[int, ...] | None = None,
) -> ChairScan:
    """Captures RGB-D at each of :data:`SCAN_CONFIGURATIONS` and reconstructs the chair.

    The arm goes HOME and looks at the chair area from there; where the object runs past
    that view's side edges it turns its base to look further (side looks: the extent, and
    fused too where the object reaches beyond the chair volume); views whose motion would
    pass within 3 cm of the chair it sees are visited through HOME, replaced by a view
    higher up, or skipped (``bearchair.skills.perception.clearance``); then through the views in
    order, and back HOME.

    Args:
        arm: the scanning arm (camera poses come from its forward kinematics).
        seed: seeds the floor RANSAC.
        cancel: when set, the scan stops before the next motion.
        config: reconstruction parameters (default: :class:`ReconstructionConfig`).
        views: indices into :data:`SCAN_CONFIGURATIONS` to visit, in order (None: all).

    Returns:
        The chair scan with the frames captured; ``seconds`` has ``motion`` and
        ``capture`` besides the reconstruction's steps.

    Raises:
        ScanCancelled: ``cancel`` was set.
        PerceptionError: bad frames, no chair found, or fewer than ``MIN_SCAN_VIEWS``
            views could be captured.
    """
    config = config or ReconstructionConfig()
    config = ReconstructionConfig(**{**config.__dict__, "seed": seed})
    configurations = (
        SCAN_CONFIGURATIONS if views is None else tuple(SCAN_CONFIGURATIONS[i] for i in views)
    )
    capture = capture_scan(arm, configurations, cancel, ScanCancelled)
    frames, notes, timing = capture.frames, capture.notes, capture.seconds
    if len(frames) < MIN_SCAN_VIEWS:
        raise PerceptionError(
            f"chair scan: only {len(frames)} of {len(configurations)} views could be "
            f"captured clear of the chair (need {MIN_SCAN_VIEWS}): " + "; ".join(notes)
        )
    if cancel is not None and cancel.is_set():
        raise ScanCancelled("chair scan cancelled")
    if capture.extent.source == "seen":
        # The crop holds what the looks saw of the object, however far it reaches.
        box = (tuple(capture.extent.lower), tuple(capture.extent.upper))
        config = ReconstructionConfig(**{**config.__dict__, "object_box": box})
    # The side looks are fused only for an object larger than the chair volume the views
    # were made for: there they see its ends, which no view does. On a chair inside that
    # volume the views see it all, and an oblique look from HOME turned carves its TSDF
    # (measured: a first-source chair lost a third of its points and the seat under p).
    beyond = np.any(capture.extent.lower[:2] < CHAIR_VOLUME[0][:2]) or np.any(
        capture.extent.upper[:2] > CHAIR_VOLUME[1][:2]
    )
    fused = [*capture.looks, *frames] if beyond and capture.extent.source == "seen" else frames
    scan = reconstruct_chair(fused, config)
    seconds = {**timing, **scan.seconds}
    return scan._replace(seconds=seconds, notes=tuple(notes), frames=tuple(fused), config=config)
