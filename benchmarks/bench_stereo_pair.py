"""Benchmark: stereo correspondence of one 1920 x 1200 pair (the start of stereo tracking).

Renders the virtual rig at 1920 x 1200 px, writes the pair as PNG folders and times
``track_footage`` on that one frame pair with ~200 subsets (SIFT features of the region and of
the right image's epipolar band, FLANN matching guided by the epipolar lines, RANSAC
homography, IC-GN of every subset, triangulation, rigid fit), and its matching stage alone.
For reference it also times the former matching (SIFT of the whole right image, brute-force
k-NN of the descriptors). Accuracy: the triangulated reference points against the rig's
ground-truth body plane.

Run: ``python benchmarks/bench_stereo_pair.py [--repeat N]``.
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

from _common import median_time, write_results  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    import cv2

    from jointwear.datasets.rig import RigConfig, VirtualRig, _write_bodies_toml
    from jointwear.dic.footage._features import (
        MatchReport,
        _sift_features,
        _sift_homography,
        epipolar_band,
    )
    from jointwear.dic.footage._track import read_bodies, track_footage

    cfg = RigConfig(width=1920, height=1200)
    rig = VirtualRig(cfg)
    cal = rig.calibration
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        imgs = {}
        for cam in ("left", "right"):
            (folder / cam).mkdir()
            imgs[cam] = rig.render(cam, 0.0)
            for k in range(2):  # a two-frame sequence: the pair, then the same pair again
                cv2.imwrite(str(folder / cam / f"{cam}_{k:02d}.png"), imgs[cam])
        tc, bodies = read_bodies(_write_bodies_toml(rig, folder / "bodies.toml"))
        tc = dataclasses.replace(tc, step=20, world_origin=[0.0, 0.0, 0.0])

        def run():
            return track_footage(
                folder / "left",
                folder / "right",
                fps=cfg.fps,
                bodies=bodies,
                calibration=cal,
                config=tc,
                max_frames=1,
            )

        t_track, runs = median_time(run, repeat=args.repeat, warmup=1)
        ds = run()
        n_points = {b.name: int(ds[f"{b.name}_n_points"].values[0]) for b in bodies}

        polys = [np.asarray(b.polygon, dtype=float) for b in bodies]
        L, R = imgs["left"], imgs["right"]

        def guided():
            band = epipolar_band(cal, polys, R.shape, 3.0)
            fr = _sift_features(R, mask=band)
            for poly in polys:
                rep = MatchReport()
                _sift_homography(_sift_features(L, poly), fr, calibration=cal, report=rep)
            return rep

        t_guided, _ = median_time(guided, repeat=args.repeat, warmup=1)
        rep = guided()

        def brute():
            fr = cv2.SIFT_create().detectAndCompute(R, None)
            for poly in polys:
                fl = _sift_features(L, poly)
                cv2.BFMatcher(cv2.NORM_L2).knnMatch(fl[1], fr[1], k=2)

        t0 = time.perf_counter()
        brute()
        t_brute = time.perf_counter() - t0

    figures = {
        "image_size_px": [cfg.width, cfg.height],
        "subsets_per_body": n_points,
        "subsets_total": int(sum(n_points.values())),
        "track_one_pair_s": round(t_track, 3),
        "track_one_pair_runs_s": [round(t, 3) for t in runs],
        "matching_guided_s": round(t_guided, 3),
        "matching_bruteforce_whole_image_s": round(t_brute, 3),
        "last_body_features_region_band": [rep.features_ref, rep.features_target],
        "last_body_epipolar_matches": rep.epipolar_inliers,
        "last_body_homography_inliers": rep.homography_inliers,
        "note": "track_one_pair: track_footage on one 1920x1200 PNG pair (decoding, SIFT, "
        "matching, IC-GN of every subset, triangulation, rigid fit), numba kernels cached",
    }
    write_results("stereo_pair", figures)


if __name__ == "__main__":
    main()
