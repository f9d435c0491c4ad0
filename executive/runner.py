"""The tick loop: set the tree up, tick it until it ends, and say how it went."""

from __future__ import annotations

import logging
import signal
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import py_trees
from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.behaviours.mission_inputs import set_mission_inputs
from bearchair.core.arena import Arena
from bearchair.core.errors import RunRecordError
from bearchair.executive.interrupts import (
    emergency_stop_on_second_signal,
    raise_if_received,
    signal_name,
)
from bearchair.executive.records.jsonable import to_jsonable
from bearchair.executive.records.run_record import RecordWriteError, RunRecorder
from bearchair.executive.records.run_summary import (
    JsonRecord,
    JudgementRecord,
    ReleaseRecord,
    RunInfo,
    RunSummary,
    SittingPoseRecord,
    StageRecord,
)
from bearchair.hardware.interfaces import Robot
from bearchair.hardware.real import RobotFault
from bearchair.skills.mission_skills import MissionSkills

logger = logging.getLogger(__name__)

R = TypeVar("R", bound=JsonRecord)


@dataclass
class StageTiming:
    """When one of the root's children started and ended: wall seconds since the run
    began, and seconds on the robot's clock (simulated time in simulation)."""

    name: str
    status: str = Status.INVALID.value
    started_s: float | None = None
    ended_s: float | None = None
    feedback: str = ""
    robot_started_s: float | None = None
    robot_ended_s: float | None = None

    @property
    def seconds(self) -> float:
        """The stage's wall seconds."""
        return _span(self.started_s, self.ended_s)

    @property
    def robot_seconds(self) -> float:
        """The stage's seconds on the robot's clock."""
        return _span(self.robot_started_s, self.robot_ended_s)


def _span(started_s: float | None, ended_s: float | None) -> float:
    if started_s is None:
        return 0.0
    return (ended_s if ended_s is not None else started_s) - started_s


@dataclass
class MissionOutcome:
    """How a run ended: what the summary is built from."""

    status: Status
    stages: list[StageTiming]
    ticks: int
    wall_s: float
    interrupted: bool = False
    failed_leaf: py_trees.behaviour.Behaviour | None = None
    failures: list[str] = field(default_factory=list)
    blackboard: dict[str, Any] = field(default_factory=dict)
    stop_signal: str | None = None
    record_error: str | None = None


