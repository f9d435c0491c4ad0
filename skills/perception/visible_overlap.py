"""The visible overlap of a chair carried by a fit into new depth frames: the share of
its points the frames saw where they could have seen them (a wrong fit puts chair where
a camera saw through to the floor or beyond), whether a fit is a peak of it, and the
climb of a fit to its local maximum. Used by
:func:`bearchair.skills.perception.registration.register_chair`."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from bearchair.core.geometry import transform_points, yaw_transform
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.skills.perception.registration_config import RegistrationConfig


def visible_fitness(
    points_world: np.ndarray, frames: list[RGBDFrame], config: RegistrationConfig | None = None
) -> float:
    """Share of ``points_world`` that the frames saw, among those they could have seen.

    Each point is projected into each frame: within ``visible_tolerance_m`` of the
    measured depth it is seen; nearer the camera by more, the camera saw through it;
    farther, something nearer hides it. A point seen in some frame counts as seen, one
    only seen through as contradicted; the rest say nothing.

    Returns:
        seen / (seen + contradicted), or 0 when no frame could see any point.
    """
    config = config or RegistrationConfig()
    seen, contradicted = visibility_masks(points_world, frames, config.visible_tolerance_m)
    judged = int(seen.sum() + contradicted.sum())
    return float(seen.sum()) / judged if judged else 0.0


def is_visible_peak(
    points_world: np.ndarray, frames: list[RGBDFrame], config: RegistrationConfig | None = None
) -> bool:
    """Whether the reference carried by a fit (``points_world``) scores a visible overlap
    at least as high as every neighbouring fit: moved by ``peak_step_m`` along ±x and ±y,
    or turned by ±``peak_step_deg`` about its centroid's vertical."""
    config = config or RegistrationConfig()
    points = np.asarray(points_world, dtype=np.float64)
    score = visible_fitness(points, frames, config)
    centre = points.mean(axis=0)
    step = config.peak_step_m
    neighbours = [
        yaw_transform(0.0, np.array([dx, dy, 0.0]))
        for dx, dy in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step))
    ]
    for sign in (1.0, -1.0):
        turn = yaw_transform(sign * math.radians(config.peak_step_deg))
        neighbours.append(yaw_transform(0.0, centre) @ turn @ yaw_transform(0.0, -centre))
    return all(
        visible_fitness(transform_points(T, points), frames, config) <= score for T in neighbours
    )


def visibility_masks(
    points_world: np.ndarray, frames: Sequence[RGBDFrame], tolerance_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """(seen, contradicted) masks of ``points_world`` (see :func:`visible_fitness`; a point
    within ``tolerance_m`` of a frame's depth is seen)."""
    points = np.asarray(points_world, dtype=np.float64)
    seen = np.zeros(len(points), bool)
    through = np.zeros(len(points), bool)
    for frame in frames:
        T_camera_world = np.linalg.inv(np.asarray(frame.T_world_camera, dtype=np.float64))
        local = transform_points(T_camera_world, points)
        intr = frame.intrinsics
        z = local[:, 2]
        front = z > 0.05
        u = np.full(len(points), -1, np.int64)
        v = np.full(len(points), -1, np.int64)
        u[front] = np.round(intr.fx * local[front, 0] / z[front] + intr.cx).astype(np.int64)
        v[front] = np.round(intr.fy * local[front, 1] / z[front] + intr.cy).astype(np.int64)
        inside = front & (u >= 0) & (u < intr.width) & (v >= 0) & (v < intr.height)
        depth = np.zeros(len(points))
        depth[inside] = np.asarray(frame.depth_m)[v[inside], u[inside]]
        valid = inside & np.isfinite(depth) & (depth > 0)
        residual = z - depth
        seen |= valid & (np.abs(residual) <= tolerance_m)
        through |= valid & (residual < -tolerance_m)
    return seen, through & ~seen


def climb_visible_overlap(
    T_world_new_old: np.ndarray,
    reference_points: np.ndarray,
    frames: list[RGBDFrame],
    config: RegistrationConfig | None = None,
) -> tuple[np.ndarray, float]:
    """A fit moved to the nearest local maximum of the visible overlap
    (:func:`visible_fitness`) of the reference it carries.

    Coordinate ascent on (dx, dy, dyaw) applied after the fit: at each scale of
    ``climb_steps_m`` / ``climb_steps_deg``, the six moves (±dx, ±dy, ±dyaw about the
    carried reference's centroid) are tried and the first that raises the overlap is
    kept, until none does; then the next, finer scale. At most
    ``climb_max_evaluations`` overlaps are computed.

    Args:
        T_world_new_old: the fit to start from (world frame motion of the chair).
        reference_points: (N, 3) the chair before the turn (world frame).
        frames: the captures of the turned chair.

    Returns:
        The climbed T_world_new_old and its visible overlap.
    """
    config = config or RegistrationConfig()
    carried = transform_points(T_world_new_old, np.asarray(reference_points, np.float64))
    centre = carried.mean(axis=0)

    def move(offset: np.ndarray) -> np.ndarray:
        """The world motion of the offset (dx m, dy m, dyaw rad), turning about ``centre``."""
        return yaw_transform(float(offset[2]), centre + np.array([offset[0], offset[1], 0.0])) @ (
            yaw_transform(0.0, -centre)
        )

    offset = np.zeros(3)
    best = visible_fitness(carried, frames, config)
    evaluations = 1
    for step_m, step_deg in zip(config.climb_steps_m, config.climb_steps_deg, strict=True):
        unit_steps = np.diag([step_m, step_m, math.radians(step_deg)])
        steps = [sign * step for step in unit_steps for sign in (1.0, -1.0)]
        rising = True
        while rising and evaluations < config.climb_max_evaluations:
            rising = False
            for step in steps:
                score = visible_fitness(
                    transform_points(move(offset + step), carried), frames, config
                )
                evaluations += 1
                if score > best:
                    best, offset, rising = score, offset + step, True
                    break
    return move(offset) @ T_world_new_old, best
