"""The running mission in Groot2 (``bearchair run --groot2 [PORT]``).

Groot2 monitors a tree over ZMQ (BehaviorTree.CPP's ``groot2_protocol.h``): a REP socket
on PORT answers requests (``FULLTREE``: the tree as XML whose nodes carry ``_uid``;
``STATUS``: every node's uid and status), and PORT + 1 publishes breakpoint events.
:class:`Groot2Monitor` is the py_trees side, a post-tick hook of the mission runner that
hands each tick's statuses to one of two publishers:

* :class:`LoopbackServer` (the default, ``--groot2-bind 127.0.0.1``): the protocol's
  monitoring part served with pyzmq on the address asked for, the statuses straight from
  py_trees, the XML our export's (:func:`bearchair.executive.btcpp.tree_to_btcpp_xml`),
  checked first by BehaviorTree.CPP's own parser. It refuses breakpoints and status
  replacement: Groot2 only watches.
* :class:`BtcppMirror` (``--groot2-bind '*'``): a BehaviorTree.CPP tree built from the
  same XML by behaviortreepy, each leaf answering its py_trees twin's status, ticked once
  per mission tick in its own thread, published by BT.CPP's ``Groot2Publisher``. That
  publisher binds ``tcp://*:PORT`` and ``tcp://*:PORT+1`` (hard-coded in BT.CPP's
  ``src/loggers/groot2_publisher.cpp``; behaviortreepy's constructor takes only the port),
  so it can only be had on every interface: hence the loopback server as the default.

Both need the ``groot2`` extra (:data:`INSTALL_HINT`).
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import queue
import struct
import threading
import time
import uuid
import xml.etree.ElementTree as ET
from typing import Any

import py_trees
from py_trees.common import Status

from bearchair.core.errors import BackendUnavailable, InputError, one_line
from bearchair.executive.btcpp import tree_to_btcpp_xml
from bearchair.executive.record import tree_nodes

logger = logging.getLogger(__name__)

DEFAULT_PORT = 1667
"""Groot2's default port (BT.CPP's ``Groot2Publisher``); PORT + 1 is used too."""
ALL_INTERFACES = ("*", "0.0.0.0")
"""``--groot2-bind`` values that select BT.CPP's own publisher (it binds only these)."""
INSTALL_HINT = "pip install 'bearchair[groot2]' (behaviortreepy and pyzmq)"
PROTOCOL_ID = 2
"""``BT::Monitor::kProtocolID``."""
REQUEST_HEADER = struct.Struct("<BBI")
"""protocol (uint8), request type (uint8, a letter), unique id (uint32)."""
FULLTREE, STATUS = ord("T"), ord("S")
HOOKS_DUMP, REMOVE_ALL_HOOKS, DISABLE_ALL_HOOKS = ord("D"), ord("A"), ord("X")
BTCPP_STATUS = {Status.INVALID: 0, Status.RUNNING: 1, Status.SUCCESS: 2, Status.FAILURE: 3}
"""py_trees' statuses as ``BT::NodeStatus`` (IDLE, RUNNING, SUCCESS, FAILURE)."""
IDLE_FROM = 10
"""An idle node that was X is sent as 10 + X (BT.CPP's ``IDLE_FROM_SUCCESS``, ...)."""


class Groot2Unavailable(BackendUnavailable):
    """The groot2 extra is missing, or the port cannot be had."""


def missing_modules() -> list[str]:
    """The modules of the groot2 extra that are not installed."""
    return [name for name in ("behaviortreepy", "zmq") if importlib.util.find_spec(name) is None]


def check_groot2_port(port: int) -> int:
    """Groot2 uses PORT and PORT + 1: both must be valid TCP ports.

    Raises:
        InputError: out of range.
    """
    if not 1 <= port <= 65534:
        raise InputError(f"--groot2 {port}: a TCP port from 1 to 65534 (PORT + 1 is used too)")
    return port


