"""Walking control: following the SE(2) path with PID controllers on the tracked pose.

See :mod:`bearchair.skills.control.walk`; :mod:`bearchair.hardware.fakes` holds the test doubles it walks.
"""

from bearchair.skills.control.pid import PID
from bearchair.skills.control.walk import WalkError, WalkGains, walk_path

__all__ = ["PID", "WalkError", "WalkGains", "walk_path"]
