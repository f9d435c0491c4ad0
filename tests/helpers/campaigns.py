"""A campaign without physics: the fake trial worker, box chairs with a manifest, a
stand-in for the Ray calls the backend makes, and Table 1 without its timings."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import trimesh

from bearchair.evaluation.report import compute_table
from bearchair.evaluation.trial_record import TrialRecord

# The fake worker speaks the real worker's protocol. Its summary depends only on the
# trial's seed and placement, so the same campaign seed gives the same records. Chairs
# named "crash*" segfault on trial 1, "hang*" sleep forever on trial 2; FAKE_SLEEP_S
# slows every trial; every start is appended to FAKE_LOG.
FAKE_WORKER = textwrap.dedent(
    """
    import json, os, signal, sys, time
    from pathlib import Path
    payload = json.loads(sys.argv[-1])
    out = Path(payload["out_dir"]); out.mkdir(parents=True, exist_ok=True)
    chair = Path(payload["chair_path"]).name
    index, seed = payload["trial_index"], payload["seed"]
    with open(os.environ["FAKE_LOG"], "a") as log:
        log.write(f"{chair} {index} {seed} {os.getpid()}\\n")
    time.sleep(float(os.environ.get("FAKE_SLEEP_S", "0")))
    if chair.startswith("crash") and index == 1:
        os.kill(os.getpid(), signal.SIGSEGV)
    if chair.startswith("hang") and index == 2:
        time.sleep(1000)
    inaccessible = payload["placement"] == "inaccessible"
    success = seed % 4 != 0
    accessible = seed % 7 != 0
    failed = None if success else ("ReleaseAndStand" if seed % 3 else "ImagineSitting")
    stages = [{"name": n, "status": "SUCCESS", "seconds": round(1 + (seed % 10) / 10 * k, 3),
               "message": ""} for k, n in enumerate(["ScanChair", "ImagineSitting", "WalkToChair"], 1)]
    summary = {
        "outcome": "success" if success else "failure", "failed_stage": failed,
        "reason": "" if success else f"{failed}: fake failure {seed % 3}",
        "stages": stages, "sitting_pose": {"position_m": [0.8, 0.0, 0.3], "yaw_deg": 10.0},
        "instructions": ["turn the chair"] * (2 if inaccessible else 0),
        "rotations": 2 if inaccessible else 0, "accessible": accessible,
        "judgement": {"seated": success, "on_seat": True, "torso_tilt_deg": 3.0,
                      "facing_error_deg": float(seed % 50), "reason": ""},
        "wall_seconds": 12.5, "interrupted": False,
    }
    (out / "summary.json").write_text(json.dumps(summary))
    scene = os.environ.get("FAKE_SCENE")
    if scene:
        (out / "final_scene.png").write_bytes(Path(scene).read_bytes())
        (out / "chair_reconstructed.ply").write_bytes(Path(os.environ["FAKE_PLY"]).read_bytes())
    print("noise on stdout")
    print("BEARCHAIR-TRIAL-RESULT " + json.dumps({"summary": summary}), flush=True)
    """
)


def write_chairs(folder: Path, names: list[str], manifest: dict | None = None) -> Path:
    """Box "chairs" with a manifest (by default each with a front of 90 degrees)."""
    folder.mkdir(parents=True, exist_ok=True)
    box = trimesh.creation.box((0.4, 0.4, 0.5))
    for name in names:
        box.export(folder / name)
    if manifest is None:
        manifest = {"meshes": [{"file": n, "kind": "chair", "front_yaw_deg": 90.0} for n in names]}
    (folder / "manifest.json").write_text(json.dumps(manifest))
    return folder


def worker_starts(tmp_path: Path) -> list[str]:
    log = tmp_path / "fake_worker.log"
    return log.read_text().splitlines() if log.exists() else []


def worker_pids(tmp_path: Path) -> list[int]:
    return [int(line.split()[3]) for line in worker_starts(tmp_path)]


def table_without_timing(records: list[TrialRecord]) -> tuple:
    table = compute_table(records)
    return table.seating, table.assistance, table.failure_causes, table.stage_median_s


class FakeRay:
    """The few Ray calls the backend makes, on threads (Ray itself is an optional extra)."""

    def __init__(self, cpus: float = 3.0):
        from concurrent.futures import ThreadPoolExecutor

        self.pool = ThreadPoolExecutor(max_workers=4)
        self.init_kwargs = None
        self.remote_options = None
        self.cpus = cpus
        self.shipped_files: list[Path] = []

    def init(self, **kwargs):
        self.init_kwargs = kwargs
        for folder in (kwargs.get("runtime_env") or {}).get("py_modules", []):
            # Ray zips the folder during init; the head removes its copy afterwards.
            self.shipped_files = [p for p in Path(folder).rglob("*")]
            self.shipped_links = [p for p in self.shipped_files if p.is_symlink()]

    def cluster_resources(self):
        return {"CPU": self.cpus}

    def nodes(self):
        return [{"Alive": True}, {"Alive": True}]

    def remote(self, **options):
        self.remote_options = options
        fake = self

        def decorate(function):
            class Task:
                @staticmethod
                def remote(*args):
                    return fake.pool.submit(function, *args)

            return Task

        return decorate

    def wait(self, refs, num_returns=1):
        from concurrent.futures import FIRST_COMPLETED, wait

        done, _ = wait(refs, return_when=FIRST_COMPLETED)
        ready = list(done)[:num_returns]
        return ready, [r for r in refs if r not in ready]

    def get(self, ref):
        return ref.result()

    def cancel(self, ref, force=False):
        ref.cancel()
