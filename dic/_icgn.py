"""Inverse-compositional Gauss-Newton (IC-GN) subset matching, numba kernels.

Criterion: zero-normalised sum of squared differences (ZNSSD, insensitive to offset and gain of
the intensities), ``C = sum [ (f - fm)/fn - (g - gm)/gn ]**2 = 2 (1 - ZNCC)``, minimised by IC-GN
(Baker & Matthews 2004; Pan, Li & Tong 2013): the Hessian is built once per subset from the
reference gradients, each iteration interpolates the deformed image at the warped subset
(B-spline on prefiltered coefficients, :mod:`jointwear.dic._interp`) and the warp is updated by
``W(p) <- W(p) o W(dp)^-1``. Second-order warps are composed through their 6x6 matrix
representation (Gao et al. 2015).

Shape parameters (always a 12-vector, the affine case uses 6 of them)::

    p = [
        u,
        du / dx,
        du / dy,
        d2u / dx2,
        d2u / dxdy,
        d2u / dy2,
        v,
        dv / dx,
        dv / dy,
        d2v / dx2,
        d2v / dxdy,
        d2v / dy2,
    ]

so that a subset point at offset (dx, dy) from the centre maps to
``x + dx + u + ux dx + uy dy + uxx dx^2/2 + uxy dx dy + uyy dy^2/2`` (and likewise in y).

Kernels: :func:`icgn_many` (all points in parallel, ``prange``) and :func:`rg_propagate`
(reliability-guided propagation from seeds, one heap per group of points, groups in parallel).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from jointwear.dic._flags import (
    AFFINE_INDEX,
    FLAG_DIVERGED,
    FLAG_INVALID_PIXELS,
    FLAG_LOW_CORRELATION,
    FLAG_NO_TEXTURE,
    FLAG_NOT_CONVERGED,
    FLAG_OK,
    FLAG_OUTSIDE,
)
from jointwear.dic._interp import PAD, interp_value

# a subset still below this ZNCC after this many iterations is not going to match
_HOPELESS_AFTER = 10
_HOPELESS_ZNCC = 0.5

_FM = {"nsz", "arcp", "contract", "reassoc"}  # fastmath without no-NaN/no-inf assumptions

QUADRATIC_INDEX = np.arange(12)


@njit(cache=True)
def _solve_spd(A, b, n):
    """Solve A x = b (n x n symmetric positive definite) by Cholesky; None-safe: returns ok flag."""
    L = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    # forward / backward substitution for each column of b
    m = b.shape[1]
    for c in range(m):
        y = np.zeros(n)
        for i in range(n):
            s = b[i, c]
            for k in range(i):
                s -= L[i, k] * y[k]
            y[i] = s / L[i, i]
        for i in range(n - 1, -1, -1):
            s = y[i]
            for k in range(i + 1, n):
                s -= L[k, i] * b[k, c]
            b[i, c] = s / L[i, i]
    return True


@njit(cache=True)
def _quad_matrix(p, M):
    a0 = p[0]
    a1 = 1.0 + p[1]
    a2 = p[2]
    a3 = 0.5 * p[3]
    a4 = p[4]
    a5 = 0.5 * p[5]
    b0 = p[6]
    b1 = p[7]
    b2 = 1.0 + p[8]
    b3 = 0.5 * p[9]
    b4 = p[10]
    b5 = 0.5 * p[11]
    M[0, 0] = a1 * a1 + 2 * a0 * a3
    M[0, 1] = 2 * a1 * a2 + 2 * a0 * a4
    M[0, 2] = a2 * a2 + 2 * a0 * a5
    M[0, 3] = 2 * a0 * a1
    M[0, 4] = 2 * a0 * a2
    M[0, 5] = a0 * a0
    M[1, 0] = a1 * b1 + a0 * b3 + a3 * b0
    M[1, 1] = a1 * b2 + a2 * b1 + a0 * b4 + a4 * b0
    M[1, 2] = a2 * b2 + a0 * b5 + a5 * b0
    M[1, 3] = a0 * b1 + a1 * b0
    M[1, 4] = a0 * b2 + a2 * b0
    M[1, 5] = a0 * b0
    M[2, 0] = b1 * b1 + 2 * b0 * b3
    M[2, 1] = 2 * b1 * b2 + 2 * b0 * b4
    M[2, 2] = b2 * b2 + 2 * b0 * b5
    M[2, 3] = 2 * b0 * b1
    M[2, 4] = 2 * b0 * b2
    M[2, 5] = b0 * b0
    M[3, 0] = a3
    M[3, 1] = a4
    M[3, 2] = a5
    M[3, 3] = a1
    M[3, 4] = a2
    M[3, 5] = a0
    M[4, 0] = b3
    M[4, 1] = b4
    M[4, 2] = b5
    M[4, 3] = b1
    M[4, 4] = b2
    M[4, 5] = b0
    for j in range(5):
        M[5, j] = 0.0
    M[5, 5] = 1.0


@njit(cache=True)
def _invert(A, out):
    """Gauss-Jordan inverse with partial pivoting of a small square matrix; False if singular."""
    n = A.shape[0]
    M = A.copy()
    for i in range(n):
        for j in range(n):
            out[i, j] = 1.0 if i == j else 0.0
    for col in range(n):
        piv = col
        best = abs(M[col, col])
        for r in range(col + 1, n):
            if abs(M[r, col]) > best:
                best = abs(M[r, col])
                piv = r
        if not best > 1e-300:
            return False
        if piv != col:
            for j in range(n):
                M[col, j], M[piv, j] = M[piv, j], M[col, j]
                out[col, j], out[piv, j] = out[piv, j], out[col, j]
        d = 1.0 / M[col, col]
        for j in range(n):
            M[col, j] *= d
            out[col, j] *= d
        for r in range(n):
            if r != col:
                fct = M[r, col]
                if fct != 0.0:
                    for j in range(n):
                        M[r, j] -= fct * M[col, j]
                        out[r, j] -= fct * out[col, j]
    return True


@njit(cache=True)
def _compose_affine(p, dp):
    """p <- p o dp^-1 for affine warps W = [[1+ux, uy, u], [vx, 1+vy, v]]; False if singular."""
    a11 = 1.0 + dp[1]
    a12 = dp[2]
    a21 = dp[7]
    a22 = 1.0 + dp[8]
    det = a11 * a22 - a12 * a21
    if det == 0.0 or not math.isfinite(det):
        return False
    i11 = a22 / det
    i12 = -a12 / det
    i21 = -a21 / det
    i22 = a11 / det
    it1 = -(i11 * dp[0] + i12 * dp[6])
    it2 = -(i21 * dp[0] + i22 * dp[6])
    w11 = 1.0 + p[1]
    w12 = p[2]
    w21 = p[7]
    w22 = 1.0 + p[8]
    t1 = p[0]
    t2 = p[6]
    p[1] = w11 * i11 + w12 * i21 - 1.0
    p[2] = w11 * i12 + w12 * i22
    p[0] = w11 * it1 + w12 * it2 + t1
    p[7] = w21 * i11 + w22 * i21
    p[8] = w21 * i12 + w22 * i22 - 1.0
    p[6] = w21 * it1 + w22 * it2 + t2
    return True


@njit(cache=True)
def _compose_quadratic(p, dp):
    """p <- p o dp^-1 for second-order warps through their 6x6 matrices (Gao et al. 2015)."""
    Mp = np.empty((6, 6))
    Md = np.empty((6, 6))
    Mi = np.empty((6, 6))
    _quad_matrix(p, Mp)
    _quad_matrix(dp, Md)
    if not _invert(Md, Mi):
        return False
    R = np.zeros((6, 6))
    for i in range(3, 5):
        for j in range(6):
            s = 0.0
            for k in range(6):
                s += Mp[i, k] * Mi[k, j]
            R[i, j] = s
    p[3] = 2.0 * R[3, 0]
    p[4] = R[3, 1]
    p[5] = 2.0 * R[3, 2]
    p[1] = R[3, 3] - 1.0
    p[2] = R[3, 4]
    p[0] = R[3, 5]
    p[9] = 2.0 * R[4, 0]
    p[10] = R[4, 1]
    p[11] = 2.0 * R[4, 2]
    p[7] = R[4, 3]
    p[8] = R[4, 4] - 1.0
    p[6] = R[4, 5]
    return True


@njit(cache=True)
def _compose_inverse(p, dp, quadratic):
    """p <- p o dp^-1 (inverse-compositional update), in place. Returns False if singular."""
    if quadratic:
        return _compose_quadratic(p, dp)
    return _compose_affine(p, dp)


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
        # node gradients are central differences of the pixels, see jointwear.dic._interp)
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
    fm = 0.0
    for k in range(n):
        fm += f[k]
    fm /= n
    fn = 0.0
    for k in range(n):
        f[k] -= fm
        fn += f[k] * f[k]
    fn = math.sqrt(fn)
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


@njit(cache=True, fastmath=_FM)
def _hessian_affine(f, gx, gy, half, Hm, jf, js):
    """Affine Gauss-Newton Hessian ``sum J J^T``, ``sum J f`` and ``sum J`` (row-wise sums)."""
    m = np.zeros(18)  # aa, ab, bb moments: 1, c, r, cc, cr, rr
    k = 0
    for r in range(-half, half + 1):
        rr = float(r)
        raa = raac = raacc = rab = rabc = rabcc = rbb = rbbc = rbbcc = 0.0
        rfa = rfac = rfb = rfbc = rsa = rsac = rsb = rsbc = 0.0
        for c in range(-half, half + 1):
            a = gx[k]
            b = gy[k]
            fk = f[k]
            q = a * a
            raa += q
            raac += q * c
            raacc += q * c * c
            q = a * b
            rab += q
            rabc += q * c
            rabcc += q * c * c
            q = b * b
            rbb += q
            rbbc += q * c
            rbbcc += q * c * c
            rfa += a * fk
            rfac += a * fk * c
            rfb += b * fk
            rfbc += b * fk * c
            rsa += a
            rsac += a * c
            rsb += b
            rsbc += b * c
            k += 1
        for o, s1, sc, scc in (
            (0, raa, raac, raacc),
            (6, rab, rabc, rabcc),
            (12, rbb, rbbc, rbbcc),
        ):
            m[o] += s1
            m[o + 1] += sc
            m[o + 2] += s1 * rr
            m[o + 3] += scc
            m[o + 4] += sc * rr
            m[o + 5] += s1 * rr * rr
        jf[0] += rfa
        jf[1] += rfac
        jf[2] += rfa * rr
        jf[3] += rfb
        jf[4] += rfbc
        jf[5] += rfb * rr
        js[0] += rsa
        js[1] += rsac
        js[2] += rsa * rr
        js[3] += rsb
        js[4] += rsbc
        js[5] += rsb * rr
    # J = [a, a c, a r, b, b c, b r]: block (i, j) of sum J J^T from the moments
    for blk_i in range(2):
        for blk_j in range(blk_i, 2):
            o = 0 if (blk_i == 0 and blk_j == 0) else (6 if blk_i != blk_j else 12)
            M3 = np.empty((3, 3))
            M3[0, 0] = m[o]
            M3[0, 1] = m[o + 1]
            M3[0, 2] = m[o + 2]
            M3[1, 0] = m[o + 1]
            M3[1, 1] = m[o + 3]
            M3[1, 2] = m[o + 4]
            M3[2, 0] = m[o + 2]
            M3[2, 1] = m[o + 4]
            M3[2, 2] = m[o + 5]
            for i in range(3):
                for j in range(3):
                    Hm[3 * blk_i + i, 3 * blk_j + j] = M3[i, j]
                    Hm[3 * blk_j + j, 3 * blk_i + i] = M3[i, j]


@njit(cache=True, fastmath=_FM)
def _sample_cubic(coef, x_start, y_start, a11, a12, a21, a22, half, f, gx, gy, acc):
    """Sample the deformed subset (cubic B-spline) and accumulate into ``acc`` (9,):
    sum g, sum g^2, sum g f, sum J g (6)."""
    for i in range(9):
        acc[i] = 0.0
    k = 0
    for r in range(-half, half + 1):
        rr = float(r)
        xw = x_start + a12 * rr
        yw = y_start + a22 * rr
        ga = gac = gb = gbc = 0.0
        sg = sgg = sgf = 0.0
        for c in range(-half, half + 1):
            ix = int(xw)
            iy = int(yw)
            t = xw - ix
            s = 1.0 - t
            t2 = t * t
            t3 = t2 * t
            w0 = s * s * s
            w1 = 4.0 - 6.0 * t2 + 3.0 * t3
            w2 = 1.0 + 3.0 * (t + t2 - t3)
            w3 = t3
            t = yw - iy
            s = 1.0 - t
            t2 = t * t
            t3 = t2 * t
            bx = ix + PAD - 1
            by = iy + PAD - 1
            r0 = coef[by]
            r1 = coef[by + 1]
            r2 = coef[by + 2]
            r3 = coef[by + 3]
            gv = (
                s * s * s * (w0 * r0[bx] + w1 * r0[bx + 1] + w2 * r0[bx + 2] + w3 * r0[bx + 3])
                + (4.0 - 6.0 * t2 + 3.0 * t3)
                * (w0 * r1[bx] + w1 * r1[bx + 1] + w2 * r1[bx + 2] + w3 * r1[bx + 3])
                + (1.0 + 3.0 * (t + t2 - t3))
                * (w0 * r2[bx] + w1 * r2[bx + 1] + w2 * r2[bx + 2] + w3 * r2[bx + 3])
                + t3 * (w0 * r3[bx] + w1 * r3[bx + 1] + w2 * r3[bx + 2] + w3 * r3[bx + 3])
            ) * (1.0 / 36.0)
            sg += gv
            sgg += gv * gv
            sgf += gv * f[k]
            q = gx[k] * gv
            ga += q
            gac += q * c
            q = gy[k] * gv
            gb += q
            gbc += q * c
            xw += a11
            yw += a21
            k += 1
        acc[0] += sg
        acc[1] += sgg
        acc[2] += sgf
        acc[3] += ga
        acc[4] += gac
        acc[5] += ga * rr
        acc[6] += gb
        acc[7] += gbc
        acc[8] += gb * rr


@njit(cache=True, fastmath=_FM)
def _sample_quintic(coef, x_start, y_start, a11, a12, a21, a22, half, f, gx, gy, acc):
    """As :func:`_sample_cubic` with the quintic B-spline."""
    for i in range(9):
        acc[i] = 0.0
    k = 0
    for r in range(-half, half + 1):
        rr = float(r)
        xw = x_start + a12 * rr
        yw = y_start + a22 * rr
        ga = gac = gb = gbc = 0.0
        sg = sgg = sgf = 0.0
        for c in range(-half, half + 1):
            ix = int(xw)
            iy = int(yw)
            # quintic B-spline weights (x 120), Horner form
            t = xw - ix
            s = 1.0 - t
            s2 = s * s
            t2 = t * t
            w0 = s2 * s2 * s
            w5 = t2 * t2 * t
            w1 = 26.0 + t * (-50.0 + t * (20.0 + t * (20.0 + t * (-20.0 + 5.0 * t))))
            w2 = 66.0 + t2 * (-60.0 + t2 * (30.0 - 10.0 * t))
            w3 = 26.0 + t * (50.0 + t * (20.0 + t * (-20.0 + t * (-20.0 + 10.0 * t))))
            w4 = 1.0 + t * (5.0 + t * (10.0 + t * (10.0 + t * (5.0 - 5.0 * t))))
            t = yw - iy
            s = 1.0 - t
            s2 = s * s
            t2 = t * t
            v0 = s2 * s2 * s
            v5 = t2 * t2 * t
            v1 = 26.0 + t * (-50.0 + t * (20.0 + t * (20.0 + t * (-20.0 + 5.0 * t))))
            v2 = 66.0 + t2 * (-60.0 + t2 * (30.0 - 10.0 * t))
            v3 = 26.0 + t * (50.0 + t * (20.0 + t * (-20.0 + t * (-20.0 + 10.0 * t))))
            v4 = 1.0 + t * (5.0 + t * (10.0 + t * (10.0 + t * (5.0 - 5.0 * t))))
            bx = ix + PAD - 2
            by = iy + PAD - 2
            r0 = coef[by]
            r1 = coef[by + 1]
            r2 = coef[by + 2]
            r3 = coef[by + 3]
            r4 = coef[by + 4]
            r5 = coef[by + 5]
            h0 = v0 * r0[bx] + v1 * r1[bx] + v2 * r2[bx] + v3 * r3[bx] + v4 * r4[bx] + v5 * r5[bx]
            b1 = bx + 1
            h1 = v0 * r0[b1] + v1 * r1[b1] + v2 * r2[b1] + v3 * r3[b1] + v4 * r4[b1] + v5 * r5[b1]
            b2 = bx + 2
            h2 = v0 * r0[b2] + v1 * r1[b2] + v2 * r2[b2] + v3 * r3[b2] + v4 * r4[b2] + v5 * r5[b2]
            b3 = bx + 3
            h3 = v0 * r0[b3] + v1 * r1[b3] + v2 * r2[b3] + v3 * r3[b3] + v4 * r4[b3] + v5 * r5[b3]
            b4 = bx + 4
            h4 = v0 * r0[b4] + v1 * r1[b4] + v2 * r2[b4] + v3 * r3[b4] + v4 * r4[b4] + v5 * r5[b4]
            b5 = bx + 5
            h5 = v0 * r0[b5] + v1 * r1[b5] + v2 * r2[b5] + v3 * r3[b5] + v4 * r4[b5] + v5 * r5[b5]
            gv = (w0 * h0 + w1 * h1 + w2 * h2 + w3 * h3 + w4 * h4 + w5 * h5) * (1.0 / 14400.0)
            sg += gv
            sgg += gv * gv
            sgf += gv * f[k]
            q = gx[k] * gv
            ga += q
            gac += q * c
            q = gy[k] * gv
            gb += q
            gbc += q * c
            xw += a11
            yw += a21
            k += 1
        acc[0] += sg
        acc[1] += sgg
        acc[2] += sgf
        acc[3] += ga
        acc[4] += gac
        acc[5] += ga * rr
        acc[6] += gb
        acc[7] += gbc
        acc[8] += gb * rr


@njit(cache=True)
def _solve_affine(
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    xc,
    yc,
    half,
    p,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    f,
    gx,
    gy,
    w,
):
    """Affine IC-GN for one subset, one sampling pass per iteration (see :func:`solve_point`):
    the reference subset and its Hessian, then :func:`_iterate_affine`."""
    flag0, fn = _load_reference(
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
    )
    if flag0 != FLAG_OK:
        return np.nan, 0, flag0
    Hinv = np.eye(6)
    jf = np.zeros(6)
    js = np.zeros(6)
    if not _affine_system(f, gx, gy, half, Hinv, jf, js):
        return np.nan, 0, FLAG_NO_TEXTURE
    return _iterate_affine(
        f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p, max_iter,
        tol, max_shift, border, w,
    )  # fmt: skip


@njit(cache=True, nogil=True)
def _affine_system(f, gx, gy, half, Hinv, jf, js):
    """Inverse Gauss-Newton Hessian (into ``Hinv``, which must hold the identity), ``sum J f``
    and ``sum J``; False when the Hessian is singular (no texture)."""
    Hm = np.empty((6, 6))
    _hessian_affine(f, gx, gy, half, Hm, jf, js)
    return _solve_spd(Hm, Hinv, 6)


@njit(cache=True, nogil=True)
def _iterate_affine(
    f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p, max_iter, tol,
    max_shift, border, w,
):  # fmt: skip
    """Gauss-Newton iterations of the affine IC-GN from the loaded reference subset.

    Uses ``sum J (f - fm - fn/gn (g - gm)) = Jf - fn/gn (Jg - gm Js)`` with ``Jf``, ``Js``
    fixed per subset, so each iteration samples the deformed subset once and accumulates.
    """
    Hd = def_coef.shape[0] - 2 * PAD
    Wd = def_coef.shape[1] - 2 * PAD
    n = (2 * half + 1) ** 2
    acc = np.empty(9)
    e = np.empty(6)
    dp = np.zeros(12)
    p_start_u = p[0]
    p_start_v = p[6]
    zncc = np.nan
    it = 0
    hh2 = float(half) * float(half)
    while it < max_iter:
        it += 1
        a11 = 1.0 + p[1]
        a12 = p[2]
        a21 = p[7]
        a22 = 1.0 + p[8]
        # the warped subset is a parallelogram: its corners bound it
        xmin = 1e300
        xmax = -1e300
        ymin = 1e300
        ymax = -1e300
        for corner in range(4):
            c = -half if corner % 2 == 0 else half
            r = -half if corner < 2 else half
            xw = xc + p[0] + a11 * c + a12 * r
            yw = yc + p[6] + a21 * c + a22 * r
            xmin = min(xmin, xw)
            xmax = max(xmax, xw)
            ymin = min(ymin, yw)
            ymax = max(ymax, yw)
        if not (
            xmin >= border
            and ymin >= border
            and xmax <= Wd - 1 - border
            and ymax <= Hd - 1 - border
        ):
            return np.nan, it, FLAG_OUTSIDE
        if def_invalid.shape[0] > 1 and _box_has_invalid(
            def_invalid,
            int(math.floor(xmin)) - 3,
            int(math.floor(ymin)) - 3,
            int(math.ceil(xmax)) + 3,
            int(math.ceil(ymax)) + 3,
        ):
            return np.nan, it, FLAG_INVALID_PIXELS
        x_start = xc + p[0] - a11 * half
        y_start = yc + p[6] - a21 * half
        if order == 3:
            _sample_cubic(def_coef, x_start, y_start, a11, a12, a21, a22, half, f, gx, gy, acc)
        else:
            _sample_quintic(def_coef, x_start, y_start, a11, a12, a21, a22, half, f, gx, gy, acc)
        gm = acc[0] / n
        gn2 = acc[1] - n * gm * gm
        if not gn2 > 1e-300:
            return np.nan, it, FLAG_NO_TEXTURE
        gn = math.sqrt(gn2)
        zncc = acc[2] / (fn * gn)
        if it >= _HOPELESS_AFTER and not (zncc >= _HOPELESS_ZNCC):
            return zncc, it, FLAG_NOT_CONVERGED  # far from any match: stop early
        ratio = fn / gn
        for j in range(6):
            e[j] = jf[j] - ratio * (acc[3 + j] - gm * js[j])
        for i in range(6):
            s = 0.0
            for j in range(6):
                s += Hinv[i, j] * e[j]
            dp[AFFINE_INDEX[i]] = -s
        if not _compose_affine(p, dp):
            return zncc, it, FLAG_DIVERGED
        ok = True
        for i in range(12):
            if not math.isfinite(p[i]):
                ok = False
        if not ok or abs(p[0] - p_start_u) > max_shift or abs(p[6] - p_start_v) > max_shift:
            return np.nan, it, FLAG_DIVERGED
        norm = dp[0] * dp[0] + dp[6] * dp[6]
        norm += hh2 * (dp[1] * dp[1] + dp[2] * dp[2] + dp[7] * dp[7] + dp[8] * dp[8])
        if math.sqrt(norm) < tol:
            _store_sigma(w, fn, zncc, n, 6, Hinv[0, 0], Hinv[3, 3])
            return zncc, it, FLAG_OK
    return zncc, it, FLAG_NOT_CONVERGED


@njit(cache=True, inline="always")
def _interp_point(coef, order, xw, yw):
    """B-spline value at (xw, yw) >= 0 [pixel] (cubic or quintic, Horner weights)."""
    ix = int(xw)
    iy = int(yw)
    if order == 3:
        t = xw - ix
        s = 1.0 - t
        t2 = t * t
        t3 = t2 * t
        w0 = s * s * s
        w1 = 4.0 - 6.0 * t2 + 3.0 * t3
        w2 = 1.0 + 3.0 * (t + t2 - t3)
        w3 = t3
        t = yw - iy
        s = 1.0 - t
        t2 = t * t
        t3 = t2 * t
        bx = ix + PAD - 1
        by = iy + PAD - 1
        r0 = coef[by]
        r1 = coef[by + 1]
        r2 = coef[by + 2]
        r3 = coef[by + 3]
        return (
            s * s * s * (w0 * r0[bx] + w1 * r0[bx + 1] + w2 * r0[bx + 2] + w3 * r0[bx + 3])
            + (4.0 - 6.0 * t2 + 3.0 * t3)
            * (w0 * r1[bx] + w1 * r1[bx + 1] + w2 * r1[bx + 2] + w3 * r1[bx + 3])
            + (1.0 + 3.0 * (t + t2 - t3))
            * (w0 * r2[bx] + w1 * r2[bx + 1] + w2 * r2[bx + 2] + w3 * r2[bx + 3])
            + t3 * (w0 * r3[bx] + w1 * r3[bx + 1] + w2 * r3[bx + 2] + w3 * r3[bx + 3])
        ) * (1.0 / 36.0)
    t = xw - ix
    s = 1.0 - t
    s2 = s * s
    t2 = t * t
    w0 = s2 * s2 * s
    w5 = t2 * t2 * t
    w1 = 26.0 + t * (-50.0 + t * (20.0 + t * (20.0 + t * (-20.0 + 5.0 * t))))
    w2 = 66.0 + t2 * (-60.0 + t2 * (30.0 - 10.0 * t))
    w3 = 26.0 + t * (50.0 + t * (20.0 + t * (-20.0 + t * (-20.0 + 10.0 * t))))
    w4 = 1.0 + t * (5.0 + t * (10.0 + t * (10.0 + t * (5.0 - 5.0 * t))))
    t = yw - iy
    s = 1.0 - t
    s2 = s * s
    t2 = t * t
    v0 = s2 * s2 * s
    v5 = t2 * t2 * t
    v1 = 26.0 + t * (-50.0 + t * (20.0 + t * (20.0 + t * (-20.0 + 5.0 * t))))
    v2 = 66.0 + t2 * (-60.0 + t2 * (30.0 - 10.0 * t))
    v3 = 26.0 + t * (50.0 + t * (20.0 + t * (-20.0 + t * (-20.0 + 10.0 * t))))
    v4 = 1.0 + t * (5.0 + t * (10.0 + t * (10.0 + t * (5.0 - 5.0 * t))))
    bx = ix + PAD - 2
    by = iy + PAD - 2
    r0 = coef[by]
    r1 = coef[by + 1]
    r2 = coef[by + 2]
    r3 = coef[by + 3]
    r4 = coef[by + 4]
    r5 = coef[by + 5]
    acc = 0.0
    for q in range(6):
        b = bx + q
        h = v0 * r0[b] + v1 * r1[b] + v2 * r2[b] + v3 * r3[b] + v4 * r4[b] + v5 * r5[b]
        wq = (
            w0
            if q == 0
            else (w1 if q == 1 else (w2 if q == 2 else (w3 if q == 3 else (w4 if q == 4 else w5))))
        )
        acc += wq * h
    return acc * (1.0 / 14400.0)


@njit(cache=True, fastmath=_FM)
def _solve_quadratic(
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    xc,
    yc,
    half,
    p,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    f,
    gx,
    gy,
    w,
):
    """Second-order IC-GN for one subset, one sampling pass per iteration (as
    :func:`_solve_affine`, with the 12-parameter Jacobian and 6x6 warp composition)."""
    Hd = def_coef.shape[0] - 2 * PAD
    Wd = def_coef.shape[1] - 2 * PAD
    n = (2 * half + 1) ** 2
    flag0, fn = _load_reference(
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
    )
    if flag0 != FLAG_OK:
        return np.nan, 0, flag0
    Hm = np.zeros((12, 12))
    J = np.empty(12)
    jf = np.zeros(12)
    js = np.zeros(12)
    k = 0
    for r in range(-half, half + 1):
        for c in range(-half, half + 1):
            a = gx[k]
            b = gy[k]
            J[0] = a
            J[1] = a * c
            J[2] = a * r
            J[3] = 0.5 * a * c * c
            J[4] = a * c * r
            J[5] = 0.5 * a * r * r
            J[6] = b
            J[7] = b * c
            J[8] = b * r
            J[9] = 0.5 * b * c * c
            J[10] = b * c * r
            J[11] = 0.5 * b * r * r
            fk = f[k]
            for i in range(12):
                ji = J[i]
                jf[i] += ji * fk
                js[i] += ji
                for j in range(i + 1):
                    Hm[i, j] += ji * J[j]
            k += 1
    for i in range(12):
        for j in range(i + 1, 12):
            Hm[i, j] = Hm[j, i]
    Hinv = np.eye(12)
    if not _solve_spd(Hm, Hinv, 12):
        return np.nan, 0, FLAG_NO_TEXTURE
    jg = np.empty(12)
    e = np.empty(12)
    dp = np.zeros(12)
    p_start_u = p[0]
    p_start_v = p[6]
    zncc = np.nan
    it = 0
    hh = float(half)
    lo = float(border)
    hix = Wd - 1.0 - border
    hiy = Hd - 1.0 - border
    while it < max_iter:
        it += 1
        for i in range(12):
            jg[i] = 0.0
        sg = sgg = sgf = 0.0
        xmin = 1e300
        xmax = -1e300
        ymin = 1e300
        ymax = -1e300
        k = 0
        for r in range(-half, half + 1):
            rr = float(r)
            ra = rb = rac = rbc = racc = rbcc = 0.0
            for c in range(-half, half + 1):
                cc = float(c)
                xw = xc + cc + p[0] + p[1] * cc + p[2] * rr
                xw += 0.5 * p[3] * cc * cc + p[4] * cc * rr + 0.5 * p[5] * rr * rr
                yw = yc + rr + p[6] + p[7] * cc + p[8] * rr
                yw += 0.5 * p[9] * cc * cc + p[10] * cc * rr + 0.5 * p[11] * rr * rr
                if not (xw >= lo and yw >= lo and xw <= hix and yw <= hiy):
                    return np.nan, it, FLAG_OUTSIDE
                xmin = min(xmin, xw)
                xmax = max(xmax, xw)
                ymin = min(ymin, yw)
                ymax = max(ymax, yw)
                gv = _interp_point(def_coef, order, xw, yw)
                sg += gv
                sgg += gv * gv
                sgf += gv * f[k]
                qa = gx[k] * gv
                qb = gy[k] * gv
                ra += qa
                rac += qa * cc
                racc += qa * cc * cc
                rb += qb
                rbc += qb * cc
                rbcc += qb * cc * cc
                k += 1
            jg[0] += ra
            jg[1] += rac
            jg[2] += ra * rr
            jg[3] += 0.5 * racc
            jg[4] += rac * rr
            jg[5] += 0.5 * ra * rr * rr
            jg[6] += rb
            jg[7] += rbc
            jg[8] += rb * rr
            jg[9] += 0.5 * rbcc
            jg[10] += rbc * rr
            jg[11] += 0.5 * rb * rr * rr
        if def_invalid.shape[0] > 1 and _box_has_invalid(
            def_invalid,
            int(math.floor(xmin)) - 3,
            int(math.floor(ymin)) - 3,
            int(math.ceil(xmax)) + 3,
            int(math.ceil(ymax)) + 3,
        ):
            return np.nan, it, FLAG_INVALID_PIXELS
        gm = sg / n
        gn2 = sgg - n * gm * gm
        if not gn2 > 1e-300:
            return np.nan, it, FLAG_NO_TEXTURE
        gn = math.sqrt(gn2)
        zncc = sgf / (fn * gn)
        if it >= _HOPELESS_AFTER and not (zncc >= _HOPELESS_ZNCC):
            return zncc, it, FLAG_NOT_CONVERGED  # far from any match: stop early
        ratio = fn / gn
        for j in range(12):
            e[j] = jf[j] - ratio * (jg[j] - gm * js[j])
        for i in range(12):
            s = 0.0
            for j in range(12):
                s += Hinv[i, j] * e[j]
            dp[i] = -s
        if not _compose_quadratic(p, dp):
            return zncc, it, FLAG_DIVERGED
        ok = True
        for i in range(12):
            if not math.isfinite(p[i]):
                ok = False
        if not ok or abs(p[0] - p_start_u) > max_shift or abs(p[6] - p_start_v) > max_shift:
            return np.nan, it, FLAG_DIVERGED
        norm = dp[0] * dp[0] + dp[6] * dp[6]
        norm += hh * hh * (dp[1] * dp[1] + dp[2] * dp[2] + dp[7] * dp[7] + dp[8] * dp[8])
        q = 0.5 * hh * hh
        norm += q * q * (dp[3] ** 2 + dp[5] ** 2 + dp[9] ** 2 + dp[11] ** 2)
        norm += hh**4 * (dp[4] ** 2 + dp[10] ** 2)
        if math.sqrt(norm) < tol:
            _store_sigma(w, fn, zncc, n, 12, Hinv[0, 0], Hinv[6, 6])
            return zncc, it, FLAG_OK
    return zncc, it, FLAG_NOT_CONVERGED


@njit(cache=True)
def make_work(half):
    """Scratch arrays for :func:`solve_point` (one set per thread/chunk)."""
    n = (2 * half + 1) ** 2
    return np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty((4, 6))


@njit(cache=True)
def solve_point(
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    xc,
    yc,
    half,
    quadratic,
    p,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    work,
):
    """Match one subset centred at (xc, yc) of the reference; refines ``p`` (12,) in place.

    ``work`` comes from :func:`make_work`. Returns ``(zncc, iterations, flag)``.
    """
    f, gx, gy, g, w = work
    w[3, 4] = np.nan
    w[3, 5] = np.nan
    if quadratic:
        return _solve_quadratic(
            ref_img,
            ref_gx,
            ref_gy,
            ref_coef,
            ref_invalid,
            def_coef,
            def_invalid,
            order,
            xc,
            yc,
            half,
            p,
            max_iter,
            tol,
            min_std,
            max_shift,
            border,
            f,
            gx,
            gy,
            w,
        )
    return _solve_affine(
        ref_img,
        ref_gx,
        ref_gy,
        ref_coef,
        ref_invalid,
        def_coef,
        def_invalid,
        order,
        xc,
        yc,
        half,
        p,
        max_iter,
        tol,
        min_std,
        max_shift,
        border,
        f,
        gx,
        gy,
        w,
    )


@njit(cache=True, inline="always")
def _store_point(i, p, z, it, fl, w, zncc_min, P, zncc, iters, flags, sigma):
    """Write point ``i``'s outcome (low ZNCC flagged) and its u, v uncertainty from ``w``."""
    if fl == FLAG_OK and not (z >= zncc_min):
        fl = FLAG_LOW_CORRELATION
    for q in range(12):
        P[i, q] = p[q]
    zncc[i] = z
    iters[i] = it
    flags[i] = fl
    sigma[i, 0] = w[3, 4]
    sigma[i, 1] = w[3, 5]