def zmq_endpoint(bind: str, port: int) -> str:
    """``tcp://HOST:PORT``, an IPv6 address in brackets."""
    return f"tcp://{f'[{bind}]' if ':' in bind else bind}:{port}"


def check_groot2_address(port: int, bind: str) -> None:
    """Binds PORT and PORT + 1 on ``bind`` and lets them go: a taken port or an address
    not of this machine is one line before the mission starts, not after the world is
    built.

    Raises:
        Groot2Unavailable: the address cannot be bound.
    """
    import zmq

    with zmq.Context() as context:
        sockets = []
        try:
            for offset in (0, 1):
                socket = context.socket(zmq.REP)
                sockets.append(socket)
                socket.setsockopt(zmq.LINGER, 0)
                socket.setsockopt(zmq.IPV6, ":" in bind)
                socket.bind(zmq_endpoint(bind, port + offset))
        except zmq.ZMQError as error:
            raise Groot2Unavailable(
                f"--groot2: cannot listen on {bind}:{port} and {port + 1}: {error}"
            ) from error
        finally:
            for socket in sockets:
                socket.close(linger=0)


def status_codes(nodes: list[py_trees.behaviour.Behaviour], last: list[int]) -> list[int]:
    """Each node's BT.CPP status code now; ``last`` (updated) holds the last non-idle one."""
    codes = []
    for index, node in enumerate(nodes):
        code = BTCPP_STATUS[node.status]
        if code:
            last[index] = code
        codes.append(code if code or not last[index] else IDLE_FROM + last[index])
    return codes


_COUNT = ("input_port", "int")
BUILTIN_MODELS: dict[str, tuple[str, tuple[tuple[str, str, str, str], ...]]] = {
    "Sequence": ("Control", ()),
    "ReactiveSequence": ("Control", ()),
    "Fallback": ("Control", ()),
    "ReactiveFallback": ("Control", ()),
    "Parallel": (
        "Control",
        (
            ("failure_count", *_COUNT, "number of children that need to fail to trigger a FAILURE"),
            (
                "success_count",
                *_COUNT,
                "number of children that need to succeed to trigger a SUCCESS",
            ),
        ),
    ),
    "RetryUntilSuccessful": (
        "Decorator",
        (
            (
                "num_attempts",
                *_COUNT,
                "Execute again a failing child up to N times. Use -1 to create an infinite loop.",
            ),
        ),
    ),
    "Repeat": (
        "Decorator",
        (
            (
                "num_cycles",
                *_COUNT,
                "Repeat a successful child up to N times. Use -1 to create an infinite loop.",
            ),
        ),
    ),
    "Timeout": (
        "Decorator",
        (
            (
                "msec",
                "input_port",
                "unsigned int",
                "After a certain amount of time, halt() the child if it is still running.",
            ),
        ),
    ),
    "Inverter": ("Decorator", ()),
    "ForceSuccess": ("Decorator", ()),
    "ForceFailure": ("Decorator", ()),
    "AlwaysSuccess": ("Action", ()),
    "AlwaysFailure": ("Action", ()),
}
"""The models BehaviorTree.CPP 4.8 sends Groot2 for the built-in nodes we map (its
``WriteTreeToXML(tree, true, true)``): kind, and each port's name, direction, type, text."""


def xml_with_uids(xml: str) -> str:
    """Our export as Groot2 expects a ``FULLTREE`` reply, as BT.CPP's publisher sends it:
    each tree node's ``_uid`` (1, 2, ... in depth-first order, the order
    :func:`bearchair.executive.record.tree_nodes` lists them), the tree's ``_fullpath``,
    and the models of the built-in nodes it uses, all models sorted by ID."""
    document = ET.fromstring(xml)
    tree = document.find("BehaviorTree")
    models = document.find("TreeNodesModel")
    assert tree is not None and models is not None  # tree_to_btcpp_xml writes both
    tree.set("_fullpath", "")
    elements = list(tree.iter())[1:]
    for uid, element in enumerate(elements, 1):
        element.set("_uid", str(uid))
    entries = {model.get("ID"): model for model in models}
    for tag in sorted({element.tag for element in elements} & set(BUILTIN_MODELS)):
        kind, ports = BUILTIN_MODELS[tag]
        entries[tag] = model = ET.Element(kind, {"ID": tag})
        for name, direction, type_name, text in ports:
            port = ET.SubElement(model, direction, {"name": name, "type": type_name})
            port.text = text
    models[:] = [entries[key] for key in sorted(entries, key=str)]
    return ET.tostring(document, encoding="unicode")


