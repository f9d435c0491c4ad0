"""Benchmark: where a whole simulated mission's time goes, stage by stage.

Runs the whole mission on the box chair and on the first N calibration chairs with a
front in ../shared/chairs, each in a process of its own as ``bearchair trials`` runs a
trial: a fork of the preloaded trial server (``bearchair.evaluation.forked_workers``), or
with ``--fresh`` a fresh interpreter, which pays the imports and the planner's casadi
problems (about 3 s) in every run. Calibration chair k runs the paper protocol's trial k mod 6 (seeded as in the
campaign), so the six conditions (accessible, inaccessible with a helper who obeys or
disobeys) are all met; the box chair runs an accessible trial. For every run and stage
it prints:

    wall      wall time of the stage (seconds)
    cpu       CPU time of the run's process in all its threads (seconds; not its child
              processes): on a shared machine, wall time minus cpu is mostly waiting for a core
    robot     simulated time that passed (seconds)
    step      wall time stepping the world (physics and the processes that live in it:
              the NAO's kinematics, the carried bear, the helper, the contact monitor)
    physics   of which pybullet's stepSimulation
    render    wall time rendering camera frames (and the pictures of the run record)
    noise     wall time applying the camera noise model
    rest      wall - step - render - noise: the mission's own compute (and waiting)
    rtf       robot / wall, the simulated world's real-time factor
    frames    frames rendered (and their megapixels)

"setup" is the process from its start to the first tick (building the world, and with
``--fresh`` the imports; the server's one-off preload time is printed apart),
"teardown" what follows the last tick (final picture, ground truth, record). Then the
medians over runs, and each run's peak memory (resident set of the run's process; of
its whole process tree, sampled every 2 s, including the imagination's workers).

    .venv/bin/python bench/mission.py [--chairs 6] [--seed 0] [--profile] [--out DIR]
        [--json FILE] [--no-box] [--fresh]

``--profile`` runs each mission under cProfile in every thread (the tick loop and the
leaves' workers) and prints the top functions by cumulative time, summed over threads
and runs; the merged statistics are written to OUT/profile.pstats.
"""

from __future__ import annotations

import time

PROCESS_STARTED = time.perf_counter()

import argparse  # noqa: E402  (the clock above starts before the imports are paid)
import dataclasses  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SHARED_CHAIRS = ROOT.parent / "shared" / "chairs"
RESULT_MARKER = "BENCH-MISSION-RESULT "
COLUMNS = ("wall", "cpu", "robot", "step", "physics", "render", "noise", "rest")
MEASURED_STAGES = ("WalkToChair", "ScanChair", "SeatBear", "ReleaseAndStand")


# --- in the run's own process -------------------------------------------------------------


class StageMeter:
    """An ``on_tick`` callback that splits the run's time among the mission's stages.

    The work between two ticks belongs to the stage that was running after the first of
    them (a leaf's worker starts in the tick that initialises it).
    """

    def __init__(self, started: float) -> None:
        self.rows: dict[str, dict[str, float]] = {}
        self.clock: Any = None
        self.peak_tree_bytes = 0
        self._started = started
        self._last: tuple[float, float, Any, float] | None = None
        self._current = "setup"
        self._process = _psutil_process()
        self._next_sample = 0.0

    def __call__(self, runner: Any) -> None:
        if self.clock is None:
            self.clock = runner.robot.clock
        self._charge()
        running = [s.name for s in runner.stages if s.status == "RUNNING"]
        self._current = running[0] if running else "teardown"
        # Listing a process's children reads every /proc/*/stat: at most every 2 s, or it
        # would take the tick loop's GIL from the mission.
        if self._process is not None and time.perf_counter() >= self._next_sample:
            self.peak_tree_bytes = max(self.peak_tree_bytes, _tree_rss(self._process))
            self._next_sample = time.perf_counter() + 2.0

    def finish(self) -> None:
        """Charges what followed the last tick to the current stage ("teardown")."""
        self._charge()

    def _charge(self) -> None:
        from bearchair.hardware.sim.clock import WorldTimers

        timers = self.clock.timers.copy()
        now = (time.perf_counter(), self.clock.now(), timers, time.process_time())
        before = self._last or (self._started, 0.0, WorldTimers(), 0.0)
        row = self.rows.setdefault(
            self._current, {**dict.fromkeys(COLUMNS, 0.0), "frames": 0, "megapixels": 0.0}
        )
        row["wall"] += now[0] - before[0]
        row["robot"] += now[1] - before[1]
        row["cpu"] += now[3] - before[3]
        row["step"] += timers.stepping_s - before[2].stepping_s
        row["physics"] += timers.physics_s - before[2].physics_s
        row["render"] += timers.render_s - before[2].render_s
        row["noise"] += timers.noise_s - before[2].noise_s
        row["frames"] += timers.frames - before[2].frames
        row["megapixels"] += (timers.pixels - before[2].pixels) / 1e6
        row["rest"] = row["wall"] - row["step"] - row["render"] - row["noise"]
        self._last = now


