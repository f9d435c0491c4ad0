"""Can the NAO's arms put the bear's pelvis at a point in front of it?

A sagittal-plane reach model used when the whole-body planner is not available, and to
decide how far the sitting position may be from the NAO (the paper's "robot workspace
constraint" in the System Pipeline). Numbers from qibullet's ``nao.urdf``:

* hip height standing: tibia 0.1029 + thigh 0.1 + ankle-to-sole 0.04519 = 0.248 m;
  torso 0.085 m above the hips (``HipOffsetZ``), so 0.333 m above the floor;
* shoulders 0.1 m above the torso and 0.098 m to the side (``LShoulderPitch`` origin);
* shoulder to palm: upper arm 0.105 + forearm 0.05595 + hand 0.05775 = 0.2187 m.

The two hands hold the bear by its sides (``BEAR_HALF_WIDTH_M`` from its centre line), so
each arm also covers 0.098 - 0.06 m sideways; the bear's pelvis hangs
``GRASP_ABOVE_PELVIS_M`` below the hands. The body may bend forward at the hips by up to
``MAX_TORSO_PITCH_RAD`` (the paper prefers little bending) and crouch by up to
``MAX_CROUCH_M``. A point is reachable when some bend and crouch put it within the arm's
length of the shoulder, in front of the torso.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

HIP_HEIGHT_M = 0.1029 + 0.1 + 0.04519
HIP_TO_SHOULDER_M = 0.085 + 0.1
SHOULDER_OFFSET_Y_M = 0.098
ARM_LENGTH_M = 0.105 + 0.05595 + 0.05775
BEAR_HALF_WIDTH_M = 0.06
GRASP_ABOVE_PELVIS_M = 0.05
MAX_TORSO_PITCH_RAD = 0.6
MAX_CROUCH_M = 0.06
MIN_FORWARD_M = 0.10
"""The bear must be at least this far in front of the NAO's vertical axis (its own body)."""
REACH_MARGIN = 0.95
"""Fraction of the arm's length used, to keep clear of the singular stretched arm."""

_EFFECTIVE_ARM_M = REACH_MARGIN * math.sqrt(
    ARM_LENGTH_M**2 - (SHOULDER_OFFSET_Y_M - BEAR_HALF_WIDTH_M) ** 2
)
_pitches, _crouches = np.meshgrid(
    np.linspace(0.0, MAX_TORSO_PITCH_RAD, 13), np.linspace(0.0, MAX_CROUCH_M, 4)
)
# Shoulder positions (forward, up) over every bend and crouch, NAO frame, metres.
_SHOULDERS = np.stack(
    [
        HIP_TO_SHOULDER_M * np.sin(_pitches).ravel(),
        HIP_HEIGHT_M - _crouches.ravel() + HIP_TO_SHOULDER_M * np.cos(_pitches).ravel(),
    ],
    axis=1,
)


class ReachCheck(NamedTuple):
    """The arm-reach verdict for one bear placement.

    Attributes:
        reachable: the hands can put the bear's pelvis there.
        forward_m: horizontal distance of the pelvis in front of the NAO.
        height_m: pelvis height above the floor.
        max_forward_m: the farthest reachable forward distance at that height (0 if none).
        reason: why not (empty when reachable).
    """

    reachable: bool
    forward_m: float
    height_m: float
    max_forward_m: float
    reason: str = ""


def max_forward_reach(pelvis_height_m: float) -> float:
    """Farthest horizontal distance (metres) in front of the NAO at which its hands can hold
    the bear's pelvis at ``pelvis_height_m``; 0 when that height is out of reach."""
    dz = pelvis_height_m + GRASP_ABOVE_PELVIS_M - _SHOULDERS[:, 1]
    inside = np.abs(dz) <= _EFFECTIVE_ARM_M
    if not inside.any():
        return 0.0
    forward = _SHOULDERS[inside, 0] + np.sqrt(_EFFECTIVE_ARM_M**2 - dz[inside] ** 2)
    return float(forward.max())


def check_reach(forward_m: float, pelvis_height_m: float) -> ReachCheck:
    """Whether the NAO can place the bear's pelvis ``forward_m`` ahead at ``pelvis_height_m``.

    Args:
        forward_m: horizontal distance from the NAO's vertical axis along its heading.
        pelvis_height_m: height of the bear's pelvis above the floor.
    """
    max_forward = max_forward_reach(pelvis_height_m)
    if max_forward == 0.0:
        return ReachCheck(
            False,
            forward_m,
            pelvis_height_m,
            0.0,
            f"the seat is out of the NAO's reach in height ({pelvis_height_m:.2f} m)",
        )
    if forward_m > max_forward:
        return ReachCheck(
            False,
            forward_m,
            pelvis_height_m,
            max_forward,
            f"the sitting position is {forward_m:.2f} m ahead, beyond the arms' "
            f"{max_forward:.2f} m",
        )
    if forward_m < MIN_FORWARD_M:
        return ReachCheck(
            False,
            forward_m,
            pelvis_height_m,
            max_forward,
            f"the sitting position is {forward_m:.2f} m ahead, inside the NAO's body",
        )
    target = np.array([forward_m, pelvis_height_m + GRASP_ABOVE_PELVIS_M])
    if np.linalg.norm(_SHOULDERS - target, axis=1).min() > _EFFECTIVE_ARM_M:
        return ReachCheck(False, forward_m, pelvis_height_m, max_forward, "out of the arms' reach")
    return ReachCheck(True, forward_m, pelvis_height_m, max_forward)
