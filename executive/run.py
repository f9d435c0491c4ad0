"""One mission run in the simulated world, from configuration to run record."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import math
import signal
import sys
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bearchair.core.errors import one_line
from bearchair.core.geometry import wrap_angle
from bearchair.core.meshes import load_mesh
from bearchair.core.userfiles import printable
from bearchair.executive.config import RunConfig, front_yaw_from_manifest
from bearchair.executive.interrupts import raise_if_received, signal_name
from bearchair.executive.outputs import atomic_path, write_text_atomic
from bearchair.executive.recording.mission_recording import open_recording
from bearchair.executive.records.run_record import RecordWriteError, RunRecorder
from bearchair.executive.records.run_summary import GroundTruth, RunInfo, RunSummary
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.executive.tick_watchers import ScenePictures, StageSnapshots, both
from bearchair.executive.tree_source import build_tree
from bearchair.skills.mission_skills import MissionSkills
from bearchair.trees.mission import create_tree
from bearchair.trees.options import TreeFactory

if TYPE_CHECKING:
    from bearchair.hardware.sim.world import SimConfig, SimWorld

logger = logging.getLogger(__name__)


CONFIG_FILE = "config.json"
"""The run folder's copy of the resolved configuration (``RunConfig.record_json``)."""


def run_in_simulation(
    config: RunConfig,
    skills: MissionSkills | None = None,
    on_tick: Callable[[MissionRunner], None] | None = None,
    tree: TreeFactory | None = None,
) -> RunSummary:
    """Builds the simulated world and the tree, runs the mission, writes the run record.

    Args:
        config: the run.
        skills: the skills (None: the default skills with ``config``'s parameters and
            skill plug-ins).
        on_tick: called after every tick (progress).
        tree: the tree factory, called with ``config.tree_options`` (None: the mission's
            ``create_tree``; see ``bearchair.executive.tree_source.load_tree_factory``).

    Returns:
        The summary written to ``summary.json``.

    Raises:
        core.meshes.MeshLoadError: the chair file is unusable (checked before anything runs).
        PluginError: the tree factory fails or returns no behaviour.
    """
    sim_config = _sim_config(config)
    root = build_tree(tree or create_tree, config.tree_options, config.tree_spec)
    recorder = RunRecorder(config.out_dir, root)
    write_config(config)
    run_info = RunInfo(
        chair=config.chair_name(),
        placement=config.placement,
        helper=config.helper,
        seed=config.seed,
        backend="sim",
        tree=config.tree_spec,
        started_at=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
    )
    try:
        world = _open_world(sim_config)
    except BaseException as error:
        # Interrupted (or failed) before the first tick: the record still gets a summary.
        summary = summary_before_start(root, run_info, error, "building the simulated world")
        try:
            # Tick 0, the tree as it stood: a record `inspect` can replay.
            with contextlib.suppress(RecordWriteError):
                recorder.record_final(0, 0.0)
            recorder.write_summary(summary)
        finally:
            recorder.close()
        if isinstance(error, KeyboardInterrupt):
            return summary
        raise
    pictures = ScenePictures(world, config.chair_name(), config.seed)
    if config.snapshots:
        on_tick = both(on_tick, StageSnapshots(pictures, config.out_dir / "snapshots"))
    try:
        return _run_tree(
            root,
            recorder,
            world.robot,
            config,
            run_info,
            skills,
            on_tick,
            pictures.final,
            lambda summary: _ground_truth(world, summary),
        )
    finally:
        world.close()


def write_config(config: RunConfig) -> Path:
    """Writes the resolved configuration to the run folder's :data:`CONFIG_FILE`."""
    path = config.out_dir / CONFIG_FILE
    with atomic_path(path) as scratch:
        scratch.write_text(json.dumps(config.record_json(), indent=2, default=str) + "\n")
    return path


def _sim_config(config: RunConfig) -> SimConfig:
    """The simulated world's configuration, with its voice.

    Raises:
        core.meshes.MeshLoadError: the chair file is unusable (one line, before anything runs).
    """
    front_yaw_deg = 0.0  # the built-in box chair faces +x
    if config.chair_path is not None:
        load_mesh(config.chair_path)  # fail fast, with one line, on a bad file
        front_yaw_deg = front_yaw_from_manifest(config.chair_path)

    from bearchair.hardware.sim.world import SimConfig
    from bearchair.hardware.speech import TextToSpeech

    return SimConfig(
        chair_path=config.chair_path,
        placement=config.placement,
        helper=config.helper,
        seed=config.seed,
        gui=config.gui,
        front_yaw_deg=front_yaw_deg,
        arena=config.arena,
        voice=TextToSpeech(mute=config.mute),
    )


