"""Where the arm's camera looks from: the scan, overview and still-check configurations.

The joint vectors were chosen offline by ``bench/perception_views.py``: for each wanted
camera pose (an eye looking at a target in the chair area) it solved the Panda's IK in
pybullet (panda.urdf, base at the world origin, camera along the hand's approach axis),
and checked by forward kinematics the optical axis (within 3 degrees), the eye (within
2 cm), joint limits, self-collision and 5 cm clearance to the floor and 3 cm to the
chair volume of that time (the chair area widened by 0.25 m, 0.58 m high). A larger
chair can reach into some of them: before every scan the views are checked again
against the chair's extent as seen from HOME, inside :data:`CHAIR_VOLUME`, and routed,
replaced or skipped (``bearchair.skills.perception.clearance``). The camera pose of every capture
still comes from the arm's own forward kinematics (``RGBDFrame.T_world_camera``), so a
different hand-eye extrinsic only shifts the views by a few centimetres.
"""

from __future__ import annotations

import numpy as np

from bearchair.core.arena import DEFAULT_ARENA, Arena

MAX_CHAIR_REACH_M = 0.45
"""How far (metres) any part of a chair reaches horizontally from its centre, whatever
its yaw: the widest children's seat planned for is a 0.8 m bench 0.4 m deep (half its
diagonal, 0.45 m); chairs 0.4 x 0.4 m reach 0.28 m. The chair's centre lies in the
arena's chair area, so this margin around the area bounds every placement."""

MAX_CHAIR_HEIGHT_M = 0.8
"""The tallest chair planned for (metres): the highest children's seat (0.45 m, beyond the
NAO's reach, refused later but still scanned) under a 0.32 m backrest; children's chairs
stand 0.45-0.62 m overall."""

VIEW_CLEARANCE_M = 0.03
"""A scan view, and the straight joint-space motion into it, keeps the arm's links this
far (metres) from the chair's possible extent; closer, the view is replaced or skipped
(``bearchair.skills.perception.clearance``)."""


def chair_volume(
    arena: Arena = DEFAULT_ARENA,
    reach_m: float = MAX_CHAIR_REACH_M,
    height_m: float = MAX_CHAIR_HEIGHT_M,
) -> tuple[np.ndarray, np.ndarray]:
    """The world box (min corner, max corner) any chair in the chair area lies in (metres).

    Args:
        arena: the workspace (its chair area holds the chair's centre).
        reach_m: how far a chair reaches from its centre (:data:`MAX_CHAIR_REACH_M`).
        height_m: how tall a chair is (:data:`MAX_CHAIR_HEIGHT_M`).
    """
    area = arena.chair_area
    # Nothing reaches into the arm's base footprint (the obstacle boxes, + 2 cm).
    x_min = max(area.x_min - reach_m, max(b.x_max for b in arena.obstacles) + 0.02)
    lower = np.array([x_min, area.y_min - reach_m, 0.0])
    upper = np.array([area.x_max + reach_m, area.y_max + reach_m, height_m])
    return lower, upper


CHAIR_VOLUME = chair_volume()


