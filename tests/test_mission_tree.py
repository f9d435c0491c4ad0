"""The mission tree end to end with stubbed skills: the stage order, the assistance loop
(0 to 3 rotations, then failure), failure naming the leaf, and the run record."""

from __future__ import annotations

import json
import time

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.core.errors import RunRecordError
from bearchair.executive.records.replay import RecordedRun
from bearchair.executive.records.run_record import RunRecorder
from bearchair.executive.records.run_summary import RunInfo
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.executive.tree_render import render_text
from bearchair.hardware.fakes import fake_robot
from bearchair.skills.mission_skills import SkillNotReady
from bearchair.skills.perception.errors import RegistrationError
from bearchair.skills.results import AccessibilityResult, SeatReachability
from bearchair.testing.scripted import ScriptedSkills, default_results
from bearchair.trees.mission import STAGES, create_tree
from bearchair.trees.options import TreeOptions
from tests.helpers.missions import run_scripted_mission

DEFAULTS = default_results()
ACCESSIBLE = DEFAULTS["check_accessibility"]
BLOCKED = AccessibilityResult(False, None, ACCESSIBLE.sitting_pose, (), "s_goal outside the arena")


def test_the_tree_has_the_mission_stages_in_order():
    root = create_tree()
    assert isinstance(root, py_trees.composites.Sequence) and root.memory
    assert tuple(child.name for child in root.children) == STAGES


def test_every_leaf_is_a_named_behaviour_with_no_hardware_before_setup():
    for node in create_tree().iterate():
        assert node.name
        if not node.children and hasattr(node, "robot"):
            assert node.robot is None and node.skills is None


def test_accessible_mission_succeeds_without_instructions():
    summary, _ = run_scripted_mission(ScriptedSkills())
    assert summary.outcome == "success", summary.reason
    assert summary.failed_stage is None
    assert [s.status for s in summary.stages] == ["SUCCESS"] * len(STAGES)
    assert summary.rotations == 0 and summary.instructions == ()
    assert summary.judgement is not None and summary.judgement.seated is True
    assert summary.sitting_pose is not None and summary.sitting_pose.yaw_deg == 0.0


@pytest.mark.parametrize("rotations_needed", [1, 2, 3])
def test_assistance_loop_asks_until_accessible(rotations_needed):
    checks = [BLOCKED] * rotations_needed + [ACCESSIBLE]
    skills = ScriptedSkills({"check_accessibility": checks})
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "success", summary.reason
    assert summary.rotations == rotations_needed
    assert len(summary.instructions) == rotations_needed
    assert len(skills.calls["measure_chair_rotation"]) == rotations_needed
    assert len(skills.calls["check_accessibility"]) == rotations_needed + 1
    assert len(skills.calls["walk_path"]) == 1


def test_a_turned_chair_no_fit_accepts_is_scanned_and_imagined_anew():
    rejected = RegistrationError("chair registration rejected: visible overlap 0.78 (need 0.88)")
    skills = ScriptedSkills(
        {"check_accessibility": [BLOCKED, ACCESSIBLE], "measure_chair_rotation": rejected}
    )
    summary, runner = run_scripted_mission(skills)
    assert summary.outcome == "success", summary.reason
    assert summary.rotations == 1
    assert len(skills.calls["scan_chair"]) == 2 and len(skills.calls["imagine_sitting"]) == 2
    # The second accessibility check asks about the chair as scanned anew.
    assert len(skills.calls["check_accessibility"]) == 2
    assert any("registration rejected" in failure for failure in summary.failures)
    statuses = {node.name: node.status for node in runner.root.iterate()}
    assert statuses["ScanTurnedChair"] == statuses["ImagineTurnedChair"] == Status.SUCCESS


