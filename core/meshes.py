"""Chair meshes: loading, checking, hashing, the solid under a surface, and a box chair.

Every mesh here is z up, in metres. Caches of what is derived from a mesh are ``.npz``
files under :func:`cache_dir` (``bearchair.core.cache``), named by the mesh's digest.
"""

from __future__ import annotations

import hashlib
import logging
import math
import os
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import cast

import numpy as np
import trimesh
from scipy import ndimage
from scipy.spatial import QhullError

from bearchair.core.cache import (  # noqa: F401 - their home before bearchair.core.cache
    cache_dir,
    read_cached_arrays,
    write_cached_arrays,
)
from bearchair.core.errors import MeshError, one_line
from bearchair.core.posture import posture_warning
from bearchair.core.userfiles import open_regular_file, printable

logger = logging.getLogger(__name__)

SUPPORTED_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")


class MeshLoadError(MeshError, ValueError):
    """A mesh file is missing, empty, unreadable or not a surface mesh."""


MAX_MESH_BYTES = 512 * 1024 * 1024
"""Largest mesh file read (bytes): the largest calibration mesh is a few MB; a scan of a
chair at 2 mm is about 50 MB as OBJ."""


def load_mesh(path: str | os.PathLike) -> trimesh.Trimesh:
    """Loads a triangle mesh, merging every part of a scene into one mesh.

    Args:
        path: an OBJ, PLY, STL, OFF or GLB/glTF file.

    Returns:
        The mesh as stored (no re-centring, no unit change).

    Raises:
        MeshLoadError: with one line saying what is wrong with the file.
    """
    path = Path(path)
    shown = printable(path)
    if path.suffix.lower() not in SUPPORTED_SUFFIXES and not path.is_dir():
        raise MeshLoadError(
            f"{shown}: unsupported format '{printable(path.suffix)}' "
            f"(use {', '.join(SUPPORTED_SUFFIXES)})"
        )
    os.close(open_regular_file(path, "mesh file", MeshLoadError))  # a FIFO would block
    size = path.stat().st_size
    if size == 0:
        raise MeshLoadError(f"{shown}: empty file")
    if size > MAX_MESH_BYTES:
        raise MeshLoadError(
            f"{shown}: {size / 1e6:.0f} MB, larger than any chair mesh bearchair reads "
            f"({MAX_MESH_BYTES / 1e6:.0f} MB); simplify it"
        )
    kind = path.suffix.lower().lstrip(".").upper()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # trimesh warns on every odd line of a bad file
            loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as error:
        raise MeshLoadError(
            f"{shown}: not a readable {kind} file ({one_line(error, 160)}); "
            "check that it is a mesh and re-export it"
        ) from error
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshLoadError(
            f"{shown}: contains no triangles (a point cloud or an empty scene?); give a surface mesh"
        )
    faces = np.asarray(loaded.faces)
    if faces.min() < 0 or faces.max() >= len(loaded.vertices):
        raise MeshLoadError(f"{shown}: faces refer to vertices that do not exist; re-export it")
    bad = int(np.count_nonzero(~np.all(np.isfinite(loaded.vertices), axis=1)))
    if bad:
        raise MeshLoadError(
            f"{shown}: has non-finite vertex coordinates ({bad} of {len(loaded.vertices)} "
            "vertices are NaN or infinite); repair or re-export the mesh"
        )
    return loaded


MIN_CHAIR_SIZE_M = 0.05
"""Below this in every direction a mesh cannot be a chair at any plausible unit (a
metre-sized chair written in kilometres, say); refused."""
MAX_CHAIR_SIZE_M = 20.0
"""Above this in any direction the mesh is in millimetres or centimetres (a 0.8 m chair
is 800 or 80 units): refused, the simulated arena is a few metres wide."""
TALL_CHAIR_M = 2.0
"""Taller than this: warned (the paper's chairs are for children, 0.45-0.62 m)."""


