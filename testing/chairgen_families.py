"""The generator's families of real chairs' harder shapes (see :mod:`bearchair.testing.chairgen`).

Each builds its parts around a seat centred on the origin, +x its front, its top at
``seat.top`` just behind the front edge (the first surface a sitter's thighs meet):

* ``x_frame``: a folding chair: two crossed bars on each side, a sling seat that sags
  between its front and back rails, armrest rails on the crosses' tops;
* ``basket``: a round seat dishing down inside its rim, a wrap-around back, four legs;
* ``swivel_tub``: a round seat on a column and a five-armed star foot, a tub back
  wrapping round to armrests at the sides;
* ``rocking``: four legs on two curved runners, a backrest;
* ``small_plain``: a small seat (0.20-0.30 m wide) on four legs with a backrest;
* ``lounge``: a deep, low seat on a closed base with a back reclined 20-35 deg;
* ``slatted``: a seat of slats across with gaps between them, four legs, a backrest;
* ``spindle_back``: a seat on four legs whose back is a row of thin spindles under a rail;
* ``sofa``: a wide seat on a closed base with a thick back cushion and armrests.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
import trimesh


class _Seat(Protocol):
    """The seat drawn for a chair (``bearchair.testing.chairgen``'s, metres)."""

    @property
    def top(self) -> float: ...
    @property
    def thickness(self) -> float: ...
    @property
    def depth(self) -> float: ...
    @property
    def width(self) -> float: ...
    @property
    def front_x(self) -> float: ...
    @property
    def back_x(self) -> float: ...


FAMILY_SEATS: dict[str, tuple[tuple[float, float], tuple[float, float], tuple[float, float]]] = {
    "x_frame": ((0.22, 0.40), (0.26, 0.34), (0.30, 0.40)),
    "basket": ((0.20, 0.38), (0.32, 0.40), (0.32, 0.40)),
    "swivel_tub": ((0.22, 0.40), (0.28, 0.36), (0.28, 0.36)),
    "rocking": ((0.20, 0.38), (0.24, 0.34), (0.28, 0.38)),
    "small_plain": ((0.18, 0.34), (0.20, 0.28), (0.20, 0.30)),
    "lounge": ((0.18, 0.26), (0.36, 0.48), (0.34, 0.46)),
    "slatted": ((0.20, 0.40), (0.24, 0.36), (0.28, 0.40)),
    "spindle_back": ((0.20, 0.40), (0.24, 0.34), (0.26, 0.38)),
    "sofa": ((0.18, 0.32), (0.30, 0.42), (0.60, 0.90)),
}
"""Family -> (seat top height, depth, width) ranges (metres)."""
ROUND_FAMILIES = ("basket", "swivel_tub")


def box(extents, centre, rotation_y_rad: float = 0.0) -> trimesh.Trimesh:
    """A box of ``extents`` centred at ``centre``, turned about its own y axis."""
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(rotation_y_rad, (0, 1, 0)))
    mesh.apply_translation(centre)
    return mesh


def cylinder(radius: float, z_low: float, z_high: float, xy=(0.0, 0.0)) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(
        radius=radius,
        height=z_high - z_low,
        sections=24,
        transform=trimesh.transformations.translation_matrix((xy[0], xy[1], (z_low + z_high) / 2)),
    )


def arc_wall(
    radius: float, thickness: float, z_low: float, heights, from_deg: float, to_deg: float
) -> list[trimesh.Trimesh]:
    """Boxes standing along a circle (a tub's or basket's wall), ``heights[i]`` tall each,
    from ``from_deg`` to ``to_deg`` (measured from +x, the front)."""
    angles = np.radians(np.linspace(from_deg, to_deg, len(heights) + 1))
    parts = []
    for a0, a1, height in zip(angles[:-1], angles[1:], heights, strict=True):
        middle = 0.5 * (a0 + a1)
        length = 2.0 * radius * math.sin(0.5 * (a1 - a0)) + 0.01
        piece = trimesh.creation.box(extents=(thickness, length, height))
        piece.apply_transform(trimesh.transformations.rotation_matrix(middle, (0, 0, 1)))
        piece.apply_translation(
            (radius * math.cos(middle), radius * math.sin(middle), z_low + height / 2.0)
        )
        parts.append(piece)
    return parts


