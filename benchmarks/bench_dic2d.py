"""Speed and accuracy of the 2D subset-DIC engine (``python benchmarks/bench_dic2d.py``).

A 512x512 analytic speckle pair (5-px speckles, 8 bit) moved by (3.3, -2.7) px, 33-px subsets,
16-px and 4-px grid steps: points of interest per second of the whole ``correlate`` call
(B-spline prefilter of both images, seed search, reliability-guided propagation, IC-GN,
output Dataset) and the error against the exact truth, without noise and with 2 grey levels of
Gaussian noise. Two numba threads (wall clock, ``poi_per_s``); because the machine is shared,
the CPU time of one call on one thread is also given (``poi_per_cpu_second_1_thread``), which
other users of the machine do not distort. Quote medians with the load average.
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
from jointwear.dic import SubsetCorrelator, correlate  # noqa: E402

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
    figures["load_average_1min_at_end"] = os.getloadavg()[0]
    write_results("dic2d", figures)


if __name__ == "__main__":
    main()
