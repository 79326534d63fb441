"""Uncertainty of a match relative to its camera's reference image, sub-pixel pattern
mismatch included (:mod:`jointwear.dic.field._measure`).

The IC-GN's standard uncertainty ``s^2 H^-1`` treats the match residual as white noise of equal
variance at every pixel. That holds between two images of a static specimen (the residual is
the cameras' noise), not once the specimen has moved by a fraction of a pixel: the camera then
samples the speckle at another sub-pixel phase, and the image is no longer a shifted copy of
the reference - the pattern's content above the Nyquist frequency aliases differently, the
B-spline interpolant misses it, the 8-bit quantisation differs. That *pattern mismatch* is
largest on the steep speckle edges, where the image gradient (the Gauss-Newton Jacobian) is
large, so it moves the match more than white noise of the same residual variance would
(noise-free 8-bit speckle on the virtual rig, 25-pixel subsets, quintic: 1.24 / 1.73 mpx RMS
error along the motion at 0.25 / 0.5 pixel of sub-pixel shift, against 1.01 / 1.37 mpx from
``s^2 H^-1``; zero at whole-pixel shifts). It is not the mean S-curve bias of the interpolant
(0.4 mpx here, see :mod:`jointwear.dic.icgn._interp`) but a zero-mean error that differs from
subset to subset with the texture.

The heteroscedasticity-consistent (sandwich) covariance ``H^-1 (sum_i J_i J_i^T r_i^2) H^-1
n / (n - 6)`` weights every pixel's residual ``r_i`` by its own Jacobian ``J_i`` and so counts
the mismatch where it acts; for white noise it equals ``s^2 H^-1``. :func:`relative_sigma`
computes it from the residual between the two images whose difference
the displacement is: the left reference and the current left image (the match itself) and, in
stereo, the right reference and the current right image, each sampled at its match of the left
reference subsets (their common mismatch with the left reference - perspective, surface
curvature - cancels in ``P_k - P_0`` and is left out; the engine's residual against the left
reference includes it and over-stated the static right-image noise 1.3-fold).
"""

from __future__ import annotations

import numpy as np

__all__ = ["relative_sigma", "spline_coefficients"]

_CHUNK = 512  # points per vectorised block (memory: chunk x subset pixels x 6 doubles)


def spline_coefficients(img: np.ndarray, interpolation: str) -> np.ndarray:
    """Prefiltered B-spline coefficients of ``img`` (the engine's spline: mirror boundary)."""
    from scipy import ndimage

    order = 5 if interpolation == "quintic" else 3
    return ndimage.spline_filter(np.asarray(img, np.float64), order=order, mode="mirror")


def _warp(centres, params, dx, dy):
    """Positions (N, n) of the subset pixels (offsets dx, dy) under 12-vector shape params."""
    p = params
    x = (
        centres[:, :1] + dx + p[:, :1] + p[:, 1:2] * dx + p[:, 2:3] * dy
        + 0.5 * p[:, 3:4] * dx**2 + p[:, 4:5] * dx * dy + 0.5 * p[:, 5:6] * dy**2
    )  # fmt: skip
    y = (
        centres[:, 1:] + dy + p[:, 6:7] + p[:, 7:8] * dx + p[:, 8:9] * dy
        + 0.5 * p[:, 9:10] * dx**2 + p[:, 10:11] * dx * dy + 0.5 * p[:, 11:12] * dy**2
    )  # fmt: skip
    return x, y


def relative_sigma(
    ref_coef: np.ndarray,
    centres: np.ndarray,
    subset_size: int,
    pairs: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
    interpolation: str,
) -> list[np.ndarray]:
    """Standard uncertainties (N, 2) [pixel] of u and v of the relative position of two
    matches of the same subsets, from their residual: the sandwich ``H^-1 (sum J J^T r^2) H^-1
    n / (n - 6)`` (see module docstring), without the kappa factor of the central-difference
    gradients.

    ``ref_coef``: spline coefficients of the left reference image (its central differences at
    the subset pixels are the Jacobian, as in the IC-GN, computed once for all ``pairs``);
    ``pairs``: ``(a_coef, a_params, b_coef, b_params)`` per result, two images and their
    matches (N, 12) of the left reference subsets centred at ``centres`` (N, 2). One array per
    pair, NaN where either match is missing.
    """
    from scipy import ndimage

    order = 5 if interpolation == "quintic" else 3
    half = subset_size // 2
    off = np.arange(-half, half + 1, dtype=float)
    dyg, dxg = np.meshgrid(off, off, indexing="ij")
    dx, dy = dxg.ravel()[None], dyg.ravel()[None]
    n = dx.size
    outs = [np.full((len(centres), 2), np.nan) for _ in pairs]

    def sample(coef, x, y):
        v = ndimage.map_coordinates(
            coef, [y.ravel(), x.ravel()], order=order, mode="mirror", prefilter=False
        )
        return v.reshape(x.shape)

    idx = np.flatnonzero(np.isfinite(centres).all(axis=1))
    for s in range(0, len(idx), _CHUNK):
        i = idx[s : s + _CHUNK]
        c = centres[i]
        x0, y0 = c[:, :1] + dx, c[:, 1:] + dy
        gx = 0.5 * (sample(ref_coef, x0 + 1.0, y0) - sample(ref_coef, x0 - 1.0, y0))
        gy = 0.5 * (sample(ref_coef, x0, y0 + 1.0) - sample(ref_coef, x0, y0 - 1.0))
        J = np.stack([gx, gx * dx, gx * dy, gy, gy * dx, gy * dy], axis=-1)  # (m, n, 6)
        H = np.einsum("mki,mkj->mij", J, J)
        good = np.linalg.det(H) > 0
        Hi = np.full_like(H, np.nan)
        Hi[good] = np.linalg.inv(H[good])
        for out, (a_coef, a_params, b_coef, b_params) in zip(outs, pairs, strict=True):
            have = np.isfinite(a_params[i]).all(axis=1) & np.isfinite(b_params[i]).all(axis=1)
            j = i[have]
            fa = sample(a_coef, *_warp(c[have], a_params[j], dx, dy))
            fb = sample(b_coef, *_warp(c[have], b_params[j], dx, dy))
            fa -= fa.mean(axis=1, keepdims=True)
            fb -= fb.mean(axis=1, keepdims=True)
            na = np.sqrt(np.sum(fa**2, axis=1, keepdims=True))
            nb = np.sqrt(np.sum(fb**2, axis=1, keepdims=True))
            r = fb * (na / np.maximum(nb, 1e-12)) - fa
            Jh, Hih = J[have], Hi[have]
            Om = np.einsum("mki,mk,mkj->mij", Jh, r**2, Jh) * (n / (n - 6))
            cov = Hih @ Om @ Hih
            out[j, 0] = np.sqrt(np.maximum(cov[:, 0, 0], 0.0))
            out[j, 1] = np.sqrt(np.maximum(cov[:, 3, 3], 0.0))
    return outs