def check_chair_mesh(mesh: trimesh.Trimesh, path: str | os.PathLike = "mesh") -> list[str]:
    """Sanity of a chair mesh's units, size and up axis (z up, metres expected).

    Returns:
        Warnings, one line each, saying what looks wrong and what to do.

    Raises:
        MeshLoadError: when nothing sensible can be done with it (far too small or too
            large for any chair in metres, or flat in every direction).
    """
    path = printable(path)  # a name as the terminal may show it
    extents = np.asarray(mesh.extents, dtype=float)
    size = " x ".join(f"{value:.3g}" for value in extents)
    if float(extents.max()) < MIN_CHAIR_SIZE_M:
        raise MeshLoadError(
            f"{path}: {size} (x, y, z) is too small for a chair in metres; "
            "scale it to metres (z up)"
        )
    if float(extents.max()) > MAX_CHAIR_SIZE_M:
        raise MeshLoadError(
            f"{path}: {size} (x, y, z) is not a chair in metres; {_unit_hint(extents)}"
        )
    if float(np.sort(extents)[1]) < 1e-3:
        raise MeshLoadError(f"{path}: {size} (x, y, z) is a line or a point, not a chair")
    if float(extents.min()) < 1e-3:
        raise MeshLoadError(f"{path}: {size} (x, y, z) is flat (a sheet), not a chair")
    found: list[str] = []
    if extents[2] > TALL_CHAIR_M:
        found.append(
            f"{path}: {extents[2]:.2f} m tall, taller than any chair ({TALL_CHAIR_M:.0f} m); "
            "check its units (metres) and up axis (z)"
        )
    try:
        posture = posture_warning(mesh, path)
    except QhullError as error:  # coplanar or degenerate beyond the checks above
        raise MeshLoadError(f"{path}: {size} (x, y, z) has no volume, not a chair") from error
    return [*found, posture] if posture else found


def _unit_hint(extents: np.ndarray) -> str:
    """What unit a mesh far too large for metres seems to be in, from its largest extent.

    A chair is 0.2-2 m in its largest direction (the paper's are 0.45-0.62 m): in
    centimetres that is 20-200 units, in millimetres 200-2000 (and up to 20000 for any
    furniture). Beyond, no length unit makes it a chair.
    """
    largest = float(extents.max())
    if largest <= 200.0:
        return "it looks like centimetres: scale it by 0.01"
    if largest <= 20000.0:
        return "it looks like millimetres: scale it by 0.001"
    return (
        f"its largest extent, {largest:.3g} units, is no chair in any length unit "
        "(a broken export?); check the file"
    )


def load_chair_mesh(path: str | os.PathLike) -> trimesh.Trimesh:
    """:func:`load_mesh` and :func:`check_chair_mesh`; warnings are logged (one line each).

    Raises:
        MeshLoadError: the file is unusable, or no sensible chair in metres.
    """
    mesh = load_mesh(path)
    for warning in check_chair_mesh(mesh, path):
        logger.warning(warning)
    return mesh


def mesh_digest(mesh: trimesh.Trimesh) -> str:
    """A stable hex digest of a mesh's geometry (vertices rounded to 0.1 mm, and faces)."""
    digest = hashlib.sha1()
    digest.update(np.round(np.asarray(mesh.vertices, dtype=np.float64), 4).tobytes())
    digest.update(np.asarray(mesh.faces, dtype=np.int64).tobytes())
    return digest.hexdigest()