def _open_world(sim_config: SimConfig) -> SimWorld:
    """The simulated world, unless a stop signal came
    before or while it was built (then it is closed and ``KeyboardInterrupt`` raised)."""
    from bearchair.hardware.sim.world import SimWorld

    raise_if_received()
    world = SimWorld(sim_config)
    try:
        raise_if_received()
    except BaseException:
        world.close()
        raise
    return world


def run_on_robots(
    config: RunConfig,
    cell_file: Path | Mapping[str, Any],
    skills: MissionSkills | None = None,
    on_tick: Callable[[MissionRunner], None] | None = None,
    confirm: Callable[[str], bool] | None = None,
    tree: TreeFactory | None = None,
) -> RunSummary:
    """Runs the mission on the real NAO and Panda described by ``cell_file`` (a cell
    file, or its fields: a configuration's ``[robots.cell]``).

    ``tree`` is the tree factory (None: the mission's ``create_tree``), called with
    ``config.tree_options`` before any robot is connected.

    The cell file is checked first; connecting moves nothing; the robots are activated
    (the NAO set up for carrying) only once ``confirm`` agrees (None: agreed, ``--yes``).

    Raises:
        executive.cell_config.CellConfigError: the cell file is wrong (one line).
        core.errors.BackendUnavailable: an SDK or a robot is missing, or the operator
            said no.
    """
    from bearchair.core.errors import BackendUnavailable
    from bearchair.executive.cell_config import load_cell_config, parse_cell_config
    from bearchair.hardware.real.robots import activate, connect_robots

    if isinstance(cell_file, Mapping):
        cell = parse_cell_config(dict(cell_file), config.arena)
    else:
        cell = load_cell_config(cell_file, config.arena)
    root = build_tree(tree or create_tree, config.tree_options, config.tree_spec)
    robot = connect_robots(cell, mute=config.mute)
    try:  # however it ends, the robots stop and the qi session closes before the exit
        if confirm is not None and not confirm(
            "The NAO and the Panda will move now. Go on? [y/N] "
        ):
            raise BackendUnavailable(
                f"the operator did not confirm: nothing moved{_why_not_asked()}"
            )
        try:
            activate(robot)
        except Exception as error:
            robot.emergency_stop()
            raise BackendUnavailable(f"could not set the NAO up for carrying: {error}") from error
        except BaseException:  # Ctrl-C while setting up: stop, then let it through
            robot.emergency_stop()
            raise
        return _record_on_robots(config, cell, cell_file, root, robot, skills, on_tick)
    finally:
        robot.close()


def _record_on_robots(
    config: RunConfig,
    cell: Any,
    cell_file: Path | Mapping[str, Any],
    root: Any,
    robot: Any,
    skills: MissionSkills | None,
    on_tick: Callable[[MissionRunner], None] | None,
) -> RunSummary:
    """The run record of a mission on the activated real robots, watched by the monitor."""
    from bearchair.hardware.real import sdk_versions
    from bearchair.hardware.real.monitor import RobotMonitor

    # Battery, falls, temperature and the arm's mode, watched for the whole run: a fault
    # stops the robots at once and the mission after that tick, with the reason.
    monitor = RobotMonitor(robot).start()
    on_tick = both(on_tick, monitor.check)
    recorder = RunRecorder(config.out_dir, root)
    write_config(config)
    write_text_atomic(config.out_dir / "cell.json", json.dumps(cell.to_json(), indent=2))
    run_info = RunInfo(
        chair="real",
        placement="real",
        helper="person",
        seed=config.seed,
        backend="real",
        tree=config.tree_spec,
        started_at=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        cell_file="inline ([robots.cell])" if isinstance(cell_file, Mapping) else str(cell_file),
        sdk_versions=sdk_versions(),
    )
    try:
        return _run_tree(root, recorder, robot, config, run_info, skills, on_tick, None)
    finally:
        monitor.close()