def legs(rng, seat: _Seat, top_z: float, spread: float = 1.0) -> list[trimesh.Trimesh]:
    side = float(rng.uniform(0.02, 0.035))
    half_x = spread * seat.depth / 2.0 - side / 2.0 - 0.005
    half_y = spread * seat.width / 2.0 - side / 2.0 - 0.005
    return [
        box((side, side, top_z), (sx * half_x, sy * half_y, top_z / 2.0))
        for sx in (-1.0, 1.0)
        for sy in (-1.0, 1.0)
    ]


def panel_back(rng, seat: _Seat, recline_deg: tuple[float, float]) -> list[trimesh.Trimesh]:
    """A backrest panel on the seat's back edge, reclined within ``recline_deg``."""
    height = float(rng.uniform(0.15, 0.30))
    thickness = float(rng.uniform(0.02, 0.04))
    recline = math.radians(float(rng.uniform(*recline_deg)))
    panel = box((thickness, seat.width, height), (0.0, 0.0, height / 2.0), -recline)
    panel.apply_translation((seat.back_x + thickness / 2.0, 0.0, seat.top))
    return [panel]


def family_parts(rng: np.random.Generator, family: str, seat: _Seat) -> list[trimesh.Trimesh]:
    """The parts of a chair of one of :data:`FAMILY_SEATS`' families, seat included."""
    return _BUILDERS[family](rng, seat)


def _plain_seat(seat: _Seat) -> trimesh.Trimesh:
    return box((seat.depth, seat.width, seat.thickness), (0.0, 0.0, seat.top - seat.thickness / 2))


