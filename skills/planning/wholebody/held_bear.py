"""The bear in the NAO's hands: its outline, the grasp, and where a posture holds it.

The bear (0.2 kg, its frame at its seat point: the bottom centre of its torso) is held
rigidly between the palms in the pose it had when handed over: upright, its seat point
``BEAR_SEAT_BELOW_HANDS_M`` below the palms' middle with the NAO in
``CARRYING_POSTURE_RAD`` (both from :mod:`bearchair.core.nao_carrying`, shared with the
simulator; see :func:`carrying_grasp`). The whole-body problems
(:mod:`.optimisation`) place it through :func:`held_bear`. Planar NAO frame: x forward,
z up, metres, radians.
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np
from scipy.spatial.transform import Rotation

from bearchair.core.nao_carrying import (
    BEAR_COM_HEIGHT_M,
    BEAR_SEAT_BELOW_HANDS_M,
    CARRYING_POSTURE_RAD,
    PALM_IN_WRIST_M,
)
from bearchair.hardware.bear_model import BEAR_MASS_KG
from bearchair.skills.planning.wholebody.nao_model import PlanarNao, link_transforms

BEAR_HEIGHT_M = 0.25
"""Height of the bear's outline above its seat point (the simulated bear's 0.25 m)."""
BEAR_DEPTH_M = 0.10
"""Fore-aft extent of the bear's outline (torso and head; its short legs are ignored)."""
BEAR_SNOUT_M = 0.03
"""How far the bear's snout and nose stand out of its outline's front (toward the NAO),
metres, over the heights ``BEAR_SNOUT_Z_M`` above its base (the simulated bear,
``hardware/bear_model.py``, has its nose 0.076 m ahead of its centre, 0.145-0.18 m up)."""
BEAR_SNOUT_Z_M = (0.14, 0.19)

# Bear outline points (x along the bear's forward, z up from its base), metres.
BEAR_OUTLINE = (
    *(
        (sx * BEAR_DEPTH_M / 2.0, fz * BEAR_HEIGHT_M, f"bear {side} {level}")
        for sx, side in ((-1.0, "front"), (1.0, "back"))
        for fz, level in ((0.0, "bottom"), (0.5, "middle"), (1.0, "top"))
    ),
    (0.0, 0.0, "bear bottom centre"),
    (0.0, BEAR_HEIGHT_M, "bear top centre"),
)


@lru_cache(maxsize=1)
def carrying_grasp() -> tuple[float, np.ndarray]:
    """The held bear in the hands frame: (ψ_c, (x, z) offset of its seat point).

    The hands frame is the palms' middle with the mean of both palms' orientations; in a
    mirror-symmetric posture that mean is a pure pitch ψ about y. When the bear is handed
    over (NAO in :data:`CARRYING_POSTURE_RAD`), it is upright with its seat point
    :data:`BEAR_SEAT_BELOW_HANDS_M` (b) below the palms' middle, so in the hands frame its
    orientation is a pitch of -ψ_c and its seat point is ``R_y(-ψ_c) (0, -b)``.
    """
    frames = link_transforms(CARRYING_POSTURE_RAD)
    T_palm = frames["l_wrist"].copy()
    T_palm[:3, 3] = T_palm[:3, :3] @ np.asarray(PALM_IN_WRIST_M) + T_palm[:3, 3]
    mirror = np.diag([1.0, -1.0, 1.0])
    left = Rotation.from_matrix(T_palm[:3, :3]).as_quat()
    right = Rotation.from_matrix(mirror @ T_palm[:3, :3] @ mirror).as_quat()
    if np.dot(left, right) < 0.0:
        right = -right
    mean = Rotation.from_quat(left + right).as_matrix()
    pitch = math.atan2(-mean[2, 0], mean[0, 0])
    c, s = math.cos(pitch), math.sin(pitch)
    # World (x, z) = R_y(ψ) (x, z)_hands with R_y(ψ)(x, z) = (c x + s z, -s x + c z).
    below = np.array([0.0, -BEAR_SEAT_BELOW_HANDS_M])
    offset = np.array([c * below[0] - s * below[1], s * below[0] + c * below[1]])
    return pitch, offset


def held_bear(
    nao: PlanarNao, frames: dict[str, ca.SX], bear_held: ca.SX
) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX, ca.SX]:
    """(bear base (x, z), its forward and up axes, the centre of mass (x, z) of the NAO and
    the bear it holds, the torso's pitch) of a symbolic posture's ``frames``."""
    nao_com, nao_mass = nao.centre_of_mass(frames)
    # The hands frame (the palms' middle, their mean orientation: a pure pitch ψ by
    # symmetry) and the bear rigidly attached to it as in the carrying posture.
    palm = nao.point(frames, "l_wrist", PALM_IN_WRIST_M)
    rot = frames["l_wrist"][:3, :3]
    hands_x = ca.vertcat(rot[0, 0], rot[2, 0])
    hands_z = ca.vertcat(-hands_x[1], hands_x[0])
    grasp_pitch, grasp_offset = carrying_grasp()
    bear_base = palm + grasp_offset[0] * hands_x + grasp_offset[1] * hands_z
    c, s = math.cos(grasp_pitch), math.sin(grasp_pitch)
    forward = c * hands_x + s * hands_z
    up = -s * hands_x + c * hands_z
    bear_com = bear_base + BEAR_COM_HEIGHT_M * up
    bear_mass = BEAR_MASS_KG * bear_held
    com = (nao_mass * nao_com + bear_mass * bear_com) / (nao_mass + bear_mass)
    torso_rot = frames["torso"][:3, :3]
    torso_pitch = ca.atan2(-torso_rot[2, 0], torso_rot[0, 0])
    return bear_base, forward, up, com, torso_pitch
