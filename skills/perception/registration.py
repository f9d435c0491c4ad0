"""The chair's rotation by the helper (g_rot): global yaw search, then point-to-plane ICP.

Plain ICP from the identity only converges for small rotations (about 30 degrees, see
../shared/NOTES.md), so the search starts from 12 yaw hypotheses, every 30 degrees about
the vertical axis through the centroids, each refined by a coarse point-to-plane ICP;
the best (highest fitness, then lowest RMSE) is refined at a finer scale. The chair
stands on the floor before and after, so the result is projected onto a rotation about
+z and a horizontal translation.

Fitness (the share of the new points the reference explains) is low for a right fit
when the turned chair shows sides the reference never saw, and can be high for a wrong
one (a bench turned a quarter turn the wrong way matched 0.70 of its points). So when
the new frames are given, a fit is judged by what those views could see instead
(``visible_fitness``): the reference, carried by the fit into the new pose and
projected into each new frame, must lie on the surface each camera measured wherever
nothing nearer hides it; a wrong fit puts chair where the camera saw through to the
floor or beyond. If the best-fitting hypothesis fails that test, the best of the other
yaws and a feature-based global registration (FPFH + RANSAC, ../shared/NOTES.md) are
refined and judged too, and the most consistent fit is kept if it passes: a fixed
bound, or a lower floor where the fit is a peak of the visible overlap (every fit a few
centimetres or degrees from it scores lower; how high a right fit scores depends on the
chair, a wrong one has a better neighbour). Where neither holds, the fit is climbed to
the visible overlap's local maximum (small moves and turns while the overlap rises) and
judged by the fixed bound again, agreeing with the turn asked for as a peak must. ICP on
a turned chair is pulled a few centimetres along it by the sides the reference never
saw, and the overlap falls steeply with that error: over the 19 generated chairs of the
mission bench whose turn ICP could not measure, ICP's fits scored 0.68-0.88 (the right
ones 0.5-4 cm off); climbed, the right ones scored 0.91-0.99 within 1.8 cm and 1.4
degrees of the helper's turn, while the wrong ones (a turn 180 degrees off, a sofa slid
10 cm along itself) stayed at 0.68-0.86, below the bound. Without frames, the fitness
bound decides as before.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import open3d as o3d

from bearchair.core.geometry import rot_z, transform_points, wrap_angle, yaw_of
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.skills.perception.determinism import one_open3d_thread
from bearchair.skills.perception.errors import RegistrationError
from bearchair.skills.perception.registration_config import RegistrationConfig
from bearchair.skills.perception.visible_overlap import (
    climb_visible_overlap,
    is_visible_peak,
    visibility_masks,
    visible_fitness,
)

__all__ = [
    "Registration",
    "RegistrationConfig",
    "climb_visible_overlap",
    "is_visible_peak",
    "register_chair",
    "visible_fitness",
]


class Registration(NamedTuple):
    """A fitted motion: T_world_new_old, fitness (0..1), inlier RMSE (metres), and the
    share of the reference the new views saw where they could (NaN without frames)."""

    T_world_new_old: np.ndarray
    fitness: float
    inlier_rmse_m: float
    visible_fitness: float = math.nan


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


class _FineClouds(NamedTuple):
    """The fine stage's clouds: the new points (source) and the reference (target)."""

    source: o3d.geometry.PointCloud
    target: o3d.geometry.PointCloud
    centre_new: np.ndarray


