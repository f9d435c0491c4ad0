"""How deep the NAO went into the chair: contacts that neither body feels in this world.

The NAO's joints are kinematic and the chair is static (:mod:`bearchair.hardware.sim.chair`), so
a NAO that walks or reaches into the chair passes through it instead of pushing it. The
monitor runs before every physics step and keeps the deepest NAO-chair contact, so a run
that ought to have bumped the chair says so in its ground truth.
"""

from __future__ import annotations

from typing import NamedTuple

from bearchair.hardware.sim.bullet import LockedBullet


class ChairTouch(NamedTuple):
    """The deepest NAO-chair contact so far.

    Attributes:
        depth_m: penetration depth in metres (0 when they never touched).
        nao_link: the NAO link that went deepest ("" when they never touched).
        time_s: simulated time of that contact.
    """

    depth_m: float = 0.0
    nao_link: str = ""
    time_s: float = 0.0


class ChairTouchMonitor:
    """A clock process (``monitor(now_s, dt_s)``) recording :class:`ChairTouch`.

    Args:
        bullet: the world's client.
        nao_body, chair_body: the two bodies.
        link_names: the NAO's link index -> name.
    """

    def __init__(
        self, bullet: LockedBullet, nao_body: int, chair_body: int, link_names: dict[int, str]
    ) -> None:
        self._bullet = bullet
        self._nao = nao_body
        self._chair = chair_body
        self._link_names = link_names
        self.deepest = ChairTouch()

    def __call__(self, now_s: float, dt_s: float) -> None:
        # The contacts of the step just taken: reading them costs nothing extra.
        for contact in self._bullet.getContactPoints(bodyA=self._nao, bodyB=self._chair):
            depth_m = -float(contact[8])
            if depth_m > self.deepest.depth_m:
                link = self._link_names.get(int(contact[3]), str(contact[3]))
                self.deepest = ChairTouch(depth_m, link, now_s)
