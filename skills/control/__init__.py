"""Walking control: following the SE(2) path with PID controllers on the tracked pose.

See :mod:`skills.control.walk`; :mod:`hardware.fakes` holds the test doubles it walks.
"""

from skills.control.pid import PID
from skills.control.walk import WalkError, WalkGains, walk_path

__all__ = ["PID", "WalkError", "WalkGains", "walk_path"]