def test_assistance_loop_gives_up_after_the_third_rotation():
    skills = ScriptedSkills({"check_accessibility": BLOCKED})
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "failure"
    assert summary.failed_stage == "MakeChairAccessible"
    assert summary.rotations == 3
    assert len(skills.calls["compose_instruction"]) == 3
    assert summary.reason == (
        "GiveUp: chair not accessible after 3 rotation(s) (at most 3); last failure: "
        "CheckAccessibilityAgain: not accessible: s_goal outside the arena"
    )
    # Every leaf failure, in order: the first check, each check after a turn, GiveUp.
    assert list(summary.failures) == [
        "CheckAccessibility: not accessible: s_goal outside the arena",
        *["CheckAccessibilityAgain: not accessible: s_goal outside the arena"] * 3,
        summary.reason,
    ]
    assert not skills.calls["walk_path"]
    statuses = {s.name: s.status for s in summary.stages}
    assert statuses["WalkToChair"] == "INVALID"


def test_a_seat_out_of_reach_is_refused_before_anyone_is_asked_to_turn_it():
    refusal = SeatReachability(
        False,
        "seat too high for the NAO: seat 0.47 m, the NAO places a bear at most 0.40 m high",
        0.47,
    )
    skills = ScriptedSkills({"check_seat_reachable": refusal})
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "failure"
    assert summary.failed_stage == "CheckSeatReachable"
    assert summary.reason.startswith("CheckSeatReachable: refused: seat too high for the NAO")
    assert summary.rotations == 0 and summary.instructions == ()
    assert not skills.calls["compose_instruction"] and not skills.calls["check_accessibility"]
    assert not skills.calls["walk_path"]


NO_SITTING = default_results()["imagine_sitting"]._replace(
    found=False, sitting_pose=None, reason="no correct sitting in 80 drops"
)


def test_no_sitting_on_the_scan_looks_from_above_and_the_mission_goes_on():
    skills = ScriptedSkills(
        {"imagine_sitting": [NO_SITTING, NO_SITTING, default_results()["imagine_sitting"]]}
    )
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "success", summary.reason
    # Two looks, each followed by the imagination on the chair reconstructed with it.
    assert len(skills.calls["look_from_above"]) == 2
    assert len(skills.calls["imagine_sitting"]) == 3
    looked = skills.results["look_from_above"].chair_mesh
    assert skills.calls["imagine_sitting"][-1][0][0] is looked
    assert skills.calls["check_seat_reachable"][0][0][0] is looked


def test_no_sitting_after_every_look_fails_the_stage_with_the_imagination_s_reason():
    # The level check takes a few ticks, as on a robot: the reason survives them.
    skills = ScriptedSkills({"imagine_sitting": NO_SITTING}, delays_s={"check_seat_levels": 0.05})
    summary, _ = run_scripted_mission(skills)
    assert summary.failed_stage == "ImagineSitting"
    # NoSittingFound, last, repeats the last imagination's failure: the scan's levels
    # (scripted) leave the seat within the NAO's heights.
    assert summary.reason == (
        "NoSittingFound: ImagineAgain: no sitting pose: no correct sitting in 80 drops"
    )
    assert len(skills.calls["look_from_above"]) == 3  # MAX_LOOKS
    assert len(skills.calls["check_seat_levels"]) == 1
    assert not skills.calls["check_seat_reachable"]


def test_no_sitting_on_a_seat_beyond_the_nao_s_heights_is_refused_with_the_height():
    too_high = SeatReachability(
        False,
        "no level surface the bear rests on within the NAO's seat heights (0.110-0.429 m): "
        "the scan's lie at 0.446 m",
        0.446,
    )
    skills = ScriptedSkills(
        {"imagine_sitting": NO_SITTING, "check_seat_levels": too_high},
        delays_s={"check_seat_levels": 0.05},
    )
    summary, _ = run_scripted_mission(skills)
    assert summary.failed_stage == "ImagineSitting"
    assert summary.reason.startswith(
        "NoSittingFound: refused: no level surface the bear rests on within the NAO's seat "
        "heights (0.110-0.429 m): the scan's lie at 0.446 m"
    )
    assert summary.reason.endswith(
        "(ImagineAgain: no sitting pose: no correct sitting in 80 drops)"
    )
    # The levels are checked on the chair with every look in it.
    looked = skills.results["look_from_above"].chair_mesh
    assert skills.calls["check_seat_levels"][0][0][0] is looked
    assert summary.rotations == 0 and not skills.calls["compose_instruction"]