def solid_below_surface_boxes(
    mesh: trimesh.Trimesh,
    pitch_m: float = 0.01,
    max_cells_per_axis: int = 256,
    tolerance_cells: int = 1,
) -> list[np.ndarray]:
    """A blocky solid, as floor-standing boxes: every grid cell under the mesh's surface.

    A scanned chair is an open surface (the camera never sees under the seat) and a
    thin one: its convex pieces are shells a voxel thick, which a falling sitter
    tunnels through and which weigh almost nothing. Filling each vertical column of a
    grid from its highest surface cell down to the floor gives scans and modelled
    meshes the same kind of solid: the top surfaces (seat, backrest front, armrests),
    which are all a sitter touches, stay where they were (to within a cell), and the
    space under the seat, which a sitter never uses, becomes solid.

    That solid is a height field, so it splits exactly into boxes: neighbouring columns
    whose tops differ by at most ``tolerance_cells`` merge greedily into rectangles,
    each box as high as its highest column (at most ``tolerance_cells * pitch`` above
    any of them). V-HACD's few convex pieces of it bridged gaps a sitter needs: the hull
    of an armrest, the seat and the legs under them filled the space between the
    armrests up to their tops.

    Args:
        mesh: any surface, z up, metres.
        pitch_m: the column size; coarsened so that no axis has more than
            ``max_cells_per_axis`` cells (a sofa, or a mesh in millimetres).
        max_cells_per_axis: bounds the grid's memory.
        tolerance_cells: how unequal the tops of merged columns may be.

    Returns:
        One (2, 3) array of (lower, upper) corners per box, in the mesh's frame (metres).
    """
    top, pitch_m, origin = _column_tops(mesh, pitch_m, max_cells_per_axis)
    boxes: list[np.ndarray] = []
    # Plain lists: the greedy scan reads single cells, where numpy indexing is slow.
    tops = top.tolist()
    covered = (top < 0).tolist()
    nx, ny = top.shape
    for i in range(nx):
        for j in range(ny):
            if covered[i][j]:
                continue
            low, high = tops[i][j] - tolerance_cells, tops[i][j] + tolerance_cells

            def mergeable(row: int, start: int, end: int, low: int = low, high: int = high) -> bool:
                return all(
                    not covered[row][k] and low <= tops[row][k] <= high for k in range(start, end)
                )

            j_end = j + 1
            while j_end < ny and mergeable(i, j_end, j_end + 1):
                j_end += 1
            i_end = i + 1
            while i_end < nx and mergeable(i_end, j, j_end):
                i_end += 1
            height = 0
            for row in range(i, i_end):
                covered[row][j:j_end] = [True] * (j_end - j)
                height = max(height, max(tops[row][j:j_end]) + 1)
            lower = origin + pitch_m * np.array([i, j, 0.0])
            upper = origin + pitch_m * np.array([i_end, j_end, height])
            boxes.append(np.array([lower, upper]))
    return boxes


def _column_tops(
    mesh: trimesh.Trimesh, pitch_m: float, max_cells_per_axis: int
) -> tuple[np.ndarray, float, np.ndarray]:
    """The solid of :func:`solid_below_surface_boxes` as a height field, its pitch and origin.

    Returns:
        (nx, ny) int array: the highest filled cell of each column counted from the
        floor (-1: empty), after the closing below; the pitch (metres); the grid's origin.

    The surface cells are those of :func:`surface_samples` at half the pitch. The solid is
    every cell from the floor up to its column's highest surface cell, closed by one cell
    (a 3x3x3 dilation, then erosion, with nothing outside the grid) to mend one-cell
    cracks in a scan without growing the outline. On a height field both reduce to
    3x3 filters of the column tops t: the dilation's tops are d = min(max t + 1, nz - 1)
    (-1 where every neighbour is empty); the erosion keeps the cells 1..e with
    e = min(min d, nz - 1) - 1, since a cell survives only if the cells above and below
    it (inside the grid) and its 8 neighbours' are all in the dilation.
    """
    pitch_m = max(pitch_m, float(np.max(mesh.extents)) / max_cells_per_axis)
    origin = np.asarray(mesh.bounds[0], dtype=float)
    shape = np.floor(np.asarray(mesh.extents) / pitch_m).astype(int) + 1
    occupied = np.zeros(shape, dtype=bool)
    # In place and through flat indices (the same cells, a third faster than fancy
    # indexing of three index arrays): millions of samples on a large table.
    flat = occupied.reshape(-1)
    upper = shape - 1
    stride_x, stride_y = int(shape[1] * shape[2]), int(shape[2])
    for points in _surface_sample_groups(mesh, 0.5 * pitch_m):
        scaled = points - origin
        scaled /= pitch_m
        np.floor(scaled, out=scaled)
        cells = scaled.astype(np.intp)
        np.maximum(cells, 0, out=cells)
        np.minimum(cells, upper, out=cells)
        index = cells[:, 0] * stride_x
        index += cells[:, 1] * stride_y
        index += cells[:, 2]
        flat[index] = True
    levels = int(shape[2])
    top = np.where(occupied.any(axis=2), levels - 1 - np.argmax(occupied[:, :, ::-1], axis=2), -1)
    highest_near = ndimage.maximum_filter(top, size=3, mode="constant", cval=-1)
    dilated = np.where(highest_near >= 0, np.minimum(highest_near + 1, levels - 1), -1)
    eroded = (
        np.minimum(ndimage.minimum_filter(dilated, size=3, mode="constant", cval=-1), levels - 1)
        - 1
    )
    return np.where(eroded >= 1, np.maximum(top, eroded), top), pitch_m, origin


