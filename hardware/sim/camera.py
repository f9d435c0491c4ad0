"""The wrist depth camera: a PrimeSense Carmine 1.09 rendered by pybullet's TinyRenderer.

The one description of the simulated Carmine (field of view, intrinsics, range,
noise model), used by the simulated Panda (:mod:`bearchair.hardware.sim.panda`) and by the
synthetic scenes the perception tests render (:mod:`bearchair.testing.synthetic_scenes`).
Rendering works in DIRECT mode (no GUI, no OpenGL context). The OpenGL z-buffer is
turned into metric depth along the optical axis, then a Carmine-like noise model is
applied (see :class:`CarmineNoise`), or only the sensor's range limits
(:func:`carmine_images`).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from bearchair.hardware.interfaces import CameraIntrinsics
from bearchair.hardware.sim.bullet import LockedBullet

CARMINE_HFOV_DEG = 58.0
"""Horizontal field of view of the Carmine 1.09's depth camera (datasheet: 57.5 deg)."""


def carmine_intrinsics(width: int = 640, height: int = 480) -> CameraIntrinsics:
    """Pinhole intrinsics of the Carmine 1.09 at 640x480: fx = fy = 320 / tan(29 deg) ≈ 577.

    The principal point is the image centre in pixel-centre coordinates (pixel (0, 0)'s
    centre is at (0, 0)), i.e. cx = (W - 1) / 2, cy = (H - 1) / 2.
    """
    focal_px = (width / 2.0) / math.tan(math.radians(CARMINE_HFOV_DEG) / 2.0)
    return CameraIntrinsics(
        width, height, focal_px, focal_px, (width - 1) / 2.0, (height - 1) / 2.0
    )


CARMINE_INTRINSICS = carmine_intrinsics()

NEAR_M = 0.05
FAR_M = 8.0
MIN_RANGE_M = 0.35
MAX_RANGE_M = 3.5
BASELINE_M = 0.075


class RenderedView(NamedTuple):
    """A noiseless rendering: rgb (H, W, 3) uint8, depth_m (H, W) float32, segmentation."""

    rgb: np.ndarray
    depth_m: np.ndarray
    segmentation: np.ndarray


_CV_TO_GL = np.diag([1.0, -1.0, -1.0, 1.0])


def opengl_matrices(
    T_world_camera: np.ndarray, intrinsics: CameraIntrinsics
) -> tuple[list[float], list[float]]:
    """pybullet view and projection matrices (column-major) for an OpenCV camera pose.

    The projection reproduces the pinhole model exactly: a point at camera coordinates
    (X, Y, Z) lands at pixel (fx X / Z + cx, fy Y / Z + cy), with pixel centres at
    integer coordinates.
    """
    view = np.linalg.inv(T_world_camera @ _CV_TO_GL)
    width, height = intrinsics.width, intrinsics.height
    projection = np.zeros((4, 4))
    projection[0, 0] = 2.0 * intrinsics.fx / width
    projection[1, 1] = 2.0 * intrinsics.fy / height
    projection[0, 2] = 1.0 - 2.0 * (intrinsics.cx + 0.5) / width
    projection[1, 2] = 2.0 * (intrinsics.cy + 0.5) / height - 1.0
    projection[2, 2] = -(FAR_M + NEAR_M) / (FAR_M - NEAR_M)
    projection[2, 3] = -2.0 * FAR_M * NEAR_M / (FAR_M - NEAR_M)
    projection[3, 2] = -1.0
    return view.T.flatten().tolist(), projection.T.flatten().tolist()


def render_view(
    bullet: LockedBullet | BulletClient, T_world_camera: np.ndarray, intrinsics: CameraIntrinsics
) -> RenderedView:
    """Renders RGB, metric depth along the optical axis and segmentation with TinyRenderer.

    Depth: with the z-buffer value b in [0, 1], z_ndc = 2b - 1 and
    z = 2 n f / (f + n - z_ndc (f - n)), the distance along the optical axis; the far
    plane (nothing hit) gives 0.
    """
    view, projection = opengl_matrices(T_world_camera, intrinsics)
    _, _, rgba, zbuffer, segmentation = bullet.getCameraImage(
        intrinsics.width,
        intrinsics.height,
        viewMatrix=view,
        projectionMatrix=projection,
        renderer=pybullet.ER_TINY_RENDERER,
        shadow=0,
        lightDirection=[0.4, 0.3, 1.0],
    )
    rgba = np.asarray(rgba, dtype=np.uint8).reshape(intrinsics.height, intrinsics.width, 4)
    zbuffer = np.asarray(zbuffer, dtype=np.float64).reshape(intrinsics.height, intrinsics.width)
    z_ndc = 2.0 * zbuffer - 1.0
    depth = 2.0 * NEAR_M * FAR_M / (FAR_M + NEAR_M - z_ndc * (FAR_M - NEAR_M))
    depth[zbuffer >= 1.0 - 1e-7] = 0.0
    segmentation = np.asarray(segmentation, dtype=np.int64).reshape(
        intrinsics.height, intrinsics.width
    )
    return RenderedView(
        np.ascontiguousarray(rgba[:, :, :3]), depth.astype(np.float32), segmentation
    )


