"""The report folder's pictures: the imagined sitting pose per chair, the final scene per trial.

The imagined-pose picture draws what the robot worked with: its reconstructed chair
(``chair_reconstructed.ply``, kept by the trial worker) and the sitting pose g = (p, γ)
of the trial's summary, both in that trial's world frame at the end of the trial. Two
orthographic views: from above, and from the side (perpendicular to the sitting
direction), with the pelvis p, the sitting direction and a stick figure of a seated
sitter.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np

SITTER_TORSO_M = 0.25
SITTER_THIGH_M = 0.16
SITTER_SHIN_M = 0.15
PLOTS_HINT = "plots need matplotlib: pip install 'bearchair[trials]'"


def trial_picture_name(record: dict[str, Any]) -> str:
    """``<chair stem>-t<index>-seed<seed>.png``."""
    stem = record["chair"].rsplit(".", 1)[0]
    return f"{stem}-t{record['trial_index']}-seed{record['seed']}.png"


def copy_trial_scenes(records: list[dict[str, Any]], trials_dir: Path) -> int:
    """Copies each trial's ``final_scene.png`` into ``trials_dir``; returns how many."""
    trials_dir.mkdir(parents=True, exist_ok=True)
    copied = 0
    for record in records:
        source = Path(record.get("run_dir") or "") / "final_scene.png"
        if record.get("run_dir") and source.is_file():
            shutil.copyfile(source, trials_dir / trial_picture_name(record))
            copied += 1
    return copied


