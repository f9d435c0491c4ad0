"""BehaviorTree.CPP v4 XML both ways: the mission exported, loaded back and exported again,
checked by BT.CPP's own parser (behaviortreepy), and the errors of bad files."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path
from typing import Any

import py_trees
import pytest

from bearchair.behaviours import keys
from bearchair.behaviours.scan import ScanChair
from bearchair.behaviours.walk import WalkToChair
from bearchair.core.errors import InputError
from bearchair.executive import btcpp
from bearchair.executive.btcpp import (
    BtcppExportError,
    BtcppImportError,
    factory_from_xml_file,
    leaf_ports,
    leaf_registry,
    tree_from_btcpp_xml,
    tree_to_btcpp_xml,
)
from bearchair.executive.cli import main
from bearchair.trees.mission import create_tree


def shape(root: py_trees.behaviour.Behaviour) -> list[tuple[Any, ...]]:
    """What the round trip must keep, node by node in tree order: depth, name, class,
    memory, the retry's count, the timeout, the parallel's policy, the ports and where
    each one is stored."""
    rows = []

    def visit(node: py_trees.behaviour.Behaviour, depth: int) -> None:
        policy = getattr(node, "policy", None)
        rows.append(
            (
                depth,
                node.name,
                type(node).__name__,
                getattr(node, "memory", None),
                getattr(node, "num_failures", None),
                getattr(node, "duration", None),
                None if policy is None else (type(policy).__name__, policy.synchronise),
                tuple(leaf_ports(node)) if not node.children else (),
            )
        )
        for child in node.children:
            visit(child, depth + 1)

    visit(root, 0)
    return rows


def parsed_by_behaviortree_cpp(xml: str, leaf_names: list[str]) -> Any:
    """BehaviorTree.CPP's own parser builds the document (our leaves as simple actions)."""
    bt = pytest.importorskip("behaviortreepy", reason="the groot2 extra (behaviortreepy)")
    factory = bt.BehaviorTreeFactory()
    for name in leaf_names:
        factory.register_simple_action(name, lambda node: bt.NodeStatus.SUCCESS)
    return factory.create_tree_from_text(xml)


def test_the_mission_round_trips_to_the_same_xml_and_the_same_structure():
    mission = create_tree()
    xml = tree_to_btcpp_xml(mission)
    loaded = tree_from_btcpp_xml(xml, leaf_registry())
    assert tree_to_btcpp_xml(loaded) == xml
    assert shape(loaded) == shape(mission)
    rows = {row[1]: row for row in shape(loaded)}
    assert rows["Up to 3 rotations"][2:5] == ("Retry", None, keys.MAX_ROTATIONS)
    assert rows["Put the bear on the chair"][3] is True
    ports = {port.name: port.direction for port in rows["InstructHelper"][7]}
    assert ports["assistance_rotations"] == "inout_port"
    assert ports["mission_seed"] == "input_port"


def test_the_mission_xml_is_accepted_by_behaviortree_cpps_parser():
    xml = tree_to_btcpp_xml(create_tree())
    tree = parsed_by_behaviortree_cpp(xml, sorted(leaf_registry()))
    bt = pytest.importorskip("behaviortreepy")
    # Every simple action succeeds, so BT.CPP runs the whole mission tree to SUCCESS.
    assert tree.tick_once() == bt.NodeStatus.SUCCESS
    with pytest.raises(RuntimeError, match="ScanChair"):
        parsed_by_behaviortree_cpp(xml, [n for n in leaf_registry() if n != "ScanChair"])


def every_mapped_node() -> py_trees.behaviour.Behaviour:
    d, c = py_trees.decorators, py_trees.composites
    parallel = c.Parallel(
        name="Both",
        policy=py_trees.common.ParallelPolicy.SuccessOnAll(synchronise=True),
        children=[py_trees.behaviours.Success(name="Yes"), WalkToChair()],
    )
    one = c.Parallel(
        name="Either",
        policy=py_trees.common.ParallelPolicy.SuccessOnOne(),
        children=[py_trees.behaviours.Failure(name="No"), ScanChair()],
    )
    return c.Selector(
        name="Reactive root",
        memory=False,
        children=[
            c.Sequence(name="Reactive", memory=False, children=[parallel]),
            d.Timeout(name="At most 2.5 s", child=one, duration=2.5),
            d.Inverter(
                name="Not", child=d.Repeat(name="Twice", child=ScanChair(name="S2"), num_success=2)
            ),
            d.FailureIsSuccess(
                name="Fine", child=d.SuccessIsFailure(name="Bad", child=ScanChair(name="S3"))
            ),
        ],
    )


