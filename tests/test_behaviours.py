"""Every mission leaf with stubbed skills: success, failure, RUNNING across ticks,
interruption, and an exception in the skill (per-tick assertions, py_trees style)."""

from __future__ import annotations

import math
import time

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.accessibility import CheckAccessibility, CheckSeatReachable
from bearchair.behaviours.assistance import (
    InstructHelper,
    MeasureChairRotation,
    WaitUntilChairStill,
)
from bearchair.behaviours.imagine import ImagineOnSeatView, ImagineSitting
from bearchair.behaviours.scan import LookAtSeat, LookFromAbove, ScanChair
from bearchair.behaviours.seat import ReleaseAndStand, SeatBear
from bearchair.behaviours.walk import WalkToChair
from bearchair.core.arena import DEFAULT_ARENA
from bearchair.core.geometry import SittingPose
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.hardware.interfaces import SeatingJudgement
from bearchair.skills.mission_skills import SkillNotReady
from bearchair.skills.results import (
    AccessibilityResult,
    ImaginationResult,
    RotationChoice,
    SeatReachability,
    WalkResult,
)
from bearchair.testing import tick_until_done, write_blackboard
from bearchair.testing.scripted import ScriptedSkills, default_results

DEFAULTS = default_results()

# leaf class, the skill it calls, a result that makes it fail (None: cannot fail by result)
NO_SITTING = ImaginationResult(False, None, 0, 56, (), {}, "no correct sitting")

LEAVES = [
    (ScanChair, "scan_chair", None),
    (LookFromAbove, "look_from_above", None),
    (LookAtSeat, "look_at_seat", None),
    (ImagineSitting, "imagine_sitting", NO_SITTING),
    (ImagineOnSeatView, "imagine_sitting", None),
    (
        CheckSeatReachable,
        "check_seat_reachable",
        SeatReachability(False, "seat too high for the NAO: seat 0.47 m", 0.47),
    ),
    (
        CheckAccessibility,
        "check_accessibility",
        AccessibilityResult(
            False, None, DEFAULTS["imagine_sitting"].sitting_pose, (), "goal outside the arena"
        ),
    ),
    (InstructHelper, "choose_rotation", RotationChoice(0.0, False, "no rotation helps", 11)),
    (WaitUntilChairStill, "wait_until_chair_still", None),
    (MeasureChairRotation, "measure_chair_rotation", None),
    (WalkToChair, "walk_path", WalkResult(False, 0.2, 0.3, 60.0, "timed out")),
    (SeatBear, "plan_seating", None),
    (ReleaseAndStand, "release_and_stand", None),
]


def fill_blackboard() -> None:
    """Everything a leaf may read, as earlier stages would have left it."""
    values = {
        keys.SEED: 7,
        keys.ARENA: DEFAULT_ARENA,
        keys.CHAIR_SCAN: DEFAULTS["scan_chair"],
        keys.CHAIR_MESH: DEFAULTS["scan_chair"].chair_mesh,
        keys.IMAGINATION: NO_SITTING,
        keys.CHAIR_POINTS: DEFAULTS["scan_chair"].chair_points,
        keys.SEAT_VIEW: "one more view from (0.49, -0.19, 0.90) m",
        keys.SITTING_POSE: DEFAULTS["imagine_sitting"].sitting_pose,
        keys.ACCESSIBILITY: DEFAULTS["check_accessibility"],
        keys.SEATING_PLAN: DEFAULTS["plan_seating"],
    }
    write_blackboard(values)


def make(leaf_class, skills, judge=None):
    fill_blackboard()
    leaf = leaf_class()
    leaf.setup(skills=skills, robot=fake_robot(judge=judge))
    return leaf


@pytest.mark.parametrize(("leaf_class", "skill", "_"), LEAVES)
def test_leaf_succeeds_with_its_skill_result(leaf_class, skill, _):
    skills = ScriptedSkills()
    leaf = make(leaf_class, skills)
    statuses = tick_until_done(leaf)
    assert statuses[-1] == Status.SUCCESS, leaf.feedback_message
    assert len(skills.calls[skill]) == 1
    assert leaf.feedback_message


@pytest.mark.parametrize(
    ("leaf_class", "skill", "failing"), [leaf for leaf in LEAVES if leaf[2] is not None]
)
def test_leaf_fails_on_a_negative_result_and_says_why(leaf_class, skill, failing):
    leaf = make(leaf_class, ScriptedSkills({skill: failing}))
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert failing.reason in leaf.feedback_message


