"""A py_trees leaf that runs one skill call in a worker thread and polls it.

Subclasses say what to run (:meth:`SkillBehaviour.prepare` reads the blackboard in the
tick and returns a job; the job runs in the worker and may block) and what its result
means for the tree (:meth:`SkillBehaviour.conclude`, which runs in the tick and must
not block). The base class owns the rest: the worker, the
RUNNING feedback, cancellation on interruption, and turning an exception into FAILURE
with the error in the feedback message (the runner collects failures from the tree).
"""

from __future__ import annotations

import concurrent.futures
import threading
import time
from collections.abc import Callable
from typing import Any

import py_trees
from py_trees.common import Access, Status

from bearchair.hardware.interfaces import Robot
from bearchair.skills.mission_skills import MissionSkills


class SkillBehaviour(py_trees.behaviour.Behaviour):
    """Base class of the mission's leaves.

    Args:
        name: the leaf's name in the tree.
        reads: blackboard keys this leaf reads (registered with READ access).
        writes: blackboard keys this leaf writes (WRITE access); a key it reads and
            writes is in both.

    Dependencies arrive at ``setup(skills=..., robot=...)`` so that the tree can be
    built, rendered and inspected with no hardware and no skills at all.
    """

    #: Shown while the worker runs, e.g. "scanning".
    activity = "working"

    def __init__(self, name: str, reads: tuple[str, ...] = (), writes: tuple[str, ...] = ()):
        super().__init__(name=name)
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in reads:
            self.blackboard.register_key(key=key, access=Access.READ)
        for key in writes:
            self.blackboard.register_key(key=key, access=Access.WRITE)
        self.skills: MissionSkills | None = None
        self.robot: Robot | None = None
        self._executor: concurrent.futures.ThreadPoolExecutor | None = None
        self._future: concurrent.futures.Future | None = None
        self._cancel = threading.Event()
        self._started_at = 0.0
        self._error: str | None = None

    # -- py_trees hooks -------------------------------------------------------------

    def setup(self, **kwargs: Any) -> None:
        """Takes the injected ``skills`` and ``robot`` (either may be absent in tests)."""
        self.skills = kwargs.get("skills", self.skills)
        self.robot = kwargs.get("robot", self.robot)
        if self._executor is None:
            self._executor = concurrent.futures.ThreadPoolExecutor(
                max_workers=1, thread_name_prefix=self.name.replace(" ", "_")
            )

    def initialise(self) -> None:
        if self._executor is None:
            self.setup()
        assert self._executor is not None  # setup() makes it
        self._cancel = threading.Event()
        self._started_at = time.monotonic()
        self.feedback_message = f"{self.activity}..."
        self._future = None
        self._error = None
        try:
            job = self.prepare()
        except Exception as error:
            self._error = _describe(error)
            return
        self._future = self._executor.submit(job)

    def update(self) -> Status:
        future = self._future
        if future is None:
            return self.fail(self._error or "the worker was never started")
        if not future.done():
            self.feedback_message = f"{self.activity} ({time.monotonic() - self._started_at:.1f} s)"
            return Status.RUNNING
        self._future = None
        error = future.exception()
        if error is not None:
            return self.fail(_describe(error))
        try:
            return self.conclude(future.result())
        except Exception as error:
            return self.fail(_describe(error))

    def terminate(self, new_status: Status) -> None:
        # INVALID means we were interrupted by a higher priority or a stop: cancel the work.
        if new_status == Status.INVALID and self._future is not None:
            self._cancel.set()
            self._future.cancel()
            self._future = None
            self.feedback_message = "cancelled"

    def shutdown(self) -> None:
        self._cancel.set()
        if self._executor is not None:
            self._executor.shutdown(wait=False, cancel_futures=True)
            self._executor = None

    # -- what subclasses provide ----------------------------------------------------

    def prepare(self) -> Callable[[], Any]:
        """Runs in the tick: reads inputs, returns the job the worker runs (may block).

        The job's return value is what :meth:`conclude` gets.
        """
        raise NotImplementedError

    def conclude(self, result: Any) -> Status:
        """Runs in the tick with the worker's result; writes outputs, returns the status."""
        raise NotImplementedError

    # -- helpers for subclasses ------------------------------------------------------

    @property
    def cancel_event(self) -> threading.Event:
        """Set when this leaf is interrupted; pass it to long skills."""
        return self._cancel

    def need(self) -> tuple[MissionSkills, Robot]:
        """The injected skills and robot, or a clear error when setup() did not get them."""
        if self.skills is None:
            raise RuntimeError(f"{self.name}: no skills given to tree.setup(skills=...)")
        if self.robot is None:
            raise RuntimeError(f"{self.name}: no robot given to tree.setup(robot=...)")
        return self.skills, self.robot

    def succeed(self, message: str) -> Status:
        self.feedback_message = message
        return Status.SUCCESS

    def fail(self, message: str) -> Status:
        self.feedback_message = message
        return Status.FAILURE

    def _optional(self, key: str, default: Any) -> Any:
        try:
            return self.blackboard.get(key)
        except KeyError:
            return default


def previous_failure(behaviour: py_trees.behaviour.Behaviour) -> str:
    """``<leaf>: <why>`` of the failure that ended the sibling ticked before
    ``behaviour`` (the tip of its previous sibling), or that none is recorded: what a
    selector's last child, ticked only when every other child failed, gives up after."""
    siblings = behaviour.parent.children if behaviour.parent is not None else [behaviour]
    index = siblings.index(behaviour)
    tip = siblings[index - 1].tip() if index > 0 else None
    if tip is None or tip.status != Status.FAILURE:
        return "no reason recorded"
    return f"{tip.name}: {tip.feedback_message}"


def _describe(error: BaseException) -> str:
    text = str(error) or type(error).__name__
    return (
        text if isinstance(error, RuntimeError | ValueError) else f"{type(error).__name__}: {text}"
    )