def test_every_mapped_node_round_trips_and_parses_in_behaviortree_cpp():
    tree = every_mapped_node()
    xml = tree_to_btcpp_xml(tree, tree_id="All")
    for tag in (
        "ReactiveFallback",
        "ReactiveSequence",
        'Parallel name="Both" success_count="-1"',
        'Timeout name="At most 2.5 s" msec="2500"',
        'Repeat name="Twice" num_cycles="2"',
        "Inverter",
        "ForceSuccess",
        "ForceFailure",
        "AlwaysSuccess",
        "AlwaysFailure",
    ):
        assert f"<{tag}" in xml
    loaded = tree_from_btcpp_xml(xml, leaf_registry())
    assert shape(loaded) == shape(tree)
    assert tree_to_btcpp_xml(loaded, tree_id="All") == xml
    parsed_by_behaviortree_cpp(xml, ["ScanChair", "WalkToChair"])


def test_a_remapped_key_is_a_port_attribute_and_comes_back_remapped():
    xml = tree_to_btcpp_xml(create_tree()).replace(
        '<WalkToChair name="WalkToChair" />',
        '<WalkToChair name="WalkToChair" walk_result="{/walk/first}" />',
    )
    loaded = tree_from_btcpp_xml(xml, leaf_registry())
    walk = next(node for node in loaded.iterate() if node.name == "WalkToChair")
    assert walk.blackboard.remappings[keys.WALK] == "/walk/first"
    assert keys.WALK in walk.blackboard.write and keys.ACCESSIBILITY in walk.blackboard.read
    assert tree_to_btcpp_xml(loaded) == xml
    # The model keeps the class's own key as the default.
    assert '<output_port name="walk_result" default="{/walk/result}" />' in xml


def test_a_port_written_at_its_own_key_is_no_remapping():
    xml = tree_to_btcpp_xml(create_tree())
    edited = xml.replace(
        '<WalkToChair name="WalkToChair" />',
        '<WalkToChair name="WalkToChair" walk_result="{/walk/result}" />',
    )
    assert tree_to_btcpp_xml(tree_from_btcpp_xml(edited, leaf_registry())) == xml


def test_nodes_bt_cpp_cannot_express_are_all_named():
    tree = py_trees.composites.Sequence(
        name="Top",
        memory=True,
        children=[
            py_trees.decorators.OneShot(
                name="Once", child=ScanChair(), policy=py_trees.common.OneShotPolicy.ON_COMPLETION
            ),
            py_trees.behaviours.Running(name="Spin"),
        ],
    )
    with pytest.raises(BtcppExportError) as error:
        tree_to_btcpp_xml(tree)
    message = str(error.value)
    assert "'Once' (py_trees.decorators.OneShot)" in message
    assert "Running" not in message  # a leaf: written under its class name, not refused


MISSION_XML = tree_to_btcpp_xml(create_tree())


def line_of(text: str, marker: str) -> int:
    return next(n for n, line in enumerate(text.splitlines(), 1) if marker in line)


@pytest.mark.parametrize(
    ("old", "new", "marker", "expected"),
    [
        ("<SeatBear name", "<SeatBare name", "SeatBare", "line {}: unknown node <SeatBare>"),
        (
            'num_attempts="3"',
            'num_attempts="three"',
            "Retry",
            "line {}: <RetryUntilSuccessful> num_attempts='three' is not an integer >= 1",
        ),
        (
            'num_attempts="3"',
            'num_attempts="0"',
            "Retry",
            "num_attempts='0' is not an integer >= 1",
        ),
        (' num_attempts="3"', "", "Retry", "line {}: <RetryUntilSuccessful> needs num_attempts="),
        (
            '<GiveUp name="GiveUp" />',
            '<GiveUp name="GiveUp" rotations="{/x}" />',
            "GiveUp",
            r"line {}: <GiveUp> has no port rotations= \(its ports: assistance_rotations\)",
        ),
        (
            '<GiveUp name="GiveUp" />',
            '<GiveUp name="GiveUp" assistance_rotations="3" />',
            "GiveUp",
            "line {}: <GiveUp> assistance_rotations='3': a port takes a blackboard key",
        ),
        (
            '<Sequence name="Scan the',
            '<Sequence memory="false" name="Scan the',
            "memory",
            "line {}: <Sequence> has an attribute memory=",
        ),
        ('BTCPP_format="4"', 'BTCPP_format="3"', "BTCPP", "line {}: <root BTCPP_format='3'>"),
        ("</root>", "", "", "not well-formed XML at line"),
        (
            'main_tree_to_execute="PutTheBearOnTheChair"',
            'main_tree_to_execute="Nope"',
            "",
            "no <BehaviorTree ID='Nope'> to run",
        ),
    ],
)
def test_a_bad_file_is_one_line_naming_its_line_and_node(tmp_path, old, new, marker, expected):
    text = MISSION_XML.replace(old, new, 1)
    assert text != MISSION_XML
    if marker:
        expected = expected.format(line_of(text, marker))
    path = tmp_path / "mission.xml"
    path.write_text(text)
    with pytest.raises(BtcppImportError, match=expected) as error:
        factory_from_xml_file(path)
    assert "\n" not in str(error.value)
    assert str(error.value).startswith(str(path))


