"""Points flagged ok that are wrong, before and after the outlier tests
(``python benchmarks/bench_dic_outliers.py``).

The left reference image of DICe's GT4 set (``/work/shared/data/dice-stereo-gt4``, or the
folder in ``JOINTWEAR_GT4``; skipped with a message if absent), 1800 x 940 pixels around the
specimen (its speckle, the hole, the dark surroundings with a faint texture), moved by an exact
sub-pixel shift (Fourier shift of the whole image, then cropped), with 1, 1.5 and 2 grey levels
of Gaussian noise on both images (then 8-bit rounding): 25-pixel subsets every 12 pixels, the
whole grid. For each noise level and shift, without the tests (both factors 0), with the
defaults (neighbour test and u test) and with the u test alone (the previous default): the
share of ok points off by more than 0.05 pixel, the worst error of an ok point, and the share
of the points that are within 0.05 pixel without the tests which the tests flag ("good points
flagged"); and, on the matches without the tests, the same two shares for other rules: on u
alone (multiples of the median with a 0.01 or 0.02 pixel floor, median + k MAD), the neighbour
test at other factors, and the normalised median test of Westerweel & Scarano (2005, Exp.
Fluids 39:1096), ``|d - d_m| / (r_m + eps) > 2`` per component with ``r_m`` the neighbours'
median residual.

Real deformation must not be taken for outliers: the same image warped by smooth fields
(a homogeneous 1 % strain with a shift; a quadratic bending field; quintic-spline
resampling, the truth at the reference points) with 1 and 2 grey levels of noise, and the
sinusoids of the speckle accuracy tests (exact truth; one of 12 % strain amplitude over a
120-pixel wavelength): good points flagged and off points kept by the defaults and by the u
test alone.
"""

from __future__ import annotations

import os
import sys
import warnings
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


RUNS = {
    "without": dict(u_outlier_factor=0, neighbour_outlier_factor=0),
    "with": {},  # the defaults
    "u_only": dict(neighbour_outlier_factor=0),  # the previous default
}
KW = dict(subset_size=25, step=12)


def _shares(ok0, e, ok) -> dict:
    """Share of ok points off by more than LIMIT, worst error, good points flagged [%]."""
    good = ok0 & (e <= LIMIT)
    return {
        "ok_points": int(ok.sum()),
        "share_off_pct": float(100 * (ok & (e > LIMIT)).sum() / ok.sum()),
        "worst_error_px": float(np.nanmax(e[ok])),
        "good_flagged_pct": float(100 * (good & ~ok).sum() / good.sum()),
    }


def _case(a, b, truth) -> dict:
    """``truth(x, y) -> (u, v)`` at the reference points [pixel]."""
    runs = {name: correlate(a, b, **KW, **kw) for name, kw in RUNS.items()}
    ds = runs["without"]
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    tu, tv = truth(X, Y)
    e = np.hypot(ds.u.values - tu, ds.v.values - tv)
    ok0 = ds.flag.values == 0
    out = {name: _shares(ok0, e, r.flag.values == 0) for name, r in runs.items()}
    out["good_points_flagged_pct"] = out["with"]["good_flagged_pct"]
    out["rules"] = _rules(ds, ok0, e)
    return out


def _arrays(ds):
    """The matches of a grid result as the flag test takes them."""
    from jointwear.dic.icgn._flags import AFFINE_INDEX

    n = ds.u.size
    P = np.zeros((n, 12))
    for k, name in zip(AFFINE_INDEX, ("u", "du_dx", "du_dy", "v", "dv_dx", "dv_dy"), strict=True):
        P[:, k] = ds[name].values.ravel()
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    index = np.indices(ds.u.shape).reshape(2, -1).T
    sigma = np.stack([ds.u_u.values.ravel(), ds.v_u.values.ravel()], axis=-1)
    return P, np.column_stack([X.ravel(), Y.ravel()]), index, sigma


