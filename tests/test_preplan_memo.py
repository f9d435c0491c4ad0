"""The pre-plan memo: the same question is planned once, a turned chair is a new one, and
the memo stays bounded."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearchair.core.geometry import SittingPose, make_transform, rot_z
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.skills.planning.preplan import (
    PREPLANS,
    PreplanMemo,
    SeatingCheck,
    wholebody_validator,
)
from bearchair.skills.planning.stance import goal_on_ray

SITTING_POSE = SittingPose(np.array([0.0, 0.0, 0.29]), 0.0)


@pytest.mark.slow
def test_a_question_asked_twice_is_planned_once_and_answered_alike() -> None:
    chair_mesh = box_chair_mesh()
    se2_goal = goal_on_ray(SITTING_POSE, 0.33)
    hits = PREPLANS.hits
    first = wholebody_validator(chair_mesh, SITTING_POSE, se2_goal)
    second = wholebody_validator(chair_mesh.copy(), SITTING_POSE, se2_goal)
    assert PREPLANS.hits == hits + 1
    assert second == first


def test_a_turned_chair_another_sitting_pose_or_another_stance_is_a_new_question() -> None:
    chair_mesh = box_chair_mesh()
    turned = chair_mesh.copy().apply_transform(
        make_transform(rot_z(math.radians(30.0)), np.zeros(3))
    )
    key = PreplanMemo.key(chair_mesh, SITTING_POSE, SE2Pose(0.3, 0.0, math.pi))
    assert PreplanMemo.key(turned, SITTING_POSE, SE2Pose(0.3, 0.0, math.pi)) != key
    assert PreplanMemo.key(chair_mesh, SITTING_POSE, SE2Pose(0.31, 0.0, math.pi)) != key
    # The same seat point, another sitting direction; another seat point.
    for other in (
        SittingPose(SITTING_POSE.position.copy(), math.radians(10.0)),
        SittingPose(SITTING_POSE.position + np.array([0.01, 0.0, 0.0]), SITTING_POSE.yaw),
    ):
        assert PreplanMemo.key(chair_mesh, other, SE2Pose(0.3, 0.0, math.pi)) != key
    assert PreplanMemo.key(chair_mesh.copy(), SITTING_POSE, SE2Pose(0.3, 0.0, math.pi)) == key


def test_the_memo_forgets_the_least_recently_used_answer_beyond_its_size() -> None:
    memo = PreplanMemo(max_size=2)
    memo.put(("a",), SeatingCheck("a"))
    memo.put(("b",), SeatingCheck("b"))
    assert memo.get(("a",)) == SeatingCheck("a")  # "b" is now the least recently used
    memo.put(("c",), SeatingCheck("c"))
    assert memo.get(("b",)) is None
    assert memo.get(("a",)) == SeatingCheck("a") and memo.get(("c",)) == SeatingCheck("c")


def test_the_runtime_reset_forgets_the_process_wide_answers() -> None:
    """What keeps the tests above independent of order (the suite's fixture resets the
    runtime before each test): the process-wide memo is registered and cleared by it."""
    from bearchair.core.runtime import RUNTIME

    PREPLANS.put(("a question",), SeatingCheck("an answer"))
    assert PREPLANS.get(("a question",)) is not None
    RUNTIME.reset()
    assert PREPLANS.get(("a question",)) is None and len(PREPLANS) == 0
