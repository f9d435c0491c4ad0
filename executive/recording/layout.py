"""The layout a mission's recording opens with: a Rerun blueprint sent with the data.

Left, the 3D scene (``world``: the arena, the robots, the scan, the drops, the path)
over the camera views (one tab per scan view, depth and colour under its pinhole).
Right, the tree as a graph (``tree``, coloured by status) over the plots (the rotations
asked and measured, the tag seen, the seating plan's joints) and the text (every log
line, the imagination's verdicts, the run's summary). The viewer's panels stay open; a
user who rearranges the views can get this layout back with "reset blueprint".
"""

from __future__ import annotations

import collections
from pathlib import Path
from typing import Any

import py_trees
import rerun.blueprint as rrb

from bearchair.skills.perception.views import SCAN_CONFIGURATIONS

CAMERA_VIEW_TABS = len(SCAN_CONFIGURATIONS)
"""One tab per planned scan view (a view replaced higher up keeps its index)."""


def mission_blueprint() -> rrb.Blueprint:
    """The recording's default layout (module docstring)."""
    scene = rrb.Vertical(
        rrb.Spatial3DView(name="scene", origin="world"),
        rrb.Tabs(
            *(
                rrb.Spatial2DView(name=f"view {index}", origin=f"world/scan/views/{index}")
                for index in range(CAMERA_VIEW_TABS)
            ),
            name="camera views",
        ),
        row_shares=[3, 2],
    )
    plots = rrb.Tabs(
        rrb.TimeSeriesView(name="rotations (deg)", origin="assistance"),
        rrb.TimeSeriesView(name="tag seen", origin="walk"),
        rrb.TimeSeriesView(name="seating plan (rad)", origin="seat/plan"),
        name="plots",
    )
    text = rrb.Tabs(
        rrb.TextLogView(name="log", origin="/"),
        rrb.TextDocumentView(name="imagination", origin="imagination/verdicts"),
        rrb.TextDocumentView(name="summary", origin="mission/summary"),
        name="text",
    )
    side = rrb.Vertical(
        rrb.GraphView(name="tree", origin="tree"), plots, text, row_shares=[3, 2, 2]
    )
    return rrb.Blueprint(rrb.Horizontal(scene, side, column_shares=[3, 2]), collapse_panels=False)


def blueprint_views(path: Path) -> list[tuple[str, str, str]]:
    """The views of a recording's blueprint as (kind, name, origin): ``("3D", "scene",
    "world")``, in the file's order (for tests and tools)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(str(path))
    views = []
    for store in reader.blueprints():
        for chunk in reader.stream(store=store).to_chunks():
            batch = chunk.to_record_batch()
            if "ViewBlueprint:class_identifier" not in batch.schema.names:
                continue
            columns = [
                batch.column(f"ViewBlueprint:{name}").to_pylist()
                for name in ("class_identifier", "display_name", "space_origin")
            ]
            views.extend(
                (_first(k), _first(n), _first(o)) for k, n, o in zip(*columns, strict=True)
            )
    return views


def _first(cell: Any) -> str:
    return str(cell[0]) if isinstance(cell, list) and cell else str(cell)


def tree_layout(
    nodes: list[tuple[str, py_trees.behaviour.Behaviour, int]],
) -> list[tuple[float, float]]:
    """A top-down tree layout: leaves side by side, parents centred over their children
    (graph units; rows 120 apart, leaves 220 apart so that labels fit)."""
    x_of: dict[str, float] = {}
    children: dict[str, list[str]] = collections.defaultdict(list)
    for path, _, _ in nodes:
        if "/" in path:
            children[path.rsplit("/", 1)[0]].append(path)
    next_leaf = 0.0

    def place(path: str) -> float:
        nonlocal next_leaf
        if not children[path]:
            x_of[path] = next_leaf
            next_leaf += 220.0
        else:
            xs = [place(child) for child in children[path]]
            x_of[path] = (xs[0] + xs[-1]) / 2.0
        return x_of[path]

    place(nodes[0][0])
    return [(x_of[path], 120.0 * depth) for path, _, depth in nodes]
