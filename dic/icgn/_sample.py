"""Sampling the deformed image for the IC-GN (numba): B-spline weights written once, the value
at one point, and a warped subset row by row with the sums the Gauss-Newton step needs.

The cubic and quintic kernels are one source; the branch on ``order`` sits outside each pixel
loop (inside it, it stops the compiler from vectorising the loop). A subset row is sampled in
passes (:func:`sample_row`): the nodes and weights of all its pixels, then the taps; one pixel
at a time its weights, taps and sums formed one long dependent chain, about 30 % slower.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from jointwear.dic.icgn._interp import PAD

_FM = {"nsz", "arcp", "contract", "reassoc"}  # fastmath without no-NaN/no-inf assumptions


@njit(cache=True, inline="always")
def bspline3(t):
    """Cubic B-spline weights (x 6) of the 4 nodes around a point at fraction ``t``."""
    s = 1.0 - t
    t2 = t * t
    t3 = t2 * t
    return s * s * s, 4.0 - 6.0 * t2 + 3.0 * t3, 1.0 + 3.0 * (t + t2 - t3), t3


@njit(cache=True, inline="always")
def bspline5(t):
    """Quintic B-spline weights (x 120) of the 6 nodes around a point at fraction ``t``
    (Horner form)."""
    s = 1.0 - t
    s2 = s * s
    t2 = t * t
    return (
        s2 * s2 * s,
        26.0 + t * (-50.0 + t * (20.0 + t * (20.0 + t * (-20.0 + 5.0 * t)))),
        66.0 + t2 * (-60.0 + t2 * (30.0 - 10.0 * t)),
        26.0 + t * (50.0 + t * (20.0 + t * (-20.0 + t * (-20.0 + 10.0 * t)))),
        1.0 + t * (5.0 + t * (10.0 + t * (10.0 + t * (5.0 - 5.0 * t)))),
        t2 * t2 * t,
    )


@njit(cache=True, inline="always")
def interp_point(coef, order, xw, yw):
    """B-spline value at (xw, yw) >= 0 [pixel] on padded prefiltered coefficients."""
    ix = int(xw)
    iy = int(yw)
    lead = 1 if order == 3 else 2  # nodes before the point's own: 1 cubic, 2 quintic
    bx = ix + PAD - lead
    by = iy + PAD - lead
    r0 = coef[by]
    r1 = coef[by + 1]
    r2 = coef[by + 2]
    r3 = coef[by + 3]
    if order == 3:
        w0, w1, w2, w3 = bspline3(xw - ix)
        v0, v1, v2, v3 = bspline3(yw - iy)
        return (
            v0 * (w0 * r0[bx] + w1 * r0[bx + 1] + w2 * r0[bx + 2] + w3 * r0[bx + 3])
            + v1 * (w0 * r1[bx] + w1 * r1[bx + 1] + w2 * r1[bx + 2] + w3 * r1[bx + 3])
            + v2 * (w0 * r2[bx] + w1 * r2[bx + 1] + w2 * r2[bx + 2] + w3 * r2[bx + 3])
            + v3 * (w0 * r3[bx] + w1 * r3[bx + 1] + w2 * r3[bx + 2] + w3 * r3[bx + 3])
        ) * (1.0 / 36.0)
    w0, w1, w2, w3, w4, w5 = bspline5(xw - ix)
    v0, v1, v2, v3, v4, v5 = bspline5(yw - iy)
    r4 = coef[by + 4]
    r5 = coef[by + 5]
    acc = 0.0
    for q, wq in enumerate((w0, w1, w2, w3, w4, w5)):
        b = bx + q
        acc += wq * (v0 * r0[b] + v1 * r1[b] + v2 * r2[b] + v3 * r3[b] + v4 * r4[b] + v5 * r5[b])
    return acc * (1.0 / 14400.0)


@njit(cache=True, inline="always")
def add_row_sums(out, o, s, sc, rr):
    """Add one subset row's sums of ``q`` and ``q c`` (``s``, ``sc``; ``rr`` the row) to
    ``out[o : o + 3]``: the sums of ``q (1, c, r)``, an affine Jacobian's pattern."""
    out[o] += s
    out[o + 1] += sc
    out[o + 2] += s * rr


