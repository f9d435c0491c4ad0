"""Run records: what a mission did, tick by tick, and how it ended.

A run directory holds:

* ``ticks.jsonl``: one JSON object per tick whose statuses, feedback or blackboard
  changed (ticks with no change are skipped; ``tick`` numbers say which ones ran).
  Each holds ``tick``, ``t`` (seconds since the start) and ``nodes`` (every node's
  ``name``, ``path``, ``status``, ``feedback``); ``blackboard`` (key -> JSON view) is
  written only when it changed, and holds until the next line that has one.
* ``tree.json``: the tree's shape (each node's ``path``, ``name``, ``type``, ``depth``).
* ``summary.json``: the outcome (see :class:`RunSummary`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import py_trees

from executive.jsonable import to_jsonable

TICKS_FILE = "ticks.jsonl"
TREE_FILE = "tree.json"
SUMMARY_FILE = "summary.json"


def tree_nodes(
    root: py_trees.behaviour.Behaviour,
) -> list[tuple[str, py_trees.behaviour.Behaviour, int]]:
    """Every node as (path, node, depth), depth first; paths are unique ("/"-joined indices)."""
    nodes: list[tuple[str, py_trees.behaviour.Behaviour, int]] = []

    def visit(node: py_trees.behaviour.Behaviour, path: str, depth: int) -> None:
        nodes.append((path, node, depth))
        for index, child in enumerate(node.children):
            visit(child, f"{path}/{index}", depth + 1)

    visit(root, "0", 0)
    return nodes


class RunRecorder:
    """Writes a run directory as the tree ticks; flushes every line so a crash loses nothing."""

    def __init__(self, out_dir: Path, root: py_trees.behaviour.Behaviour) -> None:
        self.out_dir = Path(out_dir)
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self._nodes = tree_nodes(root)
        shape = [
            {"path": path, "name": node.name, "type": type(node).__name__, "depth": depth}
            for path, node, depth in self._nodes
        ]
        (self.out_dir / TREE_FILE).write_text(json.dumps(shape, indent=1))
        self._ticks = open(self.out_dir / TICKS_FILE, "w")  # noqa: SIM115 - closed in close()
        self._last_nodes: str | None = None
        self._last_blackboard: str | None = None

    def record_tick(self, tick: int, seconds: float) -> None:
        nodes = [
            {
                "path": path,
                "name": node.name,
                "status": node.status.value,
                "feedback": node.feedback_message,
            }
            for path, node, _ in self._nodes
        ]
        storage = py_trees.blackboard.Blackboard.storage
        blackboard = {key: to_jsonable(storage[key]) for key in sorted(storage)}
        nodes_text = json.dumps(nodes)
        blackboard_text = json.dumps(blackboard, sort_keys=True)
        if nodes_text == self._last_nodes and blackboard_text == self._last_blackboard:
            return
        line: dict[str, Any] = {"tick": tick, "t": round(seconds, 3), "nodes": nodes}
        if blackboard_text != self._last_blackboard:
            line["blackboard"] = blackboard
        self._last_nodes, self._last_blackboard = nodes_text, blackboard_text
        self._ticks.write(json.dumps(line) + "\n")
        self._ticks.flush()

    def write_summary(self, summary: dict[str, Any]) -> Path:
        path = self.out_dir / SUMMARY_FILE
        path.write_text(json.dumps(to_jsonable(summary), indent=2) + "\n")
        return path

    def close(self) -> None:
        if not self._ticks.closed:
            self._ticks.close()


def load_ticks(run_dir: Path) -> list[dict[str, Any]]:
    """The recorded ticks of a run, in order, each with the blackboard in force then.

    A truncated last line (a run killed mid-write) is ignored.
    """
    ticks = []
    blackboard: dict[str, Any] = {}
    with open(Path(run_dir) / TICKS_FILE) as lines:
        for line in lines:
            try:
                tick = json.loads(line)
            except json.JSONDecodeError:
                break
            blackboard = tick.setdefault("blackboard", blackboard)
            ticks.append(tick)
    return ticks
