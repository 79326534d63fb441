"""The demo's worker pool: its compared wear run is the study's run 0, simulated once."""

from __future__ import annotations

import dataclasses
import os
import threading
from concurrent.futures import Future

import numpy as np
import pytest

from jointwear import io
from jointwear._compile_notice import NOTICE
from jointwear.reports import demo
from jointwear.reports.demo_pool import InlineExecutor, process_cpu, run_part, worker_pool
from jointwear.reports.demo_studies import demo_study, main_wear_settings

#: A study small enough for a test: 1600 cycles, ΔN = 100 ... 800, a 4 x 24 bearing grid.
TINY = dataclasses.replace(
    demo.FULL, cycles=1600.0, snapshots=(1600.0,), n_layers=4, n_points=24, rig_size=None
)


def _run0():
    from jointwear.sim.sweep._driver import _base
    from jointwear.sim.sweep._verify import _WearKind, study_tasks

    params = demo._params(TINY)
    sim, wear, _, _ = _base(_WearKind, params, None)
    _, _, tasks = study_tasks(demo_study(TINY), sim, dataclasses.replace(wear, scheme="fixed"))
    return params, next(t for t in tasks if t.index == 0)


def test_the_compared_wear_file_is_the_study_run_and_the_serial_run(tmp_path, capsys):
    from jointwear.sim import simulate_wear

    params, task = _run0()
    result, (path, metrology, early) = demo._compared_study_run(task, tmp_path, TINY, params, False)
    said = capsys.readouterr().err  # a study run states no accuracy of its own: the study's
    assert "u_num: the study" in said and "nan" not in said
    saved = io.load(path)
    assert result.status == "ok" and metrology is None and early is None
    assert saved.attrs["data_origin"] == "simulated"
    # the study keeps exactly the map the compared file holds ...
    final = np.asarray(saved["wear_depth"].isel(cycles=-1).values)
    np.testing.assert_array_equal(result.fields["wear_depth"], final)
    assert result.outputs["max_wear_depth"] == pytest.approx(float(final.max()), rel=1e-12)
    # ... and it is the run the serial demo simulated on its own (simulate_wear)
    serial = simulate_wear(
        params,
        cycles=TINY.cycles,
        snapshots=list(TINY.snapshots),
        settings=main_wear_settings(TINY),
    )
    np.testing.assert_array_equal(serial["wear_depth"].values, saved["wear_depth"].values)
    assert float(final.max()) > 0


def test_another_run_is_refused_as_the_compared_run(tmp_path):
    from jointwear.errors import SimulationError

    params, task = _run0()
    other = dataclasses.replace(task, values={**task.values, "wear.dn": 200.0})
    with pytest.raises(SimulationError, match="not the compared wear run"):
        demo._compared_study_run(other, tmp_path, TINY, params, False)


def _spin(seconds):
    import time

    t0 = time.process_time()
    while time.process_time() - t0 < seconds:
        pass


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="needs /proc")
def test_process_cpu_reads_a_process_cpu_time():
    _spin(0.2)
    import time

    before = time.process_time()
    measured = process_cpu(os.getpid())
    tick = 1.0 / os.sysconf("SC_CLK_TCK")
    assert before - 2 * tick <= measured <= time.process_time() + 2 * tick
    assert process_cpu(2**22 + 12345) is None  # no such process


class _Task:
    def __init__(self, index):
        self.index = index


def test_study_pool_hands_run_zero_to_the_wear_part(monkeypatch):
    calls = []

    def fake(task, *args):
        calls.append(task.index)
        print("compared run done", file=__import__("sys").stderr)
        return f"result {task.index}", ("sim_wear.nc", "metrology.nc")

    monkeypatch.setattr(demo, "_compared_study_run", fake)
    pool = demo._StudyPool(InlineExecutor(), "out", TINY, None, True)
    other = pool.submit(lambda t: f"run {t.index}", _Task(3))
    first = pool.submit(lambda t: "never", _Task(0))
    assert other.result() == "run 3" and first.result() == "result 0" and calls == [0]
    files, text = pool.wear.result()
    assert files == ("sim_wear.nc", "metrology.nc") and "compared run done" in text


def test_a_failed_compared_run_fails_the_study_run_and_the_wear_part(monkeypatch):
    def fails(task, *args):
        raise RuntimeError("no wear")

    monkeypatch.setattr(demo, "_compared_study_run", fails)
    pool = demo._StudyPool(InlineExecutor(), "out", TINY, None, True)
    first = pool.submit(lambda t: "never", _Task(0))
    for fut in (first, pool.wear):
        with pytest.raises(RuntimeError, match="no wear"):
            fut.result()


