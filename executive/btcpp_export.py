"""A py_trees tree as BehaviorTree.CPP v4 XML, the format Groot2 opens and edits.

The mapping (``docs/btcpp-groot2.md`` has the full table):

* composites: ``Sequence`` with memory -> ``Sequence``, without -> ``ReactiveSequence``;
  ``Selector`` with memory -> ``Fallback``, without -> ``ReactiveFallback``;
  ``Parallel`` (SuccessOnAll, synchronised) -> ``Parallel success_count="-1"``,
  (SuccessOnOne) -> ``Parallel success_count="1"``, both ``failure_count="1"``.
* decorators: ``Retry(num_failures=N)`` -> ``RetryUntilSuccessful num_attempts="N"``,
  ``Timeout(duration=s)`` -> ``Timeout msec="1000 s"``, ``Repeat(num_success=N)`` ->
  ``Repeat num_cycles="N"``, ``Inverter``, ``FailureIsSuccess`` -> ``ForceSuccess``,
  ``SuccessIsFailure`` -> ``ForceFailure``.
* py_trees' ``Success`` / ``Failure`` leaves -> ``AlwaysSuccess`` / ``AlwaysFailure``.
* any other leaf: an element named after its class (its registration ID), with a
  ``<TreeNodesModel>`` entry whose ports are the leaf's blackboard registrations:
  a key it reads is an ``input_port``, one it writes an ``output_port``, one it does both
  an ``inout_port``; the port's name is the key without its leading ``/`` and with ``/``
  as ``_`` (``/chair/mesh`` -> ``chair_mesh``) and its default the key itself
  (``{/chair/mesh}``). A leaf whose client remaps a key carries the port as an attribute
  (``chair_mesh="{/other/mesh}"``).

Anything else (``OneShot``, ``EternalGuard``, a non-synchronised ``SuccessOnAll``, ...)
has no BehaviorTree.CPP counterpart: :class:`BtcppExportError` names every such node.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import py_trees
from py_trees.common import Access

from bearchair.core.errors import InputError

BTCPP_FORMAT = "4"
"""The ``BTCPP_format`` of the files we write and read (BehaviorTree.CPP v4, Groot2)."""

PORT_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
"""What BehaviorTree.CPP accepts as a port name (``IsAllowedPortName``), minus its
reserved words, which :data:`RESERVED_ATTRIBUTES` lists."""

RESERVED_ATTRIBUTES = frozenset({"name", "ID"})


class BtcppExportError(InputError):
    """A tree holds nodes that BehaviorTree.CPP's XML cannot express."""


@dataclass(frozen=True)
class Port:
    """One port of a leaf: a blackboard key it registered.

    Attributes:
        name: the port's name in the XML (``chair_mesh``).
        direction: ``input_port``, ``output_port`` or ``inout_port``.
        key: the key the leaf's class registers (``/chair/mesh``): the port's default.
        remapped_to: where this instance's client stores it (the key itself unless remapped).
    """

    name: str
    direction: str
    key: str
    remapped_to: str


def port_name(key: str) -> str:
    """The port name of a blackboard key: ``/chair/mesh`` -> ``chair_mesh``."""
    return re.sub(r"[^A-Za-z0-9_]", "_", key.strip("/"))


def leaf_ports(leaf: py_trees.behaviour.Behaviour) -> list[Port]:
    """The ports of ``leaf``, from its blackboard clients' READ/WRITE registrations, by name.

    Raises:
        BtcppExportError: two keys give one port name, or a key gives no valid name.
    """
    reads: dict[str, str] = {}
    writes: dict[str, str] = {}
    for client in leaf.blackboards:
        for key in client.read:
            reads[key] = client.remappings.get(key, key)
        for key in client.write | client.exclusive:
            writes[key] = client.remappings.get(key, key)
    ports: dict[str, Port] = {}
    for key in sorted({*reads, *writes}):
        direction = (
            "inout_port"
            if key in reads and key in writes
            else ("input_port" if key in reads else "output_port")
        )
        name = port_name(key)
        if not PORT_NAME.match(name) or name in RESERVED_ATTRIBUTES:
            raise BtcppExportError(
                f"{leaf.name} ({type(leaf).__name__}): blackboard key {key!r} gives no "
                f"valid BehaviorTree.CPP port name ({name!r})"
            )
        if name in ports:
            raise BtcppExportError(
                f"{leaf.name} ({type(leaf).__name__}): keys {ports[name].key!r} and {key!r} "
                f"both give the port name {name!r}"
            )
        ports[name] = Port(name, direction, key, writes.get(key, reads.get(key, key)))
    return [ports[name] for name in sorted(ports)]


def node_type_of(leaf: py_trees.behaviour.Behaviour) -> str:
    """``Action`` unless the leaf's class says ``btcpp_node_type = "Condition"``.

    BehaviorTree.CPP's conditions never return RUNNING; every leaf of the mission runs a
    worker and does, so they are all actions.
    """
    kind = getattr(type(leaf), "btcpp_node_type", "Action")
    return kind if kind in ("Action", "Condition") else "Action"


def tree_id_of(root: py_trees.behaviour.Behaviour) -> str:
    """A BehaviorTree ID from the root's name: ``Put the bear on the chair`` ->
    ``PutTheBearOnTheChair`` (letters and digits only)."""
    words = re.findall(r"[A-Za-z0-9]+", root.name)
    tree_id = "".join(word[:1].upper() + word[1:] for word in words)
    return tree_id if tree_id[:1].isalpha() else f"Tree{tree_id}"


