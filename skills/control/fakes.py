"""Test doubles for walking: a kinematic humanoid, a simulated clock and a noisy tag tracker.

They implement :class:`hardware.interfaces.Humanoid` and :class:`hardware.interfaces.Clock`
well enough to close the walking loop without physics: the body follows the commanded
velocity with a first-order lag, its odometry drifts, and the tracker sees the true pose
with noise and sometimes not at all.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from core.geometry import wrap_angle
from core.se2 import SE2Pose


class FakeHumanoid:
    """A holonomic walker: body velocity → first-order lag → pose.

    Attributes:
        true_pose: where the robot really is (what a tracker sees).
        commands: every (vx, vy, ω) commanded, in order.
        stopped: :meth:`stop` was the last command.
    """

    def __init__(
        self,
        start: SE2Pose,
        *,
        lag_s: float = 0.3,
        odometry_scale: float = 1.05,
        velocity_noise: float = 0.0,
        seed: int = 0,
    ) -> None:
        """Args:
        start: initial true pose (odometry starts there too).
        lag_s: velocity time constant, seconds.
        odometry_scale: odometry over-reports travelled distance by this factor (drift).
        velocity_noise: relative standard deviation of the realised velocity.
        seed: noise seed.
        """
        self.true_pose = start
        self._odometry = start
        self._lag_s = lag_s
        self._odometry_scale = odometry_scale
        self._velocity_noise = velocity_noise
        self._rng = np.random.default_rng(seed)
        self._commanded = np.zeros(3)
        self._velocity = np.zeros(3)
        self.commands: list[tuple[float, float, float]] = []
        self.stopped = True

    def pose(self) -> SE2Pose:
        return self._odometry

    def set_velocity(self, vx_mps: float, vy_mps: float, omega_radps: float) -> None:
        self._commanded = np.array([vx_mps, vy_mps, omega_radps], dtype=float)
        self.commands.append((vx_mps, vy_mps, omega_radps))
        self.stopped = False

    def stop(self) -> None:
        self._commanded = np.zeros(3)
        self._velocity = np.zeros(3)
        self.stopped = True

    def play_joint_trajectory(
        self, joint_names: Sequence[str], times_s: Sequence[float], positions_rad: np.ndarray
    ) -> None:
        del joint_names, times_s, positions_rad

    def set_hands(self, open_hands: bool) -> None:
        del open_hands

    def step(self, dt_s: float) -> None:
        """Advances the body by ``dt_s`` seconds."""
        blend = 1.0 - math.exp(-dt_s / self._lag_s) if self._lag_s > 0 else 1.0
        self._velocity += blend * (self._commanded - self._velocity)
        realised = self._velocity * (1.0 + self._velocity_noise * self._rng.standard_normal(3))
        self.true_pose = _integrate(self.true_pose, realised, dt_s)
        self._odometry = _integrate(self._odometry, realised * self._odometry_scale, dt_s)


def _integrate(pose: SE2Pose, body_velocity: np.ndarray, dt_s: float) -> SE2Pose:
    vx, vy, omega = body_velocity
    return pose.compose(SE2Pose(vx * dt_s, vy * dt_s, omega * dt_s))


class FakeClock:
    """Simulated time: :meth:`sleep` steps the humanoid instead of waiting."""

    def __init__(self, humanoid: FakeHumanoid | None = None, step_s: float = 0.01) -> None:
        self._now = 0.0
        self._humanoid = humanoid
        self._step_s = step_s

    def now(self) -> float:
        return self._now

    def sleep(self, seconds: float) -> None:
        remaining = seconds
        while remaining > 1e-12:
            dt = min(self._step_s, remaining)
            if self._humanoid is not None:
                self._humanoid.step(dt)
            self._now += dt
            remaining -= dt


class FakeTagTracker:
    """``locate()`` for the fake: the true pose plus noise, or None when the tag is missed."""

    def __init__(
        self,
        humanoid: FakeHumanoid,
        *,
        position_noise_m: float = 0.003,
        yaw_noise_rad: float = 0.01,
        miss_probability: float = 0.0,
        seed: int = 0,
    ) -> None:
        self._humanoid = humanoid
        self._position_noise_m = position_noise_m
        self._yaw_noise_rad = yaw_noise_rad
        self._miss_probability = miss_probability
        self._rng = np.random.default_rng(seed)
        self.misses = 0

    def __call__(self) -> SE2Pose | None:
        if self._rng.random() < self._miss_probability:
            self.misses += 1
            return None
        pose = self._humanoid.true_pose
        nx, ny = self._rng.normal(0.0, self._position_noise_m, 2)
        return SE2Pose(
            pose.x + nx,
            pose.y + ny,
            wrap_angle(pose.theta + self._rng.normal(0.0, self._yaw_noise_rad)),
        )
