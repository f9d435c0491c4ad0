"""The real-robot backends against test doubles of their SDKs (no robot needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hardware.interfaces import Humanoid, ScanningArm, Speaker
from hardware.real import BackendUnavailable, import_sdk
from hardware.real.nao import MAX_FORWARD_MPS, NaoHumanoid, NaoSpeaker
from hardware.real.panda import CARMINE_INTRINSICS, PandaArm
from skills.geometry import SE2Pose, yaw_transform


class FakeService:
    """Records every call made to a NAOqi service."""

    def __init__(self, returns=None):
        self.calls = []
        self._returns = returns or {}

    def __getattr__(self, name):
        def call(*args):
            self.calls.append((name, args))
            return self._returns.get(name)

        return call


class FakeSession:
    def __init__(self):
        self.services = {
            "ALMotion": FakeService({"getRobotPosition": [1.0, 0.0, math.pi / 2]}),
            "ALRobotPosture": FakeService(),
            "ALTextToSpeech": FakeService(),
        }

    def service(self, name):
        return self.services[name]


def test_missing_sdk_names_the_package_to_install():
    with pytest.raises(BackendUnavailable, match="pip install not-a-robot-sdk"):
        import_sdk("not_a_robot_sdk_module", "not-a-robot-sdk")


def test_nao_pose_is_odometry_mapped_into_the_world():
    nao = NaoHumanoid(FakeSession(), odom_origin=SE2Pose(2.0, 0.0, math.pi))
    pose = nao.pose()
    assert isinstance(nao, Humanoid)
    assert pose.x == pytest.approx(1.0) and pose.y == pytest.approx(0.0, abs=1e-12)
    assert pose.theta == pytest.approx(-math.pi / 2)


def test_nao_velocity_is_clipped_to_walking_limits():
    session = FakeSession()
    nao = NaoHumanoid(session)
    nao.set_velocity(1.0, 0.0, -3.0)
    name, (vx, vy, omega) = session.services["ALMotion"].calls[-1]
    assert name == "move" and vx == MAX_FORWARD_MPS and omega == -0.5 and vy == 0.0


def test_nao_trajectory_becomes_one_angle_interpolation():
    session = FakeSession()
    nao = NaoHumanoid(session)
    positions = np.array([[0.0, 0.1], [0.2, 0.3], [0.4, 0.5]])
    nao.play_joint_trajectory(["LHipPitch", "RHipPitch"], [0.0, 1.0, 2.0], positions)
    name, (names, angles, times, absolute) = session.services["ALMotion"].calls[-1]
    assert name == "angleInterpolation" and absolute is True
    assert names == ["LHipPitch", "RHipPitch"]
    assert angles == [[0.2, 0.4], [0.3, 0.5]] and times == [[1.0, 2.0], [1.0, 2.0]]
    with pytest.raises(ValueError, match="does not match"):
        nao.play_joint_trajectory(["LHipPitch"], [1.0], positions)


def test_nao_hands_and_speech():
    session = FakeSession()
    nao = NaoHumanoid(session)
    nao.set_hands(True)
    assert ("openHand", ("LHand",)) in session.services["ALMotion"].calls
    speaker = NaoSpeaker(session)
    assert isinstance(speaker, Speaker)
    speaker.say("hello")
    assert session.services["ALTextToSpeech"].calls == [("say", ("hello",))]


class FakePanda:
    def __init__(self):
        self.q = np.zeros(7)

    def move_to_joint_position(self, q, speed_factor=0.2):
        self.q = np.asarray(q)
        return True

    def get_state(self):
        return type("State", (), {"q": self.q})()

    def get_pose(self):
        pose = np.eye(4)
        pose[:3, 3] = [0.4, 0.0, 0.5 + self.q[0]]
        return pose


class FakeCamera:
    intrinsics = CARMINE_INTRINSICS

    def read(self):
        return np.zeros((480, 640, 3), np.uint8), np.ones((480, 640), np.float32)


def test_panda_camera_pose_is_forward_kinematics_times_hand_eye():
    T_world_base = yaw_transform(math.pi / 2)
    T_hand_camera = np.eye(4)
    T_hand_camera[:3, 3] = [0.0, 0.0, 0.1]
    arm = PandaArm(FakePanda(), FakeCamera(), T_world_base, T_hand_camera)
    assert isinstance(arm, ScanningArm)
    arm.move_to([0.1, 0, 0, 0, 0, 0, 0])
    frame = arm.capture()
    np.testing.assert_allclose(frame.T_world_camera[:3, 3], [0.0, 0.4, 0.7], atol=1e-12)
    with pytest.raises(ValueError, match="7 joints"):
        arm.move_to([0.0, 0.0])
