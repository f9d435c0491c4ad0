"""Collision geometry for SE(2) planning: the NAO as an ellipsoid, the world as FCL objects.

The paper (section "Motion Planning") encloses the walking NAO in an ellipsoid and checks
it with FCL against the scene. Here the scene is the planning arena's walls (boxes just
outside its edges), its fixed obstacles (the arm's base) and the chair as its convex
pieces (V-HACD, :func:`skills.meshes.convex_pieces`), all in the world frame.

The NAO ellipsoid (body frame: x forward, y left, z up) has semi-axes
:data:`NAO_SEMI_AXES_M` and its centre :data:`NAO_CENTRE_FORWARD_M` ahead of the robot's
vertical axis, :data:`NAO_CENTRE_HEIGHT_M` above the floor:

* forward 0.165 m, centre 0.035 m ahead: it spans 0.13 m behind the axis (the NAO's back)
  to 0.20 m ahead of it. The NAO V6 is 0.311 m deep with its arms forward (datasheet
  574 x 275 x 311 mm); the held bear's back reaches 0.185 m ahead of the axis at 0.25 m
  height in the whole-body planner's carrying posture (skills.planning.wholebody), and
  the ellipsoid must cover it there (0.196 m at that height);
* lateral 0.14 m: 0.275 m wide across the shoulders, plus 2.5 mm;
* vertical 0.29 m: 0.574 m tall; the centre is 0.29 m above the floor.
"""

from __future__ import annotations

import math
from collections import OrderedDict

import fcl
import numpy as np
import trimesh

from skills.arena import Arena, Box2D
from skills.geometry import SE2Pose, rot_z
from skills.meshes import convex_pieces, mesh_digest

NAO_SEMI_AXES_M = (0.165, 0.14, 0.29)
"""Semi-axes (forward, lateral, vertical) of the NAO's enclosing ellipsoid, metres."""

NAO_CENTRE_FORWARD_M = 0.035
"""How far the ellipsoid's centre is ahead of the NAO's vertical axis (the held bear)."""

NAO_CENTRE_HEIGHT_M = 0.29
"""Height of the ellipsoid's centre above the floor, metres."""

WALL_THICKNESS_M = 0.2
WALL_HEIGHT_M = 1.0

_PIECES_CACHE_SIZE = 8
# faces digest -> (vertices (N, 3), convex pieces): lets a rigidly moved copy of a chair
# (the same mesh after the helper turned it) reuse its decomposition without V-HACD.
_pieces_cache: OrderedDict[str, tuple[np.ndarray, list[trimesh.Trimesh]]] = OrderedDict()


def nao_geometry() -> fcl.Ellipsoid:
    """The NAO's enclosing ellipsoid as an FCL shape (body frame)."""
    return fcl.Ellipsoid(*NAO_SEMI_AXES_M)


def nao_transform(pose: SE2Pose) -> fcl.Transform:
    """``T_world_ellipsoid`` for the NAO standing at ``pose``."""
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    centre = np.array(
        [pose.x + NAO_CENTRE_FORWARD_M * c, pose.y + NAO_CENTRE_FORWARD_M * s, NAO_CENTRE_HEIGHT_M]
    )
    return fcl.Transform(rot_z(pose.theta), centre)


