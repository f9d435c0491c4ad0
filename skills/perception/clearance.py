"""Scan views that keep the arm clear of the chair: checked, replaced or skipped.

The scan configurations were chosen offline against a chair volume of a fixed size;
a larger or taller chair can stand where a view, or the motion into it, passes. Before
the scan the arm looks down from HOME (high above the chair area) and bounds what it
sees above the floor inside :func:`bearchair.skills.perception.views.chair_volume` (the chair
area widened by the largest chair's reach, up to the tallest chair): that box, grown
by a margin for parts the high view cannot see, is the chair's possible extent. Each
view is then checked by forward kinematics (pybullet closest points between the
Panda's links and the box, along the straight joint-space motion into it):

* clear from the previous configuration: visited as planned;
* clear only from HOME: visited through HOME;
* neither: replaced by the configuration partway from HOME to it (the camera higher
  and farther, still looking at the chair) that is clear, or skipped.

An object larger than the chair area (a sofa) runs past the HOME view's side edges
(:func:`cut_sides`): the scan then takes side looks
(:mod:`bearchair.skills.perception.scan_capture`), and the extent is what all the looks
saw, inside the volume or connected to what stands over the chair area, so the views are
checked against the whole object.
Where nothing is seen (an empty frame), the whole volume is the extent.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple, cast

import numpy as np
from scipy import ndimage

from bearchair.core.arena import DEFAULT_ARENA, Box2D
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.skills.perception.pinhole import clean_depth, depth_to_world
from bearchair.skills.perception.views import (
    CHAIR_VOLUME,
    HOME_CONFIGURATION,
    VIEW_CLEARANCE_M,
)

if TYPE_CHECKING:
    from bearchair.skills.perception.panda_kinematics import PandaKinematics

HIDDEN_MARGIN_M = 0.05
"""Growth (metres) of the box seen from HOME for what the high view cannot see: parts
under the seat's overhang and depth noise."""

FLOOR_MARGIN_M = 0.03
"""Points less than this above the floor (metres) are floor, not chair."""

VOXEL_M = 0.02
"""Cell size (metres) of the occupancy count that ignores single stray depth pixels."""

MIN_POINTS_PER_VOXEL = 4
"""A cell needs this many depth points to count as chair (stray pixels have one or two)."""

REPLACEMENT_FRACTIONS = (0.8, 0.6, 0.4)
"""Where a replacement view sits on the joint-space line from HOME to a blocked view."""

MAX_AIM_ERROR_DEG = 20.0
"""A replacement's optical axis passes within this of the chair box's centre."""

PATH_STEP_RAD = 0.05
"""Largest joint step between two collision checks along a motion."""

LOOK_RANGE_M = 2.0
"""How far (metres) from the arm's base an object's parts are looked for: the depth the
reconstruction fuses (``ReconstructionConfig.depth_max_m``), where the Carmine's depth
noise (growing with the square of the distance) is still a few millimetres."""

BORDER_PX = 4
"""An object whose pixels come within this many columns of the image's side edge goes on
past it (the HOME look saw only part of it): the arm turns to look further that way."""


def look_volume(
    arena=DEFAULT_ARENA, volume: tuple[np.ndarray, np.ndarray] = CHAIR_VOLUME
) -> tuple[np.ndarray, np.ndarray]:
    """The world box an object reaching out of the chair area is looked for in (metres):
    in front of the arm's footprint (the chair volume's near side) to
    :data:`LOOK_RANGE_M` from the arm's base, as high as the chair volume."""
    base_x, base_y = arena.arm_base_xy
    lower = np.array([volume[0][0], base_y - LOOK_RANGE_M, volume[0][2]])
    upper = np.array([base_x + LOOK_RANGE_M, base_y + LOOK_RANGE_M, volume[1][2]])
    return lower, upper


LOOK_VOLUME = look_volume()


