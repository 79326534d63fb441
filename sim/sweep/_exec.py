"""Executors of sweep runs: in-process, a local dask cluster, an existing one by address, or a
caller's :class:`concurrent.futures.Executor` (e.g. the demo's pool of forked processes).

Each run is one dask task (:func:`jointwear.sim.sweep._run.evaluate_run`); results are handed
to ``on_result`` in the order they finish, so the caller writes each at once. A run whose
worker died too often (dask's ``KilledWorker``) or that dask could not deliver is reported to
``on_lost`` and stays missing (a later ``--resume`` recomputes it).
"""

from __future__ import annotations

import logging
import os
import uuid
from collections.abc import Callable, Sequence
from concurrent import futures as cf
from typing import Any

from jointwear._workers import WORKER_ENV, connect_scheduler
from jointwear.sim.sweep._run import RunResult, RunTask, evaluate_run

__all__ = ["execute", "WORKER_ENV", "LOOPBACK"]

#: Address every socket of a local cluster listens on (no other machine can reach it).
LOOPBACK = "127.0.0.1"


def _serial(tasks: Sequence[RunTask], on_result: Callable[[RunResult], None]) -> str:
    for task in tasks:
        on_result(evaluate_run(task))
    return "in-process"


def _pool(
    tasks: Sequence[RunTask],
    pool: cf.Executor,
    on_result: Callable[[RunResult], None],
    on_lost: Callable[[int, str], None],
) -> None:
    """Runs on a caller's executor (which the caller shuts down), handed on as they finish."""
    index_of = {pool.submit(evaluate_run, t): t.index for t in tasks}
    try:
        for fut in cf.as_completed(index_of):
            try:
                res = fut.result()
            except Exception as exc:  # a worker process died (BrokenProcessPool), ...
                on_lost(index_of[fut], f"{type(exc).__name__}: {exc}")
            else:
                on_result(res)
    finally:  # interrupted: runs not yet started are not started
        for fut in index_of:
            fut.cancel()


def _client(workers: int | None, scheduler: str | None) -> tuple[Any, Any, str]:
    """(client, cluster or None, description)."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        client = connect_scheduler(scheduler, timeout="15s")
        n = len(client.scheduler_info().get("workers", {}))
        return client, None, f"dask scheduler {scheduler} ({n} worker(s) now)"
    n = workers if workers is not None else (os.cpu_count() or 1)
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        # everything on the loopback interface: scheduler, workers and nannies (host), and the
        # scheduler's HTTP endpoints (health, metrics), which take a free port instead of 8787
        # (another cluster on the machine may hold it); no dashboard
        host=LOOPBACK,
        dashboard_address=f"{LOOPBACK}:0",
        scheduler_kwargs={"dashboard": False},
        env=dict(WORKER_ENV),
        silence_logs=logging.ERROR,
    )
    client = Client(cluster, set_as_default=False)
    return client, cluster, f"local dask cluster ({n} worker process(es), 1 thread each)"


def execute(
    tasks: Sequence[RunTask],
    *,
    workers: int | None,
    scheduler: str | cf.Executor | None,
    on_result: Callable[[RunResult], None],
    on_lost: Callable[[int, str], None],
    on_start: Callable[[str], None] | None = None,
) -> None:
    """Run ``tasks``; call ``on_result`` for each finished run as it comes.

    Parameters
    ----------
    tasks : sequence of RunTask
    workers : int or None
        0: in this process, no dask; N: a local cluster of N worker processes (default: one per
        core). Ignored with ``scheduler``.
    scheduler : str, Executor or None
        Address of a running dask scheduler (``tcp://host:8786``), or an executor of the
        caller's (``submit``; each run one task, results in the order they finish).
    on_result, on_lost : callable
        Called with each :class:`RunResult`, or with ``(index, reason)`` for a run dask lost.
    on_start : callable, optional
        Called with a description of the executor once it is up.
    """
    if not tasks:
        return
    if isinstance(scheduler, cf.Executor):
        if on_start:
            on_start(f"the caller's {type(scheduler).__name__}")
        _pool(tasks, scheduler, on_result, on_lost)
        return
    if scheduler is None and workers == 0:
        if on_start:
            on_start("in-process (no dask)")
        _serial(tasks, on_result)
        return
    from distributed import as_completed

    client, cluster, what = _client(workers, scheduler)
    try:
        if on_start:
            on_start(what)
        token = uuid.uuid4().hex[:8]
        keys = [f"jointwear-sweep-run-{t.index}-{token}" for t in tasks]
        futures = client.map(evaluate_run, tasks, key=keys, pure=False)
        index_of = {f.key: t.index for f, t in zip(futures, tasks, strict=True)}
        for fut in as_completed(futures, loop=client.loop):
            try:
                res = fut.result()
            except Exception as exc:  # KilledWorker, CancelledError, communication failures
                on_lost(index_of[fut.key], f"{type(exc).__name__}: {exc}")
            else:
                on_result(res)
            fut.release()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
