"""Points flagged ok that are wrong, before and after the uncertainty-outlier test
(``python benchmarks/bench_dic_outliers.py``).

The left reference image of DICe's GT4 set (``/work/shared/data/dice-stereo-gt4``, or the
folder in ``JOINTWEAR_GT4``; skipped with a message if absent), 1800 x 940 pixels around the
specimen (its speckle, the hole, the dark surroundings with a faint texture), moved by an exact
sub-pixel shift (Fourier shift of the whole image, then cropped), with 1, 1.5 and 2 grey levels
of Gaussian noise on both images (then 8-bit rounding): 25-pixel subsets every 12 pixels, the
whole grid. For each noise level and shift, without the test (``u_outlier_factor=0``) and with
the default factor: the share of ok points off by more than 0.05 pixel, the worst error of an ok
point, and the share of the points that are within 0.05 pixel without the test which the test
flags ("good points flagged"); and, on the matches without the test, the same two shares for
other thresholds on u (multiples of the median with a 0.01 or 0.02 pixel floor, median + k MAD).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from _common import write_results  # noqa: E402

from jointwear.dic import CorrelationParams, correlate  # noqa: E402

GT4 = Path(os.environ.get("JOINTWEAR_GT4", "/work/shared/data/dice-stereo-gt4"))
CROP = (slice(60, 1000), slice(60, 1860))
SHIFTS = ((0.3, -0.45), (-0.7, 0.25))
NOISE = (1.0, 1.5, 2.0)
LIMIT = 0.05


def _pair(image: np.ndarray, shift, noise: float, rng) -> tuple[np.ndarray, np.ndarray]:
    from scipy import ndimage

    dx, dy = shift
    moved = np.fft.ifft2(ndimage.fourier_shift(np.fft.fft2(image), (dy, dx))).real[CROP]
    ref = image[CROP]
    a, b = (np.clip(np.round(f + rng.normal(0, noise, f.shape)), 0, 255) for f in (ref, moved))
    return a.astype(np.uint8), b.astype(np.uint8)


def _case(a, b, shift) -> dict:
    out = {}
    err = {}
    runs = {}
    for name, factor in (("without", 0.0), ("with", CorrelationParams.u_outlier_factor)):
        ds = correlate(a, b, subset_size=25, step=12, u_outlier_factor=factor)
        runs[name] = ds
        ok = ds.flag.values == 0
        e = np.hypot(ds.u.values - shift[0], ds.v.values - shift[1])
        err[name] = (ok, e)
        out[name] = {
            "ok_points": int(ok.sum()),
            "share_off_pct": float(100 * (ok & (e > LIMIT)).sum() / ok.sum()),
            "worst_error_px": float(np.nanmax(e[ok])),
        }
    ok0, e0 = err["without"]
    good = ok0 & (e0 <= LIMIT)
    flagged = good & ~err["with"][0]
    out["good_points_flagged_pct"] = float(100 * flagged.sum() / good.sum())
    out["rules"] = _rules(ok0, e0, np.fmax(runs["without"].u_u.values, runs["without"].v_u.values))
    return out


def _rules(ok, e, u) -> dict:
    """Other thresholds on u over the same matches (without the test): per rule, the share of
    good points it flags and of ok points off by more than LIMIT it keeps [%]."""
    good = ok & (e <= LIMIT)
    s = u[ok & np.isfinite(u)]
    med = np.median(s)
    mad = 1.4826 * np.median(np.abs(s - med))
    thresholds = {
        **{
            f"{f:g}x_median_floor_{fl:g}px": max(f * med, fl)
            for f in (3, 3.5, 4)
            for fl in (0.01, 0.02)
        },
        **{f"median_plus_{k}_mad": max(med + k * mad, 0.02) for k in (3, 5, 10, 20)},
    }
    out = {}
    for name, t in thresholds.items():
        fl = ok & (u > t)
        kept = ok & ~fl
        out[name] = {
            "good_flagged_pct": float(100 * (good & fl).sum() / good.sum()),
            "off_kept_pct": float(100 * (kept & (e > LIMIT)).sum() / kept.sum()),
        }
    return out


def main() -> None:
    import cv2

    path = GT4 / "GT4-0000_0.tif"
    if not path.is_file():
        print(f"bench_dic_outliers: {path} not found (set JOINTWEAR_GT4): skipped")
        return
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED).astype(float)
    rng = np.random.default_rng(0)
    cases = {}
    for noise in NOISE:
        for shift in SHIFTS:
            key = f"noise_{noise:g}gl_shift_{shift[0]:g}_{shift[1]:g}"
            cases[key] = _case(*_pair(image, shift, noise, rng), shift)
            print(key, cases[key])
    figures = {
        "set": f"{path.name} crop rows {CROP[0].start}-{CROP[0].stop}, columns "
        f"{CROP[1].start}-{CROP[1].stop}; subset 25, step 12; off = error > {LIMIT} px",
        "u_outlier_factor": CorrelationParams.u_outlier_factor,
        "cases": cases,
        "share_off_pct_without_max": max(c["without"]["share_off_pct"] for c in cases.values()),
        "share_off_pct_with_max": max(c["with"]["share_off_pct"] for c in cases.values()),
        "good_points_flagged_pct_max": max(c["good_points_flagged_pct"] for c in cases.values()),
        "good_points_flagged_pct_min": min(c["good_points_flagged_pct"] for c in cases.values()),
        # other rules on u, worst case over the six: (good points flagged, off points kept) [%]
        "rules_worst": {
            rule: {
                q: max(c["rules"][rule][q] for c in cases.values())
                for q in ("good_flagged_pct", "off_kept_pct")
            }
            for rule in next(iter(cases.values()))["rules"]
        },
    }
    write_results("dic_outliers", figures)


if __name__ == "__main__":
    main()
