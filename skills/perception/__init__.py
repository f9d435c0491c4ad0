"""Perception: scan and reconstruct the chair, track its rotation, track the humanoid's tag."""

from skills.perception.errors import PerceptionError, RegistrationError
from skills.perception.reconstruction import ReconstructionConfig, reconstruct_chair

__all__ = ["PerceptionError", "ReconstructionConfig", "RegistrationError", "reconstruct_chair"]
