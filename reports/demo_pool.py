"""The demo's worker processes: its independent parts run side by side, one per core.

``jointwear demo`` (full size) runs the compared wear run with the virtual roundness scans, the
motion's tolerance study with the stereo footage, the input-uncertainty ensemble and every run
of the verification study as tasks of one pool of worker processes. The pool is forked before
the demo opens any file (the workers inherit the imported modules and the numba kernels already
loaded, instead of importing and loading them again), and each part's messages are captured in
its worker and printed by the demo when the part is done. ``--quick`` (and a one-core machine)
runs the same parts one after the other in the demo's own process (:class:`InlineExecutor`).
"""

from __future__ import annotations

import contextlib
import io
import multiprocessing
import os
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Any

from jointwear._workers import limit_worker_threads, numba_threads_launched

__all__ = [
    "InlineExecutor",
    "MAX_WORKERS",
    "available_cores",
    "quiet_wear_log",
    "run_part",
    "worker_pool",
]

#: At most this many worker processes (each holds a simulation's memory, a few hundred MB).
MAX_WORKERS = 4


class InlineExecutor(Executor):
    """An executor that runs each task at once, in this process (``--quick``, one core)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        fut: Future = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except Exception as exc:  # handed on by fut.result(), as a process pool would
            fut.set_exception(exc)
        return fut


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _init_worker() -> None:
    """One thread per worker process for numba and BLAS (one part or run per core); Ctrl-C is the demo
    process's to handle (it stops the workers), and SIGTERM ends a worker at once (the
    command line's handler, inherited by a fork, would turn it into an exception)."""
    import signal

    limit_worker_threads()  # numba's API where numba is imported (a fork), else the environment
    quiet_wear_log()  # a spawned worker: as the demo's own process
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def quiet_wear_log() -> None:
    """The wear runs' accuracy warnings are not printed by the demo (nothing in it can be
    changed; its wear line states the accuracy, noise included, and the files keep the
    warning in ``accuracy_warning``)."""
    import logging

    log = logging.getLogger("jointwear.sim.wear")
    if not any(isinstance(h, logging.NullHandler) for h in log.handlers):
        log.addHandler(logging.NullHandler())


def process_cpu(pid: int) -> float | None:
    """CPU seconds (user + system) of a running process (from Linux's /proc), else None."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError, AttributeError):
        return None


@contextlib.contextmanager
def worker_pool(workers: int, cpu: list[float] | None = None) -> Iterator[Executor]:
    """A pool of ``workers`` forked processes (spawned where fork does not exist or this process
    runs other threads; an :class:`InlineExecutor` for ``workers <= 1``); shut down on
    leaving, queued tasks cancelled; on an exception (Ctrl-C, a failed part) the workers are
    terminated at once. ``cpu`` receives each worker's CPU seconds when the pool
    is left (where the system says them)."""
    if workers <= 1:
        yield InlineExecutor()
        return
    # fork only a process with one thread (a fork copies no other thread, whatever lock it
    # held); otherwise the workers start afresh and import what they need
    # (numba's thread pool is a thread too: a process that started it is not forked)
    fork = (
        "fork" in multiprocessing.get_all_start_methods()
        and threading.active_count() == 1
        and not numba_threads_launched()
    )
    context = multiprocessing.get_context("fork" if fork else "spawn")
    pool = ProcessPoolExecutor(workers, mp_context=context, initializer=_init_worker)
    try:
        pool.submit(os.getpid).result()  # fork now, before this process opens any file
        yield pool
    except BaseException:  # Ctrl-C or a failed part: stop the workers, do not wait for them
        processes = list(_processes(pool).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in processes:
            proc.terminate()
        for proc in processes:
            proc.join(timeout=10)
        raise
    if cpu is not None:
        cpu.extend(t for t in map(process_cpu, _processes(pool)) if t is not None)
    pool.shutdown(wait=True, cancel_futures=True)


def _processes(pool: ProcessPoolExecutor) -> dict[int, Any]:
    """The pool's worker processes by pid (the executor does not publish them)."""
    return dict(getattr(pool, "_processes", None) or {})


def run_part(fn: Callable[..., Any], *args: Any) -> tuple[Any, str]:
    """``fn(*args)`` with what it prints on stderr captured: ``(result, text)``."""
    import sys

    buf = io.StringIO()
    try:
        with contextlib.redirect_stderr(buf):
            result = fn(*args)
    except BaseException:  # what the part said before it failed is not lost
        sys.stderr.write(buf.getvalue())
        raise
    return result, buf.getvalue()
