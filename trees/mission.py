"""The mission tree: put the bear on the chair.

.. code-block:: text

    [-] Put the bear on the chair                      Sequence (memory)
        --> ScanChair
        --> ImagineSitting
        --> CheckSeatReachable                         refuses a seat no stance reaches
        [o] MakeChairAccessible                        Selector (memory)
            --> CheckAccessibility
            (-) Up to 3 rotations                      Retry (3 failures)
                [-] Ask the helper to rotate the chair Sequence (memory)
                    --> InstructHelper
                    --> WaitUntilChairStill
                    --> MeasureChairRotation
                    --> CheckAccessibilityAgain
            --> GiveUp
        --> WalkToChair
        --> SeatBear
        --> ReleaseAndStand

Nothing here touches hardware: skills and robots arrive at
``tree.setup(skills=..., robot=...)``, so the tree renders offline
(``py-trees-render trees.mission.create_tree``).
"""

from __future__ import annotations

import py_trees

from behaviours import keys
from behaviours.accessibility import CheckAccessibility, CheckSeatReachable
from behaviours.assistance import GiveUp, InstructHelper, MeasureChairRotation, WaitUntilChairStill
from behaviours.imagine import ImagineSitting
from behaviours.scan import ScanChair
from behaviours.seat import ReleaseAndStand, SeatBear
from behaviours.walk import WalkToChair

STAGES = (
    "ScanChair",
    "ImagineSitting",
    "CheckSeatReachable",
    "MakeChairAccessible",
    "WalkToChair",
    "SeatBear",
    "ReleaseAndStand",
)
"""The mission's stages: the names of the root's children, in order."""


def create_assistance_loop(max_rotations: int = keys.MAX_ROTATIONS) -> py_trees.behaviour.Behaviour:
    """The human-assistance loop: check, then ask for up to ``max_rotations`` rotations."""
    ask_once = py_trees.composites.Sequence(
        name="Ask the helper to rotate the chair",
        memory=True,
        children=[
            InstructHelper(),
            WaitUntilChairStill(),
            MeasureChairRotation(),
            CheckAccessibility(name="CheckAccessibilityAgain"),
        ],
    )
    return py_trees.composites.Selector(
        name="MakeChairAccessible",
        memory=True,
        children=[
            CheckAccessibility(),
            py_trees.decorators.Retry(
                name=f"Up to {max_rotations} rotations", child=ask_once, num_failures=max_rotations
            ),
            GiveUp(),
        ],
    )


def create_tree() -> py_trees.behaviour.Behaviour:
    """Builds the whole mission tree (no hardware needed)."""
    return py_trees.composites.Sequence(
        name="Put the bear on the chair",
        memory=True,
        children=[
            ScanChair(),
            ImagineSitting(),
            CheckSeatReachable(),
            create_assistance_loop(),
            WalkToChair(),
            SeatBear(),
            ReleaseAndStand(),
        ],
    )