@njit(cache=True, inline="always")
def _refine_chunk(
    ch,
    n_chunks,
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    centres,
    P,
    active,
    half,
    quadratic,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    zncc_min,
    zncc,
    iters,
    flags,
    sigma,
):
    """Refine the active points ``ch, ch + n_chunks, ...`` from ``P[i]`` (in place)."""
    n = centres.shape[0]
    work = make_work(half)
    p = np.empty(12)
    for i in range(ch, n, n_chunks):
        if not active[i]:
            continue
        for q in range(12):
            p[q] = P[i, q]
        z, it, fl = solve_point(
            ref_img,
            ref_gx,
            ref_gy,
            ref_coef,
            ref_invalid,
            def_coef,
            def_invalid,
            order,
            centres[i, 0],
            centres[i, 1],
            half,
            quadratic,
            p,
            max_iter,
            tol,
            min_std,
            max_shift,
            border,
            work,
        )
        _store_point(i, p, z, it, fl, work[4], zncc_min, P, zncc, iters, flags, sigma)


@njit(cache=True, parallel=True)
def icgn_many(
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    centres,
    P,
    active,
    half,
    quadratic,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    zncc_min,
    zncc,
    iters,
    flags,
    sigma,
):
    """Refine every active point from its initial parameters ``P[i]`` (in place), in parallel."""
    n_chunks = min(centres.shape[0], 64)
    for ch in prange(n_chunks):
        _refine_chunk(
            ch,
            n_chunks,
            ref_img,
            ref_gx,
            ref_gy,
            ref_coef,
            ref_invalid,
            def_coef,
            def_invalid,
            order,
            centres,
            P,
            active,
            half,
            quadratic,
            max_iter,
            tol,
            min_std,
            max_shift,
            border,
            zncc_min,
            zncc,
            iters,
            flags,
            sigma,
        )


