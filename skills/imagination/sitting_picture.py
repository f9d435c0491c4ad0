"""A picture of the imagined sitting: the chair, the agent at g = (p, γ) and an arrow.

Drawn with matplotlib (Agg) in two orthographic 2D views with metric axes: from above
(x, y) and from the side (along the sitting direction, and z). The agent is drawn in its
key sitting configuration as a stick figure (pelvis, torso, head, thighs, shanks). The
one renderer of imagined poses: ``bearchair imagine --image`` and the trials report
(``bearchair.evaluation.pictures``) both draw with :func:`render_sitting`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np
import trimesh

from bearchair.core.errors import RenderError
from bearchair.core.geometry import SittingPose, rot_z
from bearchair.skills.imagination.agent import JOINTS

_MAX_FACES = 6000


def agent_key_points(sitting_pose: SittingPose) -> dict[str, np.ndarray]:
    """Stick-figure segments of the agent at the sitting pose, in the mesh frame.

    Returns:
        Segment name -> (2, 3) end points (metres).
    """
    key = {joint.name: joint.key_rad for joint in JOINTS}
    chest = key["chest_pitch"]

    def pitch(angle: float, vector: tuple[float, float, float]) -> np.ndarray:
        c, s = math.cos(angle), math.sin(angle)
        x, y, z = vector
        return np.array([c * x + s * z, y, -s * x + c * z])

    pelvis = np.zeros(3)
    chest_base = np.array([0.0, 0.0, 0.05])
    neck = chest_base + pitch(chest, (0.0, 0.0, 0.20))
    head = neck + pitch(chest + key["neck_pitch"], (0.0, 0.0, 0.10))
    segments = {
        "torso": (pelvis, neck),
        "neck": (neck, head),
    }
    for side, y in (("left", 0.055), ("right", -0.055)):
        hip = np.array([0.0, y, -0.03])
        knee = hip + pitch(key[f"{side}_hip_pitch"], (0.20, 0.0, 0.0))
        foot = knee + pitch(key[f"{side}_hip_pitch"] + key[f"{side}_knee_pitch"], (0.0, 0.0, -0.23))
        segments[f"{side}_thigh"] = (hip, knee)
        segments[f"{side}_shank"] = (knee, foot)
        segments[f"{side}_hip"] = (pelvis, hip)
    R = rot_z(sitting_pose.yaw)
    return {
        name: np.array([R @ a + sitting_pose.position, R @ b + sitting_pose.position])
        for name, (a, b) in segments.items()
    }


SITTING_COLOUR = "tab:red"
AGENT_COLOUR = "saddlebrown"
CHAIR_FACE = (0.45, 0.55, 0.75, 0.30)
ARROW_M = 0.25
"""The sitting direction's arrow, metres (the agent's thigh and a quarter)."""


def render_sitting(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose | None, path: str | Path, title: str = ""
) -> Path:
    """Writes a PNG of the chair from above and from the side, with the agent and its
    sitting direction when there is a pose.

    Args:
        chair_mesh: the chair in the frame of the pose (metres, z up).
        sitting_pose: g in the mesh frame, or None (the chair alone is drawn; the side
            view then looks along +x).
        path: the PNG to write.
        title: a line above the figure.

    Raises:
        RenderError: matplotlib is not installed (the message names the extra).
    """
    plt = _pyplot()
    mesh = chair_mesh
    if len(mesh.faces) > _MAX_FACES:
        keep = np.random.default_rng(0).choice(len(mesh.faces), _MAX_FACES, replace=False)
        mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[np.sort(keep)], process=False)
    triangles = np.asarray(mesh.vertices, dtype=float)[np.asarray(mesh.faces, dtype=int)]
    yaw = 0.0 if sitting_pose is None else float(sitting_pose.yaw)
    origin = np.zeros(3) if sitting_pose is None else np.asarray(sitting_pose.position, float)
    forward = np.array([math.cos(yaw), math.sin(yaw)])
    segments = [] if sitting_pose is None else list(agent_key_points(sitting_pose).values())

    figure, (top, side) = plt.subplots(1, 2, figsize=(11, 4.8))

    def along(points: np.ndarray) -> np.ndarray:
        return (points[..., :2] - origin[:2]) @ forward

    _draw_view(top, triangles[:, :, :2], [seg[:, :2] for seg in segments])
    side_triangles = np.stack([along(triangles), triangles[:, :, 2]], axis=-1)
    side_segments = [np.column_stack([along(seg), seg[:, 2]]) for seg in segments]
    _draw_view(side, side_triangles, side_segments)
    _label_views(top, side, "the sitting direction" if sitting_pose is not None else "x")
    if sitting_pose is not None:
        tip = origin[:2] + ARROW_M * forward
        _arrow(top, origin[:2], tip)
        _arrow(side, np.array([0.0, origin[2]]), np.array([ARROW_M, origin[2]]))
        x, y, z = origin
        caption = f"pelvis p = ({x:.2f}, {y:.2f}, {z:.2f}) m, facing {math.degrees(yaw):.0f} deg"
        title = f"{title}\n{caption}" if title else caption
        _fit(
            top, np.vstack([triangles[:, :, :2].reshape(-1, 2), tip, *[s[:, :2] for s in segments]])
        )
        _fit(side, np.vstack([side_triangles.reshape(-1, 2), [ARROW_M, z], *side_segments]))
    else:
        _fit(top, triangles[:, :, :2].reshape(-1, 2))
        _fit(side, side_triangles.reshape(-1, 2))
    if title:
        figure.suptitle(title)
    if segments:
        _legend_below(figure)
    else:
        figure.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=90)
    plt.close(figure)
    return path


def _label_views(top: Any, side: Any, horizontal: str) -> None:
    side.axhline(0.0, color="0.4", lw=1)  # the floor
    top.set_title("from above")
    top.set_xlabel("x (m)")
    top.set_ylabel("y (m)")
    side.set_title(f"from the side ({horizontal} to the right)")
    side.set_xlabel(f"along {horizontal} (m)")
    side.set_ylabel("z (m)")


def _legend_below(figure: Any) -> None:
    """What the agent's and the pose's colours are, under both views."""
    from matplotlib.lines import Line2D

    agent = Line2D([], [], color=AGENT_COLOUR, lw=3, label="the agent, seated")
    pose = Line2D([], [], color=SITTING_COLOUR, marker="o", label="pelvis p, sitting direction γ")
    figure.legend(handles=[agent, pose], loc="lower center", ncol=2, fontsize=9, frameon=False)
    figure.tight_layout(rect=(0.0, 0.06, 1.0, 1.0))  # room for the legend below


def _pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend, or a RenderError naming the extra."""
    try:
        import matplotlib
    except ImportError as error:
        raise RenderError(
            "the picture needs matplotlib: pip install 'bearchair[trials]'"
        ) from error
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _draw_view(axes: Any, polygons: np.ndarray, segments: list[np.ndarray]) -> None:
    """The chair's triangles (N, 3, 2) filled, the agent's segments (2, 2) over them."""
    from matplotlib.collections import PolyCollection

    axes.add_collection(
        PolyCollection(
            cast(Sequence[np.ndarray], polygons), facecolors=[CHAIR_FACE], edgecolors="none"
        )
    )
    for segment in segments:
        axes.plot(
            segment[:, 0], segment[:, 1], "-", color=AGENT_COLOUR, lw=3, solid_capstyle="round"
        )


def _arrow(axes: Any, start: np.ndarray, tip: np.ndarray) -> None:
    axes.plot(*start, "o", color=SITTING_COLOUR, ms=6)
    axes.annotate(
        "",
        xy=tuple(tip),
        xytext=tuple(start),
        annotation_clip=False,
        arrowprops={"arrowstyle": "-|>", "color": SITTING_COLOUR, "lw": 2},
    )


def _fit(axes: Any, points: np.ndarray, margin_m: float = 0.08) -> None:
    """Equal metric axes around ``points`` with a margin."""
    low = points.min(axis=0) - margin_m
    high = points.max(axis=0) + margin_m
    axes.set_xlim(low[0], high[0])
    axes.set_ylim(low[1], high[1])
    axes.set_aspect("equal")