@one_open3d_thread()
def register_chair(
    new_points: np.ndarray,
    reference_points: np.ndarray,
    config: RegistrationConfig | None = None,
    new_frames: list[RGBDFrame] | None = None,
    requested_yaw_rad: float | None = None,
) -> Registration:
    """Estimates the rigid motion that carried the chair from ``reference_points`` to
    ``new_points`` (both world frame), rotations up to ±180 degrees.

    The new (possibly partial) view is registered onto the complete reference, so the
    fitness is the fraction of the new points that the moved reference explains. With
    ``new_frames`` (the captures the new points came from), a fit whose fitness is too
    low is judged by the views' visible overlap instead (see the module doc); with
    ``requested_yaw_rad`` too (the turn the helper was asked for, counterclockwise
    positive), a fit accepted only as a peak of that overlap must agree with the request
    (``request_tolerance_deg``).

    Raises:
        RegistrationError: too few points, or the best fit's fitness (and visible
            overlap, with frames) or RMSE fails the thresholds (the message gives them).
    """
    config = config or RegistrationConfig()
    if len(new_points) < 100 or len(reference_points) < 100:
        raise RegistrationError(
            f"too few points to register ({len(new_points)} new, {len(reference_points)} reference)"
        )
    centre_new = np.asarray(new_points).mean(axis=0)
    hypotheses = _yaw_hypotheses(new_points, reference_points, centre_new, config)
    fine = _FineClouds(
        _cloud(new_points, config.fine_voxel_m),
        _cloud(reference_points, config.fine_voxel_m),
        centre_new,
    )
    T_old_new, fitness, rmse = _refine(hypotheses[0][1], fine, config)
    if not new_frames:
        if fitness >= config.min_fitness and rmse <= config.max_rmse_m:
            return Registration(np.linalg.inv(T_old_new), fitness, rmse)
        visible = math.nan
    else:
        # Judged by what the views could see; if the best-fitting hypothesis fails, the
        # best of other yaws and the global registration are judged too.
        reference = np.asarray(fine.target.points)
        visible = _seen(T_old_new, reference, new_frames, config)
        if visible < config.min_visible_fitness or rmse > config.max_rmse_m:
            T_old_new, fitness, rmse, visible = _most_visible_fit(
                (T_old_new, fitness, rmse, visible),
                hypotheses,
                new_points,
                reference_points,
                fine,
                new_frames,
                config,
            )
        against_request = not _agrees_with_request(T_old_new, requested_yaw_rad, config)
        accepted = visible >= config.min_visible_fitness or (
            visible >= config.min_peak_visible_fitness
            and not against_request
            and is_visible_peak(
                transform_points(np.linalg.inv(T_old_new), reference), new_frames, config
            )
        )
        if accepted and rmse <= config.max_rmse_m:
            return _refined_on_visible(
                T_old_new, fitness, rmse, visible, new_points, fine, new_frames, config
            )
        if not accepted:
            # The climb: not refined on the visible points after, which pull it back to
            # where ICP left it; no RMSE bound, which measures ICP's convergence: a fit
            # moved off ICP's minimum has its inliers spread over the inlier distance
            # (8.7 mm if uniform within 15 mm). A climb lifts a wrong fit too (a sofa's
            # turn read 180 deg off climbed to 0.884), so it must agree with the request
            # as a peak must.
            climbed = _climbed_on_visible(T_old_new, fine, new_frames, config)
            T_old_new = np.linalg.inv(climbed.T_world_new_old)
            against_request = not _agrees_with_request(T_old_new, requested_yaw_rad, config)
            if climbed.visible_fitness >= config.min_visible_fitness and not against_request:
                return climbed
            fitness, rmse = climbed.fitness, climbed.inlier_rmse_m
            visible = climbed.visible_fitness
        if (
            against_request
            and visible >= config.min_peak_visible_fitness
            and rmse <= config.max_rmse_m
        ):
            # The request alone rejected it: say so (else the generic rejection's reason).
            assert requested_yaw_rad is not None
            raise RegistrationError(
                f"chair registration rejected: the best fit turns the chair "
                f"{math.degrees(yaw_of(np.linalg.inv(T_old_new))):+.0f} deg, more than "
                f"{config.request_tolerance_deg:.0f} deg from the "
                f"{math.degrees(requested_yaw_rad):+.0f} deg asked for (or its reverse), on "
                + (
                    f"a visible overlap of only {visible:.2f} "
                    f"(need {config.min_visible_fitness:.2f} for that)"
                    if visible < config.min_visible_fitness
                    else f"a visible overlap of {visible:.2f} found by climbing it, which "
                    f"must agree with the turn asked for"
                )
            )
    raise _rejection(fitness, rmse, visible, config)


def _agrees_with_request(
    T_old_new: np.ndarray, requested_yaw_rad: float | None, config: RegistrationConfig
) -> bool:
    """Whether the fit's turn is within ``request_tolerance_deg`` of the requested turn
    or of its reverse (always, without a request)."""
    if requested_yaw_rad is None:
        return True
    yaw = yaw_of(np.linalg.inv(T_old_new))
    tolerance = math.radians(config.request_tolerance_deg)
    return any(abs(wrap_angle(yaw - sign * requested_yaw_rad)) <= tolerance for sign in (1.0, -1.0))