def test_a_turned_chair_sat_at_another_height_is_looked_at_from_above():
    found = default_results()["imagine_sitting"]
    sunk = found._replace(
        sitting_pose=found.sitting_pose._replace(
            position=found.sitting_pose.position - np.array([0.0, 0.0, 0.13])
        )
    )
    accessible = default_results()["check_accessibility"]
    blocked = accessible._replace(accessible=False, se2_goal=None, path=(), reason="blocked")
    skills = ScriptedSkills(
        {
            "check_accessibility": [blocked, accessible],
            "measure_chair_rotation": RegistrationError("chair registration rejected"),
            "imagine_sitting": [found, sunk, found],
        }
    )
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "success", summary.reason
    # The re-scan's sitting, 0.13 m lower than before the turn, was looked at once.
    assert len(skills.calls["look_from_above"]) == 1
    assert any("before the turn" in failure for failure in summary.failures)
    assert skills.calls["check_accessibility"][-1][0][1] is found.sitting_pose


def test_a_seat_the_scan_lacks_is_looked_at_before_the_seat_check():
    looked = default_results()["look_from_above"]
    skills = ScriptedSkills({"look_at_seat": looked})
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "success", summary.reason
    assert len(skills.calls["look_at_seat"]) == 1 and not skills.calls["look_from_above"]
    # The seat check, the accessibility check and the seating see the chair with the look.
    assert skills.calls["check_seat_reachable"][0][0][0] is looked.chair_mesh
    assert skills.calls["check_accessibility"][0][0][0] is looked.chair_mesh


def test_with_no_looks_the_stages_are_the_single_leaves_on_the_scan():
    root = create_tree(TreeOptions(max_looks=0))
    names = [node.name for node in root.iterate()]
    assert "LookFromAbove" not in names and "LookAtSeat" not in names
    assert [child.name for child in root.children] == list(STAGES)


def test_missing_skill_fails_at_its_stage_and_names_it():
    error = SkillNotReady(
        "skill 'imagine_sitting' is not implemented: no module skills.imagination"
    )
    skills = ScriptedSkills({"imagine_sitting": error})
    summary, _ = run_scripted_mission(skills)
    assert summary.outcome == "failure"
    assert summary.failed_stage == "ImagineSitting"
    # No look from above mends a skill that is not there: the reason names it.
    assert "ImagineOnScan: skill 'imagine_sitting' is not implemented" in summary.reason
    assert summary.failures[0].startswith("ImagineOnScan: skill 'imagine_sitting'")
    assert not skills.calls["look_from_above"]


def test_a_skill_exception_never_crashes_the_executive():
    summary, _ = run_scripted_mission(
        ScriptedSkills({"walk_path": ZeroDivisionError("division by zero")})
    )
    assert summary.outcome == "failure"
    assert summary.failed_stage == "WalkToChair"
    assert "ZeroDivisionError" in summary.reason


def test_timeout_stops_the_tree_and_cancels_the_running_skill():
    skills = ScriptedSkills(delays_s={"imagine_sitting": 30.0})
    root = create_tree()
    runner = MissionRunner(
        root, skills, fake_robot(), seed=0, arena=DEFAULT_ARENA, tick_period_s=0.01, timeout_s=0.3
    )
    outcome = runner.run()
    summary = summarise(outcome, RunInfo())
    assert summary.outcome == "failure"
    assert summary.failed_stage == "ImagineSitting"
    assert summary.reason == "mission timed out after 0 s"
    assert outcome.status == Status.FAILURE
    assert outcome.failed_leaf is None and summary.failures == ()
    statuses = {s.name: (s.status, s.message) for s in summary.stages}
    assert statuses["ScanChair"][0] == "SUCCESS"
    assert statuses["ImagineSitting"] == ("FAILURE", "mission timed out after 0 s")
    # The Timeout stopped the tree: the running leaf's terminate() cancelled its worker.
    assert all(node.status == Status.INVALID for node in root.iterate())
    deadline = time.monotonic() + 2.0
    while "imagine_sitting" not in skills.cancelled and time.monotonic() < deadline:
        time.sleep(0.01)
    assert "imagine_sitting" in skills.cancelled


