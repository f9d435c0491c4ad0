"""A picture of the imagined sitting: the chair, the agent at g = (p, γ) and an arrow.

Drawn with matplotlib (Agg) from three views: a perspective view, the top view and the
side view across the sitting direction. The agent is drawn in its key sitting
configuration as a stick figure (pelvis, torso, head, thighs, shanks).
"""

from __future__ import annotations

import math
from pathlib import Path

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


def render_sitting(
    chair_mesh: trimesh.Trimesh, sitting_pose: SittingPose | None, path: str | Path, title: str = ""
) -> Path:
    """Writes a PNG of the chair, and of the agent and its sitting direction when found.

    Args:
        chair_mesh: the chair in the frame of the pose.
        sitting_pose: g in the mesh frame, or None (the chair alone is drawn).
        path: the PNG to write.
        title: a line above the figure.
    """
    try:
        import matplotlib
    except ImportError as error:
        raise RenderError(
            "the picture needs matplotlib: pip install 'bearchair[trials]'"
        ) from error
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    mesh = chair_mesh
    if len(mesh.faces) > _MAX_FACES:
        keep = np.random.default_rng(0).choice(len(mesh.faces), _MAX_FACES, replace=False)
        mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[np.sort(keep)], process=False)
    triangles = mesh.vertices[mesh.faces]
    figure = plt.figure(figsize=(12, 4.5))
    views = [("perspective", 25, -60), ("top", 90, -90), ("side", 0, None)]
    side_azim = -90.0 if sitting_pose is None else math.degrees(sitting_pose.yaw) - 90.0
    lo, hi = chair_mesh.bounds
    centre = 0.5 * (lo + hi)
    half = 0.5 * float(max(hi - lo)) + 0.15
    for index, (name, elev, azim) in enumerate(views, start=1):
        axes = figure.add_subplot(1, 3, index, projection="3d")
        axes.add_collection3d(
            Poly3DCollection(triangles, facecolor=(0.6, 0.7, 0.85, 0.35), edgecolor="none")
        )
        if sitting_pose is not None:
            for segment in agent_key_points(sitting_pose).values():
                axes.plot(*segment.T, color="saddlebrown", linewidth=4)
            p = sitting_pose.position
            axes.scatter(*p, color="black", s=30)
            direction = 0.25 * np.array(
                [math.cos(sitting_pose.yaw), math.sin(sitting_pose.yaw), 0.0]
            )
            axes.quiver(*p, *direction, color="red", linewidth=2.5, arrow_length_ratio=0.3)
        axes.set_xlim(centre[0] - half, centre[0] + half)
        axes.set_ylim(centre[1] - half, centre[1] + half)
        axes.set_zlim(max(lo[2] - 0.05, centre[2] - half), centre[2] + half)
        axes.set_box_aspect((1, 1, 1))
        axes.view_init(elev=elev, azim=side_azim if azim is None else azim)
        axes.set_title(name)
        axes.set_xlabel("x (m)")
        axes.set_ylabel("y (m)")
    if title:
        figure.suptitle(title)
    figure.tight_layout()
    path = Path(path)
    figure.savefig(path, dpi=90)
    plt.close(figure)
    return path
