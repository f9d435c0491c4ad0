"""Replaying a recorded run offline: the tree at any tick, the blackboard, the timeline."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from executive.record import SUMMARY_FILE, TICKS_FILE, TREE_FILE, load_ticks

STATUS_MARKS = {"SUCCESS": "✓", "FAILURE": "✕", "RUNNING": "*", "INVALID": "-"}
STRUCTURE_MARKS = {"Sequence": "[-]", "Selector": "[o]", "Retry": "(-)", "Parallel": "[=]"}


class RunRecordError(ValueError):
    """A directory is not a readable run record."""


class RecordedRun:
    """A run directory written by :class:`executive.record.RunRecorder`."""

    def __init__(self, run_dir: Path) -> None:
        run_dir = Path(run_dir)
        for name in (TREE_FILE, TICKS_FILE):
            if not (run_dir / name).is_file():
                raise RunRecordError(f"{run_dir}: not a run record (no {name})")
        self.run_dir = run_dir
        self.shape: list[dict[str, Any]] = json.loads((run_dir / TREE_FILE).read_text())
        self.ticks = load_ticks(run_dir)
        if not self.ticks:
            raise RunRecordError(f"{run_dir}: the run recorded no tick")
        summary_path = run_dir / SUMMARY_FILE
        self.summary: dict[str, Any] | None = (
            json.loads(summary_path.read_text()) if summary_path.is_file() else None
        )

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
        """The tree with each node's status and feedback at ``tick``."""
        state = {node["path"]: node for node in self.at(tick)["nodes"]}
        lines = []
        for node in self.shape:
            recorded = state.get(node["path"], {})
            status = recorded.get("status", "INVALID")
            mark = STRUCTURE_MARKS.get(node["type"], "-->")
            feedback = recorded.get("feedback") or ""
            line = (
                f"{'    ' * node['depth']}{mark} {node['name']} [{STATUS_MARKS.get(status, '?')}]"
            )
            lines.append(f"{line} -- {feedback}" if feedback else line)
        return "\n".join(lines)

    def blackboard_text(self, tick: int | None) -> str:
        board = self.at(tick)["blackboard"]
        return "\n".join(f"{key}: {json.dumps(value)}" for key, value in sorted(board.items()))

    def timeline(self) -> list[tuple[float, int, str, str, str]]:
        """Every status change of every node: (t, tick, node, old status, new status)."""
        changes = []
        previous: dict[str, str] = {}
        names = {node["path"]: node["name"] for node in self.shape}
        for recorded in self.ticks:
            for node in recorded["nodes"]:
                old = previous.get(node["path"], "INVALID")
                if node["status"] != old:
                    changes.append(
                        (recorded["t"], recorded["tick"], names[node["path"]], old, node["status"])
                    )
                    previous[node["path"]] = node["status"]
        return changes

    def timeline_text(self) -> str:
        return "\n".join(
            f"{t:8.2f} s  tick {tick:5d}  {name:<36} {old} -> {new}"
            for t, tick, name, old, new in self.timeline()
        )
