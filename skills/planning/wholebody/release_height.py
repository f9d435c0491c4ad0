"""How high over the seat the goal posture lets the bear go: 1 cm, or higher over a low seat.

Over most seats the bear's seat point is let go r(h) = h + c over a seat top at h (c is
``BEAR_SEAT_CLEARANCE_M``). A NAO that holds the bear that low over a low seat must
crouch, and a crouching NAO reaches far less forward than one bent at the hips: its knees
stand where the bear would go. The free reach d(r), the farthest forward a goal posture
holds the bear's base at height r with nothing under it, jumps where the postures change
(on the planar model from 0.236 m at r = 0.1825 m to 0.294 m at 0.185 m); z_hip lies
``HIP_POSTURE_MARGIN_M`` above the jump (0.1975 m), and no posture holds the bear below
the deepest crouch's z_low (0.1675 m). So, with G ``LOW_SEAT_RELEASE_GAP_M``:

.. math::

    r(h) = \\begin{cases}
        h + c & h + c \\ge z_{hip} \\\\
        z_{hip} & z_{hip} - h \\le G \\\\
        \\max(h + c, z_{low}) & \\max(h + c, z_{low}) - h \\le G \\\\
        \\text{none} & \\text{otherwise.}
    \\end{cases}

The bear drops at most G more than over other seats, and only where that buys the
bent-hip postures' reach (0.30 m against the crouch's 0.22 m).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from bearchair.core.nao_carrying import BEAR_SEAT_CLEARANCE_M, LOW_SEAT_RELEASE_GAP_M

HIP_POSTURE_MARGIN_M = 0.0125
"""z_hip lies this far (metres) above the lowest height of the bent-hip postures: there they
hold the bear only at their farthest reach, while the goal must hold it at the forward
distance the stance search asks. Measured with the goal on box chairs in front of the NAO
(seat fronts 0.12-0.22 m ahead, the bear 0.5-8 cm short of the farthest reach): at the
lowest height plus 0.75 cm one distance in five failed, by 1 mm of height or the centre
of mass; at plus 1.25 cm none did (docs/decisions.md)."""
FREE_REACH_HEIGHTS_M = np.round(np.arange(0.15, 0.3001, 0.0025), 4)
"""The release heights r (metres) at which the free reach d(r) is solved; above the grid
every seat gets r(h) = h + c (the bent-hip postures reach there)."""


class ReleaseHeights(NamedTuple):
    """The free reach d(r) and the release height rule r(h) (see the module doc).

    Attributes:
        heights_m: (R,) release heights r, metres.
        free_reach_m: (R,) d(r), metres; NaN where no posture holds the bear that low.
    """

    heights_m: np.ndarray
    free_reach_m: np.ndarray

    def release_height_m(self, seat_height_m: float) -> float:
        """r(h) (metres) over a seat top at ``seat_height_m``; NaN: the NAO cannot hold
        the bear within ``LOW_SEAT_RELEASE_GAP_M`` of it."""
        usual = seat_height_m + BEAR_SEAT_CLEARANCE_M
        if len(self.heights_m) == 0 or usual >= self.hip_height_m:
            return usual
        if self.hip_height_m - seat_height_m <= LOW_SEAT_RELEASE_GAP_M + 1e-9:
            return self.hip_height_m
        crouch = max(usual, self.lowest_height_m)
        return crouch if crouch - seat_height_m <= LOW_SEAT_RELEASE_GAP_M + 1e-9 else math.nan

    @property
    def lowest_height_m(self) -> float:
        """z_low (metres): the lowest height any posture holds the bear's base at."""
        feasible = ~np.isnan(self.free_reach_m)
        return float(self.heights_m[feasible][0]) if feasible.any() else math.inf

    @property
    def hip_height_m(self) -> float:
        """z_hip (metres): ``HIP_POSTURE_MARGIN_M`` above the lowest height of the bent-hip
        postures, where the free reach jumps most between two heights."""
        jumps = np.diff(np.nan_to_num(self.free_reach_m, nan=0.0))
        jumps[np.isnan(self.free_reach_m[:-1])] = -math.inf  # not from no posture at all
        return float(self.heights_m[int(np.argmax(jumps)) + 1]) + HIP_POSTURE_MARGIN_M

    def to_json(self) -> dict:
        return {
            "heights_m": self.heights_m.tolist(),
            "free_reach_m": [
                None if math.isnan(v) else round(float(v), 4) for v in self.free_reach_m
            ],
        }

    @classmethod
    def from_json(cls, data: dict) -> ReleaseHeights:
        return cls(
            np.array(data["heights_m"], dtype=float),
            np.array([math.nan if v is None else float(v) for v in data["free_reach_m"]]),
        )


NO_LOW_SEATS = ReleaseHeights(np.zeros(0), np.zeros(0))
"""r(h) = h + c everywhere (a model without the free reach)."""


def compute_release_heights(free_reach: Callable[[float], float]) -> ReleaseHeights:
    """d(r) over :data:`FREE_REACH_HEIGHTS_M` from ``free_reach`` (metres -> metres, NaN:
    no posture). The lowest feasible height is dropped: a solve accepts a base up to 2 mm
    off the height asked, so the next one up is the first a goal surely reaches."""
    reach = np.array([free_reach(float(r)) for r in FREE_REACH_HEIGHTS_M])
    feasible = np.flatnonzero(~np.isnan(reach))
    if len(feasible):
        reach[feasible[0]] = math.nan
    return ReleaseHeights(FREE_REACH_HEIGHTS_M.copy(), reach)
