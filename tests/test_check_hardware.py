"""``bearchair check-hardware`` against the SDK stand-ins: every check, nothing moves."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from executive.cli import main

pytest.importorskip("qi")


def _cell(tmp_path, nao_url):
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


def test_check_hardware_prints_every_check_and_moves_nothing(tmp_path, capsys):
    from hardware.real.standins import NaoqiStandin

    with NaoqiStandin() as naoqi:
        status = main(["check-hardware", "--robots", str(_cell(tmp_path, naoqi.url))])
        out = capsys.readouterr().out
        moving = {"wakeUp", "moveTo", "angleInterpolation", "goToPosture", "setState"}
        assert not moving & {name for _, name, _ in naoqi.calls}
    assert status == 0, out
    for device in (
        "cell",
        "sdk qi",
        "sdk panda-python",
        "view scan4",
        "nao battery",
        "panda",
        "camera",
        "tag",
    ):
        assert f"] {device}:" in out, device
    assert "[warn] view scan4: inside panda-py's joint walls, moved: joint 2" in out
    assert "640x480" in out and "(nothing moved)" in out


def test_check_hardware_names_an_unreachable_nao_within_five_seconds(tmp_path, capsys):
    started = time.monotonic()
    status = main(["check-hardware", "--robots", str(_cell(tmp_path, "tcp://127.0.0.1:9"))])
    out = capsys.readouterr().out
    assert time.monotonic() - started < 5.0
    assert status == 1 and "[FAIL] nao:" in out
    assert out.strip().splitlines()[-1] == "check-hardware: FAILED: nao"