def _yaw_hypotheses(
    new_points: np.ndarray,
    reference_points: np.ndarray,
    centre_new: np.ndarray,
    config: RegistrationConfig,
) -> list[tuple[tuple[float, float], np.ndarray]]:
    """Every ``hypothesis_step_deg`` yaw refined by a coarse ICP, best first.

    Returns:
        ((fitness rounded to 0.001, -inlier RMSE), T_old_new) per yaw, sorted by the key.
    """
    source_coarse = _cloud(new_points, config.coarse_voxel_m)
    target_coarse = _cloud(reference_points, config.coarse_voxel_m)
    centre_old = np.asarray(reference_points).mean(axis=0)
    hypotheses = []
    steps = round(360.0 / config.hypothesis_step_deg)
    for index in range(steps):
        yaw = math.radians(index * config.hypothesis_step_deg)
        # Hypothesis for T_old_new: rotate the new view about its centroid onto the old one.
        init = np.eye(4)
        init[:3, :3] = rot_z(yaw)
        init[:3, 3] = centre_old - rot_z(yaw) @ centre_new
        fit = _icp(source_coarse, target_coarse, init, config.coarse_distance_m, 30)
        hypotheses.append(
            ((round(fit.fitness, 3), -fit.inlier_rmse), np.asarray(fit.transformation))
        )
    hypotheses.sort(key=lambda h: h[0], reverse=True)
    return hypotheses


def _refine(
    T_old_new: np.ndarray, fine: _FineClouds, config: RegistrationConfig
) -> tuple[np.ndarray, float, float]:
    """A fit made planar and refined by two fine ICP stages: (T_old_new, fitness, RMSE)."""
    T_old_new = _planar(T_old_new, fine.centre_new)
    for distance in (config.fine_distance_m, 0.5 * config.fine_distance_m):
        fit = _icp(fine.source, fine.target, T_old_new, distance, 30)
        T_old_new = _planar(np.asarray(fit.transformation), fine.centre_new)
    quality = o3d.pipelines.registration.evaluate_registration(
        fine.source, fine.target, config.inlier_distance_m, T_old_new
    )
    return T_old_new, float(quality.fitness), float(quality.inlier_rmse)


def _seen(
    T_old_new: np.ndarray,
    reference: np.ndarray,
    frames: list[RGBDFrame],
    config: RegistrationConfig,
) -> float:
    """The visible fitness of the reference carried by the fit into the new frames."""
    return visible_fitness(transform_points(np.linalg.inv(T_old_new), reference), frames, config)


def _most_visible_fit(
    first: tuple[np.ndarray, float, float, float],
    hypotheses: list[tuple[tuple[float, float], np.ndarray]],
    new_points: np.ndarray,
    reference_points: np.ndarray,
    fine: _FineClouds,
    frames: list[RGBDFrame],
    config: RegistrationConfig,
) -> tuple[np.ndarray, float, float, float]:
    """The fit the views see best among ``first`` (T_old_new, fitness, RMSE, visible
    fitness), the best three other yaws (15 degrees apart at least) and the global
    registration, each refined; ties go to the higher fitness.

    Returns:
        (T_old_new, fitness, RMSE, visible fitness) of the best.
    """
    T_old_new, fitness, rmse, visible = first
    reference = np.asarray(fine.target.points)
    candidates = [T_old_new]
    for _, T in hypotheses[1:]:
        if all(abs(wrap_angle(yaw_of(T) - yaw_of(c))) > math.radians(15) for c in candidates):
            candidates.append(T)
        if len(candidates) == 4:
            break
    candidates.append(_global_registration(new_points, reference_points, config))
    best = ((round(visible, 3), fitness), T_old_new, fitness, rmse, visible)
    for candidate in candidates[1:]:
        T, fit_fitness, fit_rmse = _refine(candidate, fine, config)
        score = _seen(T, reference, frames, config)
        key = (round(score, 3), fit_fitness)
        if key > best[0]:
            best = (key, T, fit_fitness, fit_rmse, score)
    _, T_old_new, fitness, rmse, visible = best
    return T_old_new, fitness, rmse, visible


