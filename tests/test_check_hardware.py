"""``bearchair check-hardware`` against the SDK stand-ins: every check, nothing moves."""

from __future__ import annotations

import json
import time

import pytest

from bearchair.executive.cli import main
from tests.helpers.cells import standin_cell_file

pytest.importorskip("qi")


@pytest.mark.slow
def test_check_hardware_prints_every_check_and_moves_nothing(tmp_path, capsys):
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin() as naoqi:
        status = main(["check-hardware", "--robots", str(standin_cell_file(tmp_path, naoqi.url))])
        out = capsys.readouterr().out
        moving = {"wakeUp", "move", "moveTo", "angleInterpolation", "goToPosture", "setState"}
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
    status = main(
        ["check-hardware", "--robots", str(standin_cell_file(tmp_path, "tcp://127.0.0.1:9"))]
    )
    out = capsys.readouterr().out
    assert time.monotonic() - started < 5.0
    assert status == 1 and "[FAIL] nao:" in out
    assert out.strip().splitlines()[-1] == "check-hardware: FAILED: nao"


@pytest.mark.slow
def test_run_on_robots_asks_first_then_records_the_cell_and_sdk_versions(
    tmp_path, capsys, monkeypatch
):
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(time_scale=20.0) as naoqi:
        cell = standin_cell_file(tmp_path, naoqi.url)
        monkeypatch.setattr("builtins.input", lambda prompt: "n")
        status = main(["run", "--robots", str(cell), "--out", str(tmp_path / "no")])
        assert status == 2 and "did not confirm: nothing moved" in capsys.readouterr().err
        assert not naoqi.called("wakeUp") and not naoqi.called("move")

        out = tmp_path / "yes"
        status = main(
            ["run", "--robots", str(cell), "--yes", "--out", str(out), "--timeout", "120"]
        )
        capsys.readouterr()
        assert naoqi.called("setState") == [("disabled",)] and naoqi.called("wakeUp")
    # The stand-in camera sees a flat wall: the mission fails, its record survives.
    assert status in (0, 1)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["backend"] == "real" and summary["sdk_versions"]["qi"]
    assert json.loads((out / "cell.json").read_text())["nao_url"] == naoqi.url
