"""Whole-body seating: the NAO's goal posture and trajectory by optimisation (casadi +
IPOPT), their execution through the humanoid interface, the release and the stand-up.

Public functions (the mission's skills):

* :func:`plan_seating` (chair_mesh, sitting_pose, humanoid_pose) -> SeatingPlan
* :func:`plan_seating_where_standing` (same): SeatBear's, p sliding closer if needed
* :func:`preplan_seating` (chair_mesh, sitting_pose, se2_goal) -> SeatingPlan
* :func:`preplan_approach` (same) -> where to raise the bear first, or None
* :func:`raise_bear` (humanoid, chair_mesh, sitting_pose, humanoid_pose, *, cancel=None)
* :func:`execute_seating` (humanoid, plan, *, cancel=None) -> None
* :func:`release_and_stand` (humanoid, plan, *, cancel=None) -> None

Infeasible plans raise :class:`InfeasibleSeating` (a ``ValueError``) naming the violated
constraint.
"""

from bearchair.skills.planning.wholebody.execution import (
    SeatingCancelled,
    execute_seating,
    raise_bear,
    release_and_stand,
)
from bearchair.skills.planning.wholebody.infeasible import STANCE, InfeasibleSeating
from bearchair.skills.planning.wholebody.postures import (
    RAISED_POSTURE,
    REST_POSTURE,
    STANDING_POSTURE,
)
from bearchair.skills.planning.wholebody.raising import plan_raise
from bearchair.skills.planning.wholebody.seating import (
    plan_seating,
    plan_seating_where_standing,
    preplan_approach,
    preplan_seating,
)

__all__ = [
    "RAISED_POSTURE",
    "REST_POSTURE",
    "STANCE",
    "STANDING_POSTURE",
    "InfeasibleSeating",
    "SeatingCancelled",
    "execute_seating",
    "plan_raise",
    "plan_seating",
    "plan_seating_where_standing",
    "preplan_approach",
    "preplan_seating",
    "raise_bear",
    "release_and_stand",
]
