"""What a mission tree may be asked to be: :class:`TreeOptions`, and the factory type.

A tree factory is any callable ``(options: TreeOptions) -> py_trees.behaviour.Behaviour``
(:data:`TreeFactory`): ``bearchair.trees.mission.create_tree`` is one, a plug-in's tree
(the ``bearchair.trees`` entry points, or ``--tree module:factory``) is another. Options
a factory does not understand it may ignore; the mission's own tree honours them all.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeAlias

import py_trees

from bearchair.behaviours import keys

MAX_LOOKS = 3
"""Looks from above the imagination may ask for before its stage fails: each is an arm
motion and a reconstruction (about 1 s in simulation, 10-20 s on the Panda at its scan
speed) and an imagination (3-10 s), so three keep the stage within about a minute."""


@dataclass(frozen=True)
class TreeOptions:
    """How the mission tree is composed.

    Attributes:
        assistance: ask the helper to turn an inaccessible chair (the paper's human
            assistance loop); False: an inaccessible chair fails the mission at once.
        max_rotations: rotations the helper may be asked for before giving up (>= 1).
        rescan_fallback: when ICP cannot measure the turn, scan and imagine the turned
            chair anew; False: an unmeasured turn fails that attempt.
        max_looks: when the imagination finds no sitting on the scan (the first, or a
            turned chair's re-scan), look at the chair from above and imagine again, up
            to this many times; when the scan shows no seat under the sitting point,
            look at it once (0: neither).

    Raises:
        ValueError: ``max_rotations`` is not a whole number of at least 1, or
            ``max_looks`` not one of at least 0.
    """

    assistance: bool = True
    max_rotations: int = keys.MAX_ROTATIONS
    rescan_fallback: bool = True
    max_looks: int = MAX_LOOKS

    def __post_init__(self) -> None:
        for name, least in (("max_rotations", 1), ("max_looks", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                raise ValueError(f"{name}: a whole number >= {least} is needed, got {value!r}")


TreeFactory: TypeAlias = Callable[[TreeOptions], py_trees.behaviour.Behaviour]
"""Builds a mission tree from its options (no hardware: skills and robots come at setup)."""
