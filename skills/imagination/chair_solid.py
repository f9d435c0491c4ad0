"""Chair preparation for the imagination: g_obb, the solid as boxes, mass properties.

The paper computes the chair's minimum-volume oriented bounding box (OBB) and applies
g_obb = (R_z(γ_obb), p_obb): a yaw-only rotation aligning the OBB with the axes and a
horizontal translation centring it. Because the chair is upright, the minimum-volume
box among the yaw-only boxes is the minimum-area rectangle of the footprint (the
vertices projected on the floor) times the full height, found exactly by rotating
calipers (``trimesh.bounds.oriented_bounds_2D``).

Everything is cached by the mesh's digest: in memory for this process (the last
``MEMORY_MAX_CHAIRS`` chairs) and on disk (``cache_dir()/imagination``), so a second
call on the same chair skips it.
"""

from __future__ import annotations

import math
import threading
from pathlib import Path
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.errors import SkillError
from bearchair.core.geometry import make_transform, rot_z, yaw_of
from bearchair.core.memo import BoundedMemo
from bearchair.core.meshes import (
    cache_dir,
    mesh_digest,
    read_cached_arrays,
    solid_below_surface_boxes,
    write_cached_arrays,
)

PREPARATION_VERSION = "v9"
CHAIR_DENSITY_KG_M3 = 500.0
"""Wood-like; the mass is clamped to CHAIR_MASS_RANGE_KG since the solid under the
surface overestimates the volume."""
CHAIR_MASS_RANGE_KG = (1.5, 12.0)
SOLID_PITCH_M = 0.006
"""Voxel edge of the solid the box pieces are taken from (metres). Every surface
grows by half a cell on average, so a gap between armrests narrows by about one cell:
the agent's hips (about 0.2 m wide) must still fit between a child's armchair's
armrests on a scan."""
SOLID_TOP_TOLERANCE_CELLS = 2
"""Columns whose tops differ by up to this many cells (1.2 cm) merge into one box: fewer
pieces simulate faster, and 1.2 cm is below the agent's contact resolution."""


class PreparedChair(NamedTuple):
    """A chair ready to be simulated, in its OBB frame (after g_obb).

    Attributes:
        digest: ``mesh_digest`` of the input mesh.
        T_obb_mesh: 4x4 g_obb, maps mesh-frame points into the OBB frame.
        gamma_obb_rad: the yaw of R_obb (T_obb_mesh's rotation is R_z(gamma_obb)).
        extents_m: (3,) OBB size along the OBB frame's x, y, z.
        z_min_m: lowest point of the chair (OBB frame, equal to the mesh frame's).
        z_top_m: highest point of the chair.
        pieces: the boxes' corners in the chair body frame (centred on the
            centre of mass), each an (N, 3) float array.
        collision_obj: an OBJ file of the pieces (one object each, body frame), which
            pybullet loads as a compound of convex hulls: what the agent touches.
        support_obj: an OBJ file of the pieces' convex hull (one object, body frame):
            what the floor touches (see ``simulation``: on a flat floor a rigid body
            rests on, tips about and falls onto points of its convex hull only).
        com_obb_m: (3,) centre of mass in the OBB frame (the body frame's origin).
        mass_kg: chair mass.
        inertia_diag: (3,) moments of inertia about the body axes (kg m^2); the
            products of inertia are dropped (chairs are near-symmetric in the OBB frame).
    """

    digest: str
    T_obb_mesh: np.ndarray
    gamma_obb_rad: float
    extents_m: np.ndarray
    z_min_m: float
    z_top_m: float
    pieces: tuple[np.ndarray, ...]
    collision_obj: str
    support_obj: str
    com_obb_m: np.ndarray
    mass_kg: float
    inertia_diag: np.ndarray


MEMORY_MAX_CHAIRS = 4
"""Prepared chairs kept in memory, least recently used dropped first. A mission imagines
at most two chairs (the one scanned and, once the helper has turned it, its new scan),
so four keep both chairs of the mission before too; an older one is read back from the
disk cache, which holds every chair prepared."""
_memory: BoundedMemo[str, PreparedChair] = BoundedMemo(MEMORY_MAX_CHAIRS, "prepared-chair memory")
"""This process's prepared chairs by mesh digest."""


class ChairPreparationError(SkillError, ValueError):
    """The mesh cannot be simulated (degenerate, no volume)."""


