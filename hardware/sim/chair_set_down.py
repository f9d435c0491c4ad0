"""Where the simulated world sets a chair down: clear of the arm and of the NAO's start.

A person sets a chair down in the cell in front of the arm, not into it. The chair area
holds a chair's centre, so a chair far larger than the area (a 1.7 m sofa turned
lengthwise) drawn near its arm-side edge would otherwise stand through the arm's base:
the world pulls such a chair straight out in front of the arm (+x) until it is
:data:`SET_DOWN_CLEARANCE_M` clear (:func:`slid_clear_of_arm`), and draws another
placement when it then stands in the NAO's way (:func:`clearance_to`).

The test is on points: the chair's faces subdivided to the clearance
(:func:`chair_surface_points`, chair frame, metres) against every link's world bounding
box grown by the clearance (:func:`link_boxes`). pybullet's closest points between a
concave triangle mesh and the arm crashed, or returned garbage, on some meshes.
"""

from __future__ import annotations

import math

import numpy as np
import trimesh

from bearchair.core.arena import Arena
from bearchair.hardware.sim.bullet import LockedBullet

SET_DOWN_CLEARANCE_M = 0.05
"""A chair is set down at least this far (metres) outside the bounding boxes of the
Panda's links as it stands and of the NAO's and the bear's at its start. 5 cm is the
clearance the scan's views were chosen with to the floor (``bench/perception_views.py``),
the arm's own margin."""
SET_DOWN_STEP_M = 0.01
"""The chair is slid away from the arm's base in steps of this (metres) until clear."""
SET_DOWN_DRAWS = 20
"""Placements drawn at most before keeping one that only clears the arm (with a warning)."""


def chair_surface_points(mesh_local: trimesh.Trimesh) -> np.ndarray:
    """(N, 3) points on the chair's surface (chair frame, metres) no farther apart than
    :data:`SET_DOWN_CLEARANCE_M`: its faces subdivided, so that no part of the chair passes
    through a grown box between two points."""
    subdivided = trimesh.remesh.subdivide_to_size(
        mesh_local.vertices, mesh_local.faces, max_edge=SET_DOWN_CLEARANCE_M, max_iter=20
    )
    return np.asarray(subdivided[0], float)


def link_boxes(bullet: LockedBullet, body: int) -> np.ndarray:
    """(N, 2, 3): every link's world bounding box of ``body`` (lower, upper corners,
    metres), grown by :data:`SET_DOWN_CLEARANCE_M`."""
    boxes = []
    for link in range(-1, bullet.getNumJoints(body)):
        lower, upper = bullet.getAABB(body, link)
        boxes.append(
            (np.asarray(lower) - SET_DOWN_CLEARANCE_M, np.asarray(upper) + SET_DOWN_CLEARANCE_M)
        )
    return np.asarray(boxes, float)


def any_inside(points: np.ndarray, boxes: np.ndarray) -> bool:
    """Whether any of ``points`` (N, 3) lies in any of ``boxes`` (M, 2, 3)."""
    for lower, upper in boxes:
        if np.any(np.all((points >= lower) & (points <= upper), axis=1)):
            return True
    return False


def clearance_to(surface_local: np.ndarray, T_world_chair: np.ndarray, boxes: np.ndarray) -> float:
    """0 when the chair at ``T_world_chair`` reaches into one of the grown ``boxes``, else
    :data:`SET_DOWN_CLEARANCE_M` (metres)."""
    surface = surface_local @ T_world_chair[:3, :3].T + T_world_chair[:3, 3]
    return 0.0 if any_inside(surface, boxes) else SET_DOWN_CLEARANCE_M


def slid_clear_of_arm(
    T_world_chair: np.ndarray, surface_local: np.ndarray, arena: Arena, arm_boxes: np.ndarray
) -> np.ndarray:
    """``T_world_chair`` pulled straight out in front of the arm (+x) until the whole chair
    stands :data:`SET_DOWN_CLEARANCE_M` in front of the arm's footprint (the arena's
    obstacle around the arm's base) and outside every grown link box of the arm
    (``arm_boxes``). A chair already clear keeps its pose exactly."""
    base_x, base_y = arena.arm_base_xy
    fronts = [
        box.x_max
        for box in arena.obstacles
        if box.x_min <= base_x <= box.x_max and box.y_min <= base_y <= box.y_max
    ]
    front = max(fronts, default=base_x) + SET_DOWN_CLEARANCE_M
    T = T_world_chair.copy()
    surface = surface_local @ T[:3, :3].T
    lowest = float(surface[:, 0].min())  # the chair's x extent about its centre
    if T[0, 3] + lowest < front:
        T[0, 3] = front - lowest
    for _ in range(math.ceil(float(arena.x_max - T[0, 3]) / SET_DOWN_STEP_M)):
        if not any_inside(surface + T[:3, 3], arm_boxes):
            break
        T[0, 3] += SET_DOWN_STEP_M
    return T
