"""The Franka Panda's forward kinematics and link geometry, from pybullet_data's URDF.

Used by the mission's scan (where the wrist camera looks from, how close the arm comes
to the chair: :mod:`bearchair.skills.perception.clearance`), by the synthetic scenes the
perception tests render, and by the view bench. Poses are ``T_world_<frame>`` with the
arm's base at the world origin, in metres; joint angles in radians.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pybullet
import pybullet_data

from bearchair.hardware.wrist_mount import T_HAND_CAMERA


class PandaKinematics:
    """Forward kinematics and collision queries of the Franka Panda (pybullet_data's URDF)."""

    HAND_LINK = 8

    def __init__(self) -> None:
        self.client = pybullet.connect(pybullet.DIRECT)
        pybullet.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=self.client)
        self.robot = pybullet.loadURDF(
            "franka_panda/panda.urdf",
            useFixedBase=True,
            flags=pybullet.URDF_USE_SELF_COLLISION,
            physicsClientId=self.client,
        )

    def close(self) -> None:
        """Disconnects the client."""
        if self.client >= 0:
            pybullet.disconnect(self.client)
            self.client = -1

    def set_joints(self, joints_rad: Sequence[float] | np.ndarray) -> None:
        """Sets the 7 arm joints (fingers stay open)."""
        for index, angle in enumerate(joints_rad):
            pybullet.resetJointState(self.robot, index, float(angle), physicsClientId=self.client)
        for finger in (9, 10):
            pybullet.resetJointState(self.robot, finger, 0.04, physicsClientId=self.client)

    def link_pose(self, link: int) -> np.ndarray:
        """T_world_link of a link at the current joints."""
        state = pybullet.getLinkState(
            self.robot, link, computeForwardKinematics=True, physicsClientId=self.client
        )
        transform = np.eye(4)
        transform[:3, :3] = np.asarray(
            pybullet.getMatrixFromQuaternion(state[5], physicsClientId=self.client)
        ).reshape(3, 3)
        transform[:3, 3] = state[4]
        return transform

    def camera_pose(
        self, joints_rad: Sequence[float] | np.ndarray, T_hand_camera: np.ndarray = T_HAND_CAMERA
    ) -> np.ndarray:
        """T_world_camera at a joint configuration."""
        self.set_joints(joints_rad)
        return self.link_pose(self.HAND_LINK) @ T_hand_camera
