"""Full-field DIC figures (``python benchmarks/bench_field.py``).

1. Sub-pixel S-curve bias of the 2D engine on noise-free 8-bit speckle of 3, 5 and 8 px (160 px
   images, 21-px subsets, shifts 0..1 px along x): the IC-GN Jacobian with central-difference
   image gradients (what the engine uses) against the interpolant's exact derivative.
2. Honest uncertainty, 2D: reported ``displacement_u`` against the scatter of zero-motion data
   (same pattern, independent noise of 1 grey level), speckle 3 and 5 px.
3. Honest uncertainty, stereo: a static speckled surface (virtual rig, 640 x 480, 0.31 mm per
   pixel, noise 1 grey level) imaged three times; the scatter of the displacement against the
   reported ``displacement_u``, and the geometric floor ``Z^2/(f B) sqrt(2) sigma_u``.
4. Speed: one 1920 x 1200 stereo pair with about 200 subsets through ``measure_field`` (shape
   only) and two pairs (displacement), wall clock on two numba threads.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "dic"))

import numpy as np  # noqa: E402
from _common import write_results  # noqa: E402
from _s_curve import s_curve  # noqa: E402

from jointwear.datasets import speckle as sp  # noqa: E402
from jointwear.datasets.rig import RigConfig  # noqa: E402
from jointwear.datasets.surface import SurfaceScene  # noqa: E402
from jointwear.dic import measure_field  # noqa: E402

#: sub-pixel shifts [pixel] of the S-curve (160-pixel images)
SHIFTS = np.arange(0.0, 1.0001, 0.1)


def sigma_2d(size: float) -> dict:
    params = sp.SpeckleParams(speckle_size=size, noise_std=1.0)
    frames = sp.speckle_sequence((200, 200), [None, None], params=params, seed=3)
    ds = measure_field(frames, subset_size=21, step=8)
    ok = ds.flag.values[1] == 0
    d, du = ds.displacement.values[1][ok], ds.displacement_u.values[1][ok]
    scatter = d.std(axis=0)
    reported = np.sqrt(np.mean(du**2, axis=0))
    return {
        "scatter_px": scatter.tolist(),
        "reported_px": reported.tolist(),
        "ratio": (reported / scatter).tolist(),
    }


def sigma_stereo() -> dict:
    sc = SurfaceScene()
    pairs = [sc.pair(noise_seed=k) for k in range(3)]
    ds = sc.measure(pairs, subset_size=25, step=12)
    ok = (ds.flag.values == 0).all(axis=0)
    d = ds.displacement.values[1:][:, ok].reshape(-1, 3)
    du = ds.displacement_u.values[1:][:, ok].reshape(-1, 3)
    # per-image matching noise from the left matches between static images (two images each)
    dl = (ds.subset_x.values[1:, 0] - ds.subset_x.values[0, 0])[:, ok]
    sigma_u = float(np.nanstd(dl) / np.sqrt(2))
    return {
        "points": int(ok.sum()),
        "scatter_um": (d.std(axis=0) * 1e6).tolist(),
        "reported_um": (np.sqrt(np.mean(du**2, axis=0)) * 1e6).tolist(),
        "ratio": (np.sqrt(np.mean(du**2, axis=0)) / d.std(axis=0)).tolist(),
        "sigma_u_per_image_px": sigma_u,
        "noise_floor_z_um": float(sc.rig.noise_floor_z(sigma_u) * 1e6),
    }


def speed() -> dict:
    cfg = RigConfig(width=1920, height=1200, fov_width=0.3)
    sc = SurfaceScene(size=(0.16, 0.1), config=cfg)
    t0 = time.perf_counter()
    pairs = [sc.pair(noise_seed=k) for k in range(2)]
    render = time.perf_counter() - t0
    x0, y0, x1, y1 = sc.roi_left()
    out = {"render_s": render, "roi_px": [x0, y0, x1, y1]}
    for n in (1, 2):
        for _rep in range(2):  # the first run may compile
            t0 = time.perf_counter()
            ds = sc.measure(pairs[:n], subset_size=41, step=56, strain_window=3)
            dt = time.perf_counter() - t0
        out[f"pairs_{n}"] = {
            "seconds": dt,
            "points": int(ds.sizes["point"]),
            "ok": int((ds.flag.values[-1] == 0).sum()),
        }
    return out


def main() -> None:
    figures: dict = {"threads": 2}
    figures["s_curve"] = {
        f"{size:g}px": {
            g: s_curve(size, g, SHIFTS, size=160)[0].tolist() for g in ("spline", "central")
        }
        for size in (3, 5, 8)
    }
    for v in figures["s_curve"].values():
        for g in ("spline", "central"):
            v[f"{g}_max_abs"] = float(np.max(np.abs(v[g])))
    figures["sigma_2d"] = {f"{s:g}px": sigma_2d(s) for s in (3.0, 5.0)}
    figures["sigma_stereo_static"] = sigma_stereo()
    figures["speed_1920x1200"] = speed()
    write_results("field", figures)


if __name__ == "__main__":
    main()