def _normalised_median(ds, ok, eps: float) -> np.ndarray:
    """Westerweel & Scarano (2005): ``max over (u, v) of |d - d_m| / (r_m + eps) > 2`` over
    the 8 next grid neighbours (ok ones), ``r_m`` the median of their ``|d_j - d_m|``."""
    pad = 1
    r = np.zeros(ok.shape)
    for name in ("u", "v"):
        D = np.pad(np.where(ok, ds[name].values, np.nan), pad, constant_values=np.nan)
        ny, nx = ok.shape
        S = np.array(
            [
                D[pad + dy : pad + dy + ny, pad + dx : pad + dx + nx]
                for dy in (-1, 0, 1)
                for dx in (-1, 0, 1)
                if dy or dx
            ]
        )
        with warnings.catch_warnings():  # points without an ok neighbour: All-NaN slices
            warnings.simplefilter("ignore", RuntimeWarning)
            m = np.nanmedian(S, axis=0)
            rm = np.nanmedian(np.abs(S - m), axis=0)
        r = np.fmax(r, np.abs(ds[name].values - m) / (rm + eps))
    return ok & (np.nan_to_num(r) > 2)


def _rules(ds, ok, e) -> dict:
    """Other rules over the same matches (without the tests): per rule, the share of good
    points it flags and of ok points off by more than LIMIT it keeps [%]."""
    from jointwear.dic.icgn._flags import flag_uncertainty_outliers

    u = np.fmax(ds.u_u.values, ds.v_u.values)
    good = ok & (e <= LIMIT)
    s = u[ok & np.isfinite(u)]
    med = np.median(s)
    mad = 1.4826 * np.median(np.abs(s - med))
    flags = {
        **{
            f"{f:g}x_median_floor_{fl:g}px": ok & (u > max(f * med, fl))
            for f in (3, 3.5, 4)
            for fl in (0.01, 0.02)
        },
        **{f"median_plus_{k}_mad": ok & (u > max(med + k * mad, 0.02)) for k in (3, 5, 10, 20)},
    }
    P, centres, index, sigma = _arrays(ds)
    flag = ds.flag.values.ravel()
    for k in (3, 4, 5, 6):
        new = flag_uncertainty_outliers(
            flag, sigma, CorrelationParams.u_outlier_factor, P=P, centres=centres, index=index,
            neighbour_factor=k,
        )  # fmt: skip
        flags[f"neighbour_{k:g}x_median"] = ok & (new.reshape(ok.shape) != 0)
    for eps_name, eps in (("2x_median_u", 2 * med), ("0.01px", 0.01), ("0.02px", 0.02)):
        flags[f"normalised_median_eps_{eps_name}"] = _normalised_median(ds, ok, eps)
    out = {}
    for name, fl in flags.items():
        kept = ok & ~fl
        out[name] = {
            "good_flagged_pct": float(100 * (good & fl).sum() / good.sum()),
            "off_kept_pct": float(100 * (kept & (e > LIMIT)).sum() / kept.sum()),
        }
    return out


def _warped(image: np.ndarray, field) -> np.ndarray:
    """``image`` deformed by ``field(x, y) -> (u, v)`` [pixel, reference points]: the deformed
    image at y holds the reference at X with X + u(X) = y (fixed point), quintic B-spline."""
    from scipy import ndimage

    coef = ndimage.spline_filter(image, order=5)
    Yg, Xg = np.mgrid[0 : image.shape[0], 0 : image.shape[1]].astype(float)
    X, Y = Xg.copy(), Yg.copy()
    for _ in range(20):
        fu, fv = field(X, Y)
        X, Y = Xg - fu, Yg - fv
    return ndimage.map_coordinates(coef, [Y, X], order=5, prefilter=False)


#: smooth fields on the full image's coordinates [pixel] -> (u, v) [pixel]
FIELDS = {
    "strain_1pct": lambda x, y: (0.3 + 0.01 * (x - 960), -0.45 - 0.003 * (y - 530)),
    "bending": lambda x, y: (
        0.3 + 2e-6 * (x - 960) ** 2 - 1e-5 * (y - 530) * (x - 960),
        -0.2 + 3e-6 * (x - 960) ** 2 + 1e-6 * (y - 530) ** 2,
    ),
}


#: smooth speckle fields of the accuracy tests (jointwear.datasets.speckle, exact truth):
#: name -> (field, image shape, noise [grey levels], shape function); 21-pixel subsets every
#: 6 pixels (the compared neighbours 12 pixels apart)
def _speckle_fields():
    from jointwear.datasets import speckle as sp

    wave = sp.SinusoidalField((1.0, 0.5), 300.0)  # 1.2 % strain amplitude
    sharp = sp.SinusoidalField((2.0, 1.0), 120.0)  # 12 % strain amplitude
    return {
        "wave_300px_1gl": (wave, (300, 400), 1.0, "affine"),
        "wave_120px_0gl_quadratic": (sharp, (256, 256), 0.0, "quadratic"),
        "wave_120px_2gl_quadratic": (sharp, (256, 256), 2.0, "quadratic"),
    }


