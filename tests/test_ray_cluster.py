"""Trials on Ray without a shared filesystem: what is shipped to the nodes, what comes
back, and a real local cluster of a head and two worker nodes started from different
working folders."""

from __future__ import annotations

import io
import json
import math
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bearchair.evaluation.shipping import (
    chair_files,
    pack_folder,
    stage_package,
    unpack_folder,
    write_chair,
)
from bearchair.evaluation.store import TrialStore
from bearchair.evaluation.trial_backends import NODE_FILE, RayBackend
from bearchair.executive import cli
from tests.helpers.campaigns import FAKE_WORKER, FakeRay, write_chairs

REPO = Path(__file__).resolve().parents[1]


def _head(commit: str | None) -> str | None:
    """The commit without ``+dirty``: the checkout may be edited while the suite runs
    (``git_commit`` is read once per process), which changes no commit."""
    return commit.removesuffix("+dirty") if commit else commit


def test_the_staged_package_holds_real_files_and_is_imported_before_the_install(tmp_path):
    staged = stage_package(tmp_path / "ship")
    assert (staged / "evaluation" / "worker.py").is_file()
    assert not [p for p in staged.rglob("*") if p.is_symlink()]
    assert not list(staged.rglob("__pycache__"))
    # A node's trial subprocess puts the shipped copy first: it wins over the install,
    # and its records name the version and commit of the code it was copied from.
    from bearchair.core.provenance import software_versions

    env = {**os.environ, "PYTHONPATH": str(staged.parent)}
    code = (
        "import json, bearchair.evaluation.worker as w; from bearchair.core.provenance import "
        "software_versions as s; print(json.dumps([w.__file__, s()]))"
    )
    where, software = json.loads(
        subprocess.run(
            [sys.executable, "-c", code], env=env, cwd=tmp_path, capture_output=True, text=True,
            check=True,
        ).stdout
    )  # fmt: skip
    assert Path(where).resolve() == (staged / "evaluation" / "worker.py").resolve()
    here = software_versions()
    assert here["git_commit"] is not None
    assert _head(software["git_commit"]) == _head(here["git_commit"])
    assert software["bearchair"] == here["bearchair"]


def test_a_chair_ships_with_its_own_manifest_entry_only(tmp_path):
    folder = write_chairs(tmp_path / "chairs", ["a.obj", "b.obj"])
    files = chair_files(folder / "b.obj")
    assert sorted(files) == ["b.obj", "manifest.json"]
    assert json.loads(files["manifest.json"])["meshes"] == [
        {"file": "b.obj", "kind": "chair", "front_yaw_deg": 90.0}
    ]
    mesh = write_chair(files, tmp_path / "node")
    assert mesh == tmp_path / "node" / "b.obj"
    assert mesh.read_bytes() == (folder / "b.obj").read_bytes()
    with pytest.raises(ValueError, match="bare name"):
        write_chair({"../evil.obj": b""}, tmp_path / "node")


def test_a_tree_file_ships_and_lands_in_the_nodes_folder(tmp_path):
    from bearchair.evaluation.shipping import TrialScratch, tree_file

    xml = tmp_path / "my_tree.xml"
    xml.write_text('<root BTCPP_format="4"/>')
    assert tree_file("mission") == {} and tree_file("pkg.module:factory") == {}
    files = tree_file(str(xml))
    with TrialScratch() as scratch:
        here = scratch.payload_here({"tree": str(xml), "chair_path": None}, {}, files)
        assert Path(here["tree"]).read_text() == xml.read_text()
        assert Path(here["tree"]).is_relative_to(scratch.root)
    assert not Path(here["tree"]).exists()  # the node's folder goes with the trial


def test_a_run_folder_round_trips_and_an_escaping_archive_is_refused(tmp_path):
    run = tmp_path / "run"
    (run / "snapshots").mkdir(parents=True)
    (run / "summary.json").write_text('{"outcome": "success"}')
    (run / "snapshots" / "01-ScanChair-success.png").write_bytes(b"\x89PNG")
    written = unpack_folder(pack_folder(run), tmp_path / "head")
    assert sorted(p.relative_to(tmp_path / "head").as_posix() for p in written) == [
        "snapshots/01-ScanChair-success.png",
        "summary.json",
    ]
    assert (tmp_path / "head" / "summary.json").read_text() == '{"outcome": "success"}'
    evil = io.BytesIO()
    with tarfile.open(fileobj=evil, mode="w:gz") as archive:
        info = tarfile.TarInfo("../outside.txt")
        info.size = 1
        archive.addfile(info, io.BytesIO(b"x"))
    with pytest.raises(tarfile.TarError):
        unpack_folder(evil.getvalue(), tmp_path / "head2")
    assert not (tmp_path / "outside.txt").exists()


