"""Frames and rigid transforms in 3-D, and the sitting pose.

Conventions:
    * The world frame is z up, metres, radians. Yaw is measured from +x about +z.
    * ``T_a_b`` is a 4x4 homogeneous transform that maps points expressed in frame
      ``b`` into frame ``a``: ``p_a = T_a_b @ p_b``.
    * A sitting pose g = (p, γ) (the paper, "Problem Formulation") is the position of
      the sitter's pelvis and the yaw of the direction the sitter faces.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np


def wrap_angle(angle_rad: float) -> float:
    """Wraps an angle to [-π, π)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


def rot_z(yaw_rad: float) -> np.ndarray:
    """3x3 rotation about +z by ``yaw_rad``."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def make_transform(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """Builds a 4x4 transform from a 3x3 rotation and a translation (metres)."""
    transform = np.eye(4)
    transform[:3, :3] = rotation
    transform[:3, 3] = translation
    return transform


def yaw_transform(yaw_rad: float, translation: np.ndarray | None = None) -> np.ndarray:
    """4x4 transform of a rotation about +z followed by a translation."""
    return make_transform(rot_z(yaw_rad), np.zeros(3) if translation is None else translation)


def yaw_of(transform: np.ndarray) -> float:
    """Yaw (radians) of the rotation part of a transform, assuming it is about +z."""
    return math.atan2(transform[1, 0], transform[0, 0])


def transform_points(transform: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Applies a 4x4 transform to an (N, 3) array of points."""
    return points @ transform[:3, :3].T + transform[:3, 3]


PELVIS_OVER_SEAT_M = 0.03 + 0.045
"""How far (metres) the imagined sitter's pelvis centre p rests above the seat it sits
on: its hip joints 0.03 m below p and its thighs' radius, 0.045 m
(``bearchair.skills.imagination.agent``). Two sittings on the same seat lie within about
this of each other in height; a sitting further off sits on something else."""


class SittingPose(NamedTuple):
    """The imagined sitting pose g = (p, γ) in the world frame.

    Attributes:
        position: (3,) pelvis position p in metres.
        yaw: sitting direction γ in radians, from +x about +z (the way the sitter faces).
    """

    position: np.ndarray
    yaw: float

    def transformed(self, T_world_new_old: np.ndarray) -> SittingPose:
        """The pose carried along by a rigid motion of the chair."""
        position = transform_points(T_world_new_old, self.position[None, :])[0]
        return SittingPose(position, wrap_angle(self.yaw + yaw_of(T_world_new_old)))

    def direction(self) -> np.ndarray:
        """Unit (2,) vector of the sitting direction in the xy-plane."""
        return np.array([math.cos(self.yaw), math.sin(self.yaw)])

    def to_json(self) -> dict:
        """A JSON-friendly dict: position in metres, yaw in degrees."""
        return {
            "position_m": [round(float(v), 4) for v in self.position],
            "yaw_deg": round(math.degrees(self.yaw), 2),
        }
