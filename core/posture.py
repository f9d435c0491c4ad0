"""Whether a chair mesh stands as its file has it: gravity, what it rests on, its seat.

A mesh file says nothing about which way is up; bearchair reads every mesh z up. A file
exported y up, a chair rolled by a careless export, or one upside down must be told
apart, because the advice differs (re-export z up, stand it up, flip it). Two facts
decide, both from the geometry alone:

* **Gravity.** Put on a floor with gravity along ``g``, a rigid body comes to rest on
  a face of its convex hull over which its centre of mass lies. The *rest tilt* for
  ``g`` is the angle between ``g`` and the nearest such face's outward normal: 0 for
  a chair standing on its legs, about 35 degrees for one rolled by 35 degrees. The
  centre of mass is the surface's area centroid (meshes are shells and triangle soups;
  a chair's mass lies in its surfaces too).
* **The seat.** Something to sit on is a large surface facing up (against ``g``),
  above the bottom fifth of the object, with the object under it. A chair lying on its
  back stands too, but its seat then faces sideways.

Measured over the 173 calibration meshes (``tests/test_posture.py`` reruns it where they
are present): every upright one, whatever its kind, stands and is not warned; turned
x-up or y-up (4 ways), 94 % are warned (83 % "on its side", 11 % "tips over"); rolled or
pitched 35 degrees, 99 % are warned (96 % "tips over by about N degrees", never "upside
down"); upside down, 63 % are warned (57 % "upside down"; the rest are shelves, boxes,
tables and backless stools, which stand either way).
"""

from __future__ import annotations

import numpy as np
import trimesh

MAX_REST_TILT_DEG = 10.0
"""A mesh stands as it is when it rests within this angle of its file's floor. Legs of
unequal length rock it by a few degrees (a 2 cm difference under a 0.3 m seat is
4 degrees; the upright calibration meshes rest within 9.1 degrees, most within 2); a
file rolled or pitched by more has been exported tilted."""
FACING_DEG = 20.0
"""A face counts as facing along an axis when its normal is within this angle of it."""
SEAT_BAND = (0.2, 1.0)
"""Where a seat can be, as fractions of the height above the lowest point: not the
bottom fifth (feet, a base plate, a backrest lying on the floor) up to the very top
(a stool's or a box's top)."""
SIDE_SEAT_RATIO = 1.5
"""A mesh that stands is said to lie on its side when, with gravity along a horizontal
axis under which it would stand too, the area facing up as a seat would is this many
times the area facing up as it stands (the seat of a chair on its back faces sideways)."""

SQUARER_DEG = 3.0
"""A mesh that stands is said to be upside down when, turned over, it would rest this
much more squarely (a chair upside down rocks on its backrest's and armrests' tops; the
upright calibration meshes rest at most 0.1 degree more squarely turned over)."""

DIRECTIONS = {
    "-z": np.array([0.0, 0.0, -1.0]),
    "+z": np.array([0.0, 0.0, 1.0]),
    "-x": np.array([-1.0, 0.0, 0.0]),
    "+x": np.array([1.0, 0.0, 0.0]),
    "-y": np.array([0.0, -1.0, 0.0]),
    "+y": np.array([0.0, 1.0, 0.0]),
}
"""The gravity directions tried, in the mesh's frame: "-z" is the file read z up."""


def surface_centroid(mesh: trimesh.Trimesh) -> np.ndarray:
    """The area-weighted centre of the mesh's triangles (m): its centre of mass as a shell."""
    triangles = np.asarray(mesh.triangles, dtype=float)
    areas = 0.5 * np.linalg.norm(
        np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]), axis=1
    )
    total = float(areas.sum())
    if total <= 0.0:
        return np.asarray(mesh.vertices, dtype=float).mean(axis=0)
    return (triangles.mean(axis=1) * areas[:, None]).sum(axis=0) / total


def rest_faces(mesh: trimesh.Trimesh) -> dict[str, tuple[float, np.ndarray]]:
    """For each gravity direction of :data:`DIRECTIONS`: the rest tilt (degrees) and the
    outward normal of the hull face it comes to rest on.

    A tilt of 180 where no face of the hull holds the centre of mass (not reached for a
    body; a degenerate hull).
    """
    centre = surface_centroid(mesh)
    hull = mesh.convex_hull
    triangles = np.asarray(hull.triangles, dtype=float)
    normals = np.asarray(hull.face_normals, dtype=float)
    # The centre of mass dropped along each face's normal onto its plane: inside?
    offsets = ((centre - triangles[:, 0]) * normals).sum(axis=1)
    holds = _inside_triangles(triangles, centre - offsets[:, None] * normals)
    faces = {}
    for name, gravity in DIRECTIONS.items():
        if not holds.any():
            faces[name] = (180.0, gravity)
            continue
        cosines = np.clip(normals[holds] @ gravity, -1.0, 1.0)
        best = int(np.argmax(cosines))
        faces[name] = (float(np.degrees(np.arccos(cosines[best]))), normals[holds][best])
    return faces


