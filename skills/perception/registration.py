"""The chair's rotation by the helper (g_rot): global yaw search, then point-to-plane ICP.

Plain ICP from the identity only converges for small rotations (about 30 degrees, see
../shared/NOTES.md), so the search starts from 12 yaw hypotheses, every 30 degrees about
the vertical axis through the centroids, each refined by a coarse point-to-plane ICP;
the best (highest fitness, then lowest RMSE) is refined at a finer scale. The chair
stands on the floor before and after, so the result is projected onto a rotation about
+z and a horizontal translation.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import open3d as o3d

from hardware.interfaces import RGBDFrame, ScanningArm
from skills.geometry import rot_z, transform_points, yaw_of
from skills.perception.determinism import one_open3d_thread
from skills.perception.errors import PerceptionError, RegistrationError
from skills.perception.reconstruction import ReconstructionConfig, reconstruct_chair
from skills.perception.views import HOME_CONFIGURATION, SCAN_CONFIGURATIONS, TRACKING_VIEWS
from skills.results import ChairRotation


@dataclass(frozen=True)
class RegistrationConfig:
    """Parameters of :func:`register_chair` (metres, degrees).

    Attributes:
        hypothesis_step_deg: spacing of the initial yaw hypotheses.
        coarse_voxel_m, fine_voxel_m: downsampling of the coarse and fine ICP stages.
        coarse_distance_m, fine_distance_m: correspondence distances of the two stages.
        inlier_distance_m: a point within this of the reference after the fit is an inlier.
        min_fitness: reject when fewer inliers than this fraction of the new points.
        max_rmse_m: reject when the inliers' RMSE is larger.
    """

    hypothesis_step_deg: float = 30.0
    coarse_voxel_m: float = 0.02
    fine_voxel_m: float = 0.008
    coarse_distance_m: float = 0.06
    fine_distance_m: float = 0.02
    inlier_distance_m: float = 0.015
    min_fitness: float = 0.6
    max_rmse_m: float = 0.01


class Registration(NamedTuple):
    """A fitted motion: T_world_new_old, fitness (0..1), inlier RMSE (metres)."""

    T_world_new_old: np.ndarray
    fitness: float
    inlier_rmse_m: float


def _cloud(points: np.ndarray, voxel_m: float) -> o3d.geometry.PointCloud:
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(points, np.float64)))
    cloud = cloud.voxel_down_sample(voxel_m)
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=3 * voxel_m, max_nn=30))
    return cloud


def _icp(source, target, init: np.ndarray, distance_m: float, iterations: int):
    return o3d.pipelines.registration.registration_icp(
        source,
        target,
        distance_m,
        init,
        o3d.pipelines.registration.TransformationEstimationPointToPlane(),
        o3d.pipelines.registration.ICPConvergenceCriteria(max_iteration=iterations),
    )


def _planar(T: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """The rotation about +z plus horizontal translation closest to T near ``pivot``."""
    yaw = yaw_of(T)
    planar = np.eye(4)
    planar[:3, :3] = rot_z(yaw)
    moved = T[:3, :3] @ pivot + T[:3, 3]
    planar[:3, 3] = moved - planar[:3, :3] @ pivot
    planar[2, 3] = 0.0
    return planar


@one_open3d_thread()
def register_chair(
    new_points: np.ndarray,
    reference_points: np.ndarray,
    config: RegistrationConfig | None = None,
) -> Registration:
    """Estimates the rigid motion that carried the chair from ``reference_points`` to
    ``new_points`` (both world frame), rotations up to ±180 degrees.

    The new (possibly partial) view is registered onto the complete reference, so the
    fitness is the fraction of the new points that the moved reference explains.

    Raises:
        RegistrationError: too few points, or the best fit's fitness or RMSE fails the
            thresholds (the message gives both).
    """
    config = config or RegistrationConfig()
    if len(new_points) < 100 or len(reference_points) < 100:
        raise RegistrationError(
            f"too few points to register ({len(new_points)} new, {len(reference_points)} reference)"
        )
    source_coarse = _cloud(new_points, config.coarse_voxel_m)
    target_coarse = _cloud(reference_points, config.coarse_voxel_m)
    centre_new = np.asarray(new_points).mean(axis=0)
    centre_old = np.asarray(reference_points).mean(axis=0)
    best = None
    steps = round(360.0 / config.hypothesis_step_deg)
    for index in range(steps):
        yaw = math.radians(index * config.hypothesis_step_deg)
        # Hypothesis for T_old_new: rotate the new view about its centroid onto the old one.
        init = np.eye(4)
        init[:3, :3] = rot_z(yaw)
        init[:3, 3] = centre_old - rot_z(yaw) @ centre_new
        fit = _icp(source_coarse, target_coarse, init, config.coarse_distance_m, 30)
        key = (round(fit.fitness, 3), -fit.inlier_rmse)
        if best is None or key > best[0]:
            best = (key, fit.transformation)
    T_old_new = _planar(np.asarray(best[1]), centre_new)
    source_fine = _cloud(new_points, config.fine_voxel_m)
    target_fine = _cloud(reference_points, config.fine_voxel_m)
    for distance in (config.fine_distance_m, 0.5 * config.fine_distance_m):
        fit = _icp(source_fine, target_fine, T_old_new, distance, 30)
        T_old_new = _planar(np.asarray(fit.transformation), centre_new)
    quality = o3d.pipelines.registration.evaluate_registration(
        source_fine, target_fine, config.inlier_distance_m, T_old_new
    )
    fitness, rmse = float(quality.fitness), float(quality.inlier_rmse)
    if fitness < config.min_fitness or rmse > config.max_rmse_m:
        raise RegistrationError(
            f"chair registration rejected: fitness {fitness:.2f} (need {config.min_fitness:.2f}), "
            f"inlier RMSE {1000 * rmse:.1f} mm (allowed {1000 * config.max_rmse_m:.1f} mm)"
        )
    return Registration(np.linalg.inv(T_old_new), fitness, rmse)


def measure_chair_rotation(
    arm: ScanningArm,
    reference_points: np.ndarray,
    *,
    views: tuple[int, ...] = TRACKING_VIEWS,
    more_views: tuple[int, ...] | None = None,
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
            reconstruct_chair(frames, config).chair_points, reference, registration
        )
    except RegistrationError as first:
        # A turn shows sides the reference never saw, which lowers the fitness of the
        # right fit too (0.63 at worst on the calibration chairs, wrong fits 0.53-0.60):
        # the other scan views add what the few tracking views miss before giving up.
        if not more_views:
            raise
        frames += _capture(arm, more_views, cancel)
        scan = reconstruct_chair(frames, config)
        try:
            fit = register_chair(scan.chair_points, reference, registration)
        except RegistrationError as error:
            raise RegistrationError(f"{error}, also from {len(frames)} views") from first
    moved = transform_points(fit.T_world_new_old, reference)
    return ChairRotation(
        fit.T_world_new_old, yaw_of(fit.T_world_new_old), fit.fitness, fit.inlier_rmse_m, moved
    )


def _capture(
    arm: ScanningArm, views: tuple[int, ...], cancel: threading.Event | None
) -> list[RGBDFrame]:
    """Frames from the scan configurations ``views``, visited from and back to HOME."""
    frames = []
    arm.move_to(HOME_CONFIGURATION)
    for index in views:
        if cancel is not None and cancel.is_set():
            raise PerceptionError("chair tracking cancelled")
        arm.move_to(SCAN_CONFIGURATIONS[index])
        frames.append(arm.capture())
    arm.move_to(HOME_CONFIGURATION)
    return frames
