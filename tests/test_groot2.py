"""The running tree in Groot2: a client speaking Groot2's protocol
(tests/helpers/groot2_client.py) reads the tree and its statuses from our loopback server
and from BT.CPP's own publisher on a mirror; one whole simulated mission is watched
through ``bearchair run --groot2``."""

from __future__ import annotations

import subprocess
import sys
import time
import types
import xml.etree.ElementTree as ET
from dataclasses import astuple
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status

pytest.importorskip("zmq", reason="the groot2 extra (pyzmq)")
pytest.importorskip("behaviortreepy", reason="the groot2 extra (behaviortreepy)")

import zmq

from bearchair.executive import groot2, groot2_server
from bearchair.executive.cli import main
from bearchair.executive.groot2 import Groot2Monitor, Groot2Unavailable
from bearchair.trees.mission import STAGES
from tests.helpers.groot2_client import Groot2Client, Groot2Error, free_port_pair

CODES = {Status.INVALID: 0, Status.RUNNING: 1, Status.SUCCESS: 2, Status.FAILURE: 3}


def small_tree() -> py_trees.behaviour.Behaviour:
    """A retry whose first attempt fails, between two leaves that run for a tick."""
    queue = py_trees.behaviours.StatusQueue
    attempt = py_trees.composites.Sequence(
        name="Try",
        memory=True,
        children=[
            queue(name="Ask", queue=[Status.RUNNING, Status.SUCCESS], eventually=Status.SUCCESS),
            queue(
                name="Check",
                queue=[Status.FAILURE, Status.RUNNING, Status.SUCCESS],
                eventually=Status.SUCCESS,
            ),
        ],
    )
    return py_trees.composites.Sequence(
        name="Root",
        memory=True,
        children=[
            queue(name="First", queue=[Status.RUNNING, Status.SUCCESS], eventually=Status.SUCCESS),
            py_trees.decorators.Retry(name="Twice", child=attempt, num_failures=3),
            queue(name="Last", queue=[Status.RUNNING, Status.SUCCESS], eventually=Status.SUCCESS),
        ],
    )


