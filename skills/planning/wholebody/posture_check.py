"""A posture checked against the exact (non-smoothed) constraints: every solution the
optimisation returns is re-checked here before it is used."""

from __future__ import annotations

import numpy as np

from bearchair.skills.planning.wholebody.chair_profile import ChairProfile
from bearchair.skills.planning.wholebody.optimisation import (
    ARM_POINTS,
    LEG_TORSO_HEAD_POINTS,
    NO_RELEASED_BEAR,
    SeatingProblems,
)

CHECK_TOLERANCE = 1e-4
"""The largest exact constraint violation accepted (metres or radians)."""


def _worst_violation(
    problems: SeatingProblems, values: np.ndarray, lower: np.ndarray, upper: np.ndarray
) -> tuple[float, str, str]:
    """(violation in metres or radians, group, label) of the most violated row."""
    values = values.reshape(-1, len(problems.rows))
    lower = lower.reshape(-1, len(problems.rows))
    upper = upper.reshape(-1, len(problems.rows))
    violation = np.maximum(lower - values, values - upper)
    knot, row = np.unravel_index(int(np.argmax(violation)), violation.shape)
    entry = problems.rows[row]
    label = entry.label if violation.shape[0] == 1 else f"{entry.label} at knot {knot}"
    return float(violation[knot, row]), entry.group, label


def _posture_values(
    problems: SeatingProblems,
    q: np.ndarray,
    profile: ChairProfile,
    bear_held: bool,
    released: np.ndarray = NO_RELEASED_BEAR,
) -> np.ndarray:
    return np.asarray(
        problems.posture_constraints(q, profile.as_vector(), float(bear_held), released)
    ).ravel()


def exact_posture_violation(
    problems: SeatingProblems,
    q: np.ndarray,
    profile: ChairProfile,
    *,
    g_xz: np.ndarray | None,
    tilt_rad: float,
    bear_held: bool = True,
    released: np.ndarray = NO_RELEASED_BEAR,
) -> tuple[float, str, str]:
    """Worst violation of a posture's constraints with the exact block clearance.

    The optimisation's smoothed max over-estimates the clearance by at most ln(2)/κ;
    here the clearances come from :meth:`ChairProfile.clearance` instead. ``released``:
    where a let-go bear rests (:func:`.optimisation.released_bear`), with ``bear_held``
    False.
    """
    lower, upper = problems.posture_bounds(g_xz=g_xz, tilt_rad=tilt_rad)
    values = _posture_values(problems, q, profile, bear_held, released)
    geometry = problems.geometry(q, bear_held)
    for i, row in enumerate(problems.rows):
        if row.group != "chair collision":
            continue
        if row.label.startswith("NAO "):
            label = row.label[4:]
            point = geometry.body_points[label]
            radius = _radius_of(label)
            values[i] = profile.clearance(point[None, :])[0] - radius
        elif bear_held:
            values[i] = profile.clearance(geometry.bear_points[row.label][None, :])[0]
    return _worst_violation(problems, values, lower, upper)


def _radius_of(label: str) -> float:
    for _, _, radius, name in LEG_TORSO_HEAD_POINTS + ARM_POINTS:
        if name == label:
            return radius
    raise KeyError(label)
