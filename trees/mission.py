"""The mission tree: put the bear on the chair.

.. code-block:: text

    [-] Put the bear on the chair                      Sequence (memory)
        --> ScanChair
        [o] ImagineSitting                             Selector (memory)
            --> ImagineOnScan
            (-) Up to 3 looks                          Retry (3 failures)
                [-] Look again and imagine             Sequence (memory)
                    --> LookFromAbove                  one more view, where none looked from
                    --> ImagineAgain
            --> NoSittingFound                         refuses a chair with no level surface
                                                       at the NAO's seat heights, else fails
        [-] CheckSeatReachable                         Sequence (memory)
            --> LookAtSeat                             one more view, if no seat under p
            --> ImagineOnSeatView                      the sitting again, if a view was added
            --> CheckSeatReachable                     refuses a seat no stance reaches
        [o] MakeChairAccessible                        Selector (memory)
            --> CheckAccessibility
            (-) Up to 3 rotations                      Retry (3 failures)
                [-] Ask the helper to rotate the chair Sequence (memory)
                    --> InstructHelper
                    --> WaitUntilChairStill
                    [o] LocateTurnedChair              Selector (memory)
                        --> MeasureChairRotation       ICP against the chair as it was
                        [-] Scan the turned chair anew Sequence (memory)
                            --> ScanTurnedChair        when no fit is accepted
                            [o] ImagineTurnedChair     as ImagineSitting: ImagineOnTurnedScan,
                                                       then up to 3 of LookAtTurnedChair and
                                                       ImagineTurnedAgain
                    --> CheckAccessibilityAgain
            --> GiveUp
        --> WalkToChair
        --> SeatBear
        --> ReleaseAndStand

Nothing here touches hardware: skills and robots arrive at
``tree.setup(skills=..., robot=...)``, so the tree renders offline
(``py-trees-render bearchair.trees.mission.create_tree``).

:class:`bearchair.trees.options.TreeOptions` varies it: without the assistance,
``MakeChairAccessible`` is the first accessibility check alone (an inaccessible chair
fails the mission); without the re-scan fallback, ``LocateTurnedChair`` is ICP alone; the
retry's count is ``max_rotations``; with ``max_looks`` 0, ``ImagineSitting`` and
``CheckSeatReachable`` are the one leaf each, on the scan. ``create_tree()`` is the tree above.
"""

from __future__ import annotations

import py_trees

from bearchair.behaviours import keys
from bearchair.behaviours.accessibility import CheckAccessibility, CheckSeatReachable
from bearchair.behaviours.assistance import (
    GiveUp,
    InstructHelper,
    MeasureChairRotation,
    WaitUntilChairStill,
)
from bearchair.behaviours.imagine import ImagineOnSeatView, ImagineSitting, NoSittingFound
from bearchair.behaviours.scan import LookAtSeat, LookFromAbove, ScanChair
from bearchair.behaviours.seat import ReleaseAndStand, SeatBear
from bearchair.behaviours.walk import WalkToChair
from bearchair.trees.options import TreeOptions

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


def create_imagination(
    max_looks: int,
    *,
    name: str = "ImagineSitting",
    on_scan_name: str = "ImagineOnScan",
    look_name: str = "LookFromAbove",
    again_name: str = "ImagineAgain",
    after_turn: bool = False,
) -> py_trees.behaviour.Behaviour:
    """The ``ImagineSitting`` stage: the imagination on the scan, and where it finds no
    sitting, up to ``max_looks`` looks at the chair from above, each followed by the
    imagination on the chair reconstructed with it; when all fail, ``NoSittingFound``
    says why, refusing a chair whose level surfaces are all beyond the NAO's seat heights
    (0: the imagination alone, named ``name``). The names let the turned chair's
    re-scan compose the same thing; ``after_turn`` (the turned chair), no ``NoSittingFound``
    follows: the mission goes on to the next turn, so nothing there may refuse it. (A
    sitting found there at another height than before the turn counts as none, for a look
    to follow: ``ImagineSitting``.)"""
    if max_looks == 0:
        return ImagineSitting(name=name)
    on_scan = ImagineSitting(name=on_scan_name)
    again = py_trees.composites.Sequence(
        name="Look again and imagine",
        memory=True,
        children=[
            LookFromAbove(name=look_name, backs_up=on_scan),
            ImagineSitting(name=again_name),
        ],
    )
    return py_trees.composites.Selector(
        name=name,
        memory=True,
        children=[
            on_scan,
            py_trees.decorators.Retry(
                name=f"Up to {max_looks} looks", child=again, num_failures=max_looks
            ),
            *([] if after_turn else [NoSittingFound()]),
        ],
    )