def preorder(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    nodes = [root]
    for child in root.children:
        nodes.extend(preorder(child))
    return nodes


@pytest.fixture
def port() -> int:
    return free_port_pair()


def watch(bind: str, port: int, ticks: int = 8):
    """Ticks the small tree under a monitor; yields (tick, py_trees nodes, client)."""
    root = small_tree()
    tree = py_trees.trees.BehaviourTree(root)
    monitor = Groot2Monitor(root, port, bind)
    client = Groot2Client(f"tcp://127.0.0.1:{port}")
    runner = types.SimpleNamespace(tree=tree)
    try:
        for tick in range(ticks):
            tree.tick()
            monitor(runner)
            if monitor._mirror is not None:
                assert monitor._mirror.flush()
            yield tick, preorder(root), client, monitor, runner
    finally:
        client.close()
        monitor.close()


def test_the_loopback_server_sends_the_tree_and_py_trees_statuses_each_tick(port):
    last: dict[int, int] = {}
    for tick, nodes, client, monitor, _ in watch("127.0.0.1", port):
        if tick == 0:
            tree = client.tree()
            assert [(uid, name) for uid, _, name in tree] == [
                (uid, node.name) for uid, node in enumerate(nodes, 1)
            ]
            assert [tag for _, tag, _ in tree][:4] == [
                "Sequence",
                "StatusQueue",
                "RetryUntilSuccessful",
                "Sequence",
            ]
            (xml,) = client.request("T")
            models = {m.get("ID"): m.tag for m in ET.fromstring(xml).find("TreeNodesModel")}
            assert models == {
                "Sequence": "Control",
                "RetryUntilSuccessful": "Decorator",
                "StatusQueue": "Action",
            }
            endpoint = monitor._server._server.getsockopt(zmq.LAST_ENDPOINT).decode()
            assert endpoint == f"tcp://127.0.0.1:{port}"
        expected = {}
        for uid, node in enumerate(nodes, 1):
            code = CODES[node.status]
            if code:
                last[uid] = code
            expected[uid] = code or (10 + last[uid] if uid in last else 0)
        assert client.statuses() == expected
    assert expected[1] == 2, "the root succeeded"


def test_a_node_stopped_after_it_ran_is_sent_as_idle_from_its_last_status():
    node = py_trees.behaviours.Success(name="Done")
    last = [0]
    assert groot2_server.status_codes([node], last) == [0]
    node.tick_once()
    assert groot2_server.status_codes([node], last) == [2]
    node.stop(Status.INVALID)
    assert groot2_server.status_codes([node], last) == [12]


def test_a_py_trees_behaviour_tree_takes_the_monitor_as_its_post_tick_handler(port):
    root = small_tree()
    tree = py_trees.trees.BehaviourTree(root)
    monitor = Groot2Monitor(root, port)
    tree.add_post_tick_handler(monitor)
    client = Groot2Client(f"tcp://127.0.0.1:{port}")
    try:
        seen = []
        for _ in range(8):
            tree.tick()
            seen.append(client.statuses()[1])
        assert seen[0] == 1 and seen[-1] == 2, seen
    finally:
        client.close()
        monitor.close()


def test_a_mission_stopped_mid_tick_is_shown_stopped(port):
    """The runner's last call (no new tick) after it stopped the tree: idle-after-RUNNING."""
    for _, _, client, monitor, runner in watch("127.0.0.1", port, ticks=1):
        assert client.statuses()[1] == 1
        runner.tree.root.stop(Status.INVALID)
        monitor(runner)
        assert client.statuses()[1] == 11 and client.statuses()[2] == 11


def test_the_loopback_server_refuses_breakpoints_and_answers_hook_dumps(port):
    for _, _, client, _, _ in watch("127.0.0.1", port, ticks=1):
        assert client.request("D") == [b"[]"]
        with pytest.raises(Groot2Error, match="only monitors"):
            client.request("I")
        assert client.statuses()  # still serving after an error


def test_the_server_listens_on_an_ipv6_loopback_when_told(port):
    monitor = Groot2Monitor(small_tree(), port, "::1")
    client = Groot2Client(f"tcp://[::1]:{port}")
    try:
        assert monitor.address == f"tcp://[::1]:{port}"
        assert client.tree()[0][2] == "Root"
    finally:
        client.close()
        monitor.close()


def test_a_port_in_use_is_one_line(port):
    with zmq.Context() as context, context.socket(zmq.REP) as taken:
        taken.bind(f"tcp://127.0.0.1:{port}")
        with pytest.raises(Groot2Unavailable, match=f"cannot listen on 127.0.0.1:{port}"):
            Groot2Monitor(small_tree(), port)


def test_btcpps_publisher_mirrors_the_statuses_on_a_btcpp_tree(port):
    """BT.CPP's composites work out their statuses from the leaves' py_trees statuses."""
    observed: dict[str, set[int]] = {}
    for tick, nodes, client, monitor, runner in watch("*", port):
        names = {uid: name for uid, _, name in client.tree()}
        assert sorted(names.values()) == sorted(node.name for node in nodes)
        for uid, code in client.statuses().items():
            observed.setdefault(names[uid], set()).add(code % 10)
        if tick == 7:
            monitor(runner)  # the runner's call after the end: no new tick, no restart
            assert monitor._mirror.flush()
            root_uid = next(uid for uid, name in names.items() if name == "Root")
            assert client.statuses()[root_uid] == 12, "idle after SUCCESS"
    for leaf in ("First", "Ask", "Check", "Last"):
        assert {1, 2} <= observed[leaf], leaf
    assert 3 in observed["Check"], "the failed first attempt is shown"
    assert {1, 2} <= observed["Twice"]


def test_run_groot2_without_the_extra_says_which_extra_to_install(monkeypatch, capsys):
    monkeypatch.setattr(groot2, "missing_modules", lambda: ["behaviortreepy"])
    assert main(["run", "--groot2", "--mute"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert "pip install 'bearchair[groot2]'" in err


def test_run_groot2_on_a_taken_port_stops_before_anything_runs(port, tmp_path, capsys):
    with zmq.Context() as context, context.socket(zmq.REP) as taken:
        taken.bind(f"tcp://127.0.0.1:{port + 1}")
        started = time.monotonic()
        out = tmp_path / "run"
        assert main(["run", "--groot2", str(port), "--mute", "--out", str(out)]) == 2
    assert time.monotonic() - started < 5.0, "before the world is built"
    assert not out.exists()
    err = capsys.readouterr().err.strip()
    assert f"cannot listen on 127.0.0.1:{port} and {port + 1}" in err and "\n" not in err


def test_run_groot2_bind_to_an_address_not_of_this_machine_is_one_line(port, capsys):
    assert main(["run", "--groot2", str(port), "--groot2-bind", "192.0.2.1", "--mute"]) == 2
    assert "cannot listen on 192.0.2.1" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["run", "--groot2", "65535"], "a TCP port from 1 to 65534"),
        (["run", "--groot2", "0"], "a TCP port from 1 to 65534"),
        (["run", "--groot2-bind", "*"], "--groot2-bind is for --groot2"),
        (["run", "--groot2", "x"], "invalid int value"),
    ],
)
def test_bad_groot2_arguments_are_one_line(argv, expected, capsys):
    assert main([*argv, "--mute"]) == 2
    assert expected in capsys.readouterr().err


