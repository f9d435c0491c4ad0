"""The robots in a recording: the Panda and the NAO from their URDFs, moving with their
joint states.

Each robot is logged once by Rerun's URDF loader (``rerun.urdf.UrdfTree``): its links'
geometry under ``world/<robot name>/...``, each link in a named frame
(``panda/panda_link3``, ``nao/LThigh``), and the joints' fixed offsets. A joint state
is one batch of ``Transform3D`` under ``transforms/<robot>/joints``, a transform per
joint from its parent link's frame to its child's (:func:`joint_transform`, which
agrees with Rerun's ``UrdfJoint.compute_transform``), on the timeline of the moment it
describes. The root
frames hang from the scene's own entities:

* the Panda's base link from ``world/arm_base`` (the arena's ``arm_base_xy``, on the
  floor); its seven joints as the arm reports them (``ScanningArm.joint_positions``);
* the NAO's base link from ``world/nao``, the tracked pose of the NAO frame (on the
  floor between the soles): its offset is the left sole laid flat beside that frame,
  as the simulated NAO stands (forward kinematics of the legs, :func:`chain`). Its
  joints: the carrying posture while it walks, then the seating plan's and the retract
  motion's knots, at the robot times they were played.

The URDFs are the ones the simulated world loads (the Panda drawn with its collision
meshes, the NAO with primitives): the same robots as on the real cell.
"""

from __future__ import annotations

import collections
import math
import threading
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.urdf as rru
from scipy.spatial.transform import Rotation

from bearchair.core.arena import HUMANOID_TAG
from bearchair.core.nao_carrying import CARRYING_POSTURE_RAD

PANDA_ARM_JOINTS = tuple(f"panda_joint{index}" for index in range(1, 8))
FEET_FRAME_IN_LEFT_SOLE_M = (0.0, -0.05, 0.0)
"""The NAO frame is half the standing stance (5 cm) to the right of the left sole, in
the sole's orientation (as :class:`bearchair.hardware.sim.nao.SimNao` places its body)."""
ARM_STEP_RAD = math.radians(0.5)
"""The arm's state is logged again once a joint moved half a degree."""
ARM_READ_PERIOD_S = 0.1
"""Wall seconds between two reads of the arm's joints (10 Hz: its motions last seconds)."""


class RobotModel:
    """One robot from its URDF, logged to a recording and posed by joint values.

    Args:
        urdf: the robot's URDF (meshes by absolute path or primitives).
        frame_prefix: the prefix of its link frames (``"nao/"``), unique per robot.
        anchor: the entity whose frame the robot's root link hangs from.
    """

    def __init__(self, urdf: Path, frame_prefix: str, anchor: str) -> None:
        self.tree = rru.UrdfTree.from_file_path(
            str(urdf), entity_path_prefix="world", frame_prefix=frame_prefix
        )
        self.frame_prefix = frame_prefix
        self.anchor = anchor
        self.entity = f"world/{self.tree.name}"
        """Where the URDF loader puts the links' geometry."""
        self.transforms = f"transforms/{frame_prefix.strip('/')}"
        """Where the joint states and the root's placement go (between named frames,
        so the entity path is only a name)."""
        self.joints = {joint.name: joint for joint in self.tree.joints()}
        self.root_link = self.tree.root_link().name

    def log_model(self, stream: rr.RecordingStream) -> None:
        """The links' geometry and fixed offsets (static)."""
        self.tree.log_urdf_to_recording(stream)

    def log_root(self, stream: rr.RecordingStream, T_anchor_root: np.ndarray) -> None:
        """Hangs the root link's frame from the anchor entity's frame."""
        stream.log(
            f"{self.transforms}/root",
            rr.Transform3D(
                translation=T_anchor_root[:3, 3],
                mat3x3=T_anchor_root[:3, :3],
                parent_frame=f"tf#/{self.anchor}",
                child_frame=self.frame_prefix + self.root_link,
            ),
        )

    def log_joints(self, stream: rr.RecordingStream, values: Mapping[str, float]) -> None:
        """The joints named in ``values`` (radians or metres) as one batch of transforms,
        each from its parent link's frame to its child's: one log call per state."""
        joints = [self.joints[name] for name in values if name in self.joints]
        transforms = [joint_transform(joint, float(values[joint.name])) for joint in joints]
        # One Transform3D row may hold many transforms between named frames (Rerun's URDF
        # loader writes /tf_static so); the type hints only name a single one.
        batch: dict[str, Any] = {
            "translation": [T[:3, 3] for T in transforms],
            "quaternion": [Rotation.from_matrix(T[:3, :3]).as_quat() for T in transforms],
            "parent_frame": [self.frame_prefix + joint.parent_link for joint in joints],
            "child_frame": [self.frame_prefix + joint.child_link for joint in joints],
        }
        stream.log(f"{self.transforms}/joints", rr.Transform3D.from_fields(**batch))

    def chain(self, from_link: str, to_link: str, values: Mapping[str, float]) -> np.ndarray:
        """``T_from_to``: the pose of ``to_link`` in ``from_link`` by forward kinematics
        (joints not in ``values`` at 0). ``from_link`` must be an ancestor of ``to_link``."""
        by_child = {joint.child_link: joint for joint in self.joints.values()}
        transform = np.eye(4)
        link = to_link
        while link != from_link:
            joint = by_child[link]
            transform = joint_transform(joint, values.get(joint.name, 0.0)) @ transform
            link = joint.parent_link
        return transform


