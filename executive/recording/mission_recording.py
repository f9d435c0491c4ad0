"""Recordings of a mission in Rerun: the tree and the 3D scene on one timeline.

``bearchair run --record`` writes ``RUN_DIR/mission.rrd``; ``--live`` streams the same
data to a viewer while the mission runs. Everything is logged from the tick loop's
post-tick hook (:class:`MissionRecording` is one), on two timelines: ``tick`` (the
tree's tick count) and ``robot`` (seconds on the robot's clock):

* ``tree``: the tree as a graph, each node coloured by its status with its feedback
  message, whenever a status or a message changes (``status`` and ``feedback`` are
  also logged as plain strings per node, in the order of
  :func:`bearchair.executive.records.run_record.tree_nodes`);
  ``tree/log`` has a line per status change;
* ``blackboard/<key>``: each blackboard value as JSON text whenever it changes;
* the scene: the skills' typed results drawn by :mod:`bearchair.executive.recording.scene_loggers`
  when they appear on the blackboard, and the skill calls the blackboard does not
  keep (the tag's detections, the rotations asked for, the NAO's motions), seen by
  :class:`bearchair.executive.skill_calls.SkillCalls`;
* the robots from their URDFs (:mod:`bearchair.executive.recording.urdf_robots`), in the
  layout of :mod:`bearchair.executive.recording.layout`.

A recording is read back with :func:`bearchair.executive.recording.read_back.read_entity`.

Skills hold no viewer code. Rerun (``rerun-sdk``) is the optional extra ``[viewer]``;
without it this module imports, and asking for a recording raises
:class:`RecordingUnavailable` with the install command.
"""

from __future__ import annotations

import collections
import contextlib
import importlib.util
import json
import logging
import math
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import py_trees
from py_trees.common import Status

from bearchair.behaviours import keys
from bearchair.core.errors import BackendUnavailable
from bearchair.executive.records.jsonable import to_jsonable
from bearchair.executive.records.run_record import tree_nodes
from bearchair.executive.records.run_summary import RecordingCost, RunSummary
from bearchair.executive.skill_calls import SkillCalls
from bearchair.executive.tree_labels import node_label
from bearchair.executive.viewer_links import (
    LOOPBACK,
    grpc_url,
    is_wildcard,
    reachable_host,
    serve_web_page,
    spawn_native_viewer,
    ssh_tunnel_hint,
    web_viewer_link,
)

if TYPE_CHECKING:
    import numpy as np

    from bearchair.core.se2 import SE2Pose
    from bearchair.executive.recording.urdf_robots import JointSampler
    from bearchair.executive.runner import MissionRunner
    from bearchair.skills.mission_skills import MissionSkills
    from bearchair.skills.results import SeatingPlan
logger = logging.getLogger(__name__)

RECORDING_FILE = "mission.rrd"
INSTALL_HINT = "pip install 'bearchair[viewer]' (the rerun-sdk viewer extra)"
DEFAULT_VIEWER_PORT = 9876
"""Rerun's own default gRPC port: a viewer started with ``rerun`` listens there."""
DEFAULT_WEB_PORT = 9090
STATUS_COLOURS = {
    Status.SUCCESS.value: (60, 180, 75),
    Status.FAILURE.value: (220, 50, 47),
    Status.RUNNING.value: (245, 200, 40),
    Status.INVALID.value: (170, 170, 170),
}
PATH_STEP_M = 0.02
"""The NAO's walked path gets a point every 2 cm (the walk stops within 5 mm)."""
POSE_STEP_M = 0.005
POSE_STEP_RAD = math.radians(1.0)
"""The NAO's pose is re-logged when it moved 5 mm or turned 1 degree since the last one."""
FEEDBACK_PERIOD_S = 1.0
"""Wall seconds between two logs of the tree when only feedback changed (a running
leaf's message counts its seconds every tick); status changes are logged at their tick.
Each log takes about 2 ms of the tick thread, more when the skills' threads hold the GIL."""


