"""Chair meshes: loading, hashing, convex decomposition and a chair made of boxes.

Every mesh here is z up, in metres. Convex decomposition (V-HACD, built into pybullet)
is slow compared with everything that uses it, so its pieces are cached on disk by the
mesh's digest: a second run on the same chair skips it.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import trimesh
from scipy import ndimage

SUPPORTED_SUFFIXES = (".obj", ".ply", ".stl", ".off", ".glb", ".gltf")

_decomposition_lock = threading.Lock()


class MeshLoadError(ValueError):
    """A mesh file is missing, empty, unreadable or not a surface mesh."""


def cache_dir() -> Path:
    """The on-disk cache: ``$BEARCHAIR_CACHE`` or ``~/.cache/bearchair``."""
    root = Path(os.environ.get("BEARCHAIR_CACHE", Path.home() / ".cache" / "bearchair"))
    root.mkdir(parents=True, exist_ok=True)
    return root


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
    if not path.exists():
        raise MeshLoadError(f"{path}: no such file")
    if path.is_dir():
        raise MeshLoadError(f"{path}: is a directory, not a mesh file")
    if path.suffix.lower() not in SUPPORTED_SUFFIXES:
        raise MeshLoadError(
            f"{path}: unsupported format '{path.suffix}' (use {', '.join(SUPPORTED_SUFFIXES)})"
        )
    if path.stat().st_size == 0:
        raise MeshLoadError(f"{path}: empty file")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as error:
        raise MeshLoadError(f"{path}: not a readable mesh ({error})") from error
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MeshLoadError(f"{path}: contains no triangles")
    if not np.all(np.isfinite(loaded.vertices)):
        raise MeshLoadError(f"{path}: has non-finite vertex coordinates")
    return loaded


def mesh_digest(mesh: trimesh.Trimesh) -> str:
    """A stable hex digest of a mesh's geometry (vertices rounded to 0.1 mm, and faces)."""
    digest = hashlib.sha1()
    digest.update(np.round(np.asarray(mesh.vertices, dtype=np.float64), 4).tobytes())
    digest.update(np.asarray(mesh.faces, dtype=np.int64).tobytes())
    return digest.hexdigest()


def convex_pieces(mesh: trimesh.Trimesh, max_vertices_per_piece: int = 64) -> list[trimesh.Trimesh]:
    """Splits a (possibly open, non-manifold) mesh into convex pieces with V-HACD.

    The pieces are cached as OBJ files under ``cache_dir()/convex`` by digest.

    Args:
        mesh: the surface to decompose, in any frame; pieces come back in that frame.
        max_vertices_per_piece: V-HACD's hull vertex limit.

    Returns:
        Convex meshes whose union approximates the mesh's volume.
    """
    digest = mesh_digest(mesh)
    cached = cache_dir() / "convex" / f"{digest}-{max_vertices_per_piece}.obj"
    with _decomposition_lock:
        if not cached.exists():
            _run_vhacd(mesh, cached, max_vertices_per_piece)
    decomposed = trimesh.load(cached, force="mesh", process=False)
    pieces = [piece.convex_hull for piece in decomposed.split(only_watertight=False)]
    return [piece for piece in pieces if len(piece.vertices) >= 4 and piece.volume > 1e-9]


def _run_vhacd(mesh: trimesh.Trimesh, output: Path, max_vertices_per_piece: int) -> None:
    import pybullet

    output.parent.mkdir(parents=True, exist_ok=True)
    client = pybullet.connect(pybullet.DIRECT)
    try:
        with tempfile.TemporaryDirectory() as scratch:
            source = Path(scratch) / "in.obj"
            mesh.export(source)
            partial = Path(scratch) / "out.obj"
            # V-HACD prints its progress to stdout; send it to a log file instead.
            with _stdout_to(Path(scratch) / "stdout.txt"):
                pybullet.vhacd(
                    str(source),
                    str(partial),
                    str(Path(scratch) / "vhacd.log"),
                    resolution=100000,
                    maxNumVerticesPerCH=max_vertices_per_piece,
                    physicsClientId=client,
                )
            if not partial.exists() or partial.stat().st_size == 0:
                raise RuntimeError("V-HACD produced no convex pieces")
            os.replace(partial, output)
    finally:
        pybullet.disconnect(client)


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
    for points in _surface_sample_groups(mesh, 0.5 * pitch_m):
        cells = np.floor((points - origin) / pitch_m).astype(int)
        np.clip(cells, 0, shape - 1, out=cells)
        occupied[cells[:, 0], cells[:, 1], cells[:, 2]] = True
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


class _stdout_to:
    """Redirects the process's file descriptor 1 (C libraries write there) to a file."""

    def __init__(self, path: Path) -> None:
        self._path = path

    def __enter__(self) -> None:
        import sys

        sys.stdout.flush()
        self._saved = os.dup(1)
        self._file = open(self._path, "wb")
        os.dup2(self._file.fileno(), 1)

    def __exit__(self, *exc: object) -> None:
        os.dup2(self._saved, 1)
        os.close(self._saved)
        self._file.close()


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
    return trimesh.util.concatenate(parts)


def _box(
    extents: tuple[float, float, float], centre: tuple[float, float, float]
) -> trimesh.Trimesh:
    return trimesh.creation.box(
        extents=extents, transform=trimesh.transformations.translation_matrix(centre)
    )