@pytest.mark.slow
def test_groot2_sees_every_stage_of_a_simulated_mission_change(tmp_path: Path, port):
    """``bearchair run --groot2``: the client reads the mission's tree and, for every
    stage, statuses changing while the mission runs (45 to 70 s on two cores)."""
    command = [sys.executable, "-m", "bearchair.executive.cli", "run", "--mute", "--seed", "0"]
    command += ["--out", str(tmp_path / "run"), "--groot2", str(port)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    client = Groot2Client(f"tcp://127.0.0.1:{port}", timeout_ms=200)
    tree: list[tuple[int, str, str]] = []
    history: dict[int, list[int]] = {}
    try:
        deadline = time.monotonic() + 600
        while process.poll() is None and time.monotonic() < deadline:
            try:
                if not tree:
                    tree = client.tree()
                for uid, code in client.statuses().items():
                    if not history.get(uid) or history[uid][-1] != code:
                        history.setdefault(uid, []).append(code)
            except Groot2Error:
                pass  # not serving yet (the world is being built) or already closed
            time.sleep(0.02)
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
        client.close()
    assert process.returncode == 0, err[-2000:]
    assert f"Groot2: connect to tcp://127.0.0.1:{port}" in err
    by_name = {name: uid for uid, _, name in reversed(tree)}
    assert tree[0][2] == "Put the bear on the chair"
    for stage in STAGES:
        changes = history[by_name[stage]]
        assert len(changes) >= 2, f"{stage}: {changes}"
        assert changes[-1] == 2, f"{stage} ended in SUCCESS: {changes}"


def test_a_remapped_port_is_shown_to_groot2_and_left_out_of_the_btcpp_mirror():
    from bearchair.executive.btcpp import leaf_registry, tree_from_btcpp_xml

    xml = (
        '<root BTCPP_format="4"><BehaviorTree ID="T"><Sequence name="S">'
        '<WalkToChair name="Walk" walk_result="{/walk/first}"/></Sequence></BehaviorTree></root>'
    )
    root = tree_from_btcpp_xml(xml, leaf_registry())
    for bind in ("127.0.0.1", "*"):
        port = free_port_pair()
        monitor = Groot2Monitor(root, port, bind)
        client = Groot2Client(f"tcp://127.0.0.1:{port}")
        try:
            (tree,) = client.request("T")
            assert (b'walk_result="{/walk/first}"' in tree) == (bind == "127.0.0.1")
            assert [name for _, _, name in client.tree()] == ["S", "Walk"]
        finally:
            client.close()
            monitor.close()


def test_every_btcpp_builtin_is_mapped_or_said_to_be_unmapped(port):
    """BT.CPP's publisher sends the models of all its built-in nodes (FULLTREE)."""
    import behaviortreepy as bt

    from bearchair.executive.btcpp_import import (
        COMPOSITES,
        CONTROL_ATTRIBUTES,
        DECORATOR_ATTRIBUTES,
        UNMAPPED_BUILTINS,
    )
    from bearchair.executive.groot2_server import BUILTIN_MODELS

    tree = bt.BehaviorTreeFactory().create_tree_from_text(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><AlwaysSuccess/></BehaviorTree></root>'
    )
    publisher = bt.Groot2Publisher(tree, port)
    client = Groot2Client(f"tcp://127.0.0.1:{port}")
    try:
        (xml,) = client.request("T")
    finally:
        client.close()
        del publisher
    models = {m.get("ID"): m for m in ET.fromstring(xml).find("TreeNodesModel")}
    mapped = {
        *COMPOSITES,
        *CONTROL_ATTRIBUTES,
        *DECORATOR_ATTRIBUTES,
        "AlwaysSuccess",
        "AlwaysFailure",
    }
    assert set(models) == mapped | UNMAPPED_BUILTINS | {"SubTree"}
    assert set(BUILTIN_MODELS) == mapped
    for tag, (kind, ports) in BUILTIN_MODELS.items():
        assert models[tag].tag == kind, tag
        sent = {
            (p.tag, p.get("name"), p.get("type"), (p.text or "").strip(), p.get("default", ""))
            for p in models[tag]
        }
        assert sent == {("input_port", *astuple(port)) for port in ports}, tag
