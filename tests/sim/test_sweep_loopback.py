"""A local sweep cluster listens on the loopback interface only (scheduler, workers, dashboard).

While the sweep runs (from its progress callback) the listening TCP sockets of this process
and of all its children (the nannies and worker processes) are listed with psutil, a
dependency of dask's distributed.
"""

from __future__ import annotations

import ipaddress

import psutil
import pytest

from jointwear.sim import run_sweep

pytestmark = pytest.mark.slow


def listening_addresses(pid: int) -> list[tuple[int, str, int]]:
    """(pid, ip, port) of every listening inet socket of the process ``pid`` and its children."""
    root = psutil.Process(pid)
    found = []
    for proc in [root, *root.children(recursive=True)]:
        try:
            conns = proc.net_connections(kind="inet")
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            continue
        for c in conns:
            if c.status == psutil.CONN_LISTEN:
                found.append((proc.pid, c.laddr.ip, c.laddr.port))
    return found


def test_no_socket_of_a_local_sweep_listens_beyond_loopback():
    import os

    spec = {
        "sweep": {
            "run": "function",
            "function": "linear",
            "method": "lhs",
            "samples": 4,
            "seed": 3,
            "function_args": {"delay": 0.2},
        },
        "parameters": {"x1": {"distribution": "uniform", "bounds": [0.0, 1.0]}},
    }
    seen: list[list[tuple[int, str, int]]] = []

    def look(state):
        if state["computed"] >= 1:
            seen.append(listening_addresses(os.getpid()))

    ds = run_sweep(spec, workers=2, on_progress=look)
    assert int(ds.attrs["n_ok"]) == 4
    assert seen, "the progress callback never ran while the cluster was up"
    sockets = {s for snapshot in seen for s in snapshot}
    pids = {pid for pid, _, _ in sockets}
    # the scheduler (this process) and both workers listen: the check is not vacuous
    assert len(pids) >= 3, sockets
    exposed = [s for s in sockets if not ipaddress.ip_address(s[1]).is_loopback]
    assert not exposed, f"listening beyond loopback: {exposed}"