def _psutil_process() -> Any:
    try:
        import psutil
    except ImportError:
        return None
    return psutil.Process()


def _tree_rss(process: Any) -> int:
    total = 0
    for member in [process, *process.children(recursive=True)]:
        try:
            total += member.memory_info().rss
        except Exception:  # a worker that just ended
            continue
    return total


def run_one(payload: dict[str, Any], started: float = PROCESS_STARTED) -> dict[str, Any]:
    """Runs one mission in this process and returns its measurements.

    Args:
        payload: the case (``_cases``).
        started: ``time.perf_counter()`` when the run's process began.
    """
    profiler = _ThreadProfiles() if payload.get("profile") else None
    if profiler is not None:
        profiler.start()
    from bearchair.executive.config import RunConfig
    from bearchair.executive.run import run_in_simulation

    meter = StageMeter(started)
    config = dataclasses.replace(RunConfig.from_payload({"timeout_s": 600.0, **payload}), mute=True)
    summary = run_in_simulation(config, on_tick=meter)
    meter.finish()
    result = {
        "label": payload["label"],
        "outcome": summary.outcome,
        "failed_stage": summary.failed_stage,
        "reason": summary.reason[:200],
        "stages": meter.rows,
        "wall_s": time.perf_counter() - started,
        "peak_process_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "peak_tree_bytes": meter.peak_tree_bytes,
    }
    if profiler is not None:
        result["pstats"] = profiler.dump(Path(payload["out_dir"]) / "profile.pstats")
    preload = sys.modules.get("bearchair.evaluation.server_preload")
    result["server_preload_s"] = getattr(preload, "PRELOAD_S", None)
    return result


def forked_entry(argv: list[str]) -> int:
    """:func:`run_one` in a fork of the trial server (``PreloadedLauncher``'s entry)."""
    from bearchair.evaluation.worker_process import RESULT_MARKER as TRIAL_RESULT

    started = time.perf_counter()
    result = run_one(json.loads(argv[0]), started)
    print(TRIAL_RESULT + json.dumps({"summary": result}), flush=True)
    return 0


class _ThreadProfiles:
    """cProfile in every thread started from now on, and in this one."""

    def __init__(self) -> None:
        import cProfile

        self._make = cProfile.Profile
        self._profiles: list[Any] = []

    def start(self) -> None:
        import threading

        def begin(frame: Any, event: str, arg: Any) -> None:
            # The first event of a new thread: replace this hook by a profiler of its own.
            profile = self._make()
            self._profiles.append(profile)
            profile.enable()

        threading.setprofile(begin)
        main = self._make()
        self._profiles.append(main)
        main.enable()

    def dump(self, path: Path) -> str:
        import pstats
        import threading

        threading.setprofile(None)
        merged = None
        for profile in self._profiles:
            profile.disable()
            try:
                stats = pstats.Stats(profile)
            except TypeError:  # a thread whose profiler saw no call
                continue
            if merged is None:
                merged = stats
            else:
                merged.add(stats)
        path.parent.mkdir(parents=True, exist_ok=True)
        merged.dump_stats(str(path))
        return str(path)


