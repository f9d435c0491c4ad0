"""The testing kit: ScriptedSkills bound to the protocol, the fixtures, one name for what
speakers record, the tree's options, and the executive's inputs for any host."""

from __future__ import annotations

import importlib.metadata
import inspect

import py_trees
import pytest
from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.mission_inputs import set_mission_inputs
from bearchair.core.arena import DEFAULT_ARENA
from bearchair.hardware.fakes import FakeSpeaker
from bearchair.hardware.sim.helper import SimSpeaker
from bearchair.testing import ScriptedSkills, fake_robot, set_up, tick_until_done
from bearchair.testing.scripted import SKILLS
from bearchair.trees.mission import create_tree
from bearchair.trees.options import TreeOptions

# --- ScriptedSkills -------------------------------------------------------------------


def test_a_misspelt_scripted_skill_is_an_error_naming_the_skill():
    with pytest.raises(ValueError, match=r"'scan_chiar' is not a skill .*did you mean scan_chair"):
        ScriptedSkills({"scan_chiar": RuntimeError("never used")})
    with pytest.raises(ValueError, match=r"delays_s: 'imagine' is not a skill"):
        ScriptedSkills(delays_s={"imagine": 1.0})


def test_a_wrong_keyword_to_a_skill_is_an_error_as_with_the_real_skills():
    skills = ScriptedSkills()
    with pytest.raises(TypeError, match="random_seed"):
        skills.scan_chair(None, random_seed=3)  # pyright: ignore[reportCallIssue]
    with pytest.raises(TypeError):
        skills.check_accessibility(None, None, None, None)  # pyright: ignore[reportCallIssue]  # seed missing
    assert not skills.calls  # a refused call is no call


def test_a_scripted_function_must_take_the_skill_arguments():
    with pytest.raises(TypeError, match="the function scripted for walk_path takes"):
        ScriptedSkills({"walk_path": lambda humanoid, clock: None})
    seen = []
    skills = ScriptedSkills({"locate_humanoid": lambda arm: seen.append(arm) or None})
    assert skills.locate_humanoid("arm") is None and seen == ["arm"]


def test_every_scripted_method_has_the_protocol_signature():
    for name, signature in SKILLS.items():
        method = inspect.signature(getattr(ScriptedSkills, name))
        scripted = [(p.name, p.kind, p.default) for p in list(method.parameters.values())[1:]]
        expected = [(p.name, p.kind, p.default) for p in signature.parameters.values()]
        assert scripted == expected, name


def test_values_lists_exceptions_and_delays_still_script_a_skill():
    skills = ScriptedSkills({"wait_until_chair_still": [1.0, 2.0], "raise_bear": OSError("arm")})
    clock = fake_robot().clock
    assert [skills.wait_until_chair_still(None, clock) for _ in range(3)] == [1.0, 2.0, 2.0]  # pyright: ignore[reportArgumentType]
    with pytest.raises(OSError, match="arm"):
        skills.raise_bear(None, None, None, None)  # pyright: ignore[reportArgumentType]
    assert len(skills.calls["wait_until_chair_still"]) == 3


# --- fixtures and helpers -------------------------------------------------------------


def test_the_kit_is_a_pytest_plugin():
    plugins = importlib.metadata.entry_points(group="pytest11")
    assert "bearchair.testing.plugin" in {entry.value for entry in plugins}


def test_mission_blackboard_holds_the_executive_inputs(mission_blackboard):
    storage = py_trees.blackboard.Blackboard.storage
    assert storage[keys.SEED] == 0 and storage[keys.ARENA] == DEFAULT_ARENA
    assert set(storage) == set(keys.SET_BY_EXECUTIVE)


def test_tick_until_done_fails_a_test_on_a_leaf_that_never_ends():
    running = py_trees.behaviours.Running(name="Forever")
    with pytest.raises(AssertionError, match="Forever still RUNNING after 3 ticks"):
        tick_until_done(running, max_ticks=3)


def test_every_speaker_records_what_it_said_as_spoken():
    from bearchair.hardware.speech import TextToSpeech

    for speaker in (FakeSpeaker(), SimSpeaker(None, FakeSpeaker()), TextToSpeech(mute=True)):
        speaker.say("Hello.")
        assert speaker.spoken == ["Hello."], type(speaker).__name__


# --- the executive's inputs, for any host ---------------------------------------------


def test_a_plain_py_trees_host_runs_the_mission_after_set_mission_inputs(fake_robot):
    tree = py_trees.trees.BehaviourTree(create_tree())
    set_mission_inputs(seed=4)
    tree.setup(skills=ScriptedSkills(), robot=fake_robot)
    for _ in range(2000):
        tree.tick()
        if tree.root.status != Status.RUNNING:
            break
    assert tree.root.status == Status.SUCCESS
    tree.shutdown()


