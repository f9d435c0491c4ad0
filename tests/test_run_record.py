"""The run record's ticks.jsonl, tick by tick: a line whenever a status, a visited node's
feedback or the blackboard changed, none otherwise (py_trees' SnapshotVisitor and the
blackboard's activity stream say which)."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from bearchair.executive.records.run_record import RunRecorder, load_ticks


def record(tmp_path, root, ticks: int, between=None) -> list[dict]:
    """Ticks ``root`` ``ticks`` times under a recorder; ``between(n)`` runs before tick n."""
    py_trees.blackboard.Blackboard.clear()
    tree = py_trees.trees.BehaviourTree(root)
    recorder = RunRecorder(tmp_path, root)
    recorder.watch(tree)
    tree.add_post_tick_handler(lambda tree: recorder.record_tick(tree.count + 1, 0.0))
    for number in range(1, ticks + 1):
        if between is not None:
            between(number)
        tree.tick()
    recorder.close()
    return load_ticks(tmp_path)


def statuses(line: dict) -> dict[str, str]:
    return {node["name"]: node["status"] for node in line["nodes"]}


def test_ticks_that_change_nothing_write_nothing(tmp_path):
    root = py_trees.composites.Sequence(
        "root", memory=True, children=[py_trees.behaviours.Running("busy")]
    )
    assert [line["tick"] for line in record(tmp_path, root, 5)] == [1]


def test_a_child_a_memory_selector_resets_unvisited_is_recorded(tmp_path):
    failed = py_trees.behaviours.Failure("failed")
    root = py_trees.composites.Selector(
        "root", memory=True, children=[failed, py_trees.behaviours.Running("busy")]
    )
    lines = record(tmp_path, root, 4)
    # Tick 2 visits only the root and "busy", neither changed: "failed" was reset.
    assert [line["tick"] for line in lines] == [1, 2]
    assert statuses(lines[0])["failed"] == Status.FAILURE.value
    assert statuses(lines[1])["failed"] == Status.INVALID.value


class Busy(py_trees.behaviour.Behaviour):
    """RUNNING, saying ``progress`` (changed by the test between ticks)."""

    progress = "starting"

    def update(self) -> Status:
        self.feedback_message = self.progress
        return Status.RUNNING


def test_a_visited_feedback_change_and_a_blackboard_write_are_recorded(tmp_path):
    busy = Busy("busy")
    root = py_trees.composites.Sequence("root", memory=True, children=[busy])
    writer = py_trees.blackboard.Client(name="writer")

    def change(number: int) -> None:
        if number == 3:
            busy.progress = "halfway"
        if number == 5:
            writer.register_key(key="/answer", access=py_trees.common.Access.WRITE)
            writer.set("/answer", 42)

    lines = record(tmp_path, root, 6, between=change)
    assert [line["tick"] for line in lines] == [1, 3, 5]
    assert [node["feedback"] for node in lines[1]["nodes"]] == ["", "halfway"]
    assert "/answer" not in lines[1]["blackboard"]
    assert lines[2]["blackboard"]["/answer"] == 42
