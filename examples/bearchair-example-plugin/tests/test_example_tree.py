"""The tree variant: composed as documented, and seating the bear on scripted skills."""

import py_trees
from py_trees.common import Status

from bearchair.behaviours.mission_inputs import set_mission_inputs
from bearchair.testing import ScriptedSkills, set_up
from bearchair.trees.options import TreeOptions
from bearchair_example.trees import create_tree_without_assistance


def names(root: py_trees.behaviour.Behaviour) -> list[str]:
    return [node.name for node in root.iterate()]


def test_the_variant_asks_nobody_and_announces_the_seat_before_the_walk():
    root = create_tree_without_assistance(TreeOptions())
    stages = [child.name for child in root.children]
    assert stages.index("AnnounceSeat") == stages.index("WalkToChair") - 1
    assert "InstructHelper" not in names(root) and "GiveUp" not in names(root)


def test_the_variant_seats_the_bear_on_scripted_skills(
    clean_blackboard, fake_robot, tick_until_done
):
    set_mission_inputs(seed=3)
    root = set_up(create_tree_without_assistance(TreeOptions()), ScriptedSkills(), fake_robot)
    assert tick_until_done(root, max_ticks=2000)[-1] == Status.SUCCESS
    assert fake_robot.speaker.spoken == ["I will seat the bear facing 0 degrees."]


def test_an_inaccessible_chair_fails_the_variant_without_asking(
    clean_blackboard, fake_robot, tick_until_done
):
    blocked = (
        ScriptedSkills()
        .results["check_accessibility"]
        ._replace(accessible=False, reason="no room in front of the chair")
    )
    set_mission_inputs(seed=3)
    skills = ScriptedSkills({"check_accessibility": blocked})
    root = set_up(create_tree_without_assistance(TreeOptions()), skills, fake_robot)
    assert tick_until_done(root, max_ticks=2000)[-1] == Status.FAILURE
    assert not skills.calls["choose_rotation"] and not fake_robot.speaker.spoken
    tip = root.tip()
    assert tip is not None and tip.name == "MakeChairAccessible"
