"""What a mission tree may be asked to be: :class:`TreeOptions`, and the factory type.

A tree factory is any callable ``(options: TreeOptions) -> py_trees.behaviour.Behaviour``
(:data:`TreeFactory`): ``bearchair.trees.mission.create_tree`` is one, a plug-in's tree
(the ``bearchair.trees`` entry points, or ``--tree module:factory``) is another. Options
a factory does not understand it may ignore; the mission's own tree honours all three.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeAlias

import py_trees

from bearchair.behaviours import keys


@dataclass(frozen=True)
class TreeOptions:
    """How the mission tree is composed.

    Attributes:
        assistance: ask the helper to turn an inaccessible chair (the paper's human
            assistance loop); False: an inaccessible chair fails the mission at once.
        max_rotations: rotations the helper may be asked for before giving up (>= 1).
        rescan_fallback: when ICP cannot measure the turn, scan and imagine the turned
            chair anew; False: an unmeasured turn fails that attempt.

    Raises:
        ValueError: ``max_rotations`` is not a whole number of at least 1.
    """

    assistance: bool = True
    max_rotations: int = keys.MAX_ROTATIONS
    rescan_fallback: bool = True

    def __post_init__(self) -> None:
        rotations = self.max_rotations
        if isinstance(rotations, bool) or not isinstance(rotations, int) or rotations < 1:
            raise ValueError(f"max_rotations: a whole number >= 1 is needed, got {rotations!r}")


TreeFactory: TypeAlias = Callable[[TreeOptions], py_trees.behaviour.Behaviour]
"""Builds a mission tree from its options (no hardware: skills and robots come at setup)."""
