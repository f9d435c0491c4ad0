"""Pinhole camera geometry on :class:`bearchair.hardware.interfaces.RGBDFrame` and frame checks.

Camera frames follow OpenCV: x right, y down, z forward; depth is along z in metres.
"""

from __future__ import annotations

import numpy as np

from bearchair.hardware.interfaces import RGBDFrame
from bearchair.skills.perception.errors import PerceptionError

MIN_VALID_PIXELS = 500
"""A frame with fewer usable depth pixels than this is rejected as bad."""


def validate_frame(
    frame: RGBDFrame, index: int = 0, min_valid_pixels: int = MIN_VALID_PIXELS
) -> None:
    """Checks that a frame can be used at all.

    Args:
        frame: the capture.
        index: its position in a sequence, for the message.
        min_valid_pixels: how many finite, positive depth pixels are needed.

    Raises:
        PerceptionError: the depth is missing, all zero, all NaN, of the wrong shape, has
            too few valid pixels, or the camera pose is not a finite rigid transform.
    """
    depth = np.asarray(frame.depth_m)
    intr = frame.intrinsics
    if depth.ndim != 2 or depth.shape != (intr.height, intr.width):
        raise PerceptionError(
            f"frame {index}: depth shape {depth.shape} does not match the intrinsics "
            f"({intr.height}, {intr.width})"
        )
    pose = np.asarray(frame.T_world_camera, dtype=np.float64)
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise PerceptionError(f"frame {index}: T_world_camera is not a finite 4x4 transform")
    rotation = pose[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-3):
        raise PerceptionError(f"frame {index}: T_world_camera's rotation is not orthonormal")
    valid = int(np.count_nonzero(np.isfinite(depth) & (depth > 0)))
    if valid < min_valid_pixels:
        what = "all NaN" if np.all(np.isnan(depth)) else "all zero" if not np.any(depth) else ""
        detail = f" ({what})" if what else ""
        raise PerceptionError(
            f"frame {index}: only {valid} valid depth pixels{detail}, need {min_valid_pixels}"
        )


def clean_depth(frame: RGBDFrame, depth_min_m: float = 0.2, depth_max_m: float = 3.0) -> np.ndarray:
    """Depth as float32 with NaN, infinite and out-of-range pixels set to 0 (missing)."""
    depth = np.asarray(frame.depth_m, dtype=np.float32).copy()
    bad = ~np.isfinite(depth) | (depth < depth_min_m) | (depth > depth_max_m)
    depth[bad] = 0.0
    return depth


def pixel_rays(frame: RGBDFrame) -> tuple[np.ndarray, np.ndarray]:
    """Per-pixel normalised ray coordinates ((x/z), (y/z)), each (H, W)."""
    intr = frame.intrinsics
    u = (np.arange(intr.width, dtype=np.float32) - intr.cx) / intr.fx
    v = (np.arange(intr.height, dtype=np.float32) - intr.cy) / intr.fy
    return np.broadcast_to(u[None, :], (intr.height, intr.width)), np.broadcast_to(
        v[:, None], (intr.height, intr.width)
    )


def depth_to_world(frame: RGBDFrame, depth_m: np.ndarray) -> np.ndarray:
    """Back-projects every pixel to the world frame: (H, W, 3), NaN where depth is 0.

    .. math:: p_{world} = T_{world,camera} \\, [z (u - c_x)/f_x,\\; z (v - c_y)/f_y,\\; z, 1]^T
    """
    ray_x, ray_y = pixel_rays(frame)
    z = np.where(depth_m > 0, depth_m, np.nan).astype(np.float32)
    points_camera = np.stack((ray_x * z, ray_y * z, z), axis=-1)
    pose = np.asarray(frame.T_world_camera, dtype=np.float32)
    return points_camera @ pose[:3, :3].T + pose[:3, 3]
