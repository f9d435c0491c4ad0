"""The parameters of the chair's reconstruction from posed depth frames, and the scan
volume they define (:func:`bearchair.skills.perception.reconstruction.reconstruct_chair`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bearchair.core.arena import DEFAULT_ARENA, Box2D
from bearchair.skills.perception.views import MAX_CHAIR_HEIGHT_M, MAX_CHAIR_REACH_M


@dataclass(frozen=True)
class ReconstructionConfig:
    """Parameters of :func:`reconstruct_chair` (metres unless named otherwise).

    Attributes:
        voxel_size_m: TSDF voxel edge.
        sdf_trunc_voxels: TSDF truncation distance in voxels.
        depth_max_m: depth beyond this is ignored.
        chair_area: where the chair's centre may be (world xy).
        chair_margin_m: how far the chair may reach beyond ``chair_area``.
        volume_z_m: (bottom, top) of the scan volume.
        floor_band_m: points closer to the floor plane than this are floor.
        floor_ransac_iterations: RANSAC iterations for the floor plane.
        min_chair_points: fewer chair points than this is a failure.
        with_mesh: extract the triangle mesh (off when only the points are needed).
        seed: RANSAC seed.
        object_box: (min corner, max corner) of what the scan's looks saw of the object
            (``clearance.chair_extent``); the scan volume widens to hold it (a sofa
            reaching farther than ``chair_margin_m``). None: the chair area's volume.
    """

    voxel_size_m: float = 0.008
    sdf_trunc_voxels: float = 4.0
    depth_max_m: float = 2.0
    chair_area: Box2D = field(default_factory=lambda: DEFAULT_ARENA.chair_area)
    chair_margin_m: float = MAX_CHAIR_REACH_M + 0.05
    volume_z_m: tuple[float, float] = (-0.06, MAX_CHAIR_HEIGHT_M + 0.05)
    floor_band_m: float = 0.012
    floor_ransac_iterations: int = 300
    min_chair_points: int = 300
    with_mesh: bool = True
    seed: int = 0
    object_box: tuple[tuple[float, ...], tuple[float, ...]] | None = None

    def volume(self) -> tuple[np.ndarray, np.ndarray]:
        """The scan volume's (min corner, max corner) in the world frame: the chair area
        widened by ``chair_margin_m``, and ``object_box`` when given (z as configured)."""
        a, m = self.chair_area, self.chair_margin_m
        lower = np.array([a.x_min - m, a.y_min - m, self.volume_z_m[0]])
        upper = np.array([a.x_max + m, a.y_max + m, self.volume_z_m[1]])
        if self.object_box is not None:
            lower[:2] = np.minimum(lower[:2], np.asarray(self.object_box[0], float)[:2])
            upper[:2] = np.maximum(upper[:2], np.asarray(self.object_box[1], float)[:2])
        return lower, upper