@njit(cache=True)
def icgn_serial(
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    centres,
    P,
    active,
    half,
    quadratic,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    zncc_min,
    zncc,
    iters,
    flags,
    sigma,
):
    """As :func:`icgn_many` on one thread (for a handful of points, e.g. seeds)."""
    n_chunks = min(centres.shape[0], 64)
    for ch in range(n_chunks):
        _refine_chunk(
            ch,
            n_chunks,
            ref_img,
            ref_gx,
            ref_gy,
            ref_coef,
            ref_invalid,
            def_coef,
            def_invalid,
            order,
            centres,
            P,
            active,
            half,
            quadratic,
            max_iter,
            tol,
            min_std,
            max_shift,
            border,
            zncc_min,
            zncc,
            iters,
            flags,
            sigma,
        )


@njit(cache=True, nogil=True)
def affine_references(
    ref_img, ref_gx, ref_gy, ref_coef, ref_invalid, order, centres, half, min_std, border,
    F, GX, GY, HINV, JF, JS, FN, FLAG0,
):  # fmt: skip
    """Load every reference subset once for :func:`icgn_affine_loaded`: zero-mean values
    ``F`` (n, m), gradients ``GX``, ``GY``, norms ``FN``, inverse Hessians ``HINV`` (n, 6, 6),
    ``JF``/``JS`` (n, 6) and the loading outcome ``FLAG0`` (n,)."""
    w = np.empty((4, 6))
    for i in range(centres.shape[0]):
        fl, fn = _load_reference(
            ref_img, ref_gx, ref_gy, ref_coef, ref_invalid, order, centres[i, 0], centres[i, 1],
            half, min_std, border, F[i], GX[i], GY[i], w,
        )  # fmt: skip
        FN[i] = fn
        for a in range(6):
            for b in range(6):
                HINV[i, a, b] = 1.0 if a == b else 0.0
            JF[i, a] = 0.0
            JS[i, a] = 0.0
        if fl == FLAG_OK and not _affine_system(F[i], GX[i], GY[i], half, HINV[i], JF[i], JS[i]):
            fl = FLAG_NO_TEXTURE
        FLAG0[i] = fl


