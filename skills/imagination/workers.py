"""The imagination's worker processes: a persistent pool per worker count, started
once per process, stopped by the runtime (:mod:`bearchair.core.runtime`).

Each worker has its own pybullet DIRECT client; tasks are one rotation's drops
(:class:`bearchair.skills.imagination.simulation.TaskSpec`). Running the same tasks in
this process or in the pool gives the same drops.
"""

from __future__ import annotations

import multiprocessing
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from multiprocessing.process import BaseProcess

from bearchair.core.held_signals import holding_stop_signals
from bearchair.core.progress import report as report_progress
from bearchair.core.runtime import RUNTIME
from bearchair.skills.imagination import DEFAULT_WORKERS
from bearchair.skills.imagination.drop_records import RawDrop, TaskSpec
from bearchair.skills.imagination.simulation import ping, run_task, worker_initializer

Runner = Callable[[list[TaskSpec], threading.Event | None], tuple[list[list[RawDrop]], float, bool]]
"""Runs tasks until cancelled: (the drops per task run, physics seconds, cancelled)."""


_pools: dict[int, ProcessPoolExecutor] = {}
"""One pool per worker count asked for (in practice one: ``DEFAULT_WORKERS``)."""
_pools_lock = threading.Lock()


def runner(workers: int) -> Runner:
    """The same tasks, in this process or in a pool of worker processes."""
    if workers <= 1:
        return _run_here
    return lambda tasks, cancel: _run_in_pool(_pool(workers), tasks, cancel)


def _run_here(
    tasks: list[TaskSpec], cancel: threading.Event | None
) -> tuple[list[list[RawDrop]], float, bool]:
    outcomes, seconds = [], 0.0
    total = sum(len(task.drops) for task in tasks)
    for task in tasks:
        _report_drops(outcomes, total)
        if cancel is not None and cancel.is_set():
            return outcomes, seconds, True
        drops, task_seconds = run_task(task)
        outcomes.append(drops)
        seconds += task_seconds
    _report_drops(outcomes, total)
    return outcomes, seconds, False


def _report_drops(outcomes: list[list[RawDrop]], total: int) -> None:
    """The drops of this batch simulated so far, for a console's progress bar."""
    report_progress("imagination: drops", sum(len(drops) for drops in outcomes), total)


def _run_in_pool(
    pool: ProcessPoolExecutor, tasks: list[TaskSpec], cancel: threading.Event | None
) -> tuple[list[list[RawDrop]], float, bool]:
    with holding_stop_signals():  # a submit may start a worker (the pool's first tasks)
        futures: list[Future] = [pool.submit(run_task, task) for task in tasks]
    pending = set(futures)
    total = sum(len(task.drops) for task in tasks)
    while pending:
        _, pending = wait(pending, timeout=0.05, return_when=FIRST_COMPLETED)
        report_progress(
            "imagination: drops",
            sum(len(task.drops) for task, f in zip(tasks, futures, strict=True) if f.done()),
            total,
        )
        if cancel is not None and cancel.is_set():
            for future in pending:
                future.cancel()
            done = [f.result() for f in futures if f.done() and not f.cancelled()]
            return [d for d, _ in done], sum(s for _, s in done), True
    results = [future.result() for future in futures]
    return [drops for drops, _ in results], sum(seconds for _, seconds in results), False


_pings: dict[int, list[Future]] = {}
"""Each pool's start-up no-ops (one per worker), as many pools as ``_pools``."""


def _pool(workers: int) -> ProcessPoolExecutor:
    """A persistent pool per worker count: process start-up is paid once per process.

    A new pool is sent one no-op per worker, so every worker process starts at once
    (the pool starts one per task submitted) and the caller need not wait for them.
    A stop signal meanwhile is held until they have started: a half-started worker
    belongs to no pool (:mod:`bearchair.core.held_signals`)."""
    with _pools_lock, holding_stop_signals():
        pool = _pools.get(workers)
        if pool is None:
            pool = ProcessPoolExecutor(
                max_workers=workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=worker_initializer,
            )
            _pools[workers] = pool
            _pings[workers] = [pool.submit(ping) for _ in range(workers)]
        return pool


def warm_up(workers: int = DEFAULT_WORKERS, *, wait: bool = True) -> None:
    """Starts the worker processes now (they import pybullet and connect).

    Args:
        workers: the worker count a later ``imagine_sitting`` will use.
        wait: return only once every worker is up; else start them and return.
    """
    if workers > 1:
        _pool(workers)
        if wait:
            for future in _pings[workers]:
                future.result()


def shutdown_workers(timeout_s: float = 30.0) -> bool:
    """Stops the worker processes: each ends after its current task; those still running
    after ``timeout_s`` are killed. Returns True when none had to be killed.

    The executor's own manager thread sends each worker its sentinel and reaps it; this
    waits for that thread rather than joining the workers beside it (two threads reaping
    one child race: the loser sees it alive after it has gone). The thread is taken
    before ``shutdown``, which forgets it.

    The runtime's shutdown (``bearchair.core.runtime``) calls it, at the latest at exit."""
    with _pools_lock:
        pools = list(_pools.values())
        _pings.clear()
    managers = [getattr(pool, "_executor_manager_thread", None) for pool in pools]  # private
    workers = [process for pool in pools for process in _worker_processes(pool)]
    for pool in pools:
        pool.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + timeout_s
    for manager in managers:
        if manager is not None:
            manager.join(max(deadline - time.monotonic(), 0.0))
    stuck = any(manager is not None and manager.is_alive() for manager in managers)
    late = [process for process in workers if stuck and process.exitcode is None]
    for process in late:
        process.kill()
    for manager in managers:  # its join returns once the killed workers are reaped
        if manager is not None:
            manager.join(5.0)
    with _pools_lock:  # only now: a second stop signal meanwhile still finds them
        for workers_asked, pool in list(_pools.items()):
            if pool in pools:
                del _pools[workers_asked]
    return not late


def kill_workers() -> None:
    """SIGKILLs the worker processes now and reaps them (a second stop signal).

    Takes no lock: it runs in a signal handler, perhaps while this thread holds one."""
    pools = list(_pools.values())
    _pools.clear()  # broken now: the next imagination starts a new pool
    _pings.clear()
    workers = [process for pool in pools for process in _worker_processes(pool)]
    for process in workers:
        process.kill()
    for process in workers:
        process.join(2.0)


def _worker_processes(pool: ProcessPoolExecutor) -> list[BaseProcess]:
    """The pool's worker processes (the executor keeps them by pid, in a private field)."""
    return list((getattr(pool, "_processes", None) or {}).values())


RUNTIME.register("imagination pool", shutdown=shutdown_workers, kill=kill_workers)