class ChairExtent(NamedTuple):
    """An axis-aligned world box (metres) the chair lies in, and how it was found."""

    lower: np.ndarray
    upper: np.ndarray
    source: str  # "seen" (from the HOME view) or "volume" (nothing seen: the whole volume)


def _occupied_cells(
    frames: Sequence[RGBDFrame], lower: np.ndarray, upper: np.ndarray
) -> tuple[np.ndarray, list[np.ndarray]]:
    """The :data:`VOXEL_M` cells (integer indices) with at least
    :data:`MIN_POINTS_PER_VOXEL` depth points of ``frames`` inside the box, above the floor;
    and per frame, every pixel's cell (-1 rows where the pixel counts for none)."""
    per_frame: list[np.ndarray] = []
    all_cells: list[np.ndarray] = []
    for frame in frames:
        points = depth_to_world(frame, clean_depth(frame)).reshape(-1, 3)
        valid = np.all(np.isfinite(points), axis=1)
        valid[valid] = np.all((points[valid] >= lower) & (points[valid] <= upper), axis=1)
        valid &= np.nan_to_num(points[:, 2], nan=-1.0) > lower[2] + FLOOR_MARGIN_M
        cells = np.full((len(points), 3), -1, dtype=np.int64)
        cells[valid] = np.floor(points[valid] / VOXEL_M).astype(np.int64)
        per_frame.append(np.where(valid[:, None], cells, np.iinfo(np.int64).min))
        all_cells.append(cells[valid])
    stacked = np.concatenate(all_cells) if all_cells else np.zeros((0, 3), np.int64)
    if len(stacked) == 0:
        return stacked, per_frame
    # Counted as one integer key per cell: np.unique over rows sorts far slower.
    low = np.floor(lower / VOXEL_M).astype(np.int64) - 1
    span = np.floor(upper / VOXEL_M).astype(np.int64) + 2 - low
    shifted = stacked - low
    keys = (shifted[:, 0] * span[1] + shifted[:, 1]) * span[2] + shifted[:, 2]
    unique, counts = np.unique(keys, return_counts=True)
    unique = unique[counts >= MIN_POINTS_PER_VOXEL]
    cells = np.column_stack(
        (unique // (span[1] * span[2]), (unique // span[2]) % span[1], unique % span[2])
    )
    return cells + low, per_frame


def _connected_to_area(cells: np.ndarray, area: Box2D) -> np.ndarray:
    """The cells 26-connected to a cell standing over ``area`` (xy, grown by a cell)."""
    if len(cells) == 0:
        return cells
    origin = cells.min(axis=0) - 1
    shifted = cells - origin
    grid = np.zeros(shifted.max(axis=0) + 2, dtype=bool)
    grid[tuple(shifted.T)] = True
    labels, _ = cast(
        tuple[np.ndarray, int], ndimage.label(grid, structure=np.ones((3, 3, 3), dtype=bool))
    )
    cell_labels = labels[tuple(shifted.T)]
    centre = (cells[:, :2] + 0.5) * VOXEL_M
    over = (
        (centre[:, 0] >= area.x_min - VOXEL_M)
        & (centre[:, 0] <= area.x_max + VOXEL_M)
        & (centre[:, 1] >= area.y_min - VOXEL_M)
        & (centre[:, 1] <= area.y_max + VOXEL_M)
    )
    return cells[np.isin(cell_labels, np.unique(cell_labels[over]))]


def chair_extent(
    frame: RGBDFrame | Sequence[RGBDFrame] | None,
    volume: tuple[np.ndarray, np.ndarray] = CHAIR_VOLUME,
    margin_m: float = HIDDEN_MARGIN_M,
    area: Box2D = DEFAULT_ARENA.chair_area,
    wide: tuple[np.ndarray, np.ndarray] | None = LOOK_VOLUME,
) -> ChairExtent:
    """The box holding what the frames see above the floor inside ``volume``, and whatever
    seen inside ``wide`` is connected to what stands over the chair area (a sofa reaching
    beyond the volume), grown by ``margin_m`` (the floor stays the bottom); the whole
    volume when nothing is seen."""
    lower, upper = (np.asarray(v, float) for v in volume)
    frames = [] if frame is None else [frame] if isinstance(frame, RGBDFrame) else list(frame)
    cells, _ = _occupied_cells(frames, lower, upper)
    if wide is not None and frames:
        wide_cells, _ = _occupied_cells(frames, *(np.asarray(v, float) for v in wide))
        connected = _connected_to_area(wide_cells, area)
        cells = np.concatenate([cells, connected]) if len(connected) else cells
    if len(cells) == 0:
        return ChairExtent(lower, upper, "volume")
    seen_lower = cells.min(axis=0) * VOXEL_M - margin_m
    seen_upper = (cells.max(axis=0) + 1) * VOXEL_M + margin_m
    seen_lower[2] = lower[2]
    return ChairExtent(seen_lower, seen_upper, "seen")


def cut_sides(
    frame: RGBDFrame,
    area: Box2D = DEFAULT_ARENA.chair_area,
    wide: tuple[np.ndarray, np.ndarray] = LOOK_VOLUME,
    border_px: int = BORDER_PX,
) -> tuple[bool, bool]:
    """(left, right): whether the object standing over the chair area runs into the
    image's left or right edge in ``frame`` (it goes on beyond what this view sees)."""
    cells, (pixel_cells,) = _occupied_cells([frame], *(np.asarray(v, float) for v in wide))
    connected = _connected_to_area(cells, area)
    if len(connected) == 0:
        return False, False
    width = frame.intrinsics.width
    on_object = _rows_in(pixel_cells, connected).reshape(frame.intrinsics.height, width)
    return bool(on_object[:, :border_px].any()), bool(on_object[:, width - border_px :].any())


def _rows_in(rows: np.ndarray, members: np.ndarray) -> np.ndarray:
    """Which rows of ``rows`` (N, 3 ints) are rows of ``members``."""
    lowest = np.minimum(members.min(axis=0), 0)
    span = np.maximum(members.max(axis=0), 0) - lowest + 1
    inside = np.all((rows >= lowest) & (rows < lowest + span), axis=1)
    keys = np.full(len(rows), -1, dtype=np.int64)
    shifted = rows[inside] - lowest
    keys[inside] = (shifted[:, 0] * span[1] + shifted[:, 1]) * span[2] + shifted[:, 2]
    wanted = members - lowest
    member_keys = (wanted[:, 0] * span[1] + wanted[:, 1]) * span[2] + wanted[:, 2]
    return inside & np.isin(keys, member_keys)


class ArmClearance:
    """Distances between the Panda's links and a box, by forward kinematics in pybullet.

    The arm's base stands at the world origin (as in :data:`bearchair.core.arena.DEFAULT_ARENA`).
    Owns a DIRECT pybullet client: call :meth:`close` (or use ``with``).
    """

    def __init__(self) -> None:
        from bearchair.skills.perception.panda_kinematics import PandaKinematics

        self._kinematics = PandaKinematics()
        self._box: int | None = None

    def __enter__(self) -> ArmClearance:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Disconnects the pybullet client."""
        self._kinematics.close()

    @property
    def kinematics(self) -> PandaKinematics:
        """The arm model the queries use (its joints are those of the last query)."""
        return self._kinematics

    def set_box(self, lower: np.ndarray, upper: np.ndarray) -> None:
        """The obstacle (world box, metres) the following queries measure against."""
        import pybullet

        client = self._kinematics.client
        if self._box is not None:
            pybullet.removeBody(self._box, physicsClientId=client)
        half = np.maximum((np.asarray(upper) - np.asarray(lower)) / 2.0, 1e-3)
        shape = pybullet.createCollisionShape(
            pybullet.GEOM_BOX, halfExtents=half.tolist(), physicsClientId=client
        )
        centre = (np.asarray(upper) + np.asarray(lower)) / 2.0
        self._box = pybullet.createMultiBody(
            0, shape, basePosition=centre.tolist(), physicsClientId=client
        )

    def clearance(self, joints_rad: Sequence[float], reach_m: float = 0.3) -> float:
        """Smallest distance (metres, negative inside) from the arm's links to the box;
        ``reach_m`` when farther than that."""
        import pybullet

        assert self._box is not None, "set_box first"
        kin = self._kinematics
        kin.set_joints(joints_rad)
        closest = pybullet.getClosestPoints(
            kin.robot, self._box, reach_m, physicsClientId=kin.client
        )
        # The base link (-1) and link 0 stand on the floor beside the chair area.
        distances = [c[8] for c in closest if c[3] >= 1]
        return min(distances, default=reach_m)

    def path_clearance(self, start_rad: Sequence[float], end_rad: Sequence[float]) -> float:
        """Smallest clearance along the straight joint-space motion from start to end."""
        start, end = np.asarray(start_rad, float), np.asarray(end_rad, float)
        steps = max(2, math.ceil(float(np.max(np.abs(end - start))) / PATH_STEP_RAD) + 1)
        return min(self.clearance(start + f * (end - start)) for f in np.linspace(0.0, 1.0, steps))

    def aim_error_deg(self, joints_rad: Sequence[float], target: np.ndarray) -> float:
        """Angle between the camera's optical axis and the ray from its eye to ``target``."""
        T = self._kinematics.camera_pose(joints_rad)
        ray = np.asarray(target, float) - T[:3, 3]
        cosine = float(T[:3, 2] @ ray / max(np.linalg.norm(ray), 1e-9))
        return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))


