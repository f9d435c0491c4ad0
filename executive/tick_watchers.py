"""What watches a mission each tick (the runner's ``on_tick``): the stage progress lines,
the stage snapshots, and the captioned scene pictures they draw."""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from bearchair.core.userfiles import printable
from bearchair.executive.records.run_summary import RunSummary
from bearchair.executive.runner import MissionRunner

if TYPE_CHECKING:
    from bearchair.hardware.sim.world import SimWorld

logger = logging.getLogger(__name__)


def stage_seconds_text(wall_s: float, robot_s: float | None) -> str:
    """``3.2 s wall, 8.9 s robot``: the two clocks a stage is timed on, each named (the
    robot's runs slower than the wall in simulation, and faster when rendering waits)."""
    text = f"{wall_s:.1f} s wall"
    return text if robot_s is None else f"{text}, {robot_s:.1f} s robot"


class StageProgress:
    """Prints a line whenever a stage starts or ends (long stages are the norm here),
    stamped with the run's wall seconds; an ended stage says its wall and robot seconds."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self._stream = stream
        self._seen: dict[str, str] = {}

    def __call__(self, runner: MissionRunner) -> None:
        for stage in runner.stages:
            if self._seen.get(stage.name) == stage.status or stage.status == "INVALID":
                continue
            self._seen[stage.name] = stage.status
            if stage.status == "RUNNING":
                line = f"[{runner.elapsed():7.1f} s] {stage.name} ..."
            else:
                took = stage_seconds_text(
                    stage.seconds,
                    None if stage.robot_started_s is None else stage.robot_seconds,
                )
                line = f"[{runner.elapsed():7.1f} s] {stage.name}: {stage.status} ({took}) {printable(stage.feedback, 400)}"
            try:
                print(line, file=self._stream or sys.stderr, flush=True)
            except (OSError, ValueError):  # nobody reads stderr any more: the run goes on
                self._stream = open(os.devnull, "w")  # noqa: SIM115 - lives with the run


class StageSnapshots:
    """Saves a picture of the scene whenever a stage ends (``bearchair run --snapshots``).

    The pictures go to ``out_dir`` as ``NN-<stage>-<status>.png`` (a perspective and a
    ``-top`` view): what the scene looked like when SeatBear finished, for example, which
    the final picture no longer shows. ``render(path, view=, stage=, status=, reason=)``
    draws one (:class:`ScenePictures`: captioned, with what the stage decided).
    """

    def __init__(self, render: Callable[..., object], out_dir: Path) -> None:
        self._render = render
        self._out_dir = out_dir
        self._seen: dict[str, str] = {}
        self.written: list[Path] = []

    def __call__(self, runner: MissionRunner) -> None:
        for stage in runner.stages:
            if (
                stage.status not in ("SUCCESS", "FAILURE")
                or self._seen.get(stage.name) == stage.status
            ):
                continue
            self._seen[stage.name] = stage.status
            stem = f"{len(self._seen):02d}-{stage.name}-{stage.status.lower()}"
            self._out_dir.mkdir(parents=True, exist_ok=True)
            for suffix, view in (("", "perspective"), ("-top", "top")):
                path = self._out_dir / f"{stem}{suffix}.png"
                reason = getattr(stage, "feedback", "")
                try:
                    self._render(
                        path, view=view, stage=stage.name, status=stage.status, reason=reason
                    )
                except Exception as error:  # a missing picture must not stop the mission
                    logger.warning("could not render %s: %s", path.name, error)
                    continue
                self.written.append(path)


class ScenePictures:
    """Pictures of the simulated scene with the mission's marks and a caption
    (``bearchair.executive.scene_picture``).

    Args:
        world: the simulated world (its ``render_scene`` and its clock).
        chair: the chair's name, for the caption.
        seed: the run's seed, for the caption.
    """

    def __init__(self, world: SimWorld, chair: str, seed: int) -> None:
        self._world = world
        self._chair = chair
        self._seed = seed

    def __call__(
        self,
        path: Path,
        view: str = "perspective",
        stage: str = "final",
        status: str = "",
        reason: str = "",
    ) -> list[str]:
        """Writes the picture at ``path``; returns the caption's lines."""
        from bearchair.executive import scene_picture

        frame = self._world.render_scene("top" if view == "top" else "perspective")
        caption = scene_picture.SceneCaption(
            self._chair, self._seed, stage, status, self._world.clock.now(), reason
        )
        return scene_picture.write(frame, scene_picture.SceneMarks.from_blackboard(), caption, path)

    def final(self, path: Path, summary: RunSummary) -> None:
        """The end of the run: its outcome, the failed stage and the reason (a success:
        what the last stage reported)."""
        status = summary.outcome.upper()
        if summary.failed_stage:
            status += f" at {summary.failed_stage}"
        reason = summary.reason
        if not reason and summary.stages:
            reason = summary.stages[-1].message
        self(path, "perspective", "final", status, reason)


def both(
    first: Callable[[MissionRunner], None] | None, second: Callable[[MissionRunner], None]
) -> Callable[[MissionRunner], None]:
    """One per-tick callback calling ``first`` (if any), then ``second``."""

    def call(runner: MissionRunner) -> None:
        if first is not None:
            first(runner)
        second(runner)

    return call
