"""Where the GT4 gap sits: jointwear against DICe on the real images, and jointwear against an
exact truth on a GT4-like rendered set (``python benchmarks/bench_gt4_gain.py``).

1. Real images (DICe's ``stereo_d_spec`` regression set, ``/work/shared/data/dice-stereo-gt4``
   or ``JOINTWEAR_GT4``; skipped with a message if absent): the left images GT4-0000 / GT4-0005
   correlated by jointwear at DICe's 119 solved subset centres (25-pixel subsets as DICe's
   input), quintic and cubic B-spline; the gain is the least-squares slope of jointwear's
   displacement on DICe's, per axis.
2. A known translation of a GT4-like speckle (the virtual rig's exact texture sampling, speckle
   2.6 pixel footprints: autocorrelation half-width 1.6 pixel as GT4's) seen by the rig's
   stereo pair, moved in-plane by DICe's mean GT4 frame-5 motion in the left image (0.113,
   -0.078 pixel): ``measure_field`` (stereo, 25-pixel subsets), the left-image match
   displacement against the projected truth (gain per axis, quintic and cubic) and the 3D
   displacement against the truth.
Writes ``results/gt4_gain.json`` and the figure ``docs/img/gt4_gain.png``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from _common import write_results  # noqa: E402

GT4 = Path(os.environ.get("JOINTWEAR_GT4", "/work/shared/data/dice-stereo-gt4"))
FIGURE = Path(__file__).resolve().parent.parent / "docs" / "img" / "gt4_gain.png"
MOTION_PX = (0.1128, -0.0777)  # DICe's mean frame-5 displacement, left image [pixel]


def _gain(measured: np.ndarray, truth: np.ndarray) -> list[float]:
    """Least-squares slope through the origin of ``measured`` on ``truth``, per column."""
    ok = np.isfinite(measured).all(axis=1) & np.isfinite(truth).all(axis=1)
    m, t = measured[ok], truth[ok]
    return [round(float(m[:, i] @ t[:, i] / (t[:, i] @ t[:, i])), 4) for i in range(t.shape[1])]


def real_images() -> dict | None:
    import cv2

    from jointwear.dic import correlate, read_field

    if not (GT4 / "GT4-0005_0.tif").is_file():
        print(f"bench_gt4_gain: {GT4} not found (set JOINTWEAR_GT4): real images skipped")
        return None
    files = [GT4 / "DICe_solution_0.txt", GT4 / "DICe_solution_5.txt"]
    dice = read_field(files, format="dice", data_origin="measured")
    ok = dice.flag.values[1] == 0
    pts = np.column_stack([dice.x.values, dice.y.values])[ok]
    d = dice.displacement.values[1][ok]
    a = cv2.imread(str(GT4 / "GT4-0000_0.tif"), cv2.IMREAD_UNCHANGED)
    b = cv2.imread(str(GT4 / "GT4-0005_0.tif"), cv2.IMREAD_UNCHANGED)
    out = {"points": int(ok.sum()), "dice_mean_px": [round(float(v), 4) for v in d.mean(0)]}
    for interp in ("quintic", "cubic"):
        ds = correlate(a, b, points=pts, subset_size=25, interpolation=interp, u_outlier_factor=0)
        j = np.column_stack([ds.u.values, ds.v.values])
        out[interp] = {
            "gain_vs_dice": _gain(j, d),
            "mean_px": [round(float(v), 4) for v in np.nanmean(j, axis=0)],
        }
    return out


def _gt4_like_scene():
    from jointwear.datasets.rig import speckle_texture
    from jointwear.datasets.surface import SurfaceScene

    sc = SurfaceScene(seed=4)
    sc.texture = speckle_texture(sc.texture.shape, sc.texel, 2.6 * sc.rig.pixel_footprint, seed=4)
    from scipy import ndimage

    sc._coef = ndimage.spline_filter(sc.texture.astype(np.float64), order=3, mode="mirror")
    return sc


def known_translation() -> dict:
    from jointwear.datasets.surface import SurfaceMotion
    from jointwear.dic import correlate

    sc = _gt4_like_scene()
    cam = sc.calibration.left
    # the in-plane world motion that moves the left image by MOTION_PX at the patch centre
    centre = np.array([[sc.centre_x, sc.origin[1] + sc.size[1] / 2, 0.0]])
    J = np.column_stack(
        [
            (cam.project(centre + e) - cam.project(centre - e))[0] / 2e-6
            for e in np.eye(3)[:2] * 1e-6
        ]
    )
    u0, v0 = np.linalg.solve(J, np.array(MOTION_PX))
    motion = SurfaceMotion(u0=float(u0), v0=float(v0))
    pairs = [sc.pair(noise_seed=0), sc.pair(motion, noise_seed=1)]
    out: dict = {"speckle_footprints": 2.6, "world_motion_um": [u0 * 1e6, v0 * 1e6]}
    for interp in ("quintic", "cubic"):
        ds = sc.measure(pairs, subset_size=25, step=20, strain_window=0, interpolation=interp)
        ok = ds.flag.values[1] == 0
        P0 = ds.position.values[ok]
        truth3 = motion.displacement(P0[:, 0], P0[:, 1])
        truth_px = cam.project(P0 + truth3) - cam.project(P0)
        sx, sy = ds.subset_x.values, ds.subset_y.values
        left_px = np.column_stack([sx[1, 0] - sx[0, 0], sy[1, 0] - sy[0, 0]])[ok]
        d3 = ds.displacement.values[1][ok]
        out[interp] = {
            "points": int(ok.sum()),
            "left_image_gain": _gain(left_px, truth_px),
            "displacement_gain_xy": _gain(d3[:, :2], truth3[:, :2]),
            "z_error_rms_um": round(
                float(np.sqrt(np.mean((d3[:, 2] - truth3[:, 2]) ** 2))) * 1e6, 3
            ),
        }
        # the same left images as a 2D pair (no stereo): the engine alone
        two = correlate(pairs[0][0], pairs[1][0], subset_size=25, step=20, interpolation=interp)
        X, Y = np.meshgrid(two.x.values, two.y.values)
        sel = two.flag.values == 0
        out[interp]["left_2d_mean_px"] = [
            round(float(two.u.values[sel].mean()), 5),
            round(float(two.v.values[sel].mean()), 5),
        ]
    return out


def _figure(figures: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.2))
    rows = []
    real = figures.get("real_gt4")
    for interp in ("quintic", "cubic"):
        if real:
            rows.append((f"GT4 real: jointwear {interp} / DICe", real[interp]["gain_vs_dice"]))
        rows.append(
            (
                f"GT4-like rig: jointwear {interp} / truth",
                figures["known"][interp]["left_image_gain"],
            )
        )
    for k, (_, g) in enumerate(rows):
        ax.plot([g[0]], [k], "s", color="C0", label="x" if k == 0 else None)
        ax.plot([g[1]], [k], "^", color="C1", label="y" if k == 0 else None)
    ax.axvline(1.0, color="grey", lw=0.8)
    ax.set_yticks(range(len(rows)), [r[0] for r in rows], fontsize=8)
    ax.set_xlabel("gain of the left-image displacement [1]")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("GT4 frame-5 motion (0.11 px): against DICe, and against a truth", fontsize=9)
    fig.tight_layout()
    FIGURE.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(FIGURE, dpi=110)


def main() -> None:
    figures: dict = {"motion_px": list(MOTION_PX), "subset_px": 25}
    real = real_images()
    if real is not None:
        figures["real_gt4"] = real
        print("real", real, flush=True)
    figures["known"] = known_translation()
    print("known", figures["known"], flush=True)
    _figure(figures)
    write_results("gt4_gain", figures)


if __name__ == "__main__":
    main()
