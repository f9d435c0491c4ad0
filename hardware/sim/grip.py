"""How far apart the NAO's palms are while they hold the bear: a grip no one feels here.

The simulated bear is held by a constraint to the frame between the palms
(:mod:`bearchair.hardware.sim.bear`), so it stays in the hands however far apart they
move. A real NAO holds the bear between its palms (:mod:`bearchair.core.nao_carrying`:
about 0.14 m apart on a 0.10 m torso), and palms that move apart let it go. The monitor
runs before every physics step and keeps the widest the palms were while the bear was
held, so a run whose motion would have dropped a real bear says so in its ground truth.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from bearchair.core.geometry import make_transform
from bearchair.core.nao_carrying import PALM_IN_WRIST_M

T_WRIST_PALM = make_transform(np.eye(3), np.asarray(PALM_IN_WRIST_M))
"""The palm's frame in the ``l_wrist`` / ``r_wrist`` link frames."""


class _Nao(Protocol):
    posture_count: int

    def T_world_link(self, link_name: str) -> np.ndarray: ...


class _Bear(Protocol):
    @property
    def held(self) -> bool: ...


class PalmsApart(NamedTuple):
    """How far apart the palms' centres were while holding the bear (metres; 0 before
    the first step held).

    Attributes:
        handed_over_m: when the hold began (the carrying posture's grip).
        widest_m: the widest while held.
        time_s: simulated time they were first that wide.
    """

    handed_over_m: float = 0.0
    widest_m: float = 0.0
    time_s: float = 0.0


class PalmsApartMonitor:
    """A clock process (``monitor(now_s, dt_s)``) recording :class:`PalmsApart`.

    Args:
        nao: the simulated NAO (its links' poses; ``posture_count`` goes up whenever its
            joints may have moved, and the palms are measured again only then).
        bear: the simulated bear (whether it is held).
    """

    def __init__(self, nao: _Nao, bear: _Bear) -> None:
        self._nao = nao
        self._bear = bear
        self._measured_at: int | None = None
        self.widest = PalmsApart()

    def __call__(self, now_s: float, dt_s: float) -> None:
        count = self._nao.posture_count
        if not self._bear.held or count == self._measured_at:
            return
        self._measured_at = count
        left, right = (
            (self._nao.T_world_link(link) @ T_WRIST_PALM)[:3, 3] for link in ("l_wrist", "r_wrist")
        )
        distance_m = float(np.linalg.norm(left - right))
        if self.widest.handed_over_m == 0.0:
            self.widest = PalmsApart(distance_m, distance_m, now_s)
        elif distance_m > self.widest.widest_m:
            self.widest = self.widest._replace(widest_m=distance_m, time_s=now_s)