@pytest.mark.parametrize(("leaf_class", "skill", "_"), LEAVES)
def test_leaf_is_running_while_its_skill_works(leaf_class, skill, _):
    leaf = make(leaf_class, ScriptedSkills(delays_s={skill: 0.3}))
    leaf.tick_once()
    assert leaf.status == Status.RUNNING
    started = time.monotonic()
    leaf.tick_once()
    assert time.monotonic() - started < 0.1, "update() must poll, not wait for the skill"
    assert leaf.status == Status.RUNNING
    assert "(" in leaf.feedback_message  # elapsed time is shown
    assert tick_until_done(leaf)[-1] == Status.SUCCESS


@pytest.mark.parametrize(("leaf_class", "skill", "_"), LEAVES)
def test_interrupting_a_leaf_cancels_its_skill(leaf_class, skill, _):
    skills = ScriptedSkills(delays_s={skill: 5.0})
    leaf = make(leaf_class, skills)
    leaf.tick_once()
    time.sleep(0.05)
    assert leaf.status == Status.RUNNING
    leaf.stop(Status.INVALID)
    assert leaf.status == Status.INVALID
    assert leaf.feedback_message == "cancelled"
    if "cancel" not in skills.calls[skill][0][1]:
        return  # a short skill with no cancel hook: the leaf only drops its result
    deadline = time.monotonic() + 2.0
    while skill not in skills.cancelled and time.monotonic() < deadline:
        time.sleep(0.01)
    assert skill in skills.cancelled, "the skill did not see the cancel event"


@pytest.mark.parametrize(("leaf_class", "skill", "_"), LEAVES)
def test_an_exception_in_the_skill_fails_the_leaf_with_the_error(leaf_class, skill, _):
    leaf = make(leaf_class, ScriptedSkills({skill: RuntimeError("camera unplugged")}))
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert "camera unplugged" in leaf.feedback_message


def test_a_missing_skill_fails_at_its_leaf_naming_it():
    leaf = make(
        ImagineSitting,
        ScriptedSkills(
            {"imagine_sitting": SkillNotReady("skill 'imagine_sitting' is not implemented")}
        ),
    )
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert "imagine_sitting" in leaf.feedback_message


@pytest.mark.parametrize(
    ("height_change_m", "kept"), [(-0.13, False), (0.09, False), (-0.03, True)]
)
def test_after_a_turn_a_sitting_at_another_height_is_no_sitting(height_change_m, kept):
    before = DEFAULTS["imagine_sitting"].sitting_pose
    moved = before._replace(position=before.position + np.array([0.1, 0.0, height_change_m]))
    found = DEFAULTS["imagine_sitting"]._replace(sitting_pose=moved)
    fill_blackboard()
    leaf = ImagineSitting()
    leaf.setup(skills=ScriptedSkills({"imagine_sitting": found}), robot=fake_robot())
    status = tick_until_done(leaf)[-1]
    imagination = py_trees.blackboard.Blackboard.get(keys.IMAGINATION)
    if kept:
        assert status == Status.SUCCESS and imagination.found
        assert py_trees.blackboard.Blackboard.get(keys.SITTING_POSE) is moved
        return
    # No sitting, as the look from above that follows needs, and g left as it was.
    assert status == Status.FAILURE and not imagination.found
    assert f"{abs(height_change_m):.3f} m" in leaf.feedback_message
    assert "the chair was sat at before the turn" in leaf.feedback_message
    assert py_trees.blackboard.Blackboard.get(keys.SITTING_POSE) is before


def test_a_missing_blackboard_input_fails_without_calling_the_skill():
    skills = ScriptedSkills()
    leaf = ImagineSitting()
    leaf.setup(skills=skills, robot=fake_robot())
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert "/mission/seed" in leaf.feedback_message or "/chair/mesh" in leaf.feedback_message
    assert not skills.calls["imagine_sitting"]


def test_leaf_without_injected_skills_fails_clearly():
    fill_blackboard()
    leaf = ScanChair()
    leaf.setup()
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert "skills" in leaf.feedback_message


