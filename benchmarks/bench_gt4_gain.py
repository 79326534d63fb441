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
3. The interpolant alone: a translation-only ZNSSD subset match (the uniform sub-pixel shift
   minimising the ZNSSD, by grids of shifts and quadratic fits: no solver of either code) with
   DICe's interpolant (Keys' 6-point fourth-order kernel, ``KEYS_FOURTH`` in its params.xml)
   and with jointwear's (quintic B-spline), on the known set (against the truth) and on the
   real pair (against DICe's solution).
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
    lo = (pts.min(axis=0) - 40).astype(int)
    hi = (pts.max(axis=0) + 41).astype(int)
    crop = (slice(lo[1], hi[1]), slice(lo[0], hi[0]))
    out["_data"] = ((a[crop].astype(float), b[crop].astype(float)), pts - lo, d)
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
        if interp == "quintic":  # the points and their truth for the interpolant-alone reading
            ok0 = ds.flag.values[1] == 0
            P = ds.position.values[ok0]
            t_px = cam.project(P + motion.displacement(P[:, 0], P[:, 1])) - cam.project(P)
            centres = np.column_stack([ds.subset_x.values[0, 0], ds.subset_y.values[0, 0]])[ok0]
            out["_data"] = ((pairs[0][0], pairs[1][0]), centres, t_px)
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


def _keys6(s: np.ndarray) -> np.ndarray:
    """Keys' (1981) fourth-order, 6-point cubic convolution kernel (DICe's ``KEYS_FOURTH``)."""
    a = np.abs(s)
    w = np.zeros_like(a)
    m = a < 1
    w[m] = 4 / 3 * a[m] ** 3 - 7 / 3 * a[m] ** 2 + 1
    m = (a >= 1) & (a < 2)
    w[m] = -7 / 12 * a[m] ** 3 + 3 * a[m] ** 2 - 59 / 12 * a[m] + 15 / 6
    m = (a >= 2) & (a < 3)
    w[m] = 1 / 12 * a[m] ** 3 - 2 / 3 * a[m] ** 2 + 21 / 12 * a[m] - 3 / 2
    return w


def _shift(img: np.ndarray, u: float, v: float, kernel: str) -> np.ndarray:
    """``img`` sampled at ``(x + u, y + v)``: Keys 6-point (separable) or quintic B-spline."""
    if kernel == "bspline5":
        from scipy import ndimage

        return ndimage.shift(img, (-v, -u), order=5, mode="mirror")
    out = img
    for axis, d in ((1, u), (0, v)):
        k = int(np.floor(d))
        taps = np.arange(-2, 4)
        acc = np.zeros_like(out)
        for t, wt in zip(taps, _keys6(d - k - taps), strict=True):
            acc += wt * np.roll(out, -(k + t), axis=axis)
        out = acc
    return out


def _znssd(ref: np.ndarray, cur: np.ndarray, pts: np.ndarray, half: int) -> np.ndarray:
    out = np.empty(len(pts))
    for i, (x, y) in enumerate(pts.astype(int)):
        f = ref[y - half : y + half + 1, x - half : x + half + 1].ravel()
        g = cur[y - half : y + half + 1, x - half : x + half + 1].ravel()
        f = (f - f.mean()) / np.linalg.norm(f - f.mean())
        g = (g - g.mean()) / np.linalg.norm(g - g.mean())
        out[i] = ((f - g) ** 2).sum()
    return out


def translation_reading(ref, cur, pts, kernel: str, half: int = 12) -> np.ndarray:
    """Per point the uniform shift (u, v) [pixel] minimising the ZNSSD of a translation-only
    subset match with interpolant ``kernel``: three rounds of a 9 x 9 grid of shifts around the
    median estimate, each fitted by a quadratic per point (what an interpolant alone does to
    a sub-pixel reading, independent of any solver)."""
    ref, cur = np.asarray(ref, float), np.asarray(cur, float)
    cu, cv, span, n = MOTION_PX[0], MOTION_PX[1], 0.04, 9
    for _ in range(3):
        us, vs = cu + np.linspace(-span, span, n), cv + np.linspace(-span, span, n)
        cost = np.array(
            [[_znssd(ref, _shift(cur, u, v, kernel), pts, half) for v in vs] for u in us]
        )
        U, V = (g.ravel() for g in np.meshgrid(us, vs, indexing="ij"))
        A = np.column_stack([np.ones(n * n), U, V, U * U, U * V, V * V])
        _, b, c, d, e, f = np.linalg.lstsq(A, cost.reshape(n * n, -1), rcond=None)[0]
        det = 4 * d * f - e * e
        est = np.column_stack([(-2 * f * b + e * c) / det, (-2 * d * c + e * b) / det])
        cu, cv = np.median(est, axis=0)
        span /= 4
    return est


def interpolant_alone(known_pair, known_truth_px, real) -> dict:
    """The translation-only reading of the known GT4-like motion and of the real GT4 pair with
    DICe's interpolant (Keys 6-point) and jointwear's (quintic B-spline)."""
    out: dict = {}
    (a, b), pts = known_pair
    for kernel in ("keys6", "bspline5"):
        est = translation_reading(a, b, pts, kernel)
        out[f"known_{kernel}_gain"] = _gain(est, known_truth_px)
        print(kernel, "known", out[f"known_{kernel}_gain"], flush=True)
    if real is not None:
        (a, b), pts, dice = real
        for kernel in ("keys6", "bspline5"):
            est = translation_reading(a, b, pts, kernel)
            out[f"real_{kernel}_gain_vs_dice"] = _gain(est, dice)
            print(kernel, "real", out[f"real_{kernel}_gain_vs_dice"], flush=True)
    return out


def _figure(figures: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 3.8))
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
    alone = figures["interpolant_alone"]
    rows.append(("translation-only, Keys 6 (DICe's) / truth", alone["known_keys6_gain"]))
    if "real_keys6_gain_vs_dice" in alone:
        rows.append(("GT4 real: translation-only Keys 6 / DICe", alone["real_keys6_gain_vs_dice"]))
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
    real_data = real.pop("_data") if real is not None else None
    if real is not None:
        figures["real_gt4"] = real
        print("real", real, flush=True)
    known = known_translation()
    (pair, centres, t_px) = known.pop("_data")
    figures["known"] = known
    print("known", figures["known"], flush=True)
    figures["interpolant_alone"] = interpolant_alone((pair, centres), t_px, real_data)
    _figure(figures)
    write_results("gt4_gain", figures)


if __name__ == "__main__":
    main()
