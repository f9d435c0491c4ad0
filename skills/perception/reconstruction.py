"""Chair reconstruction from posed depth frames: TSDF fusion, floor removal, clustering.

Pipeline (each step timed in ``ChairScan.seconds``):

1. ``crop``: every depth pixel is back-projected to the world; pixels outside the scan
   volume (the box any chair in the chair area lies in, widened to what the scan's looks
   saw of a larger object, floor included) are dropped, so the TSDF only allocates
   blocks where the chair can be.
2. ``tsdf``: the depths are fused in an open3d tensor ``VoxelBlockGrid``.
3. ``floor``: the lowest well-supported horizontal plane (RANSAC, several planes taken
   off in turn) is the floor, not the largest (a sofa's seat can be larger);
   everything within ``floor_band_m`` of it, or below it, is removed.
4. ``cluster``: the remaining points are voxelised and split into 26-connected
   components; the chair is the largest component whose centre lies in the chair area
   (or a larger one standing over it), with the other sizeable ones near it (its parts,
   where the scan lost a thin bar).
5. ``mesh``: marching cubes on the same grid; the faces whose vertices lie in the
   chair's voxels are kept, and the legs' cut ends are lowered onto the floor plane.
   Surfaces that at least two views saw make the mesh; where only one view saw a surface
   that faces up, flat enough to hold the bear, over the chair's footprint, it is added
   too (:data:`SUPPORT_TILT_RAD`): the floor of a dished seat or a sling's middle, which
   only the view from straight above sees past the rim or the rails.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import cast

import numpy as np
import open3d as o3d
import trimesh
from scipy import ndimage
from scipy.spatial import (
    ConvexHull,
    cKDTree,  # pyright: ignore[reportAttributeAccessIssue]  # no stub for scipy's compiled _ckdtree
)

from bearchair.core.nao_carrying import BEAR_COM_AHEAD_M, BEAR_COM_HEIGHT_M, BEAR_TORSO_DEPTH_M
from bearchair.core.seen_surface import SEEN_ATTRIBUTE, SEEN_TOLERANCE_M
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.skills.perception.determinism import one_open3d_thread
from bearchair.skills.perception.errors import PerceptionError
from bearchair.skills.perception.pinhole import clean_depth, depth_to_world, validate_frame
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.perception.views import MAX_CHAIR_REACH_M
from bearchair.skills.perception.visible_overlap import visibility_masks
from bearchair.skills.results import ChairScan


def crop_depth(frame: RGBDFrame, config: ReconstructionConfig) -> np.ndarray:
    """The frame's depth (float32 metres) with pixels outside the scan volume set to 0."""
    depth = clean_depth(frame, depth_max_m=config.depth_max_m)
    points = depth_to_world(frame, depth)
    lower, upper = config.volume()
    inside = np.all((points >= lower) & (points <= upper), axis=-1)
    return np.where(inside, depth, 0.0).astype(np.float32)


def fuse_tsdf(
    frames: Sequence[RGBDFrame], depths: Sequence[np.ndarray], config: ReconstructionConfig
) -> o3d.t.geometry.VoxelBlockGrid:
    """Integrates depth images (float32 metres, :func:`crop_depth`'s) into a tensor TSDF
    grid (open3d's VoxelBlockGrid)."""
    device = o3d.core.Device("CPU:0")
    grid = o3d.t.geometry.VoxelBlockGrid(
        attr_names=("tsdf", "weight"),
        attr_dtypes=(o3d.core.float32, o3d.core.float32),
        attr_channels=(o3d.core.SizeVector([1]), o3d.core.SizeVector([1])),
        voxel_size=config.voxel_size_m,
        block_resolution=8,
        block_count=40000,
        device=device,
    )
    for frame, depth_m in zip(frames, depths, strict=True):
        if not np.any(depth_m):
            continue
        # dtype and device as open3d would choose them (its stubs lack their defaults).
        depth = o3d.t.geometry.Image(
            o3d.core.Tensor(np.ascontiguousarray(depth_m), o3d.core.float32, device)
        )
        intrinsic = o3d.core.Tensor(frame.intrinsics.matrix(), o3d.core.float64, device)
        extrinsic = o3d.core.Tensor(np.linalg.inv(frame.T_world_camera), o3d.core.float64, device)
        blocks = grid.compute_unique_block_coordinates(
            depth,
            intrinsic,
            extrinsic,
            depth_scale=1.0,
            depth_max=config.depth_max_m,
            trunc_voxel_multiplier=config.sdf_trunc_voxels,
        )
        grid.integrate(
            blocks,
            depth,
            intrinsic,
            extrinsic,
            depth_scale=1.0,
            depth_max=config.depth_max_m,
            trunc_voxel_multiplier=config.sdf_trunc_voxels,
        )
    return grid


