"""The mission tree as a Graphviz picture with a legend, and the blackboard as a table.

py_trees' own ``render_dot_tree`` marks a composite with memory by U+24C2 (Ⓜ), which
no font installed with Graphviz here draws, and its blackboard view joins every key to
every leaf with edges that cross. This picture keeps py_trees' shapes and colours
(sequence: orange box, selector: cyan octagon, parallel: gold parallelogram, decorator:
white ellipse, leaf: grey ellipse), writes every mark in words, in ASCII, in one named
font (:data:`FONT`), adds a legend, and draws the blackboard as one table: a row per
key, a column per behaviour, W where it writes the key and R where it reads it.
"""

from __future__ import annotations

import html
import itertools
import re

import py_trees
import pydot

from bearchair.behaviours import keys

FONT = "DejaVu Sans"
"""The font every label asks for (fontconfig substitutes another if it is absent; the
labels are ASCII, so any substitute has their glyphs)."""
FONT_SIZE_PT = 10
LEAF_COLOUR = "gray"
WRITE_COLOUR = "#9ecae1"
READ_COLOUR = "#c7e9c0"
BOTH_COLOUR = "#fdd49e"


def node_style(node: py_trees.behaviour.Behaviour) -> tuple[str, str]:
    """py_trees' shape and fill colour for the node's kind."""
    if isinstance(node, py_trees.composites.Selector):
        return "octagon", "cyan"
    if isinstance(node, py_trees.composites.Sequence):
        return "box", "orange"
    if isinstance(node, py_trees.composites.Parallel):
        return "parallelogram", "gold"
    if isinstance(node, py_trees.decorators.Decorator):
        return "ellipse", "ghostwhite"
    return "ellipse", LEAF_COLOUR


def node_marks(node: py_trees.behaviour.Behaviour) -> list[str]:
    """What py_trees marks with a symbol, in words: memory, a parallel's policy."""
    marks = []
    if isinstance(node, py_trees.composites.Composite) and getattr(node, "memory", False):
        marks.append("memory")
    policy = getattr(node, "policy", None)
    if policy is not None:
        marks.append(type(policy).__name__ + (", synchronised" if policy.synchronise else ""))
    return marks


def _label(name: str, marks: list[str], lines: list[str] | None = None) -> str:
    """An HTML-like label: the name, the marks (or ``lines``) below it in small italics."""
    text = html.escape(name)
    below = [", ".join(marks)] if marks else []
    for line in [*below, *(lines or [])]:
        text += f'<BR/><FONT POINT-SIZE="{FONT_SIZE_PT - 2}"><I>{html.escape(line)}</I></FONT>'
    return f"<{text}>"


def tree_graph(root: py_trees.behaviour.Behaviour, with_blackboard: bool = False) -> pydot.Dot:
    """The tree (and the blackboard table) as a pydot graph, with its legend."""
    graph = pydot.Dot(graph_type="digraph", ordering="out", rankdir="TB", nodesep="0.25")
    graph.set_graph_defaults(fontname=FONT, fontsize=str(FONT_SIZE_PT))
    graph.set_node_defaults(fontname=FONT, fontsize=str(FONT_SIZE_PT), style="filled")
    graph.set_edge_defaults(fontname=FONT)
    ids = {}
    for number, node in enumerate(root.iterate(direct_descendants=False)):
        ids[node.id] = f"n{number}"
    for node in root.iterate():
        shape, colour = node_style(node)
        graph.add_node(
            pydot.Node(
                ids[node.id], label=_label(node.name, node_marks(node)), shape=shape,
                fillcolor=colour,
            )
        )  # fmt: skip
        for child in node.children:
            graph.add_edge(pydot.Edge(ids[node.id], ids[child.id]))
    graph.add_subgraph(legend())  # pyright: ignore[reportArgumentType] - pydot's stubs omit Cluster
    if with_blackboard:
        deepest = max(root.iterate(), key=_depth(root))
        graph.add_node(
            pydot.Node("blackboard", shape="plaintext", style="", label=blackboard_label(root))
        )
        graph.add_edge(pydot.Edge(ids[deepest.id], "blackboard", style="invis"))
    return graph


def _depth(root: py_trees.behaviour.Behaviour):
    depths = {}

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> None:
        depths[node.id] = depth
        for child in node.children:
            walk(child, depth + 1)

    walk(root, 0)
    return lambda node: depths[node.id]