def _run_tree(
    root: Any,
    recorder: RunRecorder,
    robot: Any,
    config: RunConfig,
    run_info: RunInfo,
    skills: MissionSkills | None,
    on_tick: Callable[[MissionRunner], None] | None,
    render_png: Callable[[Path, RunSummary], None] | None,
    ground_truth: Callable[[RunSummary], GroundTruth] | None = None,
) -> RunSummary:
    """Ticks the tree on ``robot`` and writes the summary; the record survives any error."""
    recording = None
    groot2 = None
    try:
        if skills is None:
            skills = configured_skills(config)
        recording = open_recording(
            root, config.out_dir, record=config.record, live=config.live, bind=config.bind
        )
        if recording is not None:
            skills = recording.watch_skills(skills, robot.clock)
            if recording.viewer_url:
                print(f"live viewer: {recording.viewer_url}", file=sys.stderr, flush=True)
            if recording.viewer_hint:
                print(recording.viewer_hint, file=sys.stderr, flush=True)
        groot2 = open_groot2(root, config)
        runner = MissionRunner(
            root,
            skills,
            robot,
            seed=config.seed,
            arena=config.arena,
            recorder=recorder,
            timeout_s=config.timeout_s,
            tick_period_s=config.tick_period_s,
            on_tick=on_tick,
            post_tick=tuple(hook for hook in (recording, groot2) if hook is not None),
            on_second_signal=lambda outcome: recorder.write_summary(summarise(outcome, run_info)),
        )
        outcome = summarise(runner.run(), run_info)
        # The outcome first: a SIGKILL while the picture renders must not lose it.
        recorder.write_summary(outcome)
        summary = dataclasses.replace(
            outcome,
            picture=_final_picture(render_png, outcome, config.out_dir),
            ground_truth=_compared(ground_truth, outcome),
            recording=None if recording is None else recording.cost(),
        )
        if recording is not None:
            recording.log_summary(summary)
        recorder.write_summary(summary)
        if summary.record_error:
            raise RecordWriteError(f"{summary.record_error} (robots stopped)")
        return summary
    finally:
        recorder.close()
        if recording is not None:
            recording.close()
        if groot2 is not None:
            groot2.close()


FINAL_PICTURE = "final_scene.png"
"""The final scene's picture in the run folder (simulation only)."""


def _final_picture(
    render_png: Callable[[Path, RunSummary], None] | None, summary: RunSummary, out_dir: Path
) -> str | None:
    """Renders the final scene beside the record; its file name, or None when not drawn."""
    if render_png is None:
        return None
    try:
        with atomic_path(out_dir / FINAL_PICTURE) as scratch:
            render_png(scratch, summary)
    except Exception as error:  # a missing picture must not lose the record
        logger.warning("could not render the final scene: %s", error)
        return None
    return FINAL_PICTURE


def _compared(
    ground_truth: Callable[[RunSummary], GroundTruth] | None, summary: RunSummary
) -> GroundTruth | None:
    """The comparison with the simulated world's truth, or None (none, or it failed)."""
    if ground_truth is None:
        return None
    try:
        return ground_truth(summary)
    except Exception as error:  # nor must a missing comparison
        logger.warning("could not compare with the ground truth: %s", error)
        return None


def open_groot2(root: Any, config: RunConfig) -> Any:
    """The Groot2 publisher of the run's tree (``--groot2``), or None when not asked for."""
    if config.groot2_port is None:
        return None
    from bearchair.executive.groot2 import Groot2Monitor

    monitor = Groot2Monitor(root, config.groot2_port, config.groot2_bind)
    where = " (it listens on every interface)" if monitor.every_interface else ""
    print(f"Groot2: connect to {monitor.address}{where}", file=sys.stderr, flush=True)
    return monitor


def configured_skills(config: RunConfig) -> MissionSkills:
    """The default skills with ``config``'s parameters, the skill plug-ins stacked over
    them, warming up.

    Raises:
        PluginError: a skill plug-in is missing or does not satisfy the protocol.
    """
    # Imported only when a mission runs: it imports every skill (about 2 s).
    from bearchair.skills.default_skills import DefaultSkills
    from bearchair.skills.skill_sets import apply_skill_plugins

    defaults = DefaultSkills(
        imagination_workers=config.imagination_workers, parameters=config.skill_parameters
    )
    defaults.warm_up()
    return apply_skill_plugins(defaults, config.skill_plugins)


