"""Speed and accuracy of the 2D subset-DIC engine (``python benchmarks/bench_dic2d.py``).

A 512x512 analytic speckle pair (5-px speckles, 8 bit) moved by (3.3, -2.7) px, 33-px subsets,
16-px and 4-px grid steps: points of interest per second of the whole ``correlate`` call
(B-spline prefilter of both images, seed search, reliability-guided propagation, IC-GN,
output Dataset) and the error against the exact truth, without noise and with 2 grey levels of
Gaussian noise. Two numba threads (wall clock, ``poi_per_s``); because the machine is shared,
the CPU time of one call on one thread is also given (``poi_per_cpu_second_1_thread``), which
other users of the machine do not distort. Quote medians with the load average.

``--pyvale``: jointwear and pyvale (``pip install pyvale``, not a dependency) side by side in one
run, CPU time on one thread, min of 3 interleaved repeats (with the part of jointwear's call
spent on the output Dataset and its outlier tests, ``output_cpu_s_of_min``), and the CLI process
against the library call at step 4 (``results/dic2d_pyvale.json``).

The affine and second-order shape functions on a sinusoidal field (``shape_functions_sinusoid``:
speed and error against the exact field).

``--split``: where one call's CPU time goes (IC-GN set-up and iterations per point, fixed cost
per call; ``results/dic2d_cost_split.json``).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from _common import median_time, write_results  # noqa: E402

from jointwear.datasets import speckle as sp  # noqa: E402
from jointwear.dic import CorrelationParams, SubsetCorrelator, correlate  # noqa: E402

SHIFT = (3.3, -2.7)


def _errors(ds, pair):
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    tu, tv = pair.truth(X, Y)
    ok = ds.flag.values == 0
    eu = (ds.u.values - tu)[ok]
    ev = (ds.v.values - tv)[ok]
    return eu, ev, ok


def _correlate(pair, step, interp, threads):
    """The benchmarked call: the whole ``correlate`` of the pair, 33-pixel subsets."""
    return correlate(
        pair.reference,
        pair.deformed,
        subset_size=33,
        step=step,
        interpolation=interp,
        threads=threads,
    )


def _cpu_seconds(pair, step, interp, repeat=3) -> float:
    """Median CPU time of one call on one thread (insensitive to other users of the machine)."""
    times = []
    for _ in range(repeat + 1):
        t0 = time.process_time()
        _correlate(pair, step, interp, threads=1)
        times.append(time.process_time() - t0)
    return float(np.median(times[1:]))


def main() -> None:
    figures: dict = {"threads": 2, "image": "512x512, 8 bit, speckle 5 px", "shift_px": SHIFT}
    pairs = {
        "noise_free": sp.speckle_pair((512, 512), sp.RigidField(SHIFT), seed=1),
        "noise_2gl": sp.speckle_pair(
            (512, 512), sp.RigidField(SHIFT), params=sp.SpeckleParams(noise_std=2.0), seed=1
        ),
    }
    for interp in ("quintic", "cubic"):
        for step in (16, 4):
            key = f"{interp}_subset33_step{step}"
            row: dict = {}
            for name, pair in pairs.items():

                def run(pair=pair, step=step, interp=interp):
                    return _correlate(pair, step, interp, threads=2)

                ds = run()
                t, _ = median_time(run, repeat=5 if step == 16 else 3, warmup=1)
                cpu = _cpu_seconds(pair, step, interp)
                eu, ev, ok = _errors(ds, pair)
                row[name] = {
                    "points": int(ok.size),
                    "points_ok": int(ok.sum()),
                    "seconds_median": round(t, 4),
                    "poi_per_s": round(ok.size / t),
                    "poi_per_cpu_second_1_thread": round(ok.size / cpu),
                    "mean_error_u_px": float(f"{eu.mean():.6f}"),
                    "mean_error_v_px": float(f"{ev.mean():.6f}"),
                    "std_error_u_px": float(f"{eu.std():.6f}"),
                    "std_error_v_px": float(f"{ev.std():.6f}"),
                    "mean_iterations": round(
                        float(ds.iterations.values[ds.flag.values == 0].mean()), 2
                    ),
                }
            figures[key] = row
            print(key, {k: v["poi_per_s"] for k, v in row.items()}, flush=True)
    # sequence use: reference prepared once, guesses from the previous frame
    pair = pairs["noise_free"]
    corr = SubsetCorrelator(pair.reference, subset_size=33, step=4, threads=2)
    guess = np.tile([3.0, -3.0], (corr.n_points, 1))
    corr.match(pair.deformed, initial_guess=guess)
    t, _ = median_time(lambda: corr.match(pair.deformed, initial_guess=guess), repeat=3)
    figures["quintic_step4_prepared_reference_with_guess"] = {
        "points": corr.n_points,
        "seconds_median": round(t, 4),
        "poi_per_s": round(corr.n_points / t),
    }
    figures["shape_functions_sinusoid"] = shape_functions()
    figures["load_average_1min_at_end"] = os.getloadavg()[0]
    write_results("dic2d", figures)


def shape_functions(repeat: int = 3) -> dict:
    """Affine against second-order subsets on a curved field: a 512x512 pair under a sinusoid
    (amplitude (2, 0.5) px, wavelength 100 px along x, 2 grey levels of noise), 33-px subsets
    every 8 px, quintic; CPU seconds of the match on one thread (reference prepared, min of
    ``repeat``), IC-GN iterations and the RMS error of u and v against the exact field."""
    pair = sp.speckle_pair(
        (512, 512),
        sp.SinusoidalField((2.0, 0.5), 100.0),
        params=sp.SpeckleParams(noise_std=2.0),
        seed=1,
    )
    out: dict = {"image": "512x512, sinusoid (2, 0.5) px over 100 px, 2 GL, subset 33, step 8"}
    for shape in ("affine", "quadratic"):
        corr = SubsetCorrelator(pair.reference, subset_size=33, step=8, threads=1, shape=shape)
        res = corr.match(pair.deformed)
        times = []
        for _ in range(repeat):
            t0 = time.process_time()
            res = corr.match(pair.deformed)
            times.append(time.process_time() - t0)
        ok = res.ok
        tu, tv = pair.truth(corr.centres[:, 0], corr.centres[:, 1])
        out[shape] = {
            "points": corr.n_points,
            "points_ok": int(ok.sum()),
            "cpu_s_min": round(min(times), 4),
            "poi_per_cpu_s": round(corr.n_points / min(times)),
            "mean_iterations": round(float(res.iterations[ok].mean()), 2),
            "rms_error_u_px": float(f"{np.sqrt(np.mean((res.params[ok, 0] - tu[ok]) ** 2)):.5f}"),
            "rms_error_v_px": float(f"{np.sqrt(np.mean((res.params[ok, 6] - tv[ok]) ** 2)):.5f}"),
        }
        print("shape", shape, out[shape], flush=True)
    return out


def _pyvale_cpu(pair, step: int, out: Path) -> tuple[float, object]:
    """CPU seconds of pyvale's ``calculate_2d`` on one thread (text output in ``out``) and its
    result: the same pair, 33-pixel subsets, ZNSSD, affine, B-spline, ZNCC gate 0.8."""
    from pyvale import dic as pdic

    mask = np.zeros(pair.reference.shape, bool)
    mask[16:-16, 16:-16] = True
    for old in out.glob("*"):
        old.unlink()
    t0 = time.process_time()
    pdic.calculate_2d(
        reference=pair.reference, deformed=pair.deformed, roi_mask=mask, seed=[256, 256],
        subset_size=33, subset_step=step, max_displacement=10, num_threads=1, threshold=0.8,
        output_basepath=out, print_level=0,
    )  # fmt: skip
    cpu = time.process_time() - t0
    return cpu, pdic.import_2d(
        data=str(out / "dic_results_*"), layout="column", binary=False, delimiter=","
    )


def _library_cpu(pair, step: int):
    """CPU seconds of the library call on one thread (what :func:`_correlate` does: reference
    prepared, matched, packaged), the Dataset, and the CPU seconds of the last part alone (the
    output Dataset with the outlier tests)."""
    params = CorrelationParams(subset_size=33, step=step, interpolation="quintic", threads=1)
    t0 = time.process_time()
    corr = SubsetCorrelator(pair.reference, params=params)
    res = corr.match(pair.deformed)
    t1 = time.process_time()
    ds = corr.to_dataset(res)
    t2 = time.process_time()
    return t2 - t0, ds, t2 - t1


def _correlate_cpu(pair, step: int) -> float:
    """CPU seconds of one ``correlate`` call on one thread (quintic, 33-pixel subsets)."""
    t0 = time.process_time()
    _correlate(pair, step, "quintic", threads=1)
    return time.process_time() - t0


def _cli_cpu(ref_png: Path, def_png: Path, out: Path, step: int) -> float:
    """CPU seconds of the whole ``jointwear dic correlate`` process (start-up included), the
    ``jointwear`` script with its modules' bytecode cached as on a user's install (as in
    ``bench_startup.py``: ``PYTHONDONTWRITEBYTECODE`` is dropped, so the first run writes it)."""
    import resource
    import subprocess

    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(
        [str(Path(sys.executable).parent / "jointwear"), "dic", "correlate", str(ref_png), str(def_png),
         "--subset", "33", "--step", str(step), "--threads", "1", "--origin", "synthetic",
         "--out", str(out), "--overwrite"],
        check=True, capture_output=True, env=env,
    )  # fmt: skip
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    assert out.is_file(), "the CLI wrote no result"
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _accuracy(u, v, x, y, pair) -> dict:
    tu, tv = pair.truth(x, y)
    eu, ev = u - tu, v - tv
    ok = np.isfinite(eu) & np.isfinite(ev)
    return {
        "points_ok": int(ok.sum()),
        "mean_error_u_px": float(f"{eu[ok].mean():.6f}"),
        "mean_error_v_px": float(f"{ev[ok].mean():.6f}"),
        "std_error_u_px": float(f"{eu[ok].std():.6f}"),
        "std_error_v_px": float(f"{ev[ok].std():.6f}"),
    }


def versus_pyvale(repeat: int = 3) -> None:
    """jointwear's ``correlate`` and pyvale's ``calculate_2d`` side by side in one run: CPU time
    of one call on one thread (the machine is shared: CPU time, min of ``repeat`` interleaved
    repeats), accuracy against the exact truth, and the CLI process against the library call
    at step 4. Writes ``results/dic2d_pyvale.json``; skipped with a message without pyvale."""
    import importlib.util
    import tempfile

    import cv2

    if importlib.util.find_spec("pyvale") is None:
        print("bench_dic2d --pyvale: pyvale is not installed (pip install pyvale): skipped")
        return
    from importlib.metadata import version

    tmp = Path(tempfile.mkdtemp())
    os.chdir(tmp)  # pyvale writes a log file into the working directory when imported
    pairs = {
        "noise_free": sp.speckle_pair((512, 512), sp.RigidField(SHIFT), seed=1),
        "noise_2gl": sp.speckle_pair(
            (512, 512), sp.RigidField(SHIFT), params=sp.SpeckleParams(noise_std=2.0), seed=1
        ),
    }
    figures: dict = {
        "pyvale_version": version("pyvale"),
        "image": "512x512, 8 bit, speckle 5 px, shift (3.3, -2.7) px; subset 33, affine, ZNSSD, "
        "B-spline (jointwear quintic), ZNCC gate 0.8, one thread each, CPU time of the call",
    }
    for step in (16, 4):
        for name, pair in pairs.items():
            jw, pv, out_part = [], [], []
            load = os.getloadavg()[0]
            for _ in range(repeat):  # interleaved
                t, ds, t_out = _library_cpu(pair, step)
                jw.append(t)
                out_part.append(t_out)
                t, res = _pyvale_cpu(pair, step, tmp)
                pv.append(t)
            n_jw = int(ds.flag.size)
            x, y = np.meshgrid(ds.x.values, ds.y.values)
            u, v = ds.u.values, ds.v.values
            px, py = np.asarray(res.ss_x, float).ravel(), np.asarray(res.ss_y, float).ravel()
            pu, pv_ = np.asarray(res.u_px, float).ravel(), np.asarray(res.v_px, float).ravel()
            row = {
                "jointwear": {
                    "points": n_jw,
                    "cpu_s_min": round(min(jw), 4),
                    "output_cpu_s_of_min": round(out_part[int(np.argmin(jw))], 4),
                    "poi_per_cpu_s": round(n_jw / min(jw)),
                    "mean_iterations": round(
                        float(ds.iterations.values[ds.flag.values == 0].mean()), 2
                    ),
                    **_accuracy(u.ravel(), v.ravel(), x.ravel(), y.ravel(), pair),
                },
                "pyvale": {
                    "points": int(px.size),
                    "cpu_s_min": round(min(pv), 4),
                    "poi_per_cpu_s": round(px.size / min(pv)),
                    **_accuracy(pu, pv_, px, py, pair),
                },
            }
            row["load_average_1min_at_start"] = round(load, 2)
            row["speed_ratio"] = round(
                row["jointwear"]["poi_per_cpu_s"] / row["pyvale"]["poi_per_cpu_s"], 2
            )
            figures[f"step{step}_{name}"] = row
            print(f"step {step} {name}: {row}", flush=True)
    pair = pairs["noise_free"]
    ref_png, def_png = tmp / "ref.png", tmp / "def.png"
    cv2.imwrite(str(ref_png), pair.reference)
    cv2.imwrite(str(def_png), pair.deformed)
    lib, cli = [], []
    for _ in range(repeat):
        lib.append(_correlate_cpu(pair, 4))
        (tmp / "cli.nc").unlink(missing_ok=True)
        cli.append(_cli_cpu(ref_png, def_png, tmp / "cli.nc", 4))
    figures["step4_cli"] = {
        "library_cpu_s_min": round(min(lib), 4),
        "cli_process_cpu_s_min": round(min(cli), 4),
        "cli_over_library_speed": round(min(lib) / min(cli), 2),
    }
    print(figures["step4_cli"])
    write_results("dic2d_pyvale", figures)


def cost_split(repeat: int = 5) -> None:
    """Where one quintic call's CPU time goes at steps 4 and 16 (one thread, min of ``repeat``):
    the whole call; per point, the IC-GN's set-up (reference subset, Hessian: the kernel run
    with 0 iterations from the converged parameters, points in raster order) and one iteration
    (the same with 1, minus the set-up); the rest is fixed cost per call (prefilters, kappa,
    texture, seeds, output, and the propagation's own bookkeeping).
    Writes ``results/dic2d_cost_split.json``."""
    from jointwear.dic.icgn._drive import _refine_chunk

    pair = sp.speckle_pair((512, 512), sp.RigidField(SHIFT), seed=1)
    figures: dict = {"image": "512x512, 8 bit, speckle 5 px, quintic, 33-px subsets, 1 thread"}
    for step in (16, 4):
        params = CorrelationParams(subset_size=33, step=step, interpolation="quintic", threads=1)
        whole = min(_correlate_cpu(pair, step) for _ in range(repeat))
        corr = SubsetCorrelator(pair.reference, params=params)
        res = corr.match(pair.deformed)
        dspl, dinv, _ = corr._prepare_deformed(pair.deformed)
        ref, dfm = corr._kernel_args(dspl, dinv)
        n = corr.n_points
        scale = corr._kappa_of_points()
        kernel_s = {}
        for iterations in (0, 1):
            opts = list(corr._solver_options())
            opts[2] = iterations
            out = (np.zeros(n), np.zeros(n, np.int32), np.zeros(n, np.int8), np.zeros((n, 2)))
            times = []
            for _ in range(repeat + 1):
                P = res.params.copy()
                t0 = time.process_time()
                # all points in raster order (one chunk): neighbours share their pixels in
                # the caches, as in the propagation
                _refine_chunk(0, 1, ref, dfm, tuple(opts), corr.centres, scale, P, res.ok, out)
                times.append(time.process_time() - t0)
            kernel_s[iterations] = min(times[1:])
        setup, one = kernel_s[0] / n, (kernel_s[1] - kernel_s[0]) / n
        iters = float(res.iterations[res.ok].mean())
        figures[f"step{step}"] = {
            "points": n,
            "call_cpu_s_min": round(whole, 4),
            "setup_us_per_point": round(setup * 1e6, 1),
            "iteration_us": round(one * 1e6, 1),
            "mean_iterations": round(iters, 2),
            "ic_gn_share_of_call": round(n * (setup + iters * one) / whole, 2),
            "fixed_cpu_s_per_call": round(whole - n * (setup + iters * one), 4),
        }
        print(step, figures[f"step{step}"], flush=True)
    figures["load_average_1min_at_end"] = os.getloadavg()[0]
    write_results("dic2d_cost_split", figures)


if __name__ == "__main__":
    if "--pyvale" in sys.argv:
        versus_pyvale()
    elif "--split" in sys.argv:
        cost_split()
    else:
        main()