def test_measure_rotation_carries_the_sitting_pose_with_the_chair():
    leaf = make(MeasureChairRotation, ScriptedSkills())
    before = DEFAULTS["imagine_sitting"].sitting_pose
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    after = py_trees.blackboard.Blackboard.get(keys.SITTING_POSE)
    # the stub turns the chair -90 deg about the world's z axis through the origin
    np.testing.assert_allclose(after.position, [0.0, -0.6, 0.28], atol=1e-9)
    assert after.yaw == pytest.approx(before.yaw - np.pi / 2)
    mesh_after = py_trees.blackboard.Blackboard.get(keys.CHAIR_MESH)
    np.testing.assert_allclose(mesh_after.bounds.mean(axis=0)[:2], [0.0, -0.6], atol=1e-9)


def test_a_second_turn_is_measured_against_the_chair_as_the_first_left_it():
    """The leaf writes the measured chair (``chair_points``) back as the next reference,
    so a second turn is registered onto the chair where it now stands, not where it was
    scanned (which would measure the sum of the turns)."""
    references: list[np.ndarray] = []
    step_m = np.array([0.1, 0.0, 0.0])  # each scripted measurement moves the chair 10 cm

    def measure(arm, reference_points, requested_yaw_rad=None):
        references.append(np.asarray(reference_points))
        return DEFAULTS["measure_chair_rotation"]._replace(
            chair_points=np.asarray(reference_points) + step_m
        )

    skills = ScriptedSkills({"measure_chair_rotation": measure})
    first = make(MeasureChairRotation, skills)
    assert tick_until_done(first)[-1] == Status.SUCCESS
    second = MeasureChairRotation(name="MeasureAgain")
    second.setup(skills=skills, robot=fake_robot())
    assert tick_until_done(second)[-1] == Status.SUCCESS
    scanned = DEFAULTS["scan_chair"].chair_points
    np.testing.assert_allclose(references[0], scanned)
    np.testing.assert_allclose(references[1], scanned + step_m)
    np.testing.assert_allclose(
        py_trees.blackboard.Blackboard.get(keys.CHAIR_POINTS), scanned + 2 * step_m
    )
    assert len(py_trees.blackboard.Blackboard.get(keys.MEASURED_ROTATIONS)) == 2


def test_instruct_helper_speaks_and_counts():
    skills = ScriptedSkills()
    fill_blackboard()
    robot = fake_robot()
    leaf = InstructHelper()
    leaf.setup(skills=skills, robot=robot)
    tick_until_done(leaf)
    leaf.stop(Status.INVALID)
    tick_until_done(leaf)
    sentence = DEFAULTS["compose_instruction"].sentence
    assert robot.speaker.spoken == [sentence, sentence]
    assert py_trees.blackboard.Blackboard.get(keys.ROTATIONS) == 2
    assert py_trees.blackboard.Blackboard.get(keys.INSTRUCTIONS) == [sentence, sentence]
    requested = DEFAULTS["choose_rotation"].rotation_rad
    assert py_trees.blackboard.Blackboard.get(keys.REQUESTED_ROTATION) == requested


def test_the_turn_asked_for_reaches_the_measurement():
    """The registration judges a weak fit against the turn asked for, so the leaf passes
    what InstructHelper wrote (and None before anything was asked)."""
    skills = ScriptedSkills()
    leaf = make(MeasureChairRotation, skills)
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    py_trees.blackboard.Blackboard.set(keys.REQUESTED_ROTATION, -np.pi)
    again = MeasureChairRotation(name="MeasureAgain")
    again.setup(skills=skills, robot=fake_robot())
    assert tick_until_done(again)[-1] == Status.SUCCESS
    asked = [kwargs["requested_yaw_rad"] for _, kwargs in skills.calls["measure_chair_rotation"]]
    assert asked == [None, -np.pi]


def test_instruct_helper_asks_for_nothing_when_no_rotation_helps():
    reason = "no rotation about the vertical axis makes the chair accessible (wall)"
    skills = ScriptedSkills(results={"choose_rotation": RotationChoice(0.0, False, reason, 11)})
    fill_blackboard()
    robot = fake_robot()
    leaf = InstructHelper()
    leaf.setup(skills=skills, robot=robot)
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert leaf.feedback_message == reason
    assert robot.speaker.spoken == [] and not skills.calls["compose_instruction"]
    _, kwargs = skills.calls["choose_rotation"][0]
    assert kwargs == {"seed": 7}


