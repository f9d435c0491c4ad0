"""Cell files: a good one's content, and one written for the SDK stand-ins."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

GOOD_CELL = {
    "nao_url": "tcp://nao.local:9559",
    "panda_host": "172.16.0.2",
    "T_world_base": np.eye(4).tolist(),
    "T_flange_camera": [[0, 1, 0, 0.065], [-1, 0, 0, 0], [0, 0, 1, 0.02], [0, 0, 0, 1]],
    "nao_start_x_m": 1.9,
    "nao_start_y_m": 0.0,
    "nao_start_yaw_rad": 3.14159,
}
"""A cell file's content that loads: every field a real cell needs."""


def standin_cell_file(tmp_path: Path, nao_url: str) -> Path:
    """A cell file in ``tmp_path`` for the SDK stand-ins: the NAO at ``nao_url``, the
    Panda's stand-in, identity mounts."""
    path = tmp_path / "cell.json"
    path.write_text(
        json.dumps(
            {
                "nao_url": nao_url,
                "panda_host": "standin",
                "T_world_base": np.eye(4).tolist(),
                "T_flange_camera": np.eye(4).tolist(),
                "nao_start_x_m": 1.9,
                "nao_start_y_m": 0.0,
                "nao_start_yaw_rad": 3.14159,
            }
        )
    )
    return path