def yaw_obb(mesh: trimesh.Trimesh) -> tuple[float, np.ndarray, np.ndarray]:
    """The yaw-only minimum-volume OBB of an upright mesh.

    Returns:
        (gamma_obb, centre_xy, extents_xy): the yaw that aligns the box with the axes
        (R_z(gamma_obb) applied to the mesh makes it axis aligned), the box centre in
        the mesh frame's xy-plane and the box's sides along the new x and y (metres).
    """
    footprint = np.asarray(mesh.convex_hull.vertices if len(mesh.vertices) > 3 else mesh.vertices)
    footprint_xy = np.unique(np.round(footprint[:, :2], 6), axis=0)
    if len(footprint_xy) < 3:
        raise ChairPreparationError("the mesh has no footprint (fewer than 3 distinct points)")
    T_box_xy, extents_xy = trimesh.bounds.oriented_bounds_2D(footprint_xy)
    # T_box_xy (3x3) maps footprint points into the box frame: a rotation by its angle.
    gamma = yaw_of(T_box_xy)
    # Fold into [-π/4, π/4): the 8 drop rotations cover the rest, and a small yaw keeps
    # the OBB frame close to the mesh frame.
    quarter = math.pi / 2.0
    folded = (gamma + math.pi / 4.0) % quarter - math.pi / 4.0
    turns = round((folded - gamma) / quarter)
    extents_xy = np.asarray(extents_xy, dtype=float)
    if turns % 2:
        extents_xy = extents_xy[::-1]
    rotated = footprint_xy @ rot_z(folded)[:2, :2].T
    centre_rotated = 0.5 * (rotated.min(axis=0) + rotated.max(axis=0))
    centre_xy = rot_z(-folded)[:2, :2] @ centre_rotated
    return folded, centre_xy, extents_xy


def prepare_chair(mesh: trimesh.Trimesh) -> PreparedChair:
    """g_obb, convex decomposition and mass properties, cached by the mesh digest.

    Args:
        mesh: the chair, z up, metres, in any horizontal placement.

    Raises:
        ChairPreparationError: when the mesh has no usable volume.
    """
    digest = mesh_digest(mesh)
    remembered = _memory.get(digest)
    if remembered is not None:
        return remembered
    path = cache_dir() / "imagination" / f"{digest}-{PREPARATION_VERSION}.npz"
    prepared = _from_cache(read_cached_arrays(path))
    if prepared is not None and not all(
        Path(name).exists() for name in (prepared.collision_obj, prepared.support_obj)
    ):
        prepared = None
    if prepared is None:
        prepared = _prepare(mesh, digest)
        write_cached_arrays(path, _to_cache(prepared))
    _memory.put(digest, prepared)
    return prepared


def horizontal_area_m2(prepared: PreparedChair, low_m: float, high_m: float) -> float:
    """Area (m²) of the solid's tops at heights low_m..high_m above the floor.

    Every piece is a box, so its top is horizontal: this is the area a seat at those
    heights offers, from above (stretchers and rails count too, with their small area).
    """
    area = 0.0
    for corners in prepared.pieces:
        top_m = float(corners[:, 2].max()) + float(prepared.com_obb_m[2]) - prepared.z_min_m
        if low_m <= top_m <= high_m:
            extent = corners.max(axis=0) - corners.min(axis=0)
            area += float(extent[0] * extent[1])
    return area


def _to_cache(prepared: PreparedChair) -> dict[str, np.ndarray]:
    """The cache entry's arrays (npz, no pickle: see ``bearchair.core.meshes.read_cached_arrays``)."""
    arrays = {name: np.asarray(value) for name, value in prepared._asdict().items()}
    arrays["pieces"] = np.stack([np.asarray(piece, dtype=float) for piece in prepared.pieces])
    return arrays


def _from_cache(arrays: dict[str, np.ndarray] | None) -> PreparedChair | None:
    """A PreparedChair from its cache entry; None when missing or not of this shape."""
    if arrays is None or set(arrays) != set(PreparedChair._fields):
        return None
    try:
        return PreparedChair(
            digest=str(arrays["digest"]),
            T_obb_mesh=np.asarray(arrays["T_obb_mesh"], dtype=float).reshape(4, 4),
            gamma_obb_rad=float(arrays["gamma_obb_rad"]),
            extents_m=np.asarray(arrays["extents_m"], dtype=float).reshape(3),
            z_min_m=float(arrays["z_min_m"]),
            z_top_m=float(arrays["z_top_m"]),
            pieces=tuple(np.asarray(piece, dtype=float) for piece in arrays["pieces"]),
            collision_obj=str(arrays["collision_obj"]),
            support_obj=str(arrays["support_obj"]),
            com_obb_m=np.asarray(arrays["com_obb_m"], dtype=float).reshape(3),
            mass_kg=float(arrays["mass_kg"]),
            inertia_diag=np.asarray(arrays["inertia_diag"], dtype=float).reshape(3),
        )
    except (TypeError, ValueError):
        return None


