"""Scene pictures that explain: what the mission decided drawn over the simulated scene,
and a caption saying which run, which stage, how it ended and when.

Overlays, all in the world frame and projected with the picture's own camera: the
planned SE(2) path of the humanoid (blue, waypoints as dots), its SE(2) goal (green
arrow: where it stands and which way it faces) and the imagined sitting pose
g = (p, γ) (red dot at the pelvis p, arrow along the sitting direction γ). The caption,
a dark band below the picture, names the chair, the seed, the stage and its status, the
robot's clock (simulated seconds since the world was built), the reason of a refusal or
failure, and the colours. Only what the mission wrote on its blackboard is drawn, never
the simulated world's truth.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NamedTuple, Protocol

import numpy as np
import py_trees
from PIL import Image, ImageDraw, ImageFont

from bearchair.behaviours import keys

PATH_COLOUR = (31, 119, 180)
GOAL_COLOUR = (44, 160, 44)
SITTING_COLOUR = (214, 39, 40)
CAPTION_BACKGROUND = (34, 34, 34)
CAPTION_TEXT = (240, 240, 240)
REASON_TEXT = (255, 170, 90)
CAPTION_FONT_PX = 18
ARROW_M = 0.25
"""Length of the goal's and the sitting direction's arrows, metres (about the NAO's
foot length and a half: visible from 4 m without hiding the chair)."""
LEGEND = (
    "blue: planned SE(2) path   green: SE(2) goal (the NAO's footprint)   "
    "red: sitting pose g (pelvis p, direction)"
)
FLOOR_MARK_M = 0.01
"""Height at which floor marks are drawn, metres (above the floor, under everything else)."""


class Frame(Protocol):
    """A picture with its camera (``bearchair.hardware.sim.camera.SceneFrame``)."""

    @property
    def rgb(self) -> np.ndarray: ...

    def project(self, points_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


class SceneMarks(NamedTuple):
    """What the mission decided, in the world frame, to draw over the scene.

    Attributes:
        path_xy: (N, 2) planned waypoints of the humanoid, metres (N may be 0).
        goal: (x, y, θ) where the humanoid stands to seat the bear, or None.
        sitting: (x, y, z, γ) the imagined sitting pose, or None.
    """

    path_xy: np.ndarray
    goal: tuple[float, float, float] | None
    sitting: tuple[float, float, float, float] | None

    @classmethod
    def from_blackboard(cls, storage: dict[str, Any] | None = None) -> SceneMarks:
        """The marks as the mission's blackboard holds them now (empty before it has any)."""
        board = py_trees.blackboard.Blackboard.storage if storage is None else storage
        access = board.get(keys.ACCESSIBILITY)
        goal = board.get(keys.SE2_GOAL) or getattr(access, "se2_goal", None)
        path = [(w.x, w.y) for w in getattr(access, "path", ())]
        if goal is not None and path:
            path.append((goal.x, goal.y))  # the last straight step in, if any
        pose = board.get(keys.SITTING_POSE)
        return cls(
            np.asarray(path, dtype=float).reshape(-1, 2),
            None if goal is None else (float(goal.x), float(goal.y), float(goal.theta)),
            None if pose is None else (*(float(v) for v in pose.position[:3]), float(pose.yaw)),  # type: ignore[return-value]
        )


class SceneCaption(NamedTuple):
    """The caption's facts.

    Attributes:
        chair: the chair's name.
        seed: the run's seed.
        stage: the stage just ended (``final`` for the end of the run).
        status: SUCCESS, FAILURE, ...
        robot_s: the robot's clock, seconds.
        reason: why it failed or refused; for a success, what the stage reports
            (its feedback message); empty for none.
    """

    chair: str
    seed: int
    stage: str
    status: str
    robot_s: float
    reason: str = ""

    def lines(self, width_chars: int = 96) -> list[str]:
        """The caption's text, line by line (the reason wrapped, then the legend)."""
        first = (
            f"{self.chair} | seed {self.seed} | {self.stage}: {self.status} "
            f"| robot time {self.robot_s:.1f} s"
        )
        prefix = "why: " if self.failed else ""
        why = textwrap.wrap(prefix + self.reason, width_chars)[:3] if self.reason else []
        return [first, *why, LEGEND]

    @property
    def failed(self) -> bool:
        return "FAILURE" in self.status