def test_run_record_and_inspect_replay(tmp_path):
    checks = [BLOCKED, ACCESSIBLE]
    _, runner = run_scripted_mission(
        ScriptedSkills({"check_accessibility": checks}, delays_s={"scan_chair": 0.05}),
        out_dir=tmp_path,
    )
    written = json.loads((tmp_path / "summary.json").read_text())
    for key in (
        "outcome",
        "failed_stage",
        "reason",
        "stages",
        "sitting_pose",
        "instructions",
        "rotations",
        "judgement",
    ):
        assert key in written
    assert written["outcome"] == "success"
    assert all({"name", "status", "seconds"} <= set(stage) for stage in written["stages"])

    recorded = RecordedRun(tmp_path)
    assert recorded.last_tick == runner.tree.count
    first = recorded.tree_text(recorded.ticks[0]["tick"])
    assert "ScanChair [*]" in first  # running on the first tick
    last = recorded.tree_text(None)
    assert "ReleaseAndStand [✓]" in last
    assert "/assistance/rotations: 1" in recorded.blackboard_text(None)
    changes = [(name, new) for _, _, name, _, new in recorded.timeline()]
    assert ("InstructHelper", "SUCCESS") in changes
    assert changes.index(("ScanChair", "SUCCESS")) < changes.index(("ImagineSitting", "SUCCESS"))
    with pytest.raises(RunRecordError):
        recorded.at(recorded.last_tick + 10)


@pytest.mark.parametrize("checks", [[ACCESSIBLE], [BLOCKED] * 4], ids=["seated", "gave-up"])
def test_inspect_draws_the_recorded_tree_as_py_trees_draws_the_live_one(tmp_path, checks):
    _, runner = run_scripted_mission(
        ScriptedSkills({"check_accessibility": checks}), out_dir=tmp_path
    )
    live = render_text(runner.root, "unicode", with_blackboard=False, show_status=True)
    assert RecordedRun(tmp_path).tree_text(None) == live.rstrip()


def test_inspect_rejects_a_directory_that_is_not_a_run(tmp_path):
    with pytest.raises(RunRecordError, match="not a run record"):
        RecordedRun(tmp_path)


def test_ctrl_c_stops_the_tree_cancels_the_skill_and_stops_the_robot(tmp_path):
    skills = ScriptedSkills(delays_s={"imagine_sitting": 30.0})
    robot = fake_robot()
    root = create_tree()
    recorder = RunRecorder(tmp_path, root)

    def press_ctrl_c(runner: MissionRunner) -> None:
        if root.children[1].status == Status.RUNNING and runner.tree.count > 3:
            raise KeyboardInterrupt

    runner = MissionRunner(
        root,
        skills,
        robot,
        seed=0,
        arena=DEFAULT_ARENA,
        recorder=recorder,
        tick_period_s=0.005,
        on_tick=press_ctrl_c,
    )
    outcome = runner.run()
    summary = summarise(outcome, RunInfo())
    recorder.write_summary(summary)
    recorder.close()
    assert outcome.interrupted
    assert summary.outcome == "failure"
    assert summary.failed_stage == "ImagineSitting"
    assert "Ctrl-C" in summary.reason
    assert robot.humanoid.stopped >= 1
    deadline = time.monotonic() + 2.0
    while "imagine_sitting" not in skills.cancelled and time.monotonic() < deadline:
        time.sleep(0.01)
    assert "imagine_sitting" in skills.cancelled
    assert RecordedRun(tmp_path).summary.interrupted is True
