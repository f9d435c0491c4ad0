"""Which parts of a scanned chair's surface a camera saw.

A TSDF grows surface where no view looked: a view that sees an armrest's top from above
and to one side writes "behind the surface" along its rays into the voxels beside the
armrest's inner face, and a second such view makes them surface (likely the mechanism:
``bench/scan_rails.py`` measures the effect, docs/decisions.md). The reconstruction
marks each vertex of the chair mesh that some frame measured (within
:data:`SEEN_TOLERANCE_M` of the frame's depth) in the mesh's vertex attribute
:data:`SEEN_ATTRIBUTE`; the planners count what stands beside the bear's lane, in the
hands' way, only where it was seen (:func:`seen_faces`,
:func:`bearchair.skills.planning.wholebody.chair_profile.stands_above_seat`). A mesh
without the attribute (a true mesh, a user's file) is seen everywhere.
"""

from __future__ import annotations

import numpy as np
import trimesh

SEEN_ATTRIBUTE = "seen"
"""Vertex attribute of a scanned chair mesh: 1.0 where a frame measured the surface,
0.0 where only the TSDF put it."""

SEEN_TOLERANCE_M = 0.006
"""A surface point within this of a frame's depth along its ray was measured (metres):
half the scan's 8 mm voxel, where marching cubes puts the surface, plus twice the
Carmine's depth noise at 0.9 m (about 1 mm)."""


def seen_vertices(mesh: trimesh.Trimesh) -> np.ndarray | None:
    """(V,) bool: the vertices a frame measured; None when the mesh carries no
    :data:`SEEN_ATTRIBUTE` (all of it counts as seen)."""
    seen = mesh.vertex_attributes.get(SEEN_ATTRIBUTE)
    if seen is None or len(seen) != len(mesh.vertices):
        return None
    return np.asarray(seen, dtype=float) > 0.5


def seen_faces(mesh: trimesh.Trimesh) -> np.ndarray | None:
    """(F,) bool: the faces all three of whose vertices a frame measured (a face along
    the edge of what was seen leans into what was not); None as :func:`seen_vertices`."""
    measured = seen_vertices(mesh)
    if measured is None:
        return None
    return np.asarray(measured[np.asarray(mesh.faces)].all(axis=1), dtype=bool)


def seen_samples(mesh: trimesh.Trimesh, face_index: np.ndarray) -> np.ndarray:
    """(N + V,) bool: of surface samples on the faces ``face_index`` followed by the
    mesh's vertices (as the planners sample a chair), which a frame measured; all of them
    for a mesh without the mark."""
    faces, vertices = seen_faces(mesh), seen_vertices(mesh)
    if faces is None or vertices is None:
        return np.ones(len(face_index) + len(mesh.vertices), bool)
    return np.concatenate([faces[face_index], vertices])