def joint_transform(joint: Any, value: float) -> np.ndarray:
    """A URDF joint's ``T_parent_child`` at ``value``: origin (xyz, fixed-axis rpy), then
    the motion about (revolute, continuous) or along (prismatic) its axis."""
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", joint.origin_rpy).as_matrix()
    T[:3, 3] = joint.origin_xyz
    motion = np.eye(4)
    axis = np.asarray(joint.axis, dtype=float)
    if joint.joint_type in ("revolute", "continuous"):
        motion[:3, :3] = Rotation.from_rotvec(axis * value).as_matrix()
    elif joint.joint_type == "prismatic":
        motion[:3, 3] = axis * value
    return T @ motion


class MissionRobots:
    """The Panda and the NAO of a mission's recording (see the module docstring)."""

    def __init__(self) -> None:
        from bearchair.hardware.sim.nao_urdf import nao_urdf
        from bearchair.hardware.sim.panda import coarse_panda_urdf
        from bearchair.hardware.sim.tag import tag_assets

        _, plate = tag_assets(HUMANOID_TAG)
        self.nao_urdf = nao_urdf(plate, HUMANOID_TAG.height_m)
        self.panda = RobotModel(coarse_panda_urdf(), "panda/", "world/arm_base")
        self.nao = RobotModel(self.nao_urdf, "nao/", "world/nao")
        # Standing straight (every joint 0) with the arms carrying: every movable joint
        # is in each state logged, so that one state is the whole posture.
        movable = [name for name, joint in self.nao.joints.items() if joint.joint_type != "fixed"]
        self._nao_joints: dict[str, float] = {**dict.fromkeys(movable, 0.0), **CARRYING_POSTURE_RAD}

    def log_static(self, stream: rr.RecordingStream, arm_base_xy: Sequence[float]) -> None:
        """Both models, the arm's base, and the NAO standing in its carrying posture."""
        self.panda.log_model(stream)
        self.nao.log_model(stream)
        self.log_arm_base(stream, arm_base_xy)
        self.panda.log_root(stream, np.eye(4))
        self.log_nao_posture(stream, self._nao_joints)

    def log_arm_base(self, stream: rr.RecordingStream, arm_base_xy: Sequence[float]) -> None:
        stream.log(
            "world/arm_base",
            rr.Transform3D(translation=(float(arm_base_xy[0]), float(arm_base_xy[1]), 0.0)),
        )

    def log_arm(self, stream: rr.RecordingStream, joints_rad: np.ndarray) -> None:
        self.panda.log_joints(stream, dict(zip(PANDA_ARM_JOINTS, joints_rad, strict=True)))

    def log_nao_posture(self, stream: rr.RecordingStream, joints: Mapping[str, float]) -> None:
        """The NAO's joints, its base placed so that the left sole lies flat on the floor."""
        self._nao_joints = {**self._nao_joints, **joints}
        self.nao.log_joints(stream, self._nao_joints)
        self.nao.log_root(stream, self.T_nao_base(self._nao_joints))

    def T_nao_base(self, joints: Mapping[str, float]) -> np.ndarray:
        """The NAO's base link in the NAO frame (on the floor between the soles)."""
        T_base_sole = self.nao.chain(self.nao.root_link, "l_sole", joints)
        T_sole_feet = np.eye(4)
        T_sole_feet[:3, 3] = FEET_FRAME_IN_LEFT_SOLE_M
        return np.linalg.inv(T_base_sole @ T_sole_feet)

    def log_nao_motion(
        self,
        stream: rr.RecordingStream,
        joint_names: Sequence[str],
        times_s: np.ndarray,
        positions_rad: np.ndarray,
        started_s: float,
    ) -> None:
        """A joint trajectory the NAO played from robot time ``started_s``, knot by knot."""
        positions = np.asarray(positions_rad, dtype=float).reshape(len(times_s), -1)
        for time_s, row in zip(np.asarray(times_s, dtype=float), positions, strict=True):
            stream.set_time("robot", duration=started_s + float(time_s))
            self.log_nao_posture(stream, dict(zip(joint_names, row, strict=True)))


class JointSampler:
    """Reads a robot's joint angles every ``period_s`` in a thread of its own, keeping
    ``(robot seconds, angles)`` whenever a joint moved ``step_rad`` since the last kept.

    Not on the tick's thread: in simulation a read waits for the world's lock while
    physics steps (9 s of a 74 s run when the tick loop read the arm itself).

    Args:
        read: the joint angles now (``ScanningArm.joint_positions``), radians.
        clock: the robot's clock (``now()``, seconds).
    """

    def __init__(
        self,
        read: Callable[[], Any],
        clock: Any,
        period_s: float = ARM_READ_PERIOD_S,
        step_rad: float = ARM_STEP_RAD,
    ) -> None:
        self._read = read
        self._clock = clock
        self._period_s = period_s
        self._step_rad = step_rad
        self._kept: collections.deque[tuple[float, np.ndarray]] = collections.deque()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="recording-joints", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        last: np.ndarray | None = None
        while True:
            try:
                joints = np.asarray(self._read(), dtype=float)
                now_s = float(self._clock.now())
            except Exception:  # a closed world or a real arm's failed read: try again
                joints = None
            if joints is not None and (
                last is None or float(np.max(np.abs(joints - last))) >= self._step_rad
            ):
                self._kept.append((now_s, joints))
                last = joints
            if self._stop.wait(self._period_s):
                return

    def drain(self) -> list[tuple[float, np.ndarray]]:
        """The states kept since the last drain, oldest first."""
        kept = []
        while self._kept:
            kept.append(self._kept.popleft())
        return kept

    def stop(self) -> None:
        """Stops reading (waits for the thread at most one period and a read)."""
        self._stop.set()
        self._thread.join(timeout=self._period_s + 5.0)