def test_without_the_inputs_the_first_leaf_that_needs_them_fails():
    root = set_up(create_tree(), ScriptedSkills(), fake_robot())
    assert tick_until_done(root)[-1] == Status.FAILURE
    assert root.tip().name == "ScanChair" and "/mission/seed" in root.tip().feedback_message


def test_set_mission_inputs_refuses_a_seed_that_is_no_whole_number():
    with pytest.raises(TypeError, match="seed: a whole number"):
        set_mission_inputs(seed="0")  # pyright: ignore[reportArgumentType]
    with pytest.raises(TypeError, match="seed: a whole number"):
        set_mission_inputs(seed=True)


# --- the tree's options ----------------------------------------------------------------


def shape(node, depth=0):
    """(name, class, depth, memory) of every node, depth first, parents first."""
    row = (node.name, type(node).__name__, depth, getattr(node, "memory", None))
    return [row] + [r for child in node.children for r in shape(child, depth + 1)]


DOCUMENTED_TREE = [
    ("Put the bear on the chair", "Sequence", 0, True),
    ("ScanChair", "ScanChair", 1, None),
    ("ImagineSitting", "Selector", 1, True),
    ("ImagineOnScan", "ImagineSitting", 2, None),
    ("Up to 3 looks", "Retry", 2, None),
    ("Look again and imagine", "Sequence", 3, True),
    ("LookFromAbove", "LookFromAbove", 4, None),
    ("ImagineAgain", "ImagineSitting", 4, None),
    ("NoSittingFound", "NoSittingFound", 2, None),
    ("CheckSeatReachable", "Sequence", 1, True),
    ("LookAtSeat", "LookAtSeat", 2, None),
    ("ImagineOnSeatView", "ImagineOnSeatView", 2, None),
    ("CheckSeatReachable", "CheckSeatReachable", 2, None),
    ("MakeChairAccessible", "Selector", 1, True),
    ("CheckAccessibility", "CheckAccessibility", 2, None),
    ("Up to 3 rotations", "Retry", 2, None),
    ("Ask the helper to rotate the chair", "Sequence", 3, True),
    ("InstructHelper", "InstructHelper", 4, None),
    ("WaitUntilChairStill", "WaitUntilChairStill", 4, None),
    ("LocateTurnedChair", "Selector", 4, True),
    ("MeasureChairRotation", "MeasureChairRotation", 5, None),
    ("Scan the turned chair anew", "Sequence", 5, True),
    ("ScanTurnedChair", "ScanChair", 6, None),
    ("ImagineTurnedChair", "Selector", 6, True),
    ("ImagineOnTurnedScan", "ImagineSitting", 7, None),
    ("Up to 3 looks", "Retry", 7, None),
    ("Look again and imagine", "Sequence", 8, True),
    ("LookAtTurnedChair", "LookFromAbove", 9, None),
    ("ImagineTurnedAgain", "ImagineSitting", 9, None),
    ("CheckAccessibilityAgain", "CheckAccessibility", 4, None),
    ("GiveUp", "GiveUp", 2, None),
    ("WalkToChair", "WalkToChair", 1, None),
    ("SeatBear", "SeatBear", 1, None),
    ("ReleaseAndStand", "ReleaseAndStand", 1, None),
]
"""The mission tree of trees/mission.py's docstring."""


def test_create_tree_with_no_argument_is_the_documented_tree():
    assert shape(create_tree()) == [tuple(row) for row in DOCUMENTED_TREE]
    assert shape(create_tree(TreeOptions())) == shape(create_tree())


def test_the_options_change_the_tree():
    names = [node.name for node in create_tree(TreeOptions(assistance=False)).iterate()]
    assert "InstructHelper" not in names and "MakeChairAccessible" in names
    no_rescan = [node.name for node in create_tree(TreeOptions(rescan_fallback=False)).iterate()]
    assert "ScanTurnedChair" not in no_rescan and "MeasureChairRotation" in no_rescan
    retries = {
        node.name: node.num_failures
        for node in create_tree(TreeOptions(max_rotations=5, max_looks=2)).iterate()
        if isinstance(node, py_trees.decorators.Retry)
    }
    assert retries == {"Up to 5 rotations": 5, "Up to 2 looks": 2}
    no_looks = create_tree(TreeOptions(max_looks=0))
    imagine = next(node for node in no_looks.children if node.name == "ImagineSitting")
    assert type(imagine).__name__ == "ImagineSitting" and not imagine.children
    with pytest.raises(ValueError, match="max_rotations"):
        TreeOptions(max_rotations=0)
    with pytest.raises(ValueError, match="max_looks"):
        TreeOptions(max_looks=-1)


def test_skill_parameters_mirror_the_perception_constants():
    from bearchair.skills.parameters import MIN_SCAN_VIEWS, SCAN_VIEW_COUNT
    from bearchair.skills.perception import scan_capture, views

    assert len(views.SCAN_CONFIGURATIONS) == SCAN_VIEW_COUNT
    assert MIN_SCAN_VIEWS == scan_capture.MIN_SCAN_VIEWS
