"""Where trial subprocesses run: here (a few at once) or as Ray tasks.

Both backends run the same trial worker (``bearchair.evaluation.worker_process``): here as
forks of a preloaded trial server (``bearchair.evaluation.forked_workers``), on Ray as a
command on the node that runs the task. They hand each :class:`WorkerOutcome` back to
the caller in the caller's thread, as soon as it is ready, so the harness alone writes
the records. On Ctrl-C (KeyboardInterrupt in
the caller's thread), a backend stops every running trial and re-raises; what was
stopped is never handed back.
"""

from __future__ import annotations

import contextlib
import importlib
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from typing import Any, Protocol

from bearchair.core.errors import BackendUnavailable
from bearchair.evaluation.forked_workers import PreloadedLauncher
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.worker_process import (
    ProcessGroup,
    WorkerLauncher,
    WorkerOutcome,
    as_launcher,
    default_worker_command,
    run_worker_with_retry,
)
from bearchair.executive.interrupts import emergency_stop_on_second_signal

Job = tuple[TrialSpec, dict[str, Any]]
"""A trial and its worker payload."""
OnResult = Callable[[TrialSpec, WorkerOutcome], None]


class Backend(Protocol):
    def run(self, jobs: Sequence[Job], on_result: OnResult) -> None:
        """Runs every job, calling ``on_result`` for each one as it finishes."""
        ...


class LocalBackend:
    """Runs ``workers`` trial subprocesses at once on this machine.

    Args:
        workers: subprocesses at once.
        timeout_s: per-trial wall time before the worker is killed.
        command: a worker command or launcher (tests inject a fake one); None forks
            the real worker from the preloaded trial server.
    """

    def __init__(
        self,
        workers: int,
        timeout_s: float,
        command: WorkerLauncher | list[str] | None = None,
    ) -> None:
        self.workers = max(1, workers)
        self.timeout_s = timeout_s
        self.launcher = PreloadedLauncher() if command is None else as_launcher(command)

    def run(self, jobs: Sequence[Job], on_result: OnResult) -> None:
        group = ProcessGroup()
        pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="trial")
        pending = {
            pool.submit(run_worker_with_retry, self.launcher, payload, self.timeout_s, group): (
                index,
                spec,
            )
            for index, (spec, payload) in enumerate(jobs)
        }
        try:
            with emergency_stop_on_second_signal(group.kill_all_now):
                self._hand_back(pending, on_result)
        except BaseException:
            group.stop_all()
            pool.shutdown(wait=True, cancel_futures=True)
            raise
        pool.shutdown(wait=True)

    @staticmethod
    def _hand_back(pending: dict, on_result: OnResult) -> None:
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: pending[f][0]):
                _, spec = pending.pop(future)
                on_result(spec, future.result())


def _ray_trial(
    command: list[str] | None, payload: dict[str, Any], timeout_s: float
) -> dict[str, Any]:
    """The Ray task: one trial subprocess on whichever node runs it."""
    outcome = run_worker_with_retry(command or default_worker_command(), payload, timeout_s)
    return outcome._asdict()


def import_ray() -> Any:
    """The ``ray`` module, or a one-line error saying how to install it."""
    try:
        # By name: Ray is an optional extra, so a type checker may not find it.
        ray = importlib.import_module("ray")
    except ImportError as error:
        raise BackendUnavailable(
            "--backend ray needs Ray, an optional extra: pip install 'bearchair[trials]'"
        ) from error
    return ray


class RayBackend:
    """Runs each trial subprocess as a Ray task, at most ``workers`` at once.

    The worker command is resolved on the node that runs it (its own Python), so the
    project must be installed there; run directories are written on that node.

    Args:
        workers: tasks in flight at once.
        timeout_s: per-trial wall time before the worker is killed (inside the task).
        address: an existing cluster (``ray://host:10001`` or ``host:6379``); None starts
            a local Ray.
        cpus_per_trial: CPUs Ray reserves per task (the imagination uses 2 processes).
        command: the worker command; None for the real worker on the remote node.
    """

    def __init__(
        self,
        workers: int,
        timeout_s: float,
        address: str | None = None,
        cpus_per_trial: float = 1.0,
        command: list[str] | None = None,
    ) -> None:
        self.ray = import_ray()
        self.workers = max(1, workers)
        self.timeout_s = timeout_s
        self.address = address
        self.cpus_per_trial = cpus_per_trial
        self.command = command

    def run(self, jobs: Sequence[Job], on_result: OnResult) -> None:
        ray = self.ray
        try:
            ray.init(address=self.address or None, ignore_reinit_error=True)
        except Exception as error:
            raise BackendUnavailable(
                f"could not start or reach Ray{f' at {self.address}' if self.address else ''}: "
                f"{str(error).splitlines()[0] if str(error) else type(error).__name__}"
            ) from error
        task = ray.remote(num_cpus=self.cpus_per_trial, max_retries=0)(_ray_trial)
        queue = list(jobs)
        in_flight: dict[Any, TrialSpec] = {}
        try:
            while queue or in_flight:
                while queue and len(in_flight) < self.workers:
                    spec, payload = queue.pop(0)
                    in_flight[task.remote(self.command, payload, self.timeout_s)] = spec
                ready, _ = ray.wait(list(in_flight), num_returns=1)
                for ref in ready:
                    spec = in_flight.pop(ref)
                    try:
                        outcome = WorkerOutcome(**ray.get(ref))
                    except Exception as error:  # the task's worker died, the node left, ...
                        first_line = str(error).strip().splitlines()[0] if str(error) else ""
                        outcome = WorkerOutcome(
                            None, f"ray task failed: {type(error).__name__}: {first_line}", 0.0
                        )
                    on_result(spec, outcome)
        except BaseException:
            for ref in in_flight:
                # Not force=True: the task gets a KeyboardInterrupt and kills its trial
                # subprocess, which a killed Ray worker would leave running.
                with contextlib.suppress(Exception):  # already finished or gone
                    ray.cancel(ref)
            raise