def test_ray_trials_run_in_a_node_folder_and_come_back_under_out(tmp_path, monkeypatch, capsys):
    script = tmp_path / "fake_worker.py"
    script.write_text(FAKE_WORKER)
    monkeypatch.setenv("FAKE_LOG", str(tmp_path / "fake_worker.log"))
    fake_worker = [sys.executable, str(script)]
    fake_ray = FakeRay(cpus=5)
    monkeypatch.setitem(sys.modules, "ray", fake_ray)
    folder = write_chairs(tmp_path / "chairs", ["a.obj"])
    out = tmp_path / "out"
    status = cli.main(
        ["trials", "--chairs", str(folder), "--out", str(out), "--backend", "ray",
         "--address", "head:6379", "--worker-cmd", " ".join(fake_worker)]
    )  # fmt: skip
    assert status == 0
    err = capsys.readouterr().err
    assert "5 CPU(s); 5 trial(s) at once" in err  # --workers defaults to the cluster's CPUs
    assert fake_ray.shipped_files and not fake_ray.shipped_links
    assert any(p.name == "worker.py" for p in fake_ray.shipped_files)
    assert fake_ray.init_kwargs["log_to_driver"] is False
    # The fake worker ran on the shipped chair in a node's temporary folder, not on the
    # head's paths; its run folder came back under --out.
    starts = (tmp_path / "fake_worker.log").read_text().splitlines()
    assert len(starts) == 6
    with TrialStore(out / "trials.sqlite") as store:
        records = store.records()
    for record in records:
        run_dir = Path(record.run_dir)
        assert run_dir.is_relative_to(out.resolve())
        assert json.loads((run_dir / "summary.json").read_text())["outcome"] in (
            "success",
            "failure",
        )
        assert (run_dir / NODE_FILE).is_file() and (run_dir / "worker.log").is_file()