@njit(cache=True, nogil=True)
def icgn_affine_loaded(
    F, GX, GY, HINV, JF, JS, FN, FLAG0, def_coef, def_invalid, order, centres, P, active,
    half, max_iter, tol, max_shift, border, zncc_min, zncc, iters, flags, sigma,
):  # fmt: skip
    """As :func:`icgn_serial` (affine shape) with the reference subsets preloaded by
    :func:`affine_references`: a tracker matching the same subsets in many frames skips the
    per-frame loading and Hessian. Runs without the GIL (one thread per call)."""
    w = np.empty((4, 6))
    p = np.empty(12)
    for i in range(centres.shape[0]):
        if not active[i]:
            continue
        if FLAG0[i] != FLAG_OK:
            zncc[i] = np.nan
            iters[i] = 0
            flags[i] = FLAG0[i]
            sigma[i, 0] = np.nan
            sigma[i, 1] = np.nan
            continue
        for q in range(12):
            p[q] = P[i, q]
        w[3, 4] = np.nan
        w[3, 5] = np.nan
        z, it, fl = _iterate_affine(
            F[i], GX[i], GY[i], FN[i], HINV[i], JF[i], JS[i], def_coef, def_invalid, order,
            centres[i, 0], centres[i, 1], half, p, max_iter, tol, max_shift, border, w,
        )  # fmt: skip
        _store_point(i, p, z, it, fl, w, zncc_min, P, zncc, iters, flags, sigma)