def pose_record_for_chair(records: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The trial whose imagined pose represents a chair: a drawable one, successes first."""
    drawable = [
        r
        for r in records
        if r.get("sitting_pose")
        and r.get("run_dir")
        and (Path(r["run_dir"]) / "chair_reconstructed.ply").is_file()
    ]
    drawable.sort(key=lambda r: (r["outcome"] != "success", r["trial_index"]))
    return drawable[0] if drawable else None


def render_chair_pictures(records: list[dict[str, Any]], chairs_dir: Path) -> dict[str, Path]:
    """One imagined-pose PNG per chair that has a drawable trial; chair name -> file."""
    chairs_dir.mkdir(parents=True, exist_ok=True)
    written = {}
    for chair in sorted({r["chair"] for r in records}):
        record = pose_record_for_chair([r for r in records if r["chair"] == chair])
        if record is None:
            continue
        import trimesh

        mesh = cast(
            "trimesh.Trimesh",  # force="mesh" makes it one
            trimesh.load(Path(record["run_dir"]) / "chair_reconstructed.ply", force="mesh"),
        )
        path = chairs_dir / f"{chair.rsplit('.', 1)[0]}.png"
        title = (
            f"{chair}: trial {record['trial_index']} ({record['experiment']}), {record['outcome']}"
        )
        render_imagined_pose(
            np.asarray(mesh.vertices), np.asarray(mesh.faces), record["sitting_pose"], path, title
        )
        written[chair] = path
    return written


def sitter_stick_figure(position: np.ndarray, yaw_rad: float) -> np.ndarray:
    """(4, 3) points head-pelvis-knee-foot of a sitter at pelvis ``position`` facing ``yaw``."""
    forward = np.array([math.cos(yaw_rad), math.sin(yaw_rad), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    pelvis = np.asarray(position, dtype=float)
    head = pelvis + SITTER_TORSO_M * up
    knee = pelvis + SITTER_THIGH_M * forward
    foot = knee - SITTER_SHIN_M * up
    return np.stack([head, pelvis, knee, foot])


def render_imagined_pose(
    vertices: np.ndarray,
    faces: np.ndarray,
    sitting_pose: dict[str, Any],
    path: Path,
    title: str = "",
) -> None:
    """Draws a chair mesh and a sitting pose from above and from the side into a PNG.

    Args:
        vertices: (V, 3) chair vertices, world frame, metres.
        faces: (F, 3) triangle indices.
        sitting_pose: ``{"position_m": [x, y, z], "yaw_deg": γ}`` in the same frame.
        path: the PNG to write.
        title: the figure's title.

    Raises:
        ImportError: matplotlib is not installed (the message names the extra).
    """
    plt = _pyplot()
    position = np.asarray(sitting_pose["position_m"], dtype=float)
    yaw = math.radians(float(sitting_pose["yaw_deg"]))
    forward = np.array([math.cos(yaw), math.sin(yaw)])
    sitter = sitter_stick_figure(position, yaw)
    triangles = np.asarray(vertices, dtype=float)[np.asarray(faces, dtype=int)]

    figure, (top, side) = plt.subplots(1, 2, figsize=(10, 4.8))
    _draw_from_above(top, triangles, sitter, position, forward)
    _draw_from_the_side(side, triangles, sitter, position, forward)
    figure.suptitle(
        (title + "\n" if title else "")
        + f"pelvis ({position[0]:.2f}, {position[1]:.2f}, {position[2]:.2f}) m, "
        f"facing {math.degrees(yaw):.0f} deg"
    )
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=90)
    plt.close(figure)


def _pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend, or an ImportError naming the extra."""
    try:
        import matplotlib
    except ImportError as error:
        raise ImportError(PLOTS_HINT) from error
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _draw_from_above(
    axes: Any, triangles: np.ndarray, sitter: np.ndarray, position: np.ndarray, forward: np.ndarray
) -> None:
    """The top view, x right and y up: the chair, the sitter's legs and the sitting direction."""
    from matplotlib.collections import PolyCollection

    axes.add_collection(
        PolyCollection(
            _polygons(triangles[:, :, :2]), facecolors="0.75", edgecolors="none", alpha=0.35
        )
    )
    axes.plot(sitter[1:, 0], sitter[1:, 1], "-", color="tab:red", lw=2)
    axes.plot(*position[:2], "o", color="tab:red")
    axes.annotate(
        "",
        xy=tuple(position[:2] + 0.25 * forward),
        annotation_clip=False,
        xytext=tuple(position[:2]),
        arrowprops={"arrowstyle": "->", "color": "tab:red", "lw": 2},
    )
    axes.set_title("from above (world x, y)")
    axes.set_xlabel("x (m)")
    axes.set_ylabel("y (m)")
    arrow_tip = position[:2] + 0.25 * forward
    _fit(axes, np.vstack([triangles[:, :, :2].reshape(-1, 2), sitter[:, :2], arrow_tip]))


def _draw_from_the_side(
    axes: Any, triangles: np.ndarray, sitter: np.ndarray, position: np.ndarray, forward: np.ndarray
) -> None:
    """The side view: horizontal along the sitting direction, vertical z; chair and sitter."""
    from matplotlib.collections import PolyCollection

    def along(points: np.ndarray) -> np.ndarray:
        return (points[..., :2] - position[:2]) @ forward

    side_polys = np.stack([along(triangles), triangles[:, :, 2]], axis=-1)
    axes.add_collection(
        PolyCollection(_polygons(side_polys), facecolors="0.75", edgecolors="none", alpha=0.35)
    )
    axes.plot(along(sitter), sitter[:, 2], "-o", color="tab:red", lw=2, ms=3)
    axes.axhline(0.0, color="0.4", lw=1)
    axes.set_title("from the side (sitting direction to the right)")
    axes.set_xlabel("along the sitting direction (m)")
    axes.set_ylabel("z (m)")
    _fit(
        axes, np.vstack([side_polys.reshape(-1, 2), np.column_stack([along(sitter), sitter[:, 2]])])
    )


def _polygons(vertices: np.ndarray) -> Sequence[np.ndarray]:
    """``vertices`` (N polygons, M vertices, 2) as matplotlib's stubs type PolyCollection's
    ``verts``: they ask for a Sequence, and it takes the array as it is."""
    return cast(Sequence[np.ndarray], vertices)


def _fit(axes: Any, points: np.ndarray, margin_m: float = 0.08) -> None:
    low = points.min(axis=0) - margin_m
    high = points.max(axis=0) + margin_m
    axes.set_xlim(low[0], high[0])
    axes.set_ylim(low[1], high[1])
    axes.set_aspect("equal")
