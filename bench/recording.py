"""What a Rerun recording costs a mission: the same simulated run with and without it.

    python bench/recording.py              # box chair, seed 0: one run without, one with
    python bench/recording.py --runs 3     # three of each, alternating; medians
    python bench/recording.py --chair MESH

Runs the whole mission in the simulated world (``bearchair.executive.run.run_in_simulation``)
alternately without and with ``--record``, same seed, and prints each run's wall time,
this process's CPU time (every thread: the mission, the simulated world, Rerun's
encoder and writer; the imagination's worker processes are left out, they do the same
work either way), the time spent in the recording's post-tick hook (its own clock, per
part) and the recording's size; then the medians and three ratios: the wall-time
difference over the run without, the CPU-time difference, and the hook's time over the
run with. Wall times of whole runs swing with the machine's load (other processes
share its cores); CPU time is the steadier figure of what recording adds, and the
hook's wall time also counts its waits for the GIL. The target (issue 19): recording
costs <= 10 % of a run's wall time.
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bearchair.executive.config import RunConfig
from bearchair.executive.recording.mission_recording import RECORDING_FILE, rerun_available
from bearchair.executive.run import run_in_simulation

TARGET_RATIO = 0.10


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=1, help="runs of each kind (default 1)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--chair", type=Path, help="a chair mesh (default: the box chair)")
    args = parser.parse_args(argv)
    if not rerun_available():
        print("bench/recording.py: needs rerun-sdk: pip install 'bearchair[viewer]'")
        return 0
    walls: dict[bool, list[float]] = {False: [], True: []}
    cpus: dict[bool, list[float]] = {False: [], True: []}
    hooks: list[float] = []
    hook_cpus: list[float] = []
    base = RunConfig(chair_path=args.chair, seed=args.seed, mute=True)
    with tempfile.TemporaryDirectory(prefix="bench-recording-") as folder:
        for index in range(args.runs):
            for record in (False, True):
                out_dir = Path(folder) / f"{'with' if record else 'without'}-{index}"
                config = dataclasses.replace(base, out_dir=out_dir, record=record)
                cpu_start = time.process_time()
                summary = run_in_simulation(config)
                cpu = time.process_time() - cpu_start
                wall = summary.wall_seconds
                walls[record].append(wall)
                cpus[record].append(cpu)
                line = (
                    f"run {index} {'with   ' if record else 'without'} recording: "
                    f"{summary.outcome:<7} wall {wall:7.1f} s, cpu {cpu:7.1f} s"
                )
                cost = summary.recording
                if record:
                    if cost is None:
                        raise SystemExit("bench/recording.py: a recorded run without its cost")
                    hooks.append(cost.seconds)
                    hook_cpus.append(cost.cpu_seconds)
                    size_mb = (out_dir / RECORDING_FILE).stat().st_size / 1e6
                    parts = ", ".join(f"{k} {v:.2f}" for k, v in cost.seconds_by_part.items())
                    line += (
                        f", hook {cost.seconds:6.2f} s ({cost.seconds / wall:5.1%}; cpu "
                        f"{cost.cpu_seconds:.2f} s), "
                        f"{size_mb:.1f} MB; parts (s): {parts}"
                    )
                if not summary.succeeded:
                    line += f"\n    failed at {summary.failed_stage}: {summary.reason}"
                print(line, flush=True)
    without, with_ = statistics.median(walls[False]), statistics.median(walls[True])
    cpu_without, cpu_with = statistics.median(cpus[False]), statistics.median(cpus[True])
    hook = statistics.median(hooks)
    wall_ratio = (with_ - without) / without
    hook_ratio = hook / with_
    print(f"median wall without recording: {without:7.1f} s (cpu {cpu_without:7.1f} s)")
    print(f"median wall with recording:    {with_:7.1f} s (cpu {cpu_with:7.1f} s)")
    print(f"wall difference / without:     {wall_ratio:+7.1%}")
    print(f"cpu difference / without:      {(cpu_with - cpu_without) / cpu_without:+7.1%}")
    print(f"hook time / wall with:         {hook_ratio:7.1%}  (target <= {TARGET_RATIO:.0%})")
    print(f"hook cpu / wall with:          {statistics.median(hook_cpus) / with_:7.1%}")
    return 0 if hook_ratio <= TARGET_RATIO else 1


if __name__ == "__main__":
    sys.exit(main())