def compose(
    frame: Frame, marks: SceneMarks, caption: SceneCaption
) -> tuple[Image.Image, list[str]]:
    """The frame with the marks drawn over it and the caption below; and the caption's lines."""
    picture = Image.fromarray(np.ascontiguousarray(frame.rgb)).convert("RGB")
    draw = ImageDraw.Draw(picture)
    width_px = max(2, picture.width // 320)
    _draw_path(draw, frame, marks.path_xy, width_px)
    if marks.goal is not None:
        _draw_footprint(draw, frame, marks.goal, width_px)
    if marks.sitting is not None:
        x, y, z, yaw = marks.sitting
        _draw_arrow(draw, frame, (x, y, z), yaw, SITTING_COLOUR, width_px, "g")
    lines = caption.lines()
    return _with_caption(picture, lines, caption.failed), lines


def write(frame: Frame, marks: SceneMarks, caption: SceneCaption, path: Path) -> list[str]:
    """Writes :func:`compose`'s picture as a PNG; returns the caption's lines drawn."""
    picture, lines = compose(frame, marks, caption)
    picture.save(path, format="PNG")
    return lines


def _font(size_px: int) -> ImageFont.ImageFont | ImageFont.FreeTypeFont:
    try:
        return ImageFont.load_default(size=size_px)
    except (TypeError, OSError):  # a Pillow without FreeType: its fixed bitmap font
        return ImageFont.load_default()


def _draw_path(draw: ImageDraw.ImageDraw, frame: Frame, path_xy: np.ndarray, width_px: int) -> None:
    if len(path_xy) == 0:
        return
    points = np.column_stack([path_xy, np.full(len(path_xy), FLOOR_MARK_M)])
    pixels, in_front = frame.project(points)
    visible = [tuple(p) for p, ok in zip(pixels.tolist(), in_front, strict=True) if ok]
    if len(visible) >= 2:
        draw.line(visible, fill=PATH_COLOUR, width=width_px, joint="curve")
    radius = width_px + 1
    for u, v in visible:
        draw.ellipse((u - radius, v - radius, u + radius, v + radius), fill=PATH_COLOUR)


def _draw_footprint(
    draw: ImageDraw.ImageDraw, frame: Frame, goal: tuple[float, float, float], width_px: int
) -> None:
    """The SE(2) goal as the planner sees the NAO there: its ellipse on the floor
    (``skills.planning.collision``), a dot at the goal and a tick toward its heading."""
    from bearchair.skills.planning.collision import NAO_CENTRE_FORWARD_M, NAO_SEMI_AXES_M

    x, y, theta = goal
    heading = np.array([math.cos(theta), math.sin(theta)])
    lateral = np.array([-heading[1], heading[0]])
    centre = np.array([x, y]) + NAO_CENTRE_FORWARD_M * heading
    angles = np.linspace(0.0, 2.0 * math.pi, 48)
    outline = (
        centre
        + np.outer(NAO_SEMI_AXES_M[0] * np.cos(angles), heading)
        + np.outer(NAO_SEMI_AXES_M[1] * np.sin(angles), lateral)
    )
    pixels, in_front = frame.project(
        np.column_stack([outline, np.full(len(outline), FLOOR_MARK_M)])
    )
    if in_front.all():
        draw.line([tuple(p) for p in pixels.tolist()], fill=GOAL_COLOUR, width=width_px)
    tick_m = NAO_SEMI_AXES_M[0]
    _draw_arrow(draw, frame, (x, y, FLOOR_MARK_M), theta, GOAL_COLOUR, width_px, "goal", tick_m)


def _draw_arrow(
    draw: ImageDraw.ImageDraw,
    frame: Frame,
    base: Sequence[float],
    yaw_rad: float,
    colour: tuple[int, int, int],
    width_px: int,
    label: str,
    length_m: float = ARROW_M,
) -> None:
    """An arrow of ``length_m`` from ``base`` along ``yaw_rad``, a dot and a label at its base."""
    start = np.asarray(base, dtype=float)
    tip = start + length_m * np.array([math.cos(yaw_rad), math.sin(yaw_rad), 0.0])
    (a, b), in_front = frame.project(np.stack([start, tip]))
    if not in_front.all():
        return
    draw.line([tuple(a), tuple(b)], fill=colour, width=width_px + 1)
    direction = (b - a) / max(float(np.linalg.norm(b - a)), 1e-6)
    normal = np.array([-direction[1], direction[0]])
    head = 6.0 * width_px
    draw.polygon(
        [
            tuple(b),
            tuple(b - head * direction + 0.6 * head * normal),
            tuple(b - head * direction - 0.6 * head * normal),
        ],
        fill=colour,
    )
    radius = 2.5 * width_px
    draw.ellipse((a[0] - radius, a[1] - radius, a[0] + radius, a[1] + radius), fill=colour)
    draw.text(
        (a[0] + 2 * radius, a[1] + radius), label, fill=colour, font=_font(CAPTION_FONT_PX - 2)
    )


def _with_caption(picture: Image.Image, lines: list[str], failed: bool) -> Image.Image:
    """The picture over a dark band holding ``lines`` (a failure's reason in orange)."""
    font = _font(CAPTION_FONT_PX)
    line_px = CAPTION_FONT_PX + 6
    band_px = 10 + line_px * len(lines)
    out = Image.new("RGB", (picture.width, picture.height + band_px), CAPTION_BACKGROUND)
    out.paste(picture, (0, 0))
    draw = ImageDraw.Draw(out)
    for number, line in enumerate(lines):
        colour = REASON_TEXT if failed and 0 < number < len(lines) - 1 else CAPTION_TEXT
        draw.text((10, picture.height + 6 + number * line_px), line, fill=colour, font=font)
    return out
