"""Procedural children's chairs: seeded, no data files, with their ground truth.

Chairs the project has never seen judge the mission; this module makes as many as a
test or a benchmark needs, over the ranges children's chairs come in (seats 0.18-0.45 m
high, 0.22-0.38 m deep, stools and benches without a back). Each chair is a union of
boxes and cylinders (separate shells, not boolean-merged, like many real meshes) in the
calibration meshes' frame: z up, metres, centred in x and y, lowest point at z = 0,
sitting direction +x (the backrest, if any, at -x).

Families (:data:`FAMILIES`):

* ``four_legs``: square seat on four legs, straight or reclined backrest;
* ``armchair``: four legs, backrest and armrests;
* ``round``: round seat on four legs with a backrest (near-symmetric from above);
* ``sled``: seat on two floor runners joined by uprights (a cantilever school chair);
* ``pedestal``: seat on a central column and a round foot;
* ``box_base``: seat on a closed box down to the floor (a plastic toddler chair);
* ``footrest``: four legs and a footrest bar sticking out in front (a high chair);
* ``stool``: round or square seat, no back;
* ``bench``: a wide seat, no back;
* and :mod:`bearchair.testing.chairgen_families`' real chairs' harder shapes: ``x_frame``
  (folding, sling seat, armrest rails), ``basket`` (dished round seat), ``swivel_tub``,
  ``rocking``, ``small_plain`` (0.20-0.30 m wide seats), ``lounge`` (deep, low,
  reclined), ``slatted``, ``spindle_back``, ``sofa``.

Usage::

    chair = generate_chair(seed=3)               # a random family
    chair = generate_chair(seed=3, family="sled")
    chair.mesh, chair.seat_height_m, chair.front_yaw_rad
"""

from __future__ import annotations

import math
from typing import NamedTuple, cast

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose, transform_points, yaw_of
from bearchair.testing.chairgen_families import FAMILY_SEATS, ROUND_FAMILIES, family_parts

FAMILIES: tuple[str, ...] = (
    "four_legs",
    "armchair",
    "round",
    "sled",
    "pedestal",
    "box_base",
    "footrest",
    "stool",
    "bench",
    *FAMILY_SEATS,
)
"""Every family :func:`generate_chair` makes (the harder shapes of real chairs from
:mod:`bearchair.testing.chairgen_families` last)."""

SEAT_HEIGHT_RANGE_M = (0.18, 0.45)
"""Seat heights drawn (metres): children's chairs, and a few beyond the NAO's reach."""


class GeneratedChair(NamedTuple):
    """A generated chair and what is true about it.

    Attributes:
        mesh: the chair, z up, metres, centred in x and y, lowest point at z = 0.
        family: one of :data:`FAMILIES`.
        seed: the seed that made it (same seed and family, same chair).
        front_yaw_rad: the direction a sitter faces, from +x about +z (0 here); None
            where the shape has no front (stools, benches).
        seat_height_m: height of the seat's top.
        seat_depth_m: depth of the seat along the sitting direction (the diameter for a
            round seat).
        seat_width_m: width of the seat across it.
        seat_front_x_m: x of the seat's front edge (the sitter's knees go over it).
        front_protrusion_m: how far anything at or below the seat (feet, runners, a
            footrest) reaches in front of the seat's front edge (0 when nothing does).
    """

    mesh: trimesh.Trimesh
    family: str
    seed: int
    front_yaw_rad: float | None
    seat_height_m: float
    seat_depth_m: float
    seat_width_m: float
    seat_front_x_m: float
    front_protrusion_m: float

    @property
    def name(self) -> str:
        """A file-friendly name: ``gen-<family>-<seed>``."""
        return f"gen-{self.family}-{self.seed:04d}"

    def true_sitting_pose(self, T_world_chair: np.ndarray) -> SittingPose:
        """The middle of the seat's top, facing the front (+x where the chair has none),
        in the world where the chair frame is ``T_world_chair`` (4 x 4, metres).

        The simulated world's chair frame is the mesh's with its x-y box centred and its
        lowest point at z = 0, which the generated mesh already is.
        """
        middle_chair = np.array(
            [self.seat_front_x_m - self.seat_depth_m / 2.0, 0.0, self.seat_height_m]
        )
        position_world = transform_points(T_world_chair, middle_chair[None, :])[0]
        return SittingPose(position_world, yaw_of(T_world_chair) + (self.front_yaw_rad or 0.0))


def _box(
    extents: tuple[float, float, float], centre: tuple[float, float, float]
) -> trimesh.Trimesh:
    return trimesh.creation.box(
        extents=extents, transform=trimesh.transformations.translation_matrix(centre)
    )


def _cylinder(radius: float, z_low: float, z_high: float, xy=(0.0, 0.0)) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(
        radius=radius,
        height=z_high - z_low,
        sections=32,
        transform=trimesh.transformations.translation_matrix(
            (xy[0], xy[1], 0.5 * (z_low + z_high))
        ),
    )


