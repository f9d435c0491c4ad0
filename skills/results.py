"""Typed results that cross from skills into the mission tree.

Each stage's skill returns one of these; behaviours put them on the blackboard and the
executive writes their ``to_json()`` into the run record. Units: metres, radians,
seconds; frames are named in the attribute docs.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import RGBDFrame

if TYPE_CHECKING:
    from bearchair.skills.perception.reconstruction_config import ReconstructionConfig


class ChairScan(NamedTuple):
    """The reconstructed chair.

    Attributes:
        chair_mesh: triangle mesh of the chair in the world frame, z up, floor removed.
        chair_points: (N, 3) point cloud of the chair in the world frame.
        views: number of RGB-D views fused.
        seconds: wall time per step (for example ``capture``, ``tsdf``, ``floor``).
        frames: the RGB-D views fused, each with its camera pose (for looking at the scan
            afterwards; empty when the scan did not keep them).
        notes: scan views skipped or replaced to keep the arm clear of the chair.
        config: the reconstruction's parameters (None: not kept), so that a later view
            is fused as the scan's were.
    """

    chair_mesh: trimesh.Trimesh
    chair_points: np.ndarray
    views: int
    seconds: dict[str, float]
    frames: tuple[RGBDFrame, ...] = ()
    notes: tuple[str, ...] = ()
    config: ReconstructionConfig | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "views": self.views,
            "notes": list(self.notes),
            "points": len(self.chair_points),
            "faces": len(self.chair_mesh.faces),
            "seconds": {k: round(v, 3) for k, v in self.seconds.items()},
        }


class DropOutcome(NamedTuple):
    """One simulated drop of the sitting agent (the chair frame after g_obb).

    Attributes:
        rotation_index: i of the chair rotation α_i = iπ/4.
        offset_m: drop offset along x from the OBB centre.
        position: (3,) final pelvis position in the chair frame.
        yaw: final pelvis yaw in the chair frame (radians).
        joint_score: J, the weighted joint-angle distance to the key configuration.
        link_score: L, the weighted link-rotation distance to the key configuration.
        sitting_height_m: H.
        upper_contacts: contact points of upper-body links with the chair.
        lower_contacts: contact points of lower-body links with the chair.
        correct: every threshold of the sitting affordance model holds.
        link_poses: (n_links, 4, 4) each link's final frame T_chair_link, in
            ``bearchair.skills.imagination.agent.LINK_NAMES`` order (None when not measured).
    """

    rotation_index: int
    offset_m: float
    position: np.ndarray
    yaw: float
    joint_score: float
    link_score: float
    sitting_height_m: float
    upper_contacts: int
    lower_contacts: int
    correct: bool
    link_poses: np.ndarray | None = None


class RotationVote(NamedTuple):
    """How the correct sittings were spread over the chair rotations α_i = iπ/4.

    Attributes:
        counts: correct sittings per rotation (8 values).
        chosen: the rotation whose sittings give the pose.
        runner_up: the strongest other rotation (None when no other has a sitting).
        share: the chosen rotation's share of all correct sittings (1: unanimous).
        split: the vote was split (see ``bearchair.skills.imagination.imagine``).
        resolved_by: what decided a split vote (empty when it was not split).
        extra_drops: drops added to settle a split vote.
    """

    counts: tuple[int, ...]
    chosen: int
    runner_up: int | None
    share: float
    split: bool
    resolved_by: str = ""
    extra_drops: int = 0

    def to_json(self) -> dict[str, Any]:
        return {
            "counts": list(self.counts),
            "chosen_deg": 45 * self.chosen,
            "runner_up_deg": None if self.runner_up is None else 45 * self.runner_up,
            "share": round(self.share, 3),
            "split": self.split,
            "resolved_by": self.resolved_by,
            "extra_drops": self.extra_drops,
        }

    def describe(self) -> str:
        """One line, e.g. ``votes 0/3/3/2/0/0/0/0, chose 45 deg (share 0.38), split``."""
        text = (
            f"votes {'/'.join(str(c) for c in self.counts)}, chose {45 * self.chosen} deg "
            f"(share {self.share:.2f})"
        )
        if self.split:
            text += f", split: resolved by {self.resolved_by}"
            if self.extra_drops:
                text += f", after {self.extra_drops} more drops"
        return text


class ImaginationResult(NamedTuple):
    """The sitting pose found by physical simulation, or why none was found.

    Attributes:
        found: a correct sitting exists.
        sitting_pose: g in the frame of the mesh given (None when not found).
        n_correct: correct sittings of the chosen rotation.
        n_drops: drops simulated in total (24 or 56).
        drops: every drop's outcome.
        seconds: wall time per step (``prepare``, ``simulate``, ``total``).
        reason: why no sitting pose was found (empty when found).
        T_mesh_chair: 4x4 pose of the drops' chair frame (after g_obb) in the frame of
            the mesh given (None when no drop was simulated).
        vote: how the correct sittings were spread over the rotations (None when none).
        backrest: the sitting direction checked against the backrest's
            (``bearchair.skills.imagination.backrest.BackrestCheck``; None when the seat has none).
    """

    found: bool
    sitting_pose: SittingPose | None
    n_correct: int
    n_drops: int
    drops: tuple[DropOutcome, ...]
    seconds: dict[str, float]
    reason: str = ""
    T_mesh_chair: np.ndarray | None = None
    vote: RotationVote | None = None
    backrest: Any = None

    def to_json(self) -> dict[str, Any]:
        return {
            "found": self.found,
            "sitting_pose": self.sitting_pose.to_json() if self.sitting_pose else None,
            "n_correct": self.n_correct,
            "n_drops": self.n_drops,
            "seconds": {k: round(v, 3) for k, v in self.seconds.items()},
            "reason": self.reason,
            "vote": None if self.vote is None else self.vote.to_json(),
            "backrest": None if self.backrest is None else self.backrest.to_json(),
        }


class SeatReachability(NamedTuple):
    """Whether the NAO can seat the bear on this seat from some stance, with the chair
    alone (no walls, no obstacles): when not, no rotation of the chair can help.

    Attributes:
        reachable: a stance and a supported sitting point pass the seating pre-plan.
        reason: why not (empty when reachable), e.g. ``seat too high for the NAO: seat
            0.47 m, the NAO places a bear at most 0.44 m high``.
        seat_height_m: the seat's height under the imagined p, metres (NaN: no seat).
        slide_m: how far p had to move toward the NAO, metres.
        stance_m: the stance's distance from the imagined p along the ray, metres (NaN
            when none).
        seconds: wall time of the check.
        centred_m: how far p had to move across the ray (between armrests), metres.
        seat_seen: the scan has the seat's top under p. When it lost it, p cannot slide
            over the seat toward the NAO, and an unreachable verdict says what the scan
            shows, not what the chair is.
    """

    reachable: bool
    reason: str
    seat_height_m: float
    slide_m: float = 0.0
    stance_m: float = math.nan
    seconds: float = 0.0
    centred_m: float = 0.0
    seat_seen: bool = True

    def to_json(self) -> dict[str, Any]:
        def number(value: float) -> float | None:
            return None if math.isnan(value) else round(value, 3)

        return {
            "reachable": self.reachable,
            "reason": self.reason,
            "seat_height_m": number(self.seat_height_m),
            "slide_m": number(self.slide_m),
            "stance_m": number(self.stance_m),
            "centred_m": number(self.centred_m),
            "seconds": round(self.seconds, 3),
            "seat_seen": self.seat_seen,
        }


class AccessibilityResult(NamedTuple):
    """Whether the humanoid can reach a pose from which it can seat the bear.

    Attributes:
        accessible: a valid SE(2) goal and a collision-free path to it exist.
        se2_goal: where the humanoid should stand, facing opposite the sitting direction.
        sitting_pose: g, possibly moved along the ray toward the humanoid (arm reach).
        path: waypoints from the humanoid's pose to ``se2_goal``, or to ``raise_at``
            when set (empty when none).
        reason: why it is not accessible (empty when it is).
        seconds: planning wall time.
        raise_at: where the humanoid raises the bear before stepping straight in to
            ``se2_goal`` (a seat higher than the carried bear); None: it walks in as it
            carries the bear.
        step_in_from: where the path ends when ``se2_goal`` is nearer the chair than the
            walking humanoid's ellipsoid allows (a footrest, a base under the seat): it
            steps straight in from there, carrying the bear (None: the path ends at
            ``se2_goal`` or at ``raise_at``).
    """

    accessible: bool
    se2_goal: SE2Pose | None
    sitting_pose: SittingPose
    path: tuple[SE2Pose, ...]
    reason: str = ""
    seconds: float = 0.0
    raise_at: SE2Pose | None = None
    step_in_from: SE2Pose | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "accessible": self.accessible,
            "se2_goal": None if self.se2_goal is None else self.se2_goal.to_json(),
            "raise_at": None if self.raise_at is None else self.raise_at.to_json(),
            "step_in_from": None if self.step_in_from is None else self.step_in_from.to_json(),
            "waypoints": len(self.path),
            "reason": self.reason,
            "seconds": round(self.seconds, 3),
        }


class Instruction(NamedTuple):
    """A request to the helper to rotate the chair.

    Attributes:
        sentence: the words spoken.
        clockwise: direction as seen from above (world z up).
        angle_deg: a multiple of 30 in 0..180.
    """

    sentence: str
    clockwise: bool
    angle_deg: int


class RotationChoice(NamedTuple):
    """The rotation to ask for.

    Attributes:
        rotation_rad: counterclockwise positive, a multiple of 30 degrees; 0 when no
            rotation is predicted to help and the chair already faces the NAO.
        predicted_accessible: whether the accessibility check plans with the chair so
            turned.
        reason: why no rotation is predicted to help ("" when one is).
        checked: how many rotations were tried.
    """

    rotation_rad: float
    predicted_accessible: bool
    reason: str = ""
    checked: int = 0


class ChairRotation(NamedTuple):
    """The chair's measured motion after the helper acted (g_rot).

    Attributes:
        T_world_new_old: 4x4 rigid motion mapping the old chair pose onto the new one.
        yaw_rad: its rotation about +z.
        fitness: ICP inlier ratio (0..1).
        inlier_rmse_m: ICP inlier RMSE in metres.
        chair_points: (N, 3) the chair as now seen, world frame: the next reference.
        visible_fitness: share of the reference the new views saw where they could see
            it (NaN when the fitness alone accepted the fit).
    """

    T_world_new_old: np.ndarray
    yaw_rad: float
    fitness: float
    inlier_rmse_m: float
    chair_points: np.ndarray
    visible_fitness: float = math.nan

    def to_json(self) -> dict[str, Any]:
        return {
            "yaw_deg": round(math.degrees(self.yaw_rad), 2),
            "translation_m": [round(float(v), 4) for v in self.T_world_new_old[:3, 3]],
            "fitness": round(self.fitness, 3),
            "inlier_rmse_m": round(self.inlier_rmse_m, 4),
            "visible_fitness": None
            if math.isnan(self.visible_fitness)
            else round(self.visible_fitness, 3),
        }


class WalkResult(NamedTuple):
    """The end of a walk along a path.

    Attributes:
        reached: the final errors are within tolerance.
        position_error_m: distance from the final tracked pose to the goal.
        yaw_error_rad: absolute heading error at the end.
        seconds: walking time on the robot's clock.
        reason: why the goal was not reached (empty when reached).
    """

    reached: bool
    position_error_m: float
    yaw_error_rad: float
    seconds: float
    reason: str = ""

    def to_json(self) -> dict[str, Any]:
        return {
            "reached": self.reached,
            "position_error_m": round(self.position_error_m, 4),
            "yaw_error_deg": round(math.degrees(self.yaw_error_rad), 2),
            "seconds": round(self.seconds, 2),
            "reason": self.reason,
        }


class SeatingPlan(NamedTuple):
    """The whole-body motion that places the bear at the sitting pose.

    Attributes:
        joint_names: the J humanoid joints driven (both sides, mirrored).
        times_s: K knot times from the start of the motion.
        positions_rad: (K, J) joint angles; the last row is q_goal.
        retract_positions_rad: (M, J) the motion after release: hands back, body upright.
        retract_times_s: M knot times of the retract motion.
        seconds: solve wall time per problem (``goal``, ``trajectory``).
        release: what the release imagination predicts for this plan's release
            (``bearchair.skills.imagination.release.ReleasePrediction``), None when not
            imagined.
    """

    joint_names: tuple[str, ...]
    times_s: np.ndarray
    positions_rad: np.ndarray
    retract_times_s: np.ndarray
    retract_positions_rad: np.ndarray
    seconds: dict[str, float]
    release: Any = None

    def to_json(self) -> dict[str, Any]:
        out = {
            "knots": len(self.times_s),
            "duration_s": round(float(self.times_s[-1]), 2) if len(self.times_s) else 0.0,
            "seconds": {k: round(v, 3) for k, v in self.seconds.items()},
        }
        if self.release is not None:
            out["release"] = self.release.to_json()
        return out
