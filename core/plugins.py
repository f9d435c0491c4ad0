"""Plug-ins through entry points: one way to find them, one way to say they are missing.

bearchair's plug-in groups (each documented in ``docs/extending.md``):

==================== ================================================= ===========================
group                an entry point names                              used by
==================== ================================================= ===========================
bearchair.trees      a tree factory ``(TreeOptions) -> Behaviour``     ``--tree NAME``
bearchair.skills     a MissionSkills class, or a mapping of overrides  configuration ``[skills]``
bearchair.backends   a robot device factory ``(settings) -> device``   the cell's ``"backend"``
bearchair.behaviours a leaf class (for trees read from XML)            the XML tree loader
bearchair.commands   a ``register(subparsers)`` adding a subcommand    ``bearchair`` itself
==================== ================================================= ===========================

A plug-in is a distribution that declares entry points in its ``pyproject.toml``; nothing
in bearchair is edited to add one.
"""

from __future__ import annotations

import importlib.metadata
from typing import Any

from bearchair.core.errors import PluginError, one_line


def entry_points(group: str) -> dict[str, importlib.metadata.EntryPoint]:
    """The installed entry points of ``group``, by name (tests replace this function)."""
    return {entry.name: entry for entry in importlib.metadata.entry_points(group=group)}


def load_entry_point(group: str, name: str, what: str) -> Any:
    """The object the entry point ``name`` of ``group`` names.

    Args:
        group: the entry point group, e.g. ``bearchair.backends``.
        name: the entry point's name.
        what: what it is, for the message (``"robot backend"``).

    Raises:
        PluginError: no such entry point (the message lists the installed ones), or its
            module or attribute cannot be loaded.
    """
    found = entry_points(group)
    if name not in found:
        known = ", ".join(sorted(found)) or "none installed"
        raise PluginError(f"no {what} named {name!r} (entry points {group}: {known})")
    entry = found[name]
    try:
        return entry.load()
    except Exception as error:  # an import error, or anything the plug-in raises on import
        raise PluginError(
            f"the {what} {name!r} ({entry.value}) cannot be loaded: {one_line(error)}"
        ) from error
