"""The simulated world: the embedded default backend of the mission.

A pybullet scene (DIRECT by default, GUI on request) with the floor, the planning
arena's walls and obstacles, a Franka Panda with a wrist Carmine camera, a chair from
any mesh, a NAO carrying a teddy bear with an ArUco tag on its head, and a helper who
turns the chair when told. Every device implements a protocol of
:mod:`bearchair.hardware.interfaces`; :attr:`SimWorld.robot` bundles them for the executive.
Everything random is drawn from generators spawned from ``SimConfig.seed``.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import pybullet
import pybullet_data
import trimesh
from PIL import Image

from bearchair.core.arena import DEFAULT_ARENA, HUMANOID_TAG, Arena, accessible_sitting_yaws
from bearchair.core.bullet_poses import matrix_to_pose, pose_to_matrix
from bearchair.core.geometry import make_transform, rot_z, wrap_angle, yaw_of
from bearchair.core.meshes import box_chair_mesh, load_mesh
from bearchair.core.nao_carrying import BEAR_SEAT_BELOW_HANDS_M
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import CameraIntrinsics, Robot, Speaker
from bearchair.hardware.sim.bear import SimBear
from bearchair.hardware.sim.bullet import LockedBullet
from bearchair.hardware.sim.camera import SceneFrame, render_view
from bearchair.hardware.sim.chair import SimChair
from bearchair.hardware.sim.chair_set_down import (
    SET_DOWN_CLEARANCE_M,
    SET_DOWN_DRAWS,
    chair_surface_points,
    clearance_to,
    link_boxes,
    slid_clear_of_arm,
)
from bearchair.hardware.sim.clock import SimClock
from bearchair.hardware.sim.contacts import ChairTouchMonitor
from bearchair.hardware.sim.grip import T_WRIST_PALM, PalmsApartMonitor
from bearchair.hardware.sim.helper import SimHelper, SimSpeaker
from bearchair.hardware.sim.judge import SimJudge
from bearchair.hardware.sim.nao import SimNao
from bearchair.hardware.sim.nao_urdf import nao_urdf
from bearchair.hardware.sim.panda import SimPanda
from bearchair.hardware.sim.tag import tag_assets

log = logging.getLogger(__name__)

TAPE_HEIGHT_M = 0.002
TAPE_WIDTH_M = 0.03
"""The arena's boundary is tape on the floor, as in the paper's lab (red dashed lines): the
planner keeps the humanoid inside it, but the chair may stand across it."""
PLACEMENT_TOLERANCE_DEG = 30.0
SETTLE_S = 0.5
PERSPECTIVE_PITCH_RAD = math.radians(45.0)
"""How far the report's perspective camera looks down. With the 46.8 degree vertical
field of view its top row is 21.6 degrees below the horizon, so from the eye's height
it meets the floor inside the renderer's 8 m far plane: no blank band at the top."""


@dataclass(frozen=True)
class SimConfig:
    """How to build the simulated world.

    Attributes:
        chair_path: a chair mesh (OBJ, PLY, STL, OFF, GLB); None for the box chair.
        placement: "accessible": the chair's sitting direction is within ±30 deg of the
            direction from the chair to the humanoid's start; "inaccessible": it points
            toward the arm (-x) or the nearer side edge of the arena (±y), ±30 deg, chosen
            by the seed.
        helper: how the helper reacts to instructions.
        seed: seeds every random choice.
        gui: open pybullet's GUI (paced to wall-clock time) instead of DIRECT.
        camera_noise: apply the Carmine noise model to captures.
        front_yaw_deg: the mesh's sitting direction in its own frame (from the manifest);
            the box chair's is 0. None: the placement yaw is random (with a warning).
        arena: the workspace layout.
        voice: speaks sentences aloud; None prints them.
    """

    chair_path: Path | None = None
    placement: Literal["accessible", "inaccessible"] = "accessible"
    helper: Literal["obeys", "disobeys", "ignores"] = "obeys"
    seed: int = 0
    gui: bool = False
    camera_noise: bool = True
    front_yaw_deg: float | None = None
    arena: Arena = DEFAULT_ARENA
    voice: Speaker | None = None