def test_release_fails_when_the_judge_says_not_seated():
    judge = FakeJudge(SeatingJudgement(False, False, 80.0, 10.0, "bear on the floor"))
    leaf = make(ReleaseAndStand, ScriptedSkills(), judge=judge)
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert "bear on the floor" in leaf.feedback_message
    assert py_trees.blackboard.Blackboard.get(keys.JUDGEMENT).torso_tilt_deg == 80.0


def test_release_succeeds_when_seated():
    leaf = make(ReleaseAndStand, ScriptedSkills(), judge=FakeJudge())
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    assert "seated" in leaf.feedback_message


def _raised_approach() -> AccessibilityResult:
    raise_at = SE2Pose(1.02, 0.0, math.pi)
    return DEFAULTS["check_accessibility"]._replace(raise_at=raise_at)


def test_seat_bear_raises_the_bear_and_steps_in_when_the_check_says_so():
    skills = ScriptedSkills()
    leaf = make(SeatBear, skills)
    py_trees.blackboard.Blackboard.set(keys.ACCESSIBILITY, _raised_approach())
    assert tick_until_done(leaf)[-1] == Status.SUCCESS, leaf.feedback_message
    assert len(skills.calls["raise_bear"]) == 1
    (walked,) = skills.calls["walk_path"]
    assert walked[0][3][-1] == DEFAULTS["check_accessibility"].se2_goal
    assert skills.calls["plan_seating"][0][1]["raised"] is True


def test_seat_bear_walks_in_without_raising_by_default():
    skills = ScriptedSkills()
    assert tick_until_done(make(SeatBear, skills))[-1] == Status.SUCCESS
    assert not skills.calls["raise_bear"] and not skills.calls["walk_path"]
    assert skills.calls["plan_seating"][0][1]["raised"] is False


def test_seat_bear_fails_when_the_step_in_falls_short():
    skills = ScriptedSkills({"walk_path": WalkResult(False, 0.1, 0.0, 20.0, "timed out")})
    leaf = make(SeatBear, skills)
    py_trees.blackboard.Blackboard.set(keys.ACCESSIBILITY, _raised_approach())
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert "stepping in with the bear raised: timed out" in leaf.feedback_message
    assert not skills.calls["plan_seating"]


@pytest.mark.parametrize("used", [True, False])
def test_imagine_says_when_the_backrest_gave_the_direction(used):
    import math

    from bearchair.skills.imagination.backrest import BackrestCheck

    check = BackrestCheck(0.0, 0.12, math.radians(45.0 if used else 10.0), used)
    result = DEFAULTS["imagine_sitting"]._replace(backrest=check)
    leaf = make(ImagineSitting, ScriptedSkills({"imagine_sitting": result}))
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    assert ("direction from the backrest" in leaf.feedback_message) == used
    if used:
        assert "+45 deg off" in leaf.feedback_message


def test_imagine_says_when_the_vote_stood_against_the_backrest():
    import math

    from bearchair.skills.imagination.backrest import BackrestCheck

    check = BackrestCheck(0.0, 0.08, math.radians(-46.0), False, 0.37, 0.86)
    result = DEFAULTS["imagine_sitting"]._replace(backrest=check)
    leaf = make(ImagineSitting, ScriptedSkills({"imagine_sitting": result}))
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    assert "direction from the backrest" not in leaf.feedback_message
    assert "-46 deg off, mirrors the chair less (0.37 against 0.86)" in leaf.feedback_message


@pytest.mark.parametrize("seat_seen", [True, False])
def test_check_seat_reachable_refuses_only_what_the_scan_shows(seat_seen):
    verdict = SeatReachability(False, "seat out of the NAO's reach", 0.31, seat_seen=seat_seen)
    leaf = make(CheckSeatReachable, ScriptedSkills({"check_seat_reachable": verdict}))
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert leaf.feedback_message.startswith("refused: ") == seat_seen
    assert "seat out of the NAO's reach" in leaf.feedback_message
    if not seat_seen:
        assert "the scan shows no seat under the sitting point" in leaf.feedback_message


def test_look_from_above_replaces_the_scan_the_later_leaves_read():
    skills = ScriptedSkills()
    leaf = make(LookFromAbove, skills)
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    (_arm, scan), kwargs = skills.calls["look_from_above"][0]
    assert scan is DEFAULTS["scan_chair"] and kwargs["seed"] == 7
    board = py_trees.blackboard.Client(name="reader")
    for key in (keys.CHAIR_SCAN, keys.CHAIR_MESH, keys.CHAIR_POINTS):
        board.register_key(key=key, access=py_trees.common.Access.READ)
    looked = skills.results["look_from_above"]
    assert board.get(keys.CHAIR_SCAN) is looked and board.get(keys.CHAIR_MESH) is looked.chair_mesh
    assert "10 views" in leaf.feedback_message


