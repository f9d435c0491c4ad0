"""Run records: what a mission did, tick by tick, and how it ended.

A run directory holds:

* ``ticks.jsonl``: one JSON object per tick whose statuses, feedback or blackboard
  changed (ticks with no change are skipped; ``tick`` numbers say which ones ran).
  Each holds ``tick``, ``t`` (seconds since the start) and ``nodes`` (every node's
  ``name``, ``path``, ``status``, ``feedback``); ``blackboard`` (key -> JSON view) is
  written only when it was written to, and holds until the next line that has one.
* ``tree.json``: the tree's shape (each node's ``path``, ``name``, ``type``, ``depth``,
  and for composites with a memory, ``memory``).
* ``summary.json``: the outcome (see
  :class:`bearchair.executive.records.run_summary.RunSummary`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import uuid
from pathlib import Path
from typing import Any

import py_trees

from bearchair.core.errors import OutputError, RunRecordError
from bearchair.core.provenance import software_versions
from bearchair.core.userfiles import open_regular_file, parse_json, printable
from bearchair.executive.outputs import describe_os_error, open_new_file, write_text_atomic
from bearchair.executive.records.jsonable import to_jsonable
from bearchair.executive.records.run_summary import RunSummary

TICKS_FILE = "ticks.jsonl"
TREE_FILE = "tree.json"
SUMMARY_FILE = "summary.json"
MAX_TICK_LINE_CHARS = 16 * 1024 * 1024
"""A longer line of ticks.jsonl is skipped as unreadable (a tick with its blackboard is a
few kB)."""
MAX_TICK_LINES = 10_000_000
"""Ticks read at most (a 900 s mission ticks at most about 10 Hz: 9000 lines)."""


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


def tree_shape(root: py_trees.behaviour.Behaviour) -> list[dict[str, Any]]:
    """``tree.json``: each node's path, name, class name, depth (and a composite's memory)."""
    return [
        {
            "path": path,
            "name": node.name,
            "type": type(node).__name__,
            "depth": depth,
            **_memory_field(node),
        }
        for path, node, depth in tree_nodes(root)
    ]


def _memory_field(node: py_trees.behaviour.Behaviour) -> dict[str, bool]:
    """A composite's ``memory`` flag as a field; nothing for a node without one."""
    memory = getattr(node, "memory", None)
    return {"memory": memory} if isinstance(memory, bool) else {}


_WRITES = frozenset(
    kind.value
    for kind in (
        py_trees.blackboard.ActivityType.WRITE,
        py_trees.blackboard.ActivityType.INITIALISED,
        py_trees.blackboard.ActivityType.UNSET,
    )
)
"""The blackboard activities that change what the record shows."""


class RecordWriteError(OutputError):
    """The run record cannot be written (full disk, folder removed, permissions)."""


class RunRecorder:
    """Writes a run directory as the tree ticks; flushes every line so a crash loses nothing.

    ``tree.json`` and ``summary.json`` are written atomically (whole or not at all);
    ``ticks.jsonl`` grows a flushed line per tick, and a reader ignores a torn last line.
    A failed write raises :class:`RecordWriteError` with one line saying why.
    """

    def __init__(self, out_dir: Path, root: py_trees.behaviour.Behaviour) -> None:
        self.out_dir = Path(out_dir)
        self._nodes = tree_nodes(root)
        self._by_id = {node.id: node for _, node, _ in self._nodes}
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            write_text_atomic(self.out_dir / TREE_FILE, json.dumps(tree_shape(root), indent=1))
            self._ticks = open_new_file(self.out_dir / TICKS_FILE)
        except (OSError, OutputError) as error:
            raise RecordWriteError(
                f"cannot start the run record in {self.out_dir}: {_why(error)}"
            ) from error
        self._snapshot = py_trees.visitors.SnapshotVisitor()
        self._feedback: dict[uuid.UUID, str] = {}
        self._last_nodes: list[dict[str, str]] | None = None
        self._blackboard_recorded = False

    def watch(self, tree: py_trees.trees.BehaviourTree) -> None:
        """Lets the record see ``tree``'s ticks: its snapshot visitor visits each tick and
        the blackboard's activity stream says when a key was written.

        Call it after the blackboard was last cleared (that disables the stream).
        """
        tree.visitors.append(self._snapshot)
        py_trees.blackboard.Blackboard.enable_activity_stream()

    def record_tick(self, tick: int, seconds: float) -> None:
        """Writes a line for the tick just run when a node's status (the snapshot visitor
        says which), a visited node's feedback, or the blackboard changed."""
        feedback = {
            id_: self._by_id[id_].feedback_message
            for id_ in self._snapshot.visited
            if id_ in self._by_id
        }
        feedback_changed = any(self._feedback.get(id_) != text for id_, text in feedback.items())
        self._feedback.update(feedback)
        # A node that left the visited path may have been reset by its parent unvisited
        # (a memory selector clears the children before its current one).
        snapshot = self._snapshot
        left_changed = any(
            self._by_id[id_].status != status
            for id_, status in snapshot.previously_visited.items()
            if id_ not in snapshot.visited and id_ in self._by_id
        )
        board_written = self._blackboard_written()
        if snapshot.changed or left_changed or feedback_changed or board_written:
            self._write(tick, seconds, board_written)

    def record_final(self, tick: int, seconds: float) -> None:
        """Writes the tree as the run left it (stopped, shut down) if it differs from the
        last line."""
        board_written = self._blackboard_written()
        if board_written or self._node_states() != self._last_nodes:
            self._write(tick, seconds, board_written)

    def _blackboard_written(self) -> bool:
        """Whether a key was written (or unset) since the last call; the first call, yes."""
        stream = py_trees.blackboard.Blackboard.activity_stream
        if stream is None:
            return not self._blackboard_recorded
        written = any(item.activity_type in _WRITES for item in stream.data)
        stream.clear()
        return written or not self._blackboard_recorded

    def _node_states(self) -> list[dict[str, str]]:
        return [
            {
                "path": path,
                "name": node.name,
                "status": node.status.value,
                "feedback": node.feedback_message,
            }
            for path, node, _ in self._nodes
        ]

    def _write(self, tick: int, seconds: float, with_blackboard: bool) -> None:
        nodes = self._node_states()
        line: dict[str, Any] = {"tick": tick, "t": round(seconds, 3), "nodes": nodes}
        if with_blackboard:
            storage = py_trees.blackboard.Blackboard.storage
            line["blackboard"] = {key: to_jsonable(storage[key]) for key in sorted(storage)}
            self._blackboard_recorded = True
        self._last_nodes = nodes
        try:
            self._ticks.write(json.dumps(line) + "\n")
            self._ticks.flush()
        except (OSError, ValueError) as error:  # ValueError: the file was closed
            raise RecordWriteError(
                f"cannot write {self.out_dir / TICKS_FILE}: {_why(error)}"
            ) from error

    def write_summary(self, summary: RunSummary) -> Path:
        """Writes ``summary.json`` whole, with the software that made it (``software``,
        unless the summary names it)."""
        path = self.out_dir / SUMMARY_FILE
        if summary.software is None:
            summary = dataclasses.replace(summary, software=software_versions())
        try:
            return write_text_atomic(path, json.dumps(summary.to_json(), indent=2) + "\n")
        except OutputError as error:
            raise RecordWriteError(str(error)) from error

    def close(self) -> None:
        if not self._ticks.closed:
            # The last flush may fail again (full disk): that was already reported.
            with contextlib.suppress(OSError):
                self._ticks.close()


