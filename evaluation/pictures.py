"""The report folder's pictures: the imagined sitting pose per chair, the final scene per trial.

The imagined-pose picture draws what the robot worked with: its reconstructed chair
(``chair_reconstructed.ply``, kept by the trial worker) and the sitting pose g = (p, γ)
of the trial's summary, both in that trial's world frame at the end of the trial, with
the renderer ``bearchair imagine --image`` uses
(``bearchair.skills.imagination.sitting_picture.render_sitting``).
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path
from typing import cast

import numpy as np

from bearchair.evaluation.trial_record import TrialRecord


def trial_picture_name(record: TrialRecord) -> str:
    """``<chair stem>-t<index>-seed<seed>.png``."""
    stem = record.chair.rsplit(".", 1)[0]
    return f"{stem}-t{record.trial_index}-seed{record.seed}.png"


def copy_trial_scenes(records: list[TrialRecord], trials_dir: Path) -> int:
    """Copies each trial's ``final_scene.png`` into ``trials_dir``; returns how many."""
    trials_dir.mkdir(parents=True, exist_ok=True)
    copied = 0
    for record in records:
        source = Path(record.run_dir or "") / "final_scene.png"
        if record.run_dir and source.is_file():
            shutil.copyfile(source, trials_dir / trial_picture_name(record))
            copied += 1
    return copied


def pose_record_for_chair(records: list[TrialRecord]) -> TrialRecord | None:
    """The trial whose imagined pose represents a chair: a drawable one, successes first."""
    drawable = [
        r
        for r in records
        if r.sitting_pose is not None
        and r.run_dir
        and (Path(r.run_dir) / "chair_reconstructed.ply").is_file()
    ]
    drawable.sort(key=lambda r: (not r.succeeded, r.trial_index))
    return drawable[0] if drawable else None


def render_chair_pictures(records: list[TrialRecord], chairs_dir: Path) -> dict[str, Path]:
    """One imagined-pose PNG per chair that has a drawable trial; chair name -> file."""
    chairs_dir.mkdir(parents=True, exist_ok=True)
    written = {}
    for chair in sorted({r.chair for r in records}):
        record = pose_record_for_chair([r for r in records if r.chair == chair])
        if record is None or record.sitting_pose is None or record.run_dir is None:
            continue
        import trimesh

        from bearchair.core.geometry import SittingPose
        from bearchair.skills.imagination.sitting_picture import render_sitting

        mesh = cast(
            "trimesh.Trimesh",  # force="mesh" makes it one
            trimesh.load(Path(record.run_dir) / "chair_reconstructed.ply", force="mesh"),
        )
        path = chairs_dir / f"{chair.rsplit('.', 1)[0]}.png"
        title = f"{chair}: trial {record.trial_index} ({record.experiment}), {record.outcome}"
        pose = record.sitting_pose
        sitting_pose = SittingPose(
            np.asarray(pose.position_m, dtype=float), math.radians(pose.yaw_deg)
        )
        render_sitting(mesh, sitting_pose, path, title)
        written[chair] = path
    return written