def test_run_part_captures_what_the_part_says():
    def part(x):
        import sys

        print(f"part {x}", file=sys.stderr)
        return x + 1

    assert run_part(part, 1) == (2, "part 1\n")
    assert isinstance(InlineExecutor().submit(int, "x"), Future)
    with pytest.raises(ValueError):
        InlineExecutor().submit(int, "x").result()


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_worker_pool_forks_a_lone_thread_and_spawns_beside_others(monkeypatch):
    import jointwear.reports.demo_pool as demo_pool

    cpu: list[float] = []
    # threads left by earlier tests of the suite (numba's pool among them) must not decide this
    # case: a lone thread
    monkeypatch.setattr(demo_pool.threading, "active_count", lambda: 1)
    monkeypatch.setattr(demo_pool, "numba_threads_launched", lambda: False)
    with worker_pool(2, cpu) as pool:
        assert pool._mp_context.get_start_method() == "fork"
        assert pool.submit(os.getpid).result() != os.getpid()
        pool.submit(_spin, 0.3).result()
    # a lone thread whose numba thread pool runs is spawned, not forked
    monkeypatch.setattr(demo_pool, "numba_threads_launched", lambda: True)
    with worker_pool(2) as pool:
        assert pool._mp_context.get_start_method() == "spawn"
    monkeypatch.undo()
    if os.path.exists("/proc/self/stat"):  # each worker's CPU, the spinning one's included
        assert len(cpu) == 2 and 0.25 <= max(cpu) < 5.0
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        with worker_pool(2) as pool:
            assert pool._mp_context.get_start_method() == "spawn"
    finally:
        stop.set()
        other.join()
    with worker_pool(1) as pool:
        assert isinstance(pool, InlineExecutor)


def test_a_cancelled_compared_run_cancels_the_wear_part():
    held: list[Future] = []

    class Holding(InlineExecutor):  # keeps each task queued, as a busy pool does
        def submit(self, fn, /, *args, **kwargs):
            held.append(Future())
            return held[-1]

    pool = demo._StudyPool(Holding(), "out", TINY, None, True)
    first = pool.submit(lambda t: "never", _Task(0))
    assert not first.done() and not pool.wear.done()
    assert held[0].cancel()  # the demo is stopped: its pool cancels the queued task
    assert first.cancelled() and pool.wear.cancelled()


#: A parent that compiled a kernel (and later started numba's threads) opens the demo's pool;
#: each worker starts numba's threads as the DIC does and compiles a kernel of its own.
_POOL_AFTER_COMPILE = """
import os


def part():
    import numba

    first = numba.get_num_threads()
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)  # as dic's set_threads does

    @numba.njit
    def twice(x):
        return 2 * x

    return first, numba.config.NUMBA_NUM_THREADS, twice(21), os.environ["NUMBA_NUM_THREADS"]


if __name__ == "__main__":
    import numba

    from jointwear.reports.demo_pool import worker_pool

    @numba.njit
    def one(x):
        return x + 1

    one(1)  # a compile in the parent before the pool
    for _ in range(2):
        with worker_pool(2) as pool:
            got = [pool.submit(part).result() for _ in range(3)]
            print(pool._mp_context.get_start_method(), *got[0])
        numba.get_num_threads()  # the parent's numba threads run: the next pool is spawned
"""