def summary_before_start(
    root: Any, run_info: RunInfo, error: BaseException, doing: str
) -> RunSummary:
    """The summary of a run that ended before its first tick (Ctrl-C, a failed world)."""
    from py_trees.common import Status

    from bearchair.executive.runner import MissionOutcome, StageTiming

    interrupted = isinstance(error, KeyboardInterrupt)
    outcome = MissionOutcome(
        status=Status.FAILURE,
        stages=[StageTiming(child.name) for child in root.children],
        ticks=0,
        wall_s=0.0,
        interrupted=interrupted,
        stop_signal=signal_name(getattr(error, "signum", signal.SIGINT)) if interrupted else None,
    )
    reason = (
        f"interrupted while {doing}" if interrupted else f"failed while {doing}: {one_line(error)}"
    )
    return dataclasses.replace(summarise(outcome, run_info), reason=reason)


def _ground_truth(world: Any, summary: RunSummary) -> GroundTruth:
    """What only the simulated world knows, at the end of the run: the chair's true
    sitting direction, how far the mission's sitting pose was from it (degrees), and how
    deep the NAO went into the chair (centimetres; the simulated chair does not move),
    with which link and in which stage (the world's clock is the robot's), and how far
    apart its palms held the bear (centimetres; the simulated bear cannot slip out)."""
    true_yaw = world.sitting_yaw_true()
    touch = world.chair_touch.deepest
    palms = world.palms_apart.widest
    error_deg = None
    pose = summary.sitting_pose
    if true_yaw is not None and pose is not None:
        error = wrap_angle(math.radians(pose.yaw_deg) - true_yaw)
        error_deg = round(abs(math.degrees(error)), 2)
    return GroundTruth(
        sitting_yaw_deg=None if true_yaw is None else round(math.degrees(true_yaw), 2),
        sitting_yaw_error_deg=error_deg,
        nao_into_chair_cm=round(100.0 * touch.depth_m, 2),
        nao_into_chair_link=touch.nao_link,
        nao_into_chair_stage=summary.stage_at(touch.time_s) if touch.nao_link else "",
        palms_apart_handed_over_cm=round(100.0 * palms.handed_over_m, 2),
        palms_apart_max_cm=round(100.0 * palms.widest_m, 2),
        palms_apart_stage=summary.stage_at(palms.time_s) if palms.widest_m else "",
    )


def format_summary(summary: RunSummary) -> str:
    """The per-stage table printed at the end of ``bearchair run``."""
    info = summary.info
    lines = [
        f"chair {info.chair} | placement {info.placement} | helper {info.helper} "
        f"| seed {info.seed}",
        f"{'stage':<20} {'status':<8} {'wall s':>7} {'robot s':>7}  outputs",
    ]
    for stage in summary.stages:
        robot_text = "" if stage.robot_seconds is None else f"{stage.robot_seconds:.2f}"
        lines.append(
            f"{stage.name:<20} {stage.status:<8} {stage.seconds:>7.2f} "
            f"{robot_text:>7}  {stage.message}"
        )
    for sentence in summary.instructions:
        lines.append(f'said: "{sentence}"')
    truth = summary.ground_truth
    if truth is not None and truth.nao_into_chair_cm:
        lines.append(
            f"ground truth: the NAO's {truth.nao_into_chair_link} went "
            f"{truth.nao_into_chair_cm:.1f} cm into the chair"
            + (f" during {truth.nao_into_chair_stage}" if truth.nao_into_chair_stage else "")
            + " (the simulated chair does not move)"
        )
    if truth is not None and truth.palms_apart_max_cm >= truth.palms_apart_handed_over_cm + 0.1:
        lines.append(
            f"ground truth: the NAO's palms held the bear {truth.palms_apart_max_cm:.1f} cm "
            f"apart"
            + (f" during {truth.palms_apart_stage}" if truth.palms_apart_stage else "")
            + f" (handed over at {truth.palms_apart_handed_over_cm:.1f} cm; the simulated bear "
            "cannot slip out)"
        )
    outcome = summary.outcome.upper()
    if summary.succeeded:
        lines.append(f"outcome: {outcome} in {summary.wall_seconds:.1f} s wall")
    else:
        where = summary.failed_stage or "the start"
        lines.append(f"outcome: {outcome} at {where}: {summary.reason}")
    return "\n".join(printable(line, 1000) for line in lines)


def default_out_dir(config: RunConfig) -> Path:
    """``runs/<date>-<time>-seed<N>``: a new directory per run, made now (unique)."""
    from bearchair.executive.outputs import default_run_dir

    return default_run_dir(config.seed)


def _why_not_asked() -> str:
    from bearchair.executive.operator import not_asked_because

    reason = not_asked_because()
    return f" ({reason})" if reason else ""