def open3d_seed(seed: int) -> int:
    """open3d's seed (a signed 32-bit int) from a run's seed (0..2**32 - 1): its low 31
    bits, the same for the same seed."""
    return int(seed) & 0x7FFFFFFF


FLOOR_PLANE_SEARCHES = 5
"""How many planes RANSAC takes off the fused points, largest first, looking for the floor:
a sofa's seat or a table top can be a larger horizontal plane than the floor in view, and
with its backrest, armrest tops and seat cushion that is at most four planes above it."""

FLOOR_LAYER_M = 0.03
"""Horizontal planes less than this (metres) above the lowest are layers of the floor, not a
seat: no seat a NAO can use is this low (the bear's own seat is 8.5 cm deep)."""

FLOOR_NORMAL_MIN_Z = 0.95
"""A floor candidate's normal has at least this vertical component (within 18 degrees)."""


def fit_floor(points: np.ndarray, config: ReconstructionConfig) -> np.ndarray:
    """The floor plane (a, b, c, d), c > 0, from RANSAC on the fused points.

    Planes are taken off the points, largest first, up to :data:`FLOOR_PLANE_SEARCHES`
    times; of those within about 18 degrees of horizontal and with at least
    ``3 * min_chair_points`` inliers, the floor is the **lowest** (at the middle of the
    points): everything stands on the floor, and a seat can be the largest horizontal
    plane in view (a sofa's seat, seen from above, outnumbers the floor around it).
    Planes that are not horizontal (a backrest) are removed and the search goes on.

    Raises:
        PerceptionError: no horizontal plane was found.
    """
    o3d.utility.random.seed(open3d_seed(config.seed))
    remaining = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    middle = points.mean(axis=0)
    candidates: list[tuple[float, int, np.ndarray]] = []
    for _ in range(FLOOR_PLANE_SEARCHES):
        if len(remaining.points) < 3 * config.min_chair_points:
            break
        plane, inliers = remaining.segment_plane(
            distance_threshold=max(0.006, 0.75 * config.voxel_size_m),
            ransac_n=3,
            num_iterations=config.floor_ransac_iterations,
        )
        plane = np.asarray(plane, dtype=np.float64)
        plane /= np.linalg.norm(plane[:3])
        if plane[2] < 0:
            plane = -plane
        if plane[2] > FLOOR_NORMAL_MIN_Z and len(inliers) >= 3 * config.min_chair_points:
            # The plane's height under the points' middle.
            height = -(plane[3] + plane[0] * middle[0] + plane[1] * middle[1]) / plane[2]
            candidates.append((height, len(inliers), plane))
        remaining = remaining.select_by_index(inliers, invert=True)
    if not candidates:
        raise PerceptionError("no floor plane found in the scan (is the floor in view?)")
    # The floor's own noisy layers can make a second plane a few millimetres off it: of
    # the planes as low as the lowest (within FLOOR_LAYER_M), the best supported.
    lowest = min(height for height, _, _ in candidates)
    floor_layers = [c for c in candidates if c[0] <= lowest + FLOOR_LAYER_M]
    return max(floor_layers, key=lambda candidate: candidate[1])[2]


MIN_VIEWS_WEIGHT = 1.5
"""A TSDF voxel is surface when more than this weight (one per view that saw it) fused into
it: two views agree, so one view's noise is not chair."""
ONE_VIEW_WEIGHT = 0.5
"""... and, for the support surfaces of :data:`SUPPORT_TILT_RAD`, when one view saw it."""
SUPPORT_TILT_RAD = math.atan((BEAR_TORSO_DEPTH_M / 2.0 - BEAR_COM_AHEAD_M) / BEAR_COM_HEIGHT_M)
"""A surface seen by a single view is added to the chair where it faces up within this
angle of vertical (radians): flat enough for the bear to rest on it, which tips at a lean
of atan((D/2 - c_x)/c_z) = 16 deg (D the torso's depth, c its centre of mass ahead of and
over its seat point). The floor of a dished seat inside its rim, the middle of a sling
between its rails, a seat deep inside armrests: only the view from straight above sees
them, and two views are needed for :data:`MIN_VIEWS_WEIGHT`. A single view's noise at
depth edges lies along its rays, which are steeper than this in every scan view (they
look down at the chair area at 30-70 deg, their streaks' surfaces at least 20 deg from
level), so it is not taken for a seat."""