def _speckle_case(field, shape, noise, shape_function) -> dict:
    from jointwear.datasets import speckle as sp

    prm = sp.SpeckleParams(noise_std=noise) if noise else sp.SpeckleParams()
    pair = sp.speckle_pair(shape, field, params=prm, seed=4)
    kw = dict(subset_size=21, step=6, shape=shape_function)
    runs = {name: correlate(pair.reference, pair.deformed, **kw, **r) for name, r in RUNS.items()}
    ds = runs["without"]
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    tu, tv = pair.truth(X, Y)
    e = np.hypot(ds.u.values - tu, ds.v.values - tv)
    ok0 = ds.flag.values == 0
    return {name: _shares(ok0, e, r.flag.values == 0) for name, r in runs.items()}


def _noisy(ref, moved, noise, rng):
    a, b = (np.clip(np.round(f + rng.normal(0, noise, f.shape)), 0, 255) for f in (ref, moved))
    return a.astype(np.uint8), b.astype(np.uint8)


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
            a, b = _pair(image, shift, noise, rng)
            cases[key] = _case(a, b, lambda x, y, s=shift: (np.full_like(x, s[0]), s[1] + 0 * y))
            print(key, {k: cases[key][k] for k in RUNS}, flush=True)
    y0, x0 = CROP[0].start, CROP[1].start
    deformed = {}
    for name, field in FIELDS.items():
        moved = _warped(image, field)[CROP]
        for noise in (1.0, 2.0):
            key = f"{name}_noise_{noise:g}gl"
            a, b = _noisy(image[CROP], moved, noise, rng)
            c = _case(a, b, lambda x, y, f=field: f(x + x0, y + y0))
            deformed[key] = {k: c[k] for k in RUNS}
            print(key, deformed[key], flush=True)

    gt4_deformed = dict(deformed)
    for name, args in _speckle_fields().items():
        deformed[name] = _speckle_case(*args)
        print(name, deformed[name], flush=True)

    def worst(group, run, q, how=max):
        return how(c[run][q] for c in group.values())

    figures = {
        "set": f"{path.name} crop rows {CROP[0].start}-{CROP[0].stop}, columns "
        f"{CROP[1].start}-{CROP[1].stop}; subset 25, step 12; off = error > {LIMIT} px",
        "u_outlier_factor": CorrelationParams.u_outlier_factor,
        "neighbour_outlier_factor": CorrelationParams.neighbour_outlier_factor,
        "cases": cases,
        "share_off_pct_without_max": worst(cases, "without", "share_off_pct"),
        "share_off_pct_without_min": worst(cases, "without", "share_off_pct", min),
        "share_off_pct_with_max": worst(cases, "with", "share_off_pct"),
        "good_points_flagged_pct_max": worst(cases, "with", "good_flagged_pct"),
        "good_points_flagged_pct_min": worst(cases, "with", "good_flagged_pct", min),
        "u_only": {
            "share_off_pct_max": worst(cases, "u_only", "share_off_pct"),
            "good_points_flagged_pct_max": worst(cases, "u_only", "good_flagged_pct"),
            "good_points_flagged_pct_min": worst(cases, "u_only", "good_flagged_pct", min),
        },
        # other rules, worst case over the six: (good points flagged, off points kept) [%]
        "rules_worst": {
            rule: {
                q: max(c["rules"][rule][q] for c in cases.values())
                for q in ("good_flagged_pct", "off_kept_pct")
            }
            for rule in next(iter(cases.values()))["rules"]
        },
        "deformed": deformed,
        # the GT4 warps (the speckle fields are in "deformed" each)
        "deformed_worst": {
            run: {
                "good_flagged_pct": worst(gt4_deformed, run, "good_flagged_pct"),
                "share_off_pct": worst(gt4_deformed, run, "share_off_pct"),
            }
            for run in RUNS
        },
    }
    write_results("dic_outliers", figures)


if __name__ == "__main__":
    main()
