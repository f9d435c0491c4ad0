"""Backends for the real robots, through their SDKs.

* :mod:`bearchair.hardware.real.nao`: the NAO through NAOqi (``qi``): walking, joint
  trajectories, hands, speech.
* :mod:`bearchair.hardware.real.panda`: the Franka Panda through ``panda_py``.
* :mod:`bearchair.hardware.real.camera`: the PrimeSense Carmine through OpenNI2 (``openni``).
* :mod:`bearchair.hardware.real.robots`: all of them from a checked cell file.
* :mod:`bearchair.hardware.real.monitor`: the devices' health watched during a run.
* :mod:`bearchair.hardware.real.bounded`: waits that never hang.
* :mod:`bearchair.hardware.real.standins`: SDK stand-ins for tests and ``check-hardware`` dry runs.

The SDKs are imported only when a backend is built, so the rest of the project installs
and tests without them; a missing SDK raises :class:`BackendUnavailable` saying what to
install.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from bearchair.core.errors import BackendError, BackendUnavailable


class EmergencyStopped(BackendError, RuntimeError):
    """A motion was refused or ended because the robot was emergency-stopped."""


class RobotFault(BackendError, RuntimeError):
    """A device reported it cannot go on (battery, fall, temperature, arm reflex): the
    mission stops with this message (:class:`bearchair.hardware.real.monitor.RobotMonitor`)."""


SDK_DISTRIBUTIONS = {
    "qi": "nao",
    "panda-python": "panda",
    "openni": "carmine",
    "pyrealsense2": "realsense",
}
"""Each robot SDK's pip distribution and the bearchair extra that installs it."""


def sdk_versions() -> dict[str, str | None]:
    """The installed version of each robot SDK (None where it is not installed)."""
    from importlib import metadata

    versions: dict[str, str | None] = {}
    for distribution in SDK_DISTRIBUTIONS:
        try:
            versions[distribution] = metadata.version(distribution)
        except metadata.PackageNotFoundError:
            versions[distribution] = None
    return versions


def import_sdk(module: str, package: str) -> ModuleType:
    """Imports a robot SDK module, or raises BackendUnavailable naming the pip package."""
    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise BackendUnavailable(
            f"the '{module}' SDK is not installed; install it with: pip install '{package}'"
        ) from error
