"""BehaviorTree.CPP v4 XML both ways, and the registry of leaves an XML file may name.

* :func:`tree_to_btcpp_xml` writes a py_trees tree as ``<root BTCPP_format="4">`` with a
  ``<TreeNodesModel>`` (``bearchair tree --format btcpp``): Groot2 opens and edits it.
* :func:`tree_from_btcpp_xml` builds a py_trees tree from such a document, its leaves
  from :func:`leaf_registry`; :func:`factory_from_xml_file` makes a tree factory of a file
  (``--tree mission.xml``).
* :func:`leaf_registry`: every leaf class of ``bearchair.behaviours`` by class name, and
  the plug-ins' through the entry points of :data:`LEAVES_GROUP`.

The mapping of nodes and ports: :mod:`bearchair.executive.btcpp_export` (writing) and
:mod:`bearchair.executive.btcpp_import` (reading); the user's page is
``docs/btcpp-groot2.md``.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import inspect
import pkgutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import py_trees

from bearchair.core.errors import InputError, one_line
from bearchair.executive.btcpp_export import BtcppExportError, leaf_ports, tree_to_btcpp_xml
from bearchair.executive.btcpp_import import BtcppImportError, tree_from_btcpp_xml

__all__ = [
    "LEAVES_GROUP",
    "BtcppExportError",
    "BtcppImportError",
    "TreeFactory",
    "factory_from_xml_file",
    "leaf_ports",
    "leaf_registry",
    "own_leaves",
    "tree_from_btcpp_xml",
    "tree_to_btcpp_xml",
]

LEAVES_GROUP = "bearchair.behaviours"
"""The entry-point group of plug-ins' leaves: each entry's name is the leaf's
registration ID (the XML tag), its object a Behaviour class (or a callable taking
``name=``) in the plug-in's package, e.g. ``PatChair = "my_pkg.leaves:PatChair"``."""

TreeFactory = Callable[[Any], py_trees.behaviour.Behaviour]
"""Makes a fresh tree; its one argument (the mission's options) may be ignored."""


def own_leaves() -> dict[str, type[py_trees.behaviour.Behaviour]]:
    """Every leaf class defined in ``bearchair.behaviours``' modules, by class name.

    A class another one of them derives from (``SkillBehaviour``) is a base, not a leaf.
    """
    import bearchair.behaviours as package

    found: dict[str, type[py_trees.behaviour.Behaviour]] = {}
    for module_info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"{package.__name__}.{module_info.name}")
        for name, cls in inspect.getmembers(module, inspect.isclass):
            if cls.__module__ == module.__name__ and issubclass(cls, py_trees.behaviour.Behaviour):
                found[name] = cls
    bases = {base for cls in found.values() for base in cls.__mro__[1:]}
    return {name: cls for name, cls in sorted(found.items()) if cls not in bases}


def plugin_leaves() -> dict[str, Callable[..., Any]]:
    """The leaves registered through :data:`LEAVES_GROUP`, by entry-point name.

    Raises:
        InputError: an entry cannot be loaded or is not callable (one line naming it).
    """
    found: dict[str, Callable[..., Any]] = {}
    for entry in sorted(importlib.metadata.entry_points(group=LEAVES_GROUP), key=lambda e: e.name):
        try:
            leaf = entry.load()
        except Exception as error:
            raise InputError(
                f"bearchair: the leaf {entry.name!r} ({entry.value}, entry point group "
                f"{LEAVES_GROUP}) cannot be loaded: {one_line(error)}"
            ) from error
        if not callable(leaf):
            raise InputError(
                f"bearchair: the leaf {entry.name!r} ({entry.value}) is not a class or callable"
            )
        found[entry.name] = leaf
    return found


def leaf_registry() -> dict[str, Callable[..., Any]]:
    """Ours (:func:`own_leaves`) and the plug-ins' (:func:`plugin_leaves`), by name.

    Raises:
        InputError: a plug-in's leaf takes the name of one of ours, or cannot be loaded.
    """
    ours: dict[str, Callable[..., Any]] = dict(own_leaves())
    theirs = plugin_leaves()
    clash = sorted(set(ours) & set(theirs))
    if clash:
        raise InputError(
            f"bearchair: plug-in leaves {', '.join(clash)} ({LEAVES_GROUP}) take the names of "
            "bearchair's own leaves: register them under other names"
        )
    return {**ours, **theirs}


def factory_from_xml_file(path: Path) -> TreeFactory:
    """A tree factory building the main tree of a BehaviorTree.CPP v4 file, afresh each call.

    The file is read and built once now, so a bad file fails here (one line naming the
    line and the node), not at the first tick.

    Raises:
        InputError: the file is missing or unreadable, or :class:`BtcppImportError`.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeError) as error:
        raise InputError(f"bearchair: --tree {path}: {one_line(error)}") from error
    leaves = leaf_registry()
    tree_from_btcpp_xml(text, leaves, source=str(path))

    def create_tree(options: Any = None) -> py_trees.behaviour.Behaviour:
        del options  # the file says everything the tree is
        return tree_from_btcpp_xml(text, leaves, source=str(path))

    return create_tree
