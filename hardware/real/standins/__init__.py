"""Stand-ins for the robot SDKs, built from the SDKs themselves, for tests and dry runs.

* :mod:`.naoqi`: :class:`NaoqiStandin`, a standalone ``qi`` session serving NAOqi's
  services with the signatures of NAOqi 2.8's API table (``naoqi_api.json``), the NAO's
  joints and limits (qibullet's nao.urdf) and the behaviours the documentation states.
* :mod:`.panda`: :class:`FakePanda`, panda-py's ``Panda`` with the Panda's kinematics,
  libfranka's state arrays, reflexes, automatic recovery and ``Robot::stop``.
* :mod:`.openni`: :class:`FakeOpenNI2`, ``openni.openni2`` with the PS1080 driver's
  defaults (320x240, mirroring on).
* :mod:`.realsense`: :class:`FakeRealSense`, ``pyrealsense2``'s pipeline.
* :mod:`.sdk_double`: :func:`sdk_double`, which puts a fake behind the installed SDK's
  own classes, so a call or attribute the SDK lacks fails as it would on the robot.

A cell file whose ``panda_host`` is ``"standin"`` gets :class:`FakePanda` and a
:class:`FakeOpenNI2` camera (``bearchair check-hardware`` dry runs).
"""

from __future__ import annotations

from typing import Any

from bearchair.hardware.real.standins.naoqi import JointKeyframes, KinematicNao, NaoqiStandin
from bearchair.hardware.real.standins.openni import FakeOpenNI2
from bearchair.hardware.real.standins.panda import (
    FRANKA_HAND_F_T_EE,
    ControlException,
    FakePanda,
    panda_flange_pose,
)
from bearchair.hardware.real.standins.realsense import FakeRealSense
from bearchair.hardware.real.standins.sdk_double import sdk_double


def sdk_panda(fake: FakePanda) -> Any:
    """``fake`` behind the installed ``panda_py.Panda`` (the fake itself without panda-py)."""
    try:
        import panda_py
    except ImportError:
        return fake
    return sdk_double(fake, panda_py.Panda, module=panda_py)


def sdk_openni2(fake: FakeOpenNI2) -> Any:
    """``fake`` behind the installed ``openni.openni2`` (the fake itself without it)."""
    try:
        from openni import openni2
    except ImportError:
        return fake
    returns = {
        "create_depth_stream": openni2.VideoStream,
        "create_color_stream": openni2.VideoStream,
        "read_frame": openni2.VideoFrame,
        "get_video_mode": openni2.VideoMode,
        "open_any": openni2.Device,
    }
    return sdk_double(fake, openni2, returns=returns)


def sdk_realsense(fake: FakeRealSense) -> Any:
    """``fake`` behind the installed ``pyrealsense2`` (the fake itself without it)."""
    try:
        import pyrealsense2
    except ImportError:
        return fake
    return sdk_double(fake, pyrealsense2)


STANDIN_HOST = "standin"
"""The ``panda_host`` that selects :class:`FakePanda` and :class:`FakeOpenNI2`."""

__all__ = [
    "FRANKA_HAND_F_T_EE",
    "STANDIN_HOST",
    "ControlException",
    "FakeOpenNI2",
    "FakePanda",
    "FakeRealSense",
    "JointKeyframes",
    "KinematicNao",
    "NaoqiStandin",
    "panda_flange_pose",
    "sdk_double",
    "sdk_openni2",
    "sdk_panda",
    "sdk_realsense",
]