def test_a_cluster_without_cpus_still_runs_one_trial_at_a_time(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", FakeRay(cpus=0))
    backend = RayBackend(None, 60.0, address="head:6379", ship_package=False)
    assert backend.connect().endswith("1 trial(s) at once")


# --- a real cluster -------------------------------------------------------------------

RAY_CLI = Path(sys.executable).with_name("ray")
MARKER = "BEARCHAIR_TEST_RAY_CLUSTER"
"""An environment variable every process of the test's cluster inherits: how the test
finds (by id) and stops the processes it started, and no other Ray on the machine."""


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _cluster_pids(marker: str) -> list[int]:
    needle = f"{MARKER}={marker}".encode()
    pids = []
    for proc in Path("/proc").iterdir():
        if proc.name.isdigit() and int(proc.name) != os.getpid():
            try:
                if needle in (proc / "environ").read_bytes().split(b"\0"):
                    pids.append(int(proc.name))
            except OSError:
                continue
    return pids


def _stop_cluster(marker: str) -> None:
    """SIGTERM, then SIGKILL, to every process of this test's cluster (found by id)."""
    for sig, wait_s in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
        for pid in _cluster_pids(marker):
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                continue
        deadline = time.monotonic() + wait_s
        while _cluster_pids(marker) and time.monotonic() < deadline:
            time.sleep(0.2)


START_ATTEMPTS = 3
"""``ray start`` gives a node 30 s to register (hard-coded in Ray); on a loaded machine it
can miss that, so the cluster is started again from scratch, up to this many times."""


def _start_cluster(root: Path, env: dict[str, str]) -> str:
    """Starts the head (not niced: it only coordinates) and two niced 1-CPU worker nodes,
    each from its own folder; returns the head's address."""
    failures = []
    for attempt in range(START_ATTEMPTS):
        address = f"127.0.0.1:{_free_port()}"
        common = ["--node-ip-address", "127.0.0.1", "--disable-usage-stats"]
        starts = [
            ("head", [], ["--head", "--num-cpus", "0", "--port", address.split(":")[1],
                          "--temp-dir", str(root / f"tmp{attempt}"), "--include-dashboard", "false"]),
            ("worker-1", ["nice", "-n", "10"], ["--address", address, "--num-cpus", "1"]),
            ("worker-2", ["nice", "-n", "10"], ["--address", address, "--num-cpus", "1"]),
        ]  # fmt: skip
        for name, prefix, args in starts:
            cwd = root / name
            cwd.mkdir(exist_ok=True)
            started = subprocess.run(
                [*prefix, str(RAY_CLI), "start", *args, *common],
                cwd=cwd, env=env, capture_output=True, text=True, timeout=180,
            )  # fmt: skip
            if started.returncode != 0:
                tail = (started.stderr or started.stdout).strip().splitlines()[-1:]
                failures.append(f"attempt {attempt + 1}, {name}: {' | '.join(tail)}")
                _stop_cluster(env[MARKER])
                break
        else:
            return address
    pytest.fail("ray start failed: " + "; ".join(failures))


@pytest.fixture
def ray_cluster() -> Iterator[tuple[str, dict[str, str]]]:
    """A head without CPUs and two 1-CPU worker nodes, each started from its own folder,
    with token authentication; yields the head's address and the environment (with the
    token) a driver needs."""
    pytest.importorskip("ray")
    if not RAY_CLI.exists():
        pytest.skip(f"no ray command beside {sys.executable}")
    # Ray's socket paths must stay under 107 characters: a short folder, not tmp_path.
    root = Path(tempfile.mkdtemp(prefix="bc-ray-", dir="/tmp"))
    marker = root.name
    token = secrets.token_hex(16)
    env = {**os.environ, MARKER: marker, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": token}
    env.pop("RAY_ADDRESS", None)
    try:
        address = _start_cluster(root, env)
        yield address, {k: v for k, v in env.items() if k != MARKER}
    finally:
        _stop_cluster(marker)
        shutil.rmtree(root, ignore_errors=True)


def _generated_chair(folder: Path) -> Path:
    from bearchair.testing.chairgen import generate_chair

    folder.mkdir(parents=True)
    chair = generate_chair(seed=1, family="four_legs")
    chair.mesh.export(folder / "gen-01.obj")
    entry = {
        "file": "gen-01.obj",
        "kind": "chair",
        "front_yaw_deg": math.degrees(chair.front_yaw_rad),
    }
    (folder / "manifest.json").write_text(json.dumps({"meshes": [entry]}))
    return folder


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_trials_on_a_two_node_cluster_write_every_record_under_the_heads_out(tmp_path, ray_cluster):
    from bearchair.core.provenance import software_versions

    address, env = ray_cluster
    head_software = software_versions()
    chairs = _generated_chair(tmp_path / "chairs")
    out = tmp_path / "out"
    # A command of its own, as a user runs it: Ray reads RAY_AUTH_MODE when imported.
    trials = subprocess.run(
        [str(Path(sys.executable).with_name("bearchair")), "trials", "--chairs", str(chairs),
         "--backend", "ray", "--address", address, "--out", str(out), "--timeout", "60",
         "--no-record"],
        env=env, cwd=tmp_path, capture_output=True, text=True, timeout=840,
    )  # fmt: skip
    assert trials.returncode == 0, trials.stderr
    assert "3 node(s), 2 CPU(s); 2 trial(s) at once" in trials.stderr
    # Only our lines on stderr: the header, the cluster, the progress, the report.
    ours = ("bearchair trials:", "[", "report:", "1 chairs x 6 trials", "trials ")
    assert [line for line in trials.stderr.splitlines() if not line.startswith(ours)] == []
    with TrialStore(out / "trials.sqlite") as store:
        records = store.records()
    assert len(records) == 6
    nodes, package_dirs, cwds = set(), set(), set()
    for record in records:
        run_dir = Path(record.run_dir)
        assert run_dir.is_relative_to(out.resolve())
        for name in ("summary.json", "ticks.jsonl", "tree.json", "worker.log", NODE_FILE):
            assert (run_dir / name).is_file(), f"{run_dir.name} lacks {name}"
        software = json.loads((run_dir / "summary.json").read_text())["software"]
        assert _head(software["git_commit"]) == _head(head_software["git_commit"])  # shipped
        where = json.loads((run_dir / NODE_FILE).read_text())
        nodes.add(where["node_id"])
        package_dirs.add(where["package_dir"])
        cwds.add(Path(where["cwd"]).name)
    assert len(nodes) == 2  # both worker nodes ran trials
    assert cwds == {"worker-1", "worker-2"}
    # The trials imported the package the head shipped, not the checkout's.
    assert not any(Path(d).resolve().is_relative_to(REPO) for d in package_dirs)
    scenes = sorted(p.name for p in (out / "trials").glob("*.png"))
    assert len(scenes) == len(
        [r for r in records if (Path(r.run_dir) / "final_scene.png").is_file()]
    )
    assert len(scenes) >= 1
    # The imagined pose is drawn on the head, from the records it unpacked.
    drawable = [r for r in records if r.sitting_pose is not None]
    assert (out / "chairs" / "gen-01.png").is_file() == bool(drawable)
    if drawable:
        assert "chairs/gen-01.png" in (out / "report.md").read_text()