class SceneFrame(NamedTuple):
    """A picture of the scene for people, with the camera that took it.

    Attributes:
        rgb: (H, W, 3) uint8.
        T_world_camera: 4x4, OpenCV convention (x right, y down, z forward).
        intrinsics: the pinhole camera.
    """

    rgb: np.ndarray
    T_world_camera: np.ndarray
    intrinsics: CameraIntrinsics

    def project(self, points_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixels (N, 2) of world points (N, 3) metres, and which are in front of the camera."""
        points = np.atleast_2d(np.asarray(points_world, dtype=float))
        T_camera_world = np.linalg.inv(self.T_world_camera)
        camera = points @ T_camera_world[:3, :3].T + T_camera_world[:3, 3]
        in_front = camera[:, 2] > NEAR_M
        z = np.where(in_front, camera[:, 2], 1.0)
        k = self.intrinsics
        pixels = np.column_stack([k.fx * camera[:, 0] / z + k.cx, k.fy * camera[:, 1] / z + k.cy])
        return pixels, in_front


class CarmineNoise(NamedTuple):
    """A structured-light depth noise model after the Carmine/Kinect v1 literature.

    The sensor measures disparity d = f b / z (pixels, baseline b = 7.5 cm) and
    quantizes it to 1/8 pixel. We add Gaussian disparity noise of ``disparity_sigma_px``
    before quantizing; the resulting axial noise grows as

        σ_z ≈ z² / (f b) · sqrt(σ_d² + q² / 12) ≈ 1.5e-3 · z²  (metres, z in metres),

    i.e. about 0.4 mm at 0.5 m, 1.5 mm at 1 m and 6 mm at 2 m. Missing pixels (depth 0):
    ``dropout_fraction`` of all pixels at random, ``edge_dropout`` of the pixels next to
    a depth discontinuity larger than 3 cm + 2 % of the depth (the projector's shadow and
    mixed pixels), and everything outside [0.35, 3.5] m. RGB gets Gaussian noise of
    ``rgb_sigma`` grey levels.
    """

    disparity_sigma_px: float = 0.054
    disparity_step_px: float = 0.125
    dropout_fraction: float = 0.02
    edge_dropout: float = 0.5
    rgb_sigma: float = 2.0

    def apply(
        self,
        rgb: np.ndarray,
        depth_m: np.ndarray,
        intrinsics: CameraIntrinsics,
        rng: np.random.Generator,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Noisy copies of ``rgb`` (uint8) and ``depth_m`` (float32, 0 = missing).

        Computed in float32 (the depth's own precision; the disparity step, 1/8 px, is
        far above its resolution), with the RGB noise drawn as whole grey levels from
        the rounded Gaussian (:func:`_rounded_gaussian_table`): a full frame's noise
        costs a third of drawing it in float64.
        """
        depth = np.asarray(depth_m, dtype=np.float32)
        valid = depth > 0.0
        focal_baseline = np.float32(intrinsics.fx * BASELINE_M)
        disparity = np.zeros_like(depth)
        np.divide(focal_baseline, depth, out=disparity, where=valid)
        noise = rng.standard_normal(depth.shape, dtype=np.float32)
        disparity += noise * np.float32(self.disparity_sigma_px)
        step = np.float32(self.disparity_step_px)
        disparity = np.round(disparity / step) * step
        noisy = np.zeros_like(depth)
        measurable = valid & (disparity > 0.0)
        np.divide(focal_baseline, disparity, out=noisy, where=measurable)

        jump = np.zeros(depth.shape, dtype=bool)
        threshold = np.float32(0.03) + np.float32(0.02) * depth
        horizontal = np.abs(np.diff(depth, axis=1)) > threshold[:, 1:]
        vertical = np.abs(np.diff(depth, axis=0)) > threshold[1:, :]
        jump[:, 1:] |= horizontal
        jump[:, :-1] |= horizontal
        jump[1:, :] |= vertical
        jump[:-1, :] |= vertical
        missing = rng.random(depth.shape, dtype=np.float32) < self.dropout_fraction
        missing |= jump & (rng.random(depth.shape, dtype=np.float32) < self.edge_dropout)
        missing |= (noisy < MIN_RANGE_M) | (noisy > MAX_RANGE_M)
        noisy[missing] = 0.0

        table = _rounded_gaussian_table(self.rgb_sigma)
        offsets = table[rng.integers(0, len(table), rgb.shape, dtype=np.uint16)]
        noisy_rgb = np.clip(rgb.astype(np.int16) + offsets, 0, 255).astype(np.uint8)
        return noisy_rgb, noisy


@lru_cache(maxsize=4)
def _rounded_gaussian_table(sigma: float, size: int = 1 << 16) -> np.ndarray:
    """A table of 2^16 whole numbers k, each appearing in proportion to P(round(e) = k),
    e ~ N(0, sigma²): a uniform index into it draws the rounded Gaussian."""
    reach = math.ceil(6.0 * sigma) + 1
    levels = np.arange(-reach, reach + 1)
    edges = (levels[:, None] + np.array([-0.5, 0.5])) / (sigma * math.sqrt(2.0))
    erf = np.vectorize(math.erf)
    probabilities = 0.5 * (erf(edges[:, 1]) - erf(edges[:, 0]))
    counts = np.round(np.cumsum(probabilities) / probabilities.sum() * size).astype(int)
    return np.repeat(levels, np.diff(np.concatenate([[0], counts]))).astype(np.int16)


def clip_range(depth_m: np.ndarray) -> np.ndarray:
    """Noiseless depth with the sensor's range limits applied (0 outside [0.35, 3.5] m)."""
    depth = depth_m.copy()
    depth[(depth < MIN_RANGE_M) | (depth > MAX_RANGE_M)] = 0.0
    return depth


def carmine_images(
    view: RenderedView,
    intrinsics: CameraIntrinsics,
    noise: CarmineNoise | None,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """What the Carmine reads out of a rendering: (rgb uint8, depth_m float32, 0 = missing).

    With ``noise``, its :meth:`CarmineNoise.apply` (drawing from ``rng``); without, the
    noiseless images with only the range limits applied (:func:`clip_range`).
    """
    if noise is None:
        return view.rgb.copy(), clip_range(view.depth_m)
    return noise.apply(view.rgb, view.depth_m, intrinsics, rng)
