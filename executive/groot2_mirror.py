"""A BehaviorTree.CPP twin of the running tree, published by BT.CPP's own
``Groot2Publisher`` (``bearchair run --groot2 --groot2-bind '*'``;
:mod:`bearchair.executive.groot2`)."""

from __future__ import annotations

import contextlib
import logging
import queue
import threading
import time
import xml.etree.ElementTree as ET
from typing import Any

import py_trees
from py_trees.common import Status

from bearchair.core.errors import InputError, one_line
from bearchair.executive.groot2_server import Groot2Unavailable

logger = logging.getLogger(__name__)


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
