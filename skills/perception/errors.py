"""Typed failures of the perception skills."""

from __future__ import annotations


class PerceptionError(RuntimeError):
    """The camera data cannot give an answer: bad frames, no chair, too few points."""


class RegistrationError(PerceptionError):
    """Registration of the chair's new view to its reference failed its quality checks."""
