"""ScanChair: scan the chair with the arm's wrist camera and reconstruct it; LookFromAbove
and LookAtSeat: one more view of it when the scan hid what the imagination or the seat
check needs."""

from __future__ import annotations

from collections.abc import Callable

import py_trees
from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour
from bearchair.skills.results import ChairScan, ImaginationResult


def put_scan(blackboard: py_trees.blackboard.Client, scan: ChairScan) -> None:
    """Writes a scan where the later leaves read the chair: the scan, its mesh, its points."""
    blackboard.set(keys.CHAIR_SCAN, scan, overwrite=True)
    blackboard.set(keys.CHAIR_MESH, scan.chair_mesh, overwrite=True)
    blackboard.set(keys.CHAIR_POINTS, scan.chair_points, overwrite=True)


class ScanChair(SkillBehaviour):
    """Moves the arm through its capture views and fuses them into a chair mesh.

    Blackboard:
        reads ``/mission/seed``; writes ``/chair/scan``, ``/chair/mesh``, ``/chair/points``.
    """

    activity = "scanning the chair"

    def __init__(self, name: str = "ScanChair"):
        super().__init__(
            name, reads=(keys.SEED,), writes=(keys.CHAIR_SCAN, keys.CHAIR_MESH, keys.CHAIR_POINTS)
        )

    def prepare(self) -> Callable[[], ChairScan]:
        skills, robot = self.need()
        seed = self.blackboard.get(keys.SEED)
        return lambda: skills.scan_chair(robot.arm, seed=seed, cancel=self.cancel_event)

    def conclude(self, scan: ChairScan) -> Status:
        put_scan(self.blackboard, scan)
        return self.succeed(
            f"chair reconstructed from {scan.views} views: {len(scan.chair_points)} points, "
            f"{len(scan.chair_mesh.faces)} faces"
        )


class LookFromAbove(SkillBehaviour):
    """Looks at the chair once more, from above where the scan has not looked from, and
    reconstructs it from every view: for a scan on which the imagination found no sitting.

    It looks only after an imagination that ended with no sitting on the current scan (a
    result, not an error: another view does not mend a failing skill); otherwise it fails
    at once, repeating why the leaf it backs up failed.

    Args:
        name: the leaf's name.
        backs_up: the leaf whose failure this look answers (its feedback is repeated
            when there is nothing to look for); None: not named.

    Blackboard:
        reads ``/mission/seed``, ``/chair/scan``, ``/sitting/imagination``;
        writes ``/chair/scan``, ``/chair/mesh``, ``/chair/points``.
    """

    activity = "looking at the chair from above"

    def __init__(
        self, name: str = "LookFromAbove", backs_up: py_trees.behaviour.Behaviour | None = None
    ):
        super().__init__(
            name,
            reads=(keys.SEED, keys.CHAIR_SCAN, keys.IMAGINATION),
            writes=(keys.CHAIR_SCAN, keys.CHAIR_MESH, keys.CHAIR_POINTS),
        )
        self.backs_up = backs_up

    def prepare(self) -> Callable[[], ChairScan]:
        skills, robot = self.need()
        scan: ChairScan = self.blackboard.get(keys.CHAIR_SCAN)
        imagination: ImaginationResult | None = self._optional(keys.IMAGINATION, None)
        if imagination is None or imagination.found:
            why = (
                f"{self.backs_up.name}: {self.backs_up.feedback_message}"
                if self.backs_up is not None
                else "the imagination ended without a result"
            )
            raise RuntimeError(f"no look from above ({why})")
        seed = self.blackboard.get(keys.SEED)
        return lambda: skills.look_from_above(robot.arm, scan, seed=seed, cancel=self.cancel_event)

    def conclude(self, scan: ChairScan) -> Status:
        put_scan(self.blackboard, scan)
        return self.succeed(
            f"{scan.notes[-1] if scan.notes else 'one more view'}: chair reconstructed from "
            f"{scan.views} views, {len(scan.chair_points)} points"
        )


class LookAtSeat(SkillBehaviour):
    """Makes sure the scan shows the seat under the sitting point: when it does not (the
    nine views saw past a rim, between rails, or not at all behind a back), the arm looks
    once from above it and the chair is reconstructed with that view. Succeeds either
    way: the seat check that follows says what the scan still lacks.

    Blackboard:
        reads ``/mission/seed``, ``/chair/scan``, ``/sitting/pose``;
        writes ``/chair/scan``, ``/chair/mesh``, ``/chair/points``, ``/chair/seat_view``
        (the view added, empty when none was).
    """

    activity = "looking for the seat under the sitting point"

    def __init__(self, name: str = "LookAtSeat"):
        super().__init__(
            name,
            reads=(keys.SEED, keys.CHAIR_SCAN, keys.SITTING_POSE),
            writes=(keys.CHAIR_SCAN, keys.CHAIR_MESH, keys.CHAIR_POINTS, keys.SEAT_VIEW),
        )

    def prepare(self) -> Callable[[], ChairScan]:
        skills, robot = self.need()
        scan: ChairScan = self.blackboard.get(keys.CHAIR_SCAN)
        sitting_pose = self.blackboard.get(keys.SITTING_POSE)
        seed = self.blackboard.get(keys.SEED)
        return lambda: skills.look_at_seat(
            robot.arm, scan, sitting_pose, seed=seed, cancel=self.cancel_event
        )

    def conclude(self, scan: ChairScan) -> Status:
        before: ChairScan = self.blackboard.get(keys.CHAIR_SCAN)
        if scan is before:
            self.blackboard.set(keys.SEAT_VIEW, "", overwrite=True)
            return self.succeed("the scan shows the seat under the sitting point")
        put_scan(self.blackboard, scan)
        note = scan.notes[-1] if scan.notes else "one more view"
        self.blackboard.set(keys.SEAT_VIEW, note, overwrite=True)
        return self.succeed(f"the scan showed no seat under the sitting point: {note}")
