"""Sweeps on real dask clusters: a scheduler and workers as subprocesses on 127.0.0.1.

The module starts one ``dask scheduler`` and one ``dask worker`` process (torn down at the end);
tests that kill a worker start their own extra one. Runs are analytic functions with a short
sleep (or a fraction of a crank cycle), so the module takes well under a minute on 2 cores.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from jointwear import io
from jointwear.sim import run_sweep
from jointwear.sim.sweep._store import parts_dir

pytestmark = pytest.mark.slow

ENV = {**os.environ, "NUMBA_NUM_THREADS": "1", "PYTHONWARNINGS": "ignore"}


def _wait(cond, timeout, what):
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            raise TimeoutError(f"timed out waiting for {what}")
        time.sleep(0.1)


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


def _start_worker(address: str, tmp: Path, name: str) -> subprocess.Popen:
    with open(tmp / f"{name}.log", "w") as log:  # the child keeps its own copy
        return _popen(
            [
                sys.executable,
                "-m",
                "distributed.cli.dask_worker",
                address,
                "--nthreads",
                "1",
                "--no-nanny",
                "--no-dashboard",
                "--host",
                "127.0.0.1",
                "--name",
                name,
            ],
            log,
        )


def _popen(cmd: list[str], log) -> subprocess.Popen:
    return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=ENV)


def _n_workers(address: str) -> int:
    from distributed import Client

    with Client(address, timeout="20s", set_as_default=False) as c:
        return len(c.scheduler_info()["workers"])


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """(address, tmp folder) of a scheduler with one worker, both subprocesses."""
    tmp = tmp_path_factory.mktemp("dask")
    sched_file = tmp / "scheduler.json"
    with open(tmp / "scheduler.log", "w") as log:
        sched = _popen(
            [
                sys.executable,
                "-m",
                "distributed.cli.dask_scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(sched_file),
            ],
            log,
        )
    procs = [sched]
    try:
        _wait(lambda: sched_file.exists() and sched_file.stat().st_size > 0, 120, "the scheduler")
        address = json.loads(sched_file.read_text())["address"]
        procs.append(_start_worker(address, tmp, "w0"))
        _wait(lambda: _n_workers(address) >= 1, 120, "the worker")
        yield address, tmp
    finally:
        for p in reversed(procs):
            _stop(p)


def linear_spec(samples, **args):
    return {
        "sweep": {
            "run": "function",
            "function": "linear",
            "method": "lhs",
            "samples": samples,
            "seed": 7,
            "function_args": args,
        },
        "parameters": {
            "x1": {"distribution": "uniform", "bounds": [0.0, 1.0]},
            "x2": {"distribution": "normal", "mean": 1.0, "std": 0.2},
        },
    }


def test_sweep_by_address_equals_the_in_process_run(cluster, tmp_path):
    address, _ = cluster
    spec = linear_spec(10, noise=0.3, fail_above={"x1": 0.85})
    here = run_sweep(spec, workers=0)
    there = run_sweep(spec, scheduler=address, out=tmp_path / "s.nc")
    for name in ("y", "y2", "status", "x1", "x2", "run_seed"):
        assert np.array_equal(here[name].values, there[name].values, equal_nan=True), name
    assert (there["status"].values == 1).any()  # the failures travel back too
    assert all(w != here["worker"].values[0] for w in there["worker"].values)
    assert "dask scheduler" in there.attrs["executor"]


def test_simulator_runs_on_a_remote_worker_give_identical_numbers(cluster):
    address, _ = cluster
    spec = {
        "sweep": {
            "run": "cycle",
            "method": "grid",
            "cycles": 0.05,
            "settle_cycles": 0.0,
            "outputs": ["mean_contact_force", "peak_contact_force", "follower_velocity_rms"],
        },
        "parameters": {
            "mechanism.joint_offset": {"values": [0.0, 0.01]},
            "joint.n_layers": {"values": [4]},
            "joint.n_points": {"values": [24]},
        },
    }
    here = run_sweep(spec, workers=0)
    there = run_sweep(spec, scheduler=address)
    assert (there["status"].values == 0).all(), there["error"].values
    for name in spec["sweep"]["outputs"]:
        assert np.array_equal(here[name].values, there[name].values), name
    assert here["mean_contact_force"].values[0] != here["mean_contact_force"].values[1]


def victim_did_a_run(out: Path, pid: int) -> bool:
    for part in parts_dir(out).glob("run-*.npz"):
        try:
            with np.load(part) as z:
                if str(z["host"]).endswith(f":{pid}"):
                    return True
        except (OSError, ValueError, KeyError):
            pass
    return False


def _warm_up(address: str) -> None:
    """Import the sweep's modules on every worker (a cold worker under load could otherwise
    stay in its first import while the warm one finishes the whole sweep)."""
    from distributed import Client

    def imports() -> None:
        import jointwear.sim.sweep._models  # noqa: F401
        import jointwear.sim.sweep._run  # noqa: F401

    with Client(address, timeout="20s", set_as_default=False) as c:
        c.run(imports)


def test_a_worker_killed_mid_sweep_does_not_stop_it(cluster, tmp_path):
    address, tmp = cluster
    victim = _start_worker(address, tmp, "victim")
    try:
        _wait(lambda: _n_workers(address) >= 2, 120, "the second worker")
        _warm_up(address)
        spec = linear_spec(24, delay=0.4, noise=0.1)
        out = tmp_path / "s.nc"
        box = {}

        def run():
            box["ds"] = run_sweep(spec, scheduler=address, out=out)

        t = threading.Thread(target=run)
        t.start()
        _wait(
            lambda: victim_did_a_run(out, victim.pid) or not t.is_alive(),
            120,
            "a run on the second worker",
        )
        assert victim_did_a_run(out, victim.pid), "the second worker never got a run"
        victim.send_signal(signal.SIGKILL)
        victim.wait(10)
        n_at_kill = len(list(parts_dir(out).glob("run-*.npz")))
        t.join(180)
        assert not t.is_alive()
    finally:
        _stop(victim)
    assert n_at_kill < 24  # killed mid-sweep
    ds = box["ds"]
    assert ds.attrs["n_ok"] == 24 and ds.attrs["n_not_run"] == 0
    hosts = {str(w).rpartition(":")[2] for w in ds["worker"].values}
    assert str(victim.pid) in hosts and len(hosts) == 2
    # the same runs in this process, without the sleep (delay only waits: the same numbers)
    ref = run_sweep(linear_spec(24, delay=0.0, noise=0.1), workers=0)
    assert np.array_equal(ds["y"].values, ref["y"].values)


def test_client_killed_then_resume_computes_only_the_missing_runs(cluster, tmp_path):
    address, _ = cluster
    log = tmp_path / "evaluated.txt"
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(
        '[sweep]\nrun = "function"\nfunction = "linear"\nmethod = "lhs"\nsamples = 16\nseed = 3\n'
        f'[sweep.function_args]\ndelay = 0.5\nnoise = 0.2\nlog = "{log}"\n'
        '[parameters.x1]\ndistribution = "uniform"\nbounds = [0, 1]\n'
        '[parameters.x3]\ndistribution = "uniform"\nbounds = [0, 1]\n'
    )
    out = tmp_path / "s.nc"
    cmd = [sys.executable, "-m", "jointwear", "sim", "sweep", str(spec_file), "--out", str(out)]
    client = subprocess.Popen(
        [*cmd, "--scheduler", address],
        env=ENV,
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        _wait(lambda: len(list(parts_dir(out).glob("run-*.npz"))) >= 4, 180, "4 finished runs")
        os.killpg(client.pid, signal.SIGKILL)
        client.wait(10)
    finally:
        if client.poll() is None:
            os.killpg(client.pid, signal.SIGKILL)
            client.wait(10)
    assert not out.exists()
    assert len(list(parts_dir(out).glob("run-*.npz"))) < 16  # killed mid-sweep
    # the scheduler drops the dead client's tasks; a task already running finishes unseen
    time.sleep(2.0)
    kept = {p: p.stat().st_mtime_ns for p in parts_dir(out).glob("run-*.npz")}
    done_before = {int(p.stem.split("-")[1]) for p in kept}
    n_logged = len(log.read_text().split())
    r = subprocess.run(
        [*cmd, "--scheduler", address, "--resume"],
        env=ENV,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    evaluated_now = [int(v) for v in log.read_text().split()[n_logged:]]
    assert sorted(evaluated_now) == sorted(set(range(16)) - done_before)
    for p, mtime in kept.items():
        assert not p.exists() or p.stat().st_mtime_ns == mtime  # never rewritten
    ds = io.load(out)
    assert ds.attrs["runs_resumed"] == len(done_before)
    assert ds.attrs["runs_computed_now"] == 16 - len(done_before)
    # the same runs in this process, without the sleep and the log (the same numbers)
    fast = tmp_path / "fast.toml"
    fast.write_text(spec_file.read_text().replace("delay = 0.5", "delay = 0.0"))
    fast.write_text("\n".join(ln for ln in fast.read_text().splitlines() if "log = " not in ln))
    ref = run_sweep(fast, workers=0)
    assert np.array_equal(ds["y"].values, ref["y"].values)
    assert not parts_dir(out).exists()


def test_local_cluster_of_processes_gives_the_same_numbers(tmp_path, recwarn):
    import socket

    spec = linear_spec(6, noise=0.3)
    with socket.socket() as s:  # hold the default dashboard port, as another cluster would
        try:
            s.bind(("127.0.0.1", 8787))
            s.listen()
        except OSError:
            pass  # already held by someone else: the same situation
        ds = run_sweep(spec, workers=2)
    ref = run_sweep(spec, workers=0)
    assert np.array_equal(ds["y"].values, ref["y"].values)
    assert "local dask cluster (2 worker" in ds.attrs["executor"]
    clash = [str(w.message) for w in recwarn if "8787" in str(w.message)]
    assert not clash  # no dashboard port clash