@njit(cache=True, inline="always")
def _nodes(xs, ys, size, col, row, wx, wy, lead, weights):
    """:func:`_row_nodes` for one spline order: ``lead`` nodes before a point's own,
    ``weights`` its B-spline weight function (:func:`bspline3` or :func:`bspline5`)."""
    for j in range(size):
        xw = xs[j]
        yw = ys[j]
        ix = int(xw)
        iy = int(yw)
        col[j] = ix + PAD - lead
        row[j] = iy + PAD - lead
        tx = weights(xw - ix)
        ty = weights(yw - iy)
        for k in range(len(tx)):
            wx[k, j] = tx[k]
            wy[k, j] = ty[k]


@njit(cache=True, inline="always")
def _row_nodes(order, xs, ys, size, col, row, wx, wy):
    """Pass 1 of a subset row: for pixel ``j`` at ``(xs[j], ys[j])`` [pixel, >= 0], the first
    node's column and row on the padded coefficients and the B-spline weights along x and y
    (``wx[:, j]``, ``wy[:, j]``; 4 cubic, 6 quintic). Independent per pixel: it vectorises;
    the branch on the order stays outside the pixel loop."""
    if order == 3:
        _nodes(xs, ys, size, col, row, wx, wy, 1, bspline3)
    else:
        _nodes(xs, ys, size, col, row, wx, wy, 2, bspline5)


@njit(cache=True)
def row_scratch(size):
    """Scratch arrays of :func:`sample_row` for rows of ``size`` pixels: positions x and y,
    node columns and rows, weights along x and y, values."""
    return (
        np.empty(size),
        np.empty(size),
        np.empty(size, dtype=np.int64),
        np.empty(size, dtype=np.int64),
        np.empty((6, size)),
        np.empty((6, size)),
        np.empty(size),
    )


@njit(cache=True, inline="always")
def sample_row(coef, order, size, scratch):
    """Spline values ``scratch[6][:size]`` at the positions ``scratch[0:2]`` of one subset
    row (nodes and weights first, then the taps)."""
    xs, ys, col, row, wx, wy, g = scratch
    _row_nodes(order, xs, ys, size, col, row, wx, wy)
    _row_taps(coef, order, size, col, row, wx, wy, g)


@njit(cache=True, inline="always")
def _taps(coef, size, col, row, wx, wy, g, n, scale):
    """:func:`_row_taps` for one spline order: ``n`` x ``n`` taps, ``scale`` its weight norm."""
    for j in range(size):
        bx = col[j]
        by = row[j]
        acc = 0.0
        for q in range(n):
            rw = coef[by + q]
            h = 0.0
            for k in range(n):
                h += wx[k, j] * rw[bx + k]
            acc += wy[q, j] * h
        g[j] = acc * scale


@njit(cache=True, inline="always")
def _row_taps(coef, order, size, col, row, wx, wy, g):
    """Pass 2 of a subset row: the spline values ``g[j]`` from pass 1's nodes and weights
    (the 16 or 36 taps, each coefficient row read contiguously)."""
    if order == 3:
        _taps(coef, size, col, row, wx, wy, g, 4, 1.0 / 36.0)
    else:
        _taps(coef, size, col, row, wx, wy, g, 6, 1.0 / 14400.0)


@njit(cache=True, fastmath=_FM)
def sample_affine(coef, order, x_start, y_start, a11, a12, a21, a22, half, f, gx, gy, acc):
    """Sample the affinely warped subset and accumulate into ``acc`` (9,): sum g, sum g^2,
    sum g f and the six sums J g (J = gradient times (1, column, row)).

    Each subset row: its pixels' positions, :func:`sample_row`, then the sums."""
    size = 2 * half + 1
    scratch = row_scratch(size)
    xs, ys, g = scratch[0], scratch[1], scratch[6]
    for i in range(9):
        acc[i] = 0.0
    k0 = 0
    for r in range(-half, half + 1):
        rr = float(r)
        x0 = x_start + a12 * rr
        y0 = y_start + a22 * rr
        for j in range(size):
            xs[j] = x0 + a11 * j
            ys[j] = y0 + a21 * j
        sample_row(coef, order, size, scratch)
        ga = gac = gb = gbc = 0.0
        sg = sgg = sgf = 0.0
        for j in range(size):
            gv = g[j]
            k = k0 + j
            c = float(j - half)
            sg += gv
            sgg += gv * gv
            sgf += gv * f[k]
            q = gx[k] * gv
            ga += q
            gac += q * c
            q = gy[k] * gv
            gb += q
            gbc += q * c
        k0 += size
        acc[0] += sg
        acc[1] += sgg
        acc[2] += sgf
        add_row_sums(acc, 3, ga, gac, rr)
        add_row_sums(acc, 6, gb, gbc, rr)
