"""The helper's turn of the chair, measured: the chair captured again from a few scan
views, reconstructed, and registered onto the chair as it stood
(:func:`bearchair.skills.perception.registration.register_chair`); the other scan views
are added when that fit is rejected."""

from __future__ import annotations

import threading

import numpy as np

from bearchair.core.geometry import transform_points, yaw_of
from bearchair.hardware.interfaces import RGBDFrame, ScanningArm
from bearchair.skills.perception.errors import PerceptionError, RegistrationError
from bearchair.skills.perception.reconstruction import reconstruct_chair
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.perception.registration import RegistrationConfig, register_chair
from bearchair.skills.perception.scan_capture import capture_views
from bearchair.skills.perception.views import SCAN_CONFIGURATIONS, TRACKING_VIEWS
from bearchair.skills.results import ChairRotation


def measure_chair_rotation(
    arm: ScanningArm,
    reference_points: np.ndarray,
    *,
    views: tuple[int, ...] = TRACKING_VIEWS,
    more_views: tuple[int, ...] | None = None,
    requested_yaw_rad: float | None = None,
    reconstruction: ReconstructionConfig | None = None,
    registration: RegistrationConfig | None = None,
    cancel: threading.Event | None = None,
) -> ChairRotation:
    """Captures the chair again from a few scan views and measures g_rot by registration.

    Args:
        arm: the scanning arm.
        reference_points: (N, 3) the chair before the helper turned it (world frame).
        views: indices into :data:`SCAN_CONFIGURATIONS` to capture, consecutive ones (the
            motions between them are checked), visited from and back to HOME.
        more_views: captured too when the fit from ``views`` is rejected; by default
            the scan views not in ``views`` (``()``: never).
        requested_yaw_rad: the turn the helper was asked for (radians, counterclockwise
            positive; None: unknown): a weak fit must agree with it
            (:func:`register_chair`).

    Returns:
        The motion T_world_new_old, its yaw, fitness and inlier RMSE; ``chair_points`` is
        the reference carried to the new pose (complete, unlike the few new views).

    Raises:
        PerceptionError: bad frames or no chair found.
        RegistrationError: the fit was rejected, from the extra views too.
    """
    reference = np.asarray(reference_points)
    if more_views is None:
        more_views = tuple(i for i in range(len(SCAN_CONFIGURATIONS)) if i not in views)
    config = reconstruction or ReconstructionConfig(with_mesh=False)
    frames = _capture(arm, views, cancel)
    try:
        fit = register_chair(
            reconstruct_chair(frames, config).chair_points,
            reference,
            registration,
            frames,
            requested_yaw_rad,
        )
    except RegistrationError as first:
        # A turn shows sides the reference never saw, which lowers the fitness of the
        # right fit too: the other scan views add what the few tracking views miss
        # before giving up.
        if not more_views:
            raise
        frames += _capture(arm, more_views, cancel)
        scan = reconstruct_chair(frames, config)
        try:
            fit = register_chair(
                scan.chair_points, reference, registration, frames, requested_yaw_rad
            )
        except RegistrationError as error:
            raise RegistrationError(f"{error}, also from {len(frames)} views") from first
    moved = transform_points(fit.T_world_new_old, reference)
    return ChairRotation(
        fit.T_world_new_old,
        yaw_of(fit.T_world_new_old),
        fit.fitness,
        fit.inlier_rmse_m,
        moved,
        fit.visible_fitness,
    )


def _capture(
    arm: ScanningArm, views: tuple[int, ...], cancel: threading.Event | None
) -> list[RGBDFrame]:
    """Frames from the scan configurations ``views``, visited from and back to HOME, each
    checked against the chair's extent first (``bearchair.skills.perception.clearance``)."""
    frames, _, _ = capture_views(
        arm, tuple(SCAN_CONFIGURATIONS[i] for i in views), cancel, PerceptionError
    )
    return frames
