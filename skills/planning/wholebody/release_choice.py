"""The seating plan whose release the bear survives: plan, imagine the release, choose.

SeatBear plans from where the NAO stopped (:func:`.seating.plan_seating_where_standing`),
then imagines letting the bear go where that plan's goal posture holds it
(:func:`bearchair.skills.imagination.release.imagine_release`, on the scanned chair).
When the bear is predicted to fall, other placements of p along the sitting ray are
planned and imagined (deeper toward the back, or nearer the NAO), and the first where
the bear stays is taken; where none stays, the seating fails before the hands open,
saying why. The NAO has already walked, so the bear's yaw is the NAO's heading and only
p moves.

``BEARCHAIR_RELEASE_CHECK`` (environment): ``prefer`` (the default: move p to the first
other placement predicted to stay, as weighed below; where none is, release as planned: a
prediction of "falls" alone never stops the release), ``predict`` (imagine and record the
prediction, release as planned), ``choose`` (as above: move p or fail before the
release), ``off``. ``prefer`` is the default: a prediction of "falls" was wrong more
often than right, so ``choose`` stopped releases the judge would have seated, while
moving p where another placement is predicted to stay seated bears ``predict`` let fall
(measurements: docs/decisions.md).

The two weak predictions are weighed against each other: a "stays" on a seat patched from
the seat map (:attr:`ReleasePrediction.seat_patched`) and a "falls" where imagined bears
dropped through the scan onto the floor (a hole the scan has and the chair may not). So
``prefer`` moves p to a placement predicted to stay on a patched seat only when the planned
release's bears all tipped over on the scanned seat itself
(:attr:`ReleasePrediction.tipped_on_seat`).
"""

from __future__ import annotations

import os

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.skills.imagination.release import (
    ReleasePrediction,
    bear_release_pose,
    imagine_release,
)
from bearchair.skills.planning.wholebody.infeasible import InfeasibleSeating
from bearchair.skills.planning.wholebody.nao_model import DRIVEN_JOINTS
from bearchair.skills.planning.wholebody.optimisation import seating_problems
from bearchair.skills.planning.wholebody.scene import seating_scene
from bearchair.skills.planning.wholebody.seating import plan_seating, plan_seating_where_standing
from bearchair.skills.results import SeatingPlan

RELEASE_CHECK_ENV = "BEARCHAIR_RELEASE_CHECK"
RELEASE_CHECK_MODES = ("choose", "prefer", "predict", "off")
OTHER_PLACEMENTS_M = (-0.02, 0.02, -0.04)
"""Where else p may go along the sitting ray (metres; negative: deeper, toward the back),
when the planned release is predicted to fail: a bear's torso is 8.5 cm deep, so 2 cm
moves its seat point a quarter of it over the seat; a bear that tipped off a front edge
or rolled back off a sloping seat lands otherwise."""
RELEASE = "release"
"""The constraint named when no placement keeps the bear seated."""

_PLANAR_JOINTS = ("LAnklePitch", "LKneePitch", "LHipPitch", "LShoulderPitch", "RElbowRoll")
"""The planar posture q's joints, in q's order (``nao_model.joint_values``)."""


def release_check_mode() -> str:
    """The mode from ``BEARCHAIR_RELEASE_CHECK`` (``prefer`` when unset).

    Raises:
        ValueError: an unknown mode.
    """
    mode = os.environ.get(RELEASE_CHECK_ENV, "prefer") or "prefer"
    if mode not in RELEASE_CHECK_MODES:
        raise ValueError(
            f"{RELEASE_CHECK_ENV}={mode!r}: expected one of {', '.join(RELEASE_CHECK_MODES)}"
        )
    return mode


def planned_release_pose(plan: SeatingPlan, humanoid_pose: SE2Pose) -> np.ndarray:
    """The bear frame in the world where the plan's goal posture (its last knot) holds it."""
    row = np.asarray(plan.positions_rad)[-1]
    q = np.array([row[DRIVEN_JOINTS.index(name)] for name in _PLANAR_JOINTS])
    geometry = seating_problems().geometry(q)
    return bear_release_pose(humanoid_pose, geometry.bear_base, geometry.bear_up)


def predict_release(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    plan: SeatingPlan,
) -> ReleasePrediction:
    """The release imagination of a plan (see :mod:`bearchair.skills.imagination.release`)."""
    T_release = planned_release_pose(plan, humanoid_pose)
    # The seat map the plan was made on: the seat top the goal let the bear go over.
    seat_top_z = seating_scene(chair_mesh, sitting_pose, humanoid_pose).profile.seat_top_z
    return imagine_release(
        chair_mesh, T_release, sitting_pose.yaw, humanoid_pose, seat_top_z=seat_top_z
    )


def plan_seating_released(
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    *,
    raised: bool = False,
) -> SeatingPlan:
    """SeatBear's plan: from where the NAO stands, with a release the bear survives.

    Returns:
        The plan, its ``release`` the prediction for it.

    Raises:
        InfeasibleSeating: no plan (as :func:`.seating.plan_seating_where_standing`), or
            (:data:`RELEASE`, ``choose`` only) the bear is predicted to fall at every
            placement tried.
    """
    mode = release_check_mode()
    plan = plan_seating_where_standing(chair_mesh, sitting_pose, humanoid_pose, raised=raised)
    if mode == "off":
        return plan
    prediction = predict_release(chair_mesh, sitting_pose, humanoid_pose, plan)
    if prediction.stays or mode == "predict":
        return plan._replace(release=prediction)
    tried = 1
    for offset_m in OTHER_PLACEMENTS_M:
        moved = SittingPose(
            np.asarray(sitting_pose.position, float)
            + np.r_[offset_m * sitting_pose.direction(), 0.0],
            sitting_pose.yaw,
        )
        try:
            other = plan_seating(chair_mesh, moved, humanoid_pose, raised=raised)
        except InfeasibleSeating:
            continue
        tried += 1
        other_prediction = predict_release(chair_mesh, moved, humanoid_pose, other)
        if other_prediction.stays and (
            mode == "choose" or not other_prediction.seat_patched or prediction.tipped_on_seat
        ):
            return other._replace(release=other_prediction)
    if mode == "prefer":
        return plan._replace(release=prediction)
    raise InfeasibleSeating(
        RELEASE,
        f"the bear would not stay seated: {prediction.reason} in "
        f"{len(prediction.releases) - prediction.staying}/{len(prediction.releases)} imagined "
        f"releases as planned, and at {tried - 1} other placement(s) along the sitting ray",
    )
