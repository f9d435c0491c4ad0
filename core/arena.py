"""The workspace layout shared by the planner and the simulated world.

The arm scans the chair area in front of it; the humanoid walks inside the planning
arena, a rectangle marked on the floor (the paper's red dashed lines), and starts at its
far end, facing the arm. The arena's back edge runs through the chair area, so a chair
whose sitting direction points at the arm or at a side edge leaves no room in front of it
for the humanoid: those are the inaccessible placements. (Measured with
``bench/planning.py``: with the back edge at 0.15 m and the sides at ±0.75 m, 4-8 of 20
placements facing the arm and all facing a side edge were still reachable; with 0.5 m
and ±0.45 m, none facing the arm and at most 1 of 20 facing a side.) Every number
is in metres or radians, world frame, z up.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from bearchair.core.se2 import SE2Pose


class Box2D(NamedTuple):
    """An axis-aligned rectangular obstacle footprint, with its height (metres)."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    height: float = 1.0


class Arena(NamedTuple):
    """The rectangle the humanoid may walk in, the chair area and fixed obstacles.

    Attributes:
        x_min, x_max, y_min, y_max: edges of the planning arena (metres).
        chair_area: where the chair's centre is placed for scanning (0.5 x 0.5 m).
        arm_base_xy: the scanning arm's base position.
        obstacles: other fixed footprints the humanoid must avoid (the arm's base).
        humanoid_start: where the humanoid waits with the bear.
    """

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    chair_area: Box2D
    arm_base_xy: tuple[float, float]
    obstacles: tuple[Box2D, ...]
    humanoid_start: SE2Pose

    def contains(self, x: float, y: float, margin: float = 0.0) -> bool:
        """True when (x, y) is inside the walls by at least ``margin`` metres."""
        return (
            self.x_min + margin <= x <= self.x_max - margin
            and self.y_min + margin <= y <= self.y_max - margin
        )


DEFAULT_ARENA = Arena(
    x_min=0.5,
    x_max=2.2,
    y_min=-0.45,
    y_max=0.45,
    chair_area=Box2D(0.35, 0.85, -0.25, 0.25),
    arm_base_xy=(0.0, 0.0),
    obstacles=(Box2D(-0.15, 0.15, -0.15, 0.15, height=0.9),),
    humanoid_start=SE2Pose(1.9, 0.0, 3.141592653589793),
)


ACCESSIBLE_TOLERANCE_RAD = math.radians(30.0)
"""An accessible placement's sitting direction is within this of the way to the humanoid."""
STANDING_ROOM_M = (0.35, 0.6)
"""... and its ray, from this near to this far from the chair's centre (metres: where the
humanoid stands once clear of chairs of every depth), stays inside the arena ..."""
STANDING_MARGIN_M = 0.15
"""... by this much (the NAO ellipsoid's lateral semi-axis, 0.14 m, and a centimetre).
Checking 0.5 m alone with 0.12 m let a box chair at the arm-side edge turned 34 degrees
count as accessible with its s_goal in the wall."""


def accessible_sitting_yaws(
    arena: Arena, centre_xy: tuple[float, float], samples: int = 61
) -> np.ndarray:
    """Sitting directions (radians) that make a chair at ``centre_xy`` accessible.

    Within ``ACCESSIBLE_TOLERANCE_RAD`` of the direction toward the humanoid's start, and
    leaving room to stand in front of the chair inside the arena; a placement generator
    draws from these so that "accessible" means the humanoid can stand there. Never empty:
    the direction straight toward the start stays when nothing else qualifies.
    """
    start = arena.humanoid_start
    x, y = centre_xy
    toward = math.atan2(start.y - y, start.x - x)
    yaws = toward + np.linspace(-ACCESSIBLE_TOLERANCE_RAD, ACCESSIBLE_TOLERANCE_RAD, samples)
    distances = np.linspace(*STANDING_ROOM_M, 6)
    room = np.array(
        [
            all(
                arena.contains(x + d * math.cos(yaw), y + d * math.sin(yaw), STANDING_MARGIN_M)
                for d in distances
            )
            for yaw in yaws
        ]
    )
    return yaws[room] if room.any() else np.array([toward])


class TagSpec(NamedTuple):
    """The ArUco tag on top of the humanoid's head, by which the arm camera tracks it.

    Attributes:
        dictionary: the cv2.aruco predefined dictionary name.
        marker_id: the tag's id in that dictionary.
        side_m: printed side length of the black square, metres.
        height_m: height of the tag's centre above the floor when standing, metres.
    The tag lies flat, its x axis along the humanoid's forward direction, its centre
    on the humanoid's vertical axis.
    """

    dictionary: str
    marker_id: int
    side_m: float
    height_m: float


HUMANOID_TAG = TagSpec(dictionary="DICT_4X4_50", marker_id=7, side_m=0.08, height_m=0.58)