LEGEND = (
    ("box", "orange", "Sequence", ["runs its children in order,", "fails at the first failure"]),
    (
        "octagon",
        "cyan",
        "Selector",
        ["tries its children in order,", "succeeds at the first success"],
    ),
    ("ellipse", "ghostwhite", "Decorator", ["changes how its child runs", "(here: repeats it)"]),
    ("ellipse", LEAF_COLOUR, "Leaf", ["a behaviour:", "an action or a check"]),
)
MEMORY_NOTE = [
    "memory: on the next tick, resumes",
    "the child that was RUNNING",
    "instead of starting over",
]


def legend() -> pydot.Cluster:
    """The legend: one sample node per kind of node, and what the marks mean."""
    cluster = pydot.Cluster(
        "legend", label="Legend", fontsize=str(FONT_SIZE_PT), style="rounded", color="gray50"
    )
    names = [f"legend{number}" for number in range(len(LEGEND))]
    for name, (shape, colour, kind, meaning) in zip(names, LEGEND, strict=True):
        cluster.add_node(
            pydot.Node(
                name, shape=shape, fillcolor=colour, fontsize=str(FONT_SIZE_PT - 1),
                label=_label(kind, [], meaning),
            )
        )  # fmt: skip
    cluster.add_node(
        pydot.Node(
            "legend_marks", shape="plaintext", style="", fontsize=str(FONT_SIZE_PT - 1),
            label=_label("", [], MEMORY_NOTE),
        )
    )  # fmt: skip
    names.append("legend_marks")
    for above, below in itertools.pairwise(names):  # stacked, top to bottom
        cluster.add_edge(pydot.Edge(above, below, style="invis"))
    return cluster


def blackboard_matrix(
    root: py_trees.behaviour.Behaviour,
) -> tuple[list[str], list[str], dict[tuple[str, str], str]]:
    """Keys, behaviours (tree order, the executive first) and who does what to which key.

    Returns:
        ``(keys, behaviours, access)`` with ``access[(key, behaviour)]`` ``"W"``, ``"R"``
        or ``"RW"``; keys in :data:`bearchair.behaviours.keys.VALUES`' order, then any
        key only the registrations know.
    """
    access: dict[tuple[str, str], str] = {(key, "executive"): "W" for key in keys.SET_BY_EXECUTIVE}
    users = ["executive"]
    for node in root.iterate():
        for client in node.blackboards:
            for mode, registered in (("W", client.write), ("R", client.read)):
                for key in registered:
                    if node.name not in users:
                        users.append(node.name)
                    now = access.get((key, node.name), "")
                    if mode not in now:
                        access[(key, node.name)] = "".join(sorted(now + mode))
    known = [key for key in keys.VALUES if any(k == key for k, _ in access)]
    others = sorted({k for k, _ in access} - set(known))
    return known + others, users, access


def _header(name: str) -> str:
    """A column header: the name broken into lines at its words (CamelCase, spaces)."""
    words = re.findall(r"[A-Z][a-z]*|[a-z]+|\d+", name) if " " not in name else name.split()
    return "<BR/>".join(html.escape(word) for word in words) or html.escape(name)


def _value_type(key: str) -> str:
    """What the key holds, short: the type's last name (``SittingPose``, ``int``)."""
    value = keys.VALUES.get(key, "?").split(": ")[0].split(" (")[0]
    return value.rsplit(".", 1)[-1]


def blackboard_label(root: py_trees.behaviour.Behaviour) -> str:
    """The blackboard as one HTML-like Graphviz table (a key per row, a user per column)."""
    rows_keys, users, access = blackboard_matrix(root)
    colour = {"W": WRITE_COLOUR, "R": READ_COLOUR, "RW": BOTH_COLOUR}
    cell = '<TD BGCOLOR="{c}">{t}</TD>'
    head = "".join(f'<TD><FONT POINT-SIZE="8">{_header(u)}</FONT></TD>' for u in users)
    lines = [
        '<<TABLE BORDER="0" CELLBORDER="1" CELLSPACING="0" CELLPADDING="3">',
        f'<TR><TD COLSPAN="{len(users) + 2}"><B>Blackboard</B>: who writes (W) and reads (R) '
        "each key</TD></TR>",
        f'<TR><TD ALIGN="LEFT"><B>key</B></TD><TD ALIGN="LEFT"><B>holds</B></TD>{head}</TR>',
    ]
    for key in rows_keys:
        cells = "".join(
            cell.format(c=colour[access[(key, u)]], t=access[(key, u)])
            if (key, u) in access
            else "<TD></TD>"
            for u in users
        )
        lines.append(
            f'<TR><TD ALIGN="LEFT">{html.escape(key)}</TD>'
            f'<TD ALIGN="LEFT"><FONT POINT-SIZE="8">{html.escape(_value_type(key))}</FONT></TD>'
            f"{cells}</TR>"
        )
    lines.append("</TABLE>>")
    return "".join(lines)