def without_leaf_ports(xml: str) -> str:
    """The XML with the leaves' port attributes (remappings) dropped, for behaviortreepy:
    its simple actions cannot declare ports, and BT.CPP refuses a port it was not told of.
    The mirror only shows statuses, so it loses nothing."""
    document = ET.fromstring(xml)
    leaves = {model.get("ID") for model in document.iterfind("TreeNodesModel/*")}
    for element in document.iterfind("BehaviorTree//*"):
        if element.tag in leaves:
            for attribute in [a for a in element.attrib if a != "name"]:
                del element.attrib[attribute]
    return ET.tostring(document, encoding="unicode")


def check_with_btcpp(xml: str, leaf_names: set[str]) -> None:
    """BehaviorTree.CPP's parser (behaviortreepy) must build the tree Groot2 is sent.

    Raises:
        InputError: it refuses the XML.
    """
    import behaviortreepy as bt

    factory = bt.BehaviorTreeFactory()
    for name in leaf_names:
        factory.register_simple_action(name, lambda node: bt.NodeStatus.SUCCESS)
    try:
        factory.create_tree_from_text(xml)
    except RuntimeError as error:
        raise InputError(
            f"--groot2: BehaviorTree.CPP refuses the tree: {one_line(error)}"
        ) from error


class LoopbackServer:
    """Groot2's monitoring protocol on ``tcp://BIND:PORT`` (and a silent PUB on PORT + 1).

    Args:
        xml: the ``FULLTREE`` reply (with ``_uid``).
        count: the number of nodes (uids 1..count).
        port, bind: where to listen.

    Raises:
        Groot2Unavailable: the address cannot be bound (in use, not ours).
    """

    def __init__(self, xml: str, count: int, port: int, bind: str) -> None:
        import zmq

        self._zmq = zmq
        self._xml = xml.encode()
        self._tree_id = uuid.uuid4().bytes
        self._lock = threading.Lock()
        self._status = b"".join(struct.pack("<HB", uid, 0) for uid in range(1, count + 1))
        self._context = zmq.Context()
        self._server = self._context.socket(zmq.REP)
        self._publisher = self._context.socket(zmq.PUB)
        for socket in (self._server, self._publisher):
            socket.setsockopt(zmq.LINGER, 0)
            socket.setsockopt(zmq.IPV6, ":" in bind)  # an IPv6 address, e.g. ::1
        try:
            self._server.bind(zmq_endpoint(bind, port))
            self._publisher.bind(zmq_endpoint(bind, port + 1))
        except zmq.ZMQError as error:
            self._context.destroy(linger=0)
            raise Groot2Unavailable(
                f"--groot2: cannot listen on {bind}:{port} and {port + 1}: {error}"
            ) from error
        self._running = True
        self._thread = threading.Thread(target=self._serve, name="groot2-server", daemon=True)
        self._thread.start()

    def publish(self, codes: list[int]) -> None:
        status = b"".join(struct.pack("<HB", uid, code) for uid, code in enumerate(codes, 1))
        with self._lock:
            self._status = status

    def _serve(self) -> None:
        zmq = self._zmq
        poller = zmq.Poller()
        poller.register(self._server, zmq.POLLIN)
        while self._running:
            try:
                if not poller.poll(100):
                    continue
                request = self._server.recv_multipart()
                self._server.send_multipart(self._reply(request))
            except zmq.ZMQError:
                if self._running:
                    logger.exception("the Groot2 server stopped")
                return

    def _reply(self, request: list[bytes]) -> list[bytes]:
        if not request or len(request[0]) != REQUEST_HEADER.size:
            return [b"error", b"wrong request header"]
        _, kind, unique_id = REQUEST_HEADER.unpack(request[0])
        header = REQUEST_HEADER.pack(PROTOCOL_ID, kind, unique_id) + self._tree_id
        if kind == FULLTREE:
            return [header, self._xml]
        if kind == STATUS:
            with self._lock:
                return [header, self._status]
        if kind == HOOKS_DUMP:
            return [header, b"[]"]
        if kind in (REMOVE_ALL_HOOKS, DISABLE_ALL_HOOKS):
            return [header]
        return [
            b"error",
            b"bearchair's Groot2 server only monitors (no breakpoints, blackboard or recording)",
        ]

    def close(self) -> None:
        self._running = False
        self._thread.join(timeout=2.0)
        self._context.destroy(linger=0)


