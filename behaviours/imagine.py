"""ImagineSitting: find how to sit on the scanned chair by physical simulation;
ImagineOnSeatView: again once the seat under the sitting point was looked at;
NoSittingFound: refuse a chair whose level surfaces the NAO cannot reach."""

from __future__ import annotations

import math
from collections.abc import Callable

from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.accessibility import REFUSED
from bearchair.behaviours.skill_behaviour import SkillBehaviour, previous_failure
from bearchair.core.geometry import PELVIS_OVER_SEAT_M, SittingPose
from bearchair.skills.results import ImaginationResult, SeatReachability


class ImagineSitting(SkillBehaviour):
    """Drops a virtual child onto the chair mesh and keeps the best sitting pose g.

    On a chair already sat on (``/sitting/pose`` set: it was turned about the vertical
    axis and scanned anew since, which keeps heights), a sitting more than
    ``PELVIS_OVER_SEAT_M`` above or below the one before sits on something else than the
    seat (the new scan lost it, or an armrest): the leaf fails as if no sitting was found,
    for a look from above to follow.

    Args:
        name: the leaf's name.

    Blackboard:
        reads ``/mission/seed``, ``/chair/mesh``, ``/sitting/pose``;
        writes ``/sitting/imagination``, ``/sitting/pose``.
    """

    activity = "imagining sitting"

    def __init__(self, name: str = "ImagineSitting"):
        super().__init__(
            name,
            reads=(keys.SEED, keys.CHAIR_MESH, keys.SITTING_POSE),
            writes=(keys.IMAGINATION, keys.SITTING_POSE),
        )
        self._before: SittingPose | None = None

    def prepare(self) -> Callable[[], ImaginationResult]:
        skills, _ = self.need()
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        seed = self.blackboard.get(keys.SEED)
        self._before = self._optional(keys.SITTING_POSE, None)
        return lambda: skills.imagine_sitting(chair_mesh, seed=seed, cancel=self.cancel_event)

    def conclude(self, result: ImaginationResult) -> Status:
        result = self._kept_height(result)
        self.blackboard.set(keys.IMAGINATION, result, overwrite=True)
        if not result.found or result.sitting_pose is None:
            return self.fail(f"no sitting pose: {result.reason or 'no correct sitting'}")
        self.blackboard.set(keys.SITTING_POSE, result.sitting_pose, overwrite=True)
        return self.succeed(describe_sitting(result))

    def _kept_height(self, result: ImaginationResult) -> ImaginationResult:
        """The result, or, on a chair sat on before, no sitting where it moved the pelvis
        more than ``PELVIS_OVER_SEAT_M`` up or down."""
        if self._before is None or not result.found or result.sitting_pose is None:
            return result
        before_m = float(self._before.position[2])
        now_m = float(result.sitting_pose.position[2])
        if abs(now_m - before_m) <= PELVIS_OVER_SEAT_M:
            return result
        return result._replace(
            found=False,
            sitting_pose=None,
            reason=(
                f"the sitting found is {now_m:.3f} m high, {abs(now_m - before_m):.3f} m "
                f"{'below' if now_m < before_m else 'above'} the {before_m:.3f} m the chair "
                f"was sat at before the turn (a turn keeps heights: the scan lost the seat, "
                f"or the sitter sat on something else)"
            ),
        )


class ImagineOnSeatView(SkillBehaviour):
    """Imagines the sitting again when LookAtSeat had to add a view over p: the sitting
    was imagined on a scan that showed no seat under its own point, so the chair the
    imagination saw lacked what the sitter sat on. Without such a view it succeeds at
    once; where the completed scan gives no sitting, the one before stands.

    Args:
        name: the leaf's name.

    Blackboard:
        reads ``/mission/seed``, ``/chair/mesh``, ``/chair/seat_view``;
        writes ``/sitting/imagination``, ``/sitting/pose``.
    """

    activity = "imagining sitting on the scan with the seat view"

    def __init__(self, name: str = "ImagineOnSeatView"):
        super().__init__(
            name,
            reads=(keys.SEED, keys.CHAIR_MESH, keys.SEAT_VIEW),
            writes=(keys.IMAGINATION, keys.SITTING_POSE),
        )

    def prepare(self) -> Callable[[], ImaginationResult | None]:
        if not self._optional(keys.SEAT_VIEW, ""):
            return lambda: None
        skills, _ = self.need()
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        seed = self.blackboard.get(keys.SEED)
        return lambda: skills.imagine_sitting(chair_mesh, seed=seed, cancel=self.cancel_event)

    def conclude(self, result: ImaginationResult | None) -> Status:
        if result is None:
            return self.succeed("no view was added: the sitting imagined on the scan stands")
        if not result.found or result.sitting_pose is None:
            return self.succeed(
                f"no sitting on the scan with the seat view "
                f"({result.reason or 'no correct sitting'}): the one imagined before stands"
            )
        self.blackboard.set(keys.IMAGINATION, result, overwrite=True)
        self.blackboard.set(keys.SITTING_POSE, result.sitting_pose, overwrite=True)
        return self.succeed(f"again with the seat view: {describe_sitting(result)}")


def describe_sitting(result: ImaginationResult) -> str:
    """A found sitting in one line: g, the vote, and where the backrest weighed in."""
    assert result.sitting_pose is not None
    pose = result.sitting_pose
    x, y, z = pose.position
    direction = ""
    check = result.backrest
    if check is not None and check.used:
        off_deg = math.degrees(check.disagreement_rad)
        direction = f"; direction from the backrest, the vote's was {off_deg:+.0f} deg off"
    elif check is not None and not math.isnan(check.mirror_vote):
        direction = (
            f"; the backrest's direction, {math.degrees(check.disagreement_rad):+.0f} deg "
            f"off, mirrors the chair less ({check.mirror_back:.2f} against "
            f"{check.mirror_vote:.2f})"
        )
    return (
        f"sit at ({x:.3f}, {y:.3f}, {z:.3f}) m facing {math.degrees(pose.yaw):.0f} deg "
        f"({result.n_correct} correct of {result.n_drops} drops{direction})"
    )


class NoSittingFound(SkillBehaviour):
    """Always FAILURE, last in the ``ImagineSitting`` selector: why no sitting pose was
    imagined. Where every level surface of the scan the bear rests on lies beyond the
    seat heights the NAO places a bear on, the mission is refused with that reason (as
    ``CheckSeatReachable`` refuses: no turn of the chair and no further look helps);
    otherwise the leaf repeats the failure before it (the last imagination's or look's).

    Blackboard:
        reads ``/chair/mesh``.
    """

    activity = "checking the scan's seat heights"

    def __init__(self, name: str = "NoSittingFound"):
        super().__init__(name, reads=(keys.CHAIR_MESH,))
        self._last_failure = ""

    def prepare(self) -> Callable[[], SeatReachability]:
        skills, _ = self.need()
        chair_mesh = self.blackboard.get(keys.CHAIR_MESH)
        # Read now, in the tick its sibling failed in: the selector resets it later.
        self._last_failure = previous_failure(self)
        return lambda: skills.check_seat_levels(chair_mesh)

    def conclude(self, verdict: SeatReachability) -> Status:
        last = self._last_failure
        if not verdict.reachable:
            return self.fail(f"{REFUSED}{verdict.reason}; no sitting imagined ({last})")
        return self.fail(last)