@pytest.mark.parametrize("imagination", ["found", "none"])
def test_look_from_above_looks_only_after_an_imagination_found_no_sitting(imagination):
    """After an imagination that found a sitting, or one that raised (no result), another
    view would mend nothing: the leaf fails at once, without moving the arm, and says why
    the leaf it backs up failed."""
    skills = ScriptedSkills()
    fill_blackboard()
    if imagination == "found":
        write_blackboard({keys.IMAGINATION: DEFAULTS["imagine_sitting"]})
    else:
        py_trees.blackboard.Blackboard.unset(keys.IMAGINATION)
    backed_up = ImagineSitting(name="ImagineOnScan")
    backed_up.feedback_message = "skill 'imagine_sitting' is not implemented"
    leaf = LookFromAbove(backs_up=backed_up)
    leaf.setup(skills=skills, robot=fake_robot())
    assert tick_until_done(leaf)[-1] == Status.FAILURE
    assert not skills.calls["look_from_above"]
    assert leaf.feedback_message == (
        "no look from above (ImagineOnScan: skill 'imagine_sitting' is not implemented)"
    )


def _sitting_pose_now():
    board = py_trees.blackboard.Client(name="reader")
    board.register_key(key=keys.SITTING_POSE, access=py_trees.common.Access.READ)
    return board.get(keys.SITTING_POSE)


def test_imagine_on_seat_view_imagines_on_the_completed_scan_and_takes_its_sitting():
    moved = SittingPose(np.array([0.62, 0.05, 0.43]), 0.4)
    found = DEFAULTS["imagine_sitting"]._replace(sitting_pose=moved)
    skills = ScriptedSkills({"imagine_sitting": found})
    leaf = make(ImagineOnSeatView, skills)
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    ((chair_mesh,), kwargs) = skills.calls["imagine_sitting"][0]
    assert chair_mesh is DEFAULTS["scan_chair"].chair_mesh and kwargs["seed"] == 7
    assert _sitting_pose_now() is moved
    assert leaf.feedback_message.startswith("again with the seat view: sit at (0.620, 0.050")


def test_imagine_on_seat_view_does_nothing_when_no_view_was_added():
    skills = ScriptedSkills()
    leaf = make(ImagineOnSeatView, skills)
    write_blackboard({keys.SEAT_VIEW: ""})
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    assert not skills.calls["imagine_sitting"]
    assert _sitting_pose_now() is DEFAULTS["imagine_sitting"].sitting_pose


def test_imagine_on_seat_view_keeps_the_sitting_when_the_completed_scan_gives_none():
    skills = ScriptedSkills({"imagine_sitting": NO_SITTING})
    leaf = make(ImagineOnSeatView, skills)
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    assert len(skills.calls["imagine_sitting"]) == 1
    assert _sitting_pose_now() is DEFAULTS["imagine_sitting"].sitting_pose
    assert "no correct sitting): the one imagined before stands" in leaf.feedback_message


@pytest.mark.parametrize("seen", [True, False])
def test_look_at_seat_keeps_a_scan_that_shows_the_seat_and_takes_the_one_with_the_look(seen):
    looked = DEFAULTS["look_from_above"]
    script = (lambda arm, scan, sitting_pose, **_: scan) if seen else looked
    skills = ScriptedSkills({"look_at_seat": script})
    leaf = make(LookAtSeat, skills)
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    (_arm, scan, sitting_pose), kwargs = skills.calls["look_at_seat"][0]
    assert scan is DEFAULTS["scan_chair"] and kwargs["seed"] == 7
    assert sitting_pose is DEFAULTS["imagine_sitting"].sitting_pose
    board = py_trees.blackboard.Client(name="reader")
    board.register_key(key=keys.CHAIR_MESH, access=py_trees.common.Access.READ)
    expected = DEFAULTS["scan_chair"] if seen else looked
    assert board.get(keys.CHAIR_MESH) is expected.chair_mesh
    assert ("no seat under the sitting point" in leaf.feedback_message) != seen
    board.register_key(key=keys.SEAT_VIEW, access=py_trees.common.Access.READ)
    assert bool(board.get(keys.SEAT_VIEW)) != seen