class SimWorld:
    """Builds and owns the whole simulated scene. Use as a context manager or call close().

    Attributes:
        config: what was built.
        robot: the devices bundled for the executive (arm, humanoid, speaker, clock,
            helper, judge).
        panda, nao, bear, chair, helper, speaker, clock, judge: the devices themselves.
        floor: the floor's body id.
        front_yaw_rad: the chair mesh's sitting direction in the chair frame (None if unknown).
        placement_yaw_rad: the yaw the chair was placed with.
    """

    def __init__(self, config: SimConfig) -> None:
        if config.placement not in ("accessible", "inaccessible"):
            raise ValueError(f"unknown placement {config.placement!r} (accessible or inaccessible)")
        self.config = config
        self._hands_cache: tuple[int, np.ndarray] | None = None
        self._hands_in_feet: tuple[int, np.ndarray] | None = None
        self._surface_cache: np.ndarray | None = None
        chair_mesh = box_chair_mesh() if config.chair_path is None else load_mesh(config.chair_path)
        front_yaw_deg = (
            0.0
            if config.chair_path is None and config.front_yaw_deg is None
            else (config.front_yaw_deg)
        )
        self.front_yaw_rad = None if front_yaw_deg is None else math.radians(front_yaw_deg)
        streams = np.random.SeedSequence(config.seed).spawn(5)
        placement_rng, camera_rng, nao_rng, helper_rng, _ = (
            np.random.default_rng(stream) for stream in streams
        )

        self._bullet = LockedBullet(gui=config.gui)
        bullet = self._bullet
        try:
            with bullet.lock:
                bullet.setGravity(0.0, 0.0, -9.81)
                if config.gui:
                    bullet.configureDebugVisualizer(pybullet.COV_ENABLE_GUI, 0)
                self.clock = SimClock(bullet, realtime=config.gui)
                self.floor = self._build_floor()
                self.walls = self._build_walls(config.arena)
                self.panda = SimPanda(
                    bullet, self.clock, config.arena.arm_base_xy, camera_rng, config.camera_noise
                )
                T_world_chair = self._placement(config, placement_rng)
                self.chair = SimChair(bullet, chair_mesh, T_world_chair)
                self.nao = self._build_nao(config.arena.humanoid_start, nao_rng)
                self._ignore_floor(self.nao.body, self.panda.body)
                self._build_bear_helper_and_judge(config, helper_rng)
                self._set_down_clear(config, placement_rng, T_world_chair)
            self.clock.sleep(SETTLE_S)
        except BaseException:
            bullet.disconnect_once()
            raise
        self.robot = Robot(
            arm=self.panda,
            humanoid=self.nao,
            speaker=self.speaker,
            clock=self.clock,
            helper=self.helper,
            judge=self.judge,
        )

    def _build_floor(self) -> int:
        """pybullet's plane, grey and with the lab floor's friction; returns its body id."""
        floor = self._bullet.loadURDF(
            str(Path(pybullet_data.getDataPath()) / "plane.urdf"), useFixedBase=True
        )
        self._bullet.changeVisualShape(
            floor, -1, textureUniqueId=-1, rgbaColor=[0.62, 0.62, 0.6, 1.0]
        )
        self._bullet.changeDynamics(floor, -1, lateralFriction=0.9)
        return floor

    def _build_nao(self, start: SE2Pose, rng: np.random.Generator) -> SimNao:
        """The NAO wearing the humanoid tag on its head, standing at ``start``."""
        texture_path, plate_path = tag_assets(HUMANOID_TAG)
        texture = self._bullet.loadTexture(str(texture_path))
        return SimNao(
            self._bullet,
            self.clock,
            str(nao_urdf(plate_path, HUMANOID_TAG.height_m)),
            start,
            rng,
            texture_id=texture,
        )

    def _build_bear_helper_and_judge(
        self, config: SimConfig, helper_rng: np.random.Generator
    ) -> None:
        """The chair-touch monitor, the bear in the NAO's hands and how far apart they
        hold it, the helper who hears the speaker, and the judge (after the NAO and the
        chair exist)."""
        bullet = self._bullet
        self.chair_touch = ChairTouchMonitor(
            bullet,
            self.nao.body,
            self.chair.body,
            {index: name for name, index in self.nao.link_indices.items()},
        )
        self.clock.add_process(self.chair_touch)
        self.bear = SimBear(bullet, self.clock, self._bear_in_hands())
        self.bear.hold(self.hands_frame, self.nao.body)
        self.palms_apart = PalmsApartMonitor(self.nao, self.bear)
        self.clock.add_process(self.palms_apart)
        self.nao.on_hands = self._on_hands
        self.helper = SimHelper(self.clock, self.chair, config.helper, helper_rng)
        self.speaker = SimSpeaker(self.helper, config.voice)
        self.judge = SimJudge(
            bullet,
            self.clock,
            self.bear,
            self.chair.body,
            self.floor,
            true_sitting_yaw=self.sitting_yaw_true,
        )

    # --- ground truth (tests and benchmarks only) ----------------------------------------
    @property
    def chair_mesh_true(self) -> trimesh.Trimesh:
        """The chair mesh at its current true pose, world frame."""
        return self.chair.mesh_world()

    def T_world_chair_true(self) -> np.ndarray:
        """The chair frame's current true pose (changes when the helper turns the chair)."""
        return self.chair.T_world_chair()

    def sitting_yaw_true(self) -> float | None:
        """The chair's current true sitting direction in the world (radians), if known."""
        if self.front_yaw_rad is None:
            return None
        return wrap_angle(self.front_yaw_rad + yaw_of(self.T_world_chair_true()))

    def place_nao(self, pose: SE2Pose) -> None:
        """Teleports the NAO (feet frame) to ``pose``, with the bear if it holds it.

        For benchmarks and tests that start a motion at a chosen stance: the true pose
        and the odometry become ``pose``, the posture is kept and a held bear keeps its
        place in the hands.
        """
        self.nao.place(pose)
        self.bear.follow_anchor()

    # --- pictures -----------------------------------------------------------------------
    def render_png(self, path: Path, view: Literal["top", "perspective"] = "perspective") -> None:
        """Writes a 960x720 picture of the scene (TinyRenderer) for reports."""
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Image.fromarray(self.render_scene(view).rgb).save(path)

    def render_scene(self, view: Literal["top", "perspective"] = "perspective") -> SceneFrame:
        """A 960x720 picture of the scene with its camera, to draw on (``SceneFrame.project``).

        ``top`` looks straight down from 3.4 m above the arena's middle, world +x up the
        picture (the arena and the Panda's base fill its height); ``perspective``
        looks at the arena from behind its far corner, 45 degrees down: steep enough that
        the top row meets the floor within the renderer's far plane (``FAR_M``), so no
        row is left blank.
        """
        arena = self.config.arena
        centre = np.array([(arena.x_min + arena.x_max) / 2.0 - 0.3, 0.0, 0.25])
        if view == "top":
            eye = centre + np.array([0.0, 0.0, 3.4])
            forward = np.array([0.0, 0.0, -1.0])
            down = np.array([-1.0, 0.0, 0.0])
        elif view == "perspective":
            eye = np.array([arena.x_max + 0.2, arena.y_min - 1.2, 0.0])
            eye[2] = centre[2] + math.tan(PERSPECTIVE_PITCH_RAD) * math.hypot(*(centre - eye)[:2])
            forward = centre - eye
            forward /= np.linalg.norm(forward)
            right = np.cross(forward, [0.0, 0.0, 1.0])
            right /= np.linalg.norm(right)
            down = np.cross(forward, right)
        else:
            raise ValueError(f"unknown view {view!r} (top or perspective)")
        right = np.cross(down, forward)
        T_world_camera = make_transform(np.column_stack([right, down, forward]), eye)
        focal = 480.0 / math.tan(math.radians(30.0))
        intrinsics = CameraIntrinsics(960, 720, focal, focal, 479.5, 359.5)
        started = time.perf_counter()
        rendered = render_view(self._bullet, T_world_camera, intrinsics)
        self.clock.timers.render_s += time.perf_counter() - started
        self.clock.timers.frames += 1
        self.clock.timers.pixels += intrinsics.width * intrinsics.height
        return SceneFrame(rendered.rgb, T_world_camera, intrinsics)

    # --- life cycle ---------------------------------------------------------------------
    def close(self) -> None:
        """Stops the robots and disconnects from pybullet; safe to call more than once."""
        if self._bullet.closed:
            return
        try:
            self.nao.stop()
        finally:
            self._bullet.disconnect_once()

    def __enter__(self) -> SimWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- construction -------------------------------------------------------------------
    def hands_frame(self) -> np.ndarray:
        """The frame between the NAO's palms: mean position, averaged orientation.

        The carried bear asks for it before every physics step; it is computed again only
        when the NAO has moved (the same array is returned until then), by forward
        kinematics only when its joints have moved.
        """
        with self._bullet.lock:
            nao = self.nao
            if self._hands_cache is not None and self._hands_cache[0] == nao.motion_count:
                return self._hands_cache[1]
            # Walking moves the whole body rigidly with the feet frame: forward kinematics
            # only when the posture changed.
            if self._hands_in_feet is None or self._hands_in_feet[0] != nao.posture_count:
                T_feet_hands = np.linalg.inv(nao.T_world_feet()) @ self._hands_frame_now()
                self._hands_in_feet = (nao.posture_count, T_feet_hands)
            frame = nao.T_world_feet() @ self._hands_in_feet[1]
            self._hands_cache = (nao.motion_count, frame)
            return frame

    def _hands_frame_now(self) -> np.ndarray:
        left = self.nao.T_world_link("l_wrist") @ T_WRIST_PALM
        right = self.nao.T_world_link("r_wrist") @ T_WRIST_PALM
        q_left = np.array(matrix_to_pose(left)[1])
        q_right = np.array(matrix_to_pose(right)[1])
        if np.dot(q_left, q_right) < 0.0:
            q_right = -q_right
        quaternion = (q_left + q_right) / np.linalg.norm(q_left + q_right)
        return pose_to_matrix((left[:3, 3] + right[:3, 3]) / 2.0, quaternion)

    def _bear_in_hands(self) -> np.ndarray:
        middle = self.hands_frame()[:3, 3]
        # As in the paper, the bear is handed over facing the NAO: when the NAO stands in
        # front of the chair facing it, the bear then faces the sitting direction.
        facing = self.nao.true_pose().theta + math.pi
        return make_transform(rot_z(facing), middle - np.array([0.0, 0.0, BEAR_SEAT_BELOW_HANDS_M]))

    def _on_hands(self, open_hands: bool) -> None:
        if open_hands:
            self.bear.release()

    def _placement(self, config: SimConfig, rng: np.random.Generator) -> np.ndarray:
        area = config.arena.chair_area
        x = rng.uniform(area.x_min, area.x_max)
        y = rng.uniform(area.y_min, area.y_max)
        tolerance = math.radians(PLACEMENT_TOLERANCE_DEG)
        offset = rng.uniform(-tolerance, tolerance)
        if config.placement == "accessible":
            sitting_yaw = float(rng.choice(accessible_sitting_yaws(config.arena, (x, y))))
        else:
            # Toward the arm, or toward the side edge nearer the chair: the far side would
            # leave room in front of the chair inside the arena.
            toward_side = math.copysign(math.pi / 2.0, y)
            sitting_yaw = float(rng.choice([math.pi, toward_side])) + offset
        if self.front_yaw_rad is None:
            placement_yaw = rng.uniform(-math.pi, math.pi)
            log.warning(
                "chair %s has no known sitting direction (front_yaw_deg): placed with a random "
                "yaw, so placement=%s is not enforced",
                config.chair_path,
                config.placement,
            )
        else:
            placement_yaw = wrap_angle(sitting_yaw - self.front_yaw_rad)
        self.placement_yaw_rad = placement_yaw
        return make_transform(rot_z(placement_yaw), np.array([x, y, 0.0]))

    def _set_down_clear(
        self, config: SimConfig, rng: np.random.Generator, first: np.ndarray
    ) -> None:
        """Places the chair where a person would set it down: the drawn placement, pulled
        out in front of the arm until it is :data:`SET_DOWN_CLEARANCE_M` clear of the arm
        (``_slid_clear_of_arm``); when it then stands in the NAO's way at its start, the
        next drawn placement (at most :data:`SET_DOWN_DRAWS`).

        The chair area holds a chair's centre, and a chair far larger than the area (a
        1.7 m sofa turned lengthwise) drawn near its arm-side edge would otherwise stand
        through the arm's base. A chair clear where it was drawn stays exactly there (the
        same seed, the same world as before for every chair that fits the cell).
        """
        kept: tuple[np.ndarray, float] | None = None
        for draw in range(SET_DOWN_DRAWS):
            T = first if draw == 0 else self._placement(config, rng)
            T = self._slid_clear_of_arm(T)
            if kept is None:
                kept = (T, self.placement_yaw_rad)
            if self._chair_clearance(self.nao.body, self.bear.body) >= SET_DOWN_CLEARANCE_M:
                kept = (T, self.placement_yaw_rad)
                break
        else:
            log.warning(
                "chair %s: no placement of %d drawn leaves the NAO's start clear; kept the "
                "first, slid clear of the arm",
                config.chair_path,
                SET_DOWN_DRAWS,
            )
        assert kept is not None
        self.chair.set_T_world_chair(kept[0])
        self.placement_yaw_rad = kept[1]

    def _slid_clear_of_arm(self, T_world_chair: np.ndarray) -> np.ndarray:
        """The chair set at ``T_world_chair`` pulled clear of the arm
        (:func:`slid_clear_of_arm`)."""
        arm_boxes = link_boxes(self._bullet, self.panda.body)
        T = slid_clear_of_arm(
            T_world_chair, self._chair_surface_points(), self.config.arena, arm_boxes
        )
        self.chair.set_T_world_chair(T)
        return T

    def _chair_clearance(self, *bodies: int) -> float:
        """The chair's clearance to ``bodies`` at its current pose (:func:`clearance_to`)."""
        boxes = np.concatenate([link_boxes(self._bullet, body) for body in bodies])
        return clearance_to(self._chair_surface_points(), self.chair.T_world_chair(), boxes)

    def _chair_surface_points(self) -> np.ndarray:
        """The chair's surface points (:func:`chair_surface_points`), computed once."""
        if self._surface_cache is None:
            self._surface_cache = chair_surface_points(self.chair.mesh_local)
        return self._surface_cache

    def _ignore_floor(self, *bodies: int) -> None:
        """No collision between the floor and the links of kinematic or fixed robots.

        The NAO's feet are placed on the floor, not stood on it, and the Panda is bolted
        down, so their contacts with the floor change nothing; but the floor's bounds are
        infinite, so each of their links would be tested against it at every step.
        """
        for body in bodies:
            for link in range(-1, self._bullet.getNumJoints(body)):
                self._bullet.setCollisionFilterPair(body, self.floor, link, -1, 0)

    def _build_walls(self, arena: Arena) -> list[int]:
        """The arena's boundary tape (visual only) and its solid obstacles."""
        bullet = self._bullet
        bodies = []
        half_w = TAPE_WIDTH_M / 2.0
        length_x = arena.x_max - arena.x_min + TAPE_WIDTH_M
        length_y = arena.y_max - arena.y_min + TAPE_WIDTH_M
        mid_x = (arena.x_min + arena.x_max) / 2.0
        mid_y = (arena.y_min + arena.y_max) / 2.0
        tapes = [
            ((length_x, TAPE_WIDTH_M), (mid_x, arena.y_min - half_w)),
            ((length_x, TAPE_WIDTH_M), (mid_x, arena.y_max + half_w)),
            ((TAPE_WIDTH_M, length_y), (arena.x_min - half_w, mid_y)),
            ((TAPE_WIDTH_M, length_y), (arena.x_max + half_w, mid_y)),
        ]
        boxes = [((sx, sy, TAPE_HEIGHT_M), (cx, cy), False) for (sx, sy), (cx, cy) in tapes]
        for obstacle in arena.obstacles:
            base_x, base_y = arena.arm_base_xy
            if (
                obstacle.x_min <= base_x <= obstacle.x_max
                and obstacle.y_min <= base_y <= obstacle.y_max
            ):
                continue  # the arm's own footprint: the Panda itself stands there
            size = (
                obstacle.x_max - obstacle.x_min,
                obstacle.y_max - obstacle.y_min,
                obstacle.height,
            )
            centre = (
                (obstacle.x_min + obstacle.x_max) / 2.0,
                (obstacle.y_min + obstacle.y_max) / 2.0,
            )
            boxes.append((size, centre, True))
        for (sx, sy, sz), (cx, cy), solid in boxes:
            half_extents = [sx / 2.0, sy / 2.0, sz / 2.0]
            collision = (
                bullet.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half_extents)
                if solid
                else -1
            )
            visual = bullet.createVisualShape(
                pybullet.GEOM_BOX,
                halfExtents=half_extents,
                rgbaColor=[0.3, 0.45, 0.7, 1.0] if solid else [0.85, 0.15, 0.1, 1.0],
            )
            bodies.append(
                bullet.createMultiBody(
                    baseMass=0.0,
                    baseCollisionShapeIndex=collision,
                    baseVisualShapeIndex=visual,
                    basePosition=[cx, cy, sz / 2.0],
                )
            )
        return bodies