def _why(error: BaseException) -> str:
    if isinstance(error, OSError):
        return describe_os_error(error)
    return str(error)


def load_ticks(run_dir: Path) -> list[dict[str, Any]]:
    """The recorded ticks of a run, in order, each with the blackboard in force then.

    Unreadable lines (a torn last line of a killed run, a damaged file) are skipped;
    :func:`read_ticks` also says which.
    """
    return read_ticks(run_dir)[0]


def read_ticks(run_dir: Path) -> tuple[list[dict[str, Any]], list[int]]:
    """The readable ticks of ``ticks.jsonl`` and the numbers (1-based) of the lines skipped.

    A line is readable when it is a JSON object with an integer ``tick``, a number ``t``
    and a list of ``nodes`` (objects with ``path`` and ``status``), and its tick comes
    after the previous readable one.

    Raises:
        RunRecordError: the file cannot be opened.
    """
    path = Path(run_dir) / TICKS_FILE
    ticks: list[dict[str, Any]] = []
    skipped: list[int] = []
    blackboard: dict[str, Any] = {}
    descriptor = open_regular_file(path, "ticks file", RunRecordError)
    try:
        with open(descriptor, encoding="utf-8", errors="replace") as lines:
            for number in range(1, MAX_TICK_LINES + 1):
                line = lines.readline(MAX_TICK_LINE_CHARS + 1)
                if not line:
                    break
                runaway = len(line) > MAX_TICK_LINE_CHARS
                if runaway:
                    _skip_rest_of_line(lines)
                tick = None if runaway else _parse_tick(line)
                if tick is None or (ticks and tick["tick"] <= ticks[-1]["tick"]):
                    if runaway or line.strip():
                        skipped.append(number)
                    continue
                board = tick.get("blackboard")
                blackboard = board if isinstance(board, dict) else blackboard
                tick["blackboard"] = blackboard
                ticks.append(tick)
    except OSError as error:
        raise RunRecordError(f"cannot read {printable(path)}: {_why(error)}") from error
    return ticks, skipped


def _skip_rest_of_line(lines: Any) -> None:
    """Reads on to the end of a runaway line in bounded pieces (the file is a regular
    file, so this ends)."""
    while True:
        piece = lines.readline(MAX_TICK_LINE_CHARS)
        if not piece or piece.endswith("\n"):
            return


def _parse_tick(line: str) -> dict[str, Any] | None:
    if not line.strip():
        return None
    try:
        tick = parse_json(line, TICKS_FILE, RunRecordError)
    except RunRecordError:  # bad JSON, nested too deep, numbers too large
        return None
    if not isinstance(tick, dict):
        return None
    number, seconds, nodes = tick.get("tick"), tick.get("t"), tick.get("nodes")
    if not isinstance(number, int) or isinstance(number, bool):
        return None
    if not isinstance(seconds, int | float) or isinstance(seconds, bool):
        return None
    if not isinstance(nodes, list) or not all(
        isinstance(node, dict)
        and isinstance(node.get("path"), str)
        and isinstance(node.get("status"), str)
        for node in nodes
    ):
        return None
    return tick
