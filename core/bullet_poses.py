"""pybullet's poses, (position, (x, y, z, w) quaternion), as 4x4 rigid transforms."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pybullet


def pose_to_matrix(
    position: Sequence[float] | np.ndarray, quaternion_xyzw: Sequence[float] | np.ndarray
) -> np.ndarray:
    """4x4 transform from a pybullet position and (x, y, z, w) quaternion."""
    transform = np.eye(4)
    transform[:3, :3] = np.array(pybullet.getMatrixFromQuaternion(quaternion_xyzw)).reshape(3, 3)
    transform[:3, 3] = position
    return transform


def matrix_to_pose(transform: np.ndarray) -> tuple[list[float], list[float]]:
    """(position, (x, y, z, w) quaternion) of a 4x4 rigid transform."""
    return list(map(float, transform[:3, 3])), rotation_to_quaternion(transform[:3, :3])


def rotation_to_quaternion(rotation: np.ndarray) -> list[float]:
    """(x, y, z, w) quaternion of a 3x3 rotation matrix (Shepperd's method)."""
    m = rotation
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = [(m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s]
    norm = math.sqrt(sum(v * v for v in q))
    return [float(v / norm) for v in q]
