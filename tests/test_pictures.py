"""Pictures that explain: the tree's glyphs and legend, the blackboard table, the scene
pictures' captions and overlays, one renderer for imagined poses."""

from __future__ import annotations

import html
import re
import shutil
import subprocess

import pytest

from bearchair.executive.render import blackboard_users, render_graph
from bearchair.executive.tree_picture import FONT, blackboard_matrix, tree_graph
from bearchair.trees.mission import create_tree

needs_dot = pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz's dot is absent")


def label_characters(dot_source: str) -> set[str]:
    """Every character a label of the dot source draws (HTML tags and entities undone)."""
    drawn = set()
    for label in re.findall(r"label=<(.*?)>[,\]]", dot_source, flags=re.S):
        drawn |= set(html.unescape(re.sub(r"<[^>]*>", "", label)))
    for label in re.findall(r'label="((?:[^"\\]|\\.)*)"', dot_source):
        drawn |= set(label)
    return drawn - {"\n"}


def font_file(family: str) -> str:
    """The font file fontconfig (hence Graphviz) draws ``family`` with."""
    return subprocess.run(
        ["fc-match", "--format=%{file}", family], capture_output=True, text=True, check=True
    ).stdout


@needs_dot
@pytest.mark.parametrize("with_blackboard", [False, True])
def test_the_tree_picture_has_a_glyph_for_every_character_it_draws(tmp_path, with_blackboard):
    ttlib = pytest.importorskip("fontTools.ttLib")
    if shutil.which("fc-match") is None:
        pytest.skip("fontconfig's fc-match is absent")
    source = tree_graph(create_tree(), with_blackboard).to_string()
    assert f'fontname="{FONT}"' in source
    drawn = label_characters(source)
    assert {"S", "q", "(", ":"} <= drawn  # the labels were found
    cmap = ttlib.TTFont(font_file(FONT)).getBestCmap()
    missing = sorted(c for c in drawn if c != " " and ord(c) not in cmap)
    assert missing == [], f"no glyph in {font_file(FONT)} for {missing}"
    # py_trees' own picture asks for U+24C2 (memory), which the font lacks: the check bites.
    assert 0x24C2 not in cmap or "Ⓜ" not in drawn
    out = render_graph(create_tree(), "png", tmp_path / "tree.png", with_blackboard)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_tree_picture_has_a_legend_and_names_the_memory_mark():
    graph = tree_graph(create_tree())
    source = graph.to_string()
    assert "cluster_legend" in source
    for kind in ("Sequence", "Selector", "Decorator", "Leaf"):
        assert kind in source
    # The root is a sequence with memory, a leaf has none: their labels say so in words.
    labels = {
        str(node.get("label")).split("<BR/>")[0]: str(node.get("label"))
        for node in graph.get_nodes()
    }
    assert "<I>memory</I>" in labels["<Put the bear on the chair"]
    assert "memory" not in labels["<ScanChair>"]


def test_the_blackboard_table_holds_every_registration_and_no_other():
    root = create_tree()
    keys, users, access = blackboard_matrix(root)
    expected: dict[tuple[str, str], set[str]] = {}
    for key, registrations in blackboard_users(root).items():
        for name, mode in registrations:
            expected.setdefault((key, name), set()).add(mode)
    from_tree = {cell: "".join(sorted(modes)) for cell, modes in expected.items()}
    assert {c: m for c, m in access.items() if c[1] != "executive"} == from_tree
    assert access[("/mission/seed", "executive")] == "W"
    assert set(keys) == {k for k, _ in access} and users[0] == "executive"
    label = tree_graph(root, with_blackboard=True).get_node("blackboard")[0].get("label")
    assert label.count("<TR>") == len(keys) + 2  # title, header, a row per key
