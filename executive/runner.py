"""The tick loop: set the tree up, tick it until it ends, and say how it went."""

from __future__ import annotations

import logging
import signal
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.common import Status

from behaviours import keys
from core.arena import Arena
from executive.interrupts import (
    emergency_stop_on_second_signal,
    raise_if_received,
    signal_name,
)
from executive.jsonable import to_jsonable
from executive.record import RecordWriteError, RunRecorder
from hardware.interfaces import Robot
from skills.toolbox import MissionSkills

logger = logging.getLogger(__name__)


@dataclass
class StageTiming:
    """When one of the root's children started and ended (seconds since the run began)."""

    name: str
    status: str = Status.INVALID.value
    started_s: float | None = None
    ended_s: float | None = None
    feedback: str = ""

    @property
    def seconds(self) -> float:
        if self.started_s is None:
            return 0.0
        end = self.ended_s if self.ended_s is not None else self.started_s
        return end - self.started_s


@dataclass
class MissionOutcome:
    """How a run ended: what the summary is built from."""

    status: Status
    stages: list[StageTiming]
    ticks: int
    wall_s: float
    interrupted: bool = False
    failed_leaf: py_trees.behaviour.Behaviour | None = None
    blackboard: dict[str, Any] = field(default_factory=dict)
    stop_signal: str | None = None
    record_error: str | None = None


class MissionRunner:
    """Ticks a mission tree to completion.

    Args:
        root: the tree (``trees.mission.create_tree()``).
        skills: the skills given to every leaf at setup.
        robot: the hardware given to every leaf at setup.
        seed: the run's seed, on the blackboard for the skills.
        arena: the workspace layout, on the blackboard for the planner.
        recorder: writes the per-tick record (optional).
        tick_period_s: wall time between ticks; the leaves' workers run meanwhile.
        timeout_s: wall time after which the mission is stopped as failed.
        on_tick: called after each tick (progress display).
        post_tick: hooks called after each tick and once more when the run has ended
            (the tree stopped): recordings and viewers (``executive.recording``).
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        skills: MissionSkills,
        robot: Robot,
        *,
        seed: int,
        arena: Arena,
        recorder: RunRecorder | None = None,
        tick_period_s: float = 0.05,
        timeout_s: float = 900.0,
        on_tick: Callable[[MissionRunner], None] | None = None,
        post_tick: Sequence[Callable[[MissionRunner], None]] = (),
    ) -> None:
        self.root = root
        self.tree = py_trees.trees.BehaviourTree(root)
        self.skills = skills
        self.robot = robot
        self.recorder = recorder
        self.tick_period_s = tick_period_s
        self.timeout_s = timeout_s
        self.on_tick = on_tick
        self.post_tick = tuple(post_tick)
        self.stages = [StageTiming(child.name) for child in root.children]
        self._seed = seed
        self._arena = arena
        self._start = 0.0

    def elapsed(self) -> float:
        return time.monotonic() - self._start

    def run(self) -> MissionOutcome:
        """Ticks until the root succeeds or fails, the timeout passes, or a stop signal.

        SIGINT/SIGTERM (``KeyboardInterrupt``) and a run record that cannot be written
        stop the tree and the robots; the outcome says which (``interrupted``,
        ``record_error``), and the caller writes what it can.
        """
        py_trees.blackboard.Blackboard.clear()
        writer = py_trees.blackboard.Client(name="executive")
        for key, value in ((keys.SEED, self._seed), (keys.ARENA, self._arena)):
            writer.register_key(key=key, access=py_trees.common.Access.WRITE)
            writer.set(key, value)
        self._start = time.monotonic()
        interrupted, stop_signal, record_error = False, None, None
        try:
            with emergency_stop_on_second_signal(lambda: stop_robots(self.robot)):
                self.tree.setup(timeout=30.0, skills=self.skills, robot=self.robot)
                self._start = time.monotonic()
                self._tick_until_done()
        except KeyboardInterrupt as error:
            interrupted = True
            stop_signal = signal_name(getattr(error, "signum", signal.SIGINT))
            how = "the operator (Ctrl-C)" if stop_signal == "SIGINT" else stop_signal
            self._stop(f"interrupted by {how}")
            logger.warning("writing the run record; a second %s exits at once", stop_signal)
        except RecordWriteError as error:
            record_error = str(error)
            self._stop(f"stopped: {error}")
        finally:
            try:
                self.tree.shutdown()
            finally:
                stop_robots(self.robot)
            if self.recorder and record_error is None:
                try:
                    self.recorder.record_tick(self.tree.count, self.elapsed())
                except RecordWriteError as error:
                    record_error = str(error)
            for hook in self.post_tick:
                hook(self)
        return MissionOutcome(
            status=self.root.status,
            stages=self.stages,
            ticks=self.tree.count,
            wall_s=self.elapsed(),
            interrupted=interrupted,
            failed_leaf=_failed_leaf(self.root),
            blackboard=dict(py_trees.blackboard.Blackboard.storage),
            stop_signal=stop_signal,
            record_error=record_error,
        )

    def _tick_until_done(self) -> None:
        while True:
            raise_if_received()
            tick_start = self.elapsed()
            self.tree.tick()
            self._time_stages(tick_start)
            self._after_tick()
            if self.root.status in (Status.SUCCESS, Status.FAILURE):
                return
            if self.elapsed() > self.timeout_s:
                self._stop(f"mission timed out after {self.timeout_s:.0f} s")
                return
            time.sleep(self.tick_period_s)

    def _after_tick(self) -> None:
        """The per-tick hooks: the run record, ``post_tick``, then the caller's ``on_tick``."""
        if self.recorder:
            self.recorder.record_tick(self.tree.count, self.elapsed())
        for hook in self.post_tick:
            hook(self)
        if self.on_tick:
            self.on_tick(self)

    def _time_stages(self, tick_start_s: float) -> None:
        now = self.elapsed()
        for stage, child in zip(self.stages, self.root.children, strict=True):
            if child.status != Status.INVALID and stage.started_s is None:
                stage.started_s = tick_start_s
            if child.status in (Status.SUCCESS, Status.FAILURE) and stage.ended_s is None:
                stage.ended_s = now
            if child.status != Status.INVALID:
                stage.status = child.status.value
                stage.feedback = _leaf_feedback(child)

    def _stop(self, reason: str) -> None:
        """Stops the tree (leaves cancel their work) and marks the running stage failed."""
        logger.warning(reason)
        running = [
            s
            for s, c in zip(self.stages, self.root.children, strict=True)
            if c.status == Status.RUNNING
        ]
        self.root.stop(Status.INVALID)
        self.root.status = Status.FAILURE
        for stage in running:
            stage.status = Status.FAILURE.value
            stage.ended_s = self.elapsed()
            stage.feedback = reason
        self.root.feedback_message = reason


