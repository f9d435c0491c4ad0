"""Where trial subprocesses run: here (a few at once) or as Ray tasks.

Both backends run the same trial worker (``bearchair.evaluation.worker_process``): here as
forks of a preloaded trial server (``bearchair.evaluation.forked_workers``), on Ray as a
command on the node that runs the task, in a temporary folder whose run record the task
sends back (``bearchair.evaluation.shipping``). They hand each :class:`WorkerOutcome` back to
the caller in the caller's thread, as soon as it is ready, so the harness alone writes
the records. On Ctrl-C (KeyboardInterrupt in
the caller's thread), a backend stops every running trial and re-raises; what was
stopped is never handed back.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import logging
import os
import tarfile
import tempfile
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path
from typing import Any, Protocol

from bearchair.core.errors import BackendUnavailable
from bearchair.evaluation.forked_workers import PreloadedLauncher
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.shipping import (
    TrialScratch,
    chair_files,
    pack_folder,
    package_dir,
    stage_package,
    tree_file,
    unpack_folder,
)
from bearchair.evaluation.worker_process import (
    CommandLauncher,
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


RAY_LOG_LEVEL = logging.WARNING
"""Ray's own log lines on the head: warnings only, so its INFO lines do not tear the
progress bar (the trials' output goes to each run folder's ``worker.log``)."""
NODE_FILE = "ray_node.json"
"""In each run folder a Ray trial sends back: the node that ran it and the package it ran."""


def _ray_trial(
    command: list[str] | None,
    payload: dict[str, Any],
    timeout_s: float,
    chair: dict[str, bytes],
    tree: dict[str, bytes] | None = None,
) -> dict[str, Any]:
    """The Ray task: one trial subprocess on whichever node runs it, its run folder sent back.

    The node shares no folder with the head: the trial runs on the shipped chair in a
    temporary folder, whose run record returns as a gzipped tar (``record``).
    """
    with TrialScratch() as scratch:
        here = scratch.payload_here(payload, chair, tree)
        launcher = CommandLauncher(command or default_worker_command(), env=_worker_env())
        outcome = run_worker_with_retry(launcher, here, timeout_s)
        scratch.run_dir.mkdir(parents=True, exist_ok=True)
        (scratch.run_dir / NODE_FILE).write_text(json.dumps(_node_description()))
        return {"outcome": outcome._asdict(), "record": pack_folder(scratch.run_dir)}


def _worker_env() -> dict[str, str]:
    """This process's environment, the package it imported first on the trial's path: on
    a Ray node the copy the head shipped (``runtime_env``), not whatever is installed."""
    env = dict(os.environ)
    root = str(package_dir().parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH", "")) if p)
    return env


def _node_description() -> dict[str, Any]:
    """Where this Ray task runs: the node's id and address, the package's folder."""
    description: dict[str, Any] = {"package_dir": str(package_dir()), "cwd": os.getcwd()}
    with contextlib.suppress(Exception):  # outside a Ray worker (tests): no node to name
        context = import_ray().get_runtime_context()
        description["node_id"] = context.get_node_id()
    with contextlib.suppress(Exception):
        description["node_ip"] = import_ray().util.get_node_ip_address()
    return description


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

    Nothing is assumed installed or shared but Ray and the dependencies: the head ships
    this ``bearchair`` package to every node (``runtime_env`` ``py_modules``) and each
    trial's chair with its task; each task sends its run folder back and the head writes
    it where the campaign keeps it (``docs/ray.md``).

    Args:
        workers: tasks in flight at once; None: the cluster's CPUs over ``cpus_per_trial``.
        timeout_s: per-trial wall time before the worker is killed (inside the task).
        address: an existing cluster (``ray://host:10001`` or ``host:6379``); None starts
            a local Ray (or joins ``RAY_ADDRESS``).
        cpus_per_trial: CPUs Ray reserves per task.
        command: the worker command; None for the real worker on the remote node.
        ship_package: send this package to the nodes (False: use the nodes' own install).
    """

    def __init__(
        self,
        workers: int | None,
        timeout_s: float,
        address: str | None = None,
        cpus_per_trial: float = 1.0,
        command: list[str] | None = None,
        ship_package: bool = True,
    ) -> None:
        self.ray = import_ray()
        self.workers = None if workers is None else max(1, workers)
        self.timeout_s = timeout_s
        self.address = address
        self.cpus_per_trial = cpus_per_trial
        self.command = command
        self.ship_package = ship_package
        self.description = ""

    def connect(self) -> str:
        """Starts or joins Ray (once), shipping the package; returns a line on the cluster.

        Raises:
            BackendUnavailable: Ray could not start, or the cluster could not be reached
                (a cluster that wants a token and got none says so).
        """
        if self.description:
            return self.description
        ray = self.ray
        where = f" at {self.address}" if self.address else ""
        with tempfile.TemporaryDirectory(prefix="bearchair-ray-") as staging:
            runtime_env = (
                {"py_modules": [str(stage_package(Path(staging)))]} if self.ship_package else None
            )
            explicit_token_mode_for_a_local_ray(self.address)
            try:
                ray.init(
                    address=self.address or None,
                    ignore_reinit_error=True,
                    runtime_env=runtime_env,
                    log_to_driver=False,
                    logging_level=RAY_LOG_LEVEL,
                )
            except Exception as error:
                raise BackendUnavailable(
                    f"could not start or reach Ray{where}: {_why(error)}"
                ) from error
        cpus = float(ray.cluster_resources().get("CPU", 0.0))
        if self.workers is None:
            self.workers = max(1, int(cpus // self.cpus_per_trial))
        nodes = sum(1 for node in ray.nodes() if node.get("Alive", True))
        self.description = (
            f"Ray{where or ' (local)'}: {nodes} node(s), {cpus:g} CPU(s); "
            f"{self.workers} trial(s) at once"
        )
        return self.description

    def run(self, jobs: Sequence[Job], on_result: OnResult) -> None:
        self.connect()
        ray = self.ray
        workers = self.workers or 1
        task = ray.remote(num_cpus=self.cpus_per_trial, max_retries=0)(_ray_trial)
        queue = list(jobs)
        in_flight: dict[Any, Job] = {}
        try:
            while queue or in_flight:
                while queue and len(in_flight) < workers:
                    spec, payload = queue.pop(0)
                    chair = chair_files(payload.get("chair_path"))
                    tree = tree_file(payload.get("tree"))
                    ref = task.remote(self.command, payload, self.timeout_s, chair, tree)
                    in_flight[ref] = (spec, payload)
                ready, _ = ray.wait(list(in_flight), num_returns=1)
                for ref in ready:
                    spec, payload = in_flight.pop(ref)
                    on_result(spec, self._outcome(ref, Path(payload["out_dir"])))
        except BaseException:
            for ref in in_flight:
                # Not force=True: the task gets a KeyboardInterrupt and kills its trial
                # subprocess, which a killed Ray worker would leave running.
                with contextlib.suppress(Exception):  # already finished or gone
                    ray.cancel(ref)
            raise
        finally:
            self.close()

    def close(self) -> None:
        """Leaves the cluster (a local Ray started here stops); :meth:`connect` rejoins."""
        if self.description:
            self.description = ""
            with contextlib.suppress(Exception):  # already gone
                self.ray.shutdown()

    def _outcome(self, ref: Any, run_dir: Path) -> WorkerOutcome:
        """The task's outcome, its run folder written into ``run_dir`` here."""
        try:
            result = self.ray.get(ref)
        except Exception as error:  # the task's worker died, the node left, ...
            return WorkerOutcome(
                None, f"ray task failed: {type(error).__name__}: {_why(error)}", 0.0
            )
        outcome = WorkerOutcome(**result["outcome"])
        try:
            unpack_folder(result["record"], run_dir)
        except (OSError, tarfile.TarError) as error:
            return outcome._replace(
                summary=None, error=f"the trial's run folder could not be written here: {error}"
            )
        return outcome


def explicit_token_mode_for_a_local_ray(address: str | None) -> None:
    """Makes Ray's default for a Ray started here explicit, which silences its warning.

    A new local Ray turns token authentication on (writing ``~/.ray/auth_token`` if
    missing) and warns that it did unless ``RAY_AUTH_MODE`` says so. Joining a cluster
    (``address``, or ``RAY_ADDRESS``) changes nothing: the user's ``RAY_AUTH_MODE`` and
    token decide (``docs/ray.md``).
    """
    if address is None and not os.environ.get("RAY_ADDRESS"):
        os.environ.setdefault("RAY_AUTH_MODE", "token")


def _why(error: BaseException) -> str:
    """One line on why Ray failed; a cluster wanting a token says how to give one."""
    text = str(error).strip()
    first = text.splitlines()[0] if text else type(error).__name__
    # Ray's own reason (an invalid token) goes to its log lines, not into the exception.
    unsure = "failed to connect" in text.lower() and os.environ.get("RAY_AUTH_MODE") != "token"
    if unsure or "authentication" in text.lower() or "token" in text.lower():
        return (
            f"{first} (if the cluster uses token authentication: export RAY_AUTH_MODE=token and "
            "RAY_AUTH_TOKEN, or copy the head's ~/.ray/auth_token here; docs/ray.md)"
        )
    return first
