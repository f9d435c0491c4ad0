"""Where the wrist depth camera sits on the Panda's hand: the cell's nominal mount.

The simulated camera is mounted here, and the mission uses it where it needs the camera
before any hand-eye calibration (aiming the scan's views clear of the chair). On a real
cell the calibrated ``T_hand_camera`` (:mod:`bearchair.skills.perception.hand_eye`)
replaces it wherever a measured pose matters.
"""

from __future__ import annotations

import numpy as np

from bearchair.core.geometry import make_transform

T_HAND_CAMERA = make_transform(
    np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    np.array([0.065, 0.0, 0.02]),
)
"""Hand-eye extrinsic: the camera (OpenCV optical frame) in the Panda's ``panda_hand`` frame.

The camera is mounted 6.5 cm off the hand's axis along the hand's +x, 2 cm along the
approach axis, looking along the hand's approach axis (+z). Its image x axis is the
hand's -y and its image y axis (down) the hand's +x, so the closed fingers lie above the
top edge of the image, outside the 45 deg vertical field of view.
"""
