"""The simulated world (pybullet): the embedded default backend of the mission.

``SimWorld(SimConfig(...)).robot`` gives every device behind the protocols of
:mod:`bearchair.hardware.interfaces`. ``python -m bearchair.hardware.sim`` prints timing figures and writes
pictures of the scene.
"""

from bearchair.hardware.sim.camera import CARMINE_INTRINSICS, CarmineNoise
from bearchair.hardware.sim.panda import PANDA_READY_RAD, look_at
from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.hardware.wrist_mount import T_HAND_CAMERA

__all__ = [
    "CARMINE_INTRINSICS",
    "PANDA_READY_RAD",
    "T_HAND_CAMERA",
    "CarmineNoise",
    "SimConfig",
    "SimWorld",
    "look_at",
]