class RecordingUnavailable(BackendUnavailable):
    """A recording was asked for but cannot be made (no rerun-sdk, no display)."""


def rerun_available() -> bool:
    """True when the ``[viewer]`` extra (rerun-sdk) is installed."""
    return importlib.util.find_spec("rerun") is not None


def has_display() -> bool:
    """True where a native window can open (always on macOS and Windows)."""
    if not sys.platform.startswith("linux"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _rerun() -> Any:
    if not rerun_available():
        raise RecordingUnavailable(f"recording needs rerun-sdk: {INSTALL_HINT}")
    import rerun

    return rerun


class MissionRecording:
    """Logs a mission to Rerun from the tick loop (a post-tick hook of MissionRunner).

    Args:
        root: the tree (its shape is logged once).
        path: the ``.rrd`` file to write (None: stream only).
        live: None (no viewer), ``"spawn"`` (start a native viewer), ``"web"`` (serve
            the web viewer; its address is in :attr:`viewer_url`) or a Rerun URL
            (``rerun+http://HOST:9876/proxy``: a viewer already running, e.g. on the
            operator's laptop while the robots run).
        web_port: the web viewer's HTTP port with ``live="web"``.
        grpc_port: the port a spawned viewer or the web viewer's server listens on.
        bind: the address the web viewer's two servers (or a spawned viewer's) listen
            on; loopback unless the user opened it (``--bind``).

    Raises:
        RecordingUnavailable: rerun-sdk is missing, or a native viewer was asked for
            where there is no display.
    """

    def __init__(
        self,
        root: py_trees.behaviour.Behaviour,
        *,
        path: Path | None,
        live: str | None = None,
        web_port: int = DEFAULT_WEB_PORT,
        grpc_port: int = DEFAULT_VIEWER_PORT,
        bind: str = LOOPBACK,
    ) -> None:
        rr = _rerun()
        from bearchair.executive.recording import scene_loggers
        from bearchair.executive.recording.urdf_robots import MissionRobots

        self._rr = rr
        self._scene = scene_loggers
        self.path = None if path is None else Path(path)
        self.viewer_url: str | None = None
        self.viewer_hint: str | None = None
        """How to reach a loopback-bound web viewer from another machine (``ssh -L``)."""
        self._bind = bind
        self._page_server: subprocess.Popen[bytes] | None = None
        self.seconds = 0.0
        """Wall time spent in the hook so far (what recording costs the run)."""
        self.cpu_seconds = 0.0
        """CPU time of the hook's thread in the hook (its wall time less the waits for
        the GIL and the skills' threads; Rerun encodes and writes in threads of its own)."""
        self.seconds_by_part: dict[str, float] = collections.defaultdict(float)
        """The same, per thing logged (``tree``, ``skill calls``, a blackboard key, ...)."""
        self._stream = rr.RecordingStream("bearchair")
        sinks = []
        if self.path is not None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            sinks.append(rr.FileSink(str(self.path)))
        if live:
            sinks.append(self._live_sink(live, web_port, grpc_port))
        if not sinks:
            raise ValueError("a recording needs a file, a viewer or both")
        self._stream.set_sinks(*sinks)
        self._nodes = tree_nodes(root)
        self._last_tree: list[tuple[str, str]] | None = None
        self._last_tree_s = -math.inf
        self._last_values: dict[str, Any] = {}
        self._skill_calls: SkillCalls | None = None
        self._walked: list[SE2Pose] = []
        self._last_pose: SE2Pose | None = None
        self._warned: set[str] = set()
        self._lock = threading.Lock()
        self._robots = MissionRobots()
        self._arm_sampler: JointSampler | None = None
        self._log_static()

    # -- set-up ---------------------------------------------------------------------

    def _live_sink(self, live: str, web_port: int, grpc_port: int) -> Any:
        rr = self._rr
        if live == "spawn":
            if not has_display():
                raise RecordingUnavailable(
                    "no display for a native viewer: use --live web (a web viewer on a port)"
                )
            spawn_native_viewer(self._bind, grpc_port)
            self.viewer_url = grpc_url(
                LOOPBACK if is_wildcard(self._bind) else self._bind, grpc_port
            )
            return rr.GrpcSink(self.viewer_url)
        if live == "web":
            # The data in this process, on `bind`; the page from Rerun's program, since
            # rr.serve_web_viewer listens on every interface (viewer_links).
            server = rr.GrpcServerSink(bind_ip=self._bind, port=grpc_port)
            self._page_server = serve_web_page(
                self._bind, web_port, grpc_url(reachable_host(self._bind), grpc_port)
            )
            self.viewer_url = web_viewer_link(self._bind, web_port, grpc_port)
            self.viewer_hint = ssh_tunnel_hint(self._bind, web_port, grpc_port)
            return server
        self.viewer_url = live
        return rr.GrpcSink(live)

    def _log_static(self) -> None:
        from bearchair.executive.recording.layout import mission_blueprint, tree_layout

        rr = self._rr
        self._stream.send_blueprint(mission_blueprint())
        self._scene.log_world_frame(self._stream)
        # The robots as they stand before the first tick; where the arena puts the arm's
        # base is known at the first tick (keys.ARENA).
        self._stream.set_time("tick", sequence=0)
        self._stream.set_time("robot", duration=0.0)
        self._guarded("robots", self._robots.log_static, self._stream, (0.0, 0.0))
        paths = [path for path, _, _ in self._nodes]
        edges = [(path.rsplit("/", 1)[0], path) for path in paths if "/" in path]
        self._stream.log(
            "tree",
            rr.GraphEdges(edges, graph_type=rr.GraphType.Directed),
            rr.GraphNodes(paths, positions=tree_layout(self._nodes)),
            static=True,
        )

    def watch_skills(self, skills: MissionSkills, clock: Any) -> MissionSkills:
        """Wraps the tree's skills so that the watched calls are recorded too."""
        self._skill_calls = SkillCalls(skills, clock)
        # SkillCalls passes every attribute through (__getattr__), which pyright cannot see.
        return cast("MissionSkills", self._skill_calls)

    # -- the post-tick hook ------------------------------------------------------------

    def __call__(self, runner: MissionRunner) -> None:
        started, cpu_started = time.perf_counter(), time.thread_time()
        with self._lock:
            events = self._skill_calls.drain() if self._skill_calls is not None else []
            tree = self._tree_to_log()
            changed = self._changed_values()
            arm = self._arm_states(runner)
            # Most ticks change nothing: then nothing reaches Rerun, not even the time
            # (each call into it hands the GIL to the skills' threads and waits for it back).
            if events or tree is not None or changed or arm:
                self._stream.set_time("tick", sequence=int(runner.tree.count))
                # The skill calls returned since the last tick, each at its own time;
                # the arm's states as well.
                self._guarded("skill calls", self._log_skill_calls, events)
                self._guarded("arm joints", self._log_arm_states, arm)
                self._stream.set_time("robot", duration=_robot_seconds(runner))
                if tree is not None:
                    self._guarded("tree", self._log_tree, *tree)
                for key, value, previous in changed:
                    self._guarded(key, self._log_value, key, value, previous)
        self.seconds += time.perf_counter() - started
        self.cpu_seconds += time.thread_time() - cpu_started

    def _arm_states(self, runner: MissionRunner) -> list[tuple[float, np.ndarray]]:
        """The arm's joint states read since the last tick (its sampler starts at the first)."""
        if self._arm_sampler is None:
            from bearchair.executive.recording.urdf_robots import JointSampler

            self._arm_sampler = JointSampler(runner.robot.arm.joint_positions, runner.robot.clock)
        return self._arm_sampler.drain()

    def _log_arm_states(self, states: list[tuple[float, np.ndarray]]) -> None:
        for robot_s, joints in states:
            self._stream.set_time("robot", duration=robot_s)
            self._robots.log_arm(self._stream, joints)

    def cost(self) -> RecordingCost:
        """What the recording cost the run so far: the hook's wall seconds, in all and
        for the five most expensive things logged, and its CPU seconds
        (``summary.json``'s ``recording``)."""
        parts = sorted(self.seconds_by_part.items(), key=lambda kv: -kv[1])[:5]
        return RecordingCost(
            file=None if self.path is None else self.path.name,
            seconds=round(self.seconds, 3),
            cpu_seconds=round(self.cpu_seconds, 3),
            seconds_by_part={name: round(seconds, 3) for name, seconds in parts},
        )

    def log_summary(self, summary: RunSummary) -> None:
        """The run's summary (``summary.json``) as a text document at the end."""
        text = json.dumps(summary.to_json(), indent=2)
        self._guarded(
            "summary",
            lambda: self._stream.log(
                "mission/summary", self._rr.TextDocument(text, media_type="text/plain")
            ),
        )

    def close(self) -> None:
        """Logs the tree's last feedback, flushes and closes the file (the viewer keeps
        what it received)."""
        if self._arm_sampler is not None:
            self._arm_sampler.stop()
        with self._lock:
            tree = self._tree_to_log(force=True)
            if tree is not None:
                self._guarded("tree", self._log_tree, *tree)
        try:
            self._stream.flush()
            self._stream.disconnect()
        except Exception as error:  # never lose the run record over the recording
            logger.warning("could not close the recording: %s", error)
        if self._page_server is not None:
            self._page_server.terminate()
            with contextlib.suppress(subprocess.TimeoutExpired):
                self._page_server.wait(timeout=5.0)
            self._page_server = None

    # -- what is logged ---------------------------------------------------------------

    def _guarded(self, what: str, log: Callable[..., None], *args: Any) -> None:
        # A recording that fails must never stop the mission: warn once and go on.
        started = time.perf_counter()
        try:
            log(*args)
        except Exception as error:
            if what not in self._warned:
                self._warned.add(what)
                logger.warning("recording: could not log %s: %s", what, error)
        finally:
            self.seconds_by_part[what] += time.perf_counter() - started

    def _tree_to_log(
        self, force: bool = False
    ) -> tuple[list[tuple[str, str]], list[tuple[str, str]]] | None:
        """(state, previous state) when the tree is to be logged now, else None."""
        state = [(node.status.value, node.feedback_message or "") for _, node, _ in self._nodes]
        if state == self._last_tree:
            return None
        previous = self._last_tree or [(Status.INVALID.value, "")] * len(state)
        now = time.monotonic()
        statuses_changed = [s for s, _ in state] != [s for s, _ in previous]
        if not (force or statuses_changed) and now - self._last_tree_s < FEEDBACK_PERIOD_S:
            return None
        self._last_tree, self._last_tree_s = state, now
        return state, previous

    def _log_tree(self, state: list[tuple[str, str]], previous: list[tuple[str, str]]) -> None:
        rr = self._rr
        for (_, node, _), (status, feedback), (old, _) in zip(
            self._nodes, state, previous, strict=True
        ):
            if status != old:
                self._stream.log(
                    "tree/log",
                    rr.TextLog(
                        f"{node.name}: {old} -> {status}" + (f": {feedback}" if feedback else ""),
                        level=_text_level(rr, status),
                    ),
                )
        self._stream.log(
            "tree",
            rr.GraphNodes(
                [path for path, _, _ in self._nodes],
                labels=[
                    node_label(node.name, feedback)
                    for (_, node, _), (_, feedback) in zip(self._nodes, state, strict=True)
                ],
                colors=[STATUS_COLOURS[status] for status, _ in state],
            ),
            rr.AnyValues(
                status=[status for status, _ in state], feedback=[text for _, text in state]
            ),
        )

    def _changed_values(self) -> list[tuple[str, Any, Any]]:
        """(key, value, previous value) of the blackboard values replaced since the last
        tick. Behaviours replace values, never mutate them, so identity says it."""
        storage = py_trees.blackboard.Blackboard.storage
        changed = []
        for key in sorted(storage):
            value = storage[key]
            if key in self._last_values and self._last_values[key] is value:
                continue
            changed.append((key, value, self._last_values.get(key)))
            self._last_values[key] = value
        return changed

    def _log_value(self, key: str, value: Any, previous: Any) -> None:
        text = json.dumps(to_jsonable(value), indent=1, sort_keys=True)
        self._stream.log(f"blackboard{key}", self._rr.TextDocument(text, media_type="text/plain"))
        if value is None:
            return
        if key == keys.HUMANOID_POSE:
            self._log_humanoid_pose(value)
        elif key == keys.MEASURED_ROTATIONS:
            for rotation in value[len(previous or []) :]:
                self._scene.log_rotation(self._stream, rotation)
        elif key in self._scene.SCENE_LOGGERS:
            self._scene.SCENE_LOGGERS[key](self._stream, value)
        if key == keys.ARENA:
            self._robots.log_arm_base(self._stream, value.arm_base_xy)

    def _log_skill_calls(self, events: list[tuple[str, Any, float]]) -> None:
        for name, result, robot_s in events:
            self._stream.set_time("robot", duration=robot_s)
            if name == "locate_humanoid":
                self._scene.log_tag_detection(self._stream, result)
                if result is not None:
                    self._log_humanoid_pose(result)
            elif name == "compose_instruction":
                self._scene.log_instruction(self._stream, result)
            elif name in SkillCalls.MOTIONS:
                self._log_motion(name, *result)

    def _log_motion(self, name: str, plan: SeatingPlan | None, started_s: float) -> None:
        """The NAO's joints as a seating or retract motion played them, knot by knot."""
        if plan is None:
            return
        if name == "execute_seating":
            times, positions = plan.times_s, plan.positions_rad
        else:
            times, positions = plan.retract_times_s, plan.retract_positions_rad
        if len(times):
            self._robots.log_nao_motion(self._stream, plan.joint_names, times, positions, started_s)

    def _log_humanoid_pose(self, pose: SE2Pose) -> None:
        """Moves the NAO to its tracked pose; its path gets a point every 2 cm."""
        last = self._last_pose
        if (
            last is None
            or last.distance_to(pose) >= POSE_STEP_M
            or abs(math.remainder(pose.theta - last.theta, math.tau)) >= POSE_STEP_RAD
        ):
            self._last_pose = pose
            self._scene.log_humanoid_pose(self._stream, pose)
        if not self._walked or self._walked[-1].distance_to(pose) >= PATH_STEP_M:
            self._walked.append(pose)
            if len(self._walked) >= 2:
                self._scene.log_walked_path(self._stream, self._walked)


def open_recording(
    root: py_trees.behaviour.Behaviour,
    out_dir: Path,
    *,
    record: bool,
    live: str | None,
    bind: str = LOOPBACK,
) -> MissionRecording | None:
    """The run's recording as asked for (``--record``, ``--live``, ``--bind``), or None
    for neither."""
    if not record and not live:
        return None
    return MissionRecording(
        root, path=out_dir / RECORDING_FILE if record else None, live=live, bind=bind
    )


def _robot_seconds(runner: MissionRunner) -> float:
    try:
        return float(runner.robot.clock.now())
    except Exception:  # a real robot's clock may fail at shutdown
        return runner.elapsed()


def _text_level(rr: Any, status: str) -> Any:
    if status == Status.FAILURE.value:
        return rr.TextLogLevel.WARN
    return rr.TextLogLevel.INFO
