"""Typed failures of the perception skills."""

from __future__ import annotations

from bearchair.core.errors import SkillError


class PerceptionError(SkillError, RuntimeError):
    """The camera data cannot give an answer: bad frames, no chair, too few points."""


class RegistrationError(PerceptionError):
    """Registration of the chair's new view to its reference failed its quality checks."""


class HandEyeError(PerceptionError):
    """The hand-eye calibration cannot give a trustworthy answer (too few poses, rotations
    too alike, inconsistent inputs): one line, exit status 2 on the command line."""


class BoardNotSeenError(HandEyeError):
    """The calibration board is not in a frame, or too little of it to fix its pose."""
