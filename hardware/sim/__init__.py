"""The simulated world (pybullet): the embedded default backend of the mission.

``SimWorld(SimConfig(...)).robot`` gives every device behind the protocols of
:mod:`hardware.interfaces`. ``python -m hardware.sim`` prints timing figures and writes
pictures of the scene.
"""

from hardware.sim.camera import CARMINE_INTRINSICS, T_HAND_CAMERA, CarmineNoise
from hardware.sim.panda import PANDA_READY_RAD, look_at
from hardware.sim.world import SimConfig, SimWorld

__all__ = [
    "CARMINE_INTRINSICS",
    "PANDA_READY_RAD",
    "T_HAND_CAMERA",
    "CarmineNoise",
    "SimConfig",
    "SimWorld",
    "look_at",
]
