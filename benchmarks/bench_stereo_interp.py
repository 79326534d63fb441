"""Benchmark: cubic or quintic B-splines for footage tracking (``[track] interpolation``)?

1. Rendered speckle (``jointwear.datasets.speckle``, 3 and 5 px speckles, 1 grey level noise,
   8 bit): sub-pixel translations 0.05..0.95 px, 21 px subsets as ``dic track`` uses, affine
   IC-GN; RMS displacement error and time per subset match for each interpolation.
2. The virtual rig (``jointwear.datasets.rig``, two 1280 x 1024 cameras, one crank revolution
   at 50 frames/s, exact cameras): follower velocity and journal out-of-plane errors against the
   ground truth, and the wall time of ``track_footage``, for each interpolation.

Run: ``python benchmarks/bench_stereo_interp.py [--rig-seconds S]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402


def speckle_errors(speckle: float, interpolation: str) -> dict:
    from jointwear.datasets.speckle import AffineField, SpeckleParams, speckle_pair
    from jointwear.dic import correlate

    params = SpeckleParams(speckle_size=speckle, noise_std=1.0, blur_std=0.4)
    errs, times = [], []
    for k, s in enumerate(np.linspace(0.05, 0.95, 10)):
        field = AffineField(translation=(s, 0.6 * s))
        pair = speckle_pair((200, 200), field, params=params, seed=k)
        t0 = time.perf_counter()
        ds = correlate(
            pair.reference, pair.deformed, subset_size=21, step=12,
            interpolation=interpolation, threads=1, roi=(30, 30, 170, 170),
        )  # fmt: skip
        X, Y = np.meshgrid(ds["x"].values, ds["y"].values)
        times.append((time.perf_counter() - t0) / X.size)
        tu, tv = field.displacement(X, Y)
        e = np.column_stack([(ds["u"].values - tu).ravel(), (ds["v"].values - tv).ravel()])
        errs.append(e[np.all(np.isfinite(e), axis=1)])
    e = np.concatenate(errs)
    return {
        "rms_error_px": float(np.sqrt(np.mean(e**2))),
        "mean_error_px": [float(v) for v in e.mean(0)],
        "time_per_subset_ms": float(np.median(times) * 1e3),
    }


def rig_errors(interpolation: str, seconds: float) -> dict:
    from jointwear import io
    from jointwear.datasets.rig import RigConfig, VirtualRig, generate_rig
    from jointwear.dic.footage._track import read_bodies, track_footage

    cfg = RigConfig(duration=seconds)
    with tempfile.TemporaryDirectory() as tmp:
        w = generate_rig(tmp, cfg, video=False, images=True, calibration_images=False)
        truth = io.load(w["truth"])
        tc, bodies = read_bodies(w["bodies"])
        tc = dataclasses.replace(tc, world_origin=[0.0, 0.0, 0.0], interpolation=interpolation)
        run = dict(fps=cfg.fps, bodies=bodies, calibration=VirtualRig(cfg).calibration, config=tc)
        track_footage(w["left_images"], w["right_images"], max_frames=3, **run)  # warm-up
        t0 = time.perf_counter()
        ds = track_footage(w["left_images"], w["right_images"], **run)
        wall = time.perf_counter() - t0
    v, vt = ds["follower_velocity"].values, truth["follower_velocity"].values
    ok = np.all(np.isfinite(v), axis=1)
    peak = float(np.max(np.linalg.norm(vt, axis=1)))
    out = {
        "track_wall_s": wall,
        "follower_velocity_rms_error_mm_s": (np.sqrt(np.mean((v[ok] - vt[ok]) ** 2, 0)) * 1e3)
        .round(4)
        .tolist(),
        "follower_velocity_peak_m_s": peak,
    }
    if "journal_displacement" in ds and "journal_displacement" in truth:
        dz = ds["journal_displacement"].values[:, 2] - truth["journal_displacement"].values[:, 2]
        out["journal_z_rms_error_um"] = float(np.sqrt(np.nanmean(dz**2)) * 1e6)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rig-seconds", type=float, default=0.5)
    args = ap.parse_args()
    figures: dict = {"speckle": {}, "rig": {}}
    for interp in ("cubic", "quintic"):
        for sp in (3.0, 5.0):
            figures["speckle"][f"{interp}_{sp:g}px"] = speckle_errors(sp, interp)
        figures["rig"][interp] = rig_errors(interp, args.rig_seconds)
    write_results("stereo_interp", figures)


if __name__ == "__main__":
    main()
