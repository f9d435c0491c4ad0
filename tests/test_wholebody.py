"""Whole-body seating: the goal posture and trajectory meet their constraints, checked
independently with the forward kinematics; infeasible requests fail cleanly."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from bearchair.core.geometry import SittingPose
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.nao_carrying import (
    BEAR_COM_AHEAD_M,
    BEAR_COM_HEIGHT_M,
    BEAR_SEAT_BELOW_HANDS_M,
    BEAR_SEAT_CLEARANCE_M,
    CARRYING_POSTURE_RAD,
    PALM_IN_WRIST_M,
    PLACEMENT_TOLERANCE_M,
)
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.wholebody import (
    RAISED_POSTURE,
    STANCE,
    STANDING_POSTURE,
    InfeasibleSeating,
    SeatingCancelled,
    execute_seating,
    plan_raise,
    plan_seating,
    plan_seating_where_standing,
    preplan_approach,
    preplan_seating,
    release_and_stand,
)
from bearchair.skills.planning.wholebody.chair_profile import (
    BAND_HALF_WIDTH_M,
    HANDS_ABOVE_SEAT_M,
    RAIL_CLEARANCE_M,
    largest_horizontal_surface_height,
)
from bearchair.skills.planning.wholebody.goal import goal_posture_candidates
from bearchair.skills.planning.wholebody.held_bear import (
    BEAR_DEPTH_M,
    BEAR_HEIGHT_M,
    BEAR_SNOUT_M,
    BEAR_SNOUT_Z_M,
)
from bearchair.skills.planning.wholebody.nao_model import (
    DRIVEN_JOINTS,
    joint_values,
    link_transforms,
    parse_urdf,
    planar_nao,
)
from bearchair.skills.planning.wholebody.optimisation import (
    BEAR_LEAN_BACK_RAD,
    BEAR_TILT_GOAL_RAD,
    COARSE_KNOTS,
    NO_RELEASED_BEAR,
    released_bear,
    seating_problems,
)
from bearchair.skills.planning.wholebody.posture_check import exact_posture_violation
from bearchair.skills.planning.wholebody.scene import seating_scene
from bearchair.skills.planning.wholebody.trajectory import PLANNING_VELOCITY_RADPS, solve_trajectory

SEAT_HEIGHT_M = 0.24
# The box chair faces +x; g sits 2 cm above the seat, 2 cm in front of the seat's middle.
SITTING_POSE = SittingPose(np.array([0.02, 0.0, SEAT_HEIGHT_M + 0.02]), 0.0)
# The NAO faces the chair (-x), 0.3 m in front of g.
NAO_POSE = SE2Pose(0.32, 0.0, math.pi)


@pytest.fixture(scope="module")
def chair():
    return box_chair_mesh(seat_height_m=SEAT_HEIGHT_M)


@pytest.fixture(scope="module")
def plan(chair):
    return plan_seating(chair, SITTING_POSE, NAO_POSE)


def _planar(positions_rad: np.ndarray) -> np.ndarray:
    """Back from qibullet joint angles to q = (ankle, knee, hip, shoulder, elbow)."""
    column = {name: i for i, name in enumerate(DRIVEN_JOINTS)}
    left = positions_rad[
        :, [column[n] for n in ("LAnklePitch", "LKneePitch", "LHipPitch", "LShoulderPitch")]
    ]
    right = positions_rad[
        :, [column[n] for n in ("RAnklePitch", "RKneePitch", "RHipPitch", "RShoulderPitch")]
    ]
    np.testing.assert_allclose(left, right)  # pitch axes are +y on both sides
    elbow_left = -positions_rad[:, column["LElbowRoll"]]
    elbow_right = positions_rad[:, column["RElbowRoll"]]
    np.testing.assert_allclose(elbow_left, elbow_right)  # the roll limits mirror
    return np.column_stack([left, elbow_left])


def _frames(q: np.ndarray) -> dict[str, np.ndarray]:
    return planar_nao().numeric_frames(q)


def _com_x(q: np.ndarray, bear_base_and_up: tuple[np.ndarray, np.ndarray] | None) -> float:
    """Centre of mass x from the URDF's link masses, computed here independently."""
    _, links = parse_urdf()
    frames = _frames(q)
    total, mass = 0.0, 0.0
    for name, link in links.items():
        if link.mass_kg > 0 and name in frames:
            point = frames[name][:3, :3] @ link.com + frames[name][:3, 3]
            total += link.mass_kg * point[0]
            mass += link.mass_kg
    if bear_base_and_up is not None:
        base, up = bear_base_and_up
        total += 0.2 * (base + 0.09 * up)[0]
        mass += 0.2
    return total / mass