def create_seat_check(max_looks: int) -> py_trees.behaviour.Behaviour:
    """The ``CheckSeatReachable`` stage: where the scan shows no seat under the sitting
    point, one look from above it first and the sitting imagined again with that view
    (neither with ``max_looks`` 0); then the check, its leaf named as the stage so its
    refusals read as before."""
    if max_looks == 0:
        return CheckSeatReachable()
    return py_trees.composites.Sequence(
        name="CheckSeatReachable",
        memory=True,
        children=[LookAtSeat(), ImagineOnSeatView(), CheckSeatReachable()],
    )


def create_locate_turned_chair(
    rescan_fallback: bool = True, max_looks: int = 0
) -> py_trees.behaviour.Behaviour:
    """Where the chair is after a turn: the rotation measured by ICP, or, when no fit is
    accepted (a turn that shows sides the first scan never saw), the chair scanned and its
    sitting pose imagined again (with up to ``max_looks`` looks from above, as on the
    first scan: a chair turned half round shows the arm its back, which hides the seat),
    so that the next instruction is not given for a chair where it no longer stands.
    Without ``rescan_fallback``: ICP alone."""
    if not rescan_fallback:
        return MeasureChairRotation()
    imagine = create_imagination(
        max_looks,
        name="ImagineTurnedChair",
        on_scan_name="ImagineOnTurnedScan",
        look_name="LookAtTurnedChair",
        again_name="ImagineTurnedAgain",
        after_turn=True,
    )
    anew = py_trees.composites.Sequence(
        name="Scan the turned chair anew",
        memory=True,
        children=[ScanChair(name="ScanTurnedChair"), imagine],
    )
    return py_trees.composites.Selector(
        name="LocateTurnedChair", memory=True, children=[MeasureChairRotation(), anew]
    )


def create_assistance_loop(
    max_rotations: int = keys.MAX_ROTATIONS, rescan_fallback: bool = True, max_looks: int = 0
) -> py_trees.behaviour.Behaviour:
    """The human-assistance loop: check, then ask for up to ``max_rotations`` rotations
    (``rescan_fallback`` and ``max_looks``: :func:`create_locate_turned_chair`)."""
    ask_once = py_trees.composites.Sequence(
        name="Ask the helper to rotate the chair",
        memory=True,
        children=[
            InstructHelper(),
            WaitUntilChairStill(),
            create_locate_turned_chair(rescan_fallback, max_looks),
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


def create_accessibility(options: TreeOptions) -> py_trees.behaviour.Behaviour:
    """The ``MakeChairAccessible`` stage: the assistance loop, or without the assistance
    the one check (named as the stage, so the stages keep their names)."""
    if not options.assistance:
        return CheckAccessibility(name="MakeChairAccessible")
    return create_assistance_loop(options.max_rotations, options.rescan_fallback, options.max_looks)


def create_tree(options: TreeOptions | None = None) -> py_trees.behaviour.Behaviour:
    """Builds the whole mission tree (no hardware needed).

    Args:
        options: how to compose it; None: ``TreeOptions()``, the tree of the module
            docstring.
    """
    options = options or TreeOptions()
    return py_trees.composites.Sequence(
        name="Put the bear on the chair",
        memory=True,
        children=[
            ScanChair(),
            create_imagination(options.max_looks),
            create_seat_check(options.max_looks),
            create_accessibility(options),
            WalkToChair(),
            SeatBear(),
            ReleaseAndStand(),
        ],
    )