def _backrest(
    rng: np.random.Generator, seat_top: float, back_x: float, width: float
) -> list[trimesh.Trimesh]:
    """A backrest panel standing on the seat's back edge, reclined 0-20 deg backwards."""
    height = float(rng.uniform(0.15, 0.32))
    thickness = float(rng.uniform(0.02, 0.04))
    recline = math.radians(float(rng.choice([0.0, rng.uniform(5.0, 20.0)])))
    panel = _box((thickness, width, height), (0.0, 0.0, height / 2.0))
    # Tilt about the panel's bottom front edge so that it leans away from the sitter.
    panel.apply_transform(trimesh.transformations.rotation_matrix(-recline, (0, 1, 0)))
    panel.apply_translation((back_x + thickness / 2.0, 0.0, seat_top))
    return [panel]


def _four_legs(
    rng: np.random.Generator, seat_bottom: float, depth: float, width: float, inset: float
) -> list[trimesh.Trimesh]:
    side = float(rng.uniform(0.02, 0.04))
    return [
        _box(
            (side, side, seat_bottom),
            (
                sx * (depth / 2.0 - inset - side / 2.0),
                sy * (width / 2.0 - inset - side / 2.0),
                seat_bottom / 2.0,
            ),
        )
        for sx in (-1.0, 1.0)
        for sy in (-1.0, 1.0)
    ]


class _Seat(NamedTuple):
    """The seat drawn for a chair (metres; the seat centred on the origin, +x its front).

    Attributes:
        top: height of the seat's top.
        bottom: height of its underside.
        thickness: top - bottom.
        depth: along x (the diameter for a round seat).
        width: along y.
        round: a round seat (a cylinder), else a box.
    """

    top: float
    bottom: float
    thickness: float
    depth: float
    width: float
    round: bool

    @property
    def front_x(self) -> float:
        return self.depth / 2.0

    @property
    def back_x(self) -> float:
        return -self.depth / 2.0


def generate_chair(seed: int, family: str | None = None) -> GeneratedChair:
    """A random chair of ``family`` (drawn from :data:`FAMILIES` when None).

    Args:
        seed: the random seed; the same seed and family give the same chair.
        family: one of :data:`FAMILIES`, or None for a seeded choice.

    Raises:
        ValueError: an unknown family.
    """
    # The draws below come in one fixed order per family: the seed's chair stays the same.
    rng = np.random.default_rng(seed)
    if family is None:
        family = str(rng.choice(FAMILIES))
    if family not in FAMILIES:
        raise ValueError(f"unknown chair family {family!r} (known: {', '.join(FAMILIES)})")
    if family in FAMILY_SEATS:
        return _harder_shape(rng, family, seed)
    seat = _draw_seat(rng, family)
    if seat.round:
        parts = [_cylinder(seat.depth / 2.0, seat.bottom, seat.top)]
    else:
        parts = [
            _box(
                (seat.depth, seat.width, seat.thickness),
                (0.0, 0.0, seat.bottom + seat.thickness / 2.0),
            )
        ]
    base, protrusion = _base(rng, family, seat)
    parts += base
    if family == "footrest":
        footrest, protrusion = _footrest(rng, seat)
        parts += footrest
    front_yaw: float | None = 0.0
    if family in ("stool", "bench"):
        front_yaw = None
    else:
        parts += _backrest(rng, seat.top, seat.back_x, seat.width)
    if family == "armchair":
        parts += _armrests(rng, seat)
    return _placed(parts, family, seed, front_yaw, seat, protrusion)


def _draw_seat(rng: np.random.Generator, family: str) -> _Seat:
    """The seat's height, thickness, depth and width, and whether it is round."""
    seat_top = float(rng.uniform(*SEAT_HEIGHT_RANGE_M))
    thickness = float(rng.uniform(0.02, 0.05))
    seat_bottom = seat_top - thickness
    depth = float(rng.uniform(0.22, 0.38))
    width = float(rng.uniform(0.26, 0.42))
    round_seat = family == "round" or (family in ("stool", "pedestal") and rng.random() < 0.5)
    if family == "bench":
        width = float(rng.uniform(0.5, 0.8))
    if round_seat:
        width = depth
    return _Seat(seat_top, seat_bottom, thickness, depth, width, round_seat)


def _harder_shape(rng: np.random.Generator, family: str, seed: int) -> GeneratedChair:
    """A chair of one of :data:`FAMILY_SEATS`' families (its own seat ranges)."""
    heights, depths, widths = FAMILY_SEATS[family]
    top = float(rng.uniform(*heights))
    thickness = float(rng.uniform(0.02, 0.04))
    depth = float(rng.uniform(*depths))
    round_seat = family in ROUND_FAMILIES
    width = depth if round_seat else float(rng.uniform(*widths))
    seat = _Seat(top, top - thickness, thickness, depth, width, round_seat)
    parts = family_parts(rng, family, seat)
    low = np.concatenate([part.vertices for part in parts])
    low = low[low[:, 2] < seat.top - 0.05]
    protrusion = max(0.0, float(low[:, 0].max()) - seat.front_x) if len(low) else 0.0
    return _placed(parts, family, seed, 0.0, seat, protrusion)