def chair_convex_pieces(chair_mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    """Convex pieces of a chair, reusing an earlier decomposition of the same chair moved.

    When a mesh with identical faces was decomposed before and the vertices differ only by
    a rigid motion (residual below 0.1 mm), that motion is applied to the cached pieces;
    otherwise :func:`skills.meshes.convex_pieces` (disk-cached V-HACD) runs.
    """
    faces_key = mesh_digest(trimesh.Trimesh(np.zeros((0, 3)), chair_mesh.faces, process=False))
    faces_key += f"-{len(chair_mesh.vertices)}"
    vertices = np.asarray(chair_mesh.vertices, dtype=np.float64)
    cached = _pieces_cache.get(faces_key)
    if cached is not None:
        transform = _rigid_fit(cached[0], vertices)
        if transform is not None:
            _pieces_cache.move_to_end(faces_key)
            return [piece.copy().apply_transform(transform) for piece in cached[1]]
    pieces = convex_pieces(chair_mesh)
    _pieces_cache[faces_key] = (vertices.copy(), pieces)
    while len(_pieces_cache) > _PIECES_CACHE_SIZE:
        _pieces_cache.popitem(last=False)
    return pieces


def _rigid_fit(
    source: np.ndarray, target: np.ndarray, tolerance_m: float = 1e-4
) -> np.ndarray | None:
    """The 4x4 rigid motion mapping ``source`` onto ``target`` (Kabsch), or None if none fits."""
    if source.shape != target.shape or len(source) < 3:
        return None
    source_centre, target_centre = source.mean(axis=0), target.mean(axis=0)
    covariance = (source - source_centre).T @ (target - target_centre)
    u, _, vt = np.linalg.svd(covariance)
    sign = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rotation = vt.T @ np.diag([1.0, 1.0, sign]) @ u.T
    translation = target_centre - rotation @ source_centre
    residual = np.abs(source @ rotation.T + translation - target).max()
    if residual > tolerance_m:
        return None
    transform = np.eye(4)
    transform[:3, :3], transform[:3, 3] = rotation, translation
    return transform


def _convex(piece: trimesh.Trimesh) -> fcl.Convex:
    faces = np.asarray(piece.faces, dtype=np.int64)
    flat = np.hstack([np.full((len(faces), 1), 3, dtype=np.int64), faces]).ravel()
    return fcl.Convex(np.asarray(piece.vertices, dtype=np.float64), len(faces), flat)


def _box_object(box: Box2D) -> fcl.CollisionObject:
    extents = (box.x_max - box.x_min, box.y_max - box.y_min, box.height)
    centre = np.array(
        [(box.x_min + box.x_max) / 2.0, (box.y_min + box.y_max) / 2.0, box.height / 2.0]
    )
    return fcl.CollisionObject(fcl.Box(*extents), fcl.Transform(centre))


def wall_boxes(arena: Arena) -> tuple[Box2D, ...]:
    """The four walls just outside the planning arena's edges."""
    t, h = WALL_THICKNESS_M, WALL_HEIGHT_M
    return (
        Box2D(arena.x_min - t, arena.x_min, arena.y_min - t, arena.y_max + t, h),
        Box2D(arena.x_max, arena.x_max + t, arena.y_min - t, arena.y_max + t, h),
        Box2D(arena.x_min - t, arena.x_max + t, arena.y_min - t, arena.y_min, h),
        Box2D(arena.x_min - t, arena.x_max + t, arena.y_max, arena.y_max + t, h),
    )


class _ObjectGroup:
    """A set of static FCL objects behind one broad-phase manager."""

    def __init__(self, objects: list[fcl.CollisionObject]) -> None:
        self._objects = objects
        self._manager = fcl.DynamicAABBTreeCollisionManager()
        if objects:
            self._manager.registerObjects(objects)
            self._manager.setup()

    def collides(self, probe: fcl.CollisionObject) -> bool:
        if not self._objects:
            return False
        data = fcl.CollisionData(request=fcl.CollisionRequest())
        self._manager.collide(probe, data, fcl.defaultCollisionCallback)
        return bool(data.result.is_collision)


class NaoCollisionChecker:
    """Answers "does the NAO standing at this SE(2) pose touch anything?".

    Attributes:
        arena: the planning arena (walls and fixed obstacles).
    """

    def __init__(self, arena: Arena, chair_pieces: list[trimesh.Trimesh]) -> None:
        """Builds the FCL scene.

        Args:
            arena: walls and fixed obstacles, world frame.
            chair_pieces: the chair's convex pieces in the world frame.
        """
        self.arena = arena
        self._nao = fcl.CollisionObject(nao_geometry(), fcl.Transform())
        self._walls = _ObjectGroup([_box_object(box) for box in wall_boxes(arena)])
        self._obstacles = _ObjectGroup([_box_object(box) for box in arena.obstacles])
        self._chair = _ObjectGroup(
            [fcl.CollisionObject(_convex(p), fcl.Transform()) for p in chair_pieces]
        )
        self.checks = 0

    def _placed(self, pose: SE2Pose) -> fcl.CollisionObject:
        self._nao.setTransform(nao_transform(pose))
        self.checks += 1
        return self._nao

    def collides_with_chair(self, pose: SE2Pose) -> bool:
        """The NAO at ``pose`` touches the chair."""
        return self._chair.collides(self._placed(pose))

    def collides_with_walls(self, pose: SE2Pose) -> bool:
        """The NAO at ``pose`` touches a wall of the arena."""
        return self._walls.collides(self._placed(pose))

    def collides_with_obstacles(self, pose: SE2Pose) -> bool:
        """The NAO at ``pose`` touches a fixed obstacle (the arm's base)."""
        return self._obstacles.collides(self._placed(pose))

    def blocked_by(self, pose: SE2Pose) -> str:
        """What the NAO at ``pose`` touches ("wall", "obstacle", "chair"), or "" if nothing."""
        if self.collides_with_walls(pose):
            return "wall"
        if self.collides_with_obstacles(pose):
            return "obstacle"
        if self.collides_with_chair(pose):
            return "chair"
        return ""

    def is_free(self, x: float, y: float, theta: float) -> bool:
        """The NAO at (x, y, θ) is inside the arena and touches nothing (OMPL's checker)."""
        if not self.arena.contains(x, y):
            return False
        probe = self._placed(SE2Pose(x, y, theta))
        return not (
            self._walls.collides(probe)
            or self._obstacles.collides(probe)
            or self._chair.collides(probe)
        )
