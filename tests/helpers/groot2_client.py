"""A Groot2 client for tests: the requests Groot2 sends to monitor a tree, written from
BehaviorTree.CPP's ``include/behaviortree_cpp/loggers/groot2_protocol.h`` (not from our
server's code): a 6-byte request header (protocol 2, a request letter, a random uint32
id), a reply whose first part is that header with the tree's 16-byte UUID after it."""

from __future__ import annotations

import random
import socket
import struct
import xml.etree.ElementTree as ET

import zmq

PROTOCOL = 2
STATUS_NAMES = {0: "IDLE", 1: "RUNNING", 2: "SUCCESS", 3: "FAILURE", 4: "SKIPPED"}


class Groot2Error(RuntimeError):
    """The server answered with an error, or not in time."""


class Groot2Client:
    """Requests over a REQ socket; a request that times out drops the socket (a REQ
    socket cannot send again before it has a reply) and raises."""

    def __init__(self, address: str, timeout_ms: int = 1000) -> None:
        self.address = address
        self.timeout_ms = timeout_ms
        self._context = zmq.Context()
        self._socket: zmq.Socket | None = None

    def _connect(self) -> zmq.Socket:
        if self._socket is None:
            self._socket = self._context.socket(zmq.REQ)
            self._socket.setsockopt(zmq.LINGER, 0)
            self._socket.setsockopt(zmq.IPV6, "[" in self.address)
            self._socket.connect(self.address)
        return self._socket

    def request(self, kind: str) -> list[bytes]:
        """The reply's parts after the header, for request type ``kind`` (a letter)."""
        sock = self._connect()
        unique_id = random.getrandbits(32)
        sock.send(struct.pack("<BBI", PROTOCOL, ord(kind), unique_id))
        if not sock.poll(self.timeout_ms):
            sock.close()
            self._socket = None
            raise Groot2Error(f"no reply to {kind!r} within {self.timeout_ms} ms")
        reply = sock.recv_multipart()
        if reply[0] == b"error":
            raise Groot2Error(b" ".join(reply[1:]).decode())
        protocol, reply_kind, reply_id = struct.unpack("<BBI", reply[0][:6])
        assert len(reply[0]) == 22, "reply header: 6 bytes of request header + 16 of UUID"
        assert (protocol, reply_kind, reply_id) == (PROTOCOL, ord(kind), unique_id)
        return reply[1:]

    def tree(self) -> list[tuple[int, str, str]]:
        """``FULLTREE``: (uid, tag, name) of every node, depth first."""
        (xml,) = self.request("T")
        document = ET.fromstring(xml)
        return [
            (int(e.attrib["_uid"]), e.tag, e.attrib.get("name", ""))
            for e in document.iter()
            if "_uid" in e.attrib
        ]

    def statuses(self) -> dict[int, int]:
        """``STATUS``: each uid's status code (10 + X: idle, was X)."""
        (buffer,) = self.request("S")
        return {uid: code for uid, code in struct.iter_unpack("<HB", buffer)}

    def close(self) -> None:
        self._context.destroy(linger=0)


def free_port_pair() -> int:
    """A port P with P and P + 1 free on loopback now."""
    for _ in range(50):
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            port = probe.getsockname()[1]
        if port >= 65534:
            continue
        with socket.socket() as other:
            try:
                other.bind(("127.0.0.1", port + 1))
            except OSError:
                continue
        return port
    raise RuntimeError("no free pair of ports")
