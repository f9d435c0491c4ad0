"""Perception: scan and reconstruct the chair, track its rotation, track the humanoid's tag.

Everything works on :class:`bearchair.hardware.interfaces.RGBDFrame` from any camera backend; the
functions taking a :class:`bearchair.hardware.interfaces.ScanningArm` move it and capture.
"""

from bearchair.skills.perception.chair_turn import measure_chair_rotation
from bearchair.skills.perception.errors import PerceptionError, RegistrationError
from bearchair.skills.perception.look_from_above import (
    LookCancelled,
    NoViewFromAbove,
    look_at_seat,
    look_from_above,
)
from bearchair.skills.perception.motion import wait_until_chair_still
from bearchair.skills.perception.reconstruction import reconstruct_chair
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.perception.registration import RegistrationConfig, register_chair
from bearchair.skills.perception.scan import ScanCancelled, scan_chair
from bearchair.skills.perception.tags import TagSightings, estimate_tag_pose, locate_humanoid

__all__ = [
    "LookCancelled",
    "NoViewFromAbove",
    "PerceptionError",
    "ReconstructionConfig",
    "RegistrationConfig",
    "RegistrationError",
    "ScanCancelled",
    "TagSightings",
    "estimate_tag_pose",
    "locate_humanoid",
    "look_at_seat",
    "look_from_above",
    "measure_chair_rotation",
    "reconstruct_chair",
    "register_chair",
    "scan_chair",
    "wait_until_chair_still",
]
