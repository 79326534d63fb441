"""``--scheduler ADDRESS`` where no dask scheduler answers: refused, naming the option and the fix
(the one connection helper ``dic track`` and ``sim sweep`` share)."""

from __future__ import annotations

import socket
import time

import pytest

from jointwear._workers import connect_scheduler
from jointwear.errors import BadInputError


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_no_scheduler_at_the_address_is_refused_with_the_fix():
    address = f"tcp://127.0.0.1:{_free_port()}"
    t0 = time.perf_counter()
    with pytest.raises(BadInputError) as info:
        connect_scheduler(address, timeout="1s")
    assert time.perf_counter() - t0 < 30
    msg = str(info.value)
    assert msg.startswith(f"--scheduler {address}: cannot reach a dask scheduler there")
    assert "tcp://host:port" in msg and "`dask scheduler`" in msg and "drop --scheduler" in msg