CHAIR_PART_SHARE = 0.05
"""A component of the scan near the chair with at least this share of the chair's largest
component's cells is a part of the chair: where a bar is thinner than the TSDF's voxels
(a swivel chair's column, a backrest's stem) the scan loses it and the chair comes apart
into its seat, base and backrest. Smaller crumbs are the TSDF's noise."""


def chair_cluster(
    points: np.ndarray, config: ReconstructionConfig, cell_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Keeps the 26-connected components of occupied cells that make the chair: the
    biggest whose centre is in the chair area (grown by 5 cm), or a bigger one standing
    over that area (a sofa whose centre lies beyond it), with every other one of at least
    ``CHAIR_PART_SHARE`` of its size whose centre lies within ``MAX_CHAIR_REACH_M`` of its
    centre, or within the main component's own half diagonal when that is larger
    (horizontally: a part of the same chair).

    Returns:
        (mask over ``points``, boolean occupancy grid of the chair, grid origin).

    Raises:
        PerceptionError: no component lies in the chair area.
    """
    origin = points.min(axis=0) - 2 * cell_m
    cells = np.floor((points - origin) / cell_m).astype(np.int64)
    shape = cells.max(axis=0) + 3
    occupancy = np.zeros(shape, dtype=bool)
    occupancy[tuple(cells.T)] = True
    labels, count = cast(
        tuple[np.ndarray, int],
        ndimage.label(occupancy, structure=np.ones((3, 3, 3), dtype=bool)),
    )
    if count == 0:
        raise PerceptionError("nothing left above the floor in the scan area")
    point_labels = labels[tuple(cells.T)]
    sizes = np.bincount(point_labels, minlength=count + 1)
    sizes[0] = 0
    by_size = [int(label) for label in np.argsort(sizes)[::-1] if label and sizes[label]]
    counts = np.maximum(sizes, 1)
    centres = np.column_stack(
        [
            np.bincount(point_labels, weights=points[:, axis], minlength=count + 1) / counts
            for axis in (0, 1)
        ]
    )
    area = config.chair_area
    over_area = (
        (points[:, 0] >= area.x_min - 0.05)
        & (points[:, 0] <= area.x_max + 0.05)
        & (points[:, 1] >= area.y_min - 0.05)
        & (points[:, 1] <= area.y_max + 0.05)
    )
    centred = {
        label
        for label in by_size
        if area.x_min - 0.05 <= centres[label][0] <= area.x_max + 0.05
        and area.y_min - 0.05 <= centres[label][1] <= area.y_max + 0.05
    }
    # A chair larger than the area (a sofa) may have its centre outside it: then the
    # biggest component standing over the area.
    over = set(np.unique(point_labels[over_area]).tolist()) - {0}
    main = next((label for label in by_size if label in centred), None)
    biggest_over = next((label for label in by_size if label in over), None)
    if biggest_over is not None and (main is None or sizes[biggest_over] > sizes[main]):
        main = biggest_over
    if main is None:
        raise PerceptionError("no object found over the chair area")
    # Parts lie within a chair's reach of its centre, or of a larger chair's own extent.
    own = points[point_labels == main][:, :2]
    reach = max(MAX_CHAIR_REACH_M, float(np.hypot(*(np.ptp(own, axis=0) / 2.0))))
    parts = [
        label
        for label in by_size
        if sizes[label] >= CHAIR_PART_SHARE * sizes[main]
        and np.hypot(*(centres[label] - centres[main])) <= reach
    ]
    return np.isin(point_labels, parts), np.isin(labels, parts), origin


@one_open3d_thread()
def reconstruct_chair(frames: Sequence[RGBDFrame], config: ReconstructionConfig) -> ChairScan:
    """Reconstructs the chair from posed RGB-D frames of any camera backend.

    Args:
        frames: captures with ``T_world_camera`` from the arm's forward kinematics.
        config: voxel size, scan volume and thresholds.

    Returns:
        The chair's mesh and points in the world frame (z up, floor removed, the legs'
        lowest points on the floor plane; the vertices a frame measured marked in the
        mesh, :mod:`bearchair.core.seen_surface`), the number of views and the time per
        step.

    Raises:
        PerceptionError: a frame is bad (all zeros, NaN, too few points, bad pose), or
            no floor, or no chair-sized object in the chair area.
    """
    if not frames:
        raise PerceptionError("no frames to reconstruct from")
    seconds: dict[str, float] = {}
    started = time.perf_counter()
    depths = _cropped_depths(frames, config)
    seconds["crop"] = time.perf_counter() - started

    tick = time.perf_counter()
    grid = fuse_tsdf(frames, depths, config)
    cloud = grid.extract_point_cloud(weight_threshold=MIN_VIEWS_WEIGHT)
    points = cloud.point.positions.numpy().astype(np.float64)
    seconds["tsdf"] = time.perf_counter() - tick
    if len(points) < config.min_chair_points:
        raise PerceptionError(f"the fused scan has only {len(points)} points")

    tick = time.perf_counter()
    plane, above = _above_floor(points, config)
    seconds["floor"] = time.perf_counter() - tick

    tick = time.perf_counter()
    cell_m = 1.5 * config.voxel_size_m
    if len(above) < config.min_chair_points:
        raise PerceptionError("nothing chair-sized stands on the floor in the chair area")
    keep, chair_cells, origin = chair_cluster(above, config, cell_m)
    # open3d's hash map returns points in no fixed order: sort them so that the same
    # frames always give the same arrays.
    chair_points = _sorted_rows(above[keep])
    seconds["cluster"] = time.perf_counter() - tick
    if len(chair_points) < config.min_chair_points:
        raise PerceptionError(
            f"the chair has only {len(chair_points)} points (need {config.min_chair_points})"
        )

    chair_mesh = trimesh.Trimesh()
    if config.with_mesh:
        tick = time.perf_counter()
        chair_mesh = _chair_mesh(grid, chair_cells, origin, cell_m, plane, config)
        seen, _ = visibility_masks(chair_mesh.vertices, frames, SEEN_TOLERANCE_M)
        chair_mesh.vertex_attributes[SEEN_ATTRIBUTE] = seen.astype(np.float64)
        seconds["mesh"] = time.perf_counter() - tick
    seconds["total"] = time.perf_counter() - started
    return ChairScan(chair_mesh, chair_points, len(frames), seconds)


def _cropped_depths(frames: Sequence[RGBDFrame], config: ReconstructionConfig) -> list[np.ndarray]:
    """Every frame validated and its depth cropped to the scan volume (``crop_depth``).

    Raises:
        PerceptionError: a bad frame, or too few depth pixels inside the volume.
    """
    for index, frame in enumerate(frames):
        validate_frame(frame, index)
    depths = [crop_depth(frame, config) for frame in frames]
    if sum(int(np.count_nonzero(d)) for d in depths) < config.min_chair_points:
        raise PerceptionError("the frames show nothing inside the scan volume")
    return depths


def _above_floor(points: np.ndarray, config: ReconstructionConfig) -> tuple[np.ndarray, np.ndarray]:
    """The floor plane (``fit_floor``) and the points more than ``floor_band_m`` above it."""
    plane = fit_floor(points, config)
    height = points @ plane[:3] + plane[3]
    return plane, points[height > config.floor_band_m]


def _chair_mesh(
    grid: o3d.t.geometry.VoxelBlockGrid,
    chair_cells: np.ndarray,
    origin: np.ndarray,
    cell_m: float,
    plane: np.ndarray,
    config: ReconstructionConfig,
) -> trimesh.Trimesh:
    chair = _on_chair(
        grid.extract_triangle_mesh(weight_threshold=MIN_VIEWS_WEIGHT),
        chair_cells,
        origin,
        cell_m,
        plane,
        config,
    )
    if len(chair.faces) == 0:
        raise PerceptionError("the chair's surface could not be extracted from the TSDF")
    # Floor removal cut the legs a band above the floor: lower their ends onto it.
    vertices = np.array(chair.vertices)
    height = vertices @ plane[:3] + plane[3]
    cut = height < height.min() + config.voxel_size_m
    vertices[cut] -= np.outer(height[cut], plane[:3])
    chair.vertices = vertices
    # Small disconnected crumbs of the TSDF surface are noise, not chair.
    parts = chair.split(only_watertight=False)
    if len(parts) > 1:
        biggest = max(len(part.faces) for part in parts)
        chair = cast(
            trimesh.Trimesh,
            trimesh.util.concatenate([p for p in parts if len(p.faces) >= 0.02 * biggest]),
        )
    support = _one_view_support(grid, chair, chair_cells, origin, cell_m, plane, config)
    if len(support.faces):
        chair = cast(trimesh.Trimesh, trimesh.util.concatenate([chair, support]))
    return _canonical(chair)


def _on_chair(
    mesh: o3d.t.geometry.TriangleMesh,
    chair_cells: np.ndarray,
    origin: np.ndarray,
    cell_m: float,
    plane: np.ndarray,
    config: ReconstructionConfig,
) -> trimesh.Trimesh:
    """The faces of a TSDF mesh whose vertices lie in (or next to) the chair's cells and
    above the floor band."""
    vertices = mesh.vertex.positions.numpy().astype(np.float64)
    faces = mesh.triangle.indices.numpy().astype(np.int64)
    if len(faces) == 0:
        return trimesh.Trimesh()
    # A vertex belongs to the chair when its cell, or a neighbour, is a chair cell.
    grown = ndimage.binary_dilation(chair_cells, structure=np.ones((3, 3, 3), dtype=bool))
    cells = np.floor((vertices - origin) / cell_m).astype(np.int64)
    inside = np.all((cells >= 0) & (cells < np.array(grown.shape)), axis=1)
    on_chair = np.zeros(len(vertices), dtype=bool)
    on_chair[inside] = grown[tuple(cells[inside].T)]
    height = vertices @ plane[:3] + plane[3]
    on_chair &= height > config.floor_band_m
    faces = faces[np.all(on_chair[faces], axis=1)]
    chair = trimesh.Trimesh(vertices, faces, process=False)
    chair.remove_unreferenced_vertices()
    return chair


def _one_view_support(
    grid: o3d.t.geometry.VoxelBlockGrid,
    chair: trimesh.Trimesh,
    chair_cells: np.ndarray,
    origin: np.ndarray,
    cell_m: float,
    plane: np.ndarray,
    config: ReconstructionConfig,
) -> trimesh.Trimesh:
    """The support surfaces a single view saw (:data:`SUPPORT_TILT_RAD`) that the chair's
    mesh lacks: faces of the one-view mesh over the chair's footprint
    (:func:`_over_footprint`: a seat the two-view surfaces lost lies inside it), above the floor band, facing up
    within the tilt (their vertices' normals, averaged over the neighbouring faces, so a
    facet of marching cubes' staircase does not decide), and farther than a voxel from
    every vertex of the chair's mesh (not a second copy of a surface it has)."""
    single = grid.extract_triangle_mesh(weight_threshold=ONE_VIEW_WEIGHT)
    vertices = single.vertex.positions.numpy().astype(np.float64)
    faces = single.triangle.indices.numpy().astype(np.int64)
    if len(faces) == 0 or len(chair.vertices) == 0:
        return trimesh.Trimesh()
    keep = _over_footprint(vertices[:, :2], chair_cells, origin, cell_m)
    keep &= vertices @ plane[:3] + plane[3] > config.floor_band_m + config.voxel_size_m
    over_chair = trimesh.Trimesh(vertices, faces[np.all(keep[faces], axis=1)], process=False)
    over_chair.remove_unreferenced_vertices()
    if len(over_chair.faces) == 0:
        return over_chair
    normals = np.asarray(over_chair.vertex_normals)[over_chair.faces].mean(axis=1)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    up = np.flatnonzero(normals @ plane[:3] >= math.cos(SUPPORT_TILT_RAD))
    distance, _ = cKDTree(np.asarray(chair.vertices)).query(over_chair.triangles_center[up])
    support = trimesh.Trimesh(
        over_chair.vertices, over_chair.faces[up[distance > config.voxel_size_m]], process=False
    )
    support.remove_unreferenced_vertices()
    return support


def _over_footprint(
    xy: np.ndarray, chair_cells: np.ndarray, origin: np.ndarray, cell_m: float
) -> np.ndarray:
    """(N,) which points lie over the chair's footprint: the convex hull, seen from above,
    of the chair's cells (grown by a cell). A seat the two-view surfaces lost lies between
    the chair's legs, rails, armrests and back, so inside it."""
    columns = np.argwhere(chair_cells.any(axis=2))
    corners = np.array([(dx, dy) for dx in (-1.0, 2.0) for dy in (-1.0, 2.0)])
    cells = (columns[:, None, :] + corners[None]).reshape(-1, 2)
    hull = ConvexHull(cells)
    inside = (np.asarray(xy) - origin[:2]) / cell_m @ hull.equations[:, :2].T
    return np.all(inside + hull.equations[:, 2] <= 1e-9, axis=1)


def _sorted_rows(points: np.ndarray) -> np.ndarray:
    return points[np.lexsort(points.T[::-1])]


def _canonical(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh with its vertices and faces in a fixed (sorted) order, for determinism."""
    # Marching cubes sums in no fixed order either: round away the last bits (1 µm).
    vertices = np.round(np.asarray(mesh.vertices), 6)
    order = np.lexsort(vertices.T[::-1])
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    faces = rank[np.asarray(mesh.faces)]
    # Rotate each face so that its smallest index comes first (keeps the winding).
    faces = np.take_along_axis(
        faces, (np.argmin(faces, axis=1)[:, None] + np.arange(3)[None]) % 3, axis=1
    )
    faces = faces[np.lexsort(faces.T[::-1])]
    return trimesh.Trimesh(vertices[order], faces, process=False)