class BtcppMirror:
    """A BehaviorTree.CPP twin of the tree, published by BT.CPP's ``Groot2Publisher``.

    Each leaf of the twin is a stateful action answering its py_trees twin's status of
    the tick being mirrored; the twin's composites work out their own statuses, as
    BT.CPP's ``Sequence``/``Fallback``/``RetryUntilSuccessful`` do. A leaf that py_trees
    did not tick in that tick, or that BT.CPP ticks a second time in one tick (its retry
    loops within a tick, py_trees' retries over ticks), answers RUNNING: it waits for
    py_trees' next tick. The twin is ticked in its own thread, so nothing Groot2 does to
    it (a breakpoint) can hold up the mission.

    Raises:
        Groot2Unavailable: the publisher cannot bind its ports.
    """

    def __init__(self, xml: str, nodes: list[py_trees.behaviour.Behaviour], port: int) -> None:
        import behaviortreepy as bt

        self._bt = bt
        self._nodes = nodes
        self._answered: set[int] = set()
        self._snapshot: tuple[dict[int, Status], set[int]] = ({}, set())
        factory = bt.BehaviorTreeFactory()
        answer = self._answer
        for name in {type(node).__name__ for node in nodes if not node.children}:
            factory.register_simple_stateful_action(name, answer, answer, lambda node: None)
        self._tree = factory.create_tree_from_text(xml)
        self._root_uid = self._tree.root_node().uid()
        try:
            self._publisher = bt.Groot2Publisher(self._tree, port)
        except Exception as error:
            raise Groot2Unavailable(
                f"--groot2: BT.CPP's publisher cannot use port {port}: {one_line(error)}"
            ) from error
        self._queue: queue.Queue[tuple[dict[int, Status], set[int]] | None] = queue.Queue(
            maxsize=10_000
        )
        self._thread = threading.Thread(target=self._tick_loop, name="groot2-mirror", daemon=True)
        self._thread.start()

    def publish(self, statuses: dict[int, Status], visited: set[int]) -> None:
        # A full queue: the twin is held (a breakpoint); the mission goes on.
        with contextlib.suppress(queue.Full):
            self._queue.put_nowait((statuses, visited))

    def _answer(self, node: Any) -> Any:
        index = node.uid() - self._root_uid
        statuses, visited = self._snapshot
        if index in self._answered or index not in visited:
            return self._bt.NodeStatus.RUNNING
        self._answered.add(index)
        status = statuses.get(index, Status.RUNNING)
        return {
            Status.SUCCESS: self._bt.NodeStatus.SUCCESS,
            Status.FAILURE: self._bt.NodeStatus.FAILURE,
        }.get(status, self._bt.NodeStatus.RUNNING)

    def _tick_loop(self) -> None:
        while (item := self._queue.get()) is not None:
            self._snapshot, self._answered = item, set()
            try:
                self._tree.tick_exactly_once()
            except Exception as error:  # the monitor must never stop the mission
                logger.warning("the Groot2 mirror stopped: %s", one_line(error))
                return
            finally:
                self._queue.task_done()

    def flush(self, timeout_s: float = 2.0) -> bool:
        """Waits until every tick handed over is mirrored; False if it took too long."""
        deadline = time.monotonic() + timeout_s
        while self._queue.unfinished_tasks and time.monotonic() < deadline:
            time.sleep(0.005)
        return not self._queue.unfinished_tasks

    def close(self) -> None:
        self.flush()
        self._queue.put(None)
        self._thread.join(timeout=2.0)
        self._tree.halt_tree()
        del self._publisher