# --- the driver ----------------------------------------------------------------------------


def _cases(chairs: int, seed: int, box: bool, out: Path) -> list[dict[str, Any]]:
    cases = []
    if box:
        cases.append(
            {
                "label": "box-chair accessible",
                "chair_path": None,
                "placement": "accessible",
                "helper": "obeys",
                "seed": seed,
            }
        )
    if chairs > 0:
        if not (SHARED_CHAIRS / "manifest.json").is_file():
            print(f"{SHARED_CHAIRS} not found: only the box chair is run", file=sys.stderr)
        else:
            from bearchair.evaluation.protocol import discover_chairs, expand_protocol

            found, _ = discover_chairs(SHARED_CHAIRS, chairs)
            specs = expand_protocol(found, "paper", seed)
            per_chair = len(specs) // max(len(found), 1)
            for index in range(len(found)):
                spec = specs[index * per_chair + index % per_chair]
                cases.append(
                    {
                        "label": f"{Path(spec.chair).stem} t{spec.trial_index} {spec.experiment}",
                        "chair_path": str(SHARED_CHAIRS / spec.chair),
                        "placement": spec.placement,
                        "helper": spec.helper,
                        "seed": spec.seed,
                    }
                )
    for index, case in enumerate(cases):
        case["out_dir"] = str(out / f"run{index:02d}")
    return cases


def _run_forked(case: dict[str, Any]) -> dict[str, Any]:
    # By its package name, so that the trial server can import the entry.
    sys.path.insert(0, str(ROOT))
    from bearchair.evaluation.forked_workers import PreloadedLauncher
    from bearchair.evaluation.worker_process import run_worker
    from bench import mission as this_module

    outcome = run_worker(PreloadedLauncher(this_module.forked_entry), case, 1800.0)
    if outcome.summary is None:
        return {"label": case["label"], "error": outcome.error}
    return outcome.summary


def _run_fresh(case: dict[str, Any]) -> dict[str, Any]:
    environment = {
        **os.environ,
        "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
    }
    process = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--one", json.dumps(case)],
        capture_output=True,
        text=True,
        env=environment,
        cwd=ROOT,
    )
    for line in process.stdout.splitlines():
        if line.startswith(RESULT_MARKER):
            return json.loads(line[len(RESULT_MARKER) :])
    tail = "\n".join(process.stderr.strip().splitlines()[-5:])
    return {"label": case["label"], "error": f"exit {process.returncode}: {tail}"}


def _print_run(result: dict[str, Any]) -> None:
    print(
        f"\n{result['label']}: {result['outcome']}"
        + (f" at {result['failed_stage']} ({result['reason']})" if result["failed_stage"] else "")
    )
    print(f"  {'stage':<20}" + "".join(f"{c:>8}" for c in COLUMNS) + f"{'rtf':>7}{'frames':>8}")
    for name, row in result["stages"].items():
        rtf = row["robot"] / row["wall"] if row["wall"] > 0 else 0.0
        print(
            f"  {name:<20}"
            + "".join(f"{row[c]:8.2f}" for c in COLUMNS)
            + f"{rtf:7.1f}{row['frames']:5d}/{row['megapixels']:.0f}M"
        )
    print(
        f"  total {result['wall_s']:.1f} s; peak memory {result['peak_process_bytes'] / 2**20:.0f} MiB "
        f"(process), {result['peak_tree_bytes'] / 2**20:.0f} MiB (process tree, sampled)"
    )


