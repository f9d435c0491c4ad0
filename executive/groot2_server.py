"""Groot2's monitoring protocol served with pyzmq on the address asked for (the default
publisher of ``bearchair run --groot2``; :mod:`bearchair.executive.groot2`).

What is sent follows BehaviorTree.CPP's ``loggers/groot2_protocol.h`` and
``src/loggers/groot2_publisher.cpp`` (4.8.2): every reply's first part is the request's
6-byte header (protocol 2, the request letter, its id) and the tree's 16-byte UUID;
``FULLTREE`` answers the XML with ``_uid`` on every node, ``STATUS`` 3 bytes per node
(uint16 uid, uint8 status; an idle node that was X is 10 + X).
"""

from __future__ import annotations

import logging
import struct
import threading
import uuid
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import py_trees
from py_trees.common import Status

from bearchair.core.errors import BackendUnavailable

logger = logging.getLogger(__name__)

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


def zmq_endpoint(bind: str, port: int) -> str:
    """``tcp://HOST:PORT``, an IPv6 address in brackets."""
    return f"tcp://{f'[{bind}]' if ':' in bind else bind}:{port}"


def status_codes(nodes: list[py_trees.behaviour.Behaviour], last: list[int]) -> list[int]:
    """Each node's BT.CPP status code now; ``last`` (updated) holds the last non-idle one."""
    codes = []
    for index, node in enumerate(nodes):
        code = BTCPP_STATUS[node.status]
        if code:
            last[index] = code
        codes.append(code if code or not last[index] else IDLE_FROM + last[index])
    return codes


@dataclass(frozen=True)
class BuiltinPort:
    """An input port of a BT.CPP built-in node's model, as BT.CPP describes it."""

    name: str
    type: str
    text: str
    default: str = ""


_RETRIES = "Execute again a failing child up to N times. Use -1 to create an infinite loop."
_REPEATS = "Repeat a successful child up to N times. Use -1 to create an infinite loop."
_TIMEOUT = "After a certain amount of time, halt() the child if it is still running."
_FAILURES = "number of children that need to fail to trigger a FAILURE"
_SUCCESSES = "number of children that need to succeed to trigger a SUCCESS"
BUILTIN_MODELS: dict[str, tuple[str, tuple[BuiltinPort, ...]]] = {
    "Sequence": ("Control", ()),
    "ReactiveSequence": ("Control", ()),
    "Fallback": ("Control", ()),
    "ReactiveFallback": ("Control", ()),
    "Parallel": (
        "Control",
        (
            BuiltinPort("failure_count", "int", _FAILURES, "1"),
            BuiltinPort("success_count", "int", _SUCCESSES, "-1"),
        ),
    ),
    "RetryUntilSuccessful": ("Decorator", (BuiltinPort("num_attempts", "int", _RETRIES),)),
    "Repeat": ("Decorator", (BuiltinPort("num_cycles", "int", _REPEATS),)),
    "Timeout": ("Decorator", (BuiltinPort("msec", "unsigned int", _TIMEOUT),)),
    "Inverter": ("Decorator", ()),
    "ForceSuccess": ("Decorator", ()),
    "ForceFailure": ("Decorator", ()),
    "AlwaysSuccess": ("Action", ()),
    "AlwaysFailure": ("Action", ()),
}
"""The models BehaviorTree.CPP 4.8.2 sends Groot2 for the built-in nodes we map (its
``WriteTreeToXML(tree, true, true)``): the kind of node and its input ports."""


def xml_with_uids(xml: str) -> str:
    """Our export as Groot2 expects a ``FULLTREE`` reply, as BT.CPP's publisher sends it:
    each tree node's ``_uid`` (1, 2, ... in depth-first order, the order
    :func:`bearchair.executive.records.run_record.tree_nodes` lists them), the tree's ``_fullpath``,
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
        for port in ports:
            default = {"default": port.default} if port.default else {}
            element = ET.SubElement(
                model, "input_port", {"name": port.name, "type": port.type, **default}
            )
            element.text = port.text
    models[:] = [entries[key] for key in sorted(entries, key=str)]
    return ET.tostring(document, encoding="unicode")


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