def stop_robots(robot: Robot) -> None:
    """Stops every actuator of ``robot``: the one place the executive stops the robots.

    Called when a mission ends, fails, is interrupted, or on a second stop signal; it
    must never raise.
    """
    try:
        robot.emergency_stop()
    except Exception as error:  # stopping must not hide why we stopped
        logger.error("stopping the robots raised: %s", error)


def _failed_leaf(root: py_trees.behaviour.Behaviour) -> py_trees.behaviour.Behaviour | None:
    """The leaf whose failure ended the mission: the last failed leaf in tick order."""
    failed = None
    for node in root.iterate():
        if not node.children and node.status == Status.FAILURE:
            failed = node
    return failed


def _leaf_feedback(node: py_trees.behaviour.Behaviour) -> str:
    """The feedback of the deepest active leaf under ``node``, or the node's own."""
    message = node.feedback_message
    for child in node.iterate():
        if not child.children and child.status != Status.INVALID and child.feedback_message:
            message = child.feedback_message
    return message


def summarise(outcome: MissionOutcome, run_info: dict[str, Any]) -> dict[str, Any]:
    """The ``summary.json`` of a run: outcome, failed stage, reason, stages and key outputs."""
    board = outcome.blackboard
    success = outcome.status == Status.SUCCESS and not outcome.interrupted
    failed_stage = next((s.name for s in outcome.stages if s.status == Status.FAILURE.value), None)
    if success:
        reason = ""
    elif outcome.interrupted or outcome.failed_leaf is None:
        reason = next((s.feedback for s in outcome.stages if s.name == failed_stage), "")
    else:
        reason = f"{outcome.failed_leaf.name}: {outcome.failed_leaf.feedback_message}"
    judgement = board.get(keys.JUDGEMENT)
    return {
        **run_info,
        "outcome": "success" if success else "failure",
        "failed_stage": None if success else failed_stage,
        "reason": reason,
        "interrupted": outcome.interrupted,
        **({"signal": outcome.stop_signal} if outcome.stop_signal else {}),
        **({"record_error": outcome.record_error} if outcome.record_error else {}),
        "wall_seconds": round(outcome.wall_s, 3),
        "ticks": outcome.ticks,
        "stages": [
            {
                "name": s.name,
                "status": s.status,
                "seconds": round(s.seconds, 3),
                "message": s.feedback,
            }
            for s in outcome.stages
        ],
        "sitting_pose": to_jsonable(board.get(keys.SITTING_POSE)),
        "se2_goal": to_jsonable(board.get(keys.SE2_GOAL)),
        "instructions": list(board.get(keys.INSTRUCTIONS, [])),
        "rotations": int(board.get(keys.ROTATIONS, 0)),
        "measured_rotations": to_jsonable(board.get(keys.MEASURED_ROTATIONS, [])),
        "accessible": bool(getattr(board.get(keys.ACCESSIBILITY), "accessible", False)),
        "walk": to_jsonable(board.get(keys.WALK)),
        "judgement": to_jsonable(judgement),
        "failures": list(board.get(keys.FAILURES, [])),
    }
