"""B-spline image interpolation with precomputed, prefiltered coefficients.

An image is turned once into B-spline coefficients (cubic or quintic, mirror boundary, the
recursive prefilter of :func:`scipy.ndimage.spline_filter`), padded by a few mirrored samples so
that the numba kernels never test indices, and its exact interpolant gradient at the pixel nodes
is tabulated. The interpolant passes through every pixel value, so the reference intensities
at integer positions are the pixels themselves.

Kernels (numba, ``cache=True``): :func:`interp_value` evaluates the spline at one position
[pixel, x = column, y = row]; :func:`interp_value_grad` also returns the two derivatives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["SplineImage", "prefilter", "interp_value", "interp_value_grad", "PAD"]

#: mirrored coefficients added on every side (quintic needs 3 beyond the last node)
PAD = 4

_ORDERS = {"cubic": 3, "quintic": 5}


@dataclass(frozen=True)
class SplineImage:
    """An image ready for sub-pixel interpolation.

    Attributes
    ----------
    image : ndarray (H, W) float64
        The pixel values (NaN where invalid).
    coef : ndarray (H + 2 PAD, W + 2 PAD) float64
        Prefiltered B-spline coefficients, mirror-padded by :data:`PAD`.
    gx, gy : ndarray (H, W) float64
        Derivatives of the interpolant at the pixel nodes [grey level / pixel].
    order : int
        3 (cubic) or 5 (quintic).
    valid : ndarray (H, W) bool
        Finite pixels.
    """

    image: np.ndarray
    coef: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    order: int
    valid: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        return self.image.shape  # type: ignore[return-value]


def prefilter(image: np.ndarray, interpolation: str = "cubic") -> SplineImage:
    """Compute B-spline coefficients and node gradients of ``image`` (done once per image).

    Non-finite pixels are replaced by the image mean for the prefilter (their neighbourhood is
    flagged by the correlation, never trusted).
    """
    from scipy import ndimage

    order = _ORDERS[interpolation]
    img = np.asarray(image, dtype=np.float64)
    valid = np.isfinite(img)
    work = img if valid.all() else np.where(valid, img, np.nanmean(img) if valid.any() else 0.0)
    coef = ndimage.spline_filter(work, order=order, mode="mirror", output=np.float64)
    coef = np.ascontiguousarray(np.pad(coef, PAD, mode="reflect"))
    gx, gy = _node_gradients(coef, order, img.shape[0], img.shape[1])
    return SplineImage(
        image=np.ascontiguousarray(img), coef=coef, gx=gx, gy=gy, order=order, valid=valid
    )


def _node_gradients(coef: np.ndarray, order: int, h: int, w: int):
    if order == 3:
        val = np.array([1.0, 4.0, 1.0]) / 6.0
        der = np.array([-0.5, 0.0, 0.5])
    else:
        val = np.array([1.0, 26.0, 66.0, 26.0, 1.0]) / 120.0
        der = np.array([-1.0, -10.0, 0.0, 10.0, 1.0]) / 24.0
    r = len(val) // 2
    c = coef[PAD - r : PAD + h + r, PAD - r : PAD + w + r]
    # separable: derivative along x, value along y (and vice versa)
    tx = sum(der[k] * c[:, k : k + w] for k in range(len(der)))
    gx = sum(val[k] * tx[k : k + h, :] for k in range(len(val)))
    ty = sum(val[k] * c[:, k : k + w] for k in range(len(val)))
    gy = sum(der[k] * ty[k : k + h, :] for k in range(len(der)))
    return np.ascontiguousarray(gx), np.ascontiguousarray(gy)


@njit(cache=True, inline="always")
def _weights3(t, w):
    t2 = t * t
    t3 = t2 * t
    s = 1.0 - t
    w[0] = s * s * s / 6.0
    w[1] = (4.0 - 6.0 * t2 + 3.0 * t3) / 6.0
    w[2] = (1.0 + 3.0 * t + 3.0 * t2 - 3.0 * t3) / 6.0
    w[3] = t3 / 6.0


@njit(cache=True, inline="always")
def _dweights3(t, d):
    t2 = t * t
    s = 1.0 - t
    d[0] = -0.5 * s * s
    d[1] = (-12.0 * t + 9.0 * t2) / 6.0
    d[2] = (3.0 + 6.0 * t - 9.0 * t2) / 6.0
    d[3] = 0.5 * t2


@njit(cache=True, inline="always")
def _weights5(t, w):
    t2 = t * t
    t3 = t2 * t
    t4 = t3 * t
    t5 = t4 * t
    s = 1.0 - t
    s2 = s * s
    w[0] = s2 * s2 * s / 120.0
    w[1] = (26.0 - 50.0 * t + 20.0 * t2 + 20.0 * t3 - 20.0 * t4 + 5.0 * t5) / 120.0
    w[2] = (66.0 - 60.0 * t2 + 30.0 * t4 - 10.0 * t5) / 120.0
    w[3] = (26.0 + 50.0 * t + 20.0 * t2 - 20.0 * t3 - 20.0 * t4 + 10.0 * t5) / 120.0
    w[4] = (1.0 + 5.0 * t + 10.0 * t2 + 10.0 * t3 + 5.0 * t4 - 5.0 * t5) / 120.0
    w[5] = t5 / 120.0


@njit(cache=True, inline="always")
def _dweights5(t, d):
    t2 = t * t
    t3 = t2 * t
    t4 = t3 * t
    s = 1.0 - t
    s2 = s * s
    d[0] = -5.0 * s2 * s2 / 120.0
    d[1] = (-50.0 + 40.0 * t + 60.0 * t2 - 80.0 * t3 + 25.0 * t4) / 120.0
    d[2] = (-120.0 * t + 120.0 * t3 - 50.0 * t4) / 120.0
    d[3] = (50.0 + 40.0 * t - 60.0 * t2 - 80.0 * t3 + 50.0 * t4) / 120.0
    d[4] = (5.0 + 20.0 * t + 30.0 * t2 + 20.0 * t3 - 25.0 * t4) / 120.0
    d[5] = 5.0 * t4 / 120.0


@njit(cache=True)
def interp_value(coef, order, x, y, wx, wy):
    """Spline value at (x, y) [pixel]; ``wx``, ``wy`` are scratch arrays of length 6.

    The caller guarantees ``0 <= x <= W - 1`` and ``0 <= y <= H - 1`` (within tolerance).
    """
    ix = int(math.floor(x))
    iy = int(math.floor(y))
    tx = x - ix
    ty = y - iy
    acc = 0.0
    if order == 3:
        _weights3(tx, wx)
        _weights3(ty, wy)
        bx = ix + PAD - 1
        by = iy + PAD - 1
        for r in range(4):
            row = coef[by + r]
            s = wx[0] * row[bx] + wx[1] * row[bx + 1] + wx[2] * row[bx + 2] + wx[3] * row[bx + 3]
            acc += wy[r] * s
    else:
        _weights5(tx, wx)
        _weights5(ty, wy)
        bx = ix + PAD - 2
        by = iy + PAD - 2
        for r in range(6):
            row = coef[by + r]
            s = 0.0
            for c in range(6):
                s += wx[c] * row[bx + c]
            acc += wy[r] * s
    return acc


@njit(cache=True)
def interp_value_grad(coef, order, x, y, wx, wy, dx, dy):
    """Spline value and derivatives ``(f, df/dx, df/dy)`` at (x, y) [pixel]."""
    ix = int(math.floor(x))
    iy = int(math.floor(y))
    tx = x - ix
    ty = y - iy
    if order == 3:
        _weights3(tx, wx)
        _weights3(ty, wy)
        _dweights3(tx, dx)
        _dweights3(ty, dy)
        n = 4
        bx = ix + PAD - 1
        by = iy + PAD - 1
    else:
        _weights5(tx, wx)
        _weights5(ty, wy)
        _dweights5(tx, dx)
        _dweights5(ty, dy)
        n = 6
        bx = ix + PAD - 2
        by = iy + PAD - 2
    f = 0.0
    fx = 0.0
    fy = 0.0
    for r in range(n):
        row = coef[by + r]
        s = 0.0
        sd = 0.0
        for c in range(n):
            s += wx[c] * row[bx + c]
            sd += dx[c] * row[bx + c]
        f += wy[r] * s
        fx += wy[r] * sd
        fy += dy[r] * s
    return f, fx, fy