def _x_frame(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    sag = float(rng.uniform(0.01, 0.03))
    flat = 0.06  # the sling lies on its front rail this far back from the front edge
    cloth = 0.006
    middle_depth = seat.depth - 2.0 * flat
    parts = [
        box((flat, seat.width, cloth), (seat.front_x - flat / 2.0, 0.0, seat.top - cloth / 2)),
        box((middle_depth, seat.width, cloth), (0.0, 0.0, seat.top - sag - cloth / 2)),
        box((flat, seat.width, cloth), (seat.back_x + flat / 2.0, 0.0, seat.top - cloth / 2)),
    ]
    arm_height = float(rng.uniform(0.10, 0.18))
    top = seat.top + arm_height
    span = math.hypot(seat.depth, top)
    angle = math.atan2(top, seat.depth)
    for sy in (-1.0, 1.0):
        y = sy * (seat.width / 2.0 + 0.015)
        for sign in (1.0, -1.0):
            parts.append(box((span, 0.02, 0.025), (0.0, y, top / 2.0), sign * angle))
        parts.append(box((seat.depth, 0.03, 0.025), (0.0, y, top)))  # the armrest rail
    parts += panel_back(rng, seat, (5.0, 15.0))
    return parts


def _basket(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    radius = seat.depth / 2.0
    dish = float(rng.uniform(0.015, 0.035))
    rim = float(rng.uniform(0.045, 0.06))
    parts = [
        # The rim: a ring of wall pieces lying flat around the seat, its top at seat.top.
        *arc_wall(radius - rim / 2.0, rim, seat.top - 0.02, [0.02] * 16, 0.0, 360.0),
        cylinder(radius - rim + 0.005, seat.top - dish - seat.thickness, seat.top - dish),
        *legs(rng, seat, seat.top - dish - seat.thickness, spread=1.0 / math.sqrt(2.0)),
    ]
    height = float(rng.uniform(0.16, 0.28))
    parts += arc_wall(radius - 0.015, 0.03, seat.top, [height] * 9, 100.0, 260.0)
    return parts


def _swivel_tub(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    radius = seat.depth / 2.0
    bottom = seat.top - seat.thickness
    parts = [cylinder(radius, bottom, seat.top), cylinder(0.025, 0.03, bottom)]
    foot = float(rng.uniform(0.16, 0.22))
    for k in range(5):
        angle = 2.0 * math.pi * k / 5.0 + math.pi / 5.0
        arm = box((foot, 0.03, 0.03), (foot / 2.0, 0.0, 0.015))
        arm.apply_transform(trimesh.transformations.rotation_matrix(angle, (0, 0, 1)))
        parts.append(arm)
    back = float(rng.uniform(0.16, 0.26))
    arms = float(rng.uniform(0.08, 0.14))
    # Low at the sides (armrests), high behind; open at the front.
    heights = [arms, arms, back * 0.8, back, back, back * 0.8, arms, arms]
    parts += arc_wall(radius - 0.015, 0.03, seat.top, heights, 60.0, 300.0)
    return parts


def _rocking(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    rise = float(rng.uniform(0.03, 0.06))  # the runners' ends above their middle
    lift = 0.03
    parts = [_plain_seat(seat), *legs(rng, seat, seat.top - seat.thickness)]
    length = seat.depth + 0.16
    radius = (length / 2.0) ** 2 / (2.0 * rise) + rise / 2.0
    for sy in (-1.0, 1.0):
        y = sy * (seat.width / 2.0 - 0.02)
        for k in range(8):
            x0 = -length / 2.0 + k * length / 8.0
            x1 = x0 + length / 8.0
            z0, z1 = (radius - math.sqrt(radius**2 - x**2) for x in (x0, x1))
            angle = -math.atan2(z1 - z0, x1 - x0)
            piece = box((math.hypot(x1 - x0, z1 - z0) + 0.004, 0.025, 0.02), (0, 0, 0), angle)
            piece.apply_translation((0.5 * (x0 + x1), y, lift + 0.5 * (z0 + z1)))
            parts.append(piece)
    parts += panel_back(rng, seat, (5.0, 15.0))
    return parts


def _small_plain(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    back = panel_back(rng, seat, (0.0, 12.0))
    return [_plain_seat(seat), *legs(rng, seat, seat.top - seat.thickness), *back]


def _lounge(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    base = seat.top - seat.thickness
    return [
        _plain_seat(seat),
        box((seat.depth * 0.9, seat.width * 0.9, base), (0.0, 0.0, base / 2.0)),
        *panel_back(rng, seat, (20.0, 35.0)),
    ]


def _slatted(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    count = int(rng.integers(4, 7))
    gap = float(rng.uniform(0.01, 0.025))
    slat = (seat.depth - (count - 1) * gap) / count
    parts = [
        box(
            (slat, seat.width, seat.thickness),
            (seat.front_x - slat / 2.0 - k * (slat + gap), 0.0, seat.top - seat.thickness / 2),
        )
        for k in range(count)
    ]
    for sy in (-1.0, 1.0):  # the side rails the slats lie on
        y = sy * (seat.width / 2.0 - 0.015)
        parts.append(box((seat.depth, 0.03, 0.03), (0.0, y, seat.top - seat.thickness - 0.015)))
    parts += legs(rng, seat, seat.top - seat.thickness - 0.03)
    return parts + panel_back(rng, seat, (0.0, 12.0))


def _spindle_back(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    parts = [_plain_seat(seat), *legs(rng, seat, seat.top - seat.thickness)]
    height = float(rng.uniform(0.18, 0.30))
    count = int(rng.integers(4, 8))
    radius = float(rng.uniform(0.007, 0.012))
    x = seat.back_x + 0.02
    for y in np.linspace(-seat.width / 2.0 + 0.03, seat.width / 2.0 - 0.03, count):
        parts.append(cylinder(radius, seat.top, seat.top + height, (x, float(y))))
    parts.append(box((0.03, seat.width, 0.04), (x, 0.0, seat.top + height)))
    return parts


def _sofa(rng, seat: _Seat) -> list[trimesh.Trimesh]:
    base = seat.top - seat.thickness
    cushion = float(rng.uniform(0.08, 0.15))
    back_height = float(rng.uniform(0.15, 0.25))
    arm_width = float(rng.uniform(0.06, 0.12))
    arm_height = float(rng.uniform(0.06, 0.14))
    parts = [
        _plain_seat(seat),
        box((seat.depth, seat.width, base), (0.0, 0.0, base / 2.0)),
        box(
            (cushion, seat.width + 2 * arm_width, seat.top + back_height),
            (seat.back_x - cushion / 2.0, 0.0, (seat.top + back_height) / 2.0),
        ),
    ]
    for sy in (-1.0, 1.0):
        y = sy * (seat.width / 2.0 + arm_width / 2.0)
        parts.append(
            box(
                (seat.depth, arm_width, seat.top + arm_height),
                (0.0, y, (seat.top + arm_height) / 2.0),
            )
        )
    return parts


_BUILDERS = {
    "x_frame": _x_frame,
    "basket": _basket,
    "swivel_tub": _swivel_tub,
    "rocking": _rocking,
    "small_plain": _small_plain,
    "lounge": _lounge,
    "slatted": _slatted,
    "spindle_back": _spindle_back,
    "sofa": _sofa,
}
