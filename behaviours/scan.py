"""ScanChair: scan the chair with the arm's wrist camera and reconstruct it."""

from __future__ import annotations

from collections.abc import Callable

from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour
from bearchair.skills.results import ChairScan


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
        self.blackboard.set(keys.CHAIR_SCAN, scan, overwrite=True)
        self.blackboard.set(keys.CHAIR_MESH, scan.chair_mesh, overwrite=True)
        self.blackboard.set(keys.CHAIR_POINTS, scan.chair_points, overwrite=True)
        return self.succeed(
            f"chair reconstructed from {scan.views} views: {len(scan.chair_points)} points, "
            f"{len(scan.chair_mesh.faces)} faces"
        )
