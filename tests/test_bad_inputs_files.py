"""Hostile files as input: each is refused at once with exit 2 and one stderr line that
names it, nothing is printed raw, and nothing is lost (issue 32, files and inputs).

A FIFO or ``/dev/zero`` behind a name, JSON nested 100000 deep, a 401-digit number,
YAML aliases that expand to gigabytes, duplicate manifest entries and keys, a symlink
loop, a newline or an escape sequence in a name, a calibration file of 18000 views.
Every case calls ``bearchair.executive.cli.main`` in this process.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest

from bearchair.core.meshes import box_chair_mesh
from bearchair.executive import cli
from tests.helpers.campaigns import write_chairs
from tests.helpers.cli_calls import refused

DEEP = "[" * 100_000 + "]" * 100_000
HUGE_INT = "1" * 401
BILLION_LAUGHS = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(8)
)


def quickly_refused(argv: list[str], capsys, within_s: float = 10.0) -> str:
    started = time.monotonic()
    line = refused(argv, capsys)
    assert time.monotonic() - started < within_s  # no blocking read, no expansion
    return line


def no_control_characters(text: str) -> bool:
    return all(c.isprintable() or c == "\n" for c in text)


# --- the manifest -----------------------------------------------------------------------


def chairs_with_manifest(tmp_path: Path, manifest: str | None, names=("a.obj",)) -> Path:
    folder = write_chairs(tmp_path / "chairs", list(names))
    if manifest is not None:
        (folder / "manifest.json").write_text(manifest)
    return folder


def trials(folder: Path, tmp_path: Path, *extra: str) -> list[str]:
    return ["trials", "--chairs", str(folder), "--out", str(tmp_path / "out"), *extra]


@pytest.mark.parametrize(
    ("manifest", "said"),
    [
        ('{"meshes": ' + DEEP + "}", "nested too deeply"),
        ('{"meshes": [{"file": "a.obj", "front_yaw_deg": ' + HUGE_INT + "}]}", "401 digits"),
        ('{"meshes": [{"file": "a.obj", "front_yaw_deg": 1e400}]}', "too large"),
        ('{"meshes": [{"file": "a.obj", "front_yaw_deg": 1, "front_yaw_deg": 90}]}', "twice"),
        ('{"meshes": []}', '"meshes" list is empty'),
        (
            '{"meshes": [{"file": "a.obj", "front_yaw_deg": 1}, {"file": "a.obj"}]}',
            "meshes[0] and meshes[1] both list a.obj",
        ),
    ],
    ids=["deep", "401-digits", "1e400", "duplicate-key", "empty", "duplicate-entry"],
)
def test_a_hostile_manifest_is_one_line_and_no_trial_runs(tmp_path, capsys, manifest, said):
    folder = chairs_with_manifest(tmp_path, manifest)
    line = quickly_refused(trials(folder, tmp_path), capsys)
    assert said in line and "Traceback" not in line
    assert not (tmp_path / "out" / "trials.sqlite").exists()


@pytest.mark.parametrize("kind", ["fifo", "dev-zero"])
def test_a_manifest_that_never_ends_is_refused_at_once(tmp_path, capsys, kind):
    folder = chairs_with_manifest(tmp_path, None)
    (folder / "manifest.json").unlink()
    if kind == "fifo":
        os.mkfifo(folder / "manifest.json")
    else:
        (folder / "manifest.json").symlink_to("/dev/zero")
    line = quickly_refused(trials(folder, tmp_path), capsys, within_s=5.0)
    assert "manifest.json: not a regular file" in line


def test_a_name_differing_in_case_says_so(tmp_path, capsys):
    manifest = json.dumps({"meshes": [{"file": "A.obj", "kind": "chair", "front_yaw_deg": 0}]})
    folder = chairs_with_manifest(tmp_path, manifest)
    line = refused(trials(folder, tmp_path), capsys)
    assert "a.obj: not in manifest.json (it lists A.obj: the names differ in case)" in line


def test_skip_bad_with_every_chair_bad_gives_each_reason(tmp_path, capsys):
    manifest = json.dumps(
        {"meshes": [{"file": "a.obj", "front_yaw_deg": "east"}, {"file": "b.obj"}]}
    )
    folder = chairs_with_manifest(tmp_path, manifest, names=("a.obj", "b.obj"))
    line = refused(trials(folder, tmp_path, "--skip-bad"), capsys)
    assert "none of its 2 meshes takes part" in line
    assert "a.obj: unusable" in line and 'front_yaw_deg is "east"' in line
    assert "b.obj: chair without a front (front_yaw_deg null)" in line  # no kind: a chair
    assert "usable front" not in line


# --- meshes -------------------------------------------------------------------------------


def test_a_symlink_loop_is_not_no_such_file(tmp_path, capsys):
    loop = tmp_path / "loop.obj"
    loop.symlink_to(loop)
    line = refused(["imagine", str(loop)], capsys)
    assert "symlink loop" in line and "no such file" not in line


def test_a_path_with_a_newline_stays_one_escaped_line(tmp_path, capsys):
    path = tmp_path / "new\nline [  ok] forged.obj"
    line = refused(["imagine", str(path)], capsys)  # refused() asserts one line
    assert "\\n" in line and "no such file" in line


def test_escape_sequences_in_a_mesh_name_reach_the_terminal_escaped(tmp_path, capsys):
    path = tmp_path / "\x1b]0;owned\x07\x1b[2J.obj"
    path.write_text("not a mesh\n")
    line = refused(["imagine", str(path)], capsys)
    assert "\x1b" not in line and "\\x1b" in line and no_control_characters(line)


def test_a_mesh_larger_than_the_bound_is_refused_unread(tmp_path, capsys, monkeypatch):
    import bearchair.core.meshes as meshes

    monkeypatch.setattr(meshes, "MAX_MESH_BYTES", 1000)
    path = tmp_path / "big.obj"
    box_chair_mesh().export(path)
    line = refused(["imagine", str(path)], capsys)
    assert "larger than any chair mesh" in line


@pytest.mark.parametrize("kind", ["fifo", "dev-zero"])
def test_a_mesh_that_never_ends_is_refused_at_once(tmp_path, capsys, kind):
    path = tmp_path / "endless.obj"
    if kind == "fifo":
        os.mkfifo(path)
    else:
        path.symlink_to("/dev/zero")
    line = quickly_refused(["imagine", str(path)], capsys, within_s=5.0)
    assert "not a regular file" in line


def test_imagine_with_10000_workers_is_one_line_before_any_work(tmp_path, capsys):
    path = tmp_path / "chair.obj"
    box_chair_mesh().export(path)
    line = quickly_refused(["imagine", str(path), "--workers", "10000"], capsys, within_s=3.0)
    assert "--workers 10000" in line and "processors" in line


# --- cell files ----------------------------------------------------------------------------


def cell_text(**changes: object) -> dict:
    cell = {
        "nao_url": "tcp://127.0.0.1:9",
        "panda_host": "127.0.0.1",
        "T_world_base": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
        "T_flange_camera": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.05], [0, 0, 0, 1]],
        "nao_start_x_m": 1.0,
        "nao_start_y_m": 0.0,
        "nao_start_yaw_rad": 0.0,
    }
    cell.update(changes)
    return cell


def check_hardware(path: Path) -> list[str]:
    return ["check-hardware", "--robots", str(path)]


@pytest.mark.parametrize(
    ("name", "content", "said"),
    [
        ("cell.yaml", BILLION_LAUGHS, "aliases expand to more than"),
        ("cell.json", DEEP, "nested too deeply"),
        ("cell.json", '{"nao_start_x_m": ' + HUGE_INT + "}", "401 digits"),
    ],
    ids=["yaml-bomb", "deep-json", "401-digits"],
)
@pytest.mark.slow
def test_a_hostile_cell_file_is_one_line_at_once(tmp_path, capsys, name, content, said):
    path = tmp_path / name
    path.write_text(content)
    line = quickly_refused(check_hardware(path), capsys, within_s=5.0)
    assert said in line


def test_a_fifo_as_cell_file_is_refused_at_once(tmp_path, capsys):
    path = tmp_path / "cell.json"
    os.mkfifo(path)
    line = quickly_refused(["run", "--robots", str(path), "--out", str(tmp_path / "o")], capsys)
    assert "not a regular file" in line and not (tmp_path / "o").exists()


def test_a_newline_in_nao_url_forges_no_check_line(tmp_path, capsys):
    path = tmp_path / "cell.json"
    path.write_text(
        json.dumps(cell_text(nao_url="tcp://nao:9559\n[  ok] FAKE: everything is fine"))
    )
    assert cli.main(check_hardware(path)) == 2
    captured = capsys.readouterr()
    assert "FAKE" not in captured.out and not any(
        line.startswith("[  ok] FAKE") for line in captured.err.splitlines()
    )
    (line,) = captured.err.strip().splitlines()
    assert "nao_url" in line and "control character" in line


def test_a_numeric_password_is_refused_without_printing_it(tmp_path, capsys):
    path = tmp_path / "cell.json"
    path.write_text(
        json.dumps(cell_text(nao_url="tcps://nao:9503", nao_user="nao", nao_password=918273645))
    )
    line = refused(check_hardware(path), capsys)
    assert "nao_password" in line and "918273645" not in line and "quotes" in line


def test_a_password_with_edge_spaces_is_not_stripped_silently(tmp_path, capsys):
    path = tmp_path / "cell.json"
    path.write_text(
        json.dumps(cell_text(nao_url="tcps://nao:9503", nao_user="nao", nao_password=" s3cret "))
    )
    line = refused(check_hardware(path), capsys)
    assert "nao_password" in line and "space" in line and "s3cret" not in line


# --- calibration files -----------------------------------------------------------------------


@pytest.mark.slow
def test_a_calibration_file_of_18000_views_is_refused_at_once(tmp_path, capsys):
    view = {"name": "v", "configuration_rad": [0] * 7, "T_base_flange": [[0]]}
    path = tmp_path / "views.json"
    path.write_text(json.dumps({"board": {}, "views": [view] * 18000}))
    line = quickly_refused(["calibrate-hand-eye", "--from", str(path)], capsys, within_s=5.0)
    assert "18000 views, more than the 200" in line


@pytest.mark.parametrize(
    ("content", "said"),
    [
        (DEEP, "nested too deeply"),
        (json.dumps({"board": {}, "views": [{"name": "v"}]}), "lacks the field"),
        (json.dumps({"views": "none"}), 'no "views" list'),
    ],
    ids=["deep", "missing-field", "views-not-a-list"],
)
def test_a_bad_calibration_file_says_what_in_words(tmp_path, capsys, content, said):
    path = tmp_path / "views.json"
    path.write_text(content)
    line = refused(["calibrate-hand-eye", "--from", str(path)], capsys)
    assert said in line and "Error(" not in line and "{'" not in line


def test_a_fifo_as_calibration_file_is_refused_at_once(tmp_path, capsys):
    path = tmp_path / "views.json"
    os.mkfifo(path)
    line = quickly_refused(["calibrate-hand-eye", "--from", str(path)], capsys, within_s=5.0)
    assert "not a regular file" in line
