from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.testing import ScriptedSkills, default_results, set_up, write_blackboard
from bearchair_example.leaves import AnnounceSeat


def test_announce_seat_says_the_direction(mission_blackboard, fake_robot, tick_until_done):
    write_blackboard({keys.SITTING_POSE: default_results()["imagine_sitting"].sitting_pose})
    leaf = set_up(AnnounceSeat(), ScriptedSkills(), fake_robot)
    assert tick_until_done(leaf)[-1] == Status.SUCCESS
    assert fake_robot.speaker.spoken == ["I will seat the bear facing 0 degrees."]


def test_announce_seat_fails_without_a_pose(clean_blackboard, fake_robot, tick_until_done):
    leaf = set_up(AnnounceSeat(), ScriptedSkills(), fake_robot)
    assert tick_until_done(leaf)[-1] == Status.FAILURE and not fake_robot.speaker.spoken
