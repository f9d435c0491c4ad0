"""The simulated world: build, camera, tag, helper, walking, judge, every calibration chair."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from bearchair.core.arena import DEFAULT_ARENA, HUMANOID_TAG
from bearchair.core.geometry import transform_points, wrap_angle, yaw_of
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import (
    Clock,
    Helper,
    Humanoid,
    ScanningArm,
    SeatingJudge,
    Speaker,
)
from bearchair.hardware.sim.camera import CARMINE_INTRINSICS
from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.hardware.wrist_mount import T_HAND_CAMERA

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


def test_a_window_of_the_image_is_the_full_frame_cropped_and_tracks_the_tag():
    from bearchair.skills.perception.tags import TagSightings, locate_humanoid

    with SimWorld(SimConfig(seed=3, camera_noise=False)) as quiet:
        full = quiet.panda.capture()
        window = quiet.panda.capture_region(200, 150, 120, 90)
        with pytest.raises(ValueError, match="leaves"):
            quiet.panda.capture_region(600, 0, 100, 10)
        # Where the walk passes, 1.3 m from the arm: a full frame first, then a window.
        quiet.place_nao(SE2Pose(1.3, 0.2, 2.8))
        sightings = TagSightings()
        first = locate_humanoid(quiet.panda, sightings=sightings)
        first_shape = quiet.panda.last_view.rgb.shape[:2]
        second = locate_humanoid(quiet.panda, sightings=sightings)
        second_shape = quiet.panda.last_view.rgb.shape[:2]
        # Without a record of sightings every frame is a full one.
        locate_humanoid(quiet.panda)
        unrecorded_shape = quiet.panda.last_view.rgb.shape[:2]
        truth = quiet.nao.true_pose()
    assert window.rgb.shape == (90, 120, 3) and window.depth_m.shape == (90, 120)
    assert window.intrinsics.cx == pytest.approx(full.intrinsics.cx - 200)
    assert window.intrinsics.cy == pytest.approx(full.intrinsics.cy - 150)
    crop_rgb = full.rgb[150:240, 200:320].astype(int)
    assert np.mean(np.abs(window.rgb.astype(int) - crop_rgb)) < 2.0
    crop_depth = full.depth_m[150:240, 200:320]
    both = (crop_depth > 0) & (window.depth_m > 0)
    assert both.mean() > 0.9
    assert np.median(np.abs(window.depth_m[both] - crop_depth[both])) < 1e-3

    assert first is not None and first_shape == (480, 640)
    assert second_shape[0] * second_shape[1] < 0.1 * 480 * 640
    assert unrecorded_shape == (480, 640)
    assert second is not None and second.distance_to(truth) < 0.02
    assert abs(wrap_angle(second.theta - truth.theta)) < math.radians(3.0)
    assert second.distance_to(first) < 0.01


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


def _detect_tag(rgb: np.ndarray):
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, HUMANOID_TAG.dictionary))
    detector = cv2.aruco.ArucoDetector(dictionary, cv2.aruco.DetectorParameters())
    corners, ids, _ = detector.detectMarkers(rgb)
    return corners, ids


def test_aruco_tag_on_the_head_is_detected_from_above(world):
    from bearchair.hardware.sim.camera import render_view
    from bearchair.hardware.sim.panda import look_at

    T_world_tag = world.nao.T_world_link("aruco_tag")
    assert T_world_tag[2, 3] == pytest.approx(HUMANOID_TAG.height_m, abs=0.005)
    eye = T_world_tag[:3, 3] + np.array([0.3, 0.1, 0.8])
    T_world_camera = look_at(eye, T_world_tag[:3, 3])
    view = render_view(world._bullet, T_world_camera, CARMINE_INTRINSICS)
    corners, ids = _detect_tag(view.rgb)
    assert ids is not None and HUMANOID_TAG.marker_id in ids.ravel()
    found = corners[list(ids.ravel()).index(HUMANOID_TAG.marker_id)][0]
    half = HUMANOID_TAG.side_m / 2.0
    object_points = np.array(
        [[-half, half, 0], [half, half, 0], [half, -half, 0], [-half, -half, 0]], np.float32
    )
    ok, rvec, tvec = cv2.solvePnP(
        object_points, found, CARMINE_INTRINSICS.matrix(), None, flags=cv2.SOLVEPNP_IPPE_SQUARE
    )
    assert ok
    T_camera_tag = np.eye(4)
    T_camera_tag[:3, :3] = cv2.Rodrigues(rvec)[0]
    T_camera_tag[:3, 3] = tvec.ravel()
    T_world_measured = T_world_camera @ T_camera_tag
    assert np.linalg.norm(T_world_measured[:3, 3] - T_world_tag[:3, 3]) < 0.03
    # The tag's x axis is the NAO's forward direction.
    forward = world.nao.true_pose().theta
    assert abs(wrap_angle(yaw_of(T_world_measured) - forward)) < math.radians(5)


def _turn(world: SimWorld, sentence: str) -> tuple[float, float, bool]:
    """Says a sentence; returns (yaw change deg, centre shift m, moving at mid-turn)."""
    before = world.T_world_chair_true()
    world.speaker.say(sentence)
    world.clock.sleep(1.5)
    mid = world.T_world_chair_true()
    world.clock.sleep(4.0)
    after = world.T_world_chair_true()
    world.clock.sleep(0.5)
    still = world.T_world_chair_true()
    assert np.allclose(after, still, atol=1e-3), "the chair must be still after the turn"
    moving = not np.allclose(mid, before, atol=1e-3) and not np.allclose(mid, after, atol=1e-3)
    turned = math.degrees(wrap_angle(yaw_of(after) - yaw_of(before)))
    shift = float(np.linalg.norm(after[:2, 3] - before[:2, 3]))
    return turned, shift, moving


SENTENCE = "Please rotate the chair about the vertical axis {} for {} degrees"


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_helper_obeys_within_ten_degrees(seed):
    with SimWorld(SimConfig(seed=seed, helper="obeys", camera_noise=False)) as world:
        turned, shift, moving = _turn(world, SENTENCE.format("counterclockwise", 60))
        assert moving
        assert 50.0 <= turned <= 70.0
        assert shift <= 0.011
        turned, _, _ = _turn(world, SENTENCE.format("clockwise", 90))
        assert -100.0 <= turned <= -80.0
        assert world.sitting_yaw_true() == pytest.approx(
            wrap_angle(yaw_of(world.T_world_chair_true())), abs=1e-9
        )


@pytest.mark.parametrize(("seed", "disobedience"), [(0, "wrong_way"), (4, "no_turn")])
def test_helper_disobeys_the_first_instruction_only(seed, disobedience):
    with SimWorld(SimConfig(seed=seed, helper="disobeys", camera_noise=False)) as world:
        first, _, _ = _turn(world, SENTENCE.format("counterclockwise", 90))
        if disobedience == "wrong_way":
            assert -100.0 <= first <= -80.0
        else:
            assert abs(first) < 0.5
        second, _, _ = _turn(world, SENTENCE.format("counterclockwise", 90))
        assert 80.0 <= second <= 100.0


def test_helper_ignores():
    with SimWorld(SimConfig(seed=0, helper="ignores", camera_noise=False)) as world:
        for _ in range(2):
            turned, shift, _ = _turn(world, SENTENCE.format("clockwise", 120))
            assert abs(turned) < 0.5 and shift < 0.002
        assert len(world.speaker.spoken) == 2


def test_walking_moves_the_nao_and_odometry_drifts_little():
    with SimWorld(SimConfig(seed=5, camera_noise=False)) as world:
        start = world.nao.true_pose()
        world.nao.set_velocity(0.3, 0.0, 0.0)  # clipped to 0.1 m/s
        world.clock.sleep(5.0)
        world.nao.stop()
        world.clock.sleep(0.5)
        end = world.nao.true_pose()
        walked = start.distance_to(end)
        assert 0.35 < walked < 0.55
        heading = math.atan2(end.y - start.y, end.x - start.x)
        assert abs(wrap_angle(heading - start.theta)) < math.radians(10)
        odometry = world.nao.pose()
        assert odometry.distance_to(end) < 0.05
        # The carried bear came along.
        bear = world.bear.T_world_bear()[:3, 3]
        assert math.hypot(bear[0] - end.x, bear[1] - end.y) < 0.2
        world.nao.set_velocity(0.0, 0.0, 0.5)
        world.clock.sleep(2.0)
        world.nao.stop()
        turned = wrap_angle(world.nao.true_pose().theta - end.theta)
        assert 0.6 < turned < 1.1


def test_place_nao_moves_the_robot_and_the_held_bear():
    with SimWorld(SimConfig(seed=5, camera_noise=False)) as world:
        T_feet_bear = np.linalg.inv(world.nao.T_world_feet()) @ world.bear.T_world_bear()
        target = SE2Pose(1.2, 0.1, 2.5)
        world.place_nao(target)
        world.clock.sleep(0.5)
        for pose in (world.nao.true_pose(), world.nao.pose()):
            assert pose.distance_to(target) < 1e-6
            assert abs(wrap_angle(pose.theta - target.theta)) < 1e-6
        for sole in ("l_sole", "r_sole"):
            assert abs(world.nao.T_world_link(sole)[2, 3]) < 0.003
        # The bear stayed in the hands, where it was relative to the feet.
        assert world.bear.held
        T_moved = np.linalg.inv(world.nao.T_world_feet()) @ world.bear.T_world_bear()
        np.testing.assert_allclose(T_moved[:3, 3], T_feet_bear[:3, 3], atol=0.005)
        with pytest.raises(ValueError):
            world.place_nao(SE2Pose(math.nan, 0.0, 0.0))


def test_joint_trajectory_keeps_feet_on_the_floor():
    with SimWorld(SimConfig(seed=0, camera_noise=False)) as world:
        nao = world.nao
        torso_before = nao.T_world_link("torso")[2, 3]
        names = ["LHipPitch", "RHipPitch", "LKneePitch", "RKneePitch", "LAnklePitch", "RAnklePitch"]
        squat = np.array([[-0.5, -0.5, 1.0, 1.0, -0.5, -0.5]])
        start_s = world.clock.now()
        nao.play_joint_trajectory(names, [1.0], squat)
        assert world.clock.now() - start_s == pytest.approx(1.0, abs=0.06)
        assert nao.joint_positions(["LKneePitch"])["LKneePitch"] == pytest.approx(1.0)
        for sole in ("l_sole", "r_sole"):
            T_world_sole = nao.T_world_link(sole)
            assert abs(T_world_sole[2, 3]) < 0.003
            assert T_world_sole[2, 2] > 0.999
        assert nao.T_world_link("torso")[2, 3] < torso_before - 0.02
        with pytest.raises(ValueError):
            nao.play_joint_trajectory(["NoSuchJoint"], [1.0], np.zeros((1, 1)))
        with pytest.raises(ValueError):
            nao.play_joint_trajectory(["LKneePitch"], [1.0], np.array([[3.0]]))


def test_judge_rejects_a_bear_on_the_floor_and_accepts_one_on_the_seat():
    with SimWorld(SimConfig(seed=0, camera_noise=False)) as world:
        world.nao.set_hands(True)
        assert not world.bear.held
        verdict = world.judge.judge(world.sitting_yaw_true(), settle_s=2.0)
        assert not verdict.seated and not verdict.on_seat
        assert "floor" in verdict.reason

        # Put the bear by hand on the box chair's seat (0.24 m), facing the sitting direction.
        T_world_chair = world.T_world_chair_true()
        seat = T_world_chair @ np.array([-0.03, 0.0, 0.245, 1.0])
        from bearchair.core.geometry import make_transform, rot_z

        world.bear.set_T_world_bear(make_transform(rot_z(world.sitting_yaw_true()), seat[:3]))
        verdict = world.judge.judge(world.sitting_yaw_true(), settle_s=2.0)
        assert verdict.seated, verdict.reason
        assert verdict.torso_tilt_deg < 10 and verdict.facing_error_deg < 10
        # The judge holds the bear to the chair's true sitting direction, not to what the
        # mission imagined: a wrong imagination cannot pass its own exam.
        verdict = world.judge.judge(wrap_angle(world.sitting_yaw_true() + math.pi), settle_s=0.1)
        assert verdict.seated and verdict.facing_error_deg < 10
        # Backwards, its legs (0.13 m long) pointing at the backrest: set it forward on
        # the seat so that they clear it.
        seat_front = T_world_chair @ np.array([0.04, 0.0, 0.245, 1.0])
        backwards = make_transform(rot_z(world.sitting_yaw_true() + math.pi), seat_front[:3])
        world.bear.set_T_world_bear(backwards)
        verdict = world.judge.judge(world.sitting_yaw_true(), settle_s=1.0)
        assert not verdict.seated and "facing" in verdict.reason


@pytest.mark.parametrize("placement", ["accessible", "inaccessible"])
def test_placement_sets_the_sitting_direction(placement):
    for seed in range(4):
        with SimWorld(SimConfig(seed=seed, placement=placement, camera_noise=False)) as world:
            sitting = world.sitting_yaw_true()
            centre = world.T_world_chair_true()[:3, 3]
            start = DEFAULT_ARENA.humanoid_start
            toward_humanoid = math.atan2(start.y - centre[1], start.x - centre[0])
            off = abs(wrap_angle(sitting - toward_humanoid))
            if placement == "accessible":
                assert off <= math.radians(30.5)
            else:
                errors = [
                    abs(wrap_angle(sitting - d)) for d in (math.pi, math.pi / 2, -math.pi / 2)
                ]
                assert min(errors) <= math.radians(30.5)


def test_same_seed_same_world():
    poses = []
    for _ in range(2):
        with SimWorld(SimConfig(seed=11)) as world:
            frame = world.panda.capture()
            poses.append((world.T_world_chair_true(), frame.depth_m))
    np.testing.assert_array_equal(poses[0][0], poses[1][0])
    np.testing.assert_array_equal(poses[0][1], poses[1][1])


def test_test_built_box_chair_mesh_file_loads(tmp_path):
    import trimesh

    seat = trimesh.creation.box(extents=(0.3, 0.3, 0.04))
    seat.apply_translation((0, 0, 0.25))
    legs = [
        trimesh.creation.box(extents=(0.03, 0.03, 0.23)).apply_translation((sx, sy, 0.115))
        for sx in (-0.13, 0.13)
        for sy in (-0.13, 0.13)
    ]
    back = trimesh.creation.box(extents=(0.03, 0.3, 0.3)).apply_translation((-0.135, 0, 0.42))
    path = tmp_path / "chair.ply"
    trimesh.util.concatenate([seat, *legs, back]).export(path)
    with SimWorld(SimConfig(chair_path=path, front_yaw_deg=0.0, camera_noise=False)) as world:
        world.clock.sleep(1.0)
        mesh = world.chair_mesh_true
        assert mesh.bounds[0, 2] == pytest.approx(0.0, abs=0.01)
        assert mesh.bounds[1, 2] == pytest.approx(0.57, abs=0.01)


def test_missing_chair_file_is_one_clear_error(tmp_path):
    from bearchair.core.meshes import MeshLoadError

    with pytest.raises(MeshLoadError, match="no such file"):
        SimWorld(SimConfig(chair_path=tmp_path / "absent.obj"))


@pytest.mark.shared
@pytest.mark.slow
def test_every_calibration_mesh_loads_into_the_world():
    import json

    if not (SHARED_CHAIRS / "manifest.json").exists():
        pytest.skip(f"no calibration meshes at {SHARED_CHAIRS}")
    manifest = json.loads((SHARED_CHAIRS / "manifest.json").read_text())
    problems = []
    for entry in manifest["meshes"]:
        config = SimConfig(
            chair_path=SHARED_CHAIRS / entry["file"],
            front_yaw_deg=entry["front_yaw_deg"],
            camera_noise=False,
            seed=1,
        )
        with SimWorld(config) as world:
            world.clock.sleep(0.5)
            T_start = world.T_world_chair_true()
            world.clock.sleep(0.5)
            T_end = world.T_world_chair_true()
            mesh = world.chair_mesh_true
            name = entry["file"]
            footprint = np.ptp(world.chair.mesh_local.vertices[:, :2], axis=0)
            if mesh.bounds[0, 2] < -0.02:
                problems.append(f"{name} sank into the floor")
            if np.linalg.norm(T_end[:3, 3] - T_start[:3, 3]) > 0.01:
                problems.append(f"{name} still moving after 1 s")
            # Sofas and big tables do not fit between the arena's walls and get pushed.
            fits = float(np.hypot(*footprint)) < 1.0
            if fits and abs(mesh.bounds[1, 2] - entry["height_m"]) > 0.03:
                problems.append(
                    f"{name} top at {mesh.bounds[1, 2]:.3f} m, not upright on the floor"
                )
            if (entry["front_yaw_deg"] is None) != (world.sitting_yaw_true() is None):
                problems.append(f"{name}: sitting direction known iff the manifest gives it")
    assert not problems, "; ".join(problems)


def test_simulated_run_records_the_ground_truth(tmp_path):
    import json

    from bearchair.executive.config import RunConfig
    from bearchair.executive.run import run_in_simulation
    from bearchair.testing.scripted import ScriptedSkills

    summary = run_in_simulation(
        RunConfig(seed=0, out_dir=tmp_path, mute=True, timeout_s=120.0), skills=ScriptedSkills()
    )
    truth = json.loads((tmp_path / "summary.json").read_text())["ground_truth"]
    assert summary.ground_truth is not None and truth == summary.ground_truth.to_json()
    with SimWorld(SimConfig(seed=0, camera_noise=False)) as world:
        true_yaw = world.sitting_yaw_true()
    assert truth["sitting_yaw_deg"] == pytest.approx(math.degrees(true_yaw), abs=0.01)
    assert summary.sitting_pose is not None
    imagined = math.radians(summary.sitting_pose.yaw_deg)
    expected = abs(math.degrees(wrap_angle(imagined - true_yaw)))
    assert truth["sitting_yaw_error_deg"] == pytest.approx(expected, abs=0.02)


def test_the_chair_collides_as_its_own_surface_not_as_convex_pieces(tmp_path):
    from bearchair.core.geometry import make_transform, rot_z
    from bearchair.core.meshes import box_chair_mesh

    # An armchair whose armrest panels stand 12 cm above the seat: convex pieces of the
    # seat and its sides would bridge them and hold the bear at the armrests' height.
    seat_top_m = 0.30
    chair_path = tmp_path / "armchair.obj"
    box_chair_mesh(seat_height_m=seat_top_m, armrest_height_m=seat_top_m + 0.12).export(chair_path)
    config = SimConfig(chair_path=chair_path, front_yaw_deg=0.0, camera_noise=False)
    with SimWorld(config) as world:
        world.nao.set_hands(True)
        T_world_chair = world.T_world_chair_true()
        above_seat = T_world_chair @ np.array([0.0, 0.0, seat_top_m + 0.03, 1.0])
        world.bear.set_T_world_bear(make_transform(rot_z(world.sitting_yaw_true()), above_seat[:3]))
        verdict = world.judge.judge(world.sitting_yaw_true(), settle_s=1.5)
        assert verdict.seated, verdict.reason
        # The bear frame's origin is its seat point: it rests on the seat itself.
        assert world.bear.T_world_bear()[2, 3] == pytest.approx(seat_top_m, abs=0.006)


def test_the_nao_reaching_into_the_chair_is_recorded(world):
    assert world.chair_touch.deepest.depth_m == 0.0
    T_world_chair = world.T_world_chair_true()
    sitting = world.sitting_yaw_true()
    # Feet 12 cm in front of the seat's centre, facing the chair: the shins are in the seat.
    feet_xy = T_world_chair[:2, 3] + 0.12 * np.array([math.cos(sitting), math.sin(sitting)])
    world.place_nao(SE2Pose(float(feet_xy[0]), float(feet_xy[1]), wrap_angle(sitting + math.pi)))
    world.clock.sleep(0.05)
    touch = world.chair_touch.deepest
    assert touch.depth_m > 0.01 and touch.nao_link
    world.place_nao(DEFAULT_ARENA.humanoid_start)


def test_a_bear_reclining_against_a_reclined_back_is_seated(tmp_path):
    import trimesh

    from bearchair.core.geometry import make_transform, rot_z
    from bearchair.hardware.seating_criteria import MAX_RECLINE_DEG, MAX_TILT_DEG, _leans_back

    # A garden chair: seat top 0.24 m, its backrest reclined 38 deg from vertical.
    seat = trimesh.creation.box(extents=(0.28, 0.32, 0.03)).apply_translation((0, 0, 0.225))
    legs = [
        trimesh.creation.box(extents=(0.03, 0.03, 0.21)).apply_translation((sx, sy, 0.105))
        for sx in (-0.125, 0.125)
        for sy in (-0.145, 0.145)
    ]
    recline = np.radians(38.0)
    back = trimesh.creation.box(extents=(0.03, 0.32, 0.34))
    back.apply_transform(trimesh.transformations.rotation_matrix(-recline, (0, 1, 0)))
    back.apply_translation((-0.14 - 0.17 * np.sin(recline), 0, 0.24 + 0.17 * np.cos(recline)))
    path = tmp_path / "garden.ply"
    trimesh.util.concatenate([seat, *legs, back]).export(path)
    with SimWorld(SimConfig(chair_path=path, front_yaw_deg=0.0, camera_noise=False)) as world:
        world.nao.set_hands(True)
        T_world_chair = world.T_world_chair_true()
        yaw = world.sitting_yaw_true()
        # Sat 12 cm in front of the backrest, leaning back: it falls back against it.
        seat_point = T_world_chair @ np.array([-0.02, 0.0, 0.245, 1.0])
        lean_back = make_transform(rot_z(yaw), np.zeros(3)) @ make_transform(
            trimesh.transformations.rotation_matrix(-recline, (0, 1, 0))[:3, :3], np.zeros(3)
        )
        lean_back[:3, 3] = seat_point[:3]
        world.bear.set_T_world_bear(lean_back)
        verdict = world.judge.judge(yaw, settle_s=1.5)
        assert MAX_TILT_DEG < verdict.torso_tilt_deg < MAX_RECLINE_DEG
        assert verdict.seated, verdict.reason
    # Leaning back, not forward or sideways: only then does the back support count.
    facing = np.array([1.0, 0.0, 0.0])
    assert _leans_back(np.array([-0.5, 0.0, 0.8]), facing)
    assert not _leans_back(np.array([0.5, 0.0, 0.8]), facing)
    assert not _leans_back(np.array([0.0, 0.5, 0.8]), facing)


def _wide_sofa_file(tmp_path: Path) -> Path:
    """A 1.6 m sofa (as wide as the cell in front of the arm is deep), front along +x."""
    from bearchair.testing.chairgen import generate_chair

    mesh = generate_chair(0, "sofa").mesh.copy()
    mesh.apply_scale([1.0, 1.6 / float(np.ptp(mesh.vertices[:, 1])), 1.0])
    path = tmp_path / "wide-sofa.obj"
    mesh.export(path)
    return path


def test_a_sofa_larger_than_the_chair_area_is_set_down_clear_of_the_arm(tmp_path):
    from bearchair.hardware.sim.chair_set_down import SET_DOWN_CLEARANCE_M, SET_DOWN_STEP_M

    path = _wide_sofa_file(tmp_path)
    arm_front = max(box.x_max for box in DEFAULT_ARENA.obstacles)
    moved = 0
    for placement, seed in [(p, s) for p in ("accessible", "inaccessible") for s in range(3)]:
        config = SimConfig(
            chair_path=path, front_yaw_deg=0.0, placement=placement, camera_noise=False, seed=seed
        )
        with SimWorld(config) as world:
            vertices = np.asarray(world.chair_mesh_true.vertices)
            closest = world._bullet.getClosestPoints(world.chair.body, world.panda.body, 1.0)
            assert min(point[8] for point in closest) >= SET_DOWN_CLEARANCE_M - 1e-3, seed
            assert vertices[:, 0].min() >= arm_front + SET_DOWN_CLEARANCE_M - 1e-3, seed
            nao = world._bullet.getClosestPoints(world.chair.body, world.nao.body, 1.0)
            assert min((point[8] for point in nao), default=1.0) >= SET_DOWN_CLEARANCE_M - 1e-3
            centre = world.T_world_chair_true()[:3, 3]
            # Pulled out to the set-down line (drawn where it stood through the arm).
            moved += vertices[:, 0].min() < arm_front + SET_DOWN_CLEARANCE_M + SET_DOWN_STEP_M
            # The helper's rule still holds: the placement's sitting direction.
            start = DEFAULT_ARENA.humanoid_start
            toward = math.atan2(start.y - centre[1], start.x - centre[0])
            if placement == "accessible":
                assert abs(wrap_angle(world.sitting_yaw_true() - toward)) <= math.radians(45.0)
    assert moved, "no draw needed moving: the test would not test"


def test_a_chair_that_fits_the_cell_stands_where_it_was_drawn():
    # The box chair drawn clear of the arm is not moved: the same worlds as before.
    for seed in range(4):
        with SimWorld(SimConfig(seed=seed, camera_noise=False)) as world:
            area = DEFAULT_ARENA.chair_area
            x, y = world.T_world_chair_true()[:2, 3]
            assert area.x_min <= x <= area.x_max and area.y_min <= y <= area.y_max
