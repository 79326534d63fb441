"""Reference subsets of the IC-GN (numba): loading values and gradients, invalid-pixel boxes,
texture, and the Gauss-Newton standard uncertainty."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from jointwear.dic.icgn._flags import FLAG_INVALID_PIXELS, FLAG_NO_TEXTURE, FLAG_OK, FLAG_OUTSIDE
from jointwear.dic.icgn._interp import (
    PAD,
    interp_value,
    node_filters,
    node_row_sums,
)


@njit(cache=True)
def _box_has_invalid(integral, x0, y0, x1, y1):
    """True if any invalid pixel in [x0, x1] x [y0, y1] (integral image of invalid counts;
    a (1, 1) table means that every pixel is valid)."""
    if integral.shape[0] == 1:
        return False
    h = integral.shape[0] - 1
    w = integral.shape[1] - 1
    if x0 < 0:
        x0 = 0
    if y0 < 0:
        y0 = 0
    if x1 > w - 1:
        x1 = w - 1
    if y1 > h - 1:
        y1 = h - 1
    s = integral[y1 + 1, x1 + 1] - integral[y0, x1 + 1] - integral[y1 + 1, x0] + integral[y0, x0]
    return s > 0


#: fastmath without no-NaN/no-inf assumptions: sums may be reassociated (vectorised)
_FM = {"nsz", "arcp", "contract", "reassoc"}


@njit(cache=True, fastmath=_FM)
def _centre(f, n):
    """Subtract the mean of ``f[:n]`` in place and return the norm of the result. The sums
    are vectorised (reassociated): each is a chain of ``n`` additions otherwise, whose latency
    was a third of a subset's set-up; the same numbers to rounding (1e-16 relative)."""
    fm = 0.0
    for k in range(n):
        fm += f[k]
    fm /= n
    fn = 0.0
    for k in range(n):
        f[k] -= fm
        fn += f[k] * f[k]
    return math.sqrt(fn)


@njit(cache=True)
def _load_reference(
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    order,
    xc,
    yc,
    half,
    min_std,
    border,
    f,
    gx,
    gy,
    w,
):
    """Reference subset values (zero-mean, into ``f``) and gradients. Returns (flag, fn)."""
    H, W = ref_img.shape
    size = 2 * half + 1
    n = size * size
    if not math.isfinite(xc) or not math.isfinite(yc):
        return FLAG_INVALID_PIXELS, 0.0
    if (
        xc - half < border
        or yc - half < border
        or xc + half > W - 1 - border
        or yc + half > H - 1 - border
    ):
        return FLAG_OUTSIDE, 0.0
    x0 = int(math.floor(xc)) - half - 1
    y0 = int(math.floor(yc)) - half - 1
    if _box_has_invalid(ref_invalid, x0, y0, x0 + size + 2, y0 + size + 2):
        return FLAG_INVALID_PIXELS, 0.0
    k = 0
    if xc == math.floor(xc) and yc == math.floor(yc):
        ic = int(xc)
        jc = int(yc)
        for r in range(-half, half + 1):
            for c in range(-half, half + 1):
                f[k] = ref_img[jc + r, ic + c]
                gx[k] = ref_gx[jc + r, ic + c]
                gy[k] = ref_gy[jc + r, ic + c]
                k += 1
    else:
        # off the pixel grid: the values and the central differences of the interpolant (the
        # node gradients are central differences of the pixels, see jointwear.dic.icgn._interp)
        for r in range(-half, half + 1):
            for c in range(-half, half + 1):
                x = xc + c
                y = yc + r
                f[k] = interp_value(ref_coef, order, x, y, w[0], w[1])
                gx[k] = 0.5 * (
                    interp_value(ref_coef, order, x + 1.0, y, w[0], w[1])
                    - interp_value(ref_coef, order, x - 1.0, y, w[0], w[1])
                )
                gy[k] = 0.5 * (
                    interp_value(ref_coef, order, x, y + 1.0, w[0], w[1])
                    - interp_value(ref_coef, order, x, y - 1.0, w[0], w[1])
                )
                k += 1
    fn = _centre(f, n)
    if fn <= min_std * math.sqrt(n):
        return FLAG_NO_TEXTURE, fn
    return FLAG_OK, fn


@njit(cache=True)
def _store_sigma(w, fn, zncc, n, n_params, hinv_u, hinv_v):
    """Standard uncertainty of u and v from the residual (Gauss-Newton covariance
    ``s2 H^-1``, ``s2 = fn^2 ZNSSD / (n - n_params)`` in reference grey levels), kept in the
    scratch ``w[3, 4:6]``."""
    znssd = max(2.0 * (1.0 - zncc), 0.0)
    s2 = fn * fn * znssd / max(n - n_params, 1)
    w[3, 4] = math.sqrt(s2 * hinv_u)
    w[3, 5] = math.sqrt(s2 * hinv_v)


