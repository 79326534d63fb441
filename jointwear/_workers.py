"""Where the parallel runs execute: local worker processes with one thread each, or the
dask.distributed scheduler a user names with ``--scheduler`` (``dic track``, ``sim sweep``).

A worker process runs one thread for numba and BLAS (one run per core). numba reads
``NUMBA_NUM_THREADS`` when it is imported and again before every compilation
(``numba.core.config.reload_config``); once its thread pool is running, a changed value is an
error ("Cannot set NUMBA_NUM_THREADS to a different value once the threads have been
launched"). So the variable is set only in a process that has not imported numba (a fresh
worker, before its first import); a process that has (a forked worker inherits its parent's
numba) is limited through numba's own API, :func:`numba.set_num_threads`, and its environment
keeps the value numba read. This module imports nothing heavy: a spawned worker calls
:func:`limit_worker_threads` before anything imports numba.
"""

from __future__ import annotations

import os
import sys
from typing import Any

from jointwear.errors import BadInputError

__all__ = ["WORKER_ENV", "connect_scheduler", "limit_worker_threads", "numba_threads_launched"]

#: Environment of local workers: one thread each for numba and BLAS (one run per core).
WORKER_ENV = {
    "NUMBA_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
}


def numba_threads_launched() -> bool:
    """Whether this process has started numba's thread pool (a fork of it would not be safe
    for numba's parallel kernels, and its ``NUMBA_NUM_THREADS`` is fixed)."""
    parallel = sys.modules.get("numba.np.ufunc.parallel")
    return bool(getattr(parallel, "_is_initialized", False))


def limit_worker_threads() -> None:
    """One thread for numba and BLAS in this (worker) process.

    Before numba is imported: through the environment (:data:`WORKER_ENV`). After: through
    :func:`numba.set_num_threads` (this thread's count, the one a worker's tasks run in), never
    by changing ``NUMBA_NUM_THREADS`` under a running numba.
    """
    env = dict(WORKER_ENV)
    numba = sys.modules.get("numba")
    if numba is not None:
        del env["NUMBA_NUM_THREADS"]
        numba.set_num_threads(1)
    os.environ.update(env)


def connect_scheduler(address: str, *, timeout: str = "20s") -> Any:
    """A ``distributed.Client`` on the scheduler at ``address`` (not made the default client).

    Raises
    ------
    BadInputError
        Nothing answers at ``address`` within ``timeout`` (or ``distributed`` is missing): the
        message names ``--scheduler`` and how to fix it.
    """
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise BadInputError(
            "--scheduler needs the 'distributed' package (pip install distributed)"
        ) from None
    try:
        return Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise BadInputError(
            f"--scheduler {address}: cannot reach a dask scheduler there ({exc}); check the "
            "address (tcp://host:port) and that the scheduler is running (start one with "
            "`dask scheduler` and workers with `dask worker ADDRESS`), or drop --scheduler"
        ) from None
