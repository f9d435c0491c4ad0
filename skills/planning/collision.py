"""Collision geometry for SE(2) planning: the NAO as an ellipsoid, the world as FCL objects.

The paper (section "Motion Planning") encloses the walking NAO in an ellipsoid and checks
it with FCL against the scene. Here the scene is the planning arena's walls (boxes just
outside its edges), its fixed obstacles (the arm's base) and the chair as the solid
under its surface (:func:`chair_solid_boxes`), all in the world frame.

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

import fcl
import numpy as np
import trimesh

from bearchair.core.arena import Arena, Box2D
from bearchair.core.geometry import rot_z
from bearchair.core.meshes import solid_below_surface_boxes
from bearchair.core.se2 import SE2Pose

NAO_SEMI_AXES_M = (0.165, 0.14, 0.29)
"""Semi-axes (forward, lateral, vertical) of the NAO's enclosing ellipsoid, metres."""

NAO_CENTRE_FORWARD_M = 0.035
"""How far the ellipsoid's centre is ahead of the NAO's vertical axis (the held bear)."""

NAO_CENTRE_HEIGHT_M = 0.29
"""Height of the ellipsoid's centre above the floor, metres."""

WALL_THICKNESS_M = 0.2
WALL_HEIGHT_M = 1.0

CHAIR_CELL_M = 0.01
"""Column size of the chair's solid, metres: the spacing of the validity checks along a
motion (``se2.CHECK_RESOLUTION_M``). The solid's outline lies at most one cell outside
the chair's surface, so a stance is judged at most this much too near."""


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


def chair_solid_boxes(chair_mesh: trimesh.Trimesh) -> list[np.ndarray]:
    """The chair as the walking NAO meets it: every column under its surface, as boxes.

    The NAO's ellipsoid reaches the floor, so the space under a seat is as closed to it
    as the seat itself; a scanned chair is an open surface with no inside, which only a
    solid can stand for. :func:`bearchair.core.meshes.solid_below_surface_boxes` fills each
    :data:`CHAIR_CELL_M` column from its highest surface point to the floor and merges
    the columns into a few boxes (tens to a few hundred on a chair, in about 0.1 s),
    with no decomposition to run or cache.

    Args:
        chair_mesh: the chair, world frame, z up, metres.

    Returns:
        One (2, 3) array of (lower, upper) corners per box, world frame, metres.
    """
    return solid_below_surface_boxes(chair_mesh, pitch_m=CHAIR_CELL_M)


def _corner_box_object(corners: np.ndarray) -> fcl.CollisionObject:
    lower, upper = np.asarray(corners, dtype=np.float64)
    return fcl.CollisionObject(fcl.Box(*(upper - lower)), fcl.Transform((lower + upper) / 2.0))


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

    def __init__(self, arena: Arena, chair_boxes: list[np.ndarray]) -> None:
        """Builds the FCL scene.

        Args:
            arena: walls and fixed obstacles, world frame.
            chair_boxes: the chair's solid (:func:`chair_solid_boxes`): (2, 3) arrays of
                lower and upper corners, world frame, metres.
        """
        self.arena = arena
        self._nao = fcl.CollisionObject(nao_geometry(), fcl.Transform())
        self._walls = _ObjectGroup([_box_object(box) for box in wall_boxes(arena)])
        self._obstacles = _ObjectGroup([_box_object(box) for box in arena.obstacles])
        self._chair = _ObjectGroup([_corner_box_object(box) for box in chair_boxes])
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