def surface_samples(mesh: trimesh.Trimesh, spacing_m: float) -> np.ndarray:
    """Points on every triangle, no farther than ``spacing_m`` apart along its edges.

    Deterministic (a barycentric lattice per triangle, finer for larger triangles), so
    the same mesh always gives the same solid; the vertices are included.
    """
    return np.concatenate(list(_surface_sample_groups(mesh, spacing_m)))


def _surface_sample_groups(mesh: trimesh.Trimesh, spacing_m: float) -> Iterator[np.ndarray]:
    """:func:`surface_samples` in parts: the vertices, then each lattice size's points.

    Parts keep the memory of a large mesh's samples (millions of points) bounded by the
    largest part; the weighted corners are summed term by term (faster than einsum).
    A sliver (a long, thin triangle, as in tessellated tables) would get a lattice of
    (n+1)(n+2)/2 points for a few cells of area: it is sampled in rows parallel to its
    longest edge instead (:func:`_sliver_samples`).
    """
    triangles = np.asarray(mesh.triangles, dtype=float)
    sides = np.linalg.norm(triangles - np.roll(triangles, 1, axis=1), axis=2)
    edges = sides.max(axis=1)
    divisions = np.maximum(np.ceil(edges / spacing_m).astype(int), 1)
    # Rows across a sliver: its height over the longest edge, in spacings.
    areas = 0.5 * np.linalg.norm(
        np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1
    )
    rows = np.ceil(2.0 * areas / np.maximum(edges, 1e-12) / spacing_m).astype(int) + 1
    # Only where the lattice is 32 times the rows' points: of the calibration meshes, 8
    # tables, a sofa and 6 chairs have such triangles (2-636), and the chairs' solids
    # came out the same box for box (the sofa's differs by one box).
    sliver = (divisions + 1) * (divisions + 2) // 2 > 32 * rows * (divisions + 1)
    yield np.asarray(mesh.vertices, dtype=float)
    if np.any(sliver):
        yield _sliver_samples(triangles[sliver], sides[sliver], spacing_m)
    for n in np.unique(divisions[~sliver]):
        i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
        keep = i + j <= n
        weights = np.stack([i[keep], j[keep], n - i[keep] - j[keep]], axis=1) / n
        group = triangles[(divisions == n) & ~sliver]
        # Chunks of about 2^15 points stay in the processor's cache for the passes below.
        step = max(1, _CHUNK_POINTS // len(weights))
        for start in range(0, len(group), step):
            part = group[start : start + step]
            points = weights[None, :, 0, None] * part[:, None, 0, :]
            points += weights[None, :, 1, None] * part[:, None, 1, :]
            points += weights[None, :, 2, None] * part[:, None, 2, :]
            yield points.reshape(-1, 3)


def _sliver_samples(triangles: np.ndarray, sides: np.ndarray, spacing_m: float) -> np.ndarray:
    """Points on thin triangles: rows parallel to the longest edge, at most
    ``spacing_m / sqrt(2)`` apart across it, each row divided as finely (ends included).

    Every point of the triangle is then within a spacing of a sample, as on the lattice,
    with points in proportion to the length times the rows rather than to the length
    squared.
    """
    parts = []
    step_m = spacing_m / math.sqrt(2.0)  # a square of this side has a diagonal of spacing_m
    for corners, lengths in zip(triangles, sides, strict=True):
        # sides[k] is the edge from corner k-1 to corner k: the base runs from there.
        k = int(np.argmax(lengths))
        start, end, apex = corners[k - 1], corners[k], corners[k - 2]
        base = float(lengths[k])
        height = float(np.linalg.norm(np.cross(end - start, apex - start))) / base
        for t in np.linspace(0.0, 1.0, int(np.ceil(height / step_m)) + 1):
            left, right = start + t * (apex - start), end + t * (apex - end)
            count = max(int(np.ceil((1.0 - t) * base / step_m)), 1)
            u = np.linspace(0.0, 1.0, count + 1)[:, None]
            parts.append(left + u * (right - left))
    return np.concatenate(parts)


_CHUNK_POINTS = 1 << 15


def box_chair_mesh(
    seat_height_m: float = 0.24,
    seat_width_m: float = 0.32,
    seat_depth_m: float = 0.28,
    seat_thickness_m: float = 0.03,
    overall_height_m: float = 0.535,
    backrest_thickness_m: float = 0.03,
    leg_side_m: float = 0.03,
    armrest_height_m: float | None = None,
) -> trimesh.Trimesh:
    """A child-sized chair made of boxes: four legs, a seat and a backrest.

    With ``armrest_height_m`` (above the floor), two solid side panels from the seat up
    to that height close the seat at +-y, like an armchair's armrests.

    The sitting direction is +x (the backrest stands at -x); the chair is centred in
    x and y with its lowest point at z = 0, like the calibration meshes.

    Returns:
        One mesh (the boxes' union as separate shells, not boolean-merged).
    """
    half_depth, half_width = seat_depth_m / 2.0, seat_width_m / 2.0
    seat_top = seat_height_m
    parts = [
        _box(
            (seat_depth_m, seat_width_m, seat_thickness_m),
            (0.0, 0.0, seat_top - seat_thickness_m / 2.0),
        ),
        _box(
            (backrest_thickness_m, seat_width_m, overall_height_m - seat_top),
            (
                -half_depth + backrest_thickness_m / 2.0,
                0.0,
                seat_top + (overall_height_m - seat_top) / 2.0,
            ),
        ),
    ]
    leg_height = seat_top - seat_thickness_m
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            parts.append(
                _box(
                    (leg_side_m, leg_side_m, leg_height),
                    (
                        sx * (half_depth - leg_side_m / 2.0),
                        sy * (half_width - leg_side_m / 2.0),
                        leg_height / 2.0,
                    ),
                )
            )
    if armrest_height_m is not None:
        panel_height = armrest_height_m - seat_top
        for sy in (-1.0, 1.0):
            parts.append(
                _box(
                    (seat_depth_m, leg_side_m, panel_height),
                    (
                        0.0,
                        sy * (half_width - leg_side_m / 2.0),
                        seat_top + panel_height / 2.0,
                    ),
                )
            )
    return cast(trimesh.Trimesh, trimesh.util.concatenate(parts))  # of Trimeshes: a Trimesh


def _box(
    extents: tuple[float, float, float], centre: tuple[float, float, float]
) -> trimesh.Trimesh:
    return trimesh.creation.box(
        extents=extents, transform=trimesh.transformations.translation_matrix(centre)
    )