def _print_summary(results: list[dict[str, Any]]) -> None:
    ok = [r for r in results if "error" not in r]
    if not ok:
        return
    stages: list[str] = []
    for result in ok:
        stages += [name for name in result["stages"] if name not in stages]
    print(f"\nmedians over {len(ok)} runs (a stage's median over the runs that reached it)")
    print(f"  {'stage':<20}" + "".join(f"{c:>8}" for c in COLUMNS) + f"{'rtf':>7}")
    for name in stages:
        rows = [r["stages"][name] for r in ok if name in r["stages"]]
        medians = {c: statistics.median(row[c] for row in rows) for c in COLUMNS}
        rtf = statistics.median(row["robot"] / row["wall"] for row in rows if row["wall"] > 0)
        print(f"  {name:<20}" + "".join(f"{medians[c]:8.2f}" for c in COLUMNS) + f"{rtf:7.1f}")

    def total(result: dict[str, Any], column: str, names: tuple[str, ...] | None = None) -> float:
        return sum(
            row[column] for name, row in result["stages"].items() if names is None or name in names
        )

    walls = [r["wall_s"] for r in ok]
    compute = [total(r, "rest") for r in ok]
    print(
        f"\n  run wall time (process start to end): median {statistics.median(walls):.1f} s, "
        f"max {max(walls):.1f} s"
    )
    print(
        f"  mission compute (wall - stepping - rendering - noise): median "
        f"{statistics.median(compute):.1f} s, max {max(compute):.1f} s"
    )
    for names in (("WalkToChair",), ("ScanChair",), ("SeatBear", "ReleaseAndStand")):
        ratios = [
            total(r, "robot", names) / total(r, "wall", names)
            for r in ok
            if total(r, "wall", names) > 0
        ]
        if ratios:
            print(
                f"  real-time factor in {'+'.join(names)}: median {statistics.median(ratios):.1f}, "
                f"min {min(ratios):.1f}"
            )
    preloads = [r["server_preload_s"] for r in ok if r.get("server_preload_s") is not None]
    if preloads:
        print(f"  trial server's preload (paid once, not in any run): {preloads[0]:.1f} s")
    peaks = [r["peak_process_bytes"] / 2**20 for r in ok]
    trees = [r["peak_tree_bytes"] / 2**20 for r in ok]
    print(f"  peak memory: process max {max(peaks):.0f} MiB, process tree max {max(trees):.0f} MiB")
    outcomes = sum(r["outcome"] == "success" for r in ok)
    print(f"  outcomes: {outcomes}/{len(ok)} seated")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--chairs", type=int, default=6, help="calibration chairs (default 6)")
    parser.add_argument("--seed", type=int, default=0, help="campaign seed (default 0)")
    parser.add_argument("--no-box", action="store_true", help="skip the box chair")
    parser.add_argument("--profile", action="store_true", help="cProfile every thread")
    parser.add_argument("--top", type=int, default=30, help="profile lines to print")
    parser.add_argument("--out", type=Path, help="run records (default: a temporary folder)")
    parser.add_argument("--json", type=Path, help="write every measurement here")
    parser.add_argument(
        "--fresh", action="store_true", help="each run in a fresh interpreter (no preloading)"
    )
    parser.add_argument("--one", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    if args.one:
        result = run_one(json.loads(args.one))
        print(RESULT_MARKER + json.dumps(result), flush=True)
        return 0

    out = args.out or Path(tempfile.mkdtemp(prefix="bearchair-bench-mission-"))
    cases = _cases(args.chairs, args.seed, not args.no_box, out)
    results = []
    for case in cases:
        case["profile"] = args.profile
        print(f"running {case['label']} (seed {case['seed']}) ...", file=sys.stderr, flush=True)
        result = _run_fresh(case) if args.fresh else _run_forked(case)
        results.append(result)
        if "error" in result:
            print(f"\n{result['label']}: ERROR {result['error']}")
        else:
            _print_run(result)
        sys.stdout.flush()
    _print_summary(results)
    if args.profile:
        import pstats

        files = [r["pstats"] for r in results if "pstats" in r]
        if files:
            merged = pstats.Stats(*files, stream=sys.stdout)
            merged.dump_stats(str(out / "profile.pstats"))
            print(f"\nprofile over {len(files)} runs, every thread ({out / 'profile.pstats'}):")
            merged.sort_stats("cumulative").print_stats(args.top)
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    print(f"run records: {out}")
    return 0 if all("error" not in r for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
