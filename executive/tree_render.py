"""Rendering the mission tree: text for terminals, dot/SVG/PNG for people."""

from __future__ import annotations

import shutil
from pathlib import Path

import py_trees

from bearchair.behaviours import keys
from bearchair.core.errors import RenderError, one_line
from bearchair.executive.outputs import atomic_path

TEXT_FORMATS = ("ascii", "unicode")
GRAPH_FORMATS = ("dot", "svg", "png")


def render_text(
    root: py_trees.behaviour.Behaviour, fmt: str, with_blackboard: bool, show_status: bool = False
) -> str:
    """The tree as ASCII or Unicode art, py_trees' own (``bearchair tree`` and ``inspect``).

    Args:
        root: the tree.
        fmt: ``ascii`` or ``unicode``.
        with_blackboard: append every blackboard key and its users.
        show_status: show each node's status mark and feedback message.
    """
    draw = py_trees.display.ascii_tree if fmt == "ascii" else py_trees.display.unicode_tree
    art = draw(root, show_status=show_status)
    if not with_blackboard:
        return art
    lines = [art.rstrip(), "", "Blackboard keys (R read, W write):"]
    for key, users in sorted(blackboard_users(root).items()):
        lines.append(f"  {key:<28} " + ", ".join(f"{name} ({mode})" for name, mode in users))
    return "\n".join(lines)


def blackboard_users(root: py_trees.behaviour.Behaviour) -> dict[str, list[tuple[str, str]]]:
    """For each blackboard key, the behaviours registered on it and how (R or W)."""
    users: dict[str, list[tuple[str, str]]] = {}
    for node in root.iterate():
        for client in node.blackboards:
            for key in sorted(client.read):
                users.setdefault(key, []).append((node.name, "R"))
            for key in sorted(client.write):
                users.setdefault(key, []).append((node.name, "W"))
    return users


def blackboard_table(root: py_trees.behaviour.Behaviour) -> str:
    """The table of ``bearchair.behaviours.keys``' docstring, from the blackboard registrations.

    One row per key, in :data:`bearchair.behaviours.keys.VALUES`' order then any key only the
    registrations know: what it holds, the behaviour classes (and the executive) that
    register it for writing, and those that register it for reading, in tree order.
    """
    writers: dict[str, list[str]] = {key: ["executive"] for key in keys.SET_BY_EXECUTIVE}
    readers: dict[str, list[str]] = {}
    for node in root.iterate():
        for client in node.blackboards:
            for users, registered in ((writers, client.write), (readers, client.read)):
                for key in registered:
                    names = users.setdefault(key, [])
                    if type(node).__name__ not in names:
                        names.append(type(node).__name__)
    used = [key for key in {**writers, **readers} if key not in keys.VALUES]
    rows = [("key", "value", "written by", "read by")] + [
        (
            key,
            keys.VALUES.get(key, "?"),
            ", ".join(writers.get(key, [])),
            ", ".join(readers.get(key, [])),
        )
        for key in [*keys.VALUES, *sorted(used)]
    ]
    widths = [max(len(row[column]) for row in rows) for column in range(4)]
    rule = " ".join("=" * width for width in widths)

    def line(row: tuple[str, ...]) -> str:
        return " ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()

    return "\n".join([rule, line(rows[0]), rule, *(line(row) for row in rows[1:]), rule])


def render_graph(
    root: py_trees.behaviour.Behaviour, fmt: str, out: Path, with_blackboard: bool
) -> Path:
    """Writes the tree (``executive.tree_picture``) as a dot, SVG or PNG file at ``out``.

    SVG and PNG need Graphviz's ``dot``.
    """
    from bearchair.executive.tree_picture import tree_graph

    if fmt in ("svg", "png") and shutil.which("dot") is None:
        raise RenderError("Graphviz's 'dot' is not installed (apt-get install graphviz)")
    graph = tree_graph(root, with_blackboard)
    out.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as scratch:
        if fmt == "dot":
            Path(scratch).write_text(graph.to_string(), encoding="utf-8")
        else:
            try:
                image = graph.create(prog="dot", format=fmt)
                Path(scratch).write_bytes(image if isinstance(image, bytes) else image.encode())
            except Exception as error:  # pydot raises bare Exception on dot's errors
                raise RenderError(f"Graphviz's dot failed: {one_line(error)}") from error
    return out


def write_btcpp(root: py_trees.behaviour.Behaviour, out: Path | None) -> int:
    """``bearchair tree --format btcpp``: the BehaviorTree.CPP v4 XML on stdout, or in ``out``
    (written whole or not at all)."""
    from bearchair.executive.btcpp import tree_to_btcpp_xml
    from bearchair.executive.outputs import check_output_file, write_text_atomic

    xml = tree_to_btcpp_xml(root)
    if out is None:
        print(xml, end="")
        return 0
    print(write_text_atomic(check_output_file(out, "--out", (".xml",)), xml))
    return 0