def _composite(node: py_trees.composites.Composite) -> tuple[str, dict[str, str]] | None:
    """The BT.CPP tag and attributes of a composite, or None if it has none."""
    memory = getattr(node, "memory", None)
    if type(node) is py_trees.composites.Sequence:
        return ("Sequence" if memory else "ReactiveSequence"), {}
    if type(node) is py_trees.composites.Selector:
        return ("Fallback" if memory else "ReactiveFallback"), {}
    if type(node) is py_trees.composites.Parallel:
        policy = node.policy
        if type(policy) is py_trees.common.ParallelPolicy.SuccessOnAll and policy.synchronise:
            return "Parallel", {"success_count": "-1", "failure_count": "1"}
        if type(policy) is py_trees.common.ParallelPolicy.SuccessOnOne:
            return "Parallel", {"success_count": "1", "failure_count": "1"}
    return None


def _decorator(node: py_trees.decorators.Decorator) -> tuple[str, dict[str, str]] | None:
    """The BT.CPP tag and attributes of a decorator, or None if it has none."""
    decorators = py_trees.decorators
    kind = type(node)
    if isinstance(node, decorators.Retry) and kind is decorators.Retry:
        return "RetryUntilSuccessful", {"num_attempts": str(node.num_failures)}
    if isinstance(node, decorators.Timeout) and kind is decorators.Timeout:
        return "Timeout", {"msec": str(round(1000.0 * node.duration))}
    if isinstance(node, decorators.Repeat) and kind is decorators.Repeat:
        return "Repeat", {"num_cycles": str(node.num_success)}
    plain = {
        decorators.Inverter: "Inverter",
        decorators.FailureIsSuccess: "ForceSuccess",
        decorators.SuccessIsFailure: "ForceFailure",
    }
    return (plain[kind], {}) if kind in plain else None


BUILTIN_LEAVES = {
    py_trees.behaviours.Success: "AlwaysSuccess",
    py_trees.behaviours.Failure: "AlwaysFailure",
}
"""py_trees' own leaves with a BehaviorTree.CPP built-in counterpart."""


class _Writer:
    """Builds the XML elements of a tree and collects the leaf models and the misfits."""

    def __init__(self) -> None:
        self.models: dict[str, tuple[str, list[Port]]] = {}
        self.unmapped: list[str] = []

    def element(self, node: py_trees.behaviour.Behaviour) -> ET.Element:
        if isinstance(node, py_trees.composites.Composite):
            mapped = _composite(node)
        elif isinstance(node, py_trees.decorators.Decorator):
            mapped = _decorator(node)
        elif type(node) in BUILTIN_LEAVES:
            mapped = BUILTIN_LEAVES[type(node)], {}
        else:
            return self._leaf(node)
        if mapped is None:
            self.unmapped.append(f"{node.name!r} ({type(node).__module__}.{type(node).__name__})")
            mapped = type(node).__name__, {}
        tag, attributes = mapped
        element = ET.Element(tag, {"name": node.name, **attributes})
        for child in node.children:
            element.append(self.element(child))
        return element

    def _leaf(self, leaf: py_trees.behaviour.Behaviour) -> ET.Element:
        if leaf.children:
            self.unmapped.append(f"{leaf.name!r} (a {type(leaf).__name__} with children)")
        ports = leaf_ports(leaf)
        kind = type(leaf).__name__
        model = (node_type_of(leaf), [Port(p.name, p.direction, p.key, p.key) for p in ports])
        if self.models.setdefault(kind, model) != model:
            raise BtcppExportError(
                f"two {kind} leaves register different blackboard keys: one model per "
                f"node type in BehaviorTree.CPP (remap keys instead)"
            )
        element = ET.Element(kind, {"name": leaf.name})
        for port in ports:
            if port.remapped_to != port.key:
                element.set(port.name, "{" + port.remapped_to + "}")
        return element


def tree_to_btcpp_xml(root: py_trees.behaviour.Behaviour, tree_id: str | None = None) -> str:
    """The tree as a BehaviorTree.CPP v4 XML document (text, ending with a newline).

    Args:
        root: the tree's root.
        tree_id: the ``<BehaviorTree ID>``; default from the root's name (:func:`tree_id_of`).

    Raises:
        BtcppExportError: nodes with no BehaviorTree.CPP counterpart (all of them named),
            or ports that cannot be named.
    """
    writer = _Writer()
    tree_id = tree_id or tree_id_of(root)
    document = ET.Element("root", {"BTCPP_format": BTCPP_FORMAT, "main_tree_to_execute": tree_id})
    tree = ET.SubElement(document, "BehaviorTree", {"ID": tree_id})
    tree.append(writer.element(root))
    if writer.unmapped:
        raise BtcppExportError(
            "no BehaviorTree.CPP counterpart for " + ", ".join(writer.unmapped) + " (the "
            "mapped nodes are listed in docs/btcpp-groot2.md)"
        )
    models = ET.SubElement(document, "TreeNodesModel")
    for kind in sorted(writer.models):
        node_type, ports = writer.models[kind]
        model = ET.SubElement(models, node_type, {"ID": kind})
        for port in ports:
            ET.SubElement(model, port.direction, {"name": port.name, "default": f"{{{port.key}}}"})
    ET.indent(document, space="  ")
    return ET.tostring(document, encoding="unicode") + "\n"


def access_of(direction: str) -> tuple[Access, ...]:
    """The py_trees accesses of a port direction."""
    return {
        "input_port": (Access.READ,),
        "output_port": (Access.WRITE,),
        "inout_port": (Access.READ, Access.WRITE),
    }[direction]
