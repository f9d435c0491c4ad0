"""A tree variant: the mission without the human assistance, announcing the seat."""

from __future__ import annotations

import dataclasses

import py_trees

from bearchair.trees.mission import create_tree
from bearchair.trees.options import TreeOptions
from bearchair_example.leaves import AnnounceSeat


def create_tree_without_assistance(options: TreeOptions) -> py_trees.behaviour.Behaviour:
    """The mission tree with ``assistance`` off (an inaccessible chair fails at once) and
    :class:`AnnounceSeat` before the walk. The other options are honoured."""
    root = create_tree(dataclasses.replace(options, assistance=False))
    assert isinstance(root, py_trees.composites.Composite)  # the mission's root is a Sequence
    walk = [child.name for child in root.children].index("WalkToChair")
    root.insert_child(AnnounceSeat(), walk)
    return root
