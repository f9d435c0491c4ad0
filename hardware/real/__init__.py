"""Backends for the real robots, through their SDKs.

* :mod:`hardware.real.nao`: the NAO through NAOqi (``qi``): walking, joint
  trajectories, hands, speech.
* :mod:`hardware.real.panda`: the Franka Panda through ``panda_py`` with a PrimeSense
  Carmine through OpenNI2 (``openni``) on its wrist.

The SDKs are imported only when a backend is built, so the rest of the project installs
and tests without them; a missing SDK raises :class:`BackendUnavailable` saying what to
install.
"""

from __future__ import annotations

import importlib
from types import ModuleType


class BackendUnavailable(RuntimeError):
    """A robot SDK is not installed or the robot cannot be reached."""


def import_sdk(module: str, package: str) -> ModuleType:
    """Imports a robot SDK module, or raises BackendUnavailable naming the pip package."""
    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise BackendUnavailable(
            f"the '{module}' SDK is not installed ({error}); install it with: pip install {package}"
        ) from error