@njit(cache=True)
def subset_std(img, invalid, centres, half, border):
    """Standard deviation of the reference subset at every centre (NaN: unusable centre)."""
    H, W = img.shape
    n = centres.shape[0]
    out = np.full(n, np.nan)
    size = 2 * half + 1
    # sums over each subset from summed-area tables: O(image + points), not O(points x subset)
    # (integer grey levels sum exactly in float64, as they did pixel by pixel)
    S, S2 = _integrals_finite(img)  # subsets with invalid pixels are skipped
    for i in range(n):
        xc = centres[i, 0]
        yc = centres[i, 1]
        if not (math.isfinite(xc) and math.isfinite(yc)):
            continue
        if xc - half < border or yc - half < border:
            continue
        if xc + half > W - 1 - border or yc + half > H - 1 - border:
            continue
        x0 = int(round(xc)) - half
        y0 = int(round(yc)) - half
        if _box_has_invalid(invalid, x0, y0, x0 + size - 1, y0 + size - 1):
            continue
        s = _box_sum(S, x0, y0, x0 + size, y0 + size)
        s2 = _box_sum(S2, x0, y0, x0 + size, y0 + size)
        m = s / (size * size)
        out[i] = math.sqrt(max(s2 / (size * size) - m * m, 0.0))
    return out


@njit(cache=True)
def _integrals_finite(img):
    """Summed-area tables ``T`` (h + 1, w + 1) of ``img`` and ``img^2``, ``T[y, x] = sum
    a[:y, :x]`` (non-finite pixels as 0), in one pass without temporary arrays."""
    h, w = img.shape
    T = np.empty((h + 1, w + 1))
    T2 = np.empty((h + 1, w + 1))
    for x in range(w + 1):
        T[0, x] = 0.0
        T2[0, x] = 0.0
    for y in range(h):
        T[y + 1, 0] = 0.0
        T2[y + 1, 0] = 0.0
        row = 0.0
        row2 = 0.0
        for x in range(w):
            v = img[y, x]
            if not math.isfinite(v):
                v = 0.0
            row += v
            row2 += v * v
            T[y + 1, x + 1] = T[y, x + 1] + row
            T2[y + 1, x + 1] = T2[y, x + 1] + row2
    return T, T2


@njit(cache=True)
def _kappa_tables(coef, order, gx, gy, x0, y0, x1, y1):
    """Summed-area tables over the box ``[x0, x1) x [y0, y1)`` of ``|g_c|^2``, ``g_c . g_s``
    (0 where either is not finite) and of the count of such nodes, ``g_s`` the interpolant's
    exact node derivative (:func:`~jointwear.dic.icgn._interp._node_gradients`' sums, the
    same numbers) computed on the fly: one pass, no box-sized temporaries but the x-filtered
    rows."""
    val, der = node_filters(order)
    r = val.shape[0] // 2
    bh = y1 - y0
    bw = x1 - x0
    # along x first (value and derivative filters) on the box's rows -r..bh+r; every loop
    # runs over a row's nodes (vectorised), each sum in the order of node_row_sums
    tv = np.zeros((bh + 2 * r, bw))
    td = np.zeros((bh + 2 * r, bw))
    for i in range(bh + 2 * r):
        row = coef[y0 + i + PAD - r]
        tvi = tv[i]
        tdi = td[i]
        for b in range(2 * r + 1):
            vb = val[b]
            db = der[b]
            j0 = x0 + PAD - r + b
            for j in range(bw):
                cv = row[j0 + j]
                tvi[j] += vb * cv
                tdi[j] += db * cv
    A = np.empty((bh + 1, bw + 1))
    B = np.empty((bh + 1, bw + 1))
    N = np.empty((bh + 1, bw + 1))
    for x in range(bw + 1):
        A[0, x] = 0.0
        B[0, x] = 0.0
        N[0, x] = 0.0
    sx = np.empty(bw)
    sy = np.empty(bw)
    for i in range(bh):
        sx[:] = 0.0
        sy[:] = 0.0
        for a in range(2 * r + 1):
            va = val[a]
            da = der[a]
            tda = td[i + a]
            tva = tv[i + a]
            for j in range(bw):
                sx[j] += va * tda[j]
                sy[j] += da * tva[j]
        A[i + 1, 0] = 0.0
        B[i + 1, 0] = 0.0
        N[i + 1, 0] = 0.0
        ra = 0.0
        rb = 0.0
        rn = 0.0
        gxi = gx[y0 + i]
        gyi = gy[y0 + i]
        for j in range(bw):
            cx = gxi[x0 + j]
            cy = gyi[x0 + j]
            pa = cx * cx + cy * cy
            pb = cx * sx[j] + cy * sy[j]
            if math.isfinite(pa) and math.isfinite(pb):
                ra += pa
                rb += pb
            else:
                rn += 1.0
            A[i + 1, j + 1] = A[i, j + 1] + ra
            B[i + 1, j + 1] = B[i, j + 1] + rb
            N[i + 1, j + 1] = N[i, j + 1] + rn
    return A, B, N


