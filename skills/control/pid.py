"""A discrete PID controller with anti-windup, for one scalar error."""

from __future__ import annotations

import math


class PID:
    """u = kp e + ki ∫e dt + kd de/dt, with the integral clamped to ±``integral_limit``.

    The derivative is taken on the error and skipped on the first update after a reset,
    so a new setpoint gives no derivative kick.
    """

    def __init__(
        self, kp: float, ki: float = 0.0, kd: float = 0.0, integral_limit: float = math.inf
    ) -> None:
        self.kp, self.ki, self.kd = kp, ki, kd
        self.integral_limit = integral_limit
        self.reset()

    def reset(self) -> None:
        """Forgets the integral and the previous error."""
        self._integral = 0.0
        self._previous: float | None = None

    def update(self, error: float, dt_s: float) -> float:
        """The control output for ``error`` after ``dt_s`` seconds."""
        if dt_s <= 0.0:
            raise ValueError(f"PID time step must be positive, got {dt_s}")
        self._integral = max(
            -self.integral_limit, min(self.integral_limit, self._integral + error * dt_s)
        )
        derivative = 0.0 if self._previous is None else (error - self._previous) / dt_s
        self._previous = error
        return self.kp * error + self.ki * self._integral + self.kd * derivative