def _base(
    rng: np.random.Generator, family: str, seat: _Seat
) -> tuple[list[trimesh.Trimesh], float]:
    """What holds the seat up: legs, runners, a column and foot, or a closed box.

    Returns:
        (the parts, how far they reach in front of the seat's front edge in metres).
    """
    parts: list[trimesh.Trimesh] = []
    protrusion = 0.0
    seat_bottom, depth, width = seat.bottom, seat.depth, seat.width
    if family in ("four_legs", "armchair", "round", "footrest", "bench"):
        inset = 0.0 if seat.round else float(rng.uniform(0.0, 0.03))
        # Legs of a round seat stand inside its circle.
        leg_depth, leg_width = (depth / math.sqrt(2.0),) * 2 if seat.round else (depth, width)
        parts += _four_legs(rng, seat_bottom, leg_depth, leg_width, inset)
    elif family == "sled":
        runner_length = depth + float(rng.uniform(0.0, 0.08))
        runner_x = float(rng.uniform(-0.02, 0.04))
        for sy in (-1.0, 1.0):
            y = sy * (width / 2.0 - 0.02)
            parts.append(_box((runner_length, 0.025, 0.02), (runner_x, y, 0.01)))
            for x in (seat.back_x + 0.03, seat.front_x - 0.03):
                parts.append(_box((0.025, 0.025, seat_bottom), (x, y, seat_bottom / 2.0)))
        protrusion = max(0.0, runner_x + runner_length / 2.0 - seat.front_x)
    elif family in ("pedestal", "stool"):
        column = float(rng.uniform(0.025, 0.05))
        foot = float(rng.uniform(0.12, min(0.2, depth / 2.0 + 0.02)))
        if family == "stool" and rng.random() < 0.5:
            parts += _four_legs(rng, seat_bottom, depth * 0.8, width * 0.8, 0.0)
        else:
            parts.append(_cylinder(column, 0.02, seat_bottom))
            parts.append(_cylinder(foot, 0.0, 0.02))
            protrusion = max(0.0, foot - seat.front_x)
    elif family == "box_base":
        parts.append(_box((depth * 0.9, width * 0.9, seat_bottom), (0.0, 0.0, seat_bottom / 2.0)))
    return parts, protrusion


def _footrest(rng: np.random.Generator, seat: _Seat) -> tuple[list[trimesh.Trimesh], float]:
    """A bar in front of the seat on two side rails (a high chair's).

    Returns:
        (the parts, how far they reach in front of the seat's front edge in metres).
    """
    reach = float(rng.uniform(0.04, 0.12))
    bar_z = float(rng.uniform(0.06, max(0.07, seat.top - 0.12)))
    parts = [_box((0.02, seat.width, 0.02), (seat.front_x + reach, 0.0, bar_z))]
    for sy in (-1.0, 1.0):
        parts.append(
            _box(
                (reach, 0.02, 0.02),
                (seat.front_x + reach / 2.0, sy * (seat.width / 2.0 - 0.01), bar_z),
            )
        )
    return parts, reach + 0.01


def _armrests(rng: np.random.Generator, seat: _Seat) -> list[trimesh.Trimesh]:
    """Two armrest panels along the seat's sides, 10-18 cm high."""
    arm_height = float(rng.uniform(0.10, 0.18))
    return [
        _box(
            (seat.depth, 0.03, arm_height),
            (0.0, sy * (seat.width / 2.0 - 0.015), seat.top + arm_height / 2.0),
        )
        for sy in (-1.0, 1.0)
    ]


def _placed(
    parts: list[trimesh.Trimesh],
    family: str,
    seed: int,
    front_yaw: float | None,
    seat: _Seat,
    protrusion: float,
) -> GeneratedChair:
    """The parts as one mesh in the calibration meshes' frame, with the truth about it."""
    mesh = cast(trimesh.Trimesh, trimesh.util.concatenate(parts))
    # The calibration meshes' frame: centred in x and y, lowest point at z = 0.
    centre = mesh.bounds.mean(axis=0)
    shift = np.array([-centre[0], -centre[1], -mesh.bounds[0, 2]])
    mesh.apply_translation(shift)
    return GeneratedChair(
        mesh=mesh,
        family=family,
        seed=seed,
        front_yaw_rad=front_yaw,
        seat_height_m=seat.top + float(shift[2]),
        seat_depth_m=seat.depth,
        seat_width_m=seat.width,
        seat_front_x_m=seat.front_x + float(shift[0]),
        front_protrusion_m=protrusion,
    )


def generate_chairs(count: int, seed: int = 0) -> list[GeneratedChair]:
    """``count`` chairs cycling through :data:`FAMILIES`, chair i seeded ``seed + i``."""
    return [generate_chair(seed + i, FAMILIES[i % len(FAMILIES)]) for i in range(count)]