@njit(cache=True, inline="always")
def _box_sum(T, x0, y0, x1, y1):
    """Sum of the table's array over ``[y0, y1) x [x0, x1)``."""
    return T[y1, x1] - T[y0, x1] - T[y1, x0] + T[y0, x0]


@njit(cache=True, inline="always")
def _node_derivative(coef, x, y, val, der, r):
    """The interpolant's exact derivative ``(d/dx, d/dy)`` at the pixel node (x, y), summed
    as :func:`~jointwear.dic.icgn._interp._node_gradients` sums it (the same numbers)."""
    sx = 0.0
    sy = 0.0
    for p in range(2 * r + 1):
        vv, vd = node_row_sums(coef[y + PAD - r + p], x + PAD - r, val, der)
        sx += val[p] * vd
        sy += der[p] * vv
    return sx, sy


@njit(cache=True, inline="always")
def _square(centres, i, half, w, h):
    """Columns ``[xa, xb)`` and rows ``[ya, yb)`` of subset ``i``'s square, clipped to the
    ``h`` x ``w`` image (empty for a NaN centre)."""
    xc = centres[i, 0]
    yc = centres[i, 1]
    if not (math.isfinite(xc) and math.isfinite(yc)):
        return 0, 0, 0, 0
    ic = int(round(xc))
    jc = int(round(yc))
    return max(ic - half, 0), min(ic + half + 1, w), max(jc - half, 0), min(jc + half + 1, h)


@njit(cache=True)
def subset_kappa(coef, order, gx, gy, centres, half, out):
    """Per subset, ``kappa = sum |g_c|^2 / sum g_c . g_s``: central-difference node gradients
    ``gx``, ``gy`` against the interpolant's exact node derivative ``g_s`` (from the padded
    coefficients), over the subset square around each centre (1 where undefined).

    Where the subsets together cover more nodes than the box around them has (a dense grid:
    every node lies in many subsets), ``g_s`` is computed once per node of that box and the
    subsets' sums are read from summed-area tables of ``|g_c|^2`` and ``g_c . g_s`` (O(box +
    points) instead of O(points x subset)); otherwise (scattered points) per subset node. Both
    give the same numbers to rounding (1e-12 relative).
    """
    val, der = node_filters(order)
    r = val.shape[0] // 2
    h, w = gx.shape
    # the box [x0, x1) x [y0, y1) the subset squares cover
    x0, y0, x1, y1 = w, h, 0, 0
    for i in range(centres.shape[0]):
        xa, xb, ya, yb = _square(centres, i, half, w, h)
        if xb > xa and yb > ya:
            x0, x1, y0, y1 = min(x0, xa), max(x1, xb), min(y0, ya), max(y1, yb)
    box = max(x1 - x0, 0) * max(y1 - y0, 0)
    dense = box > 0 and centres.shape[0] * (2 * half + 1) ** 2 > box
    if dense:
        # per-subset sums from summed-area tables of the two products (O(box + points)); a
        # subset holding a non-finite product keeps kappa 1
        A, B, N = _kappa_tables(coef, order, gx, gy, x0, y0, x1, y1)
        for i in range(centres.shape[0]):
            out[i] = 1.0
            xa, xb, ya, yb = _square(centres, i, half, w, h)
            if xb <= xa or yb <= ya:
                continue
            xa, xb, ya, yb = xa - x0, xb - x0, ya - y0, yb - y0
            a = _box_sum(A, xa, ya, xb, yb)
            b = _box_sum(B, xa, ya, xb, yb)
            if _box_sum(N, xa, ya, xb, yb) == 0.0 and b > 0.0 and math.isfinite(a / b):
                out[i] = a / b
        return
    for i in range(centres.shape[0]):
        out[i] = 1.0
        xa, xb, ya, yb = _square(centres, i, half, w, h)
        a = 0.0
        b = 0.0
        for y in range(ya, yb):
            for x in range(xa, xb):
                sx, sy = _node_derivative(coef, x, y, val, der, r)
                a += gx[y, x] * gx[y, x] + gy[y, x] * gy[y, x]
                b += gx[y, x] * sx + gy[y, x] * sy
        if b > 0.0 and math.isfinite(a / b):
            out[i] = a / b
