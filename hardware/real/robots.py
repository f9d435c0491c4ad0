"""Connecting the real robots from a checked cell configuration.

Connecting reads state and moves nothing; :func:`activate` sets the NAO up for carrying
(it moves) and is called only after the operator agrees.
"""

from __future__ import annotations

from typing import Any

from bearchair.hardware.backends import build_device
from bearchair.hardware.interfaces import Robot
from bearchair.hardware.real.camera import READ_TIMEOUT_S
from bearchair.hardware.real.nao import NaoHumanoid, NaoSpeaker, WallClock, connect
from bearchair.hardware.real.panda import CONNECT_TIMEOUT_S, PandaArm
from bearchair.hardware.real.standins import (
    STANDIN_HOST,
    OpenNI2Standin,
    PandaStandin,
    sdk_openni2,
    sdk_panda,
)


def connect_panda(config: Any, timeout_s: float = CONNECT_TIMEOUT_S) -> PandaArm:
    """The arm and its camera (``panda_host`` "standin": the SDK stand-ins), each read
    bounded by ``timeout_s``."""
    if config.panda_host == STANDIN_HOST:
        from bearchair.hardware.real.camera import CarmineCamera

        camera = CarmineCamera(
            sdk_openni2(OpenNI2Standin()),
            library_dir=config.openni_library_dir,
            intrinsics=config.camera_intrinsics,
            timeout_s=min(timeout_s, READ_TIMEOUT_S),
        )
        panda = PandaStandin(STANDIN_HOST)
        panda.time_scale = 100.0  # a dry run: the stand-in arm moves 100 times faster
        return PandaArm(
            sdk_panda(panda),
            camera,
            config.T_world_base,
            config.T_flange_camera,
            config.panda_speed_factor,
            payload_mass_kg=config.payload_mass_kg,
        )
    return PandaArm.connect(
        config.panda_host,
        config.T_world_base,
        config.T_flange_camera,
        config.panda_speed_factor,
        config.openni_library_dir,
        camera=config.camera,
        camera_intrinsics=config.camera_intrinsics,
        timeout_s=timeout_s,
        payload_mass_kg=config.payload_mass_kg,
    )


def connect_robots(config: Any, mute: bool = False) -> Robot:
    """Connects the NAO and the Panda of an :class:`bearchair.executive.cell_config.CellConfig`.

    A device whose section names a plug-in backend (``config.devices``) is made by it
    (:func:`bearchair.hardware.backends.build_device`) instead; the NAO is reached only
    when the humanoid or the speaker is the built-in one.

    Args:
        config: the checked cell file.
        mute: the NAO stays silent; instructions are logged as text instead.

    Raises:
        BackendUnavailable: an SDK or a robot is missing (the message names which).
        PluginError: a plug-in backend is missing or does not satisfy its protocol.
    """
    devices: dict[str, dict[str, Any]] = getattr(config, "devices", {}) or {}
    made = {
        role: build_device(role, section["backend"], _settings(section))
        for role, section in devices.items()
    }
    session = None
    if "humanoid" not in made or "speaker" not in made:
        session = connect(config.nao_url, config.nao_user, config.nao_password)
    speaker: Any = made["speaker"] if "speaker" in made else NaoSpeaker(session)
    if mute:
        from bearchair.hardware.speech import TextToSpeech

        speaker = TextToSpeech(mute=True)
    return Robot(
        arm=made["arm"] if "arm" in made else connect_panda(config),
        humanoid=made["humanoid"]
        if "humanoid" in made
        else NaoHumanoid(session, odom_origin=config.nao_start),
        speaker=speaker,
        clock=WallClock(),
    )


def _settings(section: dict[str, Any]) -> dict[str, Any]:
    return {key: value for key, value in section.items() if key != "backend"}


def activate(robot: Robot) -> None:
    """Sets the arm's collision thresholds and payload, then the NAO up for carrying
    (Autonomous Life and awareness off, no arm swing, carrying posture, hands closed,
    head held): the robots move from here on. A plug-in's device without ``activate``
    needs none."""
    for device in (robot.arm, robot.humanoid):
        activate_device = getattr(device, "activate", None)
        if callable(activate_device):
            activate_device()
