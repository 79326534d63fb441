"""Benchmark: 10 s of 50 frames/s stereo footage (two 1280 x 1024 cameras, ~200 points/frame).

Renders one crank revolution of the virtual rig (25 frame pairs; the motion is 0.5 s periodic)
and writes it 20 times into two lossless raw-grey AVI videos (500 frame pairs = 10 s), then times
``track_footage`` (decoding, stereo DIC of the follower and journal patches, triangulation,
rigid fits, velocities), once in memory and once writing the result file as
``jointwear dic track --out`` does (partial results after chunks, inputs hashed for the
provenance), checks the accuracy against the ground truth and reports the result's size per
frame (what grows in memory with the recording's length) and the peak resident memory.

Run: ``python benchmarks/bench_stereo.py [--repeat N] [--workers W]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import median_time, write_results  # noqa: E402

CODEC = "GREY"  # raw 8-bit grey AVI: lossless and the fastest to decode (4 ms vs 38 ms for FFV1)


def make_footage(folder: Path, seconds: float = 10.0):
    import cv2

    from jointwear.datasets.rig import RigConfig, VirtualRig, _write_bodies_toml

    cfg = RigConfig(duration=0.5)
    rig = VirtualRig(cfg)
    times = rig.frame_times()
    n_total = int(round(seconds * cfg.fps))
    paths = {}
    for cam in ("left", "right"):
        frames = [rig.render(cam, t, frame_index=k) for k, t in enumerate(times)]
        path = folder / f"{cam}.avi"
        w = cv2.VideoWriter(
            str(path), cv2.VideoWriter_fourcc(*CODEC), cfg.fps, (cfg.width, cfg.height), False
        )
        for k in range(n_total):
            w.write(frames[k % len(frames)])
        w.release()
        paths[cam] = path
    bodies = _write_bodies_toml(rig, folder / "bodies.toml")
    truth = rig.ground_truth(np.arange(n_total) / cfg.fps)
    return rig, paths, bodies, truth


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--warmup", type=int, default=1)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument(
        "--interpolation", choices=["cubic", "quintic"], default=None, help="default: the TOML's"
    )
    args = ap.parse_args()

    from jointwear.dic.footage._track import read_bodies, track_footage

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        rig, paths, bodies_path, truth = make_footage(folder, args.seconds)
        t_make = time.perf_counter() - t0
        os.sync()  # the 1.3 GB just written is flushed now, not during the timed runs
        tc, bodies = read_bodies(bodies_path)
        tc = dataclasses.replace(
            tc, step=14, world_origin=[0.0, 0.0, 0.0], workers=args.workers, chunk_size=250
        )
        if args.interpolation:
            tc = dataclasses.replace(tc, interpolation=args.interpolation)
        result = {}

        def run():
            c0 = time.process_time()
            result["ds"] = track_footage(
                paths["left"], paths["right"], bodies=bodies, calibration=rig.calibration, config=tc
            )
            result.setdefault("cpu", []).append(time.process_time() - c0)

        med, times = median_time(run, repeat=args.repeat, warmup=args.warmup)
        ds = result["ds"]

        # the command-line path: the result file is written during the run (partial results
        # after chunks of 50 frames, with the inputs' sha256 in its provenance)
        out = folder / "motion.nc"
        inputs = (paths["left"], paths["right"], bodies_path)
        # (the command line's default chunks of 50 frames; worker processes keep their chunks
        # of 250 frames, since each chunk re-prepares the references)
        tc_cli = dataclasses.replace(tc, chunk_size=50) if args.workers == 1 else tc

        def run_with_output():
            out.unlink(missing_ok=True)
            track_footage(
                paths["left"],
                paths["right"],
                bodies=bodies,
                calibration=rig.calibration,
                config=tc_cli,
                out=out,
                inputs=inputs,
            )

        med_out, times_out = median_time(run_with_output, repeat=args.repeat, warmup=0)
        result_mb = ds.nbytes / 1e6
        n_frames = ds.sizes["time"]
        n_points = int(np.median(ds["follower_n_points"] + ds["journal_n_points"]))
        v, vt = ds["follower_velocity"].values, truth["follower_velocity"].values
        ok = np.all(np.isfinite(v), axis=1)
        peak = float(np.max(np.linalg.norm(vt, axis=1)))
        vel_rms = np.sqrt(np.mean((v[ok] - vt[ok]) ** 2, axis=0)) / peak * 100
        jz = ds["journal_displacement"].sel(axis="z").values
        jz_t = truth["journal_displacement"].sel(axis="z").values
        z_rms = float(np.sqrt(np.nanmean((jz - jz_t) ** 2)))
        write_results(
            ("stereo" if args.workers == 1 else f"stereo_workers{args.workers}")
            + (f"_{args.interpolation}" if args.interpolation else ""),
            {
                "footage": f"{args.seconds:g} s at 50 frames/s, two 1280x1024 {CODEC} AVI videos",
                "frame_pairs": n_frames,
                "points_per_frame_median": n_points,
                "workers": args.workers,
                "interpolation": tc.interpolation,
                "wall_time_s_median": round(med, 2),
                "wall_time_s_runs": [round(t, 2) for t in times],
                "cpu_time_s_runs_main_process": [round(t, 2) for t in result["cpu"]],
                "note": "the machine is shared (see load average): CPU time is what the run "
                "needed, wall time what it took here",
                "wall_time_s_median_writing_output": round(med_out, 2),
                "wall_time_s_runs_writing_output": [round(t, 2) for t in times_out],
                "output_file_mb": round(out.stat().st_size / 1e6, 1),
                "result_bytes_per_frame_pair": round(result_mb * 1e6 / n_frames),
                "result_mb_for_10_minutes_extrapolated": round(result_mb * 30000 / n_frames),
                "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
                "realtime_factor": round(args.seconds / med, 3),
                "frames_per_second": round(n_frames / med, 1),
                "target_s": 10.0,
                "footage_generation_s": round(t_make, 1),
                "follower_velocity_rms_error_percent_of_peak": [
                    round(float(e), 3) for e in vel_rms
                ],
                "journal_z_rms_error_um": round(z_rms * 1e6, 3),
            },
        )


if __name__ == "__main__":
    main()