@njit(cache=True)
def subset_std(img, invalid, centres, half, border):
    """Standard deviation of the reference subset at every centre (NaN: unusable centre)."""
    H, W = img.shape
    n = centres.shape[0]
    out = np.full(n, np.nan)
    size = 2 * half + 1
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
        s = 0.0
        s2 = 0.0
        for r in range(size):
            for c in range(size):
                v = img[y0 + r, x0 + c]
                s += v
                s2 += v * v
        m = s / (size * size)
        out[i] = math.sqrt(max(s2 / (size * size) - m * m, 0.0))
    return out


# ---------------------------------------------------------------- reliability-guided propagation


@njit(cache=True)
def _heap_push(keys, vals, size, key, val):
    i = size
    keys[i] = key
    vals[i] = val
    while i > 0:
        parent = (i - 1) // 2
        if keys[parent] >= keys[i]:
            break
        keys[parent], keys[i] = keys[i], keys[parent]
        vals[parent], vals[i] = vals[i], vals[parent]
        i = parent
    return size + 1


@njit(cache=True)
def _heap_pop(keys, vals, size):
    val = vals[0]
    size -= 1
    keys[0] = keys[size]
    vals[0] = vals[size]
    i = 0
    while True:
        left = 2 * i + 1
        right = left + 1
        best = i
        if left < size and keys[left] > keys[best]:
            best = left
        if right < size and keys[right] > keys[best]:
            best = right
        if best == i:
            break
        keys[best], keys[i] = keys[i], keys[best]
        vals[best], vals[i] = vals[i], vals[best]
        i = best
    return val, size