def _refined_on_visible(
    T_old_new: np.ndarray,
    fitness: float,
    rmse: float,
    visible: float,
    new_points: np.ndarray,
    fine: _FineClouds,
    frames: list[RGBDFrame],
    config: RegistrationConfig,
) -> Registration:
    """An accepted fit refined on what the new views saw of the reference: every such
    point has its counterpart in the new cloud, unlike new points on sides the reference
    lacks, which pull the fit along the chair. Fewer than 100 such points: as it is."""
    reference = np.asarray(fine.target.points)
    T_new_old = np.linalg.inv(T_old_new)
    carried = transform_points(T_new_old, reference)
    mask, _ = visibility_masks(carried, frames, config.visible_tolerance_m)
    if mask.sum() >= 100:
        target = _cloud(new_points, config.fine_voxel_m)
        source = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(reference[mask]))
        centre = reference[mask].mean(axis=0)
        for distance in (config.fine_distance_m, 0.5 * config.fine_distance_m):
            fit = _icp(source, target, T_new_old, distance, 30)
            T_new_old = _planar(np.asarray(fit.transformation), centre)
        T_old_new = np.linalg.inv(T_new_old)
        quality = o3d.pipelines.registration.evaluate_registration(
            fine.source, fine.target, config.inlier_distance_m, T_old_new
        )
        fitness, rmse = float(quality.fitness), float(quality.inlier_rmse)
        visible = _seen(T_old_new, reference, frames, config)
    return Registration(np.linalg.inv(T_old_new), fitness, rmse, visible)


def _climbed_on_visible(
    T_old_new: np.ndarray, fine: _FineClouds, frames: list[RGBDFrame], config: RegistrationConfig
) -> Registration:
    """The fit climbed by :func:`climb_visible_overlap`, with its fitness, RMSE (the new
    points against the reference, as for any fit) and visible overlap."""
    reference = np.asarray(fine.target.points)
    T_new_old, visible = climb_visible_overlap(np.linalg.inv(T_old_new), reference, frames, config)
    quality = o3d.pipelines.registration.evaluate_registration(
        fine.source, fine.target, config.inlier_distance_m, np.linalg.inv(T_new_old)
    )
    return Registration(T_new_old, float(quality.fitness), float(quality.inlier_rmse), visible)


def _rejection(
    fitness: float, rmse: float, visible: float, config: RegistrationConfig
) -> RegistrationError:
    """The error of a rejected fit, with its numbers and the bounds they failed
    (``visible`` NaN: judged without frames, by the fitness)."""
    return RegistrationError(
        "chair registration rejected: "
        + (
            f"fitness {fitness:.2f} (need {config.min_fitness:.2f})"
            if math.isnan(visible)
            else f"visible overlap {visible:.2f} (need {config.min_visible_fitness:.2f}, or "
            f"{config.min_peak_visible_fitness:.2f} where no neighbouring fit scores higher), "
            f"fitness {fitness:.2f}"
        )
        + f", inlier RMSE {1000 * rmse:.1f} mm (allowed {1000 * config.max_rmse_m:.1f} mm)"
    )


def _global_registration(
    new_points: np.ndarray, reference_points: np.ndarray, config: RegistrationConfig
) -> np.ndarray:
    """T_old_new by FPFH features and RANSAC (seeded, so repeatable)."""
    registration = o3d.pipelines.registration
    voxel = config.global_voxel_m
    clouds = [_cloud(points, voxel) for points in (new_points, reference_points)]
    features = [
        registration.compute_fpfh_feature(  # pyright: ignore[reportCallIssue]  # open3d's stubs lack the default of indices (None: every point)
            cloud, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100)
        )
        for cloud in clouds
    ]
    o3d.utility.random.seed(0)
    result = registration.registration_ransac_based_on_feature_matching(
        clouds[0],
        clouds[1],
        features[0],
        features[1],
        True,
        1.5 * voxel,
        registration.TransformationEstimationPointToPoint(False),
        3,
        [
            registration.CorrespondenceCheckerBasedOnEdgeLength(0.9),
            registration.CorrespondenceCheckerBasedOnDistance(1.5 * voxel),
        ],
        registration.RANSACConvergenceCriteria(100000, 0.999),
    )
    return np.asarray(result.transformation)