def test_a_pool_opened_after_a_compile_compiles_in_its_workers(tmp_path):
    """The race of #37: a forked worker used to set NUMBA_NUM_THREADS=1 under the numba it
    inherited (2 threads); the next compile after its threads started raised RuntimeError."""
    import subprocess
    import sys

    script = tmp_path / "pool_after_compile.py"
    script.write_text(_POOL_AFTER_COMPILE)
    env = {**os.environ, "NUMBA_NUM_THREADS": "2", "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    run = subprocess.run(
        [sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr[-2000:]
    forked, spawned = (line.split() for line in run.stdout.splitlines())
    # forked: numba's API set one thread; the environment keeps the value numba read
    assert forked == ["fork", "1", "2", "42", "2"]
    # spawned: the environment said one thread before the worker imported numba
    assert spawned == ["spawn", "1", "1", "42", "1"]


@pytest.mark.slow
def test_the_full_demo_on_an_empty_kernel_cache_then_dic_correlate_compiles_nothing(tmp_path):
    """The README's first command on a fresh install (#37): ``jointwear demo`` at full size on an
    empty numba cache compiles every kernel once (the warm-up), runs its parts in two worker
    processes and ends as designed: the report written, exit code 1 because the planted model
    error (the 6-degree turn) fails the wear-field criterion. Afterwards a speckle pair and the
    first ``dic correlate`` on it compile no kernel (numba's cache log says what it saved)."""
    import subprocess
    import sys

    from jointwear import _compile

    env = {
        **os.environ,
        "NUMBA_NUM_THREADS": "2",
        "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
        _compile.SWITCH: "1",
    }
    env.pop("JOINTWEAR_KERNEL_MANIFEST", None)
    jw = [sys.executable, "-m", "jointwear"]
    out = tmp_path / "demo"
    run = subprocess.run(
        [*jw, "demo", "--out", str(out)], env=env, capture_output=True, text=True, timeout=2400
    )
    said = run.stderr
    assert run.returncode == 1, said[-3000:]  # a failed criterion, not an error (exit 3)
    assert "Traceback" not in said and "This is a bug" not in said
    assert "compiling the numerical kernels once" in said and "compiled 18 kernels" in said
    assert "[1/2] simulating and measuring in 2 worker processes" in said
    assert "[2/2] comparing and writing the report" in said
    assert "12 criteria: 10 pass, 1 fail, 1 not comparable" in said
    assert "exit code 1 because 1 criterion failed - wear field within" in said
    assert f"the report was written ({out / 'report.html'})" in said
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "wear field" in html and "synthetic" in html
    for name in ("sim_wear.nc", "metrology_wear.nc", "ensemble.nc", "sim_verification.nc",
                 "dic_motion.nc", "posterior.nc", "prediction.nc", "metrics.nc"):  # fmt: skip
        assert (out / name).is_file(), name
    _check_the_calibration_step(out)
    # the next commands load every kernel from the cache: none is compiled
    logged = {**env, "NUMBA_DEBUG_CACHE": "1"}
    pair = tmp_path / "pair"
    made = subprocess.run(
        [*jw, "datasets", "speckle", str(pair), "--size", "128x128"],
        env=logged, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert made.returncode == 0, made.stderr[-2000:]
    assert "data saved" not in made.stdout
    run = subprocess.run(
        [*jw, "dic", "correlate", str(pair / "reference.png"), str(pair / "deformed.png"),
         "--subset", "21", "--step", "16", "--out", str(tmp_path / "f.nc")],
        env=logged, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-2000:]
    assert "data loaded" in run.stdout  # the kernels came from the cache ...
    assert "data saved" not in run.stdout  # ... and none was compiled
    # nor did the command warm up again or compile one itself (its compile notice)
    assert NOTICE not in run.stderr and "kernel(s)" not in run.stderr
    assert "compiling the numerical kernels" not in run.stderr + made.stderr


def _check_the_calibration_step(out):
    """The demo's calibrate -> validate step (#35 item 5): the synthetic bore (the model's map
    10 % deeper, turned 6 degree) scanned at 1e5 and 2e5 cycles; kw calibrated on the 1e5 map
    comes out above the nominal (the truth wears more) and informed, the prediction is the
    compared simulation, and the 1e5 map is refused as validation data."""
    from jointwear.compare import load_comparison
    from jointwear.errors import BadInputError
    from jointwear.reports.demo_calibration import CalibrationStep, with_prediction
    from jointwear.sim import DEFAULT_KW

    early, validation = out / "metrology_wear_calibration.nc", out / "metrology_wear.nc"
    assert io.load(early).attrs["cycles"] == demo.FULL.calibration_cycles
    assert io.load(validation).attrs["cycles"] == demo.FULL.cycles
    post = io.load(out / "posterior.nc", validate=False)
    mean, ratio = float(post["posterior_mean"].values[0]), float(post["width_ratio"].values[0])
    assert DEFAULT_KW < mean < 1.3 * DEFAULT_KW and ratio < 0.5, (mean / DEFAULT_KW, ratio)
    step = CalibrationStep(
        out / "posterior.nc", out / "prediction.nc", early, out / "calibrate.toml",
        out / "calibrate_params.toml", 0.0,
    )  # fmt: skip
    sims, _, ens_paths, _ = with_prediction(step, [out / "sim_wear.nc"], [validation], [], [])
    assert sims == [step.prediction] and ens_paths == [step.prediction]
    with pytest.raises(BadInputError, match="calibration data never validate"):
        with_prediction(step, [out / "sim_wear.nc"], [early], [], [])
    states = load_comparison(io.load(out / "metrics.nc")).decisions.set_index("key").state
    assert states["max_wear_depth"] == "pass" and states["wear_field"] == "fail"