class MissionRunner:
    """Ticks a mission tree to completion.

    The tree ticked is ``root`` under a :class:`py_trees.decorators.Timeout`: on time it
    stops the mission (the running leaf's ``terminate()`` cancels its worker) and fails.

    Args:
        root: the tree (``bearchair.trees.mission.create_tree()``).
        skills: the skills given to every leaf at setup.
        robot: the hardware given to every leaf at setup.
        seed: the run's seed, on the blackboard for the skills.
        arena: the workspace layout, on the blackboard for the planner.
        recorder: writes the per-tick record (optional).
        tick_period_s: wall time between ticks; the leaves' workers run meanwhile.
        timeout_s: wall time after which the mission is stopped as failed.
        on_tick: called after each tick (progress display).
        post_tick: hooks called after each tick and once more when the run has ended
            (the tree stopped): recordings and viewers
            (:mod:`bearchair.executive.recording.mission_recording`).
        on_second_signal: called with the outcome so far when a second stop signal
            exits the process at once, after the robots were stopped (it writes the
            summary that the orderly stop had no time to write).
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
        on_second_signal: Callable[[MissionOutcome], object] | None = None,
    ) -> None:
        self.root = root
        self.timeout = py_trees.decorators.Timeout(
            name="Mission timeout", child=root, duration=timeout_s
        )
        self.tree = py_trees.trees.BehaviourTree(self.timeout)
        self.failures = FailureLog()
        self.stage_clock = StageClock(root, self.elapsed, self.robot_seconds)
        self.tree.visitors += [self.stage_clock, self.failures]
        self.skills = skills
        self.robot = robot
        self.recorder = recorder
        if recorder is not None:
            self.tree.add_post_tick_handler(self._record_tick)
        self.tick_period_s = tick_period_s
        self.timeout_s = timeout_s
        self.on_tick = on_tick
        self.post_tick = tuple(post_tick)
        self.on_second_signal = on_second_signal
        self.stages = self.stage_clock.stages
        self._seed = seed
        self._arena = arena
        self._start = 0.0
        self._record_error: RecordWriteError | None = None

    def elapsed(self) -> float:
        """Wall seconds since the run began."""
        return time.monotonic() - self._start

    def robot_seconds(self) -> float | None:
        """The robot's clock now (None when it cannot be read, e.g. at shutdown)."""
        try:
            return float(self.robot.clock.now())
        except Exception:  # a real robot's clock may fail; the wall time still counts
            return None

    def run(self) -> MissionOutcome:
        """Ticks until the root succeeds or fails, the timeout passes, or a stop signal.

        SIGINT/SIGTERM (``KeyboardInterrupt``) and a run record that cannot be written
        stop the tree and the robots; the outcome says which (``interrupted``,
        ``record_error``), and the caller writes what it can.
        """
        py_trees.blackboard.Blackboard.clear()
        if self.recorder:
            self.recorder.watch(self.tree)
        set_mission_inputs(seed=self._seed, arena=self._arena)
        self._start = time.monotonic()
        stopped, stop_signal, record_error = False, None, None
        # The second signal's stops cover the clean-up too: that is when it comes.
        with (
            emergency_stop_on_second_signal(lambda: stop_robots(self.robot)),
            emergency_stop_on_second_signal(self._last_words),
        ):
            try:
                self.tree.setup(timeout=30.0, skills=self.skills, robot=self.robot)
                self._start = time.monotonic()
                self._tick_until_done()
            except KeyboardInterrupt as error:
                stopped = True
                stop_signal = signal_name(getattr(error, "signum", signal.SIGINT))
                how = "the operator (Ctrl-C)" if stop_signal == "SIGINT" else stop_signal
                self._stop(f"interrupted by {how}")
                logger.warning("writing the run record; a second %s exits at once", stop_signal)
            except RecordWriteError as error:
                stopped, record_error = True, str(error)
                self._stop(f"stopped: {error}")
            except RobotFault as error:  # a device's monitor: the robots first, then the tree
                stopped = True
                stop_robots(self.robot)
                self._stop(f"stopped: {error}")
            finally:
                record_error = self._finish(record_error)
        return MissionOutcome(
            status=Status.FAILURE if stopped else self.timeout.status,
            stages=self.stages,
            ticks=self.tree.count,
            wall_s=self.elapsed(),
            interrupted=stop_signal is not None,
            failed_leaf=self.root.tip() if self.root.status == Status.FAILURE else None,
            failures=list(self.failures.messages),
            blackboard=dict(py_trees.blackboard.Blackboard.storage),
            stop_signal=stop_signal,
            record_error=record_error,
        )

    def _last_words(self) -> None:
        """The outcome so far, to :attr:`on_second_signal` (a second stop signal)."""
        if self.on_second_signal is None:
            return
        first = signal_name()
        self._fail_running_stages(f"interrupted by {first}; a second signal exited at once")
        self.on_second_signal(
            MissionOutcome(
                status=Status.FAILURE,
                stages=self.stages,
                ticks=self.tree.count,
                wall_s=self.elapsed(),
                interrupted=True,
                failures=list(self.failures.messages),
                blackboard=dict(py_trees.blackboard.Blackboard.storage),
                stop_signal=first,
            )
        )

    def _finish(self, record_error: str | None) -> str | None:
        """Shuts the tree down, stops the robots, writes the final record and calls the
        hooks a last time; returns the record's error, if any."""
        try:
            self.tree.shutdown()
        finally:
            stop_robots(self.robot)
        if self.recorder and record_error is None:
            try:
                self.recorder.record_final(self.tree.count, self.elapsed())
            except RecordWriteError as error:
                record_error = str(error)
        for hook in self.post_tick:
            hook(self)
        return record_error

    def _tick_until_done(self) -> None:
        while True:
            raise_if_received()
            self.tree.tick()
            if self._record_error is not None:
                raise self._record_error
            self._after_tick()
            if self.timeout.status == Status.FAILURE and self.root.status != Status.FAILURE:
                self._fail_running_stages(f"mission timed out after {self.timeout_s:.0f} s")
            if self.timeout.status in (Status.SUCCESS, Status.FAILURE):
                return
            time.sleep(self.tick_period_s)

    def _after_tick(self) -> None:
        """The per-tick hooks after the run record: ``post_tick``, then ``on_tick``."""
        for hook in self.post_tick:
            hook(self)
        if self.on_tick:
            self.on_tick(self)

    def _record_tick(self, tree: py_trees.trees.BehaviourTree) -> None:
        """The post-tick handler writing the run record; a failed write is raised by
        the tick loop once py_trees has counted the tick."""
        assert self.recorder is not None
        try:
            # py_trees counts the tick after its post-tick handlers.
            self.recorder.record_tick(tree.count + 1, self.elapsed())
        except RecordWriteError as error:
            self._record_error = error

    def _stop(self, reason: str) -> None:
        """Stops the tree (leaves cancel their work) and marks the running stage failed."""
        self.tree.root.stop(Status.INVALID)
        self._fail_running_stages(reason)

    def _fail_running_stages(self, reason: str) -> None:
        """Marks the stages that were running when the mission was cut short as failed."""
        logger.warning(reason)
        for stage in self.stages:
            if stage.status == Status.RUNNING.value and stage.ended_s is None:
                stage.status = Status.FAILURE.value
                stage.ended_s = self.elapsed()
                stage.robot_ended_s = self.robot_seconds()
                stage.feedback = reason


