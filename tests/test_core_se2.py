"""SE(2) as a group (core.se2): each operation against the matrices it stands for."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearchair.core.geometry import wrap_angle
from bearchair.core.se2 import SE2Pose


def random_poses(count: int, seed: int = 0) -> list[SE2Pose]:
    rng = np.random.default_rng(seed)
    return [
        SE2Pose(float(x), float(y), float(t))
        for x, y, t in zip(
            rng.uniform(-3, 3, count),
            rng.uniform(-3, 3, count),
            rng.uniform(-4, 4, count),
            strict=True,
        )
    ]


def same(a: SE2Pose, b: SE2Pose, tol: float = 1e-12) -> bool:
    return (
        abs(a.x - b.x) < tol and abs(a.y - b.y) < tol and abs(wrap_angle(a.theta - b.theta)) < tol
    )


@pytest.mark.parametrize("a,b", list(zip(random_poses(20, 1), random_poses(20, 2), strict=True)))
def test_compose_is_the_matrix_product(a, b):
    product = a.as_matrix() @ b.as_matrix()
    assert np.allclose((a @ b).as_matrix(), product, atol=1e-12)
    assert same(a.compose(b), SE2Pose.from_transform(a.as_transform() @ b.as_transform()))


@pytest.mark.parametrize("a", random_poses(20, 3))
def test_inverse_undoes_the_pose_on_either_side(a):
    assert np.allclose(a.inverse().as_matrix(), np.linalg.inv(a.as_matrix()), atol=1e-12)
    assert same(a @ a.inverse(), SE2Pose.identity())
    assert same(a.inverse() @ a, SE2Pose.identity())


def test_composition_is_associative_and_between_is_the_relative_pose():
    for a, b, c in zip(random_poses(10, 4), random_poses(10, 5), random_poses(10, 6), strict=True):
        assert same((a @ b) @ c, a @ (b @ c), tol=1e-11)
        assert same(a.between(b), a.inverse() @ b)
        assert same(a @ a.between(b), b, tol=1e-11)


def test_apply_maps_body_points_into_the_parent_frame():
    pose = SE2Pose(1.0, 2.0, math.pi / 2)
    points = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    assert np.allclose(pose.apply(points), [[1.0, 3.0], [0.0, 2.0], [1.0, 2.0]])
    assert np.allclose(pose.apply(points[0]), [1.0, 3.0])


def test_headings_stay_wrapped():
    turned = SE2Pose(0.0, 0.0, 3.0) @ SE2Pose(0.0, 0.0, 3.0)
    assert -math.pi <= turned.theta < math.pi
    assert math.isclose(turned.theta, 6.0 - 2 * math.pi)


def test_transformed_follows_a_rigid_motion_of_the_world():
    # The chair (and what stands on it) turned by 90 deg about a point off the origin.
    pivot = np.array([0.5, -0.2, 0.0])
    T = np.eye(4)
    T[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = pivot - T[:3, :3] @ pivot
    moved = SE2Pose(1.5, -0.2, 0.0).transformed(T)
    assert same(moved, SE2Pose(0.5, 0.8, math.pi / 2))


def test_a_pose_in_a_record_has_its_units_in_the_keys():
    pose = SE2Pose(1.23456, -0.5, math.pi / 2)
    assert pose.to_json() == {"x_m": 1.2346, "y_m": -0.5, "theta_deg": 90.0}


def test_the_blackboard_and_the_accessibility_result_record_a_goal_alike():
    # Both are in the same ticks.jsonl line: the goal on its own and inside the result.
    from bearchair.core.geometry import SittingPose
    from bearchair.executive.records.jsonable import to_jsonable
    from bearchair.skills.results import AccessibilityResult

    goal = SE2Pose(0.7, 0.1, -2.0)
    result = AccessibilityResult(True, goal, SittingPose(np.zeros(3), 0.0), (goal,))
    assert to_jsonable(goal) == to_jsonable(result)["se2_goal"] == goal.to_json()
    assert set(goal.to_json()) == {"x_m", "y_m", "theta_deg"}
