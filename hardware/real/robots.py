"""Connecting the real robots from a JSON description of the cell."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from hardware.interfaces import Robot
from hardware.real import BackendUnavailable
from hardware.real.nao import NaoHumanoid, NaoSpeaker, WallClock, connect
from hardware.real.panda import PandaArm
from skills.geometry import SE2Pose

EXAMPLE = """{
  "nao_url": "tcp://nao.local:9559",
  "panda_host": "172.16.0.2",
  "T_world_base": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]],
  "T_hand_camera": [[1,0,0,0.05],[0,1,0,0],[0,0,1,0.06],[0,0,0,1]],
  "nao_start": [1.9, 0.0, 3.14159]
}"""


def connect_robots(cell_file: Path) -> Robot:
    """Connects the NAO and the Panda described by ``cell_file`` (see :data:`EXAMPLE`).

    Raises:
        BackendUnavailable: a file, an SDK or a robot is missing.
    """
    try:
        cell = json.loads(Path(cell_file).read_text())
        nao_url, panda_host = cell["nao_url"], cell["panda_host"]
        T_world_base = np.asarray(cell["T_world_base"], dtype=float).reshape(4, 4)
        T_hand_camera = np.asarray(cell["T_hand_camera"], dtype=float).reshape(4, 4)
        nao_start = SE2Pose(*map(float, cell.get("nao_start", (0.0, 0.0, 0.0))))
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise BackendUnavailable(
            f"{cell_file}: not a usable cell description ({error}); see README, 'Real robots'"
        ) from error
    session = connect(nao_url)
    return Robot(
        arm=PandaArm.connect(panda_host, T_world_base, T_hand_camera),
        humanoid=NaoHumanoid(session, odom_origin=nao_start),
        speaker=NaoSpeaker(session),
        clock=WallClock(),
    )
