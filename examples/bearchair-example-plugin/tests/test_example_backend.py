"""The toy backend: selected by a cell section, made through bearchair's backend registry."""

import pytest

from bearchair.core.errors import PluginError
from bearchair.executive.cell_config import parse_cell_config
from bearchair.hardware.backends import build_device

CELL = {
    "nao_url": "tcp://127.0.0.1:9559",
    "panda_host": "standin",
    "T_world_base": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
    "T_flange_camera": [[0, 1, 0, 0.065], [-1, 0, 0, 0], [0, 0, 1, 0.02], [0, 0, 0, 1]],
    "nao_start_x_m": 1.9,
    "nao_start_y_m": 0.0,
    "nao_start_yaw_rad": 3.14159,
}


def test_a_cell_section_selects_the_log_speaker(tmp_path):
    cell = parse_cell_config(
        {**CELL, "speaker": {"backend": "example-log-speaker", "path": str(tmp_path / "said.txt")}}
    )
    section = cell.devices["speaker"]
    speaker = build_device("speaker", section["backend"], {"path": section["path"]})
    speaker.say("Hello.")
    assert (tmp_path / "said.txt").read_text() == "Hello.\n" and speaker.spoken == ["Hello."]


def test_a_wrong_setting_is_refused_in_one_line():
    with pytest.raises(PluginError, match=r"example-log-speaker.*unknown setting 'volume'"):
        build_device("speaker", "example-log-speaker", {"path": "x", "volume": 1})
