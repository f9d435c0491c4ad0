"""SE(2): planar rigid motions, the poses of everything that moves on the floor.

A pose a = (x, y, θ) of a body in a parent frame is the transform

    T_a = [[cos θ, -sin θ, x],
           [sin θ,  cos θ, y],
           [0,      0,     1]],

which maps points in the body frame into the parent frame. Composition, inverse and the
relative pose are the matrix product, inverse and ``T_a⁻¹ T_b``, in closed form:

    a ∘ b = (x_a + cos θ_a x_b - sin θ_a y_b,  y_a + sin θ_a x_b + cos θ_a y_b,  θ_a + θ_b)
    a⁻¹   = (-cos θ_a x_a - sin θ_a y_a,  sin θ_a x_a - cos θ_a y_a,  -θ_a)

Headings are wrapped to [-π, π) after every operation. Metres and radians; θ from +x
about +z (the world frame is z up).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from bearchair.core.geometry import wrap_angle, yaw_of, yaw_transform


class SE2Pose(NamedTuple):
    """A planar pose: an element of SE(2).

    Attributes:
        x: metres.
        y: metres.
        theta: heading in radians, from +x about +z.
    """

    x: float
    y: float
    theta: float

    @classmethod
    def identity(cls) -> SE2Pose:
        return cls(0.0, 0.0, 0.0)

    @classmethod
    def from_transform(cls, transform: np.ndarray) -> SE2Pose:
        """The planar part of a 3x3 (SE(2)) or 4x4 transform whose rotation is about +z."""
        column = transform.shape[1] - 1
        return cls(float(transform[0, column]), float(transform[1, column]), yaw_of(transform))

    def compose(self, other: SE2Pose) -> SE2Pose:
        """``self ∘ other``: ``other`` (given in this pose's frame) in the parent frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return SE2Pose(
            self.x + c * other.x - s * other.y,
            self.y + s * other.x + c * other.y,
            wrap_angle(self.theta + other.theta),
        )

    __matmul__ = compose

    def inverse(self) -> SE2Pose:
        """The parent frame's pose in this pose's frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return SE2Pose(-c * self.x - s * self.y, s * self.x - c * self.y, wrap_angle(-self.theta))

    def between(self, other: SE2Pose) -> SE2Pose:
        """``self⁻¹ ∘ other``: ``other`` in this pose's frame (for odometry increments)."""
        dx, dy = other.x - self.x, other.y - self.y
        c, s = math.cos(self.theta), math.sin(self.theta)
        return SE2Pose(c * dx + s * dy, -s * dx + c * dy, wrap_angle(other.theta - self.theta))

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Maps (..., 2) points from this pose's frame into the parent frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        points = np.asarray(points, dtype=float)
        return points @ np.array([[c, s], [-s, c]]) + np.array([self.x, self.y])

    def as_matrix(self) -> np.ndarray:
        """The 3x3 homogeneous transform ``T_parent_body``."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return np.array([[c, -s, self.x], [s, c, self.y], [0.0, 0.0, 1.0]])

    def as_transform(self) -> np.ndarray:
        """``T_world_body`` in 3-D (4x4), with the body on the floor (z = 0)."""
        return yaw_transform(self.theta, np.array([self.x, self.y, 0.0]))

    def transformed(self, T_world_new_old: np.ndarray) -> SE2Pose:
        """The pose after a rigid motion ``T_world_new_old`` (4x4) about the world's z axis."""
        return SE2Pose.from_transform(T_world_new_old).compose(self)

    def stepped_back(self, distance_m: float) -> SE2Pose:
        """This pose moved ``distance_m`` metres backwards along its own heading."""
        return SE2Pose(
            self.x - distance_m * math.cos(self.theta),
            self.y - distance_m * math.sin(self.theta),
            self.theta,
        )

    def to_json(self) -> dict[str, float]:
        """The pose for a run record, units in the keys: ``x_m``, ``y_m`` (metres, to
        0.1 mm) and ``theta_deg`` (degrees, to 0.01°)."""
        return {
            "x_m": round(self.x, 4),
            "y_m": round(self.y, 4),
            "theta_deg": round(math.degrees(self.theta), 2),
        }

    def distance_to(self, other: SE2Pose) -> float:
        """Euclidean distance in metres between the two positions."""
        return math.hypot(self.x - other.x, self.y - other.y)
