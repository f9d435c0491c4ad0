"""Which tree a command runs: ``--tree SPEC`` resolved to a :data:`TreeFactory`.

A SPEC is one of:

- a name: ``mission`` (the shipped tree, :func:`bearchair.trees.mission.create_tree`) or
  the name of an entry point of :data:`TREES_GROUP` (a plug-in's tree);
- ``module:factory``: a callable importable from a module (``my_trees.variants:no_help``;
  dots after the colon reach an attribute of an attribute);
- a file ending in ``.xml``: a BehaviorTree.CPP v4 tree built with the registered leaves
  (``bearchair.executive.btcpp``).

Every factory is called with the run's :class:`bearchair.trees.options.TreeOptions`
(:func:`build_tree`), and what it returns must be a py_trees behaviour.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import py_trees

from bearchair.core.errors import InputError, PluginError, one_line
from bearchair.core.plugins import entry_points, load_entry_point
from bearchair.trees.mission import create_tree
from bearchair.trees.options import TreeFactory, TreeOptions

__all__ = ["DEFAULT_TREE", "TREES_GROUP", "TreeFactory", "build_tree", "load_tree_factory"]

TREES_GROUP = "bearchair.trees"
"""The entry point group of plug-in trees: each names a :data:`TreeFactory`."""
DEFAULT_TREE = "mission"
"""The shipped mission tree's name."""


def load_tree_factory(spec: str) -> TreeFactory:
    """The tree factory ``spec`` names (see the module docstring).

    Raises:
        PluginError: the name, module, attribute or XML support is missing, or what it
            names is not a callable taking one argument (the options); one line.
    """
    spec = spec.strip()
    if not spec:
        raise PluginError("--tree: empty tree name")
    if spec.endswith(".xml"):
        return _xml_factory(Path(spec))
    if ":" in spec:
        factory = _import_factory(spec)
    elif spec == DEFAULT_TREE:
        factory = create_tree
    else:
        factory = load_entry_point(TREES_GROUP, spec, "tree")
    _check_factory(factory, spec)
    return factory


def build_tree(
    factory: TreeFactory, options: TreeOptions | None = None, spec: str = "the tree"
) -> py_trees.behaviour.Behaviour:
    """``factory(options)``, checked to be a py_trees behaviour.

    Raises:
        PluginError: the factory raised, or returned something else than a behaviour.
    """
    try:
        root = factory(options or TreeOptions())
    except Exception as error:
        raise PluginError(f"--tree {spec}: building the tree failed: {one_line(error)}") from error
    if not isinstance(root, py_trees.behaviour.Behaviour):
        raise PluginError(
            f"--tree {spec}: the factory returned {type(root).__name__}, not a "
            "py_trees.behaviour.Behaviour"
        )
    return root


def available_trees() -> list[str]:
    """The names ``--tree`` accepts besides ``module:factory`` and XML files."""
    return [DEFAULT_TREE, *sorted(entry_points(TREES_GROUP))]


def _import_factory(spec: str) -> TreeFactory:
    module_name, _, attribute = spec.partition(":")
    if not module_name or not attribute:
        raise PluginError(f"--tree {spec}: write module:factory (e.g. my_trees:create_tree)")
    try:
        target: object = importlib.import_module(module_name)
    except Exception as error:  # ModuleNotFoundError, or the module's own error
        raise PluginError(
            f"--tree {spec}: cannot import {module_name}: {one_line(error)}"
        ) from error
    for part in attribute.split("."):
        if not hasattr(target, part):
            raise PluginError(f"--tree {spec}: {module_name} has no attribute {attribute}")
        target = getattr(target, part)
    return target  # pyright: ignore[reportReturnType]  # checked by _check_factory


def _check_factory(factory: object, spec: str) -> None:
    if not callable(factory):
        raise PluginError(f"--tree {spec}: {type(factory).__name__} is not callable")
    try:
        inspect.signature(factory).bind(TreeOptions())
    except TypeError as error:
        raise PluginError(
            f"--tree {spec}: a tree factory takes one argument, the TreeOptions ({error})"
        ) from None
    except ValueError:  # no signature to check (a builtin): calling it will tell
        pass


def _xml_factory(path: Path) -> TreeFactory:
    """A BehaviorTree.CPP XML file's factory (``bearchair.executive.btcpp``)."""
    from bearchair.executive import btcpp

    if not path.is_file():
        raise InputError(f"--tree {path}: no such file")
    return btcpp.factory_from_xml_file(path)
