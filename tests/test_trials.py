"""The trials harness, with a fake trial worker (no physics): protocol, records, resume,
crashes and hangs, Ctrl-C, Table 1 and the report."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bearchair.evaluation.campaign import run_campaign
from bearchair.evaluation.campaign_progress import Progress, format_duration
from bearchair.evaluation.pictures import copy_trial_scenes, render_chair_pictures
from bearchair.evaluation.protocol import (
    ChairEntry,
    ChairSetError,
    discover_chairs,
    expand_protocol,
    trial_seed,
)
from bearchair.evaluation.report import compute_table, failure_kind, format_table, markdown_report
from bearchair.evaluation.store import TrialStore, record_from_error, record_from_summary
from bearchair.evaluation.trial_backends import LocalBackend
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.executive import cli
from bearchair.executive.records.run_summary import RunSummary
from tests.helpers.campaigns import (
    FAKE_WORKER,
    FakeRay,
    table_without_timing,
    worker_pids,
    worker_starts,
    write_chairs,
)
from tests.helpers.process_tree import process_alive

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def fake_worker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    script = tmp_path / "fake_worker.py"
    script.write_text(FAKE_WORKER)
    monkeypatch.setenv("FAKE_LOG", str(tmp_path / "fake_worker.log"))
    return [sys.executable, str(script)]


def entries(names: list[str], folder: Path = Path("/chairs")) -> list[ChairEntry]:
    return [ChairEntry(folder / name, "chair", 90.0) for name in names]


# --- protocol ------------------------------------------------------------------------


def test_paper_protocol_is_six_trials_per_chair_and_72_for_12():
    chairs = entries([f"chair-{i:02d}.obj" for i in range(12)])
    trials = expand_protocol(chairs, "paper", campaign_seed=3)
    assert len(trials) == 72
    first = [t for t in trials if t.chair == "chair-00.obj"]
    assert [(t.placement, t.helper) for t in first] == [
        ("accessible", "obeys"),
        ("accessible", "obeys"),
        ("accessible", "obeys"),
        ("inaccessible", "obeys"),
        ("inaccessible", "obeys"),
        ("inaccessible", "disobeys"),
    ]
    assert sum(t.experiment == "accessible" for t in trials) == 36
    assert sum(t.experiment == "inaccessible_obeys" for t in trials) == 24
    assert sum(t.experiment == "inaccessible_disobeys" for t in trials) == 12
    assert len({t.key for t in trials}) == 72
    assert len({t.seed for t in trials}) == 72


@pytest.mark.slow
def test_trial_seeds_are_deterministic_across_processes_and_depend_on_the_campaign_seed():
    chairs = entries(["a.obj", "b.obj"])
    assert expand_protocol(chairs, "paper", 7) == expand_protocol(chairs, "paper", 7)
    assert [t.seed for t in expand_protocol(chairs, "paper", 7)] != [
        t.seed for t in expand_protocol(chairs, "paper", 8)
    ]
    # Another interpreter (another hash salt) derives the same seed.
    code = "from evaluation.protocol import trial_seed; print(trial_seed(7, 'a.obj', 4))"
    other = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO
    )
    assert int(other.stdout) == trial_seed(7, "a.obj", 4)
    with pytest.raises(ValueError, match="unknown protocol"):
        expand_protocol(chairs, "nope", 0)


def test_manifest_keeps_meshes_with_a_front_in_sorted_order(tmp_path: Path):
    manifest = {
        "meshes": [
            {"file": "c-chair.obj", "kind": "chair", "front_yaw_deg": 90.0},
            {"file": "a-chair.stl", "kind": "chair", "front_yaw_deg": 10.0},
            {"file": "b-table.obj", "kind": "table", "front_yaw_deg": None},
            {"file": "d-chair.ply", "kind": "chair", "front_yaw_deg": 0.0},
        ]
    }
    folder = write_chairs(
        tmp_path / "chairs",
        ["c-chair.obj", "a-chair.stl", "b-table.obj", "d-chair.ply", "e-extra.obj"],
        manifest,
    )
    (folder / "notes.txt").write_text("not a mesh")
    chosen, skipped = discover_chairs(folder)
    assert [c.name for c in chosen] == ["a-chair.stl", "c-chair.obj", "d-chair.ply"]
    assert chosen[2].front_yaw_deg == 0.0  # a front of 0 deg is a front
    reasons = dict(skipped)
    assert "not a chair: kind 'table'" in reasons["b-table.obj"]
    assert "not in manifest" in reasons["e-extra.obj"]
    chosen, skipped = discover_chairs(folder, max_chairs=2)
    assert [c.name for c in chosen] == ["a-chair.stl", "c-chair.obj"]
    assert "--max-chairs 2" in dict(skipped)["d-chair.ply"]


def test_only_seats_with_a_front_take_part_and_the_new_fields_are_read(tmp_path: Path):
    names = [f"{kind}.obj" for kind in ("box", "shelf", "cabinet", "toy", "hammock")]
    names += ["sofa.obj", "bench.obj", "stool.obj", "old.obj", "backless-bench.obj"]
    manifest = {"meshes": [{"file": n, "kind": n[:-4], "front_yaw_deg": 45.0} for n in names]}
    manifest["meshes"][-2] = {"file": "old.obj", "front_yaw_deg": 45.0}  # no kind: a chair
    manifest["meshes"][-1] = {"file": "backless-bench.obj", "kind": "bench", "front_yaw_deg": None}
    manifest["meshes"][5].update(seat_height_m=0.234, style="sofa")
    chosen, skipped = discover_chairs(write_chairs(tmp_path / "chairs", names, manifest))
    assert sorted(c.name for c in chosen) == ["bench.obj", "old.obj", "sofa.obj", "stool.obj"]
    sofa = next(c for c in chosen if c.name == "sofa.obj")
    assert (sofa.kind, sofa.seat_height_m, sofa.style) == ("sofa", 0.234, "sofa")
    assert next(c for c in chosen if c.name == "old.obj").kind == "chair"
    reasons = dict(skipped)
    for kind in ("box", "shelf", "cabinet", "toy", "hammock"):  # with a front, still no chair
        assert reasons[f"{kind}.obj"].startswith(f"not a chair: kind '{kind}'")
    assert "bench without a front" in reasons["backless-bench.obj"]


@pytest.mark.parametrize(
    "values, message",
    [
        ({"seat_height_m": -0.2}, "seat_height_m is -0.2, not a positive number"),
        ({"seat_height_m": "low"}, 'seat_height_m is "low"'),
        ({"style": 4}, "style is 4, not a string"),
    ],
)
def test_bad_new_manifest_fields_are_named(values: dict, message: str):
    from bearchair.evaluation.protocol import manifest_entry_problem

    entry = {"file": "a.obj", "kind": "chair", "front_yaw_deg": 0.0, **values}
    assert message in (manifest_entry_problem(entry) or "")
    assert manifest_entry_problem({**entry, **dict.fromkeys(values)}) is None  # null is fine


def test_a_folder_needs_a_manifest_and_every_listed_mesh_takes_part(tmp_path: Path):
    folder = write_chairs(tmp_path / "chairs", ["b.obj", "a.off"])
    chosen, skipped = discover_chairs(folder)
    assert [c.name for c in chosen] == ["a.off", "b.obj"] and skipped == []
    (folder / "manifest.json").unlink()  # placements would be random: refused
    with pytest.raises(ChairSetError, match=r"no manifest\.json"):
        discover_chairs(folder)
    with pytest.raises(ChairSetError, match="no chair meshes"):
        discover_chairs(write_chairs(tmp_path / "empty", []))
    with pytest.raises(ChairSetError, match="no such directory"):
        discover_chairs(tmp_path / "missing")


def test_shared_chairs_give_72_trials_on_12_chairs_with_a_front(shared_chairs, shared_manifest):
    chosen, skipped = discover_chairs(shared_chairs, max_chairs=12)
    assert len(chosen) == 12 and all(c.front_yaw_deg is not None for c in chosen)
    assert len(expand_protocol(chosen, "paper", 0)) == 72
    no_front = {e["file"] for e in shared_manifest if e["front_yaw_deg"] is None}
    assert no_front <= {s.name for s in skipped}


# --- bad arguments -------------------------------------------------------------------


@pytest.mark.parametrize(
    "extra, message",
    [
        ([], "no such directory"),
        (["--workers", "0"], "--workers"),
        (["--timeout", "-1"], "--timeout"),
    ],
)
def test_bad_arguments_give_one_line_and_status_2(tmp_path, capsys, extra, message):
    chairs = tmp_path / "missing" if not extra else write_chairs(tmp_path / "c", ["a.obj"])
    status = cli.main(["trials", "--chairs", str(chairs), "--out", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert message in err and len(err.splitlines()) == 1 and err.startswith("bearchair trials:")


def test_a_folder_without_meshes_is_a_user_error(tmp_path, capsys):
    folder = tmp_path / "nothing"
    folder.mkdir()
    (folder / "readme.txt").write_text("hello")
    assert cli.main(["trials", "--chairs", str(folder)]) == 2
    err = capsys.readouterr().err.strip()
    assert "no chair meshes" in err and len(err.splitlines()) == 1


def test_ray_backend_without_ray_says_how_to_install(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray -> ImportError
    folder = write_chairs(tmp_path / "c", ["a.obj"])
    assert cli.main(["trials", "--chairs", str(folder), "--backend", "ray"]) == 2
    err = capsys.readouterr().err.strip()
    assert "pip install 'bearchair[trials]'" in err and len(err.splitlines()) == 1


# --- records, resume, crashes, hangs ---------------------------------------------------


@pytest.mark.slow
def test_records_are_committed_and_a_rerun_skips_finished_trials(tmp_path, fake_worker):
    specs = expand_protocol(entries(["a.obj", "b.obj"], tmp_path), "paper", 1)
    backend = LocalBackend(workers=2, timeout_s=30, command=fake_worker)
    with TrialStore(tmp_path / "t.sqlite") as store:
        first = run_campaign(specs, store, backend, tmp_path / "runs", 30)
    assert first == (12, 0, False)
    assert len(worker_starts(tmp_path)) == 12
    # Another connection sees every row: each was committed.
    rows = sqlite3.connect(tmp_path / "t.sqlite").execute("SELECT COUNT(*) FROM trials").fetchone()
    assert rows[0] == 12
    with TrialStore(tmp_path / "t.sqlite") as store:
        second = run_campaign(specs, store, backend, tmp_path / "runs", 30)
        records = store.records(specs)
    assert second == (0, 12, False)
    assert len(worker_starts(tmp_path)) == 12  # nothing ran again
    record = records[3]
    assert record.experiment == "inaccessible_obeys" and record.rotations == 2
    assert set(record.stage_seconds) == {"ScanChair", "ImagineSitting", "WalkToChair"}
    assert record.sitting_pose is not None and record.sitting_pose.yaw_deg == 10.0
    assert record.torso_tilt_deg == 3.0 and record.mission_seconds == 12.5
    assert records[0].accessible_after_assistance is None  # no instruction given
    # A different campaign seed is a different campaign: its trials are not skipped.
    other = expand_protocol(entries(["a.obj"], tmp_path), "paper", 2)
    with TrialStore(tmp_path / "t.sqlite") as store:
        assert run_campaign(other, store, backend, tmp_path / "runs", 30).ran == 6


@pytest.mark.slow
def test_a_crashing_and_a_hanging_trial_are_failures_and_the_harness_goes_on(tmp_path, fake_worker):
    specs = expand_protocol(entries(["crash.obj", "hang.obj"], tmp_path), "paper", 0)
    backend = LocalBackend(workers=2, timeout_s=3.0, command=fake_worker)
    start = time.monotonic()
    with TrialStore(tmp_path / "t.sqlite") as store:
        result = run_campaign(specs, store, backend, tmp_path / "runs", 3.0)
        records = {(r.chair, r.trial_index): r for r in store.records()}
    assert result.ran == 12 and len(records) == 12
    assert time.monotonic() - start < 25
    crashed = records[("crash.obj", 1)]
    assert crashed.outcome == "failure" and "SIGSEGV" in crashed.error
    assert "Fatal Python error" in crashed.error or "crashed" in crashed.error
    hung = records[("hang.obj", 2)]
    assert hung.outcome == "failure" and "timed out after 3 s" in hung.error
    assert hung.wall_seconds >= 3.0
    others = [r for key, r in records.items() if key not in {("crash.obj", 1), ("hang.obj", 2)}]
    assert all(r.error is None for r in others)
    causes = dict(compute_table(list(records.values())).failure_causes)
    assert any(cause.startswith("harness: worker crashed") for cause in causes)
    assert any(cause.startswith("harness: timed out") for cause in causes)


@pytest.mark.slow
def test_interrupted_then_resumed_gives_the_same_table_as_uninterrupted(tmp_path, fake_worker):
    specs = expand_protocol(entries(["a.obj", "b.obj", "c.obj"], tmp_path), "paper", 5)
    backend = LocalBackend(workers=2, timeout_s=30, command=fake_worker)
    with TrialStore(tmp_path / "straight.sqlite") as store:
        run_campaign(specs, store, backend, tmp_path / "runs-a", 30)
        straight = store.records(specs)

    def interrupt_after_five(record: dict) -> None:
        if interrupt_after_five.count == 4:
            raise KeyboardInterrupt
        interrupt_after_five.count += 1

    interrupt_after_five.count = 0
    with TrialStore(tmp_path / "resumed.sqlite") as store:
        stopped = run_campaign(
            specs, store, backend, tmp_path / "runs-b", 30, on_record=interrupt_after_five
        )
        assert stopped.interrupted and stopped.ran == 5
        assert len(store.records()) == 5
        resumed = run_campaign(specs, store, backend, tmp_path / "runs-b", 30)
        assert resumed == (13, 5, False)
        records = store.records(specs)
    assert len(records) == 18
    assert table_without_timing(records) == table_without_timing(straight)


@pytest.mark.slow
@pytest.mark.parametrize("stop_signal", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_on_the_cli_keeps_finished_trials_and_says_how_to_resume(
    tmp_path, fake_worker, stop_signal
):
    folder = write_chairs(tmp_path / "chairs", ["a.obj", "b.obj"])
    out = tmp_path / "out"
    command = [
        sys.executable, "-m", "bearchair.executive.cli", "trials", "--chairs", str(folder),
        "--out", str(out), "--seed", "9", "--worker-cmd", " ".join(fake_worker),
    ]  # fmt: skip
    env = {**os.environ, "FAKE_SLEEP_S": "0.4"}
    harness = subprocess.Popen(
        command, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    db = out / "trials.sqlite"
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        if db.exists():
            try:
                rows = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
            except sqlite3.OperationalError:
                rows = 0
            if rows >= 3:
                break
        time.sleep(0.1)
    harness.send_signal(stop_signal)
    _, err = harness.communicate(timeout=30)
    assert harness.returncode == 128 + stop_signal, err
    assert "Resume with:" in err and "--seed 9" in err
    assert not [pid for pid in worker_pids(tmp_path) if process_alive(pid)]  # none orphaned
    kept = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
    assert 3 <= kept < 12
    env["FAKE_SLEEP_S"] = "0"
    finished = subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True)
    assert finished.returncode == 0, finished.stderr
    assert len(worker_starts(tmp_path)) <= 12 + 1  # at most the interrupted trial ran twice
    assert "(1) Seating bear success" in finished.stdout
    assert (out / "report.md").is_file()
    with TrialStore(db) as store:
        assert len(store.records()) == 12


# --- Table 1 and the report ------------------------------------------------------------


def make_record(experiment, outcome, instructions=0, accessible=True, **extra):
    placement = "accessible" if experiment == "accessible" else "inaccessible"
    record = {
        "chair": extra.pop("chair", "a.obj"),
        "trial_index": extra.pop("trial_index", 0),
        "seed": extra.pop("seed", 1),
        "experiment": experiment,
        "placement": placement,
        "helper": "disobeys" if experiment.endswith("disobeys") else "obeys",
        "outcome": outcome,
        "instructions": instructions,
        "accessible_after_assistance": accessible if instructions else None,
        "failed_stage": None if outcome == "success" else "ReleaseAndStand",
        "reason": "" if outcome == "success" else "ReleaseAndStand: bear not seated",
        "stage_seconds": {},
        "wall_seconds": 40.0,
        "error": None,
    }
    record.update(extra)
    return TrialRecord(**record)


def test_table_1_numbers_from_known_records():
    records = (
        [make_record("accessible", "success")] * 34
        + [make_record("accessible", "failure")] * 2
        + [make_record("inaccessible_obeys", "success", 1)] * 22
        + [make_record("inaccessible_obeys", "failure", 2, accessible=False)]
        + [
            make_record(
                "inaccessible_obeys",
                "failure",
                0,
                failed_stage="ImagineSitting",
                reason="ImagineSitting: no correct sitting",
            )
        ]
        + [make_record("inaccessible_disobeys", "success", 2)] * 11
        + [
            make_record(
                "inaccessible_disobeys",
                "failure",
                0,
                error="timed out after 300 s",
                failed_stage=None,
            )
        ]
    )
    table = compute_table(records)
    assert [(r.label, r.n, r.count) for r in table.seating] == [
        ("Accessible", 36, 34),
        ("Inaccessible + Human Obeys", 24, 22),
        ("Inaccessible + Human Disobeys", 12, 11),
        ("Total", 72, 67),
    ]
    assert table.seating[3].rate == pytest.approx(67 / 72)
    assert [(r.label, r.n, r.count) for r in table.assistance] == [
        ("Obeys", 23, 22),
        ("Disobeys", 11, 11),
        ("Total", 34, 33),
    ]
    assert dict(table.failure_causes) == {
        "ReleaseAndStand: bear not seated": 3,
        "ImagineSitting: no correct sitting": 1,
        "harness: timed out after 300 s": 1,
    }
    assert table.failure_stages == [("ReleaseAndStand", 3), ("ImagineSitting", 1), ("harness", 1)]
    assert failure_kind("ReleaseAndStand: torso tilted 48 deg > 30 (tilt -4.5 deg)") == (
        "ReleaseAndStand: torso tilted # deg > # (tilt # deg)"
    )
    assert table.errors == 1 and table.trial_median_s == 40.0
    text = format_table(table)
    assert "Total" in text and "93.1%" in text and "97.1%" in text
    markdown = markdown_report(table, records)
    assert "| Total | 72 | 67 | 93.1% |" in markdown
    assert "| Total | 34 | 33 | 97.1% |" in markdown


def test_stage_medians_over_the_trials_where_the_stage_ran():
    records = [
        make_record("accessible", "success", stage_seconds={"ScanChair": s, "SeatBear": 2 * s})
        for s in (1.0, 2.0, 9.0)
    ] + [make_record("accessible", "failure", stage_seconds={"ScanChair": 4.0})]
    medians = compute_table(records).stage_median_s
    assert medians["ScanChair"] == (3.0, 4)
    assert medians["SeatBear"] == (4.0, 3)
    assert list(medians) == ["ScanChair", "SeatBear"]  # mission order


def test_records_from_a_summary_and_from_an_error():
    spec = expand_protocol(entries(["a.obj"]), "paper", 0)[5]
    summary = {
        "outcome": "failure",
        "failed_stage": "WalkToChair",
        "reason": "WalkToChair: lost",
        "stages": [
            {"name": "ScanChair", "status": "SUCCESS", "seconds": 7.1, "message": ""},
            {"name": "WalkToChair", "status": "FAILURE", "seconds": 20.0, "message": ""},
            {"name": "SeatBear", "status": "INVALID", "seconds": 0.0, "message": ""},
        ],
        "instructions": ["turn it", "turn it more"],
        "rotations": 2,
        "accessible": True,
        "judgement": None,
        "wall_seconds": 55.1,
    }
    record = record_from_summary(spec, RunSummary.from_json(summary), 61.0, "/runs/x")
    assert record.stage_seconds == {"ScanChair": 7.1, "WalkToChair": 20.0}
    assert record.accessible_after_assistance is True and record.instructions == 2
    assert record.seated is None and record.error is None
    assert record.helper == "disobeys" and record.wall_seconds == 61.0
    failed = record_from_error(spec, "worker crashed: killed by SIGSEGV", 3.0, None)
    assert failed.outcome == "failure" and failed.error.endswith("SIGSEGV")


@pytest.mark.slow
def test_report_folder_has_a_picture_per_chair_and_per_trial(tmp_path, fake_worker, monkeypatch):
    scene = tmp_path / "scene.png"
    from PIL import Image

    Image.new("RGB", (8, 8), (200, 10, 10)).save(scene)
    ply = tmp_path / "chair.ply"
    trimesh.creation.box((0.4, 0.4, 0.5)).apply_translation((0.8, 0.0, 0.25)).export(ply)
    monkeypatch.setenv("FAKE_SCENE", str(scene))
    monkeypatch.setenv("FAKE_PLY", str(ply))
    folder = write_chairs(tmp_path / "chairs", ["a.obj", "b.obj"])
    out = tmp_path / "out"
    status = cli.main(
        ["trials", "--chairs", str(folder), "--out", str(out), "--workers", "3",
         "--worker-cmd", " ".join(fake_worker)]
    )  # fmt: skip
    assert status == 0
    assert sorted(p.name for p in (out / "chairs").iterdir()) == ["a.png", "b.png"]
    assert len(list((out / "trials").glob("*.png"))) == 12
    picture = np.asarray(Image.open(out / "chairs" / "a.png"))
    assert picture.shape[0] > 200 and picture.std() > 5  # something was drawn
    report = (out / "report.md").read_text()
    assert "## (1) Seating bear success" in report and "chairs/a.png" in report
    with TrialStore(out / "trials.sqlite") as store:
        records = store.records()
    assert copy_trial_scenes(records, tmp_path / "again") == 12
    assert set(render_chair_pictures(records, tmp_path / "again-chairs")) == {"a.obj", "b.obj"}


def test_progress_lines_and_eta():
    class Stream:
        def __init__(self):
            self.text = ""

        def write(self, text):
            self.text += text

        def flush(self):
            pass

    now = [100.0]
    stream = Stream()
    progress = Progress(10, already_done=2, stream=stream, clock=lambda: now[0])
    assert progress.eta_seconds() is None
    now[0] += 30.0
    progress.update(make_record("accessible", "success", trial_index=2))
    now[0] += 30.0
    progress.update(make_record("accessible", "failure", trial_index=3))
    assert progress.eta_seconds() == pytest.approx(30.0 * 6)
    lines = stream.text.splitlines()
    assert len(lines) == 2 and "\r" not in stream.text  # not a terminal: a line per trial
    assert "4/10" in lines[-1] and "ETA 3m00s" in lines[-1] and "at ReleaseAndStand" in lines[-1]
    assert format_duration(3725) == "1h02m" and format_duration(42) == "42s"


@pytest.mark.slow
def test_ray_backend_runs_the_same_trials_with_the_same_records(tmp_path, fake_worker, monkeypatch):
    fake_ray = FakeRay()
    monkeypatch.setitem(sys.modules, "ray", fake_ray)
    folder = write_chairs(tmp_path / "chairs", ["a.obj", "crash.obj"])
    out = tmp_path / "out"
    status = cli.main(
        ["trials", "--chairs", str(folder), "--out", str(out), "--backend", "ray",
         "--address", "ray://head:10001", "--workers", "3", "--worker-cmd", " ".join(fake_worker)]
    )  # fmt: skip
    assert status == 0
    assert fake_ray.init_kwargs["address"] == "ray://head:10001"
    assert fake_ray.remote_options["max_retries"] == 0
    with TrialStore(out / "trials.sqlite") as store:
        ray_records = store.records()
    assert len(ray_records) == 12
    crashed = next(r for r in ray_records if r.chair == "crash.obj" and r.trial_index == 1)
    assert "SIGSEGV" in (crashed.error or "")
    status = cli.main(
        ["trials", "--chairs", str(folder), "--out", str(tmp_path / "local"),
         "--worker-cmd", " ".join(fake_worker)]
    )  # fmt: skip
    with TrialStore(tmp_path / "local" / "trials.sqlite") as store:
        local_records = store.records()
    assert table_without_timing(ray_records) == table_without_timing(local_records)


def test_the_real_worker_reports_an_unusable_chair_as_an_error(tmp_path, capsys):
    from bearchair.evaluation import worker
    from bearchair.evaluation.worker_process import RESULT_MARKER

    payload = {
        "chair_path": str(tmp_path / "missing.obj"),
        "placement": "accessible",
        "helper": "obeys",
        "seed": 1,
        "trial_index": 0,
        "out_dir": str(tmp_path / "run"),
        "timeout_s": 300,
    }
    assert worker.main([json.dumps(payload)]) == 3
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert line.startswith(RESULT_MARKER)
    assert "no such file" in json.loads(line[len(RESULT_MARKER) :])["error"]
    assert worker.main([]) == 2
    assert worker.mission_timeout_s(300) == 270 and worker.mission_timeout_s(20) == 16


def test_an_interrupted_run_worker_kills_its_trial_process(tmp_path, fake_worker, monkeypatch):
    import threading

    from bearchair.evaluation.worker_process import run_worker

    monkeypatch.setenv("FAKE_SLEEP_S", "30")
    spec = expand_protocol(entries(["a.obj"], tmp_path), "paper", 0)[0]

    # Ctrl-C must reach Python as KeyboardInterrupt, whatever an earlier test's library
    # (a qi session installs its own signal handling) left installed.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    sent_at: list[float] = []

    def interrupt_once_the_worker_runs() -> None:
        # Not after a fixed delay: on a loaded machine the worker may still be starting,
        # and an interrupt then is the harness stopping before the trial began.
        deadline = time.monotonic() + 30.0
        while not worker_pids(tmp_path) and time.monotonic() < deadline:
            time.sleep(0.02)
        sent_at.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=interrupt_once_the_worker_runs, daemon=True).start()
    try:
        with pytest.raises(KeyboardInterrupt):
            run_worker(fake_worker, spec.to_payload(tmp_path / "run", 60), 60)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert time.monotonic() - sent_at[0] < 10  # stopped, not waited for (it sleeps 30 s)
    pids = worker_pids(tmp_path)
    assert len(pids) == 1 and not process_alive(pids[0])


def test_refused_chairs_are_a_cause_of_their_own():
    reason = "seat too high for the NAO: seat 0.43 m, the NAO places a bear at most 0.40 m high"
    refused = make_record(
        "accessible",
        "failure",
        chair="tall.obj",
        failed_stage="CheckSeatReachable",
        reason=f"CheckSeatReachable: refused: {reason}",
    )
    records = [refused] * 3 + [make_record("accessible", "failure")]
    table = compute_table(records)
    assert table.refusals == (("tall.obj", reason, 3),)
    assert ("CheckSeatReachable", 3) in table.failure_stages
    text = format_table(table)
    assert "Refused (no stance reaches the seat): 3 trial(s) on 1 chair(s)" in text
    assert f"tall.obj (3): {reason}" in text
    assert "## Refused chairs" in markdown_report(table, records)
    markdown = markdown_report(table, records, seat_heights_m={"tall.obj": 0.4325})
    assert "tall.obj (3 trials, manifest seat 0.432 m)" in markdown


def test_a_refusal_where_no_sitting_was_imagined_is_counted_as_one():
    reason = (
        "no level surface the bear rests on within the NAO's seat heights (0.110-0.429 m): "
        "the scan's lie at 0.446 m"
    )
    refused = make_record(
        "accessible",
        "failure",
        chair="sled.obj",
        failed_stage="ImagineSitting",
        reason=f"NoSittingFound: refused: {reason}; no sitting imagined (ImagineAgain: ...)",
    )
    not_refused = make_record(
        "accessible",
        "failure",
        chair="sofa.obj",
        failed_stage="ImagineSitting",
        reason="NoSittingFound: ImagineAgain: no sitting pose: no correct sitting in 80 drops",
    )
    table = compute_table([refused, not_refused])
    assert table.refusals == (
        ("sled.obj", f"{reason}; no sitting imagined (ImagineAgain: ...)", 1),
    )


def test_a_scan_that_cannot_tell_the_reach_is_not_a_refusal():
    lost = make_record(
        "accessible",
        "failure",
        chair="tub.obj",
        failed_stage="CheckSeatReachable",
        reason=(
            "CheckSeatReachable: cannot tell whether the seat is within reach: the scan shows "
            "no seat under the sitting point (seat out of the NAO's reach: ...)"
        ),
    )
    table = compute_table([lost])
    assert table.refusals == ()
    assert ("CheckSeatReachable", 1) in table.failure_stages


@pytest.mark.parametrize(
    ("backend", "workers", "cores", "expected"),
    [
        ("local", 2, 2, 1),
        ("local", 1, 2, 2),
        ("local", 4, 2, 1),
        ("local", 1, 8, 2),
        ("ray", 8, 2, 2),
    ],
)
def test_each_trials_imagination_gets_the_cores_the_other_trials_leave(
    monkeypatch, backend, workers, cores, expected
):
    import argparse

    from bearchair.evaluation import cmd_trials as trials_cli

    monkeypatch.setattr(trials_cli.os, "cpu_count", lambda: cores)
    args = argparse.Namespace(backend=backend, workers=workers)
    assert trials_cli.imagination_workers(args) == expected


@pytest.mark.slow
def test_the_imagination_workers_reach_the_trials_payload_and_the_skills(tmp_path):
    from bearchair.skills.default_skills import DefaultSkills

    spec = expand_protocol([ChairEntry(tmp_path / "a.obj", "chair", 90.0)], "paper", 0)[0]
    assert spec.to_payload(tmp_path, 60.0, imagination_workers=1)["imagination_workers"] == 1
    assert DefaultSkills(imagination_workers=1).imagine_sitting.keywords == {"workers": 1}