@njit(cache=True)
def _extrapolate(p_from, dx, dy, out):
    """Shape parameters of a neighbour at offset (dx, dy) from a solved point."""
    for i in range(12):
        out[i] = p_from[i]
    for o in (0, 6):
        out[o] = (
            p_from[o]
            + p_from[o + 1] * dx
            + p_from[o + 2] * dy
            + 0.5 * p_from[o + 3] * dx * dx
            + p_from[o + 4] * dx * dy
            + 0.5 * p_from[o + 5] * dy * dy
        )
        out[o + 1] = p_from[o + 1] + p_from[o + 3] * dx + p_from[o + 4] * dy
        out[o + 2] = p_from[o + 2] + p_from[o + 4] * dx + p_from[o + 5] * dy


@njit(cache=True)
def _propagate_group(
    g,
    group,
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    centres,
    nb_ptr,
    nb_idx,
    P,
    half,
    quadratic,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    zncc_min,
    zncc,
    iters,
    flags,
    sigma,
    done,
):
    n = centres.shape[0]
    keys = np.empty(n)
    vals = np.empty(n, dtype=np.int64)
    size = 0
    for i in range(n):
        if (g < 0 or group[i] == g) and done[i] and flags[i] == FLAG_OK:
            size = _heap_push(keys, vals, size, zncc[i], i)
    guess = np.empty(12)
    work = make_work(half)
    while size > 0:
        i, size = _heap_pop(keys, vals, size)
        for q in range(nb_ptr[i], nb_ptr[i + 1]):
            j = nb_idx[q]
            if done[j] or (g >= 0 and group[j] != g):
                continue
            _extrapolate(P[i], centres[j, 0] - centres[i, 0], centres[j, 1] - centres[i, 1], guess)
            z, it, fl = solve_point(
                ref_img,
                ref_gx,
                ref_gy,
                ref_coef,
                ref_invalid,
                def_coef,
                def_invalid,
                order,
                centres[j, 0],
                centres[j, 1],
                half,
                quadratic,
                guess,
                max_iter,
                tol,
                min_std,
                max_shift,
                border,
                work,
            )
            if fl == FLAG_OK and not (z >= zncc_min):
                fl = FLAG_LOW_CORRELATION
            done[j] = True
            P[j] = guess
            zncc[j] = z
            iters[j] = it
            flags[j] = fl
            sigma[j, 0] = work[4][3, 4]
            sigma[j, 1] = work[4][3, 5]
            if fl == FLAG_OK:
                size = _heap_push(keys, vals, size, z, j)