def look_at(eye: np.ndarray, target: np.ndarray) -> np.ndarray:
    """T_world_camera (OpenCV axes) of a camera at ``eye`` looking at ``target``, image up ~ +z."""
    forward = np.asarray(target, float) - np.asarray(eye, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    if np.linalg.norm(right) < 1e-6:  # looking straight down: image up along +x
        right = np.cross(forward, [1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    transform = np.eye(4)
    transform[:3, :3] = np.column_stack((right, down, forward))
    transform[:3, 3] = eye
    return transform


HOME_CONFIGURATION: tuple[float, ...] = (-0.0421, -0.5278, -0.0006, -0.8539, 0.0280, 0.8495, 0.7669)
"""High above the arm's base, the camera at (0.15, 0, 0.98) looking at the chair area.

Every scan configuration is reached from here by a straight joint-space motion that keeps
3 cm clear of the chair volume (checked by bench/perception_views.py), so motions that
are not checked go through here."""

SCAN_CONFIGURATIONS: tuple[tuple[float, ...], ...] = (
    # Made by bench/perception_views.py (seed 0, 200000 samples near HOME): each looks at
    # the chair area's centre 0.2 m up, (0.6, 0, 0.2), within 8 degrees; in visiting
    # order, the straight joint-space motion from the previous one (HOME for the first)
    # keeps the clearance given.
    # path from the previous configuration: clearance 0.10 m
    # scan0: eye [0.368, 0.072, 0.848] -> [0.6, 0.0, 0.2], axis 5.5 deg off, clearance floor 0.45 m, chair volume 0.10 m
    (-0.4401, -0.5156, 0.4579, -1.4279, 0.0752, 1.3938, 1.7677),
    # path from the previous configuration: clearance 0.03 m
    # scan1: eye [0.354, 0.306, 0.771] -> [0.6, 0.0, 0.2], axis 5.9 deg off, clearance floor 0.39 m, chair volume 0.03 m
    (-0.7847, -0.7347, 0.8780, -1.4368, 0.0653, 1.4070, -0.2061),
    # path from the previous configuration: clearance 0.03 m
    # scan2: eye [-0.2, -0.156, 0.742] -> [0.6, 0.0, 0.2], axis 4.6 deg off, clearance floor 0.28 m, chair volume 0.26 m
    (-0.5450, -1.4281, -0.6664, -1.7423, 0.0933, 0.9440, -0.0883),
    # path from the previous configuration: clearance 0.13 m
    # scan3: eye [-0.043, -0.472, 0.595] -> [0.6, 0.0, 0.2], axis 7.6 deg off, clearance floor 0.25 m, chair volume 0.13 m
    (0.2339, -1.5596, -0.9157, -1.7553, -0.1397, 1.3150, 1.8748),
    # path from the previous configuration: clearance 0.04 m
    # scan4: eye [0.043, -0.617, 0.362] -> [0.6, 0.0, 0.2], axis 2.2 deg off, clearance floor 0.14 m, chair volume 0.04 m
    (0.7243, -1.7541, -1.1765, -1.2645, -0.3069, 1.0444, 1.9513),
    # path from the previous configuration: clearance 0.03 m
    # scan5: eye [0.117, -0.157, 0.932] -> [0.6, 0.0, 0.2], axis 7.7 deg off, clearance floor 0.41 m, chair volume 0.11 m
    (0.9458, -0.8337, -0.1894, -1.0215, -0.3638, 0.8335, 1.9365),
    # path from the previous configuration: clearance 0.07 m
    # scan6: eye [0.175, -0.447, 0.814] -> [0.6, 0.0, 0.2], axis 3.5 deg off, clearance floor 0.41 m, chair volume 0.07 m
    (1.2273, -0.8288, -1.2134, -0.4303, -0.1856, 0.7049, 0.1794),
    # path from the previous configuration: clearance 0.07 m
    # scan7: eye [0.002, 0.684, 0.346] -> [0.6, 0.0, 0.2], axis 5.4 deg off, clearance floor 0.17 m, chair volume 0.14 m
    (-0.9273, -1.6529, 1.2063, -0.7165, 0.3829, 0.8312, 0.3738),
    # path from the previous configuration: clearance 0.11 m
    # scan8: eye [-0.095, 0.414, 0.812] -> [0.6, 0.0, 0.2], axis 4.6 deg off, clearance floor 0.38 m, chair volume 0.11 m
    (-1.0055, -0.9839, 0.0917, -0.2305, 1.0178, 0.4258, 1.6507),
)
"""The 9 scan configurations of the Panda's 7 joints (radians), in visiting order."""

OVERVIEW_CONFIGURATION: tuple[float, ...] = (
    0.2092,
    -0.8667,
    -0.1012,
    -2.1189,
    -0.2262,
    2.3339,
    0.9414,
)
"""Sees the humanoid's walking area from the chair area to its start, from above the arm
(overview: eye [0.35, 0.0, 0.85] -> [1.3, 0.0, 0.35], axis 0.0 deg off, clearance floor 0.41 m, chair volume 0.06 m); reached through HOME."""

STILL_CHECK_CONFIGURATION: tuple[float, ...] = HOME_CONFIGURATION
"""The fixed, high view of the whole chair area used to see the chair stop moving."""

TRACKING_VIEWS: tuple[int, ...] = (4, 5, 6, 7, 8)
"""Scan configurations captured again to track the chair's rotation: consecutive ones, so
every motion between them is a checked one."""