class StageClock(py_trees.visitors.VisitorBase):
    """Times the root's children (the stages) as each tick visits them: a stage's status
    is taken before anything above it (the mission's timeout) can stop it.

    Args:
        root: the mission tree; its children are the stages.
        clock: wall seconds since the run began.
        robot_clock: the robot's clock (None where it cannot be read).
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        clock: Callable[[], float],
        robot_clock: Callable[[], float | None] = lambda: None,
    ) -> None:
        super().__init__(full=False)
        self.stages = [StageTiming(child.name) for child in root.children]
        self._stage_of = {
            child.id: stage for child, stage in zip(root.children, self.stages, strict=True)
        }
        self._clock = clock
        self._robot_clock = robot_clock
        self._tick_start_s = 0.0
        self._tick_robot_start_s: float | None = None

    def initialise(self) -> None:
        self._tick_start_s = self._clock()
        self._tick_robot_start_s = self._robot_clock()

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        stage = self._stage_of.get(behaviour.id)
        if stage is None or behaviour.status == Status.INVALID:
            return
        if stage.started_s is None:
            stage.started_s = self._tick_start_s
            stage.robot_started_s = self._tick_robot_start_s
        if behaviour.status in (Status.SUCCESS, Status.FAILURE) and stage.ended_s is None:
            stage.ended_s = self._clock()
            stage.robot_ended_s = self._robot_clock()
        stage.status = behaviour.status.value
        stage.feedback = _leaf_feedback(behaviour)


class FailureLog(py_trees.visitors.VisitorBase):
    """Visits each tick's path and keeps ``<leaf>: <feedback>`` for every leaf failure,
    in the order they happened (``summary.json``'s ``failures``)."""

    def __init__(self) -> None:
        super().__init__(full=False)
        self.messages: list[str] = []

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        if not behaviour.children and behaviour.status == Status.FAILURE:
            self.messages.append(f"{behaviour.name}: {behaviour.feedback_message}")


def stop_robots(robot: Robot) -> None:
    """Stops every actuator of ``robot``: the one place the executive stops the robots.

    Called when a mission ends, fails, is interrupted, or on a second stop signal; it
    must never raise.
    """
    try:
        robot.emergency_stop()
    except Exception as error:  # stopping must not hide why we stopped
        logger.error("stopping the robots raised: %s", error)


def _leaf_feedback(node: py_trees.behaviour.Behaviour) -> str:
    """The feedback of the deepest active leaf under ``node``, or the node's own."""
    message = node.feedback_message
    for child in node.iterate():
        if not child.children and child.status != Status.INVALID and child.feedback_message:
            message = child.feedback_message
    return message


def summarise(outcome: MissionOutcome, info: RunInfo) -> RunSummary:
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
    return RunSummary(
        outcome="success" if success else "failure",
        info=info,
        failed_stage=None if success else failed_stage,
        reason=reason,
        interrupted=outcome.interrupted,
        signal=outcome.stop_signal or None,
        record_error=outcome.record_error or None,
        wall_seconds=round(outcome.wall_s, 3),
        ticks=outcome.ticks,
        stages=tuple(_stage_record(stage) for stage in outcome.stages),
        sitting_pose=_view_record(SittingPoseRecord, board.get(keys.SITTING_POSE)),
        se2_goal=to_jsonable(board.get(keys.SE2_GOAL)),
        instructions=tuple(str(sentence) for sentence in board.get(keys.INSTRUCTIONS, [])),
        rotations=int(board.get(keys.ROTATIONS, 0)),
        measured_rotations=_as_tuple(to_jsonable(board.get(keys.MEASURED_ROTATIONS, []))),
        accessible=bool(getattr(board.get(keys.ACCESSIBILITY), "accessible", False)),
        walk=to_jsonable(board.get(keys.WALK)),
        judgement=_view_record(JudgementRecord, board.get(keys.JUDGEMENT)),
        release_prediction=_view_record(
            ReleaseRecord, getattr(board.get(keys.SEATING_PLAN), "release", None)
        ),
        failures=tuple(outcome.failures),
    )


def _as_tuple(view: Any) -> tuple[Any, ...]:
    """A JSON view as the record's tuple: a list's items, else the one value."""
    return tuple(view) if isinstance(view, list) else (view,)


def _stage_record(stage: StageTiming) -> StageRecord:
    return StageRecord(
        name=stage.name,
        status=stage.status,
        seconds=round(stage.seconds, 3),
        robot_seconds=round(stage.robot_seconds, 3),
        message=stage.feedback,
        robot_started_s=None if stage.robot_started_s is None else round(stage.robot_started_s, 3),
    )


def _view_record(record: type[R], value: Any) -> R | None:
    """``value``'s JSON view (``to_jsonable``) read as ``record``; None when there is no
    value, or when it is not such a record (a plug-in's own result: a warning says so)."""
    if value is None:
        return None
    try:
        return record.from_json(to_jsonable(value))
    except RunRecordError as error:
        logger.warning("the summary leaves out %s: %s", type(value).__name__, error)
        return None
