"""A py_trees tree from BehaviorTree.CPP v4 XML (ours, or one edited in Groot2).

How the XML maps to py_trees is the inverse of :mod:`bearchair.executive.btcpp_export`;
for leaves:

* the element's tag is the leaf's registration ID, looked up in the ``leaves`` registry
  (:func:`bearchair.executive.btcpp.leaf_registry`); the leaf is built as
  ``cls(name=<the name attribute>)`` (the tag when there is none). A leaf needing
  other constructor arguments is registered as a callable that supplies them.
* an attribute named after one of the leaf's ports (:func:`leaf_ports`) remaps it:
  ``chair_mesh="{/other/mesh}"`` makes the leaf store ``/chair/mesh`` at ``/other/mesh``;
  ``{=}`` or the port's own key leaves it as it is. A literal value (no braces) is refused:
  our leaves take their inputs from the blackboard only.
* ``<SubTree ID="X"/>`` is replaced by the ``<BehaviorTree ID="X">`` it names (no port
  remapping across it); ``<TreeNodesModel>`` is not read (the registry's classes say
  what their ports are).

Every error is an :class:`BtcppImportError` (an InputError: one line, exit 2) naming the
file's line and the node.
"""

from __future__ import annotations

import xml.parsers.expat
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import py_trees
from py_trees.common import Access

from bearchair.core.errors import InputError
from bearchair.executive.btcpp_export import BTCPP_FORMAT, BUILTIN_LEAVES, leaf_ports


class BtcppImportError(InputError):
    """A BehaviorTree.CPP XML document cannot be built into a tree."""


@dataclass
class XmlElement:
    """An XML element with the line it starts on (ElementTree keeps no line numbers)."""

    tag: str
    attributes: dict[str, str]
    line: int
    children: list[XmlElement] = field(default_factory=list)


