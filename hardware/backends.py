"""Robot backends by name: the ``bearchair.backends`` entry points, checked against the protocols.

A cell file (``bearchair run --robots cell.json``) may give a device a section of its
own naming its backend, e.g. ``"speaker": {"backend": "my-speaker", "volume": 0.5}``.
``nao`` and ``panda`` are the built-in backends; any other name is an entry point of
:data:`BACKENDS_GROUP` naming a factory called with the section's other keys::

    def make_speaker(settings: Mapping[str, Any]) -> Speaker: ...

The device it returns must satisfy the protocol of its role (:data:`ROLES`): a missing
or incompatible method is refused with one line naming it, before anything moves.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from bearchair.core.errors import PluginError, one_line
from bearchair.core.plugins import load_entry_point
from bearchair.core.protocols import protocol_gaps
from bearchair.hardware.interfaces import Humanoid, ScanningArm, Speaker

BACKENDS_GROUP = "bearchair.backends"
"""The entry point group of robot backends."""
ROLES: dict[str, type] = {"arm": ScanningArm, "humanoid": Humanoid, "speaker": Speaker}
"""The devices a cell section may select a backend for, and the protocol each satisfies."""
BUILT_IN: dict[str, str] = {"arm": "panda", "humanoid": "nao", "speaker": "nao"}
"""The backend each role has unless its section names another."""


def build_device(role: str, backend: str, settings: Mapping[str, Any]) -> Any:
    """The device of ``role`` made by the plug-in backend ``backend`` from ``settings``.

    Raises:
        PluginError: the role is unknown, the backend is not installed or cannot be
            loaded, its factory fails, or the device does not satisfy the role's protocol.
    """
    if role not in ROLES:
        raise PluginError(f"no device role {role!r}; roles: {', '.join(ROLES)}")
    origin = f"{role} backend {backend!r}"
    factory = load_entry_point(BACKENDS_GROUP, backend, "robot backend")
    if not callable(factory):
        raise PluginError(f"{origin}: {type(factory).__name__} is not a device factory")
    try:
        device = factory(dict(settings))
    except Exception as error:
        raise PluginError(f"{origin}: making the device failed: {one_line(error)}") from error
    check_device(device, role, origin)
    return device


def check_device(device: object, role: str, origin: str) -> None:
    """Raises PluginError (one line) unless ``device`` satisfies the protocol of ``role``."""
    protocol = ROLES[role]
    gaps = protocol_gaps(device, protocol)
    if gaps:
        raise PluginError(f"{origin}: not a {protocol.__name__}: {'; '.join(gaps)}")