def _prepare(mesh: trimesh.Trimesh, digest: str) -> PreparedChair:
    vertices = np.asarray(mesh.vertices, dtype=float)
    if len(vertices) < 4 or float(np.ptp(vertices[:, 2])) < 1e-3:
        raise ChairPreparationError("the mesh is flat or has fewer than 4 vertices")
    gamma, centre_xy, extents_xy = yaw_obb(mesh)
    rotation = rot_z(gamma)
    translation = -rotation @ np.array([centre_xy[0], centre_xy[1], 0.0])
    T_obb_mesh = make_transform(rotation, translation)
    z_min, z_top = float(vertices[:, 2].min()), float(vertices[:, 2].max())

    # Scans are open, thin surfaces; modelled meshes may be too. Both are simulated as
    # the solid under their top surfaces, split into boxes in the OBB frame (see
    # solid_below_surface_boxes: convex decomposition closed the gaps between armrests).
    obb_mesh = mesh.copy()
    obb_mesh.apply_transform(T_obb_mesh)
    boxes = np.array(
        solid_below_surface_boxes(
            obb_mesh, SOLID_PITCH_M, tolerance_cells=SOLID_TOP_TOLERANCE_CELLS
        )
    )
    if len(boxes) == 0:
        raise ChairPreparationError("the mesh encloses no solid")
    sizes = boxes[:, 1] - boxes[:, 0]
    centres = boxes.mean(axis=1)
    volumes = np.prod(sizes, axis=1)
    total_volume = float(volumes.sum())
    mass = float(np.clip(total_volume * CHAIR_DENSITY_KG_M3, *CHAIR_MASS_RANGE_KG))
    density = mass / total_volume
    com = (volumes[:, None] * centres).sum(0) / total_volume
    # Boxes' own moments (m/12 (b^2 + c^2), ...) plus the parallel-axis terms.
    squares = sizes**2
    own = squares.sum(axis=1, keepdims=True) - squares
    offsets = centres - com
    piece_masses = density * volumes
    inertia = np.einsum("n,nij->ij", piece_masses, _outer_terms(offsets)) + np.diag(
        (piece_masses[:, None] * own / 12.0).sum(0)
    )
    pieces = tuple(_box_corners(box) - com for box in boxes)
    collision_obj = cache_dir() / "imagination" / f"{digest}-{PREPARATION_VERSION}-pieces.obj"
    _write_pieces_obj(collision_obj, [(piece, _BOX_FACES) for piece in pieces])
    hull = trimesh.convex.convex_hull(np.concatenate(pieces))
    support_obj = collision_obj.with_name(f"{digest}-{PREPARATION_VERSION}-support.obj")
    _write_pieces_obj(support_obj, [(np.asarray(hull.vertices), np.asarray(hull.faces))])
    return PreparedChair(
        digest=digest,
        T_obb_mesh=T_obb_mesh,
        gamma_obb_rad=gamma,
        extents_m=np.array([extents_xy[0], extents_xy[1], z_top - z_min]),
        z_min_m=z_min,
        z_top_m=z_top,
        pieces=pieces,
        collision_obj=str(collision_obj),
        support_obj=str(support_obj),
        com_obb_m=com,
        mass_kg=mass,
        inertia_diag=np.maximum(np.diag(inertia), 1e-6),
    )


# Corner k of a box has x from bit 0, y from bit 1 and z from bit 2 of k (0: lower).
_BOX_FACES = np.array(
    [
        [0, 2, 1], [1, 2, 3],  # z-
        [4, 5, 6], [5, 7, 6],  # z+
        [0, 1, 4], [1, 5, 4],  # y-
        [2, 6, 3], [3, 6, 7],  # y+
        [0, 4, 2], [2, 4, 6],  # x-
        [1, 3, 5], [3, 7, 5],  # x+
    ]
)  # fmt: skip


def _box_corners(box: np.ndarray) -> np.ndarray:
    """(8, 3) corners of a box given as (lower, upper) corners."""
    bits = (np.arange(8)[:, None] >> np.arange(3)[None, :]) & 1
    return np.where(bits == 1, box[1], box[0])


def _outer_terms(offsets: np.ndarray) -> np.ndarray:
    """Parallel-axis tensors |d|^2 I - d d^T for each offset d (n, 3 -> n, 3, 3)."""
    squared = np.einsum("ni,ni->n", offsets, offsets)
    return squared[:, None, None] * np.eye(3) - np.einsum("ni,nj->nij", offsets, offsets)


def _write_pieces_obj(path: Path, pieces: list[tuple[np.ndarray, np.ndarray]]) -> None:
    """Writes the pieces as separate OBJ objects (pybullet: one convex hull per object)."""
    lines: list[str] = []
    base = 1
    for index, (vertices, faces) in enumerate(pieces):
        lines.append(f"o piece_{index}")
        lines.extend(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices)
        lines.extend(f"f {a + base} {b + base} {c + base}" for a, b, c in faces)
        base += len(vertices)
    path.parent.mkdir(parents=True, exist_ok=True)
    scratch = path.with_suffix(f".{threading.get_ident()}.tmp")
    scratch.write_text("\n".join(lines) + "\n")
    scratch.replace(path)