class PlannedView(NamedTuple):
    """One scan view as it will be visited.

    Attributes:
        index: the view's index in the list planned.
        joints: the configuration visited (the view's own, or its replacement).
        via_home: move to HOME first (the direct motion would pass too close).
        status: ``kept``, ``via_home``, ``replaced`` or ``skipped``.
        clearance_m: the smallest clearance of the motion into it (metres).
    """

    index: int
    joints: tuple[float, ...]
    via_home: bool
    status: str
    clearance_m: float


def plan_views(
    views: Sequence[Sequence[float]],
    extent: ChairExtent,
    clearance: ArmClearance,
    min_clearance_m: float = VIEW_CLEARANCE_M,
    home: Sequence[float] = HOME_CONFIGURATION,
) -> list[PlannedView]:
    """Checks every view (in visiting order, starting at HOME) against the chair's extent."""
    clearance.set_box(extent.lower, extent.upper)
    home = tuple(float(v) for v in home)
    target = (extent.lower + extent.upper) / 2.0
    planned: list[PlannedView] = []
    current = home
    for index, view in enumerate(views):
        view = tuple(float(v) for v in view)
        direct = clearance.path_clearance(current, view)
        if direct >= min_clearance_m:
            planned.append(PlannedView(index, view, False, "kept", direct))
            current = view
            continue
        from_home = clearance.path_clearance(home, view) if current != home else direct
        if from_home >= min_clearance_m:
            planned.append(PlannedView(index, view, True, "via_home", from_home))
            current = view
            continue
        replacement = None
        for fraction in REPLACEMENT_FRACTIONS:
            joints = tuple(h + fraction * (v - h) for h, v in zip(home, view, strict=True))
            path = clearance.path_clearance(home, joints)
            if (
                path >= min_clearance_m
                and clearance.aim_error_deg(joints, target) <= MAX_AIM_ERROR_DEG
            ):
                replacement = PlannedView(index, joints, True, "replaced", path)
                break
        if replacement is not None:
            planned.append(replacement)
            current = replacement.joints
        else:
            planned.append(PlannedView(index, view, False, "skipped", min(direct, from_home)))
    return planned
