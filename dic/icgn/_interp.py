"""B-spline image interpolation with precomputed, prefiltered coefficients.

An image is turned once into B-spline coefficients (cubic or quintic, mirror boundary, the
recursive prefilter of :func:`scipy.ndimage.spline_filter`), padded by a few mirrored samples so
that the numba kernels never test indices, and the image gradient at the pixel nodes is
tabulated as central differences ``(I[x+1] - I[x-1]) / 2`` (mirror boundary). The interpolant
passes through every pixel value, so the reference intensities at integer positions are the
pixels themselves.

Why central differences and not the interpolant's exact derivative: the gradient only enters
the IC-GN through the Gauss-Newton Jacobian, so it sets which weighted residual is driven to
zero. With the exact spline derivative the sub-pixel S-curve bias on noise-free 8-bit speckle
(21-px subsets, shifts 0..1 px, quintic) peaks at 0.0020 px for 3-px speckles and 0.00033 px
for 5-px ones; with central differences at 0.0012 and 0.00022 px (4th/6th-order differences and
a Sobel-like smoothed difference measure in between: 0.0014-0.0016 / 0.00022-0.00027 px;
cubic, 5-px: 0.00135 -> 0.00106 px). ``benchmarks/bench_field.py`` re-measures it.

Kernels (numba, ``cache=True``): :func:`interp_value` evaluates the spline at one position
[pixel, x = column, y = row]; :func:`interp_value_grad` also returns the two derivatives.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = [
    "SplineImage",
    "prefilter",
    "prefilter_region",
    "interp_value",
    "interp_value_grad",
    "PAD",
]

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


def prefilter(
    image: np.ndarray,
    interpolation: str = "quintic",
    *,
    gradients: bool = True,
    gradient: str = "central",
) -> SplineImage:
    """Compute B-spline coefficients and node gradients of ``image`` (done once per image).

    ``gradients=False`` skips the node gradients (deformed images do not need them; ``gx``,
    ``gy`` are then empty arrays). ``gradient``: ``"central"`` (central differences of the
    pixels, what the IC-GN uses; see the module docstring) or ``"spline"`` (the interpolant's
    exact derivative, kept for comparison).

    Non-finite pixels are replaced by the image mean for the prefilter (their neighbourhood is
    flagged by the correlation, never trusted).
    """
    order = _ORDERS[interpolation]
    img = np.ascontiguousarray(image, dtype=np.float64)
    valid = np.isfinite(img)
    all_valid = bool(valid.all())
    work = img if all_valid else np.where(valid, img, np.nanmean(img) if valid.any() else 0.0)
    coef = np.empty((img.shape[0] + 2 * PAD, img.shape[1] + 2 * PAD))
    _prefilter_2d(work, order, coef)
    if gradients:
        gx = np.empty(img.shape)
        gy = np.empty(img.shape)
        if gradient == "central":
            _central_gradients(work, gx, gy)
        elif gradient == "spline":
            _node_gradients(coef, order, gx, gy)
        else:
            raise ValueError(f"gradient={gradient!r}: expected 'central' or 'spline'")
    else:
        gx = gy = np.empty((0, 0))
    return SplineImage(image=img, coef=coef, gx=gx, gy=gy, order=order, valid=valid)


def prefilter_region(
    image: np.ndarray,
    interpolation: str,
    centres: np.ndarray,
    radius: float,
    *,
    workspace: dict | None = None,
    window: tuple[int, int, int, int] | None = None,
) -> SplineImage:
    """B-spline coefficients of ``image`` computed only near some points (no node gradients).

    Tracking a few hundred subsets in a large frame needs the spline only where the warped
    subsets can reach. The recursive prefilter is run on the row and column spans that cover
    the squares of half-width ``radius`` [pixel] around ``centres`` (N, 2) (x, y), widened by
    the filter's decay length, so the coefficients inside the squares equal those of
    :func:`prefilter` on the whole image to about 1e-7 of the intensity range; coefficients
    elsewhere are NaN, so a subset that strays outside gives NaN (a failed match), never a
    wrong value. The cost scales with the covered area instead of the image's.

    ``radius`` must include the subset's warped half-width, the largest displacement the
    solver may still add (``max_shift``) and the spline support (3 pixels).

    ``workspace``: a dict kept by the caller between calls on same-sized images; the arrays
    are then reused (the returned coefficients live in it until the next call).

    ``window`` ``(x0, y0, width, height)`` [pixel]: work on that rectangle of ``image`` (which
    must lie inside it) as if it had been cropped, without copying or converting the frame;
    ``centres`` are then in window coordinates. Integer frames (uint8, uint16) are read as is.
    """
    order = _ORDERS[interpolation]
    if window is not None:
        x0, y0, ww, wh = (int(v) for v in window)
        H, W = image.shape
        if x0 < 0 or y0 < 0 or x0 + ww > W or y0 + wh > H or ww < 1 or wh < 1:
            raise ValueError(f"window {window} does not lie inside the {W}x{H} image")
        img = image
        view = image[y0 : y0 + wh, x0 : x0 + ww]
    else:
        x0 = y0 = 0
        img = np.ascontiguousarray(image)
        if img.dtype not in (np.float32, np.float64):
            img = img.astype(np.float64)
        view = img
        wh, ww = img.shape
    if np.issubdtype(view.dtype, np.integer):
        ws_valid = (workspace or {}).get("valid_all")
        valid = ws_valid if ws_valid is not None and ws_valid.shape == view.shape else None
        if valid is None:
            valid = np.ones(view.shape, dtype=bool)
            if workspace is not None:
                workspace["valid_all"] = valid
        all_valid = True
    else:
        valid = np.isfinite(view)
        all_valid = bool(valid.all())
    fill = 0.0 if all_valid else (float(np.nanmean(view)) if valid.any() else 0.0)
    c = np.ascontiguousarray(centres, dtype=np.float64).reshape(-1, 2)
    c = c[np.all(np.isfinite(c), axis=1)]
    ws = {} if workspace is None else workspace
    shape = (wh + 2 * PAD, ww + 2 * PAD)
    if ws.get("coef") is None or ws["coef"].shape != shape:
        ws["coef"] = np.full(shape, np.nan)
        ws["tmp"] = np.zeros((wh, ww))  # finite scratch (see _prefilter_spans)
        ws["row_lo"] = np.full(wh, ww, np.int64)
        ws["row_hi"] = np.full(wh, -1, np.int64)
    else:  # back to NaN where the previous call wrote (cheaper than refilling everything)
        _reset_spans(ws["coef"], ws["row_lo"], ws["row_hi"])
    coef = ws["coef"]
    # decay length of the slowest pole to 1e-7 (cubic 12, quintic 20 pixels)
    z = abs(_Z3[0]) if order == 3 else abs(_Z5[0])
    margin = int(math.ceil(math.log(1e-7) / math.log(z)))
    _prefilter_spans(
        img,
        y0,
        x0,
        wh,
        ww,
        order,
        coef,
        ws["tmp"],
        c,
        int(math.ceil(radius)),
        margin,
        fill,
        ws["row_lo"],
        ws["row_hi"],
    )
    empty = np.empty((0, 0))
    return SplineImage(image=view, coef=coef, gx=empty, gy=empty, order=order, valid=valid)


@njit(cache=True, nogil=True)
def _reset_spans(out, row_lo, row_hi):
    """NaN where :func:`_prefilter_spans` wrote with these row spans (and the padding)."""
    h = row_lo.shape[0]
    for y in range(h):
        for x in range(row_lo[y], row_hi[y] + 1):
            out[y + PAD, x + PAD] = np.nan
    for k in range(PAD):
        out[k, :] = np.nan
        out[h + PAD + k, :] = np.nan
        out[:, k] = np.nan
        out[:, out.shape[1] - 1 - k] = np.nan


@njit(cache=True, nogil=True)
def _prefilter_spans(img, oy, ox, h, w, order, out, tmp, centres, r, m, fill, row_lo, row_hi):
    """Prefilter the h x w window at (ox, oy) of img over the spans covering squares of
    half-width r around centres (x, y, window coordinates).

    Rows are filtered over every square grown by r + m around a centre, columns over the
    columns within r of a centre and the rows within r + m of it: the row pass is then exact
    (to the decay length m) wherever the column pass reads it, and the column pass wherever
    the kernel reads the result.
    """
    z1, z2, npoles = _poles(order)
    row_lo[:] = w  # the row spans are returned (the next call resets them)
    row_hi[:] = -1
    col_lo = np.full(w, h, np.int64)
    col_hi = np.full(w, -1, np.int64)
    for k in range(centres.shape[0]):
        cx = int(round(centres[k, 0]))
        cy = int(round(centres[k, 1]))
        rm = r + m
        for y in range(max(cy - rm, 0), min(cy + rm, h - 1) + 1):
            row_lo[y] = min(row_lo[y], max(cx - rm, 0))
            row_hi[y] = max(row_hi[y], min(cx + rm, w - 1))
        for x in range(max(cx - r, 0), min(cx + r, w - 1) + 1):
            col_lo[x] = min(col_lo[x], max(cy - rm, 0))
            col_hi[x] = max(col_hi[x], min(cy + rm, h - 1))
    line = np.empty(max(h, w))
    for y in range(h):
        a = row_lo[y]
        b = row_hi[y] + 1
        if b <= a:
            continue
        for x in range(a, b):
            v = float(img[y + oy, x + ox])
            line[x - a] = v if math.isfinite(v) else fill
        seg = line[: b - a]
        _filter_line(seg, z1, z2, npoles)
        for x in range(a, b):
            tmp[y, x] = seg[x - a]
    # columns in blocks of 16 over the union of their spans (row-major, cache friendly); the
    # rows a column does not need hold finite scratch values (``tmp`` starts as zeros) whose
    # influence has decayed (length m) where the column's own span begins
    blk = 16
    for x0 in range(0, w, blk):
        x1 = min(x0 + blk, w)
        a = h
        b = -1
        for x in range(x0, x1):
            if col_hi[x] >= col_lo[x]:
                a = min(a, col_lo[x])
                b = max(b, col_hi[x])
        if b < a:
            continue
        _filter_columns(tmp[a : b + 1], x0, x1, z1, z2, npoles)
        for y in range(a, b + 1):
            for x in range(x0, x1):
                if col_lo[x] <= y <= col_hi[x]:
                    out[y + PAD, x + PAD] = tmp[y, x]
    # mirrored padding (reflect without repeating the edge sample), as in _prefilter_2d
    for k in range(1, PAD + 1):
        for x in range(w + 2 * PAD):
            out[PAD - k, x] = out[PAD + k, x]
            out[PAD + h - 1 + k, x] = out[PAD + h - 1 - k, x]
    for y in range(h + 2 * PAD):
        for k in range(1, PAD + 1):
            out[y, PAD - k] = out[y, PAD + k]
            out[y, PAD + w - 1 + k] = out[y, PAD + w - 1 - k]


@njit(cache=True, inline="always")
def _poles(order):
    """Poles of the cubic (one) or quintic (two) B-spline prefilter, and their count."""
    if order == 3:
        return math.sqrt(3.0) - 2.0, 0.0, 1
    a = math.sqrt(17745.0 / 4.0)
    b = math.sqrt(105.0 / 4.0)
    return (
        math.sqrt(135.0 / 2.0 - a) + b - 13.0 / 2.0,
        math.sqrt(135.0 / 2.0 + a) - b - 13.0 / 2.0,
        2,
    )


# poles of the cubic and quintic B-spline prefilters (Unser 1999; Thevenaz et al. 2000)
_Z3 = (np.sqrt(3.0) - 2.0,)
_Z5 = (
    np.sqrt(135.0 / 2.0 - np.sqrt(17745.0 / 4.0)) + np.sqrt(105.0 / 4.0) - 13.0 / 2.0,
    np.sqrt(135.0 / 2.0 + np.sqrt(17745.0 / 4.0)) - np.sqrt(105.0 / 4.0) - 13.0 / 2.0,
)


@njit(cache=True, inline="always")
def _gain(z1, z2, npoles):
    """Gain of the B-spline prefilter with poles ``z1`` (and ``z2``)."""
    lam = (1.0 - z1) * (1.0 - 1.0 / z1)
    if npoles == 2:
        lam *= (1.0 - z2) * (1.0 - 1.0 / z2)
    return lam


@njit(cache=True, inline="always")
def _horizon(z):
    """Samples after which ``z**k`` falls below 1e-14 (truncated causal initialisation)."""
    return int(math.ceil(math.log(1e-14) / math.log(abs(z))))


@njit(cache=True, inline="always")
def _mirror_start(c, z):
    """Exact causal initialisation of a line ``c`` shorter than the horizon (mirror
    boundary, the whole line summed)."""
    n = c.shape[0]
    zn = z
    iz = 1.0 / z
    z2n = z ** (n - 1)
    s = c[0] + z2n * c[n - 1]
    z2n *= z2n * iz
    for k in range(1, n - 1):
        s += (zn + z2n) * c[k]
        zn *= z
        z2n *= iz
    return s / (1.0 - zn * zn)


@njit(cache=True, nogil=True)
def _filter_line(c, z1, z2, npoles):
    """In-place recursive B-spline prefilter of one line, mirror boundary (s[-k] = s[k])."""
    n = c.shape[0]
    if n == 1:
        return
    lam = _gain(z1, z2, npoles)
    for i in range(n):
        c[i] *= lam
    for q in range(npoles):
        z = z1 if q == 0 else z2
        # causal initialisation (mirror boundary), truncated at 1e-14 relative
        horizon = _horizon(z)
        if horizon < n:
            zn = z
            s = c[0]
            for k in range(1, horizon):
                s += zn * c[k]
                zn *= z
            c[0] = s
        else:
            c[0] = _mirror_start(c, z)
        for k in range(1, n):
            c[k] += z * c[k - 1]
        c[n - 1] = (z / (z * z - 1.0)) * (z * c[n - 2] + c[n - 1])
        for k in range(n - 2, -1, -1):
            c[k] = z * (c[k + 1] - c[k])


@njit(cache=True, nogil=True)
def _filter_columns(c, j0, j1, z1, z2, npoles):
    """In-place prefilter along axis 0 of columns j0..j1-1, row by row (cache friendly)."""
    n = c.shape[0]
    if n == 1:
        return
    lam = _gain(z1, z2, npoles)
    for i in range(n):
        for j in range(j0, j1):
            c[i, j] *= lam
    acc = np.empty(j1 - j0)
    for q in range(npoles):
        z = z1 if q == 0 else z2
        horizon = _horizon(z)
        if horizon < n:
            for j in range(j0, j1):
                acc[j - j0] = c[0, j]
            zn = z
            for k in range(1, horizon):
                for j in range(j0, j1):
                    acc[j - j0] += zn * c[k, j]
                zn *= z
            for j in range(j0, j1):
                c[0, j] = acc[j - j0]
        else:
            for j in range(j0, j1):
                c[0, j] = _mirror_start(c[:, j].copy(), z)
        for k in range(1, n):
            for j in range(j0, j1):
                c[k, j] += z * c[k - 1, j]
        g = z / (z * z - 1.0)
        for j in range(j0, j1):
            c[n - 1, j] = g * (z * c[n - 2, j] + c[n - 1, j])
        for k in range(n - 2, -1, -1):
            for j in range(j0, j1):
                c[k, j] = z * (c[k + 1, j] - c[k, j])


#: rows filtered together by :func:`_prefilter_2d` (8 measured fastest of 4-32 on 512^2)
_STRIP = 8


@njit(cache=True, nogil=True)
def _prefilter_2d(img, order, out):
    """B-spline coefficients of ``img`` written into ``out`` with a mirrored border of PAD."""
    h, w = img.shape
    z1, z2, npoles = _poles(order)
    # along rows: strips of _STRIP rows copied transposed into a small buffer and filtered as
    # its columns (the strip's lines recurse side by side, vectorised, instead of one line's
    # latency-bound recursion at a time; the same operations on each line, the same numbers),
    # written straight into out's interior
    buf = np.empty((w, _STRIP))
    for i0 in range(0, h, _STRIP):
        nr = min(_STRIP, h - i0)
        for k in range(w):
            for r in range(nr):
                buf[k, r] = img[i0 + r, k]
        _filter_columns(buf, 0, nr, z1, z2, npoles)
        for r in range(nr):
            orow = out[PAD + i0 + r]
            for k in range(w):
                orow[PAD + k] = buf[k, r]
    # along columns, in place on the interior rows, 64 columns at a time
    inner = out[PAD : PAD + h]
    nb = (w + 63) // 64
    for blk in range(nb):
        _filter_columns(inner, PAD + blk * 64, PAD + min(w, blk * 64 + 64), z1, z2, npoles)
    # mirrored padding (reflect without repeating the edge sample): the interior rows' left
    # and right pads, then the whole top and bottom rows
    for i in range(PAD, PAD + h):
        for j in range(PAD):
            out[i, j] = out[i, PAD + _reflect(j - PAD, w)]
            out[i, PAD + w + j] = out[i, PAD + _reflect(w + j, w)]
    for i in range(PAD):
        top = PAD + _reflect(i - PAD, h)
        bottom = PAD + _reflect(h + i, h)
        for j in range(w + 2 * PAD):
            out[i, j] = out[top, j]
            out[PAD + h + i, j] = out[bottom, j]


@njit(cache=True, inline="always")
def _reflect(i, n):
    """Index ``i`` reflected into ``0 .. n - 1`` without repeating the edge sample."""
    if i < 0:
        return -i
    if i > n - 1:
        return 2 * (n - 1) - i
    return i


@njit(cache=True)
def _central_gradients(img, gx, gy):
    """Central differences ``(I[x+1] - I[x-1]) / 2`` [grey level / pixel], mirror boundary
    (zero on the first and last row/column)."""
    h, w = img.shape
    for i in range(h):
        il = i - 1 if i > 0 else min(1, h - 1)
        ir = i + 1 if i < h - 1 else max(h - 2, 0)
        row, up, down = img[i], img[il], img[ir]
        gxi, gyi = gx[i], gy[i]
        for j in range(w):  # y: no branch in the row (vectorised)
            gyi[j] = 0.5 * (down[j] - up[j])
        for j in range(1, w - 1):  # x inside the row, then its two ends mirrored
            gxi[j] = 0.5 * (row[j + 1] - row[j - 1])
        for j in (0, w - 1):
            jl = j - 1 if j > 0 else min(1, w - 1)
            jr = j + 1 if j < w - 1 else max(w - 2, 0)
            gxi[j] = 0.5 * (row[jr] - row[jl])


@njit(cache=True)
def node_filters(order):
    """B-spline value and derivative weights at a pixel node, over its 2r+1 coefficients
    (``order`` 3: cubic, r = 1; else quintic, r = 2)."""
    if order == 3:
        return np.array([1.0, 4.0, 1.0]) / 6.0, np.array([-0.5, 0.0, 0.5])
    return (
        np.array([1.0, 26.0, 66.0, 26.0, 1.0]) / 120.0,
        np.array([-1.0, -10.0, 0.0, 10.0, 1.0]) / 24.0,
    )


@njit(cache=True, inline="always")
def node_row_sums(row, j0, val, der):
    """Value and derivative filters over ``row[j0 : j0 + len(val)]``: ``(sum val c,
    sum der c)``."""
    sv = 0.0
    sd = 0.0
    for b in range(val.shape[0]):
        cv = row[j0 + b]
        sv += val[b] * cv
        sd += der[b] * cv
    return sv, sd


@njit(cache=True)
def _node_gradients(coef, order, gx, gy):
    """Exact derivatives of the interpolant at the pixel nodes [grey level / pixel]."""
    h, w = gx.shape
    val, der = node_filters(order)
    r = val.shape[0] // 2
    # separable: along x first (value and derivative filters) on rows -r..h+r, then along y
    tv = np.empty((h + 2 * r, w))
    td = np.empty((h + 2 * r, w))
    for i in range(h + 2 * r):
        row = coef[i + PAD - r]
        for j in range(w):
            tv[i, j], td[i, j] = node_row_sums(row, j + PAD - r, val, der)
    for i in range(h):
        for j in range(w):
            sx = 0.0
            sy = 0.0
            for a in range(2 * r + 1):
                sx += val[a] * td[i + a, j]
                sy += der[a] * tv[i + a, j]
            gx[i, j] = sx
            gy[i, j] = sy


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
    lead = 1 if order == 3 else 2  # nodes before the point's own: 1 cubic, 2 quintic
    bx = ix + PAD - lead
    by = iy + PAD - lead
    if order == 3:
        _weights3(tx, wx)
        _weights3(ty, wy)
        for r in range(4):
            row = coef[by + r]
            s = wx[0] * row[bx] + wx[1] * row[bx + 1] + wx[2] * row[bx + 2] + wx[3] * row[bx + 3]
            acc += wy[r] * s
    else:
        _weights5(tx, wx)
        _weights5(ty, wy)
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
    else:
        _weights5(tx, wx)
        _weights5(ty, wy)
        _dweights5(tx, dx)
        _dweights5(ty, dy)
    lead = 1 if order == 3 else 2  # nodes before the point's own: 1 cubic, 2 quintic
    n = 2 * lead + 2
    bx = ix + PAD - lead
    by = iy + PAD - lead
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