@njit(cache=True, parallel=True)
def rg_propagate(
    n_groups,
    group,
    ref_img,
    ref_gx,
    ref_gy,
    ref_coef,
    ref_invalid,
    def_coef,
    def_invalid,
    order,
    centres,
    nb_ptr,
    nb_idx,
    P,
    half,
    quadratic,
    max_iter,
    tol,
    min_std,
    max_shift,
    border,
    zncc_min,
    zncc,
    iters,
    flags,
    sigma,
    done,
):
    """Reliability-guided propagation: from the solved (``done`` and ok) points of each group,
    always extend from the best-correlated point to its unsolved neighbours (guess = its
    parameters extrapolated). Groups run in parallel; ``n_groups = 0`` runs one global pass
    ignoring groups."""
    if n_groups == 0:
        _propagate_group(
            -1,
            group,
            ref_img,
            ref_gx,
            ref_gy,
            ref_coef,
            ref_invalid,
            def_coef,
            def_invalid,
            order,
            centres,
            nb_ptr,
            nb_idx,
            P,
            half,
            quadratic,
            max_iter,
            tol,
            min_std,
            max_shift,
            border,
            zncc_min,
            zncc,
            iters,
            flags,
            sigma,
            done,
        )
        return
    for g in prange(n_groups):
        _propagate_group(
            g,
            group,
            ref_img,
            ref_gx,
            ref_gy,
            ref_coef,
            ref_invalid,
            def_coef,
            def_invalid,
            order,
            centres,
            nb_ptr,
            nb_idx,
            P,
            half,
            quadratic,
            max_iter,
            tol,
            min_std,
            max_shift,
            border,
            zncc_min,
            zncc,
            iters,
            flags,
            sigma,
            done,
        )
