"""``dic track --scheduler`` on a real dask cluster: a ``dask scheduler`` and a ``dask worker``
process on 127.0.0.1 (torn down at the end). The worker is a daemonic process, where
``workers > 1`` used to crash ("daemonic processes are not allowed to have children")."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from jointwear import io
from jointwear.datasets.rig import RigConfig, VirtualRig, generate_rig

pytest.importorskip("distributed")


def _start(args, log):
    return subprocess.Popen(
        [sys.executable, "-m", *args], stdout=log, stderr=subprocess.STDOUT, env=os.environ.copy()
    )


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    d = tmp_path_factory.mktemp("dask")
    sched_file = d / "scheduler.json"
    log = open(d / "log.txt", "w")  # noqa: SIM115 - closed at teardown
    procs = [
        _start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                "--dashboard-address", ":0", "--scheduler-file", str(sched_file)], log)
    ]  # fmt: skip
    try:
        for _ in range(600):
            if sched_file.exists() and sched_file.stat().st_size > 0:
                break
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(
            _start(["distributed.cli.dask_worker", address, "--nthreads", "1", "--nworkers", "1",
                    "--dashboard-address", ":0", "--host", "127.0.0.1"], log)
        )  # fmt: skip
        from distributed import Client

        with Client(address, timeout="60s") as client:
            client.wait_for_workers(1, timeout=120)
        yield address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
        log.close()


@pytest.fixture(scope="module")
def footage(tmp_path_factory):
    out = tmp_path_factory.mktemp("dask_rig")
    cfg = RigConfig(width=640, height=512, duration=0.1)
    written = generate_rig(out, cfg, video=False, images=True, calibration_images=False)
    return cfg, written


def test_track_on_a_real_cluster_and_inside_a_worker(cluster, footage, tmp_path):
    import dataclasses

    from distributed import Client

    from jointwear.cli import main
    from jointwear.dic.footage._track import read_bodies, track_footage

    cfg, written = footage
    cal = tmp_path / "cal.nc"
    VirtualRig(cfg).calibration.save(cal)
    base = ["dic", "track", "--left", str(written["left_images"]), "--right",
            str(written["right_images"]), "--fps", "50", "--bodies", str(written["bodies"]),
            "-c", str(cal), "--chunk-size", "2", "--max-frames", "4"]  # fmt: skip
    # chunks in two local processes, and as tasks on the cluster: the same poses
    assert main([*base, "--out", str(tmp_path / "local.nc"), "--workers", "2"]) == 0
    assert main([*base, "--out", str(tmp_path / "dask.nc"), "--scheduler", cluster]) == 0
    a = io.load(tmp_path / "local.nc")["follower_position"].values
    b = io.load(tmp_path / "dask.nc")["follower_position"].values
    assert a.shape == (4, 3)
    np.testing.assert_allclose(a, b, atol=1e-9)
    # the issue: `dic track --workers 2` inside a dask worker crashed with "daemonic processes
    # are not allowed to have children"; its chunks now run in threads there
    tc, bodies = read_bodies(written["bodies"])
    tc = dataclasses.replace(tc, workers=2, chunk_size=2)
    kw = dict(bodies=bodies, calibration=VirtualRig(cfg).calibration, config=tc, fps=50,
              max_frames=4)  # fmt: skip
    with Client(cluster, timeout="60s") as client:
        probe = "__import__('multiprocessing').current_process().daemon"
        assert client.submit(eval, probe, pure=False).result()  # a daemonic worker process
        remote = client.submit(
            track_footage, written["left_images"], written["right_images"], **kw, pure=False
        ).result(timeout=600)
    assert remote.attrs["workers"] == 2
    np.testing.assert_allclose(remote["follower_position"].values, a, atol=1e-9)
