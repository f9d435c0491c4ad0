"""Connecting the real robots from a checked cell configuration.

Connecting reads state and moves nothing; :func:`activate` sets the NAO up for carrying
(it moves) and is called only after the operator agrees.
"""

from __future__ import annotations

from typing import Any

from bearchair.hardware.backends import build_device
from bearchair.hardware.interfaces import Robot
from bearchair.hardware.real.nao import NaoHumanoid, NaoSpeaker, WallClock, connect
from bearchair.hardware.real.panda import PandaArm
from bearchair.hardware.real.standins import STANDIN_HOST, FakeOpenNI2, FakePanda


def connect_panda(config: Any) -> PandaArm:
    """The arm and its camera (``panda_host`` "standin": the SDK stand-ins)."""
    if config.panda_host == STANDIN_HOST:
        from bearchair.hardware.real.camera import CarmineCamera

        camera = CarmineCamera(FakeOpenNI2(), library_dir=config.openni_library_dir)
        panda = FakePanda(STANDIN_HOST)
        panda.time_scale = 100.0  # a dry run: the stand-in arm moves 100 times faster
        return PandaArm(
            panda,
            camera,
            config.T_world_base,
            config.T_flange_camera,
            config.panda_speed_factor,
        )
    return PandaArm.connect(
        config.panda_host,
        config.T_world_base,
        config.T_flange_camera,
        config.panda_speed_factor,
        config.openni_library_dir,
        camera=config.camera,
    )


def connect_robots(config: Any) -> Robot:
    """Connects the NAO and the Panda of an :class:`bearchair.executive.cell_config.CellConfig`.

    A device whose section names a plug-in backend (``config.devices``) is made by it
    (:func:`bearchair.hardware.backends.build_device`) instead; the NAO is reached only
    when the humanoid or the speaker is the built-in one.

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
    return Robot(
        arm=made["arm"] if "arm" in made else connect_panda(config),
        humanoid=made["humanoid"]
        if "humanoid" in made
        else NaoHumanoid(session, odom_origin=config.nao_start),
        speaker=made["speaker"] if "speaker" in made else NaoSpeaker(session),
        clock=WallClock(),
    )


def _settings(section: dict[str, Any]) -> dict[str, Any]:
    return {key: value for key, value in section.items() if key != "backend"}


def activate(robot: Robot) -> None:
    """Sets the NAO up for carrying (Autonomous Life and awareness off, no arm swing,
    carrying posture, hands closed, head held): the robots move from here on."""
    activate_humanoid = getattr(robot.humanoid, "activate", None)  # a plug-in's may have none
    if callable(activate_humanoid):
        activate_humanoid()