def _hands_frame(frames: dict[str, np.ndarray]) -> np.ndarray:
    """The simulator's rule: the palms' middle, the mean of both palms' orientations."""
    palm = np.eye(4)
    palm[:3, 3] = PALM_IN_WRIST_M
    left, right = frames["l_wrist"] @ palm, frames["r_wrist"] @ palm
    q_left = Rotation.from_matrix(left[:3, :3]).as_quat()
    q_right = Rotation.from_matrix(right[:3, :3]).as_quat()
    if q_left @ q_right < 0:
        q_right = -q_right
    hands = np.eye(4)
    hands[:3, :3] = Rotation.from_quat(q_left + q_right).as_matrix()
    hands[:3, 3] = (left[:3, 3] + right[:3, 3]) / 2
    return hands


def _bear(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(base, forward, up) of the held bear in the NAO's (x, z) plane, in 3D.

    The bear was handed over upright, 6.5 cm below the palms, in the carrying posture,
    and stays rigidly attached to the hands frame.
    """
    carrying = _hands_frame(link_transforms(CARRYING_POSTURE_RAD))
    T_carry_bear = np.eye(4)
    T_carry_bear[:3, 3] = carrying[:3, 3] - [0.0, 0.0, BEAR_SEAT_BELOW_HANDS_M]
    T_hands_bear = np.linalg.inv(carrying) @ T_carry_bear
    values = {name: float(v) for name, v in joint_values(q).items()}
    T_bear = _hands_frame(link_transforms(values)) @ T_hands_bear
    assert abs(T_bear[1, 3]) < 1e-6 and abs(T_bear[1, 0]) < 1e-6  # stays in the plane
    return T_bear[[0, 2], 3], T_bear[[0, 2], 0], T_bear[[0, 2], 2]


def _sample_points(q: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Points along the NAO's leg, torso, head and arm chain in the (x, z) plane."""
    frames = _frames(q)
    chain = [
        "l_ankle",
        "LTibia",
        "LThigh",
        "torso",
        "Head",
        "LBicep",
        "LElbow",
        "l_wrist",
        "l_gripper",
    ]
    points = [(name, frames[name][:3, 3][[0, 2]]) for name in chain]
    for a, b in (("l_ankle", "LTibia"), ("LTibia", "LThigh"), ("LBicep", "LElbow")):
        mid = 0.5 * (frames[a][:3, 3] + frames[b][:3, 3])
        points.append((f"{a}-{b}", mid[[0, 2]]))
    return points


def _chair_clearance(point: np.ndarray, chair_points: np.ndarray) -> float:
    """Distance from a point to the chair's cross-section points (NAO frame, x-z)."""
    return float(np.min(np.linalg.norm(chair_points - point, axis=1)))


def _chair_section(chair) -> np.ndarray:
    """The box chair's surface near the NAO's sagittal plane, in the NAO's (x, z)."""
    T_nao_world = np.linalg.inv(NAO_POSE.as_transform())
    points = chair.sample(40000, seed=0)
    points = points @ T_nao_world[:3, :3].T + T_nao_world[:3, 3]
    band = np.abs(points[:, 1]) <= 0.13
    return points[band][:, [0, 2]]


def test_goal_posture_meets_every_constraint(chair, plan):
    q_all = _planar(plan.positions_rad)
    q_goal = q_all[-1]
    nao = planar_nao()
    # Joint limits: the URDF's limits of every driven joint on both sides.
    joints, _ = parse_urdf()
    for column, name in enumerate(DRIVEN_JOINTS):
        joint = joints[name]
        assert joint.lower - 1e-6 <= plan.positions_rad[-1, column] <= joint.upper + 1e-6, name
    # Bear placement: its base at g in the NAO frame, within the tolerance.
    scene = seating_scene(chair, SITTING_POSE, NAO_POSE)
    np.testing.assert_allclose(scene.g_xz, [0.30, SEAT_HEIGHT_M + BEAR_SEAT_CLEARANCE_M], atol=1e-9)
    base, forward, up = _bear(q_goal)
    assert np.max(np.abs(base - scene.g_xz)) <= PLACEMENT_TOLERANCE_M + 1e-6
    # Never let go higher than g: the bear drops what the hands hold it over the seat.
    assert base[1] <= scene.g_xz[1] + 1e-6
    # Upright bear, facing the sitting direction (the NAO's -x).
    assert abs(math.asin(forward[1])) <= BEAR_TILT_GOAL_RAD + 1e-6
    # ... let go leaning back toward the backrest, not forward over the seat's front.
    assert math.asin(up[0]) == pytest.approx(BEAR_LEAN_BACK_RAD, abs=math.radians(2.0))
    # Centre of mass inside the feet's support interval with the margin.
    x_back, x_front = nao.support_x
    com_x = _com_x(q_goal, (base, up))
    assert x_back + 0.01 - 1e-6 <= com_x <= x_front - 0.01 + 1e-6
    # No collision: every body sample point and the bear's outline clear the chair's
    # actual surface (not the planner's blocks).
    section = _chair_section(chair)
    for name, point in _sample_points(q_goal):
        assert _chair_clearance(point, section) >= 0.02, name
    seat_top = SEAT_HEIGHT_M
    bear_x = base[0] + np.array([-1, 1]) * BEAR_DEPTH_M / 2
    assert base[1] >= seat_top - 1e-6  # the bear's bottom is on or above the seat
    backrest_front_nao = NAO_POSE.x - (-0.14 + 0.03)  # backrest's front face, NAO frame
    assert bear_x.max() <= backrest_front_nao
    assert base[1] + BEAR_HEIGHT_M > seat_top
    # The torso's bending is what the optimisation kept small: not folded over.
    assert abs(sum(q_goal[:3])) < 1.2


@pytest.mark.slow
def test_trajectory_is_stable_and_within_velocity_limits(chair, plan):
    q_all = _planar(plan.positions_rad)
    times = plan.times_s
    assert len(times) == len(q_all) >= 3
    assert np.all(np.diff(times) > 0)
    speeds = np.abs(np.diff(q_all, axis=0)) / np.diff(times)[:, None]
    assert speeds.max() <= PLANNING_VELOCITY_RADPS + 1e-3
    assert np.all(planar_nao().velocity_limit > PLANNING_VELOCITY_RADPS)
    x_back, x_front = planar_nao().support_x
    section = _chair_section(chair)
    # The knots and the postures halfway between them, which the robot passes through.
    halfway = (q_all[1:] + q_all[:-1]) / 2.0
    for q in np.vstack([q_all, halfway]):
        base, _, up = _bear(q)
        com_x = _com_x(q, (base, up))
        assert x_back <= com_x <= x_front
        for name, point in _sample_points(q):
            assert _chair_clearance(point, section) >= 0.015, name
    # It starts standing with the bear where the carrying posture holds it.
    np.testing.assert_allclose(q_all[0], STANDING_POSTURE)
    carrying = _hands_frame(link_transforms(CARRYING_POSTURE_RAD))
    base, _, _ = _bear(q_all[0])
    np.testing.assert_allclose(
        base, carrying[[0, 2], 3] - [0.0, BEAR_SEAT_BELOW_HANDS_M], atol=0.005
    )


def test_a_urdf_joint_without_its_parent_is_refused(tmp_path):
    urdf = tmp_path / "broken.urdf"
    urdf.write_text(
        '<robot name="r"><link name="a"/><link name="b"/>'
        '<joint name="j" type="revolute"><child link="b"/></joint></robot>'
    )
    with pytest.raises(ValueError, match="'link'"):
        parse_urdf(str(urdf))


def test_carrying_posture_matches_the_simulator():
    nao_sim = pytest.importorskip("bearchair.hardware.sim.nao")
    assert nao_sim.HOLDING_POSTURE_RAD.items() >= CARRYING_POSTURE_RAD.items()


def test_the_bear_the_planner_sees_is_the_simulated_bear():
    from bearchair.hardware.bear_model import bear_centre_of_mass

    com = bear_centre_of_mass()
    assert com[0] == pytest.approx(BEAR_COM_AHEAD_M, abs=5e-4)
    assert com[2] == pytest.approx(BEAR_COM_HEIGHT_M, abs=2e-3)


def test_carrying_posture_holds_the_bear_high_stably_within_limits():
    joints, _ = parse_urdf()
    for name, value in CARRYING_POSTURE_RAD.items():
        assert joints[name].lower <= value <= joints[name].upper, name
    frames = link_transforms(CARRYING_POSTURE_RAD)
    hands = _hands_frame(frames)
    seat_point = hands[:3, 3] - [0.0, 0.0, BEAR_SEAT_BELOW_HANDS_M]
    # High enough to carry the bear over seats of about 0.30 m, the ears below the tag.
    assert seat_point[2] >= 0.31
    assert seat_point[2] + BEAR_HEIGHT_M < 0.58
    assert abs(seat_point[1]) < 1e-6
    # Standing straight with the bear: the centre of mass over the feet, with a margin.
    _, links = parse_urdf()
    total, mass = 0.2 * (seat_point[0]), 0.2
    for name, link in links.items():
        if link.mass_kg > 0 and name in frames:
            total += link.mass_kg * (frames[name][:3, :3] @ link.com + frames[name][:3, 3])[0]
            mass += link.mass_kg
    x_back, x_front = planar_nao().support_x
    assert x_back + 0.02 <= total / mass <= x_front - 0.02
    # The planar start posture has the palms where the carrying posture has them.
    start = _hands_frame(_frames(STANDING_POSTURE))
    assert np.linalg.norm(start[[0, 2], 3] - hands[[0, 2], 3]) < 0.003
    pitch = Rotation.from_matrix(start[:3, :3] @ hands[:3, :3].T).magnitude()
    assert pitch < math.radians(2.0)


def test_retract_releases_upright_and_stable(chair, plan):
    q_all = _planar(plan.retract_positions_rad)
    np.testing.assert_allclose(q_all[0], _planar(plan.positions_rad)[-1])
    assert np.all(np.diff(plan.retract_times_s) > 0)
    x_back, x_front = planar_nao().support_x
    for q in q_all:
        assert x_back <= _com_x(q, None) <= x_front
    # The hands first withdraw back and up while the legs hold still.
    legs_still = np.all(np.abs(q_all[:, :3] - q_all[0, :3]) < 1e-9, axis=1)
    withdrawn = q_all[int(np.argmin(legs_still)) - 1]
    hand_start = _frames(q_all[0])["l_gripper"][[0, 2], 3]
    hand_withdrawn = _frames(withdrawn)["l_gripper"][[0, 2], 3]
    # At least 2 cm back and up each (the bear's arms, which the palms hold, are 3.6 cm
    # thick); how far of RETRACT_OFFSETS_M the arms get depends on their joint limits.
    assert hand_withdrawn[0] < hand_start[0] - 0.02
    assert hand_withdrawn[1] > hand_start[1] + 0.02
    # Ends upright: torso pitch zero, arms down.
    assert abs(sum(q_all[-1][:3])) < 1e-6
    assert q_all[-1][3] > 1.0


def test_retract_keeps_the_head_and_torso_off_the_bear_it_let_go(chair, plan):
    # The bear stays where it was let go (its box: 0.10 m deep, 0.25 m tall); standing
    # up, the head and torso must not sweep through it and knock it off the seat.
    # Nor through its snout, which stands out of that box toward the NAO: no deeper than
    # where the bear was let go.
    q_all = _planar(plan.retract_positions_rad)
    base, forward, up = _bear(q_all[0])
    let_go_in_snout_m = released_bear(seating_problems().geometry(q_all[0]))[4]
    assert let_go_in_snout_m < 0.01
    snout_low, snout_high = BEAR_SNOUT_Z_M
    for q in q_all:
        frames = _frames(q)
        for link, offset, radius in (
            ("Head", (0, 0, 0.05), 0.055),
            ("torso", (0.045, 0, 0.09), 0.02),
        ):
            point = (frames[link] @ np.r_[offset, 1.0])[[0, 2]]
            rel = point - base
            along, height = float(rel @ forward), float(rel @ up)
            outside = max(abs(along) - BEAR_DEPTH_M / 2, height - BEAR_HEIGHT_M, -height)
            assert outside >= radius, (link, q)
            face = BEAR_DEPTH_M / 2  # forward faces the NAO: the snout is at along > face
            snout = max(
                face - along, along - face - BEAR_SNOUT_M, snout_low - height, height - snout_high
            )
            assert snout >= radius - let_go_in_snout_m - 1e-6, (link, q)


def test_a_released_bear_is_an_obstacle_for_the_body_not_a_load(chair, plan):
    problems = seating_problems()
    profile = seating_scene(chair, SITTING_POSE, NAO_POSE).profile
    q_goal = _planar(plan.positions_rad)[-1]
    standing = STANDING_POSTURE
    # A bear resting 6 cm ahead of the standing NAO's head is in its way...
    head = problems.geometry(standing).body_points["head"]
    in_the_way = np.array([head[0] + 0.06, head[1] - 0.2, 1.0, 0.0, 0.0])
    worst, group, _ = exact_posture_violation(
        problems,
        standing,
        profile,
        g_xz=None,
        tilt_rad=math.pi,
        bear_held=False,
        released=in_the_way,
    )
    assert group == "bear-body collision" and worst > 0.01
    # ...none is not, and the released bear where it was let go is clear of the goal.
    for released in (NO_RELEASED_BEAR, released_bear(problems.geometry(q_goal))):
        worst, _, _ = exact_posture_violation(
            problems,
            q_goal,
            profile,
            g_xz=None,
            tilt_rad=math.pi,
            bear_held=False,
            released=released,
        )
        assert worst <= 1e-4


def test_where_the_nao_stops_does_not_change_the_chair_it_plans_against(chair):
    # An armrest whose inner face lies 2 mm inside the band the NAO's arms sweep.
    armrest = trimesh.creation.box(
        extents=(0.2, 0.03, 0.02),
        transform=trimesh.transformations.translation_matrix(
            (0.0, -(BAND_HALF_WIDTH_M - 0.002) - 0.015, 0.32)
        ),
    )
    armchair = trimesh.util.concatenate([chair, armrest])
    profiles = {
        seating_scene(armchair, SITTING_POSE, SE2Pose(NAO_POSE.x, y, NAO_POSE.theta)).profile
        for y in (-0.005, 0.0, 0.005)  # the walk stops within 5 mm of its goal
    }
    assert len({round(p.seat_top_z, 6) for p in profiles}) == 1


def test_a_rail_at_the_band_edge_raises_the_seat_whichever_way_the_nao_stops_turned(chair):
    # A rail in the hands' way, its top sloping 20 deg (no horizontal face: a scanned
    # armrest's top is rarely flat), its inner edge 1 mm inside the band: a turn of the
    # NAO within the walk's stop box moves the rail's top in and out of the band.
    rail_top_m = SEAT_HEIGHT_M + 0.068
    rail = trimesh.creation.box(
        extents=(0.2, 0.03, 0.01),
        transform=trimesh.transformations.rotation_matrix(math.radians(20.0), (1, 0, 0)),
    )
    (_, y_low, _), (_, _, z_high) = rail.bounds
    rail.apply_translation((0.0, BAND_HALF_WIDTH_M - 0.001 - y_low, rail_top_m - z_high))
    railed = trimesh.util.concatenate([chair, rail])
    highest = rail_top_m - HANDS_ABOVE_SEAT_M + RAIL_CLEARANCE_M
    for turn_deg in (-2.5, 0.0, 2.5):
        pose = SE2Pose(NAO_POSE.x, NAO_POSE.y, NAO_POSE.theta + math.radians(turn_deg))
        scene = seating_scene(railed, SITTING_POSE, pose)
        # Raised for the part of the rail inside the band (its top slopes 1 cm across).
        assert highest - 0.011 <= scene.profile.seat_top_z <= highest + 1e-3, turn_deg
        # Not something standing on the seat in front of the bear.
        assert scene.profile.back_front_x > scene.g_xz[0], turn_deg


@pytest.mark.parametrize("rail_above_seat_m", [0.045, 0.068])
def test_rails_beside_the_bear_raise_the_seat_only_as_far_as_the_palms_must_clear_them(
    chair, rail_above_seat_m
):
    # Rails on both sides, 0.09 m from the bear's centre line: beside its lane, under the
    # hands.
    rails = [
        trimesh.creation.box(
            extents=(0.2, 0.03, 0.01),
            transform=trimesh.transformations.translation_matrix(
                (0.0, side * 0.09, SEAT_HEIGHT_M + rail_above_seat_m - 0.005)
            ),
        )
        for side in (-1.0, 1.0)
    ]
    railed = trimesh.util.concatenate([chair, *rails])
    seat_top = seating_scene(railed, SITTING_POSE, NAO_POSE).profile.seat_top_z
    if rail_above_seat_m <= HANDS_ABOVE_SEAT_M:
        assert seat_top == pytest.approx(SEAT_HEIGHT_M, abs=1e-3)  # the bear's own seat
    else:
        expected = SEAT_HEIGHT_M + rail_above_seat_m - HANDS_ABOVE_SEAT_M + RAIL_CLEARANCE_M
        assert seat_top == pytest.approx(expected, abs=1e-3)


def test_bear_one_metre_away_is_out_of_reach(chair):
    with pytest.raises(InfeasibleSeating, match="bear placement") as info:
        preplan_seating(chair, SITTING_POSE, SE2Pose(1.02, 0.0, math.pi))
    assert info.value.constraint == "bear placement"
    assert "1.00 m forward" in str(info.value)


@pytest.mark.slow
def test_from_where_it_stopped_p_slides_into_reach_on_a_deep_seat() -> None:
    deep_chair = box_chair_mesh(seat_height_m=SEAT_HEIGHT_M, seat_depth_m=0.40)
    stopped_short = SE2Pose(0.37, 0.0, math.pi)
    with pytest.raises(InfeasibleSeating, match="out of reach"):
        plan_seating(deep_chair, SITTING_POSE, stopped_short)
    plan = plan_seating_where_standing(deep_chair, SITTING_POSE, stopped_short)
    assert len(plan.times_s) > 2
    # Too far for the 3 cm slides, or for the seat: the first failure is reported.
    with pytest.raises(InfeasibleSeating, match=r"0\.38 m forward"):
        plan_seating_where_standing(deep_chair, SITTING_POSE, SE2Pose(0.40, 0.0, math.pi))


def test_seat_one_metre_high_is_out_of_reach() -> None:
    tall_chair = box_chair_mesh(seat_height_m=1.0, overall_height_m=1.3)
    high = SittingPose(np.array([0.02, 0.0, 1.06]), 0.0)
    with pytest.raises(InfeasibleSeating, match="bear placement") as info:
        plan_seating(tall_chair, high, NAO_POSE)
    # The bear goes BEAR_SEAT_CLEARANCE_M over the seat's top, not at the sitter's pelvis.
    assert f"{1.0 + BEAR_SEAT_CLEARANCE_M:.2f} m high" in str(info.value)


def test_bear_is_set_down_just_over_the_seat_not_at_the_pelvis(chair) -> None:
    pelvis_high = SittingPose(SITTING_POSE.position + np.array([0.0, 0.0, 0.08]), 0.0)
    scene = seating_scene(chair, pelvis_high, NAO_POSE)
    assert scene.g_xz[1] == pytest.approx(SEAT_HEIGHT_M + BEAR_SEAT_CLEARANCE_M, abs=0.005)


def test_nao_facing_away_and_standing_inside_the_chair_fail_cleanly(chair):
    with pytest.raises(InfeasibleSeating) as info:
        plan_seating(chair, SITTING_POSE, SE2Pose(0.32, 0.0, 0.0))
    assert info.value.constraint == "sitting direction"
    with pytest.raises(InfeasibleSeating) as info:
        plan_seating(chair, SITTING_POSE, SE2Pose(0.15, 0.0, math.pi))
    assert info.value.constraint == STANCE


@pytest.mark.slow
def test_repeated_solves_reuse_the_built_problems(chair):
    problems = seating_problems()
    plan_seating(chair, SITTING_POSE, SE2Pose(0.30, 0.01, math.pi - 0.05))
    assert seating_problems() is problems


def test_seat_height_from_the_largest_horizontal_surface(chair):
    assert largest_horizontal_surface_height(chair) == pytest.approx(SEAT_HEIGHT_M, abs=0.005)


class _RecordingHumanoid:
    def __init__(self, cancel: threading.Event | None = None) -> None:
        self.calls: list[tuple] = []
        self.cancel = cancel

    def play_joint_trajectory(self, joint_names, times_s, positions_rad) -> None:
        self.calls.append(("play", tuple(joint_names), len(times_s), positions_rad.shape))
        if self.cancel is not None:
            self.cancel.set()

    def set_hands(self, open_hands: bool) -> None:
        self.calls.append(("hands", open_hands))


def test_execute_and_release_drive_the_humanoid(plan):
    humanoid = _RecordingHumanoid()
    execute_seating(humanoid, plan)
    release_and_stand(humanoid, plan)
    assert [c[0] for c in humanoid.calls] == ["play", "hands", "play"]
    assert humanoid.calls[1] == ("hands", True)
    assert humanoid.calls[0][1] == DRIVEN_JOINTS
    assert humanoid.calls[2][2] == len(plan.retract_times_s)


def test_cancel_stops_execution(plan):
    cancel = threading.Event()
    humanoid = _RecordingHumanoid(cancel)
    with pytest.raises(SeatingCancelled):
        execute_seating(humanoid, plan, cancel=cancel)
    with pytest.raises(SeatingCancelled):
        release_and_stand(humanoid, plan, cancel=cancel)
    assert [c[0] for c in humanoid.calls] == ["play"]


@pytest.mark.slow
def test_over_a_seat_higher_than_the_carried_bear_the_nao_raises_it_first(chair) -> None:
    high_chair = box_chair_mesh(seat_height_m=0.33, overall_height_m=0.6)
    sitting = SittingPose(np.array([0.02, 0.0, 0.35]), 0.0)
    se2_goal = SE2Pose(0.28, 0.0, math.pi)
    # Carried low (seat point 0.32 m), the bear would stand in the seat.
    with pytest.raises(InfeasibleSeating) as info:
        plan_seating(high_chair, sitting, se2_goal)
    assert info.value.constraint == STANCE and info.value.carried_bear
    raise_at = preplan_approach(high_chair, sitting, se2_goal)
    assert raise_at is not None
    # Back along the ray (the NAO faces -x), facing the same way.
    assert raise_at.x > se2_goal.x and raise_at.y == pytest.approx(0.0)
    assert raise_at.theta == pytest.approx(se2_goal.theta)
    times_s, positions = plan_raise(high_chair, sitting, raise_at)
    assert np.all(np.diff(times_s) > 0.0)
    np.testing.assert_allclose(_planar(positions)[-1], RAISED_POSTURE, atol=1e-6)
    # Raising at s_goal itself would put the bear through the seat's front.
    with pytest.raises(InfeasibleSeating):
        plan_raise(high_chair, sitting, se2_goal)
    plan = plan_seating(high_chair, sitting, se2_goal, raised=True)
    np.testing.assert_allclose(_planar(plan.positions_rad)[0], RAISED_POSTURE, atol=1e-6)
    # A seat under the carried bear needs no raise.
    assert preplan_approach(chair, SITTING_POSE, NAO_POSE) is None


def test_a_trajectory_is_solved_on_coarse_knots_when_they_hold_between_knots(chair):
    problems = seating_problems()
    scene = seating_scene(chair, SITTING_POSE, NAO_POSE)
    q_goal = next(goal_posture_candidates(problems, scene))
    _, knots = solve_trajectory(problems, scene.profile, STANDING_POSTURE, q_goal, bear_held=True)
    assert len(knots) <= COARSE_KNOTS < problems.n_knots


def test_a_centre_of_mass_off_the_feet_where_it_stopped_slides_p_closer(monkeypatch) -> None:
    from bearchair.skills.planning.wholebody import seating

    deep_chair = box_chair_mesh(seat_height_m=SEAT_HEIGHT_M, seat_depth_m=0.40)
    tried: list[float] = []

    def leaning_too_far(chair_mesh, sitting_pose, humanoid_pose, *, raised=False):
        tried.append(float(sitting_pose.position[0]))
        if len(tried) == 1:
            raise InfeasibleSeating("support polygon", "centre of mass violated by 0.001")
        return "plan"

    monkeypatch.setattr(seating, "plan_seating", leaning_too_far)
    assert seating.plan_seating_where_standing(deep_chair, SITTING_POSE, NAO_POSE) == "plan"
    assert tried[1] > tried[0]  # p moved toward the NAO (+x)

    def colliding(chair_mesh, sitting_pose, humanoid_pose, *, raised=False):
        raise InfeasibleSeating("chair collision", "knee")

    monkeypatch.setattr(seating, "plan_seating", colliding)
    with pytest.raises(InfeasibleSeating, match="knee"):
        seating.plan_seating_where_standing(deep_chair, SITTING_POSE, NAO_POSE)


def test_the_problems_build_in_the_background_and_the_fine_trajectory_on_first_use() -> None:
    from bearchair.skills.planning.wholebody import optimisation

    builder = optimisation.start_building_problems()
    builder.join(timeout=60.0)
    assert not builder.is_alive()
    problems = optimisation.seating_problems()
    assert problems is optimisation.seating_problems()
    fine = problems.trajectory_solver(problems.n_knots)
    assert fine is problems.trajectory_solver(problems.n_knots)
    assert fine is not problems.trajectory_solver(optimisation.COARSE_KNOTS)