def _inside_triangles(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Whether each point (in its triangle's plane) lies in its triangle (barycentric)."""
    edge_1 = triangles[:, 1] - triangles[:, 0]
    edge_2 = triangles[:, 2] - triangles[:, 0]
    to_point = points - triangles[:, 0]
    d11, d12, d22 = (edge_1 * edge_1).sum(1), (edge_1 * edge_2).sum(1), (edge_2 * edge_2).sum(1)
    p1, p2 = (to_point * edge_1).sum(1), (to_point * edge_2).sum(1)
    denominator = d11 * d22 - d12 * d12
    denominator = np.where(denominator == 0.0, np.inf, denominator)
    u = (d22 * p1 - d12 * p2) / denominator
    v = (d11 * p2 - d12 * p1) / denominator
    slack = 1e-9
    return (u >= -slack) & (v >= -slack) & (u + v <= 1.0 + slack)


class _Faces:
    """A mesh's triangles as unit normals, centres and areas (degenerate ones dropped)."""

    def __init__(self, mesh: trimesh.Trimesh) -> None:
        triangles = np.asarray(mesh.triangles, dtype=float)
        cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        double_area = np.linalg.norm(cross, axis=1)
        keep = double_area > 0
        self.normals = cross[keep] / double_area[keep, None]
        self.centres = triangles[keep].mean(axis=1)
        self.areas = 0.5 * double_area[keep]

    def seat_area_m2(self, gravity: np.ndarray) -> float:
        """The area (m²) of faces facing along ``gravity`` in :data:`SEAT_BAND` of the
        height against it. Normals count either way (meshes are often soups with
        inconsistent winding)."""
        heights = self.centres @ -gravity
        low, extent = heights.min(), max(float(np.ptp(heights)), 1e-9)
        fraction = (heights - low) / extent
        chosen = np.abs(self.normals @ gravity) > np.cos(np.radians(FACING_DEG))
        chosen &= (fraction > SEAT_BAND[0]) & (fraction <= SEAT_BAND[1])
        return float(self.areas[chosen].sum())


def seat_areas_m2(mesh: trimesh.Trimesh) -> dict[str, float]:
    """For each gravity direction of :data:`DIRECTIONS`: the area (m²) a seat would have."""
    faces = _Faces(mesh)
    return {name: faces.seat_area_m2(gravity) for name, gravity in DIRECTIONS.items()}


def posture_warning(mesh: trimesh.Trimesh, path: object = "mesh") -> str | None:
    """One line saying how the mesh does not stand z up, and what to do; None if it does.

    Standing as it is (a rest tilt within :data:`MAX_REST_TILT_DEG`), it is warned only
    when it would rest as squarely (or more) on a side on which its seat would face up, with
    :data:`SIDE_SEAT_RATIO` times the area (a y-up chair lying on its back), or
    :data:`SQUARER_DEG` more squarely turned over (upside down). Not standing,
    the way it would stand with the most seat tells why: on what is now its top (upside
    down), on a side (x-up or y-up), or on the face it tips onto (rolled or pitched).
    """
    rests = rest_faces(mesh)
    faces = _Faces(mesh)
    seats = {name: faces.seat_area_m2(gravity) for name, gravity in DIRECTIONS.items()}
    stands = {name for name, (tilt, _) in rests.items() if tilt <= MAX_REST_TILT_DEG}
    sides = [name for name in ("-x", "+x", "-y", "+y") if name in stands]
    tilt = rests["-z"][0]
    if "-z" in stands:
        side = max(sides, key=lambda name: seats[name], default=None)
        if side and seats[side] > SIDE_SEAT_RATIO * seats["-z"] and rests[side][0] <= tilt:
            return _side_warning(path, side)
        if rests["+z"][0] <= tilt - SQUARER_DEG:
            return _upside_down_warning(path)
        return None
    tilted_seat = faces.seat_area_m2(rests["-z"][1])
    flipped_seat = seats["+z"] if "+z" in stands else 0.0
    side = max(sides, key=lambda name: seats[name], default=None)
    if side and seats[side] > SIDE_SEAT_RATIO * max(tilted_seat, flipped_seat):
        return _side_warning(path, side)
    if "+z" in stands and flipped_seat >= tilted_seat:
        return _upside_down_warning(path)
    return (
        f"{path}: does not stand as the file has it: it would tip over by about "
        f"{tilt:.0f} degrees before resting on the floor (rolled or pitched?); "
        "re-export it standing on its base, z up"
    )


def _upside_down_warning(path: object) -> str:
    return (
        f"{path}: seems upside down: it would stand on what is now its top "
        "(turn it over, z up, before using it)"
    )


def _side_warning(path: object, down: str) -> str:
    axis = down[1]
    return (
        f"{path}: seems to lie on its side: its seat faces ±{axis}, not ±z "
        f"(is the file {axis}-up? bearchair expects z up: re-export it with z up)"
    )
