"""The blackboard registrations are what the leaves do: each leaf registers READ exactly
the keys it reads and WRITE exactly those it writes, and ``bearchair.behaviours.keys``' table is
the one generated from the registrations."""

from __future__ import annotations

from collections import defaultdict

import py_trees
import pytest

from bearchair.behaviours import keys
from bearchair.core.arena import DEFAULT_ARENA
from bearchair.executive.runner import MissionRunner
from bearchair.executive.tree_render import blackboard_table
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.skills.perception.errors import RegistrationError
from bearchair.skills.results import AccessibilityResult
from bearchair.testing.scripted import ScriptedSkills, default_results
from bearchair.trees.mission import create_tree

ACCESSIBLE = default_results()["check_accessibility"]
BLOCKED = AccessibilityResult(False, None, ACCESSIBLE.sitting_pose, (), "s_goal outside the arena")
REJECTED = RegistrationError("chair registration rejected: visible overlap 0.78 (need 0.88)")
FOUND = default_results()["imagine_sitting"]
NOT_FOUND = FOUND._replace(found=False, sitting_pose=None, reason="no correct sitting")

READS = {"READ", "ACCESSED", "NO_KEY"}
WRITES = {"WRITE", "INITIALISED"}

SCENARIOS = [
    # accessible at once
    {},
    # one turn measured by ICP, then seated
    {"check_accessibility": [BLOCKED, ACCESSIBLE]},
    # one turn no fit accepts: the chair scanned and imagined anew
    {"check_accessibility": [BLOCKED, ACCESSIBLE], "measure_chair_rotation": REJECTED},
    # the same, and no sitting on the turned chair's scan: looked at from above
    {
        "check_accessibility": [BLOCKED, ACCESSIBLE],
        "measure_chair_rotation": REJECTED,
        "imagine_sitting": [FOUND, NOT_FOUND, FOUND],
    },
    # never accessible: GiveUp
    {"check_accessibility": BLOCKED},
    # no sitting on the scan: looked at from above, then found
    {"imagine_sitting": [NOT_FOUND, FOUND]},
    # no seat under the sitting point on the scan: looked at
    {"look_at_seat": default_results()["look_from_above"]},
    # no sitting on the scan after every look: NoSittingFound
    {"imagine_sitting": NOT_FOUND},
    # nor on the turned chair's scan (no NoSittingFound there: the next turn follows)
    {
        "check_accessibility": BLOCKED,
        "measure_chair_rotation": REJECTED,
        "imagine_sitting": [FOUND, NOT_FOUND],
    },
]


def test_the_keys_table_is_generated_from_the_registrations():
    assert blackboard_table(create_tree()) in keys.__doc__


def used_keys(results: dict) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """Per blackboard client (leaf name), the keys a mission read and wrote."""
    read: dict[str, set[str]] = defaultdict(set)
    written: dict[str, set[str]] = defaultdict(set)

    def watch(_: py_trees.trees.BehaviourTree) -> None:
        if py_trees.blackboard.Blackboard.activity_stream is None:  # cleared by the run
            py_trees.blackboard.Blackboard.enable_activity_stream(maximum_size=10**6)

    def collect(_: MissionRunner) -> None:
        stream = py_trees.blackboard.Blackboard.activity_stream
        for item in stream.data:
            if item.activity_type in READS:
                read[item.client_name].add(item.key)
            elif item.activity_type in WRITES:
                written[item.client_name].add(item.key)
        stream.clear()

    runner = MissionRunner(
        create_tree(),
        ScriptedSkills(results),
        fake_robot(judge=FakeJudge()),
        seed=3,
        arena=DEFAULT_ARENA,
        tick_period_s=0.002,
        timeout_s=60,
        on_tick=collect,
    )
    runner.tree.add_pre_tick_handler(watch)
    runner.run()
    return read, written


@pytest.fixture(scope="module")
def usage() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    read: dict[str, set[str]] = defaultdict(set)
    written: dict[str, set[str]] = defaultdict(set)
    for results in SCENARIOS:
        scenario_read, scenario_written = used_keys(results)
        for name, used in scenario_read.items():
            read[name] |= used
        for name, used in scenario_written.items():
            written[name] |= used
    return read, written


@pytest.mark.parametrize("name", [node.name for node in create_tree().iterate()])
def test_each_behaviour_registers_what_it_reads_and_writes(name, usage):
    read, written = usage
    node = next(node for node in create_tree().iterate() if node.name == name)
    registered_read = set().union(*(client.read for client in node.blackboards))
    registered_write = set().union(*(client.write for client in node.blackboards))
    assert read.get(name, set()) == registered_read, "READ registrations differ from the reads"
    assert written.get(name, set()) == registered_write, "WRITE registrations differ"
