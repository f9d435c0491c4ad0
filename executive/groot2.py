"""The running mission in Groot2 (``bearchair run --groot2 [PORT]``).

Groot2 monitors a tree over ZMQ (BehaviorTree.CPP's ``groot2_protocol.h``): a REP socket
on PORT answers requests (``FULLTREE``: the tree as XML whose nodes carry ``_uid``;
``STATUS``: every node's uid and status), and PORT + 1 publishes breakpoint events.
:class:`Groot2Monitor` is the py_trees side, a post-tick hook of the mission runner that
hands each tick's statuses to one of two publishers:

* :class:`~bearchair.executive.groot2_server.LoopbackServer` (the default,
  ``--groot2-bind 127.0.0.1``): the protocol's monitoring part served with pyzmq on the
  address asked for, the statuses straight from py_trees, the XML our export's
  (:func:`bearchair.executive.btcpp.tree_to_btcpp_xml`), checked first by
  BehaviorTree.CPP's own parser. It refuses breakpoints and status replacement: Groot2
  only watches.
* :class:`~bearchair.executive.groot2_mirror.BtcppMirror` (``--groot2-bind '*'``): a
  BehaviorTree.CPP tree built from the same XML by behaviortreepy, each leaf answering its
  py_trees twin's status, ticked once per mission tick in its own thread, published by
  BT.CPP's ``Groot2Publisher``. That publisher binds ``tcp://*:PORT`` and
  ``tcp://*:PORT+1`` (hard-coded in BT.CPP's ``src/loggers/groot2_publisher.cpp``;
  behaviortreepy's constructor takes only the port), so it can only be had on every
  interface: hence the loopback server as the default.

Both need the ``groot2`` extra (:data:`INSTALL_HINT`).
"""

from __future__ import annotations

import importlib.util
from typing import Any

import py_trees
from py_trees.common import Status

from bearchair.core.errors import InputError
from bearchair.executive.btcpp import tree_to_btcpp_xml
from bearchair.executive.groot2_mirror import BtcppMirror, check_with_btcpp, without_leaf_ports
from bearchair.executive.groot2_server import (
    Groot2Unavailable,
    LoopbackServer,
    status_codes,
    xml_with_uids,
    zmq_endpoint,
)
from bearchair.executive.records.run_record import tree_nodes

__all__ = ["Groot2Monitor", "Groot2Unavailable", "check_groot2_address", "check_groot2_port"]

DEFAULT_PORT = 1667
"""Groot2's default port (BT.CPP's ``Groot2Publisher``); PORT + 1 is used too."""
ALL_INTERFACES = ("*", "0.0.0.0")
"""``--groot2-bind`` values that select BT.CPP's own publisher (it binds only these)."""
INSTALL_HINT = "pip install 'bearchair[groot2]' (behaviortreepy and pyzmq)"


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
        self.every_interface = bind in ALL_INTERFACES
        """True when BT.CPP's publisher listens on every interface of the machine."""
        self.address = zmq_endpoint("127.0.0.1" if self.every_interface else bind, port)
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

    def __call__(self, host: Any) -> None:
        """After a tick: the mission runner's post-tick hook
        (``bearchair.executive.runner.MissionRunner``, called after each tick and once more
        when the run has ended), or a py_trees ``BehaviourTree``'s post-tick handler
        (``tree.add_post_tick_handler(monitor)``)."""
        tree = (
            host if isinstance(host, py_trees.trees.BehaviourTree) else getattr(host, "tree", None)
        )
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
