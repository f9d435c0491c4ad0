"""Playing the seating motions on a :class:`bearchair.hardware.interfaces.Humanoid`: the raise, the
seating motion, the release and the stand-up (the only part of the whole-body planner
that moves the robot)."""

from __future__ import annotations

import threading

import numpy as np
import trimesh

from bearchair.core.errors import Cancelled
from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Humanoid
from bearchair.skills.planning.wholebody.nao_model import DRIVEN_JOINTS
from bearchair.skills.planning.wholebody.raising import plan_raise
from bearchair.skills.results import SeatingPlan


class SeatingCancelled(Cancelled, RuntimeError):
    """The seating motion was cancelled before or while it played."""


def raise_bear(
    humanoid: Humanoid,
    chair_mesh: trimesh.Trimesh,
    sitting_pose: SittingPose,
    humanoid_pose: SE2Pose,
    *,
    cancel: threading.Event | None = None,
) -> None:
    """Plans (:func:`plan_raise`) and plays the raise where the NAO stands; blocks.

    Raises:
        InfeasibleSeating: the raise is not clear of the chair from here.
        SeatingCancelled: ``cancel`` was set before or during the motion.
    """
    times_s, positions_rad = plan_raise(chair_mesh, sitting_pose, humanoid_pose)
    _play(humanoid, DRIVEN_JOINTS, times_s, positions_rad, cancel, "raising the bear")


def _play(
    humanoid: Humanoid,
    joint_names: tuple[str, ...],
    times_s: np.ndarray,
    positions_rad: np.ndarray,
    cancel: threading.Event | None,
    what: str,
) -> None:
    if cancel is not None and cancel.is_set():
        raise SeatingCancelled(f"{what} cancelled before it started")
    humanoid.play_joint_trajectory(joint_names, list(map(float, times_s)), positions_rad)
    if cancel is not None and cancel.is_set():
        raise SeatingCancelled(f"{what} cancelled while playing")


def execute_seating(
    humanoid: Humanoid, plan: SeatingPlan, *, cancel: threading.Event | None = None
) -> None:
    """Plays the seating motion; blocks until it ends.

    Raises:
        SeatingCancelled: ``cancel`` was set before or during the motion.
    """
    _play(humanoid, plan.joint_names, plan.times_s, plan.positions_rad, cancel, "seating motion")


def release_and_stand(
    humanoid: Humanoid, plan: SeatingPlan, *, cancel: threading.Event | None = None
) -> None:
    """Opens the hands (releasing the bear), folds them back and stands upright.

    Raises:
        SeatingCancelled: ``cancel`` was set before or during the motion.
    """
    if cancel is not None and cancel.is_set():
        raise SeatingCancelled("release cancelled before it started")
    humanoid.set_hands(True)
    _play(
        humanoid,
        plan.joint_names,
        plan.retract_times_s,
        plan.retract_positions_rad,
        cancel,
        "retract motion",
    )