def test_an_unmapped_bt_cpp_builtin_is_named_as_such():
    text = MISSION_XML.replace('<GiveUp name="GiveUp" />', '<Sleep msec="10" />')
    with pytest.raises(
        BtcppImportError,
        match=f"line {line_of(text, 'Sleep')}: BehaviorTree.CPP's <Sleep> has no py_trees counterpart",
    ):
        tree_from_btcpp_xml(text, leaf_registry())


def test_a_missing_file_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match=r"no-such\.xml"):
        factory_from_xml_file(tmp_path / "no-such.xml")


def test_the_factory_of_a_file_makes_a_fresh_tree_each_call(tmp_path):
    path = tmp_path / "mission.xml"
    path.write_text(MISSION_XML)
    create = factory_from_xml_file(path)
    first, second = create(None), create({"ignored": True})
    assert first is not second
    assert {n.id for n in first.iterate()}.isdisjoint({n.id for n in second.iterate()})
    assert shape(first) == shape(create_tree())


def test_a_file_as_groot2_saves_it_loads():
    """Groot2 writes an XML declaration, comments, and every port on every leaf."""
    text = '<?xml version="1.0" encoding="UTF-8"?>\n' + MISSION_XML.replace(
        "  <TreeNodesModel>",
        "  <!-- Description of Node Models (used by Groot) -->\n  <TreeNodesModel>",
    ).replace(
        '<WalkToChair name="WalkToChair" />',
        '<WalkToChair name="WalkToChair" accessibility_result="{/accessibility/result}" '
        'walk_result="{=}" />',
    )
    assert tree_to_btcpp_xml(tree_from_btcpp_xml(text, leaf_registry())) == MISSION_XML


def test_subtrees_are_inlined():
    xml = MISSION_XML.replace(
        '<WalkToChair name="WalkToChair" />', '<SubTree ID="Walk" />'
    ).replace(
        "  <TreeNodesModel>",
        '  <BehaviorTree ID="Walk">\n    <WalkToChair name="WalkToChair" />\n  </BehaviorTree>\n  <TreeNodesModel>',
    )
    assert tree_to_btcpp_xml(tree_from_btcpp_xml(xml, leaf_registry())) == MISSION_XML


def test_the_registry_holds_every_leaf_of_the_mission_and_no_base_class():
    registry = leaf_registry()
    assert {type(n).__name__ for n in create_tree().iterate() if not n.children} <= set(registry)
    assert "SkillBehaviour" not in registry


class PatChair(py_trees.behaviour.Behaviour):
    """A plug-in's leaf, registered through an entry point in the test below."""

    def update(self) -> py_trees.common.Status:
        return py_trees.common.Status.SUCCESS


def _entry_points(*points: importlib.metadata.EntryPoint):
    def entry_points(group: str):
        return [p for p in points if p.group == group]

    return entry_points


def test_plugin_leaves_come_from_their_entry_points(monkeypatch):
    point = importlib.metadata.EntryPoint("PatChair", f"{__name__}:PatChair", btcpp.LEAVES_GROUP)
    monkeypatch.setattr(btcpp.importlib.metadata, "entry_points", _entry_points(point))
    xml = MISSION_XML.replace('<GiveUp name="GiveUp" />', '<PatChair name="Pat it" />')
    loaded = tree_from_btcpp_xml(xml, leaf_registry())
    assert any(isinstance(n, PatChair) and n.name == "Pat it" for n in loaded.iterate())


@pytest.mark.parametrize(
    ("value", "why"),
    [("tests.no_such_module:Leaf", "cannot be loaded"), (f"{__name__}:MISSION_XML", "not a class")],
)
def test_a_broken_plugin_leaf_is_one_line(monkeypatch, value, why):
    point = importlib.metadata.EntryPoint("Broken", value, btcpp.LEAVES_GROUP)
    monkeypatch.setattr(btcpp.importlib.metadata, "entry_points", _entry_points(point))
    with pytest.raises(InputError, match=f"'Broken'.*{why}"):
        leaf_registry()


def test_a_plugin_leaf_may_not_take_one_of_our_names(monkeypatch):
    point = importlib.metadata.EntryPoint("ScanChair", f"{__name__}:PatChair", btcpp.LEAVES_GROUP)
    monkeypatch.setattr(btcpp.importlib.metadata, "entry_points", _entry_points(point))
    with pytest.raises(InputError, match=r"ScanChair.*take the names"):
        leaf_registry()


def test_tree_format_btcpp_prints_or_writes_the_xml(tmp_path: Path, capsys):
    assert main(["tree", "--format", "btcpp"]) == 0
    assert capsys.readouterr().out == MISSION_XML
    out = tmp_path / "mission.xml"
    assert main(["tree", "--format", "btcpp", "--out", str(out)]) == 0
    assert out.read_text() == MISSION_XML
    assert main(["tree", "--format", "btcpp", "--out", str(tmp_path / "m.txt")]) == 2
    assert "expected a .xml file name" in capsys.readouterr().err