def parse_xml(text: str, source: str = "<xml>") -> XmlElement:
    """The document's root element, with line numbers (expat, no external entities).

    Raises:
        BtcppImportError: not well-formed XML (with the line and column).
    """
    parser = xml.parsers.expat.ParserCreate()
    stack: list[XmlElement] = []
    roots: list[XmlElement] = []

    def start(tag: str, attributes: dict[str, str]) -> None:
        element = XmlElement(tag, dict(attributes), parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def end(_tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as error:
        raise BtcppImportError(
            f"{source}: not well-formed XML at line {error.lineno} column {error.offset}: "
            f"{xml.parsers.expat.ErrorString(error.code)}"
        ) from error
    return roots[0]


def _int(element: XmlElement, attribute: str, source: str, minimum: int) -> int:
    value = element.attributes.get(attribute)
    if value is None:
        raise BtcppImportError(
            f'{source} line {element.line}: <{element.tag}> needs {attribute}="..."'
        )
    try:
        number = int(value)
    except ValueError:
        number = minimum - 1
    if number < minimum:
        raise BtcppImportError(
            f"{source} line {element.line}: <{element.tag}> {attribute}={value!r} is not an "
            f"integer >= {minimum}"
        )
    return number


COMPOSITES = {
    "Sequence": (py_trees.composites.Sequence, True),
    "ReactiveSequence": (py_trees.composites.Sequence, False),
    "Fallback": (py_trees.composites.Selector, True),
    "ReactiveFallback": (py_trees.composites.Selector, False),
}
"""BT.CPP control nodes built as py_trees composites: (class, memory)."""

DECORATOR_ATTRIBUTES = {
    "RetryUntilSuccessful": ("num_attempts",),
    "Timeout": ("msec",),
    "Repeat": ("num_cycles",),
    "Inverter": (),
    "ForceSuccess": (),
    "ForceFailure": (),
}
CONTROL_ATTRIBUTES = {"Parallel": ("success_count", "failure_count")}
# fmt: off
UNMAPPED_BUILTINS = frozenset({
    "AsyncFallback", "AsyncSequence", "Delay", "IfThenElse", "KeepRunningUntilFailure",
    "LoopBool", "LoopDouble", "LoopInt", "LoopString", "ParallelAll", "Precondition",
    "RunOnce", "Script", "ScriptCondition", "SequenceWithMemory", "SetBlackboard",
    "SkipUnlessUpdated", "Sleep", "Switch2", "Switch3", "Switch4", "Switch5", "Switch6",
    "UnsetBlackboard", "WaitValueUpdate", "WasEntryUpdated", "WhileDoElse",
})
# fmt: on
"""BT.CPP 4.8.2's built-in nodes with no py_trees counterpart here (said as such); with
the mapped ones and ``SubTree`` they are all its built-ins (a test asks BT.CPP)."""
IGNORED_ATTRIBUTES = frozenset({"_uid", "_fullpath"})
"""Attributes Groot2 and BT.CPP add to trees they write that mean nothing here."""


class _Builder:
    def __init__(
        self,
        trees: Mapping[str, XmlElement],
        leaves: Mapping[str, Callable[..., object]],
        source: str,
        main: str,
    ):
        self.trees = trees
        self.leaves = leaves
        self.source = source
        self._expanding: list[str] = [main]  # the trees being built, to refuse a cycle

    def where(self, element: XmlElement) -> str:
        return f"{self.source} line {element.line}: <{element.tag}>"

    def build(self, element: XmlElement) -> py_trees.behaviour.Behaviour:
        tag = element.tag
        if tag == "SubTree":
            return self._subtree(element)
        allowed = ("name", *DECORATOR_ATTRIBUTES.get(tag, ()), *CONTROL_ATTRIBUTES.get(tag, ()))
        if tag in COMPOSITES or tag in DECORATOR_ATTRIBUTES or tag in CONTROL_ATTRIBUTES:
            self._check_attributes(element, allowed)
            children = [self.build(child) for child in element.children]
            name = element.attributes.get("name", tag)
            if tag in DECORATOR_ATTRIBUTES:
                return self._decorator(element, name, children)
            if not children:
                raise BtcppImportError(f"{self.where(element)} has no children")
            if tag in CONTROL_ATTRIBUTES:
                return self._parallel(element, name, children)
            kind, memory = COMPOSITES[tag]
            return kind(name=name, memory=memory, children=children)
        builtin = {tag_: kind for kind, tag_ in BUILTIN_LEAVES.items()}
        if tag in builtin:
            self._check_attributes(element, ("name",))
            return builtin[tag](name=element.attributes.get("name", tag))
        return self._leaf(element)

    def _check_attributes(self, element: XmlElement, allowed: tuple[str, ...]) -> None:
        for attribute in element.attributes:
            if attribute not in allowed and attribute not in IGNORED_ATTRIBUTES:
                raise BtcppImportError(
                    f"{self.where(element)} has an attribute {attribute}= that is not mapped "
                    f"to py_trees (known here: {', '.join(allowed)})"
                )

    def _decorator(
        self, element: XmlElement, name: str, children: list[py_trees.behaviour.Behaviour]
    ) -> py_trees.behaviour.Behaviour:
        if len(children) != 1:
            raise BtcppImportError(
                f"{self.where(element)} needs exactly one child, not {len(children)}"
            )
        (child,) = children
        decorators = py_trees.decorators
        tag = element.tag
        if tag == "RetryUntilSuccessful":
            count = _int(element, "num_attempts", self.source, 1)
            return decorators.Retry(name=name, child=child, num_failures=count)
        if tag == "Timeout":
            msec = _int(element, "msec", self.source, 1)
            return decorators.Timeout(name=name, child=child, duration=msec / 1000.0)
        if tag == "Repeat":
            cycles = _int(element, "num_cycles", self.source, 1)
            return decorators.Repeat(name=name, child=child, num_success=cycles)
        plain = {
            "Inverter": decorators.Inverter,
            "ForceSuccess": decorators.FailureIsSuccess,
            "ForceFailure": decorators.SuccessIsFailure,
        }
        return plain[tag](name=name, child=child)

    def _parallel(
        self, element: XmlElement, name: str, children: list[py_trees.behaviour.Behaviour]
    ) -> py_trees.behaviour.Behaviour:
        success = element.attributes.get("success_count", "-1")
        failure = element.attributes.get("failure_count", "1")
        policies = {
            ("-1", "1"): py_trees.common.ParallelPolicy.SuccessOnAll(synchronise=True),
            ("1", "1"): py_trees.common.ParallelPolicy.SuccessOnOne(),
        }
        if (success, failure) not in policies:
            raise BtcppImportError(
                f"{self.where(element)} success_count={success!r} failure_count={failure!r} "
                "is not mapped to py_trees (mapped: -1/1, all must succeed; 1/1, one must)"
            )
        return py_trees.composites.Parallel(
            name=name, policy=policies[(success, failure)], children=children
        )

    def _subtree(self, element: XmlElement) -> py_trees.behaviour.Behaviour:
        self._check_attributes(element, ("ID", "name", "_autoremap"))
        tree_id = element.attributes.get("ID", "")
        if tree_id not in self.trees:
            raise BtcppImportError(f"{self.where(element)} names no <BehaviorTree ID={tree_id!r}>")
        if tree_id in self._expanding:
            raise BtcppImportError(f"{self.where(element)} includes itself ({tree_id!r})")
        self._expanding.append(tree_id)
        try:
            return self.build(_only_child(self.trees[tree_id], self.source))
        finally:
            self._expanding.pop()

    def _leaf(self, element: XmlElement) -> py_trees.behaviour.Behaviour:
        tag = element.tag
        make = self.leaves.get(tag)
        if make is None and tag in UNMAPPED_BUILTINS:
            raise BtcppImportError(
                f"{self.source} line {element.line}: BehaviorTree.CPP's <{tag}> has no py_trees "
                "counterpart here (the mapped nodes: docs/btcpp-groot2.md)"
            )
        if make is None:
            known = ", ".join(sorted(self.leaves))
            raise BtcppImportError(
                f"{self.source} line {element.line}: unknown node <{tag}> (not a mapped "
                f"BehaviorTree.CPP node nor a registered leaf; registered: {known})"
            )
        if element.children:
            raise BtcppImportError(f"{self.where(element)} is a leaf: it takes no children")
        name = element.attributes.get("name", tag)
        try:
            leaf = make(name=name)
        except Exception as error:
            raise BtcppImportError(f"{self.where(element)} could not be built: {error}") from error
        if not isinstance(leaf, py_trees.behaviour.Behaviour):
            raise BtcppImportError(f"{self.where(element)}: the registry's {tag} made no behaviour")
        ports = {port.name: port for port in leaf_ports(leaf)}
        for attribute, value in element.attributes.items():
            if attribute in ("name", *IGNORED_ATTRIBUTES):
                continue
            port = ports.get(attribute)
            if port is None:
                raise BtcppImportError(
                    f"{self.where(element)} has no port {attribute}= (its ports: "
                    f"{', '.join(ports) or 'none'})"
                )
            target = self._remap_target(element, attribute, value, port.key)
            if target != port.key:
                _remap(leaf, port.key, target)
        return leaf

    def _remap_target(self, element: XmlElement, attribute: str, value: str, key: str) -> str:
        if value == "{=}":
            return key
        if len(value) < 3 or value[0] != "{" or value[-1] != "}":
            raise BtcppImportError(
                f"{self.where(element)} {attribute}={value!r}: a port takes a blackboard key "
                f"in braces ({{{key}}}), not a value"
            )
        target = value[1:-1]
        # BT.CPP's "@key" is the root blackboard: ours is one blackboard, keys absolute.
        target = "/" + target.lstrip("@/")
        return target


def _remap(leaf: py_trees.behaviour.Behaviour, key: str, target: str) -> None:
    """Re-registers ``key`` on the leaf's clients, stored at ``target``, same accesses."""
    for client in leaf.blackboards:
        accesses = [
            access
            for access, registered in (
                (Access.READ, client.read),
                (Access.WRITE, client.write),
                (Access.EXCLUSIVE_WRITE, client.exclusive),
            )
            if key in registered
        ]
        if not accesses:
            continue
        client.unregister_key(key, clear=False)
        for access in accesses:
            client.register_key(key=key, access=access, remap_to=target)


def _only_child(tree: XmlElement, source: str) -> XmlElement:
    if len(tree.children) != 1:
        raise BtcppImportError(
            f"{source} line {tree.line}: <BehaviorTree ID={tree.attributes.get('ID')!r}> "
            f"must hold exactly one node, not {len(tree.children)}"
        )
    return tree.children[0]


def tree_from_btcpp_xml(
    text: str, leaves: Mapping[str, Callable[..., object]], source: str = "<xml>"
) -> py_trees.behaviour.Behaviour:
    """Builds the main tree of a BehaviorTree.CPP v4 document.

    Args:
        text: the XML document.
        leaves: leaf classes (or callables taking ``name=``) by registration ID.
        source: what to call the document in errors (its path).

    Raises:
        BtcppImportError: not BT.CPP v4, an unknown node, a bad attribute (with the line).
    """
    root = parse_xml(text, source)
    trees = _behavior_trees(root, source)
    main = root.attributes.get("main_tree_to_execute") or (
        next(iter(trees)) if len(trees) == 1 else ""
    )
    if main not in trees:
        raise BtcppImportError(
            f"{source} line {root.line}: no <BehaviorTree ID={main!r}> to run (say which "
            f"with main_tree_to_execute; found: {', '.join(trees) or 'none'})"
        )
    return _Builder(trees, leaves, source, main).build(_only_child(trees[main], source))


def _behavior_trees(root: XmlElement, source: str) -> dict[str, XmlElement]:
    """The ``<BehaviorTree>`` elements of a BT.CPP v4 ``<root>``, by ID.

    Raises:
        BtcppImportError: not ``<root BTCPP_format="4">``, or an element we do not read.
    """
    if root.tag != "root":
        raise BtcppImportError(
            f"{source} line {root.line}: the document's element is <{root.tag}>, not <root>"
        )
    version = root.attributes.get("BTCPP_format")
    if version != BTCPP_FORMAT:
        raise BtcppImportError(
            f"{source} line {root.line}: <root BTCPP_format={version!r}>: only BehaviorTree.CPP "
            f'v4 files (BTCPP_format="{BTCPP_FORMAT}") are read'
        )
    trees: dict[str, XmlElement] = {}
    for element in root.children:
        if element.tag == "BehaviorTree":
            trees[element.attributes.get("ID", "")] = element
        elif element.tag == "include":
            raise BtcppImportError(
                f"{source} line {element.line}: <include> is not supported: inline the file"
            )
        elif element.tag != "TreeNodesModel":
            raise BtcppImportError(
                f"{source} line {element.line}: unexpected <{element.tag}> in <root>"
            )
    return trees
