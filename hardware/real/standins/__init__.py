"""Stand-ins for the robot SDKs, built from the SDKs themselves, for tests and dry runs.

* :mod:`.naoqi`: :class:`NaoqiStandin`, a standalone ``qi`` session serving NAOqi's
  services with the signatures of NAOqi 2.8's API table (``naoqi_api.json``), the NAO's
  joints and limits (qibullet's nao.urdf) and the behaviours the documentation states.
* :mod:`.panda`: :class:`PandaStandin`, panda-py's ``Panda`` with the Panda's kinematics,
  libfranka's state arrays, reflexes, automatic recovery and ``Robot::stop``.
* :mod:`.openni`: :class:`OpenNI2Standin`, ``openni.openni2`` with the PS1080 driver's
  defaults (320x240, mirroring on).
* :mod:`.realsense`: :class:`RealSenseStandin`, ``pyrealsense2``'s pipeline.
* :mod:`.sdk_double`: :func:`sdk_double`, which puts a stand-in behind the installed SDK's
  own classes, so a call or attribute the SDK lacks fails as it would on the robot.

A cell file whose ``panda_host`` is ``"standin"`` gets :class:`PandaStandin` and a
:class:`OpenNI2Standin` camera (``bearchair check-hardware`` dry runs).
"""

from __future__ import annotations

from typing import Any

from bearchair.hardware.real.standins.naoqi import JointKeyframes, KinematicNao, NaoqiStandin
from bearchair.hardware.real.standins.openni import OpenNI2Standin
from bearchair.hardware.real.standins.panda import (
    FRANKA_HAND_F_T_EE,
    ControlException,
    PandaStandin,
    panda_flange_pose,
)
from bearchair.hardware.real.standins.realsense import RealSenseStandin
from bearchair.hardware.real.standins.sdk_double import sdk_double


def sdk_panda(standin: PandaStandin) -> Any:
    """``standin`` behind the installed ``panda_py.Panda`` (the stand-in itself without
    panda-py)."""
    try:
        import panda_py
    except ImportError:
        return standin
    return sdk_double(standin, panda_py.Panda, module=panda_py)


def sdk_openni2(standin: OpenNI2Standin) -> Any:
    """``standin`` behind the installed ``openni.openni2`` (the stand-in itself without it)."""
    try:
        from openni import openni2
    except ImportError:
        return standin
    returns = {
        "create_depth_stream": openni2.VideoStream,
        "create_color_stream": openni2.VideoStream,
        "read_frame": openni2.VideoFrame,
        "get_video_mode": openni2.VideoMode,
        "open_any": openni2.Device,
    }
    return sdk_double(standin, openni2, returns=returns)


def sdk_realsense(standin: RealSenseStandin) -> Any:
    """``standin`` behind the installed ``pyrealsense2`` (the stand-in itself without it)."""
    try:
        import pyrealsense2
    except ImportError:
        return standin
    return sdk_double(standin, pyrealsense2)


STANDIN_HOST = "standin"
"""The ``panda_host`` that selects :class:`PandaStandin` and :class:`OpenNI2Standin`."""

__all__ = [
    "FRANKA_HAND_F_T_EE",
    "STANDIN_HOST",
    "ControlException",
    "JointKeyframes",
    "KinematicNao",
    "NaoqiStandin",
    "OpenNI2Standin",
    "PandaStandin",
    "RealSenseStandin",
    "panda_flange_pose",
    "sdk_double",
    "sdk_openni2",
    "sdk_panda",
    "sdk_realsense",
]
