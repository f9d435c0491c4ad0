"""Bad inputs to every subcommand: each one is refused with exit status 2 and one line
on stderr that names the problem, never a traceback, and before any work is done.

Most cases call ``bearchair.executive.cli.main`` in this process (a bad input is refused before
any world is built, so each takes milliseconds); a few run the real console process,
where the exit status and stderr are the point.
"""

from __future__ import annotations

import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bearchair.core.meshes import box_chair_mesh, check_chair_mesh
from bearchair.evaluation.store import campaign_lock
from bearchair.executive import cli
from bearchair.executive.records.run_record import RunRecorder
from bearchair.trees.mission import create_tree
from tests.helpers.cli_calls import refused

REPO = Path(__file__).resolve().parents[1]


# --- files the cases use, made once -------------------------------------------------


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("bad")
    made: dict[str, Path] = {"root": root}

    def text(name: str, content: str | bytes) -> None:
        path = root / name
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        made[name] = path

    box_chair_mesh().export(root / "chair.obj")
    made["chair.obj"] = root / "chair.obj"
    made["missing.obj"] = root / "missing.obj"
    (root / "folder.obj").mkdir()
    made["folder.obj"] = root / "folder.obj"
    os.mkfifo(root / "fifo.obj")
    made["fifo.obj"] = root / "fifo.obj"
    text("chair.txt", "v 0 0 0\n")
    text("empty.obj", "")
    text("garbage.off", "OFF\nthis is not\n")
    text("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n")
    text("words.obj", "hello world\n")
    text("noise.stl", bytes(np.random.default_rng(0).integers(0, 256, 600, dtype=np.uint8)))
    text("binary.glb", b"\x00\x01\x02 not a glb at all \xff" * 10)
    text("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    text("inf.obj", "v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    text("badindex.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n")
    text("line.obj", "v 0 0 0\nv 1 0 0\nv 0.5 0 0\nf 1 2 3\n")
    text(
        "points.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
    )
    for name, scale in (
        ("millimetres.obj", 1000.0),
        ("centimetres.obj", 100.0),
        ("tiny.obj", 1e-3),
    ):
        mesh = box_chair_mesh()
        mesh.apply_scale(scale)
        mesh.export(root / name)
        made[name] = root / name
    text("file", "a file, not a folder\n")
    (root / "record").mkdir()
    recorder = RunRecorder(root / "record", create_tree())
    recorder.close()
    made["record"] = root / "record"
    return made


BAD_MESHES = [
    ("missing.obj", "no such file"),
    ("folder.obj", "is a directory"),
    ("fifo.obj", "not a regular file"),
    ("chair.txt", "unsupported format '.txt'"),
    ("empty.obj", "empty file"),
    ("garbage.off", "not a readable OFF file"),
    ("short.off", "not a readable OFF file"),
    ("words.obj", "contains no triangles"),
    ("noise.stl", "contains no triangles"),
    ("binary.glb", "not a readable GLB file"),
    ("nan.obj", "non-finite vertex coordinates"),
    ("inf.obj", "non-finite vertex coordinates"),
    ("badindex.obj", "not a readable OBJ file"),
    ("line.obj", "a line or a point"),
    ("points.ply", "contains no triangles"),
    ("millimetres.obj", "looks like millimetres: scale it by 0.001"),
    ("centimetres.obj", "looks like centimetres: scale it by 0.01"),
    ("tiny.obj", "too small for a chair"),
]


@pytest.mark.parametrize(("name", "problem"), BAD_MESHES, ids=[m for m, _ in BAD_MESHES])
@pytest.mark.parametrize(
    "command",
    [["run", "--mute", "--chair"], ["imagine"], ["scan", "--chair"]],
    ids=["run", "imagine", "scan"],
)
@pytest.mark.slow
def test_a_bad_mesh_is_one_line_before_any_work(files, capsys, tmp_path, command, name, problem):
    extra = ["--out", str(tmp_path / "out")] if command[0] != "imagine" else []
    line = refused([*command, str(files[name]), *extra], capsys)
    assert problem in line and name in line
    assert not (tmp_path / "out").exists()  # refused before the run folder was made


# --- arguments ------------------------------------------------------------------------

BAD_ARGUMENTS = [
    ([], "the following arguments are required: command"),
    (["fly"], "invalid choice: 'fly'"),
    (["--bogus", "tree"], "unrecognized arguments: --bogus"),
    (["run", "--placement", "sideways"], "invalid choice: 'sideways'"),
    (["run", "--helper", "maybe"], "invalid choice: 'maybe'"),
    (["run", "--seed", "abc"], "invalid int value 'abc'"),
    (["run", "--seed", "-1"], "seed -1 is outside 0..4294967295"),
    (["run", "--seed", "4294967296"], "is outside 0..4294967295"),
    (["run", "--seed", "1.5"], "invalid int value '1.5'"),
    (["run", "--timeout", "nan"], "'nan' seconds: must be finite and positive"),
    (["run", "--timeout", "inf"], "'inf' seconds: must be finite and positive"),
    (["run", "--timeout", "0"], "'0' seconds: must be finite and positive"),
    (["run", "--timeout", "-5"], "'-5' seconds: must be finite and positive"),
    (["run", "--timeout", "soon"], "invalid number of seconds 'soon'"),
    (["run", "--frobnicate"], "unrecognized arguments: --frobnicate"),
    (["tree", "--format", "gif"], "invalid choice: 'gif'"),
    (["tree", "--format", "ascii", "--out", "x.txt"], "--out is for dot/svg/png"),
    (["inspect"], "the following arguments are required: run_dir"),
    (["inspect", "x", "--tick", "last"], "invalid int value: 'last'"),
    (["imagine"], "the following arguments are required: mesh"),
    (["imagine", "m.obj", "--workers", "0"], "--workers: 0: must be at least 1"),
    (["imagine", "m.obj", "--workers", "-2"], "--workers: -2: must be at least 1"),
    (["imagine", "m.obj", "--seed", "-7"], "seed -7 is outside"),
    (["scan"], "the following arguments are required: --chair"),
    (["scan", "--chair", "m.obj", "--seed", "x"], "invalid int value 'x'"),
    (["trials"], "the following arguments are required: --chairs"),
    (["trials", "--chairs", "c", "--workers", "0"], "--workers: 0: must be at least 1"),
    (["trials", "--chairs", "c", "--timeout", "nan"], "must be finite and positive"),
    (["trials", "--chairs", "c", "--max-chairs", "0"], "--max-chairs: 0: must be at least 1"),
    (["trials", "--chairs", "c", "--backend", "slurm"], "invalid choice: 'slurm'"),
    (["trials", "--chairs", "c", "--protocol", "mine"], "invalid choice: 'mine'"),
    (["trials", "--chairs", "c", "--seed", "-3"], "seed -3 is outside"),
]


@pytest.mark.parametrize(
    ("argv", "problem"), BAD_ARGUMENTS, ids=[" ".join(a) for a, _ in BAD_ARGUMENTS]
)
def test_a_bad_argument_is_one_line(capsys, argv, problem):
    line = refused(argv, capsys)
    assert problem in line and line.startswith("bearchair")


# --- output places ------------------------------------------------------------------------


def output_cases(files: dict[str, Path], tmp: Path) -> dict[str, tuple[list[str], str]]:
    chair, file_, record = str(files["chair.obj"]), files["file"], files["record"]
    return {
        "run --out is a file": (["run", "--out", str(file_)], "is a file, not a folder"),
        "run --out under a file": (["run", "--out", str(file_ / "x")], "is a file, not a folder"),
        "run --out holds a record": (["run", "--out", str(record)], "pass --overwrite"),
        "run --out holds other files": (
            ["run", "--out", str(files["root"]), "--overwrite"],
            "not a run record",
        ),
        "run --robots missing": (["run", "--robots", str(tmp / "cell.json")], "no such file"),
        "run --robots with --chair": (
            ["run", "--robots", str(file_), "--chair", chair],
            "not with --robots",
        ),
        "tree --out is a folder": (
            ["tree", "--format", "dot", "--out", str(files["folder.obj"])],
            "expected a .dot file",
        ),
        "tree --out wrong suffix": (
            ["tree", "--format", "dot", "--out", str(tmp / "t.png")],
            ".dot",
        ),
        "tree --out under a file": (
            ["tree", "--format", "dot", "--out", str(file_ / "t.dot")],
            "is a file, not a folder",
        ),
        "imagine --image is a folder": (
            ["imagine", chair, "--image", str(tmp / "pictures.png")],
            "is a folder",
        ),
        "imagine --image not png": (["imagine", chair, "--image", str(tmp / "p.jpg")], ".png"),
        "imagine --image under a file": (
            ["imagine", chair, "--image", str(file_ / "p.png")],
            "is a file, not a folder",
        ),
        "scan --out is a file": (["scan", "--chair", chair, "--out", str(file_)], "is a file"),
        "scan --out under a file": (
            ["scan", "--chair", chair, "--out", str(file_ / "x")],
            "is a file, not a folder",
        ),
    }


OUTPUT_CASES = [
    "run --out is a file",
    "run --out under a file",
    "run --out holds a record",
    "run --out holds other files",
    "run --robots missing",
    "run --robots with --chair",
    "tree --out is a folder",
    "tree --out wrong suffix",
    "tree --out under a file",
    "imagine --image is a folder",
    "imagine --image not png",
    "imagine --image under a file",
    "scan --out is a file",
    "scan --out under a file",
]


@pytest.mark.parametrize("case", OUTPUT_CASES)
def test_an_unusable_output_place_is_refused_before_any_work(files, tmp_path, capsys, case):
    (tmp_path / "pictures.png").mkdir()
    argv, problem = output_cases(files, tmp_path)[case]
    line = refused(argv, capsys)
    assert problem in line


# --- run records for inspect ---------------------------------------------------------------


def record_with(files: dict[str, Path], tmp: Path, name: str, content: bytes | None) -> Path:
    run = tmp / "run"
    run.mkdir()
    for part in ("tree.json", "ticks.jsonl"):
        (run / part).write_bytes((files["record"] / part).read_bytes())
    if content is None:
        (run / name).unlink()
    else:
        (run / name).write_bytes(content)
    return run


TICK = {"tick": 1, "t": 0.0, "nodes": [{"path": "0", "status": "RUNNING", "feedback": ""}]}

BAD_RECORDS = [
    ("tree.json", None, "no tree.json"),
    ("ticks.jsonl", None, "no ticks.jsonl"),
    ("tree.json", b"{not json", "tree.json: not valid JSON (Expecting property name"),
    ("tree.json", b"\xff\xfe\x00\x01binary", "tree.json: not valid JSON (not UTF-8 text"),
    ("tree.json", b'{"path": "0"}', "not a tree (expected a non-empty JSON list"),
    ("tree.json", b"[]", "not a tree (expected a non-empty JSON list"),
    ("tree.json", b'[{"path": 0, "name": "x", "depth": 0}]', "a node lacks a str path"),
    ("tree.json", b'[{"path": "0", "name": "x", "depth": -1}]', "a node lacks a str path"),
    ("ticks.jsonl", b"", "no readable tick"),
    ("ticks.jsonl", b"garbage\nmore garbage\n", "no readable tick"),
    ("ticks.jsonl", b"\x00\xff\xfe binary \x01\n", "no readable tick"),
    ("ticks.jsonl", b"[1, 2, 3]\n[4]\n", "no readable tick"),
    ("ticks.jsonl", b'{"tick": "one", "t": 0, "nodes": []}\n', "no readable tick"),
    ("ticks.jsonl", json.dumps({**TICK, "nodes": "all"}).encode() + b"\n", "no readable tick"),
]


@pytest.mark.parametrize(("name", "content", "problem"), BAD_RECORDS)
def test_a_damaged_run_record_is_one_line(files, tmp_path, capsys, name, content, problem):
    run = record_with(files, tmp_path, name, content)
    line = refused(["inspect", str(run)], capsys)
    assert problem in line and str(run) in line


@pytest.mark.parametrize(
    ("target", "problem"),
    [("missing", "no such folder"), ("file", "a file, not a folder")],
)
def test_inspect_of_something_that_is_not_a_record(files, tmp_path, capsys, target, problem):
    path = files["file"] if target == "file" else tmp_path / "nothing"
    assert problem in refused(["inspect", str(path)], capsys)


@pytest.mark.parametrize("tick", ["0", "-4", "99999"])
def test_inspect_of_a_tick_outside_the_run(files, tmp_path, capsys, tick):
    run = record_with(files, tmp_path, "ticks.jsonl", json.dumps(TICK).encode() + b"\n")
    (run / "ticks.jsonl").write_text(json.dumps(TICK) + "\n" + json.dumps({**TICK, "tick": 3}))
    assert "outside the run (ticks 1..3)" in refused(["inspect", str(run), "--tick", tick], capsys)


# --- chair sets and campaign databases ---------------------------------------------------


def chair_set(tmp: Path, entries: object, meshes: dict[str, bytes] | None = None) -> Path:
    folder = tmp / "chairs"
    folder.mkdir()
    box = trimesh.creation.box((0.4, 0.4, 0.5))
    for name in ("a.obj", "b.obj"):
        box.export(folder / name)
    for name, content in (meshes or {}).items():
        (folder / name).write_bytes(content)
    if entries is not None:
        text = entries if isinstance(entries, bytes) else json.dumps(entries).encode()
        (folder / "manifest.json").write_bytes(text)
    return folder


def entry(file: str, **values: object) -> dict:
    return {"file": file, "kind": "chair", "front_yaw_deg": 90.0, **values}


GOOD = {"meshes": [entry("a.obj"), entry("b.obj")]}

BAD_CHAIR_SETS = [
    ("no manifest", None, None, "no manifest.json"),
    ("manifest not JSON", b"{meshes: [", None, "manifest.json: not valid JSON"),
    ("manifest binary", b"\xff\xfe\x00\x00", None, "manifest.json: not valid JSON"),
    ("manifest a list", [entry("a.obj")], None, 'expected an object with a "meshes" list'),
    ("meshes not a list", {"meshes": {"a.obj": 90}}, None, '"meshes" list'),
    ("entry not an object", {"meshes": ["a.obj"]}, None, "meshes[0] is not an object"),
    ("entry without file", {"meshes": [{"kind": "chair"}]}, None, 'with a "file" name'),
    (
        "front as text",
        {"meshes": [entry("a.obj", front_yaw_deg="east")]},
        None,
        'front_yaw_deg is "east"',
    ),
    (
        "front as a list",
        {"meshes": [entry("a.obj", front_yaw_deg=[90])]},
        None,
        "front_yaw_deg is [90]",
    ),
    ("front true", {"meshes": [entry("a.obj", front_yaw_deg=True)]}, None, "front_yaw_deg is true"),
    (
        "front NaN",
        b'{"meshes": [{"file": "a.obj", "front_yaw_deg": NaN}]}',
        None,
        "NaN is not a number",
    ),
    ("kind a number", {"meshes": [entry("a.obj", kind=3)]}, None, "kind is 3, not a string"),
    (
        "no front anywhere",
        {"meshes": [entry("a.obj", front_yaw_deg=None)]},
        None,
        "takes part (a.obj: chair without a front (front_yaw_deg null)",
    ),
    (
        "garbage mesh",
        {"meshes": [entry("a.obj"), entry("c.off")]},
        {"c.off": b"OFF\nnope\n"},
        "pass --skip-bad",
    ),
    (
        "NaN mesh",
        {"meshes": [entry("c.obj")]},
        {"c.obj": b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
        "non-finite",
    ),
    ("empty mesh", {"meshes": [entry("c.obj")]}, {"c.obj": b""}, "c.obj: empty file"),
]


@pytest.mark.parametrize(
    ("case", "manifest", "meshes", "problem"), BAD_CHAIR_SETS, ids=[c[0] for c in BAD_CHAIR_SETS]
)
def test_a_bad_chair_set_is_one_line_before_the_first_trial(
    tmp_path, capsys, case, manifest, meshes, problem
):
    folder = chair_set(tmp_path, manifest, meshes)
    out = tmp_path / "out"
    line = refused(["trials", "--chairs", str(folder), "--out", str(out)], capsys)
    assert problem in line and line.startswith("bearchair trials:")
    assert not out.exists()


@pytest.mark.parametrize(
    ("case", "problem"),
    [
        ("missing", "no such directory"),
        ("a file", "not a directory"),
        ("no meshes", "no chair meshes"),
    ],
)
def test_a_chairs_folder_that_is_not_one(tmp_path, capsys, case, problem):
    folder = tmp_path / "chairs"
    if case == "a file":
        folder.write_text("x")
    elif case == "no meshes":
        folder.mkdir()
        (folder / "notes.txt").write_text("x")
    assert problem in refused(["trials", "--chairs", str(folder)], capsys)


def test_every_bad_chair_gets_its_line_and_skip_bad_goes_on_without_them(tmp_path, capsys):
    meshes = {"c.off": b"OFF\nnope\n", "d.obj": b""}
    manifest = {"meshes": [entry("a.obj"), entry("c.off"), entry("d.obj")]}
    folder = chair_set(tmp_path, manifest, meshes)
    assert cli.main(["trials", "--chairs", str(folder), "--out", str(tmp_path / "o")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "c.off" in lines[0] and "d.obj" in lines[1]
    assert "2 unusable" in lines[1] and "Traceback" not in "".join(lines)

    from bearchair.evaluation.protocol import discover_chairs

    chosen, skipped = discover_chairs(folder, check_meshes=True, skip_bad=True)
    assert [c.name for c in chosen] == ["a.obj"]
    assert {s.name for s in skipped if s.reason.startswith("unusable")} == {"c.off", "d.obj"}


def database_cases(tmp: Path) -> dict[str, tuple[Path, str]]:
    folder_db = tmp / "db-folder"
    folder_db.mkdir()
    garbage = tmp / "garbage.sqlite"
    garbage.write_bytes(b"this is not a database" * 100)
    foreign = tmp / "foreign.sqlite"
    connection = sqlite3.connect(foreign)
    connection.execute("CREATE TABLE trials (id INTEGER, name TEXT)")
    connection.commit()
    connection.close()
    under_file = tmp / "file"
    under_file.write_text("x")
    return {
        "a folder": (folder_db, "is a folder"),
        "not sqlite": (garbage, "not a readable SQLite database"),
        "foreign schema": (foreign, "not a bearchair campaign's (no chair"),
        "under a file": (under_file / "t.sqlite", "is a file, not a folder"),
    }


@pytest.mark.parametrize("case", ["a folder", "not sqlite", "foreign schema", "under a file"])
def test_an_unusable_database_is_refused_before_the_first_trial(tmp_path, capsys, case):
    folder = chair_set(tmp_path, GOOD)
    db, problem = database_cases(tmp_path)[case]
    argv = ["trials", "--chairs", str(folder), "--db", str(db), "--out", str(tmp_path / "o")]
    argv += ["--worker-cmd", "false"]  # never reached
    assert problem in refused(argv, capsys)
    assert not (tmp_path / "o" / "runs").exists()


def test_trials_refuse_an_out_that_is_a_file_a_short_timeout_and_a_held_database(tmp_path, capsys):
    folder = chair_set(tmp_path, GOOD)
    (tmp_path / "file").write_text("x")
    base = ["trials", "--chairs", str(folder)]
    assert "is a file" in refused([*base, "--out", str(tmp_path / "file")], capsys)
    assert "at least 30 s" in refused([*base, "--timeout", "5"], capsys)
    assert "--address only applies" in refused([*base, "--address", "x:1"], capsys)
    with campaign_lock(tmp_path / "o" / "trials.sqlite"):
        assert "in use" in refused([*base, "--out", str(tmp_path / "o")], capsys)


# --- warnings that are not refusals -----------------------------------------------------


def test_a_tall_or_y_up_chair_is_warned_with_what_to_do():
    chair = box_chair_mesh(armrest_height_m=0.35)
    assert check_chair_mesh(chair, "chair.obj") == []
    y_up = chair.copy()
    y_up.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    (warning,) = check_chair_mesh(y_up, "y-up.obj")
    assert "lie on its side" in warning and "±y" in warning and "re-export it with z up" in warning
    tall = chair.copy()
    tall.apply_scale(5.0)
    assert any("taller than any chair" in w for w in check_chair_mesh(tall, "tall.obj"))


# --- the real console process -------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "problem"),
    [
        (["run", "--seed", "-1"], "seed -1 is outside"),
        (["trials", "--chairs", "/no/such/chairs"], "no such directory"),
        (["inspect", "/no/such/run"], "not a run record"),
    ],
)
@pytest.mark.slow
def test_the_console_process_exits_2_with_one_line(argv, problem):
    done = subprocess.run(
        [sys.executable, "-m", "bearchair.executive.cli", *argv],
        cwd=REPO,
        capture_output=True,
        text=True,
    )
    assert done.returncode == 2 and done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and problem in lines[0] and "Traceback" not in done.stderr


def test_a_full_file_system_is_refused_before_the_run(tmp_path, capsys, monkeypatch):
    import shutil

    import bearchair.executive.outputs

    usage = shutil.disk_usage(tmp_path)
    monkeypatch.setattr(
        bearchair.executive.outputs.shutil,
        "disk_usage",
        lambda path: usage._replace(free=3_000_000),
    )
    line = refused(["run", "--mute", "--out", str(tmp_path / "run")], capsys)
    assert "only 3.0 MB free" in line and "free some space" in line


def test_a_read_only_database_is_refused_before_the_first_trial(tmp_path, capsys, monkeypatch):
    from bearchair.evaluation import store

    folder = chair_set(tmp_path, GOOD)
    db = tmp_path / "t.sqlite"
    store.TrialStore(db).close()
    connect = sqlite3.connect  # as root, file modes do not stop writes: open it read-only
    monkeypatch.setattr(
        store.sqlite3, "connect", lambda path: connect(f"file:{path}?mode=ro", uri=True)
    )
    argv = ["trials", "--chairs", str(folder), "--db", str(db), "--out", str(tmp_path / "o")]
    line = refused([*argv, "--worker-cmd", "false"], capsys)
    assert "read-only; give a writable --db" in line and str(db) in line
    assert not (tmp_path / "o" / "runs").exists()
