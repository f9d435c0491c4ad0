"""The cell file: every mistake the issue lists is one line naming the field."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from bearchair.executive.cell_config import CellConfigError, load_cell_config, parse_cell_config
from bearchair.executive.cli import main
from tests.helpers.cells import GOOD_CELL


def _with(**changes):
    cell = {**GOOD_CELL, **changes}
    return {key: value for key, value in cell.items() if value is not None}


def test_a_good_cell_file_loads(tmp_path):
    path = tmp_path / "cell.json"
    path.write_text(json.dumps(GOOD_CELL))
    cell = load_cell_config(path)
    assert cell.nao_start.theta == pytest.approx(3.14159) and cell.camera == "carmine"
    assert cell.to_json()["T_flange_camera"][0][3] == 0.065


@pytest.mark.parametrize(
    ("cell", "message"),
    [
        (_with(nao_strat=[1.9, 0, 3.14]), "unknown field 'nao_strat' (did you mean nao_start"),
        (_with(T_hand_camera=np.eye(4).tolist()), "T_hand_camera: renamed T_flange_camera"),
        (_with(nao_start_yaw_rad=180), "nao_start_yaw_rad: 180 is outside [-pi, pi]"),
        (
            _with(T_world_base=(2 * np.eye(4) - np.diag([0, 0, 0, 1])).tolist()),
            "T_world_base: the rotation is not a rotation",
        ),
        (
            _with(T_flange_camera=[[1, 0, 0, 65], [0, 1, 0, 0], [0, 0, 1, 20], [0, 0, 0, 1]]),
            "T_flange_camera: translation 68",
        ),
        (_with(T_flange_camera=np.diag([1, 1, -1, 1]).tolist()), "no scale or mirror"),
        (
            _with(T_world_base=[[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
            "where the scan views assume it",
        ),
        (_with(nao_start_x_m=5.0), "outside the arena"),
        (_with(nao_start_y_m=None), "missing field nao_start_y_m"),
        (_with(nao_url="nao.local"), "nao_url: 'nao.local' must start with tcp://"),
        (_with(nao_user="nao", nao_password="x"), "only sent over tcps://"),
        (_with(panda_speed_factor=1.0), "panda_speed_factor"),
        (_with(T_world_base=[[1, 0], [0, 1]]), "T_world_base: a 4x4 matrix"),
    ],
)
def test_a_bad_cell_file_is_one_line_naming_the_field(cell, message):
    with pytest.raises(CellConfigError) as caught:
        parse_cell_config(cell)
    assert message in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.slow
def test_the_cli_refuses_a_bad_cell_file_in_one_line(tmp_path, capsys):
    path = tmp_path / "cell.json"
    path.write_text(json.dumps(_with(nao_start_yaw_rad=math.degrees(math.pi))))
    assert main(["check-hardware", "--robots", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "cell.json: nao_start_yaw_rad" in err
    path.write_text("{not json")
    assert main(["run", "--robots", str(path), "--out", str(tmp_path / "run")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
