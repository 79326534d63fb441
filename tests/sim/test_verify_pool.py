"""Sweep and study runs on a caller's ``concurrent.futures`` executor (the demo's worker pool)."""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Executor, Future, ProcessPoolExecutor

import numpy as np
import pytest

from jointwear.sim import run_sweep
from jointwear.sim.sweep import _models

SWEEP = {"run": "function", "function": "linear", "method": "grid"}
GRID = {"x1": {"values": [0.0, 1.0, 2.0]}, "x2": {"values": [0.0, 0.5]}}

fork_only = pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="needs fork"
)


@fork_only
def test_a_process_pool_gives_the_numbers_of_the_serial_run():
    serial = run_sweep({"sweep": SWEEP, "parameters": GRID}, workers=0)
    ctx = multiprocessing.get_context("fork")
    with ProcessPoolExecutor(2, mp_context=ctx) as pool:
        pooled = run_sweep({"sweep": SWEEP, "parameters": GRID}, scheduler=pool)
        pids = set(pool.submit(os.getpid).result() for _ in range(4))
    # y = x1 + 2 x2 at every grid point, in the same order, none missing
    x1, x2 = serial["x1"].values, serial["x2"].values
    np.testing.assert_array_equal(serial["y"].values, x1 + 2 * x2)
    np.testing.assert_array_equal(pooled["y"].values, serial["y"].values)
    assert (pooled["status"].values == serial["status"].values).all()
    assert "ProcessPoolExecutor" in pooled.attrs["executor"] and os.getpid() not in pids


def _dies(x, **_):
    if x["x1"] == 1.0:
        os._exit(3)  # the worker process is killed mid-run
    return {"y": x["x1"], "y2": 0.0}


@fork_only
def test_a_run_whose_worker_dies_is_not_run_never_a_number(monkeypatch):
    model = _models.MODELS["linear"]
    monkeypatch.setitem(
        _models.MODELS,
        "linear",
        type(model)(model.name, model.inputs, model.outputs, _dies, model.defaults),
    )
    ctx = multiprocessing.get_context("fork")
    with ProcessPoolExecutor(1, mp_context=ctx) as pool:
        ds = run_sweep({"sweep": SWEEP, "parameters": {"x1": GRID["x1"]}}, scheduler=pool)
    meaning = dict(
        zip(
            ds["status"].attrs["flag_values"],
            ds["status"].attrs["flag_meanings"].split(),
            strict=True,
        )
    )
    lost = ds["x1"].values == 1.0
    assert meaning[int(ds["status"].values[lost][0])] == "not_run"
    assert np.isnan(ds["y"].values[lost]).all()
    assert "BrokenProcessPool" in str(ds["error"].values[lost][0])
    assert ds["y"].values[ds["x1"].values == 0.0] == 0.0  # the run before it is kept


class _Refusing(Executor):
    """Runs nothing: every future fails as a lost worker's would."""

    def submit(self, fn, /, *args, **kwargs):
        fut = Future()
        fut.set_exception(RuntimeError("worker lost"))
        return fut


def test_every_lost_run_is_reported_lost():
    ds = run_sweep({"sweep": SWEEP, "parameters": GRID}, scheduler=_Refusing())
    assert set(ds["status"].values.tolist()) == {2}  # flag_meanings: ok failed not_run
    assert np.isnan(ds["y"].values).all()
