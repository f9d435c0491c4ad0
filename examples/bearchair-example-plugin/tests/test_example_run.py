"""``bearchair run --tree`` and ``bearchair tree --tree`` with the plug-in's tree."""

import json

import pytest

from bearchair.executive import cli


def test_bearchair_tree_draws_the_variant(capsys):
    assert cli.main(["tree", "--tree", "example-no-assistance", "--format", "ascii"]) == 0
    drawn = capsys.readouterr().out
    assert "AnnounceSeat" in drawn and "InstructHelper" not in drawn


@pytest.mark.slow
def test_bearchair_run_seats_the_bear_with_the_variant(tmp_path, capsys):
    out = tmp_path / "run"
    status = cli.main(["run", "--tree", "example-no-assistance", "--mute", "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    assert status == 0, capsys.readouterr().err
    assert summary["outcome"] == "success" and summary["tree"] == "example-no-assistance"
    assert "AnnounceSeat" in [stage["name"] for stage in summary["stages"]]
    config = json.loads((out / "config.json").read_text())
    assert config["tree"]["factory"] == "example-no-assistance"
