"""The simulated world: build, camera, tag, helper, walking, judge, every calibration chair."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from hardware.interfaces import Clock, Helper, Humanoid, ScanningArm, SeatingJudge, Speaker
from hardware.sim.camera import CARMINE_INTRINSICS, T_HAND_CAMERA
from hardware.sim.world import SimConfig, SimWorld
from skills.arena import DEFAULT_ARENA
from skills.geometry import transform_points, yaw_of

SHARED_CHAIRS = Path(__file__).resolve().parents[2] / "shared" / "chairs"


@pytest.fixture(scope="module")
def world():
    with SimWorld(SimConfig(seed=3)) as built:
        yield built


def test_world_builds_with_the_box_chair_and_protocols(world):
    robot = world.robot
    assert isinstance(robot.arm, ScanningArm)
    assert isinstance(robot.humanoid, Humanoid)
    assert isinstance(robot.speaker, Speaker)
    assert isinstance(robot.clock, Clock)
    assert isinstance(robot.helper, Helper)
    assert isinstance(robot.judge, SeatingJudge)
    centre = world.T_world_chair_true()[:3, 3]
    area = DEFAULT_ARENA.chair_area
    assert area.x_min <= centre[0] <= area.x_max and area.y_min <= centre[1] <= area.y_max
    assert world.chair_mesh_true.bounds[0, 2] == pytest.approx(0.0, abs=0.01)
    start = DEFAULT_ARENA.humanoid_start
    pose = world.nao.pose()
    assert math.hypot(pose.x - start.x, pose.y - start.y) < 0.01
    assert world.bear.held


def test_capture_depth_matches_the_chair_and_pose_comes_from_fk(world):
    frame = world.panda.capture()
    assert frame.rgb.shape == (480, 640, 3) and frame.depth_m.shape == (480, 640)
    assert frame.intrinsics == CARMINE_INTRINSICS
    assert 560.0 < frame.intrinsics.fx < 590.0
    hand = world.panda.T_world_camera() @ np.linalg.inv(T_HAND_CAMERA)
    np.testing.assert_allclose(hand @ T_HAND_CAMERA, frame.T_world_camera, atol=1e-9)
    chair_pixels = world.panda.last_view.segmentation == world.chair.body
    assert chair_pixels.sum() > 2000, "the chair must be in view from the ready configuration"
    valid = chair_pixels & (frame.depth_m > 0)
    assert valid.mean() / chair_pixels.mean() > 0.8
    # Back-project chair pixels into the world: they must lie on the true chair surface.
    v, u = np.nonzero(valid)
    z = frame.depth_m[v, u].astype(float)
    K = frame.intrinsics
    points_camera = np.column_stack([(u - K.cx) * z / K.fx, (v - K.cy) * z / K.fy, z])
    points_world = transform_points(frame.T_world_camera, points_camera)
    distance = _distance_to_mesh(world.chair_mesh_true, points_world[::10])
    assert np.median(distance) < 0.005
    assert np.percentile(distance, 90) < 0.02

    before = frame.T_world_camera
    joints = world.panda.joint_positions()
    joints[0] += 0.2
    world.panda.move_to(joints)
    after = world.panda.capture().T_world_camera
    turned = math.acos(np.clip(np.dot(after[:3, 2], before[:3, 2]), -1.0, 1.0))
    assert turned > 0.1
    # The optical axis turns about the base axis with joint 1, as forward kinematics says.
    assert yaw_of(after) - yaw_of(before) == pytest.approx(0.2, abs=0.02)
    joints[0] -= 0.2
    world.panda.move_to(joints)


def test_move_to_rejects_bad_targets_and_times_out(world):
    with pytest.raises(ValueError):
        world.panda.move_to([0.0] * 6)
    with pytest.raises(ValueError):
        world.panda.move_to([0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0])  # joint 4 must be <= 0
    far = world.panda.joint_positions()
    far[0] += 1.5
    with pytest.raises(TimeoutError):
        world.panda.move_to(far, timeout_s=0.2)
    world.panda.move_to(far - np.array([1.5, 0, 0, 0, 0, 0, 0]))


def _distance_to_mesh(mesh, points: np.ndarray) -> np.ndarray:
    import open3d as o3d

    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(np.asarray(mesh.vertices, dtype=np.float32)),
        o3d.core.Tensor(np.asarray(mesh.faces, dtype=np.uint32)),
    )
    return scene.compute_distance(o3d.core.Tensor(points.astype(np.float32))).numpy()