class _Visits(py_trees.visitors.VisitorBase):
    """The ids of the nodes each tick visited."""

    def __init__(self) -> None:
        super().__init__(full=False)
        self.ids: set[Any] = set()

    def initialise(self) -> None:
        self.ids = set()

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        self.ids.add(behaviour.id)


class Groot2Monitor:
    """The py_trees side: after each tick, the tree's statuses to the publisher.

    Args:
        root: the mission tree (as exported to XML).
        port: Groot2's port (PORT + 1 is used too).
        bind: ``127.0.0.1`` (default), another address of this machine, or ``*`` for
            BT.CPP's own publisher on every interface.

    Raises:
        Groot2Unavailable: the extra is missing or the ports are taken.
        InputError: the tree cannot be written as XML or BT.CPP's parser refuses it.
    """

    def __init__(
        self, root: py_trees.behaviour.Behaviour, port: int = DEFAULT_PORT, bind: str = "127.0.0.1"
    ) -> None:
        missing = missing_modules()
        if missing:
            raise Groot2Unavailable(f"--groot2 needs {', '.join(missing)}: {INSTALL_HINT}")
        check_groot2_port(port)
        xml = tree_to_btcpp_xml(root)
        self.root = root
        self.nodes = [node for _, node, _ in tree_nodes(root)]
        check_with_btcpp(
            without_leaf_ports(xml),
            {type(node).__name__ for node in self.nodes if not node.children},
        )
        self.address = zmq_endpoint("127.0.0.1" if bind in ALL_INTERFACES else bind, port)
        self._last = [0] * len(self.nodes)
        self._visits: _Visits | None = None
        self._ticks = -1
        if bind in ALL_INTERFACES:
            self._mirror: BtcppMirror | None = BtcppMirror(
                without_leaf_ports(xml), self.nodes, port
            )
            self._server: LoopbackServer | None = None
        else:
            self._mirror = None
            self._server = LoopbackServer(xml_with_uids(xml), len(self.nodes), port, bind)

    def __call__(self, runner: Any) -> None:
        """The runner's post-tick hook (``bearchair.executive.runner.MissionRunner``),
        called after each tick and once more when the run has ended."""
        tree = getattr(runner, "tree", None)
        visited: set[Any] = set()
        new_tick = True
        if isinstance(tree, py_trees.trees.BehaviourTree):
            new_tick, self._ticks = tree.count != self._ticks, tree.count
            if self._visits is None:
                # Seen from the next tick on; the first tick visited what it left non-INVALID.
                self._visits = _Visits()
                tree.visitors.append(self._visits)
                visited = {n.id for n in self.nodes if n.status != Status.INVALID}
            else:
                visited = self._visits.ids
        self.publish(visited, new_tick=new_tick)

    def publish(self, visited: set[Any], new_tick: bool = True) -> None:
        """Sends the statuses now.

        Args:
            visited: the ids of the nodes the tick just ran.
            new_tick: False for the call after the run ended (the tree stopped, no new
                tick): the server shows the stopped tree, the mirror is not ticked again
                (it would start its tree over).
        """
        if self._server is not None:
            self._server.publish(status_codes(self.nodes, self._last))
        if self._mirror is not None and new_tick:
            statuses = {index: node.status for index, node in enumerate(self.nodes)}
            indices = {index for index, node in enumerate(self.nodes) if node.id in visited}
            self._mirror.publish(statuses, indices)

    def close(self) -> None:
        for publisher in (self._server, self._mirror):
            if publisher is not None:
                publisher.close()
