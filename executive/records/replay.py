"""Replaying a recorded run offline: the tree at any tick, the blackboard, the timeline."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status

from bearchair.core.errors import RunRecordError
from bearchair.core.userfiles import load_user_json, printable
from bearchair.executive.records.run_record import SUMMARY_FILE, TICKS_FILE, TREE_FILE, read_ticks
from bearchair.executive.records.run_summary import RunSummary
from bearchair.executive.tree_render import render_text

__all__ = ["RecordedRun", "RunRecordError"]


class RecordedRun:
    """A run directory written by :class:`bearchair.executive.records.run_record.RunRecorder`.

    A damaged record is read as far as it can be: unreadable lines of ``ticks.jsonl``
    are skipped and an unreadable ``summary.json`` is ignored, each with a note
    (:attr:`notes`); only a missing or unreadable ``tree.json`` or a run without one
    readable tick is refused (:class:`RunRecordError`).
    """

    def __init__(self, run_dir: Path) -> None:
        run_dir = Path(run_dir)
        if not run_dir.exists():
            raise RunRecordError(f"{run_dir}: not a run record (no such folder)")
        if not run_dir.is_dir():
            raise RunRecordError(f"{run_dir}: not a run record (a file, not a folder)")
        for name in (TREE_FILE, TICKS_FILE):
            if not (run_dir / name).is_file():
                raise RunRecordError(f"{run_dir}: not a run record (no {name})")
        self.run_dir = run_dir
        self.notes: list[str] = []
        self.shape = _read_shape(run_dir / TREE_FILE)
        self.ticks, skipped = read_ticks(run_dir)
        if not self.ticks:
            raise RunRecordError(f"{run_dir / TICKS_FILE}: no readable tick in the record")
        if skipped:
            lines = ", ".join(str(n) for n in skipped[:5]) + (", ..." if len(skipped) > 5 else "")
            self.notes.append(
                f"{len(skipped)} unreadable line(s) of {TICKS_FILE} skipped (line {lines})"
            )
        self.summary = self._read_summary(run_dir / SUMMARY_FILE)

    def _read_summary(self, path: Path) -> RunSummary | None:
        if not path.exists() and not path.is_symlink():
            return None
        try:
            summary = load_user_json(path, "run summary", RunRecordError)
        except RunRecordError as error:
            self.notes.append(f"{SUMMARY_FILE} ignored: unreadable ({printable(error)})")
            return None
        if not isinstance(summary, dict):
            self.notes.append(f"{SUMMARY_FILE} ignored: not a JSON object")
            return None
        try:
            return RunSummary.from_json(summary)
        except RunRecordError as error:
            self.notes.append(f"{SUMMARY_FILE} ignored: not a run summary ({printable(error)})")
            return None

    def outcome_text(self) -> str:
        """``outcome: ...`` from the summary, or why there is none."""
        if self.summary is None:
            return "outcome: unknown (no readable summary.json: the run did not finish)"
        line = f"outcome: {self.summary.outcome}"
        if self.summary.failed_stage:
            line += f" at {self.summary.failed_stage}: {self.summary.reason}"
        if self.summary.interrupted:
            line += f" (interrupted by {self.summary.signal or 'the operator'})"
        return printable(line, 2000)

    def compare_tree(self, spec: str) -> str:
        """Whether the recorded tree is the one ``spec`` (``--tree``) builds with the run's
        tree options (its ``config.json``; the defaults without one), as a phrase.

        Raises:
            PluginError: ``spec`` names no tree, or its factory fails.
        """
        from bearchair.executive.records.run_record import tree_shape
        from bearchair.executive.tree_source import build_tree, load_tree_factory

        built = tree_shape(build_tree(load_tree_factory(spec), self._tree_options(), spec))
        keys = ("path", "name", "type", "depth", "memory")
        for index, (recorded, node) in enumerate(zip(self.shape, built, strict=False)):
            if any(recorded.get(key) != node.get(key) for key in keys):
                return (
                    f"not the one {spec} builds: node {index} is {recorded.get('path')} "
                    f"({recorded.get('type')}) in the record, {node['path']} ({node['type']}) built"
                )
        if len(self.shape) != len(built):
            return (
                f"not the one {spec} builds: {len(self.shape)} nodes recorded, {len(built)} built"
            )
        return f"the one {spec} builds ({len(built)} nodes)"

    def _tree_options(self) -> Any:
        from bearchair.trees.options import TreeOptions

        try:
            config = load_user_json(self.run_dir / "config.json", "config", RunRecordError)
            section = config.get("tree") or config.get("tree_options") or {}
            names = [field.name for field in dataclasses.fields(TreeOptions)]
            return TreeOptions(**{key: section[key] for key in names if key in section})
        except (RunRecordError, ValueError, TypeError, AttributeError):
            return TreeOptions()

    @property
    def last_tick(self) -> int:
        return self.ticks[-1]["tick"]

    def at(self, tick: int | None) -> dict[str, Any]:
        """The recorded state in force at ``tick`` (the last one when None)."""
        if tick is None:
            return self.ticks[-1]
        if tick < self.ticks[0]["tick"] or tick > self.last_tick:
            raise RunRecordError(
                f"tick {tick} is outside the run (ticks {self.ticks[0]['tick']}..{self.last_tick})"
            )
        state = self.ticks[0]
        for recorded in self.ticks:
            if recorded["tick"] > tick:
                break
            state = recorded
        return state

    def tree_text(self, tick: int | None) -> str:
        """The tree with each node's status and feedback at ``tick``, drawn as
        ``bearchair tree`` draws it (py_trees' Unicode art)."""
        state = {node["path"]: node for node in self.at(tick)["nodes"]}
        return "\n".join(
            render_text(root, "unicode", with_blackboard=False, show_status=True).rstrip()
            for root in _rebuild(self.shape, state)
        )

    def blackboard_text(self, tick: int | None) -> str:
        board = self.at(tick)["blackboard"]
        return "\n".join(
            f"{printable(key)}: {printable(json.dumps(value), 2000)}"
            for key, value in sorted(board.items())
        )

    def timeline(self) -> list[tuple[float, int, str, str, str]]:
        """Every status change of every node: (t, tick, node, old status, new status)."""
        changes = []
        previous: dict[str, str] = {}
        names = {node["path"]: node["name"] for node in self.shape}
        names_of = names.get
        for recorded in self.ticks:
            for node in recorded["nodes"]:
                old = previous.get(node["path"], "INVALID")
                if node["status"] != old:
                    changes.append(
                        (
                            recorded["t"],
                            recorded["tick"],
                            printable(names_of(node["path"], node["path"]), 200),
                            printable(old, 20),
                            printable(node["status"], 20),
                        )
                    )
                    previous[node["path"]] = node["status"]
        return changes

    def timeline_text(self) -> str:
        return "\n".join(
            f"{t:8.2f} s  tick {tick:5d}  {name:<36} {old} -> {new}"
            for t, tick, name, old, new in self.timeline()
        )


def _rebuild(
    shape: list[dict[str, Any]], state: dict[str, dict[str, Any]]
) -> list[py_trees.behaviour.Behaviour]:
    """The recorded tree as py_trees behaviours (its roots), each node of its recorded
    kind, with the status and feedback recorded in ``state`` (path -> node)."""
    children: list[list[py_trees.behaviour.Behaviour]] = [[]]  # per open depth, then roots
    opened: list[dict[str, Any]] = []

    def close_to(depth: int) -> None:
        while len(opened) > depth:
            node, below = opened.pop(), children.pop()
            children[-1].append(_recorded_node(node, below, state.get(node["path"], {})))

    for node in shape:
        close_to(node["depth"])
        opened.append(node)
        children.append([])
    close_to(0)
    return children[0]


def _recorded_node(
    node: dict[str, Any], children: list[py_trees.behaviour.Behaviour], recorded: dict[str, Any]
) -> py_trees.behaviour.Behaviour:
    """One node of the recorded tree: a composite, a decorator or a leaf like the one run."""
    kind = getattr(py_trees.composites, node["type"], None) or getattr(
        py_trees.decorators, node["type"], None
    )
    kind = kind if isinstance(kind, type) else py_trees.behaviour.Behaviour
    name, memory = printable(node["name"], 200), bool(node.get("memory", False))
    built: py_trees.behaviour.Behaviour
    if issubclass(kind, py_trees.composites.Parallel):
        built = py_trees.composites.Parallel(
            name, policy=py_trees.common.ParallelPolicy.SuccessOnAll(), children=children
        )
    elif issubclass(kind, py_trees.composites.Selector):
        built = py_trees.composites.Selector(name, memory=memory, children=children)
    elif issubclass(kind, py_trees.decorators.Decorator) and len(children) == 1:
        built = py_trees.decorators.PassThrough(name, child=children[0])
    elif children:
        built = py_trees.composites.Sequence(name, memory=memory, children=children)
    else:
        built = py_trees.behaviours.Dummy(name)
    status = recorded.get("status", "INVALID")
    built.status = py_trees.common.Status(status) if status in _STATUSES else Status.INVALID
    built.feedback_message = printable(recorded.get("feedback") or "", 400)
    if isinstance(built, py_trees.composites.Composite):
        # The tip py_trees draws in bold: the last child that ran.
        active = [child for child in children if child.status != Status.INVALID]
        built.current_child = active[-1] if active else None
    return built


_STATUSES = {status.value for status in Status}


def _read_shape(path: Path) -> list[dict[str, Any]]:
    """``tree.json``: a list of nodes, each with a str path and name, a type and a depth."""
    shape = load_user_json(path, "tree file", RunRecordError)
    if not isinstance(shape, list) or not shape:
        raise RunRecordError(f"{path}: not a tree (expected a non-empty JSON list of nodes)")
    for node in shape:
        if not (
            isinstance(node, dict)
            and isinstance(node.get("path"), str)
            and isinstance(node.get("name"), str)
            and isinstance(node.get("depth"), int)
            and node["depth"] >= 0
        ):
            raise RunRecordError(
                f"{path}: not a tree (a node lacks a str path/name or an int depth)"
            )
        node.setdefault("type", "Behaviour")
    return shape
