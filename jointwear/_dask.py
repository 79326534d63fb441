"""Connecting to the dask.distributed scheduler a user names with ``--scheduler`` (shared by
``dic track`` and ``sim sweep``)."""

from __future__ import annotations

from typing import Any

from jointwear.errors import BadInputError


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
