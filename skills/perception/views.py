"""Where the arm's camera looks from: the scan, overview and still-check configurations.

The joint vectors were chosen offline by ``bench/perception_views.py``: for each wanted
camera pose (an eye looking at a target in the chair area) it solved the Panda's IK in
pybullet (panda.urdf, base at the world origin, camera along the hand's approach axis),
and checked by forward kinematics the optical axis (within 3 degrees), the eye (within
2 cm), joint limits, self-collision and 5 cm clearance to the floor and 3 cm to
:data:`CHAIR_VOLUME`. The camera pose of every capture still comes from the arm's own
forward kinematics (``RGBDFrame.T_world_camera``), so a different hand-eye extrinsic
only shifts the views by a few centimetres.
"""

from __future__ import annotations

import numpy as np

from skills.arena import DEFAULT_ARENA, Arena

CHAIR_MARGIN_M = 0.25
"""How far a chair centred in the chair area may reach beyond it (half its footprint)."""

CHAIR_HEIGHT_MAX_M = 0.58
"""The tallest chair the scan volume allows for (the calibration chairs are 0.535 m)."""


def chair_volume(arena: Arena = DEFAULT_ARENA) -> tuple[np.ndarray, np.ndarray]:
    """The world box (min corner, max corner) any chair in the chair area lies in (metres)."""
    area = arena.chair_area
    # Nothing reaches into the arm's base footprint (x below 0.15 m + 2 cm).
    x_min = max(area.x_min - CHAIR_MARGIN_M, max(b.x_max for b in arena.obstacles) + 0.02)
    lower = np.array([x_min, area.y_min - CHAIR_MARGIN_M, 0.0])
    upper = np.array([area.x_max + CHAIR_MARGIN_M, area.y_max + CHAIR_MARGIN_M, CHAIR_HEIGHT_MAX_M])
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


SCAN_CONFIGURATIONS: tuple[tuple[float, ...], ...] = (
    # Made by bench/perception_views.py (seed 0, 200000 samples): each looks at the chair
    # area's centre 0.2 m up, (0.6, 0, 0.2), within 8 degrees; clearances in metres.
    # scan0: eye [0.109, 0.015, 0.966] -> [0.6, 0.0, 0.2], axis 6.8 deg off, clearance floor 0.51 m, chair volume 0.06 m
    (1.4212, -0.1920, 0.1555, -0.3798, -1.2361, 0.6762, -2.8640),
    # scan1: eye [-0.049, 0.628, 0.448] -> [0.6, 0.0, 0.2], axis 6.4 deg off, clearance floor 0.30 m, chair volume 0.14 m
    (-1.1123, -0.9723, 2.7588, -0.6063, -0.9287, 0.5062, 0.1546),
    # scan2: eye [0.033, -0.596, 0.622] -> [0.6, 0.0, 0.2], axis 7.4 deg off, clearance floor 0.24 m, chair volume 0.07 m
    (-2.1198, 1.5681, 2.6258, -0.9979, -0.7070, 0.8591, 1.7271),
    # scan3: eye [0.05, 0.35, 0.844] -> [0.6, 0.0, 0.2], axis 7.3 deg off, clearance floor 0.45 m, chair volume 0.14 m
    (-0.0096, -0.4672, 1.1343, -1.0017, -0.6546, 0.7163, 0.2441),
    # scan4: eye [-0.013, -0.288, 0.856] -> [0.6, 0.0, 0.2], axis 3.3 deg off, clearance floor 0.45 m, chair volume 0.13 m
    (0.0509, -0.5719, -1.0478, -1.0264, 0.4499, 0.8890, -1.8919),
    # scan5: eye [-0.234, 0.077, 0.845] -> [0.6, 0.0, 0.2], axis 5.2 deg off, clearance floor 0.33 m, chair volume 0.26 m
    (0.3545, -1.0753, 0.4678, -1.0998, -0.2586, 0.8613, -2.1342),
    # scan6: eye [0.177, -0.403, 0.811] -> [0.6, 0.0, 0.2], axis 3.7 deg off, clearance floor 0.50 m, chair volume 0.04 m
    (-2.3747, 0.1705, 1.0923, -0.8768, 0.8951, 0.7329, 1.5106),
    # scan7: eye [-0.07, 0.417, 0.686] -> [0.6, 0.0, 0.2], axis 4.2 deg off, clearance floor 0.24 m, chair volume 0.15 m
    (2.5203, 1.4687, -2.5845, -1.3772, 0.3312, 0.9663, -1.5432),
    # scan8: eye [-0.123, -0.097, 0.941] -> [0.6, 0.0, 0.2], axis 5.4 deg off, clearance floor 0.41 m, chair volume 0.17 m
    (0.6196, -0.7075, 0.4058, -0.4121, -0.6632, 0.3542, 0.9162),
)
"""The 9 scan configurations of the Panda's 7 joints (radians)."""

OVERVIEW_CONFIGURATION: tuple[float, ...] = (
    -0.1661,
    -0.8640,
    0.0808,
    -2.1207,
    0.1801,
    2.3400,
    0.6611,
)
"""Sees the humanoid's walking area from the chair area to its start, from above the arm.
overview: eye [0.35, 0.0, 0.85] -> [1.3, 0.0, 0.35], axis 0.0 deg off, clearance floor 0.41 m, chair volume 0.07 m"""

STILL_CHECK_CONFIGURATION: tuple[float, ...] = SCAN_CONFIGURATIONS[0]
"""The fixed, high view of the whole chair area used to see the chair stop moving."""

TRACKING_VIEWS: tuple[int, ...] = (0, 1, 2, 3, 4)
"""Indices of the scan configurations captured again to track the chair's rotation."""
